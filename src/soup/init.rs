//! The unit-scale soup: a rigid motion (R, t̂) and a plane m for every superpixel.
//!
//! 1. Correspondences: a spread-out sample of each superpixel's pixels with reliable flow.
//! 2. Motion hypotheses: a global RANSAC (camera ego-motion), sequential RANSAC on what it leaves
//!    (other movers), and local RANSAC on superpixels still unexplained together with their K-NN
//!    neighbours (small or deforming parts).
//! 3. Assignment as multi-model fitting, not a per-superpixel argmin (a planar patch is explained
//!    by many motions equally well, DESIGN.md Pitfalls): hypotheses are ordered by support (how
//!    many superpixels they explain), each superpixel takes the best-supported hypothesis that
//!    explains it, then ICM sweeps with a Potts term over touching superpixels settle borders,
//!    and each used hypothesis is refitted on the pixels assigned to it.
//! 4. Planes: for each superpixel, m from [x̄']ₓ t̂ (x̄ᵀm) = −[x̄']ₓ R x̄ by iteratively
//!    reweighted least squares; patches without parallax or behind the camera are flagged and
//!    borrow a neighbour's plane and motion.

use nalgebra::{Matrix3, Vector3};

use super::{Degeneracy, Piece, Soup};
use crate::camera::Intrinsics;
use crate::error::{Error, Result};
use crate::flow::{FlowField, is_known};
use crate::geometry::essential::{Motion, decompose, eight_point, robust_motion, sampson};
use crate::geometry::{Correspondence, skew};
use crate::grid::Grid;
use crate::rng::Rng;
use crate::superpixels::Superpixels;
use crate::superpixels::graph::KnnGraph;

/// Settings of the unit-scale soup.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct InitParams {
    /// Correspondences sampled per superpixel for motion fitting.
    pub samples_per_superpixel: usize,
    /// RANSAC samples for the global and sequential motions.
    pub global_iterations: usize,
    /// RANSAC samples for each local motion.
    pub local_iterations: usize,
    /// At most this many local RANSAC runs.
    pub max_local_hypotheses: usize,
    /// A hypothesis explains a superpixel when its mean (truncated) Sampson error is below this, px.
    pub explain_px: f64,
    /// Potts penalty (px of mean Sampson error) per touching superpixel with another hypothesis.
    pub smoothness_px: f64,
    /// Seed of the RANSAC sampling.
    pub seed: u64,
}

impl Default for InitParams {
    fn default() -> Self {
        InitParams {
            samples_per_superpixel: 40,
            global_iterations: 300,
            local_iterations: 40,
            max_local_hypotheses: 200,
            explain_px: 0.7,
            smoothness_px: 0.15,
            seed: 2017,
        }
    }
}

/// Sampson errors above this (px) count as this much in assignment costs.
const TRUNCATE_PX: f64 = 3.0;

/// Builds the unit-scale soup. `adjacency[i]` lists the superpixels touching i (boundary graph).
///
/// Errors: [`Error::NoParallax`] when too little reliable flow is left or a single camera
/// rotation explains it (identical frames, a camera turning on the spot).
pub fn unit_scale_soup(
    sp: &Superpixels,
    knn: &KnnGraph,
    adjacency: &[Vec<u32>],
    flow: &FlowField,
    reliable: &Grid<bool>,
    k: &Intrinsics,
    params: &InitParams,
) -> Result<Soup> {
    let focal = (k.fx * k.fy).sqrt();
    let samples = sample_correspondences(sp, flow, reliable, k, params.samples_per_superpixel);
    let all: Vec<Correspondence> = samples.iter().flatten().copied().collect();
    if all.len() < 50 {
        return Err(Error::NoParallax(format!(
            "only {} pixels have reliable flow",
            all.len()
        )));
    }
    check_parallax(&all, focal)?;
    let mut rng = Rng::new(params.seed);
    let mut hypotheses = global_hypotheses(&all, focal, params, &mut rng)?;
    let mut cost: Vec<Vec<f64>> = hypotheses
        .iter()
        .map(|h| samples.iter().map(|s| mean_error(h, s, focal)).collect())
        .collect();
    add_local_hypotheses(
        &samples,
        knn,
        focal,
        params,
        &mut rng,
        &mut hypotheses,
        &mut cost,
    );
    let mut assignment = assign(&cost, adjacency, params);
    refit(&samples, &mut assignment, &mut hypotheses, focal);
    let pieces = fit_planes(sp, flow, reliable, k, &hypotheses, &assignment);
    Ok(Soup {
        pieces: fill_degenerate(pieces, adjacency),
        hypotheses,
    })
}

