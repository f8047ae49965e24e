//! Pictures of a segmentation for the page and the CLI.

use crate::image::Frame;

use super::Superpixels;
use super::graph::boundary_mask;

/// `frame` with superpixel boundaries drawn in `colour`.
pub fn boundary_overlay(frame: &Frame, sp: &Superpixels, colour: [u8; 3]) -> Frame {
    let mask = boundary_mask(&sp.labels);
    let mut out = frame.clone();
    for (px, &edge) in out.data_mut().iter_mut().zip(mask.data()) {
        if edge {
            *px = colour;
        }
    }
    out
}

/// Each pixel painted with its superpixel's mean colour.
pub fn mean_colour(sp: &Superpixels) -> Frame {
    sp.labels.map(|&l| sp.segments[l as usize].mean_rgb)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::Grid;
    use crate::superpixels::{SlicParams, slic};

    fn stripes() -> (Frame, Superpixels) {
        let frame = Grid::from_fn(60, 40, |x, y| {
            let base = if x < 30 { [200, 40, 40] } else { [40, 40, 200] };
            base.map(|c| c + ((x * 7 + y * 3) % 11) as u8)
        });
        let sp = slic(
            &frame,
            &SlicParams {
                count: 12,
                ..SlicParams::default()
            },
        )
        .unwrap();
        (frame, sp)
    }

    #[test]
    fn overlay_paints_exactly_the_boundary_pixels() {
        let (frame, sp) = stripes();
        let out = boundary_overlay(&frame, &sp, [255, 230, 0]);
        let mask = boundary_mask(&sp.labels);
        assert!(mask.data().iter().any(|&b| b) && !mask.data().iter().all(|&b| b));
        for ((&painted, &original), &edge) in out.data().iter().zip(frame.data()).zip(mask.data()) {
            assert_eq!(painted, if edge { [255, 230, 0] } else { original });
        }
    }

    #[test]
    fn mean_colour_paints_each_superpixel_with_its_average() {
        let (frame, sp) = stripes();
        let out = mean_colour(&sp);
        for seg in &sp.segments {
            let n = seg.pixels.len() as f64;
            let mean = [0, 1, 2].map(|k| {
                let sum: f64 = seg
                    .pixels
                    .iter()
                    .map(|&p| frame.data()[p as usize][k] as f64)
                    .sum();
                (sum / n).round() as u8
            });
            assert!(seg.pixels.iter().all(|&p| out.data()[p as usize] == mean));
        }
    }
}
