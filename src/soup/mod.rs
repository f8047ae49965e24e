//! The superpixel soup (the paper's sections 3–5): every superpixel becomes a planar patch with
//! a rigid motion, first at unit translation ([`init`]: the "unorganised" soup), then with a
//! relative scale λ per superpixel solved from contacts between touching pieces ([`scales`]: the
//! "organised" soup), then with planes, motions and scales refined together by particle belief
//! propagation with TRW-S ([`refine`]), and last with each piece moved to the median scale of
//! several reconstructions from nearby superpixel counts ([`ensemble`]).
//!
//! Conventions (docs/ARCHITECTURE.md): camera 1 is the world frame (x right, y down, z forward).
//! A piece's plane is mᵀX = 1, so a pixel with normalised ray x̄ = K⁻¹[u, v, 1]ᵀ has unit-scale
//! depth z = 1 / (mᵀx̄). Its motion is X' = R X + λ t̂; scaling a piece by λ scales its depths by
//! λ and its plane vector m by 1/λ, so the homography K (R + t̂ mᵀ) K⁻¹ is unchanged.

pub mod ensemble;
pub mod ground;
pub mod init;
pub mod plane;
pub mod refine;
pub mod scales;

use nalgebra::{Matrix3, Vector3};
use serde::Serialize;

/// Why a piece has no plane of its own (it then borrows one from a neighbour).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Degeneracy {
    /// Too few pixels with reliable flow.
    TooFewPixels,
    /// The correspondences do not constrain the plane (no parallax: near the epipole, far away).
    NoParallax,
    /// The best plane puts the patch behind a camera.
    NegativeDepth,
}

/// One superpixel of the soup.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Piece {
    /// Rotation of the piece's motion X' = R X + λ t̂.
    pub r: Matrix3<f64>,
    /// Unit translation direction t̂.
    pub t_hat: Vector3<f64>,
    /// Plane mᵀX = 1 at unit scale (λ = 1).
    pub m: Vector3<f64>,
    /// Relative scale λ (Σλ = 1 over the soup once solved).
    pub lambda: f64,
    /// Index of the motion hypothesis the piece uses.
    pub hypothesis: usize,
    /// Set when the plane could not be estimated from the piece's own pixels.
    pub degenerate: Option<Degeneracy>,
}

impl Piece {
    /// Depth of the pixel with normalised ray `ray` on this piece, at the piece's scale λ.
    /// NaN when the plane puts it behind the camera or at infinity.
    pub fn depth(&self, ray: &Vector3<f64>) -> f64 {
        let inv = self.m.dot(ray);
        if inv > 0.0 {
            self.lambda / inv
        } else {
            f64::NAN
        }
    }

    /// The unit-scale 3D point on the plane along `ray` (camera-1 frame).
    pub fn unit_point(&self, ray: &Vector3<f64>) -> Vector3<f64> {
        ray / self.m.dot(ray)
    }
}

/// The soup: one piece per superpixel, plus the motion hypotheses they chose from.
#[derive(Clone, Debug)]
pub struct Soup {
    pub pieces: Vec<Piece>,
    /// Distinct motions (R, t̂) found; `pieces[i].hypothesis` indexes this list.
    pub hypotheses: Vec<crate::geometry::essential::Motion>,
    /// The flow's noise as the soup sees it (px): the median over superpixels of the mean
    /// transfer error of their motion with their best plane.
    pub noise_px: f64,
    /// The strongest rival of the camera's motion (hypothesis 0) that the unit-scale soup
    /// found (`None` when there was none, or for soups not made by it).
    pub ego_rival: Option<init::EgoRival>,
    /// Superpixels the unit-scale soup gave the camera's motion because their own hypothesis
    /// made their surface rugged (`init.rugged_ratio`: a rigid motion fitted to part of a
    /// bending body); 0 for soups not made by it.
    pub rugged_to_ego: usize,
}
