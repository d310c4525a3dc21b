//! `S_CURVE_ACCELERATION`: the stepper's rate follows a quintic Bézier in time over each
//! acceleration and deceleration phase (`Stepper::_calc_bezier_curve_setup`,
//! `_eval_bezier_curve`): v(τ) = v0 + Δv·(10τ³ − 15τ⁴ + 6τ⁵), τ = t/T, over the trapezoid
//! phase's time T and distance, so the acceleration a·30τ²(1 − τ)² is 0 at both ends and
//! 1.875 a at the middle. A [`Ramp`] has a constant acceleration, so a phase is drawn as
//! [`SIDE_PIECES`] pieces on each side of a narrow middle piece: each side piece has the
//! Bézier's mean acceleration over its time (the rate is exact at its ends), the middle
//! piece the peak itself (so the peak is never under-reported), and a constant taken off
//! the rate makes the step count the stepper makes ([`super::isr`]: its rate lags the
//! Bézier's). The stepper evaluates the Bézier at the time since the block started, so a
//! span of the phase can be drawn (the first step runs before it; a deceleration can end
//! before its phase does).

use arrayvec::ArrayVec;

use super::trapezoid::Ramp;
use crate::motion::Phase;

/// Pieces on each side of the middle piece.
pub const SIDE_PIECES: u32 = 8;

/// The most piece boundaries of a phase ([`Bezier::pieces`]): its two ends and the side
/// pieces' boundaries on either side of the middle.
const MAX_BOUNDS: usize = 2 * (SIDE_PIECES as usize + 1) + 2;

/// The middle piece spans τ ∈ [½ − h, ½ + h].
const MIDDLE_HALF_WIDTH: f64 = 0.005;
/// The Bézier's peak acceleration over the trapezoid's: 30/16.
pub const PEAK_RATIO: f64 = 1.875;

/// B(τ) = 10τ³ − 15τ⁴ + 6τ⁵: the share of the rate change made by τ.
pub fn share(tau: f64) -> f64 {
    tau * tau * tau * (10.0 + tau * (-15.0 + 6.0 * tau))
}

/// ∫₀^τ B: 2.5τ⁴ − 3τ⁵ + τ⁶ (½ at τ = 1).
pub fn share_integral(tau: f64) -> f64 {
    tau.powi(4) * (2.5 + tau * (-3.0 + tau))
}

/// ∫₀^τ B²: 100τ⁷/7 − 37.5τ⁸ + 115τ⁹/3 − 18τ¹⁰ + 36τ¹¹/11 (B² = 100τ⁶ − 300τ⁷ + 345τ⁸
/// − 180τ⁹ + 36τ¹⁰).
pub fn share_squared_integral(tau: f64) -> f64 {
    tau.powi(7)
        * (100.0 / 7.0 + tau * (-37.5 + tau * (115.0 / 3.0 + tau * (-18.0 + tau * 36.0 / 11.0))))
}

/// One Bézier phase of the stepper's rate: from `v0` to `v1` over `t_s`, then `v1`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bezier {
    pub v0: f64,
    pub v1: f64,
    pub t_s: f64,
}

impl Bezier {
    /// The rate at `t` s into the phase.
    pub fn rate(&self, t: f64) -> f64 {
        if t >= self.t_s {
            return self.v1;
        }
        self.v0 + (self.v1 - self.v0) * share((t / self.t_s).max(0.0))
    }

    /// The rate's derivative at `t`: Δv·30τ²(1 − τ)²/T.
    pub fn slope(&self, t: f64) -> f64 {
        let x = (t / self.t_s).clamp(0.0, 1.0);
        (self.v1 - self.v0) * 30.0 * x * x * (1.0 - x) * (1.0 - x) / self.t_s
    }

    /// ∫₀ᵗ v and ∫₀ᵗ v² over the phase (t within it).
    pub fn integrals(&self, t: f64) -> (f64, f64) {
        let x = (t / self.t_s).clamp(0.0, 1.0);
        let dv = self.v1 - self.v0;
        let v = self.v0 * t + dv * self.t_s * share_integral(x);
        let v2 = self.t_s
            * (self.v0 * self.v0 * x
                + 2.0 * self.v0 * dv * share_integral(x)
                + dv * dv * share_squared_integral(x));
        (v, v2)
    }

