//! Depths of a correspondence under a known motion.

use nalgebra::{Matrix3, Vector3};

use super::Correspondence;

/// Depths (z₁, z₂) with `z₂ x̄' ≈ R (z₁ x̄) + t` in the least-squares sense (the midpoint method
/// in depth form). `None` when the rays are parallel (no parallax along this correspondence).
pub fn depths(c: &Correspondence, r: &Matrix3<f64>, t: &Vector3<f64>) -> Option<(f64, f64)> {
    // [R x̄, −x̄'] [z₁, z₂]ᵀ = −t, solved by its 2 × 2 normal equations.
    let a = r * c.x1;
    let b = -c.x2;
    let (aa, ab, bb) = (a.dot(&a), a.dot(&b), b.dot(&b));
    let det = aa * bb - ab * ab;
    if det.abs() < 1e-12 * aa * bb {
        return None;
    }
    let (ra, rb) = (-a.dot(t), -b.dot(t));
    let z1 = (bb * ra - ab * rb) / det;
    let z2 = (aa * rb - ab * ra) / det;
    Some((z1, z2))
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Rotation3;

    #[test]
    fn recovers_exact_depths() {
        let r = Rotation3::from_euler_angles(0.02, -0.05, 0.01).into_inner();
        let t = Vector3::new(0.3, -0.1, 0.05);
        let x = Vector3::new(0.4, -0.7, 4.0);
        let x2 = r * x + t;
        let c = Correspondence {
            x1: x / x.z,
            x2: x2 / x2.z,
        };
        let (z1, z2) = depths(&c, &r, &t).unwrap();
        assert!((z1 - 4.0).abs() < 1e-9 && (z2 - x2.z).abs() < 1e-9);
        assert!(
            depths(&c, &r, &Vector3::zeros()).is_none()
                || depths(&c, &r, &Vector3::zeros()).unwrap().0.abs() < 1e-6
        );
    }
}
