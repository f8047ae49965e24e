//! The unit-scale soup: a rigid motion (R, t̂) and a plane m for every superpixel.
//!
//! 1. Correspondences: a spread-out sample of each superpixel's pixels with reliable flow.
//! 2. Motion hypotheses: the camera's ego-motion first (hypothesis 0, `ego_candidates`: the motion
//!    under which the most superpixels are planar patches, not the one with the most epipolar
//!    inliers), then sequential RANSAC on what it leaves (other movers), then five-point RANSAC
//!    on each superpixel still badly explained together with its K-NN neighbours (small movers,
//!    deforming parts).
//! 3. Assignment as multi-model fitting (PEARL, Isack & Boykov 2012), not a per-superpixel
//!    argmin: a planar patch is explained by many motions almost equally well
//!    (docs/ARCHITECTURE.md, Pitfalls). The data cost of a superpixel under a hypothesis is the
//!    mean transfer error of the hypothesis with its best plane (the paper's E_proj); touching
//!    superpixels with different hypotheses pay a Potts penalty, and every hypothesis in use
//!    pays a label cost. α-expansion minimises that energy; each used hypothesis is then
//!    refitted on its superpixels and the assignment repeated. Finally every superpixel that the
//!    ego-motion explains about as well as its own hypothesis goes to the ego-motion
//!    (`prefer_ego_motion`): the static world is one rigid body with one scale.
//! 4. Planes: each superpixel's m under its motion by IRLS ([`super::plane`]); patches without
//!    parallax or behind the camera are flagged and borrow the plane and motion of a touching
//!    piece, the one nearest in colour first (`fill_degenerate`).

use std::collections::HashSet;

use nalgebra::{Matrix3, Vector3};

use super::plane::{fit_plane, planar_cost};
use super::{Piece, Soup};
use crate::camera::Intrinsics;
use crate::error::{Error, Result};
use crate::flow::{FlowField, is_known};
use crate::geometry::Correspondence;
use crate::geometry::essential::{
    MinimalSolver, Motion, decompose, eight_point, refine_motion, robust_motion, sampson,
};
use crate::geometry::five_point::five_point;
use crate::geometry::homography::{homography_dlt, transfer_error};
use crate::grid::Grid;
use crate::mrf::graphcut::{CostTable, alpha_expansion};
use crate::numeric::{hypot, ln};
use crate::rng::Rng;
use crate::superpixels::Superpixels;
use crate::superpixels::graph::KnnGraph;

/// Settings of the unit-scale soup.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct InitParams {
    /// Correspondences sampled per superpixel for motion fitting and assignment.
    pub samples_per_superpixel: usize,
    /// RANSAC samples for the global and sequential motions.
    pub global_iterations: usize,
    /// RANSAC samples for each local motion.
    pub local_iterations: usize,
    /// At most this many local RANSAC runs.
    pub max_local_hypotheses: usize,
    /// A hypothesis explains a superpixel when its data cost is below this (px).
    pub explain_px: f64,
    /// Potts penalty (px of mean transfer error) per touching pair with different hypotheses.
    pub smoothness_px: f64,
    /// Cost of each hypothesis in use (px of mean transfer error, summed over superpixels).
    pub label_cost_px: f64,
    /// A region of one hypothesis joins a touching region's hypothesis when that explains it at
    /// most this much worse on average (px per superpixel, beyond the fitting's noise deadband;
    /// see `merge_similar`). 0: only where the other motion explains it as well. With the
    /// sharpened flow the merges that a tolerance adds are mostly a walker joining the
    /// ego-motion or another walker's motion: from 0.6 px (the earlier value) to 0 the crowd's
    /// mean over five seeds falls 0.104 -> 0.076 and the flag's rises by 0.001; 0.1 gives the
    /// same results as 0 (docs/RESULTS.md, stop 43).
    pub merge_px: f64,
    /// ... and only where, seen under that hypothesis, its planes meet those of the region it
    /// joins: the median log-depth gap across their boundary below this (see `Surfaces::gap`).
    /// Parts of one surface meet (adjacent bands of the flag under one band's motion: 0.02–0.04,
    /// FlyingThings3D's merges 0.00–0.04); separate bodies that one motion explains about as well
    /// do not (the creature's walkers joining each other or the world: 0.27–1.6). 0.15 lies
    /// between, a kerb-sized step.
    pub merge_gap: f64,
    /// A superpixel goes to the ego-motion when that explains it at most this much worse (px of
    /// mean transfer error beyond the fitting's noise deadband) than its own hypothesis (see
    /// `prefer_ego_motion`): 0.3 px is about the computed flow's noise, so the data cannot tell
    /// the two motions apart there.
    pub ego_preference_px: f64,
    /// A hypothesis other than the ego-motion goes to the ego-motion where it makes its
    /// superpixels' surface more than this many times as rugged as the ego-motion does (the
    /// spread of ln depth over them, `spread`; see `ego_where_rugged`). Rigid motions fitted to
    /// bands of the bending flag make it 3.1–19.6 times as rugged (at the default seed, over the
    /// five members; docs/RESULTS.md, stop 54). A rigid mover's own motion mostly does the
    /// opposite, or the camera's motion puts its pieces behind the camera (every car of the
    /// street and the road). Where the other scenes' hypotheses spread more under their own (up
    /// to 4.8 times, the creature's, but for a band of its bending body at 5.85, moved), both
    /// spreads are small: see `rugged_excess`.
    pub rugged_ratio: f64,
    /// ... and by more than this much in the spread of ln depth: where the spreads under both
    /// motions are small, their ratio is noise. The flag's moved bands differ by 0.25–0.68; the
    /// other scenes' hypotheses by at most 0.11, but for one band of the creature's bending body
    /// (0.35, moved).
    pub rugged_excess: f64,
    /// At most this many windows are searched for motions (see `add_window_hypotheses`).
    /// 40, as many as the local RANSAC runs; the crowd at 1500 superpixels uses all 40, and
    /// motions that took its walkers came from windows 3 to 33.
    pub window_seeds: usize,
    /// Five-point samples drawn in each window. 50: with 30 the creature was 0.051 over five
    /// seeds (0.045 with 50), and 100 was no better than 50 (docs/RESULTS.md, stop 55).
    pub window_iterations: usize,
    /// A window is searched around a superpixel whose best cost so far (px beyond the
    /// fitting's noise deadband) is at least this, and below `explain_px`, where the local
    /// RANSAC runs already start. 0.05 px: above the rounding of the deadband, below most of
    /// the 0.01–0.56 px that the camera's motion leaves on the crowd's leftmost walker, which
    /// it explains at 1.3 times its depth.
    pub window_min_px: f64,
    /// A window's best motion becomes a hypothesis when it lowers the costs of the window's
    /// superpixels by at least this much in total (px; each cost counted up to `explain_px`).
    /// 4 px: with 2 px the motions nearest the crowd's walkers gained 2.3–9.9 px, but
    /// motions fitted to parts of the creature's bending body also took pieces of it at wrong
    /// depths (exact flow 0.028 -> 0.048; 0.036 at 4 px), and at 8 px the crowd lost its
    /// walkers' motions again at some counts (0.20 at 1300). Means over 1300–1700 superpixels
    /// at 2 / 3 / 4 / 5 / 8 px: crowd 0.072 / 0.066 / 0.054 / 0.071 / 0.10, creature 0.046 /
    /// 0.050 / 0.038 / 0.039 / 0.039 (docs/RESULTS.md, stop 55).
    pub window_gain_px: f64,
    /// A superpixel's depth counts as observed when its translation moves it by this much (px).
    pub min_parallax_px: f64,
    /// A candidate for the camera's motion whose direction of travel lies more than this many
    /// degrees from the chosen one's is its rival (see [`EgoRival`]). 5°: the best candidates
    /// of every case and preset lie within 0.6° of each other when they agree; a compromise
    /// between the camera and the crowd's walkers lies 7–11° off.
    pub rival_ego_deg: f64,
    /// The camera's motion is ambiguous when its rival scores within this share of its own
    /// planar score ([`EgoRival::excess`]); with computed flow the pipeline then makes the
    /// reconstruction again from a finer preset's flow (0 never does). 0.045: with preset fast
    /// (quarter-resolution flow) the crowd's chosen motion was a compromise 10.4° off, the depth
    /// worse than a constant, and the true motion, its rival, scored 1.9 % worse at 1500
    /// superpixels and 3.9 % at 1700; at five seeds its rival was within 1.9–2.7 % at four
    /// (11.8 % at the fifth, whose pass pins too little anyway). The flag's rival with preset
    /// fast, 3.6–3.8 %, makes it a pass with preset medium (no change in depth). With preset
    /// high no case's rival comes within 5 % at the default seeds (the crowd's 5.0 %).
    pub ambiguous_ego_excess: f64,
    /// Seed of the RANSAC sampling.
    pub seed: u64,
}

