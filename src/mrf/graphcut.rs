//! Multi-label assignment by graph cuts: α-expansion (Boykov, Veksler, Zabih, TPAMI 2001) for
//! the energy
//!
//! E(L) = Σ_i D_i(L_i) + Σ_(i,k) w_ik [L_i ≠ L_k] + Σ_h c · [h is used],
//!
//! a data cost per node and label, a Potts penalty on graph edges and a cost per label in use
//! (the label cost of PEARL, Isack & Boykov, IJCV 2012). Each expansion move is an exact
//! minimum cut (Dinic's max-flow) of the data and Potts terms; a move is kept only when it
//! lowers the whole energy, label costs included.

/// Data costs `cost(node, label)`, stored per label (labels are added one at a time).
#[derive(Clone, Debug, Default)]
pub struct CostTable {
    nodes: usize,
    columns: Vec<Vec<f32>>,
}

impl CostTable {
    /// An empty table for `nodes` nodes.
    pub fn new(nodes: usize) -> Self {
        CostTable {
            nodes,
            columns: Vec::new(),
        }
    }

    /// Number of labels.
    pub fn labels(&self) -> usize {
        self.columns.len()
    }

    /// Number of nodes.
    pub fn nodes(&self) -> usize {
        self.nodes
    }

    /// The cost of giving `node` the label `label`.
    pub fn get(&self, node: usize, label: usize) -> f32 {
        self.columns[label][node]
    }

    /// Sets one cost.
    pub fn set(&mut self, node: usize, label: usize, value: f32) {
        self.columns[label][node] = value;
    }

    /// Appends a label whose costs are all `fill`; returns its index.
    pub fn push_label(&mut self, fill: f32) -> usize {
        self.columns.push(vec![fill; self.nodes]);
        self.columns.len() - 1
    }
}

/// An undirected weighted graph over the nodes: `edges[i]` holds `(k, w_ik)`; each edge appears
/// in both lists with the same weight.
pub type Neighbours = [Vec<(u32, f32)>];

/// The energy of a labelling.
pub fn energy(
    costs: &CostTable,
    neighbours: &Neighbours,
    label_cost: f32,
    labels: &[usize],
) -> f64 {
    let mut e = 0.0f64;
    let mut used = vec![false; costs.labels()];
    for (i, &l) in labels.iter().enumerate() {
        e += costs.get(i, l) as f64;
        used[l] = true;
        for &(k, w) in &neighbours[i] {
            if (k as usize) > i && labels[k as usize] != l {
                e += w as f64;
            }
        }
    }
    e + label_cost as f64 * used.iter().filter(|&&u| u).count() as f64
}

/// An expansion is only tried when some node's cost for the label is within this of its
/// current cost.
const PROMISING: f32 = 0.25;

/// Improves `labels` by expansion moves, trying labels in `order`, sweeping until no move lowers
/// the energy (at most `sweeps` times). Nodes whose cost for the expanding label is `max_cost` or
/// more never switch to it (they would pay the full cap: this keeps each move's graph small).
/// Returns the number of accepted moves.
pub fn alpha_expansion(
    costs: &CostTable,
    neighbours: &Neighbours,
    label_cost: f32,
    max_cost: f32,
    order: &[usize],
    labels: &mut [usize],
    sweeps: usize,
) -> usize {
    let mut accepted = 0;
    let mut current = energy(costs, neighbours, label_cost, labels);
    for _ in 0..sweeps {
        let mut changed = false;
        for &alpha in order {
            // A label no node likes (nearly) as much as its own cannot win a region: skip the cut.
            let promising = labels
                .iter()
                .enumerate()
                .any(|(i, &l)| l != alpha && costs.get(i, alpha) <= costs.get(i, l) + PROMISING);
            if !promising {
                continue;
            }
            let Some(candidate) =
                expansion_move(costs, neighbours, label_cost, alpha, max_cost, labels)
            else {
                continue;
            };
            let e = energy(costs, neighbours, label_cost, &candidate);
            if e < current - 1e-6 {
                labels.copy_from_slice(&candidate);
                current = e;
                accepted += 1;
                changed = true;
            }
        }
        if !changed {
            break;
        }
    }
    accepted
}

