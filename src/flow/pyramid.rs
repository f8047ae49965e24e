//! Grey image pyramids for coarse-to-fine flow, and the resampling of flow between levels.
//!
//! Level 0 is the input; level l + 1 halves level l by 2 × 2 box averaging (sizes rounded down),
//! so pixel centre x of level l + 1 sits at 2x + 0.5 in level l. Every level keeps its
//! intensities (grey levels in [0, 255]), shared by both flow directions; their gradients are
//! computed by [`Level::gradients`] when a patch search needs them (each level is searched from
//! once, in one direction) and dropped with it, which keeps them out of the flow's peak memory.
//! Images are flat row-major `Vec<f32>`s: the inner loops index them directly.

use crate::grid::Grid;

/// One pyramid level of one image.
#[derive(Clone, Debug)]
pub struct Level {
    pub width: usize,
    pub height: usize,
    /// Grey levels in [0, 255], row-major.
    pub pixels: Vec<f32>,
}

impl Level {
    /// A level holding `pixels` (`width × height`, row-major).
    pub fn new(width: usize, height: usize, pixels: Vec<f32>) -> Self {
        Level {
            width,
            height,
            pixels,
        }
    }

    /// (∂I/∂x, ∂I/∂y) in grey levels per pixel of this level, row-major: 3 × 3 Sobel divided
    /// by 8 (a unit ramp has gradient 1), borders replicated.
    pub fn gradients(&self) -> (Vec<f32>, Vec<f32>) {
        sobel(&self.pixels, self.width, self.height)
    }

    /// Bilinear sample at (x, y) with pixel centres at integers, clamped to the image
    /// (border replication).
    #[inline]
    pub fn sample(&self, x: f32, y: f32) -> f32 {
        sample_clamped(&self.pixels, self.width, self.height, x, y)
    }
}

/// The levels `finest..=coarsest` of the pyramid of `image` (grey, [0, 1] as
/// [`crate::image::to_gray`] gives): element `i` is level `finest + i`, intensities scaled to
/// [0, 255]. Levels finer than `finest` are only passed through.
pub fn build(image: &Grid<f32>, finest: usize, coarsest: usize) -> Vec<Level> {
    let (mut w, mut h) = image.size();
    let mut pixels: Vec<f32> = image.data().iter().map(|&g| g * 255.0).collect();
    let mut levels = Vec::with_capacity(coarsest + 1 - finest.min(coarsest + 1));
    for level in 0..=coarsest {
        if level > 0 {
            (pixels, w, h) = halve(&pixels, w, h);
        }
        if level >= finest {
            levels.push(Level::new(w, h, pixels.clone()));
        }
    }
    levels
}

/// The size of level `level` of a pyramid over a `width × height` image.
pub fn level_size(width: usize, height: usize, level: usize) -> (usize, usize) {
    (width >> level, height >> level)
}

/// `image` (`w × h`) halved by 2 × 2 box averaging; a last odd row or column is dropped.
fn halve(image: &[f32], w: usize, h: usize) -> (Vec<f32>, usize, usize) {
    let (hw, hh) = (w / 2, h / 2);
    let mut out = Vec::with_capacity(hw * hh);
    for y in 0..hh {
        let top = &image[2 * y * w..][..2 * hw];
        let bottom = &image[(2 * y + 1) * w..][..2 * hw];
        out.extend(
            top.chunks_exact(2)
                .zip(bottom.chunks_exact(2))
                .map(|(t, b)| 0.25 * (t[0] + t[1] + b[0] + b[1])),
        );
    }
    (out, hw, hh)
}

/// Sobel derivatives divided by 8 (so a unit ramp has gradient 1), borders replicated.
fn sobel(image: &[f32], w: usize, h: usize) -> (Vec<f32>, Vec<f32>) {
    let mut gx = vec![0.0; w * h];
    let mut gy = vec![0.0; w * h];
    if w == 0 || h == 0 {
        return (gx, gy);
    }
    for y in 0..h {
        let up = &image[y.saturating_sub(1) * w..][..w];
        let mid = &image[y * w..][..w];
        let down = &image[(y + 1).min(h - 1) * w..][..w];
        for x in 0..w {
            let (l, r) = (x.saturating_sub(1), (x + 1).min(w - 1));
            gx[y * w + x] = ((up[r] - up[l]) + 2.0 * (mid[r] - mid[l]) + (down[r] - down[l])) / 8.0;
            gy[y * w + x] = ((down[l] - up[l]) + 2.0 * (down[x] - up[x]) + (down[r] - up[r])) / 8.0;
        }
    }
    (gx, gy)
}

