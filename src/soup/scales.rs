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
//!    the sharpest links; every segment at median depth 1; and TRW-S over offsets on a grid of
//!    step σ, which moves groups of segments together), each segment moving to the exact
//!    minimum of its terms (for truncated-linear terms it lies at one of the zero-gap points −c),
//!    within a band of depth ratios around the largest segment. The lower energy wins. This
//!    segment energy adds a *figure prior* to E: where two segments part, the smaller one pays,
//!    per link, `behind_weight` times the cost of breaking all of that link's frame-1 contacts
//!    (κ σ Σw) for lying more than σ behind the larger one (by the link's weighted-median
//!    frame-1 gap). Once a mover's contacts break, contact alone leaves its scale free, and
//!    the solve used to park movers far behind the world (a car 4–70× too far). The prior is a
//!    statement about movers: it does not bind measured static world (a segment on the
//!    ego-motion, mostly of pieces whose parallax measures their depth: `measured_share`), since
//!    a walker splits the background behind it into fragments smaller than itself. At the
//!    crowd's truth it charged such fragments 18–35 contact units, and the solve placed whole
//!    walkers 2–4× wrong to spare them. Nor does it act across a mover's bottom edge over the
//!    static world below the horizon where things stand on a floor (the ground runs to the near
//!    edge of the view): below a standing thing the floor runs towards the camera, in front of
//!    it. A weak *static prior* (`static_weight`) ties every
//!    segment on the ego-motion to the static world's scale instead: the ego-motion explains
//!    its flow at exactly that scale. Its pull on one segment is capped (`static_max`): a
//!    large segment apart from the world may be a mover the ego-motion explains at a wrong
//!    depth, which its contacts must be able to place. Not capped are the floor and the
//!    fragments that meet the world at equal scale somewhere (a link within `world_gap`,
//!    directly or through other such fragments): static world that a tight `segment_gap`
//!    split off, while such a mover meets the world nowhere at the ego-motion's scale. A *ground prior* (`ground_weight`) charges every piece
//!    outside the static world one broken contact for lying more than σ under its ground. A
//!    *rest prior* (`rest_weight`) ties every mover whose bottom pixels sit on the ground to
//!    it, in front as behind: a standing thing touches what it stands on, and its contacts with
//!    the floor are few and weak (colour edges at the feet). It acts only where the ground runs
//!    to the near edge of the view (`rest_bottom_share`): among floating things a ground-like
//!    plane behind them would pull them back onto it.
//! 3. *Tail control.* A piece whose depth disagrees with every neighbour in both frames while
//!    the flow across its boundary is continuous (nothing in the data justifies the depth edge)
//!    takes the scale that best meets its neighbours. The number of such pieces is reported.
//!
//! E is [`Problem::energy`], the contact energy alone (without the figure, static, ground and
//! rest priors, which act only between segments in step 2); `soup eval --oracle` compares it at the solution and at the
//! ground truth polished by the same per-piece descent (the "truth test").

use nalgebra::Vector3;
use serde::Serialize;

use super::{Piece, Soup, ground};
use crate::camera::Intrinsics;
use crate::flow::FlowField;
use crate::grid::Grid;
use crate::mrf::trws::{Mrf, TrwsOptions, trws};
use crate::numeric::{atanh, exp, hypot, ln, min, tanh, weighted_median};
use crate::superpixels::Superpixels;
use crate::superpixels::graph::{BoundaryEdge, BoundaryGraph};
use crate::union_find::{find, union};

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
    /// Contact evidence of a pair (see `contact_evidence`): flow jump (px) at which the
    /// flow-continuity evidence falls to 1/e.
    pub flow_scale_px: f64,
    /// Smallest contact evidence of a pair (a pair whose flow jumps, unless one piece stands on
    /// the other at an angle).
    pub evidence_floor: f64,
    /// Weight factor of a pair where the lower piece is ground-like (a plane of its own below
    /// the camera, its normal within 30° of the camera's downward axis:
    /// [`ground::has_ground_like_plane`], as for the ground plane's candidates) and the upper
    /// piece stands on it: a standing thing touches what it stands on, while its sides and top
    /// may or may not touch what is behind them.
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
    /// pixels) more than σ under the ground plane (see `soup::ground`: nothing is seen through
    /// the floor) costs this many broken contacts (w σ); 0 switches the ground off altogether
    /// (also the split of sunk pieces from the static world, see `sunk_gap`). 1: a mover of n pieces sunk under the road pays as
    /// much as n broken contacts, more than the contacts that glued it to the background
    /// behind it usually save.
    pub ground_weight: f64,
    /// The ground plane is trusted only where its pieces cover at least this share of the
    /// image (3 %: a strip of floor; less is too little to extrapolate a plane from).
    pub ground_share: f64,
    /// The rest prior: a piece on a motion of its own whose bottom pixels sit on the ground
    /// (see [`ground::resting_gaps`]) stands there, and costs this many contacts (each
    /// truncated at σ, spread over those pixels) for its bottom lying off the ground, in front
    /// or behind. A walker touches the world only where its feet meet the floor, through 2–3
    /// weak links across colour edges, and with computed flow contacts alone left the crowd's
    /// walkers 1.3–4.5× too near; the floor under their bottom pixels gave their true scale
    /// within 0.1 (log) on 88 % of those pixels. 1.5: 1–3 measured within 0.008 of each
    /// other, 3 raised the creature with exact flow from 0.024 to 0.048. 0 switches it off, as
    /// does a zero `ground_weight` (no ground at all).
    pub rest_weight: f64,
    /// The rest prior acts only where the ground covers at least this share of the image's
    /// bottom tenth ([`ground::bottom_share`]): a floor that things stand on runs to the near
    /// edge of the view (0.71–0.94 on our street, road, crowd, creature and table, 0.89 on the
    /// motorcycle), while a ground-like plane among floating things does not (FlyingThings3D:
    /// 0.45–0.49, where the floor under a flying object put it 3–5.5× too far). 0.65: at 0.6,
    /// 20 % less let FlyingThings3D's members through (+0.11); here 0.52–0.78 move no case by
    /// more than 0.002 (the street and road lose the prior at 0.78, which changes them little).
    /// The same test lifts the figure prior across a thing's bottom edge over the floor
    /// (`behind_weight`), whatever `rest_weight` is.
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
    /// Whether the static world's ground plane was found ([`ground::ground_plane`]).
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

/// The contact terms between two touching pieces a < b, as functions of δ = s_a − s_b:
/// φ(δ) = Σ_j w_j min(|δ + c_j|, σ) (frame-1 and frame-2 gaps of every pair used).
#[derive(Clone, Debug)]
pub struct Link {
    pub a: usize,
    pub b: usize,
    /// (w, c) per gap.
    pub terms: Vec<(f64, f64)>,
    /// The frame-1 gaps alone, (w, c₁) per pair: where the figure prior looks.
    pub frame1: Vec<(f64, f64)>,
    /// Median frame-1 offset c₁ (the log-depth gap at equal scales).
    pub median_c1: f64,
    /// Median flow jump across the boundary (px).
    pub flow_jump: f64,
    /// Share of the boundary's pixel pairs whose flow both pass the forward–backward check.
    pub trusted_share: f64,
    /// The piece (a or b) whose pixels lie directly above the other's on at least
    /// [`ground::MIN_RESTING_PIXELS`] of the boundary's pixel pairs (the one with more such
    /// pairs; `None` on a tie): where things stand on a floor, the piece below it may be floor
    /// in front of it (see `segment_pair_terms`).
    pub upper: Option<usize>,
}

impl Link {
    /// φ(δ).
    pub fn value(&self, delta: f64, sigma: f64) -> f64 {
        truncated(&self.terms, delta, sigma)
    }

    /// Whether the flow across the boundary is trusted and continuous: no occlusion there
    /// ([`ScaleParams::continuity_trusted_share`]).
    fn shows_continuity(&self, params: &ScaleParams) -> bool {
        self.flow_jump < params.continuous_flow_px
            && self.trusted_share >= params.continuity_trusted_share
    }

    /// φ with every gap truncated: the most the link can cost.
    fn full(&self, sigma: f64) -> f64 {
        self.terms.iter().map(|&(w, _)| w * sigma).sum()
    }

    /// The link's terms as functions of x, the log-scale of its piece a (`from_a`) or b, with
    /// the other piece's log-scale at `other`: (w, c') with gap = x + c'.
    fn seen_from(&self, from_a: bool, other: f64) -> impl Iterator<Item = (f64, f64)> + '_ {
        // δ = s_a − s_b: from a, gap = x − other + c; from b, |other − x + c| = |x − other − c|.
        let sign = if from_a { 1.0 } else { -1.0 };
        self.terms.iter().map(move |&(w, c)| (w, sign * c - other))
    }

    /// The frame-1 terms alone, seen as [`Link::seen_from`] sees all of them.
    fn frame1_seen_from(&self, from_a: bool, other: f64) -> impl Iterator<Item = (f64, f64)> + '_ {
        let sign = if from_a { 1.0 } else { -1.0 };
        self.frame1.iter().map(move |&(w, c)| (w, sign * c - other))
    }
}

/// The scale problem: one [`Link`] per touching pair of pieces.
#[derive(Clone, Debug)]
pub struct Problem {
    pub links: Vec<Link>,
    /// Per piece, the indices of its links.
    pub touching: Vec<Vec<usize>>,
    pub sigma: f64,
}

impl Problem {
    /// E at piece log-scales `s`.
    pub fn energy(&self, s: &[f64]) -> f64 {
        self.links
            .iter()
            .map(|l| l.value(s[l.a] - s[l.b], self.sigma))
            .sum()
    }

    /// The terms of piece `i` as functions of its own log-scale, the others fixed at `s`:
    /// (w, c) such that its local energy is Σ w min(|s_i + c|, σ).
    fn local_terms(&self, i: usize, s: &[f64]) -> Vec<(f64, f64)> {
        let mut out = Vec::new();
        for &e in &self.touching[i] {
            let l = &self.links[e];
            let other = if l.a == i { s[l.b] } else { s[l.a] };
            out.extend(l.seen_from(l.a == i, other));
        }
        out
    }
}

/// Σ w min(|x + c|, σ).
fn truncated(terms: &[(f64, f64)], x: f64, sigma: f64) -> f64 {
    terms
        .iter()
        .map(|&(w, c)| w * (x + c).abs().min(sigma))
        .sum()
}

/// A one-sided cost of a segment's log-scale x: `k` when `dir` · (x + c) > σ, where x + c is a
/// log-depth gap: to a larger neighbour in frame 1 (with `dir` = 1 the cost is paid when the
/// segment lies more than σ behind it, see [`ScaleParams::behind_weight`]), or to the ground
/// (paid when a piece lies more than σ under it, see [`ScaleParams::ground_weight`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Step {
    pub k: f64,
    pub c: f64,
    pub dir: f64,
}

impl Step {
    /// The x where the step switches: dir · σ − c. It is free there (the minimiser may stop on
    /// it), so activity is tested against this same number and rounding cannot make the step
    /// fire at its own edge.
    fn edge(&self, sigma: f64) -> f64 {
        self.dir * sigma - self.c
    }

    /// Whether the step's cost is paid at x: beyond its edge in the direction `dir`.
    fn is_active(&self, x: f64, sigma: f64) -> bool {
        let edge = self.edge(sigma);
        if self.dir > 0.0 { x > edge } else { x < edge }
    }
}

/// Σ k over the steps active at x.
fn steps_at(steps: &[Step], x: f64, sigma: f64) -> f64 {
    steps
        .iter()
        .filter(|st| st.is_active(x, sigma))
        .map(|st| st.k)
        .sum()
}

