//! Dense optical flow between two frames, and the flow field type shared by every stage.
//!
//! [`compute_flow`] runs DIS ([`dis`]: coarse-to-fine patch search, densification and
//! [`variational`] refinement on a grey [`pyramid`]) from frame 1 to frame 2 and back, moves
//! each field's motion boundaries onto its frame's colour edges ([`edges`]), and marks the
//! vectors that survive the forward–backward check ([`consistency`]). [`colour`] draws a
//! field with the Middlebury colour wheel.
//!
//! Conventions: flow f(u, v) = (u′ − u, v′ − v) maps a pixel of frame 1 to frame 2, pixel centres
//! at integers, u right, v down, in pixels of the frames. Everything is single-threaded and
//! deterministic: the same frames give bit-identical flow.

pub mod colour;
pub mod consistency;
pub mod dis;
pub mod edges;
mod lanes;
pub mod pyramid;
pub mod variational;

pub use dis::{DisParams, Preset};
pub use edges::EdgeParams;

use crate::error::{Error, Result};
use crate::grid::Grid;
use crate::image::{Frame, to_gray};

/// Dense flow from frame 1 to frame 2 in pixels: element (u, v) is `[u' − u, v' − v]`.
/// Unknown vectors are NaN (written to `.flo` as 1e10).
pub type FlowField = Grid<[f32; 2]>;

/// True when a flow vector is known (both components finite).
#[inline]
pub fn is_known(f: [f32; 2]) -> bool {
    f[0].is_finite() && f[1].is_finite()
}

/// `flow` (defined on a grid of its own size) resampled to `width × height`, with vectors scaled by
/// the size ratio. Pixel centres map as x' = (x + 0.5)·s − 0.5; each output vector is the bilinear
/// mix of the known input vectors around it (NaN where none is known).
pub fn resize_flow(flow: &FlowField, width: usize, height: usize) -> FlowField {
    if flow.size() == (width, height) {
        return flow.clone();
    }
    let sx = width as f32 / flow.width() as f32;
    let sy = height as f32 / flow.height() as f32;
    Grid::from_fn(width, height, |x, y| {
        let fx = ((x as f32 + 0.5) / sx - 0.5).clamp(0.0, (flow.width() - 1) as f32);
        let fy = ((y as f32 + 0.5) / sy - 0.5).clamp(0.0, (flow.height() - 1) as f32);
        let (x0, y0, ax, ay) = crate::grid::bilinear_cell(fx, fy, flow.width(), flow.height());
        let (x1, y1) = (
            (x0 + 1).min(flow.width() - 1),
            (y0 + 1).min(flow.height() - 1),
        );
        let mut sum = [0.0f32; 2];
        let mut weight = 0.0;
        for (xx, yy, w) in [
            (x0, y0, (1.0 - ax) * (1.0 - ay)),
            (x1, y0, ax * (1.0 - ay)),
            (x0, y1, (1.0 - ax) * ay),
            (x1, y1, ax * ay),
        ] {
            let f = *flow.get(xx, yy);
            if is_known(f) && w > 0.0 {
                sum[0] += w * f[0];
                sum[1] += w * f[1];
                weight += w;
            }
        }
        if weight > 0.0 {
            [sum[0] / weight * sx, sum[1] / weight * sy]
        } else {
            [f32::NAN; 2]
        }
    })
}

/// Everything [`compute_flow`] needs: the DIS parameters of a preset, the motion-edge
/// sharpening's settings and the forward–backward tolerance.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FlowParams {
    pub dis: DisParams,
    /// Absolute part of the forward–backward tolerance, in pixels.
    pub fb_threshold: f32,
    /// Part of the tolerance that grows with the motion: this share of ‖f(x)‖.
    pub fb_relative: f32,
    /// How motion boundaries are sharpened along colour edges before the check.
    pub edges: EdgeParams,
}

impl FlowParams {
    /// The DIS parameters of `preset` with the default forward–backward tolerance,
    /// 0.5 px + 2 % of the motion: on the synthetic scenes and middlebury-motorcycle it keeps
    /// 70–90 % of the vectors and gives the soup lower motion and plane errors than looser
    /// tolerances (1 px + 5 %).
    pub fn preset(preset: Preset) -> Self {
        FlowParams {
            dis: DisParams::preset(preset),
            fb_threshold: 0.5,
            fb_relative: 0.02,
            edges: EdgeParams::default(),
        }
    }

