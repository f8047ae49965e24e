//! 16-bit greyscale PNG for depth maps and superpixel labels.
//!
//! Depth: each pixel stores `round(z / scale)` with 0 meaning unknown; the scale (scene units per
//! step) is written in the PNG `tEXt` chunk `depth_scale`, so z = value × scale. The scale is
//! chosen so the farthest depth maps to 65535, giving the finest steps the range allows.

use std::io::Cursor;

use crate::error::{Error, Result};
use crate::grid::Grid;

/// `tEXt` keyword holding the depth scale.
pub const DEPTH_SCALE_KEY: &str = "depth_scale";

fn png_error(e: impl std::fmt::Display) -> Error {
    Error::format("PNG", e.to_string())
}

/// Encodes 16-bit grey pixels with `tEXt` chunks `(keyword, text)`.
pub fn encode(pixels: &Grid<u16>, text: &[(&str, String)]) -> Result<Vec<u8>> {
    let mut out = Vec::new();
    let mut encoder = png::Encoder::new(&mut out, pixels.width() as u32, pixels.height() as u32);
    encoder.set_color(png::ColorType::Grayscale);
    encoder.set_depth(png::BitDepth::Sixteen);
    for (keyword, value) in text {
        encoder
            .add_text_chunk(keyword.to_string(), value.clone())
            .map_err(png_error)?;
    }
    let mut writer = encoder.write_header().map_err(png_error)?;
    let bytes: Vec<u8> = pixels.data().iter().flat_map(|v| v.to_be_bytes()).collect();
    writer.write_image_data(&bytes).map_err(png_error)?;
    writer.finish().map_err(png_error)?;
    Ok(out)
}

/// `tEXt` chunks as `(keyword, text)` pairs.
pub type TextChunks = Vec<(String, String)>;

/// Decodes an 8- or 16-bit greyscale PNG into 16-bit values, with its `tEXt` chunks.
pub fn decode(bytes: &[u8]) -> Result<(Grid<u16>, TextChunks)> {
    let mut decoder = png::Decoder::new(Cursor::new(bytes));
    decoder.set_transformations(png::Transformations::IDENTITY);
    let mut reader = decoder.read_info().map_err(png_error)?;
    let size = reader
        .output_buffer_size()
        .ok_or_else(|| png_error("image too large"))?;
    let mut buffer = vec![0; size];
    let info = reader.next_frame(&mut buffer).map_err(png_error)?;
    if info.color_type != png::ColorType::Grayscale {
        return Err(png_error(format!(
            "expected a greyscale PNG, got {:?}",
            info.color_type
        )));
    }
    let (w, h) = (info.width as usize, info.height as usize);
    let pixels = match info.bit_depth {
        png::BitDepth::Sixteen => Grid::from_fn(w, h, |x, y| {
            let i = y * info.line_size + 2 * x;
            u16::from_be_bytes([buffer[i], buffer[i + 1]])
        }),
        png::BitDepth::Eight => Grid::from_fn(w, h, |x, y| buffer[y * info.line_size + x] as u16),
        other => return Err(png_error(format!("unsupported bit depth {other:?}"))),
    };
    let text = reader
        .info()
        .uncompressed_latin1_text
        .iter()
        .map(|t| (t.keyword.clone(), t.text.clone()))
        .collect();
    Ok((pixels, text))
}

/// Encodes a depth map (NaN or ≤ 0 = unknown) as 16-bit PNG with its scale in `depth_scale`.
pub fn encode_depth(depth: &Grid<f32>) -> Result<Vec<u8>> {
    let max = depth
        .data()
        .iter()
        .filter(|z| z.is_finite() && **z > 0.0)
        .fold(0.0f32, |a, &z| a.max(z));
    let scale = if max > 0.0 { max as f64 / 65535.0 } else { 1.0 };
    let pixels = depth.map(|&z| {
        if z.is_finite() && z > 0.0 {
            ((z as f64 / scale).round() as u32).clamp(1, 65535) as u16
        } else {
            0
        }
    });
    encode(&pixels, &[(DEPTH_SCALE_KEY, format!("{scale:e}"))])
}

/// Decodes a depth PNG written by [`encode_depth`]: z = value × `depth_scale`, 0 → NaN.
pub fn decode_depth(bytes: &[u8]) -> Result<Grid<f32>> {
    let (pixels, text) = decode(bytes)?;
    let scale: f64 = text
        .iter()
        .find(|(k, _)| k == DEPTH_SCALE_KEY)
        .and_then(|(_, v)| v.trim().parse().ok())
        .filter(|s: &f64| s.is_finite() && *s > 0.0)
        .ok_or_else(|| png_error(format!("no valid `{DEPTH_SCALE_KEY}` text chunk")))?;
    Ok(pixels.map(|&v| {
        if v == 0 {
            f32::NAN
        } else {
            (v as f64 * scale) as f32
        }
    }))
}

/// Encodes a label map as 16-bit grey; fails when a label exceeds 65535.
pub fn encode_labels(labels: &Grid<u32>) -> Result<Vec<u8>> {
    if let Some(&max) = labels.data().iter().max().filter(|&&m| m > 65535) {
        return Err(Error::InvalidParameter(format!(
            "label {max} does not fit a 16-bit PNG (at most 65536 labels)"
        )));
    }
    encode(&labels.map(|&l| l as u16), &[])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn depth_round_trip_within_one_step() {
        let depth = Grid::from_fn(7, 5, |x, y| {
            if x == 3 {
                f32::NAN
            } else {
                0.5 + (x * 5 + y) as f32 * 0.37
            }
        });
        let back = decode_depth(&encode_depth(&depth).unwrap()).unwrap();
        let step = 0.5 + 34.0 * 0.37;
        for (a, b) in depth.data().iter().zip(back.data()) {
            if a.is_nan() {
                assert!(b.is_nan());
            } else {
                assert!((a - b).abs() <= step / 65535.0, "{a} {b}");
            }
        }
    }

    #[test]
    fn labels_round_trip_and_overflow_is_an_error() {
        let labels = Grid::from_fn(9, 4, |x, y| (x * 1000 + y) as u32);
        let (back, _) = decode(&encode_labels(&labels).unwrap()).unwrap();
        assert_eq!(back.map(|&v| v as u32), labels);
        assert!(encode_labels(&Grid::filled(2, 2, 70_000)).is_err());
    }

    #[test]
    fn missing_scale_and_colour_pngs_are_errors() {
        let plain = encode(&Grid::filled(3, 3, 5u16), &[]).unwrap();
        assert!(decode_depth(&plain).is_err());
        let rgb = crate::image::encode_png(&Grid::filled(3, 3, [1u8, 2, 3])).unwrap();
        assert!(decode(&rgb).is_err());
        assert!(decode(b"not a png").is_err());
    }
}
