//! [`Grid`]: a dense 2D array stored row by row, the container for every per-pixel quantity
//! (colour frames, depth maps, flow fields, label maps, masks).

use crate::error::{Error, Result};

/// A `width × height` array of `T`, row-major: element (x, y) is `data[y * width + x]`,
/// x to the right and y down, matching pixel coordinates (u, v).
#[derive(Clone, Debug, PartialEq)]
pub struct Grid<T> {
    width: usize,
    height: usize,
    data: Vec<T>,
}

impl<T: Clone> Grid<T> {
    /// A grid filled with `value`.
    pub fn filled(width: usize, height: usize, value: T) -> Self {
        Grid {
            width,
            height,
            data: vec![value; width * height],
        }
    }
}

impl<T> Grid<T> {
    /// Wraps row-major `data`; fails unless `data.len() == width * height`.
    pub fn from_vec(width: usize, height: usize, data: Vec<T>) -> Result<Self> {
        if data.len() != width * height {
            return Err(Error::InvalidParameter(format!(
                "grid of {width}×{height} needs {} elements, got {}",
                width * height,
                data.len()
            )));
        }
        Ok(Grid {
            width,
            height,
            data,
        })
    }

    /// A grid whose element (x, y) is `f(x, y)`.
    pub fn from_fn(width: usize, height: usize, mut f: impl FnMut(usize, usize) -> T) -> Self {
        let mut data = Vec::with_capacity(width * height);
        for y in 0..height {
            for x in 0..width {
                data.push(f(x, y));
            }
        }
        Grid {
            width,
            height,
            data,
        }
    }

    /// Width in elements (pixels).
    pub fn width(&self) -> usize {
        self.width
    }

    /// Height in elements (pixels).
    pub fn height(&self) -> usize {
        self.height
    }

    /// `(width, height)`.
    pub fn size(&self) -> (usize, usize) {
        (self.width, self.height)
    }

    /// Number of elements.
    pub fn len(&self) -> usize {
        self.data.len()
    }

    /// True for a grid with no elements.
    pub fn is_empty(&self) -> bool {
        self.data.is_empty()
    }

    /// Element (x, y). Panics when out of bounds (a programming error, like slice indexing).
    #[inline]
    pub fn get(&self, x: usize, y: usize) -> &T {
        &self.data[y * self.width + x]
    }

    /// Mutable element (x, y). Panics when out of bounds.
    #[inline]
    pub fn get_mut(&mut self, x: usize, y: usize) -> &mut T {
        &mut self.data[y * self.width + x]
    }

    /// Element (x, y), or `None` outside the grid (signed coordinates for neighbourhood walks).
    #[inline]
    pub fn get_checked(&self, x: isize, y: isize) -> Option<&T> {
        if x < 0 || y < 0 || x as usize >= self.width || y as usize >= self.height {
            None
        } else {
            Some(&self.data[y as usize * self.width + x as usize])
        }
    }

    /// All elements, row-major.
    pub fn data(&self) -> &[T] {
        &self.data
    }

    /// All elements, row-major, mutable.
    pub fn data_mut(&mut self) -> &mut [T] {
        &mut self.data
    }

    /// Consumes the grid, returning its row-major elements.
    pub fn into_vec(self) -> Vec<T> {
        self.data
    }

    /// Row `y` as a slice.
    pub fn row(&self, y: usize) -> &[T] {
        &self.data[y * self.width..(y + 1) * self.width]
    }

    /// A grid of the same size with `f` applied to every element.
    pub fn map<U>(&self, f: impl FnMut(&T) -> U) -> Grid<U> {
        Grid {
            width: self.width,
            height: self.height,
            data: self.data.iter().map(f).collect(),
        }
    }

    /// Fails with [`Error::SizeMismatch`] unless `other` has this grid's size.
    pub fn check_same_size<U>(&self, other: &Grid<U>) -> Result<()> {
        if self.size() == other.size() {
            Ok(())
        } else {
            Err(Error::SizeMismatch {
                w1: self.width,
                h1: self.height,
                w2: other.width,
                h2: other.height,
            })
        }
    }
}

