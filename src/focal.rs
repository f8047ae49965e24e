//! The focal length from the two frames, where neither the user nor the photo's EXIF gave one.
//!
//! Without a focal length the pipeline guesses fx = fy = the long side
//! ([`Intrinsics::default_for`]). A wrong focal length distorts the camera's rotation into a
//! false parallax, and the depth suffers far more than the 25 % by which the guess misses the
//! synthetic scenes' camera: the creature's error goes from 0.04 to 0.70 (docs/RESULTS.md, stops
//! 58 and 62). Two views fix the focal length (with the principal point at the image centre and
//! square pixels) unless the motion is degenerate for it: a camera that only translates (stereo),
//! that moves towards its own epipole, or whose optical axes meet (orbiting a point) explains its
//! flow equally well at every focal length.
//!
//! The search: the camera's motion is fitted once, robustly, at the guess, and its inliers (the
//! static world's trusted flow, within 1 px) are kept. Then, from the guess outwards
//! along a logarithmic grid of focal lengths, the motion is polished by Levenberg–Marquardt on
//! those points alone, starting from its neighbour's (so the score follows one motion instead of
//! jumping between RANSAC draws), and scored by the median of their Sampson errors in px² (the
//! median, so that movers the first fit let in do not decide).
//! Where the frames fix the focal length the score has a clear minimum (the synthetic static
//! room: 0.0002 px² at 817 px against 0.003 at 1029 px, the grid's point next to the guess of
//! 1024, for a true 819.2); where they do
//! not, it is flat within a few per cent or falls towards an end of the grid (the street and the
//! road seen from a camera moving along its view, Middlebury's stereo pair, KITTI, the orbiting
//! table). An estimate is returned only for a minimum inside the grid that the score rises from
//! by 1.2× on both sides within a factor 1.26: otherwise the guess stands.
//!
//! Deterministic: the samples are every k-th trusted pixel, the fits use a fixed seed.

use crate::camera::Intrinsics;
use crate::eval::median;
use crate::flow::{FlowField, is_known};
use crate::geometry::Correspondence;
use crate::geometry::essential::{MinimalSolver, Motion, refine_motion, robust_motion, sampson};
use crate::grid::Grid;
use crate::numeric::{exp, ln};
use crate::rng::Rng;
use nalgebra::Vector3;

/// Trusted flow vectors the search looks at, at most (a regular subsample of them): the score's
/// median is stable at this many and each fit takes a few milliseconds.
const MAX_POINTS: usize = 2000;

/// The static world's inliers at the guess: within this Sampson distance of the guess's motion
/// (px; the flow's noise is 0.1–0.3 px, and a focal length 25 % off shifts the epipolar lines
/// by less than this over most of the view, so the static world stays in).
const INLIER_PX: f64 = 1.0;

/// Fewer inliers than this leave no estimate (too little static world to tell).
const MIN_INLIERS: usize = 200;

/// The grid: focal lengths from `GRID_LOW` to `GRID_HIGH` times the guess, `GRID_STEPS` of them
/// evenly spaced in the logarithm (a step of 6 %).
const GRID_LOW: f64 = 0.3;
const GRID_HIGH: f64 = 3.0;
const GRID_STEPS: usize = 41;

/// RANSAC draws of the fit at the guess.
const FIT_ITERATIONS: usize = 200;

/// Levenberg–Marquardt iterations that carry the motion from one focal length to the next.
const POLISH_ITERATIONS: usize = 3;

/// The sides of a clear minimum: the score at the minimum times and divided by this factor.
const SIDE_FACTOR: f64 = 1.26;

/// A clear minimum: the score at both sides ([`SIDE_FACTOR`]) is at least this many times the
/// minimum's. On the evaluation cases (preset high) the rise was 1.3–17 where an estimate came
/// out (static room 11.9, FlyingThings3D 16.5, creature 2.4, flag 1.5, Sintel's alley 1.3) and
/// 1.00–1.02 at the other interior minima (street, road, KITTI) (docs/RESULTS.md, stop 62).
const MIN_RISE: f64 = 1.2;

/// A focal length the two frames fix.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FocalEstimate {
    /// The estimated focal length (px), fx = fy.
    pub focal: f64,
    /// How clearly the frames fix it: the smaller of the scores at the minimum's sides
    /// (1.26 times and divided by it) over the score at the minimum (at least 1.2).
    pub rise: f64,
}

