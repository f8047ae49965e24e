//! Browser tests of the wasm API (`src/web`), run headless in Chromium by ./check.sh through
//! wasm-bindgen-test-runner (browser flags: `webdriver.json`).
#![cfg(target_arch = "wasm32")]
// Tests make no results: the platform's maths functions are fine here (clippy.toml).
#![allow(clippy::disallowed_methods)]

use superpixel_soup::Grid;
use superpixel_soup::image::{decode_image, encode_png};
use superpixel_soup::web::{compute_flow, decode_image_info};
use wasm_bindgen::JsValue;
use wasm_bindgen_test::{wasm_bindgen_test, wasm_bindgen_test_configure};

wasm_bindgen_test_configure!(run_in_browser);

/// A 7×5 frame whose every pixel is different, so a transposed or shifted decode shows.
fn test_png() -> (superpixel_soup::image::Frame, Vec<u8>) {
    let frame = Grid::from_fn(7, 5, |x, y| [(x * 30) as u8, (y * 50) as u8, (x * y) as u8]);
    let png = encode_png(&frame).unwrap();
    (frame, png)
}

#[wasm_bindgen_test]
fn decode_image_info_reports_png_size() {
    let (_, png) = test_png();
    let info = decode_image_info(&png).unwrap();
    assert_eq!((info.width(), info.height()), (7, 5));
    assert_eq!(info.focal_35mm(), None);
    assert_eq!(info.exif_warning(), None);
}

#[wasm_bindgen_test]
fn png_pixels_survive_a_round_trip_in_wasm() {
    let (frame, png) = test_png();
    let decoded = decode_image(&png).unwrap().frame;
    assert_eq!(decoded.size(), (7, 5));
    assert_eq!(decoded.data(), frame.data());
}

#[wasm_bindgen_test]
fn truncated_png_gives_a_readable_error() {
    let (_, png) = test_png();
    let err = decode_image_info(&png[..png.len() / 2]).unwrap_err();
    let message = js_sys::Error::from(JsValue::from(err)).message();
    assert!(
        String::from(message).starts_with("cannot decode image"),
        "unexpected error message"
    );
}

#[wasm_bindgen_test]
fn non_image_bytes_give_a_readable_error() {
    let err = decode_image_info(b"hello, this is not an image").unwrap_err();
    let message = String::from(js_sys::Error::from(JsValue::from(err)).message());
    assert!(message.contains("not a PNG or JPEG"), "got: {message}");
}

/// RGBA bytes of a `w × h` sine texture moved right by `shift` pixels.
fn texture_rgba(w: usize, h: usize, shift: f32) -> Vec<u8> {
    (0..w * h)
        .flat_map(|i| {
            let (x, y) = ((i % w) as f32 - shift, (i / w) as f32);
            let g = 128.0 + 60.0 * (0.35 * x + 0.2 * y).sin() + 50.0 * (0.27 * y - 0.31 * x).cos();
            let g = g.clamp(0.0, 255.0) as u8;
            [g, g, g, 255]
        })
        .collect()
}

#[wasm_bindgen_test]
fn compute_flow_recovers_a_shift_in_wasm() {
    let (w, h) = (64, 48);
    let result = compute_flow(
        &texture_rgba(w, h, 0.0),
        &texture_rgba(w, h, 2.0),
        w as u32,
        h as u32,
        "medium",
        None,
    )
    .unwrap_or_else(|e| {
        panic!(
            "{}",
            String::from(js_sys::Error::from(JsValue::from(e)).message())
        )
    });
    assert_eq!((result.width(), result.height()), (64, 48));
    let forward = result.forward();
    assert_eq!(
        (forward.len(), result.backward().len()),
        (2 * w * h, 2 * w * h)
    );
    let centre = 2 * (24 * w + 32);
    assert!(
        (forward[centre] - 2.0).abs() < 0.3 && forward[centre + 1].abs() < 0.3,
        "flow at the centre: {:?}",
        &forward[centre..centre + 2]
    );
    assert_eq!(result.reliable().len(), w * h);
    assert_eq!(result.forward_picture().len(), 4 * w * h);
}

#[wasm_bindgen_test]
fn compute_flow_rejects_bad_frames_with_readable_errors() {
    let frame = texture_rgba(64, 48, 0.0);
    let message =
        |e: wasm_bindgen::JsError| String::from(js_sys::Error::from(JsValue::from(e)).message());
    let err = compute_flow(&frame[..100], &frame, 64, 48, "medium", None)
        .err()
        .map(message);
    assert!(
        err.as_deref().is_some_and(|m| m.contains("RGBA frame")),
        "{err:?}"
    );
    let err = compute_flow(&frame, &frame, 64, 48, "slow", None)
        .err()
        .map(message);
    assert!(
        err.as_deref()
            .is_some_and(|m| m.contains("unknown flow preset")),
        "{err:?}"
    );
}
