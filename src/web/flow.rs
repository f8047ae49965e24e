//! Optical flow for the page: [`compute_flow`](crate::flow::compute_flow) on two RGBA frames
//! (as a canvas's `getImageData` gives them), returning typed arrays.

use wasm_bindgen::prelude::*;

use crate::flow::colour::flow_picture;
use crate::flow::{FlowPair, FlowParams, Preset};
use crate::image::frame_from_rgba;

/// Flow both ways between two frames, as [`computeFlow`](compute_flow) returns it.
#[wasm_bindgen]
pub struct FlowResult {
    width: u32,
    height: u32,
    pair: FlowPair,
}

#[wasm_bindgen]
impl FlowResult {
    /// Width of the frames in pixels.
    #[wasm_bindgen(getter)]
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height of the frames in pixels.
    #[wasm_bindgen(getter)]
    pub fn height(&self) -> u32 {
        self.height
    }

    /// Flow frame 1 → 2 as a `Float32Array` of `2 · width · height` values, `u, v` per pixel,
    /// row by row (pixels; u right, v down).
    #[wasm_bindgen(getter)]
    pub fn forward(&self) -> Vec<f32> {
        interleaved(&self.pair.forward)
    }

    /// Flow frame 2 → 1, laid out as [`forward`](Self::forward).
    #[wasm_bindgen(getter)]
    pub fn backward(&self) -> Vec<f32> {
        interleaved(&self.pair.backward)
    }

    /// A `Uint8Array` of `width · height`: 1 where the forward vector passes the
    /// forward–backward check, 0 where it does not (occluded or mismatched).
    #[wasm_bindgen(getter)]
    pub fn reliable(&self) -> Vec<u8> {
        self.pair
            .reliable
            .data()
            .iter()
            .map(|&r| u8::from(r))
            .collect()
    }

    /// The forward flow drawn with the Middlebury colour wheel, as RGBA bytes
    /// (`4 · width · height`, opaque) ready for `new ImageData(...)`.
    #[wasm_bindgen(js_name = forwardPicture)]
    pub fn forward_picture(&self) -> Vec<u8> {
        super::rgba(&flow_picture(&self.pair.forward, None))
    }
}

/// Dense optical flow both ways between two RGBA frames of `width × height` pixels with the
/// preset `"fast"`, `"medium"`, `"fine"` or `"high"`. `progress`, when given, is called with the
/// share of the work done (0 to 1). Throws an `Error` with a readable message for frames of the
/// wrong length, different sizes, frames smaller than 8 pixels a side or an unknown preset.
#[wasm_bindgen(js_name = computeFlow)]
pub fn compute_flow(
    rgba1: &[u8],
    rgba2: &[u8],
    width: u32,
    height: u32,
    preset: &str,
    progress: Option<js_sys::Function>,
) -> Result<FlowResult, JsError> {
    let params = FlowParams::preset(Preset::from_name(preset)?);
    let (w, h) = (usize::try_from(width)?, usize::try_from(height)?);
    let frame1 = frame_from_rgba(rgba1, w, h)?;
    let frame2 = frame_from_rgba(rgba2, w, h)?;
    let mut report = super::fraction_callback(progress);
    let pair = crate::flow::compute_flow(&frame1, &frame2, &params, &mut report)?;
    Ok(FlowResult {
        width,
        height,
        pair,
    })
}

/// A flow field as `u, v` pairs row by row.
pub(super) fn interleaved(flow: &crate::flow::FlowField) -> Vec<f32> {
    flow.data().iter().flat_map(|&[u, v]| [u, v]).collect()
}
