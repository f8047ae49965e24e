//! The public reconstruction API: two frames in, depth and point clouds of both frames out,
//! one plain function per stage (flow → superpixels and graphs → unit-scale soup → scales →
//! refinement → outputs, then the fusion with members from nearby superpixel counts). The CLI
//! and the web page both call [`reconstruct`].

use serde::Serialize;

use crate::camera::{Camera, Intrinsics, IntrinsicsSource};
use crate::error::{Error, Result};
use crate::flow::{
    FlowField, FlowPair, FlowParams, Preset, compute_flow, is_known, resize_flow, trusted_share,
};
use crate::focal;
use crate::grid::Grid;
use crate::image::Frame;
use crate::input::{FramePair, working_over_input};
use crate::output::{PointCloud, dense_depth, depth_at, point_clouds, scene_flow, strided_depth};
use crate::soup::Soup;
use crate::soup::ensemble::{
    EnsembleParams, EnsembleReport, MAX_MEMBERS, SAMPLE_STRIDE, Vote, fuse_scales,
};
use crate::soup::init::{EgoRival, InitParams, unit_scale_soup};
use crate::soup::refine::{self, RefineParams, RefineReport};
use crate::soup::scales::{ScaleInputs, ScaleParams, ScaleReport, depth_confidence, solve_scales};
use crate::superpixels::graph::{BoundaryGraph, KnnGraph, boundary_graph, knn_graph};
use crate::superpixels::{SlicParams, Superpixels, slic};

/// The pipeline's stages, in order, as reported to the progress callback.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Stage {
    Flow,
    Superpixels,
    Motion,
    Scales,
    Refine,
    Outputs,
    Ensemble,
}

impl Stage {
    /// Every stage, in the order the pipeline runs them.
    pub const ALL: [Stage; 7] = [
        Stage::Flow,
        Stage::Superpixels,
        Stage::Motion,
        Stage::Scales,
        Stage::Refine,
        Stage::Outputs,
        Stage::Ensemble,
    ];

    /// Name shown to users.
    pub fn name(self) -> &'static str {
        match self {
            Stage::Flow => "flow",
            Stage::Superpixels => "superpixels",
            Stage::Motion => "motion",
            Stage::Scales => "scales",
            Stage::Refine => "refine",
            Stage::Outputs => "outputs",
            Stage::Ensemble => "ensemble",
        }
    }
}

/// Every tunable of the pipeline with its default (each documented on its own type). Fields
/// missing from a deserialised value keep their defaults (parameters saved by an older version;
/// also inside `init`, `scales` and `ensemble`; elsewhere a nested object given in part does not
/// deserialise).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, serde::Deserialize)]
#[serde(default)]
pub struct Params {
    pub superpixels: SlicParams,
    /// Neighbours in the K-NN graph (local motion hypotheses are fitted on a superpixel and these).
    pub k: usize,
    pub init: InitParams,
    pub scales: ScaleParams,
    pub refine: RefineParams,
    /// Reconstructions from other superpixel counts fused into the kept one
    /// ([`crate::soup::ensemble`]).
    pub ensemble: EnsembleParams,
    /// A share in [0, 1]: when less than this share of the pixels passes the forward–backward
    /// check, the flow is computed again with the next finer preset (fast → medium → high; fine →
    /// high) and the pass with the most trusted pixels is kept; 0 never computes it again, 1
    /// always goes on to `high`. The default preset is `high`, which has no finer one, so this
    /// acts when a coarser preset is chosen. 0.75: on every case measured but one, 83–94 %
    /// passes with `medium`; on FlyingThings3D (motions of 65–85 px) 65 % does, and its depth
    /// error with `medium` swings between 0.58 and 1.44 with the superpixel count (1200–1700)
    /// against 0.52–0.72 with `high`. Given flow is never recomputed.
    pub min_reliable_flow: f64,
    /// A share in [0, 1]: when the depths of less than this share of the pixels are pinned
    /// (their superpixel's confidence, `depth_confidence`, at least `scales.min_confidence`:
    /// contacts pin its scale and its plane is its own) and the flow
    /// was computed with a preset that has a finer one, the reconstruction is made again from
    /// the finer preset's flow and the pass that pins more is kept; 0 never does. Flow too
    /// coarse to show where movers meet the world leaves their scales to guesses, which may
    /// be worse than a constant depth: when 0.7 was chosen, with preset `medium` the crowd
    /// pinned 38–43 % at four of five superpixel counts (1300–1700; MRE up to 1.28 against
    /// 0.27 for constant depth) and 55–78 % with `high` (0.14–0.19), while every other case
    /// pinned 74–100 % with `medium`; 0.7 lay below every other case, and above the crowd's
    /// 61 % when `scales.min_confidence` is 20 % lower (at 0.6 that brought the 1.28 back).
    /// Since then the contact terms pin more: with `medium` at 1500 superpixels (one
    /// reconstruction, the page's refinement) the nine cases pin 70–96 % (the table 70 %,
    /// FlyingThings3D 71 % from `high`'s flow, the crowd 79 %), and the crowd is made again
    /// for its ambiguous camera motion instead. The share is that of each pass before fusion
    /// (which runs once, on the kept pass), counting borrowed planes as unpinned.
    pub min_pinned_share: f64,
    /// Whether a reconstruction whose scale solve finds no ground plane is made again from the
    /// next finer preset's flow (and a finer pass that finds one is kept); inert with
    /// `scales.ground_weight` 0, where no ground is looked for. At quarter
    /// resolution a textured floor's pieces have roughly right depths but wrong slopes: on the
    /// crowd with preset fast at 1400 superpixels 24 of 423 well-measured pieces had a
    /// ground-like plane, no ground was found, and the walkers, with no floor to stand on, went
    /// 2.5× too far (0.303 with the page's settings, worse than a constant depth's 0.269; made
    /// again from preset medium's flow 0.082). With the page's settings and preset fast over
    /// 1300–1700 superpixels no other case changed.
    pub finer_without_ground: bool,
}

impl Default for Params {
    fn default() -> Self {
        Params {
            superpixels: SlicParams::default(),
            k: 15,
            min_reliable_flow: 0.75,
            min_pinned_share: 0.7,
            finer_without_ground: true,
            init: InitParams::default(),
            scales: ScaleParams::default(),
            refine: RefineParams::default(),
            ensemble: EnsembleParams::default(),
        }
    }
}

impl Params {
    /// These parameters with the fusion members' cheaper refinement (`ensemble.member_iterations`
    /// iterations of `ensemble.member_particles` particles), as each member and the page's kept
    /// pass run it.
    pub fn with_member_refinement(mut self) -> Params {
        self.refine.iterations = self.ensemble.member_iterations;
        self.refine.particles = self.ensemble.member_particles;
        self
    }

    /// Fails with [`Error::InvalidParameter`] for the settings [`reconstruct_unfused`] checks
    /// before it starts: the shares, the fusion's members and steps, the expansion factors
    /// (each stage checks its own parameters as it runs).
    pub fn validate(&self) -> Result<()> {
        for (name, share) in [
            ("min_reliable_flow", self.min_reliable_flow),
            ("min_pinned_share", self.min_pinned_share),
            ("ensemble.guess_weight", self.ensemble.guess_weight),
        ] {
            if !(0.0..=1.0).contains(&share) {
                return Err(Error::InvalidParameter(format!(
                    "{name} {share} must be a share in [0, 1]"
                )));
            }
        }
        let ensemble = &self.ensemble;
        if ensemble.members > MAX_MEMBERS
            || (ensemble.members > 1
                && !(ensemble.count_step > 0.0
                    && ensemble.count_step * (ensemble.members / 2) as f64 <= 0.5))
        {
            return Err(Error::InvalidParameter(format!(
                "ensemble: {} members with count_step {}: at most {MAX_MEMBERS} members, and with more \
             than one a step above 0 that keeps their superpixel counts within half and one and \
             a half times the count (step × (members / 2) ≤ 0.5)",
                ensemble.members, ensemble.count_step
            )));
        }
        let factors = self.refine.expansion_factors;
        if !factors.iter().all(|f| *f > 0.0 && *f < 1.0) {
            return Err(Error::InvalidParameter(format!(
                "refine.expansion_factors {factors:?}: each must lie strictly between 0 and 1 (it is \
             tried as a shrink f and a growth 1/f)"
            )));
        }
        Ok(())
    }
}

