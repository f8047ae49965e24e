//! Two-view geometry on normalised image coordinates x̄ = K⁻¹ [u, v, 1]ᵀ (so every function here
//! is independent of the intrinsics):
//! - [`essential`]: the normalised 8-point essential matrix, its decomposition into (R, t̂) with the
//!   cheirality test, and the Sampson error;
//! - [`five_point`]: the minimal five-point essential matrix (also valid for planar points);
//! - [`homography`]: plane-induced homographies (normalised DLT) and their decomposition into
//!   motion and plane;
//! - [`ransac`]: seeded RANSAC over any model;
//! - [`triangulate`]: depths of a correspondence under a known motion.
//!
//! Motion convention (DESIGN.md): a point X in camera 1 is `R X + t` in camera 2, so
//! x̄'ᵀ E x̄ = 0 with E = [t]ₓ R.

pub mod essential;
pub mod five_point;
pub mod homography;
pub mod ransac;
pub mod triangulate;

use nalgebra::{Matrix3, Vector3};

/// A correspondence in normalised coordinates: x̄ in frame 1 and x̄' in frame 2 (z = 1 each).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Correspondence {
    pub x1: Vector3<f64>,
    pub x2: Vector3<f64>,
}

/// The cross-product matrix [v]ₓ, with [v]ₓ w = v × w.
pub fn skew(v: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -v.z, v.y, v.z, 0.0, -v.x, -v.y, v.x, 0.0)
}

/// The similarity that moves `points` (z = 1) to their centroid and scales them to a mean
/// distance of √2 from it (Hartley's conditioning for the linear estimators).
pub(crate) fn conditioning(points: impl Iterator<Item = Vector3<f64>> + Clone) -> Matrix3<f64> {
    let n = points.clone().count().max(1) as f64;
    let (cx, cy) = points
        .clone()
        .fold((0.0, 0.0), |(x, y), p| (x + p.x, y + p.y));
    let (cx, cy) = (cx / n, cy / n);
    let mean = points.map(|p| (p.x - cx).hypot(p.y - cy)).sum::<f64>() / n;
    let s = if mean > 1e-12 {
        std::f64::consts::SQRT_2 / mean
    } else {
        1.0
    };
    Matrix3::new(s, 0.0, -s * cx, 0.0, s, -s * cy, 0.0, 0.0, 1.0)
}
