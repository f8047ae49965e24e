//! Relative scales, one per superpixel: the "3D jigsaw puzzle" of the paper (section 4), from
//! contacts between touching pieces. (The paper's ARAP energy, eq. 1, scored wrong answers below
//! the truth on every dynamic case measured, so it is not used; `soup eval --oracle` runs the same
//! truth test on this energy. Compared fairly, with the solution and the truth polished by the
//! same per-piece descent, it ranks the solution's basin at or below the truth's on every case
//! measured: docs/ARCHITECTURE.md, Pitfalls.)
//!
//! Each piece i of the unit-scale soup is known up to its scale λ_i = e^(s_i): its depths, and
//! the length of its translation, grow together, so its fit to the flow does not change. What
//! ties the scales together is *contact*: where two pieces touch, their surfaces meet, in frame
//! 1 and in frame 2, unless there is a real depth edge.
//!
//! # The contact term, in log-depth
//! For a boundary pixel pair (p in a, q in b), both planes are evaluated on the ray r through the
//! midpoint of p and q. Piece a's depth there is z_a = λ_a z̄_a(r) with z̄_a(r) = 1 / (m_a · r) its
//! unit-scale depth, so the frame-1 log-depth gap is
//!
//!   g₁ = ln z_a − ln z_b = (s_a − s_b) + (ln z̄_a(r) − ln z̄_b(r)) = δ + c₁.
//!
//! In frame 2 each piece has moved with its own motion, its point to X'_a = R_a X_a + λ_a t̂_a and
//! its plane to m'_a (see [`RayPoint`]). The frame-2 gap g₂ = ½ (ln m'_bᵀX'_a − ln m'_aᵀX'_b)
//! measures how far each moved point lies off the other's moved plane (see [`gaps`]); it too is
//! δ + c₂. Point-to-plane makes the term tolerant of sliding contact (a foot moving along the
//! floor stays on the floor's plane though it left the floor point it touched).
//!
//! Both gaps are scale-free (a global scale cancels in δ), so one truncation σ serves every
//! scene: ρ(g) = min(|g|, σ), and a real depth edge costs at most σ per pair. A pair's weight
//! is [`pair_weight`]: low where the colour jumps or the flow check failed (occlusions), and
//! every touching pair of pieces carries the same total weight whatever its boundary length.
//!
//! # The solve
//! 1. *Rigid segments.* Touching pieces that use the same motion hypothesis and whose planes
//!    meet at equal scale (median |c₁| below `segment_gap`) are one rigid body with one scale;
//!    union-find over such pairs gives the segments. (One scale per *hypothesis* is wrong on
//!    dynamic scenes: several walkers can share one motion up to scale.) The static world
//!    joins more loosely: touching pieces on the ego-motion whose own parallax measures their
//!    depth well (`world_parallax`) join when their planes meet within `world_gap` (0.2)
//!    instead of `segment_gap` (0.05), since the flow's error near edges opens larger gaps
//!    between well-measured planes (a static box that stands on the floor is one body with
//!    it). They do not join unconditionally: a walker moving parallel to the camera's
//!    translation is explained by the ego-motion too, at a wrong depth, and there it does not
//!    meet the world (on the crowd with exact flow, two walkers were glued to the world and
//!    the MRE was 0.14–0.20). Nor do pieces that sink under the static world's ground
//!    ([`super::ground`]): those are movers explained by the ego-motion at too large a depth
//!    (a car driving ahead), so the segments are built a second time with them apart.
//! 2. *Segment scales* by coordinate descent on E from three starts (a maximum spanning tree of
//!    the sharpest links; every segment at median depth 1; and TRW-S over offsets on a grid of step
//!    σ, which moves groups of segments together), each segment moving to the exact minimum of its
//!    terms (for truncated-linear terms it lies at one of the zero-gap points −c), within a band of
//!    depth ratios around the largest segment. The lower energy wins. This segment energy adds a
//!    *figure prior* to E: where two segments part, the smaller one pays, per link, `behind_weight`
//!    times the cost of breaking all of that link's frame-1 contacts (κ σ Σw) for lying more than σ
//!    behind the larger one (by the link's weighted-median frame-1 gap). Once a mover's contacts
//!    break, contact alone leaves its scale free, and the solve used to park movers far behind the
//!    world (a car 4–70× too far). The prior is a statement about movers: it does not bind measured
//!    static world (a segment on the ego-motion, mostly of pieces whose parallax measures their
//!    depth: `measured_share`), since a walker splits the background behind it into fragments
//!    smaller than itself. At the crowd's truth it charged such fragments 18–35 contact units, and
//!    the solve placed whole walkers 2–4× wrong to spare them. Nor does it act across a mover's
//!    bottom edge over the static world below the horizon where things stand on a floor (the ground
//!    runs to the near edge of the view): below a standing thing the floor runs towards the camera,
//!    in front of it. A weak *static prior* (`static_weight`) ties every segment on the ego-motion
//!    to the static world's scale instead: the ego-motion explains its flow at exactly that scale.
//!    Its pull on one segment is capped (`static_max`): a large segment apart from the world may be
//!    a mover the ego-motion explains at a wrong depth, which its contacts must be able to place.
//!    Not capped are the floor and the fragments that meet the world at equal scale somewhere (a
//!    link within `world_gap`, directly or through other such fragments): static world that a tight
//!    `segment_gap` split off, while such a mover meets the world nowhere at the ego-motion's
//!    scale. A *ground prior* (`ground_weight`) charges every piece outside the static world one
//!    broken contact for lying more than σ under its ground. A *rest prior* (`rest_weight`) ties
//!    every mover whose bottom pixels sit on the ground to it, in front as behind: a standing thing
//!    touches what it stands on, and its contacts with the floor are few and weak (colour edges at
//!    the feet). It acts only where the ground runs to the near edge of the view
//!    (`rest_bottom_share`): among floating things a ground-like plane behind them would pull them
//!    back onto it.
//! 3. *Tail control.* A piece whose depth disagrees with every neighbour in both frames while
//!    the flow across its boundary is continuous (nothing in the data justifies the depth edge)
//!    takes the scale that best meets its neighbours. The number of such pieces is reported.
//!
//! E is [`Problem::energy`], the contact energy alone (without the figure, static, ground and rest
//! priors, which act only between segments in step 2); `soup eval --oracle` compares it at the
//! solution and at the ground truth polished by the same per-piece descent (the "truth test").

