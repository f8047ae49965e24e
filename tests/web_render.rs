//! Browser tests of the point-cloud viewer (`src/render`, `src/web/viewer.rs`), run headless in
//! Chromium by ./check.sh through wasm-bindgen-test-runner (browser flags: `webdriver.json`,
//! which enable both WebGPU and WebGL2). Every property is checked once per backend.
//!
//! The viewer draws known clouds into a 160 × 120 canvas with a 60° vertical field of view; its
//! home view then looks through camera 1, so a point (x, y, z) must land on the pinhole pixel
//! u = 79.5 + f·x/z, v = 59.5 + f·y/z with f = 60 / tan 30°. Pictures are read back with
//! `screenshot()` (PNG) and checked for properties with a tolerance, never compared exactly
//! across backends.
#![cfg(all(target_arch = "wasm32", feature = "viewer"))]

use js_sys::{Float32Array, Reflect, Uint8Array, Uint32Array};
use superpixel_soup::image::{Frame, decode_image};
use superpixel_soup::render::colour::label_colour;
use superpixel_soup::render::view::DEFAULT_BACKGROUND;
use superpixel_soup::web::viewer::Viewer;
use wasm_bindgen::{JsCast, JsError, JsValue};
use wasm_bindgen_futures::JsFuture;
use wasm_bindgen_test::{wasm_bindgen_test, wasm_bindgen_test_configure};
use web_sys::{CanvasRenderingContext2d, HtmlCanvasElement};

wasm_bindgen_test_configure!(run_in_browser);

const WIDTH: u32 = 160;
const HEIGHT: u32 = 120;
const FOV_DEGREES: f64 = 60.0;
/// Per-channel tolerance when checking a colour.
const TOLERANCE: i32 = 4;

fn focal() -> f32 {
    (HEIGHT as f32 / 2.0) / (FOV_DEGREES as f32 / 2.0).to_radians().tan()
}

/// The camera-1 point at depth `z` that projects onto pixel (`u`, `v`).
fn at_pixel(u: f32, v: f32, z: f32) -> [f32; 3] {
    let f = focal();
    let (cx, cy) = (WIDTH as f32 / 2.0 - 0.5, HEIGHT as f32 / 2.0 - 0.5);
    [(u - cx) * z / f, (v - cy) * z / f, z]
}

fn ok<T>(result: Result<T, JsError>) -> T {
    result.map_err(JsValue::from).unwrap()
}

fn new_canvas() -> HtmlCanvasElement {
    let document = web_sys::window().unwrap().document().unwrap();
    let canvas: HtmlCanvasElement = document
        .create_element("canvas")
        .unwrap()
        .dyn_into()
        .unwrap();
    canvas.set_width(WIDTH);
    canvas.set_height(HEIGHT);
    canvas
}

async fn open(backend: &str) -> Viewer {
    let options = js_sys::Object::new();
    Reflect::set(&options, &"backend".into(), &backend.into()).unwrap();
    Reflect::set(&options, &"fieldOfView".into(), &FOV_DEGREES.into()).unwrap();
    Reflect::set(&options, &"controls".into(), &false.into()).unwrap();
    let viewer = ok(Viewer::create(new_canvas(), Some(options)).await);
    assert_eq!(viewer.backend(), backend);
    viewer
}

/// A cloud of `points` (frame 1), optionally moving to `moved` (frame 2), with colours.
struct Cloud {
    pos1: Vec<f32>,
    pos2: Option<Vec<f32>>,
    rgb: Vec<u8>,
    labels: Option<Vec<u32>>,
}

impl Cloud {
    fn new(points: &[([f32; 3], [u8; 3])]) -> Cloud {
        Cloud {
            pos1: points.iter().flat_map(|(p, _)| *p).collect(),
            pos2: None,
            rgb: points.iter().flat_map(|(_, c)| *c).collect(),
            labels: None,
        }
    }

    fn show(&self, viewer: &Viewer) {
        let absent = JsValue::UNDEFINED;
        ok(viewer.set_cloud(
            &Float32Array::from(&self.pos1[..]).into(),
            &self
                .pos2
                .as_ref()
                .map_or(absent.clone(), |p| Float32Array::from(&p[..]).into()),
            &Uint8Array::from(&self.rgb[..]).into(),
            &self
                .labels
                .as_ref()
                .map_or(absent, |l| Uint32Array::from(&l[..]).into()),
        ));
    }
}

async fn picture(viewer: &Viewer) -> Frame {
    let png = JsFuture::from(viewer.screenshot()).await.unwrap();
    let frame = decode_image(&Uint8Array::new(&png).to_vec()).unwrap().frame;
    assert_eq!(frame.size(), (WIDTH as usize, HEIGHT as usize));
    frame
}

