//! Colour frames: decoding PNG/JPEG (with EXIF orientation and focal length), resizing,
//! and the colour spaces later stages work in (grey, CIELAB).

use crate::error::{Error, Result};
use crate::grid::Grid;
use crate::numeric::pow_f32;

/// An 8-bit sRGB colour frame; element (u, v) is `[red, green, blue]`.
pub type Frame = Grid<[u8; 3]>;

/// What the EXIF block of a photo told us. In JSON (the web page's worker messages) the fields
/// are `focal35mm` and `warning`.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "camelCase", default)]
pub struct ExifInfo {
    /// 35 mm-equivalent focal length in millimetres (`FocalLengthIn35mmFilm`), when present and
    /// positive.
    pub focal_35mm: Option<f64>,
    /// Why EXIF could not be used although the file has some (corrupt block, unreadable tag).
    /// The image itself still loads; intrinsics then fall back to the default.
    pub warning: Option<String>,
}

/// A decoded image with the EXIF facts later stages need.
#[derive(Clone, Debug)]
pub struct LoadedImage {
    /// Pixels, already turned upright according to the EXIF orientation.
    pub frame: Frame,
    /// EXIF focal length and any problem reading it.
    pub exif: ExifInfo,
}

impl From<Frame> for LoadedImage {
    /// Pixels without metadata (no EXIF): a synthetic scene's frame, an evaluation case's.
    fn from(frame: Frame) -> Self {
        LoadedImage {
            frame,
            exif: ExifInfo::default(),
        }
    }
}

/// Decodes PNG or JPEG bytes into an upright RGB frame and reads its EXIF.
///
/// Errors: [`Error::Decode`] for anything that is not a complete PNG/JPEG (unknown format,
/// truncated data). A missing or broken EXIF block is not an error: see [`ExifInfo::warning`].
pub fn decode_image(bytes: &[u8]) -> Result<LoadedImage> {
    let format = image::guess_format(bytes)
        .map_err(|_| Error::Decode("not a PNG or JPEG file".to_string()))?;
    if !matches!(format, image::ImageFormat::Png | image::ImageFormat::Jpeg) {
        return Err(Error::Decode(format!(
            "{format:?} images are not supported; use PNG or JPEG"
        )));
    }
    if format == image::ImageFormat::Jpeg {
        check_jpeg_complete(bytes)?;
    }
    let decoded = image::load_from_memory_with_format(bytes, format)
        .map_err(|e| Error::Decode(e.to_string()))?;
    let (orientation, exif) = read_exif(bytes);
    let rgb = apply_orientation(decoded, orientation).to_rgb8();
    let frame = frame_from_rgb_image(&rgb)?;
    Ok(LoadedImage { frame, exif })
}

/// Reads a PNG/JPEG file from disk; see [`decode_image`].
pub fn read_image_file(path: &std::path::Path) -> Result<LoadedImage> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    decode_image(&bytes).map_err(|e| match e {
        Error::Decode(reason) => Error::Decode(format!("{}: {reason}", path.display())),
        other => other,
    })
}

/// Reads only the EXIF block of image file bytes (no pixel decoding), for callers whose pixels
/// come from elsewhere (the web page decodes with the browser). Never fails: a file without a
/// block, or of a kind that carries none (anything but JPEG, PNG, WebP, TIFF and AVIF), gives
/// [`ExifInfo::default`]; a broken block gives a [`warning`](ExifInfo::warning).
pub fn read_exif_info(bytes: &[u8]) -> ExifInfo {
    use image::ImageFormat::{Avif, Jpeg, Png, Tiff, WebP};
    match image::guess_format(bytes) {
        Ok(Jpeg | Png | WebP | Tiff | Avif) => read_exif(bytes).1,
        _ => ExifInfo::default(),
    }
}

/// A frame from RGBA bytes, row by row from the top (`4 · width · height` of them, as a canvas's
/// `getImageData` gives them); alpha is ignored. Errors: [`Error::InvalidParameter`] for any
/// other length.
pub fn frame_from_rgba(rgba: &[u8], width: usize, height: usize) -> Result<Frame> {
    let expected = width.checked_mul(height).and_then(|n| n.checked_mul(4));
    if expected != Some(rgba.len()) {
        return Err(Error::InvalidParameter(format!(
            "an RGBA frame of {width}×{height} pixels has {} bytes, got {}",
            4 * width as u128 * height as u128,
            rgba.len()
        )));
    }
    let pixels = rgba.chunks_exact(4).map(|p| [p[0], p[1], p[2]]).collect();
    Grid::from_vec(width, height, pixels)
}

