//! The reconstruction for the page's Web Worker: [`crate::reconstruct`] (the API the CLI calls)
//! on two RGBA frames the browser decoded, with the options of the page's form as JSON; the
//! result stays in wasm memory and hands out typed arrays, pictures, the report and the export
//! files on request.
//!
//! ```js
//! const defaults = JSON.parse(pageDefaults());            // options, stages, presets, exports
//! const exif = JSON.parse(readExif(fileBytes));           // { focal35mm?, warning? }
//! const camera = JSON.parse(resolveIntrinsics(w, h, exif.focal35mm)); // shown in the form
//! const options = { ...defaults.options, exif1: exif };
//! const one = new FrameBuilder(w1, h1);                   // frame 1, filled strip by strip
//! one.pushRows(ctx.getImageData(0, y, w1, rows).data);    // … until all rows are in
//! const result = reconstruct(one, two, JSON.stringify(options),
//!                            (stage, fraction) => { ... });   // throws an Error named below
//! const cloud = result.cloud('organised');                // positions1/2, colours, labels
//! const depth = result.picture('depth');                  // RGBA, result.width × result.height
//! const ply = result.exportFile('frame1.ply');            // bytes of a download
//! ```
//!
//! Thrown errors are `Error`s whose `name` says what went wrong (`SizeMismatchError`,
//! `TooSmallError`, `NoParallaxError`, `InvalidParameterError`, `DecodeError`, `FormatError`)
//! and whose message is the library's readable one.

use std::borrow::Cow;

use js_sys::Function;
use serde::{Deserialize, Serialize};
use wasm_bindgen::prelude::*;
use wasm_bindgen_futures::JsFuture;

use super::ground_truth::GroundTruthScores;
use super::rgba;
use crate::camera::{Intrinsics, resolve_intrinsics};
use crate::colormap::{depth_legend, depth_picture, inverse_depth_range};
use crate::error::Error;
use crate::export::{self, ExportFile};
use crate::flow::colour::flow_picture_with_reliability;
use crate::flow::{FlowField, FlowParams, Preset, compute_direction};
use crate::formats::ply::Encoding;
use crate::image::{ExifInfo, Frame, LoadedImage, frame_from_rgba, read_exif_info, resize};
use crate::input::{DEFAULT_MAX_SIDE, FramePair, MIN_SIDE, prepare_pair};
use crate::output::{cloud_labels, confidence_picture, dense_depth, depth_at, point_clouds};
use crate::pipeline::{Directions, FlowInput, Params, ProgressSpan, Reconstruction, Stage};
use crate::superpixels::view::boundary_overlay;

/// What the page asks for besides the pixels, as JSON with camelCase keys (`params` keeps the
/// library's snake_case). Missing keys take the defaults of [`pageDefaults`](page_defaults).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase", default, deny_unknown_fields)]
pub struct RunOptions {
    /// Every tunable of the pipeline.
    pub params: Params,
    /// Bound on the long side of the working resolution, in pixels.
    pub max_side: usize,
    /// Preset of the computed flow: `"fast"`, `"medium"`, `"fine"` or `"high"`.
    pub flow_preset: Preset,
    /// The user's intrinsics in pixels of the input images; `null` takes frame 1's EXIF focal
    /// length, else the default guess.
    pub intrinsics: Option<Intrinsics>,
    /// What frame 1's EXIF block said (from [`readExif`](read_exif)).
    pub exif1: ExifInfo,
    /// What frame 2's EXIF block said.
    pub exif2: ExifInfo,
    /// When the frames differ in size, resize frame 2 to frame 1's size instead of failing.
    pub resize_second: bool,
    /// The photos' own sizes `[[w1, h1], [w2, h2]]` when the page decoded them straight to the
    /// working size (to save memory): the size check, the user's intrinsics (in the photos'
    /// pixels) and the outputs at the input size (depth, flow) follow these; `null` when the
    /// frames are the photos as they are.
    pub photo_sizes: Option<[[usize; 2]; 2]>,
}

