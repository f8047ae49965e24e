//! Plane-induced homographies on normalised coordinates: estimation by the normalised DLT and
//! decomposition into motion and plane.
//!
//! Convention (docs/ARCHITECTURE.md, Homography sign): points X on the plane mᵀX = 1 (m = n/d)
//! move by X' = R X + t, so X' = (R + t mᵀ) X and x̄' ∝ H x̄ with H = R + t mᵀ.
//! (Hartley–Zisserman write R − t nᵀ/d for their plane nᵀX + d = 0; the two agree with n ↦ −n.)

use nalgebra::{Matrix3, SymmetricEigen, Vector3};

use super::essential::Motion;
use super::{Correspondence, dlt};

/// Least-squares homography with x̄' ∝ H x̄ from ≥ 4 correspondences (direct linear transform on
/// Hartley-conditioned points), scaled to unit Frobenius norm. `None` for fewer than four points
/// or a degenerate configuration (e.g. three of four points on a line).
pub fn homography_dlt(points: &[Correspondence]) -> Option<Matrix3<f64>> {
    if points.len() < 4 {
        return None;
    }
    // Two independent rows of b × (H a) = 0 per correspondence, H flattened row by row.
    let (h, t1, t2) = dlt(points, |a, b| {
        [
            [
                0.0,
                0.0,
                0.0,
                -b.z * a.x,
                -b.z * a.y,
                -b.z * a.z,
                b.y * a.x,
                b.y * a.y,
                b.y * a.z,
            ],
            [
                b.z * a.x,
                b.z * a.y,
                b.z * a.z,
                0.0,
                0.0,
                0.0,
                -b.x * a.x,
                -b.x * a.y,
                -b.x * a.z,
            ],
        ]
    })?;
    let h = t2.try_inverse()? * h * t1;
    let norm = h.norm();
    (norm > 0.0 && h.iter().all(|v| v.is_finite())).then(|| h / norm)
}

/// One reading of a homography: the motion (unit translation) and the plane m at that scale.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlanarMotion {
    pub motion: Motion,
    /// The plane mᵀX = 1 in camera 1, at the scale where ‖t‖ = 1.
    pub m: Vector3<f64>,
}

/// The physically valid decompositions of H ∝ R + t mᵀ (Faugeras' SVD method as in Ma, Soatto,
/// Košecká, Sastry, "An Invitation to 3-D Vision", §5.3): H is scaled so its middle singular
/// value is 1 and signed so the points lie in front of camera 2, then of the four candidates
/// those with every point in front of camera 1 (mᵀx̄ > 0) are kept: usually two.
/// Empty when H has no translation part (σ₁ ≈ σ₃: a pure rotation, no parallax) or is
/// degenerate.
pub fn decompose_homography(h: &Matrix3<f64>, points: &[Correspondence]) -> Vec<PlanarMotion> {
    let svd = h.svd(false, false);
    let mut sv: Vec<f64> = svd.singular_values.iter().copied().collect();
    sv.sort_by(|a, b| b.total_cmp(a));
    if sv[1].is_nan() || sv[1] <= 0.0 || points.is_empty() {
        return Vec::new();
    }
    let mut h = h / sv[1];
    // Sign: depths in both views are positive, so x̄'ᵀ H x̄ > 0 for (most) points.
    let positive = points
        .iter()
        .filter(|c| c.x2.dot(&(h * c.x1)) > 0.0)
        .count();
    if positive * 2 < points.len() {
        h = -h;
    }
    let eigen = SymmetricEigen::new(h.transpose() * h);
    let mut order = [0usize, 1, 2];
    order.sort_by(|&i, &j| eigen.eigenvalues[j].total_cmp(&eigen.eigenvalues[i]));
    let (s1, s3) = (eigen.eigenvalues[order[0]], eigen.eigenvalues[order[2]]);
    if s1 - s3 < 1e-9 {
        return Vec::new(); // H is a rotation: no translation, no plane
    }
    let mut v = Matrix3::from_columns(&[
        eigen.eigenvectors.column(order[0]).into_owned(),
        eigen.eigenvectors.column(order[1]).into_owned(),
        eigen.eigenvectors.column(order[2]).into_owned(),
    ]);
    if v.determinant() < 0.0 {
        v = -v;
    }
    let (v1, v2, v3) = (
        v.column(0).into_owned(),
        v.column(1).into_owned(),
        v.column(2).into_owned(),
    );
    let a = (1.0 - s3).max(0.0).sqrt();
    let b = (s1 - 1.0).max(0.0).sqrt();
    let norm = (s1 - s3).sqrt();
    let mut out = Vec::new();
    for u in [(a * v1 + b * v3) / norm, (a * v1 - b * v3) / norm] {
        let n = v2.cross(&u);
        let frame_u = Matrix3::from_columns(&[v2, u, n]);
        let (hv2, hu) = (h * v2, h * u);
        let frame_w = Matrix3::from_columns(&[hv2, hu, hv2.cross(&hu)]);
        let r = frame_w * frame_u.transpose();
        // t mᵀ = H − R with m ∥ n: t_over_d = (H − R) n (n unit).
        let t_over_d = (h - r) * n;
        for sign in [1.0, -1.0] {
            let (n, t_over_d) = (n * sign, t_over_d * sign);
            let scale = t_over_d.norm();
            if scale < 1e-12 {
                continue;
            }
            let m = n * scale;
            let in_front = points.iter().filter(|c| m.dot(&c.x1) > 0.0).count();
            if in_front * 10 >= points.len() * 9 {
                out.push(PlanarMotion {
                    motion: Motion {
                        r,
                        t: t_over_d / scale,
                    },
                    m,
                });
            }
        }
    }
    out
}