/// The best labelling reachable from `labels` by letting any set of nodes switch to `alpha`,
/// label costs included (Delong, Osokin, Isack, Boykov, IJCV 2012): an auxiliary node per label
/// in use pays its cost unless all its nodes switch, and one for α pays α's cost if α is new and
/// any node switches. `None` when no node would switch.
fn expansion_move(
    costs: &CostTable,
    neighbours: &Neighbours,
    label_cost: f32,
    alpha: usize,
    max_cost: f32,
    labels: &[usize],
) -> Option<Vec<usize>> {
    let n = labels.len();
    // Nodes that have α already, or could only take it at the capped cost, are fixed; they
    // enter as unary terms of their free neighbours.
    let free: Vec<bool> = (0..n)
        .map(|i| labels[i] != alpha && costs.get(i, alpha) < max_cost)
        .collect();
    let index: Vec<usize> = {
        let mut next = 0;
        (0..n)
            .map(|i| {
                if free[i] {
                    next += 1;
                    next - 1
                } else {
                    usize::MAX
                }
            })
            .collect()
    };
    let count = free.iter().filter(|&&f| f).count();
    if count == 0 {
        return None;
    }
    // Labels that could disappear: in use, and every node holding them is free to switch.
    let mut holders = vec![0usize; costs.labels()];
    let mut pinned = vec![false; costs.labels()];
    for i in 0..n {
        holders[labels[i]] += 1;
        pinned[labels[i]] |= !free[i];
    }
    let removable: Vec<usize> = (0..costs.labels())
        .filter(|&l| l != alpha && holders[l] > 0 && !pinned[l])
        .collect();
    let alpha_is_new = holders[alpha] == 0;
    let aux = removable.len() + usize::from(alpha_is_new);
    // x_i = 1 (sink side) means "switch to α"; auxiliary nodes follow the free nodes.
    let mut flow = MaxFlow::new(count + aux);
    let cost = label_cost as f64;
    if cost > 0.0 {
        let mut slot = vec![usize::MAX; costs.labels()];
        for (j, &l) in removable.iter().enumerate() {
            // y = 1 (sink side): label l is gone. Pays its cost when y = 0; y = 1 is only
            // allowed when every holder switches: (1 − x_i) · y costs ∞.
            slot[l] = count + j;
            flow.add_terminal(count + j, 0.0, cost);
        }
        for i in (0..n).filter(|&i| free[i] && slot[labels[i]] != usize::MAX) {
            flow.add_edge(index[i], slot[labels[i]], INFINITE);
        }
        if alpha_is_new {
            // z = 1 (sink side): α gets used, paying its cost; x_i (1 − z) costs ∞.
            let z = count + removable.len();
            flow.add_terminal(z, cost, 0.0);
            for i in (0..n).filter(|&i| free[i]) {
                flow.add_edge(z, index[i], INFINITE);
            }
        }
    }
    for i in (0..n).filter(|&i| free[i]) {
        let (mut keep, mut switch) = (costs.get(i, labels[i]) as f64, costs.get(i, alpha) as f64);
        for &(k, w) in &neighbours[i] {
            let (k, w) = (k as usize, w as f64);
            if free[k] {
                continue;
            }
            // Fixed neighbour with label L_k: Potts against keeping and against switching.
            if labels[k] != labels[i] {
                keep += w;
            }
            if labels[k] != alpha {
                switch += w;
            }
        }
        flow.add_terminal(index[i], switch, keep);
        for &(k, w) in &neighbours[i] {
            let k = k as usize;
            if !free[k] || k <= i {
                continue;
            }
            // Pairwise table over (x_i, x_k): A = [L_i ≠ L_k], B = [L_i ≠ α] = 1, C = 1, D = 0.
            let w = w as f64;
            let a = if labels[i] != labels[k] { w } else { 0.0 };
            let (b, c) = (w, w);
            // E = A + (C − A) x_i + (D − C) x_k + (B + C − A − D)(1 − x_i) x_k
            flow.add_linear(index[i], c - a);
            flow.add_linear(index[k], -c);
            flow.add_edge(index[i], index[k], b + c - a);
        }
    }
    flow.solve();
    let mut out = labels.to_vec();
    let mut any = false;
    for i in (0..n).filter(|&i| free[i]) {
        if flow.on_sink_side(index[i]) {
            out[i] = alpha;
            any = true;
        }
    }
    any.then_some(out)
}

/// A capacity no finite cut reaches.
const INFINITE: f64 = 1e12;

/// Minimum s–t cut by Dinic's algorithm on a graph of `n` inner nodes plus source and sink.
struct MaxFlow {
    n: usize,
    /// Per inner node, the net terminal cost: > 0 is paid on the sink side (an arc from the
    /// source), < 0 on the source side (an arc to the sink). Summed over all terms of a node and
    /// turned into at most one arc when solving, instead of one arc per term.
    terminal: Vec<f64>,
    head: Vec<usize>,
    /// Per edge: target node, residual capacity, next edge from the same node.
    to: Vec<usize>,
    cap: Vec<f64>,
    next: Vec<usize>,
    level: Vec<i32>,
}

const NONE: usize = usize::MAX;

