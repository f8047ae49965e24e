//! JPEG photos decoded straight to a working size, for the web page (issue 14: phone photos
//! within memory).
//!
//! A browser's `createImageBitmap` with a resize decodes the whole photo first (48 MB of RGBA for
//! 12 megapixels, 96 MB for 24). Here the DCT is decoded at 1/1, 1/2, 1/4 or 1/8 of the stored
//! size through a scaled inverse DCT (the `jpeg-decoder` crate: an 8×8 block becomes 8×8, 4×4,
//! 2×2 or 1×1 pixels), at the smallest of those scales that is not below the working size; that
//! image is resized to the exact working size with the library's one filter
//! ([`crate::image::resize`]) and turned upright by the EXIF orientation, as the browser's
//! `imageOrientation: 'from-image'` does. No image at the stored size is ever made.
//!
//! Colours are the file's YCbCr turned into RGB without colour management (the ICC profile is
//! ignored), as the page's `colorSpaceConversion: 'none'`. The decoder refuses what it does not
//! support (CMYK and YCCK, arithmetic coding, 12- and 16-bit samples, lossless and hierarchical
//! files) with [`Error::Decode`]; the page then lets the browser decode the file as before.

use crate::error::{Error, Result};
use crate::image::{
    Frame, LoadedImage, apply_orientation, check_jpeg_complete, frame_from_rgb_image, read_exif,
    resize_rgb, working_size,
};

/// A JPEG decoded at a working size.
#[derive(Clone, Debug)]
pub struct ScaledJpeg {
    /// Upright pixels at the working size for the `max_side` asked for (see
    /// [`crate::image::working_size`]), with the EXIF facts ([`LoadedImage::exif`]).
    pub image: LoadedImage,
    /// Upright size of the photo itself (after the EXIF orientation), `(width, height)` in pixels:
    /// what the browser reports as the image's natural size.
    pub full_size: (usize, usize),
    /// The DCT scale it was decoded at: 1/`denominator` of the stored size, with `denominator`
    /// 1, 2, 4 or 8.
    pub denominator: usize,
}

impl ScaledJpeg {
    /// The frame at the working size.
    pub fn frame(&self) -> &Frame {
        &self.image.frame
    }
}

