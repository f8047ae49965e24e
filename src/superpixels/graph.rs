//! The two graphs over superpixels:
//! - the boundary graph: for every pair of touching superpixels, the 4-neighbouring pixel pairs
//!   along their shared boundary (the paper's E_cont works on these), with each pair's colour
//!   difference;
//! - the K-NN graph over anchors (the paper's E_arap neighbourhoods) with weights
//!   w = exp(−β ‖s_i − s_k‖), anchors normalised by the image's long side.

use crate::grid::Grid;
use crate::image::Frame;

use super::Superpixels;

/// The shared boundary of superpixels `a < b`.
#[derive(Clone, Debug, PartialEq)]
pub struct BoundaryEdge {
    pub a: u32,
    pub b: u32,
    /// 4-neighbouring pixel pairs `(p, q)` as indices `y · width + x`, p in `a` and q in `b`.
    pub pairs: Vec<(u32, u32)>,
    /// Per pair, ‖I(p) − I(q)‖ with RGB in [0, 1] (Euclidean, so in [0, √3]).
    pub colour_diff: Vec<f32>,
}

/// All touching pairs, sorted by `(a, b)`.
#[derive(Clone, Debug, PartialEq)]
pub struct BoundaryGraph {
    pub edges: Vec<BoundaryEdge>,
}

impl BoundaryGraph {
    /// Labels touching each superpixel, for `count` superpixels.
    pub fn adjacency(&self, count: usize) -> Vec<Vec<u32>> {
        let mut adj = vec![Vec::new(); count];
        for e in &self.edges {
            adj[e.a as usize].push(e.b);
            adj[e.b as usize].push(e.a);
        }
        adj
    }
}

/// Collects the boundary pixel pairs between touching superpixels of `sp` (colours from `frame`).
pub fn boundary_graph(sp: &Superpixels, frame: &Frame) -> BoundaryGraph {
    let labels = &sp.labels;
    let (w, h) = labels.size();
    let mut pairs: Vec<(u32, u32, u32, u32)> = Vec::new(); // (a, b, p, q)
    for y in 0..h {
        for x in 0..w {
            let p = y * w + x;
            let lp = labels.data()[p];
            for q in [(x + 1 < w).then_some(p + 1), (y + 1 < h).then_some(p + w)]
                .into_iter()
                .flatten()
            {
                let lq = labels.data()[q];
                if lp != lq {
                    let (a, b, pa, qb) = if lp < lq {
                        (lp, lq, p, q)
                    } else {
                        (lq, lp, q, p)
                    };
                    pairs.push((a, b, pa as u32, qb as u32));
                }
            }
        }
    }
    pairs.sort_by_key(|&(a, b, _, _)| (a, b)); // stable: scan order kept within an edge
    let mut edges: Vec<BoundaryEdge> = Vec::new();
    for (a, b, p, q) in pairs {
        if edges.last().is_none_or(|e| (e.a, e.b) != (a, b)) {
            edges.push(BoundaryEdge {
                a,
                b,
                pairs: Vec::new(),
                colour_diff: Vec::new(),
            });
        }
        if let Some(edge) = edges.last_mut() {
            edge.pairs.push((p, q));
            edge.colour_diff.push(colour_distance(
                frame.data()[p as usize],
                frame.data()[q as usize],
            ));
        }
    }
    BoundaryGraph { edges }
}

fn colour_distance(a: [u8; 3], b: [u8; 3]) -> f32 {
    let d = |k: usize| (a[k] as f32 - b[k] as f32) / 255.0;
    (d(0) * d(0) + d(1) * d(1) + d(2) * d(2)).sqrt()
}

/// Directed K-NN lists: `neighbours[i]` holds `(k, w_ik)` for the K nearest superpixels of `i`,
/// nearest first.
#[derive(Clone, Debug, PartialEq)]
pub struct KnnGraph {
    pub neighbours: Vec<Vec<(u32, f64)>>,
}

/// K-NN over image anchors (normalised by the long side), weights exp(−β‖s_i − s_k‖).
pub fn knn_graph(sp: &Superpixels, k: usize, beta: f64) -> KnnGraph {
    let anchors = sp.normalised_anchors();
    knn_by(&anchors, &anchors, k, beta)
}

/// K-NN rebuilt in 3D once depths are known: neighbours by Euclidean distance between the 3D
/// anchors `points` (any consistent units), weights still exp(−β‖s_i − s_k‖) on the normalised
/// image anchors `image_anchors`, as in the paper's eq. 2.
pub fn knn_graph_3d(
    points: &[[f64; 3]],
    image_anchors: &[[f64; 2]],
    k: usize,
    beta: f64,
) -> KnnGraph {
    knn_by(points, image_anchors, k, beta)
}

