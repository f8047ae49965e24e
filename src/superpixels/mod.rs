//! Superpixels of the reference frame and the graphs the soup is built on.
//!
//! - [`slic()`]: SLIC segmentation in CIELAB, every label one 4-connected region.
//! - [`graph`]: boundary pixel pairs between touching superpixels, and K-NN graphs over anchors.
//! - [`view`]: pictures (boundary overlay, mean colour) for the page and the CLI.

mod slic;

pub mod graph;
pub mod view;

pub use slic::{SlicParams, slic};

use crate::grid::Grid;

/// One superpixel: its pixels and summary statistics.
#[derive(Clone, Debug, PartialEq)]
pub struct Segment {
    /// Pixel indices `y · width + x`, in scan order.
    pub pixels: Vec<u32>,
    /// Centroid (u, v) in pixels: the paper's anchor point.
    pub anchor: [f64; 2],
    /// Mean colour in CIELAB.
    pub mean_lab: [f32; 3],
    /// Mean colour in 8-bit sRGB.
    pub mean_rgb: [u8; 3],
    /// Bounding box `[x_min, y_min, x_max, y_max]`, inclusive.
    pub bbox: [u32; 4],
}

/// A segmentation: a label per pixel (0..N'−1, no gaps, each label one 4-connected region) and
/// the segment each label names.
#[derive(Clone, Debug, PartialEq)]
pub struct Superpixels {
    pub labels: Grid<u32>,
    pub segments: Vec<Segment>,
}

impl Superpixels {
    /// Number of superpixels.
    pub fn len(&self) -> usize {
        self.segments.len()
    }

    /// True when there are no superpixels (never the case for a segmentation of an image).
    pub fn is_empty(&self) -> bool {
        self.segments.is_empty()
    }

    /// Size in pixels of the smallest superpixel (0 when there are none).
    pub fn smallest_size(&self) -> usize {
        self.segments
            .iter()
            .map(|s| s.pixels.len())
            .min()
            .unwrap_or(0)
    }

    /// Anchors normalised by the image's long side, as the paper's weights expect.
    pub fn normalised_anchors(&self) -> Vec<[f64; 2]> {
        let long = self.labels.width().max(self.labels.height()) as f64;
        self.segments
            .iter()
            .map(|s| [s.anchor[0] / long, s.anchor[1] / long])
            .collect()
    }
}
