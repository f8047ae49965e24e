//! Two-view geometry on normalised image coordinates x̄ = K⁻¹ [u, v, 1]ᵀ (so every function here
//! is independent of the intrinsics):
//! - [`essential`]: the normalised 8-point essential matrix, its decomposition into (R, t̂) with
//!   the cheirality test, and the Sampson error;
//! - [`five_point`]: the minimal five-point essential matrix (also valid for planar points);
//! - [`homography`]: plane-induced homographies (normalised DLT) and their decomposition into
//!   motion and plane;
//! - [`ransac`]: seeded RANSAC over any model;
//! - [`triangulate`]: depths of a correspondence under a known motion.
//!
//! Motion convention (docs/ARCHITECTURE.md, Conventions): a point X in camera 1 is `R X + t` in
//! camera 2, so x̄'ᵀ E x̄ = 0 with E = \[t\]ₓ R.

pub mod essential;
pub mod five_point;
pub mod homography;
pub mod ransac;
pub mod triangulate;

use crate::numeric::hypot;
use nalgebra::{Matrix3, SMatrix, SymmetricEigen, Vector3};

/// A correspondence in normalised coordinates: x̄ in frame 1 and x̄' in frame 2 (z = 1 each).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Correspondence {
    pub x1: Vector3<f64>,
    pub x2: Vector3<f64>,
}

/// The cross-product matrix \[v\]ₓ, with \[v\]ₓ w = v × w.
pub fn skew(v: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -v.z, v.y, v.z, 0.0, -v.x, -v.y, v.x, 0.0)
}

/// The direct linear transform shared by the linear estimators: each correspondence gives `R`
/// rows of a homogeneous system in the nine entries of a 3×3 matrix M (row by row), written by
/// `rows(a, b)` for the Hartley-conditioned points a = T₁ x̄, b = T₂ x̄'. Returns M (the
/// eigenvector of AᵀA with the smallest eigenvalue, so ‖M‖ = 1) with T₁ and T₂, for the caller
/// to undo the conditioning. `None` for non-finite input or when the null space has more than
/// one dimension (a degenerate configuration: the points do not determine M).
pub(crate) fn dlt<const R: usize>(
    points: &[Correspondence],
    rows: impl Fn(&Vector3<f64>, &Vector3<f64>) -> [[f64; 9]; R],
) -> Option<(Matrix3<f64>, Matrix3<f64>, Matrix3<f64>)> {
    let t1 = conditioning(points.iter().map(|c| c.x1));
    let t2 = conditioning(points.iter().map(|c| c.x2));
    let mut ata = SMatrix::<f64, 9, 9>::zeros();
    for c in points {
        for row in rows(&(t1 * c.x1), &(t2 * c.x2)) {
            let row = SMatrix::<f64, 9, 1>::from_column_slice(&row);
            ata += row * row.transpose();
        }
    }
    if ata.iter().any(|v| !v.is_finite()) {
        return None;
    }
    let eigen = SymmetricEigen::new(ata);
    let mut order: Vec<usize> = (0..9).collect();
    order.sort_by(|&i, &j| eigen.eigenvalues[i].total_cmp(&eigen.eigenvalues[j]));
    if eigen.eigenvalues[order[1]] <= 1e-10 * eigen.eigenvalues[order[8]].max(1e-300) {
        return None;
    }
    let m = eigen.eigenvectors.column(order[0]);
    let m = Matrix3::new(m[0], m[1], m[2], m[3], m[4], m[5], m[6], m[7], m[8]);
    Some((m, t1, t2))
}

/// The similarity that moves `points` (z = 1) to their centroid and scales them to a mean
/// distance of √2 from it (Hartley's conditioning for the linear estimators).
pub(crate) fn conditioning(points: impl Iterator<Item = Vector3<f64>> + Clone) -> Matrix3<f64> {
    let n = points.clone().count().max(1) as f64;
    let (cx, cy) = points
        .clone()
        .fold((0.0, 0.0), |(x, y), p| (x + p.x, y + p.y));
    let (cx, cy) = (cx / n, cy / n);
    let mean = points.map(|p| hypot(p.x - cx, p.y - cy)).sum::<f64>() / n;
    let s = if mean > 1e-12 {
        std::f64::consts::SQRT_2 / mean
    } else {
        1.0
    };
    Matrix3::new(s, 0.0, -s * cx, 0.0, s, -s * cy, 0.0, 0.0, 1.0)
}
