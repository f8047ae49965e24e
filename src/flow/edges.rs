//! Motion boundaries sharpened along colour edges.
//!
//! Patch-based flow smears a motion boundary over a few pixels: the patches that straddle it
//! average the two motions, and the smoothness term spreads the mix further. Measured on the
//! synthetic scenes (preset high), the median end-point error is 2.4–3.1 px on the boundary,
//! 0.4–1.1 px 1.5–2.5 px from it and 0.03–0.08 px in the interiors. Downstream, a superpixel at
//! a walker's feet then gets the walker's motion and a plane that bridges the walker and the
//! floor (docs/ARCHITECTURE.md, Pitfalls).
//!
//! Here every pixel within [`EdgeParams::band`] of a flow jump takes, per component, the
//! weighted median of the flow in a window around it, each vote weighted by its colour
//! similarity (CIELAB) and spatial closeness; votes from pixels that are themselves in the band
//! count [`EdgeParams::band_vote`] as much. The answer comes from the interiors of the regions
//! the pixel looks like, so the boundary moves to the colour edge (the weighted median near
//! motion boundaries of Sun, Roth and Black, "Secrets of optical flow estimation", CVPR 2010).
//! Away from flow jumps nothing changes.
//!
//! Flow in pixels; the frame is the one the flow is defined on (frame 1 for the forward flow), at
//! the flow's resolution: [`super::compute_flow`] sharpens on the finest pyramid level DIS
//! computes (full resolution with preset high, half with medium, a quarter with fast), before
//! the field is brought to full resolution, so the band and window are in that level's pixels.

use crate::error::{Error, Result};
use crate::grid::Grid;
use crate::image::{Frame, to_lab};
use crate::numeric::{exp, hypot_f32};

use super::FlowField;

/// Settings of [`sharpen_motion_edges`]. Each value was measured over five seeds on the nine
/// evaluation cases (docs/RESULTS.md, stop 42).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct EdgeParams {
    /// 4-neighbours whose vectors differ by more than this (px) ...
    pub jump_px: f32,
    /// ... plus this share of the longer vector mark a motion boundary: 0.5 px + 2 %, the
    /// forward–backward check's tolerance, a difference the flow's noise inside a surface does
    /// not reach.
    pub jump_relative: f32,
    /// Pixels within this Chebyshev distance (px) of a boundary are estimated again; 0 turns
    /// the sharpening off. 3 px: the smear's median error falls to 0.3–0.8 px at 2.5–3.5 px from
    /// the boundary; bands of 2 and 5 px gave the soup a higher error than 3 (the crowd 0.122 and
    /// 0.123 against 0.101 over five seeds, measured with an earlier form that sharpened after
    /// upsampling to full resolution).
    pub band: usize,
    /// Half-size (px) of the voting window: 7 reaches 4 px past the band into the interiors. At
    /// most [`MAX_RADIUS`].
    pub radius: usize,
    /// Colour scale σ_c of the vote weights exp(−ΔE² / 2σ_c²), CIELAB units: 7 (Sun et al.'s
    /// value); 14 mixed more across colour edges (over five seeds, in the earlier form above: the
    /// table 0.0208 → 0.0227, FlyingThings3D 0.316 → 0.358). At least [`MIN_SIGMA_COLOUR`].
    pub sigma_colour: f32,
    /// Spatial scale σ_s (px) of the vote weights exp(−d² / 2σ_s²): 7, about the window.
    pub sigma_space: f32,
    /// Weight factor of votes from pixels inside the band (their own flow is the smeared one).
    /// 0.05: low enough that interiors outvote them, high enough that a thin part with no
    /// interior within reach (a leg, a pole) keeps its own flow; 0.01 gave FlyingThings3D 0.386
    /// against 0.316 over five seeds (earlier form).
    pub band_vote: f32,
}

/// The largest window half-size [`EdgeParams::validate`] accepts (px): 32 already costs 20×
/// the default's votes.
pub const MAX_RADIUS: usize = 32;

