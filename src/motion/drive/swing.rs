//! How far the actual acceleration swings over a whole piece, from the lag at both its
//! ends: much tighter than the ringing's envelope ([`Response::ringing`]) over a piece that
//! lasts less than a swing, which on the corpus's bunny is most of them
//! (docs/performance.md, "Fifth session").

use super::{Lag, Response};
use crate::interval::{Interval, greater, lesser};
#[cfg(target_arch = "x86_64")]
use crate::motion::{Avx2Axes, Axes};
use crate::path::Vec3;

/// The first half damped period of a piece, π/ω_d, is cut into this many windows; the
/// rest of a longer piece gets the ringing's envelope from there on. Instructions of
/// `check` on the first 5 MB of the corpus's bunny (default drive / MZV shaper): 2 windows
/// 2.169 / 4.977 G, 3 windows 2.157 / 4.960 G, 4 windows 2.186 / 4.968 G
/// (docs/performance.md).
pub const WINDOWS: usize = 3;

/// What [`Response::acceleration_range`] needs of the spring, computed once per response:
/// the windows' length, the transition matrix of the lag's free part over it (as
/// [`super::LagWalk`] uses) and the decay e^(−σ·k·step) at each window's start.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(super) struct Windows {
    step_s: f64,
    turn: [[f64; 2]; 2],
    decay: [f64; WINDOWS + 1],
}

/// ω²L²/8 of a window of length L (see [`Range::window`]).
#[inline(always)]
fn curve(r: &Response, length_s: f64) -> f64 {
    r.omega2 * length_s * length_s * 0.125
}

impl Windows {
    pub(super) fn new(r: &Response) -> Windows {
        let step_s = std::f64::consts::PI / r.omega_d / WINDOWS as f64;
        Windows {
            step_s,
            turn: r.transition(step_s),
            decay: std::array::from_fn(|k| (-r.sigma * step_s * k as f64).exp()),
        }
    }
}

/// Where the actual acceleration's free part w stands at a window's end, per axis: its
/// value and its rate.
#[derive(Clone, Copy)]
struct End {
    w: [f64; 3],
    rate: [f64; 3],
}

/// The range of w over the windows so far, per axis.
#[derive(Clone, Copy)]
struct Range {
    lo: [f64; 3],
    hi: [f64; 3],
}

impl Range {
    /// A window from `a` to `b`, where w's envelope is at most `amplitude` and its second
    /// derivative at most `amplitude`·ω², its length L given as `curve` = ω²L²/8.
    ///
    /// A damped sinusoid's extrema lie π/ω_d apart (the zeros of its rate, a damped
    /// sinusoid of the same frequency), so a window shorter than that holds at most one,
    /// and it holds one exactly when the rate changes sign between its ends: a maximum
    /// where it goes from positive to negative, a minimum the other way. The extremum is
    /// at most the envelope, and, the rate being 0 there and the second derivative at most
    /// M = `amplitude`·ω², at most M·d²/2 beyond an end d away: beyond the nearer end by at
    /// most M·L²/8. Without branches on the signs (they change from piece to piece, which
    /// the branch predictor cannot guess).
    #[inline(always)]
    fn window(&mut self, a: &End, b: &End, amplitude: [f64; 3], curve: f64) {
        for (i, &amplitude) in amplitude.iter().enumerate() {
            let beyond = amplitude * curve;
            let top = lesser(greater(a.w[i], b.w[i]) + beyond, amplitude);
            let bottom = greater(lesser(a.w[i], b.w[i]) - beyond, -amplitude);
            let up = (a.rate[i] > 0.0) & (b.rate[i] <= 0.0);
            let down = (a.rate[i] < 0.0) & (b.rate[i] >= 0.0);
            let hi = greater(self.hi[i], b.w[i]);
            let lo = lesser(self.lo[i], b.w[i]);
            self.hi[i] = greater(hi, if up { top } else { hi });
            self.lo[i] = lesser(lo, if down { bottom } else { lo });
        }
    }
}