/// The page's flow preset: `fine`, not the library's default `high`. Both compute the flow at
/// full resolution, and fine's depth is as accurate as high's (five-seed means with the page's
/// settings within 0.004 of the command line's on every evaluation case, docs/RESULTS.md stop
/// 58) in two thirds of the flow's time. Against `medium` (half resolution) fine halves the depth
/// error on static-room, the street, the creature and the table, and only with it does
/// static-room meet its 0.015 target in the page's settings. Its price (`node
/// benches/page.mjs`, stop 59, against medium in alternated runs) is small since the flow's two
/// directions are computed at once in two workers (`www/worker.js`) and the recompute of a shown
/// result is handed its flow (`www/pipeline.js`): a 12 MP photo pair's peak tab memory 373–374
/// → 385–387 MiB (budget 400) and its end to end time 4.7–5.2 → 5.0–5.1 s; a 1024 × 436 pair
/// 3.1 s either way.
/// A run whose first pass pins too few scales, leaves the camera's motion ambiguous or finds no
/// ground makes a second pass with `high` ([`Params::min_pinned_share`],
/// [`Params::finer_without_ground`]): an answer worse than a constant depth costs more than the
/// memory and time, which that pass then takes.
pub const PAGE_FLOW_PRESET: Preset = Preset::Fine;

/// The page's refinement of the kept reconstruction: the members' (2 iterations, 8 particles,
/// [`crate::soup::ensemble::EnsembleParams`]) instead of the library's 6 and 16. With five
/// members fused the end to end time at 1024 × 436 was 4.01 s with the library's (the
/// refinement 0.92 s of it in wasm), above the page's 4 s; with the members' settings the
/// mean depth errors over 1300–1700 superpixels (preset high) moved by at most 0.004
/// (FlyingThings3D 0.338 → 0.342, street 0.023 → 0.025, the rest within 0.002). The
/// parameters panel starts from these; the library's 6 and 16 can be typed in there.
pub fn page_params() -> Params {
    Params::default().with_member_refinement()
}

impl Default for RunOptions {
    fn default() -> Self {
        RunOptions {
            params: page_params(),
            max_side: DEFAULT_MAX_SIDE,
            flow_preset: PAGE_FLOW_PRESET,
            intrinsics: None,
            exif1: ExifInfo::default(),
            exif2: ExifInfo::default(),
            resize_second: false,
            photo_sizes: None,
        }
    }
}

/// What the page needs to know before a run.
#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
struct PageDefaults {
    options: RunOptions,
    /// Stage names in the order they run (the progress callback's first argument).
    stages: Vec<&'static str>,
    flow_presets: Vec<&'static str>,
    /// File names [`PageReconstruction::export_file`] accepts.
    exports: Vec<&'static str>,
    /// The smallest side, in pixels, of images the pipeline accepts.
    min_side: usize,
}

/// JSON: `{ options, stages, flowPresets, exports, minSide }`; `options` are the default
/// [`RunOptions`].
#[wasm_bindgen(js_name = pageDefaults)]
pub fn page_defaults() -> Result<String, JsError> {
    let defaults = PageDefaults {
        options: RunOptions::default(),
        stages: Stage::ALL.iter().map(|s| s.name()).collect(),
        flow_presets: Preset::ALL.iter().map(|p| p.name()).collect(),
        exports: ExportFile::ALL.iter().map(|f| f.file_name()).collect(),
        min_side: MIN_SIDE,
    };
    Ok(serde_json::to_string(&defaults)?)
}

/// The EXIF facts of image file bytes without decoding the pixels, as JSON
/// `{ "focal35mm": number | null, "warning": string | null }`. Never throws.
#[wasm_bindgen(js_name = readExif)]
pub fn read_exif(bytes: &[u8]) -> Result<String, JsError> {
    Ok(serde_json::to_string(&read_exif_info(bytes))?)
}

/// The intrinsics a `width × height` photo gets without the user's (from its EXIF 35 mm focal
/// length when given, else the default guess), as JSON
/// `{ "intrinsics": { fx, fy, cx, cy }, "source": "exif" | "default" }`.
#[wasm_bindgen(js_name = resolveIntrinsics)]
pub fn resolve_intrinsics_json(
    width: u32,
    height: u32,
    focal_35mm: Option<f64>,
) -> Result<String, JsError> {
    let camera = resolve_intrinsics(None, focal_35mm, width as usize, height as usize);
    Ok(serde_json::to_string(&camera)?)
}

