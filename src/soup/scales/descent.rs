//! Step 2 of the scale solve (see the parent module): the offsets of the rigid segments'
//! log-scales by coordinate descent over the terms between segments ([`PairTerms`]), from three
//! starts: a spanning tree of the strongest segment pairs, equal scales, and a joint labelling of
//! every segment on a grid of offsets by TRW-S.

use super::ScaleParams;
use super::contact::Problem;
use super::minimise::{Step, minimise_contacts};
use super::priors::{PairTerms, segment_pair_terms};
use super::segments::Segments;
use crate::mrf::trws::{Mrf, TrwsOptions, trws};
use crate::numeric::ln;

/// Coordinate descent over segment offsets u (log-scale s = centre + u), from three starts;
/// returns the better u and the sweeps run. Only links between segments depend on u, so the
/// descent works on [`PairTerms`].
pub(super) fn solve_segments(
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

#[cfg(test)]
mod tests {
    use super::super::contact::Link;
    use super::*;

    #[test]
    fn a_given_start_is_solved_within_the_band_like_the_solve_itself() {
        // The truth test's start can put a one-piece segment far from the rest (its contact
        // would hold it at δ = 5, past the band of ln 12); the solve from there must stay in
        // the band the solve's own starts keep to, or the two objectives are not comparable.
        let problem = Problem {
            links: vec![
                Link::single(0, 1, 1.0, 0.0),
                Link::single(1, 2, 1.0, 0.0),
                Link::single(3, 0, 0.5, -5.0),
            ],
            touching: vec![vec![0, 2], vec![0, 1], vec![1], vec![2]],
            sigma: 0.1,
        };
        let segments = Segments::of_pieces(&[0, 0, 0, 1], &[0.0, 0.0], &[true, false]);
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
    fn the_discrete_start_moves_segments_together() {
        // Segments 1 and 2 are tied to each other (equal scales) and each, more weakly, to
        // segment 0 at a log-scale 1 below it. Moving either alone breaks the strong tie, so
        // coordinate descent from equal scales stays there; the joint labelling moves both.
        // (The figure prior is off, so the links' flow does not matter.)
        let links = vec![
            Link::single(0, 1, 0.6, -1.0),
            Link::single(0, 2, 0.6, -1.0),
            Link::single(1, 2, 1.0, 0.0),
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
        let segments = Segments::of_pieces(&[0, 1, 2], &[0.0; 3], &[false; 3]);
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
