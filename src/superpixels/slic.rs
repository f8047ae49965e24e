//! SLIC (Achanta et al., TPAMI 2012): k-means over (L, a, b, x, y) with each centre searching a
//! 2S × 2S window, followed by connectivity enforcement.

use crate::error::{Error, Result};
use crate::grid::Grid;
use crate::image::{Frame, to_lab};

use super::{Segment, Superpixels};

/// SLIC parameters.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SlicParams {
    /// Requested number of superpixels (the result is within a few percent of it).
    pub count: usize,
    /// Compactness m: weight of spatial against colour distance (CIELAB units per grid step S).
    pub compactness: f32,
    /// k-means iterations.
    pub iterations: usize,
}

impl Default for SlicParams {
    fn default() -> Self {
        SlicParams {
            count: 1500,
            compactness: 10.0,
            iterations: 10,
        }
    }
}

/// A cluster centre in (L, a, b, x, y).
#[derive(Clone, Copy, Debug)]
struct Centre {
    lab: [f32; 3],
    x: f32,
    y: f32,
}

/// Segments `frame` into about `params.count` superpixels.
///
/// Errors: [`Error::InvalidParameter`] when the count is 0 or exceeds a quarter of the pixels,
/// or the compactness is not positive.
pub fn slic(frame: &Frame, params: &SlicParams) -> Result<Superpixels> {
    let (w, h) = frame.size();
    if params.count == 0 || params.count * 4 > w * h {
        return Err(Error::InvalidParameter(format!(
            "superpixel count must be between 1 and a quarter of the pixels ({}), got {}",
            w * h / 4,
            params.count
        )));
    }
    if !(params.compactness > 0.0 && params.compactness.is_finite()) {
        return Err(Error::InvalidParameter(format!(
            "compactness must be positive, got {}",
            params.compactness
        )));
    }
    let lab = to_lab(frame);
    let (mut centres, step) = seed_centres(&lab, params.count);
    let planar = [0, 1, 2].map(|k| lab.data().iter().map(|p| p[k]).collect::<Vec<f32>>());
    let mut labels = vec![u32::MAX; w * h];
    let mut dist = vec![f32::INFINITY; w * h];
    let spatial = (params.compactness / step) * (params.compactness / step);
    for _ in 0..params.iterations {
        assign(&planar, w, &centres, step, spatial, &mut labels, &mut dist);
        update_centres(&lab, &labels, &mut centres);
    }
    assign(&planar, w, &centres, step, spatial, &mut labels, &mut dist);
    let min_size = ((step * step) / 4.0).max(1.0) as usize;
    let labels = enforce_connectivity(w, h, &labels, min_size);
    Ok(segments_of(frame, &lab, labels))
}

/// Grid seeds `step` pixels apart, each moved to the lowest CIELAB gradient in its 3 × 3
/// neighbourhood (off edges and noise). Returns the seeds and the grid step S.
fn seed_centres(lab: &Grid<[f32; 3]>, count: usize) -> (Vec<Centre>, f32) {
    let (w, h) = lab.size();
    let step = ((w * h) as f32 / count as f32).sqrt();
    let nx = ((w as f32 / step).round() as usize).max(1);
    let ny = ((h as f32 / step).round() as usize).max(1);
    let (sx, sy) = (w as f32 / nx as f32, h as f32 / ny as f32);
    let mut centres = Vec::with_capacity(nx * ny);
    for j in 0..ny {
        for i in 0..nx {
            let x = ((i as f32 + 0.5) * sx) as usize;
            let y = ((j as f32 + 0.5) * sy) as usize;
            let (bx, by) = lowest_gradient(lab, x.min(w - 1), y.min(h - 1));
            centres.push(Centre {
                lab: *lab.get(bx, by),
                x: bx as f32,
                y: by as f32,
            });
        }
    }
    (centres, step)
}

