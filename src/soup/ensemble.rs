//! Fusion of several reconstructions of one pair: each piece of the kept soup takes the scale
//! that the median of the reconstructions gives it.
//!
//! Two frames leave many scales weakly pinned, and which wrong answer the scale solve and the
//! refinement land on changes with small changes of their input: the same pair segmented into
//! 1300, 1400, …, 1700 superpixels gives depth errors that swing by a factor of two (the flag
//! 0.09–0.17, FlyingThings3D 0.20–0.42), each time with different pieces placed wrong. The
//! placements that several segmentations agree on are the ones the data supports, so the
//! pipeline ([`crate::pipeline`]) makes a few *members*, reconstructions of the same flow from
//! other superpixel counts, and this module moves each piece of the kept soup to their median:
//!
//! 1. each member's depth map is brought to the soup's global scale (the median log-ratio over
//!    the pixels both have: a reconstruction's global scale is arbitrary);
//! 2. per pixel, the weighted median log-depth over the soup and its members, where a
//!    reconstruction's depth counts 1 where its scale is pinned (its piece's depth confidence is
//!    at least `scales.min_confidence`) and [`EnsembleParams::guess_weight`] where it is a guess:
//!    where they disagree, the reconstructions whose energy pins the piece decide, and where all
//!    of them guess, the median of the guesses stays;
//! 3. per piece, the median over its pixels of (that median − the piece's own log-depth) gives
//!    its factor; λ is multiplied by it (depths scale by it, the homography stays: the piece
//!    still explains its flow exactly as well), and the median λ is reset to 1.
//!
//! Only scales change: each piece keeps its own plane and motion, so depth, both point clouds,
//! the scene flow and the confidence all come from one soup, as without members.

use serde::Serialize;

use super::Soup;
use super::scales::set_scales;
use crate::grid::Grid;
use crate::numeric::{ln, weighted_median};

/// Settings of the members fused into a reconstruction.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, serde::Deserialize)]
#[serde(default)]
pub struct EnsembleParams {
    /// Reconstructions fused, the kept one included: 1 turns fusion off, at most [`MAX_MEMBERS`],
    /// and the counts must stay within 0.5–1.5 × the kept one's (`count_step` × (members / 2)
    /// ≤ 0.5). With an even number (or when a member fails) each pixel's median is the mean of
    /// the two middle values, so with 2 every piece moves halfway to the one member. 5: over
    /// 1300–1700 superpixels (preset high) the mean depth error fell on seven of nine cases (the
    /// creature 0.109 → 0.076, the crowd 0.190 → 0.159, the flag 0.127 → 0.101), kept on the
    /// table and rose on FlyingThings3D (0.318 → 0.338, its range narrowing from 0.20–0.42 to
    /// 0.29–0.42). Offline (per-pixel medians of full members): 3 gave less on the flag, the
    /// creature, the street and the road (0.100, 0.089, 0.020, 0.051 against 0.092, 0.079,
    /// 0.018, 0.049 with 5), and 9 (counts ±27 %) was not better than 5 overall.
    pub members: usize,
    /// Relative step between the members' superpixel counts: with 5 members and `count`
    /// superpixels they have count × (1 − 2s), (1 − s), (1 + s), (1 + 2s). 1/15, so that 1500
    /// gives 1300, 1400, 1600 and 1700: counts close enough that every member resolves the
    /// same structures, far enough apart that their segmentations (and so their errors) differ.
    pub count_step: f64,
    /// MP-PBP iterations of each member's refinement (the kept reconstruction uses
    /// `refine.iterations`). 2 with `member_particles` 8 costs a seventh of the full
    /// refinement. Means over 1300–1700 superpixels of FlyingThings3D, the flag and the crowd,
    /// fused: full members (6 iterations, 16 particles) 0.324, 0.100, 0.155; 3 iterations
    /// 0.338, 0.101, 0.159; 2 iterations 0.338, 0.101, 0.159; no refinement 0.351, 0.104,
    /// 0.165.
    pub member_iterations: usize,
    /// Particles per piece in each member's refinement (see `member_iterations`).
    pub member_particles: usize,
    /// Weight of a reconstruction's depth in the per-pixel median where it is a guess (its
    /// piece's depth confidence below `scales.min_confidence`), against 1 where it is pinned;
    /// in [0, 1].
    /// 0.25: over five seeds at 1500 superpixels (preset high) the crowd's mean error fell
    /// 0.142 → 0.130 (at every seed) and the flag's 0.112 → 0.094 (at four seeds of five: a
    /// band of the flag that one member guesses, another pins), the rest within 0.004. 1 is the
    /// plain median; 0 for the members' guesses took FlyingThings3D, a third of whose pixels
    /// are guesses carrying most of its error, from 0.310 to 0.339: where every member
    /// guesses, a median of guesses is better than one.
    pub guess_weight: f64,
}

