//! Accuracy metrics against ground truth, as docs/ARCHITECTURE.md (Measuring) defines them,
//! where the evaluation data is read from ([`eval_case_dir`]), and the truth test's oracle of
//! every piece's true state from exact scene flow ([`true_states`]), and the camera's own
//! ([`true_camera_motion`]) to score the estimated ego-motion ([`motion_error`]).
//!
//! Depth is known only up to one global scale, so every depth metric first aligns the estimate:
//! - MRE and δ<1.25 use s = median(z_gt / z) over pixels valid in both maps;
//! - AbsRel uses the monocular-depth convention s = median(z_gt) / median(z).
//!
//! A depth is valid when finite and > 0; a flow vector when both components are finite.

use std::path::PathBuf;

use nalgebra::{Matrix3, Vector3};
use serde::Serialize;

use crate::camera::Intrinsics;
use crate::error::{Error, Result};
use crate::flow::{FlowField, is_known};
use crate::geometry::essential::Motion;
use crate::grid::Grid;
use crate::numeric::hypot;
use crate::output::nearest_label;
use crate::soup::{Piece, Soup};

/// Depth accuracy of an estimate against ground truth.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct DepthMetrics {
    /// Mean relative error mean(|z_gt − s·z| / z_gt) with s = median(z_gt / z).
    pub mre: f64,
    /// mean(|s'·z − z_gt| / z_gt) with s' = median(z_gt) / median(z).
    pub abs_rel: f64,
    /// Share of pixels with max(s·z / z_gt, z_gt / (s·z)) < 1.25.
    pub delta_125: f64,
    /// Share of valid ground-truth pixels that have an estimate.
    pub coverage: f64,
    /// The scale s applied for MRE and δ.
    pub scale: f64,
    /// Pixels scored (valid in both maps).
    pub pixels: usize,
}

/// Scores `est` against `gt` (same size). Fails when sizes differ or no pixel is valid in both.
pub fn depth_metrics(gt: &Grid<f32>, est: &Grid<f32>) -> Result<DepthMetrics> {
    gt.check_same_size(est)?;
    let valid = |z: f32| z.is_finite() && z > 0.0;
    let gt_valid = gt.data().iter().filter(|&&z| valid(z)).count();
    let pairs: Vec<(f64, f64)> = gt
        .data()
        .iter()
        .zip(est.data())
        .filter(|&(&g, &e)| valid(g) && valid(e))
        .map(|(&g, &e)| (g as f64, e as f64))
        .collect();
    if pairs.is_empty() {
        return Err(Error::InvalidParameter(
            "no pixel has both a ground-truth depth and an estimate".into(),
        ));
    }
    let n = pairs.len() as f64;
    let scale = median(pairs.iter().map(|(g, e)| g / e).collect());
    let mre = pairs
        .iter()
        .map(|(g, e)| (g - scale * e).abs() / g)
        .sum::<f64>()
        / n;
    let delta_125 = pairs
        .iter()
        .filter(|(g, e)| {
            let r = scale * e / g;
            r.max(1.0 / r) < 1.25
        })
        .count() as f64
        / n;
    let s_rel =
        median(pairs.iter().map(|p| p.0).collect()) / median(pairs.iter().map(|p| p.1).collect());
    let abs_rel = pairs
        .iter()
        .map(|(g, e)| (s_rel * e - g).abs() / g)
        .sum::<f64>()
        / n;
    Ok(DepthMetrics {
        mre,
        abs_rel,
        delta_125,
        coverage: pairs.len() as f64 / gt_valid as f64,
        scale,
        pixels: pairs.len(),
    })
}

/// Per-pixel relative error |z_gt − s·z| / z_gt of `est` against `gt` (same size) with the
/// scale `s` of [`depth_metrics`] (pass its `scale`), the quantity whose mean is the MRE; NaN
/// where either depth is not valid.
pub fn relative_errors(gt: &Grid<f32>, est: &Grid<f32>, scale: f64) -> Result<Grid<f32>> {
    gt.check_same_size(est)?;
    let valid = |z: f32| z.is_finite() && z > 0.0;
    let (w, h) = gt.size();
    Ok(Grid::from_fn(w, h, |x, y| {
        let (g, e) = (*gt.get(x, y), *est.get(x, y));
        if valid(g) && valid(e) {
            ((g as f64 - scale * e as f64).abs() / g as f64) as f32
        } else {
            f32::NAN
        }
    }))
}

