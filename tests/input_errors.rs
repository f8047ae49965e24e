#![cfg(not(target_arch = "wasm32"))]
//! Bad input at the library's front door: every case gives a clear typed error (or, for a broken
//! EXIF block, a readable warning while the image still loads), never a panic.

use std::path::PathBuf;

use superpixel_soup::Error;
use superpixel_soup::camera::IntrinsicsSource;
use superpixel_soup::grid::Grid;
use superpixel_soup::image::{Frame, decode_image, encode_png, read_exif_info, read_image_file};
use superpixel_soup::input::prepare_pair;

fn temp_path(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("soup-input-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn textured(w: usize, h: usize) -> Frame {
    Grid::from_fn(w, h, |x, y| {
        [
            (x * 7 % 256) as u8,
            (y * 5 % 256) as u8,
            ((x ^ y) % 256) as u8,
        ]
    })
}

/// A baseline JPEG of `frame` with `app1` (an `Exif\0\0…` payload) inserted right after SOI.
fn jpeg_with_app1(frame: &Frame, app1: Option<&[u8]>) -> Vec<u8> {
    let rgb: Vec<u8> = frame.data().iter().flatten().copied().collect();
    let mut jpeg = Vec::new();
    image::codecs::jpeg::JpegEncoder::new_with_quality(&mut jpeg, 95)
        .encode(
            &rgb,
            frame.width() as u32,
            frame.height() as u32,
            image::ExtendedColorType::Rgb8,
        )
        .unwrap();
    let Some(payload) = app1 else { return jpeg };
    let mut out = jpeg[..2].to_vec();
    out.extend_from_slice(&[0xFF, 0xE1]);
    out.extend_from_slice(&((payload.len() + 2) as u16).to_be_bytes());
    out.extend_from_slice(payload);
    out.extend_from_slice(&jpeg[2..]);
    out
}

/// An EXIF block (TIFF, little-endian) with an orientation and a 35 mm focal length.
fn exif_payload(orientation: u16, focal_35mm: u16) -> Vec<u8> {
    let fields = [
        exif::Field {
            tag: exif::Tag::Orientation,
            ifd_num: exif::In::PRIMARY,
            value: exif::Value::Short(vec![orientation]),
        },
        exif::Field {
            tag: exif::Tag::FocalLengthIn35mmFilm,
            ifd_num: exif::In::PRIMARY,
            value: exif::Value::Short(vec![focal_35mm]),
        },
    ];
    let mut writer = exif::experimental::Writer::new();
    for f in &fields {
        writer.push_field(f);
    }
    let mut tiff = std::io::Cursor::new(Vec::new());
    writer.write(&mut tiff, true).unwrap();
    let mut payload = b"Exif\0\0".to_vec();
    payload.extend_from_slice(&tiff.into_inner());
    payload
}

#[test]
fn missing_file_names_the_path() {
    let path = temp_path("does-not-exist.png");
    let err = read_image_file(&path).unwrap_err();
    assert!(matches!(err, Error::Io { .. }));
    assert!(err.to_string().contains("does-not-exist.png"), "{err}");
}

#[test]
fn non_image_file_is_a_decode_error_naming_the_file() {
    let path = temp_path("notes.png");
    std::fs::write(&path, "these are not pixels").unwrap();
    let err = read_image_file(&path).unwrap_err();
    assert!(matches!(err, Error::Decode(_)));
    assert!(err.to_string().contains("notes.png"), "{err}");
}

#[test]
fn truncated_png_and_jpeg_are_decode_errors() {
    let png = encode_png(&textured(64, 48)).unwrap();
    for cut in [8, 40, png.len() / 2, png.len() - 13] {
        assert!(
            matches!(decode_image(&png[..cut]), Err(Error::Decode(_))),
            "cut at {cut}"
        );
    }
    let jpeg = jpeg_with_app1(&textured(64, 48), None);
    assert!(matches!(
        decode_image(&jpeg[..jpeg.len() / 2]),
        Err(Error::Decode(_))
    ));
}

#[test]
fn mismatched_sizes_and_tiny_images_are_refused() {
    let a = decode_image(&encode_png(&textured(64, 48)).unwrap()).unwrap();
    let b = decode_image(&encode_png(&textured(48, 64)).unwrap()).unwrap();
    let err = prepare_pair(a.clone(), b, None, 1024).unwrap_err();
    assert!(
        err.to_string().contains("64×48") && err.to_string().contains("48×64"),
        "{err}"
    );
    let tiny = decode_image(&encode_png(&textured(1, 1)).unwrap()).unwrap();
    let err = prepare_pair(tiny.clone(), tiny, None, 1024).unwrap_err();
    assert!(
        matches!(
            err,
            Error::TooSmall {
                width: 1,
                height: 1,
                ..
            }
        ),
        "{err}"
    );
}

#[test]
fn unreadable_exif_loads_the_image_with_a_warning() {
    let frame = textured(80, 60);
    let broken = jpeg_with_app1(&frame, Some(b"Exif\0\0II*\0\xff\xff\xff\x7fgarbage"));
    let loaded = decode_image(&broken).unwrap();
    assert_eq!(loaded.frame.size(), (80, 60));
    assert_eq!(loaded.exif.focal_35mm, None);
    let warning = loaded.exif.warning.clone().unwrap();
    assert!(warning.contains("EXIF"), "{warning}");
    assert_eq!(read_exif_info(&broken), loaded.exif);
    let pair = prepare_pair(loaded.clone(), loaded, None, 1024).unwrap();
    assert_eq!(pair.camera.source, IntrinsicsSource::Default);
    assert!(pair.notes.iter().any(|n| n.contains("EXIF")));
}

#[test]
fn exif_focal_length_and_orientation_are_applied() {
    // Stored 80×60, orientation 6 (rotate 90° clockwise to view), 26 mm equivalent.
    let jpeg = jpeg_with_app1(&textured(80, 60), Some(&exif_payload(6, 26)));
    let loaded = decode_image(&jpeg).unwrap();
    assert_eq!(loaded.frame.size(), (60, 80));
    assert_eq!(loaded.exif.focal_35mm, Some(26.0));
    // The page decodes pixels with the browser and reads only the EXIF block: the same facts.
    assert_eq!(read_exif_info(&jpeg), loaded.exif);
    let pair = prepare_pair(loaded.clone(), loaded, None, 1024).unwrap();
    assert_eq!(pair.camera.source, IntrinsicsSource::Exif);
    assert!((pair.camera.intrinsics.fx - 26.0 * 80.0 / 36.0).abs() < 1e-9);
}