    /// The phase from `ta` to `tb` s as pieces from step `s0`, making `steps`: the Bézier's
    /// rate less a constant (the stepper's lag or lead, [`super::isr`]). The side pieces have
    /// the Bézier's mean acceleration over their time, the middle one (τ = ½) the peak; a
    /// boundary within a quarter piece of `ta` or `tb` is dropped, so no piece is a sliver.
    pub fn pieces(&self, ta: f64, tb: f64, s0: f64, steps: f64, phase: Phase, out: &mut Vec<Ramp>) {
        let (xa, xb) = (ta / self.t_s, tb / self.t_s);
        let h = MIDDLE_HALF_WIDTH;
        let side = f64::from(SIDE_PIECES);
        let margin = 0.25 * (0.5 - h) / side;
        // On the stack: a vector here was allocated, grown and freed for every phase, 4 % of
        // a Marlin run's time in the allocator (docs/performance.md, eighteenth session).
        let mut bounds = ArrayVec::<f64, MAX_BOUNDS>::new();
        bounds.push(xa);
        bounds.extend(
            (0..=SIDE_PIECES)
                .map(|k| (0.5 - h) * f64::from(k) / side)
                .chain((0..=SIDE_PIECES).map(|k| 0.5 + h + (0.5 - h) * f64::from(k) / side))
                .filter(|&x| x > xa + margin && x < xb - margin),
        );
        bounds.push(xb);
        let peak = PEAK_RATIO * (self.v1 - self.v0) / self.t_s;
        let first = out.len();
        let (mut s, mut v) = (s0, self.rate(ta));
        for w in bounds.windows(2) {
            let (x0, x1) = (w[0], w[1]);
            let dt = (x1 - x0) * self.t_s;
            let accel = if x0 <= 0.5 && 0.5 < x1 {
                peak
            } else {
                (self.rate(x1 * self.t_s) - v) / dt
            };
            let piece = Ramp {
                dt_s: dt,
                s0: s,
                rate: v,
                accel,
                phase,
            };
            s = piece.s1();
            v += accel * dt;
            out.push(piece);
        }
        // The constant that makes the step count: taken off every piece's rate.
        let lag = (s - s0 - steps) / (tb - ta);
        let mut t = 0.0;
        for p in &mut out[first..] {
            p.rate -= lag;
            p.s0 -= lag * t;
            t += p.dt_s;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// T3: Δv = 100 mm/s at 1000 mm/s² (T = 0.1 s): v(T/4) = 10.35 mm/s, v(T/2) = 50 mm/s,
    /// the peak 1875 mm/s² at T/2, the distance 5 mm as the trapezoid's.
    #[test]
    fn the_bezier_peaks_at_1_875_times_the_acceleration_over_the_same_time_and_distance() {
        let bez = Bezier {
            v0: 0.0,
            v1: 100.0,
            t_s: 0.1,
        };
        assert!((bez.integrals(0.1).0 - 5.0).abs() < 1e-12);
        // ∫v² = T·Δv²·∫B² = 0.1 · 10⁴ · (100/7 − 37.5 + 115/3 − 18 + 36/11).
        let b2: f64 = 100.0 / 7.0 - 37.5 + 115.0 / 3.0 - 18.0 + 36.0 / 11.0;
        assert!((bez.integrals(0.1).1 - 1000.0 * b2).abs() < 1e-9);
        // … which a fine midpoint sum confirms.
        let k = 100_000;
        let sum: f64 = (0..k)
            .map(|i| bez.rate((i as f64 + 0.5) * 0.1 / k as f64).powi(2) * 0.1 / k as f64)
            .sum();
        assert!((sum - 1000.0 * b2).abs() < 1e-6, "{sum}");
        let mut out = Vec::new();
        bez.pieces(0.0, 0.1, 2.0, 5.0, Phase::Accel, &mut out);
        assert_eq!(out.len(), 2 * SIDE_PIECES as usize + 1);
        let time: f64 = out.iter().map(|p| p.dt_s).sum();
        assert!((time - 0.1).abs() < 1e-15);
        let end = out.last().unwrap();
        assert!((end.s1() - 7.0).abs() < 1e-12, "{}", end.s1());
        let v_end = end.rate + end.accel * end.dt_s;
        assert!((v_end - 100.0).abs() < 1e-3, "{v_end}");
        let peak = out.iter().map(|p| p.accel).fold(f64::MIN, f64::max);
        assert_eq!(peak, 1875.0);
        // The piece with τ = ½ in it is the peak.
        let mut t = 0.0;
        for p in &out {
            if t <= 0.05 && 0.05 < t + p.dt_s {
                assert_eq!(p.accel, 1875.0);
            }
            t += p.dt_s;
        }
        assert!((100.0 * share(0.25) - 10.3516).abs() < 1e-4);
        // Position within 10 µm of the Bézier's anywhere (here in mm).
        let mut t = 0.0;
        for p in &out {
            let tau = (t + 0.5 * p.dt_s) / 0.1;
            let want = 2.0 + 100.0 * 0.1 * share_integral(tau);
            let half = p.s0 + p.rate * 0.5 * p.dt_s + 0.125 * p.accel * p.dt_s * p.dt_s;
            assert!((half - want).abs() < 1e-2, "{half} {want}");
            t += p.dt_s;
        }
    }

    /// A span of the phase, 0.1 mm less than the Bézier's: pieces from τ = 0.1 to 0.7, the
    /// rate 0.1/0.06 mm/s under the Bézier's throughout, the peak kept, no sliver.
    #[test]
    fn a_span_makes_its_steps_with_the_rate_lowered_by_a_constant() {
        let bez = Bezier {
            v0: 20.0,
            v1: 120.0,
            t_s: 0.1,
        };
        let integral = bez.integrals(0.07).0 - bez.integrals(0.01).0;
        let mut out = Vec::new();
        bez.pieces(0.01, 0.07, 0.0, integral - 0.1, Phase::Accel, &mut out);
        let end = out.last().unwrap();
        assert!((end.s1() - (integral - 0.1)).abs() < 1e-12);
        let lag = 0.1 / 0.06;
        // (To the middle piece's excess over the Bézier: 0.05 mm/s.)
        assert!(
            (out[0].rate - (bez.rate(0.01) - lag)).abs() < 0.05,
            "{}",
            out[0].rate
        );
        let v_end = end.rate + end.accel * end.dt_s;
        assert!((v_end - (bez.rate(0.07) - lag)).abs() < 0.05, "{v_end}");
        assert!(out.iter().any(|p| p.accel == 1875.0));
        // No piece but the middle one (1 % of T) is shorter than a quarter side piece.
        let side = 0.1 * 0.495 / 8.0;
        assert!(
            out.iter()
                .all(|p| p.dt_s >= 0.25 * side || p.accel == 1875.0)
        );
    }
}
