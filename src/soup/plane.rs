//! A superpixel's plane under a given motion, and how well the pair explains its flow.
//!
//! Under a motion (R, t̂) a pixel on the plane mᵀX = 1 moves to x̄' ∝ R x̄ + t̂ (mᵀx̄), so
//! [x̄']ₓ t̂ (x̄ᵀm) = −[x̄']ₓ R x̄ (docs/ARCHITECTURE.md, The soup): three equations, linear in
//! m, per correspondence. With a = x̄' × t̂ and b = −x̄' × R x̄ they read a (x̄ᵀm) = b, whose
//! least-squares solution weighs each point by its parallax |a|²: Σ |a|² x̄ x̄ᵀ m = Σ (a·b) x̄.

use nalgebra::{Matrix3, Vector3};

use super::Degeneracy;
use crate::geometry::Correspondence;
use crate::geometry::essential::Motion;
use crate::numeric::min;

/// The normal equations of the plane for `points` under `motion`, each point weighted.
fn normal_equations(
    points: &[Correspondence],
    motion: &Motion,
    weights: impl Iterator<Item = f64>,
) -> (Matrix3<f64>, Vector3<f64>) {
    let (mut ata, mut atb) = (Matrix3::zeros(), Vector3::zeros());
    for (c, w) in points.iter().zip(weights) {
        let a = c.x2.cross(&motion.t);
        let b = -c.x2.cross(&(motion.r * c.x1));
        ata += c.x1 * c.x1.transpose() * (w * a.norm_squared());
        atb += c.x1 * (w * a.dot(&b));
    }
    (ata, atb)
}

/// Algebraic residual ‖a (x̄ᵀm) − b‖ of one correspondence.
fn residual(c: &Correspondence, motion: &Motion, m: &Vector3<f64>) -> f64 {
    let a = c.x2.cross(&motion.t);
    let b = -c.x2.cross(&(motion.r * c.x1));
    (a * c.x1.dot(m) - b).norm()
}

/// Distance in normalised units between x̄' and the transfer of x̄ by the homography R + t̂ mᵀ.
pub fn transfer_error(c: &Correspondence, motion: &Motion, m: &Vector3<f64>) -> f64 {
    let p = motion.r * c.x1 + motion.t * m.dot(&c.x1);
    if p.z <= 1e-12 {
        return f64::INFINITY;
    }
    // Not `hypot`: normalised coordinates cannot overflow, and hypot is a slow libm call (on
    // wasm32 3 % of the page's run time, from the refinement's E_proj).
    let (dx, dy) = (p.x / p.z - c.x2.x, p.y / p.z - c.x2.y);
    (dx * dx + dy * dy).sqrt()
}

/// How well `motion` with its best plane explains `points`: the least-squares plane (slightly
/// regularised, so a patch without parallax still gets one), then the mean transfer error in
/// pixels (`focal` converts), each point's error capped at `cap_px`. A point the plane puts
/// behind either camera costs `cap_px` (cheirality: a motion may not explain the flow with
/// negative depths). `cap_px` for no points.
pub fn planar_cost(points: &[Correspondence], motion: &Motion, focal: f64, cap_px: f64) -> f64 {
    if points.is_empty() {
        return cap_px;
    }
    let (ata, atb) = normal_equations(points, motion, std::iter::repeat(1.0));
    let ridge = 1e-12 * ata.trace().max(1e-300);
    let Some(inverse) = (ata + Matrix3::identity() * ridge).try_inverse() else {
        return cap_px;
    };
    mean_transfer_px(points, motion, &(inverse * atb), focal, cap_px)
}

/// The mean transfer error in pixels (`focal` converts) of `points` under `motion` and the
/// plane `m` (at the motion's translation), each point's error capped at `cap_px`; a point the
/// plane puts behind either camera costs `cap_px`. `cap_px` for no points.
pub fn mean_transfer_px(
    points: &[Correspondence],
    motion: &Motion,
    m: &Vector3<f64>,
    focal: f64,
    cap_px: f64,
) -> f64 {
    if points.is_empty() {
        return cap_px;
    }
    points
        .iter()
        .map(|c| {
            let e = transfer_error(c, motion, m) * focal;
            if e.is_finite() && m.dot(&c.x1) > 0.0 {
                min(e, cap_px)
            } else {
                cap_px
            }
        })
        .sum::<f64>()
        / points.len() as f64
}