/// The smallest colour scale σ_c [`EdgeParams::validate`] accepts (CIELAB units): below it the
/// weight table's scale overflows, and no colour difference under one unit means anything.
pub const MIN_SIGMA_COLOUR: f32 = 0.01;

impl Default for EdgeParams {
    fn default() -> Self {
        EdgeParams {
            jump_px: 0.5,
            jump_relative: 0.02,
            band: 3,
            radius: 7,
            sigma_colour: 7.0,
            sigma_space: 7.0,
            band_vote: 0.05,
        }
    }
}

impl EdgeParams {
    /// Fails with [`Error::InvalidParameter`] for values the filter cannot use.
    pub fn validate(&self) -> Result<()> {
        let positive = [
            ("colour scale σ_c", self.sigma_colour),
            ("spatial scale σ_s", self.sigma_space),
        ];
        for (name, value) in positive {
            if !(value.is_finite() && value > 0.0) {
                return Err(Error::InvalidParameter(format!(
                    "motion-edge {name} = {value} must be finite and > 0"
                )));
            }
        }
        let non_negative = [
            ("jump", self.jump_px),
            ("relative jump", self.jump_relative),
        ];
        for (name, value) in non_negative {
            if !(value.is_finite() && value >= 0.0) {
                return Err(Error::InvalidParameter(format!(
                    "motion-edge {name} = {value} must be finite and ≥ 0"
                )));
            }
        }
        if !(self.band_vote > 0.0 && self.band_vote <= 1.0) {
            return Err(Error::InvalidParameter(format!(
                "motion-edge band vote = {} must be in (0, 1]",
                self.band_vote
            )));
        }
        if self.radius > MAX_RADIUS {
            return Err(Error::InvalidParameter(format!(
                "motion-edge window half-size {} px is above {MAX_RADIUS} px",
                self.radius
            )));
        }
        if self.sigma_colour < MIN_SIGMA_COLOUR {
            return Err(Error::InvalidParameter(format!(
                "motion-edge colour scale σ_c = {} is below {MIN_SIGMA_COLOUR}",
                self.sigma_colour
            )));
        }
        if self.band > self.radius {
            return Err(Error::InvalidParameter(format!(
                "motion-edge band {} px must not exceed the window's half-size {} px",
                self.band, self.radius
            )));
        }
        Ok(())
    }
}

/// True where a pixel lies within `params.band` (Chebyshev distance, px) of a motion boundary of
/// `flow`: a pair of 4-neighbours whose vectors differ by more than `jump_px` + `jump_relative`
/// × the longer one (both pixels of such a pair are on the boundary).
pub fn boundary_band(flow: &FlowField, params: &EdgeParams) -> Grid<bool> {
    let (w, h) = flow.size();
    let jump = |a: [f32; 2], b: [f32; 2]| {
        let longer = hypot_f32(a[0], a[1]).max(hypot_f32(b[0], b[1]));
        hypot_f32(a[0] - b[0], a[1] - b[1]) > params.jump_px + params.jump_relative * longer
    };
    let vectors = flow.data();
    let mut edge = Grid::filled(w, h, false);
    let marks = edge.data_mut();
    for at in 0..w * h {
        let f = vectors[at];
        let right = (at % w + 1 < w).then(|| at + 1);
        let below = (at + w < w * h).then(|| at + w);
        for next in [right, below].into_iter().flatten() {
            if jump(f, vectors[next]) {
                marks[at] = true;
                marks[next] = true;
            }
        }
    }
    edge.dilated(params.band)
}

