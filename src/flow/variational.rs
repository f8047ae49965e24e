//! Variational refinement of a dense flow field (Brox et al. 2004 as simplified for DIS by
//! Kroeger et al. and OpenCV's `VariationalRefinement`).
//!
//! Around the current field w = (u, v) it finds the increment dw = (du, dv) minimising
//!
//! E(dw) = Σ_x δ·Ψ(E_I) + γ·Ψ(E_G) + α·Ψ(|∇(u + du)|² + |∇(v + dv)|²),   Ψ(s²) = √(s² + ε²),
//!
//! with E_I the linearised brightness constancy (I_z + I_x du + I_y dv)² and E_G the linearised
//! gradient constancy, each normalised by the squared local gradient (+ ζ²) so strong edges do
//! not dominate. Frame 2 is warped once by w; the derivatives are taken on the mean of frame 1
//! and the warped frame 2. Each fixed-point (outer) iteration freezes the robust weights Ψ' at
//! the current dw and solves the resulting linear system with a few SOR sweeps (Gauss–Seidel in
//! raster order, relaxation ω, each pixel's 2 × 2 block solved for du then dv).
//!
//! Intensities are grey levels in [0, 255]; flow in pixels of the level. Arrays are flat and
//! padded by one pixel on every side (stride w + 2): border pixels hold zero increments and
//! zero smoothness weights, so the inner loops need no bounds logic.

use super::pyramid::{Level, sample_clamped};
use crate::error::{Error, Result};

/// Weights and iteration counts of the refinement (OpenCV's defaults).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct VariationalParams {
    /// Fixed-point (outer) iterations; 0 turns the refinement off.
    pub iterations: usize,
    /// SOR sweeps per fixed-point iteration.
    pub sor_iterations: usize,
    /// SOR relaxation factor in (0, 2).
    pub omega: f32,
    /// Weight of the smoothness term α.
    pub alpha: f32,
    /// Weight of gradient constancy γ.
    pub gamma: f32,
    /// Weight of brightness constancy δ.
    pub delta: f32,
}

impl Default for VariationalParams {
    fn default() -> Self {
        VariationalParams {
            iterations: 5,
            sor_iterations: 5,
            omega: 1.6,
            alpha: 20.0,
            gamma: 10.0,
            delta: 5.0,
        }
    }
}

impl VariationalParams {
    /// Fails with [`Error::InvalidParameter`] for weights the solver cannot use.
    pub fn validate(&self) -> Result<()> {
        if !(self.omega > 0.0 && self.omega < 2.0) {
            return Err(Error::InvalidParameter(format!(
                "SOR relaxation ω = {} is outside (0, 2)",
                self.omega
            )));
        }
        for (name, value) in [("α", self.alpha), ("γ", self.gamma), ("δ", self.delta)] {
            if !(value.is_finite() && value >= 0.0) {
                return Err(Error::InvalidParameter(format!(
                    "variational weight {name} = {value} must be finite and ≥ 0"
                )));
            }
        }
        Ok(())
    }
}

/// ζ²: added to the squared gradients that normalise the data terms.
const ZETA_SQ: f32 = 0.01;
/// ε²: smooths the robust penalty Ψ near zero.
const EPSILON_SQ: f32 = 1e-6;

/// Refines the flow (u, v) from `from` to `to` (one pyramid level each) in place.
pub fn refine(from: &Level, to: &Level, u: &mut [f32], v: &mut [f32], params: &VariationalParams) {
    let (w, h) = (from.width, from.height);
    if params.iterations == 0 || w < 2 || h < 2 {
        return;
    }
    let derivatives = Derivatives::new(from, to, u, v);
    let mut system = System::new(w, h);
    // Base flow in the padded layout (border values replicate the edge).
    let pad_u = padded(u, w, h);
    let pad_v = padded(v, w, h);
    for _ in 0..params.iterations {
        system.data_terms(&derivatives, params);
        system.smoothness_terms(&pad_u, &pad_v, params);
        for _ in 0..params.sor_iterations {
            system.sor_sweep(params.omega);
        }
    }
    for y in 0..h {
        let row = (y + 1) * (w + 2) + 1;
        for x in 0..w {
            u[y * w + x] += system.du[row + x];
            v[y * w + x] += system.dv[row + x];
        }
    }
}

