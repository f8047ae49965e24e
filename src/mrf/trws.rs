//! Sequential tree-reweighted message passing, TRW-S (Kolmogorov, "Convergent Tree-Reweighted
//! Message Passing for Energy Minimization", TPAMI 2006), for pairwise energies
//!
//! E(x) = Σ_i θ_i(x_i) + Σ_(a,b) θ_ab(x_a, x_b)
//!
//! with any number of labels per node and arbitrary tables. Nodes are processed in index order:
//! a forward pass sends messages along edges to later nodes, a backward pass to earlier ones.
//! Node i's belief is split among the monotonic chains through it with weight
//! γ_i = 1 / max(edges to earlier nodes, edges to later nodes). On a tree (and so on a chain)
//! the result is exact; in general it is a good labelling plus a lower bound on the minimum,
//! computed by minimising every chain of the decomposition exactly (`lower_bound`).

use crate::numeric::min;

/// A pairwise table between nodes `a < b`: `cost[x_a · labels(b) + x_b]`.
#[derive(Clone, Debug)]
pub struct Edge {
    pub a: usize,
    pub b: usize,
    pub cost: Vec<f64>,
}

/// A pairwise MRF: per-node unary costs and pairwise tables.
#[derive(Clone, Debug, Default)]
pub struct Mrf {
    pub unary: Vec<Vec<f64>>,
    pub edges: Vec<Edge>,
}

/// Settings of [`trws`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrwsOptions {
    /// Forward + backward passes at most.
    pub iterations: usize,
}

impl Default for TrwsOptions {
    fn default() -> Self {
        TrwsOptions { iterations: 20 }
    }
}

/// The labelling TRW-S found, its energy and the lower bound on the minimum energy.
#[derive(Clone, Debug, PartialEq)]
pub struct TrwsResult {
    pub labels: Vec<usize>,
    pub energy: f64,
    pub lower_bound: f64,
}

impl Mrf {
    /// An MRF over nodes with these unary tables and no edges yet.
    pub fn new(unary: Vec<Vec<f64>>) -> Self {
        Mrf {
            unary,
            edges: Vec::new(),
        }
    }

    /// Adds θ_ab with `cost[x_a · labels(b) + x_b]`. An edge given with `a > b` is stored
    /// transposed; a self-edge, an unknown node or a table of the wrong size is ignored.
    pub fn add_edge(&mut self, a: usize, b: usize, cost: Vec<f64>) {
        let n = self.unary.len();
        if a == b || a >= n || b >= n || cost.len() != self.unary[a].len() * self.unary[b].len() {
            return;
        }
        if a < b {
            self.edges.push(Edge { a, b, cost });
        } else {
            let (la, lb) = (self.unary[a].len(), self.unary[b].len());
            let mut t = vec![0.0; cost.len()];
            for xa in 0..la {
                for xb in 0..lb {
                    t[xb * la + xa] = cost[xa * lb + xb];
                }
            }
            self.edges.push(Edge {
                a: b,
                b: a,
                cost: t,
            });
        }
    }

    /// E(labels).
    pub fn energy(&self, labels: &[usize]) -> f64 {
        let unary: f64 = self.unary.iter().zip(labels).map(|(u, &x)| u[x]).sum();
        let pairwise: f64 = self
            .edges
            .iter()
            .map(|e| e.cost[labels[e.a] * self.unary[e.b].len() + labels[e.b]])
            .sum();
        unary + pairwise
    }

    fn labels(&self, i: usize) -> usize {
        self.unary[i].len()
    }
}

/// Per node: its edges to earlier nodes (it is `b`) and to later nodes (it is `a`).
struct Incidence {
    earlier: Vec<Vec<usize>>,
    later: Vec<Vec<usize>>,
}

impl Incidence {
    fn new(mrf: &Mrf) -> Self {
        let n = mrf.unary.len();
        let (mut earlier, mut later) = (vec![Vec::new(); n], vec![Vec::new(); n]);
        for (e, edge) in mrf.edges.iter().enumerate() {
            later[edge.a].push(e);
            earlier[edge.b].push(e);
        }
        Incidence { earlier, later }
    }