    /// Fails with [`Error::InvalidParameter`] for values the algorithm cannot run with.
    pub fn validate(&self) -> Result<()> {
        self.dis.validate()?;
        self.edges.validate()?;
        if !(self.fb_threshold >= 0.0 && self.fb_relative >= 0.0) {
            return Err(Error::InvalidParameter(format!(
                "forward–backward tolerance {} px + {}·|f| must be ≥ 0",
                self.fb_threshold, self.fb_relative
            )));
        }
        Ok(())
    }

    /// The next finer preset ([`Preset::finer`]: fast → medium → high, fine → high) with this
    /// forward–backward tolerance, when the DIS parameters are those of a preset other than
    /// `high`; `None` otherwise (custom parameters are kept as given).
    pub fn finer(&self) -> Option<FlowParams> {
        let next = self.named_preset()?.finer()?;
        Some(FlowParams {
            dis: DisParams::preset(next),
            ..*self
        })
    }

    /// The preset whose DIS parameters these are, if any.
    pub fn named_preset(&self) -> Option<Preset> {
        Preset::ALL
            .into_iter()
            .find(|&p| DisParams::preset(p) == self.dis)
    }
}

/// Share of the pixels of `mask` that are trusted (true), in [0, 1]; 0 for an empty mask.
pub fn trusted_share(mask: &Grid<bool>) -> f64 {
    mask.data().iter().filter(|&&r| r).count() as f64 / mask.len().max(1) as f64
}

impl Default for FlowParams {
    fn default() -> Self {
        FlowParams::preset(Preset::default())
    }
}

/// Flow both ways between two frames and where it can be trusted.
#[derive(Clone, Debug)]
pub struct FlowPair {
    /// Flow frame 1 → frame 2.
    pub forward: FlowField,
    /// Flow frame 2 → frame 1 (defined on frame 2's pixels).
    pub backward: FlowField,
    /// True where the forward vector passes the forward–backward check (on frame 1's pixels).
    pub reliable: Grid<bool>,
}

/// The share of one direction's flow time that DIS takes; the motion-edge sharpening takes the
/// rest (measured at preset high, `cargo bench --bench flow`: 921 ms for the whole flow, 208 ms
/// of it the sharpening of both directions, so about 0.78 per direction is DIS).
const DIS_SHARE: f32 = 0.8;

/// Dense flow frame 1 → 2 and 2 → 1 with the forward–backward mask. `progress` gets the share of
/// the work done, in [0, 1].
///
/// Errors: [`Error::SizeMismatch`] when the frames differ in size, [`Error::TooSmall`] when a side
/// is shorter than a patch (8 pixels), [`Error::InvalidParameter`] for invalid parameters.
/// Identical frames give zero flow; textureless frames give a finite (zero) field.
pub fn compute_flow(
    frame1: &Frame,
    frame2: &Frame,
    params: &FlowParams,
    progress: &mut dyn FnMut(f32),
) -> Result<FlowPair> {
    let (pyramid1, pyramid2, finest) = pyramids(frame1, frame2, params)?;
    progress(0.0);
    // Each direction is half the work.
    let forward = direction(&pyramid1, &pyramid2, frame1, finest, params, &mut |f| {
        progress(0.5 * f)
    })?;
    let backward = direction(&pyramid2, &pyramid1, frame2, finest, params, &mut |f| {
        progress(0.5 + 0.5 * f)
    })?;
    let pair = pair_from_directions(forward, backward, params)?;
    progress(1.0);
    Ok(pair)
}

/// One direction of [`compute_flow`]: the flow from frame `from` to frame `to` (the same bits as
/// that direction of `compute_flow`, so the two directions can be computed apart, in two of the
/// page's workers at once, and joined by [`pair_from_directions`]). Errors as `compute_flow`'s.
pub fn compute_direction(
    from: &Frame,
    to: &Frame,
    params: &FlowParams,
    progress: &mut dyn FnMut(f32),
) -> Result<FlowField> {
    let (pyramid_from, pyramid_to, finest) = pyramids(from, to, params)?;
    progress(0.0);
    direction(&pyramid_from, &pyramid_to, from, finest, params, progress)
}

