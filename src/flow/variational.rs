//! Variational refinement of a dense flow field (Brox et al. 2004 as simplified for DIS by
//! Kroeger et al. and OpenCV's `VariationalRefinement`).
//!
//! Around the current field w = (u, v) it finds the increment dw = (du, dv) minimising
//!
//! E(dw) = Σ_x δ·Ψ(E_I) + γ·Ψ(E_G) + α·Ψ(|∇(u + du)|² + |∇(v + dv)|²),   Ψ(s²) = √(s² + ε²),
//!
//! with E_I the linearised brightness constancy (I_z + I_x du + I_y dv)² and E_G the linearised
//! gradient constancy, each normalised by the squared local gradient (+ ζ²) so strong edges do
//! not dominate. Frame 2 is warped by w (not by w + dw), row by row again in each fixed-point
//! iteration; the derivatives are taken on the mean of frame 1 and the warped frame 2. Pixels
//! that w carries outside frame 2 get no data term (frame 2 holds nothing to compare them
//! with), so smoothness extends the flow of their neighbours.
//!
//! Each fixed-point (outer) iteration freezes the robust weights Ψ' at the current dw and solves
//! the resulting linear system with a few SOR sweeps (red–black order, relaxation ω, each
//! pixel's 2 × 2 block solved for du then dv). Where the flow is already smooth Ψ' of the
//! smoothness term is large, so the refinement mostly acts around motion boundaries and noise.
//!
//! Intensities are grey levels in [0, 255]; flow in pixels of the level; derivatives are true
//! derivatives (OpenCV's unnormalised [−1, 0, 1] kernels make them twice as large, which halves
//! every increment). The linear system's arrays are padded by one pixel on every side (rows of
//! w + 2, each row an allocation of its own): border pixels hold zero increments and zero
//! smoothness weights, so the inner loops need no bounds logic. The equations and the
//! derivatives they are made from are made a row at a time from the few rows around it, as each
//! fixed-point iteration needs them.

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

/// The flow (u, v) from `from` to `to` (one pyramid level each, row-major) refined. The arrays
/// are taken by value: the refinement copies the flow into its padded layout and releases the
/// input before it allocates the increments and coefficients, so the two copies are never held
/// beside the whole system.
pub fn refine(
    from: &Level,
    to: &Level,
    u: Vec<f32>,
    v: Vec<f32>,
    params: &VariationalParams,
) -> (Vec<f32>, Vec<f32>) {
    let (w, h) = (from.width, from.height);
    if params.iterations == 0 || w < 2 || h < 2 {
        return (u, v);
    }
    let mut derivatives = Derivatives::new(from, to);
    let mut system = System::new(w, h, u, v);
    for _ in 0..params.iterations {
        system.linearise(&mut derivatives, params);
        for _ in 0..params.sor_iterations {
            system.sor_half_sweep(params.omega, 0);
            system.sor_half_sweep(params.omega, 1);
        }
    }
    system.into_refined_flow()
}

/// The linearised constancy equations of one pixel, each already divided by its normalisation
/// √(|∇·|² + ζ²): brightness `[0]·du + [1]·dv + [2]`, x-gradient `[3]·du + [4]·dv + [5]`,
/// y-gradient `[6]·du + [7]·dv + [8]`.
type Constancy = [f32; 9];

/// What the constancy equations are made of at the base flow, `to` being warped by (u, v): the
/// first derivatives of the mean of `from` and the warped `to`, and their difference (central
/// differences, one-sided at borders). Everything is made a row at a time as each fixed-point
/// iteration sweeps down the image ([`Derivatives::equations`]), from the few rows around the
/// current one: holding the equations for the whole level would take 36 bytes per pixel, and
/// holding their ingredients (the first derivatives, the difference and the inside mask) 13.
/// The price is frame 2 warped again in each iteration (rows still held from the iteration
/// before serve the next only on levels of at most five rows: the base flow does not change
/// within a refinement). The arithmetic is that of whole arrays, so the results are the same
/// bits.
struct Derivatives<'a> {
    from: &'a Level,
    to: &'a Level,
    /// Rows of the mean of `from` and the warped `to` (`a`) and of the warped `to` minus `from`
    /// (`b`).
    warped: Rows,
    /// Rows of ∂/∂x (`a`) and ∂/∂y (`b`) of the mean.
    gradients: Rows,
    /// Row `y`'s second derivatives, reused from row to row.
    second: SecondDerivativeRows,
}

