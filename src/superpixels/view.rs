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
