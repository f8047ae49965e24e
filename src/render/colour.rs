//! How points are coloured: their photo colour, a depth colour map, or a colour per superpixel.
//!
//! Each point gets two colours, one for frame 1 and one for frame 2; the shader blends them with
//! the morph parameter, so the depth colours follow the points as they move. Colours are sRGB
//! bytes; alpha is unused (always 255).

use std::str::FromStr;

use super::{RenderError, Result};
use crate::colormap::{depth_colour, inverse_depth_range};

use super::cloud::PointCloud;

/// What colours the points.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ColourMode {
    /// The colour of the pixel each point came from.
    #[default]
    Rgb,
    /// Depth (z in camera 1's frame) through the Turbo colour map on inverse depth, the same
    /// colours as the depth pictures ([`crate::colormap::depth_picture`]): near red, far blue.
    Depth,
    /// A distinct colour per superpixel label ([`label_colour`]); needs labels.
    Superpixel,
}

impl ColourMode {
    /// The name used by the JavaScript API: `"rgb"`, `"depth"` or `"superpixel"`.
    pub fn name(self) -> &'static str {
        match self {
            ColourMode::Rgb => "rgb",
            ColourMode::Depth => "depth",
            ColourMode::Superpixel => "superpixel",
        }
    }
}

impl FromStr for ColourMode {
    type Err = RenderError;

    fn from_str(s: &str) -> Result<Self> {
        match s {
            "rgb" => Ok(ColourMode::Rgb),
            "depth" => Ok(ColourMode::Depth),
            "superpixel" => Ok(ColourMode::Superpixel),
            other => Err(RenderError::InvalidParameter(format!(
                "colour mode must be \"rgb\", \"depth\" or \"superpixel\", not {other:?}"
            ))),
        }
    }
}

/// A colour for superpixel `label`: a hash of the label picks the hue, saturation and value
/// from bright, saturated ranges, so neighbouring labels (consecutive numbers) look different and
/// no label is near black or near white. The same label always gets the same colour.
pub fn label_colour(label: u32) -> [u8; 3] {
    let h = hash32(label);
    let hue = (h & 0xffff) as f32 / 65536.0;
    let saturation = 0.55 + 0.45 * ((h >> 16) & 0xff) as f32 / 255.0;
    let value = 0.65 + 0.35 * (h >> 24) as f32 / 255.0;
    hsv_to_rgb(hue, saturation, value)
}

/// A 32-bit integer hash with full avalanche (the "lowbias32" finaliser of C. Wellons).
fn hash32(mut x: u32) -> u32 {
    x ^= x >> 16;
    x = x.wrapping_mul(0x7feb_352d);
    x ^= x >> 15;
    x = x.wrapping_mul(0x846c_a68b);
    x ^= x >> 16;
    x
}

/// HSV (all in [0, 1], hue wrapping) to sRGB bytes.
fn hsv_to_rgb(hue: f32, saturation: f32, value: f32) -> [u8; 3] {
    let h6 = hue.rem_euclid(1.0) * 6.0;
    let sector = h6.floor();
    let f = h6 - sector;
    let (p, q, t) = (
        value * (1.0 - saturation),
        value * (1.0 - saturation * f),
        value * (1.0 - saturation * (1.0 - f)),
    );
    let (r, g, b) = match sector as u32 {
        0 => (value, t, p),
        1 => (q, value, p),
        2 => (p, value, t),
        3 => (p, q, value),
        4 => (t, p, value),
        _ => (value, p, q),
    };
    let byte = |c: f32| (c.clamp(0.0, 1.0) * 255.0).round() as u8;
    [byte(r), byte(g), byte(b)]
}

/// How the points of one cloud are coloured in one mode: each point's frame-1 and frame-2
/// colours as RGBA bytes ([`Colouring::pair`]).
pub struct Colouring<'a> {
    cloud: &'a PointCloud,
    mode: ColourMode,
    depth_range: (f32, f32),
}

impl<'a> Colouring<'a> {
    /// The inverse-depth range of the depth colours of `cloud`: that of its frame-1 depths
    /// ([`inverse_depth_range`]), so decimation does not change the colours.
    pub fn depth_range(cloud: &PointCloud) -> (f32, f32) {
        inverse_depth_range(cloud.pos1().iter().map(|p| p[2])).unwrap_or((0.0, 1.0))
    }

