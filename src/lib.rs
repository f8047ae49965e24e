//! Superpixel Soup: dense 3D reconstruction of a dynamic scene from two frames
//! (Kumar, Dai, Li, ICCV 2017), for the command line and the browser.
//!
//! Data flows one way through plain functions, one module per stage: frames ([`image`], [`input`],
//! [`camera`]; [`jpeg`] decodes the page's JPEG photos straight to the working size) → flow
//! ([`flow`]) → superpixels and graphs ([`superpixels`]) → unit-scale soup → scaled soup ([`soup`])
//! → outputs ([`output`]); [`pipeline::reconstruct`] runs them all; [`mrf`] holds the discrete
//! solvers the soup uses ([`numeric`]: the maths functions, the same bits on every platform).
//! [`formats`] reads and writes the files, [`export`] encodes a reconstruction's output files,
//! [`eval`] scores results, [`synth`] renders scenes with exact ground truth. At the edge:
//! [`render`], the 3D viewer, and `web` (wasm only), the page's JavaScript API.
//!
//! docs/ARCHITECTURE.md in the repository describes the pipeline, what each module owns and the
//! conventions they share (pixel and camera frames, planes, motion and homography signs, units).

// Results take their transcendental functions from `numeric` (clippy.toml forbids `f64::ln` and
// the like); tests, test-data generation and the viewer make no results.
#![cfg_attr(test, allow(clippy::disallowed_methods))]

pub mod camera;
pub mod colormap;
pub mod error;
pub mod eval;
pub mod export;
pub mod flow;
pub mod focal;
pub mod formats;
pub mod geometry;
pub mod grid;
pub mod image;
pub mod input;
pub mod jpeg;
pub mod mrf;
pub mod numeric;
pub mod output;
pub mod pipeline;
#[allow(clippy::disallowed_methods)]
pub mod render;
pub mod rng;
pub mod soup;
pub mod superpixels;
#[allow(clippy::disallowed_methods)]
pub mod synth;
mod union_find;
#[cfg(target_arch = "wasm32")]
pub mod web;

pub use error::{Error, Result};
pub use grid::Grid;
pub use pipeline::{FlowInput, Params, Reconstruction, Stage, reconstruct};