/// Where the flow 1→2 comes from. Every source yields the same two things for the later
/// stages: a flow field at the working resolution and a mask of the vectors to trust.
#[derive(Clone, Debug)]
pub enum FlowInput {
    /// A given field (a `.flo` file or ground truth) at any resolution; it is resampled to the
    /// working resolution and its known vectors are trusted.
    Given(FlowField),
    /// Computed from the two frames by [`compute_flow`] (DIS with variational refinement, both
    /// ways); vectors failing the forward–backward check are not trusted.
    Compute(FlowParams),
}

/// Where the two directions of a computed flow come from (frame 1 → 2 and frame 2 → 1, at the
/// working size, as [`crate::flow::compute_direction`] gives them): `None` leaves them to the
/// pipeline, which computes them ([`flow_both_ways`]). Natively nothing else gives them
/// ([`ComputedHere`]); the page's worker gives them from its workers, asynchronously: one
/// direction computed in a helper worker while the worker computes the other, or directions it
/// holds already (`src/web/reconstruct.rs`). The pipeline joins them with the forward–backward
/// check ([`crate::flow::pair_from_directions`]), so the flow is the same bits either way.
pub(crate) trait Directions {
    /// The two directions of the flow with `params` between the frames, or `None`. Where they
    /// are computed for the asking, their progress is `span`'s.
    fn directions(
        &mut self,
        params: &FlowParams,
        span: ProgressSpan,
    ) -> impl Future<Output = Result<Option<(FlowField, FlowField)>>>;
}

/// The [`Directions`] that gives none: the pipeline computes every flow itself.
pub(crate) struct ComputedHere;

impl Directions for ComputedHere {
    async fn directions(
        &mut self,
        _params: &FlowParams,
        _span: ProgressSpan,
    ) -> Result<Option<(FlowField, FlowField)>> {
        Ok(None)
    }
}

/// Where a flow's progress goes: `stage`'s fraction goes from `from` to `from + span` as the
/// flow's own share done goes from 0 to 1.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ProgressSpan {
    pub stage: Stage,
    pub from: f32,
    pub span: f32,
}

impl ProgressSpan {
    /// The stage's fraction when the flow's share `done` (in [0, 1]) is done.
    pub fn at(self, done: f32) -> f32 {
        self.from + self.span * done
    }
}

/// The result of `future`, which must never wait (it is polled once): the pipeline's futures
/// wait only on a [`Directions`] that does, and natively [`ComputedHere`] never does.
fn without_waiting<T>(future: impl Future<Output = Result<T>>) -> Result<T> {
    use std::task::{Context, Poll, Waker};
    let mut future = std::pin::pin!(future);
    match future
        .as_mut()
        .poll(&mut Context::from_waker(Waker::noop()))
    {
        Poll::Ready(result) => result,
        Poll::Pending => Err(Error::InvalidParameter(
            "a flow source waited where none may (a bug)".into(),
        )),
    }
}

/// Milliseconds per stage and the solve's numbers, for `report.json` and the page.
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    pub camera: Camera,
    pub working_size: (usize, usize),
    pub input_size: (usize, usize),
    pub params: Params,
    /// Milliseconds per stage, summed over every pass the run made (see
    /// [`Params::min_pinned_share`]).
    pub timings_ms: Vec<(Stage, f64)>,
    /// Parameters of the computed flow that was kept (a finer preset than the one asked for when
    /// too little of that passed its check, or when a pass from it pinned too few scales, left
    /// the camera's motion ambiguous or found no ground: see `notes`); `None` when the flow was
    /// given.
    pub flow: Option<FlowParams>,
    /// Share of the working-resolution pixels whose flow is trusted.
    pub reliable_flow: f64,
    pub superpixels: usize,
    pub degenerate: usize,
    pub hypotheses: usize,
    /// The strongest rival of the camera's motion (a candidate far from it that explains the
    /// image nearly as well; [`EgoRival`]); `None` when no candidate lay far from it.
    pub ego_rival: Option<EgoRival>,
    /// Superpixels of this reconstruction's unit-scale soup given the camera's motion because
    /// their own hypothesis made their surface rugged (a rigid motion fitted to part of a bending
    /// body; `init.rugged_ratio`). The fusion's members are not counted.
    pub rugged_to_ego: usize,
    /// The scale solve: energies, rigid segments, pieces moved by tail control.
    pub scales: ScaleReport,
    /// The refinement's energy per iteration (`None` when turned off).
    pub refine: Option<RefineReport>,
    /// The members fused into the soup (`None` when `ensemble.members` is 1 or less).
    pub ensemble: Option<EnsembleReport>,
    /// Superpixels whose depth is a guess (confidence below `scales.min_confidence`): the
    /// contacts do not pin their scale, or their plane is a neighbour's.
    pub unconfident: usize,
    /// Per superpixel (by label), how firmly its depth is known, in [0, 1]: how strongly the
    /// contacts pin its scale, or 0 where its plane is borrowed from a neighbour
    /// ([`crate::soup::scales::depth_confidence`]).
    pub confidence: Vec<f64>,
    pub notes: Vec<String>,
}

/// The result of [`reconstruct`].
#[derive(Clone, Debug)]
pub struct Reconstruction {
    /// Flow 1→2 used, at the working resolution.
    pub flow: FlowField,
    /// True where that flow is trusted (known, and for computed flow forward–backward consistent).
    pub reliable: Grid<bool>,
    pub superpixels: Superpixels,
    /// Touching superpixels and their boundary pixel pairs.
    pub boundaries: BoundaryGraph,
    /// The K-NN graph over superpixel anchors (neighbourhoods of the local motion hypotheses).
    pub knn: KnnGraph,
    /// The soup before the scale solve (λ = 1: the "unorganised" soup).
    pub unit_soup: Soup,
    /// The soup right after the scale solve, before the refinement (median λ = 1).
    pub scaled_soup: Soup,
    /// The soup right after the refinement, before the fusion (median λ = 1; the same as `soup`
    /// when no members are fused). `soup eval --oracle` compares the refinement's energies here.
    pub refined_soup: Soup,
    /// The soup with relative scales, refined and fused with the members' (median λ = 1: the
    /// "organised" soup).
    pub soup: Soup,
    /// Frame-1 depth at the working resolution (NaN = unknown).
    pub depth: Grid<f32>,
    /// Frame-1 depth at the input resolution (NaN = unknown).
    pub depth_input: Grid<f32>,
    /// The reference frame at the working resolution (the points' colours).
    pub frame1: Frame,
    pub report: Report,
}

impl Reconstruction {
    /// The point clouds of frame 1 and frame 2 (see [`point_clouds`]). Computed when asked (a
    /// few ms) rather than kept: at 1024 × 768 they would be 24 MB of every result's memory.
    pub fn clouds(&self) -> (PointCloud, PointCloud) {
        point_clouds(
            &self.soup,
            &self.superpixels.labels,
            &self.depth,
            &self.frame1,
            &self.report.camera.intrinsics,
        )
    }

