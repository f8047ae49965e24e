//! The viewer's input: a point cloud in two frames, as plain buffers, checked once.

use super::{RenderError, Result};

/// Points seen in two frames: for each point its position in frame 1 (X) and frame 2 (X'),
/// both in camera 1's OpenCV frame (x right, y down, z forward, any length unit), its colour
/// (sRGB bytes) and optionally its superpixel label.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PointCloud {
    pos1: Vec<[f32; 3]>,
    pos2: Vec<[f32; 3]>,
    rgb: Vec<[u8; 3]>,
    labels: Option<Vec<u32>>,
}

impl PointCloud {
    /// A cloud from flat buffers: `pos1` holds x, y, z per point; `pos2` the same for frame 2
    /// (`None`: the points do not move); `rgb` r, g, b per point; `labels` one per point.
    /// Points whose position is not finite in either frame (unknown depth) are left out.
    /// Fails, saying which buffer is wrong, when the lengths do not agree.
    pub fn new(
        pos1: &[f32],
        pos2: Option<&[f32]>,
        rgb: &[u8],
        labels: Option<&[u32]>,
    ) -> Result<PointCloud> {
        // `extend` checks the lengths.
        let mut cloud = PointCloud::with_capacity(pos1.len() / 3, labels.is_some());
        cloud.extend(pos1, pos2, rgb, labels)?;
        Ok(cloud)
    }

    /// The number of points of flat buffers of these lengths (numbers in `pos1` and `pos2`,
    /// bytes in `rgb`, labels), as [`PointCloud::new`] takes them; fails, saying which buffer
    /// is wrong, when the lengths do not agree.
    pub fn check_lengths(
        pos1: usize,
        pos2: Option<usize>,
        rgb: usize,
        labels: Option<usize>,
    ) -> Result<usize> {
        let bad = |reason: String| RenderError::InvalidParameter(format!("point cloud: {reason}"));
        if !pos1.is_multiple_of(3) {
            return Err(bad(format!(
                "frame-1 positions hold {pos1} numbers, not a multiple of 3 (x, y, z per point)"
            )));
        }
        let n = pos1 / 3;
        if let Some(pos2) = pos2
            && pos2 != pos1
        {
            return Err(bad(format!(
                "frame-2 positions hold {pos2} numbers for {n} points (3 per point expected)"
            )));
        }
        if rgb != 3 * n {
            return Err(bad(format!(
                "colours hold {rgb} bytes for {n} points (3 per point expected)"
            )));
        }
        if let Some(labels) = labels
            && labels != n
        {
            return Err(bad(format!(
                "{labels} labels for {n} points (1 per point expected)"
            )));
        }
        Ok(n)
    }

    /// An empty cloud with room for `n` points, with labels or without.
    pub fn with_capacity(n: usize, labels: bool) -> PointCloud {
        PointCloud {
            pos1: Vec::with_capacity(n),
            pos2: Vec::with_capacity(n),
            rgb: Vec::with_capacity(n),
            labels: labels.then(|| Vec::with_capacity(n)),
        }
    }

    /// Appends the points of flat buffers laid out as for [`PointCloud::new`] (a slice of a
    /// larger cloud, say), leaving out points that are not finite in either frame. Fails when
    /// the lengths do not agree, or when labels are given to a cloud without them or missing
    /// for a cloud with them.
    pub fn extend(
        &mut self,
        pos1: &[f32],
        pos2: Option<&[f32]>,
        rgb: &[u8],
        labels: Option<&[u32]>,
    ) -> Result<()> {
        let n = PointCloud::check_lengths(
            pos1.len(),
            pos2.map(<[f32]>::len),
            rgb.len(),
            labels.map(<[u32]>::len),
        )?;
        if labels.is_some() != self.labels.is_some() {
            return Err(RenderError::InvalidParameter(
                "point cloud: labels must be given for every point or for none".into(),
            ));
        }
        let pos2 = pos2.unwrap_or(pos1);
        for i in 0..n {
            let p1 = [pos1[3 * i], pos1[3 * i + 1], pos1[3 * i + 2]];
            let p2 = [pos2[3 * i], pos2[3 * i + 1], pos2[3 * i + 2]];
            if p1.iter().chain(&p2).all(|v| v.is_finite()) {
                self.pos1.push(p1);
                self.pos2.push(p2);
                self.rgb.push([rgb[3 * i], rgb[3 * i + 1], rgb[3 * i + 2]]);
                if let (Some(kept), Some(labels)) = (self.labels.as_mut(), labels) {
                    kept.push(labels[i]);
                }
            }
        }
        Ok(())
    }

