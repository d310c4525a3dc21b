//! Interval arithmetic: ranges [lo, hi] that contain every value a quantity takes over a
//! set of inputs. The sparse evaluation (docs/performance.md) bounds the model's outputs
//! over a run of samples with it. Endpoints are rounded to nearest, not outwards: a user of
//! a bound widens it by a margin far above the rounding (see `delta::bounds`).

use std::ops::{Add, Mul, Neg, Sub};

/// The closed range [lo, hi] (lo ≤ hi unless a NaN went in).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Interval {
    pub lo: f64,
    pub hi: f64,
}

impl Interval {
    /// The range of the two values, in either order.
    #[inline(always)]
    pub fn hull(a: f64, b: f64) -> Interval {
        Interval {
            lo: lesser(a, b),
            hi: greater(a, b),
        }
    }

    /// The smallest range holding both. The upper end is [`greater`] written as `o.hi <
    /// self.hi`, the same comparison (NaN included): both ends then compare with one
    /// predicate, and LLVM joins the boxes' packed [lo, hi] lanes with one `vcmpltpd` and
    /// blends instead of a compare per predicate and a pack of the two masks (the
    /// whole-move pass's join of each piece's box: −0.8 % of a default run's instructions,
    /// −0.6 % of a shaped run's, docs/performance.md).
    #[inline(always)]
    pub fn join(self, o: Interval) -> Interval {
        Interval {
            lo: lesser(self.lo, o.lo),
            hi: if o.hi < self.hi { self.hi } else { o.hi },
        }
    }

    /// The single value `x`.
    #[inline(always)]
    pub fn point(x: f64) -> Interval {
        Interval { lo: x, hi: x }
    }

    /// `x` ± `r` (r ≥ 0).
    #[inline(always)]
    pub fn around(x: f64, r: f64) -> Interval {
        Interval {
            lo: x - r,
            hi: x + r,
        }
    }

    /// The range widened by `r` on each side.
    #[inline(always)]
    pub fn widen(self, r: f64) -> Interval {
        Interval {
            lo: self.lo - r,
            hi: self.hi + r,
        }
    }

    /// The largest magnitude in the range.
    #[inline(always)]
    pub fn mag(self) -> f64 {
        greater(self.lo.abs(), self.hi.abs())
    }

    /// The range of x² (tighter than x·x when the range holds zero).
    #[inline(always)]
    pub fn sqr(self) -> Interval {
        let (a, b) = (self.lo * self.lo, self.hi * self.hi);
        if self.lo <= 0.0 && self.hi >= 0.0 {
            Interval {
                lo: 0.0,
                hi: greater(a, b),
            }
        } else {
            Interval::hull(a, b)
        }
    }

    /// The range of √x, for a range of non-negative values.
    #[inline(always)]
    pub fn sqrt(self) -> Interval {
        Interval {
            lo: greater(self.lo, 0.0).sqrt(),
            hi: self.hi.sqrt(),
        }
    }

    /// The range of 1/x, or None when the range holds zero.
    #[inline(always)]
    pub fn recip(self) -> Option<Interval> {
        (self.lo > 0.0 || self.hi < 0.0).then(|| Interval::hull(1.0 / self.lo, 1.0 / self.hi))
    }

    /// Whether both ends are finite.
    #[inline(always)]
    pub fn is_finite(self) -> bool {
        self.lo.is_finite() && self.hi.is_finite()
    }
}

impl Add for Interval {
    type Output = Interval;
    #[inline(always)]
    fn add(self, o: Interval) -> Interval {
        Interval {
            lo: self.lo + o.lo,
            hi: self.hi + o.hi,
        }
    }
}

impl Sub for Interval {
    type Output = Interval;
    #[inline(always)]
    fn sub(self, o: Interval) -> Interval {
        Interval {
            lo: self.lo - o.hi,
            hi: self.hi - o.lo,
        }
    }
}

impl Neg for Interval {
    type Output = Interval;
    #[inline(always)]
    fn neg(self) -> Interval {
        Interval {
            lo: -self.hi,
            hi: -self.lo,
        }
    }
}

/// The smaller of two numbers that are not NaN: one instruction, where `f64::min` spends
/// four on NaN (every operation here uses it, and so do the planner, the reports' peaks
/// and the sampled moves' shares: 1.9 % of a run's instructions, docs/performance.md).
/// With `a` NaN it gives `b`, as `f64::min` does, so callers put first the operand that
/// could be NaN. Intervals are meant for finite values: a NaN may be dropped or kept, as
/// `f64::min` may drop it too. The products of finite intervals are NaN only from 0·∞,
/// which a user of the bounds rules out by refusing huge or NaN inputs (`delta::bounds`).
#[inline(always)]
pub(crate) fn lesser(a: f64, b: f64) -> f64 {
    if a < b { a } else { b }
}

/// The greater of two numbers that are not NaN (see [`lesser`]).
#[inline(always)]
pub(crate) fn greater(a: f64, b: f64) -> f64 {
    if a > b { a } else { b }
}

impl Mul for Interval {
    type Output = Interval;
    #[inline(always)]
    fn mul(self, o: Interval) -> Interval {
        let (a, b, c, d) = (
            self.lo * o.lo,
            self.lo * o.hi,
            self.hi * o.lo,
            self.hi * o.hi,
        );
        Interval {
            lo: lesser(lesser(a, b), lesser(c, d)),
            hi: greater(greater(a, b), greater(c, d)),
        }
    }
}