impl MaxFlow {
    fn new(n: usize) -> Self {
        MaxFlow {
            n,
            terminal: vec![0.0; n],
            head: vec![NONE; n + 2],
            to: Vec::new(),
            cap: Vec::new(),
            next: Vec::new(),
            level: vec![-1; n + 2],
        }
    }

    fn source(&self) -> usize {
        self.n
    }

    fn sink(&self) -> usize {
        self.n + 1
    }

    /// A directed arc u → v of capacity `c` with its residual twin v → u of capacity `back`.
    fn arc(&mut self, u: usize, v: usize, c: f64, back: f64) {
        for (from, target, capacity) in [(u, v, c), (v, u, back)] {
            self.to.push(target);
            self.cap.push(capacity);
            self.next.push(self.head[from]);
            self.head[from] = self.to.len() - 1;
        }
    }

    /// Costs `switch` if node i ends on the sink side (x_i = 1) and `keep` if on the source side
    /// (up to a constant: only the difference matters to the cut).
    fn add_terminal(&mut self, i: usize, switch: f64, keep: f64) {
        self.terminal[i] += switch - keep;
    }

    /// Adds the term `c · x_i` (up to a constant).
    fn add_linear(&mut self, i: usize, c: f64) {
        self.terminal[i] += c;
    }

    /// Turns the summed terminal costs into arcs (once, before solving).
    fn add_terminal_arcs(&mut self) {
        for i in 0..self.n {
            let c = std::mem::take(&mut self.terminal[i]);
            if c > 0.0 {
                self.arc(self.source(), i, c, 0.0);
            } else if c < 0.0 {
                self.arc(i, self.sink(), -c, 0.0);
            }
        }
    }

    /// Adds `c · (1 − x_i) · x_k`, c ≥ 0: cut when i is on the source side and k on the sink side.
    fn add_edge(&mut self, i: usize, k: usize, c: f64) {
        if c > 0.0 {
            self.arc(i, k, c, 0.0);
        }
    }

    fn solve(&mut self) {
        self.add_terminal_arcs();
        while self.bfs() {
            let mut iter = self.head.clone();
            while self.push(self.source(), f64::INFINITY, &mut iter) > 0.0 {}
        }
    }

    /// Levels from the source in the residual graph; true when the sink is reachable.
    fn bfs(&mut self) -> bool {
        self.level.iter_mut().for_each(|l| *l = -1);
        let s = self.source();
        self.level[s] = 0;
        let mut queue = std::collections::VecDeque::from([s]);
        while let Some(u) = queue.pop_front() {
            let mut e = self.head[u];
            while e != NONE {
                let v = self.to[e];
                if self.cap[e] > 1e-12 && self.level[v] < 0 {
                    self.level[v] = self.level[u] + 1;
                    queue.push_back(v);
                }
                e = self.next[e];
            }
        }
        self.level[self.sink()] >= 0
    }

    /// Sends up to `limit` along level-increasing paths from u (iterative DFS with an explicit
    /// stack, so deep graphs cannot overflow the call stack). Returns the amount sent.
    fn push(&mut self, u: usize, limit: f64, iter: &mut [usize]) -> f64 {
        let t = self.sink();
        let mut path: Vec<usize> = Vec::new(); // edges from u
        let mut node = u;
        loop {
            if node == t {
                let amount = path.iter().fold(limit, |a, &e| a.min(self.cap[e]));
                for &e in &path {
                    self.cap[e] -= amount;
                    self.cap[e ^ 1] += amount;
                }
                return amount;
            }
            let mut advanced = false;
            while iter[node] != NONE {
                let e = iter[node];
                let v = self.to[e];
                if self.cap[e] > 1e-12 && self.level[v] == self.level[node] + 1 {
                    path.push(e);
                    node = v;
                    advanced = true;
                    break;
                }
                iter[node] = self.next[e];
            }
            if !advanced {
                // Dead end: retreat one step and skip the edge that led here.
                let Some(e) = path.pop() else { return 0.0 };
                self.level[node] = -1;
                node = self.to[e ^ 1];
                iter[node] = self.next[e];
            }
        }
    }