/// A frame filled from JavaScript with RGBA rows a strip at a time (e.g. from
/// `getImageData` of a few rows), so that a large photo never sits in memory whole as RGBA.
#[wasm_bindgen]
pub struct FrameBuilder {
    width: usize,
    height: usize,
    pixels: Vec<[u8; 3]>,
}

#[wasm_bindgen]
impl FrameBuilder {
    /// An empty `width × height` frame.
    #[wasm_bindgen(constructor)]
    pub fn new(width: u32, height: u32) -> FrameBuilder {
        let (width, height) = (width as usize, height as usize);
        FrameBuilder {
            width,
            height,
            pixels: Vec::with_capacity(width.saturating_mul(height)),
        }
    }

    /// Appends whole rows given as RGBA bytes, top to bottom (alpha is ignored). Throws when
    /// the bytes are not whole rows or the frame would get too many rows.
    #[wasm_bindgen(js_name = pushRows)]
    pub fn push_rows(&mut self, rgba: &[u8]) -> Result<(), JsValue> {
        let rows = rgba.len() / (4 * self.width).max(1);
        let strip = frame_from_rgba(rgba, self.width, rows).map_err(js_error)?;
        if self.rows() + rows > self.height {
            return Err(js_error(Error::InvalidParameter(format!(
                "a frame of {}×{} pixels got {} rows",
                self.width,
                self.height,
                self.rows() + rows
            ))));
        }
        self.pixels.extend_from_slice(strip.data());
        Ok(())
    }

    /// Rows received so far.
    fn rows(&self) -> usize {
        self.pixels.len() / self.width.max(1)
    }

    /// The complete frame; fails when rows are missing.
    fn finish(self) -> crate::Result<Frame> {
        if self.rows() != self.height {
            return Err(Error::InvalidParameter(format!(
                "a frame of {}×{} pixels got only {} rows",
                self.width,
                self.height,
                self.rows()
            )));
        }
        crate::Grid::from_vec(self.width, self.height, self.pixels)
    }
}

/// Reconstructs both frames: frame 1 (the reference) and frame 2 (consumed), `options` as
/// JSON [`RunOptions`]. `progress(stage, fraction)`, when given, is called as stages start and
/// finish (fraction in [0, 1] within the stage). Throws an `Error` named after the problem
/// (module docs) with a readable message. The flow and the fusion's members are computed here,
/// one after the other; [`reconstruct_unfused`] leaves them to other workers.
#[wasm_bindgen]
pub fn reconstruct(
    frame1: FrameBuilder,
    frame2: FrameBuilder,
    options: &str,
    progress: Option<Function>,
) -> Result<PageReconstruction, JsValue> {
    let options = parse_options(options)?;
    let (pair, photo_size) = prepared_pair(frame1, frame2, &options)?;
    let flow = FlowInput::Compute(FlowParams::preset(options.flow_preset));
    let mut report = progress_callback(progress);
    let rec = crate::pipeline::reconstruct(&pair, flow, &options.params, &mut report)
        .map_err(js_error)?;
    let mut result = PageReconstruction::unfused(rec, photo_size);
    result.finish();
    Ok(result)
}

