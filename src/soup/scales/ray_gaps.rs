//! Where a boundary ray meets a piece's surface in both frames, and the frame-1 and frame-2
//! log-depth gaps between two pieces there (see the parent module's "The contact term"); also
//! the truncated gap costs of many states at once, for the refinement's pairwise tables.

use nalgebra::Vector3;

use crate::numeric::{atanh, ln, min, tanh};
use crate::soup::Piece;

/// A piece's surface where a boundary ray meets it, in both frames (camera-1 and camera-2
/// coordinates, at the piece's scale λ): what the contact gaps compare.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayPoint {
    /// ln of the frame-1 depth of the plane on the ray.
    pub log_depth: f64,
    /// That point moved into camera 2: X' = R X + λ t̂.
    pub moved: Vector3<f64>,
    /// The piece's plane in camera 2, m'ᵀX' = 1: m' = R m / (λ (1 + mᵀRᵀt̂)) with m the
    /// unit-scale plane (from X = Rᵀ(X' − λ t̂) and mᵀX = λ).
    pub plane2: Vector3<f64>,
}

impl RayPoint {
    /// A point behind a camera: NaN in every field, so it fails every comparison of
    /// [`TruncatedGaps`] and pays σ in both frames.
    pub const BEHIND: RayPoint = RayPoint {
        log_depth: f64::NAN,
        moved: Vector3::new(f64::NAN, f64::NAN, f64::NAN),
        plane2: Vector3::new(f64::NAN, f64::NAN, f64::NAN),
    };
}

/// Where `ray` meets `piece` (see [`RayPoint`]); `None` when the point or the plane is behind
/// either camera.
pub fn ray_point(piece: &Piece, ray: &Vector3<f64>) -> Option<RayPoint> {
    let inv = piece.m.dot(ray);
    let d = 1.0 + piece.m.dot(&(piece.r.transpose() * piece.t_hat));
    if !(inv > 0.0 && piece.lambda > 0.0 && d > 0.0) {
        return None;
    }
    let x = ray * (piece.lambda / inv);
    let moved = piece.r * x + piece.t_hat * piece.lambda;
    (moved.z > 0.0).then(|| RayPoint {
        log_depth: ln(x.z),
        moved,
        plane2: piece.r * piece.m / (piece.lambda * d),
    })
}

/// The log-depth gaps of a boundary pair between pieces a and b on one ray:
/// - frame 1: ln z_a − ln z_b (both planes on the ray);
/// - frame 2: ½ (ln m'_bᵀX'_a − ln m'_aᵀX'_b), how far each moved point lies off the other's
///   moved plane along its own camera-2 ray (0 when the surfaces still meet; a point sliding
///   along the other's plane, as a foot along the floor, stays at 0).
///
/// Both change by ln λ_a − ln λ_b when the scales do, and are NaN where undefined.
pub fn gaps(a: &RayPoint, b: &RayPoint) -> [f64; 2] {
    let (ab, ba) = (b.plane2.dot(&a.moved), a.plane2.dot(&b.moved));
    let g2 = if ab > 0.0 && ba > 0.0 {
        0.5 * (ln(ab) - ln(ba))
    } else {
        f64::NAN
    };
    [a.log_depth - b.log_depth, g2]
}

/// The contact costs of boundary pairs: [`gaps`]' magnitudes truncated at σ (min(|g|, σ), and
/// σ where a gap is undefined). The refinement evaluates them for every pair of particles, so
/// the frame-2 gap avoids the two logarithms: ½ (ln p − ln q) = atanh(u) with
/// u = (p − q) / (p + q), which is beyond the truncation where |u| ≥ tanh σ.
#[derive(Clone, Copy, Debug)]
pub struct TruncatedGaps {
    sigma: f64,
    tanh_sigma: f64,
}

impl TruncatedGaps {
    pub fn new(sigma: f64) -> Self {
        TruncatedGaps {
            sigma,
            tanh_sigma: tanh(sigma),
        }
    }

    /// σ, the cost of a broken gap.
    pub fn sigma(&self) -> f64 {
        self.sigma
    }

    /// The truncated frame-1 and frame-2 gaps of a and b on one ray (one pair; the
    /// refinement's tables take a column of pairs at once with [`TruncatedGaps::add_costs`]).
    /// NaN, a point behind a camera, fails every comparison and pays σ in both frames.
    #[inline]
    pub fn costs(&self, a: &RayPoint, b: &RayPoint) -> [f64; 2] {
        let (p, q) = (b.plane2.dot(&a.moved), a.plane2.dot(&b.moved));
        self.costs_of(a.log_depth - b.log_depth, p, q)
    }