fn lowest_gradient(lab: &Grid<[f32; 3]>, x: usize, y: usize) -> (usize, usize) {
    let (w, h) = lab.size();
    let diff = |a: &[f32; 3], b: &[f32; 3]| (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f32>();
    let mut best = (f32::INFINITY, x, y);
    for yy in y.saturating_sub(1)..=(y + 1).min(h - 1) {
        for xx in x.saturating_sub(1)..=(x + 1).min(w - 1) {
            let (l, r) = (xx.saturating_sub(1), (xx + 1).min(w - 1));
            let (u, d) = (yy.saturating_sub(1), (yy + 1).min(h - 1));
            let g = diff(lab.get(r, yy), lab.get(l, yy)) + diff(lab.get(xx, d), lab.get(xx, u));
            if g < best.0 {
                best = (g, xx, yy);
            }
        }
    }
    (best.1, best.2)
}

/// Assigns each pixel to the nearest centre whose 2S × 2S window covers it. `lab` is planar
/// (`[L…, a…, b…]`, each `w · h` long) so the inner loop vectorises.
fn assign(
    lab: &[Vec<f32>; 3],
    w: usize,
    centres: &[Centre],
    step: f32,
    spatial: f32,
    labels: &mut [u32],
    dist: &mut [f32],
) {
    let h = dist.len() / w;
    dist.fill(f32::INFINITY);
    for (k, c) in centres.iter().enumerate() {
        let x0 = (c.x - step).max(0.0) as usize;
        let x1 = ((c.x + step) as usize + 1).min(w);
        let y0 = (c.y - step).max(0.0) as usize;
        let y1 = ((c.y + step) as usize + 1).min(h);
        for y in y0..y1 {
            let dy = y as f32 - c.y;
            let row = y * w + x0..y * w + x1;
            let (l, a, b) = (
                &lab[0][row.clone()],
                &lab[1][row.clone()],
                &lab[2][row.clone()],
            );
            let (dist, labels) = (&mut dist[row.clone()], &mut labels[row]);
            let base = spatial * dy * dy;
            for i in 0..l.len() {
                let dx = (x0 + i) as f32 - c.x;
                let (dl, da, db) = (l[i] - c.lab[0], a[i] - c.lab[1], b[i] - c.lab[2]);
                let d = dl * dl + da * da + db * db + spatial * dx * dx + base;
                // Branch-free so the loop vectorises.
                let better = d < dist[i];
                dist[i] = if better { d } else { dist[i] };
                labels[i] = if better { k as u32 } else { labels[i] };
            }
        }
    }
}

/// Moves each centre to the mean (L, a, b, x, y) of its pixels; empty clusters stay put.
fn update_centres(lab: &Grid<[f32; 3]>, labels: &[u32], centres: &mut [Centre]) {
    let w = lab.width();
    let mut sums = vec![[0f32; 6]; centres.len()];
    for (y, (row_labels, row)) in labels
        .chunks_exact(w)
        .zip(lab.data().chunks_exact(w))
        .enumerate()
    {
        for (x, (&l, p)) in row_labels.iter().zip(row).enumerate() {
            if let Some(s) = sums.get_mut(l as usize) {
                s[0] += p[0];
                s[1] += p[1];
                s[2] += p[2];
                s[3] += x as f32;
                s[4] += y as f32;
                s[5] += 1.0;
            }
        }
    }
    for (c, s) in centres.iter_mut().zip(sums) {
        if s[5] > 0.0 {
            let n = s[5];
            *c = Centre {
                lab: [s[0] / n, s[1] / n, s[2] / n],
                x: s[3] / n,
                y: s[4] / n,
            };
        }
    }
}

/// Relabels 4-connected components 0..N'−1 in scan order so that every label is one region.
///
/// Textured images split some clusters into several pieces. A piece keeps its own label when it
/// is the largest piece of its cluster and at least `min_size / 2` pixels, or when it has at least
/// `2 · min_size` pixels on its own; any other piece joins the component just before its first
/// pixel in scan order (left or above: already final), so unions stay connected.
fn enforce_connectivity(w: usize, h: usize, labels: &[u32], min_size: usize) -> Grid<u32> {
    // Pass 1: components, their sizes and first pixels, in scan order.
    let mut component = vec![u32::MAX; w * h];
    let mut first_pixel = Vec::new();
    let mut size = Vec::new();
    let mut stack = Vec::new();
    for start in 0..w * h {
        if component[start] != u32::MAX {
            continue;
        }
        let id = first_pixel.len() as u32;
        first_pixel.push(start);
        component[start] = id;
        stack.push(start);
        let mut count = 0;
        while let Some(p) = stack.pop() {
            count += 1;
            for (x, y) in neighbours(p % w, p / w, w, h) {
                let q = y * w + x;
                if component[q] == u32::MAX && labels[q] == labels[start] {
                    component[q] = id;
                    stack.push(q);
                }
            }
        }
        size.push(count);
    }
    // The largest piece of each cluster.
    let clusters = labels
        .iter()
        .filter(|&&l| l != u32::MAX)
        .max()
        .map_or(0, |&m| m as usize + 1);
    let mut largest = vec![(0usize, u32::MAX); clusters];
    for (id, &start) in first_pixel.iter().enumerate() {
        let cluster = labels[start] as usize;
        if cluster < clusters && size[id] > largest[cluster].0 {
            largest[cluster] = (size[id], id as u32);
        }
    }
    // Pass 2: keep or merge, in discovery order.
    let mut final_label = vec![u32::MAX; first_pixel.len()];
    let mut next = 0u32;
    for (id, &start) in first_pixel.iter().enumerate() {
        let cluster = labels[start] as usize;
        let main_piece = largest.get(cluster).is_some_and(|l| l.1 == id as u32);
        let keep = size[id] >= 2 * min_size || (main_piece && 2 * size[id] >= min_size);
        let (x, y) = (start % w, start / w);
        let before = [(x > 0).then(|| start - 1), (y > 0).then(|| start - w)]
            .into_iter()
            .flatten()
            .map(|p| final_label[component[p] as usize])
            .next();
        final_label[id] = match before {
            Some(target) if !keep => target,
            _ => {
                next += 1;
                next - 1
            }
        };
    }
    Grid::from_fn(w, h, |x, y| final_label[component[y * w + x] as usize])
}

/// The up-to-four 4-neighbours of (x, y) inside a `w × h` grid.
fn neighbours(x: usize, y: usize, w: usize, h: usize) -> impl Iterator<Item = (usize, usize)> {
    [
        (x > 0).then(|| (x - 1, y)),
        (y > 0).then(|| (x, y - 1)),
        (x + 1 < w).then(|| (x + 1, y)),
        (y + 1 < h).then(|| (x, y + 1)),
    ]
    .into_iter()
    .flatten()
}

/// Per-label pixel lists and statistics.
fn segments_of(frame: &Frame, lab: &Grid<[f32; 3]>, labels: Grid<u32>) -> Superpixels {
    let w = frame.width();
    let count = labels.data().iter().max().map_or(0, |&m| m as usize + 1);
    let mut segments: Vec<Segment> = (0..count)
        .map(|_| Segment {
            pixels: Vec::new(),
            anchor: [0.0; 2],
            mean_lab: [0.0; 3],
            mean_rgb: [0; 3],
            bbox: [u32::MAX, u32::MAX, 0, 0],
        })
        .collect();
    let mut sums = vec![[0f64; 8]; count];
    for (i, &l) in labels.data().iter().enumerate() {
        let (x, y) = ((i % w) as u32, (i / w) as u32);
        let seg = &mut segments[l as usize];
        seg.pixels.push(i as u32);
        seg.bbox = [
            seg.bbox[0].min(x),
            seg.bbox[1].min(y),
            seg.bbox[2].max(x),
            seg.bbox[3].max(y),
        ];
        let (p, c) = (lab.data()[i], frame.data()[i]);
        let s = &mut sums[l as usize];
        for k in 0..3 {
            s[k] += p[k] as f64;
            s[3 + k] += c[k] as f64;
        }
        s[6] += x as f64;
        s[7] += y as f64;
    }
    for (seg, s) in segments.iter_mut().zip(&sums) {
        let n = seg.pixels.len().max(1) as f64;
        seg.mean_lab = [0, 1, 2].map(|k| (s[k] / n) as f32);
        seg.mean_rgb = [0, 1, 2].map(|k| (s[3 + k] / n).round() as u8);
        seg.anchor = [s[6] / n, s[7] / n];
    }
    Superpixels { labels, segments }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_colour_halves_never_share_a_superpixel() {
        let frame = Grid::from_fn(
            64,
            48,
            |x, _| if x < 29 { [200, 30, 30] } else { [30, 30, 200] },
        );
        let sp = slic(
            &frame,
            &SlicParams {
                count: 24,
                ..SlicParams::default()
            },
        )
        .unwrap();
        for seg in &sp.segments {
            let left = seg.pixels.iter().filter(|&&p| (p % 64) < 29).count();
            assert!(
                left == 0 || left == seg.pixels.len(),
                "segment straddles the colour edge"
            );
        }
    }

    #[test]
    fn small_fragments_are_merged_into_neighbours() {
        // Labels: a 1-pixel island of label 1 inside label 0.
        let mut labels = vec![0u32; 25];
        labels[12] = 1;
        let out = enforce_connectivity(5, 5, &labels, 3);
        assert!(out.data().iter().all(|&l| l == 0));
    }

    #[test]
    fn bad_parameters_are_errors() {
        let frame = Grid::filled(32, 32, [0u8; 3]);
        assert!(
            slic(
                &frame,
                &SlicParams {
                    count: 0,
                    ..SlicParams::default()
                }
            )
            .is_err()
        );
        assert!(
            slic(
                &frame,
                &SlicParams {
                    count: 1000,
                    ..SlicParams::default()
                }
            )
            .is_err()
        );
        assert!(
            slic(
                &frame,
                &SlicParams {
                    compactness: -1.0,
                    ..SlicParams::default()
                }
            )
            .is_err()
        );
    }
}