/// A `w × h` row-major field copied into the padded layout, borders replicating the edge.
fn padded(field: &[f32], w: usize, h: usize) -> Vec<f32> {
    let stride = w + 2;
    let mut out = Vec::with_capacity(stride * (h + 2));
    for py in 0..h + 2 {
        let row = &field[py.saturating_sub(1).min(h - 1) * w..][..w];
        out.push(row[0]);
        out.extend_from_slice(row);
        out.push(row[w - 1]);
    }
    out
}

/// Image derivatives at the current flow, in the padded layout (zero on the border).
struct Derivatives {
    /// Spatial derivatives of the mean of frame 1 and warped frame 2.
    ix: Vec<f32>,
    iy: Vec<f32>,
    /// Temporal difference (warped frame 2 − frame 1).
    iz: Vec<f32>,
    /// Second spatial derivatives of the mean image.
    ixx: Vec<f32>,
    ixy: Vec<f32>,
    iyy: Vec<f32>,
    /// Spatial derivatives of the temporal difference.
    ixz: Vec<f32>,
    iyz: Vec<f32>,
}

impl Derivatives {
    fn new(from: &Level, to: &Level, u: &[f32], v: &[f32]) -> Self {
        let (w, h) = (from.width, from.height);
        let mut mean = Vec::with_capacity(w * h);
        let mut iz = Vec::with_capacity(w * h);
        for y in 0..h {
            for x in 0..w {
                let i = y * w + x;
                let warped = sample_clamped(&to.pixels, w, h, x as f32 + u[i], y as f32 + v[i]);
                mean.push(0.5 * (from.pixels[i] + warped));
                iz.push(warped - from.pixels[i]);
            }
        }
        let (ix, iy) = central_differences(&mean, w, h);
        let (ixz, iyz) = central_differences(&iz, w, h);
        let (ixx, ixy) = central_differences(&ix, w, h);
        let (_, iyy) = central_differences(&iy, w, h);
        Derivatives {
            ix: padded_zero(&ix, w, h),
            iy: padded_zero(&iy, w, h),
            iz: padded_zero(&iz, w, h),
            ixx: padded_zero(&ixx, w, h),
            ixy: padded_zero(&ixy, w, h),
            iyy: padded_zero(&iyy, w, h),
            ixz: padded_zero(&ixz, w, h),
            iyz: padded_zero(&iyz, w, h),
        }
    }
}

/// (∂/∂x, ∂/∂y) of a `w × h` field by central differences, one-sided at the borders.
fn central_differences(f: &[f32], w: usize, h: usize) -> (Vec<f32>, Vec<f32>) {
    let mut dx = Vec::with_capacity(w * h);
    let mut dy = Vec::with_capacity(w * h);
    for y in 0..h {
        let (up, down) = (y.saturating_sub(1), (y + 1).min(h - 1));
        let sy = 1.0 / (down - up) as f32;
        for x in 0..w {
            let (l, r) = (x.saturating_sub(1), (x + 1).min(w - 1));
            dx.push((f[y * w + r] - f[y * w + l]) / (r - l) as f32);
            dy.push((f[down * w + x] - f[up * w + x]) * sy);
        }
    }
    (dx, dy)
}

/// A `w × h` field copied into the padded layout with a zero border.
fn padded_zero(field: &[f32], w: usize, h: usize) -> Vec<f32> {
    let stride = w + 2;
    let mut out = vec![0.0; stride * (h + 2)];
    for y in 0..h {
        out[(y + 1) * stride + 1..][..w].copy_from_slice(&field[y * w..][..w]);
    }
    out
}

/// The linear system of one fixed-point iteration, per pixel (padded layout):
/// `diag_u·du + a12·dv = rhs_u + Σ_n wₙ du_n` and `a12·du + diag_v·dv = rhs_v + Σ_n wₙ dv_n`
/// over the 4-neighbours n, with the current increments.
struct System {
    w: usize,
    h: usize,
    du: Vec<f32>,
    dv: Vec<f32>,
    a11: Vec<f32>,
    a12: Vec<f32>,
    a22: Vec<f32>,
    b1: Vec<f32>,
    b2: Vec<f32>,
    /// Smoothness weight of the edge from a pixel to its right neighbour (0 on the last column).
    wx: Vec<f32>,
    /// Smoothness weight of the edge from a pixel to the one below (0 on the last row).
    wy: Vec<f32>,
    /// 1 / (a11 + Σ wₙ) and 1 / (a22 + Σ wₙ).
    inv_diag_u: Vec<f32>,
    inv_diag_v: Vec<f32>,
    rhs_u: Vec<f32>,
    rhs_v: Vec<f32>,
}