/// `flow` with every pixel near a motion boundary ([`boundary_band`]) replaced, per component,
/// by the weighted median of the flow in its (2·radius + 1)² window (see the module's
/// documentation). `frame` is the image the flow is defined on, of the same size. With
/// `params.band` 0 the flow comes back unchanged.
///
/// Errors: [`Error::SizeMismatch`] when `frame` and `flow` differ in size,
/// [`Error::InvalidParameter`] for invalid `params`.
pub fn sharpen_motion_edges(
    flow: &FlowField,
    frame: &Frame,
    params: &EdgeParams,
) -> Result<FlowField> {
    flow.check_same_size(frame)?;
    params.validate()?;
    if params.band == 0 {
        return Ok(flow.clone());
    }
    let (w, h) = flow.size();
    let band = boundary_band(flow, params);
    let lab = to_lab(frame);
    let r = params.radius as isize;
    let colour_weight = ColourWeights::new(params.sigma_colour);
    let inv_space = 1.0 / (2.0 * f64::from(params.sigma_space).powi(2));
    // Window offsets (dx, dy) with their spatial weights.
    let window: Vec<(isize, isize, f32)> = (-r..=r)
        .flat_map(|dy| (-r..=r).map(move |dx| (dx, dy)))
        .map(|(dx, dy)| {
            (
                dx,
                dy,
                exp(-((dx * dx + dy * dy) as f64) * inv_space) as f32,
            )
        })
        .collect();
    let (lab, in_band, vectors) = (lab.data(), band.data(), flow.data());
    let mut out = flow.clone();
    let mut votes_u: Vec<(f32, u32)> = Vec::with_capacity(window.len());
    let mut votes_v: Vec<(f32, u32)> = Vec::with_capacity(window.len());
    for (at, _) in in_band.iter().enumerate().filter(|(_, b)| **b) {
        let (x, y) = ((at % w) as isize, (at / w) as isize);
        let c = lab[at];
        votes_u.clear();
        votes_v.clear();
        for &(dx, dy, spatial) in &window {
            let (xx, yy) = (x + dx, y + dy);
            if xx < 0 || yy < 0 || xx >= w as isize || yy >= h as isize {
                continue;
            }
            let q_at = yy as usize * w + xx as usize;
            let q = lab[q_at];
            let d2 = (c[0] - q[0]) * (c[0] - q[0])
                + (c[1] - q[1]) * (c[1] - q[1])
                + (c[2] - q[2]) * (c[2] - q[2]);
            let Some(colour) = colour_weight.at(d2) else {
                continue;
            };
            let weight = if in_band[q_at] {
                spatial * colour * params.band_vote
            } else {
                spatial * colour
            };
            let weight = fixed_point_weight(weight);
            let f = vectors[q_at];
            votes_u.push((f[0], weight));
            votes_v.push((f[1], weight));
        }
        // The pixel itself always votes, so neither list is empty.
        out.data_mut()[at] = [
            weighted_median_f32(&mut votes_u),
            weighted_median_f32(&mut votes_v),
        ];
    }
    Ok(out)
}

/// `frame` halved `levels` times by 2 × 2 box averaging (rounded), a last odd row or column
/// dropped each time: the colour image of a flow pyramid's level ([`super::pyramid::build`]
/// halves the grey frame the same way).
pub fn halve_frame(frame: &Frame, levels: usize) -> Frame {
    let mut out = frame.clone();
    for _ in 0..levels {
        let (w, h) = (out.width() / 2, out.height() / 2);
        out = Grid::from_fn(w, h, |x, y| {
            let mut sum = [0u32; 3];
            for (xx, yy) in [
                (2 * x, 2 * y),
                (2 * x + 1, 2 * y),
                (2 * x, 2 * y + 1),
                (2 * x + 1, 2 * y + 1),
            ] {
                let p = out.get(xx, yy);
                for c in 0..3 {
                    sum[c] += u32::from(p[c]);
                }
            }
            sum.map(|s| ((s + 2) / 4) as u8)
        });
    }
    out
}

/// exp(−ΔE² / 2σ_c²) by table: the exponent in steps of 1/[`ColourWeights::STEPS_PER_UNIT`]
/// (weights within 0.2 % of the exact ones), and nothing beyond [`ColourWeights::CUT`]: votes
/// whose colour weight is below e^−9 (ΔE > 3√2 σ_c) cannot move a median that nearer colours
/// decide, and leaving them out halves the work.
struct ColourWeights {
    table: Vec<f32>,
    scale: f32,
}

impl ColourWeights {
    const CUT: f32 = 9.0;
    const STEPS_PER_UNIT: f32 = 256.0;

