//! Colour maps for pictures of per-pixel quantities (depth maps, legends).

use crate::grid::Grid;
use crate::image::Frame;

/// Colour of the Turbo colour map (Mikhailov 2019, polynomial fit) at `t` in [0, 1]
/// (clamped): dark blue at 0 through green to dark red at 1.
pub fn turbo(t: f32) -> [u8; 3] {
    let t = t.clamp(0.0, 1.0) as f64;
    let poly = |c: [f64; 6]| {
        let v = c[0] + t * (c[1] + t * (c[2] + t * (c[3] + t * (c[4] + t * c[5]))));
        (v.clamp(0.0, 1.0) * 255.0).round() as u8
    };
    [
        poly([
            0.135_721_38,
            4.615_392_6,
            -42.660_322_58,
            132.131_082_34,
            -152.942_393_96,
            59.286_379_43,
        ]),
        poly([
            0.091_402_61,
            2.194_188_39,
            4.842_966_58,
            -14.185_033_33,
            4.277_298_55,
            2.829_566_04,
        ]),
        poly([
            0.106_673_3,
            12.641_946_08,
            -60.582_048_36,
            110.362_767_71,
            -89.903_109_12,
            27.348_249_81,
        ]),
    ]
}

/// The range of inverse depth that depth colours span: the 2nd–98th percentile of the valid
/// (finite, positive) depths' inverses, so a few outliers do not wash it out; `None` when no
/// depth is valid.
pub fn inverse_depth_range(depths: impl IntoIterator<Item = f32>) -> Option<(f32, f32)> {
    let mut inverse: Vec<f32> = depths
        .into_iter()
        .filter(|z| z.is_finite() && *z > 0.0)
        .map(|z| 1.0 / z)
        .collect();
    if inverse.is_empty() {
        return None;
    }
    // Two selections instead of a sort: linear time (a depth map has hundreds of thousands).
    let n = inverse.len();
    let (lo_at, hi_at) = (n * 2 / 100, (n * 98 / 100).min(n - 1));
    let (_, &mut hi, _) = inverse.select_nth_unstable_by(hi_at, f32::total_cmp);
    let (_, &mut lo, _) = inverse[..=hi_at].select_nth_unstable_by(lo_at, f32::total_cmp);
    Some((lo, hi))
}

/// Colour of depth `z` for the inverse-depth `range` of [`inverse_depth_range`]: near is warm
/// (red), far is cool (blue); unknown depth (NaN, ≤ 0) is black.
pub fn depth_colour(z: f32, (lo, hi): (f32, f32)) -> [u8; 3] {
    if z.is_finite() && z > 0.0 {
        let span = (hi - lo).max(f32::EPSILON);
        // Skip Turbo's near-black ends so that far stays blue, distinct from unknown.
        turbo(0.08 + 0.87 * (1.0 / z - lo) / span)
    } else {
        [0, 0, 0]
    }
}

/// A picture of a depth map: near is warm (red), far is cool (blue), on inverse depth so that
/// near structure gets most of the colour range; unknown depth (NaN, ≤ 0) is black. The range is
/// [`inverse_depth_range`] of the map.
pub fn depth_picture(depth: &Grid<f32>) -> Frame {
    match inverse_depth_range(depth.data().iter().copied()) {
        Some(range) => depth.map(|&z| depth_colour(z, range)),
        None => depth.map(|_| [0, 0, 0]),
    }
}

/// The key of a depth picture: colours from near to far with the depth each stands for.
#[derive(Clone, Debug, PartialEq)]
pub struct DepthLegend {
    /// Colours from near (warm) to far (cool).
    pub colours: Vec<[u8; 3]>,
    /// The depth of each colour, increasing (same unit as the depth map).
    pub depths: Vec<f32>,
}

/// A legend of `steps` (at least 2) colours for the inverse-depth `range` of
/// [`inverse_depth_range`], evenly spaced in inverse depth as the picture spreads them, from
/// the nearest depth of the range (1 / its upper end) to the farthest (1 / its lower end).
pub fn depth_legend((lo, hi): (f32, f32), steps: usize) -> DepthLegend {
    let steps = steps.max(2);
    let depths: Vec<f32> = (0..steps)
        .map(|i| {
            let t = i as f32 / (steps - 1) as f32;
            1.0 / (hi + t * (lo - hi))
        })
        .collect();
    let colours = depths.iter().map(|&z| depth_colour(z, (lo, hi))).collect();
    DepthLegend { colours, depths }
}

