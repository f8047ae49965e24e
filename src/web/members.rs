//! The fusion's members ([`crate::soup::ensemble`]) made in Web Workers of their own. A wasm
//! instance runs on one thread, so in the page's worker the four members of a run would take
//! their turns (natively they run on threads); each member depends only on what the kept
//! reconstruction saw (frame 1, the flow and its trusted vectors, the intrinsics) and on the
//! options, so other workers can make them at the same time:
//!
//! ```js
//! const result = await reconstructUnfused(one, two, optionsJson, progress, directions); // the kept pass
//! const counts = result.memberCounts();        // the members' superpixel counts
//! const inputs = result.memberInputs();        // frame, flow, reliable, intrinsics
//! // in each helper worker, for some of the counts:
//! const source = new MemberSource(optionsJson, inputs.width, inputs.height,
//!                                 inputs.intrinsics, inputs.frame, inputs.flow, inputs.reliable);
//! const vote = source.vote(count);
//! // in the first worker, for the others: result.memberVote(count)
//! // there, one per count in the order of the counts:
//! result.addVote(vote.width, vote.height, vote.depth, vote.pinned); // or addFailure(message)
//! result.fuse(membersMs);                      // the finished result, as reconstruct()'s
//! ```
//!
//! The votes are the library's ([`crate::pipeline::member_vote`]) and the fusion is
//! [`crate::pipeline::fuse_votes`]: the result is the same, bit for bit, as that of
//! [`super::reconstruct::reconstruct`], however many workers made the members.

use js_sys::{Float32Array, Float64Array, Uint8Array, Uint32Array};
use wasm_bindgen::prelude::*;

use super::reconstruct::{PageReconstruction, js_error, parse_options};
use crate::Grid;
use crate::camera::Intrinsics;
use crate::error::Error;
use crate::flow::FlowField;
use crate::image::Frame;
use crate::pipeline::{Observed, Params, fuse_votes, member_counts, member_vote};
use crate::soup::ensemble::{SAMPLE_STRIDE, Vote};

/// What the members of a run are made from, as JavaScript arrays (copies, to post to other
/// workers): the kept reconstruction's frame 1, flow and trusted vectors at the working
/// resolution and its intrinsics.
#[wasm_bindgen]
pub struct MemberInputs {
    width: u32,
    height: u32,
    intrinsics: Float64Array,
    frame: Uint8Array,
    flow: Float32Array,
    reliable: Uint8Array,
}

#[wasm_bindgen]
impl MemberInputs {
    /// Width of the working resolution, in pixels.
    #[wasm_bindgen(getter)]
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height of the working resolution, in pixels.
    #[wasm_bindgen(getter)]
    pub fn height(&self) -> u32 {
        self.height
    }

    /// `Float64Array` `[fx, fy, cx, cy]`, the intrinsics at the working resolution (pixels).
    #[wasm_bindgen(getter)]
    pub fn intrinsics(&self) -> Float64Array {
        self.intrinsics.clone()
    }

    /// `Uint8Array`, frame 1 as r, g, b per pixel, row by row.
    #[wasm_bindgen(getter)]
    pub fn frame(&self) -> Uint8Array {
        self.frame.clone()
    }

    /// `Float32Array`, the flow 1→2 as u, v per pixel (pixels; NaN where unknown).
    #[wasm_bindgen(getter)]
    pub fn flow(&self) -> Float32Array {
        self.flow.clone()
    }

    /// `Uint8Array`, 1 where the flow vector is trusted, else 0, per pixel.
    #[wasm_bindgen(getter)]
    pub fn reliable(&self) -> Uint8Array {
        self.reliable.clone()
    }
}

/// One member's vote as JavaScript arrays: its frame-1 depth at every
/// [`crate::soup::ensemble::SAMPLE_STRIDE`]-th pixel (`width × height` of that grid) and where
/// that depth is pinned.
#[wasm_bindgen]
pub struct VoteBuffers {
    width: u32,
    height: u32,
    depth: Float32Array,
    pinned: Uint8Array,
}

#[wasm_bindgen]
impl VoteBuffers {
    /// Width of the sampled grid.
    #[wasm_bindgen(getter)]
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height of the sampled grid.
    #[wasm_bindgen(getter)]
    pub fn height(&self) -> u32 {
        self.height
    }

    /// `Float32Array`, the depth per sampled pixel (any global scale; NaN or ≤ 0 = unknown).
    #[wasm_bindgen(getter)]
    pub fn depth(&self) -> Float32Array {
        self.depth.clone()
    }

