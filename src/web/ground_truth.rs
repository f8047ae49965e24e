//! Scoring the page's reconstruction against ground truth the user gives (frame-1 depth as PFM,
//! Sintel `.dpt` or 16-bit PNG with a scale; optionally flow 1→2 as `.flo`), with the metrics of
//! `soup eval` ([`crate::eval::depth_metrics`]: MRE, AbsRel, δ<1.25 after median scale
//! alignment) and [`crate::eval::flow_metrics`] (EPE). Both score what the downloads hold: depth
//! and flow at the photos' own size.
//!
//! ```js
//! const score = JSON.parse(result.scoreDepth('depth.pfm', bytes));   // or (name, bytes, pngScale)
//! score.metrics.mre;                          // also abs_rel, delta_125, coverage, scale, pixels
//! const rgba = result.errorPicture();         // relative error per pixel, result.width × height
//! const flow = JSON.parse(result.scoreFlow('flow.flo', bytes));   // { file, metrics: { epe } }
//! result.report();                            // now has "ground_truth": { depth, flow }
//! ```
//! Errors are `Error`s named as in [`super::reconstruct`] (`FormatError`, `SizeMismatchError`,
//! `InvalidParameterError`) with a readable message; a failed score leaves the earlier ones.

use serde::Serialize;
use wasm_bindgen::prelude::*;

use super::reconstruct::{PageReconstruction, js_error};
use super::rgba;
use crate::colormap::{RELATIVE_ERROR_MAX, relative_error_legend, relative_error_picture};
use crate::error::{Error, Result};
use crate::eval::{DepthMetrics, FlowMetrics, depth_metrics, flow_metrics, relative_errors};
use crate::flow::resize_flow;
use crate::formats::{decode_depth, flo};
use crate::grid::Grid;
use crate::image::Frame;

/// The scores of the current reconstruction, added to its report as `ground_truth`.
#[derive(Clone, Debug, Default, Serialize)]
pub struct GroundTruthScores {
    #[serde(skip_serializing_if = "Option::is_none")]
    pub depth: Option<Scored<DepthMetrics>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub flow: Option<Scored<FlowMetrics>>,
    /// The relative-error picture of the depth score, at the working resolution.
    #[serde(skip)]
    pub picture: Option<Frame>,
}

/// Metrics with the name of the ground-truth file they come from.
#[derive(Clone, Debug, Serialize)]
pub struct Scored<M> {
    pub file: String,
    pub metrics: M,
}

impl GroundTruthScores {
    /// True when nothing has been scored.
    pub fn is_empty(&self) -> bool {
        self.depth.is_none() && self.flow.is_none()
    }
}

/// What `scoreDepth` returns (as JSON).
#[derive(Serialize)]
struct DepthAnswer<'a> {
    file: &'a str,
    metrics: &'a DepthMetrics,
    /// The key of `errorPicture`: colours and the relative error each stands for.
    legend: Legend,
}

#[derive(Serialize)]
struct Legend {
    colours: Vec<[u8; 3]>,
    errors: Vec<f32>,
    /// Errors at or above this get the last colour.
    max: f32,
}

/// "`what` is W×H but frame 1 is W×H" when the sizes differ.
fn check_size(what: &str, (w, h): (usize, usize), (iw, ih): (usize, usize)) -> Result<()> {
    if (w, h) == (iw, ih) {
        return Ok(());
    }
    Err(Error::InvalidParameter(format!(
        "the ground-truth {what} is {w}×{h} but frame 1 is {iw}×{ih}: it must be frame 1's, at the photo's own size"
    )))
}

/// Nearest-neighbour resampling of a picture to `width` × `height` (for display only).
fn resample(picture: &Frame, width: usize, height: usize) -> Frame {
    let (w, h) = picture.size();
    Grid::from_fn(width, height, |x, y| {
        *picture.get(
            (x * w / width.max(1)).min(w - 1),
            (y * h / height.max(1)).min(h - 1),
        )
    })
}