    /// The inputs of the scale and refinement energies over this reconstruction's superpixels,
    /// graphs, flow and intrinsics (to evaluate them, or a soup's confidence, again).
    pub fn scale_inputs(&self) -> ScaleInputs<'_> {
        ScaleInputs {
            superpixels: &self.superpixels,
            boundaries: &self.boundaries,
            flow: &self.flow,
            reliable: &self.reliable,
            intrinsics: &self.report.camera.intrinsics,
        }
    }

    /// What this reconstruction's soup stages saw: frame 1, intrinsics, flow and its trusted
    /// vectors at the working resolution (what the fusion's members are made from).
    pub fn observed(&self) -> Observed<'_> {
        Observed {
            frame1: &self.frame1,
            k: &self.report.camera.intrinsics,
            flow: &self.flow,
            reliable: &self.reliable,
        }
    }

    /// Per pixel of frame 1 (working resolution): the scene flow X' − X in camera 1's frame,
    /// NaN where unknown (see [`scene_flow`]). Computed when asked, like [`Self::clouds`].
    pub fn scene_flow(&self) -> Grid<[f32; 3]> {
        scene_flow(
            &self.soup,
            &self.superpixels.labels,
            &self.depth,
            &self.report.camera.intrinsics,
        )
    }
}

/// Reconstructs both frames of `pair`. `progress(stage, fraction)` is called as stages start and
/// finish (fraction in [0, 1] within the stage).
///
/// With computed flow, a reconstruction whose scales are pinned on less than
/// [`Params::min_pinned_share`] of the image, whose camera motion is ambiguous
/// ([`InitParams::ambiguous_ego_excess`]) or whose scale solve finds no ground plane
/// ([`Params::finer_without_ground`]), is made again from the flow of the next finer preset,
/// and the best pass is kept: a finer pass replaces an ambiguous one and one without a ground
/// where it finds one, and otherwise the larger pinned share wins (each finer pass reports its
/// stages' progress again from the flow on, and an earlier pass kept after them its flow,
/// computed again, within the outputs stage; notes say what happened, and the stage times are
/// summed over the passes).
/// The kept pass is then fused with its members ([`Stage::Ensemble`], last: see
/// [`crate::soup::ensemble`]), once, and its depth and confidence are made again from the fused
/// soup. Natively the members run on up to four threads (see `solve_members`); everything else
/// runs on the calling thread.
///
/// The same in two steps, for callers that make the members elsewhere (the page, in Web Workers
/// of their own): [`reconstruct_unfused`], a [`member_vote`] for each of [`member_counts`], then
/// [`fuse_votes`].
pub fn reconstruct(
    pair: &FramePair,
    flow: FlowInput,
    params: &Params,
    progress: &mut dyn FnMut(Stage, f32),
) -> Result<Reconstruction> {
    let mut rec = reconstruct_unfused(pair, flow, params, progress)?;
    fuse(&mut rec, progress);
    Ok(rec)
}

/// [`reconstruct`] up to the fusion: the kept pass, its `soup` not yet fused with the members
/// (the same as `refined_soup`) and no [`Stage::Ensemble`] time in its report. [`fuse_votes`]
/// finishes it.
pub fn reconstruct_unfused(
    pair: &FramePair,
    flow: FlowInput,
    params: &Params,
    progress: &mut dyn FnMut(Stage, f32),
) -> Result<Reconstruction> {
    without_waiting(reconstruct_unfused_from(
        pair,
        flow,
        params,
        &mut ComputedHere,
        progress,
    ))
}

/// [`reconstruct_unfused`] with the computed flows' directions from `directions` (where it gives
/// them; the page's worker, `src/web/reconstruct.rs`), waiting for them where it waits.
pub(crate) async fn reconstruct_unfused_from(
    pair: &FramePair,
    flow: FlowInput,
    params: &Params,
    directions: &mut impl Directions,
    progress: &mut dyn FnMut(Stage, f32),
) -> Result<Reconstruction> {
    params.validate()?;
    match flow {
        FlowInput::Given(given) => {
            let input = FlowInput::Given(given);
            let mut rec = reconstruct_from(pair, input, params, None, directions, progress).await?;
            let note = ambiguity_note(rec.report.ego_rival, &params.init);
            rec.report.notes.extend(note);
            Ok(rec)
        }
        FlowInput::Compute(first) => {
            reconstruct_until_pinned(pair, first, params, directions, progress).await
        }
    }
}

/// One pass of [`reconstruct_from`] with computed flow, as [`reconstruct_until_pinned`] weighs it.
#[derive(Clone, Copy)]
struct Pass {
    /// The flow parameters the pass was asked for (they make the same pass again).
    asked: FlowParams,
    /// The flow parameters it used (finer than `asked` when too little of that flow was trusted).
    used: FlowParams,
    /// Its [`pinned_share`].
    pinned: f64,
    /// The rival of its camera motion.
    rival: Option<EgoRival>,
    /// Whether that rival explains the image nearly as well ([`EgoRival::is_ambiguous`]).
    ambiguous: bool,
    /// Whether its scale solve found no ground plane, where that asks for finer flow
    /// ([`Params::finer_without_ground`]).
    lacks_ground: bool,
}

impl Pass {
    fn of(rec: &Reconstruction, asked: FlowParams) -> Self {
        let (rival, params) = (rec.report.ego_rival, &rec.report.params);
        let init = &params.init;
        Pass {
            asked,
            used: rec.report.flow.unwrap_or(asked),
            pinned: pinned_share(rec),
            rival,
            ambiguous: rival.is_some_and(|r| r.is_ambiguous(init)),
            lacks_ground: params.finer_without_ground
                && params.scales.looks_for_ground()
                && !rec.report.scales.ground,
        }
    }

    /// Whether a finer preset's flow should be tried after this pass: its camera motion is
    /// ambiguous, it pins less than `min_pinned_share` of the image, or it found no ground.
    fn wants_finer(&self, min_pinned_share: f64) -> bool {
        self.ambiguous || self.pinned < min_pinned_share || self.lacks_ground
    }

    /// Whether this pass, made from finer flow than the `earlier` one, is better: where the
    /// earlier pass's camera motion was ambiguous (the finer flow was asked for to settle it),
    /// where this one found the ground the earlier one lacked (for the same reason), or where
    /// this one pins more. Not "unambiguous first": the crowd's camera motion with
    /// preset high has a rival within 3.5–4.5 % at some seeds and is right (MRE 0.061), and
    /// keeping an unambiguous pass of preset medium that pinned 61 % over it gave 0.111.
    fn improves_on(&self, earlier: &Pass) -> bool {
        earlier.ambiguous
            || (earlier.lacks_ground && !self.lacks_ground)
            || self.pinned > earlier.pinned
    }

    /// Why a finer preset's flow is tried after this pass, for the report's notes.
    fn why_finer(&self) -> String {
        match self.rival.filter(|_| self.ambiguous) {
            Some(r) => format!(
                "the camera's motion was ambiguous with the flow of preset {} (a motion {:.1}° \
                 apart explained the image within {:.1} %)",
                preset_name(&self.used),
                r.angle_deg,
                100.0 * r.excess
            ),
            None if self.lacks_ground => format!(
                "no ground plane was found with the flow of preset {} ({:.0} % of the image \
                 pinned)",
                preset_name(&self.used),
                100.0 * self.pinned
            ),
            None => format!(
                "the depths of only {:.0} % of the image were pinned with the flow of preset {}",
                100.0 * self.pinned,
                preset_name(&self.used)
            ),
        }
    }
}