use serde::Serialize;

use crate::camera::Intrinsics;
use crate::flow::FlowField;
use crate::grid::Grid;
use crate::numeric::exp;
use crate::soup::Soup;
use crate::superpixels::Superpixels;
use crate::superpixels::graph::BoundaryGraph;

mod confidence;
mod contact;
mod descent;
mod minimise;
mod priors;
mod ray_gaps;
mod segments;

pub use confidence::{depth_confidence, scale_confidence};
pub use contact::{Link, Problem, build_problem, pair_weight, polish, sampled_pairs};
pub use minimise::Step;
pub use ray_gaps::{PointColumn, PointColumns, RayPoint, TruncatedGaps, gaps, ray_point};
pub use segments::{
    ScaleEnergy, SegmentObjective, rigid_segments, segment_descent_from, segment_objective,
    world_pieces,
};

use contact::tail_control;
use descent::solve_segments;
use segments::Segments;

/// Settings of the scale solve. Each value is scale-free and shared by every scene.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, serde::Deserialize)]
#[serde(default)]
pub struct ScaleParams {
    /// σ: truncation of a pair's log-depth gap. A real depth edge costs at most this per pair;
    /// 0.1 is a 10 % depth jump, well above the gap that flow noise leaves between planes that
    /// really meet (about 0.01–0.03) and below typical object-to-background jumps.
    pub sigma: f64,
    /// Touching pieces of one motion hypothesis whose planes meet within this median log-depth
    /// gap at equal scale are one rigid segment (0.06: a little above the gap noise of fitted
    /// planes; at 0.04 the road at 1500 superpixels split into fragments that went to 0.146.
    /// 0.048–0.072 move no case's mean over five seeds by more than 0.012 (road 0.041 / 0.045
    /// / 0.045), since fragments of the static world that it splits off are held by the
    /// static prior without its cap where they meet the world (see `static_max`); capped, the
    /// road's sky at 0.048 went 2.7–3.7× too near, 0.110 over five seeds).
    pub segment_gap: f64,
    /// Colour difference (RGB in [0, 1], Euclidean) at which a pair's weight falls to 1/e:
    /// contacts between pieces of one colour are likelier than across a colour edge.
    pub colour_scale: f64,
    /// Weight of a pair where either pixel failed the forward–backward check (an occlusion is
    /// likely there, so the two sides need not meet).
    pub occluded_weight: f64,
    /// Each segment's median depth stays within [1/band, band] times the largest segment's.
    pub band: f64,
    /// At most this many pixel pairs are used per touching pair of pieces (evenly spaced).
    pub pairs_per_boundary: usize,
    /// Contact evidence of a pair (see `contact::contact_evidence`): flow jump (px) at which the
    /// flow-continuity evidence falls to 1/e.
    pub flow_scale_px: f64,
    /// Smallest contact evidence of a pair (a pair whose flow jumps, unless one piece stands on
    /// the other at an angle).
    pub evidence_floor: f64,
    /// Weight factor of a pair where the lower piece is ground-like (a plane of its own below the
    /// camera, its normal within 30° of the camera's downward axis:
    /// [`super::ground::has_ground_like_plane`], as for the ground plane's candidates) and the
    /// upper piece stands on it: a standing thing touches what it stands on, while its sides and
    /// top may or may not touch what is behind them.
    pub support_weight: f64,
    /// A piece's scale counts as known when its [`scale_confidence`] is at least this: moving
    /// its rigid segment by 25 % raises the energy of its rim by a tenth of what it would cost
    /// to break every contact there if each were certain. Its depth counts as known when its
    /// [`depth_confidence`] is at least this (the same, and its plane its own).
    pub min_confidence: f64,
    /// The figure prior: per link between two rigid segments, the cost (in broken contacts, w σ)
    /// of the smaller segment lying more than σ behind the larger one where the link's median
    /// frame-1 gap says so, unless the smaller one is measured static world (see
    /// `measured_share`), which may lie behind anything, or the link's trusted flow is
    /// continuous (see `continuity_trusted_share`). A small moving region seen against a
    /// larger one is usually in front of it (a mover against the world); behind, it would be
    /// seen through a hole. Two frames often leave a mover's scale free once its contacts
    /// break, and then this decides; 10 makes lying behind dearer than any contact the move
    /// could make. It does not act across a mover's bottom edge over the static world below the
    /// horizon where the ground runs to the near edge of the view (`rest_bottom_share`): below a
    /// standing thing the floor lies in front of it (on the table it held a sliding box 1.5×
    /// too near).
    pub behind_weight: f64,
    /// A boundary's flow counts as continuous (its median jump below `continuous_flow_px`)
    /// only where at least this share of its pixel pairs pass the forward–backward check.
    /// Continuous trusted flow shows no occlusion there, so the figure prior, whose premise is
    /// an occluder in front, does not act across it: two parts of one bending body, each on a
    /// rigid motion of its own, are neither in front of the other (their planes, distorted by
    /// those motions, need not meet, and the prior charged the truth 39 on the flag). Half:
    /// where most of a boundary fails the check, its flow is no evidence either way
    /// (FlyingThings3D, whose flow jump does not tell depth edges from contacts). Tail control
    /// asks the same of a boundary before it moves a piece to its neighbours' scale.
    pub continuity_trusted_share: f64,
    /// Pieces of the static world (on the ego-motion) share one scale when their parallax is at
    /// least this many times the flow's noise: their depth error is then about 1/30 ≈ 3 % or
    /// less, while pieces near the epipole or far away (little parallax) keep a scale of their
    /// own that contacts correct.
    pub world_parallax: f64,
    /// Touching world pieces (see `world_parallax`) are one body when their planes meet within
    /// this median log-depth gap at the world's scale: looser than `segment_gap`, since their
    /// depth is well measured and a larger gap is the flow's error near edges (0.2 = 2σ, a
    /// depth jump of 22 %). Not unconditional: a mover whose motion parallels the camera's is
    /// explained by the ego-motion at a wrong depth and does not meet the world there. A
    /// segment on the ego-motion that meets the world's segment within this gap somewhere is
    /// attached to it: the static prior holds it without its cap (see `static_max`).
    pub world_gap: f64,
    /// A piece on the ego-motion that lies more than this (log-depth, by the median of its
    /// pixels) under the static world's ground at the world's scale is not static world: a
    /// mover explained by the ego-motion at too large a depth (see `Segments::new`). 0.2: above
    /// the 0.1–0.2 that pieces straddling a contact with the floor read at the truth, below
    /// the road's cars (0.7–1.1).
    pub sunk_gap: f64,
    /// The static prior: each segment on the ego-motion is tied to the static world's scale
    /// as if by this many contacts per piece (each at most σ), up to `static_max`. Weak: 0.05
    /// gives a segment of 20 pieces the pull of one full contact, so contacts overrule it
    /// wherever they agree (0.05–0.3 measured within ±0.01 on most scenes; 0.3 raised the
    /// crowd by 0.03).
    pub static_weight: f64,
    /// The static prior's pull on one segment at most, in contacts: 1.5, that of 30 pieces;
    /// the floor (a segment mostly on the static world's ground) is not capped. A large
    /// segment on the ego-motion apart from the static world is as likely a mover that the
    /// ego-motion explains at a wrong depth (the crowd's brick-box walker: 56–79 pieces at 0.4
    /// of its depth) as a static thing, and the pull of 4 contacts held such a walker against
    /// its body resting on the floor (crowd 0.076 over five seeds, 0.064 at most 1.5; 1.2 and
    /// 1.8 within 0.001 of it). The floor is static whatever its size: capped, the crowd's
    /// floor, apart from the wall, followed its walkers (0.08 -> 0.20 with the page's
    /// settings at 1400 superpixels). Small fragments keep the full 0.05 per piece. Nor is a
    /// segment capped that meets the static world at equal scale across a link within
    /// `world_gap` (directly or through other such segments): a fragment of the static world
    /// (the road's sky, split off at a `segment_gap` of 0.048: 191–429 pieces whose links met
    /// the world within 0.05–0.2, went 2.7–3.7× too near under the cap), while the brick-box
    /// walker meets it 0.72 and more off, the log of its depth error.
    pub static_max: f64,
    /// A segment on the ego-motion is measured static world, free of the figure prior, when at
    /// least this share of its pieces have the parallax of `world_parallax`. Half: a fragment
    /// of mostly poorly measured pieces may be a mover that the ego-motion explains by accident
    /// (more of them with half-resolution flow: exempting every segment on the ego-motion took
    /// the street with preset medium from 0.066 to 0.121).
    pub measured_share: f64,
    /// The ground prior: each piece outside the static world that lies (by the median of its
    /// pixels) more than σ under the ground plane (see `soup::ground`: nothing is seen through the
    /// floor) costs this many broken contacts (w σ); 0 switches the ground off altogether (also the
    /// split of sunk pieces from the static world, see `sunk_gap`). 1: a mover of n pieces sunk
    /// under the road pays as much as n broken contacts, more than the contacts that glued it to
    /// the background behind it usually save.
    pub ground_weight: f64,
    /// The ground plane is trusted only where its pieces cover at least this share of the
    /// image (3 %: a strip of floor; less is too little to extrapolate a plane from).
    pub ground_share: f64,
    /// The rest prior: a piece on a motion of its own whose bottom pixels sit on the ground
    /// (see [`super::ground::resting_gaps`]) stands there, and costs this many contacts (each
    /// truncated at σ, spread over those pixels) for its bottom lying off the ground, in front
    /// or behind. A walker touches the world only where its feet meet the floor, through 2–3
    /// weak links across colour edges, and with computed flow contacts alone left the crowd's
    /// walkers 1.3–4.5× too near; the floor under their bottom pixels gave their true scale
    /// within 0.1 (log) on 88 % of those pixels. 1.5: 1–3 measured within 0.008 of each
    /// other, 3 raised the creature with exact flow from 0.024 to 0.048. 0 switches it off, as
    /// does a zero `ground_weight` (no ground at all).
    pub rest_weight: f64,
    /// The rest prior acts only where the ground covers at least this share of the image's bottom
    /// tenth ([`super::ground::bottom_share`]): a floor that things stand on runs to the near edge
    /// of the view (0.71–0.94 on our street, road, crowd, creature and table, 0.89 on the
    /// motorcycle), while a ground-like plane among floating things does not (FlyingThings3D:
    /// 0.45–0.49, where the floor under a flying object put it 3–5.5× too far). 0.65: at 0.6, 20 %
    /// less let FlyingThings3D's members through (+0.11); here 0.52–0.78 move no case by more than
    /// 0.002 (the street and road lose the prior at 0.78, which changes them little). The same test
    /// lifts the figure prior across a thing's bottom edge over the floor (`behind_weight`),
    /// whatever `rest_weight` is.
    pub rest_bottom_share: f64,
    /// Flow jump (px) across a boundary below which the flow counts as continuous there, where
    /// enough of it is trusted (`continuity_trusted_share`): a depth edge needs a flow edge to
    /// be believed (tail control), and nothing occludes anything there (the figure prior).
    pub continuous_flow_px: f64,
}