/// Decodes JPEG `bytes` upright at the working size for `max_side` (the long side, in pixels,
/// at most `max_side`; a smaller photo keeps its size), reading its EXIF block too.
///
/// The output is deterministic and the same natively and in wasm (the crate's SIMD IDCT is
/// disabled).
///
/// Memory (the wasm memory of the worker that runs it): the file's bytes, the planes and the RGB
/// image at the decoded scale (about 4.5 bytes per decoded pixel: 14 MB for a 12 MP photo
/// decoded at 1/2, 2016 × 1512), and the resize's floating-point intermediate (the decoded width
/// × the working height × 12 bytes: 19 MB there). A **progressive** JPEG costs more: its scans
/// refine the same coefficients one after the other, so the decoder keeps every DCT coefficient
/// of the whole image, at full size whatever the scale, 2 bytes each: 3 bytes per photo pixel
/// with 4:2:0 chroma (36 MB for 12 MP, 72 MB for 24 MP), 6 bytes with 4:4:4 (72 and 144 MB).
/// Measured, the worker's wasm memory after one decode to a long side of 1024 (the photos of
/// the page's benchmark, quality 92): 12 MP 40 MiB baseline, 74 MiB progressive 4:2:0, 114 MiB
/// progressive 4:4:4; 24 MP 26, 94 and 166 MiB. The browser's decode of the same photo makes a
/// full-size RGBA image (4 bytes per pixel, 46 and 92 MiB) and more; the page runs this decode in
/// a worker of its own, so the memory is handed back as soon as the photo is decoded.
///
/// Errors: [`Error::Decode`] for bytes that are not a complete JPEG (no end-of-image marker: the
/// decoder would fill the missing part with grey), a corrupt one, or one the decoder does not
/// support (module comment); [`Error::InvalidParameter`] for `max_side` 0.
pub fn decode_jpeg_scaled(bytes: &[u8], max_side: usize) -> Result<ScaledJpeg> {
    if max_side == 0 {
        return Err(Error::InvalidParameter(
            "the working size must be at least 1 pixel".to_string(),
        ));
    }
    if !bytes.starts_with(&[0xFF, 0xD8]) {
        return Err(Error::Decode("not a JPEG file".to_string()));
    }
    check_jpeg_complete(bytes)?;
    let mut decoder = jpeg_decoder::Decoder::new(bytes);
    decoder.read_info().map_err(decode_error)?;
    let info = decoder
        .info()
        .ok_or_else(|| Error::Decode("JPEG without a frame header".to_string()))?;
    if info.coding_process == jpeg_decoder::CodingProcess::Lossless {
        // No DCT to scale: left to the browser, as before.
        return Err(Error::Decode(
            "lossless JPEGs are not supported by the scaled decoder".to_string(),
        ));
    }
    let channels = match info.pixel_format {
        jpeg_decoder::PixelFormat::RGB24 => 3,
        jpeg_decoder::PixelFormat::L8 => 1,
        other => {
            return Err(Error::Decode(format!(
                "{other:?} JPEGs are not supported by the scaled decoder"
            )));
        }
    };
    let stored = (usize::from(info.width), usize::from(info.height));
    if stored.0 == 0 || stored.1 == 0 {
        return Err(Error::Decode("JPEG of zero size".to_string()));
    }
    let (orientation, exif) = read_exif(bytes);
    let transposed = (5..=8).contains(&orientation);
    let swap = |(a, b): (usize, usize)| if transposed { (b, a) } else { (a, b) };
    let full_size = swap(stored);
    // The target in the stored orientation: the upright working size turned back.
    let target = swap(working_size(full_size.0, full_size.1, max_side));
    let denominator = scale_denominator(stored, target);
    let request = |side: usize| u16::try_from(side.div_ceil(denominator)).unwrap_or(u16::MAX);
    decoder
        .scale(request(stored.0), request(stored.1))
        .map_err(decode_error)?;
    let pixels = decoder.decode().map_err(decode_error)?;
    // The decoder's output size: what `scale` chose, read back after the decode.
    let info = decoder
        .info()
        .ok_or_else(|| Error::Decode("JPEG without a frame header".to_string()))?;
    let (dw, dh) = (u32::from(info.width), u32::from(info.height));
    let rgb = if channels == 3 {
        pixels
    } else {
        pixels.iter().flat_map(|&l| [l, l, l]).collect()
    };
    let decoded = image::RgbImage::from_raw(dw, dh, rgb).ok_or_else(|| {
        Error::Decode(format!(
            "the decoder gave too few pixels for {dw}×{dh} at 1/{denominator}"
        ))
    })?;
    let resized = resize_rgb(decoded, target.0, target.1);
    let upright =
        apply_orientation(image::DynamicImage::ImageRgb8(resized), orientation).into_rgb8();
    Ok(ScaledJpeg {
        image: LoadedImage {
            frame: frame_from_rgb_image(&upright)?,
            exif,
        },
        full_size,
        denominator,
    })
}

/// The largest of 8, 4, 2 at which the DCT-scaled size (`⌈side / d⌉` each way, how the decoder
/// rounds) of a `stored` image still covers `target` on both sides; 1 when none does.
fn scale_denominator(stored: (usize, usize), target: (usize, usize)) -> usize {
    [8, 4, 2]
        .into_iter()
        .find(|&d| stored.0.div_ceil(d) >= target.0 && stored.1.div_ceil(d) >= target.1)
        .unwrap_or(1)
}