impl Default for EnsembleParams {
    fn default() -> Self {
        EnsembleParams {
            members: 5,
            count_step: 1.0 / 15.0,
            member_iterations: 2,
            member_particles: 8,
            guess_weight: 0.25,
        }
    }
}

impl EnsembleParams {
    /// The superpixel counts of the members other than the kept reconstruction (made with
    /// `count`): `count · (1 + j · count_step)` for j = −1, +1, −2, +2, … until there are
    /// `members − 1`, rounded, at least 1.
    pub fn member_counts(&self, count: usize) -> Vec<usize> {
        (1..self.members)
            .map(|i| {
                let j = i.div_ceil(2) as f64 * if i % 2 == 1 { -1.0 } else { 1.0 };
                ((count as f64 * (1.0 + j * self.count_step))
                    .round()
                    .max(1.0)) as usize
            })
            .collect()
    }
}

/// The most members [`EnsembleParams::members`] may ask for (each costs a third of a
/// reconstruction; the page's field stops there too).
pub const MAX_MEMBERS: usize = 15;

/// The members' depth maps are kept at every `SAMPLE_STRIDE`-th pixel in x and y only: a piece
/// of 1500 on a 1024 × 768 image has about 500 pixels, so each median still sees about 125,
/// and four members' maps take 3 MB instead of 12 MB (with full maps the 12 MP photo pair's
/// peak tab memory was 402 MiB, above the page's 400; now 373 MiB).
pub const SAMPLE_STRIDE: usize = 2;

/// What the fusion did.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct EnsembleReport {
    /// Superpixel counts asked of the members (the kept reconstruction's not included; those
    /// in `failed` were left out).
    pub counts: Vec<usize>,
    /// Notes on members that could not be made (their error), left out of the fusion.
    pub failed: Vec<String>,
    /// Pieces whose scale the fusion changed by more than 10 % relative to the soup's median.
    pub rescaled: usize,
}

/// A relative change of a piece's scale that [`EnsembleReport::rescaled`] counts.
const RESCALED_LOG: f64 = 0.0953; // ln 1.1

/// One reconstruction's say in the fusion: its depth map and where that depth is pinned.
#[derive(Clone, Debug, PartialEq)]
pub struct Vote {
    /// Frame-1 depth (any global scale; NaN or ≤ 0 = unknown).
    pub depth: Grid<f32>,
    /// Where the depth's scale is pinned (the piece's depth confidence is at least
    /// `scales.min_confidence`); elsewhere it is a guess and weighs
    /// [`EnsembleParams::guess_weight`].
    pub pinned: Grid<bool>,
}

impl Vote {
    /// The weight of pixel `i`'s depth: 1 where pinned, else `guess_weight`.
    fn weight(&self, i: usize, guess_weight: f64) -> f64 {
        if self.pinned.data()[i] {
            1.0
        } else {
            guess_weight
        }
    }
}