/// The exact minimiser of Σ w min(|x + c|, σ) + Σ steps over x in [lo, hi], preferring
/// `current` on ties. The truncated sum is piecewise linear, concave except at its kinks −c, and
/// a step only adds a constant on one side of its edge, so the minimum lies at a kink, at a
/// step's edge (on its free side) or at a bound.
///
/// One sweep over the sorted breakpoints (−c − σ, −c, −c + σ), between which the sum is linear,
/// gives its value at every candidate in O(n log n) instead of O(n²) (segments of the background
/// carry thousands of terms); [`minimise_contacts_plain`] is the reference it is tested against.
fn minimise_contacts(
    terms: &[(f64, f64)],
    steps: &[Step],
    sigma: f64,
    current: f64,
    lo: f64,
    hi: f64,
) -> f64 {
    let events = breakpoints(terms, steps, sigma);
    // Steps by edge, to add the active ones at each candidate by binary search.
    let edges = |dir: f64| {
        let mut v: Vec<(f64, f64)> = steps
            .iter()
            .filter(|st| st.dir == dir)
            .map(|st| (st.edge(sigma), st.k))
            .collect();
        v.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut sum = 0.0;
        let prefix: Vec<f64> = std::iter::once(0.0)
            .chain(v.iter().map(|e| {
                sum += e.1;
                sum
            }))
            .collect();
        (v, prefix)
    };
    let (behind, behind_sum) = edges(1.0);
    let (ahead, ahead_sum) = edges(-1.0);
    let step_cost = |x: f64| {
        // dir = 1: active when x > edge; dir = −1: active when x < edge.
        let below = behind.partition_point(|e| e.0 < x);
        let above = ahead.partition_point(|e| e.0 <= x);
        behind_sum[below] + (ahead_sum[ahead.len()] - ahead_sum[above])
    };
    let mut value: f64 = terms.iter().map(|&(w, _)| w * sigma).sum();
    let (mut slope, mut at) = (0.0, f64::NEG_INFINITY);
    let mut best_candidate: Option<(f64, f64)> = None;
    for &(x, change, candidate) in &events {
        if at.is_finite() {
            value += slope * (x - at);
        }
        at = x;
        if candidate && (lo..=hi).contains(&x) {
            let total = value + step_cost(x);
            if best_candidate.is_none_or(|(v, _)| total < v) {
                best_candidate = Some((total, x));
            }
        }
        slope += change;
    }
    let total = |x: f64| truncated(terms, x, sigma) + steps_at(steps, x, sigma);
    let mut best = (total(current), current);
    let candidates = best_candidate.map(|(_, x)| x).into_iter().chain([lo, hi]);
    for x in candidates.filter(|x| (lo..=hi).contains(x)) {
        let e = total(x);
        if e < best.0 - 1e-12 {
            best = (e, x);
        }
    }
    best.1
}

/// The breakpoints of [`minimise_contacts`]' sum in ascending position: (position, slope
/// change, is a candidate). Each term's kink −c (a candidate, slope +2w) and its truncation
/// points −c ± σ (slope −w), and each step's edge (a candidate where the step is still free).
/// The kinks are sorted once and the three shifted copies merged, a third of the sorting of
/// all 3n points.
fn breakpoints(terms: &[(f64, f64)], steps: &[Step], sigma: f64) -> Vec<(f64, f64, bool)> {
    let mut kinks: Vec<(f64, f64)> = terms.iter().map(|&(w, c)| (-c, w)).collect();
    kinks.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut edges: Vec<f64> = steps.iter().map(|st| st.edge(sigma)).collect();
    edges.sort_by(f64::total_cmp);
    // Four ascending streams (shifting by σ keeps the order): lower truncations, kinks, upper
    // truncations, step edges.
    let streams: [Vec<(f64, f64, bool)>; 4] = [
        kinks.iter().map(|&(x, w)| (x - sigma, -w, false)).collect(),
        kinks.iter().map(|&(x, w)| (x, 2.0 * w, true)).collect(),
        kinks.iter().map(|&(x, w)| (x + sigma, -w, false)).collect(),
        edges.iter().map(|&x| (x, 0.0, true)).collect(),
    ];
    let mut next = [0; 4];
    let mut events = Vec::with_capacity(streams.iter().map(Vec::len).sum());
    while let Some(i) = (0..4)
        .filter(|&i| next[i] < streams[i].len())
        .min_by(|&i, &j| streams[i][next[i]].0.total_cmp(&streams[j][next[j]].0))
    {
        events.push(streams[i][next[i]]);
        next[i] += 1;
    }
    events
}

/// [`minimise_contacts`] by evaluating the sum at every candidate: the plain reference.
#[cfg(test)]
fn minimise_contacts_plain(
    terms: &[(f64, f64)],
    steps: &[Step],
    sigma: f64,
    current: f64,
    lo: f64,
    hi: f64,
) -> f64 {
    let total = |x: f64| truncated(terms, x, sigma) + steps_at(steps, x, sigma);
    let mut best = (total(current), current);
    for x in terms
        .iter()
        .map(|&(_, c)| -c)
        .chain(steps.iter().map(|st| st.edge(sigma)))
        .chain([lo, hi])
        .filter(|x| (lo..=hi).contains(x))
    {
        let e = total(x);
        if e < best.0 - 1e-12 {
            best = (e, x);
        }
    }
    best.1
}

/// Builds the contact problem of `soup` (its pieces' planes and motions; scales are ignored).
pub fn build_problem(soup: &Soup, inputs: &ScaleInputs, params: &ScaleParams) -> Problem {
    let ScaleInputs {
        boundaries,
        flow,
        reliable,
        ..
    } = *inputs;
    let unit = |p: &Piece| Piece { lambda: 1.0, ..*p };
    let width = inputs.superpixels.labels.width();
    let mut links = Vec::new();
    for edge in boundaries.edges.iter().filter(|e| !e.pairs.is_empty()) {
        let (a, b) = (edge.a as usize, edge.b as usize);
        let (pa, pb) = (&soup.pieces[a], &soup.pieces[b]);
        let mut jumps: Vec<f64> = edge
            .pairs
            .iter()
            .map(|&(p, q)| flow_jump(flow.data()[p as usize], flow.data()[q as usize]))
            .collect();
        let mut terms = Vec::new();
        let mut c1s = Vec::new();
        let mut frame1 = Vec::new();
        for (j, r) in sampled_pairs(edge, inputs, params) {
            let (Some(ra), Some(rb)) = (ray_point(&unit(pa), &r), ray_point(&unit(pb), &r)) else {
                continue;
            };
            let w = pair_weight(soup, inputs, params, edge, j);
            // The gap in each frame at log-scales s is (s_a − s_b) + (its value at unit scale).
            for (f, c) in gaps(&ra, &rb).into_iter().enumerate() {
                if c.is_finite() {
                    terms.push((w, c));
                    if f == 0 {
                        c1s.push(c);
                        frame1.push((w, c));
                    }
                }
            }
        }
        if terms.is_empty() {
            continue;
        }
        // Every touching pair carries total weight (its gaps' share) independent of its length.
        let total: f64 = terms.len() as f64;
        terms.iter_mut().for_each(|t| t.0 /= total);
        frame1.iter_mut().for_each(|t| t.0 /= total);
        jumps.sort_by(f64::total_cmp);
        c1s.sort_by(f64::total_cmp);
        let trusted = edge
            .pairs
            .iter()
            .filter(|&&(p, q)| reliable.data()[p as usize] && reliable.data()[q as usize])
            .count();
        links.push(Link {
            upper: upper_piece(edge, width),
            a,
            b,
            terms,
            frame1,
            median_c1: c1s.get(c1s.len() / 2).copied().unwrap_or(f64::NAN),
            flow_jump: jumps[jumps.len() / 2],
            trusted_share: trusted as f64 / edge.pairs.len() as f64,
        });
    }
    let mut touching = vec![Vec::new(); soup.pieces.len()];
    for (e, l) in links.iter().enumerate() {
        touching[l.a].push(e);
        touching[l.b].push(e);
    }
    Problem {
        links,
        touching,
        sigma: params.sigma,
    }
}

/// The piece of `edge` whose pixels lie directly above the other's (one row up, in an image
/// `width` pixels wide) on at least [`ground::MIN_RESTING_PIXELS`] of its pixel pairs (the one
/// with more such pairs; `None` on a tie), see [`Link::upper`].
fn upper_piece(edge: &BoundaryEdge, width: usize) -> Option<usize> {
    let (mut a_over_b, mut b_over_a) = (0, 0);
    for &(p, q) in &edge.pairs {
        let (p, q) = (p as usize, q as usize);
        a_over_b += usize::from(q == p + width);
        b_over_a += usize::from(p == q + width);
    }
    if a_over_b.max(b_over_a) < ground::MIN_RESTING_PIXELS || a_over_b == b_over_a {
        None
    } else if a_over_b > b_over_a {
        Some(edge.a as usize)
    } else {
        Some(edge.b as usize)
    }
}

/// Rigid segments: union-find over touching pieces of one hypothesis whose planes meet at
/// log-scales `s` (median frame-1 gap below [`ScaleParams::segment_gap`], or below
/// [`ScaleParams::world_gap`] between two pieces of the static world, see `world_pieces`).
/// Pieces marked in `apart` join only each other (pieces sunk under the ground, see
/// `Segments::new`). Returns the segment of every piece (0-based, dense) and the segments'
/// sizes.
pub fn rigid_segments(
    soup: &Soup,
    inputs: &ScaleInputs,
    problem: &Problem,
    s: &[f64],
    params: &ScaleParams,
    apart: Option<&[bool]>,
) -> (Vec<usize>, Vec<usize>) {
    let apart = |i: usize| apart.is_some_and(|a| a[i]);
    let n = soup.pieces.len();
    let world = world_pieces(soup, inputs, params.world_parallax);
    let mut parent: Vec<usize> = (0..n).collect();
    for l in &problem.links {
        let g = (l.median_c1 + s[l.a] - s[l.b]).abs();
        let meet = g < params.segment_gap || (world[l.a] && world[l.b] && g < params.world_gap);
        let same_side = apart(l.a) == apart(l.b);
        if soup.pieces[l.a].hypothesis == soup.pieces[l.b].hypothesis && meet && same_side {
            union(&mut parent, l.a, l.b);
        }
    }
    let mut index = vec![usize::MAX; n];
    let mut sizes = Vec::new();
    let segment = (0..n)
        .map(|i| {
            let r = find(&mut parent, i);
            if index[r] == usize::MAX {
                index[r] = sizes.len();
                sizes.push(0);
            }
            sizes[index[r]] += 1;
            index[r]
        })
        .collect();
    (segment, sizes)
}

/// The rigid segments of a soup at equal scales, as the segment solve sees them.
struct Segments {
    /// Segment of every piece.
    segment: Vec<usize>,
    /// Pieces per segment.
    sizes: Vec<usize>,
    /// Per segment, the log-scale that puts it at median depth 1 (see `segment_centres`).
    centre: Vec<f64>,
    /// Per segment, whether it is on the ego-motion (hypothesis 0) and not sunk under the
    /// ground: a part of the static world.
    ego: Vec<bool>,
    /// Per segment, whether it is measured static world: on the ego-motion, with at least
    /// [`ScaleParams::measured_share`] of its pieces well measured (`world_pieces`).
    measured: Vec<bool>,
    /// The static world's segment: the largest on the ego-motion.
    world: Option<usize>,
    /// Per segment, whether it is floor: on the ego-motion, with at least half of its pieces
    /// within σ of the static world's ground at equal scale (see `below`). The static prior
    /// holds such a segment with its full weight (`ScaleParams::static_max` does not cap it).
    grounded: Vec<bool>,
    /// Per segment, whether it is on the ego-motion and meets the static world's segment at
    /// equal scale, directly or through other such segments, across a link whose median
    /// frame-1 gap is below [`ScaleParams::world_gap`] (see `attached_to_world`): a part of
    /// the static world that `segment_gap` split off. The static prior holds it with its full
    /// weight, like the floor.
    attached: Vec<bool>,
    /// Per piece, how far it lies under the static world's ground at equal scales
    /// ([`ground::depth_below_ground`]); `None` for pieces above the horizon, and for every
    /// piece when no ground is in view.
    below: Vec<Option<f64>>,
    /// Per piece on a motion of its own, where it rests on the ground: the log-depth gaps of
    /// its bottom pixels over the ground at equal scales ([`ground::resting_gaps`]); empty for
    /// the static world's pieces, for pieces that do not rest on it, and for every piece when
    /// the rest prior is off or the ground does not reach the bottom of the view
    /// ([`ScaleParams::rest_bottom_share`]).
    resting: Vec<Vec<f64>>,
    /// Whether the static world's ground runs to the near edge of the view
    /// ([`ScaleParams::rest_bottom_share`]): a floor that things stand on, so the world below a
    /// mover's bottom edge may be floor in front of it (see `segment_pair_terms`).
    floor: bool,
    /// Whether the static world's ground plane was found.
    ground: bool,
}

/// The static world's segment: the largest on the ego-motion (the earlier one on a tie).
fn static_world(sizes: &[usize], ego: &[bool]) -> Option<usize> {
    (0..sizes.len())
        .filter(|&g| ego[g])
        .max_by_key(|&g| (sizes[g], std::cmp::Reverse(g)))
}

