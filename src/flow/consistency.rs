//! The forward–backward consistency check: a flow vector is reliable when following it to
//! frame 2 and the backward flow from there leads back to where it started,
//! ‖f(x) + b(x + f(x))‖ < τ_abs + τ_rel · ‖f(x)‖. Occluded, disoccluded and mismatched pixels
//! fail it, as do pixels whose vector leaves the image.

use super::{FlowField, is_known};
use crate::error::Result;
use crate::grid::Grid;

/// True where `forward` (1 → 2) and `backward` (2 → 1, same size) agree to within
/// `threshold + relative · ‖f‖` pixels. The backward field is sampled bilinearly at x + f(x)
/// (pixel centres at integers); a target outside the image or next to an unknown vector fails.
pub fn forward_backward_mask(
    forward: &FlowField,
    backward: &FlowField,
    threshold: f32,
    relative: f32,
) -> Result<Grid<bool>> {
    forward.check_same_size(backward)?;
    let (w, h) = forward.size();
    Ok(Grid::from_fn(w, h, |x, y| {
        let f = *forward.get(x, y);
        if !is_known(f) {
            return false;
        }
        let (tx, ty) = (x as f32 + f[0], y as f32 + f[1]);
        let Some(b) = sample_flow(backward, tx, ty) else {
            return false;
        };
        let (gx, gy) = (f[0] + b[0], f[1] + b[1]);
        let gap = (gx * gx + gy * gy).sqrt();
        gap < threshold + relative * (f[0] * f[0] + f[1] * f[1]).sqrt()
    }))
}

/// Bilinear sample of a flow field at (x, y); `None` outside [0, w − 1] × [0, h − 1] or when a
/// vector it mixes is unknown.
#[inline]
fn sample_flow(flow: &FlowField, x: f32, y: f32) -> Option<[f32; 2]> {
    let (w, h) = flow.size();
    if !(x >= 0.0 && y >= 0.0 && x <= (w - 1) as f32 && y <= (h - 1) as f32) {
        return None;
    }
    // Non-negative here, so truncation is the floor.
    let (x0, y0) = (x as usize, y as usize);
    let (ax, ay) = (x - x0 as f32, y - y0 as f32);
    let (x1, y1) = ((x0 + 1).min(w - 1), (y0 + 1).min(h - 1));
    let corners = [
        (*flow.get(x0, y0), (1.0 - ax) * (1.0 - ay)),
        (*flow.get(x1, y0), ax * (1.0 - ay)),
        (*flow.get(x0, y1), (1.0 - ax) * ay),
        (*flow.get(x1, y1), ax * ay),
    ];
    let mut out = [0.0f32; 2];
    for (v, weight) in corners {
        if !is_known(v) {
            return None;
        }
        out[0] += weight * v[0];
        out[1] += weight * v[1];
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn opposite_fields_agree_and_targets_outside_fail() {
        let forward = Grid::filled(10, 6, [2.0, 0.0]);
        let backward = Grid::filled(10, 6, [-2.0, 0.0]);
        let mask = forward_backward_mask(&forward, &backward, 0.5, 0.0).unwrap();
        // x + 2 leaves the image for the last two columns.
        assert!(*mask.get(7, 3) && !mask.get(8, 3) && !mask.get(9, 0));
        assert_eq!(mask.data().iter().filter(|&&m| m).count(), 8 * 6);
    }

    #[test]
    fn disagreement_and_unknowns_fail_and_relative_slack_grows_with_motion() {
        let forward = Grid::filled(8, 8, [3.0, 0.0]);
        let backward = Grid::filled(8, 8, [-2.0, 0.0]);
        assert!(
            !forward_backward_mask(&forward, &backward, 0.5, 0.0)
                .unwrap()
                .get(1, 1)
        );
        assert!(
            *forward_backward_mask(&forward, &backward, 0.5, 0.2)
                .unwrap()
                .get(1, 1)
        );
        let mut holey = backward.clone();
        *holey.get_mut(4, 4) = [f32::NAN; 2];
        let mask = forward_backward_mask(&forward, &holey, 5.0, 0.0).unwrap();
        assert!(!mask.get(1, 4) && *mask.get(0, 0));
        assert!(forward_backward_mask(&forward, &Grid::filled(4, 4, [0.0; 2]), 1.0, 0.0).is_err());
    }
}
