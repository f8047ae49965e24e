//! Turning two decoded images into the pipeline's input: same size checked, intrinsics resolved
//! (user → EXIF → default) at the input resolution, then both frames scaled to the working size
//! with K scaled to match.

use crate::camera::{Camera, Intrinsics, resolve_intrinsics};
use crate::error::{Error, Result};
use crate::image::{Frame, LoadedImage, resize, working_size};

/// The smallest side (pixels) the pipeline accepts: below this flow and superpixels have nothing to
/// work on.
pub const MIN_SIDE: usize = 32;

/// Default bound on the long side of the working resolution, in pixels.
pub const DEFAULT_MAX_SIDE: usize = 1024;

/// Two frames at the working resolution with the camera that goes with them.
#[derive(Clone, Debug)]
pub struct FramePair {
    /// Reference frame (frame 1), at the working resolution.
    pub frame1: Frame,
    /// Second frame, at the working resolution.
    pub frame2: Frame,
    /// Intrinsics at the working resolution, and where they came from. A guess
    /// ([`crate::camera::IntrinsicsSource::Default`]) is replaced by the pipeline, after the flow,
    /// where the two frames fix the focal length ([`crate::focal`]; the report has the camera
    /// used).
    pub camera: Camera,
    /// Size of the input images, `(width, height)`.
    pub input_size: (usize, usize),
    /// Notes for the user (EXIF problems, downscaling) to show beside the result.
    pub notes: Vec<String>,
}

impl FramePair {
    /// Working size divided by input size, `(sx, sy)`.
    pub fn scale(&self) -> (f64, f64) {
        working_over_input(self.frame1.size(), self.input_size)
    }
}

/// `working` size divided by `input` size (both `(width, height)` in pixels), `(sx, sy)`.
pub fn working_over_input(working: (usize, usize), input: (usize, usize)) -> (f64, f64) {
    (
        working.0 as f64 / input.0 as f64,
        working.1 as f64 / input.1 as f64,
    )
}

/// Checks a pair of decoded images and brings them to the working resolution.
///
/// `user` intrinsics are for the input resolution (what a person knows about their photos);
/// the EXIF focal length is taken from frame 1. `max_side` bounds the long side of the result.
/// Errors: [`Error::SizeMismatch`] naming both sizes, [`Error::TooSmall`] below [`MIN_SIDE`],
/// [`Error::InvalidParameter`] for a `max_side` below [`MIN_SIDE`] or invalid user intrinsics.
pub fn prepare_pair(
    image1: LoadedImage,
    image2: LoadedImage,
    user: Option<Intrinsics>,
    max_side: usize,
) -> Result<FramePair> {
    let (w, h) = image1.frame.size();
    image1.frame.check_same_size(&image2.frame)?;
    if w < MIN_SIDE || h < MIN_SIDE {
        return Err(Error::TooSmall {
            width: w,
            height: h,
            min: MIN_SIDE,
        });
    }
    if max_side < MIN_SIDE {
        return Err(Error::InvalidParameter(format!(
            "working size must be at least {MIN_SIDE} pixels, got {max_side}"
        )));
    }
    let user = user.map(Intrinsics::validated).transpose()?;
    let full = resolve_intrinsics(user, image1.exif.focal_35mm, w, h);
    let mut notes: Vec<String> = [&image1, &image2]
        .iter()
        .filter_map(|img| img.exif.warning.clone())
        .collect();
    let (ww, wh) = working_size(w, h, max_side);
    if (ww, wh) != (w, h) {
        notes.push(format!("downscaled from {w}×{h} to {ww}×{wh}"));
    }
    let camera = Camera {
        intrinsics: full
            .intrinsics
            .scaled(ww as f64 / w as f64, wh as f64 / h as f64),
        source: full.source,
    };
    Ok(FramePair {
        frame1: resize(&image1.frame, ww, wh),
        frame2: resize(&image2.frame, ww, wh),
        camera,
        input_size: (w, h),
        notes,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::IntrinsicsSource;
    use crate::grid::Grid;
    use crate::image::ExifInfo;

    fn loaded(w: usize, h: usize, focal: Option<f64>) -> LoadedImage {
        LoadedImage {
            frame: Grid::from_fn(w, h, |x, y| [(x % 256) as u8, (y % 256) as u8, 7]),
            exif: ExifInfo {
                focal_35mm: focal,
                warning: None,
            },
        }
    }

    #[test]
    fn mismatched_sizes_name_both() {
        let err = prepare_pair(loaded(64, 48, None), loaded(48, 64, None), None, 1024).unwrap_err();
        let text = err.to_string();
        assert!(text.contains("64×48") && text.contains("48×64"), "{text}");
    }

    #[test]
    fn tiny_images_are_rejected() {
        let err = prepare_pair(loaded(1, 1, None), loaded(1, 1, None), None, 1024).unwrap_err();
        assert!(matches!(err, Error::TooSmall { .. }));
    }

    #[test]
    fn downscale_scales_intrinsics_from_exif() {
        let pair = prepare_pair(
            loaded(2048, 1024, Some(36.0)),
            loaded(2048, 1024, None),
            None,
            1024,
        )
        .unwrap();
        assert_eq!(pair.frame1.size(), (1024, 512));
        assert_eq!(pair.camera.source, IntrinsicsSource::Exif);
        assert_eq!(pair.camera.intrinsics.fx, 1024.0);
        assert_eq!(pair.camera.intrinsics.cx, 511.5);
        assert_eq!(pair.scale(), (0.5, 0.5));
        assert_eq!(pair.notes.len(), 1);
    }
}