impl Default for InitParams {
    fn default() -> Self {
        InitParams {
            samples_per_superpixel: 32,
            global_iterations: 300,
            local_iterations: 20,
            max_local_hypotheses: 40,
            explain_px: 0.5,
            smoothness_px: 0.2,
            label_cost_px: 12.0,
            merge_px: 0.0,
            merge_gap: 0.15,
            ego_preference_px: 0.3,
            rugged_ratio: 3.0,
            rugged_excess: 0.2,
            window_seeds: 40,
            window_iterations: 50,
            window_min_px: 0.05,
            window_gain_px: 4.0,
            min_parallax_px: 0.05,
            rival_ego_deg: 5.0,
            ambiguous_ego_excess: 0.045,
            seed: 2017,
        }
    }
}

/// The strongest rival of the camera's motion: the best-scoring candidate (`ego_candidates`)
/// whose direction of travel lies more than [`InitParams::rival_ego_deg`] from the chosen one's.
/// A rival scoring nearly as well means the flow does not single out the camera's motion: where
/// walkers fill half the view, a compromise between them and the camera explains about as many
/// superpixels as the camera's own motion (docs/ARCHITECTURE.md, Pitfalls).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct EgoRival {
    /// The angle between its direction of travel and the chosen motion's (degrees).
    pub angle_deg: f64,
    /// How much higher its planar score is than the chosen motion's, as a share of that
    /// (0.02: 2 % higher; lower scores are better).
    pub excess: f64,
}

impl EgoRival {
    /// Whether the rival scores within `params.ambiguous_ego_excess` of the chosen motion.
    pub fn is_ambiguous(&self, params: &InitParams) -> bool {
        self.excess < params.ambiguous_ego_excess
    }
}

/// Transfer errors above this (px) count as this much in data costs.
const CAP_PX: f64 = 3.0;

/// PEARL rounds: assign, refit, re-evaluate.
const ROUNDS: usize = 3;

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
    let mut fit = Fitting {
        samples: &samples,
        focal,
        hypotheses: Vec::new(),
        costs: CostTable::new(sp.len()),
        everywhere: Vec::new(),
        deadband: 0.0,
    };
    let candidates = ego_candidates(&samples, &all, focal, params, &mut rng);
    let ego = candidates.first().map(|&(_, m)| m);
    let ego_rival = ego_rival(&candidates, params.rival_ego_deg);
    for motion in global_hypotheses(&all, ego, focal, params, &mut rng)? {
        fit.add(motion, None);
    }
    add_local_hypotheses(&mut fit, knn, params, &mut rng);
    fit.set_noise();
    add_window_hypotheses(&mut fit, knn, params, &mut rng);

    let neighbours: Vec<Vec<(u32, f32)>> = adjacency
        .iter()
        .map(|list| {
            list.iter()
                .map(|&k| (k, params.smoothness_px as f32))
                .collect()
        })
        .collect();
    let surfaces = Surfaces {
        sp,
        samples: &samples,
        k,
        focal,
        min_parallax_px: params.min_parallax_px,
    };
    let mut assignment = vec![0usize; sp.len()];
    for _ in 0..ROUNDS {
        let order = fit.by_support(params.explain_px);
        alpha_expansion(
            &fit.costs,
            &neighbours,
            params.label_cost_px as f32,
            fit.cap(),
            &order,
            &mut assignment,
            2,
        );
        merge_similar(
            &fit.costs,
            adjacency,
            params.merge_px,
            &mut assignment,
            |members, g, labels| {
                surfaces
                    .gap(members, labels, g, &fit.hypotheses[g], adjacency)
                    .is_none_or(|gap| gap < params.merge_gap)
            },
        );
        if !fit.refit(&assignment) {
            break;
        }
    }
    prefer_ego_motion(&fit.costs, params.ego_preference_px, &mut assignment);
    // The flow's noise before the rugged hypotheses' pieces go to the ego-motion: that motion
    // explains their flow worse by design (a bending read as parallax), which is not noise.
    let noise_px = flow_noise(&samples, &fit.hypotheses, &assignment, focal);
    let rugged_to_ego = ego_where_rugged(&surfaces, &fit.hypotheses, params, &mut assignment);
    let pieces = fit_planes(sp, flow, reliable, k, &fit.hypotheses, &assignment, params);
    Ok(Soup {
        pieces: fill_degenerate(pieces, sp, adjacency),
        hypotheses: fit.hypotheses,
        noise_px,
        ego_rival,
        rugged_to_ego,
    })
}

/// Gives the ego-motion (hypothesis 0) every superpixel it explains at most `margin_px` worse
/// than the superpixel's own hypothesis. `costs` are net of the fitting's noise deadband d (see
/// `Fitting::set_noise`), so errors below d count as 0: where the own hypothesis fits within d,
/// the ego-motion takes the superpixel when its raw error is at most d + `margin_px`, that is
/// when it too fits within the noise plus the margin. A planar patch is explained by many
/// motions almost equally well, and a patch of the static world that a mover's motion wins gets
/// that mover's scale: its depth is then only as good as the contacts that place the mover.
/// Under the ego-motion it shares the world's one scale (see `scales::rigid_segments`).
fn prefer_ego_motion(costs: &CostTable, margin_px: f64, labels: &mut [usize]) {
    if costs.labels() == 0 {
        return;
    }
    for (i, label) in labels.iter_mut().enumerate() {
        if (costs.get(i, 0) as f64) <= costs.get(i, *label) as f64 + margin_px {
            *label = 0;
        }
    }
}

/// Gives the ego-motion (hypothesis 0) all superpixels of every other hypothesis that makes
/// their surface far more rugged than the ego-motion does: the spread of ln depth over them
/// ([`Surfaces::log_depth_spreads`]) more than `params.rugged_ratio` times,
/// and by more than `params.rugged_excess`, the spread under the ego-motion, with at least 90 %
/// of them in front of the camera under both. A rigid motion fitted to a band of a bending sheet
/// explains the bending as parallax and tilts the band's planes to do it (the flag's folds came
/// out eight times as deep as they are); the camera's motion reads the same bending as a
/// smaller error in depth, at the world's scale. A rigid mover's own motion mostly makes its
/// surface smoother than the camera's, which puts parts of it behind the camera or far apart.
/// Returns how many superpixels it moved.
fn ego_where_rugged(
    surfaces: &Surfaces,
    hypotheses: &[Motion],
    params: &InitParams,
    labels: &mut [usize],
) -> usize {
    let Some(ego) = hypotheses.first() else {
        return 0;
    };
    let mut moved = 0;
    for (g, own) in hypotheses.iter().enumerate().skip(1) {
        let members: Vec<usize> = (0..labels.len()).filter(|&i| labels[i] == g).collect();
        if members.is_empty() {
            continue;
        }
        let Some((spread_own, spread_ego)) = surfaces.log_depth_spreads(&members, own, ego) else {
            continue;
        };
        if spread_own > params.rugged_ratio * spread_ego
            && spread_own - spread_ego > params.rugged_excess
        {
            members.iter().for_each(|&i| labels[i] = 0);
            moved += members.len();
        }
    }
    moved
}

/// The flow's noise as the assignment sees it (px): the median over superpixels with samples of
/// the mean transfer error of their motion with their best plane.
fn flow_noise(
    samples: &[Vec<Correspondence>],
    hypotheses: &[Motion],
    assignment: &[usize],
    focal: f64,
) -> f64 {
    let mut residuals: Vec<f64> = samples
        .iter()
        .zip(assignment)
        .filter(|(s, _)| !s.is_empty())
        .map(|(s, &h)| planar_cost(s, &hypotheses[h], focal, CAP_PX))
        .collect();
    residuals.sort_by(f64::total_cmp);
    residuals.get(residuals.len() / 2).copied().unwrap_or(0.0)
}

/// Joins whole regions of one hypothesis into a touching hypothesis that explains them at most
/// `merge_px` worse per superpixel on average, smallest region first, until none qualifies;
/// `meets(region, g, labels)` must also hold: the region's surface continues that of the
/// superpixels labelled g (see `Surfaces::gap`).
/// The label cost alone cannot do this for large regions: on a static scene with computed flow,
/// local motions fitted to the flow's regional biases each beat the camera motion by a little on
/// hundreds of superpixels, which splits one rigid scene into several groups of different scale.
/// On a dynamic scene the mean excess does not tell such a region from a body of its own: the
/// creature's walkers, explained by one another's motions at 0.4–0.5 px on average, were joined
/// into motions that place them at one another's depths. The default tolerance is 0 (a region
/// joins only a motion that explains it as well): with the flow's motion edges sharpened, the
/// static scenes at presets high and medium no longer need more (`InitParams::merge_px`).
fn merge_similar(
    costs: &CostTable,
    adjacency: &[Vec<u32>],
    merge_px: f64,
    labels: &mut [usize],
    meets: impl Fn(&[usize], usize, &[usize]) -> bool,
) {
    loop {
        let mut members = vec![Vec::new(); costs.labels()];
        labels
            .iter()
            .enumerate()
            .for_each(|(i, &l)| members[l].push(i));
        let mut used: Vec<usize> = (0..members.len())
            .filter(|&l| !members[l].is_empty())
            .collect();
        used.sort_by_key(|&l| (members[l].len(), l));
        let mut merged = false;
        for &h in &used {
            let mut touching: Vec<usize> = members[h]
                .iter()
                .flat_map(|&i| adjacency[i].iter().map(|&k| labels[k as usize]))
                .filter(|&g| g != h)
                .collect();
            touching.sort_unstable();
            touching.dedup();
            let worse = |g: usize| {
                members[h]
                    .iter()
                    .map(|&i| (costs.get(i, g) - costs.get(i, h)) as f64)
                    .sum::<f64>()
                    / members[h].len() as f64
            };
            let best = touching
                .into_iter()
                .map(|g| (worse(g), g))
                .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            if let Some((loss, g)) = best
                && loss <= merge_px
                && meets(&members[h], g, labels)
            {
                members[h].iter().for_each(|&i| labels[i] = g);
                merged = true;
                break;
            }
        }
        if !merged {
            return;
        }
    }
}

