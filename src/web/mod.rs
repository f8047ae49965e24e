//! The JavaScript API of the wasm build (compiled only for `wasm32`), used by the page in `www/`.
//!
//! This layer stays thin: each export converts its arguments from JavaScript, calls the public
//! Rust API that the CLI uses too, and converts the result (or a readable [`JsError`]) back.
//! No algorithm lives here.
//!
//! - this file: `version`, `decodeImageInfo`
//! - [`reconstruct`]: the pipeline for the page's Web Worker (`reconstruct`,
//!   `reconstructUnfused`, `readExif`,
//!   `resolveIntrinsics`, `pageDefaults`) and the result's pictures, clouds and export files
//! - [`members`]: the fusion's members made in other workers (after `reconstructUnfused`:
//!   `memberCounts`, `memberVote`, `memberInputs`, `MemberSource`, `addVote`, `addFailure`,
//!   `fuse`)
//! - [`decode`]: JPEG photos decoded straight to the working size in the worker (`decodeJpeg`)
//! - [`ground_truth`]: scores of the result against the user's ground truth (`scoreDepth`,
//!   `scoreFlow`, `errorPicture`)
//! - [`memory`]: out-of-memory reporting (`failedAllocation`, `memoryBytes`)
//! - `flow`: `computeFlow`
//! - [`superpixels`]: SLIC for the page (`computeSuperpixels`)
//! - [`viewer`] (feature `viewer`, on by default): the 3D point-cloud viewer. The worker's lean
//!   module (scripts/build-web.sh) is built without it.

use wasm_bindgen::prelude::*;

use crate::image::Frame;

pub mod decode;
mod flow;
pub mod ground_truth;
pub mod members;
pub mod memory;
pub mod reconstruct;
#[cfg(feature = "viewer")]
pub mod viewer;

pub use flow::{FlowResult, compute_flow};

/// `computeSuperpixels`: SLIC superpixels and their pictures for the page.
pub mod superpixels;

/// Runs once when the module is instantiated: Rust panics then reach the browser console as
/// readable messages instead of a bare `unreachable` trap.
#[wasm_bindgen(start)]
pub fn start() {
    console_error_panic_hook::set_once();
}

/// The crate version, e.g. `"0.1.0"`.
#[wasm_bindgen]
pub fn version() -> String {
    env!("CARGO_PKG_VERSION").to_string()
}

/// What [`decode_image_info`] found in an image file.
#[wasm_bindgen]
#[derive(Clone, Debug, PartialEq)]
pub struct ImageInfo {
    width: u32,
    height: u32,
    focal_35mm: Option<f64>,
    exif_warning: Option<String>,
}

#[wasm_bindgen]
impl ImageInfo {
    /// Width in pixels, after turning the image upright by its EXIF orientation.
    #[wasm_bindgen(getter)]
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in pixels, after turning the image upright by its EXIF orientation.
    #[wasm_bindgen(getter)]
    pub fn height(&self) -> u32 {
        self.height
    }

    /// EXIF 35 mm-equivalent focal length in millimetres; `undefined` when the file has none.
    #[wasm_bindgen(getter, js_name = focal35mm)]
    pub fn focal_35mm(&self) -> Option<f64> {
        self.focal_35mm
    }

    /// Why the file's EXIF block could not be read (the image itself decoded fine);
    /// `undefined` when there was no problem.
    #[wasm_bindgen(getter, js_name = exifWarning)]
    pub fn exif_warning(&self) -> Option<String> {
        self.exif_warning.clone()
    }
}

/// Decodes PNG or JPEG file bytes with [`crate::image::decode_image`] and reports the upright
/// size and EXIF focal length. Throws an `Error` with a readable message for anything that is
/// not a complete PNG or JPEG.
#[wasm_bindgen(js_name = decodeImageInfo)]
pub fn decode_image_info(bytes: &[u8]) -> Result<ImageInfo, JsError> {
    let image = crate::image::decode_image(bytes)?;
    let (width, height) = image.frame.size();
    Ok(ImageInfo {
        width: u32::try_from(width)?,
        height: u32::try_from(height)?,
        focal_35mm: image.exif.focal_35mm,
        exif_warning: image.exif.warning,
    })
}

/// A `progress(fraction)` for the library from an optional JavaScript callback: calls it with the
/// share of the work done (0 to 1) when given; a callback that throws does not abort the work.
fn fraction_callback(progress: Option<js_sys::Function>) -> impl FnMut(f32) {
    move |fraction: f32| {
        if let Some(callback) = &progress {
            let _ = callback.call1(&JsValue::NULL, &JsValue::from_f64(fraction.into()));
        }
    }
}

/// A frame as opaque RGBA bytes, ready for `new ImageData(...)`.
fn rgba(frame: &Frame) -> Vec<u8> {
    frame
        .data()
        .iter()
        .flat_map(|&[r, g, b]| [r, g, b, 255])
        .collect()
}