    /// Colours `cloud` in `mode`, depth colours spanning `depth_range` (from
    /// [`Colouring::depth_range`]). Fails for [`ColourMode::Superpixel`] when the cloud has no
    /// labels.
    pub fn new(
        cloud: &'a PointCloud,
        mode: ColourMode,
        depth_range: (f32, f32),
    ) -> Result<Colouring<'a>> {
        if mode == ColourMode::Superpixel && cloud.labels().is_none() {
            return Err(RenderError::InvalidParameter(
                "superpixel colours need per-point labels, and this cloud has none".into(),
            ));
        }
        Ok(Colouring {
            cloud,
            mode,
            depth_range,
        })
    }

    /// The frame-1 and frame-2 colours of point `i` of the cloud (RGBA, alpha 255).
    pub fn pair(&self, i: usize) -> [[u8; 4]; 2] {
        let rgba = |[r, g, b]: [u8; 3]| [r, g, b, 255];
        match self.mode {
            ColourMode::Rgb => [rgba(self.cloud.rgb()[i]); 2],
            ColourMode::Depth => [
                rgba(depth_colour(self.cloud.pos1()[i][2], self.depth_range)),
                rgba(depth_colour(self.cloud.pos2()[i][2], self.depth_range)),
            ],
            ColourMode::Superpixel => {
                let label = self.cloud.labels().map_or(0, |labels| labels[i]);
                [rgba(label_colour(label)); 2]
            }
        }
    }
}

/// The colours of the points `shown` (indices into `cloud`) under `mode`: for each point its
/// frame-1 colour then its frame-2 colour, as RGBA bytes (8 bytes per point). The depth range is
/// taken from the frame-1 depths of the whole cloud, so decimation does not change the colours.
/// Fails for [`ColourMode::Superpixel`] when the cloud has no labels. (The view colours slices
/// through [`Colouring`] directly; this whole-list form is what the tests compare.)
#[cfg(test)]
fn point_colours(cloud: &PointCloud, shown: &[u32], mode: ColourMode) -> Result<Vec<[u8; 4]>> {
    let colouring = Colouring::new(cloud, mode, Colouring::depth_range(cloud))?;
    Ok(shown
        .iter()
        .flat_map(|&i| colouring.pair(i as usize))
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cloud(labels: Option<&[u32]>) -> PointCloud {
        let pos1 = [0.0, 0.0, 1.0, 0.0, 0.0, 4.0, 1.0, 1.0, 10.0];
        let pos2 = [0.0, 0.0, 10.0, 0.0, 0.0, 4.0, 1.0, 1.0, 1.0];
        let rgb = [10, 20, 30, 40, 50, 60, 70, 80, 90];
        PointCloud::new(&pos1, Some(&pos2), &rgb, labels).unwrap()
    }

    #[test]
    fn mode_names_round_trip() {
        for mode in [ColourMode::Rgb, ColourMode::Depth, ColourMode::Superpixel] {
            assert_eq!(mode.name().parse::<ColourMode>().unwrap(), mode);
        }
        let err = "Depth".parse::<ColourMode>().unwrap_err().to_string();
        assert!(err.contains("colour mode must be"), "{err}");
    }

    #[test]
    fn rgb_mode_repeats_the_photo_colour_for_both_frames() {
        let colours = point_colours(&cloud(None), &[0, 2], ColourMode::Rgb).unwrap();
        assert_eq!(
            colours,
            vec![
                [10, 20, 30, 255],
                [10, 20, 30, 255],
                [70, 80, 90, 255],
                [70, 80, 90, 255]
            ]
        );
    }

    #[test]
    fn depth_mode_is_warm_near_and_cool_far_and_follows_the_motion() {
        let colours = point_colours(&cloud(None), &[0, 1, 2], ColourMode::Depth).unwrap();
        let warm = |c: [u8; 4]| c[0] > c[2];
        // Point 0 moves from z = 1 (near) to z = 10 (far); point 2 the other way.
        assert!(warm(colours[0]) && !warm(colours[1]));
        assert!(!warm(colours[4]) && warm(colours[5]));
        // Point 1 does not move: same colour in both frames.
        assert_eq!(colours[2], colours[3]);
    }

    #[test]
    fn superpixel_mode_colours_by_label_and_needs_labels() {
        let colours =
            point_colours(&cloud(Some(&[7, 7, 8])), &[0, 1, 2], ColourMode::Superpixel).unwrap();
        assert_eq!(colours[0], colours[2]);
        assert_ne!(colours[0], colours[4]);
        let [r, g, b] = label_colour(7);
        assert_eq!(colours[0], [r, g, b, 255]);
        assert!(point_colours(&cloud(None), &[0], ColourMode::Superpixel).is_err());
    }

    #[test]
    fn label_colours_are_bright_and_distinct_for_neighbours() {
        let colours: Vec<[u8; 3]> = (0..2000).map(label_colour).collect();
        for c in &colours {
            let max = *c.iter().max().unwrap();
            let min = *c.iter().min().unwrap();
            assert!(max >= 165, "too dark: {c:?}");
            assert!(max - min >= 70, "too grey: {c:?}");
        }
        // Consecutive labels (often neighbouring superpixels) differ clearly.
        let distance = |a: [u8; 3], b: [u8; 3]| {
            a.iter()
                .zip(b)
                .map(|(&x, y)| (x as i32 - y as i32).abs())
                .sum::<i32>()
        };
        let close = colours
            .windows(2)
            .filter(|w| distance(w[0], w[1]) < 40)
            .count();
        assert!(
            close < 2000 / 50,
            "{close} of 2000 consecutive pairs look alike"
        );
    }
}