/// The superpixels' sampled correspondences and where they lie: what it takes to see whether
/// two regions form one surface under a motion (see [`Surfaces::gap`]).
struct Surfaces<'a> {
    sp: &'a Superpixels,
    samples: &'a [Vec<Correspondence>],
    k: &'a Intrinsics,
    focal: f64,
    min_parallax_px: f64,
}

impl Surfaces<'_> {
    /// The log-depth gap between the superpixels `members` and the touching superpixels labelled
    /// `g` (in `labels`) when all are seen under `motion`: the median, over their touching pairs,
    /// of |ln z_i − ln z_q|, each superpixel's plane fitted under `motion` to its samples and
    /// both evaluated on the ray through the midpoint of the two anchors (depths at the motion's
    /// unit translation, so comparable). Pairs where either plane puts that point behind the
    /// camera count as apart. `None` without a pair where both superpixels have a plane.
    fn gap(
        &self,
        members: &[usize],
        labels: &[usize],
        g: usize,
        motion: &Motion,
        adjacency: &[Vec<u32>],
    ) -> Option<f64> {
        // Each superpixel's plane is fitted once, however many pairs it is in.
        let mut planes = std::collections::HashMap::new();
        let mut plane = |i: usize| {
            *planes.entry(i).or_insert_with(|| {
                fit_plane(&self.samples[i], motion, self.focal, self.min_parallax_px).ok()
            })
        };
        let mut gaps = Vec::new();
        for &i in members {
            let Some(mi) = plane(i) else {
                continue;
            };
            for q in adjacency[i].iter().map(|&q| q as usize) {
                if labels[q] != g {
                    continue;
                }
                let Some(mq) = plane(q) else {
                    continue;
                };
                let (a, b) = (self.sp.segments[i].anchor, self.sp.segments[q].anchor);
                let ray = Vector3::from(self.k.ray(0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])));
                // Inverse depths 1/z = mᵀx̄ at unit translation.
                let (ui, uq) = (mi.dot(&ray), mq.dot(&ray));
                gaps.push(if ui > 0.0 && uq > 0.0 {
                    (ln(ui) - ln(uq)).abs()
                } else {
                    f64::INFINITY
                });
            }
        }
        if gaps.is_empty() {
            return None;
        }
        let mid = gaps.len() / 2;
        Some(*gaps.select_nth_unstable_by(mid, f64::total_cmp).1)
    }

    /// The spread ([`spread`]) of ln z over the superpixels `members` under motion `a`
    /// and under motion `b`: each superpixel's plane fitted under each motion to its samples and
    /// evaluated at its anchor (depths at each motion's unit translation; the spread does not
    /// depend on that scale, and is computed on ln 1/z, which spreads as much). `None` for no
    /// members, or unless at least 90 % of them have a plane under both motions that puts their
    /// anchor in front of the camera.
    fn log_depth_spreads(&self, members: &[usize], a: &Motion, b: &Motion) -> Option<(f64, f64)> {
        let log_inverse_depth = |i: usize, motion: &Motion| {
            let m = fit_plane(&self.samples[i], motion, self.focal, self.min_parallax_px).ok()?;
            let [x, y] = self.sp.segments[i].anchor;
            let u = m.dot(&Vector3::from(self.k.ray(x, y)));
            (u > 0.0 && u.is_finite()).then(|| ln(u))
        };
        let (la, lb): (Vec<f64>, Vec<f64>) = members
            .iter()
            .filter_map(|&i| Some((log_inverse_depth(i, a)?, log_inverse_depth(i, b)?)))
            .unzip();
        if la.is_empty() || la.len() * 10 < members.len() * 9 {
            return None;
        }
        Some((spread(&la), spread(&lb)))
    }
}

/// The spread of `values`: their standard deviation (0 for none). Not a robust spread: a bent
/// surface read as parallax shows in the tails (the folds of the flag's bands), which a median
/// absolute deviation or a 10th–90th percentile range discards (docs/RESULTS.md, stop 54). A
/// wild value needs a plane nearly edge-on at its anchor, which puts the samples on one side of
/// the anchor behind the camera; `fit_plane` refuses a plane with more than a quarter behind.
fn spread(values: &[f64]) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    (values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n).sqrt()
}

/// The hypotheses found so far and their data costs on every superpixel.
struct Fitting<'a> {
    samples: &'a [Vec<Correspondence>],
    focal: f64,
    hypotheses: Vec<Motion>,
    costs: CostTable,
    /// Per hypothesis: evaluated on every superpixel (not only near its seed).
    everywhere: Vec<bool>,
    /// Costs at or below this many px count as zero: differences within the flow's noise (and
    /// the planar approximation's) say nothing about which motion is right, and without the
    /// deadband a hypothesis fitted to a region's noise would win it. See [`Fitting::set_noise`].
    deadband: f64,
}

impl Fitting<'_> {
    /// Adds a hypothesis, evaluated on the superpixels in `near` (all when `None`; the rest get
    /// the capped cost). Returns its index.
    fn add(&mut self, motion: Motion, near: Option<&[usize]>) -> usize {
        let h = self.costs.push_label(self.cap());
        self.hypotheses.push(motion);
        self.everywhere.push(near.is_none());
        match near {
            Some(list) => list.iter().for_each(|&i| self.evaluate(i, h)),
            None => (0..self.samples.len()).for_each(|i| self.evaluate(i, h)),
        }
        h
    }

    fn evaluate(&mut self, i: usize, h: usize) {
        let cost = if self.samples[i].is_empty() {
            0.0 // no reliable flow: only its neighbours decide
        } else {
            planar_cost(&self.samples[i], &self.hypotheses[h], self.focal, CAP_PX)
        };
        self.costs.set(i, h, (cost - self.deadband).max(0.0) as f32);
    }

    /// The cost of a superpixel a hypothesis does not explain at all (after the deadband).
    fn cap(&self) -> f32 {
        (CAP_PX - self.deadband) as f32
    }

    /// Estimates the noise floor from the hypotheses so far: twice the 10th percentile of each
    /// superpixel's best cost (the well-explained superpixels' residual), at most 1 px. Costs
    /// are then re-evaluated with it as their deadband.
    fn set_noise(&mut self) {
        let mut best: Vec<f32> = (0..self.samples.len())
            .filter(|&i| !self.samples[i].is_empty())
            .map(|i| self.best(i))
            .collect();
        if best.is_empty() {
            return;
        }
        let at = best.len() / 10;
        let (_, q, _) = best.select_nth_unstable_by(at, f32::total_cmp);
        self.deadband = (2.0 * *q as f64).min(1.0);
        for h in 0..self.hypotheses.len() {
            for i in 0..self.samples.len() {
                let c = self.costs.get(i, h) as f64;
                self.costs.set(i, h, (c - self.deadband).max(0.0) as f32);
            }
        }
    }

    /// The best data cost of superpixel i over all hypotheses.
    fn best(&self, i: usize) -> f32 {
        (0..self.costs.labels())
            .map(|h| self.costs.get(i, h))
            .fold(f32::INFINITY, f32::min)
    }

    /// The hypotheses worth expanding, ordered by how many superpixels they explain, most first
    /// (ties: older first). A hypothesis that explains no superpixel and is no superpixel's best
    /// (within 0.05 px) cannot win any region and is left out.
    fn by_support(&self, explain_px: f64) -> Vec<usize> {
        let labels = self.costs.labels();
        let mut support = vec![0usize; labels];
        let mut best_somewhere = vec![false; labels];
        for i in 0..self.costs.nodes() {
            let best = self.best(i);
            for (h, s) in support.iter_mut().enumerate() {
                let c = self.costs.get(i, h);
                if (c as f64) < explain_px {
                    *s += 1;
                }
                if c <= best + 0.05 && c < self.cap() {
                    best_somewhere[h] = true;
                }
            }
        }
        let mut order: Vec<usize> = (0..labels)
            .filter(|&h| support[h] > 0 || best_somewhere[h])
            .collect();
        order.sort_by(|&a, &b| support[b].cmp(&support[a]).then(a.cmp(&b)));
        order
    }

    /// Refits each used hypothesis on the correspondences of its superpixels within 1.5 px of
    /// it (Levenberg–Marquardt from the current motion, which stays valid when they all lie on
    /// one plane), keeping the refit where it explains those superpixels better, and evaluates
    /// it everywhere. Returns true when any hypothesis changed.
    fn refit(&mut self, assignment: &[usize]) -> bool {
        let loose = (0.5 / self.focal).powi(2);
        let mut changed = false;
        for h in 0..self.hypotheses.len() {
            let members: Vec<usize> = (0..assignment.len())
                .filter(|&i| assignment[i] == h)
                .collect();
            if members.is_empty() {
                continue;
            }
            let e = self.hypotheses[h].essential();
            let points: Vec<Correspondence> = members
                .iter()
                .flat_map(|&i| self.samples[i].iter().copied())
                .filter(|c| sampson(&e, c) < loose)
                .collect();
            let stride = points.len().div_ceil(600).max(1);
            let points: Vec<Correspondence> = points.into_iter().step_by(stride).collect();
            // Points off one plane pin the motion down: re-estimate it linearly. On one plane a
            // linear estimate is degenerate: only polish the current motion.
            let candidate = if is_planar(&points, self.focal) {
                refine_motion(&points, &self.hypotheses[h], 6)
            } else {
                eight_point(&points)
                    .and_then(|e| decompose(&e, &points))
                    .map(|m| refine_motion(&points, &m, 6))
                    .unwrap_or(self.hypotheses[h])
            };
            let cost = |m: &Motion| {
                members
                    .iter()
                    .map(|&i| planar_cost(&self.samples[i], m, self.focal, CAP_PX))
                    .sum::<f64>()
            };
            let better = cost(&candidate) < cost(&self.hypotheses[h]) - 1e-6;
            if better {
                self.hypotheses[h] = candidate;
                changed = true;
            }
            // Used hypotheses are known everywhere from now on.
            if better || !self.everywhere[h] {
                (0..self.samples.len()).for_each(|i| self.evaluate(i, h));
                self.everywhere[h] = true;
            }
        }
        changed
    }
}

