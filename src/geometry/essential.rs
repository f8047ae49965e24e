//! The essential matrix E = \[t\]ₓ R on normalised coordinates (x̄'ᵀ E x̄ = 0): linear estimation,
//! decomposition into a rigid motion with the cheirality test, and the Sampson error.

use nalgebra::{Matrix3, Vector3};

use super::{Correspondence, dlt, skew, triangulate};
use crate::numeric::atan2;

/// A rigid motion X' = R X + t̂ with unit translation direction t̂ (scale unknown).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Motion {
    pub r: Matrix3<f64>,
    pub t: Vector3<f64>,
}

impl Motion {
    /// Its essential matrix [t̂]ₓ R.
    pub fn essential(&self) -> Matrix3<f64> {
        skew(&self.t) * self.r
    }

    /// The angle between its direction of translation and `other`'s (radians, in [0, π]; both
    /// translations non-zero).
    pub fn translation_angle(&self, other: &Motion) -> f64 {
        // atan2(sin, cos): exact near 0, where acos of a cosine near 1 is not.
        let (a, b) = (self.t.normalize(), other.t.normalize());
        atan2(a.cross(&b).norm(), a.dot(&b))
    }

    /// The angle of the rotation R Rₒᵀ between its rotation and `other`'s (radians, in [0, π]).
    pub fn rotation_angle(&self, other: &Motion) -> f64 {
        // A rotation by θ about an axis: its skew part holds 2 sin θ · axis, its trace 1 + 2 cos θ.
        let d = self.r * other.r.transpose();
        let twice_sin = Vector3::new(d.m32 - d.m23, d.m13 - d.m31, d.m21 - d.m12).norm();
        atan2(twice_sin, d.trace() - 1.0)
    }
}

/// Least-squares essential matrix from ≥ 8 correspondences (the 8-point algorithm on normalised
/// coordinates, then projection onto the essential manifold: singular values (1, 1, 0)).
/// `None` for fewer than 8 points or a degenerate configuration.
pub fn eight_point(points: &[Correspondence]) -> Option<Matrix3<f64>> {
    if points.len() < 8 {
        return None;
    }
    // One row per correspondence: b = x̄'ᵀ E a = 0 in E's entries, row by row.
    let (e, t1, t2) = dlt(points, |a, b| {
        [[
            b.x * a.x,
            b.x * a.y,
            b.x * a.z,
            b.y * a.x,
            b.y * a.y,
            b.y * a.z,
            b.z * a.x,
            b.z * a.y,
            b.z * a.z,
        ]]
    })?;
    let e = t2.transpose() * e * t1;
    let svd = e.svd(true, true);
    let (u, v_t) = (svd.u?, svd.v_t?);
    let projected = u * Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, 0.0)) * v_t;
    projected.iter().all(|v| v.is_finite()).then_some(projected)
}

/// The motion behind `e` that puts the most of `points` in front of both cameras (cheirality),
/// among the four (R, ±t̂) candidates. `None` when no candidate has a point in front.
pub fn decompose(e: &Matrix3<f64>, points: &[Correspondence]) -> Option<Motion> {
    let svd = e.svd(true, true);
    let (mut u, mut v_t) = (svd.u?, svd.v_t?);
    if u.determinant() < 0.0 {
        u = -u;
    }
    if v_t.determinant() < 0.0 {
        v_t = -v_t;
    }
    let w = Matrix3::new(0.0, -1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0);
    let t = u.column(2).into_owned();
    let candidates = [
        Motion { r: u * w * v_t, t },
        Motion {
            r: u * w * v_t,
            t: -t,
        },
        Motion {
            r: u * w.transpose() * v_t,
            t,
        },
        Motion {
            r: u * w.transpose() * v_t,
            t: -t,
        },
    ];
    let in_front = |m: &Motion| {
        points
            .iter()
            .filter(|c| {
                triangulate::depths(c, &m.r, &m.t).is_some_and(|(z1, z2)| z1 > 0.0 && z2 > 0.0)
            })
            .count()
    };
    let scores: Vec<usize> = candidates.iter().map(in_front).collect();
    let best = (0..4).max_by_key(|&i| (scores[i], std::cmp::Reverse(i)))?;
    (scores[best] > 0).then_some(candidates[best])
}