/// Fails unless the JPEG's marker structure runs from SOI to EOI. The decoder itself fills a
/// truncated scan with grey instead of failing, which would hand garbage pixels to the pipeline.
pub(crate) fn check_jpeg_complete(bytes: &[u8]) -> Result<()> {
    let truncated = || Error::Decode("truncated JPEG (no end-of-image marker)".to_string());
    let mut i = 2; // after SOI
    loop {
        // Marker segments: FF xx, then a big-endian length that counts itself.
        while bytes.get(i) == Some(&0xFF) && bytes.get(i + 1) == Some(&0xFF) {
            i += 1; // fill bytes
        }
        let (Some(&0xFF), Some(&marker)) = (bytes.get(i), bytes.get(i + 1)) else {
            return Err(truncated());
        };
        if marker == 0xD9 {
            return Ok(());
        }
        let len = match (bytes.get(i + 2), bytes.get(i + 3)) {
            (Some(&hi), Some(&lo)) => u16::from_be_bytes([hi, lo]) as usize,
            _ => return Err(truncated()),
        };
        i += 2 + len;
        if marker == 0xDA {
            // Entropy-coded data: FF is stuffed as FF 00 and restart markers are FF D0–D7;
            // any other FF xx is the next marker.
            loop {
                match (bytes.get(i), bytes.get(i + 1)) {
                    (Some(&0xFF), Some(&next))
                        if next != 0x00 && !(0xD0..=0xD7).contains(&next) =>
                    {
                        break;
                    }
                    (Some(_), Some(_)) => i += 1,
                    _ => return Err(truncated()),
                }
            }
        }
    }
}

/// EXIF orientation (1–8, 1 = upright) and focal length. Never fails: problems land in the warning.
pub(crate) fn read_exif(bytes: &[u8]) -> (u32, ExifInfo) {
    let mut cursor = std::io::Cursor::new(bytes);
    let exif = match exif::Reader::new().read_from_container(&mut cursor) {
        Ok(exif) => exif,
        Err(exif::Error::NotFound(_)) => return (1, ExifInfo::default()),
        Err(e) => {
            return (
                1,
                ExifInfo {
                    focal_35mm: None,
                    warning: Some(format!(
                        "EXIF block unreadable ({e}); using default intrinsics"
                    )),
                },
            );
        }
    };
    let orientation = exif
        .get_field(exif::Tag::Orientation, exif::In::PRIMARY)
        .and_then(|f| f.value.get_uint(0))
        .filter(|o| (1..=8).contains(o))
        .unwrap_or(1);
    let focal_35mm = exif
        .get_field(exif::Tag::FocalLengthIn35mmFilm, exif::In::PRIMARY)
        .and_then(|f| f.value.get_uint(0))
        .map(f64::from)
        .filter(|f| *f > 0.0);
    (
        orientation,
        ExifInfo {
            focal_35mm,
            warning: None,
        },
    )
}

/// Turns an image upright for EXIF orientation `o` (1 = as stored).
pub(crate) fn apply_orientation(img: image::DynamicImage, o: u32) -> image::DynamicImage {
    match o {
        2 => img.fliph(),
        3 => img.rotate180(),
        4 => img.flipv(),
        5 => img.rotate90().fliph(),
        6 => img.rotate90(),
        7 => img.rotate270().fliph(),
        8 => img.rotate270(),
        _ => img,
    }
}

/// Encodes a frame as an 8-bit RGB PNG.
pub fn encode_png(frame: &Frame) -> Result<Vec<u8>> {
    let mut out = Vec::new();
    let mut encoder = png::Encoder::new(&mut out, frame.width() as u32, frame.height() as u32);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let bytes: Vec<u8> = frame.data().iter().flatten().copied().collect();
    let mut writer = encoder
        .write_header()
        .map_err(|e| Error::format("PNG", e.to_string()))?;
    writer
        .write_image_data(&bytes)
        .map_err(|e| Error::format("PNG", e.to_string()))?;
    writer
        .finish()
        .map_err(|e| Error::format("PNG", e.to_string()))?;
    Ok(out)
}

/// The largest size with the aspect ratio of `width × height` whose long side is at most
/// `max_side` (unchanged when already small enough). Sides are rounded to whole pixels, at least 1.
pub fn working_size(width: usize, height: usize, max_side: usize) -> (usize, usize) {
    let long = width.max(height);
    if long <= max_side || long == 0 {
        return (width, height);
    }
    let s = max_side as f64 / long as f64;
    let w = ((width as f64 * s).round() as usize).clamp(1, max_side);
    let h = ((height as f64 * s).round() as usize).clamp(1, max_side);
    (w, h)
}

