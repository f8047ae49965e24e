//! Numeric helpers shared by the pipeline: the same bits on every platform, and fast in the hot
//! loops of the solvers.
//!
//! Transcendental functions come from the `libm` crate, never from `f64`'s methods: those call
//! the platform's maths library (glibc natively, a Rust port on wasm32), whose results differ in
//! the last bit for some inputs, and the soup's discrete choices (RANSAC, assignments,
//! truncations) amplify one bit into a different reconstruction. With these the command line
//! and the page give the same depth for the same input. Only `sqrt` (exactly rounded by IEEE
//! 754) and the basic operations are taken from the language. Test-data generation
//! ([`crate::synth`]) and the viewer ([`crate::render`]) are exempt: they do not make results.

/// The smaller of `a` and `b`, or `a` when `b` is NaN: the same as `a.min(b)` for any `a` that
/// is not NaN. `f64::min` also ignores a NaN `a`, which wasm's `f64.min` instruction cannot, so
/// on wasm32 it compiles to a call to libm's `fmin` (measured: 14 % of the page's run time,
/// most of it in TRW-S's message loops); this compiles to a comparison and a select everywhere.
#[inline(always)]
pub fn min(a: f64, b: f64) -> f64 {
    if b < a { b } else { a }
}

/// Natural logarithm.
#[inline]
pub fn ln(x: f64) -> f64 {
    libm::log(x)
}

/// e^x.
#[inline]
pub fn exp(x: f64) -> f64 {
    libm::exp(x)
}

/// Base-2 logarithm.
#[inline]
pub fn log2(x: f64) -> f64 {
    libm::log2(x)
}

/// Cosine (radians).
#[inline]
pub fn cos(x: f64) -> f64 {
    libm::cos(x)
}

/// Sine (radians).
#[inline]
pub fn sin(x: f64) -> f64 {
    libm::sin(x)
}

/// The angle of the point (x, y) from the positive x axis, in (−π, π] (radians).
#[inline]
pub fn atan2(y: f64, x: f64) -> f64 {
    libm::atan2(y, x)
}

/// Hyperbolic tangent.
#[inline]
pub fn tanh(x: f64) -> f64 {
    libm::tanh(x)
}

/// Inverse hyperbolic tangent.
#[inline]
pub fn atanh(x: f64) -> f64 {
    libm::atanh(x)
}

/// x^y.
#[inline]
pub fn pow(x: f64, y: f64) -> f64 {
    libm::pow(x, y)
}

/// √(x² + y²) without overflow.
#[inline]
pub fn hypot(x: f64, y: f64) -> f64 {
    libm::hypot(x, y)
}

/// x^y, single precision.
#[inline]
pub fn pow_f32(x: f32, y: f32) -> f32 {
    libm::powf(x, y)
}

/// Natural logarithm, single precision.
#[inline]
pub fn ln_f32(x: f32) -> f32 {
    libm::logf(x)
}

/// The angle of (x, y) from the x axis (radians), single precision.
#[inline]
pub fn atan2_f32(y: f32, x: f32) -> f32 {
    libm::atan2f(y, x)
}

/// √(x² + y²) without overflow, single precision.
#[inline]
pub fn hypot_f32(x: f32, y: f32) -> f32 {
    libm::hypotf(x, y)
}

/// The weighted median of the values v of `items` (weight, v), sorting them by v: the value
/// where the weight below it and the weight above it each stay under half the total, or the
/// mean of two neighbouring values where the weight up to the first is exactly half (so with
/// equal weights it is the plain median). `None` without positive total weight.
pub fn weighted_median(items: &mut [(f64, f64)]) -> Option<f64> {
    items.sort_by(|a, b| a.1.total_cmp(&b.1));
    let total: f64 = items.iter().map(|t| t.0).sum();
    if total.is_nan() || total <= 0.0 {
        return None;
    }
    let mut below = 0.0;
    for (k, &(w, v)) in items.iter().enumerate() {
        below += w;
        if below == 0.5 * total
            && let Some(&(_, next)) = items[k + 1..].iter().find(|t| t.0 > 0.0)
        {
            return Some(0.5 * (v + next));
        }
        if below >= 0.5 * total {
            return Some(v);
        }
    }
    items.last().map(|t| t.1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn min_agrees_with_the_library_unless_the_first_argument_is_nan() {
        let values = [
            f64::NEG_INFINITY,
            -2.5,
            -0.0,
            0.0,
            1e-300,
            3.0,
            f64::INFINITY,
            f64::NAN,
        ];
        for a in values.into_iter().filter(|a| !a.is_nan()) {
            for b in values {
                assert_eq!(min(a, b), a.min(b), "min({a}, {b})");
            }
        }
    }

    #[test]
    fn the_functions_agree_with_the_platform_within_an_ulp_or_two() {
        for k in 1..2000 {
            let x = k as f64 * 0.0137;
            let close = |a: f64, b: f64| (a - b).abs() <= 4.0 * f64::EPSILON * b.abs().max(1e-300);
            assert!(close(ln(x), x.ln()), "ln {x}");
            assert!(close(exp(x / 10.0), (x / 10.0).exp()), "exp {x}");
            assert!(
                (cos(x) - x.cos()).abs() < 1e-15 && (sin(x) - x.sin()).abs() < 1e-15,
                "{x}"
            );
            let u = x / 30.0 - 0.5;
            assert!(
                close(tanh(u), u.tanh()) && close(atanh(u), u.atanh()),
                "{u}"
            );
            assert!(
                close(pow(x, 2.4), x.powf(2.4)) && close(hypot(x, u), x.hypot(u)),
                "{x}"
            );
            assert!(close(log2(x), x.log2()), "{x}");
            let xf = x as f32;
            let closef = |a: f32, b: f32| (a - b).abs() <= 4.0 * f32::EPSILON * b.abs().max(1e-30);
            assert!(closef(ln_f32(xf), xf.ln()) && closef(hypot_f32(xf, 1.0), xf.hypot(1.0)));
            assert!(closef(pow_f32(xf, 2.4), xf.powf(2.4)), "{x}");
            assert!(
                (atan2_f32(xf, 1.0 - xf) - xf.atan2(1.0 - xf)).abs() < 1e-6,
                "{x}"
            );
        }
    }

    #[test]
    fn weighted_medians_split_the_weight() {
        let mut items = vec![(1.0, 3.0), (0.5, -1.0), (2.0, 0.5), (0.2, 9.0)];
        assert_eq!(weighted_median(&mut items), Some(0.5));
        let mut heavy = vec![(0.1, 0.0), (5.0, 2.0)];
        assert_eq!(weighted_median(&mut heavy), Some(2.0));
        assert_eq!(weighted_median(&mut []), None);
        assert_eq!(weighted_median(&mut [(0.0, 1.0)]), None);
        // Equal weights: the plain median, the mean of the middle two for an even count.
        assert_eq!(
            weighted_median(&mut [(1.0, 4.0), (1.0, 1.0), (1.0, 2.0)]),
            Some(2.0)
        );
        assert_eq!(weighted_median(&mut [(1.0, 4.0), (1.0, 1.0)]), Some(2.5));
        // A light value on one side moves the median less than a heavy one.
        let mut guesses = vec![(1.0, 1.0), (0.25, 5.0), (0.25, 6.0), (1.0, 1.2)];
        assert_eq!(weighted_median(&mut guesses), Some(1.2));
    }
}
