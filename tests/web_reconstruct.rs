//! Browser tests of the reconstruction API of the page's worker (`src/web/reconstruct.rs`,
//! `src/web/memory.rs`), run headless in Chromium by ./check.sh through wasm-bindgen-test-runner.
//! They call the exports as the worker does: RGBA frames, options as JSON, errors as named
//! JavaScript `Error`s.
#![cfg(target_arch = "wasm32")]

use std::cell::RefCell;
use std::rc::Rc;

use js_sys::Function;
use superpixel_soup::Params;
use superpixel_soup::eval::depth_metrics;
use superpixel_soup::flow::Preset;
use superpixel_soup::formats::{dpt, flo, pfm, ply};
use superpixel_soup::image::resize;
use superpixel_soup::image::{Frame, encode_png};
use superpixel_soup::input::DEFAULT_MAX_SIDE;
use superpixel_soup::synth::{SceneKind, render};
use superpixel_soup::web::members::MemberSource;
use superpixel_soup::web::memory::failed_allocation;
use superpixel_soup::web::reconstruct::{
    FrameBuilder, PAGE_FLOW_PRESET, PageReconstruction, flow_direction, page_defaults, page_params,
    read_exif, reconstruct, reconstruct_unfused, resolve_intrinsics_json,
};
use wasm_bindgen::closure::Closure;
use wasm_bindgen::{JsCast, JsValue};
use wasm_bindgen_test::{wasm_bindgen_test, wasm_bindgen_test_configure};

wasm_bindgen_test_configure!(run_in_browser);

/// A FrameBuilder filled with `frame`, in strips of up to 7 rows (as the worker fills it).
fn builder(frame: &Frame) -> FrameBuilder {
    let mut builder = FrameBuilder::new(frame.width() as u32, frame.height() as u32);
    let rows: Vec<u8> = frame
        .data()
        .iter()
        .flat_map(|&[r, g, b]| [r, g, b, 255])
        .collect();
    for strip in rows.chunks(7 * 4 * frame.width()) {
        builder.push_rows(strip).unwrap();
    }
    builder
}

/// The options the page sends: the defaults with a few superpixels (a small, quick run).
fn options(changes: &str) -> String {
    let defaults: serde_json::Value = serde_json::from_str(&page_defaults().unwrap()).unwrap();
    let mut options = defaults["options"].clone();
    options["params"]["superpixels"]["count"] = 150.into();
    let changes: serde_json::Value = serde_json::from_str(changes).unwrap();
    for (key, value) in changes.as_object().unwrap() {
        options[key] = value.clone();
    }
    options.to_string()
}

fn run(one: &Frame, two: &Frame, options: &str) -> Result<PageReconstruction, JsValue> {
    reconstruct(builder(one), builder(two), options, None)
}

/// `reconstructUnfused` of `one` and `two` with `options`, its flows' directions asked of
/// `directions` (see [`directions`]; `None` computes them in wasm).
fn run_unfused(
    one: &Frame,
    two: &Frame,
    options: &str,
    directions: Option<Function>,
) -> impl Future<Output = Result<PageReconstruction, JsValue>> + use<> {
    reconstruct_unfused(builder(one), builder(two), options.into(), None, directions)
}

/// Asserts that `a` and `b` export the same bytes for each of `files`.
fn assert_same_files(a: &mut PageReconstruction, b: &mut PageReconstruction, files: &[&str]) {
    for &file in files {
        assert_eq!(
            a.export_file(file).unwrap(),
            b.export_file(file).unwrap(),
            "{file}"
        );
    }
}

/// The `name` and `message` of a thrown error.
fn name_and_message(error: JsValue) -> (String, String) {
    let error = js_sys::Error::from(error);
    (error.name().into(), error.message().into())
}

