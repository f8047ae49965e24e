//! Four `f32` lanes with element-wise arithmetic, written so the compiler turns each operation
//! into one SIMD instruction (SSE natively, simd128 in wasm builds that enable it) or four
//! independent scalar ones. The patch search's inner loops use it; sums over lanes keep a fixed
//! order, so results are bit-identical from run to run.

use std::ops::{Add, AddAssign, Mul, Sub};

/// Four lanes of `f32`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct F4(pub [f32; 4]);

impl F4 {
    /// All four lanes set to `value`.
    #[inline(always)]
    pub fn splat(value: f32) -> Self {
        F4([value; 4])
    }

    /// The first four values of `values` (which must hold at least four).
    #[inline(always)]
    pub fn load(values: &[f32]) -> Self {
        let mut lanes = [0.0; 4];
        lanes.copy_from_slice(&values[..4]);
        F4(lanes)
    }

    /// Sum of the lanes, (l0 + l2) + (l1 + l3).
    #[inline(always)]
    pub fn sum(self) -> f32 {
        (self.0[0] + self.0[2]) + (self.0[1] + self.0[3])
    }

    /// Lane-wise `f(self, other)`.
    #[inline(always)]
    fn zip(self, other: F4, f: impl Fn(f32, f32) -> f32) -> F4 {
        F4([
            f(self.0[0], other.0[0]),
            f(self.0[1], other.0[1]),
            f(self.0[2], other.0[2]),
            f(self.0[3], other.0[3]),
        ])
    }
}

impl Add for F4 {
    type Output = F4;
    #[inline(always)]
    fn add(self, other: F4) -> F4 {
        self.zip(other, |a, b| a + b)
    }
}

impl Sub for F4 {
    type Output = F4;
    #[inline(always)]
    fn sub(self, other: F4) -> F4 {
        self.zip(other, |a, b| a - b)
    }
}

impl Mul for F4 {
    type Output = F4;
    #[inline(always)]
    fn mul(self, other: F4) -> F4 {
        self.zip(other, |a, b| a * b)
    }
}

impl AddAssign for F4 {
    #[inline(always)]
    fn add_assign(&mut self, other: F4) {
        *self = *self + other;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lanes_compute_element_wise() {
        let a = F4::load(&[1.0, 2.0, 3.0, 4.0, 99.0]);
        let b = F4::splat(2.0);
        assert_eq!((a * b + a - b).0, [1.0, 4.0, 7.0, 10.0]);
        let mut acc = F4::default();
        acc += a;
        assert_eq!(acc.sum(), 10.0);
    }
}
