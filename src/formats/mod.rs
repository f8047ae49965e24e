//! Reading and writing the files the product exchanges with other tools: PFM depth, Middlebury
//! `.flo` flow, PLY point clouds, 16-bit PNG (depth and labels), and the evaluation case layout.

pub mod case;
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

/// Reads a little-endian f32 at `offset` (caller checks bounds).
fn f32_le(bytes: &[u8], offset: usize) -> f32 {
    f32::from_le_bytes([
        bytes[offset],
        bytes[offset + 1],
        bytes[offset + 2],
        bytes[offset + 3],
    ])
}