/// Passes of [`reconstruct_from`] from the flow of `first` (each flow's directions from
/// `directions` where it gives them), then of the next finer preset while
/// the last pass pins less than [`Params::min_pinned_share`] (flow too coarse to show where
/// movers meet the world leaves their scales to guesses), its camera motion is ambiguous
/// (flow too coarse to tell the camera's motion from a compromise with the movers) or it found
/// no ground ([`Params::finer_without_ground`]: flow too coarse for a floor's slopes). Returns the
/// best pass ([`Pass::improves_on`]; the earliest on a tie), with the notes of every pass in the
/// order they ran and its stage times summed over all of them. While a finer pass runs, the best
/// one so far waits set aside ([`SetAside`]): its superpixels and graphs, which the later passes
/// share (they do not depend on the flow), its soups and its report. If it stays the best, its
/// flow is computed again and its depth made from its soup; its motions, scales and refinement
/// are not. So the memory is that of one running pass (the page's budget) plus the set-aside
/// pass's superpixels, graphs and soups (the superpixels and graphs were held before too, as
/// the copy the later passes shared). A best
/// pass whose camera motion is ambiguous keeps only its superpixels and graphs: any finer pass
/// replaces it, so it is made again whole only where every later pass fails. A later pass that
/// fails leaves the best one so far, with a note.
async fn reconstruct_until_pinned(
    pair: &FramePair,
    first: FlowParams,
    params: &Params,
    directions: &mut impl Directions,
    progress: &mut dyn FnMut(Stage, f32),
) -> Result<Reconstruction> {
    let input = FlowInput::Compute(first);
    let first_pass = reconstruct_from(pair, input, params, None, directions, progress).await?;
    let mut best = Pass::of(&first_pass, first);
    let mut last = best;
    let mut notes = first_pass.report.notes.clone();
    let mut spent = first_pass.report.timings_ms.clone();
    let mut held = Held::Whole(Box::new(first_pass));
    while let Some(finer) =
        (last.used.finer()).filter(|_| last.wants_finer(params.min_pinned_share))
    {
        notes.push(format!(
            "{}; reconstructed again with preset {}",
            last.why_finer(),
            preset_name(&finer),
        ));
        held = held.set_aside(!best.ambiguous);
        match reconstruct_from(
            pair,
            FlowInput::Compute(finer),
            params,
            held.segmentation(),
            directions,
            progress,
        )
        .await
        {
            Ok(again) => {
                // A note every pass makes alike (the focal length's) is said once.
                for note in &again.report.notes[pair.notes.len()..] {
                    if !notes.contains(note) {
                        notes.push(note.clone());
                    }
                }
                spent.extend_from_slice(&again.report.timings_ms);
                last = Pass::of(&again, finer);
                if last.improves_on(&best) {
                    (best, held) = (last, Held::Whole(Box::new(again)));
                }
            }
            Err(e) => {
                notes.push(format!(
                    "reconstructing again with preset {} failed: {e}",
                    preset_name(&finer)
                ));
                break;
            }
        }
    }
    let mut kept = match held {
        Held::Whole(rec) => *rec,
        Held::Aside(aside) => {
            notes.push(format!(
                "kept the reconstruction from preset {} ({:.0} % pinned; {:.0} % with preset {})",
                preset_name(&best.used),
                100.0 * best.pinned,
                100.0 * last.pinned,
                preset_name(&last.used),
            ));
            aside
                .restore(pair, &mut spent, directions, progress)
                .await?
        }
        Held::Dropped(segmentation) => {
            notes.push(format!(
                "kept the reconstruction from preset {} ({:.0} % pinned), made again",
                preset_name(&best.used),
                100.0 * best.pinned,
            ));
            let again = reconstruct_from(
                pair,
                FlowInput::Compute(best.asked),
                params,
                Some(&segmentation),
                directions,
                progress,
            )
            .await?;
            spent.extend_from_slice(&again.report.timings_ms);
            again
        }
    };
    notes.extend(ambiguity_note(kept.report.ego_rival, &params.init));
    kept.report.notes = notes;
    kept.report.timings_ms = summed_by_stage(&spent);
    Ok(kept)
}

/// The best pass of [`reconstruct_until_pinned`] so far.
enum Held {
    /// As its pass returned it.
    Whole(Box<Reconstruction>),
    /// Set aside while a finer pass runs.
    Aside(Box<SetAside>),
    /// Only its superpixels and graphs, while a finer pass that will replace it runs.
    Dropped(Box<Segmentation>),
}

impl Held {
    /// The pass set aside where it may still be kept (`may_stay`), else dropped but for its
    /// superpixels and graphs; a pass already set aside or dropped stays as it is.
    fn set_aside(self, may_stay: bool) -> Held {
        match self {
            Held::Whole(rec) if may_stay => Held::Aside(Box::new(SetAside::of(*rec))),
            Held::Whole(rec) => Held::Dropped(Box::new(SetAside::of(*rec).segmentation)),
            held => held,
        }
    }

    /// The superpixels and graphs of a pass set aside or dropped, for the later passes to share.
    fn segmentation(&self) -> Option<&Segmentation> {
        match self {
            Held::Whole(_) => None,
            Held::Aside(aside) => Some(&aside.segmentation),
            Held::Dropped(segmentation) => Some(segmentation),
        }
    }
}

/// The share of the outputs stage's progress that a pass set aside and kept gives to computing
/// its flow again ([`SetAside::restore`]): the flow takes most of its time (medium's flow
/// 188 ms against 7 ms for the depth and clouds natively).
const RESTORED_FLOW_SHARE: f32 = 0.9;

/// A [`Reconstruction`] without its flow, trust mask, depth maps and frame: its superpixels and
/// graphs (which the later passes share), soups and report. The flow is the one large array
/// that is expensive to make again; kept, it would add 9 bytes per pixel to the peak of the
/// finer pass's flow (7 MB at 1024 × 768, where the page's crowd already reaches its 400 MiB).
struct SetAside {
    segmentation: Segmentation,
    unit_soup: Soup,
    scaled_soup: Soup,
    refined_soup: Soup,
    soup: Soup,
    report: Report,
}

impl SetAside {
    /// `rec` set aside.
    fn of(rec: Reconstruction) -> Self {
        let Reconstruction {
            superpixels,
            boundaries,
            knn,
            unit_soup,
            scaled_soup,
            refined_soup,
            soup,
            report,
            flow: _,
            reliable: _,
            depth: _,
            depth_input: _,
            frame1: _,
        } = rec;
        SetAside {
            segmentation: Segmentation {
                superpixels,
                boundaries,
                knn,
            },
            unit_soup,
            scaled_soup,
            refined_soup,
            soup,
            report,
        }
    }

    /// The reconstruction again, from `pair` (the pair it was made from): its flow computed
    /// again with the parameters it used (deterministic, so the same flow and trust mask; its
    /// directions from `directions` where it gives them), its
    /// depth maps made from its soup as its pass made them. The stages' times go to `spent`;
    /// `progress` hears of it all as [`Stage::Outputs`] (the flow's share first), since no new
    /// pass starts (the page's progress bar counts a return to the flow as one).
    async fn restore(
        self,
        pair: &FramePair,
        spent: &mut Vec<(Stage, f64)>,
        directions: &mut impl Directions,
        progress: &mut dyn FnMut(Stage, f32),
    ) -> Result<Reconstruction> {
        let SetAside {
            segmentation,
            unit_soup,
            scaled_soup,
            refined_soup,
            soup,
            report,
        } = self;
        let mut clock = Clock::start();
        progress(Stage::Outputs, 0.0);
        let used = report.flow.ok_or_else(|| {
            Error::InvalidParameter("a pass set aside had no computed flow".into())
        })?;
        let FlowPair {
            forward: flow,
            reliable,
            ..
        } = flow_of(
            pair,
            &used,
            directions,
            ProgressSpan {
                stage: Stage::Outputs,
                from: 0.0,
                span: RESTORED_FLOW_SHARE,
            },
            progress,
        )
        .await?;
        clock.lap(Stage::Flow);
        let k = report.camera.intrinsics;
        let inputs = segmentation.scale_inputs(&flow, &reliable, &k);
        let (_, depth, depth_input) = outputs(report.input_size, &soup, &inputs, &report.params);
        clock.lap(Stage::Outputs);
        progress(Stage::Outputs, 1.0);
        spent.extend_from_slice(&clock.laps);
        let Segmentation {
            superpixels,
            boundaries,
            knn,
        } = segmentation;
        Ok(Reconstruction {
            flow,
            reliable,
            superpixels,
            boundaries,
            knn,
            unit_soup,
            scaled_soup,
            refined_soup,
            soup,
            depth,
            depth_input,
            frame1: pair.frame1.clone(),
            report,
        })
    }
}

