//! `decodeJpeg`: a JPEG photo decoded straight to the working size ([`crate::jpeg`]) in the
//! worker, so that neither the page nor the worker ever holds its full-size pixels.

use wasm_bindgen::prelude::*;

use crate::jpeg::decode_jpeg_scaled;

/// A photo decoded by [`decode_jpeg`]: its upright size, its pixels at the working size and its
/// EXIF facts.
#[wasm_bindgen]
pub struct DecodedJpeg {
    width: u32,
    height: u32,
    frame_width: u32,
    frame_height: u32,
    exif: String,
    pixels: Vec<u8>,
}

#[wasm_bindgen]
impl DecodedJpeg {
    /// Width of the photo in pixels, upright (after its EXIF orientation).
    #[wasm_bindgen(getter)]
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height of the photo in pixels, upright.
    #[wasm_bindgen(getter)]
    pub fn height(&self) -> u32 {
        self.height
    }

    /// Width of the decoded pixels (the working size), in pixels.
    #[wasm_bindgen(getter, js_name = frameWidth)]
    pub fn frame_width(&self) -> u32 {
        self.frame_width
    }

    /// Height of the decoded pixels (the working size), in pixels.
    #[wasm_bindgen(getter, js_name = frameHeight)]
    pub fn frame_height(&self) -> u32 {
        self.frame_height
    }

    /// The EXIF facts as JSON: `{ focal35mm, warning }` (see [`crate::image::ExifInfo`]).
    #[wasm_bindgen(getter)]
    pub fn exif(&self) -> String {
        self.exif.clone()
    }

    /// The pixels at the working size as opaque RGBA bytes, row by row from the top (ready for
    /// `new ImageData(...)`); moved out, so a second call gives an empty array.
    #[wasm_bindgen(js_name = takePixels)]
    pub fn take_pixels(&mut self) -> Vec<u8> {
        std::mem::take(&mut self.pixels)
    }
}

/// Decodes JPEG file bytes upright at the working size for `max_side` (the long side at most
/// that many pixels) with a DCT-scaled decode ([`crate::jpeg::decode_jpeg_scaled`]). Throws an
/// `Error` for a file it cannot or does not decode (damaged, CMYK, arithmetic coding, …): the
/// page then lets the browser decode it.
#[wasm_bindgen(js_name = decodeJpeg)]
pub fn decode_jpeg(bytes: &[u8], max_side: u32) -> Result<DecodedJpeg, JsError> {
    let decoded = decode_jpeg_scaled(bytes, usize::try_from(max_side)?)?;
    let (width, height) = decoded.full_size;
    let frame = decoded.frame();
    Ok(DecodedJpeg {
        width: u32::try_from(width)?,
        height: u32::try_from(height)?,
        frame_width: u32::try_from(frame.width())?,
        frame_height: u32::try_from(frame.height())?,
        exif: serde_json::to_string(&decoded.image.exif)?,
        pixels: super::rgba(frame),
    })
}
