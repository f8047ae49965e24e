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
