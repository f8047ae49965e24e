//! Middlebury `.flo` optical flow: `PIEH` magic (the float 202021.25), width and height as
//! little-endian i32, then (u, v) float32 pairs row by row. Vectors with |u| or |v| > 1e9 are
//! unknown; in memory they are NaN ([`crate::flow::FlowField`]) and we write them as 1e10.

use super::{f32_le, pieh_header, read_pieh_header};
use crate::error::{Error, Result};
use crate::flow::FlowField;
use crate::grid::Grid;

/// The value written for unknown flow.
pub const UNKNOWN: f32 = 1e10;
/// Components above this magnitude are read as unknown.
pub const UNKNOWN_THRESHOLD: f32 = 1e9;

/// Encodes a flow field; NaN vectors become [`UNKNOWN`].
pub fn encode(flow: &FlowField) -> Vec<u8> {
    let (w, h) = flow.size();
    let mut out = pieh_header(w, h);
    out.reserve(w * h * 8);
    for &[u, v] in flow.data() {
        let known = crate::flow::is_known([u, v]);
        let (u, v) = if known { (u, v) } else { (UNKNOWN, UNKNOWN) };
        out.extend_from_slice(&u.to_le_bytes());
        out.extend_from_slice(&v.to_le_bytes());
    }
    out
}

/// Decodes a `.flo` file; unknown vectors come back as NaN.
pub fn decode(bytes: &[u8]) -> Result<FlowField> {
    let bad = |reason: String| Error::format(".flo", reason);
    let (w, h) = read_pieh_header(bytes, ".flo", "missing PIEH magic")?;
    let need = 12 + w * h * 8;
    if bytes.len() < need {
        return Err(bad(format!(
            "{w}×{h} needs {need} bytes, file has {}",
            bytes.len()
        )));
    }
    let unknown = |c: f32| !c.is_finite() || c.abs() > UNKNOWN_THRESHOLD;
    Ok(Grid::from_fn(w, h, |x, y| {
        let offset = 12 + (y * w + x) * 8;
        let (u, v) = (f32_le(bytes, offset), f32_le(bytes, offset + 4));
        if unknown(u) || unknown(v) {
            [f32::NAN, f32::NAN]
        } else {
            [u, v]
        }
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_keeps_vectors_and_unknowns() {
        let flow = Grid::from_fn(4, 3, |x, y| {
            if (x, y) == (1, 2) {
                [f32::NAN, f32::NAN]
            } else {
                [x as f32 - 1.5, y as f32 * 0.25]
            }
        });
        let bytes = encode(&flow);
        assert_eq!(bytes.len(), 12 + 4 * 3 * 8);
        let back = decode(&bytes).unwrap();
        assert!(back.get(1, 2)[0].is_nan());
        assert_eq!(*back.get(3, 1), [1.5, 0.25]);
        assert_eq!(f32_le(&bytes, 12 + (2 * 4 + 1) * 8), UNKNOWN);
    }

    #[test]
    fn huge_components_read_as_unknown() {
        let mut bytes = b"PIEH".to_vec();
        bytes.extend_from_slice(&1i32.to_le_bytes());
        bytes.extend_from_slice(&1i32.to_le_bytes());
        bytes.extend_from_slice(&2e9f32.to_le_bytes());
        bytes.extend_from_slice(&0f32.to_le_bytes());
        assert!(decode(&bytes).unwrap().get(0, 0)[1].is_nan());
    }

    #[test]
    fn malformed_files_are_errors() {
        assert!(decode(b"PIEH").is_err());
        assert!(decode(b"XXXX\x01\0\0\0\x01\0\0\0").is_err());
        assert!(decode(b"PIEH\x02\0\0\0\x02\0\0\0\0\0\0\0").is_err());
        assert!(decode(b"PIEH\xff\xff\xff\xff\x02\0\0\0").is_err());
    }
}
