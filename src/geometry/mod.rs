//! Two-view geometry on normalised image coordinates x̄ = K⁻¹ [u, v, 1]ᵀ (so every function here
//! is independent of the intrinsics):
//! - [`essential`]: the normalised 8-point essential matrix, its decomposition into (R, t̂) with the
//!   cheirality test, and the Sampson error;
//! - [`ransac`]: seeded RANSAC over any model;
//! - [`triangulate`]: depths of a correspondence under a known motion.
//!
//! Motion convention (DESIGN.md): a point X in camera 1 is `R X + t` in camera 2, so
//! x̄'ᵀ E x̄ = 0 with E = [t]ₓ R.

pub mod essential;
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