/// A note for the report when the kept pass's camera motion, whose rival is `rival`, is
/// ambiguous ([`EgoRival::is_ambiguous`] with `init`): no finer flow was left to try (or the
/// flow was given), so the user should know.
fn ambiguity_note(rival: Option<EgoRival>, init: &InitParams) -> Option<String> {
    let rival = rival?;
    rival.is_ambiguous(init).then(|| {
        format!(
            "the camera's motion is ambiguous: a motion {:.1}° from it explains the image within \
             {:.1} % as well, so the depths may be distorted",
            rival.angle_deg,
            100.0 * rival.excess
        )
    })
}

/// The name of `params`' preset, or "custom".
fn preset_name(params: &FlowParams) -> &'static str {
    params.named_preset().map_or("custom", Preset::name)
}

/// Share in [0, 1] of the working-resolution pixels of `rec` whose superpixel's depth is pinned
/// (its confidence, [`crate::soup::scales::depth_confidence`], at least `scales.min_confidence`
/// of the parameters it was made with).
pub fn pinned_share(rec: &Reconstruction) -> f64 {
    let min = rec.report.params.scales.min_confidence;
    let pinned: usize = (rec.superpixels.segments.iter())
        .zip(&rec.report.confidence)
        .filter(|&(_, &c)| c >= min)
        .map(|(seg, _)| seg.pixels.len())
        .sum();
    pinned as f64 / rec.superpixels.labels.len().max(1) as f64
}

/// Milliseconds per stage, each stage once (in pipeline order) with the sum of its laps.
fn summed_by_stage(laps: &[(Stage, f64)]) -> Vec<(Stage, f64)> {
    Stage::ALL
        .into_iter()
        .filter_map(|stage| {
            let mine = laps.iter().filter(|(s, _)| *s == stage);
            let total: f64 = mine.clone().map(|(_, ms)| ms).sum();
            (mine.count() > 0).then_some((stage, total))
        })
        .collect()
}

/// Frame 1's superpixels and their graphs: they depend on frame 1 and the parameters only, so
/// the passes of [`reconstruct_until_pinned`] share them.
#[derive(Clone)]
struct Segmentation {
    superpixels: Superpixels,
    boundaries: BoundaryGraph,
    knn: KnnGraph,
}

impl Segmentation {
    /// SLIC on `frame1`, the boundary graph and the K-NN graph, with `params`.
    fn compute(frame1: &Frame, params: &Params) -> Result<Self> {
        let superpixels = slic(frame1, &params.superpixels)?;
        let boundaries = boundary_graph(&superpixels, frame1);
        // The graph's distance weights are not used by the pipeline (only the neighbour lists).
        let knn = knn_graph(&superpixels, params.k, 0.0);
        Ok(Segmentation {
            superpixels,
            boundaries,
            knn,
        })
    }

    /// The inputs of the scale and refinement energies over these superpixels and graphs, with
    /// `flow` (its trusted vectors `reliable`) and intrinsics `k`, all at the working resolution.
    fn scale_inputs<'a>(
        &'a self,
        flow: &'a FlowField,
        reliable: &'a Grid<bool>,
        k: &'a Intrinsics,
    ) -> ScaleInputs<'a> {
        ScaleInputs {
            superpixels: &self.superpixels,
            boundaries: &self.boundaries,
            flow,
            reliable,
            intrinsics: k,
        }
    }
}

/// `camera`, or where it is only the default guess, the focal length the trusted `flow` fixes
/// ([`crate::focal`]), with a note saying which (in pixels of the working size). Its time counts
/// in [`Stage::Flow`]'s.
fn camera_from_flow(
    camera: Camera,
    flow: &FlowField,
    reliable: &Grid<bool>,
    notes: &mut Vec<String>,
) -> Camera {
    if camera.source != IntrinsicsSource::Default {
        return camera;
    }
    let guess = camera.intrinsics;
    match focal::estimate_focal(flow, reliable, &guess) {
        Some(estimate) => {
            notes.push(format!(
                "no focal length was given: the two frames fix it at {:.0} px at the working size \
                 (the guess was {:.0} px, its long side)",
                estimate.focal, guess.fx
            ));
            Camera {
                intrinsics: Intrinsics {
                    fx: estimate.focal,
                    fy: estimate.focal,
                    ..guess
                },
                source: IntrinsicsSource::Estimated,
            }
        }
        None => {
            notes.push(format!(
                "no focal length was given and the two frames do not fix it: guessed {:.0} px at \
                 the working size (its long side); give the intrinsics if the depth looks \
                 distorted",
                guess.fx
            ));
            camera
        }
    }
}

/// One pass of the pipeline: flow (given, or computed by [`trusted_flow`]), superpixels (or a
/// copy of `segmentation`, made by an earlier pass with the same frame 1 and parameters),
/// unit-scale soup, scales, refinement and outputs.
async fn reconstruct_from(
    pair: &FramePair,
    flow: FlowInput,
    params: &Params,
    segmentation: Option<&Segmentation>,
    directions: &mut impl Directions,
    progress: &mut dyn FnMut(Stage, f32),
) -> Result<Reconstruction> {
    let (w, h) = pair.frame1.size();
    let mut clock = Clock::start();
    let mut notes = pair.notes.clone();

    progress(Stage::Flow, 0.0);
    let (flow, reliable, flow_params) = match flow {
        FlowInput::Given(given) => {
            let flow = resize_flow(&given, w, h);
            let reliable = flow.map(|&f| is_known(f));
            (flow, reliable, None)
        }
        FlowInput::Compute(flow_params) => {
            let (computed, used) = trusted_flow(
                pair,
                flow_params,
                directions,
                params.min_reliable_flow,
                &mut notes,
                progress,
            )
            .await?;
            (computed.forward, computed.reliable, Some(used))
        }
    };
    if flow
        .data()
        .iter()
        .all(|f| is_known(*f) && f[0].abs() < 1e-3 && f[1].abs() < 1e-3)
    {
        return Err(Error::NoParallax(
            "the flow is zero everywhere (identical frames?)".into(),
        ));
    }
    let camera = camera_from_flow(pair.camera, &flow, &reliable, &mut notes);
    let k = camera.intrinsics;
    clock.lap(Stage::Flow);

    let seen = Observed {
        frame1: &pair.frame1,
        k: &k,
        flow: &flow,
        reliable: &reliable,
    };
    let solved = solve_soup(seen, params, segmentation, &mut clock, progress)?;
    progress(Stage::Outputs, 0.0);
    let inputs = solved.segmentation.scale_inputs(&flow, &reliable, &k);
    let (confidence, depth, depth_input) = outputs(pair.input_size, &solved.soup, &inputs, params);
    clock.lap(Stage::Outputs);
    progress(Stage::Outputs, 1.0);
    let Solved {
        segmentation:
            Segmentation {
                superpixels: sp,
                boundaries,
                knn,
            },
        unit_soup,
        scaled_soup,
        soup,
        scales,
        refine,
    } = solved;

    let report = Report {
        camera,
        working_size: (w, h),
        input_size: pair.input_size,
        params: *params,
        timings_ms: clock.laps,
        flow: flow_params,
        reliable_flow: trusted_share(&reliable),
        superpixels: sp.len(),
        degenerate: soup
            .pieces
            .iter()
            .filter(|p| p.degenerate.is_some())
            .count(),
        hypotheses: soup.hypotheses.len(),
        ego_rival: unit_soup.ego_rival,
        rugged_to_ego: unit_soup.rugged_to_ego,
        scales,
        refine,
        ensemble: None,
        unconfident: unconfident(&confidence, params),
        confidence,
        notes,
    };
    Ok(Reconstruction {
        flow,
        reliable,
        superpixels: sp,
        boundaries,
        knn,
        unit_soup,
        scaled_soup,
        refined_soup: soup.clone(),
        soup,
        depth,
        depth_input,
        frame1: pair.frame1.clone(),
        report,
    })
}