/// [`reconstruct`] without the fusion, its flows' directions computed elsewhere where
/// `directions` gives them: the result is not finished until the members' votes are given to
/// it and it is fused ([`super::members`]: `memberInputs`, `addVote`, `addFailure`, `fuse`);
/// until then its clouds, pictures and files are those before the fusion. Resolves to the
/// result; rejects as `reconstruct` throws.
///
/// `directions(preset, stage, from, to)`, when given, is asked for each flow the run computes
/// (its preset's name: the first pass's, and a finer one's where a pass asks for one; where it
/// computes them, their progress is `progress(stage, fraction)` with the fraction going from
/// `from` to `to`) and returns a promise of `{ forward, backward, ms }`, the flow's two
/// directions as [`flow_direction`] gives them (frame 1 → 2 and 2 → 1 of these frames and these
/// options with that preset, `u, v` pairs row by row at the working size) and, where they were
/// computed before this run, the milliseconds that took (added to the report's flow time), or
/// of `null`: then they are computed here. The page's worker computes one direction in a helper
/// worker while it computes the other, or gives directions it holds (www/worker.js); the result
/// is the same bits. A `directions` that throws or rejects counts as `null`. It may call into
/// this module, before it returns (the worker computes its direction then) and while its
/// promise is pending: no object of the module is borrowed across the call.
#[wasm_bindgen(js_name = reconstructUnfused)]
pub async fn reconstruct_unfused(
    frame1: FrameBuilder,
    frame2: FrameBuilder,
    options: String,
    progress: Option<Function>,
    directions: Option<Function>,
) -> Result<PageReconstruction, JsValue> {
    let options = parse_options(&options)?;
    let (pair, photo_size) = prepared_pair(frame1, frame2, &options)?;
    let flow = FlowInput::Compute(FlowParams::preset(options.flow_preset));
    let mut report = progress_callback(progress);
    let mut source = PageDirections {
        request: directions,
        size: pair.frame1.size(),
        earlier_ms: 0.0,
    };
    let mut rec = crate::pipeline::reconstruct_unfused_from(
        &pair,
        flow,
        &options.params,
        &mut source,
        &mut report,
    )
    .await
    .map_err(js_error)?;
    let timings = &mut rec.report.timings_ms;
    if let Some((_, flow_ms)) = timings.iter_mut().find(|(stage, _)| *stage == Stage::Flow) {
        *flow_ms += source.earlier_ms;
    }
    Ok(PageReconstruction::unfused(rec, photo_size))
}

/// The flows' directions as the page's worker gives them ([`reconstruct_unfused`]'s
/// `directions`).
struct PageDirections {
    /// `directions(preset, stage, from, to)`, a JavaScript function returning a promise.
    request: Option<Function>,
    /// The working size, which the directions must have.
    size: (usize, usize),
    /// The milliseconds that the directions given computed before this run took (their `ms`).
    earlier_ms: f64,
}

impl Directions for PageDirections {
    async fn directions(
        &mut self,
        params: &FlowParams,
        span: ProgressSpan,
    ) -> crate::Result<Option<(FlowField, FlowField)>> {
        let (Some(request), Some(preset)) = (&self.request, params.named_preset()) else {
            return Ok(None);
        };
        let arguments = js_sys::Array::new();
        arguments.push(&JsValue::from_str(preset.name()));
        arguments.push(&JsValue::from_str(span.stage.name()));
        arguments.push(&JsValue::from_f64(span.at(0.0).into()));
        arguments.push(&JsValue::from_f64(span.at(1.0).into()));
        let Ok(promise) = request.apply(&JsValue::NULL, &arguments) else {
            return Ok(None);
        };
        let Ok(given) = JsFuture::from(js_sys::Promise::resolve(&promise)).await else {
            return Ok(None);
        };
        if given.is_null() || given.is_undefined() {
            return Ok(None);
        }
        let (w, h) = self.size;
        // Copied straight into the field (one allocation, not a list of numbers then a field).
        let field = |key: &str| {
            let array = (js_sys::Reflect::get(&given, &JsValue::from_str(key)).ok())
                .and_then(|v| v.dyn_into::<js_sys::Float32Array>().ok())
                .ok_or_else(|| {
                    Error::InvalidParameter(format!("the given flow has no {key} direction"))
                })?;
            if array.length() as usize != 2 * w * h {
                return Err(Error::InvalidParameter(format!(
                    "a flow direction of {} numbers for {w}×{h} frames",
                    array.length()
                )));
            }
            let mut vectors = vec![[0.0f32; 2]; w * h];
            array.copy_to(vectors.as_flattened_mut());
            FlowField::from_vec(w, h, vectors)
        };
        let directions = (field("forward")?, field("backward")?);
        let ms = js_sys::Reflect::get(&given, &JsValue::from_str("ms")).ok();
        self.earlier_ms += ms.and_then(|ms| ms.as_f64()).unwrap_or(0.0);
        Ok(Some(directions))
    }
}