/// Rows of two `w`-wide fields, row r in slot r mod [`Rows::COUNT`]: each slot holds the last
/// row asked for that falls in it. The equations of row y need the first derivatives of rows
/// y − 1 … y + 1, and those the mean of rows y − 2 … y + 2, so five slots hold every row a row's
/// equations read (four would do, as rows y − 2 and y + 2 are never read together; three would
/// not).
struct Rows {
    w: usize,
    a: Vec<f32>,
    b: Vec<f32>,
    /// The row each slot holds (`usize::MAX`: none yet).
    held: [usize; Rows::COUNT],
}

impl Rows {
    const COUNT: usize = 5;

    /// Empty slots for rows `w` wide.
    fn new(w: usize) -> Self {
        Rows {
            w,
            a: vec![0.0; Self::COUNT * w],
            b: vec![0.0; Self::COUNT * w],
            held: [usize::MAX; Self::COUNT],
        }
    }

    /// Whether row `r` is held.
    fn holds(&self, r: usize) -> bool {
        self.held[r % Self::COUNT] == r
    }

    /// Row `r` of field `a` (held).
    fn a(&self, r: usize) -> &[f32] {
        debug_assert!(self.holds(r), "row {r} is not held");
        &self.a[(r % Self::COUNT) * self.w..][..self.w]
    }

    /// Row `r` of field `b` (held).
    fn b(&self, r: usize) -> &[f32] {
        debug_assert!(self.holds(r), "row {r} is not held");
        &self.b[(r % Self::COUNT) * self.w..][..self.w]
    }

    /// The slots of row `r` in both fields, to be filled; from now on they hold row `r`.
    fn fill(&mut self, r: usize) -> (&mut [f32], &mut [f32]) {
        let slot = r % Self::COUNT;
        self.held[slot] = r;
        let w = self.w;
        (&mut self.a[slot * w..][..w], &mut self.b[slot * w..][..w])
    }
}

/// One row of each second derivative, reused from row to row by [`Derivatives::equations`]
/// (∂ₓ of iy is not needed: ixy is ∂_y of ix).
struct SecondDerivativeRows {
    ixz: Vec<f32>,
    iyz: Vec<f32>,
    ixx: Vec<f32>,
    ixy: Vec<f32>,
    iyy: Vec<f32>,
}

/// The rows a central difference in y at row `y` of an `h`-row field reads (one-sided at the
/// borders), and the factor its difference is scaled by.
fn y_neighbours(y: usize, h: usize) -> (usize, usize, f32) {
    let (up, down) = (y.saturating_sub(1), (y + 1).min(h - 1));
    (up, down, 1.0 / (down - up) as f32)
}

impl<'a> Derivatives<'a> {
    /// The derivatives of the flow from `from` to `to` (both `w × h`, w, h ≥ 2) at the base
    /// flow each [`Derivatives::equations`] call is given; no row is made yet.
    fn new(from: &'a Level, to: &'a Level) -> Self {
        let w = from.width;
        let row = || vec![0.0; w];
        Derivatives {
            from,
            to,
            warped: Rows::new(w),
            gradients: Rows::new(w),
            second: SecondDerivativeRows {
                ixz: row(),
                iyz: row(),
                ixx: row(),
                ixy: row(),
                iyy: row(),
            },
        }
    }

    /// Makes row `r` of the mean and the difference, unless held: `to` sampled at (x + u, y + v)
    /// with (u, v) from `flow` (the base flow of row r, `w` values).
    fn warp_row(&mut self, r: usize, flow: &[[f32; 2]]) {
        if self.warped.holds(r) {
            return;
        }
        let (from, to) = (self.from, self.to);
        let (w, h) = (from.width, from.height);
        let pixels = &from.pixels[r * w..][..w];
        let (mean, difference) = self.warped.fill(r);
        for (x, (((m, d), &f), &[u, v])) in (mean
            .iter_mut()
            .zip(difference.iter_mut())
            .zip(pixels)
            .zip(flow))
        .enumerate()
        {
            let warped = sample_clamped(&to.pixels, w, h, x as f32 + u, r as f32 + v);
            *m = 0.5 * (f + warped);
            *d = warped - f;
        }
    }

