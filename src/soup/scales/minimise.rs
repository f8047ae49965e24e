//! The exact one-dimensional minimiser every step of the scale solve uses: a sum of truncated
//! absolute values Σ w min(|x + c|, σ) plus one-sided steps, minimised over an interval by one
//! sweep over its sorted breakpoints, and tested against a plain evaluation at every candidate.

/// Σ w min(|x + c|, σ).
pub(super) fn truncated(terms: &[(f64, f64)], x: f64, sigma: f64) -> f64 {
    terms
        .iter()
        .map(|&(w, c)| w * (x + c).abs().min(sigma))
        .sum()
}

/// A one-sided cost of a segment's log-scale x: `k` when `dir` · (x + c) > σ, where x + c is a
/// log-depth gap: to a larger neighbour in frame 1 (with `dir` = 1 the cost is paid when the
/// segment lies more than σ behind it, see [`super::ScaleParams::behind_weight`]), or to the ground
/// (paid when a piece lies more than σ under it, see [`super::ScaleParams::ground_weight`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Step {
    pub k: f64,
    pub c: f64,
    pub dir: f64,
}

impl Step {
    /// The x where the step switches: dir · σ − c. It is free there (the minimiser may stop on
    /// it), so activity is tested against this same number and rounding cannot make the step
    /// fire at its own edge.
    fn edge(&self, sigma: f64) -> f64 {
        self.dir * sigma - self.c
    }

    /// Whether the step's cost is paid at x: beyond its edge in the direction `dir`.
    fn is_active(&self, x: f64, sigma: f64) -> bool {
        let edge = self.edge(sigma);
        if self.dir > 0.0 { x > edge } else { x < edge }
    }
}

/// Σ k over the steps active at x.
pub(super) fn steps_at(steps: &[Step], x: f64, sigma: f64) -> f64 {
    steps
        .iter()
        .filter(|st| st.is_active(x, sigma))
        .map(|st| st.k)
        .sum()
}

/// The exact minimiser of Σ w min(|x + c|, σ) + Σ steps over x in [lo, hi], preferring
/// `current` on ties. The truncated sum is piecewise linear, concave except at its kinks −c, and
/// a step only adds a constant on one side of its edge, so the minimum lies at a kink, at a
/// step's edge (on its free side) or at a bound.
///
/// One sweep over the sorted breakpoints (−c − σ, −c, −c + σ), between which the sum is linear,
/// gives its value at every candidate in O(n log n) instead of O(n²) (segments of the background
/// carry thousands of terms); `minimise_contacts_plain` (in the tests) is the reference it is
/// tested against.
pub(super) fn minimise_contacts(
    terms: &[(f64, f64)],
    steps: &[Step],
    sigma: f64,
    current: f64,
    lo: f64,
    hi: f64,
) -> f64 {
    let events = breakpoints(terms, steps, sigma);
    // Steps by edge, to add the active ones at each candidate by binary search.
    let edges = |dir: f64| {
        let mut v: Vec<(f64, f64)> = steps
            .iter()
            .filter(|st| st.dir == dir)
            .map(|st| (st.edge(sigma), st.k))
            .collect();
        v.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut sum = 0.0;
        let prefix: Vec<f64> = std::iter::once(0.0)
            .chain(v.iter().map(|e| {
                sum += e.1;
                sum
            }))
            .collect();
        (v, prefix)
    };
    let (behind, behind_sum) = edges(1.0);
    let (ahead, ahead_sum) = edges(-1.0);
    let step_cost = |x: f64| {
        // dir = 1: active when x > edge; dir = −1: active when x < edge.
        let below = behind.partition_point(|e| e.0 < x);
        let above = ahead.partition_point(|e| e.0 <= x);
        behind_sum[below] + (ahead_sum[ahead.len()] - ahead_sum[above])
    };
    let mut value: f64 = terms.iter().map(|&(w, _)| w * sigma).sum();
    let (mut slope, mut at) = (0.0, f64::NEG_INFINITY);
    let mut best_candidate: Option<(f64, f64)> = None;
    for &(x, change, candidate) in &events {
        if at.is_finite() {
            value += slope * (x - at);
        }
        at = x;
        if candidate && (lo..=hi).contains(&x) {
            let total = value + step_cost(x);
            if best_candidate.is_none_or(|(v, _)| total < v) {
                best_candidate = Some((total, x));
            }
        }
        slope += change;
    }
    let total = |x: f64| truncated(terms, x, sigma) + steps_at(steps, x, sigma);
    let mut best = (total(current), current);
    let candidates = best_candidate.map(|(_, x)| x).into_iter().chain([lo, hi]);
    for x in candidates.filter(|x| (lo..=hi).contains(x)) {
        let e = total(x);
        if e < best.0 - 1e-12 {
            best = (e, x);
        }
    }
    best.1
}