/// The focal length that the trusted `flow` (frame 1 → 2, where `reliable`) fixes, searched
/// around `guess` (whose principal point is kept, fx = fy); `None` where the frames do not fix
/// it (see the module's text), with fewer than 200 static-world inliers at the guess, or where
/// `reliable` is not the flow's size. Pixels of the flow's resolution.
pub fn estimate_focal(
    flow: &FlowField,
    reliable: &Grid<bool>,
    guess: &Intrinsics,
) -> Option<FocalEstimate> {
    if reliable.size() != flow.size() {
        return None;
    }
    let pixels = trusted_pairs(flow, reliable);
    let f0 = guess.fx;
    let at = |f: f64, idx: &[usize]| -> Vec<Correspondence> {
        idx.iter()
            .map(|&i| normalised(&pixels[i], f, guess))
            .collect()
    };
    let all: Vec<usize> = (0..pixels.len()).collect();
    let (motion, static_world) = fit(&at(f0, &all), f0)?;
    if static_world.len() < MIN_INLIERS {
        return None;
    }
    let grid: Vec<f64> = (0..GRID_STEPS)
        .map(|s| {
            let x = s as f64 / (GRID_STEPS - 1) as f64;
            f0 * exp(ln(GRID_LOW) + x * (ln(GRID_HIGH) - ln(GRID_LOW)))
        })
        .collect();
    // From the guess outwards, each focal length's motion polished from its neighbour's, so the
    // score follows one motion continuously instead of jumping between RANSAC's draws.
    let first = grid.iter().position(|&f| f >= f0).unwrap_or(0);
    let mut scores = vec![f64::INFINITY; grid.len()];
    let mut follow = |order: &mut dyn Iterator<Item = usize>| {
        let mut current = motion;
        for g in order {
            let points = at(grid[g], &static_world);
            current = refine_motion(&points, &current, POLISH_ITERATIONS);
            scores[g] = median_px2(&points, &current.essential(), grid[g]);
        }
    };
    follow(&mut (first..grid.len()));
    follow(&mut (0..first).rev());
    clear_minimum(&grid, &scores)
}

/// Every k-th trusted, known flow vector as a pixel pair ((u, v), (u', v')), at most
/// [`MAX_POINTS`].
fn trusted_pairs(flow: &FlowField, reliable: &Grid<bool>) -> Vec<[f64; 4]> {
    let width = flow.width();
    let trusted: Vec<usize> = (0..flow.len())
        .filter(|&p| reliable.data()[p] && is_known(flow.data()[p]))
        .collect();
    let step = trusted.len().div_ceil(MAX_POINTS).max(1);
    trusted
        .iter()
        .step_by(step)
        .map(|&p| {
            let (u, v) = ((p % width) as f64, (p / width) as f64);
            let [du, dv] = flow.data()[p];
            [u, v, u + f64::from(du), v + f64::from(dv)]
        })
        .collect()
}

/// A pixel pair in normalised coordinates at focal length `f` and `k`'s principal point.
fn normalised(pair: &[f64; 4], f: f64, k: &Intrinsics) -> Correspondence {
    let k = Intrinsics { fx: f, fy: f, ..*k };
    let ray = |u: f64, v: f64| Vector3::from(k.ray(u, v));
    Correspondence {
        x1: ray(pair[0], pair[1]),
        x2: ray(pair[2], pair[3]),
    }
}

/// The camera's motion fitted robustly to `points` at focal length `f` (always from the same
/// seed): the motion and the inliers within [`INLIER_PX`].
fn fit(points: &[Correspondence], f: f64) -> Option<(Motion, Vec<usize>)> {
    let mut rng = Rng::new(1);
    let (motion, inliers) = robust_motion(
        points,
        f,
        FIT_ITERATIONS,
        2.0 * INLIER_PX,
        INLIER_PX,
        MinimalSolver::FivePoint,
        &mut rng,
    )?;
    Some((motion, inliers))
}

/// The median Sampson error (px²) of `points` under the essential matrix `e` at focal length
/// `f`; infinite for no points.
fn median_px2(points: &[Correspondence], e: &nalgebra::Matrix3<f64>, f: f64) -> f64 {
    if points.is_empty() {
        return f64::INFINITY;
    }
    median(points.iter().map(|c| sampson(e, c) * f * f).collect())
}