    /// Makes row `r` of ∂/∂x and ∂/∂y of the mean, unless held; `flow(r)` gives the base flow
    /// of row r.
    fn gradient_row<'f>(&mut self, r: usize, flow: &impl Fn(usize) -> &'f [[f32; 2]]) {
        if self.gradients.holds(r) {
            return;
        }
        let (up, down, scale) = y_neighbours(r, self.from.height);
        for row in [up, r, down] {
            self.warp_row(row, flow(row));
        }
        let (dx, dy) = self.gradients.fill(r);
        x_differences(self.warped.a(r), dx);
        y_differences(self.warped.a(up), self.warped.a(down), scale, dy);
    }

    /// The constancy equations of row `y` into `out[x]` for pixel x (`w` entries) at the base
    /// flow `flow(r)` of each row r (`w` values): zero where the flow leaves the image (frame 2
    /// holds nothing to compare with, so smoothness alone decides).
    fn equations<'f>(
        &mut self,
        y: usize,
        flow: impl Fn(usize) -> &'f [[f32; 2]],
        out: &mut [Constancy],
    ) {
        let (w, h) = (self.from.width, self.from.height);
        let (up, down, scale) = y_neighbours(y, h);
        for row in [up, y, down] {
            self.gradient_row(row, &flow);
        }
        let SecondDerivativeRows {
            ixz,
            iyz,
            ixx,
            ixy,
            iyy,
        } = &mut self.second;
        let (warped, gradients) = (&self.warped, &self.gradients);
        x_differences(warped.b(y), ixz);
        y_differences(warped.b(up), warped.b(down), scale, iyz);
        x_differences(gradients.a(y), ixx);
        y_differences(gradients.a(up), gradients.a(down), scale, ixy);
        y_differences(gradients.b(up), gradients.b(down), scale, iyy);
        let (ix, iy, iz) = (gradients.a(y), gradients.b(y), warped.b(y));
        let (xmax, ymax) = ((w - 1) as f32, (h - 1) as f32);
        for (x, (out, &[u, v])) in out[..w].iter_mut().zip(flow(y)).enumerate() {
            let (tx, ty) = (x as f32 + u, y as f32 + v);
            if !((0.0..=xmax).contains(&tx) && (0.0..=ymax).contains(&ty)) {
                *out = [0.0; 9];
                continue;
            }
            let b = 1.0 / (ix[x] * ix[x] + iy[x] * iy[x] + ZETA_SQ).sqrt();
            let gx = 1.0 / (ixx[x] * ixx[x] + ixy[x] * ixy[x] + ZETA_SQ).sqrt();
            let gy = 1.0 / (iyy[x] * iyy[x] + ixy[x] * ixy[x] + ZETA_SQ).sqrt();
            *out = [
                ix[x] * b,
                iy[x] * b,
                iz[x] * b,
                ixx[x] * gx,
                ixy[x] * gx,
                ixz[x] * gx,
                ixy[x] * gy,
                iyy[x] * gy,
                iyz[x] * gy,
            ];
        }
    }
}

/// The ∂/∂x of one `w`-wide row (w ≥ 2) into `dx` by central differences, one-sided at the
/// ends.
fn x_differences(row: &[f32], dx: &mut [f32]) {
    let w = row.len();
    dx[0] = row[1] - row[0];
    for (d, t) in dx[1..w - 1].iter_mut().zip(row.windows(3)) {
        *d = 0.5 * (t[2] - t[0]);
    }
    dx[w - 1] = row[w - 1] - row[w - 2];
}

/// The ∂/∂y of a row from the rows `above` and `below` it ([`y_neighbours`], with its `scale`)
/// into `dy`.
fn y_differences(above: &[f32], below: &[f32], scale: f32, dy: &mut [f32]) {
    for ((d, a), b) in dy.iter_mut().zip(above).zip(below) {
        *d = (b - a) * scale;
    }
}

/// Row `r` of the base flow (u, v) (`w` values) in [`System`]'s padded layout: padded row
/// r + 1, from column 1.
fn base_row(flow: &PaddedRows<[f32; 2]>, w: usize, r: usize) -> &[[f32; 2]] {
    &flow.row(r + 1)[1..][..w]
}

