//! What a reconstruction gives: dense depth of frame 1 and the point clouds of both frames
//! (X and X' = R X + λ t̂ per pixel, coloured from frame 1), from the scaled soup.

use nalgebra::Vector3;

use crate::camera::Intrinsics;
use crate::formats::ply::PointCloud;
use crate::grid::Grid;
use crate::image::Frame;
use crate::soup::Soup;

/// Frame-1 z-depth at the working resolution: each pixel on its superpixel's plane; NaN where
/// the plane puts it behind the camera.
pub fn dense_depth(soup: &Soup, labels: &Grid<u32>, k: &Intrinsics) -> Grid<f32> {
    Grid::from_fn(labels.width(), labels.height(), |x, y| {
        let piece = &soup.pieces[*labels.get(x, y) as usize];
        piece.depth(&Vector3::from(k.ray(x as f64, y as f64))) as f32
    })
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
    let sx = labels.width() as f64 / width as f64;
    let sy = labels.height() as f64 / height as f64;
    Grid::from_fn(width, height, |x, y| {
        let lx = (((x as f64 + 0.5) * sx - 0.5).round().max(0.0) as usize).min(labels.width() - 1);
        let ly = (((y as f64 + 0.5) * sy - 0.5).round().max(0.0) as usize).min(labels.height() - 1);
        let piece = &soup.pieces[*labels.get(lx, ly) as usize];
        piece.depth(&Vector3::from(k_out.ray(x as f64, y as f64))) as f32
    })
}

/// Scene flow per pixel of frame 1 at the working resolution: X' − X with X = z x̄ (camera-1
/// coordinates) and X' = R X + λ t̂ its position after the piece's motion (camera-2
/// coordinates), as DESIGN.md stage 6 defines it (for a static point this is the camera motion's
/// effect, not zero). NaN where the pixel has no depth.
pub fn scene_flow(
    soup: &Soup,
    labels: &Grid<u32>,
    depth: &Grid<f32>,
    k: &Intrinsics,
) -> Grid<[f32; 3]> {
    Grid::from_fn(labels.width(), labels.height(), |x, y| {
        let z = *depth.get(x, y) as f64;
        if !z.is_finite() || z <= 0.0 {
            return [f32::NAN; 3];
        }
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
            let z = *depth.get(x, y) as f64;
            if !z.is_finite() || z <= 0.0 {
                continue;
            }
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