/// Reprojection error in normalised units: the distance between x̄' and the dehomogenised H x̄
/// (infinite when H sends the point to infinity).
pub fn transfer_error(h: &Matrix3<f64>, c: &Correspondence) -> f64 {
    let p = h * c.x1;
    if p.z.abs() < 1e-12 {
        return f64::INFINITY;
    }
    // Not `hypot`: normalised coordinates cannot overflow, and hypot is a slow libm call (on
    // wasm32 3 % of the page's run time, from the refinement's E_proj).
    let (dx, dy) = (p.x / p.z - c.x2.x, p.y / p.z - c.x2.y);
    (dx * dx + dy * dy).sqrt()
}

/// The homography R + t mᵀ of a motion and a plane.
pub fn plane_homography(motion: &Motion, m: &Vector3<f64>) -> Matrix3<f64> {
    motion.r + motion.t * m.transpose()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;
    use nalgebra::Rotation3;

    fn truth() -> PlanarMotion {
        PlanarMotion {
            motion: Motion {
                r: Rotation3::from_euler_angles(0.03, -0.02, 0.01).into_inner(),
                t: Vector3::new(0.5, 0.1, 0.2).normalize(),
            },
            // The plane −0.2 x + 0.1 y + z = 6, as m = n/d with ‖t‖ = 1.
            m: Vector3::new(-0.2, 0.1, 1.0) / 6.0,
        }
    }

    fn points(p: &PlanarMotion, n: usize, noise: f64, rng: &mut Rng) -> Vec<Correspondence> {
        (0..n)
            .map(|_| {
                let ray = Vector3::new(rng.uniform() - 0.5, rng.uniform() * 0.6 - 0.3, 1.0);
                let x = ray / p.m.dot(&ray);
                let x2 = p.motion.r * x + p.motion.t;
                let jitter = |rng: &mut Rng| Vector3::new(rng.normal(), rng.normal(), 0.0) * noise;
                Correspondence {
                    x1: ray + jitter(rng),
                    x2: x2 / x2.z + jitter(rng),
                }
            })
            .collect()
    }

    #[test]
    fn the_plane_convention_maps_plane_points() {
        // x̄' ∝ (R + t mᵀ) x̄ exactly for points on mᵀX = 1: the sign test that
        // docs/ARCHITECTURE.md (Homography sign) asks for.
        let p = truth();
        let h = plane_homography(&p.motion, &p.m);
        for c in points(&p, 20, 0.0, &mut Rng::new(1)) {
            assert!(transfer_error(&h, &c) < 1e-12);
        }
    }

    #[test]
    fn dlt_recovers_the_homography_from_noisy_points() {
        let p = truth();
        let exact = plane_homography(&p.motion, &p.m);
        let exact = exact / exact.norm();
        let pts = points(&p, 200, 0.3 / 800.0, &mut Rng::new(2));
        let h = homography_dlt(&pts).unwrap();
        let err = (h - exact).norm().min((h + exact).norm());
        assert!(err < 5e-3, "{err}");
        let mean_px = pts.iter().map(|c| transfer_error(&h, c)).sum::<f64>() / 200.0 * 800.0;
        assert!(mean_px < 0.6, "{mean_px}");
    }

    #[test]
    fn decomposition_contains_the_true_motion_and_plane() {
        let p = truth();
        let pts = points(&p, 50, 0.0, &mut Rng::new(3));
        let h = homography_dlt(&pts).unwrap() * -3.7; // any scale and sign
        let readings = decompose_homography(&h, &pts);
        assert!(!readings.is_empty() && readings.len() <= 2, "{readings:?}");
        let best = readings
            .iter()
            .map(|q| {
                (q.motion.r - p.motion.r).norm()
                    + (q.motion.t - p.motion.t).norm()
                    + (q.m - p.m).norm()
            })
            .fold(f64::INFINITY, f64::min);
        assert!(best < 1e-8, "{best}");
        for q in &readings {
            // Every reading reproduces the homography.
            let hq = plane_homography(&q.motion, &q.m);
            assert!(pts.iter().all(|c| transfer_error(&hq, c) < 1e-9));
        }
    }

    #[test]
    fn pure_rotation_has_no_decomposition() {
        let r = Rotation3::from_euler_angles(0.02, 0.05, 0.0).into_inner();
        let pts: Vec<Correspondence> = (0..12)
            .map(|i| {
                let x1 = Vector3::new(0.1 * (i % 4) as f64 - 0.2, 0.1 * (i / 4) as f64, 1.0);
                let x2 = r * x1;
                Correspondence { x1, x2: x2 / x2.z }
            })
            .collect();
        let h = homography_dlt(&pts).unwrap();
        assert!(decompose_homography(&h, &pts).is_empty());
    }

    #[test]
    fn too_few_or_collinear_points_give_none() {
        let c = |x: f64, y: f64| Correspondence {
            x1: Vector3::new(x, y, 1.0),
            x2: Vector3::new(x + 0.01, y, 1.0),
        };
        assert!(homography_dlt(&[c(0.0, 0.0), c(0.1, 0.0), c(0.0, 0.1)]).is_none());
        let line: Vec<Correspondence> = (0..6).map(|i| c(0.1 * i as f64, 0.0)).collect();
        assert!(homography_dlt(&line).is_none());
    }
}
