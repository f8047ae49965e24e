//! Browser tests of `computeSuperpixels` (src/web/superpixels.rs), run headless in Chromium by
//! ./check.sh through wasm-bindgen-test-runner.
#![cfg(target_arch = "wasm32")]

use superpixel_soup::web::superpixels::compute_superpixels;
use wasm_bindgen::{JsError, JsValue};
use wasm_bindgen_test::{wasm_bindgen_test, wasm_bindgen_test_configure};

wasm_bindgen_test_configure!(run_in_browser);

const W: usize = 96;
const H: usize = 64;

/// Colour of the block a pixel lies in: four blocks split at x = 40 and y = 28.
fn block(x: usize, y: usize) -> [u8; 3] {
    match (x < 40, y < 28) {
        (true, true) => [220, 40, 40],
        (false, true) => [40, 200, 60],
        (true, false) => [40, 60, 220],
        (false, false) => [230, 230, 60],
    }
}

/// RGBA bytes of the four blocks with a little texture (±6 grey levels).
fn blocks_rgba() -> Vec<u8> {
    (0..W * H)
        .flat_map(|i| {
            let (x, y) = (i % W, i / W);
            let texture = ((x * 7 + y * 13) % 13) as u8;
            let [r, g, b] = block(x, y).map(|c| c - 6 + texture);
            [r, g, b, 255]
        })
        .collect()
}

fn message(e: JsError) -> String {
    String::from(js_sys::Error::from(JsValue::from(e)).message())
}

#[wasm_bindgen_test]
fn compute_superpixels_segments_the_blocks() {
    let result = compute_superpixels(&blocks_rgba(), W as u32, H as u32, 24, 10.0)
        .unwrap_or_else(|e| panic!("{}", message(e)));
    assert_eq!((result.width(), result.height()), (W as u32, H as u32));
    let count = result.count() as usize;
    assert!((20..=28).contains(&count), "{count} superpixels for 24");
    let labels = result.labels();
    assert_eq!(labels.len(), W * H);
    // Every label is used, the sizes add up, and no superpixel straddles two blocks.
    let sizes = result.sizes();
    assert_eq!(sizes.len(), count);
    for (label, &size) in sizes.iter().enumerate() {
        let pixels: Vec<usize> = (0..W * H).filter(|&p| labels[p] == label as u32).collect();
        assert_eq!(pixels.len(), size as usize);
        let first = block(pixels[0] % W, pixels[0] / W);
        assert!(pixels.iter().all(|&p| block(p % W, p / W) == first));
    }
    assert_eq!(sizes.iter().sum::<u32>() as usize, W * H);
    let anchors = result.anchors();
    assert_eq!(anchors.len(), 2 * count);
    assert!(
        anchors
            .chunks(2)
            .all(|a| (0.0..W as f64).contains(&a[0]) && (0.0..H as f64).contains(&a[1]))
    );
    // Mean colours are the blocks' colours, give or take the texture.
    let means = result.mean_colours();
    assert_eq!(means.len(), 3 * count);
    for (label, mean) in means.chunks(3).enumerate() {
        let p = labels.iter().position(|&l| l == label as u32).unwrap();
        let expected = block(p % W, p / W);
        assert!(
            (0..3).all(|k| mean[k].abs_diff(expected[k]) <= 6),
            "{mean:?} vs {expected:?}"
        );
    }
    // Pictures: opaque RGBA; the overlay is yellow exactly where the right or lower neighbour
    // has another label, and the mean picture paints every pixel with its superpixel's mean.
    let (overlay, mean_picture) = (result.overlay_picture(), result.mean_picture());
    assert_eq!((overlay.len(), mean_picture.len()), (4 * W * H, 4 * W * H));
    let rgba = blocks_rgba();
    for p in 0..W * H {
        let (x, y) = (p % W, p / W);
        let edge =
            (x + 1 < W && labels[p + 1] != labels[p]) || (y + 1 < H && labels[p + W] != labels[p]);
        let expected = if edge {
            [255, 230, 0, 255]
        } else {
            [rgba[4 * p], rgba[4 * p + 1], rgba[4 * p + 2], 255]
        };
        assert_eq!(overlay[4 * p..4 * p + 4], expected, "overlay at ({x}, {y})");
        let l = labels[p] as usize;
        assert_eq!(
            mean_picture[4 * p..4 * p + 4],
            [means[3 * l], means[3 * l + 1], means[3 * l + 2], 255]
        );
    }
}

#[wasm_bindgen_test]
fn compute_superpixels_rejects_bad_input_with_readable_errors() {
    let rgba = blocks_rgba();
    for (bytes, n, compactness, expected) in [
        (&rgba[..100], 24, 10.0, "RGBA frame"),
        (&rgba[..], 0, 10.0, "superpixel count"),
        (&rgba[..], 5000, 10.0, "superpixel count"),
        (&rgba[..], 24, -1.0, "compactness"),
    ] {
        let err = compute_superpixels(bytes, W as u32, H as u32, n, compactness)
            .err()
            .map(message);
        assert!(
            err.as_deref().is_some_and(|m| m.contains(expected)),
            "{err:?}"
        );
    }
}
