//! Browser tests of the wasm API (`src/web`), run headless in Chromium by ./check.sh through
//! wasm-bindgen-test-runner (browser flags: `webdriver.json`).
#![cfg(target_arch = "wasm32")]

use superpixel_soup::Grid;
use superpixel_soup::image::{decode_image, encode_png};
use superpixel_soup::web::{decode_image_info, version};
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
fn version_is_the_crate_version() {
    assert_eq!(version(), env!("CARGO_PKG_VERSION"));
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