/// One direction of the flow [`reconstruct_unfused`] computes first for these frames and
/// options (frame 1 → 2, or 2 → 1 when `backward`; a finer pass's flow with the options' flow
/// preset set to its preset), as `u, v` pairs row by row at the working size: the page's
/// worker computes one while a helper computes the other, and gives both to
/// `reconstructUnfused` (the same result bit for bit). `progress(fraction)`, when given, is
/// called as the work goes. Throws as `reconstructUnfused` does.
#[wasm_bindgen(js_name = flowDirection)]
pub fn flow_direction(
    frame1: FrameBuilder,
    frame2: FrameBuilder,
    options: &str,
    backward: bool,
    progress: Option<Function>,
) -> Result<Vec<f32>, JsValue> {
    let options = parse_options(options)?;
    let (pair, _) = prepared_pair(frame1, frame2, &options)?;
    let (from, to) = if backward {
        (&pair.frame2, &pair.frame1)
    } else {
        (&pair.frame1, &pair.frame2)
    };
    let params = FlowParams::preset(options.flow_preset);
    let mut report = super::fraction_callback(progress);
    let flow = compute_direction(from, to, &params, &mut report).map_err(js_error)?;
    Ok(super::flow::interleaved(&flow))
}

/// The run's options from their JSON ([`RunOptions`]), their parameters checked
/// ([`Params::validate`]).
pub(super) fn parse_options(options: &str) -> Result<RunOptions, JsValue> {
    let options: RunOptions = serde_json::from_str(options)
        .map_err(|e| js_error(Error::InvalidParameter(format!("options: {e}"))))?;
    options.params.validate().map_err(js_error)?;
    Ok(options)
}

/// The frames as the pipeline takes them (at the working size, the camera resolved) and the
/// photos' own size where the page decoded them smaller.
fn prepared_pair(
    frame1: FrameBuilder,
    frame2: FrameBuilder,
    options: &RunOptions,
) -> Result<(FramePair, Option<(usize, usize)>), JsValue> {
    let frame1 = frame1.finish().map_err(js_error)?;
    let mut frame2 = frame2.finish().map_err(js_error)?;
    let mut intrinsics = options.intrinsics;
    let mut photo_size = None;
    if let Some([[w1, h1], [w2, h2]]) = options.photo_sizes {
        if (w1, h1) != (w2, h2) && !options.resize_second {
            return Err(js_error(Error::SizeMismatch { w1, h1, w2, h2 }));
        }
        if w1 == 0 || h1 == 0 {
            return Err(js_error(Error::InvalidParameter(
                "photo sizes must be positive".into(),
            )));
        }
        // The user's intrinsics are in the photo's pixels; the frames are smaller.
        let (sx, sy) = (
            frame1.width() as f64 / w1 as f64,
            frame1.height() as f64 / h1 as f64,
        );
        intrinsics = intrinsics.map(|k| k.scaled(sx, sy));
        photo_size = Some((w1, h1));
    }
    if options.resize_second && frame2.size() != frame1.size() {
        frame2 = resize(&frame2, frame1.width(), frame1.height());
    }
    let mut pair = prepare_pair(
        LoadedImage {
            frame: frame1,
            exif: options.exif1.clone(),
        },
        LoadedImage {
            frame: frame2,
            exif: options.exif2.clone(),
        },
        intrinsics,
        options.max_side,
    )
    .map_err(js_error)?;
    let photo_size = photo_size.filter(|&size| size != pair.input_size);
    if let Some((w, h)) = photo_size {
        let (ww, wh) = pair.frame1.size();
        pair.notes.retain(|n| !n.starts_with("downscaled from"));
        pair.notes.push(format!(
            "downscaled from {w}×{h} to {ww}×{wh} (as the page decoded the photos)"
        ));
    }
    Ok((pair, photo_size))
}

/// The pipeline's progress callback calling `progress(stage, fraction)` when given.
fn progress_callback(progress: Option<Function>) -> impl FnMut(Stage, f32) {
    move |stage: Stage, fraction: f32| {
        if let Some(callback) = &progress {
            // A throwing callback must not abort the reconstruction.
            let _ = callback.call2(
                &JsValue::NULL,
                &JsValue::from_str(stage.name()),
                &JsValue::from_f64(fraction.into()),
            );
        }
    }
}