/// Flow accuracy of an estimate against ground truth.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct FlowMetrics {
    /// Average end-point error ‖f_est − f_gt‖ in pixels over pixels known in both.
    pub epe: f64,
    /// Share of those pixels with end-point error > 3 px and > 5 % of the GT magnitude (KITTI Fl).
    pub outliers: f64,
    /// Share of those pixels with end-point error > 3 px.
    pub over_3px: f64,
    /// Share of known ground-truth pixels that have an estimate.
    pub coverage: f64,
    /// Pixels scored.
    pub pixels: usize,
}

/// Scores flow `est` against `gt` (same size); unknown vectors are skipped.
pub fn flow_metrics(gt: &FlowField, est: &FlowField) -> Result<FlowMetrics> {
    gt.check_same_size(est)?;
    let gt_known = gt.data().iter().filter(|&&f| is_known(f)).count();
    let errors: Vec<(f64, f64)> = gt
        .data()
        .iter()
        .zip(est.data())
        .filter(|&(&g, &e)| is_known(g) && is_known(e))
        .map(|(g, e)| {
            let err = hypot((g[0] - e[0]) as f64, (g[1] - e[1]) as f64);
            (err, hypot(g[0] as f64, g[1] as f64))
        })
        .collect();
    if errors.is_empty() {
        return Err(Error::InvalidParameter(
            "no pixel has both a ground-truth flow and an estimate".into(),
        ));
    }
    let n = errors.len() as f64;
    Ok(FlowMetrics {
        epe: errors.iter().map(|e| e.0).sum::<f64>() / n,
        outliers: errors
            .iter()
            .filter(|(e, m)| *e > 3.0 && *e > 0.05 * m)
            .count() as f64
            / n,
        over_3px: errors.iter().filter(|(e, _)| *e > 3.0).count() as f64 / n,
        coverage: errors.len() as f64 / gt_known as f64,
        pixels: errors.len(),
    })
}

/// Boundary recall of a segmentation: the share of ground-truth depth discontinuities that lie
/// within `tolerance` pixels (Chebyshev) of a label boundary; `None` when there are none.
///
/// A discontinuity is a 4-neighbour pair (p, q) whose depths differ by more than `jump` (relative
/// to the nearer) and where that step is not the smooth continuation of the surface on either
/// side: inverse depth is affine in the image on a plane, so q's depth predicted by extrapolating
/// 1/z from the two pixels before p (and p's from the two after q) must also miss by more than
/// `jump`. Without that test, slanted surfaces seen at grazing angles (a road near the horizon)
/// count as discontinuities although nothing there separates two surfaces.
pub fn boundary_recall(
    labels: &Grid<u32>,
    depth: &Grid<f32>,
    jump: f32,
    tolerance: usize,
) -> Result<Option<f64>> {
    labels.check_same_size(depth)?;
    let (w, h) = labels.size();
    let boundary = Grid::from_fn(w, h, |x, y| {
        let l = *labels.get(x, y);
        [(1isize, 0isize), (-1, 0), (0, 1), (0, -1)]
            .iter()
            .any(|&(dx, dy)| {
                labels
                    .get_checked(x as isize + dx, y as isize + dy)
                    .is_some_and(|&m| m != l)
            })
    });
    let near_boundary = boundary.dilated(tolerance);
    let z_at = |x: isize, y: isize| {
        depth
            .get_checked(x, y)
            .copied()
            .filter(|z| z.is_finite() && *z > 0.0)
    };
    let misses = |predicted: Option<f32>, z: f32| {
        predicted.is_none_or(|p| p <= 0.0 || (1.0 / p - z).abs() > jump * z)
    };
    let (mut found, mut total) = (0usize, 0usize);
    for y in 0..h as isize {
        for x in 0..w as isize {
            for (dx, dy) in [(1isize, 0isize), (0, 1)] {
                let (Some(zp), Some(zq)) = (z_at(x, y), z_at(x + dx, y + dy)) else {
                    continue;
                };
                if (zp - zq).abs() <= jump * zp.min(zq) {
                    continue;
                }
                // Inverse depth extrapolated across the step from each side.
                let before = z_at(x - dx, y - dy).map(|zb| 2.0 / zp - 1.0 / zb);
                let after = z_at(x + 2 * dx, y + 2 * dy).map(|za| 2.0 / zq - 1.0 / za);
                if misses(before, zq) && misses(after, zp) {
                    total += 1;
                    found += usize::from(*near_boundary.get(x as usize, y as usize));
                }
            }
        }
    }
    Ok((total > 0).then(|| found as f64 / total as f64))
}

