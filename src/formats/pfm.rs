//! PFM (portable float map), single channel (`Pf`): the depth format of the evaluation cases.
//!
//! Layout: `Pf\n<width> <height>\n<scale>\n` then float32 samples, rows stored bottom to top;
//! a negative scale means little-endian. NaN marks unknown depth. We write little-endian.

use super::f32_le;
use crate::error::{Error, Result};
use crate::grid::Grid;

/// Encodes a single-channel float map (row 0 of the grid is the top image row).
pub fn encode(map: &Grid<f32>) -> Vec<u8> {
    let (w, h) = map.size();
    let mut out = format!("Pf\n{w} {h}\n-1.0\n").into_bytes();
    out.reserve(w * h * 4);
    for y in (0..h).rev() {
        for v in map.row(y) {
            out.extend_from_slice(&v.to_le_bytes());
        }
    }
    out
}

/// Decodes a `Pf` map (either byte order) into a grid with row 0 at the top.
pub fn decode(bytes: &[u8]) -> Result<Grid<f32>> {
    let bad = |reason: &str| Error::format("PFM", reason.to_string());
    let (tokens, data_start) = header_tokens(bytes, 4).ok_or_else(|| bad("truncated header"))?;
    match tokens[0].as_str() {
        "Pf" => {}
        "PF" => {
            return Err(bad(
                "colour PFM (PF) given where a single-channel map (Pf) is needed",
            ));
        }
        _ => return Err(bad("missing Pf magic")),
    }
    let parse_dim = |s: &str| s.parse::<usize>().ok().filter(|&d| d > 0 && d <= 1 << 16);
    let (Some(w), Some(h)) = (parse_dim(&tokens[1]), parse_dim(&tokens[2])) else {
        return Err(bad("invalid width or height"));
    };
    let scale: f32 = tokens[3].parse().map_err(|_| bad("invalid scale"))?;
    if scale == 0.0 || !scale.is_finite() {
        return Err(bad("scale must be a non-zero number"));
    }
    let data = &bytes[data_start..];
    if data.len() < w * h * 4 {
        return Err(bad(&format!(
            "{w}×{h} needs {} bytes of samples, file has {}",
            w * h * 4,
            data.len()
        )));
    }
    let little = scale < 0.0;
    Ok(Grid::from_fn(w, h, |x, y| {
        let offset = ((h - 1 - y) * w + x) * 4;
        if little {
            f32_le(data, offset)
        } else {
            f32::from_be_bytes([
                data[offset],
                data[offset + 1],
                data[offset + 2],
                data[offset + 3],
            ])
        }
    }))
}

/// The first `n` whitespace-separated ASCII tokens and the offset just after the single
/// whitespace byte that ends the last one (where binary data starts).
pub(super) fn header_tokens(bytes: &[u8], n: usize) -> Option<(Vec<String>, usize)> {
    let mut tokens = Vec::with_capacity(n);
    let mut i = 0;
    while tokens.len() < n {
        while i < bytes.len() && bytes[i].is_ascii_whitespace() {
            i += 1;
        }
        let start = i;
        while i < bytes.len() && !bytes[i].is_ascii_whitespace() {
            i += 1;
        }
        if start == i || i >= bytes.len() || i - start > 32 {
            return None;
        }
        tokens.push(String::from_utf8_lossy(&bytes[start..i]).into_owned());
    }
    Some((tokens, i + 1))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_keeps_values_nan_and_row_order() {
        let map = Grid::from_fn(5, 3, |x, y| {
            if x == 2 && y == 1 {
                f32::NAN
            } else {
                (x * 10 + y) as f32 + 0.25
            }
        });
        let back = decode(&encode(&map)).unwrap();
        assert_eq!(back.size(), (5, 3));
        assert!(back.get(2, 1).is_nan());
        assert_eq!(*back.get(4, 0), 40.25);
        assert_eq!(*back.get(0, 2), 2.25);
        // Row 0 of the grid is stored last (bottom-to-top).
        let bytes = encode(&map);
        let last = f32::from_le_bytes(bytes[bytes.len() - 4..].try_into().unwrap());
        assert_eq!(last, 40.25);
    }

    #[test]
    fn big_endian_files_are_read() {
        let mut bytes = b"Pf\n2 1\n1.0\n".to_vec();
        bytes.extend_from_slice(&1.5f32.to_be_bytes());
        bytes.extend_from_slice(&(-2.0f32).to_be_bytes());
        let map = decode(&bytes).unwrap();
        assert_eq!(map.data(), &[1.5, -2.0]);
    }

    #[test]
    fn malformed_files_are_errors() {
        assert!(decode(b"").is_err());
        assert!(decode(b"P6\n2 2\n255\n").is_err());
        assert!(decode(b"PF\n2 2\n-1\nxxxxxxxx").is_err());
        assert!(decode(b"Pf\n2 2\n-1\n\0\0\0\0").is_err());
        assert!(decode(b"Pf\n-2 2\n-1\n").is_err());
        assert!(decode(b"Pf\n2 2\n0\n").is_err());
    }
}
