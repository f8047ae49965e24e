//! Dense optical flow: the flow field type shared by every stage.

use crate::grid::Grid;

/// Dense flow from frame 1 to frame 2 in pixels: element (u, v) is `[u' − u, v' − v]`.
/// Unknown vectors are NaN (written to `.flo` as 1e10).
pub type FlowField = Grid<[f32; 2]>;

/// True when a flow vector is known (both components finite).
#[inline]
pub fn is_known(f: [f32; 2]) -> bool {
    f[0].is_finite() && f[1].is_finite()
}

/// `flow` (defined on a grid of its own size) resampled to `width × height`, with vectors scaled by
/// the size ratio. Pixel centres map as x' = (x + 0.5)·s − 0.5; each output vector is the bilinear
/// mix of the known input vectors around it (NaN where none is known).
pub fn resize_flow(flow: &FlowField, width: usize, height: usize) -> FlowField {
    if flow.size() == (width, height) {
        return flow.clone();
    }
    let sx = width as f32 / flow.width() as f32;
    let sy = height as f32 / flow.height() as f32;
    Grid::from_fn(width, height, |x, y| {
        let fx = ((x as f32 + 0.5) / sx - 0.5).clamp(0.0, (flow.width() - 1) as f32);
        let fy = ((y as f32 + 0.5) / sy - 0.5).clamp(0.0, (flow.height() - 1) as f32);
        let (x0, y0, ax, ay) = crate::grid::bilinear_cell(fx, fy, flow.width(), flow.height());
        let (x1, y1) = (
            (x0 + 1).min(flow.width() - 1),
            (y0 + 1).min(flow.height() - 1),
        );
        let mut sum = [0.0f32; 2];
        let mut weight = 0.0;
        for (xx, yy, w) in [
            (x0, y0, (1.0 - ax) * (1.0 - ay)),
            (x1, y0, ax * (1.0 - ay)),
            (x0, y1, (1.0 - ax) * ay),
            (x1, y1, ax * ay),
        ] {
            let f = *flow.get(xx, yy);
            if is_known(f) && w > 0.0 {
                sum[0] += w * f[0];
                sum[1] += w * f[1];
                weight += w;
            }
        }
        if weight > 0.0 {
            [sum[0] / weight * sx, sum[1] / weight * sy]
        } else {
            [f32::NAN; 2]
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resizing_scales_vectors_and_keeps_unknowns() {
        let flow = Grid::from_fn(
            8,
            4,
            |x, _| if x == 0 { [f32::NAN; 2] } else { [2.0, -1.0] },
        );
        let half = resize_flow(&flow, 4, 2);
        assert_eq!(*half.get(3, 1), [1.0, -0.5]);
        let double = resize_flow(&flow, 16, 8);
        assert!(double.get(0, 0)[0].is_nan());
        assert_eq!(*double.get(10, 3), [4.0, -2.0]);
    }
}
