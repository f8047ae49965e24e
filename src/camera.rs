//! Pinhole intrinsics, where they came from, and how they follow a resize.
//!
//! Conventions (docs/ARCHITECTURE.md): pixel (u, v) with u right, v down and pixel centres at
//! integers; camera axes x right, y down, z forward; K = [[fx, 0, cx], [0, fy, cy], [0, 0, 1]].

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// Pinhole intrinsics in pixels.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Intrinsics {
    pub fx: f64,
    pub fy: f64,
    pub cx: f64,
    pub cy: f64,
}

/// Where a frame's intrinsics came from, in the order they are tried.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum IntrinsicsSource {
    /// Given by the user (CLI flag, page field, or a case's `intrinsics.txt`).
    User,
    /// From the photo's EXIF 35 mm-equivalent focal length.
    Exif,
    /// Guessed: fx = fy = max(W, H), principal point at the image centre. In a reconstruction's
    /// report: the guess stood, because the two frames do not fix a focal length
    /// ([`crate::focal`]).
    Default,
    /// Estimated from the two frames' flow where they fix it ([`crate::focal`]), in place of
    /// the guess; principal point at the image centre.
    Estimated,
}

impl std::fmt::Display for IntrinsicsSource {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            IntrinsicsSource::User => "user",
            IntrinsicsSource::Exif => "EXIF",
            IntrinsicsSource::Default => "default",
            IntrinsicsSource::Estimated => "the frames",
        })
    }
}

impl Intrinsics {
    /// The fallback guess for a `width × height` image: fx = fy = max(W, H), centre
    /// W/2 − 0.5, H/2 − 0.5 (a horizontal field of view of about 53° on the long side).
    pub fn default_for(width: usize, height: usize) -> Self {
        let f = width.max(height) as f64;
        Intrinsics {
            fx: f,
            fy: f,
            cx: width as f64 / 2.0 - 0.5,
            cy: height as f64 / 2.0 - 0.5,
        }
    }

    /// From a 35 mm-equivalent focal length in mm: fx = fy = f35 · long side / 36 (the 36 mm film
    /// width maps to the long side), principal point at the centre.
    pub fn from_focal_35mm(focal_35mm: f64, width: usize, height: usize) -> Self {
        let f = focal_35mm * width.max(height) as f64 / 36.0;
        Intrinsics {
            fx: f,
            fy: f,
            ..Intrinsics::default_for(width, height)
        }
    }

    /// Parses `"fx fy cx cy"` (whitespace or commas between the four numbers).
    pub fn parse(text: &str) -> Result<Self> {
        let values: Vec<f64> = text
            .split(|c: char| c.is_whitespace() || c == ',')
            .filter(|s| !s.is_empty())
            .map(|s| s.parse::<f64>())
            .collect::<std::result::Result<_, _>>()
            .map_err(|_| bad_intrinsics(text))?;
        let [fx, fy, cx, cy] = values[..] else {
            return Err(bad_intrinsics(text));
        };
        Intrinsics { fx, fy, cx, cy }.validated()
    }

    /// Checks that all values are finite and the focal lengths positive.
    pub fn validated(self) -> Result<Self> {
        let finite = [self.fx, self.fy, self.cx, self.cy]
            .iter()
            .all(|v| v.is_finite());
        if finite && self.fx > 0.0 && self.fy > 0.0 {
            Ok(self)
        } else {
            Err(Error::InvalidParameter(format!(
                "intrinsics must be finite with positive focal lengths, got fx={} fy={} cx={} cy={}",
                self.fx, self.fy, self.cx, self.cy
            )))
        }
    }

    /// The intrinsics of the same camera after resizing the image by `sx` horizontally and `sy`
    /// vertically. With pixel centres at integers, a centre c maps to (c + 0.5)·s − 0.5.
    pub fn scaled(&self, sx: f64, sy: f64) -> Self {
        Intrinsics {
            fx: self.fx * sx,
            fy: self.fy * sy,
            cx: (self.cx + 0.5) * sx - 0.5,
            cy: (self.cy + 0.5) * sy - 0.5,
        }
    }

