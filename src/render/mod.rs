//! The 3D point-cloud viewer: draws a cloud seen in two frames (X and X' per point), lets the
//! user orbit, pan and zoom, toggles between the frames or morphs from one to the other, and
//! colours points by photo colour, depth or superpixel. It knows nothing of the reconstruction:
//! it takes plain buffers ([`cloud::PointCloud`]).
//!
//! - [`camera`]: orbit camera, projection, home view through camera 1 (pure maths)
//! - [`controls`]: pointer, touch and wheel gestures → camera moves
//! - [`decimate`]: deterministic decimation to a point budget
//! - [`colour`]: colour modes (RGB, depth colour map, superpixel id)
//! - [`view`]: the viewer's state and what the GPU draws from it (packed buffers, uniforms)
//! - `gpu` (wasm only, feature `viewer`): wgpu on WebGPU or WebGL2, instanced screen-space quads
//!   (`points.wgsl`), read-back for screenshots
//!
//! The JavaScript API is `crate::web::viewer` (wasm only).

pub mod camera;
pub mod cloud;
pub mod colour;
pub mod controls;
pub mod decimate;
#[cfg(all(target_arch = "wasm32", feature = "viewer"))]
pub mod gpu;
pub mod view;