/// The minimal solver drawing RANSAC hypotheses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MinimalSolver {
    /// Five points ([`crate::geometry::five_point`]): up to ten candidates per sample, also
    /// valid for points on one plane (a superpixel and its neighbours often are).
    FivePoint,
    /// Eight points, linear: one candidate, degenerate for planar points.
    EightPoint,
}

impl MinimalSolver {
    fn sample_size(self) -> usize {
        match self {
            MinimalSolver::FivePoint => 5,
            MinimalSolver::EightPoint => 8,
        }
    }

    fn solve(self, sample: &[Correspondence]) -> Vec<Matrix3<f64>> {
        match self {
            MinimalSolver::FivePoint => super::five_point::five_point(sample),
            MinimalSolver::EightPoint => eight_point(sample).into_iter().collect(),
        }
    }
}

/// A robust motion from correspondences (normalised coordinates; `focal` in pixels converts the
/// pixel thresholds). Minimal samples are noisy (tens of pixels of error from 0.3 px of noise),
/// so RANSAC scores them with a loose `loose_px` threshold; the winner is then locally optimised
/// while the threshold halves down to `final_px`. At each threshold the candidates are the
/// current motion, that motion polished by Levenberg–Marquardt on its inliers, and the polished
/// winner of an inner RANSAC (larger eight-point samples, or five-point samples, which stay valid
/// on planes) drawn from the points within twice the threshold; the one with the most inliers
/// goes on; on a tie the later one in that order (the inner winner, then the polish), so a
/// polish that loses nothing is kept. (A linear eight-point refit on all the loose inliers, as
/// before, is pulled off by every point that only lies near its epipolar line: in a crowd it
/// returned motions with 2 % of the inliers of the truth.) Returns the motion and the inlier
/// indices at `final_px`, which may be empty: callers that need support check its size. `None`
/// when no sample gives a motion.
pub fn robust_motion(
    points: &[Correspondence],
    focal: f64,
    iterations: usize,
    loose_px: f64,
    final_px: f64,
    solver: MinimalSolver,
    rng: &mut crate::rng::Rng,
) -> Option<(Motion, Vec<usize>)> {
    use super::ransac::{RansacParams, ransac};
    let to_normalised = |px: f64| (px / focal) * (px / focal);
    let params = RansacParams {
        sample_size: solver.sample_size(),
        iterations,
        threshold: to_normalised(loose_px),
    };
    let subset = |idx: &[usize]| idx.iter().map(|&i| points[i]).collect::<Vec<_>>();
    let (e0, inliers) = ransac(
        points.len(),
        None,
        &params,
        rng,
        |s| solver.solve(&subset(s)),
        |e, i| sampson(e, &points[i]),
    )?;
    let count = |m: &Motion, px: f64| {
        let e = m.essential();
        (0..points.len())
            .filter(|&i| sampson(&e, &points[i]) < to_normalised(px))
            .count()
    };
    let within = |m: &Motion, px: f64| -> Vec<Correspondence> {
        let e = m.essential();
        points
            .iter()
            .filter(|c| sampson(&e, c) < to_normalised(px))
            .copied()
            .collect()
    };
    let mut motion = decompose(&e0, &subset(&inliers))?;
    let mut px = loose_px;
    while px > final_px {
        px = (px / 2.0).max(final_px);
        let pool = (0..points.len())
            .filter(|&i| sampson(&motion.essential(), &points[i]) < to_normalised(2.0 * px))
            .collect::<Vec<_>>();
        let inner = RansacParams {
            sample_size: match solver {
                MinimalSolver::FivePoint => 5,
                MinimalSolver::EightPoint => pool.len().min(24),
            },
            iterations: iterations.clamp(10, 30),
            threshold: to_normalised(px),
        };
        let mut candidates = vec![motion, refine_motion(&within(&motion, px), &motion, 8)];
        if let Some((e, next)) = ransac(
            points.len(),
            Some(&pool),
            &inner,
            rng,
            |s| solver.solve(&subset(s)),
            |e, i| sampson(e, &points[i]),
        ) && let Some(m) = decompose(&e, &subset(&next))
        {
            candidates.push(refine_motion(&within(&m, px), &m, 8));
        }
        motion = candidates
            .into_iter()
            .map(|m| (count(&m, px), m))
            .max_by_key(|c| c.0)?
            .1;
    }
    let e = motion.essential();
    let inliers = (0..points.len())
        .filter(|&i| sampson(&e, &points[i]) < to_normalised(final_px))
        .collect();
    Some((motion, inliers))
}