fn near(actual: [u8; 3], expected: [u8; 3]) -> bool {
    actual
        .iter()
        .zip(expected)
        .all(|(&a, e)| (a as i32 - e as i32).abs() <= TOLERANCE)
}

fn is_background(pixel: [u8; 3]) -> bool {
    near(pixel, DEFAULT_BACKGROUND)
}

fn pixel(frame: &Frame, u: usize, v: usize) -> [u8; 3] {
    *frame.get(u, v)
}

fn covered(frame: &Frame) -> usize {
    frame.data().iter().filter(|p| !is_background(**p)).count()
}

const RED: [u8; 3] = [230, 30, 40];
const GREEN: [u8; 3] = [30, 200, 60];
const BLUE: [u8; 3] = [40, 60, 230];
const YELLOW: [u8; 3] = [240, 220, 20];
const WHITE: [u8; 3] = [250, 250, 250];

/// Runs `$check(backend)` as two tests, one per backend.
macro_rules! on_both_backends {
    ($check:ident: $webgpu:ident, $webgl2:ident) => {
        #[wasm_bindgen_test]
        async fn $webgpu() {
            $check("webgpu").await;
        }

        #[wasm_bindgen_test]
        async fn $webgl2() {
            $check("webgl2").await;
        }
    };
}

/// Points land on their pinhole pixels in their colours; everything else is background.
async fn points_land_where_camera_one_sees_them(backend: &str) {
    let viewer = open(backend).await;
    let targets = [
        ((30, 20), 3.0, RED),
        ((130, 25), 5.0, GREEN),
        ((80, 60), 4.0, BLUE),
        ((40, 100), 6.0, YELLOW),
        ((125, 95), 2.5, WHITE),
    ];
    let points: Vec<([f32; 3], [u8; 3])> = targets
        .iter()
        .map(|&((u, v), z, c)| (at_pixel(u as f32, v as f32, z), c))
        .collect();
    Cloud::new(&points).show(&viewer);
    ok(viewer.set_point_size(3.0));
    let frame = picture(&viewer).await;
    for &((u, v), _, colour) in &targets {
        for (du, dv) in [(0, 0), (-1, 0), (1, 0), (0, -1), (0, 1)] {
            let got = pixel(&frame, (u + du) as usize, (v + dv) as usize);
            assert!(
                near(got, colour),
                "{backend}: ({u}+{du}, {v}+{dv}) is {got:?}, not {colour:?}"
            );
        }
    }
    // Away from the points (more than 2 px), only background.
    for v in 0..HEIGHT as i32 {
        for u in 0..WIDTH as i32 {
            let far = targets
                .iter()
                .all(|&((pu, pv), _, _)| (u - pu).abs() > 2 || (v - pv).abs() > 2);
            if far {
                let got = pixel(&frame, u as usize, v as usize);
                assert!(
                    is_background(got),
                    "{backend}: ({u}, {v}) should be background, is {got:?}"
                );
            }
        }
    }
    assert_eq!(
        covered(&frame),
        targets.len() * 9,
        "{backend}: 3 × 3 pixels per point"
    );
}
on_both_backends!(points_land_where_camera_one_sees_them: points_webgpu, points_webgl2);

/// The nearer of two points on one ray wins, whichever is drawn first.
async fn nearer_points_hide_farther_ones(backend: &str) {
    let viewer = open(backend).await;
    Cloud::new(&[
        (at_pixel(40.0, 30.0, 2.0), RED),
        (at_pixel(40.0, 30.0, 6.0), GREEN),
        (at_pixel(120.0, 90.0, 6.0), GREEN),
        (at_pixel(120.0, 90.0, 2.0), RED),
        // Far context so the two depths are not both at the ends of the depth range.
        (at_pixel(80.0, 60.0, 9.0), BLUE),
    ])
    .show(&viewer);
    ok(viewer.set_point_size(5.0));
    let frame = picture(&viewer).await;
    for (u, v) in [(40, 30), (120, 90)] {
        let got = pixel(&frame, u, v);
        assert!(
            near(got, RED),
            "{backend}: ({u}, {v}) is {got:?}, the near point is red"
        );
    }
}
on_both_backends!(nearer_points_hide_farther_ones: depth_test_webgpu, depth_test_webgl2);

