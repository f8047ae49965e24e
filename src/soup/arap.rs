//! Relative scales by the as-rigid-as-possible energy (the paper's eq. 1 and 6):
//!
//! E(λ) = Σ_i Σ_{k∈N_i} w_ik ( √(‖R_i − R_k‖²_F + ‖λ_i t̂_i − λ_k t̂_k‖²)
//!                            + ρ(| ‖λ_i X_i − λ_k X_k‖ − ‖λ_i X'_i − λ_k X'_k‖ |) ),
//!
//! X_i the unit-scale anchor of piece i in frame 1, X'_i = R_i X_i + t̂_i, w_ik from the K-NN
//! graph, subject to Σλ = 1, λ > 0. ρ truncates the rigidity term at half the mean of the two
//! distances, so pieces on a motion boundary cannot drag scales without bound (DESIGN.md
//! Pitfalls: the free problem collapses some λ towards 0).
//!
//! Solver: block coordinate descent. Pieces sharing a motion hypothesis form one block and first
//! move together (a rigid body with one motion has one scale); then each piece is refined on its
//! own within a band around its block. Block scales stay within a band around the largest
//! block's, which also fixes the gauge during the search (DESIGN.md Pitfalls: a fast mover's
//! cheapest state is λ → 0). Each 1-D step is a log-spaced grid search followed by golden-section
//! refinement, on the energy of the edges it touches; λ is normalised to Σλ = 1 at the end.

use nalgebra::Vector3;
use serde::Serialize;

use super::Soup;
use crate::camera::Intrinsics;
use crate::superpixels::Superpixels;
use crate::superpixels::graph::KnnGraph;

/// Blocks keep their scale within [1/B, B] of the largest block's: the sane band of DESIGN.md
/// against the collapse of fast movers, whose cheapest ARAP state is a tiny scale.
const BLOCK_BAND: f64 = 4.0;

/// A piece refines its scale within [1/B, B] of its block's.
const PIECE_BAND: f64 = 2.0;

/// What the scale solve did.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ArapReport {
    /// E at λ = 1/N (the paper's start).
    pub energy_start: f64,
    /// E at the solution (Σλ = 1).
    pub energy_end: f64,
    /// Coordinate-descent sweeps run.
    pub sweeps: usize,
    /// Largest / smallest λ.
    pub lambda_ratio: f64,
}

/// One term's data: a directed K-NN edge (i → k) with its weight.
#[derive(Clone, Copy, Debug)]
struct Edge {
    i: usize,
    k: usize,
    w: f64,
    /// ‖R_i − R_k‖²_F.
    rotation: f64,
}

/// The energy's fixed data: unit-scale anchors in both frames and the edges.
struct Problem {
    x: Vec<Vector3<f64>>,
    x2: Vec<Vector3<f64>>,
    t: Vec<Vector3<f64>>,
    edges: Vec<Edge>,
    /// Edge indices touching each piece.
    touching: Vec<Vec<usize>>,
}

impl Problem {
    fn new(soup: &Soup, sp: &Superpixels, knn: &KnnGraph, k: &Intrinsics) -> Self {
        let x: Vec<Vector3<f64>> = soup
            .pieces
            .iter()
            .zip(&sp.segments)
            .map(|(p, s)| p.unit_point(&Vector3::from(k.ray(s.anchor[0], s.anchor[1]))))
            .collect();
        let x2 = soup
            .pieces
            .iter()
            .zip(&x)
            .map(|(p, x)| p.r * x + p.t_hat)
            .collect();
        let t = soup.pieces.iter().map(|p| p.t_hat).collect();
        let mut edges = Vec::new();
        let mut touching = vec![Vec::new(); soup.pieces.len()];
        for (i, list) in knn.neighbours.iter().enumerate() {
            for &(kk, w) in list {
                let kk = kk as usize;
                let rotation = (soup.pieces[i].r - soup.pieces[kk].r).norm_squared();
                touching[i].push(edges.len());
                touching[kk].push(edges.len());
                edges.push(Edge {
                    i,
                    k: kk,
                    w,
                    rotation,
                });
            }
        }
        Problem {
            x,
            x2,
            t,
            edges,
            touching,
        }
    }

    fn term(&self, e: &Edge, lambda: &[f64]) -> f64 {
        let (li, lk) = (lambda[e.i], lambda[e.k]);
        let motion = (e.rotation + (self.t[e.i] * li - self.t[e.k] * lk).norm_squared()).sqrt();
        let d1 = (self.x[e.i] * li - self.x[e.k] * lk).norm();
        let d2 = (self.x2[e.i] * li - self.x2[e.k] * lk).norm();
        let rigidity = (d1 - d2).abs().min(0.25 * (d1 + d2));
        let value = e.w * (motion + rigidity);
        if value.is_finite() { value } else { 1e6 }
    }