/// A reconstruction kept in wasm memory; the worker takes what the page shows and downloads.
#[wasm_bindgen]
pub struct PageReconstruction {
    pub(super) rec: Reconstruction,
    /// Scores against the user's ground truth ([`super::ground_truth`]), added to the report.
    pub(super) ground_truth: GroundTruthScores,
    /// The photos' own size when the page decoded them to the working size: the report's input
    /// size once the reconstruction is finished ([`Self::finish`]).
    photo_size: Option<(usize, usize)>,
    /// Until fused ([`super::members`]): the members' votes given so far, in the order of their
    /// counts (`Err`: why that member could not be made).
    pub(super) votes: Option<Vec<Result<crate::soup::ensemble::Vote, String>>>,
}

impl PageReconstruction {
    /// A reconstruction not fused yet (its votes to come), from photos of `photo_size` where
    /// the page decoded them smaller.
    fn unfused(rec: Reconstruction, photo_size: Option<(usize, usize)>) -> Self {
        PageReconstruction {
            rec,
            ground_truth: GroundTruthScores::default(),
            photo_size,
            votes: Some(Vec::new()),
        }
    }

    /// After the fusion: the outputs at the input size (depth files, flow.flo, the ground-truth
    /// scores) are at the photo's size, as if the library had downscaled it; the depth at that
    /// size is made when asked for (a 12-megapixel depth map is 48 MB of wasm memory the run
    /// itself does not need).
    pub(super) fn finish(&mut self) {
        if let Some(size) = self.photo_size {
            self.rec.report.input_size = size;
        }
        self.votes = None;
    }

    /// Frame-1 depth at the input size (the photo's): the reconstruction's own, or, when the page
    /// decoded the photos at the working size, the soup's depth rendered at the photo's size
    /// with the intrinsics scaled to it.
    pub(super) fn depth_at_input(&self) -> Cow<'_, crate::Grid<f32>> {
        let rec = &self.rec;
        let (iw, ih) = rec.report.input_size;
        if rec.depth_input.size() == (iw, ih) {
            return Cow::Borrowed(&rec.depth_input);
        }
        let (w, h) = self.rec.frame1.size();
        let k = rec
            .report
            .camera
            .intrinsics
            .scaled(iw as f64 / w as f64, ih as f64 / h as f64);
        Cow::Owned(depth_at(&rec.soup, &rec.superpixels.labels, iw, ih, &k))
    }

    /// `report.json`: the library's report, with the ground-truth scores when there are any.
    fn report_bytes(&self) -> crate::Result<Vec<u8>> {
        let bytes = export::report_json(&self.rec)?;
        if self.ground_truth.is_empty() {
            return Ok(bytes);
        }
        let json = |e: serde_json::Error| Error::format("JSON", e.to_string());
        let mut report: serde_json::Value = serde_json::from_slice(&bytes).map_err(json)?;
        if let Some(object) = report.as_object_mut() {
            object.insert(
                "ground_truth".into(),
                serde_json::to_value(&self.ground_truth).map_err(json)?,
            );
        }
        serde_json::to_vec_pretty(&report).map_err(json)
    }

    /// The soup of a stage: `"unorganised"` (every superpixel at λ = 1, before the scale solve)
    /// or `"scaled"` (after the scale solve, before the refinement); `None` for another name.
    fn stage_soup(&self, name: &str) -> Option<&crate::soup::Soup> {
        match name {
            "unorganised" => Some(&self.rec.unit_soup),
            "scaled" => Some(&self.rec.scaled_soup),
            _ => None,
        }
    }

    /// Frame-1 depth of `soup` at the working resolution.
    fn depth_of(&self, soup: &crate::soup::Soup) -> crate::Grid<f32> {
        let rec = &self.rec;
        dense_depth(soup, &rec.superpixels.labels, &rec.report.camera.intrinsics)
    }
}

#[wasm_bindgen]
impl PageReconstruction {
    /// Width of the working resolution, in pixels (the pictures' width).
    #[wasm_bindgen(getter)]
    pub fn width(&self) -> u32 {
        self.rec.frame1.width() as u32
    }

    /// Height of the working resolution, in pixels.
    #[wasm_bindgen(getter)]
    pub fn height(&self) -> u32 {
        self.rec.frame1.height() as u32
    }