/// Per segment, whether it is on the ego-motion (`ego`) and reaches the static world's segment
/// `world` through links between such segments whose median frame-1 gap at equal scale is
/// below `gap` (the world itself included). The ego-motion gives every static piece the world's
/// scale, so a static fragment that a tight `segment_gap` split off still meets the world
/// nearly there somewhere (the road's sky at 0.048: links within 0.05-0.2), while a mover that
/// the ego-motion explains at a wrong depth meets it nowhere (the crowd's brick-box walker:
/// 0.72 and more, the log of its depth error).
fn attached_to_world(
    problem: &Problem,
    segment: &[usize],
    ego: &[bool],
    world: Option<usize>,
    gap: f64,
) -> Vec<bool> {
    let Some(world) = world else {
        return vec![false; ego.len()];
    };
    let mut parent: Vec<usize> = (0..ego.len()).collect();
    for l in &problem.links {
        let (ga, gb) = (segment[l.a], segment[l.b]);
        if ego[ga] && ego[gb] && l.median_c1.abs() < gap {
            union(&mut parent, ga, gb);
        }
    }
    let root = find(&mut parent, world);
    (0..ego.len())
        .map(|g| find(&mut parent, g) == root)
        .collect()
}

/// The static world's ground plane at the unit scale of `world_piece` (the well-measured pieces
/// of the static world, which share the ego-motion's unit scale whatever segment they end in;
/// see [`ground::ground_plane`]). `None` without a ground in view or with a zero
/// [`ScaleParams::ground_weight`].
fn world_ground(
    soup: &Soup,
    inputs: &ScaleInputs,
    world_piece: &[bool],
    params: &ScaleParams,
) -> Option<Vector3<f64>> {
    params
        .looks_for_ground()
        .then(|| {
            ground::ground_plane(
                soup,
                inputs.superpixels,
                inputs.intrinsics,
                world_piece,
                params.ground_share,
            )
        })
        .flatten()
}

/// Per piece, how far it lies under `plane` at equal scales (see `Segments::below`). Pieces
/// without a plane of their own count too: near the epipole a car driving ahead has too little
/// parallax for one, and its borrowed camera-facing planes are what sinks (leaving them out took
/// the road with exact flow from 0.048 to 0.061). All `None` without a plane.
fn depths_below(
    soup: &Soup,
    inputs: &ScaleInputs,
    plane: Option<&Vector3<f64>>,
) -> Vec<Option<f64>> {
    (0..soup.pieces.len())
        .map(|i| {
            plane.and_then(|m| {
                ground::depth_below_ground(soup, inputs.superpixels, inputs.intrinsics, m, i)
            })
        })
        .collect()
}

/// Whether `plane`, the static world's ground, covers at least
/// [`ScaleParams::rest_bottom_share`] of the view's bottom rows ([`ground::bottom_share`]): a
/// floor that things stand on runs to the near edge of the view (see `Segments::floor`).
fn floor_in_view(
    soup: &Soup,
    inputs: &ScaleInputs,
    world_piece: &[bool],
    plane: Option<&Vector3<f64>>,
    params: &ScaleParams,
) -> bool {
    plane.is_some_and(|m| {
        ground::bottom_share(soup, inputs.superpixels, inputs.intrinsics, m, world_piece)
            >= params.rest_bottom_share
    })
}

/// Per piece on a motion of its own, where it rests on `plane` (see `Segments::resting`): the
/// log-depth gaps of its resting pixels ([`ground::resting_gaps`]). All empty without a plane,
/// with a zero [`ScaleParams::rest_weight`], or without a `floor` ([`floor_in_view`]).
fn resting_on(
    soup: &Soup,
    inputs: &ScaleInputs,
    world_piece: &[bool],
    plane: Option<&Vector3<f64>>,
    floor: bool,
    params: &ScaleParams,
) -> Vec<Vec<f64>> {
    let plane = plane.filter(|_| floor && params.rest_weight > 0.0);
    (0..soup.pieces.len())
        .map(|i| match plane {
            Some(m) if soup.pieces[i].hypothesis != 0 => ground::resting_gaps(
                soup,
                inputs.superpixels,
                inputs.intrinsics,
                m,
                world_piece,
                i,
            ),
            _ => Vec::new(),
        })
        .collect()
}

impl Segments {
    /// The segments of `soup` at equal scales ([`rigid_segments`] at s = 0).
    ///
    /// Pieces on the ego-motion that lie more than [`ScaleParams::sunk_gap`] under the ground
    /// of the static world at its scale are not static: a mover that the ego-motion explains
    /// at a wrong, larger depth (a car driving ahead, seen near the epipole) sinks under the
    /// road. Such pieces join only each other and their segments are movers (no static prior,
    /// no exemption from the figure prior). Pieces touching the image's border are not split
    /// off: their flow (pixels leaving the view) and planes are the least reliable, and on the
    /// crowd the floor's border pieces read 0.2–0.5 under its own ground.
    fn new(soup: &Soup, inputs: &ScaleInputs, problem: &Problem, params: &ScaleParams) -> Self {
        let n = soup.pieces.len();
        let world_piece = world_pieces(soup, inputs, params.world_parallax);
        let plane = world_ground(soup, inputs, &world_piece, params);
        let below = depths_below(soup, inputs, plane.as_ref());
        let floor = floor_in_view(soup, inputs, &world_piece, plane.as_ref(), params);
        let resting = resting_on(soup, inputs, &world_piece, plane.as_ref(), floor, params);
        let labels = &inputs.superpixels.labels;
        let (width, height) = (labels.width() as u32, labels.height() as u32);
        let sunk: Vec<bool> = (soup.pieces.iter().zip(&below))
            .zip(&inputs.superpixels.segments)
            .map(|((piece, below), seg)| {
                let [x0, y0, x1, y1] = seg.bbox;
                let border = x0 == 0 || y0 == 0 || x1 + 1 >= width || y1 + 1 >= height;
                piece.hypothesis == 0 && !border && below.is_some_and(|b| b > params.sunk_gap)
            })
            .collect();
        let zero = vec![0.0; n];
        let (segment, sizes) = rigid_segments(soup, inputs, problem, &zero, params, Some(&sunk));
        let centre = segment_centres(soup, inputs, &segment, sizes.len());
        // Segments are of one hypothesis and one side of the split each.
        let mut ego = vec![false; sizes.len()];
        let mut well_measured = vec![0usize; sizes.len()];
        for i in 0..n {
            ego[segment[i]] = soup.pieces[i].hypothesis == 0 && !sunk[i];
            well_measured[segment[i]] += usize::from(world_piece[i]);
        }
        let measured = (0..sizes.len())
            .map(|g| ego[g] && well_measured[g] as f64 >= params.measured_share * sizes[g] as f64)
            .collect();
        let world = static_world(&sizes, &ego);
        let mut on_ground = vec![0usize; sizes.len()];
        for (&g, b) in segment.iter().zip(&below) {
            on_ground[g] += usize::from(b.is_some_and(|b| b.abs() < params.sigma));
        }
        let grounded = (0..sizes.len())
            .map(|g| ego[g] && 2 * on_ground[g] >= sizes[g])
            .collect();
        let attached = attached_to_world(problem, &segment, &ego, world, params.world_gap);
        Segments {
            segment,
            sizes,
            centre,
            ego,
            measured,
            world,
            grounded,
            attached,
            below,
            resting,
            floor,
            ground: plane.is_some(),
        }
    }

    /// Per-piece log-scales from segment offsets `u`: s = centre + u.
    fn log_scales(&self, u: &[f64]) -> Vec<f64> {
        self.segment
            .iter()
            .map(|&g| u[g] + self.centre[g])
            .collect()
    }

    /// Per segment, the median offset s − centre of its pieces in `s` (0 for a segment without
    /// a finite value; pieces past the end of `s` do not count).
    fn offsets_of(&self, s: &[f64]) -> Vec<f64> {
        let mut offsets = vec![Vec::new(); self.sizes.len()];
        for (i, &g) in self.segment.iter().enumerate() {
            if let Some(&x) = s.get(i).filter(|x| x.is_finite()) {
                offsets[g].push(x - self.centre[g]);
            }
        }
        offsets
            .into_iter()
            .map(|mut v| {
                v.sort_by(f64::total_cmp);
                v.get(v.len() / 2).copied().unwrap_or(0.0)
            })
            .collect()
    }
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

/// Per-piece log-scales `start` made one per rigid segment (each segment at the median offset
/// of its pieces), then, with `descend`, the segment solve (step 2 alone) from there instead of
/// its own starts (brought into the solve's band around the largest segment first): the truth
/// test's "truth as segments", which shows whether one scale per rigid segment can hold the
/// truth and whether the segment solve's minimum lies below it.
/// Pieces past the end of `start`, or with a non-finite value, do not count.
pub fn segment_descent_from(
    soup: &Soup,
    inputs: &ScaleInputs,
    params: &ScaleParams,
    start: &[f64],
    descend: bool,
) -> Vec<f64> {
    let problem = build_problem(soup, inputs, params);
    let segments = Segments::new(soup, inputs, &problem, params);
    let u0 = segments.offsets_of(start);
    let u = if descend {
        solve_segments(&problem, &segments, params, Some(u0)).0
    } else {
        u0
    };
    segments.log_scales(&u)
}

/// The segment solve's objective at per-piece log-scales `s` (each segment at the median
/// offset of its pieces, as [`segment_descent_from`] without descent): the truth test shows
/// which part of it ranks the truth above the solution.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SegmentObjective {
    /// Contacts between segments, the static prior and the rest prior (all truncated-linear
    /// terms).
    pub contacts: f64,
    /// The figure prior.
    pub figure: f64,
    /// The ground prior.
    pub ground: f64,
}

/// [`SegmentObjective`] of `s` for `soup` (unit scale).
pub fn segment_objective(
    soup: &Soup,
    inputs: &ScaleInputs,
    params: &ScaleParams,
    s: &[f64],
) -> SegmentObjective {
    ScaleEnergy::new(soup, inputs, params).segments(s)
}

/// The scale solve's two views of per-piece log-scales for one soup's planes and motions, added:
/// the per-piece contacts of [`build_problem`] (what the polish descends) plus the
/// [`SegmentObjective`] (what the segment solve minimises, each segment at the median of its
/// pieces). A contact between two segments counts in both views, one inside a segment in the
/// first only, the priors in the second only. Neither the contacts nor the segments depend on
/// the scales, so it is built once and scores many scalings.
pub struct ScaleEnergy {
    problem: Problem,
    segments: Segments,
    pairs: PairTerms,
}

impl ScaleEnergy {
    /// The energy for `soup`'s planes and motions.
    pub fn new(soup: &Soup, inputs: &ScaleInputs, params: &ScaleParams) -> Self {
        let problem = build_problem(soup, inputs, params);
        let segments = Segments::new(soup, inputs, &problem, params);
        let pairs = segment_pair_terms(&problem, &segments, params);
        ScaleEnergy {
            problem,
            segments,
            pairs,
        }
    }

    /// The segment objective at per-piece log-scales `s` (each segment at the median offset of
    /// its pieces).
    pub fn segments(&self, s: &[f64]) -> SegmentObjective {
        let u = self.segments.offsets_of(s);
        let sigma = self.problem.sigma;
        let mut out = SegmentObjective {
            contacts: 0.0,
            figure: 0.0,
            ground: 0.0,
        };
        for (&(g, h), pair) in &self.pairs {
            out.contacts += truncated(&pair.terms, u[g] - u[h], sigma);
            out.figure += steps_at(&pair.behind, u[g] - u[h], sigma);
            out.ground += steps_at(&pair.under, u[g] - u[h], sigma);
        }
        out
    }

    /// The whole energy at `s`: per-piece contacts plus every term of the segment objective.
    pub fn total(&self, s: &[f64]) -> f64 {
        let segments = self.segments(s);
        self.problem.energy(s) + segments.contacts + segments.figure + segments.ground
    }
}