impl Default for ScaleParams {
    fn default() -> Self {
        ScaleParams {
            sigma: 0.1,
            segment_gap: 0.06,
            colour_scale: 0.15,
            occluded_weight: 0.3,
            band: 12.0,
            pairs_per_boundary: 12,
            continuous_flow_px: 1.0,
            continuity_trusted_share: 0.5,
            behind_weight: 10.0,
            world_parallax: 30.0,
            world_gap: 0.2,
            sunk_gap: 0.2,
            static_weight: 0.05,
            static_max: 1.5,
            measured_share: 0.5,
            ground_weight: 1.0,
            ground_share: 0.03,
            rest_weight: 1.5,
            rest_bottom_share: 0.65,
            min_confidence: 0.1,
            support_weight: 4.0,
            flow_scale_px: 0.5,
            evidence_floor: 0.2,
        }
    }
}

impl ScaleParams {
    /// Whether the static world's ground is looked for at all: a zero `ground_weight` switches
    /// the ground off (its prior, the split of sunk pieces, the rest prior and the refinement's
    /// ground cost).
    pub fn looks_for_ground(&self) -> bool {
        self.ground_weight > 0.0
    }
}

/// What the scale solve did.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ScaleReport {
    /// E with every piece at unit scale (λ = 1).
    pub energy_start: f64,
    /// E at the solution.
    pub energy_end: f64,
    /// Rigid segments (the unknowns of step 2).
    pub segments: usize,
    /// Coordinate-descent sweeps over segments.
    pub sweeps: usize,
    /// Pieces moved by tail control (step 3).
    pub tail_pieces: usize,
    /// Largest / smallest λ.
    pub lambda_ratio: f64,
    /// Whether the static world's ground plane was found ([`super::ground::ground_plane`]).
    pub ground: bool,
}

