//! The terms between two rigid segments that the segment solve minimises: their links' contacts
//! and the figure, ground, rest and static priors (see the parent module, step 2).
//! Their tests run through the segment solve and live in `segments`.

use super::ScaleParams;
use super::contact::{Link, Problem};
use super::minimise::{Step, steps_at, truncated};
use super::segments::Segments;
use crate::numeric::weighted_median;

/// The terms between two segments g < h as functions of d = u_g − u_h (segment offsets u,
/// log-scale s = centre + u).
#[derive(Clone, Debug, Default)]
pub(super) struct Pair {
    /// Their links' contact terms and the rest prior's (and the static prior's): Σ w min(|d + c|,
    /// σ).
    pub(super) terms: Vec<(f64, f64)>,
    /// The figure prior, one step per link: the smaller segment's cost for lying behind the
    /// larger one, where the weighted median of the link's frame-1 gaps puts it more than σ
    /// behind (empty with a zero [`ScaleParams::behind_weight`]).
    pub(super) behind: Vec<Step>,
    /// The ground prior, one step per piece of the pair's segment that is not the static
    /// world's (the other one): its cost for lying more than σ under the ground
    /// ([`ScaleParams::ground_weight`]).
    pub(super) under: Vec<Step>,
}

impl Pair {
    pub(super) fn value(&self, d: f64, sigma: f64) -> f64 {
        truncated(&self.terms, d, sigma)
            + steps_at(&self.behind, d, sigma)
            + steps_at(&self.under, d, sigma)
    }

    /// Both priors' steps.
    pub(super) fn steps(&self) -> impl Iterator<Item = &Step> {
        self.behind.iter().chain(&self.under)
    }
}

/// Every pair of segments (g < h) that touch or share a prior (the static, ground and rest priors
/// tie segments to the static world's) and its [`Pair`].
pub(super) type PairTerms = std::collections::BTreeMap<(usize, usize), Pair>;

/// Every link between two different segments, gathered into [`PairTerms`], with the figure
/// prior ([`ScaleParams::behind_weight`]) where the smaller segment is a mover and the flow
/// across the link is not continuous and trusted, the ground prior, the rest prior
/// ([`ScaleParams::rest_weight`]) and the static prior ([`ScaleParams::static_weight`]).
pub(super) fn segment_pair_terms(
    problem: &Problem,
    segments: &Segments,
    params: &ScaleParams,
) -> PairTerms {
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

/// True when segment `g` is the figure against `h` (the smaller of the two, by pieces; the
/// later one on a tie): the side the figure prior keeps from lying behind.
fn is_figure(sizes: &[usize], g: usize, h: usize) -> bool {
    (sizes[g], std::cmp::Reverse(g)) < (sizes[h], std::cmp::Reverse(h))
}