impl Grid<bool> {
    /// True where a set cell lies within `r` cells in Chebyshev distance (a (2r + 1)² square
    /// around each set cell), by two 1-D passes: rows, then columns.
    pub fn dilated(&self, r: usize) -> Grid<bool> {
        let (w, h) = self.size();
        let mut rows = Grid::filled(w, h, false);
        for y in 0..h {
            grow_line(
                |x| *self.get(x, y),
                r,
                |x, set| *rows.get_mut(x, y) = set,
                w,
            );
        }
        let mut out = Grid::filled(w, h, false);
        for x in 0..w {
            grow_line(|y| *rows.get(x, y), r, |y, set| *out.get_mut(x, y) = set, h);
        }
        out
    }
}

/// One line of [`Grid::dilated`]: `write(i, set)` for i in 0..len, set when `read` is true
/// within `r` of i (the distance to the nearest set cell on the left, then on the right).
fn grow_line(
    read: impl Fn(usize) -> bool,
    r: usize,
    mut write: impl FnMut(usize, bool),
    len: usize,
) {
    let mut near = vec![false; len];
    let mut since = usize::MAX;
    for (i, n) in near.iter_mut().enumerate() {
        since = if read(i) { 0 } else { since.saturating_add(1) };
        *n = since <= r;
    }
    since = usize::MAX;
    for (i, n) in near.iter_mut().enumerate().rev() {
        since = if read(i) { 0 } else { since.saturating_add(1) };
        write(i, *n || since <= r);
    }
}

impl Grid<f32> {
    /// Bilinear sample at real coordinates (x, y) with pixel centres at integers;
    /// coordinates are clamped to the grid (border replication).
    pub fn sample_bilinear(&self, x: f32, y: f32) -> f32 {
        let (x0, y0, fx, fy) = bilinear_cell(x, y, self.width, self.height);
        let x1 = (x0 + 1).min(self.width - 1);
        let y1 = (y0 + 1).min(self.height - 1);
        let a = *self.get(x0, y0) * (1.0 - fx) + *self.get(x1, y0) * fx;
        let b = *self.get(x0, y1) * (1.0 - fx) + *self.get(x1, y1) * fx;
        a * (1.0 - fy) + b * fy
    }
}

/// The top-left integer cell and fractional offsets for bilinear sampling at (x, y),
/// clamped so that the cell lies inside a `width × height` grid.
#[inline]
pub fn bilinear_cell(x: f32, y: f32, width: usize, height: usize) -> (usize, usize, f32, f32) {
    let x = x.clamp(0.0, (width - 1) as f32);
    let y = y.clamp(0.0, (height - 1) as f32);
    let x0 = (x.floor() as usize).min(width.saturating_sub(1));
    let y0 = (y.floor() as usize).min(height.saturating_sub(1));
    (x0, y0, x - x0 as f32, y - y0 as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn from_vec_checks_length() {
        assert!(Grid::from_vec(2, 3, vec![0u8; 6]).is_ok());
        assert!(Grid::from_vec(2, 3, vec![0u8; 5]).is_err());
    }

    #[test]
    fn row_major_indexing() {
        let g = Grid::from_fn(3, 2, |x, y| x + 10 * y);
        assert_eq!(*g.get(2, 1), 12);
        assert_eq!(g.row(1), &[10, 11, 12]);
        assert_eq!(g.get_checked(-1, 0), None);
        assert_eq!(g.get_checked(3, 0), None);
    }

    #[test]
    fn dilation_is_the_chebyshev_square_up_to_the_borders() {
        let mut mask = Grid::filled(7, 5, false);
        *mask.get_mut(1, 1) = true;
        *mask.get_mut(6, 4) = true;
        let near = |x: usize, y: usize, r: usize| {
            [(1usize, 1usize), (6, 4)]
                .iter()
                .any(|&(a, b)| x.abs_diff(a) <= r && y.abs_diff(b) <= r)
        };
        for r in 0..4 {
            let grown = mask.dilated(r);
            for y in 0..5 {
                for x in 0..7 {
                    assert_eq!(*grown.get(x, y), near(x, y, r), "r {r} ({x}, {y})");
                }
            }
        }
    }

    #[test]
    fn bilinear_interpolates_and_clamps() {
        let g = Grid::from_fn(2, 2, |x, y| (x + 2 * y) as f32);
        assert!((g.sample_bilinear(0.5, 0.5) - 1.5).abs() < 1e-6);
        assert!((g.sample_bilinear(-5.0, 0.0) - 0.0).abs() < 1e-6);
        assert!((g.sample_bilinear(9.0, 9.0) - 3.0).abs() < 1e-6);
    }
}