/// What the outputs stage derives from a soup: each superpixel's scale confidence, the frame-1
/// depth at the working resolution and at the input resolution `input_size` (`(width,
/// height)`, pixels).
fn outputs(
    input_size: (usize, usize),
    soup: &Soup,
    inputs: &ScaleInputs,
    params: &Params,
) -> (Vec<f64>, Grid<f32>, Grid<f32>) {
    let (k, labels) = (inputs.intrinsics, &inputs.superpixels.labels);
    let confidence = depth_confidence(soup, inputs, &params.scales);
    let depth = dense_depth(soup, labels, k);
    let (iw, ih) = input_size;
    let (sx, sy) = working_over_input(labels.size(), input_size);
    let depth_input = depth_at(soup, labels, iw, ih, &k.scaled(1.0 / sx, 1.0 / sy));
    (confidence, depth, depth_input)
}

/// How many of `confidence` are below `params.scales.min_confidence`.
fn unconfident(confidence: &[f64], params: &Params) -> usize {
    let min = params.scales.min_confidence;
    confidence.iter().filter(|&&c| c < min).count()
}

/// The fusion stage of [`reconstruct`], once, on a reconstruction of [`reconstruct_unfused`]
/// (with the parameters it was made with): a [`member_vote`] for each of [`member_counts`]
/// (natively several at once, `solve_members`), then [`fuse_votes`]. Reported to `progress`
/// (and timed) as [`Stage::Ensemble`] even when `ensemble.members` is 1 and nothing is fused.
pub fn fuse(rec: &mut Reconstruction, progress: &mut dyn FnMut(Stage, f32)) {
    let start = now_ms();
    progress(Stage::Ensemble, 0.0);
    let params = &rec.report.params;
    let counts = member_counts(params);
    let seen = rec.observed();
    let vote = |count: usize| member_vote(seen, params, count);
    let made = solve_members(member_threads(), &counts, vote, &mut |f| {
        progress(Stage::Ensemble, f)
    });
    let made = made.into_iter().map(|v| v.map_err(|e| e.to_string()));
    fuse_votes(rec, made.collect(), now_ms() - start);
    progress(Stage::Ensemble, 1.0);
}

/// The superpixel counts of the members fused into a reconstruction with `params` (none when
/// `ensemble.members` is 1 or less), in the order [`fuse_votes`] takes their votes.
pub fn member_counts(params: &Params) -> Vec<usize> {
    let ensemble = &params.ensemble;
    if ensemble.members <= 1 {
        return Vec::new();
    }
    ensemble.member_counts(params.superpixels.count)
}

/// One member of the fusion ([`crate::soup::ensemble`]): the soup stages over what `seen` shows
/// (the kept reconstruction's [`Reconstruction::observed`]) from `count` superpixels, with the
/// members' cheaper refinement (`ensemble.member_iterations` and `member_particles` of
/// `params`), and its vote: its depth at every [`SAMPLE_STRIDE`]-th pixel, pinned where its
/// piece's depth confidence is at least `scales.min_confidence`. Deterministic: the same
/// inputs give the same vote on any thread or machine. A flow or trust map of another size than
/// frame 1 is an [`Error::InvalidParameter`].
pub fn member_vote(seen: Observed, params: &Params, count: usize) -> Result<Vote> {
    let size = seen.frame1.size();
    if seen.flow.size() != size || seen.reliable.size() != size {
        return Err(Error::InvalidParameter(format!(
            "a member's flow ({:?}) and trusted vectors ({:?}) must be the size of frame 1 ({size:?})",
            seen.flow.size(),
            seen.reliable.size()
        )));
    }
    let mut member = params.with_member_refinement();
    member.superpixels.count = count;
    let solved = solve_soup(seen, &member, None, &mut Clock::start(), &mut |_, _| {})?;
    let segmentation = &solved.segmentation;
    let inputs = segmentation.scale_inputs(seen.flow, seen.reliable, seen.k);
    let confidence = depth_confidence(&solved.soup, &inputs, &params.scales);
    let labels = &segmentation.superpixels.labels;
    Ok(vote_of(&solved.soup, labels, &confidence, seen.k, params))
}

/// Finishes a reconstruction of [`reconstruct_unfused`], once, with the parameters it was made
/// with: moves each piece of its soup to the weighted median scale of its own vote and the members'
/// (`made`: one per [`member_counts`], in their order; an `Err` holds why that member could not be
/// made, and it is left out with a note in the report, as is a member `made` lacks), then makes its
/// depth, confidence and report again from the fused soup. `members_ms` is the time the members
/// took, added to the [`Stage::Ensemble`] time with the fusion's own. With no members
/// (`ensemble.members` 1) only that time is recorded.
pub fn fuse_votes(
    rec: &mut Reconstruction,
    made: Vec<std::result::Result<Vote, String>>,
    members_ms: f64,
) {
    let mut clock = Clock::started_ms_ago(members_ms);
    let params = rec.report.params;
    let counts = member_counts(&params);
    let ensemble = (!counts.is_empty()).then(|| {
        let (mut votes, mut failed) = (Vec::new(), Vec::new());
        let made = made
            .into_iter()
            .chain(std::iter::repeat_with(|| Err("not made".into())));
        for (count, vote) in counts.iter().zip(made) {
            match vote {
                Ok(v) => votes.push(v),
                Err(e) => failed.push(format!("{count} superpixels: {e}")),
            }
        }
        let k = rec.report.camera.intrinsics;
        let labels = &rec.superpixels.labels;
        let own = vote_of(&rec.soup, labels, &rec.report.confidence, &k, &params);
        let guess_weight = params.ensemble.guess_weight;
        let rescaled = fuse_scales(&mut rec.soup, &sampled(labels), &own, &votes, guess_weight);
        let inputs = rec.scale_inputs();
        let (confidence, depth, depth_input) =
            outputs(rec.report.input_size, &rec.soup, &inputs, &params);
        (rec.depth, rec.depth_input) = (depth, depth_input);
        rec.report.unconfident = unconfident(&confidence, &params);
        rec.report.confidence = confidence;
        EnsembleReport {
            counts,
            failed,
            rescaled,
        }
    });
    rec.report.ensemble = ensemble;
    clock.lap(Stage::Ensemble);
    rec.report.timings_ms.extend(clock.laps);
}

/// What [`solve_soup`] makes: the segmentation and the soup after each of its stages.
struct Solved {
    segmentation: Segmentation,
    /// Before the scale solve (λ = 1).
    unit_soup: Soup,
    /// After the scale solve.
    scaled_soup: Soup,
    /// After the refinement.
    soup: Soup,
    scales: ScaleReport,
    refine: Option<RefineReport>,
}

/// What one pass of the soup stages sees, all at the working resolution (a fusion member,
/// [`member_vote`], sees the kept reconstruction's: [`Reconstruction::observed`]).
#[derive(Clone, Copy)]
pub struct Observed<'a> {
    /// The reference frame.
    pub frame1: &'a Frame,
    /// Intrinsics of the working resolution.
    pub k: &'a Intrinsics,
    /// Flow 1→2 (px), the size of `frame1`.
    pub flow: &'a FlowField,
    /// The flow vectors to trust (known, and through the forward–backward check when computed),
    /// the size of `frame1`.
    pub reliable: &'a Grid<bool>,
}

