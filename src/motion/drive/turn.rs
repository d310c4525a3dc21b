//! sin and cos of the lag's turn ω_d·τ over a piece (`Response::turn`), in 77 instructions
//! where the C library's `sincos` takes 128.
//!
//! The drive stage turns the lag once per commanded piece, and most pieces' durations are
//! new (70 % without a shaper on the corpus's bunny), so `sincos` was 17 % of the drive
//! thread's instructions (docs/performance.md, fourteenth session). Its arguments are
//! bounded here (a piece lasts seconds at most, ω_d·τ a few thousand): the reduction by
//! π/2 in three parts (Cody and Waite) is exact enough up to [`MAX_REDUCED`], and the
//! quarter turn left is the Taylor series, whose terms past the last are below the last
//! place. Beyond, and for NaN or infinities, the library's `sin_cos`.

use std::f64::consts::FRAC_2_PI;

/// π/2 as the sum of three parts, the first two of 33 significant bits: k·`PIO2_1` and
/// k·`PIO2_2` are exact for k below 2^20, and the three leave out 1e-37 of π/2.
const PIO2_1: f64 = 1.570_796_326_734_125_6;
const PIO2_2: f64 = 6.077_100_506_303_966e-11;
const PIO2_3: f64 = 2.022_266_248_795_950_6e-21;

/// The largest |x| reduced here: k = x·2/π stays below 2^20.
const MAX_REDUCED: f64 = 1.0e6;

/// 1.5·2^52: a double of magnitude below 2^51 plus this is rounded to an integer.
pub(crate) const ROUND: f64 = 6_755_399_441_055_744.0;

/// 1/n! for the odd n from 3 to 17 (sin) and the even n from 4 to 18 (cos), alternating in
/// sign: |r|^19/19! and |r|^20/20! at |r| ≤ π/4 are below 1e-19.
const SIN: [f64; 8] = [
    -1.0 / 6.0,
    1.0 / 120.0,
    -1.0 / 5_040.0,
    1.0 / 362_880.0,
    -1.0 / 39_916_800.0,
    1.0 / 6_227_020_800.0,
    -1.0 / 1_307_674_368_000.0,
    1.0 / 355_687_428_096_000.0,
];
const COS: [f64; 8] = [
    1.0 / 24.0,
    -1.0 / 720.0,
    1.0 / 40_320.0,
    -1.0 / 3_628_800.0,
    1.0 / 479_001_600.0,
    -1.0 / 87_178_291_200.0,
    1.0 / 20_922_789_888_000.0,
    -1.0 / 6_402_373_705_728_000.0,
];

/// Horner's scheme of `coefficients` (lowest power first) at `z`.
#[inline(always)]
fn horner(coefficients: &[f64; 8], z: f64) -> f64 {
    let [rest @ .., last] = coefficients;
    rest.iter().rev().fold(*last, |acc, &c| acc * z + c)
}

/// (sin x, cos x), within a unit or two in the last place of the library's.
#[inline]
pub fn sin_cos(x: f64) -> (f64, f64) {
    if x.is_nan() || x.abs() > MAX_REDUCED {
        return x.sin_cos();
    }
    // x = k·π/2 + r, |r| ≤ π/4 (and a rounding). The sum's last bits are k's (|k| < 2^20,
    // the sum 1.5·2^52 + k), which a saturating float conversion would take six
    // instructions to give.
    let shifted = x * FRAC_2_PI + ROUND;
    let k = shifted - ROUND;
    let r = ((x - k * PIO2_1) - k * PIO2_2) - k * PIO2_3;
    let z = r * r;
    let s = r + r * z * horner(&SIN, z);
    let c = 1.0 - 0.5 * z + z * z * horner(&COS, z);
    // The quadrant: sin and cos of r turned by k quarter turns, swapped when k is odd, each
    // sign set by a bit (no branch: the quadrants come at random).
    let q = shifted.to_bits();
    let (s, c) = if q & 1 == 1 { (c, s) } else { (s, c) };
    (
        f64::from_bits(s.to_bits() ^ ((q & 2) << 62)),
        f64::from_bits(c.to_bits() ^ ((q.wrapping_add(1) & 2) << 62)),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The spacing of doubles at |y| (the smallest subnormal at 0).
    fn ulp(y: f64) -> f64 {
        let a = y.abs();
        f64::from_bits(a.to_bits() + 1) - a
    }

    /// Within `n` units in the last place of the library's value.
    fn close(got: f64, want: f64, n: f64) -> bool {
        (got - want).abs() <= n * ulp(want)
    }

    fn check(x: f64) {
        let (s, c) = sin_cos(x);
        let (ws, wc) = x.sin_cos();
        assert!(close(s, ws, 2.0), "sin {x}: {s} against {ws}");
        assert!(close(c, wc, 2.0), "cos {x}: {c} against {wc}");
    }

    proptest! {
        /// Over the lag's turns of every piece length, and each quadrant's ends.
        #[test]
        fn agrees_with_the_library(x in 0.0..2.0e4f64, k in -2000i64..2000, d in -1e-3..1e-3f64) {
            check(x);
            check(-x);
            check(k as f64 * std::f64::consts::FRAC_PI_2 + d);
        }
    }

    #[test]
    fn agrees_at_zero_small_large_and_odd_arguments() {
        for x in [
            0.0,
            -0.0,
            1e-300,
            1e-8,
            std::f64::consts::FRAC_PI_4,
            std::f64::consts::PI,
            355.0,
            9.0e5,
            MAX_REDUCED,
            // The library's beyond.
            2.0e6,
            1e300,
        ] {
            check(x);
        }
        let (s, c) = sin_cos(f64::NAN);
        assert!(s.is_nan() && c.is_nan());
        let (s, c) = sin_cos(f64::INFINITY);
        assert!(s.is_nan() && c.is_nan());
    }
}