/// Up to `per` correspondences spread over each superpixel's pixels with reliable, known flow.
fn sample_correspondences(
    sp: &Superpixels,
    flow: &FlowField,
    reliable: &Grid<bool>,
    k: &Intrinsics,
    per: usize,
) -> Vec<Vec<Correspondence>> {
    let w = flow.width();
    sp.segments
        .iter()
        .map(|seg| {
            let good: Vec<u32> = seg
                .pixels
                .iter()
                .copied()
                .filter(|&p| reliable.data()[p as usize] && is_known(flow.data()[p as usize]))
                .collect();
            let step = good.len().div_ceil(per.max(1)).max(1);
            good.iter()
                .step_by(step)
                .map(|&p| {
                    correspondence(p as usize % w, p as usize / w, flow.data()[p as usize], k)
                })
                .collect()
        })
        .collect()
}

/// The correspondence of pixel (x, y) under flow `f`, in normalised coordinates.
pub fn correspondence(x: usize, y: usize, f: [f32; 2], k: &Intrinsics) -> Correspondence {
    let (u, v) = (x as f64, y as f64);
    Correspondence {
        x1: Vector3::from(k.ray(u, v)),
        x2: Vector3::from(k.ray(u + f[0] as f64, v + f[1] as f64)),
    }
}

/// Fails when one camera rotation explains (within 0.5 px) 90 % of the correspondences: then
/// nothing in the image has parallax and depth is unobservable.
fn check_parallax(all: &[Correspondence], focal: f64) -> Result<()> {
    let mut cov = Matrix3::zeros();
    for c in all {
        cov += c.x2.normalize() * c.x1.normalize().transpose();
    }
    let svd = cov.svd(true, true);
    let (Some(u), Some(v_t)) = (svd.u, svd.v_t) else {
        return Err(Error::NoParallax("degenerate flow".into()));
    };
    let mut r = u * v_t;
    if r.determinant() < 0.0 {
        r = u * Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, -1.0)) * v_t;
    }
    let explained = all
        .iter()
        .filter(|c| {
            let p = r * c.x1;
            let d = (p / p.z - c.x2) * focal;
            p.z > 0.0 && d.x.hypot(d.y) < 0.5
        })
        .count();
    if explained as f64 >= 0.9 * all.len() as f64 {
        return Err(Error::NoParallax(format!(
            "a camera rotation alone explains {:.0} % of the flow (identical frames or a camera turning on the spot)",
            100.0 * explained as f64 / all.len() as f64
        )));
    }
    Ok(())
}

/// The ego-motion and the motions found by sequential RANSAC on the points it leaves.
fn global_hypotheses(
    all: &[Correspondence],
    focal: f64,
    params: &InitParams,
    rng: &mut Rng,
) -> Result<Vec<Motion>> {
    let stride = all.len().div_ceil(4000).max(1);
    let mut remaining: Vec<Correspondence> = all.iter().step_by(stride).copied().collect();
    let mut hypotheses = Vec::new();
    while hypotheses.len() < 10 && remaining.len() >= 150 {
        let Some((motion, inliers)) =
            robust_motion(&remaining, focal, params.global_iterations, 16.0, 1.0, rng)
        else {
            break;
        };
        if inliers.len() < 60 {
            break;
        }
        hypotheses.push(motion);
        let e = motion.essential();
        let loose = (1.5 / focal) * (1.5 / focal);
        remaining.retain(|c| sampson(&e, c) >= loose);
    }
    if hypotheses.is_empty() {
        return Err(Error::NoParallax("no rigid motion fits the flow".into()));
    }
    Ok(hypotheses)
}

/// Mean Sampson error (px, each truncated at [`TRUNCATE_PX`]) of `points` under `motion`.
fn mean_error(motion: &Motion, points: &[Correspondence], focal: f64) -> f64 {
    if points.is_empty() {
        return TRUNCATE_PX;
    }
    let e = motion.essential();
    points
        .iter()
        .map(|c| (sampson(&e, c).sqrt() * focal).min(TRUNCATE_PX))
        .sum::<f64>()
        / points.len() as f64
}