/// Moves each piece of `soup` (its frame-1 labels `labels`, its own vote `own`: the dense depth
/// as [`crate::output::dense_depth`] makes it, and where it is pinned) to the scale that the
/// per-pixel weighted median of its depth and the `members`' depth maps (same size, any global
/// scale) gives it, each depth weighing 1 where its vote is pinned and `guess_weight` where not,
/// and resets the median λ to 1 ([`set_scales`]). A member sharing fewer than 100 known pixels
/// with `own` is left out; a piece without a known pixel keeps its scale; labels or members of
/// another size than `own` change nothing. Returns how many pieces with a known pixel changed
/// scale by more than 10 % relative to the median change.
pub fn fuse_scales(
    soup: &mut Soup,
    labels: &Grid<u32>,
    own: &Vote,
    members: &[Vote],
    guess_weight: f64,
) -> usize {
    let depth = &own.depth;
    if labels.size() != depth.size() || own.pinned.size() != depth.size() {
        return 0;
    }
    let own_logs: Vec<f64> = depth.data().iter().map(|&z| log_depth(z)).collect();
    let aligned: Vec<(Vec<f64>, &Vote)> = members
        .iter()
        .filter(|m| m.depth.size() == depth.size() && m.pinned.size() == depth.size())
        .filter_map(|m| Some((aligned_log_depths(&own_logs, &m.depth)?, m)))
        .collect();
    let mut offsets = vec![Vec::new(); soup.pieces.len()];
    let mut items = Vec::with_capacity(aligned.len() + 1);
    for (i, (&label, &z)) in labels.data().iter().zip(&own_logs).enumerate() {
        if !z.is_finite() {
            continue;
        }
        items.clear();
        items.push((own.weight(i, guess_weight), z));
        items.extend(
            (aligned.iter())
                .filter(|(logs, _)| logs[i].is_finite())
                .map(|(logs, vote)| (vote.weight(i, guess_weight), logs[i])),
        );
        if let (Some(median), Some(list)) =
            (weighted_median(&mut items), offsets.get_mut(label as usize))
        {
            list.push(median - z);
        }
    }
    // Per piece, its log-factor; `None` without a known pixel (it keeps its scale).
    let factors: Vec<Option<f64>> = offsets.iter_mut().map(|o| median(o)).collect();
    let mut measured: Vec<f64> = factors.iter().flatten().copied().collect();
    let centre = median(&mut measured).unwrap_or(0.0);
    let rescaled = (factors.iter().flatten())
        .filter(|&&f| (f - centre).abs() > RESCALED_LOG)
        .count();
    let logs: Vec<f64> = (soup.pieces.iter().zip(&factors))
        .map(|(p, f)| ln(p.lambda) + f.unwrap_or(0.0))
        .collect();
    set_scales(soup, &logs);
    rescaled
}

/// ln z, or NaN for a depth that is not finite and positive.
fn log_depth(z: f32) -> f64 {
    if z.is_finite() && z > 0.0 {
        ln(z as f64)
    } else {
        f64::NAN
    }
}

/// `member`'s log-depths shifted by the median of `own − member` over the pixels both know, so
/// that its global scale is `own`'s; `None` when they share fewer than 100 such pixels.
fn aligned_log_depths(own: &[f64], member: &Grid<f32>) -> Option<Vec<f64>> {
    let logs: Vec<f64> = member.data().iter().map(|&z| log_depth(z)).collect();
    let mut gaps: Vec<f64> = own
        .iter()
        .zip(&logs)
        .map(|(a, b)| a - b)
        .filter(|g| g.is_finite())
        .collect();
    if gaps.len() < 100 {
        return None;
    }
    let shift = median(&mut gaps)?;
    Some(logs.into_iter().map(|v| v + shift).collect())
}

/// The median of `values` (the mean of the two middle ones for an even count; reorders them),
/// `None` when empty. Every value must be finite.
fn median(values: &mut [f64]) -> Option<f64> {
    let n = values.len();
    if n == 0 {
        return None;
    }
    values.sort_unstable_by(f64::total_cmp);
    Some(if n % 2 == 1 {
        values[n / 2]
    } else {
        0.5 * (values[n / 2 - 1] + values[n / 2])
    })
}

#[cfg(test)]
mod tests {
    use nalgebra::{Matrix3, Vector3};

    use super::*;
    use crate::soup::Piece;