impl System {
    fn new(w: usize, h: usize) -> Self {
        let n = (w + 2) * (h + 2);
        let zeros = || vec![0.0f32; n];
        System {
            w,
            h,
            du: zeros(),
            dv: zeros(),
            a11: zeros(),
            a12: zeros(),
            a22: zeros(),
            b1: zeros(),
            b2: zeros(),
            wx: zeros(),
            wy: zeros(),
            inv_diag_u: zeros(),
            inv_diag_v: zeros(),
            rhs_u: zeros(),
            rhs_v: zeros(),
        }
    }

    /// The data terms (brightness and gradient constancy, robustly weighted at the current
    /// increments) into a11, a12, a22, b1, b2.
    fn data_terms(&mut self, d: &Derivatives, params: &VariationalParams) {
        let (half_delta, half_gamma) = (0.5 * params.delta, 0.5 * params.gamma);
        let stride = self.w + 2;
        for y in 1..=self.h {
            let row = y * stride + 1..y * stride + 1 + self.w;
            for q in row {
                let (ix, iy, iz) = (d.ix[q], d.iy[q], d.iz[q]);
                let (du, dv) = (self.du[q], self.dv[q]);
                // Brightness constancy, normalised by |∇I|² + ζ².
                let norm = ix * ix + iy * iy + ZETA_SQ;
                let r = iz + ix * du + iy * dv;
                let weight = half_delta / (r * r / norm + EPSILON_SQ).sqrt() / norm;
                let mut a11 = weight * ix * ix + ZETA_SQ;
                let mut a12 = weight * ix * iy;
                let mut a22 = weight * iy * iy + ZETA_SQ;
                let mut b1 = -weight * iz * ix;
                let mut b2 = -weight * iz * iy;
                // Gradient constancy, each component normalised by its own gradient.
                let (ixx, ixy, iyy, ixz, iyz) = (d.ixx[q], d.ixy[q], d.iyy[q], d.ixz[q], d.iyz[q]);
                let nx = ixx * ixx + ixy * ixy + ZETA_SQ;
                let ny = iyy * iyy + ixy * ixy + ZETA_SQ;
                let rx = ixz + ixx * du + ixy * dv;
                let ry = iyz + ixy * du + iyy * dv;
                let weight = half_gamma / (rx * rx / nx + ry * ry / ny + EPSILON_SQ).sqrt();
                a11 += weight * (ixx * ixx / nx + ixy * ixy / ny);
                a12 += weight * (ixx * ixy / nx + ixy * iyy / ny);
                a22 += weight * (ixy * ixy / nx + iyy * iyy / ny);
                b1 -= weight * (ixx * ixz / nx + ixy * iyz / ny);
                b2 -= weight * (ixy * ixz / nx + iyy * iyz / ny);
                self.a11[q] = a11;
                self.a12[q] = a12;
                self.a22[q] = a22;
                self.b1[q] = b1;
                self.b2[q] = b2;
            }
        }
    }

    /// Smoothness weights α/2 · Ψ'(|∇(u + du)|² + |∇(v + dv)|²) from forward differences, one per
    /// pixel, given to its right and lower edges; then folds the base flow's smoothness pull and
    /// the data terms into `rhs_*` and `inv_diag_*`.
    fn smoothness_terms(&mut self, u: &[f32], v: &[f32], params: &VariationalParams) {
        let half_alpha = 0.5 * params.alpha;
        let (w, h) = (self.w, self.h);
        let stride = w + 2;
        for y in 1..=h {
            for x in 1..=w {
                let q = y * stride + x;
                let (uq, vq) = (u[q] + self.du[q], v[q] + self.dv[q]);
                let (ux, vx) = if x < w {
                    (
                        u[q + 1] + self.du[q + 1] - uq,
                        v[q + 1] + self.dv[q + 1] - vq,
                    )
                } else {
                    (0.0, 0.0)
                };
                let (uy, vy) = if y < h {
                    (
                        u[q + stride] + self.du[q + stride] - uq,
                        v[q + stride] + self.dv[q + stride] - vq,
                    )
                } else {
                    (0.0, 0.0)
                };
                let weight =
                    half_alpha / (ux * ux + uy * uy + vx * vx + vy * vy + EPSILON_SQ).sqrt();
                self.wx[q] = if x < w { weight } else { 0.0 };
                self.wy[q] = if y < h { weight } else { 0.0 };
            }
        }
        for y in 1..=h {
            for q in y * stride + 1..y * stride + 1 + w {
                let (wl, wr, wu, wd) =
                    (self.wx[q - 1], self.wx[q], self.wy[q - stride], self.wy[q]);
                let sum = wl + wr + wu + wd;
                let pull = |f: &[f32]| {
                    wl * (f[q - 1] - f[q])
                        + wr * (f[q + 1] - f[q])
                        + wu * (f[q - stride] - f[q])
                        + wd * (f[q + stride] - f[q])
                };
                self.rhs_u[q] = self.b1[q] + pull(u);
                self.rhs_v[q] = self.b2[q] + pull(v);
                self.inv_diag_u[q] = 1.0 / (self.a11[q] + sum);
                self.inv_diag_v[q] = 1.0 / (self.a22[q] + sum);
            }
        }
    }