/// The breakpoints of [`minimise_contacts`]' sum in ascending position: (position, slope
/// change, is a candidate). Each term's kink −c (a candidate, slope +2w) and its truncation
/// points −c ± σ (slope −w), and each step's edge (a candidate where the step is still free).
/// The kinks are sorted once and the three shifted copies merged, a third of the sorting of
/// all 3n points.
fn breakpoints(terms: &[(f64, f64)], steps: &[Step], sigma: f64) -> Vec<(f64, f64, bool)> {
    let mut kinks: Vec<(f64, f64)> = terms.iter().map(|&(w, c)| (-c, w)).collect();
    kinks.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut edges: Vec<f64> = steps.iter().map(|st| st.edge(sigma)).collect();
    edges.sort_by(f64::total_cmp);
    // Four ascending streams (shifting by σ keeps the order): lower truncations, kinks, upper
    // truncations, step edges.
    let streams: [Vec<(f64, f64, bool)>; 4] = [
        kinks.iter().map(|&(x, w)| (x - sigma, -w, false)).collect(),
        kinks.iter().map(|&(x, w)| (x, 2.0 * w, true)).collect(),
        kinks.iter().map(|&(x, w)| (x + sigma, -w, false)).collect(),
        edges.iter().map(|&x| (x, 0.0, true)).collect(),
    ];
    let mut next = [0; 4];
    let mut events = Vec::with_capacity(streams.iter().map(Vec::len).sum());
    while let Some(i) = (0..4)
        .filter(|&i| next[i] < streams[i].len())
        .min_by(|&i, &j| streams[i][next[i]].0.total_cmp(&streams[j][next[j]].0))
    {
        events.push(streams[i][next[i]]);
        next[i] += 1;
    }
    events
}

/// [`minimise_contacts`] by evaluating the sum at every candidate: the plain reference.
#[cfg(test)]
fn minimise_contacts_plain(
    terms: &[(f64, f64)],
    steps: &[Step],
    sigma: f64,
    current: f64,
    lo: f64,
    hi: f64,
) -> f64 {
    let total = |x: f64| truncated(terms, x, sigma) + steps_at(steps, x, sigma);
    let mut best = (total(current), current);
    for x in terms
        .iter()
        .map(|&(_, c)| -c)
        .chain(steps.iter().map(|st| st.edge(sigma)))
        .chain([lo, hi])
        .filter(|x| (lo..=hi).contains(x))
    {
        let e = total(x);
        if e < best.0 - 1e-12 {
            best = (e, x);
        }
    }
    best.1
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    #[test]
    fn contact_sums_are_minimised_exactly() {
        // Against a fine grid and the plain reference, on random sums of truncated absolute
        // values with and without one-sided steps.
        let mut rng = Rng::new(5);
        for round in 0..100 {
            let terms: Vec<(f64, f64)> = (0..7)
                .map(|_| (rng.uniform() + 0.1, 2.0 * rng.uniform() - 1.0))
                .collect();
            let steps: Vec<Step> = (0..if round % 2 == 0 { 0 } else { 3 })
                .map(|_| Step {
                    k: rng.uniform() * 0.3,
                    c: 2.0 * rng.uniform() - 1.0,
                    dir: if rng.uniform() < 0.5 { 1.0 } else { -1.0 },
                })
                .collect();
            let sigma = 0.05 + 0.3 * rng.uniform();
            let total = |x: f64| truncated(&terms, x, sigma) + steps_at(&steps, x, sigma);
            let x = minimise_contacts(&terms, &steps, sigma, 0.3, -2.0, 2.0);
            let grid = (0..=40_000)
                .map(|j| total(-2.0 + j as f64 * 1e-4))
                .fold(f64::INFINITY, f64::min);
            assert!(total(x) <= grid + 1e-12, "round {round}");
            assert!((-2.0..=2.0).contains(&x));
            let plain = minimise_contacts_plain(&terms, &steps, sigma, 0.3, -2.0, 2.0);
            assert!(
                (total(x) - total(plain)).abs() < 1e-9,
                "sweep {x} vs plain {plain}"
            );
        }
    }

    #[test]
    fn a_minimum_on_a_step_edge_is_found() {
        // One term pulls x past a heavy step's edge, so the minimum sits exactly on the edge.
        // With random offsets, dir · (edge + c) often rounds to just above σ: the step must
        // still count as free there (it did not once, and the minimiser then gave up the edge).
        let mut rng = Rng::new(11);
        let mut rounded_past_edge = 0;
        for round in 0..2000 {
            let sigma = 0.05 + 0.3 * rng.uniform();
            let dir = if round % 2 == 0 { 1.0 } else { -1.0 };
            let step = Step {
                k: 10.0,
                c: 2.0 * rng.uniform() - 1.0,
                dir,
            };
            let edge = step.edge(sigma);
            if dir * (edge + step.c) > sigma {
                rounded_past_edge += 1;
            }
            // The term's own minimum lies 0.5σ beyond the edge, on the step's costly side.
            let terms = [(1.0, -(edge + dir * 0.5 * sigma))];
            let total = |x: f64| truncated(&terms, x, sigma) + steps_at(&[step], x, sigma);
            let best = total(edge);
            assert!(best < 0.5 * sigma + 1e-9, "round {round}: the edge is free");
            for minimise in [minimise_contacts, minimise_contacts_plain] {
                let x = minimise(&terms, &[step], sigma, 0.0, -3.0, 3.0);
                assert!(
                    total(x) <= best + 1e-12,
                    "round {round}: {x} vs edge {edge}"
                );
            }
        }
        assert!(rounded_past_edge > 0, "the rounding case is exercised");
    }
}