/// What the scale solve reads besides the soup, all at the working resolution.
#[derive(Clone, Copy, Debug)]
pub struct ScaleInputs<'a> {
    /// The superpixels the soup's pieces are.
    pub superpixels: &'a Superpixels,
    /// The touching pixel pairs.
    pub boundaries: &'a BoundaryGraph,
    /// Flow 1→2 (continuity across boundaries).
    pub flow: &'a FlowField,
    /// Where that flow is trusted (forward–backward consistent).
    pub reliable: &'a Grid<bool>,
    pub intrinsics: &'a Intrinsics,
}

/// Solves the relative scales of `soup` in place (median λ = 1 over pieces) and reports.
pub fn solve_scales(soup: &mut Soup, inputs: &ScaleInputs, params: &ScaleParams) -> ScaleReport {
    let problem = build_problem(soup, inputs, params);
    let n = soup.pieces.len();
    let energy_start = problem.energy(&vec![0.0; n]);
    let segments = Segments::new(soup, inputs, &problem, params);
    let (u, sweeps) = solve_segments(&problem, &segments, params, None);
    let mut s = segments.log_scales(&u);
    let tail_pieces = tail_control(&problem, &mut s, params);
    let energy_end = problem.energy(&s);
    set_scales(soup, &s);
    let (lo, hi) = soup
        .pieces
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(a, b), p| {
            (a.min(p.lambda), b.max(p.lambda))
        });
    ScaleReport {
        energy_start,
        energy_end,
        segments: segments.sizes.len(),
        sweeps,
        tail_pieces,
        lambda_ratio: if n > 0 { hi / lo } else { 1.0 },
        ground: segments.ground,
    }
}

/// Sets every piece's λ = e^(s_i), normalised so the median λ is 1.
pub fn set_scales(soup: &mut Soup, s: &[f64]) {
    let mut sorted: Vec<f64> = s.iter().copied().filter(|v| v.is_finite()).collect();
    sorted.sort_by(f64::total_cmp);
    let median = sorted.get(sorted.len() / 2).copied().unwrap_or(0.0);
    for (p, &v) in soup.pieces.iter_mut().zip(s) {
        p.lambda = if v.is_finite() { exp(v - median) } else { 1.0 };
    }
}
