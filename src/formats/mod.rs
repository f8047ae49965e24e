//! Reading and writing the files the product exchanges with other tools: PFM depth, MPI Sintel
//! `.dpt` depth, Middlebury `.flo` flow, PLY point clouds, 16-bit PNG (depth and labels), and
//! the evaluation case layout.

pub mod case;
pub mod dpt;
pub mod flo;
pub mod pfm;
pub mod ply;
pub mod png16;

use crate::error::{Error, Result};
use std::path::Path;

/// Reads a whole file, naming the path in the error.
pub fn read_file(path: &Path) -> Result<Vec<u8>> {
    std::fs::read(path).map_err(|e| Error::io(path, e))
}

/// Writes a whole file, naming the path in the error.
pub fn write_file(path: &Path, bytes: &[u8]) -> Result<()> {
    std::fs::write(path, bytes).map_err(|e| Error::io(path, e))
}

/// Decodes a ground-truth depth map from a file's bytes, whichever of our depth formats it is
/// (told by its first bytes, not its name): PFM (`Pf`), Sintel `.dpt`, or a 16-bit greyscale
/// PNG where z = value × scale and 0 is unknown. The PNG's scale is its `depth_scale` text chunk
/// (our own depth PNGs) when it has one, else `png_scale`. Unknown depth comes back as NaN or
/// ≤ 0 (what the metrics skip).
pub fn decode_depth(bytes: &[u8], png_scale: Option<f64>) -> Result<crate::Grid<f32>> {
    const PNG_MAGIC: &[u8] = b"\x89PNG\r\n\x1a\n";
    if bytes.starts_with(b"Pf") || bytes.starts_with(b"PF") {
        pfm::decode(bytes)
    } else if bytes.starts_with(b"PIEH") {
        dpt::decode(bytes)
    } else if bytes.starts_with(PNG_MAGIC) {
        let (pixels, text) = png16::decode(bytes)?;
        let own = text
            .iter()
            .find(|(k, _)| k == png16::DEPTH_SCALE_KEY)
            .and_then(|(_, v)| v.trim().parse::<f64>().ok());
        let scale = own.or(png_scale).ok_or_else(|| {
            Error::InvalidParameter(
                "a 16-bit depth PNG needs its scale (depth = value × scale): enter it".into(),
            )
        })?;
        if !(scale.is_finite() && scale > 0.0) {
            return Err(Error::InvalidParameter(format!(
                "the depth PNG's scale must be a positive number, not {scale}"
            )));
        }
        Ok(pixels.map(|&v| {
            if v == 0 {
                f32::NAN
            } else {
                (v as f64 * scale) as f32
            }
        }))
    } else {
        Err(Error::format(
            "depth",
            "not a PFM, Sintel .dpt or 16-bit PNG depth map",
        ))
    }
}

/// The 12-byte header that `.flo` and Sintel's `.dpt` share: the bytes `PIEH` (the float
/// 202021.25), then width and height as little-endian i32.
fn pieh_header(width: usize, height: usize) -> Vec<u8> {
    let mut out = b"PIEH".to_vec();
    out.extend_from_slice(&(width as i32).to_le_bytes());
    out.extend_from_slice(&(height as i32).to_le_bytes());
    out
}

/// Width and height from a [`pieh_header`]. Errors name `format`: `missing` when the tag is
/// not there, or the size when it is not in 1..=65536.
fn read_pieh_header(bytes: &[u8], format: &'static str, missing: &str) -> Result<(usize, usize)> {
    if bytes.len() < 12 || &bytes[..4] != b"PIEH" {
        return Err(Error::format(format, missing));
    }
    let w = i32::from_le_bytes([bytes[4], bytes[5], bytes[6], bytes[7]]);
    let h = i32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]);
    if !(1..=1 << 16).contains(&w) || !(1..=1 << 16).contains(&h) {
        return Err(Error::format(format, format!("invalid size {w}×{h}")));
    }
    Ok((w as usize, h as usize))
}

/// Reads a little-endian f32 at `offset` (caller checks bounds).
fn f32_le(bytes: &[u8], offset: usize) -> f32 {
    f32::from_le_bytes([
        bytes[offset],
        bytes[offset + 1],
        bytes[offset + 2],
        bytes[offset + 3],
    ])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Grid;

    #[test]
    fn decode_depth_reads_every_depth_format_by_its_first_bytes() {
        let depth = Grid::from_fn(6, 4, |x, y| 1.0 + x as f32 + 0.5 * y as f32);
        assert_eq!(decode_depth(&pfm::encode(&depth), None).unwrap(), depth);
        assert_eq!(
            decode_depth(&dpt::encode(&depth), Some(9.0)).unwrap(),
            depth
        );
        // Our own depth PNG carries its scale; a foreign one takes the given scale.
        let own = decode_depth(&png16::encode_depth(&depth).unwrap(), None).unwrap();
        assert!((own.get(5, 3) - depth.get(5, 3)).abs() < 1e-3);
        let raw = png16::encode(&Grid::from_fn(6, 4, |x, _| x as u16 * 1000), &[]).unwrap();
        let scaled = decode_depth(&raw, Some(0.001)).unwrap();
        assert_eq!(*scaled.get(2, 1), 2.0);
        assert!(scaled.get(0, 0).is_nan(), "0 is unknown");
        let err = decode_depth(&raw, None).unwrap_err().to_string();
        assert!(err.contains("scale"), "{err}");
        assert!(decode_depth(&raw, Some(-1.0)).is_err());
        let err = decode_depth(b"GIF89a", None).unwrap_err().to_string();
        assert!(err.contains("not a PFM"), "{err}");
    }
}