/// The pieces of the static world whose depth their own flow measures well: on the ego-motion
/// (hypothesis 0), with a plane of their own and a parallax of at least `world_parallax` times
/// the flow's noise ([`Soup::noise_px`]). Where their planes meet within
/// [`ScaleParams::world_gap`] they are one rigid body and share one scale.
///
/// With noiseless flow (noise ≈ 0) every such piece with any parallax qualifies: its depth is
/// then as exact as its plane. Non-degenerate pieces already have a mean parallax of at least
/// `init.min_parallax_px`; the test at the anchor must also be positive.
pub fn world_pieces(soup: &Soup, inputs: &ScaleInputs, world_parallax: f64) -> Vec<bool> {
    soup.pieces
        .iter()
        .zip(&inputs.superpixels.segments)
        .map(|(p, seg)| {
            let parallax = parallax_px(p, inputs, seg.anchor);
            p.hypothesis == 0
                && p.degenerate.is_none()
                && parallax > 0.0
                && parallax >= world_parallax * soup.noise_px
        })
        .collect()
}

/// The image displacement (px) the translation of `piece` causes at `anchor` at unit scale: the
/// parallax its depth is measured by.
fn parallax_px(piece: &Piece, inputs: &ScaleInputs, anchor: [f64; 2]) -> f64 {
    let k = inputs.intrinsics;
    let ray = Vector3::from(k.ray(anchor[0], anchor[1]));
    let unit = Piece {
        lambda: 1.0,
        ..*piece
    };
    let Some(p) = ray_point(&unit, &ray) else {
        return 0.0;
    };
    let turned = piece.r * ray;
    if turned.z <= 0.0 {
        return 0.0;
    }
    let d = p.moved / p.moved.z - turned / turned.z;
    (k.fx * k.fy).sqrt() * hypot(d.x, d.y)
}