    /// True when node i is not reachable from the source in the residual graph after `solve`.
    fn on_sink_side(&self, i: usize) -> bool {
        self.level[i] < 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every labelling of a small problem, for brute force.
    fn all_labellings(n: usize, labels: usize) -> Vec<Vec<usize>> {
        let mut out = vec![vec![]];
        for _ in 0..n {
            out = out
                .into_iter()
                .flat_map(|l| {
                    (0..labels).map(move |a| {
                        let mut m = l.clone();
                        m.push(a);
                        m
                    })
                })
                .collect();
        }
        out
    }

    fn chain(n: usize, w: f32) -> Vec<Vec<(u32, f32)>> {
        (0..n)
            .map(|i| {
                let mut v = Vec::new();
                if i > 0 {
                    v.push((i as u32 - 1, w));
                }
                if i + 1 < n {
                    v.push((i as u32 + 1, w));
                }
                v
            })
            .collect()
    }

    #[test]
    fn max_flow_cuts_the_cheapest_side() {
        // Node 0 prefers switching (cost 1 vs 5), node 1 prefers keeping (4 vs 2), an edge 0→1
        // of 10 makes "0 keeps, 1 switches" expensive.
        let mut f = MaxFlow::new(2);
        f.add_terminal(0, 1.0, 5.0);
        f.add_terminal(1, 4.0, 2.0);
        f.add_edge(0, 1, 10.0);
        f.solve();
        assert!(f.on_sink_side(0));
        assert!(!f.on_sink_side(1));
    }

    #[test]
    fn expansion_is_optimal_for_two_labels_and_near_optimal_for_three() {
        let mut rng = crate::rng::Rng::new(4);
        for trial in 0..30 {
            let (n, labels) = (6, if trial % 2 == 0 { 2 } else { 3 });
            let mut costs = CostTable::new(n);
            for l in 0..labels {
                costs.push_label(0.0);
                for i in 0..n {
                    costs.set(i, l, (rng.uniform() * 3.0) as f32);
                }
            }
            let nb = chain(n, 0.7);
            let mut got = vec![0; n];
            let order: Vec<usize> = (0..labels).collect();
            alpha_expansion(&costs, &nb, 0.0, f32::INFINITY, &order, &mut got, 10);
            let best = all_labellings(n, labels)
                .iter()
                .map(|l| energy(&costs, &nb, 0.0, l))
                .fold(f64::INFINITY, f64::min);
            let e = energy(&costs, &nb, 0.0, &got);
            if labels == 2 {
                assert!((e - best).abs() < 1e-5, "{e} vs {best}");
            } else {
                // α-expansion is within a factor 2 of the optimum for Potts.
                assert!(e <= 2.0 * best + 1e-5, "{e} vs {best}");
            }
        }
    }

    #[test]
    fn label_costs_remove_a_barely_useful_label() {
        // Label 1 is slightly better on two nodes only; with a label cost it is not worth using.
        let mut costs = CostTable::new(4);
        costs.push_label(1.0);
        costs.push_label(1.0);
        costs.set(0, 1, 0.9);
        costs.set(1, 1, 0.9);
        costs.set(2, 1, 1.1);
        costs.set(3, 1, 1.1);
        let nb = chain(4, 0.0);
        let mut free = vec![0; 4];
        alpha_expansion(&costs, &nb, 0.0, f32::INFINITY, &[1, 0], &mut free, 5);
        assert_eq!(free, vec![1, 1, 0, 0]);
        let mut costly = vec![0; 4];
        alpha_expansion(&costs, &nb, 1.0, f32::INFINITY, &[1, 0], &mut costly, 5);
        assert_eq!(costly, vec![0, 0, 0, 0]);
    }

    #[test]
    fn expansion_drops_a_label_that_only_marginally_helps() {
        // Label 1 is marginally better on a block of three nodes; with a label cost of 1,
        // expanding label 0 over that block removes label 1 and pays for itself, although each
        // node's own cost rises.
        let mut costs = CostTable::new(6);
        costs.push_label(0.0);
        costs.push_label(5.0);
        for i in 0..3 {
            costs.set(i, 0, 0.1);
            costs.set(i, 1, 0.0);
        }
        let nb = chain(6, 0.01);
        let mut free = vec![1, 1, 1, 0, 0, 0];
        alpha_expansion(&costs, &nb, 0.0, f32::INFINITY, &[0, 1], &mut free, 5);
        assert_eq!(
            free,
            vec![1, 1, 1, 0, 0, 0],
            "without a label cost label 1 stays"
        );
        let mut costly = vec![1, 1, 1, 0, 0, 0];
        alpha_expansion(&costs, &nb, 1.0, f32::INFINITY, &[0, 1], &mut costly, 5);
        assert_eq!(costly, vec![0; 6]);
    }

    #[test]
    fn cost_table_grows_by_labels() {
        let mut t = CostTable::new(3);
        t.push_label(2.0);
        t.set(1, 0, 5.0);
        let l = t.push_label(7.0);
        assert_eq!((l, t.labels(), t.nodes()), (1, 2, 3));
        assert_eq!((t.get(1, 0), t.get(1, 1), t.get(2, 1)), (5.0, 7.0, 7.0));
    }
}
