//! Relative scales: the "3D jigsaw puzzle" of the paper (eq. 1 and its combined energy eq. 6).
//!
//! Each piece of the unit-scale soup is known up to its scale λ_i (depths and translation scale
//! together, so its homography and thus its fit to the flow do not change). The energy, over
//! K-NN edges (i, k) and over pixel pairs (p, q) on the boundaries of touching pieces:
//!
//! E(λ) = Σ_(i,k) w_ik ( √(‖R_i − R_k‖²_F + (‖λ_i t̂_i − λ_k t̂_k‖ / z̄)²)
//!                      + | ‖λ_i X_i − λ_k X_k‖ − ‖λ_i X'_i − λ_k X'_k‖ | / z̄ )          (E_arap)
//!      + α Σ_(i,k touching) mean_(p,q) c_pq ( ρ(‖λ_i P_i(p) − λ_k P_k(q)‖ / z̄_pq)
//!                                           + ρ(‖λ_i P'_i(p) − λ_k P'_k(q)‖ / z̄'_pq) )   (E_cont)
//!
//! with X_i the unit-scale anchor of piece i in frame 1, X'_i = R_i X_i + t̂_i in frame 2, P_i(p)
//! the unit-scale point of boundary pixel p on piece i's plane, w_ik = exp(−β‖s_i − s_k‖) (image
//! anchors normalised by the long side) and ρ = min(·, σ). This is eq. 1 plus the continuity term
//! of eq. 6 (E_proj of eq. 6 does not depend on λ), with every length measured relative to the
//! mean depth z̄ of the two points it joins. That makes E independent of the global scale, so
//! Σλ = 1 only fixes the gauge, and a piece can no longer make its terms vanish by shrinking to
//! the camera centre (docs/ARCHITECTURE.md, Pitfalls). (Measuring against the nearer of the
//! two depths instead was tried: it pushed floating movers back onto the background behind them,
//! MRE 2.6 instead of 0.5 on ft3d-pair.) The continuity weight c_pq is
//! `contact_evidence` instead of the paper's colour weight w4: two bodies in contact usually
//! differ in colour, and the scale solve needs exactly those contacts. α = 0 leaves eq. 1 alone.
//!
//! Every term depends on one difference of log-scales δ = ln λ_i − ln λ_k. Pieces that share a
//! motion hypothesis were reconstructed with the same unit translation, so they are mutually
//! consistent and form one *group* with one scale (a rigid body with one motion has one scale).
//! The terms between two groups add up to a one-dimensional φ_ab(δ), tabulated once. A spanning
//! tree of the most sharply determined group pairs gives the start; coordinate descent then
//! moves one group at a time to the global minimum of its own terms (grid search, then golden
//! section) until nothing improves. The search is centred where every group has median depth 1
//! (unit-scale depths of different motions can differ by orders of magnitude), and each group's
//! median depth stays within a band around the largest group's: the energy is often lowest
//! with a mover shrunk towards the camera, and the band is the bound on that.
//!
//! (Letting single pieces leave their group's scale, against a penalty, was tried for deforming
//! surfaces: on the synthetic flag it did not help, and on rigid scenes the planar approximation's
//! small boundary gaps pulled pieces off their correct common scale.)

use nalgebra::Vector3;
use serde::Serialize;

use super::Soup;
use crate::camera::Intrinsics;
use crate::flow::FlowField;
use crate::superpixels::Superpixels;
use crate::superpixels::graph::{BoundaryGraph, KnnGraph};

/// Settings of the scale solve.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, serde::Deserialize)]
pub struct ScaleParams {
    /// α: weight of the boundary continuity term against E_arap (0 = eq. 1 alone).
    pub continuity: f64,
    /// σ: truncation of a boundary pair's relative 3D gap (gap / depth), so real depth
    /// discontinuities cost a bounded amount.
    pub sigma: f64,
    /// Each group's median depth stays within [1/band, band] times the largest group's.
    pub band: f64,
    /// At most this many pixel pairs are used per touching pair of superpixels (evenly spaced).
    pub pairs_per_boundary: usize,
}