fn decode_error(e: jpeg_decoder::Error) -> Error {
    Error::Decode(e.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::Grid;
    use crate::image::{ExifInfo, decode_image, resize};

    /// A smooth, non-symmetric colour image (gradients and slow waves), `w × h`.
    fn smooth(w: usize, h: usize) -> Frame {
        Grid::from_fn(w, h, |x, y| {
            let (u, v) = (x as f32 / w as f32, y as f32 / h as f32);
            let wave = (6.0 * u + 2.0 * v).sin() * 0.5 + 0.5;
            [
                (40.0 + 180.0 * u) as u8,
                (30.0 + 190.0 * v * v) as u8,
                (20.0 + 200.0 * wave) as u8,
            ]
        })
    }

    /// `frame` as a baseline JPEG (the `image` crate's encoder, 4:2:0 chroma).
    fn jpeg(frame: &Frame, quality: u8) -> Vec<u8> {
        let bytes: Vec<u8> = frame.data().iter().flatten().copied().collect();
        let mut out = Vec::new();
        image::codecs::jpeg::JpegEncoder::new_with_quality(&mut out, quality)
            .encode(
                &bytes,
                frame.width() as u32,
                frame.height() as u32,
                image::ExtendedColorType::Rgb8,
            )
            .unwrap();
        out
    }

    /// `jpeg` with an EXIF block (APP1 right after SOI) holding orientation `o` in IFD0.
    fn with_orientation(jpeg: &[u8], o: u16) -> Vec<u8> {
        let mut tiff = b"II*\0\x08\0\0\0".to_vec();
        tiff.extend_from_slice(&1u16.to_le_bytes()); // one entry
        tiff.extend_from_slice(&0x0112u16.to_le_bytes()); // Orientation
        tiff.extend_from_slice(&3u16.to_le_bytes()); // SHORT
        tiff.extend_from_slice(&1u32.to_le_bytes());
        tiff.extend_from_slice(&o.to_le_bytes());
        tiff.extend_from_slice(&[0, 0]);
        tiff.extend_from_slice(&0u32.to_le_bytes()); // no next IFD
        let mut payload = b"Exif\0\0".to_vec();
        payload.extend_from_slice(&tiff);
        let len = (payload.len() + 2) as u16;
        let mut out = jpeg[..2].to_vec();
        out.extend_from_slice(&[0xFF, 0xE1]);
        out.extend_from_slice(&len.to_be_bytes());
        out.extend_from_slice(&payload);
        out.extend_from_slice(&jpeg[2..]);
        out
    }

    /// Mean absolute difference per channel, in units of 1/255.
    fn mean_abs_diff(a: &Frame, b: &Frame) -> f64 {
        assert_eq!(a.size(), b.size());
        let sum: u64 = a
            .data()
            .iter()
            .zip(b.data())
            .flat_map(|(p, q)| (0..3).map(move |k| u64::from(p[k].abs_diff(q[k]))))
            .sum();
        sum as f64 / (3 * a.len()) as f64
    }

    /// Stored pixel shown at upright `(x, y)` for EXIF orientation `o`, for a stored `sw × sh`
    /// image (the EXIF definitions: e.g. 6, row 0 is the right side, column 0 the top).
    fn stored_at(o: u16, x: usize, y: usize, sw: usize, sh: usize) -> (usize, usize) {
        match o {
            2 => (sw - 1 - x, y),
            3 => (sw - 1 - x, sh - 1 - y),
            4 => (x, sh - 1 - y),
            5 => (y, x),
            6 => (y, sh - 1 - x),
            7 => (sw - 1 - y, sh - 1 - x),
            8 => (sw - 1 - y, x),
            _ => (x, y),
        }
    }

    #[test]
    fn scaled_decode_matches_a_full_decode_resized() {
        // Sides that are not multiples of the 16-pixel MCU; each working size picks a scale.
        let photo = jpeg(&smooth(803, 605), 92);
        let full = decode_image(&photo).unwrap().frame;
        for (max_side, denominator) in [(100, 8), (200, 4), (300, 2), (600, 1), (803, 1)] {
            let scaled = decode_jpeg_scaled(&photo, max_side).unwrap();
            assert_eq!(scaled.denominator, denominator, "max side {max_side}");
            assert_eq!(scaled.full_size, (803, 605));
            let size = working_size(803, 605, max_side);
            assert_eq!(scaled.frame().size(), size);
            let reference = resize(&full, size.0, size.1);
            let mad = mean_abs_diff(scaled.frame(), &reference);
            assert!(mad < 2.0, "max side {max_side}: mean |Δ| {mad:.3}/255");
        }
    }

    #[test]
    fn every_exif_orientation_turns_the_photo_upright() {
        let (sw, sh) = (160, 96);
        let plain = jpeg(&smooth(sw, sh), 90);
        let stored = decode_jpeg_scaled(&plain, 64).unwrap();
        let (tw, th) = stored.frame().size();
        assert_eq!((tw, th), (64, 38));
        for o in 1..=8 {
            let turned = decode_jpeg_scaled(&with_orientation(&plain, o), 64).unwrap();
            let upright = turned.frame();
            let expected_size = if o >= 5 { (th, tw) } else { (tw, th) };
            assert_eq!(upright.size(), expected_size, "orientation {o}");
            let full = if o >= 5 { (sh, sw) } else { (sw, sh) };
            assert_eq!(turned.full_size, full, "orientation {o}");
            for y in 0..upright.height() {
                for x in 0..upright.width() {
                    let (sx, sy) = stored_at(o, x, y, tw, th);
                    assert_eq!(
                        upright.get(x, y),
                        stored.frame().get(sx, sy),
                        "{o}: ({x}, {y})"
                    );
                }
            }
            // The same orientation as the library's full decode (image::decode_image).
            let reference = decode_image(&with_orientation(&plain, o)).unwrap().frame;
            let reference = resize(&reference, upright.width(), upright.height());
            let mad = mean_abs_diff(upright, &reference);
            assert!(mad < 2.0, "orientation {o}: mean |Δ| {mad:.3}/255");
        }
    }

    #[test]
    fn exif_focal_length_and_grey_photos_come_through() {
        let grey = Grid::from_fn(64, 48, |x, y| {
            let l = (2 * x + y) as u8;
            [l, l, l]
        });
        let bytes: Vec<u8> = grey.data().iter().map(|p| p[0]).collect();
        let mut out = Vec::new();
        image::codecs::jpeg::JpegEncoder::new_with_quality(&mut out, 95)
            .encode(&bytes, 64, 48, image::ExtendedColorType::L8)
            .unwrap();
        let decoded = decode_jpeg_scaled(&out, 1024).unwrap();
        assert_eq!(decoded.frame().size(), (64, 48));
        assert!(mean_abs_diff(decoded.frame(), &grey) < 1.0);
        assert!(
            decoded
                .frame()
                .data()
                .iter()
                .all(|p| p[0] == p[1] && p[1] == p[2])
        );
        assert_eq!(decoded.image.exif, ExifInfo::default());
    }

    #[test]
    fn the_same_bytes_decode_to_the_same_pixels() {
        let photo = jpeg(&smooth(300, 200), 85);
        let a = decode_jpeg_scaled(&photo, 120).unwrap();
        let b = decode_jpeg_scaled(&photo, 120).unwrap();
        assert_eq!(a.frame(), b.frame());
    }

    #[test]
    fn bad_input_is_a_decode_error() {
        let photo = jpeg(&smooth(64, 64), 90);
        let cases: [&[u8]; 4] = [
            b"",
            b"\x89PNG\r\n\x1a\n",
            &photo[..photo.len() / 2],
            &photo[..4],
        ];
        for bytes in cases {
            assert!(matches!(
                decode_jpeg_scaled(bytes, 32),
                Err(Error::Decode(_))
            ));
        }
        // A complete marker structure with a corrupt frame header.
        let mut broken = photo.clone();
        let sof = broken.windows(2).position(|w| w == [0xFF, 0xC0]).unwrap();
        broken[sof + 5..sof + 9].fill(0);
        assert!(matches!(
            decode_jpeg_scaled(&broken, 32),
            Err(Error::Decode(_))
        ));
        assert!(matches!(
            decode_jpeg_scaled(&photo, 0),
            Err(Error::InvalidParameter(_))
        ));
    }

    #[test]
    fn the_scale_is_the_smallest_that_covers_the_target() {
        assert_eq!(scale_denominator((4032, 3024), (1024, 768)), 2);
        assert_eq!(scale_denominator((6000, 4000), (1024, 683)), 4);
        assert_eq!(scale_denominator((8192, 8192), (1024, 1024)), 8);
        assert_eq!(scale_denominator((1024, 436), (1024, 436)), 1);
        // 2017 / 2 rounds up to 1009: still enough for 1008.
        assert_eq!(scale_denominator((2017, 1513), (1009, 757)), 2);
    }
}