    /// `Uint8Array`, 1 where the depth's scale is pinned, 0 where it is a guess.
    #[wasm_bindgen(getter)]
    pub fn pinned(&self) -> Uint8Array {
        self.pinned.clone()
    }
}

/// What a helper worker makes members from: a run's [`MemberInputs`] and its options (the same
/// JSON [`RunOptions`](super::reconstruct::RunOptions) the run was given: the members use its
/// parameters), held once in this instance's memory for all the members it makes.
#[wasm_bindgen]
pub struct MemberSource {
    frame: Frame,
    k: Intrinsics,
    flow: FlowField,
    reliable: Grid<bool>,
    params: Params,
}

#[wasm_bindgen]
impl MemberSource {
    /// From [`MemberInputs`]' `width`, `height`, `intrinsics`, `frame`, `flow` and `reliable`
    /// and the run's options. Throws an `InvalidParameterError` when the arrays do not fit the
    /// size, or the options cannot be read or hold a parameter out of its range (as
    /// `reconstruct` does).
    #[wasm_bindgen(constructor)]
    pub fn new(
        options: &str,
        width: u32,
        height: u32,
        intrinsics: &[f64],
        frame: Vec<u8>,
        flow: Vec<f32>,
        reliable: Vec<u8>,
    ) -> Result<MemberSource, JsValue> {
        let options = parse_options(options)?;
        let &[fx, fy, cx, cy] = intrinsics else {
            return Err(js_error(Error::InvalidParameter(format!(
                "a member's intrinsics are [fx, fy, cx, cy], not {} numbers",
                intrinsics.len()
            ))));
        };
        let (w, h) = (width as usize, height as usize);
        for (name, len, per_pixel) in [
            ("frame", frame.len(), 3),
            ("flow", flow.len(), 2),
            ("reliable", reliable.len(), 1),
        ] {
            if len != per_pixel * w * h {
                return Err(js_error(Error::InvalidParameter(format!(
                    "a member's {name} of {w}×{h} pixels has {per_pixel} values per pixel, not {len} in all"
                ))));
            }
        }
        // Each array is dropped once converted (`grid` takes it): the members reuse its memory.
        let frame = grid(w, h, frame, |v| [v[0], v[1], v[2]], 3);
        let flow = grid(w, h, flow, |v| [v[0], v[1]], 2);
        let reliable = grid(w, h, reliable, |v| v[0] != 0, 1);
        Ok(MemberSource {
            frame: frame.map_err(js_error)?,
            k: Intrinsics { fx, fy, cx, cy },
            flow: flow.map_err(js_error)?,
            reliable: reliable.map_err(js_error)?,
            params: options.params,
        })
    }

    /// The vote of the member made from `count` superpixels
    /// ([`crate::pipeline::member_vote`]); throws the library's error, named as by
    /// `reconstruct`, when it cannot be made.
    pub fn vote(&self, count: u32) -> Result<VoteBuffers, JsValue> {
        let seen = Observed {
            frame1: &self.frame,
            k: &self.k,
            flow: &self.flow,
            reliable: &self.reliable,
        };
        vote_buffers(seen, &self.params, count)
    }
}

/// [`member_vote`] as [`VoteBuffers`].
fn vote_buffers(seen: Observed, params: &Params, count: u32) -> Result<VoteBuffers, JsValue> {
    let vote = member_vote(seen, params, count as usize).map_err(js_error)?;
    let pinned: Vec<u8> = vote.pinned.data().iter().map(|&p| u8::from(p)).collect();
    Ok(VoteBuffers {
        width: vote.depth.width() as u32,
        height: vote.depth.height() as u32,
        depth: Float32Array::from(vote.depth.data()),
        pinned: Uint8Array::from(pinned.as_slice()),
    })
}

/// A `w × h` grid of `values`, `per_pixel` of them per pixel made into one by `pixel`
/// (`values` has `per_pixel · w · h`, checked by the caller); `values` is dropped on return.
pub(super) fn grid<T: Copy, P>(
    w: usize,
    h: usize,
    values: Vec<T>,
    pixel: impl Fn(&[T]) -> P,
    per_pixel: usize,
) -> crate::Result<Grid<P>> {
    Grid::from_vec(w, h, values.chunks_exact(per_pixel).map(pixel).collect())
}