    fn new(sigma_colour: f32) -> Self {
        let steps = (Self::CUT * Self::STEPS_PER_UNIT) as usize;
        let table = (0..=steps)
            .map(|i| exp(-(i as f64) / f64::from(Self::STEPS_PER_UNIT)) as f32)
            .collect();
        ColourWeights {
            table,
            scale: Self::STEPS_PER_UNIT / (2.0 * sigma_colour * sigma_colour),
        }
    }

    /// The weight of a squared colour difference `d2` (CIELAB units²), `None` past the cut.
    #[inline]
    fn at(&self, d2: f32) -> Option<f32> {
        self.table.get((d2 * self.scale + 0.5) as usize).copied()
    }
}

/// A vote's weight in (0, 1] as an integer in units of 2⁻²⁴, so that the weighted median's sums
/// are exact: the median then does not depend on the order in which the selection visits the
/// votes (float sums do, in their last bits, and that order is the standard library's choice).
/// Weights below 2⁻²⁴ become 0 and do not vote.
#[inline]
fn fixed_point_weight(weight: f32) -> u32 {
    (weight * FIXED_POINT_ONE) as u32
}

/// 1.0 in [`fixed_point_weight`]'s units.
const FIXED_POINT_ONE: f32 = 16_777_216.0;

/// The weighted median of (value, weight) pairs: the smallest value at which the weight up to
/// and including it reaches half the total; with a total of 0, the smallest value. By
/// quickselect, expected linear time; the list is reordered. The weights are integers
/// ([`fixed_point_weight`]) and their sums exact, so the result is the same whatever order the
/// votes come in or the selection leaves them in. `crate::numeric::weighted_median`, which
/// sorts, is the plain reference it is tested against (they differ only where the weight below
/// a value is exactly half, where that one returns the mean of two values). It exists beside
/// that one for speed: it runs twice for every pixel near a motion edge, on up to 225 votes.
/// `votes` must not be empty.
fn weighted_median_f32(votes: &mut [(f32, u32)]) -> f32 {
    let total: u64 = votes.iter().map(|v| u64::from(v.1)).sum();
    if total == 0 {
        return votes.iter().map(|v| v.0).fold(f32::INFINITY, f32::min);
    }
    // `rest` is twice the weight still to be reached: the median is the first value at which
    // twice the weight up to it reaches the total.
    let mut rest = total;
    let mut slice = votes;
    loop {
        if slice.len() <= 16 {
            slice.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
            let mut below = 0u64;
            for &(value, weight) in slice.iter() {
                below += u64::from(weight);
                if 2 * below >= rest {
                    return value;
                }
            }
            return slice.last().map_or(0.0, |v| v.0);
        }
        let mid = slice.len() / 2;
        let (left, pivot, _) = slice.select_nth_unstable_by(mid, |a, b| a.0.total_cmp(&b.0));
        let below: u64 = left.iter().map(|v| u64::from(v.1)).sum();
        let (value, weight) = (pivot.0, u64::from(pivot.1));
        if 2 * below >= rest {
            slice = &mut slice[..mid];
        } else if 2 * (below + weight) >= rest {
            return value;
        } else {
            rest -= 2 * (below + weight);
            slice = &mut slice[mid + 1..];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 40 × 20 frame, red left of column 20 and blue from it on, with flow (1, 0) on the red
    /// part and (5, −2) on the blue part, smeared linearly over columns 17..23.
    fn two_regions() -> (Frame, FlowField, impl Fn(usize) -> [f32; 2]) {
        let truth = |x: usize| if x < 20 { [1.0, 0.0] } else { [5.0, -2.0] };
        let frame = Grid::from_fn(
            40,
            20,
            |x, _| if x < 20 { [200, 40, 40] } else { [40, 60, 200] },
        );
        let flow = Grid::from_fn(40, 20, |x, _| {
            let t = ((x as f32 - 17.0) / 6.0).clamp(0.0, 1.0);
            let (a, b) = (truth(0), truth(39));
            [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]
        });
        (frame, flow, truth)
    }

    #[test]
    fn a_smeared_boundary_moves_to_the_colour_edge() {
        let (frame, flow, truth) = two_regions();
        let before: f32 = (0..40)
            .map(|x| {
                hypot_f32(
                    flow.get(x, 10)[0] - truth(x)[0],
                    flow.get(x, 10)[1] - truth(x)[1],
                )
            })
            .sum();
        let sharp = sharpen_motion_edges(&flow, &frame, &EdgeParams::default()).unwrap();
        for y in 0..20 {
            for x in 0..40 {
                let (f, t) = (sharp.get(x, y), truth(x));
                assert!(
                    (f[0] - t[0]).abs() < 1e-4 && (f[1] - t[1]).abs() < 1e-4,
                    "({x}, {y}): {f:?} against {t:?}"
                );
            }
        }
        assert!(before > 5.0, "the test's smear is too weak: {before}");
    }

    #[test]
    fn the_fast_weighted_median_agrees_with_the_sorting_one() {
        let mut rng = crate::rng::Rng::new(5);
        for n in [1, 2, 3, 17, 60, 225] {
            for _ in 0..50 {
                let votes: Vec<(f32, u32)> = (0..n)
                    .map(|_| {
                        (
                            (rng.uniform() * 10.0).round() as f32,
                            fixed_point_weight(rng.uniform() as f32 + 1e-3),
                        )
                    })
                    .collect();
                let mut fast = votes.clone();
                // Integer weights are exact in f64, so the reference's sums are exact too.
                let mut plain: Vec<(f64, f64)> = votes
                    .iter()
                    .map(|&(v, w)| (f64::from(w), f64::from(v)))
                    .collect();
                let got = weighted_median_f32(&mut fast);
                let want = crate::numeric::weighted_median(&mut plain).unwrap();
                // The reference takes the mean of two values where the weight below is exactly
                // half; with random weights that does not happen.
                assert_eq!(f64::from(got), want, "{votes:?}");
            }
        }
    }

    #[test]
    fn the_fast_weighted_median_handles_zero_weights_and_equal_values() {
        // Zero weights never decide; a single voter with weight decides alone.
        let mut votes = vec![(5.0, 0), (1.0, 0), (3.0, 2), (-4.0, 0)];
        assert_eq!(weighted_median_f32(&mut votes), 3.0);
        let mut equal = vec![(2.5, 3); 40];
        assert_eq!(weighted_median_f32(&mut equal), 2.5);
        // A heavy vote outweighs many light ones on the other side.
        let mut heavy: Vec<(f32, u32)> = (0..30).map(|i| (i as f32, 1)).collect();
        heavy.push((-1.0, 100));
        assert_eq!(weighted_median_f32(&mut heavy), -1.0);
        // Without any weight, the smallest value.
        let mut none = vec![(4.0, 0), (-2.0, 0), (7.0, 0)];
        assert_eq!(weighted_median_f32(&mut none), -2.0);
        // Exactly half below: the value at which half is reached, not the next one.
        let mut split = vec![(1.0, 5), (9.0, 5)];
        assert_eq!(weighted_median_f32(&mut split), 1.0);
    }

    #[test]
    fn the_fast_weighted_median_does_not_depend_on_the_order_of_the_votes() {
        // Windows as the sharpening makes them: 15 x 15 spatial weights (sigma 7 px), two colours
        // and two flow values split by a line through the window, band votes x 0.05. Such
        // windows are often symmetric, the weight on one side exactly half the total in exact
        // arithmetic: where sums round in an order-dependent way, the median may tip either way.
        // (A float-sum version passed these windows too; on windows from real frames, reversing
        // the votes changed 23 of 300 000 of its medians.)
        let mut rng = crate::rng::Rng::new(11);
        let spatial = |dx: i32, dy: i32| crate::numeric::exp(-f64::from(dx * dx + dy * dy) / 98.0);
        for _ in 0..5_000 {
            let (a, b) = (
                (rng.uniform() * 4.0) as i32 - 2,
                (rng.uniform() * 3.0) as i32 - 1,
            );
            let colour = if rng.uniform() < 0.5 { 1.0 } else { 0.3 };
            let band_width = (rng.uniform() * 4.0) as i32;
            let votes: Vec<(f32, u32)> = (-7..=7)
                .flat_map(|dy| (-7..=7).map(move |dx| (dx, dy)))
                .map(|(dx, dy)| {
                    let side = a * dx + b * dy;
                    let value = if side < 0 { 1.5 } else { 4.0 };
                    let mut weight = spatial(dx, dy) * if side < 0 { colour } else { 1.0 };
                    if side.abs() <= band_width {
                        weight *= 0.05;
                    }
                    (value, fixed_point_weight(weight as f32))
                })
                .collect();
            let mut forward = votes.clone();
            let mut reversed: Vec<(f32, u32)> = votes.iter().rev().copied().collect();
            let mut rotated = votes.clone();
            rotated.rotate_left(votes.len() / 3);
            let want = weighted_median_f32(&mut forward);
            assert_eq!(weighted_median_f32(&mut reversed).to_bits(), want.to_bits());
            assert_eq!(weighted_median_f32(&mut rotated).to_bits(), want.to_bits());
        }
    }

    #[test]
    fn a_horizontal_boundary_gives_a_band_across_the_columns_up_to_the_borders() {
        let flow = Grid::from_fn(6, 20, |_, y| if y < 10 { [0.0, 0.0] } else { [0.0, -2.0] });
        let band = boundary_band(&flow, &EdgeParams::default());
        for y in 0..20 {
            for x in 0..6 {
                assert_eq!(*band.get(x, y), (6..=13).contains(&y), "({x}, {y})");
            }
        }
    }

    #[test]
    fn flow_without_jumps_is_left_alone() {
        let (frame, _, _) = two_regions();
        // A smooth field: neighbours differ by 0.05 px.
        let flow = Grid::from_fn(40, 20, |x, y| [0.05 * x as f32, -0.05 * y as f32]);
        let same = sharpen_motion_edges(&flow, &frame, &EdgeParams::default()).unwrap();
        assert_eq!(same.data(), flow.data());
        assert!(
            !boundary_band(&flow, &EdgeParams::default())
                .data()
                .contains(&true)
        );
    }

    #[test]
    fn the_band_spans_the_jump_by_its_width_on_each_side() {
        let flow = Grid::from_fn(30, 5, |x, _| if x < 15 { [0.0, 0.0] } else { [3.0, 0.0] });
        let params = EdgeParams {
            band: 2,
            ..EdgeParams::default()
        };
        let band = boundary_band(&flow, &params);
        for y in 0..5 {
            for x in 0..30 {
                // Pixels 14 and 15 are the boundary; the band adds 2 on each side.
                assert_eq!(*band.get(x, y), (12..=17).contains(&x), "({x}, {y})");
            }
        }
    }

    #[test]
    fn bad_settings_and_sizes_are_errors() {
        let (frame, flow, _) = two_regions();
        for bad in [
            EdgeParams {
                sigma_colour: 0.0,
                ..EdgeParams::default()
            },
            EdgeParams {
                jump_px: f32::NAN,
                ..EdgeParams::default()
            },
            EdgeParams {
                band_vote: 0.0,
                ..EdgeParams::default()
            },
            EdgeParams {
                band: 9,
                ..EdgeParams::default()
            },
            EdgeParams {
                radius: MAX_RADIUS + 1,
                ..EdgeParams::default()
            },
            EdgeParams {
                sigma_colour: 1e-4,
                ..EdgeParams::default()
            },
        ] {
            assert!(matches!(
                sharpen_motion_edges(&flow, &frame, &bad),
                Err(Error::InvalidParameter(_))
            ));
        }
        let small = Grid::filled(10, 10, [0u8; 3]);
        assert!(matches!(
            sharpen_motion_edges(&flow, &small, &EdgeParams::default()),
            Err(Error::SizeMismatch { .. })
        ));
        let off = EdgeParams {
            band: 0,
            ..EdgeParams::default()
        };
        assert_eq!(
            sharpen_motion_edges(&flow, &frame, &off).unwrap().data(),
            flow.data()
        );
    }
}