/// The plane m (mᵀX = 1, at the motion's unit translation) through `points` under `motion`, by
/// iteratively reweighted least squares with Cauchy weights. `focal` (px) converts
/// `min_parallax_px`: the mean image displacement the translation must cause for the depth to
/// count as observed.
///
/// Errors: [`Degeneracy::TooFewPixels`] for fewer than 8 points, [`Degeneracy::NoParallax`]
/// when the points do not constrain the plane (near the epipole, or less translation parallax
/// than `min_parallax_px`: the rotation alone explains them, as for a pure camera rotation),
/// [`Degeneracy::NegativeDepth`] when the plane puts more than a quarter of them behind camera 1.
pub fn fit_plane(
    points: &[Correspondence],
    motion: &Motion,
    focal: f64,
    min_parallax_px: f64,
) -> Result<Vector3<f64>, Degeneracy> {
    if points.len() < 8 {
        return Err(Degeneracy::TooFewPixels);
    }
    let mut weights = vec![1.0; points.len()];
    let mut m = Vector3::zeros();
    for _ in 0..4 {
        let (ata, atb) = normal_equations(points, motion, weights.iter().copied());
        let eig = ata.symmetric_eigenvalues();
        let (lo, hi) = (eig.min(), eig.max());
        if hi.is_nan() || hi <= 0.0 || lo < 1e-9 * hi {
            return Err(Degeneracy::NoParallax);
        }
        m = ata.try_inverse().ok_or(Degeneracy::NoParallax)? * atb;
        let residuals: Vec<f64> = points.iter().map(|c| residual(c, motion, &m)).collect();
        let mut sorted = residuals.clone();
        sorted.sort_by(f64::total_cmp);
        let sigma = (1.4826 * sorted[sorted.len() / 2]).max(1e-9) * 2.0;
        weights = residuals
            .iter()
            .map(|r| 1.0 / (1.0 + (r / sigma).powi(2)))
            .collect();
    }
    let parallax = points
        .iter()
        .map(|c| transfer_error(c, motion, &Vector3::zeros()) - transfer_error(c, motion, &m))
        .map(|gain| if gain.is_finite() { gain } else { 0.0 })
        .sum::<f64>()
        / points.len() as f64;
    if parallax * focal < min_parallax_px {
        return Err(Degeneracy::NoParallax);
    }
    let behind = points.iter().filter(|c| m.dot(&c.x1) <= 0.0).count();
    if behind * 4 > points.len() {
        return Err(Degeneracy::NegativeDepth);
    }
    Ok(m)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;
    use nalgebra::Rotation3;

    fn motion() -> Motion {
        Motion {
            r: Rotation3::from_euler_angles(0.01, 0.02, 0.0).into_inner(),
            t: Vector3::new(1.0, 0.1, 0.2).normalize(),
        }
    }

    /// Correspondences of the plane `m` (at unit translation) seen in a small patch.
    fn patch(motion: &Motion, m: &Vector3<f64>, rng: &mut Rng) -> Vec<Correspondence> {
        (0..40)
            .map(|_| {
                let ray = Vector3::new(0.1 + 0.04 * rng.uniform(), 0.04 * rng.uniform(), 1.0);
                let x = ray / m.dot(&ray);
                let x2 = motion.r * x + motion.t;
                Correspondence {
                    x1: ray,
                    x2: x2 / x2.z,
                }
            })
            .collect()
    }

    #[test]
    fn recovers_a_slanted_plane_and_explains_it_exactly() {
        let mv = motion();
        let m = Vector3::new(0.02, -0.03, 0.1);
        let pts = patch(&mv, &m, &mut Rng::new(1));
        let got = fit_plane(&pts, &mv, 800.0, 0.1).unwrap();
        assert!((got - m).norm() < 1e-9, "{got:?}");
        let cost = planar_cost(&pts, &mv, 800.0, 3.0);
        assert!(cost < 1e-6, "{cost}");
        assert!(pts.iter().all(|c| transfer_error(c, &mv, &m) < 1e-12));
    }

    #[test]
    fn a_wrong_motion_explains_the_patch_worse() {
        let mv = motion();
        let m = Vector3::new(0.02, -0.03, 0.1);
        let pts = patch(&mv, &m, &mut Rng::new(2));
        let wrong = Motion {
            r: Rotation3::from_euler_angles(0.0, 0.05, 0.0).into_inner(),
            t: Vector3::new(0.0, 0.0, 1.0),
        };
        assert!(planar_cost(&pts, &wrong, 800.0, 3.0) > 0.5);
    }

    #[test]
    fn degenerate_patches_are_flagged() {
        let mv = motion();
        let pts = patch(&mv, &Vector3::new(0.0, 0.0, 0.1), &mut Rng::new(3));
        assert_eq!(
            fit_plane(&pts[..5], &mv, 800.0, 0.1),
            Err(Degeneracy::TooFewPixels)
        );
        // A pure rotation: the flow says nothing about depth.
        let turned: Vec<Correspondence> = pts
            .iter()
            .map(|c| {
                let x2 = mv.r * c.x1;
                Correspondence {
                    x1: c.x1,
                    x2: x2 / x2.z,
                }
            })
            .collect();
        assert_eq!(
            fit_plane(&turned, &mv, 800.0, 0.1),
            Err(Degeneracy::NoParallax)
        );
    }
}