    /// γ_i = 1 / (number of monotonic chains through node i).
    fn gamma(&self, i: usize) -> f64 {
        1.0 / self.earlier[i].len().max(self.later[i].len()).max(1) as f64
    }
}

/// Messages of every edge: `to_b[e]` (over b's labels) and `to_a[e]` (over a's labels).
struct Messages {
    to_b: Vec<Vec<f64>>,
    to_a: Vec<Vec<f64>>,
}

impl Messages {
    fn new(mrf: &Mrf) -> Self {
        Messages {
            to_b: mrf
                .edges
                .iter()
                .map(|e| vec![0.0; mrf.labels(e.b)])
                .collect(),
            to_a: mrf
                .edges
                .iter()
                .map(|e| vec![0.0; mrf.labels(e.a)])
                .collect(),
        }
    }

    /// θ̂_i = θ_i + every message into i.
    fn belief(&self, mrf: &Mrf, inc: &Incidence, i: usize) -> Vec<f64> {
        let mut b = mrf.unary[i].clone();
        for &e in &inc.earlier[i] {
            add(&mut b, &self.to_b[e]);
        }
        for &e in &inc.later[i] {
            add(&mut b, &self.to_a[e]);
        }
        b
    }
}

fn add(acc: &mut [f64], v: &[f64]) {
    acc.iter_mut().zip(v).for_each(|(a, b)| *a += b);
}

/// Subtracts the minimum so messages stay bounded.
fn normalise(v: &mut [f64]) {
    let m = v.iter().copied().fold(f64::INFINITY, min);
    if m.is_finite() {
        v.iter_mut().for_each(|x| *x -= m);
    }
}

/// Minimises `mrf` by TRW-S. Returns the best labelling seen (by exact energy) and the
/// best lower bound.
pub fn trws(mrf: &Mrf, options: &TrwsOptions) -> TrwsResult {
    let n = mrf.unary.len();
    let inc = Incidence::new(mrf);
    let mut msg = Messages::new(mrf);
    let mut best: Option<(f64, Vec<usize>)> = None;
    for _ in 0..options.iterations.max(1) {
        // Forward pass: messages to later nodes, and a labelling chosen in order.
        let mut labels = vec![0usize; n];
        for i in 0..n {
            let belief = msg.belief(mrf, &inc, i);
            labels[i] = choose_label(mrf, &inc, &msg, i, &labels);
            let g = inc.gamma(i);
            for &e in &inc.later[i] {
                let edge = &mrf.edges[e];
                let (la, lb) = (mrf.labels(edge.a), mrf.labels(edge.b));
                let mut out = vec![f64::INFINITY; lb];
                for (xa, (&bel, &back)) in belief.iter().zip(&msg.to_a[e]).enumerate().take(la) {
                    let base = g * bel - back;
                    let row = &edge.cost[xa * lb..(xa + 1) * lb];
                    for (o, &c) in out.iter_mut().zip(row) {
                        *o = min(*o, base + c);
                    }
                }
                normalise(&mut out);
                msg.to_b[e] = out;
            }
        }
        let e = mrf.energy(&labels);
        if best.as_ref().is_none_or(|(b, _)| e < *b) {
            best = Some((e, labels));
        }
        // Backward pass: messages to earlier nodes.
        for i in (0..n).rev() {
            let belief = msg.belief(mrf, &inc, i);
            let g = inc.gamma(i);
            for &e in &inc.earlier[i] {
                let edge = &mrf.edges[e];
                let (la, lb) = (mrf.labels(edge.a), mrf.labels(edge.b));
                let base: Vec<f64> = (0..lb).map(|xb| g * belief[xb] - msg.to_b[e][xb]).collect();
                let mut out = vec![f64::INFINITY; la];
                for (xa, o) in out.iter_mut().enumerate() {
                    let row = &edge.cost[xa * lb..(xa + 1) * lb];
                    *o = row
                        .iter()
                        .zip(&base)
                        .map(|(c, b)| c + b)
                        .fold(f64::INFINITY, min);
                }
                normalise(&mut out);
                msg.to_a[e] = out;
            }
        }
    }
    let (energy, labels) = best.unwrap_or((mrf.energy(&vec![0; n]), vec![0; n]));
    TrwsResult {
        labels,
        energy,
        lower_bound: lower_bound(mrf, &inc, &msg).min(energy),
    }
}