impl Response {
    /// The range of the actual acceleration (mm/s², per axis) over a whole commanded piece
    /// of acceleration `a_c` lasting `dt_s`, from `start`, the lag at its beginning, to
    /// `end`, the lag at its end ([`Self::lag_at`] at `dt_s`); `envelope` is the ringing's
    /// acceleration amplitude from the start ([`Self::ringing`] at 0, `acc`).
    ///
    /// The actual acceleration is a_c − w, with w = ω²u + 2σu̇ a damped sinusoid whose rate
    /// is ẇ = ω²u̇ − 2σw. The first half damped period is cut into [`WINDOWS`] windows,
    /// their ends reached by a fixed turn of (u, u̇), the last one's end being `end`: over
    /// each, w's range is its ends' hull, widened where the window holds an extremum
    /// ([`Range::window`]); a piece longer than that gets the envelope from there on.
    ///
    /// Inlined into the box of a piece: out of line, its arguments and result went through
    /// memory (3.6 % of a default run's worker instructions more). With `AVX2` (only in code
    /// compiled for AVX2, which runs only on a CPU with it), the three axes in one register
    /// ([`Self::acceleration_range_avx2`]).
    #[inline(always)]
    pub(crate) fn acceleration_range<const AVX2: bool>(
        &self,
        start: &Lag,
        end: &Lag,
        a_c: Vec3,
        dt_s: f64,
        envelope: Vec3,
    ) -> [Interval; 3] {
        #[cfg(target_arch = "x86_64")]
        if AVX2 {
            // SAFETY: `AVX2` is set only in code compiled for AVX2, chosen at run time on a
            // CPU that has it.
            return unsafe { self.acceleration_range_avx2(start, end, a_c, dt_s, envelope) };
        }
        self.acceleration_range_scalar(start, end, a_c, dt_s, envelope)
    }

    /// [`Self::acceleration_range`] an axis at a time.
    #[inline(always)]
    fn acceleration_range_scalar(
        &self,
        start: &Lag,
        end: &Lag,
        a_c: Vec3,
        dt_s: f64,
        envelope: Vec3,
    ) -> [Interval; 3] {
        let Windows {
            turn: [[m00, m01], [m10, m11]],
            decay,
            ..
        } = &self.windows;
        let (w2, two_sigma, to_e) = (self.omega2, 2.0 * self.sigma, self.to_e);
        let at = |u: &[f64; 3], du: &[f64; 3]| {
            let w: [f64; 3] = std::array::from_fn(|i| w2 * u[i] + two_sigma * du[i]);
            End {
                w,
                rate: std::array::from_fn(|i| w2 * du[i] - two_sigma * w[i]),
            }
        };
        // Windows [k·step, (k + 1)·step], the last one ending at the piece's end, unless the
        // piece outlasts them all (then the envelope from there on).
        let span = Span::new(self, dt_s);
        let (tail, x, full) = (span.tail, span.x, span.full);
        let e_p: [f64; 3] = std::array::from_fn(|i| a_c[i] * to_e);
        let mut u: [f64; 3] = std::array::from_fn(|i| start.e[i] - e_p[i]);
        let mut du: [f64; 3] = std::array::from_fn(|i| start.de[i]);
        let turn = |u: &mut [f64; 3], du: &mut [f64; 3]| {
            for i in 0..3 {
                (u[i], du[i]) = (m00 * u[i] + m01 * du[i], m10 * u[i] + m11 * du[i]);
            }
        };
        let mut a = at(&u, &du);
        let mut w = Range { lo: a.w, hi: a.w };
        let amplitude = |decay: f64| std::array::from_fn(|i| envelope[i] * decay);
        let mut n = 1;
        while n < WINDOWS && (tail || x >= n as f64) {
            turn(&mut u, &mut du);
            let b = at(&u, &du);
            w.window(&a, &b, amplitude(decay[n - 1]), full);
            a = b;
            n += 1;
        }
        let last = span.last(self, dt_s, n);
        if tail {
            turn(&mut u, &mut du);
        } else {
            u = std::array::from_fn(|i| end.e[i] - e_p[i]);
            du = std::array::from_fn(|i| end.de[i]);
        }
        w.window(&a, &at(&u, &du), amplitude(decay[n - 1]), last);
        if tail {
            // Past the windows, the envelope.
            for i in 0..3 {
                let peak = envelope[i] * decay[WINDOWS];
                w.hi[i] = greater(w.hi[i], peak);
                w.lo[i] = lesser(w.lo[i], -peak);
            }
        }
        std::array::from_fn(|i| Interval {
            lo: a_c[i] - w.hi[i],
            hi: a_c[i] - w.lo[i],
        })
    }
}