impl PageReconstruction {
    fn score_depth_inner(
        &mut self,
        file_name: &str,
        bytes: &[u8],
        png_scale: Option<f64>,
    ) -> Result<String> {
        let gt = decode_depth(bytes, png_scale)?;
        check_size("depth", gt.size(), self.rec.report.input_size)?;
        let est = self.depth_at_input();
        let metrics = depth_metrics(&gt, &est)?;
        let errors = relative_errors(&gt, &est, metrics.scale)?;
        drop(est);
        let (w, h) = self.rec.frame1.size();
        let picture = resample(&relative_error_picture(&errors), w, h);
        let (colours, errors) = relative_error_legend(64);
        let answer = serde_json::to_string(&DepthAnswer {
            file: file_name,
            metrics: &metrics,
            legend: Legend {
                colours,
                errors,
                max: RELATIVE_ERROR_MAX,
            },
        })
        .map_err(|e| Error::format("JSON", e.to_string()))?;
        self.ground_truth.depth = Some(Scored {
            file: file_name.to_string(),
            metrics,
        });
        self.ground_truth.picture = Some(picture);
        Ok(answer)
    }

    fn score_flow_inner(&mut self, file_name: &str, bytes: &[u8]) -> Result<String> {
        let gt = flo::decode(bytes)?;
        let (iw, ih) = self.rec.report.input_size;
        check_size("flow", gt.size(), (iw, ih))?;
        let metrics = flow_metrics(&gt, &resize_flow(&self.rec.flow, iw, ih))?;
        let scored = Scored {
            file: file_name.to_string(),
            metrics,
        };
        let answer =
            serde_json::to_string(&scored).map_err(|e| Error::format("JSON", e.to_string()))?;
        self.ground_truth.flow = Some(scored);
        Ok(answer)
    }
}

#[wasm_bindgen]
impl PageReconstruction {
    /// Scores frame 1's depth (at the photo's size, as `depth.pfm`) against a ground-truth depth
    /// file: PFM, Sintel `.dpt`, or a 16-bit PNG with z = value × `pngScale` (or its own
    /// `depth_scale` text chunk). Returns JSON `{ file, metrics: { mre, abs_rel, delta_125,
    /// coverage, scale, pixels }, legend: { colours, errors, max } }`; `errorPicture` then has
    /// the per-pixel relative error.
    #[wasm_bindgen(js_name = scoreDepth)]
    pub fn score_depth(
        &mut self,
        file_name: &str,
        bytes: &[u8],
        png_scale: Option<f64>,
    ) -> Result<String, JsValue> {
        self.score_depth_inner(file_name, bytes, png_scale)
            .map_err(js_error)
    }

    /// Scores the flow 1→2 (at the photos' size, as `flow.flo`) against a ground-truth `.flo`.
    /// Returns JSON `{ file, metrics: { epe, outliers, over_3px, coverage, pixels } }`.
    #[wasm_bindgen(js_name = scoreFlow)]
    pub fn score_flow(&mut self, file_name: &str, bytes: &[u8]) -> Result<String, JsValue> {
        self.score_flow_inner(file_name, bytes).map_err(js_error)
    }

    /// The relative depth error of the last depth score per pixel, as RGBA at the working
    /// resolution (Turbo: dark blue exact, dark red ≥ 50 %, black unknown).
    #[wasm_bindgen(js_name = errorPicture)]
    pub fn error_picture(&self) -> Result<Vec<u8>, JsError> {
        self.ground_truth
            .picture
            .as_ref()
            .map(rgba)
            .ok_or_else(|| JsError::new("no ground-truth depth has been scored"))
    }

    /// Forgets the ground-truth scores (the report no longer has them).
    #[wasm_bindgen(js_name = clearGroundTruth)]
    pub fn clear_ground_truth(&mut self) {
        self.ground_truth = GroundTruthScores::default();
    }
}