/// Node i's label given the labels of earlier nodes: its unary, the exact tables to earlier
/// nodes and the messages from later ones.
fn choose_label(mrf: &Mrf, inc: &Incidence, msg: &Messages, i: usize, labels: &[usize]) -> usize {
    let mut cost = mrf.unary[i].clone();
    for &e in &inc.earlier[i] {
        let edge = &mrf.edges[e];
        let lb = mrf.labels(i);
        let row = &edge.cost[labels[edge.a] * lb..(labels[edge.a] + 1) * lb];
        add(&mut cost, row);
    }
    for &e in &inc.later[i] {
        add(&mut cost, &msg.to_a[e]);
    }
    argmin(&cost)
}

fn argmin(v: &[f64]) -> usize {
    (0..v.len())
        .min_by(|&a, &b| v[a].total_cmp(&v[b]))
        .unwrap_or(0)
}

/// The lower bound of the chain decomposition: the energy is the sum of monotonic chains (each
/// node's incoming edges paired with its outgoing ones), where every chain through node i
/// carries γ_i θ̂_i and each edge its reparametrised table θ_ab − m_→b − m_→a; the sum of the
/// chains' exact minima (dynamic programming) is at most the minimum of E.
fn lower_bound(mrf: &Mrf, inc: &Incidence, msg: &Messages) -> f64 {
    let n = mrf.unary.len();
    let beliefs: Vec<Vec<f64>> = (0..n).map(|i| msg.belief(mrf, inc, i)).collect();
    // next[e]: the edge that continues the chain of edge e beyond its node b.
    let mut next = vec![usize::MAX; mrf.edges.len()];
    let mut starts = Vec::new(); // chains start with an edge out of a node...
    let mut single = Vec::new(); // ...or are a lone node without edges
    for i in 0..n {
        let (ein, eout) = (&inc.earlier[i], &inc.later[i]);
        for (k, &e) in ein.iter().enumerate() {
            if let Some(&f) = eout.get(k) {
                next[e] = f;
            }
        }
        starts.extend(eout.iter().skip(ein.len()).copied());
        if ein.is_empty() && eout.is_empty() {
            single.push(i);
        }
    }
    let scaled = |i: usize| -> Vec<f64> {
        let g = inc.gamma(i);
        beliefs[i].iter().map(|b| g * b).collect()
    };
    let mut bound: f64 = single
        .iter()
        .map(|&i| mrf.unary[i].iter().copied().fold(f64::INFINITY, min))
        .sum();
    for &start in &starts {
        // Viterbi along the chain: cost-to-here per label of the current node.
        let mut acc = scaled(mrf.edges[start].a);
        let mut e = start;
        while e != usize::MAX {
            let edge = &mrf.edges[e];
            let (la, lb) = (mrf.labels(edge.a), mrf.labels(edge.b));
            let node_b = scaled(edge.b);
            let mut out = vec![f64::INFINITY; lb];
            for (xa, (&a, &back)) in acc.iter().zip(&msg.to_a[e]).enumerate().take(la) {
                let base = a - back;
                let row = &edge.cost[xa * lb..(xa + 1) * lb];
                for ((o, &c), &m) in out.iter_mut().zip(row).zip(&msg.to_b[e]) {
                    *o = min(*o, base + c - m);
                }
            }
            acc = out.iter().zip(&node_b).map(|(o, b)| o + b).collect();
            e = next[e];
        }
        bound += acc.iter().copied().fold(f64::INFINITY, min);
    }
    bound
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    /// A random MRF with `labels` labels per node over the given edges.
    fn random_mrf(rng: &mut Rng, n: usize, labels: usize, edges: &[(usize, usize)]) -> Mrf {
        let unary = (0..n)
            .map(|_| (0..labels).map(|_| rng.uniform() * 4.0).collect())
            .collect();
        let mut mrf = Mrf::new(unary);
        for &(a, b) in edges {
            mrf.add_edge(
                a,
                b,
                (0..labels * labels).map(|_| rng.uniform() * 4.0).collect(),
            );
        }
        mrf
    }

    /// The exact minimum by enumerating every labelling.
    fn brute_force(mrf: &Mrf) -> f64 {
        let n = mrf.unary.len();
        let mut labels = vec![0usize; n];
        let mut best = f64::INFINITY;
        loop {
            best = best.min(mrf.energy(&labels));
            let mut i = 0;
            loop {
                if i == n {
                    return best;
                }
                labels[i] += 1;
                if labels[i] < mrf.unary[i].len() {
                    break;
                }
                labels[i] = 0;
                i += 1;
            }
        }
    }

    #[test]
    fn exact_on_chains() {
        let mut rng = Rng::new(1);
        for _ in 0..20 {
            let edges: Vec<(usize, usize)> = (0..6).map(|i| (i, i + 1)).collect();
            let mrf = random_mrf(&mut rng, 7, 3, &edges);
            let r = trws(&mrf, &TrwsOptions::default());
            let exact = brute_force(&mrf);
            assert!((r.energy - exact).abs() < 1e-9, "{} vs {exact}", r.energy);
            assert!(
                (r.lower_bound - exact).abs() < 1e-6,
                "bound {} vs {exact}",
                r.lower_bound
            );
        }
    }

    #[test]
    fn exact_on_trees_in_any_node_order() {
        let mut rng = Rng::new(2);
        for _ in 0..20 {
            // A random tree: each node after the first hangs on a random earlier node, with
            // edges given in either orientation.
            let n = 8;
            let edges: Vec<(usize, usize)> = (1..n)
                .map(|i| {
                    let p = rng.below(i);
                    if rng.uniform() < 0.5 { (p, i) } else { (i, p) }
                })
                .collect();
            let mrf = random_mrf(&mut rng, n, 3, &edges);
            let r = trws(&mrf, &TrwsOptions::default());
            let exact = brute_force(&mrf);
            assert!((r.energy - exact).abs() < 1e-9, "{} vs {exact}", r.energy);
        }
    }

    #[test]
    fn bound_below_the_minimum_and_labelling_near_it_on_loopy_graphs() {
        let mut rng = Rng::new(3);
        let mut gap = 0.0;
        for _ in 0..20 {
            // A 3×3 grid (loops) with one diagonal.
            let mut edges = Vec::new();
            for y in 0..3 {
                for x in 0..3 {
                    let i = y * 3 + x;
                    if x < 2 {
                        edges.push((i, i + 1));
                    }
                    if y < 2 {
                        edges.push((i, i + 3));
                    }
                }
            }
            edges.push((0, 4));
            let mrf = random_mrf(&mut rng, 9, 3, &edges);
            let r = trws(&mrf, &TrwsOptions::default());
            let exact = brute_force(&mrf);
            assert!(
                r.lower_bound <= exact + 1e-9,
                "bound {} > min {exact}",
                r.lower_bound
            );
            assert!(r.energy >= exact - 1e-9);
            assert!((mrf.energy(&r.labels) - r.energy).abs() < 1e-9);
            gap += (r.energy - exact) / exact;
        }
        // TRW-S is not exact on loopy graphs, but on small random ones it is close.
        assert!(gap / 20.0 < 0.05, "mean relative gap {}", gap / 20.0);
    }

    #[test]
    fn different_label_counts_and_isolated_nodes() {
        let mut mrf = Mrf::new(vec![vec![3.0, 1.0], vec![0.0, 2.0, 5.0], vec![4.0, 0.5]]);
        // Node 2 stays isolated; the edge, given as (1, 0) with cost[x1 · 2 + x0], strongly
        // prefers x1 = 2 with x0 = 0.
        let mut t = vec![10.0; 6];
        t[2 * 2] = -20.0;
        mrf.add_edge(1, 0, t);
        let r = trws(&mrf, &TrwsOptions::default());
        assert_eq!(r.labels, vec![0, 2, 1]);
        assert!((r.energy - (3.0 + 5.0 - 20.0 + 0.5)).abs() < 1e-12);
        assert!((r.lower_bound - r.energy).abs() < 1e-9);
    }
}