/// The soup stages of one pass over what `seen` shows: superpixels of its frame 1 (or a copy of
/// `segmentation`), unit-scale soup, scales and refinement, with `params`. Each stage is timed
/// on `clock`.
fn solve_soup(
    seen: Observed,
    params: &Params,
    segmentation: Option<&Segmentation>,
    clock: &mut Clock,
    progress: &mut dyn FnMut(Stage, f32),
) -> Result<Solved> {
    let Observed {
        frame1,
        k,
        flow,
        reliable,
    } = seen;
    progress(Stage::Superpixels, 0.0);
    let segmentation = match segmentation {
        Some(shared) => shared.clone(),
        None => Segmentation::compute(frame1, params)?,
    };
    let sp = &segmentation.superpixels;
    let adjacency = segmentation.boundaries.adjacency(sp.len());
    clock.lap(Stage::Superpixels);

    progress(Stage::Motion, 0.0);
    let unit_soup = unit_scale_soup(
        sp,
        &segmentation.knn,
        &adjacency,
        flow,
        reliable,
        k,
        &params.init,
    )?;
    clock.lap(Stage::Motion);

    progress(Stage::Scales, 0.0);
    let mut soup = unit_soup.clone();
    let inputs = segmentation.scale_inputs(flow, reliable, k);
    let scales = solve_scales(&mut soup, &inputs, &params.scales);
    let scaled_soup = soup.clone();
    clock.lap(Stage::Scales);

    progress(Stage::Refine, 0.0);
    let refine = (params.refine.iterations > 0).then(|| {
        let problem = refine::Problem::new(&soup, &inputs, &params.scales, &params.refine);
        refine::refine(&mut soup, &problem, &inputs, &params.scales)
    });
    clock.lap(Stage::Refine);
    Ok(Solved {
        segmentation,
        unit_soup,
        scaled_soup,
        soup,
        scales,
        refine,
    })
}

/// `labels` at every [`SAMPLE_STRIDE`]-th pixel in x and y, as the fusion sees them.
fn sampled(labels: &Grid<u32>) -> Grid<u32> {
    let s = SAMPLE_STRIDE;
    let (w, h) = (labels.width().div_ceil(s), labels.height().div_ceil(s));
    Grid::from_fn(w, h, |x, y| *labels.get(x * s, y * s))
}

/// A soup's vote in the fusion: its depth at every [`SAMPLE_STRIDE`]-th pixel, pinned where the
/// superpixel's depth confidence (`confidence`, by label) is at least `scales.min_confidence`.
fn vote_of(
    soup: &Soup,
    labels: &Grid<u32>,
    confidence: &[f64],
    k: &Intrinsics,
    params: &Params,
) -> Vote {
    let depth = strided_depth(soup, labels, k, SAMPLE_STRIDE);
    let min = params.scales.min_confidence;
    let pinned = sampled(labels).map(|&l| confidence.get(l as usize).is_some_and(|&c| c >= min));
    Vote { depth, pinned }
}

/// Flow both ways between the pair's frames with `params`, as [`compute_flow`] gives it (the
/// same bits): natively, on a machine with more than one core, the backward direction on a
/// thread of its own while the calling thread computes the forward one (each is half the flow's
/// time); in wasm one after the other (the page computes them in two workers instead, and gives
/// them through [`Directions`]). `progress` gets the share done in [0, 1] (with two threads, that of
/// the forward direction). Errors as `compute_flow`'s.
fn flow_both_ways(
    pair: &FramePair,
    params: &FlowParams,
    progress: &mut dyn FnMut(f32),
) -> Result<FlowPair> {
    let (one, two) = (&pair.frame1, &pair.frame2);
    #[cfg(not(target_arch = "wasm32"))]
    if std::thread::available_parallelism().is_ok_and(|n| n.get() > 1) {
        use crate::flow::{compute_direction, pair_from_directions};
        let (forward, backward) = std::thread::scope(|scope| {
            let backward = scope.spawn(|| compute_direction(two, one, params, &mut |_| {}));
            let forward = compute_direction(one, two, params, progress);
            // A panic (a bug, never bad input) goes on from here, as it would without a thread.
            let backward = backward
                .join()
                .unwrap_or_else(|p| std::panic::resume_unwind(p));
            (forward, backward)
        });
        let flow = pair_from_directions(forward?, backward?, params)?;
        progress(1.0);
        return Ok(flow);
    }
    compute_flow(one, two, params, progress)
}

/// At most this many members are made at once natively: each holds a whole reconstruction's
/// segmentation, soups and refinement problem, so the memory grows with it. 4: the default
/// number of members besides the kept reconstruction.
#[cfg(not(target_arch = "wasm32"))]
const MAX_MEMBER_THREADS: usize = 4;

/// How many members are made at once: natively up to `MAX_MEMBER_THREADS`, no more than the
/// machine has cores; in wasm, whose instance has one thread, one (the page makes them in
/// workers of their own instead: [`member_vote`], `src/web/members.rs`).
fn member_threads() -> usize {
    #[cfg(not(target_arch = "wasm32"))]
    let threads = std::thread::available_parallelism()
        .map_or(1, |n| n.get())
        .min(MAX_MEMBER_THREADS);
    #[cfg(target_arch = "wasm32")]
    let threads = 1;
    threads
}

/// `member(count)` for each of `counts`, in their order, on `threads` threads
/// ([`member_threads`]; one: in turn, on the calling thread). The members are independent and
/// deterministic, so the results do not depend on how many threads run them. `progress` gets
/// the share of members done, from 0, as they finish.
#[cfg_attr(target_arch = "wasm32", allow(unused_variables))]
fn solve_members<T: Send, F>(
    threads: usize,
    counts: &[usize],
    member: F,
    progress: &mut dyn FnMut(f32),
) -> Vec<Result<T>>
where
    F: Fn(usize) -> Result<T> + Sync,
{
    #[cfg(not(target_arch = "wasm32"))]
    if threads > 1 && counts.len() > 1 {
        return in_parallel(threads, counts, member, progress);
    }
    let share = |done: usize| done as f32 / counts.len() as f32;
    (counts.iter().enumerate())
        .map(|(done, &count)| {
            progress(share(done));
            member(count)
        })
        .collect()
}

/// [`solve_members`] with more than one thread: each takes the next member not yet taken,
/// and each result goes to its member's place, whichever finishes first. A panic (a bug, never
/// bad input) goes on from here once every thread has stopped, as it would without threads.
#[cfg(not(target_arch = "wasm32"))]
fn in_parallel<T: Send, F>(
    threads: usize,
    counts: &[usize],
    member: F,
    progress: &mut dyn FnMut(f32),
) -> Vec<Result<T>>
where
    F: Fn(usize) -> Result<T> + Sync,
{
    use std::sync::atomic::{AtomicUsize, Ordering};
    let n = counts.len();
    let next = AtomicUsize::new(0);
    let mut slots: Vec<Option<Result<T>>> = (0..n).map(|_| None).collect();
    progress(0.0);
    std::thread::scope(|scope| {
        let (done_tx, done_rx) = std::sync::mpsc::channel();
        for _ in 0..threads.min(n) {
            let (done_tx, next, member) = (done_tx.clone(), &next, &member);
            scope.spawn(move || {
                loop {
                    let i = next.fetch_add(1, Ordering::Relaxed);
                    if i >= n || done_tx.send((i, member(counts[i]))).is_err() {
                        break;
                    }
                }
            });
        }
        // The receiver ends when every thread has stopped (each holds a sender).
        drop(done_tx);
        for (done, (i, result)) in done_rx.iter().enumerate() {
            slots[i] = Some(result);
            if done + 1 < n {
                progress((done + 1) as f32 / n as f32);
            }
        }
    });
    // Every slot is filled unless a thread panicked, and then the scope has panicked already.
    slots.into_iter().flatten().collect()
}