#[wasm_bindgen_test]
fn without_intrinsics_the_frames_fix_the_static_room_s_focal_length() {
    // PNG frames carry no EXIF and the options no intrinsics: the guess (the long side, 384 px)
    // gives way to the focal length the static room's flow fixes (the scene's is 307.2 px).
    let scene = render(SceneKind::StaticRoom, 384, 164).unwrap();
    let result = run(&scene.frame1, &scene.frame2, &options("{}")).unwrap();
    let report: serde_json::Value = serde_json::from_str(&result.report().unwrap()).unwrap();
    assert_eq!(report["camera"]["source"], "estimated");
    let fx = report["camera"]["intrinsics"]["fx"].as_f64().unwrap();
    assert!((fx / scene.intrinsics.fx - 1.0).abs() < 0.1, "fx {fx}");
    assert_eq!(report["camera"]["intrinsics"]["fy"].as_f64(), Some(fx));
    let notes = report["notes"].as_array().unwrap();
    assert!(
        notes
            .iter()
            .any(|n| n.as_str().unwrap().contains("the two frames fix it"))
    );
}

#[wasm_bindgen_test]
fn the_street_is_reconstructed_with_pictures_clouds_and_files() {
    let scene = render(SceneKind::Street, 192, 82).unwrap();
    let stages = Rc::new(RefCell::new(Vec::<String>::new()));
    let seen = stages.clone();
    let progress = wasm_bindgen::closure::Closure::<dyn FnMut(String, f64)>::new(
        move |stage: String, fraction: f64| {
            assert!((0.0..=1.0).contains(&fraction));
            let mut seen = seen.borrow_mut();
            if seen.last() != Some(&stage) {
                seen.push(stage);
            }
        },
    );
    let mut result = reconstruct(
        builder(&scene.frame1),
        builder(&scene.frame2),
        &options(r#"{"maxSide": 128}"#),
        Some(progress.as_ref().unchecked_ref::<Function>().clone()),
    )
    .unwrap();
    // Every pass reports the stages in order; a pass beyond the first (from finer flow, where
    // too few scales were pinned: at this size the street takes one) has a note of its own.
    // The fusion runs once, last, on the pass that is kept.
    let order = [
        "flow",
        "superpixels",
        "motion",
        "scales",
        "refine",
        "outputs",
    ];
    let stages = stages.borrow();
    let (last, passes) = stages.split_last().expect("no stage reported");
    assert_eq!(last, "ensemble", "{stages:?}");
    assert!(
        !passes.is_empty() && passes.len().is_multiple_of(order.len()),
        "{stages:?}"
    );
    assert!(
        passes.chunks(order.len()).all(|pass| pass == order),
        "{stages:?}"
    );
    let report: serde_json::Value = serde_json::from_str(&result.report().unwrap()).unwrap();
    let again = report["notes"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|n| {
            let n = n.as_str().unwrap();
            n.contains("reconstructed again") || n.contains("made again")
        })
        .count();
    assert_eq!(passes.len() / order.len(), 1 + again, "{report}");
    drop(stages);
    // Working size 128 × 55 (downscaled from 192 × 82).
    let (w, h) = (result.width() as usize, result.height() as usize);
    assert_eq!((w, h), (128, 55));
    for name in [
        "depth",
        "unorganised",
        "scaled",
        "superpixels",
        "flow",
        "confidence",
    ] {
        assert_eq!(result.picture(name).unwrap().len(), 4 * w * h, "{name}");
    }
    assert!(result.picture("albedo").is_err());

    let cloud = result.cloud("organised").unwrap();
    let count = cloud.count() as usize;
    assert!(count > w * h / 2, "{count} points");
    assert_eq!(cloud.positions1().length() as usize, 3 * count);
    assert_eq!(cloud.positions2().length() as usize, 3 * count);
    assert_eq!(cloud.colours().length() as usize, 3 * count);
    assert_eq!(cloud.labels().length() as usize, count);
    for stage in ["unorganised", "scaled"] {
        let cloud = result.cloud(stage).unwrap();
        assert_eq!(cloud.labels().length(), cloud.count(), "{stage}");
        assert!(
            cloud.count() as usize > w * h / 2,
            "{stage}: {} points",
            cloud.count()
        );
    }
    assert!(result.cloud("stew").is_err());

    let ply = ply::decode(&result.export_file("frame1.ply").unwrap()).unwrap();
    assert_eq!(ply.positions.len(), count);
    assert_eq!(
        result.export_media_type("depth16.png").unwrap(),
        "image/png"
    );
    assert!(result.export_file("depth.exr").is_err());

    assert_eq!(report["input_size"], serde_json::json!([192, 82]));
    assert_eq!(report["camera"]["source"], "default");
    assert_eq!(report["params"]["superpixels"]["count"], 150);
    let legend: serde_json::Value = serde_json::from_str(&result.depth_legend(8).unwrap()).unwrap();
    assert_eq!(legend["colours"].as_array().unwrap().len(), 8);
    assert_eq!(legend["depths"].as_array().unwrap().len(), 8);
}

#[wasm_bindgen_test]
fn bad_input_throws_named_errors_with_the_library_messages() {
    let scene = render(SceneKind::StaticRoom, 64, 48).unwrap();
    let small = render(SceneKind::StaticRoom, 48, 36).unwrap();

    let (name, message) = name_and_message(
        run(&scene.frame1, &small.frame2, &options("{}"))
            .err()
            .unwrap(),
    );
    assert_eq!(name, "SizeMismatchError");
    assert!(
        message.contains("64×48") && message.contains("48×36"),
        "{message}"
    );
    // Resizing frame 2 instead gets past the size check.
    let resized = run(
        &scene.frame1,
        &small.frame2,
        &options(r#"{"resizeSecond": true}"#),
    );
    if let Err(error) = resized {
        assert_ne!(name_and_message(error).0, "SizeMismatchError");
    }

    let tiny = render(SceneKind::StaticRoom, 16, 16).unwrap();
    let (name, _) = name_and_message(
        run(&tiny.frame1, &tiny.frame2, &options("{}"))
            .err()
            .unwrap(),
    );
    assert_eq!(name, "TooSmallError");

    let (name, message) = name_and_message(
        run(&scene.frame1, &scene.frame1, &options("{}"))
            .err()
            .unwrap(),
    );
    assert_eq!(name, "NoParallaxError");
    assert!(message.starts_with("no parallax"), "{message}");

    let (name, message) = name_and_message(
        run(&scene.frame1, &scene.frame2, r#"{"maxSide": "big"}"#)
            .err()
            .unwrap(),
    );
    assert_eq!(name, "InvalidParameterError");
    assert!(
        message.starts_with("invalid parameter: options:"),
        "{message}"
    );

    // Frames filled wrongly: ragged rows, too many rows, missing rows.
    let mut ragged = FrameBuilder::new(64, 48);
    let (name, message) = name_and_message(ragged.push_rows(&[0; 4 * 64 + 4]).unwrap_err());
    assert_eq!(name, "InvalidParameterError");
    assert!(message.contains("has 256 bytes, got 260"), "{message}");
    let mut full = builder(&scene.frame1);
    let (_, message) = name_and_message(full.push_rows(&[0; 4 * 64]).unwrap_err());
    assert!(message.contains("got 49 rows"), "{message}");
    let mut partial = FrameBuilder::new(64, 48);
    partial.push_rows(&[0; 4 * 64 * 47]).unwrap();
    let (name, message) = name_and_message(
        reconstruct(partial, builder(&scene.frame2), &options("{}"), None)
            .err()
            .unwrap(),
    );
    assert_eq!(name, "InvalidParameterError");
    assert!(message.contains("got only 47 rows"), "{message}");
}

#[wasm_bindgen_test]
fn exif_intrinsics_and_defaults_as_json() {
    let png = encode_png(&render(SceneKind::Flag, 32, 32).unwrap().frame1).unwrap();
    assert_eq!(
        read_exif(&png).unwrap(),
        r#"{"focal35mm":null,"warning":null}"#
    );
    let camera: serde_json::Value =
        serde_json::from_str(&resolve_intrinsics_json(640, 480, Some(36.0)).unwrap()).unwrap();
    assert_eq!(camera["source"], "exif");
    assert_eq!(camera["intrinsics"]["fx"], 640.0);
    let camera: serde_json::Value =
        serde_json::from_str(&resolve_intrinsics_json(640, 480, None).unwrap()).unwrap();
    assert_eq!(camera["source"], "default");
    assert_eq!(camera["intrinsics"]["cx"], 319.5);

    let defaults: serde_json::Value = serde_json::from_str(&page_defaults().unwrap()).unwrap();
    // The page's defaults are the library's, every parameter of them, but for the flow preset
    // (fine in a browser tab: high's depth in less time) and the kept reconstruction's
    // refinement (the fused members', for time).
    assert_eq!(defaults["options"]["maxSide"], DEFAULT_MAX_SIDE);
    assert_eq!(defaults["options"]["flowPreset"], PAGE_FLOW_PRESET.name());
    assert_eq!(PAGE_FLOW_PRESET, Preset::Fine);
    assert_eq!(
        defaults["options"]["params"],
        serde_json::to_value(page_params()).unwrap()
    );
    let mut library = Params::default();
    (library.refine.iterations, library.refine.particles) = (2, 8);
    assert_eq!(page_params(), library);
    assert_eq!(
        defaults["stages"].as_array().unwrap().len(),
        superpixel_soup::Stage::ALL.len()
    );
    assert_eq!(
        defaults["flowPresets"],
        serde_json::json!(["fast", "medium", "fine", "high"])
    );
    assert!(
        defaults["exports"]
            .as_array()
            .unwrap()
            .contains(&"flow.flo".into())
    );
}

#[wasm_bindgen_test]
fn a_failed_allocation_is_remembered() {
    // Three allocations of 1.5 GB cannot all fit in the 4 GiB of wasm32 memory (growing only
    // reserves address space, so this costs no real memory).
    const SIZE: usize = 1_500_000_000;
    let mut blocks = [Vec::<u8>::new(), Vec::new(), Vec::new()];
    let failed = blocks
        .iter_mut()
        .map(|block| block.try_reserve_exact(SIZE))
        .filter(Result::is_err)
        .count();
    assert!(failed > 0);
    assert_eq!(failed_allocation(), Some(SIZE as f64));
}

#[wasm_bindgen_test]
fn ground_truth_is_scored_with_the_eval_metrics_and_added_to_the_report() {
    let scene = render(SceneKind::Street, 160, 68).unwrap();
    let mut result = run(&scene.frame1, &scene.frame2, &options("{}")).unwrap();
    // The result's own depth scores 0 (up to scale), as PFM and as Sintel .dpt.
    let own = pfm::decode(&result.export_file("depth.pfm").unwrap()).unwrap();
    let score: serde_json::Value = serde_json::from_str(
        &result
            .score_depth("own.dpt", &dpt::encode(&own), None)
            .unwrap(),
    )
    .unwrap();
    assert!(score["metrics"]["mre"].as_f64().unwrap() < 1e-6, "{score}");
    assert_eq!(score["legend"]["colours"].as_array().unwrap().len(), 64);
    assert_eq!(result.error_picture().unwrap().len(), 4 * 160 * 68);
    // The true depth: the metrics of soup eval, and the report carries them.
    let truth = pfm::encode(&scene.depth1);
    let score: serde_json::Value =
        serde_json::from_str(&result.score_depth("depth1.pfm", &truth, None).unwrap()).unwrap();
    // (serde_json reads floats back to within an ulp or so.)
    let metric = |name: &str| score["metrics"][name].as_f64().unwrap();
    let eval = depth_metrics(&scene.depth1, &own).unwrap();
    let mre = metric("mre");
    assert!((mre - eval.mre).abs() < 1e-12, "{mre} vs {}", eval.mre);
    assert!((metric("abs_rel") - eval.abs_rel).abs() < 1e-12);
    assert!((metric("delta_125") - eval.delta_125).abs() < 1e-12);
    let flow: serde_json::Value = serde_json::from_str(
        &result
            .score_flow("flow12.flo", &flo::encode(&scene.flow12))
            .unwrap(),
    )
    .unwrap();
    assert!(flow["metrics"]["epe"].as_f64().unwrap() > 0.0);
    let report: serde_json::Value =
        serde_json::from_slice(&result.export_file("report.json").unwrap()).unwrap();
    assert_eq!(report["ground_truth"]["depth"]["file"], "depth1.pfm");
    assert_eq!(report["ground_truth"]["depth"]["metrics"]["mre"], mre);
    assert!(report["ground_truth"]["flow"]["metrics"]["epe"].is_number());
    // A depth of another size, or not a depth file: named errors; the scores stay.
    let small = pfm::encode(&resize(&scene.frame1, 80, 34).map(|_| 1.0f32));
    let (name, message) =
        name_and_message(result.score_depth("small.pfm", &small, None).unwrap_err());
    assert_eq!(name, "InvalidParameterError");
    assert!(message.contains("80×34 but frame 1 is 160×68"), "{message}");
    let (name, _) = name_and_message(result.score_depth("x.pfm", b"junk", None).unwrap_err());
    assert_eq!(name, "FormatError");
    let report: serde_json::Value = serde_json::from_str(&result.report().unwrap()).unwrap();
    assert_eq!(report["ground_truth"]["depth"]["metrics"]["mre"], mre);
}

#[wasm_bindgen_test]
fn frames_decoded_smaller_keep_the_photos_size_for_outputs_and_checks() {
    let scene = render(SceneKind::Street, 160, 68).unwrap();
    let half = |f: &Frame| resize(f, 80, 34);
    let mut result = run(
        &half(&scene.frame1),
        &half(&scene.frame2),
        &options(r#"{"photoSizes": [[160, 68], [160, 68]]}"#),
    )
    .unwrap();
    assert_eq!((result.width(), result.height()), (80, 34));
    let report: serde_json::Value = serde_json::from_str(&result.report().unwrap()).unwrap();
    assert_eq!(report["input_size"], serde_json::json!([160, 68]));
    let depth = pfm::decode(&result.export_file("depth.pfm").unwrap()).unwrap();
    assert_eq!(depth.size(), (160, 68));
    let flow = flo::decode(&result.export_file("flow.flo").unwrap()).unwrap();
    assert_eq!(flow.size(), (160, 68));
    // Photos of different sizes are told apart by their own sizes.
    let (name, message) = name_and_message(
        run(
            &half(&scene.frame1),
            &half(&scene.frame2),
            &options(r#"{"photoSizes": [[160, 68], [320, 136]]}"#),
        )
        .err()
        .unwrap(),
    );
    assert_eq!(name, "SizeMismatchError");
    assert!(
        message.contains("160×68") && message.contains("320×136"),
        "{message}"
    );
}

/// A `directions` function for `reconstructUnfused` (www/worker.js's way) that records the
/// presets it is asked for in `asked` (with the stage their progress goes to where it is not
/// the flow's) and answers each with `answer(preset)`. Each flow's progress must span a part of
/// its stage.
fn directions(
    asked: &Rc<RefCell<Vec<String>>>,
    mut answer: impl FnMut(&str) -> JsValue + 'static,
) -> Function {
    let asked = asked.clone();
    let request = Closure::<dyn FnMut(String, String, f64, f64) -> js_sys::Promise>::new(
        move |preset: String, stage: String, from: f64, to: f64| {
            assert!(0.0 <= from && from < to && to <= 1.0, "{from}..{to}");
            let value = answer(&preset);
            let asked_for = match stage.as_str() {
                "flow" => preset,
                _ => format!("{preset} ({stage})"),
            };
            asked.borrow_mut().push(asked_for);
            js_sys::Promise::resolve(&value)
        },
    );
    request.into_js_value().unchecked_into()
}

/// `{ forward, backward }` as the worker gives a flow's directions.
fn directions_object(forward: &[f32], backward: &[f32]) -> JsValue {
    let object = js_sys::Object::new();
    for (key, data) in [("forward", forward), ("backward", backward)] {
        let array = js_sys::Float32Array::from(data);
        js_sys::Reflect::set(&object, &key.into(), &array).unwrap();
    }
    object.into()
}

/// Answers for `directions` as a helper worker and the worker give them: the two directions of
/// the asked preset's flow between `one` and `two` with the options `json` ([`flow_direction`]),
/// as if computed before the run in `ms` milliseconds.
fn computed_directions(
    one: &Frame,
    two: &Frame,
    json: &str,
    ms: f64,
) -> impl FnMut(&str) -> JsValue + use<> {
    let (one, two, json) = (one.clone(), two.clone(), json.to_string());
    move |preset: &str| {
        let mut with_preset: serde_json::Value = serde_json::from_str(&json).unwrap();
        with_preset["flowPreset"] = preset.into();
        let with_preset = with_preset.to_string();
        let direction = |backward| {
            flow_direction(builder(&one), builder(&two), &with_preset, backward, None).unwrap()
        };
        let given = directions_object(&direction(false), &direction(true));
        js_sys::Reflect::set(&given, &"ms".into(), &ms.into()).unwrap();
        given
    }
}

#[wasm_bindgen_test]
async fn flow_directions_given_apart_fit_the_frames_and_give_the_same_result() {
    let s = render(SceneKind::Street, 64, 48).unwrap();
    let options = options("{}");
    let asked = Rc::new(RefCell::new(Vec::new()));
    let unfused = |answer: JsValue| {
        let request = directions(&asked, move |_| answer.clone());
        run_unfused(&s.frame1, &s.frame2, &options, Some(request))
    };
    let half = js_sys::Object::new();
    let full = js_sys::Float32Array::from(&vec![0.0f32; 2 * 64 * 48][..]);
    js_sys::Reflect::set(&half, &"forward".into(), &full).unwrap();
    let (name, message) = name_and_message(unfused(half.into()).await.err().unwrap());
    assert_eq!(name, "InvalidParameterError");
    assert!(message.contains("no backward direction"), "{message}");
    let short = directions_object(&[0.0; 10], &[0.0; 10]);
    let (_, message) = name_and_message(unfused(short).await.err().unwrap());
    assert!(message.contains("10 numbers for 64×48"), "{message}");
    // `null` leaves the directions to the pipeline, which computes them (here in two passes,
    // the second asking for preset high's flow).
    let mut computed = unfused(JsValue::NULL).await.unwrap();
    assert_eq!(*asked.borrow(), ["fine", "fine", "fine", "high"]);
    // The finer pass's flow given apart too: the same files as with the directions computed here.
    asked.borrow_mut().clear();
    let request = directions(
        &asked,
        computed_directions(&s.frame1, &s.frame2, &options, 0.0),
    );
    let mut apart = run_unfused(&s.frame1, &s.frame2, &options, Some(request))
        .await
        .unwrap();
    assert_eq!(*asked.borrow(), ["fine", "high"]);
    assert_same_files(
        &mut apart,
        &mut computed,
        &["depth.pfm", "flow.flo", "frame1.ply"],
    );
}

#[wasm_bindgen_test]
async fn a_pass_kept_after_a_finer_one_is_given_its_flow_again() {
    // The table at 64 × 48 with its own intrinsics: preset fine's pass finds no ground, preset
    // high's pins no more, and fine's pass is kept: its flow is asked for again, within the
    // outputs stage (the worker gives the directions it holds), and the files are those with
    // every flow computed here.
    let s = render(SceneKind::Table, 64, 48).unwrap();
    let k = serde_json::to_string(&s.intrinsics).unwrap();
    let options = options(&format!(r#"{{"intrinsics": {k}}}"#));
    let unfused = |directions| run_unfused(&s.frame1, &s.frame2, &options, directions);
    let asked = Rc::new(RefCell::new(Vec::new()));
    let answer = computed_directions(&s.frame1, &s.frame2, &options, 0.0);
    let mut apart = unfused(Some(directions(&asked, answer))).await.unwrap();
    assert_eq!(*asked.borrow(), ["fine", "high", "fine (outputs)"]);
    let report: serde_json::Value = serde_json::from_str(&apart.report().unwrap()).unwrap();
    let notes = report["notes"].to_string();
    assert!(
        notes.contains("kept the reconstruction from preset fine"),
        "{notes}"
    );
    let mut here = unfused(None).await.unwrap();
    assert_same_files(
        &mut apart,
        &mut here,
        &["depth.pfm", "flow.flo", "frame1.ply"],
    );
}

#[wasm_bindgen_test]
async fn members_made_in_other_workers_fuse_to_the_same_result() {
    // The worker's way (www/worker.js): each flow's directions apart (one in a helper worker),
    // the kept pass, each member's vote from the copied inputs (in a helper worker, here in
    // turn), the votes added in the order of their counts, then the fusion; the same files and
    // report as the one-call reconstruct, but for times.
    let s = render(SceneKind::Street, 256, 110).unwrap();
    let options = options("{}");
    let mut whole = run(&s.frame1, &s.frame2, &options).unwrap();
    let asked = Rc::new(RefCell::new(Vec::new()));
    let answer = computed_directions(&s.frame1, &s.frame2, &options, 1000.0);
    let request = directions(&asked, answer);
    let mut parts = run_unfused(&s.frame1, &s.frame2, &options, Some(request))
        .await
        .unwrap();
    assert_eq!(*asked.borrow(), ["fine"]);
    let inputs = parts.member_inputs();
    let counts = parts.member_counts().to_vec();
    assert_eq!(counts, vec![140, 160, 130, 170]);
    let (frame, flow, reliable) = (
        inputs.frame().to_vec(),
        inputs.flow().to_vec(),
        inputs.reliable().to_vec(),
    );
    let (w, h, k) = (
        inputs.width(),
        inputs.height(),
        inputs.intrinsics().to_vec(),
    );
    assert_eq!(
        (w, h, frame.len(), flow.len()),
        (256, 110, 3 * 256 * 110, 2 * 256 * 110)
    );
    let source = |flow: &[f32]| {
        let (frame, flow, reliable) = (frame.clone(), flow.to_vec(), reliable.clone());
        MemberSource::new(&options, w, h, &k, frame, flow, reliable)
    };
    let helper = source(&flow).unwrap();
    // Members 0 and 2 made "here", 1 and 3 by a "helper".
    for (i, &count) in counts.iter().enumerate() {
        let v = if i % 2 == 0 {
            parts.member_vote(count)
        } else {
            helper.vote(count)
        };
        let v = v.unwrap();
        (parts.add_vote(
            v.width(),
            v.height(),
            &v.depth().to_vec(),
            &v.pinned().to_vec(),
        ))
        .unwrap();
    }
    // A fifth vote, or one of another size, is refused.
    let v = helper.vote(150).unwrap();
    let (depth, pinned) = (v.depth().to_vec(), v.pinned().to_vec());
    let refused = parts.add_vote(v.width(), v.height(), &depth, &pinned);
    assert!(name_and_message(refused.unwrap_err()).1.contains("all in"));
    let refused = parts.add_vote(v.width() - 1, v.height(), &depth, &pinned);
    assert_eq!(
        name_and_message(refused.unwrap_err()).0,
        "InvalidParameterError"
    );
    parts.fuse(12.0).unwrap();
    let files = ["depth.pfm", "frame1.ply", "frame2.ply", "flow.flo"];
    assert_same_files(&mut parts, &mut whole, &files);
    let report = |r: &PageReconstruction| -> serde_json::Value {
        serde_json::from_str(&r.report().unwrap()).unwrap()
    };
    let without_times = |r: &PageReconstruction| {
        let mut json = report(r);
        json.as_object_mut().unwrap().remove("timings_ms");
        json
    };
    assert_eq!(without_times(&parts), without_times(&whole));
    // The flow's time counts the 1000 ms the directions took before the run.
    let flow_ms = report(&parts)["timings_ms"]
        .as_array()
        .unwrap()
        .iter()
        .find(|t| t[0] == "flow")
        .map(|t| t[1].as_f64().unwrap());
    assert!(flow_ms.is_some_and(|ms| ms >= 1000.0), "{flow_ms:?}");
    // Finished: the fusion's methods throw.
    for thrown in [parts.add_failure("late"), parts.fuse(0.0)] {
        assert_eq!(
            name_and_message(thrown.unwrap_err()).0,
            "InvalidParameterError"
        );
    }
    // Arrays that do not fit the size throw named errors.
    let (name, message) = name_and_message(source(&flow[2..]).err().unwrap());
    assert_eq!(name, "InvalidParameterError");
    assert!(message.contains("flow"), "{message}");
    // So do options with a parameter out of its range, as the run's would.
    let mut bad: serde_json::Value = serde_json::from_str(&options).unwrap();
    bad["params"]["refine"]["expansion_factors"] = serde_json::json!([0.5, 0.4, 0.6, 1.5]);
    let refused = MemberSource::new(&bad.to_string(), w, h, &k, frame, flow, reliable);
    let (name, message) = name_and_message(refused.err().unwrap());
    assert_eq!(name, "InvalidParameterError");
    assert!(message.contains("expansion_factors"), "{message}");
}