/// A padded field of [`System`], one allocation per row. Row-sized pieces fit the gaps other
/// arrays leave: in wasm, where the allocator grows the memory by a whole request whenever no
/// gap holds it, one array of a full level's coefficients (28 bytes a pixel) made the flow's
/// memory grow by half again what it ever held at once.
struct PaddedRows<T> {
    rows: Vec<Vec<T>>,
}

impl<T: Copy> PaddedRows<T> {
    /// `count` rows of `stride` copies of `value`.
    fn filled(stride: usize, count: usize, value: T) -> Self {
        PaddedRows {
            rows: (0..count).map(|_| vec![value; stride]).collect(),
        }
    }

    /// Row `y`.
    fn row(&self, y: usize) -> &[T] {
        &self.rows[y]
    }

    /// Rows y − 1 and y + 1 to read and row y to write (0 < y < count − 1).
    fn around_mut(&mut self, y: usize) -> (&[T], &mut [T], &[T]) {
        let (above, rest) = self.rows.split_at_mut(y);
        let (row, below) = rest.split_at_mut(1);
        (&above[y - 1], &mut row[0], &below[0])
    }
}

/// One pixel's row of the linear system of a fixed-point iteration:
/// `du = (rhs_u + Σₙ wₙ·du_n − a12·dv) · inv_u` and `dv = (rhs_v + Σₙ wₙ·dv_n − a12·du) · inv_v`
/// over the 4-neighbours n, where the edge weights are this pixel's `wx` (right), `wy` (down)
/// and its left and upper neighbours' `wx` and `wy`.
#[derive(Clone, Copy, Default)]
struct Coefficients {
    /// Smoothness weight of the edge to the right neighbour (0 on the last column).
    wx: f32,
    /// Smoothness weight of the edge to the neighbour below (0 on the last row).
    wy: f32,
    a12: f32,
    rhs_u: f32,
    rhs_v: f32,
    /// 1 / (a11 + Σ wₙ) and 1 / (a22 + Σ wₙ).
    inv_u: f32,
    inv_v: f32,
}

/// The fixed-point problem on a padded `(w + 2) × (h + 2)` layout: border pixels keep zero
/// increments and zero weights, so the loops need no bounds logic.
struct System {
    w: usize,
    h: usize,
    /// Base flow (u, v), borders replicating the edge.
    flow: PaddedRows<[f32; 2]>,
    /// Increments (du, dv).
    increment: PaddedRows<[f32; 2]>,
    coefficients: PaddedRows<Coefficients>,
}

impl System {
    /// The system around the base flow (u, v) (`w × h`, row-major), zero increments; (u, v) is
    /// released once copied, before the increments and coefficients are allocated.
    fn new(w: usize, h: usize, u: Vec<f32>, v: Vec<f32>) -> Self {
        let stride = w + 2;
        let flow = PaddedRows {
            rows: (0..h + 2)
                .map(|py| {
                    let y = py.saturating_sub(1).min(h - 1);
                    (0..stride)
                        .map(|px| {
                            let i = y * w + px.saturating_sub(1).min(w - 1);
                            [u[i], v[i]]
                        })
                        .collect()
                })
                .collect(),
        };
        drop((u, v));
        System {
            w,
            h,
            flow,
            increment: PaddedRows::filled(stride, h + 2, [0.0; 2]),
            coefficients: PaddedRows::filled(stride, h + 2, Coefficients::default()),
        }
    }

    /// The base flow plus the increments, as (u, v) row-major without the padding; the
    /// coefficients are released first.
    fn into_refined_flow(self) -> (Vec<f32>, Vec<f32>) {
        let System {
            w,
            h,
            flow,
            increment,
            coefficients,
        } = self;
        drop(coefficients);
        let (mut u, mut v) = (Vec::with_capacity(w * h), Vec::with_capacity(w * h));
        for y in 1..=h {
            let base = &flow.row(y)[1..][..w];
            let step = &increment.row(y)[1..][..w];
            for (f, d) in base.iter().zip(step) {
                u.push(f[0] + d[0]);
                v.push(f[1] + d[1]);
            }
        }
        (u, v)
    }