    /// A soup of `n` fronto-parallel pieces at depth 1 (unit scale, λ = 1), and labels that give
    /// piece i the columns 10 i .. 10 i + 9 of a 10n × 20 image.
    fn strips(n: usize) -> (Soup, Grid<u32>) {
        let piece = Piece {
            r: Matrix3::identity(),
            t_hat: Vector3::x(),
            m: Vector3::z(),
            lambda: 1.0,
            hypothesis: 0,
            degenerate: None,
        };
        let soup = Soup {
            pieces: vec![piece; n],
            hypotheses: Vec::new(),
            noise_px: 0.1,
            ego_rival: None,
            rugged_to_ego: 0,
        };
        let labels = Grid::from_fn(10 * n, 20, |x, _| (x / 10) as u32);
        (soup, labels)
    }

    /// Depth map of `labels` with piece i at `depths[i]`.
    fn depth_map(labels: &Grid<u32>, depths: &[f32]) -> Grid<f32> {
        labels.map(|&l| depths[l as usize])
    }

    /// A vote pinned everywhere (every depth weighs 1).
    fn all_pinned(depth: Grid<f32>) -> Vote {
        let pinned = depth.map(|_| true);
        Vote { depth, pinned }
    }

    /// A vote pinned everywhere with piece i at `depths[i]`.
    fn pinned(labels: &Grid<u32>, depths: &[f32]) -> Vote {
        all_pinned(depth_map(labels, depths))
    }

    /// A vote with piece i at `depths[i]`, a guess on the pieces in `guessed`.
    fn guessing(labels: &Grid<u32>, depths: &[f32], guessed: &[u32]) -> Vote {
        Vote {
            depth: depth_map(labels, depths),
            pinned: labels.map(|l| !guessed.contains(l)),
        }
    }

    const GUESS: f64 = 0.25;

    #[test]
    fn a_piece_moves_to_where_most_members_put_it() {
        let (mut soup, labels) = strips(5);
        let own = pinned(&labels, &[1.0; 5]);
        // Three of four members put piece 2 twice as deep; every member has its own global scale.
        let members = [
            pinned(&labels, &[3.0, 3.0, 6.0, 3.0, 3.0]),
            pinned(&labels, &[0.5, 0.5, 1.0, 0.5, 0.5]),
            pinned(&labels, &[2.0, 2.0, 4.0, 2.0, 2.0]),
            pinned(&labels, &[1.0, 1.0, 1.0, 1.0, 1.0]),
        ];
        let rescaled = fuse_scales(&mut soup, &labels, &own, &members, GUESS);
        let lambdas: Vec<f64> = soup.pieces.iter().map(|p| p.lambda).collect();
        for (i, l) in lambdas.iter().enumerate() {
            let want = if i == 2 { 2.0 } else { 1.0 };
            assert!((l - want).abs() < 1e-9, "piece {i}: λ {l}, want {want}");
        }
        assert_eq!(rescaled, 1);
    }

    #[test]
    fn one_member_alone_moves_nothing() {
        let (mut soup, labels) = strips(4);
        let own = pinned(&labels, &[1.0, 2.0, 3.0, 4.0]);
        for (i, p) in soup.pieces.iter_mut().enumerate() {
            p.lambda = (i + 1) as f64;
        }
        let before = soup.pieces.clone();
        // One wild member among two that agree with the soup.
        let members = [
            pinned(&labels, &[1.0, 2.0, 3.0, 4.0]),
            pinned(&labels, &[1.0, 2.0, 3.0, 4.0]),
            pinned(&labels, &[9.0, 0.1, 30.0, 4.0]),
        ];
        assert_eq!(fuse_scales(&mut soup, &labels, &own, &members, GUESS), 0);
        // The relative scales stay (only the median reset may move them all together).
        let ratio = soup.pieces[0].lambda / before[0].lambda;
        for (p, q) in soup.pieces.iter().zip(&before) {
            assert!(
                (p.lambda / q.lambda - ratio).abs() < 1e-9,
                "{:?}",
                soup.pieces
            );
        }
    }