/// Median of a non-empty list (upper median for even lengths).
pub fn median(mut values: Vec<f64>) -> f64 {
    let mid = values.len() / 2;
    let (_, m, _) = values.select_nth_unstable_by(mid, f64::total_cmp);
    *m
}

/// The folder of the public evaluation case `name`: `$SOUP_EVAL_DIR/name` when that variable is
/// set, else `../shared/eval/name` beside the crate. `None` when it does not exist (tests and
/// benches then skip, saying so).
pub fn eval_case_dir(name: &str) -> Option<PathBuf> {
    let root = std::env::var_os("SOUP_EVAL_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/eval"));
    let dir = root.join(name);
    dir.is_dir().then_some(dir)
}

/// The true state of every piece of `soup` from exact scene flow (our synthetic scenes): per
/// superpixel (`labels`, at any resolution: each pixel of the truth takes the nearest label),
/// the rigid motion that best moves its pixels' true 3D points at time 1 (camera-1 frame, from
/// `depth1`) onto theirs at time 2 (camera-2 frame, from `flow12` and `depth12`: the z-depth in
/// camera 2 of frame 1's point) by least squares (Kabsch), and the least-squares plane through
/// the first, at the truth's metric scale (λ = |t|). `k` is the intrinsics of the truth's
/// resolution. A piece with fewer than 8 such pixels, or no translation, keeps its state in
/// `soup`, scaled by the median ratio of true to `soup` depth over the others (so that the
/// contacts between kept and true pieces are judged at one global scale). The truth test's
/// oracle: the refinement's energy at these states, against the solution's, separates the
/// energy from the optimiser.
///
/// Errors: [`Error::SizeMismatch`] when the three truths differ in size,
/// [`Error::InvalidParameter`] for empty `labels`.
pub fn true_states(
    soup: &Soup,
    labels: &Grid<u32>,
    depth1: &Grid<f32>,
    flow12: &FlowField,
    depth12: &Grid<f32>,
    k: &Intrinsics,
) -> Result<Soup> {
    depth1.check_same_size(flow12)?;
    depth1.check_same_size(depth12)?;
    if labels.data().is_empty() {
        return Err(Error::InvalidParameter(
            "true states need superpixel labels".into(),
        ));
    }
    let (w, h) = depth1.size();
    let mut points = vec![Vec::new(); soup.pieces.len()];
    for (x, y, pair) in surface_point_pairs(depth1, flow12, depth12, k) {
        if let Some(list) = points.get_mut(nearest_label(labels, w, h, x, y)) {
            list.push(pair);
        }
    }
    let mut out = soup.clone();
    let mut kept = Vec::new();
    let mut ratios = Vec::new();
    for (i, (piece, pairs)) in out.pieces.iter_mut().zip(&points).enumerate() {
        let Some(state) = rigid_state(pairs) else {
            kept.push(i);
            continue;
        };
        // The true and the soup's depth along the ray through the piece's true centroid.
        let centroid = pairs.iter().map(|p| p.0).sum::<Vector3<f64>>() / pairs.len() as f64;
        let ratio = centroid.z / piece.depth(&(centroid / centroid.z));
        if ratio.is_finite() && ratio > 0.0 {
            ratios.push(ratio);
        }
        *piece = Piece {
            degenerate: piece.degenerate,
            hypothesis: piece.hypothesis,
            ..state
        };
    }
    if !ratios.is_empty() {
        let scale = median(ratios);
        kept.iter().for_each(|&i| out.pieces[i].lambda *= scale);
    }
    Ok(out)
}

