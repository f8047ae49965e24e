//! Superpixels for the page: [`slic`](crate::superpixels::slic) on an RGBA frame (as a canvas's
//! `getImageData` gives it), returning typed arrays and the two pictures of
//! [`superpixels::view`](crate::superpixels::view).

use wasm_bindgen::prelude::*;

use crate::image::Frame;
use crate::image::frame_from_rgba;
use crate::superpixels::view::{boundary_overlay, mean_colour};
use crate::superpixels::{SlicParams, Superpixels, slic};

/// Colour of the boundaries in [`overlayPicture`](SuperpixelsResult::overlay_picture), as in
/// `soup superpixels --overlay`.
const BOUNDARY_COLOUR: [u8; 3] = [255, 230, 0];

/// A segmentation, as [`computeSuperpixels`](compute_superpixels) returns it.
#[wasm_bindgen]
pub struct SuperpixelsResult {
    frame: Frame,
    superpixels: Superpixels,
}

#[wasm_bindgen]
impl SuperpixelsResult {
    /// Width of the frame in pixels.
    #[wasm_bindgen(getter)]
    pub fn width(&self) -> u32 {
        self.frame.width() as u32
    }

    /// Height of the frame in pixels.
    #[wasm_bindgen(getter)]
    pub fn height(&self) -> u32 {
        self.frame.height() as u32
    }

    /// Number of superpixels N' (within about 15 % of the requested number).
    #[wasm_bindgen(getter)]
    pub fn count(&self) -> u32 {
        self.superpixels.len() as u32
    }

    /// The label of every pixel (0..count − 1), row by row, as a `Uint32Array` of
    /// `width · height`. Each label is one 4-connected region.
    #[wasm_bindgen(getter)]
    pub fn labels(&self) -> Vec<u32> {
        self.superpixels.labels.data().to_vec()
    }

    /// Pixel count of each superpixel, as a `Uint32Array` of `count`.
    #[wasm_bindgen(getter)]
    pub fn sizes(&self) -> Vec<u32> {
        self.superpixels
            .segments
            .iter()
            .map(|s| s.pixels.len() as u32)
            .collect()
    }

    /// Anchor (centroid) of each superpixel as `u, v` pairs in pixels (u right, v down), a
    /// `Float64Array` of `2 · count`.
    #[wasm_bindgen(getter)]
    pub fn anchors(&self) -> Vec<f64> {
        self.superpixels
            .segments
            .iter()
            .flat_map(|s| s.anchor)
            .collect()
    }

    /// Mean colour of each superpixel as `r, g, b` bytes, a `Uint8Array` of `3 · count`.
    #[wasm_bindgen(getter, js_name = meanColours)]
    pub fn mean_colours(&self) -> Vec<u8> {
        self.superpixels
            .segments
            .iter()
            .flat_map(|s| s.mean_rgb)
            .collect()
    }

    /// The frame with superpixel boundaries drawn in yellow, as RGBA bytes (`4 · width · height`,
    /// opaque) ready for `new ImageData(...)`.
    #[wasm_bindgen(js_name = overlayPicture)]
    pub fn overlay_picture(&self) -> Vec<u8> {
        super::rgba(&boundary_overlay(
            &self.frame,
            &self.superpixels,
            BOUNDARY_COLOUR,
        ))
    }

    /// Each superpixel painted with its mean colour, as RGBA bytes like
    /// [`overlayPicture`](Self::overlay_picture).
    #[wasm_bindgen(js_name = meanPicture)]
    pub fn mean_picture(&self) -> Vec<u8> {
        super::rgba(&mean_colour(&self.superpixels))
    }
}

/// SLIC superpixels of an RGBA frame of `width × height` pixels: about `n` of them, compactness
/// `compactness` (10 is the usual; larger gives more regular, less colour-driven shapes). Throws
/// an `Error` with a readable message for a frame of the wrong length, `n` of 0 or more than a
/// quarter of the pixels, or a compactness that is not positive.
#[wasm_bindgen(js_name = computeSuperpixels)]
pub fn compute_superpixels(
    rgba: &[u8],
    width: u32,
    height: u32,
    n: u32,
    compactness: f32,
) -> Result<SuperpixelsResult, JsError> {
    let frame = frame_from_rgba(rgba, usize::try_from(width)?, usize::try_from(height)?)?;
    let params = SlicParams {
        count: usize::try_from(n)?,
        compactness,
        ..SlicParams::default()
    };
    let superpixels = slic(&frame, &params)?;
    Ok(SuperpixelsResult { frame, superpixels })
}
