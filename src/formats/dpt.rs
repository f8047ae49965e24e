//! MPI Sintel depth (`.dpt`): the tag float 202021.25 (the bytes `PIEH`, as in `.flo`), width and
//! height as little-endian i32, then width × height float32 depths, row by row from the top.

use super::{f32_le, pieh_header, read_pieh_header};
use crate::error::{Error, Result};
use crate::grid::Grid;

/// Encodes a depth map as `.dpt` (values written as they are, NaN included).
pub fn encode(depth: &Grid<f32>) -> Vec<u8> {
    let (w, h) = depth.size();
    let mut out = pieh_header(w, h);
    out.reserve(w * h * 4);
    for z in depth.data() {
        out.extend_from_slice(&z.to_le_bytes());
    }
    out
}

/// Decodes a `.dpt` file into a grid with row 0 at the top. Fails on a wrong tag, an invalid
/// size, or too few samples (a `.flo` of the same size has twice as many bytes: it is named as
/// such).
pub fn decode(bytes: &[u8]) -> Result<Grid<f32>> {
    let bad = |reason: String| Error::format(".dpt", reason);
    let (w, h) = read_pieh_header(
        bytes,
        ".dpt",
        "missing the PIEH tag (202021.25) of a Sintel depth file",
    )?;
    let data = &bytes[12..];
    if data.len() == w * h * 8 {
        return Err(bad(format!(
            "{w}×{h} with two floats per pixel: this is optical flow (.flo), not depth"
        )));
    }
    if data.len() < w * h * 4 {
        return Err(bad(format!(
            "{w}×{h} needs {} bytes of depths, file has {}",
            w * h * 4,
            data.len()
        )));
    }
    Ok(Grid::from_fn(w, h, |x, y| f32_le(data, (y * w + x) * 4)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_keeps_every_value_and_the_row_order() {
        let depth = Grid::from_fn(5, 3, |x, y| {
            if (x, y) == (2, 1) {
                f32::NAN
            } else {
                1.0 + x as f32 + 10.0 * y as f32
            }
        });
        let bytes = encode(&depth);
        assert_eq!(&bytes[..4], b"PIEH");
        assert_eq!(bytes.len(), 12 + 5 * 3 * 4);
        // Row 0 first: the second sample is (1, 0).
        assert_eq!(f32_le(&bytes, 16), 2.0);
        let back = decode(&bytes).unwrap();
        assert_eq!(back.size(), (5, 3));
        for y in 0..3 {
            for x in 0..5 {
                let (a, b) = (*depth.get(x, y), *back.get(x, y));
                assert!(a == b || (a.is_nan() && b.is_nan()), "({x}, {y})");
            }
        }
    }

    #[test]
    fn bad_files_are_errors() {
        let depth = Grid::filled(4, 2, 3.0f32);
        let bytes = encode(&depth);
        assert!(decode(&bytes[..20]).is_err());
        assert!(decode(b"Pf\n4 2\n-1\n").is_err());
        let mut wrong_size = bytes.clone();
        wrong_size[4..8].copy_from_slice(&(-1i32).to_le_bytes());
        assert!(decode(&wrong_size).is_err());
        let flow = super::super::flo::encode(&Grid::filled(4, 2, [1.0f32, 2.0]));
        let err = decode(&flow).unwrap_err().to_string();
        assert!(err.contains("optical flow"), "{err}");
    }
}