/// Resizes a frame to `width × height` with an anti-aliased triangle filter
/// (its support widens with the downscale factor, so large photos do not alias).
pub fn resize(frame: &Frame, width: usize, height: usize) -> Frame {
    if frame.size() == (width, height) {
        return frame.clone();
    }
    let bytes: Vec<u8> = frame.data().iter().flatten().copied().collect();
    let Some(buffer) =
        image::RgbImage::from_raw(frame.width() as u32, frame.height() as u32, bytes)
    else {
        // from_raw only fails when the buffer is too short, which a Grid rules out.
        return frame.clone();
    };
    let out = resize_rgb(buffer, width, height);
    Grid::from_fn(width, height, |x, y| out.get_pixel(x as u32, y as u32).0)
}

/// [`resize`] of an `image` crate RGB buffer (the same filter), given back as it is when it
/// already has the size.
pub(crate) fn resize_rgb(img: image::RgbImage, width: usize, height: usize) -> image::RgbImage {
    if (img.width() as usize, img.height() as usize) == (width, height) {
        return img;
    }
    image::imageops::resize(
        &img,
        width as u32,
        height as u32,
        image::imageops::FilterType::Triangle,
    )
}

/// A frame of an `image` crate RGB buffer (a copy). Errors only when the buffer is shorter than
/// its size says, which the `image` crate rules out.
pub(crate) fn frame_from_rgb_image(img: &image::RgbImage) -> Result<Frame> {
    let pixels = img.pixels().map(|p| p.0).collect();
    Grid::from_vec(img.width() as usize, img.height() as usize, pixels)
}

/// Luma in [0, 1] (Rec. 601 weights on the gamma-encoded values, as OpenCV's grey conversion).
pub fn to_gray(frame: &Frame) -> Grid<f32> {
    frame.map(|&[r, g, b]| (0.299 * r as f32 + 0.587 * g as f32 + 0.114 * b as f32) / 255.0)
}

/// CIELAB (D65 white, sRGB input): L in [0, 100], a and b roughly in [−128, 127].
pub fn to_lab(frame: &Frame) -> Grid<[f32; 3]> {
    let lut = srgb_to_linear_table();
    frame.map(|&[r, g, b]| linear_rgb_to_lab(lut[r as usize], lut[g as usize], lut[b as usize]))
}

/// The same CIELAB values as [`to_lab`], stored as three planes `[L, a, b]` (structure of
/// arrays), each row-major like the frame (`y · width + x`): the layout for loops that run over
/// one channel of a row at a time.
pub fn to_lab_planes(frame: &Frame) -> [Vec<f32>; 3] {
    // Linear RGB by table look-ups first, then CIELAB in place: that loop is plain arithmetic and
    // vectorises.
    let lut = srgb_to_linear_table();
    let [mut l, mut a, mut b] = [0, 1, 2].map(|k| {
        frame
            .data()
            .iter()
            .map(|p| lut[p[k] as usize])
            .collect::<Vec<f32>>()
    });
    for ((l, a), b) in l.iter_mut().zip(&mut a).zip(&mut b) {
        [*l, *a, *b] = linear_rgb_to_lab(*l, *a, *b);
    }
    [l, a, b]
}

/// Linear light of each 8-bit sRGB value.
fn srgb_to_linear_table() -> [f32; 256] {
    std::array::from_fn(|c| srgb_to_linear(c as f32 / 255.0))
}

/// sRGB transfer function inverse: encoded value in [0, 1] to linear light.
fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        pow_f32((c + 0.055) / 1.055, 2.4)
    }
}

/// Linear sRGB (each in [0, 1]) to CIELAB with the D65 white point.
fn linear_rgb_to_lab(r: f32, g: f32, b: f32) -> [f32; 3] {
    let x = (0.412_456_4 * r + 0.357_576_1 * g + 0.180_437_5 * b) / 0.950_47;
    let y = 0.212_672_9 * r + 0.715_152_2 * g + 0.072_175 * b;
    let z = (0.019_333_9 * r + 0.119_192 * g + 0.950_304_1 * b) / 1.088_83;
    let f = |t: f32| {
        if t > 0.008_856 {
            cube_root(t)
        } else {
            7.787 * t + 16.0 / 116.0
        }
    };
    let (fx, fy, fz) = (f(x), f(y), f(z));
    [116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz)]
}