/// What the windows of [`Response::acceleration_range`] need of a piece lasting `dt`:
/// whether it outlasts them (`tail`), its length in windows (`x`, dt/step) and a full
/// window's length as ω²L²/8 (`full`). The windows before the last are the full ones
/// k·step ≤ dt (k < [`WINDOWS`]), found by comparisons in the windows' loop itself, which
/// LLVM unrolls: not a float's saturating conversion to `usize` (a dozen instructions on
/// x86-64), nor a count before a loop over the decays' slice (−0.26 % of a default run's
/// instructions in the AVX2 kernel, −0.23 % of a shaped run's in the scalar one).
struct Span {
    tail: bool,
    x: f64,
    full: f64,
}

impl Span {
    #[inline(always)]
    fn new(r: &Response, dt_s: f64) -> Span {
        let step_s = r.windows.step_s;
        Span {
            tail: dt_s > WINDOWS as f64 * step_s,
            x: dt_s / step_s,
            full: curve(r, step_s),
        }
    }

    /// The last window's length as ω²L²/8, the `n`th of a piece lasting `dt_s`: a full one
    /// when the piece outlasts the windows, else from the (n − 1)th window's end to the
    /// piece's.
    #[inline(always)]
    fn last(&self, r: &Response, dt_s: f64, n: usize) -> f64 {
        if self.tail {
            self.full
        } else {
            curve(r, dt_s - (n - 1) as f64 * r.windows.step_s)
        }
    }
}