    /// `row[k] += w (g₁ + g₂)` for a against the k-th point of `column` (whose slices hold at
    /// least `row.len()` points): [`TruncatedGaps::costs`] over a column of points stored field
    /// by field, with the same arithmetic in the same order, so the same bits. Where tanh σ ≤
    /// 0.1 (the default σ = 0.1) the loop has no branches and the compiler turns it into vector
    /// instructions; the refinement's contact tables are most of its time.
    #[inline]
    pub fn add_costs(&self, w: f64, a: &RayPoint, column: &PointColumn<'_>, row: &mut [f64]) {
        let n = row.len();
        debug_assert!(column.log_depth.len() >= n, "a column shorter than its row");
        // Slices of the row's length, so the loops below index them without bounds checks.
        let ld = &column.log_depth[..n];
        let [mx, my, mz] = column.moved.map(|c| &c[..n]);
        let [px, py, pz] = column.plane2.map(|c| &c[..n]);
        // The signed frame-1 gap and the frame-2 plane values p, q of a against point k.
        let gap_and_planes = |k: usize| {
            // The dot products in nalgebra's order: (x + y) + z.
            let p = px[k] * a.moved.x + py[k] * a.moved.y + pz[k] * a.moved.z;
            let q = a.plane2.x * mx[k] + a.plane2.y * my[k] + a.plane2.z * mz[k];
            (a.log_depth - ld[k], p, q)
        };
        // Two loops so that σ is tested once, outside them: the series loop has no branches.
        if self.series_suffices() {
            for (k, t) in row.iter_mut().enumerate() {
                let (d1, p, q) = gap_and_planes(k);
                let [g1, g2] = self.series_costs(d1, p, q);
                *t += w * (g1 + g2);
            }
        } else {
            for (k, t) in row.iter_mut().enumerate() {
                let (d1, p, q) = gap_and_planes(k);
                let [g1, g2] = self.costs_of(d1, p, q);
                *t += w * (g1 + g2);
            }
        }
    }

    /// Whether the series alone is exact inside the truncation (tanh σ ≤ 0.1).
    fn series_suffices(&self) -> bool {
        self.tanh_sigma <= SERIES_LIMIT
    }

    /// The truncated gaps [min(σ, |d1|), min(σ, |g₂|)] from the signed frame-1 gap `d1` and the
    /// frame-2 plane values p = m'_bᵀX'_a, q = m'_aᵀX'_b.
    #[inline]
    fn costs_of(&self, d1: f64, p: f64, q: f64) -> [f64; 2] {
        if !self.series_suffices() {
            let u = (p - q) / (p + q);
            let inside = (p > 0.0) & (q > 0.0) & (u.abs() < self.tanh_sigma);
            if inside && u.abs() > SERIES_LIMIT {
                return [min(self.sigma, d1.abs()), min(self.sigma, atanh(u).abs())];
            }
        }
        self.series_costs(d1, p, q)
    }

    /// [`TruncatedGaps::costs_of`] where the series is exact inside the truncation (tanh σ ≤ 0.1,
    /// or |u| ≤ 0.1): no branches.
    #[inline]
    fn series_costs(&self, d1: f64, p: f64, q: f64) -> [f64; 2] {
        let sigma = self.sigma;
        let u = (p - q) / (p + q);
        let inside = (p > 0.0) & (q > 0.0) & (u.abs() < self.tanh_sigma);
        let series = atanh_series(u).abs();
        let g2 = if inside { series } else { sigma };
        [min(sigma, d1.abs()), min(sigma, g2)]
    }
}