/// Cube root of a positive, normal `t` (within 3 ulp of `t.cbrt()` on CIELAB's range [0.0089, 2]).
/// Plain IEEE arithmetic, no library call: per-pixel loops vectorise, and native and wasm builds
/// agree bit for bit. The first guess divides the exponent by three (the bit trick of fdlibm's
/// `cbrtf`, within 4 %); two Halley steps each cube the relative error (4 % → 10⁻⁴ → rounding).
fn cube_root(t: f32) -> f32 {
    let halley = |y: f32| {
        let y3 = y * y * y;
        y * (y3 + 2.0 * t) / (2.0 * y3 + t)
    };
    halley(halley(f32::from_bits(t.to_bits() / 3 + 709_958_130)))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn checker(w: usize, h: usize) -> Frame {
        Grid::from_fn(w, h, |x, y| {
            if (x / 4 + y / 4) % 2 == 0 {
                [250, 20, 20]
            } else {
                [10, 200, 90]
            }
        })
    }

    #[test]
    fn png_round_trip_keeps_pixels() {
        let f = checker(37, 21);
        let loaded = decode_image(&encode_png(&f).unwrap()).unwrap();
        assert_eq!(loaded.frame, f);
        assert_eq!(loaded.exif, ExifInfo::default());
    }

    #[test]
    fn garbage_and_truncated_data_are_decode_errors() {
        assert!(matches!(
            decode_image(b"hello world"),
            Err(Error::Decode(_))
        ));
        let png = encode_png(&checker(64, 64)).unwrap();
        let truncated = &png[..png.len() / 2];
        assert!(matches!(decode_image(truncated), Err(Error::Decode(_))));
        assert!(matches!(decode_image(&[]), Err(Error::Decode(_))));
    }

    #[test]
    fn rgba_bytes_become_rgb_frames() {
        let rgba = [1, 2, 3, 255, 4, 5, 6, 0, 7, 8, 9, 9, 10, 11, 12, 128];
        let frame = frame_from_rgba(&rgba, 2, 2).unwrap();
        assert_eq!(
            frame.data(),
            &[[1, 2, 3], [4, 5, 6], [7, 8, 9], [10, 11, 12]]
        );
        let err = frame_from_rgba(&rgba[..12], 2, 2).unwrap_err();
        assert!(err.to_string().contains("has 16 bytes, got 12"), "{err}");
        assert!(frame_from_rgba(&[], usize::MAX, 2).is_err());
    }

    #[test]
    fn exif_of_a_png_without_one_is_empty() {
        let png = encode_png(&checker(8, 8)).unwrap();
        assert_eq!(read_exif_info(&png), ExifInfo::default());
        assert_eq!(read_exif_info(b"not an image"), ExifInfo::default());
        assert_eq!(
            read_exif_info(b"GIF89a\x01\x00\x01\x00"),
            ExifInfo::default()
        );
    }

    #[test]
    fn working_size_keeps_aspect_and_bounds_long_side() {
        assert_eq!(working_size(4032, 3024, 1024), (1024, 768));
        assert_eq!(working_size(3024, 4032, 1024), (768, 1024));
        assert_eq!(working_size(640, 480, 1024), (640, 480));
    }

    #[test]
    fn resize_averages_colours() {
        let small = resize(&checker(64, 64), 8, 8);
        assert_eq!(small.size(), (8, 8));
        // A 4-pixel checker seen through an 8× downscale is close to the mean colour.
        let [r, g, _] = *small.get(4, 4);
        assert!(
            (100..=160).contains(&r) && (80..=140).contains(&g),
            "{r} {g}"
        );
    }

    #[test]
    fn cube_root_matches_the_library_to_a_few_ulp() {
        // Every t that CIELAB's f(t) takes the cube root of, and beyond.
        let mut t = 0.008_856f32;
        while t < 2.0 {
            let (fast, exact) = (cube_root(t), t.cbrt());
            assert!(
                (fast - exact).abs() <= 4.0 * f32::EPSILON * exact,
                "{t}: {fast} vs {exact}"
            );
            t = f32::from_bits(t.to_bits() + 97);
        }
    }

    #[test]
    fn lab_planes_hold_the_lab_values() {
        let f = checker(9, 5);
        let planes = to_lab_planes(&f);
        for (i, lab) in to_lab(&f).data().iter().enumerate() {
            assert_eq!([planes[0][i], planes[1][i], planes[2][i]], *lab);
        }
    }

    #[test]
    fn lab_of_white_black_and_red() {
        let f = Grid::from_vec(3, 1, vec![[255, 255, 255], [0, 0, 0], [255, 0, 0]]).unwrap();
        let lab = to_lab(&f);
        let [l, a, b] = *lab.get(0, 0);
        assert!((l - 100.0).abs() < 0.1 && a.abs() < 0.1 && b.abs() < 0.1);
        assert!(lab.get(1, 0)[0].abs() < 1e-3);
        let [l, a, b] = *lab.get(2, 0);
        assert!((l - 53.24).abs() < 0.1 && (a - 80.09).abs() < 0.2 && (b - 67.20).abs() < 0.2);
    }
}