/// Every pixel (x, y) of frame 1 with known depth in both cameras and known flow, with its
/// surface point in camera 1's frame and the same point in camera 2's (metres, or the truth's
/// units). The three grids must have one size (callers check).
fn surface_point_pairs<'a>(
    depth1: &'a Grid<f32>,
    flow12: &'a FlowField,
    depth12: &'a Grid<f32>,
    k: &'a Intrinsics,
) -> impl Iterator<Item = (usize, usize, (Vector3<f64>, Vector3<f64>))> + 'a {
    let (w, h) = depth1.size();
    (0..h)
        .flat_map(move |y| (0..w).map(move |x| (x, y)))
        .filter_map(move |(x, y)| {
            let (f, a, b) = (*flow12.get(x, y), *depth1.get(x, y), *depth12.get(x, y));
            if !(is_known(f) && a.is_finite() && b.is_finite() && a > 0.0 && b > 0.0) {
                return None;
            }
            let p1 = Vector3::from(k.ray(x as f64, y as f64)) * f64::from(a);
            let (x2, y2) = (x as f64 + f64::from(f[0]), y as f64 + f64::from(f[1]));
            let p2 = Vector3::from(k.ray(x2, y2)) * f64::from(b);
            Some((x, y, (p1, p2)))
        })
}

/// How far an estimated camera motion is from the true one, in degrees.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct MotionError {
    /// The angle between the directions of translation (the scale of t is unknown).
    pub translation_deg: f64,
    /// The angle of the rotation R_est R_trueᵀ.
    pub rotation_deg: f64,
}

/// The camera's true motion between the frames (X₂ = R X₁ + λ t̂ for every point of the static
/// world, camera frames; t̂ of unit length), from exact scene flow: the rigid fit
/// ([`rigid_state`]) of the surface points of the pixels that `moving` marks as still. `None`
/// when fewer than 8 such pixels have depth in both cameras and flow, or the camera does not
/// translate.
///
/// Errors: [`Error::SizeMismatch`] when the four truths differ in size.
pub fn true_camera_motion(
    moving: &Grid<bool>,
    depth1: &Grid<f32>,
    flow12: &FlowField,
    depth12: &Grid<f32>,
    k: &Intrinsics,
) -> Result<Option<Motion>> {
    depth1.check_same_size(flow12)?;
    depth1.check_same_size(depth12)?;
    depth1.check_same_size(moving)?;
    let still: Vec<(Vector3<f64>, Vector3<f64>)> = surface_point_pairs(depth1, flow12, depth12, k)
        .filter(|&(x, y, _)| !*moving.get(x, y))
        .map(|(_, _, pair)| pair)
        .collect();
    Ok(rigid_state(&still).map(|state| Motion {
        r: state.r,
        t: state.t_hat,
    }))
}

/// The error of the `estimated` motion against the `truth`.
pub fn motion_error(estimated: &Motion, truth: &Motion) -> MotionError {
    MotionError {
        translation_deg: estimated.translation_angle(truth).to_degrees(),
        rotation_deg: estimated.rotation_angle(truth).to_degrees(),
    }
}