/// Points of several states on one ray (see [`RayPoint`]), field by field: element k of each
/// slice belongs to the k-th state, NaN in every field where that state's point is behind a
/// camera.
#[derive(Clone, Copy, Debug)]
pub struct PointColumn<'a> {
    /// [`RayPoint::log_depth`] of each state.
    pub log_depth: &'a [f64],
    /// x, y and z of [`RayPoint::moved`] of each state.
    pub moved: [&'a [f64]; 3],
    /// x, y and z of [`RayPoint::plane2`] of each state.
    pub plane2: [&'a [f64]; 3],
}

/// Points of several states on several rays, field by field and ray by ray (the storage of
/// [`PointColumn`]s): element `r · n + k` of each field is state k on ray r, n states per ray.
pub struct PointColumns {
    /// States per ray.
    n: usize,
    log_depth: Vec<f64>,
    moved: [Vec<f64>; 3],
    plane2: [Vec<f64>; 3],
}

impl PointColumns {
    /// Where each of `states` meets each of `rays` ([`ray_point`]; [`RayPoint::BEHIND`] where
    /// that point is behind a camera).
    pub fn new(states: &[Piece], rays: &[Vector3<f64>]) -> Self {
        let len = states.len() * rays.len();
        let mut columns = PointColumns {
            n: states.len(),
            log_depth: Vec::with_capacity(len),
            moved: std::array::from_fn(|_| Vec::with_capacity(len)),
            plane2: std::array::from_fn(|_| Vec::with_capacity(len)),
        };
        for ray in rays {
            for state in states {
                let p = ray_point(state, ray).unwrap_or(RayPoint::BEHIND);
                columns.log_depth.push(p.log_depth);
                for axis in 0..3 {
                    columns.moved[axis].push(p.moved[axis]);
                    columns.plane2[axis].push(p.plane2[axis]);
                }
            }
        }
        columns
    }

    /// The states' points on ray `r`.
    pub fn ray(&self, r: usize) -> PointColumn<'_> {
        let range = r * self.n..(r + 1) * self.n;
        PointColumn {
            log_depth: &self.log_depth[range.clone()],
            moved: self.moved.each_ref().map(|c| &c[range.clone()]),
            plane2: self.plane2.each_ref().map(|c| &c[range.clone()]),
        }
    }
}

/// Where [`atanh_series`] stops being exact to double precision.
const SERIES_LIMIT: f64 = 0.1;