impl Interval {
    /// The range of x·r for a range `r` of positive values (`r.lo` > 0), x this range: the
    /// lower end from x's lower end, the upper from its upper. Rounding to nearest is
    /// monotonic, so `x.lo·r` is at most `x.hi·r` at each end of `r`, and these two
    /// products of each end are the least and greatest of `x * r`'s four: the same values,
    /// bit for bit but for the sign of a zero (which no bound keeps: a zero end only ever
    /// meets a product, a sum with a nonzero value, or a margin widening it), with two of
    /// the six comparisons.
    #[inline(always)]
    pub fn times_positive(self, r: Interval) -> Interval {
        Interval {
            lo: lesser(self.lo * r.lo, self.lo * r.hi),
            hi: greater(self.hi * r.lo, self.hi * r.hi),
        }
    }
}

impl Mul<f64> for Interval {
    type Output = Interval;
    #[inline(always)]
    fn mul(self, k: f64) -> Interval {
        Interval::hull(self.lo * k, self.hi * k)
    }
}

impl Add<f64> for Interval {
    type Output = Interval;
    #[inline(always)]
    fn add(self, k: f64) -> Interval {
        Interval {
            lo: self.lo + k,
            hi: self.hi + k,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn range() -> impl Strategy<Value = (Interval, f64)> {
        // An interval and a point in it (t ∈ [0, 1] along it).
        (-1e3..1e3f64, 0.0..1e3f64, 0.0..=1.0f64)
            .prop_map(|(lo, w, t)| (Interval { lo, hi: lo + w }, lo + t * w))
    }

    /// `lesser` and `greater` are `f64::min` and `max` on numbers, and like them give the
    /// second operand when the first is NaN (the order their callers rely on).
    #[test]
    fn lesser_and_greater_are_min_and_max_and_drop_a_first_nan() {
        let values = [
            -3.5,
            -0.0,
            0.0,
            1e-300,
            2.0,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ];
        for a in values {
            for b in values {
                assert_eq!(lesser(a, b), a.min(b), "{a} {b}");
                assert_eq!(greater(a, b), a.max(b), "{a} {b}");
            }
            assert_eq!(lesser(f64::NAN, a).to_bits(), a.to_bits());
            assert_eq!(greater(f64::NAN, a).to_bits(), a.to_bits());
        }
    }

    fn holds(i: Interval, x: f64) -> bool {
        // Round to nearest: an endpoint may be one rounding off the exact one.
        let slack = 1e-12 * (1.0 + x.abs());
        i.lo - slack <= x && x <= i.hi + slack
    }

    proptest! {
        #[test]
        fn every_operation_contains_its_value_at_any_point((a, x) in range(), (b, y) in range()) {
            prop_assert!(holds(a + b, x + y));
            prop_assert!(holds(a - b, x - y));
            prop_assert!(holds(-a, -x));
            prop_assert!(holds(a * b, x * y));
            prop_assert!(holds(a * 3.5, x * 3.5));
            prop_assert!(holds(a * -2.0, x * -2.0));
            prop_assert!(holds(a + 7.0, x + 7.0));
            prop_assert!(holds(a.sqr(), x * x));
            prop_assert!(holds(a.widen(0.5), x));
            prop_assert!(a.mag() >= x.abs());
            if x >= 0.0 {
                let p = Interval { lo: a.lo.max(0.0), hi: a.hi };
                prop_assert!(holds(p.sqrt(), x.sqrt()));
            }
            match a.recip() {
                Some(r) => prop_assert!(holds(r, 1.0 / x)),
                None => prop_assert!(a.lo <= 0.0 && a.hi >= 0.0),
            }
        }
    }

    proptest! {
        /// A product by a range of positive values is the general product, end for end
        /// (`==`: a zero's sign aside), over ranges of either sign, wide or a point, and
        /// ends with and without zeros.
        #[test]
        fn a_product_by_a_positive_range_is_the_product(
            (a, _) in range(), r_lo in 1e-3..1e3f64, r_w in 0.0..1e3f64,
            ends in prop::sample::select(vec![(1.0, 1.0), (0.0, 1.0), (-0.0, 0.0), (1.0, 0.0)]),
        ) {
            let r = Interval { lo: r_lo, hi: r_lo + r_w };
            for x in [a, Interval::hull(a.lo * ends.0, a.hi * ends.1)] {
                let (got, want) = (x.times_positive(r), x * r);
                prop_assert!(got.lo == want.lo && got.hi == want.hi, "{x:?} {r:?}: {got:?} {want:?}");
            }
        }
    }

    #[test]
    fn a_square_around_zero_starts_at_zero() {
        let i = Interval { lo: -2.0, hi: 3.0 };
        assert_eq!(i.sqr(), Interval { lo: 0.0, hi: 9.0 });
        assert_eq!((i * i).lo, -6.0);
        assert_eq!(Interval::hull(4.0, -1.0), Interval { lo: -1.0, hi: 4.0 });
        assert_eq!(Interval::around(1.0, 0.5).mag(), 1.5);
        assert_eq!(Interval::point(2.0).recip(), Some(Interval::point(0.5)));
    }
}