/// Bilinear sample of a flat `w × h` image at (x, y), coordinates clamped to the image.
#[inline]
pub fn sample_clamped(image: &[f32], w: usize, h: usize, x: f32, y: f32) -> f32 {
    let x = x.clamp(0.0, (w - 1) as f32);
    let y = y.clamp(0.0, (h - 1) as f32);
    let (x0, y0) = (x as usize, y as usize);
    let (x1, y1) = ((x0 + 1).min(w - 1), (y0 + 1).min(h - 1));
    let (ax, ay) = (x - x0 as f32, y - y0 as f32);
    let top = image[y0 * w + x0] * (1.0 - ax) + image[y0 * w + x1] * ax;
    let bottom = image[y1 * w + x0] * (1.0 - ax) + image[y1 * w + x1] * ax;
    top * (1.0 - ay) + bottom * ay
}

/// A flow component of a level `factor` times coarser resampled to `w × h` and multiplied by
/// `factor` (a power of two): pixel x here reads the coarse field at (x + 0.5) / factor − 0.5
/// (bilinear, clamped).
pub fn upsample(coarse: &[f32], cw: usize, ch: usize, w: usize, h: usize, factor: f32) -> Vec<f32> {
    // Bilinear taps along one axis: (first index, second index, weight of the second).
    let taps = |n: usize, coarse_n: usize| -> Vec<(usize, usize, f32)> {
        (0..n)
            .map(|i| {
                let c = ((i as f32 + 0.5) / factor - 0.5).clamp(0.0, (coarse_n - 1) as f32);
                let i0 = c as usize;
                (i0, (i0 + 1).min(coarse_n - 1), c - i0 as f32)
            })
            .collect()
    };
    let (xs, ys) = (taps(w, cw), taps(h, ch));
    let mut out = Vec::with_capacity(w * h);
    for &(y0, y1, ay) in &ys {
        let (top, bottom) = (&coarse[y0 * cw..][..cw], &coarse[y1 * cw..][..cw]);
        out.extend(xs.iter().map(|&(x0, x1, ax)| {
            let t = top[x0] + ax * (top[x1] - top[x0]);
            let b = bottom[x0] + ax * (bottom[x1] - bottom[x0]);
            factor * (t + ay * (b - t))
        }));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn levels_halve_and_average() {
        let image = Grid::from_fn(9, 6, |x, y| (x + 10 * y) as f32 / 255.0);
        let levels = build(&image, 0, 2);
        assert_eq!(levels.len(), 3);
        assert_eq!((levels[1].width, levels[1].height), (4, 3));
        assert_eq!((levels[2].width, levels[2].height), (2, 1));
        // Level 1 pixel (1, 1) averages level-0 pixels x 2..3, y 2..3: 2.5 + 10·2.5.
        assert!((levels[1].pixels[4 + 1] - 27.5).abs() < 1e-4);
        assert_eq!(level_size(9, 6, 2), (2, 1));
        assert_eq!(build(&image, 1, 2).len(), 2);
    }

    #[test]
    fn sobel_of_a_ramp_is_its_slope() {
        let level = Level::new(
            6,
            5,
            (0..30)
                .map(|i| (i % 6) as f32 * 3.0 + (i / 6) as f32)
                .collect(),
        );
        let (gx, gy) = level.gradients();
        assert!((gx[2 * 6 + 3] - 3.0).abs() < 1e-5);
        assert!((gy[2 * 6 + 3] - 1.0).abs() < 1e-5);
    }

    #[test]
    fn upsampling_doubles_a_constant_field() {
        let coarse = vec![1.5; 4 * 3];
        let fine = upsample(&coarse, 4, 3, 9, 6, 2.0);
        assert_eq!(fine.len(), 54);
        assert!(fine.iter().all(|&f| (f - 3.0).abs() < 1e-6));
    }

    #[test]
    fn clamped_sampling_replicates_borders() {
        let image = [0.0, 10.0, 20.0, 30.0];
        assert_eq!(sample_clamped(&image, 2, 2, -3.0, 0.0), 0.0);
        assert_eq!(sample_clamped(&image, 2, 2, 0.5, 0.5), 15.0);
        assert_eq!(sample_clamped(&image, 2, 2, 5.0, 5.0), 30.0);
    }
}