/// atanh(u) by its series up to u^13, exact to double precision (remainder below 1e-16) for
/// |u| ≤ [`SERIES_LIMIT`]; no library call.
#[inline]
fn atanh_series(u: f64) -> f64 {
    let v = u * u;
    let series = [11.0, 9.0, 7.0, 5.0, 3.0]
        .iter()
        .fold(1.0 / 13.0, |tail, k| 1.0 / k + v * tail);
    u * (1.0 + v * series)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    #[test]
    fn gaps_vanish_where_surfaces_meet_and_follow_the_scales() {
        // The camera moves forward by 1. Piece a: the floor y = 1 (static, so it moves by
        // (0, 0, −1) in camera coordinates, along its own plane). Piece b: a wall z = 5 that
        // also slides sideways by 0.3 along the floor. They meet on y = 1, z = 5 in frame 1
        // and still touch in frame 2 (the wall's foot slid along the floor).
        let floor = Piece {
            r: nalgebra::Matrix3::identity(),
            t_hat: Vector3::new(0.0, 0.0, -1.0),
            m: Vector3::new(0.0, 1.0, 0.0),
            lambda: 1.0,
            hypothesis: 0,
            degenerate: None,
        };
        let motion = Vector3::new(0.3, 0.0, -1.0);
        let lambda = motion.norm();
        let wall = Piece {
            t_hat: motion / lambda,
            m: Vector3::new(0.0, 0.0, 0.2) * lambda,
            lambda,
            hypothesis: 1,
            ..floor
        };
        let ray = Vector3::new(0.1, 0.2, 1.0); // meets y = 1 at z = 5
        let (a, b) = (
            ray_point(&floor, &ray).unwrap(),
            ray_point(&wall, &ray).unwrap(),
        );
        let [g1, g2] = gaps(&a, &b);
        assert!(g1.abs() < 1e-12 && g2.abs() < 1e-12, "{g1} {g2}");
        // Doubling the wall's scale opens both gaps by −ln 2.
        let far = Piece {
            lambda: wall.lambda * 2.0,
            ..wall
        };
        let [h1, h2] = gaps(&a, &ray_point(&far, &ray).unwrap());
        assert!(
            (h1 + 2f64.ln()).abs() < 1e-12 && (h2 + 2f64.ln()).abs() < 1e-12,
            "{h1} {h2}"
        );
    }

    /// `add_costs` over a column gives, bit for bit, the sum of `costs` pair by pair, on both
    /// of its loops (σ = 0.1: the series alone; 0.15 and 0.3: the library's atanh too), with
    /// points behind a camera (NaN in every field) among the column's.
    #[test]
    fn column_costs_equal_the_pairwise_costs_bit_for_bit() {
        let mut rng = Rng::new(5);
        // Every fifth plane faces away from the camera: its point is behind it.
        let piece = |rng: &mut Rng, k: usize| {
            let facing = if k % 5 == 4 { -0.2 } else { 0.2 };
            Piece {
                r: *nalgebra::Rotation3::new(Vector3::new(0.0, 0.01 * rng.normal(), 0.0)).matrix(),
                t_hat: Vector3::new(0.2 * rng.normal(), 0.1, -1.0).normalize(),
                m: Vector3::new(0.05 * rng.normal(), 0.05 * rng.normal(), facing),
                lambda: (0.1 * rng.normal()).exp(),
                hypothesis: 0,
                degenerate: None,
            }
        };
        let ray = Vector3::new(0.1, -0.05, 1.0);
        let point = |p: &Piece| ray_point(p, &ray).unwrap_or(RayPoint::BEHIND);
        let b: Vec<Piece> = (0..13).map(|k| piece(&mut rng, k)).collect();
        let columns = PointColumns::new(&b, &[ray]);
        assert!(b.iter().any(|p| ray_point(p, &ray).is_none()));
        for sigma in [0.1, 0.15, 0.3] {
            let gaps = TruncatedGaps::new(sigma);
            for k in 0..40 {
                let a = point(&piece(&mut rng, k));
                let w = 0.3;
                let mut row = vec![0.25; b.len()];
                gaps.add_costs(w, &a, &columns.ray(0), &mut row);
                for (got, pb) in row.iter().zip(&b) {
                    let [g1, g2] = gaps.costs(&a, &point(pb));
                    let want = 0.25 + w * (g1 + g2);
                    assert_eq!(
                        got.to_bits(),
                        want.to_bits(),
                        "σ {sigma}: {got} against {want}"
                    );
                }
            }
        }
    }

    #[test]
    fn truncated_gaps_match_the_gaps() {
        // Random pairs of states around one surface, many near the truncation and some with
        // a point behind the other's plane (undefined frame-2 gap). σ = 0.15 reaches past the
        // atanh series into the library's atanh.
        for sigma in [0.1, 0.15] {
            truncated_gaps_match_the_gaps_at(sigma);
        }
    }

    fn truncated_gaps_match_the_gaps_at(sigma: f64) {
        let mut rng = Rng::new(11);
        let mut within = 0;
        for _ in 0..20_000 {
            let mut state = || {
                let jitter = |rng: &mut Rng, s: f64| s * rng.normal();
                Piece {
                    r: *nalgebra::Rotation3::new(Vector3::new(
                        jitter(&mut rng, 0.02),
                        jitter(&mut rng, 0.02),
                        jitter(&mut rng, 0.02),
                    ))
                    .matrix(),
                    t_hat: Vector3::new(jitter(&mut rng, 0.3), 0.1, -1.0).normalize(),
                    m: Vector3::new(jitter(&mut rng, 0.1), jitter(&mut rng, 0.1), 0.2),
                    lambda: jitter(&mut rng, 0.15).exp(),
                    hypothesis: 0,
                    degenerate: None,
                }
            };
            let (a, b) = (state(), state());
            let ray = Vector3::new(0.2 * rng.normal(), 0.2 * rng.normal(), 1.0);
            let (Some(ra), Some(rb)) = (ray_point(&a, &ray), ray_point(&b, &ray)) else {
                continue;
            };
            let reference = gaps(&ra, &rb).map(|g| if g.abs() < sigma { g.abs() } else { sigma });
            let fast = TruncatedGaps::new(sigma).costs(&ra, &rb);
            for (f, r) in fast.iter().zip(reference) {
                assert!((f - r).abs() < 1e-15, "{fast:?} against {reference:?}");
            }
            within += usize::from(reference[1] < sigma);
        }
        assert!(within > 2_000, "only {within} pairs inside the truncation");
    }

    #[test]
    fn the_atanh_series_matches_the_library() {
        for j in -1000..=1000 {
            let u = j as f64 * SERIES_LIMIT / 1000.0;
            assert!((atanh_series(u) - u.atanh()).abs() < 1e-16, "{u}");
        }
    }
}