#[cfg(target_arch = "x86_64")]
impl Response {
    /// [`Self::acceleration_range`] with the three axes in the lanes of one AVX2 register
    /// (the fourth zero): the same operations on each axis in the same order, so the same
    /// bits (test `the_range_holds_the_acceleration_at_every_instant`).
    #[target_feature(enable = "avx2")]
    #[inline]
    fn acceleration_range_avx2(
        &self,
        start: &Lag,
        end: &Lag,
        a_c: Vec3,
        dt_s: f64,
        envelope: Vec3,
    ) -> [Interval; 3] {
        use std::arch::x86_64::*;
        // A vector's three axes in one masked load, the fourth lane zero: building the lanes
        // from the axes took four instructions each, six vectors a piece (−0.75 % of a default
        // run's instructions).
        let lanes = |v: &Vec3| Avx2Axes::load(v).0;
        let k = |x: f64| _mm256_set1_pd(x);
        let (add, sub, mul) = (_mm256_add_pd, _mm256_sub_pd, _mm256_mul_pd);
        // −x, exactly: the sign bit flipped.
        let neg = |x: __m256d| _mm256_xor_pd(x, _mm256_set1_pd(-0.0));
        let Windows {
            turn: [[m00, m01], [m10, m11]],
            decay,
            ..
        } = &self.windows;
        let (w2, two_sigma, to_e) = (k(self.omega2), k(2.0 * self.sigma), self.to_e);
        let (m00, m01, m10, m11) = (k(*m00), k(*m01), k(*m10), k(*m11));
        let at = |u: __m256d, du: __m256d| {
            let w = add(mul(w2, u), mul(two_sigma, du));
            (w, sub(mul(w2, du), mul(two_sigma, w)))
        };
        let zero = _mm256_setzero_pd();
        // Range::window, an axis per lane: `lesser` and `greater` are `vminpd`/`vmaxpd`
        // (the first operand where it is strictly less/greater, else the second).
        let window = |lo: &mut __m256d,
                      hi: &mut __m256d,
                      (aw, arate): (__m256d, __m256d),
                      (bw, brate): (__m256d, __m256d),
                      amplitude: __m256d,
                      curve: f64| {
            let beyond = mul(amplitude, k(curve));
            let top = _mm256_min_pd(add(_mm256_max_pd(aw, bw), beyond), amplitude);
            let bottom = _mm256_max_pd(sub(_mm256_min_pd(aw, bw), beyond), neg(amplitude));
            let up = _mm256_and_pd(
                _mm256_cmp_pd::<_CMP_GT_OQ>(arate, zero),
                _mm256_cmp_pd::<_CMP_LE_OQ>(brate, zero),
            );
            let down = _mm256_and_pd(
                _mm256_cmp_pd::<_CMP_LT_OQ>(arate, zero),
                _mm256_cmp_pd::<_CMP_GE_OQ>(brate, zero),
            );
            let h = _mm256_max_pd(*hi, bw);
            let l = _mm256_min_pd(*lo, bw);
            *hi = _mm256_max_pd(h, _mm256_blendv_pd(h, top, up));
            *lo = _mm256_min_pd(l, _mm256_blendv_pd(l, bottom, down));
        };
        let span = Span::new(self, dt_s);
        let (tail, x, full) = (span.tail, span.x, span.full);
        let a4 = lanes(&a_c);
        let env = lanes(&envelope);
        let e_p = mul(a4, k(to_e));
        let mut u = sub(lanes(&start.e), e_p);
        let mut du = lanes(&start.de);
        let turn = |u: &mut __m256d, du: &mut __m256d| {
            (*u, *du) = (
                add(mul(m00, *u), mul(m01, *du)),
                add(mul(m10, *u), mul(m11, *du)),
            );
        };
        let mut a = at(u, du);
        let (mut lo, mut hi) = (a.0, a.0);
        let mut n = 1;
        while n < WINDOWS && (tail || x >= n as f64) {
            turn(&mut u, &mut du);
            let b = at(u, du);
            window(&mut lo, &mut hi, a, b, mul(env, k(decay[n - 1])), full);
            a = b;
            n += 1;
        }
        let last = span.last(self, dt_s, n);
        if tail {
            turn(&mut u, &mut du);
        } else {
            u = sub(lanes(&end.e), e_p);
            du = lanes(&end.de);
        }
        window(
            &mut lo,
            &mut hi,
            a,
            at(u, du),
            mul(env, k(decay[n - 1])),
            last,
        );
        if tail {
            // Past the windows, the envelope.
            let peak = mul(env, k(decay[WINDOWS]));
            hi = _mm256_max_pd(hi, peak);
            lo = _mm256_min_pd(lo, neg(peak));
        }
        // The intervals interleaved in the lanes: `array::from_fn` over the lanes stored
        // apart was called out of line, 70 instructions a piece (−2.8 % of a default run's
        // instructions).
        let (l, h) = (sub(a4, hi), sub(a4, lo));
        let (x, z) = (_mm256_unpacklo_pd(l, h), _mm256_unpackhi_pd(l, h));
        let mut out = [0.0; 6];
        // SAFETY: four doubles, then two, into an array of six.
        unsafe {
            _mm256_storeu_pd(out.as_mut_ptr(), _mm256_permute2f128_pd::<0x20>(x, z));
            _mm_storeu_pd(out.as_mut_ptr().add(4), _mm256_extractf128_pd::<1>(x));
        }
        let [l0, h0, l1, h1, l2, h2] = out;
        [
            Interval { lo: l0, hi: h0 },
            Interval { lo: l1, hi: h1 },
            Interval { lo: l2, hi: h2 },
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::super::Spring;
    use super::*;
    use proptest::prelude::*;

    fn response(frequency_hz: f64, damping_ratio: f64) -> Response {
        Response::new(&Spring {
            frequency_hz,
            damping_ratio,
        })
    }

    /// The actual acceleration every `h` s of the piece and at its end, by the closed
    /// form.
    fn dense(r: &Response, start: &Lag, a_c: Vec3, dt_s: f64, h: f64) -> Vec<Vec3> {
        let n = (dt_s / h).ceil() as usize;
        (0..=n)
            .map(|k| r.acceleration(&r.lag_at(start, a_c, (k as f64 * h).min(dt_s))))
            .collect()
    }

    /// The swing over a piece from `start`, in scalar code or (`AVX2`, only where the CPU
    /// has it) in the AVX2 lanes.
    fn range<const AVX2: bool>(r: &Response, start: &Lag, a_c: Vec3, dt_s: f64) -> [Interval; 3] {
        let envelope = r.ringing(start, a_c, 0.0).acc;
        r.acceleration_range::<AVX2>(start, &r.lag_at(start, a_c, dt_s), a_c, dt_s, envelope)
    }

    proptest! {
        /// Every instant of the piece, densely (1/50 of a window), lies in the range; a
        /// range that forgot an extremum inside a window or its bound beyond the nearer end
        /// (M·L²/8), or took windows longer than half a damped period, fails (each tried).
        /// The AVX2 lanes give the scalar range bit for bit (a window's length or decay
        /// taken wrong there fails it).
        #[test]
        fn the_range_holds_the_acceleration_at_every_instant(
            f in 20.0..120.0f64, zeta in 0.0..0.5f64,
            e in proptest::array::uniform3(-0.05..0.05f64),
            de in proptest::array::uniform3(-60.0..60.0f64),
            a_c in proptest::array::uniform3(-5000.0..5000.0f64),
            periods in 0.0..3.0f64,
        ) {
            let r = response(f, zeta);
            let start = Lag { e: Vec3::from(e), de: Vec3::from(de) };
            let a_c = Vec3::from(a_c);
            let dt_s = periods * r.period_s();
            let got = range::<false>(&r, &start, a_c, dt_s);
            #[cfg(target_arch = "x86_64")]
            if std::arch::is_x86_feature_detected!("avx2") {
                let bits = |x: [Interval; 3]| x.map(|i| (i.lo.to_bits(), i.hi.to_bits()));
                prop_assert_eq!(bits(range::<true>(&r, &start, a_c, dt_s)), bits(got));
            }
            let h = r.windows.step_s / 50.0;
            for acc in dense(&r, &start, a_c, dt_s, h) {
                for i in 0..3 {
                    let slack = 1e-9 * (1.0 + acc[i].abs());
                    prop_assert!(acc[i] >= got[i].lo - slack && acc[i] <= got[i].hi + slack,
                        "axis {i}: {} outside {:?}", acc[i], got[i]);
                }
            }
        }
    }

    #[test]
    fn over_a_short_piece_the_range_is_the_swing_not_the_envelope() {
        // A corner's ringing (a velocity jump of 30 mm/s on X) through the default drive,
        // over pieces of 2, 5 and 9 ms and one of 60 ms: within 5 % of the dense samples'
        // range over the short ones, where the envelope is up to twice as wide.
        let r = response(51.23, 0.1);
        let start = Lag {
            e: Vec3::zeros(),
            de: Vec3::new(-30.0, 0.0, 0.0),
        };
        let a_c = Vec3::new(3000.0, 0.0, 0.0);
        let envelope = r.ringing(&start, a_c, 0.0).acc[0];
        for (dt_s, tight) in [(0.002, true), (0.005, true), (0.009, true), (0.06, false)] {
            let got = range::<false>(&r, &start, a_c, dt_s)[0];
            let samples = dense(&r, &start, a_c, dt_s, 1e-6);
            let lo = samples.iter().map(|a| a[0]).fold(f64::INFINITY, f64::min);
            let hi = samples
                .iter()
                .map(|a| a[0])
                .fold(f64::NEG_INFINITY, f64::max);
            assert!(got.lo <= lo && got.hi >= hi, "{dt_s}: {got:?} [{lo}, {hi}]");
            let width = got.hi - got.lo;
            if tight {
                assert!(width <= (hi - lo) * 1.05, "{dt_s}: {width} {}", hi - lo);
                assert!(width < 2.0 * envelope * 0.6, "{dt_s}: {width} {envelope}");
            } else {
                // Past the windows the envelope from π/ω_d on.
                let tail = envelope * r.windows.decay[WINDOWS];
                assert!(width >= 2.0 * tail * 0.999);
            }
        }
    }
}