impl Default for ScaleParams {
    fn default() -> Self {
        ScaleParams {
            continuity: 100.0,
            sigma: 0.04,
            band: 12.0,
            pairs_per_boundary: 12,
        }
    }
}

/// What the scale solve did.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ArapReport {
    /// E at λ = 1/N (the paper's start).
    pub energy_start: f64,
    /// E at the solution.
    pub energy_end: f64,
    /// The E_arap part (eq. 1, relative form) at the start and at the solution.
    pub arap_start: f64,
    pub arap_end: f64,
    /// Groups of pieces sharing one motion (the unknowns).
    pub groups: usize,
    /// Coordinate-descent sweeps run.
    pub sweeps: usize,
    /// Largest / smallest λ.
    pub lambda_ratio: f64,
}

/// Step of the tabulated log-ratio grid.
const GRID_STEP: f64 = 0.02;

/// A term between two pieces, as a function of the log-ratio of their scales.
enum Term {
    /// A K-NN edge: weight, ‖R_i − R_k‖², unit-scale anchors and translations of both pieces.
    Arap {
        w: f64,
        rotation: f64,
        x: [Vector3<f64>; 2],
        x2: [Vector3<f64>; 2],
        t: [Vector3<f64>; 2],
    },
    /// A boundary pixel pair: weight (α / pairs used on that boundary, times the pair's
    /// [`contact_evidence`]) and the unit-scale points of both sides in frame 1 and frame 2.
    Contact {
        w: f64,
        p: [Vector3<f64>; 2],
        p2: [Vector3<f64>; 2],
    },
}

impl Term {
    /// The term's value when the first piece has scale e^δ and the second scale 1; `sigma`
    /// truncates contacts.
    fn value(&self, delta: f64, sigma: f64) -> f64 {
        let r = delta.exp();
        let v = match self {
            Term::Arap {
                w,
                rotation,
                x,
                x2,
                t,
            } => {
                let depth = 0.5 * (r * x[0].z + x[1].z);
                let translation = (t[0] * r - t[1]).norm() / depth;
                let d1 = (x[0] * r - x[1]).norm();
                let d2 = (x2[0] * r - x2[1]).norm();
                w * ((rotation + translation * translation).sqrt() + (d1 - d2).abs() / depth)
            }
            Term::Contact { w, p, p2 } => {
                let gap = |a: &Vector3<f64>, b: &Vector3<f64>| {
                    let depth = 0.5 * (r * a.z + b.z).abs();
                    ((a * r - b).norm() / depth.max(1e-12)).min(sigma)
                };
                w * (gap(&p[0], &p[1]) + gap(&p2[0], &p2[1]))
            }
        };
        if v.is_finite() { v } else { 1e6 }
    }

    fn is_arap(&self) -> bool {
        matches!(self, Term::Arap { .. })
    }
}

/// A term between pieces `i` and `k` (the term's first and second piece).
struct PieceTerm {
    i: usize,
    k: usize,
    term: Term,
}

/// The problem: every term between two pieces, and the groups of the pieces.
struct Problem {
    terms: Vec<PieceTerm>,
    group_of: Vec<usize>,
    group_sizes: Vec<usize>,
    /// Per group, the log-scale that brings its median unit-scale anchor depth to 1: the
    /// centre of the scale search, so that the band bounds depth ratios between groups.
    centre: Vec<f64>,
    sigma: f64,
}

impl Problem {
    /// The group with the most pieces (the lowest index among equals): the scale reference.
    fn largest_group(&self) -> Option<usize> {
        (0..self.group_sizes.len()).max_by_key(|&g| (self.group_sizes[g], std::cmp::Reverse(g)))
    }

