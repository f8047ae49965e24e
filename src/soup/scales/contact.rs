//! The contact terms between touching pieces (see the parent module's "The contact term"): one
//! [`Link`] per touching pair with the weighted gaps of its sampled boundary pairs, gathered
//! into a [`Problem`], plus the per-piece operations on it (tail control and the truth test's
//! polish).

use nalgebra::Vector3;

use super::minimise::{minimise_contacts, truncated};
use super::ray_gaps::{gaps, ray_point};
use super::{ScaleInputs, ScaleParams};
use crate::numeric::{exp, hypot};
use crate::soup::{Piece, Soup, ground};
use crate::superpixels::graph::BoundaryEdge;

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
    /// in front of it (see `priors::segment_pair_terms`).
    pub upper: Option<usize>,
}

impl Link {
    /// φ(δ).
    pub fn value(&self, delta: f64, sigma: f64) -> f64 {
        truncated(&self.terms, delta, sigma)
    }

    /// Whether the flow across the boundary is trusted and continuous: no occlusion there
    /// ([`ScaleParams::continuity_trusted_share`]).
    pub(super) fn shows_continuity(&self, params: &ScaleParams) -> bool {
        self.flow_jump < params.continuous_flow_px
            && self.trusted_share >= params.continuity_trusted_share
    }

    /// φ with every gap truncated: the most the link can cost.
    fn full(&self, sigma: f64) -> f64 {
        self.terms.iter().map(|&(w, _)| w * sigma).sum()
    }

    /// The link's terms as functions of x, the log-scale of its piece a (`from_a`) or b, with
    /// the other piece's log-scale at `other`: (w, c') with gap = x + c'.
    pub(super) fn seen_from(
        &self,
        from_a: bool,
        other: f64,
    ) -> impl Iterator<Item = (f64, f64)> + '_ {
        // δ = s_a − s_b: from a, gap = x − other + c; from b, |other − x + c| = |x − other − c|.
        let sign = if from_a { 1.0 } else { -1.0 };
        self.terms.iter().map(move |&(w, c)| (w, sign * c - other))
    }

    /// The frame-1 terms alone, seen as [`Link::seen_from`] sees all of them.
    pub(super) fn frame1_seen_from(
        &self,
        from_a: bool,
        other: f64,
    ) -> impl Iterator<Item = (f64, f64)> + '_ {
        let sign = if from_a { 1.0 } else { -1.0 };
        self.frame1.iter().map(move |&(w, c)| (w, sign * c - other))
    }
}

#[cfg(test)]
impl Link {
    /// For tests: a link between pieces a and b with one gap c (frame 1, weight w) whose
    /// trusted flow jumps by 2 px, a boundary where one side may occlude the other.
    pub(super) fn single(a: usize, b: usize, w: f64, c: f64) -> Link {
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
    pub(super) fn local_terms(&self, i: usize, s: &[f64]) -> Vec<(f64, f64)> {
        let mut out = Vec::new();
        for &e in &self.touching[i] {
            let l = &self.links[e];
            let other = if l.a == i { s[l.b] } else { s[l.a] };
            out.extend(l.seen_from(l.a == i, other));
        }
        out
    }
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

/// Tail control: pieces whose depth disagrees with every touching neighbour in both frames
/// (each link's cost within 10 % of its fully truncated value) while some boundary of theirs
/// shows continuous trusted flow ([`Link::shows_continuity`], the figure prior's test) move to
/// the scale that best meets their neighbours.
/// Returns how many moved.
pub(super) fn tail_control(problem: &Problem, s: &mut [f64], params: &ScaleParams) -> usize {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::Intrinsics;
    use crate::flow::FlowField;
    use crate::grid::Grid;
    use crate::superpixels::Superpixels;
    use crate::superpixels::graph::BoundaryGraph;

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
    fn a_pair_weighs_support_weight_more_only_where_its_lower_piece_is_own_floor() {
        // Two pieces in a 2 × 2 image, on still trusted flow of one colour (so colour and
        // continuity weigh 1): piece 0 is the top-left pixel, piece 1 the other three. Pair
        // (0, 2) is stacked (pixel 2 lies under pixel 0), pair (0, 1) is side by side.
        let params = ScaleParams::default();
        let labels = Grid::from_fn(2, 2, |x, y| u32::from(x + y > 0));
        let segment = |pixels: Vec<u32>, anchor, bbox| crate::superpixels::Segment {
            pixels,
            anchor,
            mean_lab: [0.0; 3],
            mean_rgb: [0; 3],
            bbox,
        };
        let superpixels = Superpixels {
            labels,
            segments: vec![
                segment(vec![0], [0.0, 0.0], [0, 0, 0, 0]),
                segment(vec![1, 2, 3], [2.0 / 3.0, 2.0 / 3.0], [0, 0, 1, 1]),
            ],
        };
        let flow: FlowField = Grid::filled(2, 2, [0.0, 0.0]);
        let reliable = Grid::filled(2, 2, true);
        let k = Intrinsics {
            fx: 100.0,
            fy: 100.0,
            cx: 0.5,
            cy: 0.5,
        };
        let boundaries = BoundaryGraph { edges: Vec::new() };
        let inputs = ScaleInputs {
            superpixels: &superpixels,
            boundaries: &boundaries,
            flow: &flow,
            reliable: &reliable,
            intrinsics: &k,
        };
        let piece = |m: Vector3<f64>, degenerate| Piece {
            r: nalgebra::Matrix3::identity(),
            t_hat: Vector3::new(1.0, 0.0, 0.0),
            m,
            lambda: 1.0,
            hypothesis: 0,
            degenerate,
        };
        // Planes m = n / d, y down: a wall at depth 5, a floor 2 below the camera, a ceiling 2
        // above it.
        let wall = Vector3::new(0.0, 0.0, 0.2);
        let floor = Vector3::new(0.0, 0.5, 0.0);
        let ceiling = Vector3::new(0.0, -0.5, 0.0);
        let weight = |upper: Piece, lower: Piece, pair: (u32, u32)| {
            let soup = Soup {
                pieces: vec![upper, lower],
                hypotheses: Vec::new(),
                noise_px: 0.0,
                ego_rival: None,
                rugged_to_ego: 0,
            };
            let edge = BoundaryEdge {
                a: 0,
                b: 1,
                pairs: vec![pair],
                colour_diff: vec![0.0],
            };
            pair_weight(&soup, &inputs, &params, &edge, 0)
        };
        let (stacked, beside) = ((0, 2), (0, 1));
        let on_floor = weight(piece(wall, None), piece(floor, None), stacked);
        assert!(
            (on_floor - params.support_weight).abs() < 1e-12,
            "{on_floor}"
        );
        // Not where the lower plane is a ceiling's, is borrowed, or is the upper piece's; nor
        // beside the floor.
        let borrowed = Some(crate::soup::Degeneracy::TooFewPixels);
        for (upper, lower, pair) in [
            (piece(wall, None), piece(ceiling, None), stacked),
            (piece(wall, None), piece(floor, borrowed), stacked),
            (piece(floor, None), piece(wall, None), stacked),
            (piece(wall, None), piece(floor, None), beside),
        ] {
            let w = weight(upper, lower, pair);
            assert!((w - 1.0).abs() < 1e-12, "{w}");
        }
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
                ..Link::single(a, b, 1.0, 0.0)
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
}