/// [`Segments::resting`] at the soup's current scales: per piece on a motion of its own, the
/// log-depth gaps ln z_i − ln z_G of its resting pixels over the ground, which is fitted to the
/// static world's well-measured pieces each at its own scale.
fn resting_at_scales(soup: &Soup, inputs: &ScaleInputs, params: &ScaleParams) -> Vec<Vec<f64>> {
    if params.rest_weight <= 0.0 {
        return vec![Vec::new(); soup.pieces.len()];
    }
    let world = world_pieces(soup, inputs, params.world_parallax);
    let mut absolute = soup.clone();
    for piece in &mut absolute.pieces {
        piece.m /= piece.lambda;
        piece.lambda = 1.0;
    }
    let plane = world_ground(&absolute, inputs, &world, params);
    let floor = floor_in_view(&absolute, inputs, &world, plane.as_ref(), params);
    resting_on(&absolute, inputs, &world, plane.as_ref(), floor, params)
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

/// Per segment, −median ln z̄ of its pieces' unit-scale anchor depths (0 without one): the
/// log-scale that puts the segment at median depth 1. Unit-scale depths of different motions
/// can differ by orders of magnitude, so scales are searched around these centres.
fn segment_centres(soup: &Soup, inputs: &ScaleInputs, segment: &[usize], count: usize) -> Vec<f64> {
    let mut logs = vec![Vec::new(); count];
    for ((piece, seg), &g) in soup
        .pieces
        .iter()
        .zip(&inputs.superpixels.segments)
        .zip(segment)
    {
        let z = piece.depth(&Vector3::from(
            inputs.intrinsics.ray(seg.anchor[0], seg.anchor[1]),
        )) / piece.lambda;
        if z.is_finite() && z > 0.0 {
            logs[g].push(ln(z));
        }
    }
    logs.into_iter()
        .map(|mut v| {
            if v.is_empty() {
                return 0.0;
            }
            v.sort_by(f64::total_cmp);
            -v[v.len() / 2]
        })
        .collect()
}

/// True when segment `g` is the figure against `h` (the smaller of the two, by pieces; the
/// later one on a tie): the side the figure prior keeps from lying behind.
fn is_figure(sizes: &[usize], g: usize, h: usize) -> bool {
    (sizes[g], std::cmp::Reverse(g)) < (sizes[h], std::cmp::Reverse(h))
}

/// Coordinate descent over segment offsets u (log-scale s = centre + u), from three starts;
/// returns the better u and the sweeps run. Only links between segments depend on u, so the
/// descent works on [`PairTerms`].
fn solve_segments(
    problem: &Problem,
    segments: &Segments,
    params: &ScaleParams,
    only_start: Option<Vec<f64>>,
) -> (Vec<f64>, usize) {
    let sizes = &segments.sizes;
    let count = sizes.len();
    let sigma = problem.sigma;
    let reference = (0..count).max_by_key(|&g| (sizes[g], std::cmp::Reverse(g)));
    let band = ln(params.band.max(1.0));
    let pairs = segment_pair_terms(problem, segments, params);
    let mut around: Vec<Vec<(usize, usize)>> = vec![Vec::new(); count];
    for &(g, h) in pairs.keys() {
        around[g].push((g, h));
        around[h].push((g, h));
    }
    let energy = |u: &[f64]| -> f64 {
        pairs
            .iter()
            .map(|(&(g, h), pair)| pair.value(u[g] - u[h], sigma))
            .sum()
    };
    // Segment g's terms as functions of its own offset x, the others fixed at u.
    let seg_terms = |g: usize, u: &[f64]| -> (Vec<(f64, f64)>, Vec<Step>) {
        let (mut terms, mut steps) = (Vec::new(), Vec::new());
        for key in &around[g] {
            let pair = &pairs[key];
            // d = x − u_h seen from the first of the pair, d = u_h − x from the second.
            let (sign, other) = if key.0 == g {
                (1.0, u[key.1])
            } else {
                (-1.0, u[key.0])
            };
            terms.extend(pair.terms.iter().map(|&(w, c)| (w, sign * c - other)));
            steps.extend(pair.steps().map(|st| Step {
                k: st.k,
                c: sign * st.c - other,
                dir: sign * st.dir,
            }));
        }
        (terms, steps)
    };
    let starts = match only_start {
        // The solve keeps every segment within the band around the reference, so a start
        // (the truth test's) is brought into it: a segment of one or two pieces can lie
        // e^5 and more from the rest at the truth, where the solve cannot reach.
        Some(mut start) => {
            if let Some(r) = reference {
                let centre = start[r];
                start
                    .iter_mut()
                    .for_each(|x| *x = x.clamp(centre - band, centre + band));
            }
            vec![start]
        }
        None => vec![
            spanning_tree_start(&pairs, sigma, count, reference, band),
            vec![0.0; count],
            discrete_start(&pairs, sigma, count, reference, band, sigma),
        ],
    };
    let mut best: Option<(f64, Vec<f64>)> = None;
    let mut sweeps = 0;
    for start in starts {
        let mut u = start;
        // Segments whose terms changed since they were last minimised (the minimiser keeps
        // the current offset on ties, so the others would not move).
        let mut dirty = vec![true; count];
        for _ in 0..30 {
            sweeps += 1;
            let mut moved = false;
            for g in 0..count {
                if Some(g) == reference || !dirty[g] {
                    continue;
                }
                dirty[g] = false;
                let r = reference.map_or(0.0, |r| u[r]);
                let (terms, steps) = seg_terms(g, &u);
                let x = minimise_contacts(&terms, &steps, sigma, u[g], r - band, r + band);
                if (x - u[g]).abs() > 1e-9 {
                    moved = true;
                    u[g] = x;
                    for &(a, b) in &around[g] {
                        dirty[if a == g { b } else { a }] = true;
                    }
                }
            }
            if !moved {
                break;
            }
        }
        let e = energy(&u);
        if best.as_ref().is_none_or(|(b, _)| e < *b) {
            best = Some((e, u));
        }
    }
    (
        best.map(|b| b.1).unwrap_or_else(|| vec![0.0; count]),
        sweeps,
    )
}

/// The terms between two segments g < h as functions of d = u_g − u_h (segment offsets u,
/// log-scale s = centre + u).
#[derive(Clone, Debug, Default)]
struct Pair {
    /// Their links' contact terms and the rest prior's (and the static prior's): Σ w min(|d + c|,
    /// σ).
    terms: Vec<(f64, f64)>,
    /// The figure prior, one step per link: the smaller segment's cost for lying behind the
    /// larger one, where the weighted median of the link's frame-1 gaps puts it more than σ
    /// behind (empty with a zero [`ScaleParams::behind_weight`]).
    behind: Vec<Step>,
    /// The ground prior, one step per piece of the pair's segment that is not the static
    /// world's (the other one): its cost for lying more than σ under the ground
    /// ([`ScaleParams::ground_weight`]).
    under: Vec<Step>,
}

impl Pair {
    fn value(&self, d: f64, sigma: f64) -> f64 {
        truncated(&self.terms, d, sigma)
            + steps_at(&self.behind, d, sigma)
            + steps_at(&self.under, d, sigma)
    }

    /// Both priors' steps.
    fn steps(&self) -> impl Iterator<Item = &Step> {
        self.behind.iter().chain(&self.under)
    }
}

/// Every pair of segments (g < h) that touch or share a prior (the static, ground and rest priors
/// tie segments to the static world's) and its [`Pair`].
type PairTerms = std::collections::BTreeMap<(usize, usize), Pair>;

/// Every link between two different segments, gathered into [`PairTerms`], with the figure
/// prior ([`ScaleParams::behind_weight`]) where the smaller segment is a mover and the flow
/// across the link is not continuous and trusted, the ground prior, the rest prior
/// ([`ScaleParams::rest_weight`]) and the static prior ([`ScaleParams::static_weight`]).
fn segment_pair_terms(problem: &Problem, segments: &Segments, params: &ScaleParams) -> PairTerms {
    let Segments {
        segment,
        sizes,
        centre,
        ..
    } = segments;
    let kappa = params.behind_weight;
    let mut pairs = PairTerms::new();
    for l in &problem.links {
        let (ga, gb) = (segment[l.a], segment[l.b]);
        if ga == gb {
            continue;
        }
        // Seen from g with h's offset at 0: δ = (centre_a + u_a) − (centre_b + u_b), and the
        // gap d + c is ln z_g − ln z_h.
        let (g, h) = (ga.min(gb), ga.max(gb));
        let other = centre[h] - centre[g];
        pairs
            .entry((g, h))
            .or_default()
            .terms
            .extend(l.seen_from(ga == g, other));
        // A measured part of the static world may lie behind anything: its own parallax placed
        // it. Across continuous trusted flow nothing occludes anything.
        let g_is_figure = is_figure(sizes, g, h);
        let figure = if g_is_figure { g } else { h };
        if kappa <= 0.0
            || segments.measured[figure]
            || l.shows_continuity(params)
            || stands_over_world(segments, l, figure)
        {
            continue;
        }
        let mut gaps: Vec<(f64, f64)> = l.frame1_seen_from(ga == g, other).collect();
        let weight: f64 = gaps.iter().map(|t| t.0).sum();
        if let Some(c) = weighted_median(&mut gaps) {
            // The figure g is behind when d + c > σ; the figure h when −(d + c) > σ.
            let dir = if g_is_figure { 1.0 } else { -1.0 };
            pairs.entry((g, h)).or_default().behind.push(Step {
                k: kappa * problem.sigma * weight,
                c,
                dir,
            });
        }
    }
    add_ground_prior(&mut pairs, segments, params.ground_weight * problem.sigma);
    add_rest_prior(&mut pairs, segments, params.rest_weight);
    add_static_prior(
        &mut pairs,
        segments,
        params.static_weight,
        params.static_max,
    );
    // Sorted terms reach `minimise_contacts` as sorted runs, which its sort merges.
    for pair in pairs.values_mut() {
        pair.terms.sort_by(|a, b| a.1.total_cmp(&b.1));
    }
    pairs
}

/// Whether link `l` is the bottom edge of the figure segment `figure` (the smaller one) over the
/// static world below the horizon, where things stand on a floor ([`Segments::floor`]): the
/// figure's piece lies directly above the world's there ([`Link::upper`]), and the world
/// piece's rays meet the ground ([`Segments::below`]). Below a standing thing the floor runs
/// towards the camera, in front of it, so lying behind the world there is no sign of a hole;
/// and the floor pieces at its feet mix floor with feet, their planes nearer still (at the
/// crowd's truth they put a walker 0.1–0.6 in log-depth behind them, and the prior charged the
/// truth 0.54 there). The ground prior still keeps the figure from sinking under the ground,
/// and the rest prior ties a mover to the ground it rests on.
fn stands_over_world(segments: &Segments, l: &Link, figure: usize) -> bool {
    let (piece, other) = if segments.segment[l.a] == figure {
        (l.a, l.b)
    } else {
        (l.b, l.a)
    };
    segments.floor
        && l.upper == Some(piece)
        && Some(segments.segment[other]) == segments.world
        && segments.below[other].is_some()
}

/// The ground prior: every piece outside the ground's segment whose rays meet the ground pays
/// `k` where its segment's offset puts it (the median of its pixels) more than σ under the
/// ground.
fn add_ground_prior(pairs: &mut PairTerms, segments: &Segments, k: f64) {
    let Some(w) = segments.world.filter(|_| k > 0.0) else {
        return;
    };
    for (&g, below) in segments.segment.iter().zip(&segments.below) {
        let Some(below) = below.filter(|_| g != w) else {
            continue;
        };
        // ln z_piece − ln z_ground = (u_g − u_w) + (centre_g − centre_w) + below.
        let c = segments.centre[g] - segments.centre[w] + below;
        let (key, step) = if g < w {
            ((g, w), Step { k, c, dir: 1.0 })
        } else {
            // d = u_w − u_g: under the ground when −(d − c) > σ.
            (
                (w, g),
                Step {
                    k,
                    c: -c,
                    dir: -1.0,
                },
            )
        };
        pairs.entry(key).or_default().under.push(step);
    }
}

/// The rest prior: every piece outside the ground's segment that rests on the ground
/// (`Segments::resting`) is tied to it as if by `weight` contacts, spread evenly over its
/// resting pixels, each gap the log-depth of the piece's bottom over the ground there.
fn add_rest_prior(pairs: &mut PairTerms, segments: &Segments, weight: f64) {
    let Some(w) = segments.world.filter(|_| weight > 0.0) else {
        return;
    };
    for (&g, gaps) in segments.segment.iter().zip(&segments.resting) {
        if g == w || gaps.is_empty() {
            continue;
        }
        let each = weight / gaps.len() as f64;
        // ln z_piece − ln z_ground = (u_g − u_w) + (centre_g − centre_w) + gap.
        let offset = segments.centre[g] - segments.centre[w];
        let (key, sign) = if g < w { ((g, w), 1.0) } else { ((w, g), -1.0) };
        let terms = &mut pairs.entry(key).or_default().terms;
        // Seen from w (d = u_w − u_g) the gap is −(d − c): the same magnitude as d − c.
        terms.extend(gaps.iter().map(|&gap| (each, sign * (offset + gap))));
    }
}

/// The static prior: every segment on the ego-motion but the largest (the static world) is
/// tied to that one as if by `weight` contacts per piece at equal scale, by at most `max`
/// contacts unless it is floor (`Segments::grounded`) or meets the world at equal scale
/// (`Segments::attached`). The ego-motion explains such a
/// segment's flow at the world's scale, so it is static unless its contacts say otherwise (a
/// walker moving parallel to the camera's translation); the floor does not move.
fn add_static_prior(pairs: &mut PairTerms, segments: &Segments, weight: f64, max: f64) {
    let Segments {
        sizes, centre, ego, ..
    } = segments;
    let Some(world) = segments.world.filter(|_| weight > 0.0) else {
        return;
    };
    let pull = |g: usize| {
        let full = weight * sizes[g] as f64;
        if segments.grounded[g] || segments.attached[g] {
            full
        } else {
            full.min(max)
        }
    };
    for g in (0..sizes.len()).filter(|&g| ego[g] && g != world) {
        // s_a − s_b = d + centre_a − centre_b with d = u_a − u_b.
        let (a, b) = (g.min(world), g.max(world));
        pairs
            .entry((a, b))
            .or_default()
            .terms
            .push((pull(g), centre[a] - centre[b]));
    }
}

/// Start: a maximum spanning tree over segment pairs by how much their links weigh, walked from
/// the reference segment; each segment takes the offset that best meets its tree parent.
fn spanning_tree_start(
    pairs: &PairTerms,
    sigma: f64,
    count: usize,
    reference: Option<usize>,
    band: f64,
) -> Vec<f64> {
    let mut u = vec![0.0; count];
    let Some(root) = reference else { return u };
    let mut edges: Vec<((usize, usize), f64, f64)> = pairs
        .iter()
        .map(|(&key, pair)| {
            let weight: f64 = pair.terms.iter().map(|t| t.0).sum();
            // Best d = u_g − u_h.
            let d = minimise_contacts(
                &pair.terms,
                &pair.steps().copied().collect::<Vec<_>>(),
                sigma,
                0.0,
                -2.0 * band,
                2.0 * band,
            );
            (key, weight, d)
        })
        .collect();
    edges.sort_by(|x, y| y.1.total_cmp(&x.1).then(x.0.cmp(&y.0)));
    let mut placed = vec![false; count];
    placed[root] = true;
    while let Some(&((g, h), _, d)) = edges.iter().find(|e| placed[e.0.0] != placed[e.0.1]) {
        if placed[g] {
            u[h] = (u[g] - d).clamp(-band, band);
            placed[h] = true;
        } else {
            u[g] = (u[h] + d).clamp(-band, band);
            placed[g] = true;
        }
    }
    u
}

/// Offsets on each side of 0 in [`discrete_start`]'s grid at most: 2 · 32 + 1 labels keep its
/// pairwise tables at 33 KB per segment pair whatever σ is.
const MAX_HALF_GRID: f64 = 32.0;

/// TRW-S passes of [`discrete_start`] (its MRF has tens of nodes; 30 passes converge).
const DISCRETE_PASSES: usize = 30;

/// Start: the segment offsets (log-scales, relative to the reference segment's) on a grid of
/// step `step` (at least band / [`MAX_HALF_GRID`]) within ±`band`, all at once, by TRW-S over
/// the segment graph (each pairwise table is the segments' links summed at each offset
/// difference). Coordinate descent moves one segment at a time and stops where moving any
/// single one breaks more contacts than it makes, e.g. a box glued to the wall behind it that
/// would have to move together with the piece of floor it stands on; the joint labelling sees
/// such moves. The reference segment stays at 0; all stay at 0 when the band has no room.
fn discrete_start(
    pairs: &PairTerms,
    sigma: f64,
    count: usize,
    reference: Option<usize>,
    band: f64,
    step: f64,
) -> Vec<f64> {
    let step = step.max(band / MAX_HALF_GRID);
    let half = (band / step).floor();
    if half.is_nan() || half < 1.0 {
        return vec![0.0; count];
    }
    let half = half as usize;
    let labels = 2 * half + 1;
    let offset = |l: usize| (l as f64 - half as f64) * step;
    // Ties go to the segment's centre (offset 0) by a vanishing preference.
    let unary = (0..count)
        .map(|g| {
            (0..labels)
                .map(|l| {
                    if Some(g) == reference && l != half {
                        1e9
                    } else {
                        1e-9 * offset(l).abs()
                    }
                })
                .collect()
        })
        .collect();
    let mut mrf = Mrf::new(unary);
    for (&(g, h), pair) in pairs {
        // The table depends on d = u_g − u_h only: 2·labels − 1 values.
        let by_difference: Vec<f64> = (0..2 * labels - 1)
            .map(|k| pair.value((k as f64 - (labels - 1) as f64) * step, sigma))
            .collect();
        let mut table = Vec::with_capacity(labels * labels);
        for lg in 0..labels {
            for lh in 0..labels {
                table.push(by_difference[lg + labels - 1 - lh]);
            }
        }
        mrf.add_edge(g, h, table);
    }
    let result = trws(
        &mrf,
        &TrwsOptions {
            iterations: DISCRETE_PASSES,
        },
    );
    result.labels.into_iter().map(offset).collect()
}

/// Tail control: pieces whose depth disagrees with every touching neighbour in both frames
/// (each link's cost within 10 % of its fully truncated value) while some boundary of theirs
/// shows continuous trusted flow ([`Link::shows_continuity`], the figure prior's test) move to
/// the scale that best meets their neighbours.
/// Returns how many moved.
fn tail_control(problem: &Problem, s: &mut [f64], params: &ScaleParams) -> usize {
    let sigma = problem.sigma;
    let mut moved = 0;
    for i in 0..s.len() {
        let links = &problem.touching[i];
        if links.is_empty() {
            continue;
        }
        let disagrees = links.iter().all(|&e| {
            let l = &problem.links[e];
            l.value(s[l.a] - s[l.b], sigma) >= 0.9 * l.full(sigma)
        });
        let continuous = links
            .iter()
            .any(|&e| problem.links[e].shows_continuity(params));
        if disagrees && continuous {
            let terms = problem.local_terms(i, s);
            let x = minimise_contacts(&terms, &[], sigma, s[i], f64::NEG_INFINITY, f64::INFINITY);
            if (x - s[i]).abs() > 1e-9 {
                s[i] = x;
                moved += 1;
            }
        }
    }
    moved
}

/// Per-piece coordinate descent on E from `s` (each piece in turn to the exact minimum of its
/// own terms) until nothing moves or `sweeps` pass: the polisher of the truth test.
pub fn polish(problem: &Problem, s: &mut [f64], sweeps: usize) {
    for _ in 0..sweeps {
        let mut moved = false;
        for i in 0..s.len() {
            if problem.touching[i].is_empty() {
                continue;
            }
            let terms = problem.local_terms(i, s);
            let x = minimise_contacts(
                &terms,
                &[],
                problem.sigma,
                s[i],
                f64::NEG_INFINITY,
                f64::INFINITY,
            );
            if (x - s[i]).abs() > 1e-9 {
                s[i] = x;
                moved = true;
            }
        }
        if !moved {
            break;
        }
    }
}

/// How much a boundary pixel pair (p, q) between two pieces says that they touch, in
/// [evidence_floor, 1]:
/// - the continuity of the flow across the pair, exp(−‖f(p) − f(q)‖ / flow_scale_px): a surface
///   that really continues (a waving flag) moves continuously;
/// - where one piece stands on the other (`standing`: the lower pixel's piece has a ground-like
///   plane of its own, [`ground::has_ground_like_plane`]), at least the sine of the angle
///   between their planes: feet move while the floor does not, so the flow jumps between them,
///   yet they meet along the line where their planes cross, and a boundary that matches there
///   is no accident.
///
/// Elsewhere planes at an angle are no evidence: the planes of small pieces of a bending sheet,
/// or along a floating object's outline, lie at noisy angles to their neighbours', and counting
/// those glued the flag's bands and FlyingThings3D's objects to their neighbours at wrong
/// depths (docs/RESULTS.md, Stop 50). What is left weak is a pair whose flow jumps: an occlusion
/// (one person in front of another), which scaling one plane onto the other would fake as a
/// contact. Unknown flow (a given flow's missing vectors) or a piece without a plane gives no
/// evidence of its kind (`f64::max` passes over NaN).
fn contact_evidence(
    m_a: &Vector3<f64>,
    m_b: &Vector3<f64>,
    f_p: [f32; 2],
    f_q: [f32; 2],
    standing: bool,
    params: &ScaleParams,
) -> f64 {
    let continuity = exp(-flow_jump(f_p, f_q) / params.flow_scale_px);
    let angle = if standing {
        m_a.normalize().cross(&m_b.normalize()).norm()
    } else {
        0.0
    };
    continuity.max(angle).max(params.evidence_floor)
}

/// The boundary pairs of `edge` that the contact terms use, each with the ray (normalised,
/// z = 1) through the midpoint of its two pixels. A boundary of at most `pairs_per_boundary`
/// pairs uses them all; a longer one uses as many as every ⌈len / pairs_per_boundary⌉-th pair
/// would give, spread evenly over its side-by-side pairs and its stacked pairs in proportion
/// to their counts (see `sample_indices`).
pub fn sampled_pairs<'e>(
    edge: &'e crate::superpixels::graph::BoundaryEdge,
    inputs: &ScaleInputs<'e>,
    params: &ScaleParams,
) -> impl Iterator<Item = (usize, Vector3<f64>)> + 'e {
    let width = inputs.superpixels.labels.width();
    let k = *inputs.intrinsics;
    sample_indices(&edge.pairs, width, params.pairs_per_boundary)
        .into_iter()
        .map(move |j| {
            let (p, q) = edge.pairs[j];
            let (p, q) = (p as usize, q as usize);
            let mid = [
                (p % width + q % width) as f64 * 0.5,
                (p / width + q / width) as f64 * 0.5,
            ];
            (j, Vector3::from(k.ray(mid[0], mid[1])))
        })
}