    /// The point clouds of both frames, one point per pixel with a depth: `"organised"` (the
    /// result: solved scales, refined), `"scaled"` (after the scale solve, before the
    /// refinement) or `"unorganised"` (every superpixel at unit scale λ = 1, before the scale
    /// solve: the paper's Fig. 5).
    pub fn cloud(&self, soup: &str) -> Result<CloudBuffers, JsError> {
        let labels = &self.rec.superpixels.labels;
        let k = &self.rec.report.camera.intrinsics;
        if soup == "organised" {
            let (c1, c2) = self.rec.clouds();
            return Ok(CloudBuffers::new(
                &c1,
                &c2,
                &cloud_labels(labels, &self.rec.depth),
            ));
        }
        let stage = self.stage_soup(soup).ok_or_else(|| {
            JsError::new(&format!(
                "unknown soup {soup:?}; choose organised, scaled or unorganised"
            ))
        })?;
        let depth = self.depth_of(stage);
        let (c1, c2) = point_clouds(stage, labels, &depth, &self.rec.frame1, k);
        Ok(CloudBuffers::new(&c1, &c2, &cloud_labels(labels, &depth)))
    }

    /// A picture at the working resolution as RGBA bytes (`4 · width · height`, opaque), ready
    /// for `new ImageData(...)`: `"depth"` (frame-1 depth, near warm, far cool, unknown black),
    /// `"unorganised"` (the same for the soup at unit scales, before the scale solve),
    /// `"scaled"` (the same after the scale solve, before the refinement),
    /// `"superpixels"` (frame 1 with superpixel boundaries), `"flow"` (the flow used, Middlebury
    /// colours, untrusted vectors darker), `"confidence"` (frame 1 with the superpixels whose
    /// scale no contact pins tinted magenta: their depth is a guess).
    pub fn picture(&self, name: &str) -> Result<Vec<u8>, JsError> {
        let rec = &self.rec;
        if let Some(stage) = self.stage_soup(name) {
            return Ok(rgba(&depth_picture(&self.depth_of(stage))));
        }
        let frame = match name {
            "depth" => depth_picture(&rec.depth),
            "superpixels" => boundary_overlay(&self.rec.frame1, &rec.superpixels, [255, 230, 0]),
            "flow" => flow_picture_with_reliability(&rec.flow, &rec.reliable),
            "confidence" => confidence_picture(
                &self.rec.frame1,
                &rec.superpixels.labels,
                &rec.report.confidence,
                rec.report.params.scales.min_confidence,
            ),
            other => {
                return Err(JsError::new(&format!(
                    "unknown picture {other:?}; choose depth, unorganised, scaled, superpixels, flow or confidence"
                )));
            }
        };
        Ok(rgba(&frame))
    }

    /// The key of the `"depth"` picture as JSON `{ "colours": [[r, g, b], …], "depths": […] }`,
    /// `steps` colours from near to far (depth in the reconstruction's unit: relative, the
    /// global scale of a monocular reconstruction is unknown); `null` when no depth is known.
    #[wasm_bindgen(js_name = depthLegend)]
    pub fn depth_legend(&self, steps: u32) -> Result<String, JsError> {
        let legend = inverse_depth_range(self.rec.depth.data().iter().copied())
            .map(|range| depth_legend(range, steps as usize));
        #[derive(Serialize)]
        struct Legend<'a> {
            colours: &'a [[u8; 3]],
            depths: &'a [f32],
        }
        let json = legend.as_ref().map(|l| Legend {
            colours: &l.colours,
            depths: &l.depths,
        });
        Ok(serde_json::to_string(&json)?)
    }

    /// The report (intrinsics and their source, sizes, parameters, milliseconds per stage,
    /// counts, energies) as JSON, as `report.json` of the CLI, plus `ground_truth` (the scores
    /// of [`super::ground_truth`]) once the user has scored the result.
    pub fn report(&self) -> Result<String, JsError> {
        Ok(String::from_utf8(self.report_bytes()?)?)
    }

    /// The bytes of an output file by name (`frame1.ply`, `frame2.ply`, `depth16.png`,
    /// `flow.flo`, `report.json`, `depth.pfm`, `depth.png`, `labels.png`), exactly as
    /// `soup reconstruct --out` writes it (binary PLY).
    #[wasm_bindgen(js_name = exportFile)]
    pub fn export_file(&mut self, name: &str) -> Result<Vec<u8>, JsError> {
        let file = ExportFile::from_file_name(name)?;
        if file == ExportFile::Report {
            return Ok(self.report_bytes()?);
        }
        let depth_file = matches!(
            file,
            ExportFile::DepthPfm | ExportFile::DepthPng16 | ExportFile::DepthPicture
        );
        if depth_file && let Cow::Owned(depth) = self.depth_at_input() {
            // Encoded with the photo-size depth in place, then the working-size one back.
            let working = std::mem::replace(&mut self.rec.depth_input, depth);
            let bytes = export::encode(&self.rec, file, Encoding::BinaryLittleEndian);
            self.rec.depth_input = working;
            return Ok(bytes?);
        }
        Ok(export::encode(
            &self.rec,
            file,
            Encoding::BinaryLittleEndian,
        )?)
    }

    /// The media type of an output file by name (for the download's `Blob`).
    #[wasm_bindgen(js_name = exportMediaType)]
    pub fn export_media_type(&self, name: &str) -> Result<String, JsError> {
        Ok(ExportFile::from_file_name(name)?.media_type().to_string())
    }
}