    /// True when the piece log-scales `s` keep every group's median depth within
    /// [1/band, band] times the largest group's (see [`group_centres`]).
    fn within_band(&self, s: &[f64], band: f64) -> bool {
        let Some(r) = self.largest_group() else {
            return true;
        };
        let mut u = vec![0.0; self.group_sizes.len()];
        for (&g, &v) in self.group_of.iter().zip(s) {
            u[g] = v - self.centre[g];
        }
        let limit = band.max(1.0).ln() + 1e-9;
        u.iter().all(|&v| (v - u[r]).abs() <= limit)
    }

    /// E at piece log-scales `s`; `arap_only` drops the contact terms.
    fn energy(&self, s: &[f64], arap_only: bool) -> f64 {
        self.terms
            .iter()
            .filter(|t| !arap_only || t.term.is_arap())
            .map(|t| t.term.value(s[t.i] - s[t.k], self.sigma))
            .sum()
    }
}

/// What the scale solve reads besides the soup, all at the working resolution.
#[derive(Clone, Copy, Debug)]
pub struct ScaleInputs<'a> {
    /// The superpixels (anchors, labels) the soup's pieces are.
    pub superpixels: &'a Superpixels,
    /// The K-NN graph of E_arap.
    pub knn: &'a KnnGraph,
    /// The touching pixel pairs of E_cont.
    pub boundaries: &'a BoundaryGraph,
    /// Flow 1→2, for the flow continuity across boundaries.
    pub flow: &'a FlowField,
    pub intrinsics: &'a Intrinsics,
}

/// Solves the relative scales of `soup` in place (Σλ = 1) and reports the energies.
pub fn solve_scales(soup: &mut Soup, inputs: &ScaleInputs, params: &ScaleParams) -> ArapReport {
    let n = soup.pieces.len();
    let problem = build_problem(soup, inputs, params);
    let zero = vec![0.0; n];
    let (energy_start, arap_start) = (problem.energy(&zero, false), problem.energy(&zero, true));

    let (group_scales, sweeps) = solve_groups(&problem, params);
    let mut s: Vec<f64> = problem.group_of.iter().map(|&g| group_scales[g]).collect();
    // The solver must not lose to its start, where that start respects the band.
    if problem.energy(&s, false) > energy_start && problem.within_band(&zero, params.band) {
        s = zero;
    }
    let (energy_end, arap_end) = (problem.energy(&s, false), problem.energy(&s, true));

    let mut lambda: Vec<f64> = s.iter().map(|v| v.exp()).collect();
    let total: f64 = lambda.iter().sum();
    lambda.iter_mut().for_each(|l| *l /= total);
    for (p, &l) in soup.pieces.iter_mut().zip(&lambda) {
        p.lambda = l;
    }
    let (lo, hi) = lambda
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(a, b), &l| (a.min(l), b.max(l)));
    ArapReport {
        energy_start,
        energy_end,
        arap_start,
        arap_end,
        groups: problem.group_sizes.len(),
        sweeps,
        lambda_ratio: if n > 0 { hi / lo } else { 1.0 },
    }
}

/// E (the energy above) at the scales the soup's pieces carry now. For checking a solve
/// against other scales (e.g. oracle scales).
pub fn scale_energy(soup: &Soup, inputs: &ScaleInputs, params: &ScaleParams) -> f64 {
    let problem = build_problem(soup, inputs, params);
    let s: Vec<f64> = soup.pieces.iter().map(|p| p.lambda.ln()).collect();
    problem.energy(&s, false)
}