/// Indices (ascending) of the pairs of one boundary that its contact terms sample: all of them
/// up to `per_boundary`, else ⌈len / ⌈len / per_boundary⌉⌉ of them, shared between
/// side-by-side pairs (q = p + 1) and stacked pairs (q = p + width) in proportion to their
/// counts and evenly spaced within each kind. The pairs come in scan order, where a slanted
/// boundary alternates the two kinds, so a plain stride would take only one kind whenever it
/// is even; only stacked pairs carry ground support (`pair_weight`), so which kind the stride
/// took used to change a boundary's weight with the parity of its length (the flag moved by
/// 0.054 between 10 and 12 pairs per boundary).
fn sample_indices(pairs: &[(u32, u32)], width: usize, per_boundary: usize) -> Vec<usize> {
    let len = pairs.len();
    let per_boundary = per_boundary.max(1);
    if len <= per_boundary {
        return (0..len).collect();
    }
    let count = len.div_ceil(len.div_ceil(per_boundary));
    let (stacked, side): (Vec<usize>, Vec<usize>) =
        (0..len).partition(|&j| pairs[j].1 as usize == pairs[j].0 as usize + width);
    // Rounded share of the stacked kind, at least one of each kind present.
    let mut n_stacked = (count * stacked.len() + len / 2) / len;
    if !stacked.is_empty() {
        n_stacked = n_stacked.max(1);
    }
    if !side.is_empty() {
        n_stacked = n_stacked.min(count - 1);
    }
    let evenly = |kind: &[usize], n: usize| -> Vec<usize> {
        let n = n.min(kind.len());
        (0..n)
            .map(|i| kind[(2 * i + 1) * kind.len() / (2 * n)])
            .collect()
    };
    let mut picked = evenly(&stacked, n_stacked);
    picked.extend(evenly(&side, count - n_stacked));
    picked.sort_unstable();
    picked
}

/// ‖f(p) − f(q)‖ in pixels: how much the flow jumps between two pixels.
fn flow_jump(f_p: [f32; 2], f_q: [f32; 2]) -> f64 {
    hypot((f_p[0] - f_q[0]) as f64, (f_p[1] - f_q[1]) as f64)
}

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

/// The weight of boundary pair `j` of `edge`: colour similarity exp(−‖ΔI‖ / colour_scale)
/// times the `contact_evidence` of the two pieces' planes and flow there, times
/// `occluded_weight` where either pixel failed the forward–backward check, times
/// `support_weight` where the pair is stacked and the lower pixel's piece is ground-like
/// ([`ground::has_ground_like_plane`]: the upper piece may stand on it).
pub fn pair_weight(
    soup: &Soup,
    inputs: &ScaleInputs,
    params: &ScaleParams,
    edge: &crate::superpixels::graph::BoundaryEdge,
    j: usize,
) -> f64 {
    let (p, q) = edge.pairs[j];
    let (p, q) = (p as usize, q as usize);
    let flow = inputs.flow.data();
    let reliable = inputs.reliable.data();
    let (pa, pb) = (&soup.pieces[edge.a as usize], &soup.pieces[edge.b as usize]);
    // Vertical pairs: the piece of the lower pixel may support the other.
    let width = inputs.superpixels.labels.width();
    let lower = if q == p + width {
        Some(pb)
    } else if p == q + width {
        Some(pa)
    } else {
        None
    };
    let standing = lower.is_some_and(ground::has_ground_like_plane);
    let mut w = exp(-(edge.colour_diff[j] as f64) / params.colour_scale)
        * contact_evidence(&pa.m, &pb.m, flow[p], flow[q], standing, params);
    if !(reliable[p] && reliable[q]) {
        w *= params.occluded_weight;
    }
    if standing {
        w *= params.support_weight;
    }
    w
}

/// How firmly each piece's depth is known, in [0, 1]: its [`scale_confidence`], or 0 where the
/// piece has no plane of its own ([`super::Piece::degenerate`]: too little trusted flow, no
/// parallax, or a plane behind a camera, so it carries a neighbour's plane). Such a depth is
/// the neighbour's surface extended over the piece, a guess however firmly the contacts then
/// pin its scale: at 1500 superpixels the pieces with borrowed planes that the contacts pin had
/// 1.7–14× the MRE of the pinned pieces with planes of their own on every case measured (static
/// room 0.056 against 0.006, motorcycle 0.10 against 0.024, FlyingThings3D 0.77 against 0.054).
pub fn depth_confidence(soup: &Soup, inputs: &ScaleInputs, params: &ScaleParams) -> Vec<f64> {
    let scale = scale_confidence(soup, inputs, params);
    (soup.pieces.iter().zip(scale))
        .map(|(piece, c)| if piece.degenerate.is_some() { 0.0 } else { c })
        .collect()
}