/// Frame 2 shows X', the morph moves points along X → X', frame 1 shows X.
async fn morph_moves_points_from_frame_one_to_frame_two(backend: &str) {
    let viewer = open(backend).await;
    let mut cloud = Cloud::new(&[
        (at_pixel(50.0, 60.0, 4.0), RED),
        (at_pixel(80.0, 20.0, 5.0), GREEN),
    ]);
    let mut moved = at_pixel(110.0, 60.0, 4.0).to_vec();
    moved.extend(at_pixel(80.0, 20.0, 5.0)); // the green point stays
    cloud.pos2 = Some(moved);
    cloud.show(&viewer);
    ok(viewer.set_point_size(3.0));

    let frame1 = picture(&viewer).await;
    assert!(near(pixel(&frame1, 50, 60), RED), "{backend}: frame 1");
    assert!(is_background(pixel(&frame1, 110, 60)));

    ok(viewer.set_frame(2));
    let frame2 = picture(&viewer).await;
    assert!(near(pixel(&frame2, 110, 60), RED), "{backend}: frame 2");
    assert!(is_background(pixel(&frame2, 50, 60)));

    // Same depth in both frames, so the halfway point projects halfway.
    ok(viewer.set_morph(0.5));
    let halfway = picture(&viewer).await;
    assert!(near(pixel(&halfway, 80, 60), RED), "{backend}: morph 0.5");
    assert!(is_background(pixel(&halfway, 50, 60)) && is_background(pixel(&halfway, 110, 60)));
    for frame in [&frame1, &frame2, &halfway] {
        assert!(
            near(pixel(frame, 80, 20), GREEN),
            "{backend}: the still point stays"
        );
    }
    assert!(viewer.set_morph(1.5).is_err());
}
on_both_backends!(morph_moves_points_from_frame_one_to_frame_two: morph_webgpu, morph_webgl2);

/// Coverage grows with the square of the point size.
async fn point_size_sets_the_covered_area(backend: &str) {
    let viewer = open(backend).await;
    let points: Vec<([f32; 3], [u8; 3])> = (0..12)
        .map(|i| {
            let (u, v) = (25 + 22 * (i % 6), 30 + 60 * (i / 6));
            (at_pixel(u as f32, v as f32, 3.0 + i as f32 * 0.25), YELLOW)
        })
        .collect();
    Cloud::new(&points).show(&viewer);
    ok(viewer.set_point_size(1.0));
    assert_eq!(
        covered(&picture(&viewer).await),
        12,
        "{backend}: one pixel per point"
    );
    ok(viewer.set_point_size(3.0));
    assert_eq!(covered(&picture(&viewer).await), 12 * 9, "{backend}: 3 × 3");
    ok(viewer.set_point_size(7.0));
    assert_eq!(
        covered(&picture(&viewer).await),
        12 * 49,
        "{backend}: 7 × 7"
    );
}
on_both_backends!(point_size_sets_the_covered_area: point_size_webgpu, point_size_webgl2);

/// Depth colours are warm near and cool far; superpixel colours are the label colours.
async fn colour_modes_recolour_the_points(backend: &str) {
    let viewer = open(backend).await;
    let mut cloud = Cloud::new(&[
        (at_pixel(30.0, 60.0, 1.5), WHITE),
        (at_pixel(80.0, 60.0, 4.0), WHITE),
        (at_pixel(130.0, 60.0, 12.0), WHITE),
    ]);
    cloud.labels = Some(vec![3, 4, 3]);
    cloud.show(&viewer);
    ok(viewer.set_point_size(3.0));

    ok(viewer.set_colour_mode("depth"));
    assert_eq!(viewer.colour_mode(), "depth");
    let depth = picture(&viewer).await;
    let [r, _, b] = pixel(&depth, 30, 60);
    assert!(
        r > b + 50,
        "{backend}: near should be warm, is {:?}",
        pixel(&depth, 30, 60)
    );
    let [r, _, b] = pixel(&depth, 130, 60);
    assert!(
        b > r + 50,
        "{backend}: far should be cool, is {:?}",
        pixel(&depth, 130, 60)
    );

    ok(viewer.set_colour_mode("superpixel"));
    let labels = picture(&viewer).await;
    assert!(
        near(pixel(&labels, 30, 60), label_colour(3)),
        "{backend}: label 3"
    );
    assert!(
        near(pixel(&labels, 80, 60), label_colour(4)),
        "{backend}: label 4"
    );
    assert!(
        near(pixel(&labels, 130, 60), label_colour(3)),
        "{backend}: label 3 again"
    );

    ok(viewer.set_colour_mode("rgb"));
    assert!(near(pixel(&picture(&viewer).await, 80, 60), WHITE));
    assert!(viewer.set_colour_mode("rainbow").is_err());
}
on_both_backends!(colour_modes_recolour_the_points: colour_modes_webgpu, colour_modes_webgl2);