/// Relative errors at or above this share of the true depth get the last colour of
/// [`relative_error_picture`].
pub const RELATIVE_ERROR_MAX: f32 = 0.5;

/// Colour of a relative depth error `e` (0 = exact): Turbo from dark blue (0) to dark red
/// ([`RELATIVE_ERROR_MAX`] and above); unknown (NaN) is black.
pub fn relative_error_colour(e: f32) -> [u8; 3] {
    if e.is_finite() {
        turbo(0.08 + 0.87 * (e / RELATIVE_ERROR_MAX).clamp(0.0, 1.0))
    } else {
        [0, 0, 0]
    }
}

/// A picture of per-pixel relative depth errors (see [`relative_error_colour`]).
pub fn relative_error_picture(errors: &Grid<f32>) -> Frame {
    errors.map(|&e| relative_error_colour(e))
}

/// The key of [`relative_error_picture`]: `steps` (at least 2) colours with the error each
/// stands for, evenly from 0 to [`RELATIVE_ERROR_MAX`].
pub fn relative_error_legend(steps: usize) -> (Vec<[u8; 3]>, Vec<f32>) {
    let steps = steps.max(2);
    let errors: Vec<f32> = (0..steps)
        .map(|i| RELATIVE_ERROR_MAX * i as f32 / (steps - 1) as f32)
        .collect();
    (
        errors.iter().map(|&e| relative_error_colour(e)).collect(),
        errors,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn turbo_runs_from_blue_to_red() {
        let [r0, _, b0] = turbo(0.1);
        let [r1, _, b1] = turbo(0.9);
        assert!(b0 > r0 && r1 > b1);
        assert_eq!(turbo(-3.0), turbo(0.0));
    }

    #[test]
    fn near_is_red_far_is_blue_unknown_is_black() {
        let depth = Grid::from_vec(3, 1, vec![1.0, 10.0, f32::NAN]).unwrap();
        let pic = depth_picture(&depth);
        let [r, _, b] = *pic.get(0, 0);
        assert!(r > b, "near should be warm");
        let [r, _, b] = *pic.get(1, 0);
        assert!(b > r, "far should be cool");
        assert_eq!(*pic.get(2, 0), [0, 0, 0]);
    }

    #[test]
    fn the_range_is_the_2nd_to_98th_percentile_of_inverse_depth() {
        // Inverse depths 1..=100 (shuffled), plus unknown and negative depths that are ignored.
        let mut depths: Vec<f32> = (1..=100).map(|i| 1.0 / ((i * 37) % 101) as f32).collect();
        depths.extend([f32::NAN, -1.0, 0.0]);
        assert_eq!(inverse_depth_range(depths), Some((3.0, 99.0)));
        assert_eq!(inverse_depth_range([f32::NAN]), None);
        assert_eq!(inverse_depth_range([0.5]), Some((2.0, 2.0)));
    }

    #[test]
    fn legend_runs_from_near_and_warm_to_far_and_cool() {
        let depth = Grid::from_fn(50, 1, |x, _| 1.0 + x as f32);
        let range = inverse_depth_range(depth.data().iter().copied()).unwrap();
        let legend = depth_legend(range, 16);
        assert_eq!(legend.colours.len(), 16);
        assert!(legend.depths.windows(2).all(|w| w[0] < w[1]));
        assert!((legend.depths[0] - 1.0 / range.1).abs() < 1e-5);
        assert!((legend.depths[15] - 1.0 / range.0).abs() < 1e-3);
        let [r, _, b] = legend.colours[0];
        assert!(r > b, "near should be warm");
        let [r, _, b] = legend.colours[15];
        assert!(b > r, "far should be cool");
        // The legend's colours are the picture's colours at those depths.
        let picture = depth_picture(&Grid::from_vec(1, 1, vec![legend.depths[5]]).unwrap());
        let one = depth_legend(inverse_depth_range([legend.depths[5]]).unwrap(), 2);
        assert_eq!(*picture.get(0, 0), one.colours[0]);
        assert_eq!(legend.colours[5], depth_colour(legend.depths[5], range));
        assert_eq!(depth_legend(range, 0).colours.len(), 2);
    }
}
