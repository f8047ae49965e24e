//! What a reconstruction gives: dense depth of frame 1, the point clouds of both frames
//! (X and X' = R X + λ t̂ per pixel, coloured from frame 1) and the scene flow, from a soup with
//! its scales, and the [`PointCloud`] type they come in.

use nalgebra::Vector3;

use crate::camera::Intrinsics;
use crate::grid::Grid;
use crate::image::Frame;
use crate::soup::Soup;

/// Points with colours: `positions[i]` (x, y, z in the frame and units of whoever made the
/// cloud; for [`point_clouds`], camera coordinates at the scene's scale) coloured `colours[i]`
/// (sRGB bytes). The output of the pipeline, written by [`crate::formats::ply`] and shown by the
/// page's viewer.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PointCloud {
    pub positions: Vec<[f32; 3]>,
    pub colours: Vec<[u8; 3]>,
}

/// Frame-1 z-depth at the working resolution: each pixel on its superpixel's plane; NaN where
/// the plane puts it behind the camera.
pub fn dense_depth(soup: &Soup, labels: &Grid<u32>, k: &Intrinsics) -> Grid<f32> {
    strided_depth(soup, labels, k, 1)
}

/// [`dense_depth`] at every `stride`-th pixel in x and y only: (x, y) of the result is pixel
/// (stride·x, stride·y) of the working resolution (⌈w / stride⌉ × ⌈h / stride⌉; a stride of 0
/// counts as 1).
pub fn strided_depth(soup: &Soup, labels: &Grid<u32>, k: &Intrinsics, stride: usize) -> Grid<f32> {
    let s = stride.max(1);
    let (w, h) = (labels.width().div_ceil(s), labels.height().div_ceil(s));
    Grid::from_fn(w, h, |x, y| {
        let (u, v) = (x * s, y * s);
        let piece = &soup.pieces[*labels.get(u, v) as usize];
        piece.depth(&Vector3::from(k.ray(u as f64, v as f64))) as f32
    })
}

/// The superpixel label of pixel (x, y) of a `width` × `height` image (e.g. the input's): the
/// label of the nearest working-resolution pixel (pixel centres at integers on both grids).
pub fn nearest_label(labels: &Grid<u32>, width: usize, height: usize, x: usize, y: usize) -> usize {
    let sx = labels.width() as f64 / width as f64;
    let sy = labels.height() as f64 / height as f64;
    let lx = (((x as f64 + 0.5) * sx - 0.5).round().max(0.0) as usize).min(labels.width() - 1);
    let ly = (((y as f64 + 0.5) * sy - 0.5).round().max(0.0) as usize).min(labels.height() - 1);
    *labels.get(lx, ly) as usize
}

/// Frame-1 z-depth at another resolution (e.g. the input's, `k_out` its intrinsics): each pixel
/// takes the label of the nearest working-resolution pixel and is evaluated on that plane at its
/// own ray, so planes stay exact instead of being upsampled.
pub fn depth_at(
    soup: &Soup,
    labels: &Grid<u32>,
    width: usize,
    height: usize,
    k_out: &Intrinsics,
) -> Grid<f32> {
    Grid::from_fn(width, height, |x, y| {
        let piece = &soup.pieces[nearest_label(labels, width, height, x, y)];
        piece.depth(&Vector3::from(k_out.ray(x as f64, y as f64))) as f32
    })
}

/// Whether [`point_clouds`] makes a point of a pixel with depth `z`: finite and in front.
fn has_point(z: f32) -> bool {
    z.is_finite() && z > 0.0
}

/// The superpixel label of each point of [`point_clouds`] (same depth map, same order: pixels
/// row by row, those without a depth left out), e.g. to colour the points by superpixel.
pub fn cloud_labels(labels: &Grid<u32>, depth: &Grid<f32>) -> Vec<u32> {
    labels
        .data()
        .iter()
        .zip(depth.data())
        .filter(|&(_, &z)| has_point(z))
        .map(|(&label, _)| label)
        .collect()
}

/// Scene flow per pixel of frame 1 at the working resolution: X' − X with X = z x̄ (camera-1
/// coordinates) and X' = R X + λ t̂ its position after the piece's motion (camera-2
/// coordinates; docs/ARCHITECTURE.md, Conventions, Motion). For a static point this is the
/// camera motion's effect, not zero. NaN where the pixel has no depth.
pub fn scene_flow(
    soup: &Soup,
    labels: &Grid<u32>,
    depth: &Grid<f32>,
    k: &Intrinsics,
) -> Grid<[f32; 3]> {
    Grid::from_fn(labels.width(), labels.height(), |x, y| {
        let z = *depth.get(x, y);
        if !has_point(z) {
            return [f32::NAN; 3];
        }
        let z = z as f64;
        let piece = &soup.pieces[*labels.get(x, y) as usize];
        let p = Vector3::from(k.ray(x as f64, y as f64)) * z;
        let d = piece.r * p + piece.t_hat * piece.lambda - p;
        [d.x as f32, d.y as f32, d.z as f32]
    })
}

