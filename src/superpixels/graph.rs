//! The two graphs over superpixels:
//! - the boundary graph: for every pair of touching superpixels, the 4-neighbouring pixel pairs
//!   along their shared boundary (the paper's E_cont works on these), with each pair's colour
//!   difference;
//! - the K-NN graph over anchors (the neighbourhoods of local motion hypotheses) with weights
//!   w = exp(−β ‖s_i − s_k‖), anchors normalised by the image's long side.

use crate::grid::Grid;
use crate::image::Frame;

use super::Superpixels;
use crate::numeric::exp;

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
    let labels = sp.labels.data();
    let (w, h) = sp.labels.size();
    // Pairs (a, b, p, q) with a < b in scan order of their first pixel, right neighbour first.
    let mut pairs: Vec<(u32, u32, u32, u32)> = Vec::new();
    let mut add = |p: usize, q: usize| {
        let (lp, lq) = (labels[p], labels[q]);
        if lp < lq {
            pairs.push((lp, lq, p as u32, q as u32));
        } else if lq < lp {
            pairs.push((lq, lp, q as u32, p as u32));
        }
    };
    for y in 0..h {
        let row = y * w..(y + 1) * w;
        let below = labels.get(row.start + w..row.end + w).unwrap_or(&[]);
        for (x, &l) in labels[row.clone()].iter().enumerate() {
            let p = row.start + x;
            if x + 1 < w && labels[p + 1] != l {
                add(p, p + 1);
            }
            if below.get(x).is_some_and(|&m| m != l) {
                add(p, p + w);
            }
        }
    }
    // Group by (a, b) keeping scan order within each edge: a counting sort by a, then a stable
    // sort by b of each a's few pairs.
    let count = sp.len();
    let mut first = vec![0usize; count + 1];
    for &(a, ..) in &pairs {
        first[a as usize + 1] += 1;
    }
    for a in 0..count {
        first[a + 1] += first[a];
    }
    let mut by_a = vec![(0, 0, 0, 0); pairs.len()];
    let mut fill = first.clone();
    for pair in pairs {
        by_a[fill[pair.0 as usize]] = pair;
        fill[pair.0 as usize] += 1;
    }
    let mut edges: Vec<BoundaryEdge> = Vec::new();
    for a in 0..count {
        let bucket = &mut by_a[first[a]..first[a + 1]];
        bucket.sort_by_key(|&(_, b, ..)| b);
        for run in bucket.chunk_by(|x, y| x.1 == y.1) {
            edges.push(BoundaryEdge {
                a: a as u32,
                b: run[0].1,
                pairs: run.iter().map(|&(_, _, p, q)| (p, q)).collect(),
                colour_diff: run
                    .iter()
                    .map(|&(_, _, p, q)| {
                        colour_distance(frame.data()[p as usize], frame.data()[q as usize])
                    })
                    .collect(),
            });
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

/// The `k` nearest of `points` to each point (Euclidean; ties to the lower index), weighted on
/// the image anchors. A point with a non-finite coordinate has no neighbours and is nobody's.
///
/// The points are bucketed on a grid over their first two coordinates; each search visits rings
/// of cells around its point's cell and stops when the next ring is farther than the k-th
/// nearest found (about 3k points visited for anchors spread over an image, instead of all).
fn knn_by<const D: usize>(
    points: &[[f64; D]],
    image_anchors: &[[f64; 2]],
    k: usize,
    beta: f64,
) -> KnnGraph {
    let grid = Buckets::new(points);
    let mut nearest = Vec::with_capacity(k + 1);
    let neighbours = (0..points.len())
        .map(|i| {
            nearest.clear();
            if k > 0 && grid.is_member(i) {
                grid.nearest(points, i, k, &mut nearest);
            }
            nearest
                .iter()
                .map(|&(_, j)| {
                    let (a, b) = (image_anchors[i], image_anchors[j as usize]);
                    let d = ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt();
                    (j, exp(-beta * d))
                })
                .collect()
        })
        .collect();
    KnnGraph { neighbours }
}

/// The finite points bucketed on a uniform grid over their first two coordinates (about two
/// points per cell), stored cell by cell (row-major) in index order.
struct Buckets {
    origin: [f64; 2],
    cell: f64,
    cols: usize,
    rows: usize,
    /// Points of cell c: `members[first[c]..first[c + 1]]`.
    first: Vec<usize>,
    members: Vec<u32>,
    /// Cell of each point; `None` for a point with a non-finite coordinate.
    cell_of: Vec<Option<usize>>,
}

impl Buckets {
    fn new<const D: usize>(points: &[[f64; D]]) -> Buckets {
        let finite = |p: &[f64; D]| p.iter().all(|v| v.is_finite());
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        let mut count = 0;
        for p in points.iter().filter(|p| finite(p)) {
            for c in 0..2 {
                (lo[c], hi[c]) = (lo[c].min(p[c]), hi[c].max(p[c]));
            }
            count += 1;
        }
        let extent = [hi[0] - lo[0], hi[1] - lo[1]];
        // Cells of two points on average; points on a line or all equal get one row or one cell.
        let cell = [
            (2.0 * extent[0] * extent[1] / count as f64).sqrt(),
            2.0 * extent[0].max(extent[1]) / count as f64,
        ]
        .into_iter()
        .find(|&c| c > 0.0 && c.is_finite())
        .unwrap_or(1.0);
        let cells_along = |e: f64| ((e / cell) as usize + 1).min(1 << 12);
        let (cols, rows) = (cells_along(extent[0]), cells_along(extent[1]));
        let cell_of: Vec<Option<usize>> = points
            .iter()
            .map(|p| {
                finite(p).then(|| {
                    let col = (((p[0] - lo[0]) / cell) as usize).min(cols - 1);
                    let row = (((p[1] - lo[1]) / cell) as usize).min(rows - 1);
                    row * cols + col
                })
            })
            .collect();
        // Counting sort of the points by cell.
        let mut first = vec![0usize; cols * rows + 1];
        for &c in cell_of.iter().flatten() {
            first[c + 1] += 1;
        }
        for c in 0..cols * rows {
            first[c + 1] += first[c];
        }
        let mut fill = first.clone();
        let mut members = vec![0u32; count];
        for (i, c) in cell_of.iter().enumerate() {
            if let &Some(c) = c {
                members[fill[c]] = i as u32;
                fill[c] += 1;
            }
        }
        Buckets {
            origin: lo,
            cell,
            cols,
            rows,
            first,
            members,
            cell_of,
        }
    }

    fn is_member(&self, i: usize) -> bool {
        self.cell_of[i].is_some()
    }

    /// Fills `nearest` with the `k` (≥ 1) nearest other points of point `i` as
    /// (squared distance, index), nearest first.
    fn nearest<const D: usize>(
        &self,
        points: &[[f64; D]],
        i: usize,
        k: usize,
        nearest: &mut Vec<(f64, u32)>,
    ) {
        let Some(home) = self.cell_of[i] else { return };
        let p = &points[i];
        let (col, row) = ((home % self.cols) as isize, (home / self.cols) as isize);
        for ring in 0..=self.cols.max(self.rows) as isize {
            // Ring r lies outside the square of cells within r − 1 of home: no point on it is
            // nearer to p than that square's border.
            let inner = |home: isize, origin: f64, x: f64| {
                let low = origin + (home - ring + 1) as f64 * self.cell;
                let high = origin + (home + ring) as f64 * self.cell;
                (x - low).min(high - x)
            };
            let gap = if ring == 0 {
                0.0
            } else {
                inner(col, self.origin[0], p[0])
                    .min(inner(row, self.origin[1], p[1]))
                    .max(0.0)
            };
            if nearest.len() == k && gap * gap > nearest[k - 1].0 {
                return;
            }
            for r in row - ring..=row + ring {
                let step = if r == row - ring || r == row + ring {
                    1
                } else {
                    2 * ring.max(1)
                };
                for c in (col - ring..=col + ring).step_by(step as usize) {
                    if r < 0 || c < 0 || r as usize >= self.rows || c as usize >= self.cols {
                        continue;
                    }
                    let cell = r as usize * self.cols + c as usize;
                    for &j in &self.members[self.first[cell]..self.first[cell + 1]] {
                        if j as usize != i {
                            offer(nearest, k, distance2(p, &points[j as usize]), j);
                        }
                    }
                }
            }
        }
    }
}

fn distance2<const D: usize>(a: &[f64; D], b: &[f64; D]) -> f64 {
    (0..D).map(|c| (a[c] - b[c]) * (a[c] - b[c])).sum()
}

/// Inserts (d, j) into `nearest`, sorted by (distance, index) and at most k long, if it belongs.
fn offer(nearest: &mut Vec<(f64, u32)>, k: usize, d: f64, j: u32) {
    if nearest.len() == k && (d, j) >= nearest[k - 1] {
        return;
    }
    let at = nearest.partition_point(|&other| other < (d, j));
    nearest.insert(at, (d, j));
    nearest.truncate(k);
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

    /// K nearest by brute force: every other finite point, ordered by (distance², index).
    fn knn_reference<const D: usize>(points: &[[f64; D]], k: usize) -> Vec<Vec<u32>> {
        let finite = |p: &[f64; D]| p.iter().all(|v| v.is_finite());
        (0..points.len())
            .map(|i| {
                if !finite(&points[i]) {
                    return Vec::new();
                }
                let mut all: Vec<(f64, u32)> = (0..points.len())
                    .filter(|&j| j != i && finite(&points[j]))
                    .map(|j| (distance2(&points[i], &points[j]), j as u32))
                    .collect();
                all.sort_by(|a, b| a.partial_cmp(b).unwrap());
                all.into_iter().take(k).map(|(_, j)| j).collect()
            })
            .collect()
    }

    fn indices(g: &KnnGraph) -> Vec<Vec<u32>> {
        g.neighbours
            .iter()
            .map(|list| list.iter().map(|&(j, _)| j).collect())
            .collect()
    }

    #[test]
    fn knn_search_finds_the_brute_force_neighbours() {
        let mut rng = crate::rng::Rng::new(3);
        // Scattered anchors; a jittered grid with exact ties; clustered 3D points with a depth
        // spread; points on a line; one repeated point; a non-finite point.
        let scattered: Vec<[f64; 2]> = (0..700)
            .map(|_| [rng.uniform() * 2.3, rng.uniform()])
            .collect();
        let mut grid: Vec<[f64; 2]> = (0..400)
            .map(|i| [(i % 25) as f64, (i / 25) as f64])
            .collect();
        grid[17] = [f64::NAN, 3.0];
        let line: Vec<[f64; 2]> = (0..60).map(|i| [0.5 * i as f64, 2.0]).collect();
        let same = vec![[1.0, 1.0]; 20];
        for (name, points) in [
            ("scattered", &scattered),
            ("grid", &grid),
            ("line", &line),
            ("same", &same),
        ] {
            for k in [0, 1, 15, 30, 1000] {
                let g = knn_by(points, points, k, 3.0);
                assert_eq!(indices(&g), knn_reference(points, k), "{name}, k = {k}");
            }
        }
        let points: Vec<[f64; 3]> = (0..500)
            .map(|i| {
                let z = if i % 3 == 0 { 20.0 } else { 2.0 };
                [rng.normal(), rng.normal(), z + rng.uniform()]
            })
            .collect();
        let image: Vec<[f64; 2]> = points.iter().map(|p| [p[0], p[1]]).collect();
        let g = knn_graph_3d(&points, &image, 15, 3.0);
        assert_eq!(indices(&g), knn_reference(&points, 15));
    }

    #[test]
    fn boundary_graph_holds_every_label_change_once() {
        let mut rng = crate::rng::Rng::new(5);
        let frame = Grid::from_fn(48, 32, |_, _| [0, 1, 2].map(|_| rng.below(256) as u8));
        let sp = slic(
            &frame,
            &SlicParams {
                count: 30,
                ..SlicParams::default()
            },
        )
        .unwrap();
        let g = boundary_graph(&sp, &frame);
        let (w, labels) = (48, sp.labels.data());
        let changes = (0..labels.len())
            .map(|p| {
                let right = (p % w + 1 < w && labels[p + 1] != labels[p]) as usize;
                let below = (p + w < labels.len() && labels[p + w] != labels[p]) as usize;
                right + below
            })
            .sum::<usize>();
        assert_eq!(
            g.edges.iter().map(|e| e.pairs.len()).sum::<usize>(),
            changes
        );
        assert!(
            g.edges
                .windows(2)
                .all(|e| (e[0].a, e[0].b) < (e[1].a, e[1].b))
        );
        for e in &g.edges {
            // Scan order of the pixel that comes first, right neighbour before the one below.
            let key = |&(p, q): &(u32, u32)| (p.min(q), p.max(q) - p.min(q) != 1);
            assert!(e.pairs.windows(2).all(|pq| key(&pq[0]) < key(&pq[1])));
            for (&(p, q), &d) in e.pairs.iter().zip(&e.colour_diff) {
                assert_eq!((labels[p as usize], labels[q as usize]), (e.a, e.b));
                let (cp, cq) = (frame.data()[p as usize], frame.data()[q as usize]);
                assert_eq!(d, colour_distance(cp, cq));
            }
        }
    }
}