    /// Number of points kept.
    pub fn len(&self) -> usize {
        self.pos1.len()
    }

    /// Whether there are no points.
    pub fn is_empty(&self) -> bool {
        self.pos1.is_empty()
    }

    /// Frame-1 positions X.
    pub fn pos1(&self) -> &[[f32; 3]] {
        &self.pos1
    }

    /// Frame-2 positions X'.
    pub fn pos2(&self) -> &[[f32; 3]] {
        &self.pos2
    }

    /// Colours, sRGB bytes.
    pub fn rgb(&self) -> &[[u8; 3]] {
        &self.rgb
    }

    /// Superpixel labels, if given.
    pub fn labels(&self) -> Option<&[u32]> {
        self.labels.as_deref()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn buffers_become_points_and_unknown_points_are_dropped() {
        let pos1 = [0.0, 1.0, 2.0, f32::NAN, 0.0, 1.0, 3.0, 4.0, 5.0];
        let pos2 = [0.5, 1.0, 2.0, 0.0, 0.0, 1.0, 3.0, 4.0, f32::INFINITY];
        let rgb = [1, 2, 3, 4, 5, 6, 7, 8, 9];
        let c = PointCloud::new(&pos1, Some(&pos2), &rgb, Some(&[10, 11, 12])).unwrap();
        assert_eq!(c.len(), 1);
        assert_eq!(c.pos1(), &[[0.0, 1.0, 2.0]]);
        assert_eq!(c.pos2(), &[[0.5, 1.0, 2.0]]);
        assert_eq!(c.rgb(), &[[1, 2, 3]]);
        assert_eq!(c.labels(), Some(&[10][..]));
    }

    #[test]
    fn missing_frame_two_means_static_points() {
        let c = PointCloud::new(&[1.0, 2.0, 3.0], None, &[0, 0, 0], None).unwrap();
        assert_eq!(c.pos1(), c.pos2());
        assert_eq!(c.labels(), None);
    }

    #[test]
    fn mismatched_lengths_say_which_buffer_is_wrong() {
        let message = |r: Result<PointCloud>| r.unwrap_err().to_string();
        let m = message(PointCloud::new(&[1.0, 2.0], None, &[], None));
        assert!(m.contains("not a multiple of 3"), "{m}");
        let m = message(PointCloud::new(
            &[1.0, 2.0, 3.0],
            Some(&[1.0]),
            &[0; 3],
            None,
        ));
        assert!(m.contains("frame-2 positions"), "{m}");
        let m = message(PointCloud::new(&[1.0, 2.0, 3.0], None, &[0; 4], None));
        assert!(m.contains("colours hold 4 bytes for 1 points"), "{m}");
        let m = message(PointCloud::new(&[1.0, 2.0, 3.0], None, &[0; 3], Some(&[])));
        assert!(m.contains("0 labels for 1 points"), "{m}");
    }

    #[test]
    fn a_cloud_built_in_slices_equals_one_built_at_once() {
        let pos1: Vec<f32> = (0..30)
            .map(|i| if i == 7 { f32::NAN } else { i as f32 })
            .collect();
        let pos2: Vec<f32> = pos1.iter().map(|v| v + 0.5).collect();
        let rgb: Vec<u8> = (0..30).collect();
        let labels: Vec<u32> = (0..10).collect();
        let whole = PointCloud::new(&pos1, Some(&pos2), &rgb, Some(&labels)).unwrap();
        assert_eq!(whole.len(), 9);
        let mut sliced = PointCloud::with_capacity(10, true);
        for k in (0..10).step_by(4) {
            let end = (k + 4).min(10);
            sliced
                .extend(
                    &pos1[3 * k..3 * end],
                    Some(&pos2[3 * k..3 * end]),
                    &rgb[3 * k..3 * end],
                    Some(&labels[k..end]),
                )
                .unwrap();
        }
        assert_eq!(sliced, whole);
        assert!(sliced.extend(&[0.0; 3], None, &[0; 3], None).is_err());
    }
}