/// True when one homography transfers the points to within 0.5 px (median): they lie on one
/// plane (or show no parallax), so they cannot pin down a motion by themselves.
fn is_planar(points: &[Correspondence], focal: f64) -> bool {
    let Some(h) = homography_dlt(points) else {
        return true;
    };
    let mut errors: Vec<f64> = points
        .iter()
        .map(|c| transfer_error(&h, c) * focal)
        .collect();
    if errors.is_empty() {
        return true;
    }
    let mid = errors.len() / 2;
    let (_, median, _) = errors.select_nth_unstable_by(mid, f64::total_cmp);
    *median < 0.5
}

/// Up to `per` correspondences spread over each superpixel's pixels with reliable, known flow.
pub(super) fn sample_correspondences(
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
            p.z > 0.0 && hypot(d.x, d.y) < 0.5
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

/// Planar costs above this (px) count as this much when motions compete for the whole image in
/// [`ego_candidates`]: a superpixel this badly explained belongs to something else (0.5 px: above
/// the computed flow's noise, well below a mover's misfit).
const EGO_TRUNCATION_PX: f64 = 0.5;

/// Candidate motions [`ego_candidates`] scores by planes (5×) and then refines (1×).
const EGO_CANDIDATES: usize = 4;

/// Correspondences per superpixel when [`ego_candidates`] first scores candidates by planes: every
/// ⌊n / 8⌋-th of its n points, so 8 to 15 of them (superpixels with fewer are left out).
const EGO_LIGHT_SAMPLES: usize = 8;

/// Candidates for the camera's ego-motion with their planar scores, best first: the ego-motion is
/// the motion under which the most superpixels are explained as planar patches, scored by
/// Σ_i min(planar cost_i, 0.5 px) over superpixels (lower is better). Counting epipolar inliers
/// (RANSAC's usual score) does not find it in a crowd: a point only has to lie on its epipolar
/// line, and a compromise between the camera and the walkers puts more points within 1 px of
/// theirs than the true motion does (measured on the synthetic crowd with exact flow: 79.4 %
/// against 78.8 %), which leaves the static world with distorted planes. A plane per superpixel
/// is the stronger constraint. Candidates come from five-point samples, ranked first by epipolar
/// inliers at 1 px (the cheap score); the best 5 × [`EGO_CANDIDATES`] are scored by planes on 8–15
/// points per superpixel ([`EGO_LIGHT_SAMPLES`]), and the best [`EGO_CANDIDATES`] refined
/// (Levenberg–Marquardt on the points of the superpixels they explain, kept while the full planar
/// score falls). Empty when no sample gives a motion. The runner-up far from the first is its
/// rival ([`EgoRival`]).
fn ego_candidates(
    samples: &[Vec<Correspondence>],
    all: &[Correspondence],
    focal: f64,
    params: &InitParams,
    rng: &mut Rng,
) -> Vec<(f64, Motion)> {
    let stride = all.len().div_ceil(1000).max(1);
    let sparse: Vec<Correspondence> = all.iter().step_by(stride).copied().collect();
    if sparse.len() < 5 {
        return Vec::new();
    }
    let within = (1.0 / focal).powi(2);
    let mut ranked: Vec<(usize, Motion)> = Vec::new();
    for _ in 0..params.global_iterations {
        let pick: Vec<Correspondence> = rng
            .sample_distinct(sparse.len(), 5)
            .into_iter()
            .map(|i| sparse[i])
            .collect();
        for e in five_point(&pick) {
            let count = sparse.iter().filter(|c| sampson(&e, c) < within).count();
            if let Some(m) = decompose(&e, &pick) {
                ranked.push((count, m));
            }
        }
    }
    ranked.sort_by_key(|r| std::cmp::Reverse(r.0));
    ranked.truncate(5 * EGO_CANDIDATES);
    // Superpixels with enough points to need a plane.
    let full: Vec<&[Correspondence]> = samples
        .iter()
        .filter(|s| s.len() >= EGO_LIGHT_SAMPLES)
        .map(Vec::as_slice)
        .collect();
    let light: Vec<Vec<Correspondence>> = full.iter().map(|s| light_samples(s)).collect();
    let score = |m: &Motion, set: &mut dyn Iterator<Item = &[Correspondence]>| -> f64 {
        set.map(|s| planar_cost(s, m, focal, CAP_PX).min(EGO_TRUNCATION_PX))
            .sum()
    };
    let mut scored: Vec<(f64, Motion)> = ranked
        .into_iter()
        .map(|(_, m)| (score(&m, &mut light.iter().map(Vec::as_slice)), m))
        .collect();
    scored.sort_by(|a, b| a.0.total_cmp(&b.0));
    scored.truncate(EGO_CANDIDATES);
    let full_score = |m: &Motion| score(m, &mut full.iter().copied());
    let explained = |m: &Motion| -> Vec<Correspondence> {
        full.iter()
            .filter(|s| planar_cost(s, m, focal, CAP_PX) < EGO_TRUNCATION_PX)
            .flat_map(|s| s.iter().step_by(2).copied())
            .collect()
    };
    let mut refined: Vec<(f64, Motion)> = scored
        .into_iter()
        .map(|(_, m)| polish(m, full_score, explained))
        .collect();
    refined.sort_by(|a, b| a.0.total_cmp(&b.0));
    refined
}

/// Every ⌊n / [`EGO_LIGHT_SAMPLES`]⌋-th of the n correspondences `points` (8 to 15 of them when
/// n ≥ 8): enough to score a motion by a superpixel's plane at a fraction of the cost.
fn light_samples(points: &[Correspondence]) -> Vec<Correspondence> {
    let step = (points.len() / EGO_LIGHT_SAMPLES).max(1);
    points.iter().step_by(step).copied().collect()
}

/// `start` refined by Levenberg–Marquardt on the correspondences `points` picks for the current
/// motion, for as long as `score` (lower is better) falls, at most 3 rounds; with its score.
fn polish(
    start: Motion,
    score: impl Fn(&Motion) -> f64,
    points: impl Fn(&Motion) -> Vec<Correspondence>,
) -> (f64, Motion) {
    let (mut best, mut m) = (score(&start), start);
    for _ in 0..3 {
        let candidate = refine_motion(&points(&m), &m, 8);
        let e = score(&candidate);
        if e < best - 1e-9 {
            (best, m) = (e, candidate);
        } else {
            break;
        }
    }
    (best, m)
}

/// The rival ([`EgoRival`]) of the first of `candidates` ((planar score, motion), best first)
/// among the others more than `min_angle_deg` away from it.
fn ego_rival(candidates: &[(f64, Motion)], min_angle_deg: f64) -> Option<EgoRival> {
    let (&(best, chosen), others) = candidates.split_first()?;
    others
        .iter()
        .map(|(score, m)| (score, m.translation_angle(&chosen).to_degrees()))
        .filter(|&(_, angle)| angle > min_angle_deg)
        .min_by(|a, b| a.0.total_cmp(b.0))
        .map(|(score, angle_deg)| EgoRival {
            angle_deg,
            excess: (score - best) / best.max(f64::MIN_POSITIVE),
        })
}

/// The ego-motion (`ego`, when found; else the first RANSAC motion stands in for it) and the
/// motions found by sequential RANSAC on the points it leaves.
fn global_hypotheses(
    all: &[Correspondence],
    ego: Option<Motion>,
    focal: f64,
    params: &InitParams,
    rng: &mut Rng,
) -> Result<Vec<Motion>> {
    let stride = all.len().div_ceil(4000).max(1);
    let mut remaining: Vec<Correspondence> = all.iter().step_by(stride).copied().collect();
    let mut hypotheses = Vec::new();
    if let Some(motion) = ego {
        hypotheses.push(motion);
        let e = motion.essential();
        let loose = (1.5 / focal) * (1.5 / focal);
        remaining.retain(|c| sampson(&e, c) >= loose);
    }
    while hypotheses.len() < 10 && remaining.len() >= 150 {
        let Some((motion, inliers)) = robust_motion(
            &remaining,
            focal,
            params.global_iterations,
            16.0,
            1.0,
            MinimalSolver::EightPoint,
            rng,
        ) else {
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

/// Five-point RANSAC on still badly explained superpixels with their K-NN neighbours, worst
/// first; a seed's neighbours are covered by its run and seed no run of their own, so runs
/// spread over the image. Each new hypothesis is evaluated on the seed's neighbours and theirs.
fn add_local_hypotheses(fit: &mut Fitting, knn: &KnnGraph, params: &InitParams, rng: &mut Rng) {
    let n = fit.samples.len();
    let mut order: Vec<usize> = (0..n).filter(|&i| fit.samples[i].len() >= 8).collect();
    let best: Vec<f32> = (0..n).map(|i| fit.best(i)).collect();
    order.sort_by(|&a, &b| best[b].total_cmp(&best[a]).then(a.cmp(&b)));
    let mut runs = 0;
    let mut mark = vec![false; n];
    let mut covered = vec![false; n];
    for seed in order {
        if runs >= params.max_local_hypotheses
            || covered[seed]
            || (fit.best(seed) as f64) < params.explain_px
        {
            continue;
        }
        runs += 1;
        covered[seed] = true;
        knn.neighbours[seed]
            .iter()
            .for_each(|&(k, _)| covered[k as usize] = true);
        // Every third sample of the seed and its neighbours: enough points, a third of the work.
        let points: Vec<Correspondence> = std::iter::once(seed)
            .chain(knn.neighbours[seed].iter().map(|&(k, _)| k as usize))
            .flat_map(|i| fit.samples[i].iter().step_by(3).copied())
            .collect();
        let Some((motion, _)) = robust_motion(
            &points,
            fit.focal,
            params.local_iterations,
            2.0,
            1.0,
            MinimalSolver::FivePoint,
            rng,
        ) else {
            continue;
        };
        let mut near = vec![seed];
        mark[seed] = true;
        for &(k, _) in &knn.neighbours[seed] {
            for j in std::iter::once(k).chain(knn.neighbours[k as usize].iter().map(|e| e.0)) {
                if !mark[j as usize] {
                    mark[j as usize] = true;
                    near.push(j as usize);
                }
            }
        }
        near.iter().for_each(|&j| mark[j] = false);
        fit.add(motion, Some(&near));
    }
}

/// Searches motions in windows around the superpixels that the hypotheses so far explain only
/// roughly (best cost between `params.window_min_px` and `explain_px`, worst first, with at
/// least [`EGO_LIGHT_SAMPLES`] correspondences; at most `params.window_seeds` windows, none
/// around a superpixel already in one): each window is the seed with its K-NN neighbours and
/// theirs (about 50 superpixels). Candidates come from `params.window_iterations` five-point
/// samples, one point from each of five of the window's superpixels, and are scored by their
/// gain: how much they lower the window's costs (each superpixel with its best plane, costs
/// counted up to `explain_px`) below the best costs before the search ([`best_in_window`]; the
/// costs are not lowered as windows add motions, so overlapping windows may add near copies of
/// one motion). The best, polished by Levenberg–Marquardt on the superpixels it explains
/// better, becomes a hypothesis (evaluated around the window) when its gain over all their
/// correspondences is at least `params.window_gain_px`.
///
/// Why: the camera's motion explains the crowd's leftmost walker, who moves along the camera's
/// direction of travel, within 0.01–0.56 px at 1.3 times its depth, so no local RANSAC starts
/// there; and the walker's own motion is found neither from 16 superpixels of one of its sides
/// (one plane: a motion fitted to it is one of a family, and the other reading of that plane
/// explains the other side no better than the camera's) nor by counting epipolar inliers
/// (within a pixel, compromises count as many). Over a window that spans both of its sides the
/// planes pin it: the motions found there lie about 4° from the walker's.
fn add_window_hypotheses(fit: &mut Fitting, knn: &KnnGraph, params: &InitParams, rng: &mut Rng) {
    let n = fit.samples.len();
    let best: Vec<f64> = (0..n).map(|i| fit.best(i) as f64).collect();
    let mut order: Vec<usize> = (0..n)
        .filter(|&i| fit.samples[i].len() >= EGO_LIGHT_SAMPLES)
        .filter(|&i| best[i] >= params.window_min_px && best[i] < params.explain_px)
        .collect();
    order.sort_by(|&a, &b| best[b].total_cmp(&best[a]).then(a.cmp(&b)));
    let mut covered = vec![false; n];
    let mut windows = 0;
    for seed in order {
        if windows >= params.window_seeds {
            break;
        }
        if covered[seed] {
            continue;
        }
        windows += 1;
        let window = knn_rings(knn, &[seed], 2);
        window.iter().for_each(|&i| covered[i] = true);
        let Some((gain, motion)) = best_in_window(fit, &window, &best, params, rng) else {
            continue;
        };
        if gain >= params.window_gain_px {
            fit.add(motion, Some(&knn_rings(knn, &window, 1)));
        }
    }
}

/// `start` with the superpixels up to `rings` steps away from it in the K-NN graph, each once,
/// `start` first.
fn knn_rings(knn: &KnnGraph, start: &[usize], rings: usize) -> Vec<usize> {
    let mut seen: HashSet<usize> = start.iter().copied().collect();
    let mut all = start.to_vec();
    let mut from = 0;
    for _ in 0..rings {
        let to = all.len();
        for i in from..to {
            for &(k, _) in &knn.neighbours[all[i]] {
                if seen.insert(k as usize) {
                    all.push(k as usize);
                }
            }
        }
        from = to;
    }
    all
}

/// The motion that lowers the costs of `window`'s superpixels most below `best` (their best
/// costs so far, px beyond the deadband), with that gain (see [`add_window_hypotheses`]). The
/// candidates are ranked by their gain on [`light_samples`] of each superpixel, summed most
/// open superpixel first; a candidate is dropped as soon as what it may still gain cannot lift
/// it above the best so far (the same winner, at a fraction of the planes fitted). The winner is
/// polished and its gain taken over all the correspondences. `None` when the window has fewer
/// than five superpixels with enough correspondences, when even explaining all of them would
/// gain less than `params.window_gain_px`, or when no sample gives a motion.
fn best_in_window(
    fit: &Fitting,
    window: &[usize],
    best: &[f64],
    params: &InitParams,
    rng: &mut Rng,
) -> Option<(f64, Motion)> {
    let (focal, d, cap) = (fit.focal, fit.deadband, params.explain_px);
    let sampled: Vec<usize> = (window.iter().copied())
        .filter(|&i| fit.samples[i].len() >= EGO_LIGHT_SAMPLES)
        .collect();
    if sampled.len() < 5 {
        return None;
    }
    // The draws come first and every window makes them, so that which windows are skipped
    // below changes no later window's draws.
    let picks: Vec<Vec<Correspondence>> = (0..params.window_iterations)
        .map(|_| {
            (rng.sample_distinct(sampled.len(), 5).into_iter())
                .map(|j| {
                    let points = &fit.samples[sampled[j]];
                    points[rng.below(points.len())]
                })
                .collect()
        })
        .collect();
    // Only superpixels not yet explained within the deadband can gain.
    let mut open: Vec<usize> = sampled.iter().copied().filter(|&i| best[i] > 0.0).collect();
    open.sort_by(|&a, &b| best[b].total_cmp(&best[a]).then(a.cmp(&b)));
    // What the open superpixels from the k-th on can gain at most.
    let mut left = vec![0.0; open.len() + 1];
    for k in (0..open.len()).rev() {
        left[k] = left[k + 1] + best[open[k]].min(cap);
    }
    // A window that could not gain `window_gain_px` even if every open superpixel were
    // explained is not searched (most windows of a static scene).
    if left[0] < params.window_gain_px {
        return None;
    }
    let light: Vec<Vec<Correspondence>> = open
        .iter()
        .map(|&i| light_samples(&fit.samples[i]))
        .collect();
    let gain = |i: usize, points: &[Correspondence], m: &Motion| {
        let cost = (planar_cost(points, m, focal, CAP_PX) - d).max(0.0);
        (best[i].min(cap) - cost.min(cap)).max(0.0)
    };
    let mut top: Option<(f64, Motion)> = None;
    for pick in &picks {
        for e in five_point(pick) {
            let Some(m) = decompose(&e, pick) else {
                continue;
            };
            let bar = top.map_or(f64::NEG_INFINITY, |(g, _)| g);
            let (mut g, mut k) = (0.0, 0);
            while k < open.len() && g + left[k] > bar {
                g += gain(open[k], &light[k], &m);
                k += 1;
            }
            if k == open.len() && g > bar {
                top = Some((g, m));
            }
        }
    }
    let (_, start) = top?;
    let loss = |m: &Motion| -> f64 {
        -(open.iter())
            .map(|&i| gain(i, &fit.samples[i], m))
            .sum::<f64>()
    };
    let improved = |m: &Motion| -> Vec<Correspondence> {
        (open.iter())
            .filter(|&&i| planar_cost(&fit.samples[i], m, focal, CAP_PX) - d < best[i])
            .flat_map(|&i| fit.samples[i].iter().step_by(2).copied())
            .collect()
    };
    let (loss, m) = polish(start, loss, improved);
    Some((-loss, m))
}

/// The plane of every superpixel under its assigned motion, from up to 100 of its pixels.
fn fit_planes(
    sp: &Superpixels,
    flow: &FlowField,
    reliable: &Grid<bool>,
    k: &Intrinsics,
    hypotheses: &[Motion],
    assignment: &[usize],
    params: &InitParams,
) -> Vec<Piece> {
    let focal = (k.fx * k.fy).sqrt();
    sample_correspondences(sp, flow, reliable, k, 100)
        .iter()
        .zip(assignment)
        .map(|(points, &h)| {
            let motion = hypotheses[h];
            let (m, degenerate) = match fit_plane(points, &motion, focal, params.min_parallax_px) {
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

/// Gives every degenerate piece the plane and motion of a touching piece that has them,
/// nearest colours first: the filled region grows from the valid pieces, each step filling the
/// degenerate piece whose colour (mean CIELAB) is nearest to that of a filled neighbour, from
/// that neighbour. A piece without trusted flow usually lies on the same surface as the
/// touching piece that looks like it (a thin strap of an object whose flow the check rejects
/// is more like the rest of the strap than like the wall behind it). Ties go to the lower
/// indices, so the result is the same on every run.
fn fill_degenerate(mut pieces: Vec<Piece>, sp: &Superpixels, adjacency: &[Vec<u32>]) -> Vec<Piece> {
    use std::cmp::Reverse;
    use std::collections::BinaryHeap;
    let mut filled: Vec<bool> = pieces.iter().map(|p| p.degenerate.is_none()).collect();
    // Squared colour distances are finite and non-negative, so their bit patterns order as
    // they do.
    let distance = |a: usize, b: usize| {
        let (p, q) = (sp.segments[a].mean_lab, sp.segments[b].mean_lab);
        let d2: f32 = (0..3).map(|c| (p[c] - q[c]) * (p[c] - q[c])).sum();
        d2.to_bits()
    };
    let mut frontier = BinaryHeap::new();
    let offer = |frontier: &mut BinaryHeap<_>, donor: usize, filled: &[bool]| {
        for &i in &adjacency[donor] {
            if !filled[i as usize] {
                frontier.push(Reverse((distance(i as usize, donor), i, donor as u32)));
            }
        }
    };
    for donor in 0..pieces.len() {
        if filled[donor] {
            offer(&mut frontier, donor, &filled);
        }
    }
    while let Some(Reverse((_, i, donor))) = frontier.pop() {
        let (i, donor) = (i as usize, donor as usize);
        if filled[i] {
            continue;
        }
        pieces[i] = Piece {
            degenerate: pieces[i].degenerate,
            ..pieces[donor]
        };
        filled[i] = true;
        offer(&mut frontier, i, &filled);
    }
    pieces
}

#[cfg(test)]
mod tests {
    use super::*;

    const FOCAL: f64 = 500.0;

    fn camera() -> Motion {
        Motion {
            r: nalgebra::Rotation3::from_euler_angles(0.01, -0.02, 0.005).into_inner(),
            t: Vector3::new(1.0, 0.1, 0.05).normalize(),
        }
    }

    /// 60 superpixels of 30 points each: small patches on fronto-parallel planes at depths 3 to
    /// 12 (at unit translation) spread over the image, seen under `motion`, with `noise_px` of
    /// Gaussian noise added to their frame-2 positions.
    fn patches(motion: &Motion, noise_px: f64, rng: &mut Rng) -> Vec<Vec<Correspondence>> {
        (0..60)
            .map(|i| {
                let centre = [(i % 10) as f64 * 0.08 - 0.36, (i / 10) as f64 * 0.08 - 0.2];
                let m = Vector3::new(0.0, 0.0, 1.0 / (3.0 + (i * 7 % 10) as f64));
                (0..30)
                    .map(|_| {
                        let ray = Vector3::new(
                            centre[0] + 0.03 * rng.uniform(),
                            centre[1] + 0.03 * rng.uniform(),
                            1.0,
                        );
                        let x = ray / m.dot(&ray);
                        let moved = motion.r * x + motion.t;
                        let noise =
                            Vector3::new(rng.normal(), rng.normal(), 0.0) * noise_px / FOCAL;
                        Correspondence {
                            x1: ray,
                            x2: moved / moved.z + noise,
                        }
                    })
                    .collect()
            })
            .collect()
    }

    #[test]
    fn the_flow_noise_is_the_median_planar_residual() {
        let motion = camera();
        let exact = patches(&motion, 0.0, &mut Rng::new(1));
        let assignment = vec![0; exact.len()];
        let none = flow_noise(&exact, &[motion], &assignment, FOCAL);
        assert!(none < 1e-6, "exact flow: {none} px");
        // Gaussian noise of σ px gives a mean 2D error of σ √(π/2) ≈ 1.25 σ, a little less after
        // each patch's plane absorbs some of it.
        let mut noisy = patches(&motion, 0.4, &mut Rng::new(2));
        let noise = flow_noise(&noisy, &[motion], &assignment, FOCAL);
        assert!((0.4..0.52).contains(&noise), "0.4 px noise: {noise} px");
        // Superpixels without samples do not count; none at all gives 0.
        noisy.extend(std::iter::repeat_with(Vec::new).take(100));
        let padded = flow_noise(&noisy, &[motion], &vec![0; noisy.len()], FOCAL);
        assert_eq!(padded, noise);
        assert_eq!(flow_noise(&[], &[motion], &[], FOCAL), 0.0);
    }

    #[test]
    fn the_ego_motion_is_found_by_planes_and_ransac_stands_in_without_it() {
        let motion = camera();
        let samples = patches(&motion, 0.2, &mut Rng::new(3));
        let all: Vec<Correspondence> = samples.iter().flatten().copied().collect();
        let params = InitParams::default();
        let angle = |m: &Motion| m.translation_angle(&motion).to_degrees();
        let candidates = ego_candidates(&samples, &all, FOCAL, &params, &mut Rng::new(4));
        let &(_, ego) = candidates.first().expect("a motion from 1800 points");
        assert!(angle(&ego) < 0.5, "ego-motion {:.2}° off", angle(&ego));
        assert!(
            candidates.windows(2).all(|w| w[0].0 <= w[1].0),
            "best first"
        );
        // Too few points for a five-point sample: no ego-motion, and the first RANSAC motion
        // stands in as hypothesis 0.
        assert!(ego_candidates(&samples, &all[..4], FOCAL, &params, &mut Rng::new(4)).is_empty());
        let hypotheses = global_hypotheses(&all, None, FOCAL, &params, &mut Rng::new(5)).unwrap();
        assert!(
            angle(&hypotheses[0]) < 0.5,
            "RANSAC {:.2}° off",
            angle(&hypotheses[0])
        );
    }

    #[test]
    fn the_rival_is_the_best_candidate_far_from_the_chosen_motion() {
        // The camera's motion with its direction of travel turned by `deg` about an axis
        // across it.
        let turned = |deg: f64, score: f64| {
            let m = camera();
            let across = nalgebra::Unit::new_normalize(m.t.cross(&Vector3::y()));
            let t = nalgebra::Rotation3::from_axis_angle(&across, deg.to_radians()) * m.t;
            (score, Motion { r: m.r, t })
        };
        // A near twin (1°) scores best after the chosen motion but is no rival; of the two far
        // ones the better (8°, 2 % worse) is.
        let candidates = [
            turned(0.0, 100.0),
            turned(1.0, 100.5),
            turned(8.0, 102.0),
            turned(-12.0, 101.0 + 5.0),
        ];
        let rival = ego_rival(&candidates, 5.0).expect("a rival 8° away");
        assert!((rival.angle_deg - 8.0).abs() < 1e-6, "{rival:?}");
        assert!((rival.excess - 0.02).abs() < 1e-12, "{rival:?}");
        let params = InitParams::default();
        assert!(
            rival.is_ambiguous(&params),
            "2 % is within the default 4.5 %"
        );
        let clear = EgoRival {
            excess: 0.05,
            ..rival
        };
        assert!(!clear.is_ambiguous(&params));
        // Only near twins, or one candidate: no rival.
        assert!(ego_rival(&candidates[..2], 5.0).is_none());
        assert!(ego_rival(&candidates[..1], 5.0).is_none());
        assert!(ego_rival(&[], 5.0).is_none());
    }

    #[test]
    fn the_ego_motion_takes_what_it_explains_about_as_well() {
        // Superpixel 0: ego 0.1 px, own 0.0 → ego. 1: ego 0.5, own 0.1 → stays. 2: already ego.
        let mut costs = CostTable::new(3);
        costs.push_label(3.0);
        costs.push_label(3.0);
        for (i, (ego, own)) in [(0.1, 0.0), (0.5, 0.1), (0.0, 2.0)].into_iter().enumerate() {
            costs.set(i, 0, ego);
            costs.set(i, 1, own);
        }
        let mut labels = vec![1, 1, 0];
        prefer_ego_motion(&costs, 0.3, &mut labels);
        assert_eq!(labels, vec![0, 1, 0]);
    }

    /// Superpixels of one pixel each in a row, of mean colours `lab` (CIELAB), their anchors
    /// `spacing` px apart along the top row.
    fn pixel_row(lab: &[[f32; 3]], spacing: f64) -> Superpixels {
        let segments = lab
            .iter()
            .enumerate()
            .map(|(i, &mean_lab)| crate::superpixels::Segment {
                pixels: vec![i as u32],
                anchor: [spacing * i as f64, 0.0],
                mean_lab,
                mean_rgb: [0; 3],
                bbox: [i as u32, 0, i as u32, 0],
            })
            .collect();
        Superpixels {
            labels: Grid::from_fn(lab.len(), 1, |x, _| x as u32),
            segments,
        }
    }

    #[test]
    fn regions_meet_where_their_planes_continue_under_one_motion() {
        // Three superpixels in a row, 40 px apart, on fronto-parallel planes at depths 4, 4 and
        // 8 (at unit translation), seen under one motion: 0 and 1 form one surface, 1 and 2 a
        // step of ln 2 in log-depth.
        let motion = camera();
        let planes = [4.0, 4.0, 8.0].map(|d| Vector3::new(0.0, 0.0, 1.0 / d));
        let (sp, samples, k) = planar_row(&planes, &[motion; 3]);
        let surfaces = surfaces_of(&sp, &samples, &k);
        let adjacency = vec![vec![1], vec![0, 2], vec![1]];
        // Superpixel 0 alone (label 1) beside 1 and 2 (label 0): one surface.
        let same = surfaces.gap(&[0], &[1, 0, 0], 0, &motion, &adjacency);
        assert!(same.is_some_and(|g| g < 0.01), "{same:?}");
        // Superpixel 2 alone beside 0 and 1: the step.
        let step = surfaces.gap(&[2], &[0, 0, 1], 0, &motion, &adjacency);
        assert!(
            step.is_some_and(|g| (g - 2f64.ln()).abs() < 0.01),
            "{step:?}"
        );
        // Nothing labelled 0 touches superpixel 0: no gap to measure.
        assert_eq!(surfaces.gap(&[0], &[1, 2, 2], 0, &motion, &adjacency), None);
    }

    /// Superpixels of one pixel each in a row, 40 px apart (`pixel_row`), each with 30
    /// correspondences within 10 px right of and below its anchor on the plane `planes[i]` (mᵀX = 1, at unit translation)
    /// seen under `motions[i]`, and the intrinsics they are seen with.
    fn planar_row(
        planes: &[Vector3<f64>],
        motions: &[Motion],
    ) -> (Superpixels, Samples, Intrinsics) {
        let k = Intrinsics {
            fx: FOCAL,
            fy: FOCAL,
            cx: 20.0 * (planes.len() - 1) as f64,
            cy: 0.0,
        };
        let mut rng = Rng::new(11);
        let samples = planes
            .iter()
            .zip(motions)
            .enumerate()
            .map(|(i, (m, motion))| {
                let centre = Vector3::from(k.ray(40.0 * i as f64, 0.0));
                (0..30)
                    .map(|_| {
                        let ray =
                            centre + Vector3::new(0.02 * rng.uniform(), 0.02 * rng.uniform(), 0.0);
                        let moved = motion.r * (ray / m.dot(&ray)) + motion.t;
                        Correspondence {
                            x1: ray,
                            x2: moved / moved.z,
                        }
                    })
                    .collect()
            })
            .collect();
        (pixel_row(&vec![[0.0; 3]; planes.len()], 40.0), samples, k)
    }

    type Samples = Vec<Vec<Correspondence>>;

    /// The surfaces of the superpixels `sp` with `samples`, seen with `k` (focal [`FOCAL`]).
    fn surfaces_of<'a>(
        sp: &'a Superpixels,
        samples: &'a [Vec<Correspondence>],
        k: &'a Intrinsics,
    ) -> Surfaces<'a> {
        Surfaces {
            sp,
            samples,
            k,
            focal: FOCAL,
            min_parallax_px: 0.05,
        }
    }

    /// Planes mᵀX = 1 tilted the same way, at depth `d` on the optical axis for each of `depths`
    /// (at unit translation).
    fn tilted(depths: &[f64]) -> Vec<Vector3<f64>> {
        depths
            .iter()
            .map(|&d| Vector3::new(0.3, -0.2, 1.0) / d)
            .collect()
    }

    /// A motion whose translation shifts the points along +x, and the same with its rotation
    /// turned by `turn` radians about y: that turn adds about −`turn` to every inverse depth the
    /// motion reads from the first one's flow (its rotation shifts points along x as its
    /// translation does).
    fn sideways(turn: f64) -> (Motion, Motion) {
        let r = nalgebra::Rotation3::from_euler_angles(0.01, -0.02, 0.005).into_inner();
        let t = Vector3::new(1.0, 0.0, 0.0);
        let turned = nalgebra::Rotation3::from_euler_angles(0.0, turn, 0.0).into_inner() * r;
        (Motion { r, t }, Motion { r: turned, t })
    }

    #[test]
    fn the_log_depth_spread_is_that_of_the_true_depths_under_the_true_motion() {
        // Five tilted planes at depths 20–90 (at unit translation), seen under one motion.
        let planes = tilted(&[20.0, 80.0, 30.0, 90.0, 25.0]);
        let (motion, turned) = sideways(-0.05);
        let (sp, samples, k) = planar_row(&planes, &[motion; 5]);
        let surfaces = surfaces_of(&sp, &samples, &k);
        let truth: Vec<f64> = (0..5)
            .map(|i| {
                let [x, y] = sp.segments[i].anchor;
                -ln(planes[i].dot(&Vector3::from(k.ray(x, y))))
            })
            .collect();
        let truth = spread(&truth);
        let members = [0, 1, 2, 3, 4];
        let (own, read) = surfaces
            .log_depth_spreads(&members, &motion, &turned)
            .unwrap();
        assert!((own - truth).abs() < 1e-3, "{own} against {truth}");
        // The turned motion reads inverse depths about 0.05 larger: a flatter surface.
        assert!(read < 0.5 * own, "{read} against {own}");
        // Under the opposite translation every plane lies behind the camera.
        let backwards = Motion {
            r: motion.r,
            t: -motion.t,
        };
        assert_eq!(
            surfaces.log_depth_spreads(&members, &motion, &backwards),
            None
        );
        assert_eq!(surfaces.log_depth_spreads(&[], &motion, &motion), None);
    }

    #[test]
    fn a_motion_that_makes_its_surface_rugged_goes_to_the_ego_motion() {
        // Pieces 0–4: tilted planes at depths 20–90 under motion 1, which the ego-motion (0)
        // reads as a far flatter surface: motion 1 explains a smooth surface's flow as relief.
        // Pieces 5–7: the ego-motion's own, on one smooth surface. Pieces 8–10: a mover
        // (motion 2) whose smooth surface the ego-motion spreads more. Pieces 11–13: a mover
        // travelling against the camera (motion 3), which the ego-motion puts behind it: its
        // surface has no depth to compare there, and it keeps its motion.
        let (own, ego) = sideways(-0.1);
        let mover = Motion {
            r: own.r,
            t: Vector3::new(-1.0, 0.2, 0.0).normalize(),
        };
        let against = Motion {
            r: ego.r,
            t: -ego.t,
        };
        let planes = tilted(&[
            20.0, 80.0, 30.0, 90.0, 25.0, 40.0, 42.0, 44.0, 30.0, 31.0, 32.0, 20.0, 80.0, 30.0,
        ]);
        let motions: Vec<Motion> = (0..14)
            .map(|i| match i {
                0..=4 => own,
                5..=7 => ego,
                8..=10 => mover,
                _ => against,
            })
            .collect();
        let (sp, samples, k) = planar_row(&planes, &motions);
        let surfaces = surfaces_of(&sp, &samples, &k);
        let hypotheses = [ego, own, mover, against];
        let start = vec![1, 1, 1, 1, 1, 0, 0, 0, 2, 2, 2, 3, 3, 3];
        let params = InitParams::default();
        let mut labels = start.clone();
        let moved = ego_where_rugged(&surfaces, &hypotheses, &params, &mut labels);
        assert_eq!(labels, vec![0, 0, 0, 0, 0, 0, 0, 0, 2, 2, 2, 3, 3, 3]);
        assert_eq!(moved, 5);
        // Not where the relief is less than `rugged_ratio` times the ego-motion's, nor where it
        // exceeds the ego-motion's by less than `rugged_excess` (here about 0.5).
        for strict in [
            InitParams {
                rugged_ratio: 100.0,
                ..params
            },
            InitParams {
                rugged_excess: 0.8,
                ..params
            },
        ] {
            let mut labels = start.clone();
            assert_eq!(
                ego_where_rugged(&surfaces, &hypotheses, &strict, &mut labels),
                0
            );
            assert_eq!(labels, start);
        }
    }

    /// A box turning by 3.4° about its vertical axis while it moves sideways, 4 units in front of
    /// the camera (at unit camera translation), its corner facing the camera: 24 superpixels on
    /// its left face and 24 on its right, each 30 points, in a grid of 8 × 6 patch centres with
    /// 0.1 px of noise; and the box's motion as camera 2 sees it (the camera's `camera()` motion
    /// after the box's).
    fn turning_box(rng: &mut Rng) -> (Vec<Vec<Correspondence>>, Vec<[f64; 2]>, Motion) {
        let centre = Vector3::new(0.0, 0.0, 4.0);
        let corner = Vector3::new(0.0, 0.0, 3.6);
        let faces = [
            Vector3::new(-1.0, 0.0, -1.0).normalize(),
            Vector3::new(1.0, 0.0, -1.0).normalize(),
        ]
        .map(|n| n / n.dot(&corner)); // m with mᵀX = 1 through the corner
        let turn = nalgebra::Rotation3::from_euler_angles(0.0, -0.06, 0.0).into_inner();
        let shift = Vector3::new(0.9, 0.0, 0.4);
        let cam = camera();
        let r = cam.r * turn;
        let t = cam.r * (centre - turn * centre + shift) + cam.t;
        let truth = Motion {
            r,
            t: t.normalize(),
        };
        let mut samples = Vec::new();
        let mut centres = Vec::new();
        for i in 0..48 {
            let c = [(i % 8) as f64 * 0.03 - 0.105, (i / 8) as f64 * 0.03 - 0.075];
            let m = faces[usize::from(c[0] > 0.0)];
            let points = (0..30)
                .map(|_| {
                    let ray = Vector3::new(
                        c[0] + 0.012 * (rng.uniform() - 0.5),
                        c[1] + 0.012 * (rng.uniform() - 0.5),
                        1.0,
                    );
                    let moved = r * (ray / m.dot(&ray)) + t;
                    let noise = Vector3::new(rng.normal(), rng.normal(), 0.0) * 0.1 / FOCAL;
                    Correspondence {
                        x1: ray,
                        x2: moved / moved.z + noise,
                    }
                })
                .collect();
            samples.push(points);
            centres.push(c);
        }
        (samples, centres, truth)
    }

    /// Each superpixel's 15 nearest by `centres` (the pipeline's K-NN graph, K = 15).
    fn nearest(centres: &[[f64; 2]]) -> KnnGraph {
        let points: Vec<[f64; 3]> = centres.iter().map(|c| [c[0], c[1], 0.0]).collect();
        crate::superpixels::graph::knn_graph_3d(&points, centres, 15, 1.0)
    }

    /// A fitting of `samples` with `motions` evaluated everywhere, without a noise deadband.
    fn fitting<'a>(samples: &'a [Vec<Correspondence>], motions: &[Motion]) -> Fitting<'a> {
        let mut fit = Fitting {
            samples,
            focal: FOCAL,
            hypotheses: Vec::new(),
            costs: CostTable::new(samples.len()),
            everywhere: Vec::new(),
            deadband: 0.0,
        };
        motions.iter().for_each(|&m| _ = fit.add(m, None));
        fit
    }

    #[test]
    fn a_window_across_both_sides_of_a_turning_box_finds_its_motion() {
        let (samples, centres, truth) = turning_box(&mut Rng::new(7));
        let off = |m: &Motion| {
            let (t, r) = (m.translation_angle(&truth), m.rotation_angle(&truth));
            (t.to_degrees(), r.to_degrees())
        };
        // The motion fitted to the left side alone explains that side (one plane, so a motion
        // of a family) and not the right.
        let left: Vec<usize> = (0..48).filter(|&i| centres[i][0] < 0.0).collect();
        let one_side: Vec<Correspondence> = left.iter().flat_map(|&i| samples[i].clone()).collect();
        let twin = {
            let h = homography_dlt(&one_side).expect("a homography of one face");
            let readings = crate::geometry::homography::decompose_homography(&h, &one_side);
            (readings.into_iter().map(|p| p.motion))
                .max_by(|a, b| off(a).0.total_cmp(&off(b).0))
                .expect("two readings of one plane")
        };
        assert!(off(&twin).0 > 10.0, "the other reading: {:?}°", off(&twin));
        let fit = fitting(&samples, &[twin]);
        let best: Vec<f64> = (0..48).map(|i| fit.best(i) as f64).collect();
        let right_cost: f64 = (0..48).filter(|i| !left.contains(i)).map(|i| best[i]).sum();
        assert!(right_cost > 10.0, "the right side costs {right_cost} px");
        // A window spanning both sides gives the box's motion back, and the gain is what the
        // right side cost (each superpixel's cost counted up to `explain_px`).
        let params = InitParams {
            explain_px: 3.0,
            ..InitParams::default()
        };
        let window: Vec<usize> = (0..48).collect();
        let (gain, found) = best_in_window(&fit, &window, &best, &params, &mut Rng::new(8))
            .expect("a motion from 48 superpixels");
        let (dt, dr) = off(&found);
        assert!(
            dt < 1.0 && dr < 0.5,
            "{dt:.2}° / {dr:.2}° off the box's motion"
        );
        // The gain is about what the right side cost: each superpixel's cost counted up to
        // `explain_px`, less the noise (0.1 px) left on all 48.
        let right_capped: f64 = (0..48)
            .filter(|i| !left.contains(i))
            .map(|i| best[i].min(3.0))
            .sum();
        assert!(
            (right_capped - 8.0..=right_capped).contains(&gain),
            "gain {gain} for the right side's {right_capped} px"
        );
        // Fewer than five superpixels with samples: no motion.
        assert!(best_in_window(&fit, &window[..4], &best, &params, &mut Rng::new(8)).is_none());
        // A window that cannot gain `window_gain_px` is not searched, and it makes the same
        // draws as one that is, so the windows after it draw the same samples.
        let reachable: f64 = best.iter().map(|b| b.min(3.0)).sum();
        let unreachable = InitParams {
            window_gain_px: reachable + 0.1,
            ..params
        };
        let (mut searched, mut skipped) = (Rng::new(8), Rng::new(8));
        assert!(best_in_window(&fit, &window, &best, &params, &mut searched).is_some());
        assert!(best_in_window(&fit, &window, &best, &unreachable, &mut skipped).is_none());
        assert_eq!(searched.next_u32(), skipped.next_u32());
    }

    #[test]
    fn windows_add_a_motion_where_it_gains_enough() {
        let (samples, centres, truth) = turning_box(&mut Rng::new(7));
        let knn = nearest(&centres);
        let off = |m: &Motion| m.translation_angle(&truth).to_degrees();
        let camera_only = |params: &InitParams| {
            let mut fit = fitting(&samples, &[camera()]);
            add_window_hypotheses(&mut fit, &knn, params, &mut Rng::new(9));
            fit.hypotheses
        };
        // Under the camera's motion every superpixel costs between 0.05 px and `explain_px`.
        let params = InitParams {
            explain_px: 10.0,
            ..InitParams::default()
        };
        let hypotheses = camera_only(&params);
        assert!(hypotheses.len() >= 2, "no motion added");
        let closest = hypotheses[1..]
            .iter()
            .map(off)
            .fold(f64::INFINITY, f64::min);
        assert!(
            closest < 1.0,
            "the added motions are {closest:.2}° off or more"
        );
        // No windows, a gain out of reach, or superpixels explained better than the windows'
        // threshold: nothing is added.
        for params in [
            InitParams {
                window_seeds: 0,
                ..params
            },
            InitParams {
                window_gain_px: 1e6,
                ..params
            },
            InitParams {
                window_min_px: 10.0,
                ..params
            },
        ] {
            assert_eq!(camera_only(&params).len(), 1);
        }
    }

    #[test]
    fn a_piece_without_a_plane_borrows_from_the_neighbour_of_its_colour() {
        // Pieces 0 (red) and 1 (blue) have planes; 2 (blue) touches both, 3 (red) touches 0 and
        // 2, and 4 (blue) touches only 3. Listed first in 2's neighbours, red 0 must not win.
        let lab = [
            [50.0, 70.0, 50.0],
            [40.0, 20.0, -70.0],
            [42.0, 18.0, -66.0],
            [52.0, 66.0, 48.0],
            [41.0, 21.0, -69.0],
        ];
        let sp = pixel_row(&lab, 1.0);
        let piece = |depth: f64, degenerate| Piece {
            r: Matrix3::identity(),
            t_hat: Vector3::x(),
            m: Vector3::new(0.0, 0.0, 1.0 / depth),
            lambda: 1.0,
            hypothesis: 0,
            degenerate,
        };
        let none = Some(super::super::Degeneracy::TooFewPixels);
        let pieces = vec![
            piece(2.0, None),
            piece(9.0, None),
            piece(0.0, none),
            piece(0.0, none),
            piece(0.0, none),
        ];
        let adjacency = vec![vec![2, 3], vec![2], vec![0, 1, 3], vec![0, 2, 4], vec![3]];
        let filled = fill_degenerate(pieces, &sp, &adjacency);
        let depths: Vec<f64> = filled.iter().map(|p| 1.0 / p.m.z).collect();
        assert_eq!(depths, [2.0, 9.0, 9.0, 2.0, 2.0]);
        // They keep the reason they had no plane of their own.
        assert!(filled[2..].iter().all(|p| p.degenerate == none));
    }
}