/// Local RANSAC on each still-unexplained superpixel with its K-NN neighbours, worst first.
fn add_local_hypotheses(
    samples: &[Vec<Correspondence>],
    knn: &KnnGraph,
    focal: f64,
    params: &InitParams,
    rng: &mut Rng,
    hypotheses: &mut Vec<Motion>,
    cost: &mut Vec<Vec<f64>>,
) {
    let best =
        |cost: &Vec<Vec<f64>>, i: usize| cost.iter().map(|c| c[i]).fold(f64::INFINITY, f64::min);
    let mut order: Vec<usize> = (0..samples.len())
        .filter(|&i| samples[i].len() >= 8)
        .collect();
    order.sort_by(|&a, &b| best(cost, b).total_cmp(&best(cost, a)).then(a.cmp(&b)));
    let mut runs = 0;
    for i in order {
        if runs >= params.max_local_hypotheses || best(cost, i) < params.explain_px {
            continue;
        }
        runs += 1;
        let mut points = samples[i].clone();
        for &(n, _) in &knn.neighbours[i] {
            points.extend_from_slice(&samples[n as usize]);
        }
        if let Some((motion, _)) =
            robust_motion(&points, focal, params.local_iterations, 8.0, 1.0, rng)
        {
            cost.push(
                samples
                    .iter()
                    .map(|s| mean_error(&motion, s, focal))
                    .collect(),
            );
            hypotheses.push(motion);
        }
    }
}

/// Support-ordered assignment followed by ICM with a Potts term over touching superpixels.
fn assign(cost: &[Vec<f64>], adjacency: &[Vec<u32>], params: &InitParams) -> Vec<usize> {
    let n = adjacency.len();
    let support: Vec<usize> = cost
        .iter()
        .map(|c| c.iter().filter(|&&e| e < params.explain_px).count())
        .collect();
    let mut by_support: Vec<usize> = (0..cost.len()).collect();
    by_support.sort_by(|&a, &b| support[b].cmp(&support[a]).then(a.cmp(&b)));
    let argmin = |i: usize| {
        (0..cost.len())
            .min_by(|&a, &b| cost[a][i].total_cmp(&cost[b][i]))
            .unwrap_or(0)
    };
    let mut label: Vec<usize> = (0..n)
        .map(|i| {
            by_support
                .iter()
                .copied()
                .find(|&h| cost[h][i] < params.explain_px)
                .unwrap_or_else(|| argmin(i))
        })
        .collect();
    for _ in 0..4 {
        let mut changed = false;
        for i in 0..n {
            let energy = |h: usize, label: &[usize]| {
                cost[h][i]
                    + params.smoothness_px
                        * adjacency[i]
                            .iter()
                            .filter(|&&k| label[k as usize] != h)
                            .count() as f64
            };
            let mut candidates: Vec<usize> =
                adjacency[i].iter().map(|&k| label[k as usize]).collect();
            candidates.push(argmin(i));
            let current = energy(label[i], &label);
            if let Some((h, e)) = candidates
                .into_iter()
                .map(|h| (h, energy(h, &label)))
                .min_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)))
                && e < current - 1e-9
            {
                label[i] = h;
                changed = true;
            }
        }
        if !changed {
            break;
        }
    }
    label
}

/// Refits each used hypothesis on the correspondences of its superpixels (inliers at 1.5 px).
fn refit(
    samples: &[Vec<Correspondence>],
    assignment: &mut [usize],
    hypotheses: &mut [Motion],
    focal: f64,
) {
    let loose = (1.5 / focal) * (1.5 / focal);
    for (h, motion) in hypotheses.iter_mut().enumerate() {
        let e = motion.essential();
        let points: Vec<Correspondence> = assignment
            .iter()
            .enumerate()
            .filter(|&(_, &a)| a == h)
            .flat_map(|(i, _)| samples[i].iter().copied())
            .filter(|c| sampson(&e, c) < loose)
            .collect();
        if points.len() < 40 {
            continue;
        }
        if let Some(better) = eight_point(&points).and_then(|e| decompose(&e, &points))
            && mean_error(&better, &points, focal) <= mean_error(motion, &points, focal)
        {
            *motion = better;
        }
    }
}

