//! The 3D point-cloud viewer: draws a cloud seen in two frames (X and X' per point), lets the
//! user orbit, pan and zoom, toggles between the frames or morphs from one to the other, and
//! colours points by photo colour, depth or superpixel. It knows nothing of the reconstruction:
//! it takes plain buffers ([`cloud::PointCloud`]), and it owns its errors ([`RenderError`]).
//!
//! - [`camera`]: orbit camera, projection, home view through camera 1 (pure maths)
//! - [`controls`]: pointer, touch and wheel gestures → camera moves
//! - [`decimate`]: deterministic decimation to a point budget
//! - [`colour`]: colour modes (RGB, depth colour map, superpixel id)
//! - [`view`]: the viewer's state and what the GPU draws from it (packed buffers, uniforms)
//! - `gpu` (wasm only, feature `viewer`): wgpu on WebGPU or WebGL2; each point is one
//!   screen-space triangle whose vertices fetch the point from textures in a single
//!   non-instanced draw (`points.wgsl`, the measurements behind this in `gpu/points.rs`), and
//!   read-back for screenshots
//!
//! Everything but `gpu` is plain Rust, tested natively. The JavaScript API is
//! `crate::web::viewer` (wasm only).

pub mod camera;
pub mod cloud;
pub mod colour;
pub mod controls;
pub mod decimate;
#[cfg(all(target_arch = "wasm32", feature = "viewer"))]
pub mod gpu;
pub mod view;

/// What can go wrong in the viewer.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// A setting or buffer handed to the viewer is out of its valid range or malformed.
    #[error("invalid parameter: {0}")]
    InvalidParameter(String),
    /// The browser's graphics (WebGPU / WebGL2) cannot do what the 3D view needs; the message
    /// says what was tried.
    #[error("{0}")]
    Graphics(String),
}

/// Shorthand for results with the viewer's [`RenderError`].
pub type Result<T, E = RenderError> = std::result::Result<T, E>;