/// How strongly the contacts pin each piece's scale, in [0, 1]: the piece's rigid segment is
/// moved by ±25 % in scale as a whole, and the smaller rise of the contact energy across the
/// segment's rim is divided by σ per touching neighbour, the rise if every contact on the rim
/// were certain (weight 1) and broke (ground support weighs more, so a rim resting on the
/// ground reaches 1 sooner; values are clamped to [0, 1]). The rest prior counts as
/// [`ScaleParams::rest_weight`] more contacts of a mover that rests on the ground. So a segment
/// held only by weak evidence (contacts across colour edges, flow jumps or failed flow checks:
/// what an object in front of a wall looks like) scores low even where all of them break.
/// 0: nothing ties the segment to the rest (a mover touching nothing, or touching only through
/// contacts it can slide along), so its scale is a guess; 1: every contact is certain and breaks.
/// The largest segment fixes the global scale and gets 1. The soup's current λ are the scales
/// examined.
pub fn scale_confidence(soup: &Soup, inputs: &ScaleInputs, params: &ScaleParams) -> Vec<f64> {
    let n = soup.pieces.len();
    let problem = build_problem(soup, inputs, params);
    let s: Vec<f64> = soup.pieces.iter().map(|p| ln(p.lambda)).collect();
    let (segment, sizes) = rigid_segments(soup, inputs, &problem, &s, params, None);
    let largest = (0..sizes.len()).max_by_key(|&g| (sizes[g], std::cmp::Reverse(g)));
    let step = ln(1.25);
    // Per segment: energy of its rim at offsets −step, 0, +step, and the rim's full weight.
    let mut rise = vec![[0.0f64; 3]; sizes.len()];
    let mut full = vec![0.0f64; sizes.len()];
    for l in &problem.links {
        let (ga, gb) = (segment[l.a], segment[l.b]);
        if ga == gb {
            continue;
        }
        let delta = s[l.a] - s[l.b];
        // What the link could cost at most if every one of its contacts were certain
        // (weight 1 per pair): weak evidence pins a segment weakly.
        let weight = problem.sigma;
        for (j, d) in [-step, 0.0, step].into_iter().enumerate() {
            rise[ga][j] += l.value(delta + d, problem.sigma);
            rise[gb][j] += l.value(delta - d, problem.sigma);
        }
        full[ga] += weight;
        full[gb] += weight;
    }
    // A mover resting on the ground is held by the rest prior as by `rest_weight` contacts, per
    // resting piece.
    let sigma = problem.sigma;
    for (i, gaps) in resting_at_scales(soup, inputs, params).iter().enumerate() {
        let g = segment[i];
        if gaps.is_empty() || Some(g) == largest {
            continue;
        }
        let each = params.rest_weight / gaps.len() as f64;
        for (j, d) in [-step, 0.0, step].into_iter().enumerate() {
            rise[g][j] += gaps
                .iter()
                .map(|&c| each * (c + d).abs().min(sigma))
                .sum::<f64>();
        }
        full[g] += params.rest_weight * sigma;
    }
    let confidence: Vec<f64> = (0..sizes.len())
        .map(|g| {
            if Some(g) == largest {
                return 1.0;
            }
            let [lo, mid, hi] = rise[g];
            if full[g] <= 0.0 {
                0.0
            } else {
                ((lo.min(hi) - mid) / full[g]).clamp(0.0, 1.0)
            }
        })
        .collect();
    (0..n).map(|i| confidence[segment[i]]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    #[test]
    fn planes_at_an_angle_are_evidence_of_contact_only_where_one_stands_on_the_other() {
        let params = ScaleParams {
            flow_scale_px: 0.5,
            evidence_floor: 0.2,
            ..ScaleParams::default()
        };
        // Planes m = n / d: a wall facing the camera at depth 5, and a floor 2 below the camera
        // (y down).
        let (wall, floor) = (Vector3::new(0.0, 0.0, 0.2), Vector3::new(0.0, 0.5, 0.0));
        // A 3 px jump in the flow: continuity exp(−6) alone is below the floor.
        let (still, moving) = ([0.0f32, 0.0], [3.0f32, 0.0]);
        let standing = contact_evidence(&wall, &floor, still, moving, true, &params);
        assert!(
            (standing - 1.0).abs() < 1e-9,
            "feet on the floor: {standing}"
        );
        let beside = contact_evidence(&wall, &floor, still, moving, false, &params);
        assert_eq!(beside, params.evidence_floor);
        // Parallel planes get nothing from their angle, standing or not.
        let on_top = contact_evidence(&floor, &floor, still, moving, true, &params);
        assert_eq!(on_top, params.evidence_floor);
        // Continuous flow is evidence of contact wherever the pair lies.
        let together = contact_evidence(&wall, &floor, moving, moving, false, &params);
        assert!((together - 1.0).abs() < 1e-9);
        // Unknown flow is no evidence; a piece without a plane has no angle.
        let unknown = [f32::NAN, f32::NAN];
        let blind = contact_evidence(&wall, &floor, still, unknown, false, &params);
        assert_eq!(blind, params.evidence_floor);
        let flat = contact_evidence(&Vector3::zeros(), &floor, unknown, unknown, true, &params);
        assert_eq!(flat, params.evidence_floor);
    }

    #[test]
    fn a_slanted_boundary_samples_both_kinds_of_pair_in_proportion() {
        // A 45° staircase in scan order on a 100-pixel-wide image: per row a side-by-side pair
        // (p, p + 1), then a stacked pair (p, p + 100), as `boundary_graph` lists them.
        let width = 100;
        let stair = |rows: usize| -> Vec<(u32, u32)> {
            (0..rows)
                .flat_map(|y| {
                    let p = (y * width + 10 + y) as u32;
                    [(p, p + 1), (p + 1, p + 1 + width as u32)]
                })
                .collect()
        };
        let stacked = |pairs: &[(u32, u32)], picked: &[usize]| {
            picked
                .iter()
                .filter(|&&j| pairs[j].1 == pairs[j].0 + width as u32)
                .count()
        };
        for (rows, per_boundary) in [(12, 12), (12, 10), (15, 12), (20, 12), (9, 4), (40, 14)] {
            let pairs = stair(rows);
            let len = pairs.len();
            let picked = sample_indices(&pairs, width, per_boundary);
            // As many as a stride of ⌈len / per_boundary⌉ gives, ascending, distinct, in range.
            assert_eq!(picked.len(), len.div_ceil(len.div_ceil(per_boundary)));
            assert!(picked.windows(2).all(|w| w[0] < w[1]) && picked[picked.len() - 1] < len);
            // Half of them stacked (a plain even stride took none).
            let half = picked.len() as f64 / 2.0;
            let n = stacked(&pairs, &picked) as f64;
            assert!(
                (n - half).abs() <= 0.5,
                "{rows} rows, {per_boundary}: {n} of {picked:?}"
            );
        }
        // A short boundary keeps every pair; one of a single kind is spread evenly over it.
        let short = stair(5);
        assert_eq!(
            sample_indices(&short, width, 12),
            (0..10).collect::<Vec<_>>()
        );
        let row: Vec<(u32, u32)> = (0..30u32).map(|x| (x, x + width as u32)).collect();
        assert_eq!(
            sample_indices(&row, width, 12),
            vec![1, 4, 7, 10, 13, 16, 19, 22, 25, 28]
        );
    }

    #[test]
    fn contact_sums_are_minimised_exactly() {
        // Against a fine grid and the plain reference, on random sums of truncated absolute
        // values with and without one-sided steps.
        let mut rng = Rng::new(5);
        for round in 0..100 {
            let terms: Vec<(f64, f64)> = (0..7)
                .map(|_| (rng.uniform() + 0.1, 2.0 * rng.uniform() - 1.0))
                .collect();
            let steps: Vec<Step> = (0..if round % 2 == 0 { 0 } else { 3 })
                .map(|_| Step {
                    k: rng.uniform() * 0.3,
                    c: 2.0 * rng.uniform() - 1.0,
                    dir: if rng.uniform() < 0.5 { 1.0 } else { -1.0 },
                })
                .collect();
            let sigma = 0.05 + 0.3 * rng.uniform();
            let total = |x: f64| truncated(&terms, x, sigma) + steps_at(&steps, x, sigma);
            let x = minimise_contacts(&terms, &steps, sigma, 0.3, -2.0, 2.0);
            let grid = (0..=40_000)
                .map(|j| total(-2.0 + j as f64 * 1e-4))
                .fold(f64::INFINITY, f64::min);
            assert!(total(x) <= grid + 1e-12, "round {round}");
            assert!((-2.0..=2.0).contains(&x));
            let plain = minimise_contacts_plain(&terms, &steps, sigma, 0.3, -2.0, 2.0);
            assert!(
                (total(x) - total(plain)).abs() < 1e-9,
                "sweep {x} vs plain {plain}"
            );
        }
    }

    #[test]
    fn a_minimum_on_a_step_edge_is_found() {
        // One term pulls x past a heavy step's edge, so the minimum sits exactly on the edge.
        // With random offsets, dir · (edge + c) often rounds to just above σ: the step must
        // still count as free there (it did not once, and the minimiser then gave up the edge).
        let mut rng = Rng::new(11);
        let mut rounded_past_edge = 0;
        for round in 0..2000 {
            let sigma = 0.05 + 0.3 * rng.uniform();
            let dir = if round % 2 == 0 { 1.0 } else { -1.0 };
            let step = Step {
                k: 10.0,
                c: 2.0 * rng.uniform() - 1.0,
                dir,
            };
            let edge = step.edge(sigma);
            if dir * (edge + step.c) > sigma {
                rounded_past_edge += 1;
            }
            // The term's own minimum lies 0.5σ beyond the edge, on the step's costly side.
            let terms = [(1.0, -(edge + dir * 0.5 * sigma))];
            let total = |x: f64| truncated(&terms, x, sigma) + steps_at(&[step], x, sigma);
            let best = total(edge);
            assert!(best < 0.5 * sigma + 1e-9, "round {round}: the edge is free");
            for minimise in [minimise_contacts, minimise_contacts_plain] {
                let x = minimise(&terms, &[step], sigma, 0.0, -3.0, 3.0);
                assert!(
                    total(x) <= best + 1e-12,
                    "round {round}: {x} vs edge {edge}"
                );
            }
        }
        assert!(rounded_past_edge > 0, "the rounding case is exercised");
    }

    /// A link between pieces a and b with one gap c (frame 1, weight w) whose trusted flow
    /// jumps by 2 px: a boundary where one side may occlude the other.
    fn link(a: usize, b: usize, w: f64, c: f64) -> Link {
        Link {
            a,
            b,
            terms: vec![(w, c)],
            frame1: vec![(w, c)],
            median_c1: c,
            flow_jump: 2.0,
            trusted_share: 1.0,
            upper: None,
        }
    }

    /// Segments with the given piece-to-segment map, centres and ego-motion flags (a segment on
    /// the ego-motion counts as measured static world).
    fn segments_of(segment: &[usize], centre: &[f64], ego: &[bool]) -> Segments {
        let mut sizes = vec![0; centre.len()];
        segment.iter().for_each(|&g| sizes[g] += 1);
        let world = static_world(&sizes, ego);
        Segments {
            segment: segment.to_vec(),
            sizes,
            centre: centre.to_vec(),
            ego: ego.to_vec(),
            measured: ego.to_vec(),
            world,
            grounded: vec![false; centre.len()],
            attached: vec![false; centre.len()],
            below: vec![None; segment.len()],
            resting: vec![Vec::new(); segment.len()],
            floor: false,
            ground: false,
        }
    }

    /// A two-segment soup solved with `params`: the static world's segment (on the ego-motion)
    /// and a mover's, by the piece-to-segment map `segment`; `roles` = (a piece of the mover, a
    /// piece of the world, the mover's segment centre, the world's). `setup` gives the
    /// segments the prior's inputs. Returns the mover's log-scale over the world's.
    fn mover_over_world(
        problem: &Problem,
        segment: &[usize],
        roles: (usize, usize, f64, f64),
        params: &ScaleParams,
        setup: impl Fn(&mut Segments),
    ) -> f64 {
        let (mover, world, mover_centre, world_centre) = roles;
        let (g_mover, g_world) = (segment[mover], segment[world]);
        let mut centre = [0.0; 2];
        centre[g_mover] = mover_centre;
        centre[g_world] = world_centre;
        let mut ego = [false; 2];
        ego[g_world] = true;
        let mut segments = segments_of(segment, &centre, &ego);
        setup(&mut segments);
        let u = solve_segments(problem, &segments, params, None).0;
        (centre[g_mover] + u[g_mover]) - (centre[g_world] + u[g_world])
    }

    /// World pieces 0–1–2 in a chain of certain contacts that meet at equal scale, and piece 3
    /// touching them only through `contact` (a link of piece 3 and piece 0).
    fn world_and_one_piece(contact: Link) -> Problem {
        Problem {
            links: vec![link(0, 1, 1.0, 0.0), link(1, 2, 1.0, 0.0), contact],
            touching: vec![vec![0, 2], vec![0, 1], vec![1], vec![2]],
            sigma: 0.1,
        }
    }

    /// Segment 0 (the world, pieces 0–2, on the ego-motion) and a one-piece mover (piece 3, on
    /// a motion of its own). The mover's contact with world piece 0 would hold it 1
    /// (log-scale) behind, its contact with piece 1 (`mover_to_1`, weight 0.45, gap c = 0.3)
    /// 0.3 in front; the first weighs a little more, so contact alone parks the mover behind.
    /// δ = s_a − s_b with a the mover: gap = δ + c = 0 at δ = −c. Returns the mover's offset.
    fn place_loose_mover(mover_to_1: Link, behind_weight: f64) -> f64 {
        let problem = Problem {
            links: vec![
                link(0, 1, 1.0, 0.0),
                link(1, 2, 1.0, 0.0),
                link(3, 0, 0.5, -1.0),
                mover_to_1,
            ],
            touching: vec![vec![0, 2], vec![0, 1, 3], vec![1], vec![2, 3]],
            sigma: 0.1,
        };
        let segments = segments_of(&[0, 0, 0, 1], &[0.0, 0.0], &[true, false]);
        let params = ScaleParams {
            behind_weight,
            ..ScaleParams::default()
        };
        solve_segments(&problem, &segments, &params, None).0[1]
    }

    #[test]
    fn a_given_start_is_solved_within_the_band_like_the_solve_itself() {
        // The truth test's start can put a one-piece segment far from the rest (its contact
        // would hold it at δ = 5, past the band of ln 12); the solve from there must stay in
        // the band the solve's own starts keep to, or the two objectives are not comparable.
        let problem = world_and_one_piece(link(3, 0, 0.5, -5.0));
        let segments = segments_of(&[0, 0, 0, 1], &[0.0, 0.0], &[true, false]);
        // Without the figure prior, which would pull the segment in front by itself.
        let params = ScaleParams {
            behind_weight: 0.0,
            ..ScaleParams::default()
        };
        let band = params.band.ln();
        let u = solve_segments(&problem, &segments, &params, Some(vec![0.0, 6.0])).0;
        assert!((u[1] - u[0]).abs() <= band + 1e-9, "{u:?} beyond ±{band}");
    }

    #[test]
    fn tail_control_moves_a_stray_piece_only_across_continuous_trusted_flow() {
        // Piece 1 lies 2 (log-scale) off both its neighbours 0 and 2, whose planes meet it at
        // equal scale (and meet pieces 3 and 4 where they are); its boundaries show no flow
        // edge. Where that flow passes the forward–backward check, nothing justifies the depth
        // edge and the piece joins its neighbours; where it fails, the flow is no evidence and
        // the piece stays.
        let stray = |trusted_share: f64| {
            let quiet = |a, b| Link {
                flow_jump: 0.2,
                trusted_share,
                ..link(a, b, 1.0, 0.0)
            };
            let problem = Problem {
                links: vec![quiet(0, 1), quiet(1, 2), quiet(0, 3), quiet(2, 4)],
                touching: vec![vec![0, 2], vec![0, 1], vec![1, 3], vec![2], vec![3]],
                sigma: 0.1,
            };
            let mut s = vec![0.0, 2.0, 0.0, 0.0, 0.0];
            let moved = tail_control(&problem, &mut s, &ScaleParams::default());
            (moved, s[1])
        };
        let (moved, s1) = stray(1.0);
        assert_eq!(moved, 1);
        assert!(s1.abs() < 1e-9, "{s1}");
        assert_eq!(stray(0.2), (0, 2.0));
    }

    #[test]
    fn the_figure_prior_keeps_a_loose_mover_in_front() {
        // With the figure prior, lying behind piece 1 costs more and the mover stays in front.
        let solve = |behind_weight| place_loose_mover(link(3, 1, 0.45, 0.3), behind_weight);
        assert!((solve(0.0) - 1.0).abs() < 1e-9, "{}", solve(0.0));
        assert!((solve(1.0) + 0.3).abs() < 1e-9, "{}", solve(1.0));
    }

    #[test]
    fn the_figure_prior_does_not_act_across_a_mover_s_bottom_edge_over_a_floor() {
        // The loose mover (piece 3) stands over world piece 1: its pixels lie directly above
        // piece 1's, where the floor runs towards the camera in front of it. With a floor in
        // view nothing there says the mover should be in front, and contacts park it 1 behind
        // as without the prior. Without a floor in view, where the world piece lies above the
        // mover (it hangs below the world: a hole is what would show it), or where the world
        // piece is above the horizon (no floor there), the prior holds the mover in front.
        let placement = |mover_first: bool, upper: Option<usize>, floor: bool, horizon: bool| {
            let (a, b, c) = if mover_first {
                (3, 1, 0.3)
            } else {
                (1, 3, -0.3)
            };
            let problem = Problem {
                links: vec![
                    link(0, 1, 1.0, 0.0),
                    link(1, 2, 1.0, 0.0),
                    link(3, 0, 0.5, -1.0),
                    Link {
                        upper,
                        ..link(a, b, 0.45, c)
                    },
                ],
                touching: vec![vec![0, 2], vec![0, 1, 3], vec![1], vec![2, 3]],
                sigma: 0.1,
            };
            let mut segments = segments_of(&[0, 0, 0, 1], &[0.0, 0.0], &[true, false]);
            segments.floor = floor;
            // Piece 1's rays meet the ground unless it lies above the horizon.
            segments.below[1] = (!horizon).then_some(-0.5);
            let params = ScaleParams {
                behind_weight: 1.0,
                ..ScaleParams::default()
            };
            solve_segments(&problem, &segments, &params, None).0[1]
        };
        for mover_first in [true, false] {
            let standing = placement(mover_first, Some(3), true, false);
            assert!((standing - 1.0).abs() < 1e-9, "{mover_first}: {standing}");
            for (upper, floor, horizon) in [
                (Some(3), false, false),
                (Some(1), true, false),
                (None, true, false),
                (Some(3), true, true),
            ] {
                let held = placement(mover_first, upper, floor, horizon);
                assert!(
                    (held + 0.3).abs() < 1e-9,
                    "{mover_first} {upper:?} {floor} {horizon}: {held}"
                );
            }
        }
    }

    #[test]
    fn the_upper_piece_of_a_boundary_is_the_one_above_on_enough_pairs() {
        // An image 10 pixels wide: pairs (p, q) with q one row below p put a above b.
        let width = 10;
        let edge = |pairs: Vec<(u32, u32)>| BoundaryEdge {
            a: 4,
            b: 7,
            colour_diff: vec![0.0; pairs.len()],
            pairs,
        };
        let below = |p: u32| (p, p + width as u32);
        let beside = |p: u32| (p, p + 1);
        let above = |p: u32| (p + width as u32, p);
        let a_on_b = edge(vec![below(21), below(22), below(23), beside(24), above(5)]);
        assert_eq!(upper_piece(&a_on_b, width), Some(4));
        let b_on_a = edge(vec![above(21), above(22), above(23), above(24), below(5)]);
        assert_eq!(upper_piece(&b_on_a, width), Some(7));
        // Too few pairs one above the other, or as many each way: no upper piece.
        assert_eq!(
            upper_piece(&edge(vec![below(21), below(22), beside(23)]), width),
            None
        );
        let even = edge(vec![
            below(21),
            below(22),
            below(23),
            above(31),
            above(32),
            above(33),
        ]);
        assert_eq!(upper_piece(&even, width), None);
    }

    #[test]
    fn the_figure_prior_does_not_act_across_continuous_trusted_flow() {
        // The loose mover with the flow across its boundary with piece 1 continuous: nothing
        // is occluded there, so the figure prior does not keep the mover from lying behind
        // piece 1 and contacts park it 1 behind, as without the prior. Where most of that
        // boundary's flow fails the check, its continuity is no evidence and the prior holds
        // the mover in front again.
        let placement = |jump: f64, trusted_share: f64| {
            let mover_to_1 = Link {
                flow_jump: jump,
                trusted_share,
                ..link(3, 1, 0.45, 0.3)
            };
            place_loose_mover(mover_to_1, 1.0)
        };
        let continuous = placement(0.2, 0.9);
        assert!((continuous - 1.0).abs() < 1e-9, "{continuous}");
        let untrusted = placement(0.2, 0.3);
        assert!((untrusted + 0.3).abs() < 1e-9, "{untrusted}");
        let jumping = placement(1.5, 0.9);
        assert!((jumping + 0.3).abs() < 1e-9, "{jumping}");
    }

    #[test]
    fn the_ground_prior_lifts_a_sunk_segment_onto_the_ground_from_either_side() {
        // A mover (one piece) touches the world (three pieces) twice: it meets the far
        // background at δ = s_mover − s_world = 1 (weight 0.5) and the road at δ = 0 (0.3).
        // Contacts alone glue it to the background; there its median pixel lies δ − 0.5 under
        // the road, more than σ, and the ground prior (one broken contact) lifts it onto the
        // road. The mover is the first segment or the second, with non-zero centres.
        for mover in [0usize, 3] {
            let world: Vec<usize> = (0..4).filter(|&i| i != mover).collect();
            // Seen from the mover (a = mover): gap = δ + c.
            let problem = Problem {
                links: vec![
                    link(world[0], world[1], 1.0, 0.0),
                    link(world[1], world[2], 1.0, 0.0),
                    link(mover, world[0], 0.5, -1.0),
                    link(mover, world[1], 0.3, 0.0),
                ],
                touching: (0..4)
                    .map(|i| match i {
                        i if i == mover => vec![2, 3],
                        i if i == world[0] => vec![0, 2],
                        i if i == world[1] => vec![0, 1, 3],
                        _ => vec![1],
                    })
                    .collect(),
                sigma: 0.1,
            };
            let segment: Vec<usize> = (0..4)
                .map(|i| usize::from((i == mover) == (mover == 3)))
                .collect();
            let placement = |ground_weight: f64| {
                let params = ScaleParams {
                    behind_weight: 0.0,
                    ground_weight,
                    ..ScaleParams::default()
                };
                let roles = (mover, world[0], -0.2, 0.7);
                mover_over_world(&problem, &segment, roles, &params, |segments| {
                    segments.below[mover] = Some(-0.5);
                })
            };
            let glued = placement(0.0);
            assert!((glued - 1.0).abs() < 1e-9, "mover {mover}: {glued}");
            let lifted = placement(1.0);
            assert!(lifted.abs() < 1e-9, "mover {mover}: {lifted}");
        }
    }

    #[test]
    fn the_rest_prior_stands_a_mover_on_the_ground_from_either_side() {
        // World pieces 0–2 and a one-piece mover (piece 3) whose only contact, of weight 0.5,
        // glues it to world piece 0 at δ = s_mover − s_world = 1. Its five resting pixels say
        // its bottom lies 0.4 in front of the ground at equal scale, so it stands on the ground
        // at δ = 0.4, where the rest prior (1.5 contacts) puts it. The mover's segment is the
        // first or the second, at non-zero centres.
        let problem = world_and_one_piece(link(3, 0, 0.5, -1.0));
        for segment in [[0, 0, 0, 1], [1, 1, 1, 0]] {
            let placement = |rest_weight: f64| {
                let params = ScaleParams {
                    behind_weight: 0.0,
                    rest_weight,
                    ..ScaleParams::default()
                };
                mover_over_world(&problem, &segment, (3, 0, 0.3, -0.6), &params, |segments| {
                    segments.resting[3] = vec![-0.4; 5];
                })
            };
            let glued = placement(0.0);
            assert!((glued - 1.0).abs() < 1e-9, "{segment:?}: {glued}");
            let standing = placement(1.5);
            assert!((standing - 0.4).abs() < 1e-9, "{segment:?}: {standing}");
            // Weaker than the contact, the prior gives way.
            let weak = placement(0.3);
            assert!((weak - 1.0).abs() < 1e-9, "{segment:?}: {weak}");
        }
    }

    #[test]
    fn the_figure_prior_holds_from_either_side_and_at_any_centre() {
        // The configuration above with the mover as piece 0 and segment 0 (the figure is the
        // first of the pair, g, not h) and non-zero segment centres: the result, in log-scale
        // s = centre + u, must be the same relative placement.
        // Pieces: 0 the mover; 1, 2, 3 the world. δ = s_mover − s_world as before.
        let problem = Problem {
            links: vec![
                link(1, 2, 1.0, 0.0),
                link(2, 3, 1.0, 0.0),
                link(0, 1, 0.5, -1.0),
                link(0, 2, 0.45, 0.3),
            ],
            touching: vec![vec![1, 2], vec![0, 2], vec![0, 1, 3], vec![2]],
            sigma: 0.1,
        };
        let centre = [-0.2, 0.7];
        let placement = |behind_weight, mover_on_ego| {
            let params = ScaleParams {
                behind_weight,
                ..ScaleParams::default()
            };
            let segments = segments_of(&[0, 1, 1, 1], &centre, &[mover_on_ego, true]);
            let u = solve_segments(&problem, &segments, &params, None).0;
            (centre[0] + u[0]) - (centre[1] + u[1])
        };
        assert!((placement(0.0, false) - 1.0).abs() < 1e-9);
        assert!((placement(1.0, false) + 0.3).abs() < 1e-9);
        // On the ego-motion the small segment is a part of the static world, which may lie
        // behind anything: its contacts alone place it (the static prior ties it to the larger
        // segment, but that one is the world and the pull is 0.05 against contacts of 0.95).
        let v = placement(1.0, true);
        assert!((v - 1.0).abs() < 1e-9, "{v}");
    }

    #[test]
    fn the_static_prior_ties_a_part_of_the_world_to_the_world() {
        // World pieces 0, 1, 2 (segment 0) and piece 3 (segment 1), whose one contact, with
        // piece 0, holds it 1 (log-scale) behind at weight 0.02: less than the static prior's
        // 0.05 for one piece. On the ego-motion it takes the world's scale; on a motion of its
        // own, or without the prior, its contact places it.
        let problem = world_and_one_piece(link(3, 0, 0.02, -1.0));
        let centre = [0.3, -0.4];
        let placement = |static_weight, on_ego| {
            let params = ScaleParams {
                static_weight,
                ..ScaleParams::default()
            };
            let segments = segments_of(&[0, 0, 0, 1], &centre, &[true, on_ego]);
            let u = solve_segments(&problem, &segments, &params, None).0;
            (centre[1] + u[1]) - (centre[0] + u[0])
        };
        let tied = placement(0.05, true);
        assert!(tied.abs() < 1e-9, "{tied}");
        for (weight, on_ego) in [(0.0, true), (0.05, false), (0.01, true)] {
            let v = placement(weight, on_ego);
            assert!((v - 1.0).abs() < 1e-9, "{weight} {on_ego}: {v}");
        }
    }

    #[test]
    fn the_static_prior_on_a_large_segment_pulls_no_more_than_static_max_contacts() {
        // The world (segment 0, 200 pieces) and a segment of 100 pieces on the ego-motion
        // (segment 1) whose one contact, between pieces 200 and 0, holds it 1 (log-scale)
        // behind with the weight of two contacts. At 0.05 per piece its static prior would
        // pull like 5 contacts and tie it to the world; at most 1.5 (the default), its contact
        // places it. Below the cap the prior pulls per piece (10 pieces: 0.5, overruled too);
        // a segment of floor (`grounded`), or one that meets the world at equal scale
        // (`attached`), is held with the full weight.
        let place = |pieces: usize, params: &ScaleParams, held: bool| {
            let mut touching = vec![Vec::new(); 200 + pieces];
            touching[0].push(0);
            touching[200].push(0);
            let problem = Problem {
                links: vec![link(200, 0, 2.0, -1.0)],
                touching,
                sigma: 0.1,
            };
            let segment: Vec<usize> = (0..200 + pieces).map(|i| usize::from(i >= 200)).collect();
            let mut segments = segments_of(&segment, &[0.0, 0.0], &[true, true]);
            segments.grounded[1] = held;
            let floor = solve_segments(&problem, &segments, params, None).0;
            segments.grounded[1] = false;
            segments.attached[1] = held;
            let attached = solve_segments(&problem, &segments, params, None).0;
            assert_eq!(floor, attached);
            attached[1] - attached[0]
        };
        let defaults = ScaleParams::default();
        for pieces in [10, 100] {
            let v = place(pieces, &defaults, false);
            assert!((v - 1.0).abs() < 1e-9, "{pieces} pieces: {v}");
        }
        let uncapped = ScaleParams {
            static_max: f64::INFINITY,
            ..defaults
        };
        let tied = place(100, &uncapped, false);
        assert!(tied.abs() < 1e-9, "{tied}");
        // The floor, and a fragment attached to the world, are not capped.
        let held = place(100, &defaults, true);
        assert!(held.abs() < 1e-9, "{held}");
    }

    #[test]
    fn a_fragment_of_the_world_is_attached_where_it_meets_the_world_at_equal_scale() {
        // Segments (one piece each): 0 the world; 1 meets it within world_gap (0.15);
        // 2 meets only 1 (0.18): attached through it; 3 meets the world 0.7 off (a mover the
        // ego-motion explains at half its depth); 4 meets it exactly but is not on the
        // ego-motion; 5 meets only 3.
        let links = vec![
            link(1, 0, 1.0, 0.15),
            link(2, 1, 1.0, -0.18),
            link(3, 0, 1.0, 0.7),
            link(4, 0, 1.0, 0.0),
            link(5, 3, 1.0, 0.0),
        ];
        let problem = Problem {
            links,
            touching: vec![Vec::new(); 6],
            sigma: 0.1,
        };
        let segment: Vec<usize> = (0..6).collect();
        let ego = [true, true, true, true, false, true];
        let gap = ScaleParams::default().world_gap;
        let attached = attached_to_world(&problem, &segment, &ego, Some(0), gap);
        assert_eq!(attached, [true, true, true, false, false, false]);
        assert_eq!(
            attached_to_world(&problem, &segment, &ego, None, gap),
            [false; 6]
        );
    }

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

    #[test]
    fn the_discrete_start_moves_segments_together() {
        // Segments 1 and 2 are tied to each other (equal scales) and each, more weakly, to
        // segment 0 at a log-scale 1 below it. Moving either alone breaks the strong tie, so
        // coordinate descent from equal scales stays there; the joint labelling moves both.
        // (The figure prior is off, so the links' flow does not matter.)
        let links = vec![
            link(0, 1, 0.6, -1.0),
            link(0, 2, 0.6, -1.0),
            link(1, 2, 1.0, 0.0),
        ];
        let problem = Problem {
            touching: vec![vec![0, 1], vec![0, 2], vec![1, 2]],
            links,
            sigma: 0.1,
        };
        let stuck = [0.0; 3];
        let params = ScaleParams {
            behind_weight: 0.0,
            ..ScaleParams::default()
        };
        let segments = segments_of(&[0, 1, 2], &[0.0; 3], &[false; 3]);
        let pairs = segment_pair_terms(&problem, &segments, &params);
        let u = discrete_start(&pairs, 0.1, 3, Some(0), 12f64.ln(), 0.1);
        assert!(u[0].abs() < 1e-12 && (u[1] + 1.0).abs() < 1e-9 && (u[2] + 1.0).abs() < 1e-9);
        assert!(problem.energy(&u) < 1e-9);
        // Each single move from equal scales raises the energy: the start coordinate descent
        // could not leave.
        for g in 1..3 {
            let terms = problem.local_terms(g, &stuck);
            let x = minimise_contacts(&terms, &[], 0.1, 0.0, -2.0, 2.0);
            assert_eq!(x, 0.0);
        }
        assert!(problem.energy(&stuck) > 0.1);
    }
}