fn knn_by<const D: usize>(
    points: &[[f64; D]],
    image_anchors: &[[f64; 2]],
    k: usize,
    beta: f64,
) -> KnnGraph {
    let dist2 =
        |a: &[f64; D], b: &[f64; D]| (0..D).map(|d| (a[d] - b[d]) * (a[d] - b[d])).sum::<f64>();
    let finite: Vec<bool> = points
        .iter()
        .map(|p| p.iter().all(|v| v.is_finite()))
        .collect();
    let mut order: Vec<(f64, u32)> = Vec::with_capacity(points.len());
    let by_distance = |a: &(f64, u32), b: &(f64, u32)| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1));
    let neighbours = points
        .iter()
        .enumerate()
        .map(|(i, p)| {
            order.clear();
            order.extend(
                points
                    .iter()
                    .enumerate()
                    .filter(|&(j, _)| j != i && finite[j])
                    .map(|(j, q)| (dist2(p, q), j as u32)),
            );
            let take = k.min(order.len());
            if take > 0 && take < order.len() {
                order.select_nth_unstable_by(take - 1, by_distance);
            }
            order.truncate(take);
            order.sort_by(by_distance);
            order
                .iter()
                .map(|&(_, j)| {
                    let (a, b) = (image_anchors[i], image_anchors[j as usize]);
                    let d = ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt();
                    (j, (-beta * d).exp())
                })
                .collect()
        })
        .collect();
    KnnGraph { neighbours }
}

/// True where a pixel's right or lower neighbour has another label (a boundary pixel).
pub fn boundary_mask(labels: &Grid<u32>) -> Grid<bool> {
    let (w, h) = labels.size();
    Grid::from_fn(w, h, |x, y| {
        let l = *labels.get(x, y);
        (x + 1 < w && *labels.get(x + 1, y) != l) || (y + 1 < h && *labels.get(x, y + 1) != l)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::superpixels::{SlicParams, slic};

    fn quadrants() -> (Superpixels, Frame) {
        let frame = Grid::from_fn(40, 40, |x, y| match (x < 20, y < 20) {
            (true, true) => [250, 0, 0],
            (false, true) => [0, 250, 0],
            (true, false) => [0, 0, 250],
            (false, false) => [250, 250, 0],
        });
        let sp = slic(
            &frame,
            &SlicParams {
                count: 4,
                compactness: 5.0,
                iterations: 10,
            },
        )
        .unwrap();
        (sp, frame)
    }

    #[test]
    fn boundary_pairs_are_neighbours_across_labels() {
        let (sp, frame) = quadrants();
        assert_eq!(sp.len(), 4);
        let g = boundary_graph(&sp, &frame);
        // Four quadrants touch along 4 edges (diagonal ones do not share a 4-neighbour pair).
        assert_eq!(g.edges.len(), 4);
        for e in &g.edges {
            assert!(e.a < e.b && e.pairs.len() == 20);
            for (&(p, q), &d) in e.pairs.iter().zip(&e.colour_diff) {
                assert_eq!(sp.labels.data()[p as usize], e.a);
                assert_eq!(sp.labels.data()[q as usize], e.b);
                let gap = (p as i64 - q as i64).abs();
                assert!(gap == 1 || gap == 40);
                assert!(d > 0.9);
            }
        }
        assert_eq!(
            g.adjacency(4).iter().map(Vec::len).collect::<Vec<_>>(),
            vec![2, 2, 2, 2]
        );
    }

    #[test]
    fn knn_weights_follow_the_paper() {
        let (sp, _) = quadrants();
        let g = knn_graph(&sp, 2, 3.0);
        for (i, list) in g.neighbours.iter().enumerate() {
            assert_eq!(list.len(), 2);
            for &(k, w) in list {
                assert_ne!(k as usize, i);
                // Side neighbours are half the 40-pixel side apart: w = exp(−3 · 0.5).
                assert!((w - (-1.5f64).exp()).abs() < 0.05, "{w}");
            }
        }
        let pts = [[0.0, 0.0, 1.0], [0.0, 0.0, 5.0], [0.0, 0.0, 1.1]];
        let img = [[0.0, 0.0], [0.1, 0.0], [0.2, 0.0]];
        let g3 = knn_graph_3d(&pts, &img, 1, 3.0);
        assert_eq!(g3.neighbours[0][0].0, 2);
        assert!((g3.neighbours[0][0].1 - (-0.6f64).exp()).abs() < 1e-12);
    }
}