/// Flow by [`compute_flow`] with `params` ([`flow_of`]: from `directions` where it gives them),
/// computed again with the next finer preset
/// ([`FlowParams::finer`]) while less than `min_reliable` of the pixels passes the
/// forward–backward check (large motions that the coarser preset tracks badly); the pass with
/// the most trusted pixels is kept, with the parameters it used. Each new pass adds a note, and
/// so does keeping an earlier pass than the last.
///
/// `progress` hears of it as [`Stage::Flow`], the share of the work done in [0, 1]. A pass that
/// may be followed by a finer one gets the share of what is left that its preset's cost has
/// beside the finer one's
/// ([`Preset::relative_cost`]); the last possible pass (every pass when `min_reliable` is 0)
/// gets all that is left.
async fn trusted_flow(
    pair: &FramePair,
    params: FlowParams,
    directions: &mut impl Directions,
    min_reliable: f64,
    notes: &mut Vec<String>,
    progress: &mut dyn FnMut(Stage, f32),
) -> Result<(FlowPair, FlowParams)> {
    let mut start = 0.0f32;
    let (mut trusted, mut best) = spanned_flow(
        pair,
        &params,
        directions,
        min_reliable,
        &mut start,
        progress,
    )
    .await?;
    let (mut best_share, mut best_params, mut used) = (trusted, params, params);
    while let Some(finer) = used.finer().filter(|_| trusted < min_reliable) {
        notes.push(format!(
            "only {:.0} % of the flow passed the forward–backward check with preset {}; computed \
             again with preset {}",
            100.0 * trusted,
            preset_name(&used),
            preset_name(&finer),
        ));
        let (share, flow) =
            spanned_flow(pair, &finer, directions, min_reliable, &mut start, progress).await?;
        if share > best_share {
            (best_share, best, best_params) = (share, flow, finer);
        }
        (trusted, used) = (share, finer);
    }
    if best_params != used {
        notes.push(format!(
            "kept the flow of preset {} ({:.0} % passed its check; {:.0} % with preset {})",
            preset_name(&best_params),
            100.0 * best_share,
            100.0 * trusted,
            preset_name(&used),
        ));
    }
    progress(Stage::Flow, 1.0);
    Ok((best, best_params))
}

/// The flow with `params` of one of [`trusted_flow`]'s passes ([`flow_of`]) and its share of
/// trusted pixels. Its progress goes to `progress` as [`Stage::Flow`] from `start`, over its
/// share of what is left (see [`trusted_flow`]), and `start` moves past it.
async fn spanned_flow(
    pair: &FramePair,
    params: &FlowParams,
    directions: &mut impl Directions,
    min_reliable: f64,
    start: &mut f32,
    progress: &mut dyn FnMut(Stage, f32),
) -> Result<(f64, FlowPair)> {
    let cost = |p: &FlowParams| p.named_preset().map_or(1.0, Preset::relative_cost);
    let next = params.finer().filter(|_| min_reliable > 0.0);
    let share = next.map_or(1.0, |f| cost(params) / (cost(params) + cost(&f)));
    let span = ProgressSpan {
        stage: Stage::Flow,
        from: *start,
        span: share * (1.0 - *start),
    };
    let computed = flow_of(pair, params, directions, span, progress).await?;
    *start += span.span;
    Ok((trusted_share(&computed.reliable), computed))
}

/// The flow with `params` between the pair's frames, as [`compute_flow`] gives it: from the
/// two directions `directions` gives (checked to be of the frames' size), else computed
/// ([`flow_both_ways`]). Its progress goes to `progress` over `span`.
async fn flow_of(
    pair: &FramePair,
    params: &FlowParams,
    directions: &mut impl Directions,
    span: ProgressSpan,
    progress: &mut dyn FnMut(Stage, f32),
) -> Result<FlowPair> {
    let Some((forward, backward)) = directions.directions(params, span).await? else {
        return flow_both_ways(pair, params, &mut |f| progress(span.stage, span.at(f)));
    };
    let (w, h) = pair.frame1.size();
    for given in [&forward, &backward] {
        if given.size() != (w, h) {
            return Err(Error::InvalidParameter(format!(
                "a given flow direction is {}×{}; the frames are {w}×{h}",
                given.width(),
                given.height()
            )));
        }
    }
    let flow = crate::flow::pair_from_directions(forward, backward, params)?;
    progress(span.stage, span.at(1.0));
    Ok(flow)
}

/// Wall-clock lap timer of the stages, natively and in the browser (where `Instant` is
/// unavailable).
struct Clock {
    last: f64,
    /// Milliseconds per finished stage, in the order they finished.
    laps: Vec<(Stage, f64)>,
}

impl Clock {
    fn start() -> Self {
        Clock {
            last: now_ms(),
            laps: Vec::new(),
        }
    }

    /// A clock whose first lap counts `ms` milliseconds more (work timed elsewhere).
    fn started_ms_ago(ms: f64) -> Self {
        let mut clock = Clock::start();
        clock.last -= ms;
        clock
    }

    /// Records the milliseconds since the previous lap as `stage`'s.
    fn lap(&mut self, stage: Stage) {
        let now = now_ms();
        self.laps.push((stage, now - self.last));
        self.last = now;
    }
}

#[cfg(not(target_arch = "wasm32"))]
fn now_ms() -> f64 {
    use std::sync::OnceLock;
    static START: OnceLock<std::time::Instant> = OnceLock::new();
    START
        .get_or_init(std::time::Instant::now)
        .elapsed()
        .as_secs_f64()
        * 1e3
}

#[cfg(target_arch = "wasm32")]
fn now_ms() -> f64 {
    js_sys::Date::now()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_ambiguous_camera_motion_is_noted() {
        let init = InitParams::default();
        let rival = |excess| {
            Some(EgoRival {
                angle_deg: 8.25,
                excess,
            })
        };
        let note = ambiguity_note(rival(0.019), &init).expect("1.9 % is ambiguous");
        assert!(note.contains("8.2°") && note.contains("1.9 %"), "{note}");
        assert!(ambiguity_note(rival(0.05), &init).is_none());
        assert!(ambiguity_note(None, &init).is_none());
    }

    #[test]
    fn members_come_back_in_the_order_of_their_counts_with_their_errors() {
        // Whatever finishes first, each result stays with its count, an error stays an error,
        // and progress grows from 0 without reaching 1 (the fusion reports 1 once fused). Earlier
        // members take longer, so on several threads later ones finish first.
        let counts = [1300, 1400, 1600, 1700, 1200, 1800, 1100];
        let member = |count: usize| {
            let place = counts.iter().position(|&c| c == count).unwrap();
            std::thread::sleep(std::time::Duration::from_millis(8 * (7 - place) as u64));
            if count == 1600 {
                return Err(Error::InvalidParameter("no member of 1600".into()));
            }
            Ok(Grid::from_fn(3, 2, |x, y| (count + x + 10 * y) as f32))
        };
        for threads in [1, 2, 3, 8] {
            let mut shares = Vec::new();
            let out = solve_members(threads, &counts, member, &mut |share| shares.push(share));
            assert_eq!(out.len(), counts.len(), "{threads} threads");
            for (&count, result) in counts.iter().zip(&out) {
                match result {
                    Ok(grid) => assert_eq!(*grid.get(2, 1), (count + 12) as f32),
                    Err(e) => assert!(count == 1600 && e.to_string().contains("1600")),
                }
            }
            assert_eq!(shares.len(), counts.len(), "{threads} threads: {shares:?}");
            assert_eq!(shares[0], 0.0);
            assert!(shares.windows(2).all(|w| w[0] < w[1]) && shares.iter().all(|&s| s < 1.0));
        }
    }

    #[test]
    fn parameters_saved_without_newer_fields_keep_their_defaults() {
        // Parameters as an older version saved them: no `min_reliable_flow`, another k.
        let mut old = serde_json::to_value(Params::default()).unwrap();
        let object = old.as_object_mut().unwrap();
        object.remove("min_reliable_flow");
        object.insert("k".into(), 9.into());
        let params: Params = serde_json::from_value(old).unwrap();
        assert_eq!(params.k, 9);
        assert_eq!(
            params.min_reliable_flow,
            Params::default().min_reliable_flow
        );
        assert_eq!(params.scales, ScaleParams::default());
    }
}