/// The plane of every superpixel under its assigned motion.
fn fit_planes(
    sp: &Superpixels,
    flow: &FlowField,
    reliable: &Grid<bool>,
    k: &Intrinsics,
    hypotheses: &[Motion],
    assignment: &[usize],
) -> Vec<Piece> {
    let w = flow.width();
    sp.segments
        .iter()
        .zip(assignment)
        .map(|(seg, &h)| {
            let motion = hypotheses[h];
            let good: Vec<Correspondence> = seg
                .pixels
                .iter()
                .filter(|&&p| reliable.data()[p as usize] && is_known(flow.data()[p as usize]))
                .map(|&p| {
                    correspondence(p as usize % w, p as usize / w, flow.data()[p as usize], k)
                })
                .collect();
            let step = good.len().div_ceil(150).max(1);
            let points: Vec<Correspondence> = good.into_iter().step_by(step).collect();
            let (m, degenerate) = match plane(&points, &motion) {
                Ok(m) => (m, None),
                Err(d) => (Vector3::zeros(), Some(d)),
            };
            Piece {
                r: motion.r,
                t_hat: motion.t,
                m,
                lambda: 1.0,
                hypothesis: h,
                degenerate,
            }
        })
        .collect()
}

/// The plane m (mᵀX = 1) through the correspondences under `motion`, by IRLS with Cauchy weights.
pub fn plane(
    points: &[Correspondence],
    motion: &Motion,
) -> std::result::Result<Vector3<f64>, Degeneracy> {
    if points.len() < 8 {
        return Err(Degeneracy::TooFewPixels);
    }
    let rows: Vec<(Matrix3<f64>, Vector3<f64>)> = points
        .iter()
        .map(|c| {
            let s = skew(&c.x2);
            (s * motion.t * c.x1.transpose(), -(s * motion.r * c.x1))
        })
        .collect();
    let mut weights = vec![1.0; rows.len()];
    let mut m = Vector3::zeros();
    for _ in 0..5 {
        let (mut ata, mut atb) = (Matrix3::zeros(), Vector3::zeros());
        for ((a, b), w) in rows.iter().zip(&weights) {
            ata += a.transpose() * a * *w;
            atb += a.transpose() * b * *w;
        }
        let eig = ata.symmetric_eigenvalues();
        let (lo, hi) = (eig.min(), eig.max());
        if hi.is_nan() || hi <= 0.0 || lo < 1e-9 * hi {
            return Err(Degeneracy::NoParallax);
        }
        m = ata.try_inverse().ok_or(Degeneracy::NoParallax)? * atb;
        let residuals: Vec<f64> = rows.iter().map(|(a, b)| (a * m - b).norm()).collect();
        let mut sorted = residuals.clone();
        sorted.sort_by(f64::total_cmp);
        let sigma = (1.4826 * sorted[sorted.len() / 2]).max(1e-9) * 2.0;
        weights = residuals
            .iter()
            .map(|r| 1.0 / (1.0 + (r / sigma).powi(2)))
            .collect();
    }
    let behind = points.iter().filter(|c| m.dot(&c.x1) <= 0.0).count();
    if behind * 4 > points.len() {
        return Err(Degeneracy::NegativeDepth);
    }
    Ok(m)
}

/// Gives every degenerate piece the plane and motion of a touching valid piece (the one sharing
/// the most boundary, found by breadth-first growth from valid pieces).
fn fill_degenerate(mut pieces: Vec<Piece>, adjacency: &[Vec<u32>]) -> Vec<Piece> {
    let mut filled: Vec<bool> = pieces.iter().map(|p| p.degenerate.is_none()).collect();
    if !filled.iter().any(|&f| f) {
        return pieces;
    }
    loop {
        let mut progress = false;
        for i in 0..pieces.len() {
            if filled[i] {
                continue;
            }
            if let Some(&donor) = adjacency[i].iter().find(|&&k| filled[k as usize]) {
                let d = pieces[donor as usize];
                let reason = pieces[i].degenerate;
                pieces[i] = Piece {
                    degenerate: reason,
                    ..d
                };
                filled[i] = true;
                progress = true;
            }
        }
        if !progress {
            return pieces;
        }
    }
}