    #[test]
    fn unknown_depths_and_mismatched_members_are_left_out() {
        let (mut soup, labels) = strips(3);
        let own = pinned(&labels, &[1.0, f32::NAN, 1.0]);
        let wrong_size = all_pinned(Grid::filled(7, 7, 5.0f32));
        let members = [
            pinned(&labels, &[1.0, 1.0, 3.0]),
            pinned(&labels, &[1.0, 1.0, 3.0]),
            wrong_size,
        ];
        fuse_scales(&mut soup, &labels, &own, &members, GUESS);
        // Piece 1 has no known pixel: it keeps λ (1 before the median reset, whose centre is
        // piece 0's or 2's factor).
        let l: Vec<f64> = soup.pieces.iter().map(|p| p.lambda).collect();
        assert!(l.iter().all(|v| v.is_finite() && *v > 0.0), "{l:?}");
        assert!((l[2] / l[0] - 3.0).abs() < 1e-9, "{l:?}");
    }

    #[test]
    fn the_median_scale_is_one_afterwards() {
        let (mut soup, labels) = strips(3);
        for (p, l) in soup.pieces.iter_mut().zip([0.5, 1.0, 2.0]) {
            p.lambda = l;
        }
        let own = pinned(&labels, &[0.5, 1.0, 2.0]);
        // Both members put piece 0 four times as deep as the soup does, relative to the rest.
        let member = pinned(&labels, &[2.0, 1.0, 2.0]);
        fuse_scales(&mut soup, &labels, &own, &[member.clone(), member], GUESS);
        let mut l: Vec<f64> = soup.pieces.iter().map(|p| p.lambda).collect();
        assert!((l[0] / l[1] - 2.0).abs() < 1e-9, "{l:?}");
        l.sort_by(f64::total_cmp);
        assert!((l[1] - 1.0).abs() < 1e-12, "median λ {l:?}");
    }

    #[test]
    fn pinned_depths_outweigh_guesses_and_guesses_alone_keep_their_median() {
        // Piece 1: the soup and two members guess it at depth 1, two members pin it at 2 (the
        // plain median would keep 1). Piece 2: everyone guesses; three of five put it at 3.
        // Pieces 0, 3 and 4 agree everywhere (they set each member's global scale).
        let (mut soup, labels) = strips(5);
        let own = guessing(&labels, &[1.0; 5], &[1, 2]);
        let members = [
            guessing(&labels, &[1.0, 1.0, 3.0, 1.0, 1.0], &[1, 2]),
            guessing(&labels, &[1.0, 1.0, 3.0, 1.0, 1.0], &[1, 2]),
            guessing(&labels, &[1.0, 2.0, 3.0, 1.0, 1.0], &[2]),
            guessing(&labels, &[1.0, 2.0, 1.0, 1.0, 1.0], &[2]),
        ];
        fuse_scales(&mut soup, &labels, &own, &members, GUESS);
        let l: Vec<f64> = soup.pieces.iter().map(|p| p.lambda).collect();
        assert!((l[1] / l[0] - 2.0).abs() < 1e-9, "{l:?}");
        assert!((l[2] / l[0] - 3.0).abs() < 1e-9, "{l:?}");
        // With guesses weighing as much as pinned depths, it is the plain median again.
        let (mut plain, _) = strips(5);
        fuse_scales(&mut plain, &labels, &own, &members, 1.0);
        let l: Vec<f64> = plain.pieces.iter().map(|p| p.lambda).collect();
        assert!((l[1] / l[0] - 1.0).abs() < 1e-9, "{l:?}");
        assert!((l[2] / l[0] - 3.0).abs() < 1e-9, "{l:?}");
    }

    #[test]
    fn member_counts_alternate_around_the_kept_count() {
        let params = EnsembleParams::default();
        assert_eq!(params.member_counts(1500), vec![1400, 1600, 1300, 1700]);
        let one = EnsembleParams {
            members: 1,
            ..params
        };
        assert!(one.member_counts(1500).is_empty());
    }
}