/// Groups (pieces sharing a hypothesis) and every term between two pieces.
fn build_problem(soup: &Soup, inputs: &ScaleInputs, params: &ScaleParams) -> Problem {
    let ScaleInputs {
        superpixels: sp,
        knn,
        boundaries,
        flow,
        intrinsics: k,
    } = *inputs;
    let (group_of, group_sizes) = groups(soup);
    // Unit-scale anchor points in frame 1, once per piece.
    let anchors: Vec<Vector3<f64>> = soup
        .pieces
        .iter()
        .zip(&sp.segments)
        .map(|(piece, seg)| piece.unit_point(&Vector3::from(k.ray(seg.anchor[0], seg.anchor[1]))))
        .collect();
    let moved = |i: usize, x: &Vector3<f64>| soup.pieces[i].r * x + soup.pieces[i].t_hat;
    let mut terms = Vec::new();
    for (i, list) in knn.neighbours.iter().enumerate() {
        for &(kk, w) in list {
            let kk = kk as usize;
            let (xi, xk) = (anchors[i], anchors[kk]);
            terms.push(PieceTerm {
                i,
                k: kk,
                term: Term::Arap {
                    w,
                    rotation: (soup.pieces[i].r - soup.pieces[kk].r).norm_squared(),
                    x: [xi, xk],
                    x2: [moved(i, &xi), moved(kk, &xk)],
                    t: [soup.pieces[i].t_hat, soup.pieces[kk].t_hat],
                },
            });
        }
    }
    if params.continuity > 0.0 {
        let width = sp.labels.width();
        let point = |i: usize, pixel: u32| {
            let (x, y) = (
                (pixel as usize % width) as f64,
                (pixel as usize / width) as f64,
            );
            soup.pieces[i].unit_point(&Vector3::from(k.ray(x, y)))
        };
        for edge in boundaries.edges.iter().filter(|e| !e.pairs.is_empty()) {
            let (a, b) = (edge.a as usize, edge.b as usize);
            let step = edge.pairs.len().div_ceil(params.pairs_per_boundary.max(1));
            let used = edge.pairs.len().div_ceil(step);
            for &(p, q) in edge.pairs.iter().step_by(step) {
                let evidence = contact_evidence(
                    &soup.pieces[a].m,
                    &soup.pieces[b].m,
                    flow.data()[p as usize],
                    flow.data()[q as usize],
                );
                let (xa, xb) = (point(a, p), point(b, q));
                terms.push(PieceTerm {
                    i: a,
                    k: b,
                    term: Term::Contact {
                        w: params.continuity * evidence / used as f64,
                        p: [xa, xb],
                        p2: [moved(a, &xa), moved(b, &xb)],
                    },
                });
            }
        }
    }
    let centre = group_centres(&anchors, &group_of, group_sizes.len());
    Problem {
        terms,
        group_of,
        group_sizes,
        centre,
        sigma: params.sigma,
    }
}

/// Per group, −median ln z over the depths z of its pieces' unit-scale `anchors` (0 for a group
/// without a finite positive depth). Unit-scale depths of different hypotheses can differ by orders of
/// magnitude (a slow mover's unit translation blows its depths up), so scales are searched
/// around these centres, where every group has median depth 1.
fn group_centres(anchors: &[Vector3<f64>], group_of: &[usize], count: usize) -> Vec<f64> {
    let mut log_depths = vec![Vec::new(); count];
    for (anchor, &g) in anchors.iter().zip(group_of) {
        let z = anchor.z;
        if z.is_finite() && z > 0.0 {
            log_depths[g].push(z.ln());
        }
    }
    log_depths
        .into_iter()
        .map(|mut v| {
            if v.is_empty() {
                return 0.0;
            }
            v.sort_by(f64::total_cmp);
            -v[v.len() / 2]
        })
        .collect()
}

/// The group of every piece (pieces sharing a hypothesis) and the size of every group.
fn groups(soup: &Soup) -> (Vec<usize>, Vec<usize>) {
    let mut index = vec![usize::MAX; soup.hypotheses.len().max(1)];
    let mut sizes = Vec::new();
    let group_of = soup
        .pieces
        .iter()
        .map(|p| {
            let h = p.hypothesis.min(index.len() - 1);
            if index[h] == usize::MAX {
                index[h] = sizes.len();
                sizes.push(0);
            }
            sizes[index[h]] += 1;
            index[h]
        })
        .collect();
    (group_of, sizes)
}