/// Point clouds of frame 1 (X = z x̄, camera-1 coordinates) and frame 2 (X' = R X + λ t̂, each
/// point moved by its piece's motion, i.e. camera-2 coordinates), one point per pixel with a
/// depth, coloured from frame 1. X' − X is the scene flow plus the camera motion.
pub fn point_clouds(
    soup: &Soup,
    labels: &Grid<u32>,
    depth: &Grid<f32>,
    frame1: &Frame,
    k: &Intrinsics,
) -> (PointCloud, PointCloud) {
    let (mut c1, mut c2) = (PointCloud::default(), PointCloud::default());
    for y in 0..labels.height() {
        for x in 0..labels.width() {
            let z = *depth.get(x, y);
            if !has_point(z) {
                continue;
            }
            let z = z as f64;
            let piece = &soup.pieces[*labels.get(x, y) as usize];
            let p = Vector3::from(k.ray(x as f64, y as f64)) * z;
            let p2 = piece.r * p + piece.t_hat * piece.lambda;
            c1.positions.push([p.x as f32, p.y as f32, p.z as f32]);
            c2.positions.push([p2.x as f32, p2.y as f32, p2.z as f32]);
            let colour = *frame1.get(x, y);
            c1.colours.push(colour);
            c2.colours.push(colour);
        }
    }
    (c1, c2)
}

/// Frame 1 with the superpixels whose depth is a guess (confidence below `min`, see
/// [`crate::soup::scales::depth_confidence`]) tinted magenta: the parts of the reconstruction
/// that are guesses. `confidence` has one value per label.
pub fn confidence_picture(
    frame: &Frame,
    labels: &Grid<u32>,
    confidence: &[f64],
    min: f64,
) -> Frame {
    const TINT: [f32; 3] = [255.0, 0.0, 200.0];
    Grid::from_fn(labels.width(), labels.height(), |x, y| {
        let pixel = *frame.get(x, y);
        let known = confidence
            .get(*labels.get(x, y) as usize)
            .is_some_and(|&c| c >= min);
        if known {
            pixel
        } else {
            [0, 1, 2].map(|c| (0.4 * pixel[c] as f32 + 0.6 * TINT[c]).round() as u8)
        }
    })
}

#[cfg(test)]
mod tests {
    use nalgebra::Matrix3;

    use super::*;
    use crate::soup::Piece;

    /// A 6×2 soup: columns 0–1 a wall at depth 2 moving by (1, 0, 0), columns 2–3 a plane
    /// behind the camera, columns 4–5 a static wall at depth 4.
    fn soup_and_labels() -> (Soup, Grid<u32>) {
        let piece = |m: [f64; 3], t: [f64; 3]| Piece {
            r: Matrix3::identity(),
            t_hat: Vector3::from(t),
            m: Vector3::from(m),
            lambda: 1.0,
            hypothesis: 0,
            degenerate: None,
        };
        let soup = Soup {
            pieces: vec![
                piece([0.0, 0.0, 0.5], [1.0, 0.0, 0.0]),
                piece([0.0, 0.0, -1.0], [0.0, 0.0, 0.0]),
                piece([0.0, 0.0, 0.25], [0.0, 0.0, 0.0]),
            ],
            hypotheses: Vec::new(),
            noise_px: 0.0,
            ego_rival: None,
            rugged_to_ego: 0,
        };
        (soup, Grid::from_fn(6, 2, |x, _| (x / 2) as u32))
    }

    #[test]
    fn clouds_skip_pixels_without_depth_and_labels_follow_the_points() {
        let (soup, labels) = soup_and_labels();
        let k = Intrinsics::default_for(6, 2);
        let depth = dense_depth(&soup, &labels, &k);
        assert_eq!(*depth.get(0, 0), 2.0);
        assert!(depth.get(2, 1).is_nan());
        assert_eq!(*depth.get(5, 1), 4.0);
        let frame = Grid::from_fn(6, 2, |x, y| [x as u8, y as u8, 0]);
        let (c1, c2) = point_clouds(&soup, &labels, &depth, &frame, &k);
        let point_labels = cloud_labels(&labels, &depth);
        assert_eq!(point_labels, [0, 0, 2, 2, 0, 0, 2, 2]);
        assert_eq!(c1.positions.len(), point_labels.len());
        assert_eq!(c2.positions.len(), point_labels.len());
        // Points in row-major order: the first is pixel (0, 0), the third pixel (4, 0).
        assert_eq!(c1.colours[2], [4, 0, 0]);
        assert_eq!(c1.positions[2][2], 4.0);
        assert!((c2.positions[0][0] - c1.positions[0][0] - 1.0).abs() < 1e-6);
        assert_eq!(c2.positions[2], c1.positions[2]);
    }

    #[test]
    fn strided_depth_is_the_dense_depth_at_every_stride_th_pixel() {
        let (soup, labels) = soup_and_labels();
        let k = Intrinsics::default_for(6, 2);
        let dense = dense_depth(&soup, &labels, &k);
        for stride in [2, 4] {
            let strided = strided_depth(&soup, &labels, &k, stride);
            assert_eq!(strided.size(), (6usize.div_ceil(stride), 1));
            for x in 0..strided.width() {
                let (a, b) = (*strided.get(x, 0), *dense.get(x * stride, 0));
                assert!(
                    a == b || (a.is_nan() && b.is_nan()),
                    "stride {stride}, x {x}"
                );
            }
        }
    }

    #[test]
    fn the_confidence_picture_tints_exactly_the_unconfident_superpixels() {
        let frame = Grid::filled(4, 2, [100u8, 100, 100]);
        let labels = Grid::from_fn(4, 2, |x, _| (x / 2) as u32);
        let picture = confidence_picture(&frame, &labels, &[0.5, 0.05], 0.1);
        for y in 0..2 {
            for x in 0..4 {
                let p = *picture.get(x, y);
                if x < 2 {
                    assert_eq!(p, [100, 100, 100], "label 0 is confident");
                } else {
                    assert_eq!(p, [193, 40, 160], "label 1 is not");
                }
            }
        }
    }
}