    fn energy(&self, lambda: &[f64]) -> f64 {
        self.edges.iter().map(|e| self.term(e, lambda)).sum()
    }

    /// Energy of the edges touching any of `members` (each edge once).
    fn local_energy(&self, members: &[usize], lambda: &[f64], seen: &mut [bool]) -> f64 {
        let mut sum = 0.0;
        let mut visited = Vec::new();
        for &m in members {
            for &e in &self.touching[m] {
                if !seen[e] {
                    seen[e] = true;
                    visited.push(e);
                    sum += self.term(&self.edges[e], lambda);
                }
            }
        }
        visited.into_iter().for_each(|e| seen[e] = false);
        sum
    }
}

/// Solves the relative scales of `soup` in place (Σλ = 1) and reports the energies.
pub fn solve_scales(
    soup: &mut Soup,
    sp: &Superpixels,
    knn: &KnnGraph,
    k: &Intrinsics,
) -> ArapReport {
    let n = soup.pieces.len();
    let problem = Problem::new(soup, sp, knn, k);
    let uniform = vec![1.0 / n as f64; n];
    let energy_start = problem.energy(&uniform);
    let mut lambda = vec![1.0; n];
    let mut seen = vec![false; problem.edges.len()];

    // Blocks: pieces sharing a hypothesis, largest first; the largest keeps its scale.
    let count = soup.hypotheses.len().max(1);
    let mut blocks: Vec<Vec<usize>> = vec![Vec::new(); count];
    for (i, p) in soup.pieces.iter().enumerate() {
        blocks[p.hypothesis.min(count - 1)].push(i);
    }
    blocks.retain(|b| !b.is_empty());
    blocks.sort_by(|a, b| b.len().cmp(&a.len()).then(a[0].cmp(&b[0])));
    let mut sweeps = 0;
    for _ in 0..4 {
        sweeps += 1;
        for block in blocks.iter().skip(1) {
            let best = search(1.0 / BLOCK_BAND, BLOCK_BAND, |s| {
                block.iter().for_each(|&i| lambda[i] = s);
                problem.local_energy(block, &lambda, &mut seen)
            });
            block.iter().for_each(|&i| lambda[i] = best);
        }
    }
    // Each piece on its own, within a band around its block's scale.
    for _ in 0..2 {
        sweeps += 1;
        for i in 0..n {
            let current = lambda[i];
            let best = search(current / PIECE_BAND, current * PIECE_BAND, |s| {
                lambda[i] = s;
                problem.local_energy(&[i], &lambda, &mut seen)
            });
            lambda[i] = best;
        }
    }
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
        energy_end: problem.energy(&lambda),
        sweeps,
        lambda_ratio: hi / lo,
    }
}

/// Minimises `f` over [lo, hi] (lo > 0): a 25-point log grid, then golden-section search in log
/// space around the best grid point. Ties go to the smaller argument, so results are reproducible.
fn search(lo: f64, hi: f64, mut f: impl FnMut(f64) -> f64) -> f64 {
    let (a, b) = (lo.ln(), hi.ln());
    let steps = 24;
    let at = |j: usize| a + (b - a) * j as f64 / steps as f64;
    let (mut best_j, mut best_v) = (0, f64::INFINITY);
    for j in 0..=steps {
        let v = f(at(j).exp());
        if v < best_v {
            (best_j, best_v) = (j, v);
        }
    }
    let (mut l, mut r) = (at(best_j.saturating_sub(1)), at((best_j + 1).min(steps)));
    let g = 0.618_033_988_749_895;
    let (mut c, mut d) = (r - g * (r - l), l + g * (r - l));
    let (mut fc, mut fd) = (f(c.exp()), f(d.exp()));
    for _ in 0..12 {
        if fc <= fd {
            (r, d, fd) = (d, c, fc);
            c = r - g * (r - l);
            fc = f(c.exp());
        } else {
            (l, c, fc) = (c, d, fd);
            d = l + g * (r - l);
            fd = f(d.exp());
        }
    }
    let x = if fc <= fd { c } else { d };
    if f(x.exp()) <= best_v {
        x.exp()
    } else {
        at(best_j).exp()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn golden_search_finds_a_minimum() {
        let x = search(0.01, 100.0, |s| (s.ln() - 2.0f64.ln()).powi(2));
        assert!((x - 2.0).abs() < 1e-3, "{x}");
    }
}