/// How much a boundary pixel pair (p, q) between two pieces says about their relative scale,
/// in [0.2, 1]: the larger of
/// - the sine of the angle between their planes: planes at an angle meet only along their line
///   of intersection, so a boundary that matches there is a real contact (feet on the floor);
/// - the continuity of the flow across the pair, exp(−‖f(p) − f(q)‖ / 0.5 px): a surface that
///   really continues (a waving flag) moves continuously.
///
/// What is left weak is a pair of nearly parallel planes whose flow jumps: an occlusion (one
/// person in front of another), which scaling one plane onto the other would fake as a contact.
fn contact_evidence(m_a: &Vector3<f64>, m_b: &Vector3<f64>, f_p: [f32; 2], f_q: [f32; 2]) -> f64 {
    let sin = m_a.normalize().cross(&m_b.normalize()).norm();
    let jump = ((f_p[0] - f_q[0]) as f64).hypot((f_p[1] - f_q[1]) as f64);
    let continuity = (-jump / 0.5).exp();
    let e = sin.max(continuity);
    if e.is_finite() { e.max(0.2) } else { 1.0 }
}

/// All terms between one pair of groups (a < b), tabulated over u_a − u_b, where a group's
/// log-scale is s = centre + u (see [`group_centres`]).
struct Link {
    a: usize,
    b: usize,
    /// centre_a − centre_b: δ = s_a − s_b = offset + (u_a − u_b).
    offset: f64,
    /// Terms with their orientation: +1 when the term's first piece is in group a.
    terms: Vec<(f64, usize)>,
    /// φ at u_a − u_b = −range + j · GRID_STEP.
    table: Vec<f64>,
}

impl Link {
    /// φ at u_a − u_b = `du`, summed exactly over the terms.
    fn value(&self, problem: &Problem, du: f64) -> f64 {
        let delta = self.offset + du;
        self.terms
            .iter()
            .map(|&(sign, t)| problem.terms[t].term.value(sign * delta, problem.sigma))
            .sum()
    }

    /// φ by linear interpolation in the table (clamped to its range).
    fn lookup(&self, delta: f64, range: f64) -> f64 {
        let last = self.table.len() - 1;
        let x = ((delta + range) / GRID_STEP).clamp(0.0, last as f64);
        let j = (x.floor() as usize).min(last.saturating_sub(1));
        let f = x - j as f64;
        self.table[j] * (1.0 - f) + self.table[(j + 1).min(last)] * f
    }

    /// How sharply the link determines δ: the table's median minus its minimum.
    fn sharpness(&self) -> f64 {
        let mut sorted = self.table.clone();
        sorted.sort_by(f64::total_cmp);
        sorted[sorted.len() / 2] - sorted[0]
    }

    /// The δ of the table's minimum.
    fn best_delta(&self, range: f64) -> f64 {
        let j = (0..self.table.len())
            .min_by(|&i, &j| self.table[i].total_cmp(&self.table[j]))
            .unwrap_or(0);
        -range + j as f64 * GRID_STEP
    }
}