    /// The normalised ray x̄ = K⁻¹ [u, v, 1]ᵀ (its z is 1).
    pub fn ray(&self, u: f64, v: f64) -> [f64; 3] {
        [(u - self.cx) / self.fx, (v - self.cy) / self.fy, 1.0]
    }

    /// Projects a camera-frame point (z > 0 in front) to pixel (u, v).
    pub fn project(&self, p: [f64; 3]) -> [f64; 2] {
        [
            self.fx * p[0] / p[2] + self.cx,
            self.fy * p[1] / p[2] + self.cy,
        ]
    }

    /// `"fx fy cx cy"`, the format of a case's `intrinsics.txt`.
    pub fn to_line(&self) -> String {
        format!("{} {} {} {}", self.fx, self.fy, self.cx, self.cy)
    }
}

fn bad_intrinsics(text: &str) -> Error {
    Error::InvalidParameter(format!(
        "intrinsics must be four numbers \"fx fy cx cy\", got {text:?}"
    ))
}

/// Intrinsics together with their source.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Camera {
    pub intrinsics: Intrinsics,
    pub source: IntrinsicsSource,
}

/// Picks intrinsics for a `width × height` image in the order user → EXIF → default.
pub fn resolve_intrinsics(
    user: Option<Intrinsics>,
    exif_focal_35mm: Option<f64>,
    width: usize,
    height: usize,
) -> Camera {
    match (user, exif_focal_35mm) {
        (Some(intrinsics), _) => Camera {
            intrinsics,
            source: IntrinsicsSource::User,
        },
        (None, Some(f35)) => Camera {
            intrinsics: Intrinsics::from_focal_35mm(f35, width, height),
            source: IntrinsicsSource::Exif,
        },
        (None, None) => Camera {
            intrinsics: Intrinsics::default_for(width, height),
            source: IntrinsicsSource::Default,
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resolution_order_is_user_exif_default() {
        let user = Intrinsics {
            fx: 500.0,
            fy: 510.0,
            cx: 320.0,
            cy: 240.0,
        };
        assert_eq!(
            resolve_intrinsics(Some(user), Some(26.0), 640, 480).source,
            IntrinsicsSource::User
        );
        let exif = resolve_intrinsics(None, Some(36.0), 640, 480);
        assert_eq!(exif.source, IntrinsicsSource::Exif);
        assert_eq!(exif.intrinsics.fx, 640.0);
        let default = resolve_intrinsics(None, None, 640, 480);
        assert_eq!(default.source, IntrinsicsSource::Default);
        assert_eq!(default.intrinsics.cx, 319.5);
        assert_eq!(default.intrinsics.cy, 239.5);
    }

    #[test]
    fn scaling_keeps_the_centre_pixel_centred() {
        let k = Intrinsics::default_for(4032, 3024).scaled(0.25, 0.25);
        assert_eq!(k.cx, 1008.0 / 2.0 - 0.5);
        assert_eq!(k.fx, 1008.0);
    }

    #[test]
    fn project_inverts_ray() {
        let k = Intrinsics {
            fx: 700.0,
            fy: 690.0,
            cx: 300.2,
            cy: 200.7,
        };
        let r = k.ray(10.0, 400.0);
        let p = k.project([r[0] * 3.0, r[1] * 3.0, 3.0]);
        assert!((p[0] - 10.0).abs() < 1e-9 && (p[1] - 400.0).abs() < 1e-9);
    }

    #[test]
    fn parse_accepts_four_numbers_only() {
        assert_eq!(Intrinsics::parse("1 2, 3 4").unwrap().fy, 2.0);
        assert!(Intrinsics::parse("1 2 3").is_err());
        assert!(Intrinsics::parse("a b c d").is_err());
        assert!(Intrinsics::parse("0 1 2 3").is_err());
        assert!(Intrinsics::parse("1 1 NaN 3").is_err());
    }
}