/// What `render()` puts on the canvas itself matches the screenshot.
async fn the_canvas_shows_the_points(backend: &str) {
    let canvas = new_canvas();
    let options = js_sys::Object::new();
    Reflect::set(&options, &"backend".into(), &backend.into()).unwrap();
    Reflect::set(&options, &"fieldOfView".into(), &FOV_DEGREES.into()).unwrap();
    let viewer = ok(Viewer::create(canvas.clone(), Some(options)).await);
    Cloud::new(&[
        (at_pixel(60.0, 40.0, 3.0), RED),
        (at_pixel(100.0, 80.0, 3.0), BLUE),
    ])
    .show(&viewer);
    ok(viewer.set_point_size(5.0));
    viewer.render();
    // Copy the canvas in the same task, before the browser composites (and may clear) it.
    let copy = new_canvas();
    let context: CanvasRenderingContext2d =
        copy.get_context("2d").unwrap().unwrap().dyn_into().unwrap();
    context
        .draw_image_with_html_canvas_element(&canvas, 0.0, 0.0)
        .unwrap();
    let rgba = |u: f64, v: f64| {
        let data = context.get_image_data(u, v, 1.0, 1.0).unwrap().data();
        [data[0], data[1], data[2]]
    };
    assert!(
        near(rgba(60.0, 40.0), RED),
        "{backend}: canvas at the red point is {:?}",
        rgba(60.0, 40.0)
    );
    assert!(
        near(rgba(100.0, 80.0), BLUE),
        "{backend}: canvas at the blue point"
    );
    assert!(
        is_background(rgba(5.0, 5.0)),
        "{backend}: canvas corner is {:?}",
        rgba(5.0, 5.0)
    );
}
on_both_backends!(the_canvas_shows_the_points: canvas_webgpu, canvas_webgl2);

/// Clouds larger than a texture row (1024 points) are drawn whole; decimation keeps the budget;
/// an empty cloud draws only background.
async fn budget_and_empty_cloud(backend: &str) {
    let viewer = open(backend).await;
    // 3000 points on distinct pixels: two full texture rows and part of a third.
    let points: Vec<([f32; 3], [u8; 3])> = (0..3000)
        .map(|i| {
            let (u, v) = (8 + i % 144, 8 + 5 * (i / 144));
            (at_pixel(u as f32, v as f32, 4.0 + (i % 7) as f32), GREEN)
        })
        .collect();
    Cloud::new(&points).show(&viewer);
    ok(viewer.set_point_size(1.0));
    assert_eq!(
        covered(&picture(&viewer).await),
        3000,
        "{backend}: every point drawn"
    );
    ok(viewer.set_point_budget(100));
    assert_eq!(
        (viewer.point_count(), viewer.shown_point_count()),
        (3000, 100)
    );
    assert_eq!(
        covered(&picture(&viewer).await),
        100,
        "{backend}: the budget"
    );
    Cloud::new(&[]).show(&viewer);
    assert_eq!(covered(&picture(&viewer).await), 0);
}
on_both_backends!(budget_and_empty_cloud: budget_webgpu, budget_webgl2);

#[wasm_bindgen_test]
async fn auto_prefers_webgpu_where_it_works() {
    let viewer = ok(Viewer::create(new_canvas(), None).await);
    assert_eq!(viewer.backend(), "webgpu");
}

#[wasm_bindgen_test]
async fn bad_options_and_buffers_give_readable_errors() {
    let options = js_sys::Object::new();
    Reflect::set(&options, &"backend".into(), &"vulkan".into()).unwrap();
    let message = |e: JsError| String::from(js_sys::Error::from(JsValue::from(e)).message());
    let err = Viewer::create(new_canvas(), Some(options))
        .await
        .err()
        .unwrap();
    assert!(message(err).contains("backend must be"));

    let viewer = open("webgl2").await;
    let err = viewer
        .set_cloud(
            &Float32Array::from(&[0.0, 0.0, 1.0][..]).into(),
            &JsValue::NULL,
            &Uint8Array::from(&[1, 2][..]).into(),
            &JsValue::UNDEFINED,
        )
        .unwrap_err();
    assert!(message(err).contains("colours hold 2 bytes for 1 points"));
    let err = viewer
        .set_cloud(
            &"0 0 1".into(),
            &JsValue::NULL,
            &Uint8Array::from(&[1, 2, 3][..]).into(),
            &JsValue::UNDEFINED,
        )
        .unwrap_err();
    assert!(message(err).contains("frame-1 positions must be a Float32Array"));
    // Plain arrays of numbers are converted.
    let plain = |values: &[f64]| {
        JsValue::from(
            values
                .iter()
                .map(|&v| JsValue::from(v))
                .collect::<js_sys::Array>(),
        )
    };
    ok(viewer.set_cloud(
        &plain(&[0.0, 0.0, 1.0]),
        &JsValue::NULL,
        &plain(&[1.0, 2.0, 3.0]),
        &JsValue::NULL,
    ));
    assert_eq!(viewer.point_count(), 1);
    let err = viewer.set_colour_mode("superpixel").unwrap_err();
    assert!(message(err).contains("labels"));
}