/// One log-scale s per group, searched as s = centre + u (every group at median depth 1 for
/// u = 0). Returns the scales and the number of sweeps. Coordinate descent finds a local
/// minimum, so it runs from two starts, the spanning-tree start and u = 0 (all groups at the
/// same median depth), and keeps the lower energy.
fn solve_groups(problem: &Problem, params: &ScaleParams) -> (Vec<f64>, usize) {
    let count = problem.group_sizes.len();
    let range = 2.0 * params.band.max(1.0 + 1e-6).ln();
    let links = group_links(problem, range);
    let reference = problem.largest_group();
    let band = params.band.max(1.0).ln();
    let group_energy = |u: &[f64]| -> f64 {
        links
            .iter()
            .map(|l| l.value(problem, u[l.a] - u[l.b]))
            .sum()
    };
    let mut best: Option<(f64, Vec<f64>)> = None;
    let mut sweeps = 0;
    for start in [
        initial_log_scales(&links, count, reference, range, band),
        vec![0.0; count],
    ] {
        let mut u = start;
        sweeps += descend_groups(problem, &links, &mut u, reference, band, range);
        let e = group_energy(&u);
        if best.as_ref().is_none_or(|(b, _)| e < *b) {
            best = Some((e, u));
        }
    }
    let u = best.map(|(_, u)| u).unwrap_or_else(|| vec![0.0; count]);
    let s: Vec<f64> = u.iter().zip(&problem.centre).map(|(u, c)| u + c).collect();
    (s, sweeps)
}

/// The terms between different groups, tabulated per group pair.
fn group_links(problem: &Problem, range: f64) -> Vec<Link> {
    let mut by_pair: std::collections::BTreeMap<(usize, usize), Vec<(f64, usize)>> =
        Default::default();
    for (t, term) in problem.terms.iter().enumerate() {
        let (gi, gk) = (problem.group_of[term.i], problem.group_of[term.k]);
        if gi != gk {
            let sign = if gi < gk { 1.0 } else { -1.0 };
            by_pair
                .entry((gi.min(gk), gi.max(gk)))
                .or_default()
                .push((sign, t));
        }
    }
    let samples = (2.0 * range / GRID_STEP).round() as usize + 1;
    by_pair
        .into_iter()
        .map(|((a, b), terms)| {
            let mut link = Link {
                a,
                b,
                offset: problem.centre[a] - problem.centre[b],
                terms,
                table: Vec::new(),
            };
            link.table = (0..samples)
                .map(|j| link.value(problem, -range + j as f64 * GRID_STEP))
                .collect();
            link
        })
        .collect()
}

/// Start: walk a maximum spanning tree of the links' sharpness from the reference group, giving
/// each group the best log-ratio to its tree parent, kept within ±`band` of the reference (at
/// 0). Groups not linked keep 0.
fn initial_log_scales(
    links: &[Link],
    count: usize,
    reference: Option<usize>,
    range: f64,
    band: f64,
) -> Vec<f64> {
    let mut s = vec![0.0; count];
    let Some(root) = reference else { return s };
    let sharp: Vec<f64> = links.iter().map(Link::sharpness).collect();
    let mut order: Vec<usize> = (0..links.len()).collect();
    order.sort_by(|&x, &y| sharp[y].total_cmp(&sharp[x]).then(x.cmp(&y)));
    let mut placed = vec![false; count];
    placed[root] = true;
    // Prim's algorithm on the sorted links: repeatedly take the sharpest link leaving the tree.
    while let Some(e) = order
        .iter()
        .copied()
        .find(|&e| placed[links[e].a] != placed[links[e].b])
    {
        let l = &links[e];
        let delta = l.best_delta(range);
        if placed[l.a] {
            s[l.b] = (s[l.a] - delta).clamp(-band, band);
            placed[l.b] = true;
        } else {
            s[l.a] = (s[l.b] + delta).clamp(-band, band);
            placed[l.a] = true;
        }
    }
    s
}