/// The grid's minimum where it is clear (see [`MIN_RISE`]), refined by a parabola through it and
/// its two neighbours in log f.
fn clear_minimum(grid: &[f64], scores: &[f64]) -> Option<FocalEstimate> {
    let best = (0..scores.len()).min_by(|&a, &b| scores[a].total_cmp(&scores[b]))?;
    let step = (ln(grid[1]) - ln(grid[0])).abs();
    let reach = (ln(SIDE_FACTOR) / step).round() as usize;
    if best < reach || best + reach >= scores.len() || !scores[best].is_finite() {
        return None;
    }
    // A tiny floor (px²) keeps the ratio finite with exact flow (a zero score at the minimum).
    let floor = 1e-12;
    let rise = scores[best - reach].min(scores[best + reach]) + floor;
    let rise = rise / (scores[best] + floor);
    if rise.is_nan() || rise < MIN_RISE {
        return None;
    }
    let (a, b, c) = (scores[best - 1], scores[best], scores[best + 1]);
    let curvature = a - 2.0 * b + c;
    let shift = if curvature > 0.0 {
        (0.5 * (a - c) / curvature).clamp(-0.5, 0.5)
    } else {
        0.0
    };
    let focal = exp(ln(grid[best]) + shift * (ln(grid[best + 1]) - ln(grid[best])));
    focal.is_finite().then_some(FocalEstimate { focal, rise })
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Rotation3;

    const W: usize = 320;
    const H: usize = 240;

    /// The flow of a static scene of fronto-parallel slabs at depths 4–12 seen by a camera with
    /// focal length `f` that turns by `turn` (radians, Euler angles) and moves by `t`.
    fn flow_of(f: f64, turn: [f64; 3], t: Vector3<f64>) -> (FlowField, Grid<bool>) {
        let k = Intrinsics {
            fx: f,
            fy: f,
            cx: W as f64 / 2.0 - 0.5,
            cy: H as f64 / 2.0 - 0.5,
        };
        let r = Rotation3::from_euler_angles(turn[0], turn[1], turn[2]).into_inner();
        let flow = Grid::from_fn(W, H, |x, y| {
            let depth = 4.0 + ((x / 40 + 3 * (y / 40)) % 9) as f64;
            let [a, b, _] = k.ray(x as f64, y as f64);
            let moved = r * (Vector3::new(a, b, 1.0) * depth) + t;
            let [u, v] = k.project([moved.x, moved.y, moved.z]);
            [(u - x as f64) as f32, (v - y as f64) as f32]
        });
        (flow, Grid::from_fn(W, H, |_, _| true))
    }

    fn guess() -> Intrinsics {
        Intrinsics::default_for(W, H)
    }

    #[test]
    fn a_turning_and_moving_camera_fixes_its_focal_length() {
        for f in [220.0, 260.0, 400.0] {
            let (flow, reliable) = flow_of(f, [0.02, 0.05, 0.01], Vector3::new(0.3, 0.05, 0.1));
            let estimate = estimate_focal(&flow, &reliable, &guess()).expect("an estimate");
            let error = (estimate.focal / f - 1.0).abs();
            assert!(error < 0.03, "true {f}, estimated {estimate:?}");
        }
    }

    #[test]
    fn a_camera_that_only_translates_leaves_the_guess() {
        let (flow, reliable) = flow_of(260.0, [0.0; 3], Vector3::new(0.3, 0.05, 0.1));
        assert_eq!(estimate_focal(&flow, &reliable, &guess()), None);
    }

    #[test]
    fn too_little_trusted_flow_leaves_the_guess() {
        let (flow, _) = flow_of(260.0, [0.02, 0.05, 0.01], Vector3::new(0.3, 0.05, 0.1));
        // Trusted vectors spread over the whole view: 300 of them fix it, 192 are too few.
        let every = |step: usize| Grid::from_fn(W, H, move |x, y| x % step == 0 && y % step == 0);
        assert!(estimate_focal(&flow, &every(16), &guess()).is_some());
        assert_eq!(estimate_focal(&flow, &every(20), &guess()), None);
        let wrong_size = Grid::from_fn(W / 2, H, |_, _| true);
        assert_eq!(estimate_focal(&flow, &wrong_size, &guess()), None);
    }
}