/// The rigid motion X' = R X + t moving the first points of `pairs` onto the second (Kabsch:
/// least squares over rotations), and the least-squares plane mᵀX = 1 through the first, as a
/// piece's state at λ = |t|. `None` for fewer than 8 pairs, no translation or a degenerate fit.
pub fn rigid_state(pairs: &[(Vector3<f64>, Vector3<f64>)]) -> Option<Piece> {
    if pairs.len() < 8 {
        return None;
    }
    let n = pairs.len() as f64;
    let c1 = pairs.iter().map(|p| p.0).sum::<Vector3<f64>>() / n;
    let c2 = pairs.iter().map(|p| p.1).sum::<Vector3<f64>>() / n;
    let cov: Matrix3<f64> = (pairs.iter())
        .map(|(p, q)| (q - c2) * (p - c1).transpose())
        .sum();
    let svd = cov.svd(true, true);
    let (u, v_t) = (svd.u?, svd.v_t?);
    let flip = if (u * v_t).determinant() < 0.0 {
        -1.0
    } else {
        1.0
    };
    let r = u * Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, flip)) * v_t;
    let t = c2 - r * c1;
    let ata: Matrix3<f64> = pairs.iter().map(|(p, _)| p * p.transpose()).sum();
    let m = ata.try_inverse()? * pairs.iter().map(|p| p.0).sum::<Vector3<f64>>();
    let lambda = t.norm();
    (lambda > 1e-9 && m.iter().all(|c| c.is_finite())).then(|| Piece {
        r,
        t_hat: t / lambda,
        m: m * lambda,
        lambda,
        hypothesis: 0,
        degenerate: None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn perfect_depth_up_to_scale_scores_zero() {
        let gt = Grid::from_fn(4, 4, |x, y| 1.0 + (x + y) as f32);
        let est = gt.map(|z| z * 0.1);
        let m = depth_metrics(&gt, &est).unwrap();
        assert!(m.mre < 1e-6 && m.abs_rel < 1e-6);
        assert!((m.scale - 10.0).abs() < 1e-5);
        assert_eq!((m.delta_125, m.coverage, m.pixels), (1.0, 1.0, 16));
    }

    #[test]
    fn hand_computed_errors_and_coverage() {
        // gt 1,1,1,1 ; est 1,1,2,NaN → ratios 1,1,0.5 → median 1 → errors 0,0,1 → MRE 1/3.
        let gt = Grid::from_vec(4, 1, vec![1.0, 1.0, 1.0, 1.0]).unwrap();
        let est = Grid::from_vec(4, 1, vec![1.0, 1.0, 2.0, f32::NAN]).unwrap();
        let m = depth_metrics(&gt, &est).unwrap();
        assert!((m.mre - 1.0 / 3.0).abs() < 1e-12);
        assert!((m.delta_125 - 2.0 / 3.0).abs() < 1e-12);
        assert!((m.coverage - 0.75).abs() < 1e-12);
        // AbsRel: medians 1 and 1 → same errors here.
        assert!((m.abs_rel - 1.0 / 3.0).abs() < 1e-12);
    }

    #[test]
    fn invalid_gt_pixels_are_ignored_and_empty_overlap_is_an_error() {
        let gt = Grid::from_vec(3, 1, vec![f32::NAN, 0.0, 2.0]).unwrap();
        let est = Grid::from_vec(3, 1, vec![5.0, 5.0, 4.0]).unwrap();
        let m = depth_metrics(&gt, &est).unwrap();
        assert_eq!((m.pixels, m.coverage), (1, 1.0));
        let none = Grid::filled(3, 1, f32::NAN);
        assert!(depth_metrics(&gt, &none).is_err());
        assert!(depth_metrics(&gt, &Grid::filled(2, 1, 1.0)).is_err());
    }

    #[test]
    fn relative_errors_average_to_the_mre() {
        let gt = Grid::from_vec(4, 1, vec![1.0, 2.0, 4.0, 1.0]).unwrap();
        let est = Grid::from_vec(4, 1, vec![1.0, 2.0, 2.0, f32::NAN]).unwrap();
        let m = depth_metrics(&gt, &est).unwrap();
        let errors = relative_errors(&gt, &est, m.scale).unwrap();
        assert_eq!(&errors.data()[..3], &[0.0, 0.0, 0.5]);
        assert!(errors.data()[3].is_nan());
        let mean = errors.data().iter().filter(|e| e.is_finite()).sum::<f32>() / 3.0;
        assert!((mean as f64 - m.mre).abs() < 1e-6);
        assert!(relative_errors(&gt, &Grid::filled(3, 1, 1.0), 1.0).is_err());
    }

    #[test]
    fn flow_end_point_error_by_hand() {
        let gt = Grid::from_vec(3, 1, vec![[0.0, 0.0], [3.0, 4.0], [f32::NAN, f32::NAN]]).unwrap();
        let est = Grid::from_vec(3, 1, vec![[3.0, 4.0], [3.0, 4.0], [1.0, 1.0]]).unwrap();
        let m = flow_metrics(&gt, &est).unwrap();
        assert!((m.epe - 2.5).abs() < 1e-12);
        assert!((m.outliers - 0.5).abs() < 1e-12);
        assert!((m.over_3px - 0.5).abs() < 1e-12);
        assert_eq!((m.coverage, m.pixels), (1.0, 2));
    }

    #[test]
    fn boundary_recall_counts_discontinuities_near_label_edges() {
        // Depth jumps between columns 4 and 5; labels split at column 5 (recall 1) or 9 (recall 0).
        let depth = Grid::from_fn(10, 4, |x, _| if x < 5 { 1.0 } else { 2.0 });
        // A slanted plane (inverse depth affine in x) with steps > 5 % has no discontinuity.
        let slanted = Grid::from_fn(10, 4, |x, _| 1.0 / (1.0 - 0.09 * x as f32));
        let good = Grid::from_fn(10, 4, |x, _| (x >= 5) as u32);
        let bad = Grid::from_fn(10, 4, |x, _| (x >= 9) as u32);
        assert_eq!(boundary_recall(&bad, &slanted, 0.05, 2).unwrap(), None);
        assert_eq!(boundary_recall(&good, &depth, 0.05, 2).unwrap(), Some(1.0));
        assert_eq!(boundary_recall(&bad, &depth, 0.05, 2).unwrap(), Some(0.0));
        assert_eq!(
            boundary_recall(&good, &Grid::filled(10, 4, 3.0), 0.05, 2).unwrap(),
            None
        );
    }

    #[test]
    fn median_picks_the_middle() {
        assert_eq!(median(vec![3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(vec![4.0, 1.0, 2.0, 3.0]), 3.0);
    }

    /// A plane z = 4 + 0.3 x seen by the `k` camera, each half of the image (label 0 left, 1
    /// right) moved by its own rigid motion; returns labels, depth1, flow12 and depth12.
    #[allow(clippy::type_complexity)]
    fn two_motion_scene(
        k: &Intrinsics,
        motions: &[(Matrix3<f64>, Vector3<f64>); 2],
    ) -> (Grid<u32>, Grid<f32>, FlowField, Grid<f32>) {
        let (w, h) = (24, 16);
        let labels = Grid::from_fn(w, h, |x, _| u32::from(x >= w / 2));
        let mut depth1 = Grid::filled(w, h, f32::NAN);
        let mut flow = Grid::filled(w, h, [f32::NAN; 2]);
        let mut depth12 = Grid::filled(w, h, f32::NAN);
        for y in 0..h {
            for x in 0..w {
                let ray = Vector3::from(k.ray(x as f64, y as f64));
                let z = 4.0 / (1.0 - 0.3 * ray.x);
                let (r, t) = &motions[*labels.get(x, y) as usize];
                let p2 = r * (ray * z) + t;
                let [u, v] = k.project([p2.x, p2.y, p2.z]);
                *depth1.get_mut(x, y) = z as f32;
                *flow.get_mut(x, y) = [(u - x as f64) as f32, (v - y as f64) as f32];
                *depth12.get_mut(x, y) = p2.z as f32;
            }
        }
        (labels, depth1, flow, depth12)
    }

    #[test]
    fn true_states_recover_each_piece_s_motion_and_plane() {
        let k = Intrinsics {
            fx: 20.0,
            fy: 20.0,
            cx: 11.5,
            cy: 7.5,
        };
        let turn = |a: f64| *nalgebra::Rotation3::new(Vector3::new(0.0, a, 0.01)).matrix();
        let motions = [
            (turn(0.02), Vector3::new(0.3, 0.0, 0.1)),
            (turn(-0.05), Vector3::new(-0.1, 0.2, -0.4)),
        ];
        let (labels, depth1, flow, depth12) = two_motion_scene(&k, &motions);
        let placeholder = Piece {
            r: Matrix3::identity(),
            t_hat: Vector3::z(),
            m: Vector3::new(0.0, 0.0, 1.0),
            lambda: 1.0,
            hypothesis: 7,
            degenerate: None,
        };
        let soup = Soup {
            pieces: vec![placeholder; 3],
            hypotheses: Vec::new(),
            noise_px: 0.0,
            ego_rival: None,
            rugged_to_ego: 0,
        };
        let states = true_states(&soup, &labels, &depth1, &flow, &depth12, &k).unwrap();
        for (piece, (r, t)) in states.pieces.iter().zip(&motions) {
            assert!((piece.r - r).norm() < 1e-5, "{:?} against {r:?}", piece.r);
            assert!((piece.t_hat * piece.lambda - t).norm() < 1e-5);
            // The plane z = 4 + 0.3 x is (−0.075, 0, 0.25)ᵀX = 1 at the truth's scale.
            let metric_m = piece.m / piece.lambda;
            assert!((metric_m - Vector3::new(-0.075, 0.0, 0.25)).norm() < 1e-6);
            assert_eq!(piece.hypothesis, 7, "the piece's bookkeeping is kept");
        }
        // A piece without pixels keeps its state, at the truth's scale: the true depths of the
        // plane's two halves lie in 3.4–4.9, the placeholder's at 1.
        let kept = states.pieces[2];
        assert_eq!(
            (kept.r, kept.t_hat, kept.m),
            (placeholder.r, placeholder.t_hat, placeholder.m)
        );
        assert!(kept.lambda > 3.4 && kept.lambda < 4.9, "{}", kept.lambda);
        assert!(rigid_state(&[(Vector3::z(), Vector3::z()); 7]).is_none());
        let small = Grid::filled(3, 3, 1.0f32);
        assert!(true_states(&soup, &labels, &small, &flow, &depth12, &k).is_err());
    }

    #[test]
    fn the_camera_motion_is_the_still_pixels_rigid_motion_and_its_error_is_in_degrees() {
        let k = Intrinsics {
            fx: 20.0,
            fy: 20.0,
            cx: 11.5,
            cy: 7.5,
        };
        let turn = |axis: Vector3<f64>| *nalgebra::Rotation3::new(axis).matrix();
        let camera = (
            turn(Vector3::new(0.0, 0.02, 0.01)),
            Vector3::new(0.3, 0.0, 0.1),
        );
        let mover = (
            turn(Vector3::new(0.0, -0.05, 0.01)),
            Vector3::new(-0.1, 0.2, -0.4),
        );
        let (labels, depth1, flow, depth12) = two_motion_scene(&k, &[camera, mover]);
        // The right half (label 1) moves in the world.
        let moving = labels.map(|&l| l == 1);
        let truth = true_camera_motion(&moving, &depth1, &flow, &depth12, &k)
            .unwrap()
            .unwrap();
        let exact = Motion {
            r: camera.0,
            t: camera.1.normalize(),
        };
        assert!((truth.r - exact.r).norm() < 1e-6 && (truth.t - exact.t).norm() < 1e-6);
        let none = motion_error(&truth, &exact);
        assert!(
            none.translation_deg < 1e-4 && none.rotation_deg < 1e-4,
            "{none:?}"
        );
        // An estimate 3° off in translation (turned about y) and 0.5° in rotation (about x).
        let off = Motion {
            r: turn(Vector3::new(0.5f64.to_radians(), 0.0, 0.0)) * exact.r,
            t: turn(Vector3::new(0.0, 3f64.to_radians(), 0.0)) * exact.t,
        };
        let error = motion_error(&off, &exact);
        assert!((error.translation_deg - 3.0).abs() < 1e-9, "{error:?}");
        assert!((error.rotation_deg - 0.5).abs() < 1e-9, "{error:?}");
        // Everything moving: no camera motion; truths of other sizes: an error.
        let all = labels.map(|_| true);
        assert!(
            true_camera_motion(&all, &depth1, &flow, &depth12, &k)
                .unwrap()
                .is_none()
        );
        let small = Grid::filled(3, 3, false);
        assert!(true_camera_motion(&small, &depth1, &flow, &depth12, &k).is_err());
    }

    #[test]
    fn rigid_states_are_proper_rotations_on_planar_points() {
        // Coplanar points leave the reflection through their plane as good a least-squares fit
        // as the rotation: the fit must pick the rotation every time.
        let mut rng = crate::rng::Rng::new(9);
        for _ in 0..50 {
            let axis = Vector3::new(rng.normal(), rng.normal(), rng.normal()) * 0.3;
            let r = *nalgebra::Rotation3::new(axis).matrix();
            let t = Vector3::new(rng.normal(), rng.normal(), rng.normal());
            let pairs: Vec<(Vector3<f64>, Vector3<f64>)> = (0..12)
                .map(|_| {
                    let (x, y) = (rng.normal(), rng.normal());
                    let p = Vector3::new(x, y, 5.0 + 0.1 * x);
                    (p, r * p + t)
                })
                .collect();
            let state = rigid_state(&pairs).unwrap();
            assert!((state.r.determinant() - 1.0).abs() < 1e-9);
            assert!((state.r - r).norm() < 1e-9);
            assert!((state.t_hat * state.lambda - t).norm() < 1e-9);
        }
    }
}