    /// One SOR sweep in raster order over the increments.
    fn sor_sweep(&mut self, omega: f32) {
        let stride = self.w + 2;
        for y in 1..=self.h {
            for q in y * stride + 1..y * stride + 1 + self.w {
                let (wl, wr, wu, wd) =
                    (self.wx[q - 1], self.wx[q], self.wy[q - stride], self.wy[q]);
                let du = &mut self.du;
                let dv = &mut self.dv;
                let nu =
                    wl * du[q - 1] + wr * du[q + 1] + wu * du[q - stride] + wd * du[q + stride];
                let nv =
                    wl * dv[q - 1] + wr * dv[q + 1] + wu * dv[q - stride] + wd * dv[q + stride];
                let a12 = self.a12[q];
                let target_u = (self.rhs_u[q] + nu - a12 * dv[q]) * self.inv_diag_u[q];
                du[q] += omega * (target_u - du[q]);
                let target_v = (self.rhs_v[q] + nv - a12 * du[q]) * self.inv_diag_v[q];
                dv[q] += omega * (target_v - dv[q]);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A smooth textured level: sums of sines, in grey levels.
    fn texture(w: usize, h: usize, shift: f32) -> Level {
        let pixels = (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as f32 - shift, (i / w) as f32);
                128.0 + 50.0 * (0.31 * x + 0.1 * y).sin() + 40.0 * (0.23 * y - 0.17 * x).cos()
            })
            .collect();
        Level::new(w, h, pixels)
    }

    #[test]
    fn refinement_pulls_a_wrong_constant_flow_towards_the_truth() {
        let (w, h) = (48, 40);
        let (a, b) = (texture(w, h, 0.0), texture(w, h, 1.0));
        let mut u = vec![0.6; w * h];
        let mut v = vec![0.3; w * h];
        refine(&a, &b, &mut u, &mut v, &VariationalParams::default());
        let err = |x: usize, y: usize| (u[y * w + x] - 1.0).hypot(v[y * w + x]);
        let mean: f32 = (8..h - 8)
            .flat_map(|y| (8..w - 8).map(move |x| (x, y)))
            .map(|(x, y)| err(x, y))
            .sum::<f32>()
            / ((w - 16) * (h - 16)) as f32;
        assert!(mean < 0.15, "mean error {mean}");
    }

    #[test]
    fn identical_images_keep_zero_flow_and_flat_ones_stay_finite() {
        let a = texture(20, 16, 0.0);
        let (mut u, mut v) = (vec![0.0; 320], vec![0.0; 320]);
        refine(&a, &a, &mut u, &mut v, &VariationalParams::default());
        assert!(u.iter().chain(&v).all(|&f| f == 0.0));
        let flat = Level::new(20, 16, vec![7.0; 320]);
        let bright = Level::new(20, 16, vec![90.0; 320]);
        refine(
            &flat,
            &bright,
            &mut u,
            &mut v,
            &VariationalParams::default(),
        );
        assert!(u.iter().chain(&v).all(|&f| f == 0.0));
    }

    #[test]
    fn invalid_weights_are_rejected() {
        let p = VariationalParams {
            omega: 2.5,
            ..Default::default()
        };
        assert!(p.validate().is_err());
        let p = VariationalParams {
            alpha: f32::NAN,
            ..Default::default()
        };
        assert!(p.validate().is_err());
    }
}