/// Coordinate descent over groups: each in turn moves to the minimum of its links' φ (grid over
/// the band around the reference, then golden section on the exact terms). Returns the sweeps.
fn descend_groups(
    problem: &Problem,
    links: &[Link],
    s: &mut [f64],
    reference: Option<usize>,
    band: f64,
    range: f64,
) -> usize {
    let count = s.len();
    let mut touching = vec![Vec::new(); count];
    for (e, l) in links.iter().enumerate() {
        touching[l.a].push(e);
        touching[l.b].push(e);
    }
    let centre = reference.map_or(0.0, |r| s[r]);
    let local = |g: usize, value: f64, s: &[f64], exact: bool| -> f64 {
        touching[g]
            .iter()
            .map(|&e| {
                let l = &links[e];
                let delta = if l.a == g {
                    value - s[l.b]
                } else {
                    s[l.a] - value
                };
                if exact {
                    l.value(problem, delta)
                } else {
                    l.lookup(delta, range)
                }
            })
            .sum()
    };
    let steps = (2.0 * band / GRID_STEP).round() as usize;
    let mut sweeps = 0;
    for _ in 0..20 {
        sweeps += 1;
        let mut moved = false;
        for g in 0..count {
            if Some(g) == reference || touching[g].is_empty() {
                continue;
            }
            let current = local(g, s[g], s, true);
            let best = (0..=steps)
                .map(|j| centre - band + j as f64 * GRID_STEP)
                .min_by(|&a, &b| local(g, a, s, false).total_cmp(&local(g, b, s, false)))
                .unwrap_or(s[g]);
            let (lo, hi) = (
                (best - GRID_STEP).max(centre - band),
                (best + GRID_STEP).min(centre + band),
            );
            let refined = golden(lo, hi, |v| local(g, v, s, true));
            if local(g, refined, s, true) < current - 1e-12 {
                moved |= (refined - s[g]).abs() > 1e-4;
                s[g] = refined;
            }
        }
        if !moved {
            break;
        }
    }
    sweeps
}

/// Golden-section minimisation of `f` on [lo, hi].
fn golden(mut lo: f64, mut hi: f64, f: impl Fn(f64) -> f64) -> f64 {
    let g = 0.618_033_988_749_895;
    let (mut c, mut d) = (hi - g * (hi - lo), lo + g * (hi - lo));
    let (mut fc, mut fd) = (f(c), f(d));
    for _ in 0..20 {
        if fc <= fd {
            (hi, d, fd) = (d, c, fc);
            c = hi - g * (hi - lo);
            fc = f(c);
        } else {
            (lo, c, fc) = (c, d, fd);
            d = lo + g * (hi - lo);
            fd = f(d);
        }
    }
    if fc <= fd { c } else { d }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn golden_search_finds_a_minimum() {
        let x = golden(-1.0, 2.0, |s| (s - 0.7).powi(2));
        assert!((x - 0.7).abs() < 1e-4, "{x}");
    }

    #[test]
    fn a_contact_term_vanishes_at_the_true_ratio() {
        // Two pieces meeting at depth 10; the second was reconstructed at twice the scale.
        let a = Vector3::new(0.0, 0.0, 10.0);
        let b = a * 2.0;
        let term = Term::Contact {
            w: 1.0,
            p: [a, b],
            p2: [a, b],
        };
        // λ_a / λ_b = 2 joins them: δ = ln 2.
        assert!(term.value(2.0f64.ln(), 0.05) < 1e-12);
        assert!(
            (term.value(0.0, 0.05) - 0.1).abs() < 1e-12,
            "truncated at σ"
        );
    }

    #[test]
    fn contact_evidence_trusts_creases_and_continuous_flow() {
        let floor = Vector3::new(0.0, 1.0, 0.0);
        let front = Vector3::new(0.0, 0.0, 1.0);
        let jump = ([0.0, 0.0], [5.0, 0.0]);
        // Perpendicular planes: a crease, full weight even though the flow jumps.
        assert!((contact_evidence(&floor, &front, jump.0, jump.1) - 1.0).abs() < 1e-12);
        // Parallel planes with a flow jump: an occlusion, minimum weight.
        assert!((contact_evidence(&front, &front, jump.0, jump.1) - 0.2).abs() < 1e-12);
        // Parallel planes moving together: a continuing surface, full weight.
        assert!((contact_evidence(&front, &front, [1.0, 2.0], [1.0, 2.0]) - 1.0).abs() < 1e-12);
    }
}