    /// Freezes the robust weights at the current increments and builds every pixel's
    /// [`Coefficients`]: smoothness weight α/2 · Ψ'(|∇(u + du)|² + |∇(v + dv)|²) from forward
    /// differences (given to the pixel's right and lower edges), the data terms weighted by
    /// Ψ' of their residuals, and the base flow's smoothness pull.
    fn linearise(&mut self, derivatives: &mut Derivatives, params: &VariationalParams) {
        let (half_alpha, half_delta, half_gamma) =
            (0.5 * params.alpha, 0.5 * params.delta, 0.5 * params.gamma);
        let (w, h) = (self.w, self.h);
        let System {
            flow,
            increment,
            coefficients,
            ..
        } = self;
        let mut equations = vec![[0.0; 9]; w + 2];
        for y in 1..=h {
            let (flow_up, flow_mid, flow_down) = (flow.row(y - 1), flow.row(y), flow.row(y + 1));
            let (increment_mid, increment_down) = (increment.row(y), increment.row(y + 1));
            // This row's equations, indexed like the padded row (column 0 unused).
            derivatives.equations(y - 1, |r| base_row(flow, w, r), &mut equations[1..]);
            let (coefficients_up, coefficients_mid, _) = coefficients.around_mut(y);
            // Weight of the edge to the left neighbour: the previous pixel's right edge.
            let mut wl = 0.0;
            for x in 1..=w {
                let total = |f: [f32; 2], d: [f32; 2]| [f[0] + d[0], f[1] + d[1]];
                let here = total(flow_mid[x], increment_mid[x]);
                let right = total(flow_mid[x + 1], increment_mid[x + 1]);
                let down = total(flow_down[x], increment_down[x]);
                let (has_right, has_down) = (x < w, y < h);
                let gx = if has_right {
                    [right[0] - here[0], right[1] - here[1]]
                } else {
                    [0.0; 2]
                };
                let gy = if has_down {
                    [down[0] - here[0], down[1] - here[1]]
                } else {
                    [0.0; 2]
                };
                let gradient = gx[0] * gx[0] + gx[1] * gx[1] + gy[0] * gy[0] + gy[1] * gy[1];
                let psi = half_alpha / (gradient + EPSILON_SQ).sqrt();
                let wr = if has_right { psi } else { 0.0 };
                let wd = if has_down { psi } else { 0.0 };
                let wu = coefficients_up[x].wy;

                let t = &equations[x];
                let [du, dv] = increment_mid[x];
                let r = t[2] + t[0] * du + t[1] * dv;
                let wb = half_delta / (r * r + EPSILON_SQ).sqrt();
                let rx = t[5] + t[3] * du + t[4] * dv;
                let ry = t[8] + t[6] * du + t[7] * dv;
                let wg = half_gamma / (rx * rx + ry * ry + EPSILON_SQ).sqrt();
                let a11 = wb * t[0] * t[0] + wg * (t[3] * t[3] + t[6] * t[6]) + ZETA_SQ;
                let a12 = wb * t[0] * t[1] + wg * (t[3] * t[4] + t[6] * t[7]);
                let a22 = wb * t[1] * t[1] + wg * (t[4] * t[4] + t[7] * t[7]) + ZETA_SQ;
                let b1 = -wb * t[2] * t[0] - wg * (t[5] * t[3] + t[8] * t[6]);
                let b2 = -wb * t[2] * t[1] - wg * (t[5] * t[4] + t[8] * t[7]);

                let (f, l, r, u, d) = (
                    flow_mid[x],
                    flow_mid[x - 1],
                    flow_mid[x + 1],
                    flow_up[x],
                    flow_down[x],
                );
                let pull_u = (wl * (l[0] - f[0]) + wr * (r[0] - f[0]))
                    + (wu * (u[0] - f[0]) + wd * (d[0] - f[0]));
                let pull_v = (wl * (l[1] - f[1]) + wr * (r[1] - f[1]))
                    + (wu * (u[1] - f[1]) + wd * (d[1] - f[1]));
                let sum = (wl + wr) + (wu + wd);
                coefficients_mid[x] = Coefficients {
                    wx: wr,
                    wy: wd,
                    a12,
                    rhs_u: b1 + pull_u,
                    rhs_v: b2 + pull_v,
                    inv_u: 1.0 / (a11 + sum),
                    inv_v: 1.0 / (a22 + sum),
                };
                wl = wr;
            }
        }
    }