/// Thrown by the fusion's methods on a result that is already finished.
fn finished() -> JsValue {
    js_error(Error::InvalidParameter(
        "this reconstruction is finished: its members were fused".into(),
    ))
}

impl PageReconstruction {
    /// Adds the next member's vote; throws when the result is finished or has all its votes.
    fn push_vote(&mut self, vote: Result<Vote, String>) -> Result<(), JsValue> {
        let members = member_counts(&self.rec.report.params).len();
        let votes = self.votes.as_mut().ok_or_else(finished)?;
        if votes.len() >= members {
            return Err(js_error(Error::InvalidParameter(format!(
                "this run fuses {members} members; their votes are all in"
            ))));
        }
        votes.push(vote);
        Ok(())
    }
}

#[wasm_bindgen]
impl PageReconstruction {
    /// `Uint32Array`, the superpixel counts of this run's members, in the order their votes are
    /// added (empty when the options fuse no members).
    #[wasm_bindgen(js_name = memberCounts)]
    pub fn member_counts(&self) -> Uint32Array {
        let counts: Vec<u32> = (member_counts(&self.rec.report.params).iter())
            .map(|&c| c as u32)
            .collect();
        Uint32Array::from(counts.as_slice())
    }

    /// The vote of this run's member made from `count` superpixels, made here (from this
    /// reconstruction's inputs, without copies); as [`MemberSource::vote`].
    #[wasm_bindgen(js_name = memberVote)]
    pub fn member_vote(&self, count: u32) -> Result<VoteBuffers, JsValue> {
        vote_buffers(self.rec.observed(), &self.rec.report.params, count)
    }

    /// What this run's members are made from ([`MemberInputs`], copies, for helper workers'
    /// [`MemberSource`]s).
    #[wasm_bindgen(js_name = memberInputs)]
    pub fn member_inputs(&self) -> MemberInputs {
        let seen = self.rec.observed();
        let (w, h) = seen.frame1.size();
        let k = seen.k;
        let reliable: Vec<u8> = seen.reliable.data().iter().map(|&r| u8::from(r)).collect();
        MemberInputs {
            width: w as u32,
            height: h as u32,
            intrinsics: Float64Array::from([k.fx, k.fy, k.cx, k.cy].as_slice()),
            frame: Uint8Array::from(seen.frame1.data().as_flattened()),
            flow: Float32Array::from(seen.flow.data().as_flattened()),
            reliable: Uint8Array::from(reliable.as_slice()),
        }
    }

    /// Adds the next member's vote (its [`VoteBuffers`]' `width`, `height`, `depth`, `pinned`),
    /// in the order of [`Self::member_counts`]. Throws when the arrays do not fit the size or
    /// the result is finished.
    #[wasm_bindgen(js_name = addVote)]
    pub fn add_vote(
        &mut self,
        width: u32,
        height: u32,
        depth: &[f32],
        pinned: &[u8],
    ) -> Result<(), JsValue> {
        let (w, h) = (width as usize, height as usize);
        let (sw, sh) = self.rec.frame1.size();
        let s = SAMPLE_STRIDE;
        if (w, h) != (sw.div_ceil(s), sh.div_ceil(s)) {
            return Err(js_error(Error::InvalidParameter(format!(
                "a member's vote is {w}×{h}; this run's are {}×{}",
                sw.div_ceil(s),
                sh.div_ceil(s)
            ))));
        }
        let depth = Grid::from_vec(w, h, depth.to_vec()).map_err(js_error)?;
        let pinned = pinned.iter().map(|&p| p != 0).collect();
        let pinned = Grid::from_vec(w, h, pinned).map_err(js_error)?;
        self.push_vote(Ok(Vote { depth, pinned }))
    }

    /// Adds the next member as one that could not be made, with why (`message`); the fusion
    /// leaves it out and the report says so. Throws when the result is finished.
    #[wasm_bindgen(js_name = addFailure)]
    pub fn add_failure(&mut self, message: &str) -> Result<(), JsValue> {
        self.push_vote(Err(message.to_string()))
    }

    /// Fuses the votes added (a member without one is left out, with a note) and finishes the
    /// result, which is then as [`super::reconstruct::reconstruct`]'s; `members_ms` is the time
    /// the members took, counted in the report's fusion time. Throws when already finished.
    pub fn fuse(&mut self, members_ms: f64) -> Result<(), JsValue> {
        let votes = self.votes.take().ok_or_else(finished)?;
        fuse_votes(&mut self.rec, votes, members_ms);
        self.finish();
        Ok(())
    }
}