/// A point cloud in both frames as flat arrays for the viewer's `setCloud`. The arrays are
/// JavaScript's own, copied straight from the reconstruction's clouds: the worker's wasm memory
/// never holds a second, interleaved copy (24 MB for a 1024 × 768 reconstruction).
#[wasm_bindgen]
pub struct CloudBuffers {
    positions1: js_sys::Float32Array,
    positions2: js_sys::Float32Array,
    colours: js_sys::Uint8Array,
    labels: js_sys::Uint32Array,
}

impl CloudBuffers {
    fn new(
        cloud1: &crate::output::PointCloud,
        cloud2: &crate::output::PointCloud,
        labels: &[u32],
    ) -> Self {
        CloudBuffers {
            positions1: js_sys::Float32Array::from(cloud1.positions.as_flattened()),
            positions2: js_sys::Float32Array::from(cloud2.positions.as_flattened()),
            colours: js_sys::Uint8Array::from(cloud1.colours.as_flattened()),
            labels: js_sys::Uint32Array::from(labels),
        }
    }
}

#[wasm_bindgen]
impl CloudBuffers {
    /// Number of points.
    #[wasm_bindgen(getter)]
    pub fn count(&self) -> u32 {
        self.labels.length()
    }

    /// `Float32Array`, x, y, z per point in frame 1 (camera 1's frame: x right, y down,
    /// z forward; relative units).
    #[wasm_bindgen(getter)]
    pub fn positions1(&self) -> js_sys::Float32Array {
        self.positions1.clone()
    }

    /// `Float32Array`, the same points in frame 2 (X' = R X + λ t̂), same frame of reference.
    #[wasm_bindgen(getter)]
    pub fn positions2(&self) -> js_sys::Float32Array {
        self.positions2.clone()
    }

    /// `Uint8Array`, r, g, b per point (frame 1's colours).
    #[wasm_bindgen(getter)]
    pub fn colours(&self) -> js_sys::Uint8Array {
        self.colours.clone()
    }

    /// `Uint32Array`, the superpixel of each point.
    #[wasm_bindgen(getter)]
    pub fn labels(&self) -> js_sys::Uint32Array {
        self.labels.clone()
    }
}

/// A JavaScript `Error` carrying the library's message, named after the kind of problem so the
/// page can react (e.g. offer to resize frame 2 on `SizeMismatchError`).
pub(super) fn js_error(error: Error) -> JsValue {
    let name = match &error {
        Error::Io { .. } => "IoError",
        Error::Decode(_) => "DecodeError",
        Error::TooSmall { .. } => "TooSmallError",
        Error::SizeMismatch { .. } => "SizeMismatchError",
        Error::Format { .. } => "FormatError",
        Error::NoParallax(_) => "NoParallaxError",
        Error::InvalidParameter(_) => "InvalidParameterError",
    };
    let js = js_sys::Error::new(&error.to_string());
    js.set_name(name);
    js.into()
}