/// Refines a motion by Levenberg–Marquardt on the signed Sampson distances of `points`, starting
/// from `start` (5 parameters: a rotation increment and a move of t̂ on the unit sphere). Staying
/// near the start, it is safe on points from one plane, where a linear re-estimation is
/// degenerate. Returns `start` when it cannot improve.
pub fn refine_motion(points: &[Correspondence], start: &Motion, iterations: usize) -> Motion {
    if points.len() < 5 {
        return *start;
    }
    let residuals = |m: &Motion| -> Vec<f64> {
        let e = m.essential();
        points.iter().map(|c| signed_sampson(&e, c)).collect()
    };
    let cost = |r: &[f64]| r.iter().map(|v| v * v).sum::<f64>();
    let mut current = *start;
    let mut r0 = residuals(&current);
    let mut c0 = cost(&r0);
    let mut damping = 1e-3;
    for _ in 0..iterations {
        let basis = tangent_basis(&current.t);
        let (jtj, jtr) = normal_equations(points, &current, &basis, &r0);
        let mut improved = false;
        for _ in 0..6 {
            let mut m = jtj;
            for a in 0..5 {
                m[(a, a)] += damping * jtj[(a, a)].max(1e-12);
            }
            let Some(delta) = m.lu().solve(&(-jtr)) else {
                break;
            };
            let d: [f64; 5] = std::array::from_fn(|k| delta[k]);
            let candidate = apply(&current, &d, &basis);
            let r = residuals(&candidate);
            let c = cost(&r);
            if c < c0 {
                (current, r0, c0) = (candidate, r, c);
                damping = (damping / 10.0).max(1e-9);
                improved = true;
                break;
            }
            damping *= 10.0;
        }
        if !improved {
            break;
        }
    }
    current
}

/// JᵀJ and Jᵀr of the signed Sampson residuals `r0` of `points` at `motion`, with J the
/// numerical Jacobian over [`apply`]'s 5 parameters (on `basis`, the tangent basis of the
/// motion's t̂; forward differences of 10⁻⁷), summed point by point.
fn normal_equations(
    points: &[Correspondence],
    motion: &Motion,
    basis: &[Vector3<f64>; 2],
    r0: &[f64],
) -> (nalgebra::SMatrix<f64, 5, 5>, nalgebra::SVector<f64, 5>) {
    const STEP: f64 = 1e-7;
    let moved: [Matrix3<f64>; 5] = std::array::from_fn(|k| {
        let mut d = [0.0; 5];
        d[k] = STEP;
        apply(motion, &d, basis).essential()
    });
    let mut jtj = nalgebra::SMatrix::<f64, 5, 5>::zeros();
    let mut jtr = nalgebra::SVector::<f64, 5>::zeros();
    for (c, &r) in points.iter().zip(r0) {
        let j: [f64; 5] = std::array::from_fn(|k| (signed_sampson(&moved[k], c) - r) / STEP);
        for a in 0..5 {
            for b in a..5 {
                jtj[(a, b)] += j[a] * j[b];
            }
            jtr[a] += j[a] * r;
        }
    }
    for a in 0..5 {
        for b in 0..a {
            jtj[(a, b)] = jtj[(b, a)];
        }
    }
    (jtj, jtr)
}

/// Two unit vectors orthogonal to `t` (and to each other).
fn tangent_basis(t: &Vector3<f64>) -> [Vector3<f64>; 2] {
    let t = t.normalize();
    let helper = if t.x.abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    let a = t.cross(&helper).normalize();
    [a, t.cross(&a)]
}

/// The motion moved by `d`: rotation exp([d₀ d₁ d₂]ₓ) R, translation t̂ + d₃ a + d₄ b normalised.
fn apply(m: &Motion, d: &[f64; 5], basis: &[Vector3<f64>; 2]) -> Motion {
    let turn = nalgebra::Rotation3::from_scaled_axis(Vector3::new(d[0], d[1], d[2]));
    Motion {
        r: turn.matrix() * m.r,
        t: (m.t + basis[0] * d[3] + basis[1] * d[4]).normalize(),
    }
}

/// Sampson distance² of a correspondence to the epipolar constraint of `e`, in normalised units
/// (multiply by f² for pixels²).
pub fn sampson(e: &Matrix3<f64>, c: &Correspondence) -> f64 {
    let (num, den) = sampson_parts(e, c);
    sampson_ratio(num, den)
}