/// Both directions of a flow (as [`compute_direction`] makes them, `params` those they were
/// made with) with the forward–backward mask: what [`compute_flow`] returns.
/// Errors: [`Error::InvalidParameter`] when the fields differ in size or for invalid
/// parameters.
pub fn pair_from_directions(
    forward: FlowField,
    backward: FlowField,
    params: &FlowParams,
) -> Result<FlowPair> {
    params.validate()?;
    if forward.size() != backward.size() {
        return Err(Error::InvalidParameter(format!(
            "the flow's directions differ in size: {}×{} forward, {}×{} backward",
            forward.width(),
            forward.height(),
            backward.width(),
            backward.height()
        )));
    }
    let reliable = consistency::forward_backward_mask(
        &forward,
        &backward,
        params.fb_threshold,
        params.fb_relative,
    )?;
    Ok(FlowPair {
        forward,
        backward,
        reliable,
    })
}

/// The grey pyramids of two frames over the levels DIS computes, and the finest of those
/// levels, once the frames and parameters are checked: same size, valid parameters, sides of at
/// least a patch.
fn pyramids(
    frame1: &Frame,
    frame2: &Frame,
    params: &FlowParams,
) -> Result<(Vec<pyramid::Level>, Vec<pyramid::Level>, usize)> {
    frame1.check_same_size(frame2)?;
    params.validate()?;
    let (w, h) = frame1.size();
    let (finest, coarsest) = dis::levels(w, h, &params.dis).ok_or(Error::TooSmall {
        width: w,
        height: h,
        min: dis::PATCH,
    })?;
    let build = |frame| pyramid::build(&to_gray(frame), finest, coarsest);
    Ok((build(frame1), build(frame2), finest))
}

/// The flow from the frame of pyramid `from` (its colour frame `colour`) to that of `to` at full
/// resolution: DIS on the pyramids' first level, `finest` (level 0: full resolution), motion
/// edges sharpened there (with the colour frame at that level, in that level's pixels), then
/// brought to full resolution.
/// `progress` goes from 0 to 1: DIS its first [`DIS_SHARE`], the sharpening the rest.
fn direction(
    from: &[pyramid::Level],
    to: &[pyramid::Level],
    colour: &Frame,
    finest: usize,
    params: &FlowParams,
    progress: &mut dyn FnMut(f32),
) -> Result<FlowField> {
    let (w, h) = colour.size();
    let (lw, lh) = pyramid::level_size(w, h, finest);
    let (u, v) = dis::dis_flow(from, to, &params.dis, &mut |f| progress(DIS_SHARE * f));
    let data = u.iter().zip(&v).map(|(&u, &v)| [u, v]).collect();
    let halved;
    let colour = if finest == 0 {
        colour
    } else {
        halved = edges::halve_frame(colour, finest);
        &halved
    };
    let level = edges::sharpen_motion_edges(&Grid::from_vec(lw, lh, data)?, colour, &params.edges)?;
    progress(1.0);
    if finest == 0 {
        return Ok(level);
    }
    let factor = (1u32 << finest) as f32;
    let (u, v): (Vec<f32>, Vec<f32>) = level.data().iter().map(|f| (f[0], f[1])).unzip();
    let u = pyramid::upsample(&u, lw, lh, w, h, factor);
    let v = pyramid::upsample(&v, lw, lh, w, h, factor);
    let data = u.into_iter().zip(v).map(|(u, v)| [u, v]).collect();
    Grid::from_vec(w, h, data)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finer_presets_chain_up_to_high_and_keep_the_tolerance() {
        let fast = FlowParams {
            fb_threshold: 0.7,
            ..FlowParams::preset(Preset::Fast)
        };
        let medium = fast.finer().unwrap();
        assert_eq!(medium.dis, DisParams::preset(Preset::Medium));
        assert_eq!(medium.fb_threshold, 0.7);
        let high = medium.finer().unwrap();
        assert_eq!(high.named_preset(), Some(Preset::High));
        assert_eq!(high.finer(), None);
        let custom = FlowParams {
            dis: DisParams {
                iterations: 3,
                ..DisParams::preset(Preset::Fast)
            },
            ..fast
        };
        assert_eq!(custom.finer(), None);
        assert_eq!(custom.named_preset(), None);
    }

    #[test]
    fn resizing_scales_vectors_and_keeps_unknowns() {
        let flow = Grid::from_fn(
            8,
            4,
            |x, _| if x == 0 { [f32::NAN; 2] } else { [2.0, -1.0] },
        );
        let half = resize_flow(&flow, 4, 2);
        assert_eq!(*half.get(3, 1), [1.0, -0.5]);
        let double = resize_flow(&flow, 16, 8);
        assert!(double.get(0, 0)[0].is_nan());
        assert_eq!(*double.get(10, 3), [4.0, -2.0]);
    }
}