    /// One SOR half-sweep over the pixels with (x + y) % 2 == `colour` (red–black ordering: the
    /// pixels of one colour depend only on the other's, so their updates are independent).
    fn sor_half_sweep(&mut self, omega: f32, colour: usize) {
        let w = self.w;
        for y in 1..=self.h {
            // Rows y − 1, y, y + 1 of the increments; only row y is written.
            let (up, row, down) = self.increment.around_mut(y);
            let coefficients = self.coefficients.row(y);
            let coefficients_up = self.coefficients.row(y - 1);
            // Column x = 1 opens the padded row; start at the first pixel of this colour.
            let mut x = 1 + usize::from((1 + y) % 2 != colour);
            while x <= w {
                let c = coefficients[x];
                let (wl, wu) = (coefficients[x - 1].wx, coefficients_up[x].wy);
                let (l, r, u, d) = (row[x - 1], row[x + 1], up[x], down[x]);
                let nu = (wl * l[0] + c.wx * r[0]) + (wu * u[0] + c.wy * d[0]);
                let nv = (wl * l[1] + c.wx * r[1]) + (wu * u[1] + c.wy * d[1]);
                let [du, dv] = row[x];
                let du = du + omega * ((c.rhs_u + nu - c.a12 * dv) * c.inv_u - du);
                let dv = dv + omega * ((c.rhs_v + nv - c.a12 * du) * c.inv_v - dv);
                row[x] = [du, dv];
                x += 2;
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
    fn refinement_removes_noise_from_a_correct_flow() {
        // The true flow is (1, 0); start from it plus ±0.4 px of seeded noise per pixel.
        let (w, h) = (48, 40);
        let (a, b) = (texture(w, h, 0.0), texture(w, h, 1.0));
        let mut rng = crate::rng::Rng::new(7);
        let mut noise = || 0.8 * (rng.uniform() as f32 - 0.5);
        let u: Vec<f32> = (0..w * h).map(|_| 1.0 + noise()).collect();
        let v: Vec<f32> = (0..w * h).map(|_| noise()).collect();
        let mean_error = |u: &[f32], v: &[f32]| {
            let inner = (4..h - 4).flat_map(|y| (4..w - 4).map(move |x| y * w + x));
            let n = ((w - 8) * (h - 8)) as f32;
            inner.map(|i| (u[i] - 1.0).hypot(v[i])).sum::<f32>() / n
        };
        let before = mean_error(&u, &v);
        let (u, v) = refine(&a, &b, u, v, &VariationalParams::default());
        let after = mean_error(&u, &v);
        assert!(
            before > 0.2 && after < 0.05,
            "mean error {before} → {after}"
        );
    }

    /// The constancy equations of every pixel from whole w × h arrays, written out plainly:
    /// the reference for the row-at-a-time [`Derivatives::equations`].
    fn equations_from_whole_arrays(
        from: &Level,
        to: &Level,
        u: &[f32],
        v: &[f32],
    ) -> Vec<Constancy> {
        let (w, h) = (from.width, from.height);
        let at = |f: &[f32], x: usize, y: usize| f[y * w + x];
        let dx = |f: &[f32]| -> Vec<f32> {
            (0..w * h)
                .map(|i| match (i % w, i / w) {
                    (0, y) => at(f, 1, y) - at(f, 0, y),
                    (x, y) if x == w - 1 => at(f, x, y) - at(f, x - 1, y),
                    (x, y) => 0.5 * (at(f, x + 1, y) - at(f, x - 1, y)),
                })
                .collect()
        };
        let dy = |f: &[f32]| -> Vec<f32> {
            (0..w * h)
                .map(|i| match (i % w, i / w) {
                    (x, 0) => (at(f, x, 1) - at(f, x, 0)) * 1.0,
                    (x, y) if y == h - 1 => (at(f, x, y) - at(f, x, y - 1)) * 1.0,
                    (x, y) => (at(f, x, y + 1) - at(f, x, y - 1)) * 0.5,
                })
                .collect()
        };
        let warped: Vec<f32> = (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as f32 + u[i], (i / w) as f32 + v[i]);
                sample_clamped(&to.pixels, w, h, x, y)
            })
            .collect();
        let mean: Vec<f32> = (0..w * h)
            .map(|i| 0.5 * (from.pixels[i] + warped[i]))
            .collect();
        let iz: Vec<f32> = (0..w * h).map(|i| warped[i] - from.pixels[i]).collect();
        let (ix, iy) = (dx(&mean), dy(&mean));
        let (ixx, ixy, iyy, ixz, iyz) = (dx(&ix), dy(&ix), dy(&iy), dx(&iz), dy(&iz));
        (0..w * h)
            .map(|i| {
                let (tx, ty) = ((i % w) as f32 + u[i], (i / w) as f32 + v[i]);
                if !(0.0..=(w - 1) as f32).contains(&tx) || !(0.0..=(h - 1) as f32).contains(&ty) {
                    return [0.0; 9];
                }
                let b = 1.0 / (ix[i] * ix[i] + iy[i] * iy[i] + ZETA_SQ).sqrt();
                let gx = 1.0 / (ixx[i] * ixx[i] + ixy[i] * ixy[i] + ZETA_SQ).sqrt();
                let gy = 1.0 / (iyy[i] * iyy[i] + ixy[i] * ixy[i] + ZETA_SQ).sqrt();
                [
                    ix[i] * b,
                    iy[i] * b,
                    iz[i] * b,
                    ixx[i] * gx,
                    ixy[i] * gx,
                    ixz[i] * gx,
                    ixy[i] * gy,
                    iyy[i] * gy,
                    iyz[i] * gy,
                ]
            })
            .collect()
    }

    #[test]
    fn equations_made_row_by_row_are_those_of_whole_arrays_bit_for_bit() {
        // A flow that carries some pixels out of frame 2, on a small and a two-row level, with
        // the rows asked for top to bottom twice (two fixed-point iterations), then every other
        // row bottom to top (rows held from other rows' requests must be the right ones).
        for (w, h) in [(37, 23), (9, 2), (2, 3)] {
            let (a, b) = (texture(w, h, 0.0), texture(w, h, 1.5));
            let mut rng = crate::rng::Rng::new(11);
            let flow: Vec<[f32; 2]> = (0..w * h)
                .map(|_| {
                    [
                        6.0 * (rng.uniform() as f32 - 0.3),
                        4.0 * (rng.uniform() as f32 - 0.5),
                    ]
                })
                .collect();
            let (u, v): (Vec<f32>, Vec<f32>) = flow.iter().map(|f| (f[0], f[1])).unzip();
            let expected = equations_from_whole_arrays(&a, &b, &u, &v);
            let outside = expected.iter().filter(|e| **e == [0.0; 9]).count();
            assert!(
                outside > 0 && outside < w * h,
                "{outside} pixels carried out"
            );
            let mut derivatives = Derivatives::new(&a, &b);
            let base = |r: usize| &flow[r * w..][..w];
            let mut row = vec![[0.0; 9]; w];
            let order: Vec<usize> = (0..h).chain(0..h).chain((0..h).rev().step_by(2)).collect();
            for y in order {
                derivatives.equations(y, base, &mut row);
                for (x, (got, want)) in row.iter().zip(&expected[y * w..][..w]).enumerate() {
                    let (got, want) = (got.map(f32::to_bits), want.map(f32::to_bits));
                    assert_eq!(got, want, "{w}×{h}, pixel ({x}, {y})");
                }
            }
        }
    }

    #[test]
    fn the_padded_base_flow_rows_are_the_input_rows() {
        let (w, h) = (5, 3);
        let u: Vec<f32> = (0..w * h).map(|i| i as f32).collect();
        let v: Vec<f32> = (0..w * h).map(|i| -(i as f32)).collect();
        let system = System::new(w, h, u.clone(), v.clone());
        for r in 0..h {
            let row: Vec<[f32; 2]> = (0..w).map(|x| [u[r * w + x], v[r * w + x]]).collect();
            assert_eq!(base_row(&system.flow, w, r), &row[..], "row {r}");
        }
    }

    #[test]
    fn identical_images_keep_zero_flow_and_flat_ones_stay_finite() {
        let a = texture(20, 16, 0.0);
        let zero = || vec![0.0; 320];
        let (u, v) = refine(&a, &a, zero(), zero(), &VariationalParams::default());
        assert!(u.iter().chain(&v).all(|&f| f == 0.0));
        let flat = Level::new(20, 16, vec![7.0; 320]);
        let bright = Level::new(20, 16, vec![90.0; 320]);
        let (u, v) = refine(&flat, &bright, u, v, &VariationalParams::default());
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