/// The signed Sampson distance: √[`sampson`] with the sign of x̄₂ᵀ E x̄₁, 0 where it is not
/// finite. [`refine_motion`]'s residual.
fn signed_sampson(e: &Matrix3<f64>, c: &Correspondence) -> f64 {
    let (num, den) = sampson_parts(e, c);
    let d = sampson_ratio(num, den).sqrt();
    if d.is_finite() { d * num.signum() } else { 0.0 }
}

/// num² / den, infinite where den ≤ 0.
#[inline]
fn sampson_ratio(num: f64, den: f64) -> f64 {
    if den <= 0.0 {
        f64::INFINITY
    } else {
        num * num / den
    }
}

/// The Sampson error's numerator x̄₂ᵀ E x̄₁ and denominator (the sum of the squared first two
/// coordinates of E x̄₁ and of Eᵀ x̄₂).
#[inline]
fn sampson_parts(e: &Matrix3<f64>, c: &Correspondence) -> (f64, f64) {
    let ex = e * c.x1;
    let etx = e.transpose() * c.x2;
    let num = c.x2.dot(&ex);
    (
        num,
        ex.x * ex.x + ex.y * ex.y + etx.x * etx.x + etx.y * etx.y,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;
    use nalgebra::Rotation3;

    fn scene(motion: &Motion, n: usize, noise: f64, rng: &mut Rng) -> Vec<Correspondence> {
        (0..n)
            .map(|_| {
                let x = Vector3::new(
                    rng.uniform() * 4.0 - 2.0,
                    rng.uniform() * 2.0 - 1.0,
                    3.0 + rng.uniform() * 7.0,
                );
                let x2 = motion.r * x + motion.t;
                let jitter =
                    |rng: &mut Rng| Vector3::new(rng.normal() * noise, rng.normal() * noise, 0.0);
                Correspondence {
                    x1: x / x.z + jitter(rng),
                    x2: x2 / x2.z + jitter(rng),
                }
            })
            .collect()
    }

    fn truth() -> Motion {
        Motion {
            r: Rotation3::from_euler_angles(0.01, 0.03, -0.02).into_inner(),
            t: Vector3::new(0.8, 0.1, 0.3).normalize(),
        }
    }

    #[test]
    fn exact_points_give_the_exact_motion() {
        let m = truth();
        let pts = scene(&m, 30, 0.0, &mut Rng::new(1));
        let e = eight_point(&pts).unwrap();
        let got = decompose(&e, &pts).unwrap();
        assert!((got.r - m.r).norm() < 1e-8 && (got.t - m.t).norm() < 1e-8);
        assert!(pts.iter().all(|c| sampson(&e, c) < 1e-20));
    }

    #[test]
    fn refinement_recovers_a_perturbed_motion() {
        let m = truth();
        let pts = scene(&m, 60, 0.0, &mut Rng::new(4));
        let start = Motion {
            r: Rotation3::from_euler_angles(0.005, -0.004, 0.003).into_inner() * m.r,
            t: (m.t + Vector3::new(0.03, -0.02, 0.01)).normalize(),
        };
        let got = refine_motion(&pts, &start, 20);
        assert!((got.r - m.r).norm() < 1e-6, "{}", (got.r - m.r).norm());
        assert!((got.t - m.t).norm() < 1e-6, "{}", (got.t - m.t).norm());
    }

    #[test]
    fn ransac_with_noise_and_outliers() {
        let m = truth();
        let mut rng = Rng::new(2);
        let mut pts = scene(&m, 300, 0.3 / 800.0, &mut rng);
        for c in pts.iter_mut().step_by(3) {
            c.x2 += Vector3::new(rng.uniform() * 0.1 - 0.05, rng.uniform() * 0.1 - 0.05, 0.0);
        }
        let (got, inliers) = robust_motion(
            &pts,
            800.0,
            300,
            16.0,
            1.5,
            MinimalSolver::EightPoint,
            &mut Rng::new(3),
        )
        .unwrap();
        let true_inliers = inliers.iter().filter(|&&i| i % 3 != 0).count();
        assert!(
            true_inliers >= 180 && inliers.len() - true_inliers <= 10,
            "{} inliers",
            inliers.len()
        );
        assert!(got.t.dot(&m.t) > 0.999, "{:?}", got.t);
        assert!((got.r - m.r).norm() < 5e-3);
    }
}
