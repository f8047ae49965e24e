//! Step 1 of the scale solve (see the parent module): the rigid segments and what each one is
//! (static world, floor, a fragment attached to the world, a mover resting on the ground); also
//! the truth test's views of the segment objective ([`ScaleEnergy`]). Step 2, the segment
//! scales, is in `descent`.

use nalgebra::Vector3;

use super::contact::{Problem, build_problem};
use super::descent::solve_segments;
use super::minimise::{steps_at, truncated};
use super::priors::{PairTerms, segment_pair_terms};
use super::ray_gaps::ray_point;
use super::{ScaleInputs, ScaleParams};
use crate::numeric::{hypot, ln};
use crate::soup::{Piece, Soup, ground};
use crate::union_find::{find, union};

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
pub(super) struct Segments {
    /// Segment of every piece.
    pub(super) segment: Vec<usize>,
    /// Pieces per segment.
    pub(super) sizes: Vec<usize>,
    /// Per segment, the log-scale that puts it at median depth 1 (see `segment_centres`).
    pub(super) centre: Vec<f64>,
    /// Per segment, whether it is on the ego-motion (hypothesis 0) and not sunk under the
    /// ground: a part of the static world.
    pub(super) ego: Vec<bool>,
    /// Per segment, whether it is measured static world: on the ego-motion, with at least
    /// [`ScaleParams::measured_share`] of its pieces well measured (`world_pieces`).
    pub(super) measured: Vec<bool>,
    /// The static world's segment: the largest on the ego-motion.
    pub(super) world: Option<usize>,
    /// Per segment, whether it is floor: on the ego-motion, with at least half of its pieces
    /// within σ of the static world's ground at equal scale (see `below`). The static prior
    /// holds such a segment with its full weight (`ScaleParams::static_max` does not cap it).
    pub(super) grounded: Vec<bool>,
    /// Per segment, whether it is on the ego-motion and meets the static world's segment at
    /// equal scale, directly or through other such segments, across a link whose median
    /// frame-1 gap is below [`ScaleParams::world_gap`] (see `attached_to_world`): a part of
    /// the static world that `segment_gap` split off. The static prior holds it with its full
    /// weight, like the floor.
    pub(super) attached: Vec<bool>,
    /// Per piece, how far it lies under the static world's ground at equal scales
    /// ([`ground::depth_below_ground`]); `None` for pieces above the horizon, and for every
    /// piece when no ground is in view.
    pub(super) below: Vec<Option<f64>>,
    /// Per piece on a motion of its own, where it rests on the ground: the log-depth gaps of
    /// its bottom pixels over the ground at equal scales ([`ground::resting_gaps`]); empty for
    /// the static world's pieces, for pieces that do not rest on it, and for every piece when
    /// the rest prior is off or the ground does not reach the bottom of the view
    /// ([`ScaleParams::rest_bottom_share`]).
    pub(super) resting: Vec<Vec<f64>>,
    /// Whether the static world's ground runs to the near edge of the view
    /// ([`ScaleParams::rest_bottom_share`]): a floor that things stand on, so the world below a
    /// mover's bottom edge may be floor in front of it (see `priors::segment_pair_terms`).
    pub(super) floor: bool,
    /// Whether the static world's ground plane was found.
    pub(super) ground: bool,
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
    /// Segments with the given piece-to-segment map, centres and ego-motion flags (a segment on
    /// the ego-motion counts as measured static world), for tests of the solve.
    #[cfg(test)]
    pub(super) fn of_pieces(segment: &[usize], centre: &[f64], ego: &[bool]) -> Segments {
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

    /// The segments of `soup` at equal scales ([`rigid_segments`] at s = 0).
    ///
    /// Pieces on the ego-motion that lie more than [`ScaleParams::sunk_gap`] under the ground
    /// of the static world at its scale are not static: a mover that the ego-motion explains
    /// at a wrong, larger depth (a car driving ahead, seen near the epipole) sinks under the
    /// road. Such pieces join only each other and their segments are movers (no static prior,
    /// no exemption from the figure prior). Pieces touching the image's border are not split
    /// off: their flow (pixels leaving the view) and planes are the least reliable, and on the
    /// crowd the floor's border pieces read 0.2–0.5 under its own ground.
    pub(super) fn new(
        soup: &Soup,
        inputs: &ScaleInputs,
        problem: &Problem,
        params: &ScaleParams,
    ) -> Self {
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
    pub(super) fn log_scales(&self, u: &[f64]) -> Vec<f64> {
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
pub(super) fn resting_at_scales(
    soup: &Soup,
    inputs: &ScaleInputs,
    params: &ScaleParams,
) -> Vec<Vec<f64>> {
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

#[cfg(test)]
mod tests {
    use super::super::contact::Link;
    use super::*;

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
        let mut segments = Segments::of_pieces(segment, &centre, &ego);
        setup(&mut segments);
        let u = solve_segments(problem, &segments, params, None).0;
        (centre[g_mover] + u[g_mover]) - (centre[g_world] + u[g_world])
    }

    /// World pieces 0–1–2 in a chain of certain contacts that meet at equal scale, and piece 3
    /// touching them only through `contact` (a link of piece 3 and piece 0).
    fn world_and_one_piece(contact: Link) -> Problem {
        Problem {
            links: vec![
                Link::single(0, 1, 1.0, 0.0),
                Link::single(1, 2, 1.0, 0.0),
                contact,
            ],
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
                Link::single(0, 1, 1.0, 0.0),
                Link::single(1, 2, 1.0, 0.0),
                Link::single(3, 0, 0.5, -1.0),
                mover_to_1,
            ],
            touching: vec![vec![0, 2], vec![0, 1, 3], vec![1], vec![2, 3]],
            sigma: 0.1,
        };
        let segments = Segments::of_pieces(&[0, 0, 0, 1], &[0.0, 0.0], &[true, false]);
        let params = ScaleParams {
            behind_weight,
            ..ScaleParams::default()
        };
        solve_segments(&problem, &segments, &params, None).0[1]
    }

    #[test]
    fn the_figure_prior_keeps_a_loose_mover_in_front() {
        // With the figure prior, lying behind piece 1 costs more and the mover stays in front.
        let solve = |behind_weight| place_loose_mover(Link::single(3, 1, 0.45, 0.3), behind_weight);
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
                    Link::single(0, 1, 1.0, 0.0),
                    Link::single(1, 2, 1.0, 0.0),
                    Link::single(3, 0, 0.5, -1.0),
                    Link {
                        upper,
                        ..Link::single(a, b, 0.45, c)
                    },
                ],
                touching: vec![vec![0, 2], vec![0, 1, 3], vec![1], vec![2, 3]],
                sigma: 0.1,
            };
            let mut segments = Segments::of_pieces(&[0, 0, 0, 1], &[0.0, 0.0], &[true, false]);
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
                ..Link::single(3, 1, 0.45, 0.3)
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
                    Link::single(world[0], world[1], 1.0, 0.0),
                    Link::single(world[1], world[2], 1.0, 0.0),
                    Link::single(mover, world[0], 0.5, -1.0),
                    Link::single(mover, world[1], 0.3, 0.0),
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
        let problem = world_and_one_piece(Link::single(3, 0, 0.5, -1.0));
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
                Link::single(1, 2, 1.0, 0.0),
                Link::single(2, 3, 1.0, 0.0),
                Link::single(0, 1, 0.5, -1.0),
                Link::single(0, 2, 0.45, 0.3),
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
            let segments = Segments::of_pieces(&[0, 1, 1, 1], &centre, &[mover_on_ego, true]);
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
        let problem = world_and_one_piece(Link::single(3, 0, 0.02, -1.0));
        let centre = [0.3, -0.4];
        let placement = |static_weight, on_ego| {
            let params = ScaleParams {
                static_weight,
                ..ScaleParams::default()
            };
            let segments = Segments::of_pieces(&[0, 0, 0, 1], &centre, &[true, on_ego]);
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
                links: vec![Link::single(200, 0, 2.0, -1.0)],
                touching,
                sigma: 0.1,
            };
            let segment: Vec<usize> = (0..200 + pieces).map(|i| usize::from(i >= 200)).collect();
            let mut segments = Segments::of_pieces(&segment, &[0.0, 0.0], &[true, true]);
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
            Link::single(1, 0, 1.0, 0.15),
            Link::single(2, 1, 1.0, -0.18),
            Link::single(3, 0, 1.0, 0.7),
            Link::single(4, 0, 1.0, 0.0),
            Link::single(5, 3, 1.0, 0.0),
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
}
