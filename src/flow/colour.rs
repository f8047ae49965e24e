//! The Middlebury flow colour picture (Baker et al., IJCV 2011): hue is the direction of the
//! vector on a 55-step colour wheel, saturation its length relative to a maximum; unknown
//! vectors are black.

use super::{FlowField, is_known};
use crate::grid::Grid;
use crate::image::Frame;
use crate::numeric::{atan2_f32, hypot_f32};

/// Steps of each segment of the wheel: red–yellow, yellow–green, green–cyan, cyan–blue,
/// blue–magenta, magenta–red.
const SEGMENTS: [usize; 6] = [15, 6, 4, 11, 13, 6];

/// The colour of the wheel at step `k` (0..55), in [0, 255] per channel.
fn wheel(k: usize) -> [f32; 3] {
    let mut k = k;
    for (segment, &len) in SEGMENTS.iter().enumerate() {
        if k < len {
            let up = (255 * k / len) as f32;
            let down = 255.0 - up;
            return match segment {
                0 => [255.0, up, 0.0],
                1 => [down, 255.0, 0.0],
                2 => [0.0, 255.0, up],
                3 => [0.0, down, 255.0],
                4 => [up, 0.0, 255.0],
                _ => [255.0, 0.0, down],
            };
        }
        k -= len;
    }
    [255.0, 0.0, 0.0]
}

/// The colour of flow vector (u, v) already divided by the maximum length: white at zero,
/// saturated at length 1 and darkened beyond. Right is red, down yellow, left cyan, up
/// blue-violet (image axes: v points down).
pub fn vector_colour(u: f32, v: f32) -> [u8; 3] {
    let steps: usize = SEGMENTS.iter().sum();
    let radius = hypot_f32(u, v);
    let angle = atan2_f32(-v, -u) / std::f32::consts::PI;
    let position = (angle + 1.0) / 2.0 * (steps - 1) as f32;
    let k0 = (position.floor() as usize).min(steps - 1);
    let k1 = (k0 + 1) % steps;
    let f = position - k0 as f32;
    let (c0, c1) = (wheel(k0), wheel(k1));
    std::array::from_fn(|i| {
        let col = ((1.0 - f) * c0[i] + f * c1[i]) / 255.0;
        let col = if radius <= 1.0 {
            1.0 - radius * (1.0 - col)
        } else {
            col * 0.75
        };
        (255.0 * col).clamp(0.0, 255.0) as u8
    })
}

/// The largest length among the known vectors of `flow` (0 when none is known).
pub fn max_radius(flow: &FlowField) -> f32 {
    flow.data()
        .iter()
        .filter(|f| is_known(**f))
        .map(|f| hypot_f32(f[0], f[1]))
        .fold(0.0, f32::max)
}

/// A picture of `flow`: each vector divided by `max_radius` (by the field's own largest known
/// length when `None`, so pictures of two fields can share a scale by passing one value) and
/// coloured by [`vector_colour`]; unknown vectors are black.
pub fn flow_picture(flow: &FlowField, max_radius: Option<f32>) -> Frame {
    let scale = max_radius
        .unwrap_or_else(|| self::max_radius(flow))
        .max(1e-6);
    flow.map(|&f| {
        if is_known(f) {
            vector_colour(f[0] / scale, f[1] / scale)
        } else {
            [0, 0, 0]
        }
    })
}

/// [`flow_picture`] of `flow` at its own scale, with the vectors that are not `reliable` (e.g.
/// failing the forward–backward check) drawn at a third of their brightness.
pub fn flow_picture_with_reliability(flow: &FlowField, reliable: &Grid<bool>) -> Frame {
    let mut picture = flow_picture(flow, None);
    for (pixel, &trusted) in picture.data_mut().iter_mut().zip(reliable.data()) {
        if !trusted {
            *pixel = pixel.map(|c| c / 3);
        }
    }
    picture
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_wheel_has_the_middlebury_hues() {
        assert_eq!(vector_colour(0.0, 0.0), [255, 255, 255]);
        // Right is red, left cyan, up (v < 0) blue-violet, down yellow.
        let right = vector_colour(1.0, 0.0);
        assert!(
            right[0] > 200 && right[1] < 60 && right[2] < 60,
            "{right:?}"
        );
        let left = vector_colour(-1.0, 0.0);
        assert!(left[0] < 60 && left[1] > 150 && left[2] > 200, "{left:?}");
        let up = vector_colour(0.0, -1.0);
        assert!(up[2] > 200 && up[1] < 60, "{up:?}");
        let down = vector_colour(0.0, 1.0);
        assert!(down[0] > 200 && down[1] > 150 && down[2] < 60, "{down:?}");
        // Half length is paler; beyond the maximum, darker.
        assert!(vector_colour(0.5, 0.0)[1] > 100);
        assert!(vector_colour(2.0, 0.0)[0] < 200);
    }

    #[test]
    fn pictures_scale_by_the_longest_vector_and_blacken_unknowns() {
        let flow = Grid::from_vec(3, 1, vec![[2.0, 0.0], [1.0, 0.0], [f32::NAN; 2]]).unwrap();
        assert_eq!(max_radius(&flow), 2.0);
        let pic = flow_picture(&flow, None);
        assert_eq!(*pic.get(0, 0), vector_colour(1.0, 0.0));
        assert_eq!(*pic.get(1, 0), vector_colour(0.5, 0.0));
        assert_eq!(*pic.get(2, 0), [0, 0, 0]);
        let shared = flow_picture(&flow, Some(4.0));
        assert_eq!(*shared.get(0, 0), vector_colour(0.5, 0.0));
    }

    #[test]
    fn unreliable_vectors_are_darker() {
        let flow = Grid::from_vec(2, 1, vec![[1.0, 0.0], [1.0, 0.0]]).unwrap();
        let reliable = Grid::from_vec(2, 1, vec![true, false]).unwrap();
        let pic = flow_picture_with_reliability(&flow, &reliable);
        assert_eq!(*pic.get(0, 0), vector_colour(1.0, 0.0));
        assert_eq!(*pic.get(1, 0), vector_colour(1.0, 0.0).map(|c| c / 3));
    }
}
