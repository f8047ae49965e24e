#![cfg(not(target_arch = "wasm32"))]
//! The output files of a reconstruction (`superpixel_soup::export`, used by the CLI and the web
//! page): each decodes with the project's own readers, at the documented resolution, with the
//! reconstruction's values.

use superpixel_soup::camera::IntrinsicsSource;
use superpixel_soup::export::{ExportFile, encode};
use superpixel_soup::flow::FlowParams;
use superpixel_soup::formats::ply::Encoding;
use superpixel_soup::formats::{flo, pfm, ply, png16};
use superpixel_soup::image::decode_image;
use superpixel_soup::input::prepare_pair;
use superpixel_soup::pipeline::Stage;
use superpixel_soup::synth::{SceneKind, render};
use superpixel_soup::{FlowInput, Params, reconstruct};

#[test]
fn every_file_decodes_at_its_resolution_with_the_reconstruction_values() {
    // 240×102 input reconstructed at a working size of 160×68.
    let scene = render(SceneKind::Street, 240, 102).unwrap();
    let pair = prepare_pair(
        scene.frame1.into(),
        scene.frame2.into(),
        Some(scene.intrinsics),
        160,
    )
    .unwrap();
    assert_eq!(pair.frame1.size(), (160, 68));
    let mut params = Params::default();
    params.superpixels.count = 200;
    let rec = reconstruct(
        &pair,
        FlowInput::Compute(FlowParams::default()),
        &params,
        &mut |_, _| {},
    )
    .unwrap();
    let file = |f| encode(&rec, f, Encoding::BinaryLittleEndian).unwrap();

    let depth = pfm::decode(&file(ExportFile::DepthPfm)).unwrap();
    assert_eq!(depth.size(), (240, 102));
    let depth16 = png16::decode_depth(&file(ExportFile::DepthPng16)).unwrap();
    assert_eq!(depth16.size(), (240, 102));
    // 16 bits from 0 to the deepest value: each depth within half a step (plus float rounding).
    let deepest = depth
        .data()
        .iter()
        .filter(|z| z.is_finite() && **z > 0.0)
        .fold(0.0f32, |m, &z| m.max(z));
    let half_step = deepest / 65535.0 / 2.0;
    let mut compared = 0;
    for (a, b) in depth.data().iter().zip(depth16.data()) {
        assert_eq!(a.is_finite() && *a > 0.0, b.is_finite(), "{a} vs {b}");
        if b.is_finite() {
            assert!((a - b).abs() <= half_step * 1.01 + 1e-6 * a, "{a} vs {b}");
            compared += 1;
        }
    }
    assert!(compared > 240 * 102 / 2, "{compared} known depths");

    let picture = decode_image(&file(ExportFile::DepthPicture)).unwrap();
    assert_eq!(picture.frame.size(), (240, 102));

    let cloud1 = ply::decode(&file(ExportFile::Frame1Ply)).unwrap();
    let cloud2 = ply::decode(&file(ExportFile::Frame2Ply)).unwrap();
    let (expected1, _) = rec.clouds();
    assert_eq!(cloud1, expected1);
    assert_eq!(cloud2.positions.len(), expected1.positions.len());
    let ascii = encode(&rec, ExportFile::Frame1Ply, Encoding::Ascii).unwrap();
    assert!(ascii.starts_with(b"ply\nformat ascii 1.0\n"));
    // Each vertex carries its superpixel's scale confidence (report `confidence`), in both
    // encodings and both frames: read back, pixel by pixel of frame 1 with a point.
    let expected: Vec<f32> = rec
        .superpixels
        .labels
        .data()
        .iter()
        .zip(rec.depth.data())
        .filter(|(_, z)| z.is_finite() && **z > 0.0)
        .map(|(&label, _)| rec.report.confidence[label as usize] as f32)
        .collect();
    assert_eq!(expected.len(), expected1.positions.len());
    for bytes in [
        file(ExportFile::Frame1Ply),
        file(ExportFile::Frame2Ply),
        ascii,
    ] {
        let confidence = ply::decode_confidence(&bytes).unwrap().unwrap();
        assert_eq!(confidence.len(), expected.len());
        for (a, b) in confidence.iter().zip(&expected) {
            assert!((a - b).abs() <= 1e-6, "{a} vs {b}");
        }
    }
    assert!(expected.iter().all(|c| (0.0..=1.0).contains(c)));

    let flow = flo::decode(&file(ExportFile::Flow)).unwrap();
    assert_eq!(flow.size(), (240, 102));
    // Vectors are scaled to the input resolution (×1.5): compare a known one with the working flow.
    let (fw, fi) = (*rec.flow.get(80, 34), *flow.get(120, 51));
    assert!((fi[0] - 1.5 * fw[0]).abs() < 0.5, "{fi:?} vs {fw:?}");
    assert!(
        fw[0].abs() > 0.3,
        "the street's flow at the centre is not zero: {fw:?}"
    );

    let (labels, _) = png16::decode(&file(ExportFile::Labels)).unwrap();
    assert_eq!(labels.size(), (160, 68));
    assert_eq!(
        *labels.get(10, 10) as u32,
        *rec.superpixels.labels.get(10, 10)
    );

    let report: serde_json::Value = serde_json::from_slice(&file(ExportFile::Report)).unwrap();
    assert_eq!(report["input_size"], serde_json::json!([240, 102]));
    assert_eq!(report["working_size"], serde_json::json!([160, 68]));
    assert_eq!(report["camera"]["source"], "user");
    assert_eq!(rec.report.camera.source, IntrinsicsSource::User);
    assert_eq!(
        report["timings_ms"].as_array().unwrap().len(),
        Stage::ALL.len()
    );
}
