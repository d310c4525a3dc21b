//! When Marlin's stepper really makes a block's steps (`Stepper::block_phase_isr`,
//! stepper.cpp), in closed form: a few pieces per block, never one per step.
//!
//! The ISR does not integrate the step-rate trapezoid. At the block's load it runs the first
//! interval at `initial_rate`; after each step event it sets the next interval from a rate
//! evaluated at the time elapsed so far, `interval = ⌊TR / rate⌋` timer ticks (TR =
//! `STEPPER_TIMER_RATE`): accelerating while `step_events_completed ≤ accelerate_until`
//! (trapezoid: `rate = initial_rate + STEP_MULTIPLY(acceleration_time, acceleration_rate)`,
//! capped at `nominal_rate`; S-curve: the Bézier at `acceleration_time`, then
//! `cruise_rate`), cruising at `nominal_rate`, and decelerating after `decelerate_after` from
//! the rate reached (the Bézier from `cruise_rate`) by the time since the deceleration began,
//! floored at `final_rate`. So, with v(t) the rate law of a phase and t_k the k-th step event:
//!
//! ```text
//! t_1 = ⌊TR / initial_rate⌋ / TR,        t_{k+1} = t_k + ⌊TR / v(t_k)⌋ / TR.
//! ```
//!
//! The rate of an interval is v at its start (a left Riemann sum in time), so an accelerating
//! ISR falls behind the integrated profile and a decelerating one runs ahead of it. Let u_k =
//! v(t_k) (trapezoid: u = initial + a·t, so time is (u − initial)/a exactly) and w = u².
//! Without the tick truncation, `u_{k+1} = u_k ± a/u_k`, so `w_{k+1} = w_k ± 2a + a²/w_k`;
//! summing with the midpoint rule (Σ_{j<k} 1/w_j ≈ ∫ dx/w over [−½, k − ½]) gives the step
//! count reached at rate u — the curve through the step events (t_k, k), in closed form:
//!
//! ```text
//! accelerating from step 1 (u_1 = initial + a·t_1):
//!     k(u) = 1 + (u² − u_1²)/2a − ¼·ln((u² − a)/(u_1² − a))       (u_1² ≥ 4a always)
//! decelerating from step D + 1 at rate p:
//!     k(u) = D + 1 + (p² − u²)/2a + ¼·ln((p² + a)/(u² + a))
//! ```
//!
//! i.e. the integrated ramp, less (accelerating) or plus (decelerating) about ½·ln of the
//! rates' ratio in steps. The truncation of each interval to whole ticks makes a step
//! ε = ½ tick shorter on average, dk/dt = 1/(1/v − ε) ≈ v + ε·v², so ε·∫v² dt more steps:
//! ε·|u³ − u_1³|/3a on a ramp. The accelerating ISR reaches `nominal_rate` at the same time
//! as the integrated ramp, (nominal − initial)/a, but fewer steps into the block (the rest
//! cruise); a decelerating one ends its block before its rate has come down to the final
//! rate (it runs out of steps), which on a deceleration to a low rate saves milliseconds.
//! With the S-curve v(t) is the Bézier and the same first-order reasoning (the rate of an
//! interval is the rate half an interval, 1/2v, earlier) gives the lag ½·ln(v(t)/v(t_1)).
//!
//! Each phase is drawn as pieces through its first and last step event: the first interval
//! at the initial rate; a trapezoid ramp as one piece with Marlin's acceleration a between
//! them (the chord of the slowly varying ln term; two pieces meeting on the curve when the
//! rate more than doubles, as the lag is concentrated at low rates); an S-curve ramp as the
//! Bézier's pieces ([`super::scurve`], the 1.875 a peak kept) less a constant rate (per
//! half, split alike); cruises and the final rate at their whole-tick rates
//! ([`ticked_rate`]). So a block has at most 8 pieces (trapezoid) or 40 (S-curve).

use super::scurve::Bezier;
use super::trapezoid::{Ramp, Trapezoid, ticked_rate};
use crate::machine::defaults::MARLIN_STEPPER_TIMER_RATE_HZ;
use crate::motion::Phase;

/// The mean time a ramp's step interval loses to its truncation to whole timer ticks: half
/// a tick, s.
const HALF_TICK_S: f64 = 0.5 / MARLIN_STEPPER_TIMER_RATE_HZ as f64;

/// Seconds of a whole number of timer ticks, `uint32(ticks)` truncated.
fn whole_ticks_s(ticks: f64) -> f64 {
    let tr = f64::from(MARLIN_STEPPER_TIMER_RATE_HZ);
    ticks.max(0.0).floor() / tr
}

/// The pieces of a block of `n` steps with trapezoid `t` and acceleration `a` steps/s², as
/// the ISR runs it (module doc); with `s_curve`, Marlin's Bézier ramps.
pub fn ramps(t: &Trapezoid, a: f64, n: f64, s_curve: bool, out: &mut Vec<Ramp>) {
    out.clear();
    let mut b = Builder { s: 0.0, out };
    let tr = f64::from(MARLIN_STEPPER_TIMER_RATE_HZ);
    let ir = t.initial_rate;
    // The block's load: the first interval at the initial rate, whole ticks.
    let t1 = whole_ticks_s(tr / ir);
    let ramp_up = t.accelerate_until >= 1.0 && a > 0.0 && ir < t.nominal_rate;
    let first_phase = if ramp_up { Phase::Accel } else { Phase::Cruise };
    b.constant(t1, n.min(1.0), first_phase);
    if n <= 1.0 {
        return;
    }
    // The steps whose intervals the acceleration branch sets end at accelerate_until + 1.
    let acc_end = (t.accelerate_until + 1.0).min(n);
    let dec_start = (t.decelerate_after + 1.0).min(n);
    // The rate the trapezoid's deceleration starts from (`acc_step_rate`; the initial rate
    // without acceleration). The S-curve's starts from `cruise_rate`.
    let mut peak = ir;
    if ramp_up && s_curve {
        let cr = cruise_rate(t, a);
        let bez = Bezier {
            v0: ir,
            v1: cr,
            t_s: whole_ticks_s(tr / a * (cr - ir)),
        };
        bezier_accelerate(&bez, t1, acc_end, &mut b);
    } else if ramp_up {
        peak = accelerate(ir, t.nominal_rate, a, t1, acc_end, &mut b);
    }
    b.constant_to(dec_start, t.nominal_rate, Phase::Cruise);
    let m = n - b.s;
    if m <= 1e-9 {
        return;
    }
    let fr = t.final_rate;
    if s_curve && a > 0.0 {
        let cr = cruise_rate(t, a);
        if cr > fr {
            let bez = Bezier {
                v0: cr,
                v1: fr,
                t_s: whole_ticks_s(tr / a * (cr - fr)),
            };
            bezier_decelerate(&bez, n, &mut b);
        } else {
            b.constant_to(n, cr, Phase::Decel);
        }
    } else if peak > fr && a > 0.0 {
        decelerate(peak, fr, a, n, &mut b);
    } else {
        b.constant_to(n, fr, Phase::Decel);
    }
}

/// `cruise_rate` of `calculate_trapezoid_for_block`: the nominal rate, or the rate reached
/// at `accelerate_until` when the block has no plateau.
fn cruise_rate(t: &Trapezoid, a: f64) -> f64 {
    if t.accelerate_until < t.decelerate_after {
        t.nominal_rate
    } else {
        (t.initial_rate * t.initial_rate + 2.0 * a * t.accelerate_until)
            .sqrt()
            .floor()
            .min(t.nominal_rate)
    }
}

/// Appends pieces, keeping the steps made so far.
struct Builder<'a> {
    s: f64,
    out: &'a mut Vec<Ramp>,
}

impl Builder<'_> {
    /// A piece of `dt` from here, which ends on step `to`.
    fn push(&mut self, dt: f64, rate: f64, accel: f64, phase: Phase, to: f64) {
        if dt > 0.0 && dt.is_finite() {
            self.out.push(Ramp {
                dt_s: dt,
                s0: self.s,
                rate,
                accel,
                phase,
            });
            self.s = to;
        }
    }

    /// `steps` in `dt` at a constant rate.
    fn constant(&mut self, dt: f64, steps: f64, phase: Phase) {
        if steps > 0.0 {
            self.push(dt, steps / dt, 0.0, phase, self.s + steps);
        }
    }

    /// On to step `to` at `rate`, run at whole ticks.
    fn constant_to(&mut self, to: f64, rate: f64, phase: Phase) {
        let steps = to - self.s;
        if steps > 1e-9 {
            let r = ticked_rate(rate);
            self.push(steps / r, r, 0.0, phase, to);
        }
    }

    /// One piece with acceleration `accel` making `steps` in `dt` (through both step events);
    /// should its rate cross zero, the piece that starts (accelerating) or ends
    /// (decelerating) at rest instead, which accelerates harder.
    fn through(&mut self, dt: f64, steps: f64, accel: f64, phase: Phase) {
        if dt.is_nan() || dt <= 0.0 || steps <= 0.0 {
            return;
        }
        let to = self.s + steps;
        let rate = steps / dt - 0.5 * accel * dt;
        let end = rate + accel * dt;
        if rate >= 0.0 && end >= 0.0 {
            self.push(dt, rate, accel, phase, to);
        } else if accel > 0.0 {
            self.push(dt, 0.0, 2.0 * steps / (dt * dt), phase, to);
        } else {
            self.push(dt, 2.0 * steps / dt, -2.0 * steps / (dt * dt), phase, to);
        }
    }

    /// The pieces of `bez` from `ta` to `tb` making `steps`.
    fn bezier(&mut self, bez: &Bezier, ta: f64, tb: f64, steps: f64, phase: Phase) {
        if tb > ta && steps > 0.0 {
            bez.pieces(ta, tb, self.s, steps, phase, self.out);
            self.s += steps;
        }
    }
}

/// Newton's method on an increasing or decreasing `f` from `x`, kept within [lo, hi].
fn solve(f: impl Fn(f64) -> (f64, f64), x: f64, lo: f64, hi: f64) -> f64 {
    let (mut lo, mut hi) = (lo, hi);
    let mut x = x.clamp(lo, hi);
    for _ in 0..60 {
        let (y, dy) = f(x);
        if y == 0.0 {
            return x;
        }
        // Keep a bracket for a step that leaves it.
        if (y > 0.0) == (dy > 0.0) {
            hi = x;
        } else {
            lo = x;
        }
        let mut next = x - y / dy;
        if !(next > lo && next < hi) {
            next = 0.5 * (lo + hi);
        }
        if (next - x).abs() <= 1e-12 * x.abs().max(1.0) {
            return next;
        }
        x = next;
    }
    x
}

/// The trapezoid's acceleration branch from step 1 (at t_1) to step `to`: returns the rate
/// the deceleration starts from (`acc_step_rate`).
fn accelerate(ir: f64, nr: f64, a: f64, t1: f64, to: f64, b: &mut Builder) -> f64 {
    let u1 = ir + a * t1;
    if u1 >= nr || to <= 1.0 {
        // Capped from the first step on.
        b.constant_to(to, if u1 >= nr { nr } else { u1 }, Phase::Accel);
        return u1.min(nr);
    }
    let w1 = u1 * u1;
    // k(u) (module doc) with the ticks' ε·(u³ − u_1³)/3a, and dk/dw.
    let k = |w: f64| {
        let u = w.sqrt();
        let y = 1.0 + (w - w1) / (2.0 * a) - 0.25 * ((w - a) / (w1 - a)).ln()
            + HALF_TICK_S * (u * w - u1 * w1) / (3.0 * a);
        let dy = 1.0 / (2.0 * a) - 0.25 / (w - a) + HALF_TICK_S * u / (2.0 * a);
        (y, dy)
    };
    let rate_at = |steps: f64| {
        let w = solve(
            |w| {
                let (y, dy) = k(w);
                (y - steps, dy)
            },
            w1 + 2.0 * a * (steps - 1.0),
            w1,
            nr * nr,
        );
        w.sqrt()
    };
    // The rate the last acceleration interval runs at, set at step `to` − 1: below the
    // nominal rate when the ramp reaches it only during that interval.
    let last = (to - 1.0).max(1.0);
    let at_cap = k(nr * nr).0;
    if at_cap <= to {
        // The rate reaches nominal at (nominal − initial)/a, `at_cap` steps in; the
        // acceleration branch's last steps run at nominal.
        let count = |u: f64| k(u * u).0;
        ramp(b, (u1, nr), a, at_cap - 1.0, count, Phase::Accel);
        b.constant_to(to, nr, Phase::Accel);
        return if at_cap > last { rate_at(last) } else { nr };
    }
    let end = rate_at(to);
    ramp(b, (u1, end), a, to - 1.0, |u| k(u * u).0, Phase::Accel);
    rate_at(last)
}

/// The trapezoid's deceleration from the current step at rate `p` to step `n`, floored at
/// `fr`.
fn decelerate(p: f64, fr: f64, a: f64, n: f64, b: &mut Builder) {
    let m = n - b.s;
    let wp = p * p;
    let k = |w: f64| {
        let u = w.sqrt();
        let y = (wp - w) / (2.0 * a)
            + 0.25 * ((wp + a) / (w + a)).ln()
            + HALF_TICK_S * (p * wp - u * w) / (3.0 * a);
        let dy = -1.0 / (2.0 * a) - 0.25 / (w + a) - HALF_TICK_S * u / (2.0 * a);
        (y, dy)
    };
    let at_floor = k(fr * fr).0;
    if at_floor < m {
        ramp(b, (p, fr), a, at_floor, |u| k(u * u).0, Phase::Decel);
        b.constant_to(n, fr, Phase::Decel);
        return;
    }
    let w = solve(
        |w| {
            let (y, dy) = k(w);
            (y - m, dy)
        },
        (wp - 2.0 * a * m).max(fr * fr),
        fr * fr,
        wp,
    );
    ramp(b, (p, w.sqrt()), a, m, |u| k(u * u).0, Phase::Decel);
}

/// A ramp whose rate's change over the rate's magnitude is above this is drawn as two
/// pieces: the ISR's ln lag is concentrated at the low rates, which one chord would spread.
const SPLIT_RATIO: f64 = 2.0;

/// A trapezoid ramp from rate `ua` to `ub` (|Δ| / a s), making `steps` from here, through
/// the step-event curve `count(u)` (steps at rate u): one piece with acceleration ±a, or two
/// meeting on the curve at the rates' geometric mean.
fn ramp(
    b: &mut Builder,
    (ua, ub): (f64, f64),
    a: f64,
    steps: f64,
    count: impl Fn(f64) -> f64,
    phase: Phase,
) {
    let accel = if ub > ua { a } else { -a };
    if ua.max(ub) > SPLIT_RATIO * ua.min(ub) {
        let um = (ua * ub).sqrt();
        let sm = (count(um) - count(ua)).abs();
        b.through((um - ua).abs() / a, sm, accel, phase);
        b.through((ub - um).abs() / a, steps - sm, accel, phase);
    } else {
        b.through((ub - ua).abs() / a, steps, accel, phase);
    }
}

/// [`ramp`]'s split for a span of Bézier `bez` from `ta` to `tb` making `steps`.
fn bezier_span(b: &mut Builder, bez: &Bezier, (ta, tb): (f64, f64), steps: f64, phase: Phase) {
    let (va, vb) = (bez.rate(ta), bez.rate(tb));
    if va.max(vb) > SPLIT_RATIO * va.min(vb) {
        let vm = (va * vb).sqrt();
        let tm = solve(
            |t| (bez.rate(t) - vm, bez.slope(t)),
            0.5 * (ta + tb),
            ta,
            tb,
        );
        let sm = bezier_steps(bez, ta, tm);
        b.bezier(bez, ta, tm, sm, phase);
        b.bezier(bez, tm, tb, steps - sm, phase);
    } else {
        b.bezier(bez, ta, tb, steps, phase);
    }
}

/// The steps the ISR makes on Bézier `bez` from `ta` to `t` (within the phase): the
/// integral, the lag ½·ln(v(t)/v(ta)) (behind when accelerating, ahead when decelerating),
/// the ticks' ε∫v².
fn bezier_steps(bez: &Bezier, ta: f64, t: f64) -> f64 {
    let (i1, q1) = bez.integrals(t);
    let (i0, q0) = bez.integrals(ta);
    i1 - i0 - 0.5 * (bez.rate(t) / bez.rate(ta)).ln() + HALF_TICK_S * (q1 - q0)
}

/// The time in [ta, the phase's end] at which the ISR has made `steps` more on `bez`.
fn bezier_time_for(bez: &Bezier, ta: f64, steps: f64) -> f64 {
    let f = |t: f64| {
        let v = bez.rate(t);
        // The lag's derivative is left out of the slope: Newton is kept bracketed.
        (bezier_steps(bez, ta, t) - steps, v + HALF_TICK_S * v * v)
    };
    solve(f, ta + steps / bez.rate(ta).max(1.0), ta, bez.t_s)
}

/// The S-curve's acceleration branch from step 1 (at `t1`) to step `to`.
fn bezier_accelerate(bez: &Bezier, t1: f64, to: f64, b: &mut Builder) {
    if t1 >= bez.t_s {
        b.constant_to(to, bez.v1, Phase::Accel);
        return;
    }
    let at_end = 1.0 + bezier_steps(bez, t1, bez.t_s);
    if at_end <= to {
        bezier_span(b, bez, (t1, bez.t_s), at_end - 1.0, Phase::Accel);
        b.constant_to(to, bez.v1, Phase::Accel);
    } else {
        let t = bezier_time_for(bez, t1, to - 1.0);
        bezier_span(b, bez, (t1, t), to - 1.0, Phase::Accel);
    }
}

/// The S-curve's deceleration from the current step (its start) to step `n`.
fn bezier_decelerate(bez: &Bezier, n: f64, b: &mut Builder) {
    let m = n - b.s;
    let at_end = bezier_steps(bez, 0.0, bez.t_s);
    if at_end < m {
        bezier_span(b, bez, (0.0, bez.t_s), at_end, Phase::Decel);
        b.constant_to(n, bez.v1, Phase::Decel);
    } else {
        let t = bezier_time_for(bez, 0.0, m);
        bezier_span(b, bez, (0.0, t), m, Phase::Decel);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::firmware::marlin::scurve;

    const TR: f64 = 2_000_000.0;

    fn trapezoid(ir: f64, fr: f64, nr: f64, a: f64, n: f64) -> Trapezoid {
        // `calculate_trapezoid_for_block`'s step counts.
        let acc_f = (nr * nr - ir * ir) / (2.0 * a);
        let dec_f = (nr * nr - fr * fr) / (2.0 * a);
        let (mut acc, mut dec) = (acc_f.ceil().max(0.0), dec_f.floor().max(0.0));
        if n - acc - dec < 0.0 {
            acc = ((n + acc_f - dec_f) / 2.0).ceil().clamp(0.0, n);
            dec = n - acc;
        }
        Trapezoid {
            initial_rate: ir,
            final_rate: fr,
            nominal_rate: nr,
            accelerate_until: acc,
            decelerate_after: n - dec,
        }
    }

    /// The time of each step event, the ISR run step by step as Marlin's stepper.cpp
    /// describes it (written here for the test: rates in whole steps/s, intervals in whole
    /// ticks; the S-curve's Bézier in floating point).
    fn step_by_step(t: &Trapezoid, a: f64, n: u32, s_curve: bool) -> Vec<f64> {
        let bez = |v0: f64, v1: f64, ticks: f64, at: f64| {
            let x = (at / ticks).min(1.0);
            (v0 + (v1 - v0) * x * x * x * (10.0 - 15.0 * x + 6.0 * x * x)).floor()
        };
        let cr = if t.accelerate_until < t.decelerate_after {
            t.nominal_rate
        } else {
            (t.initial_rate.powi(2) + 2.0 * a * t.accelerate_until)
                .sqrt()
                .floor()
        };
        let acc_ticks = (TR / a * (cr - t.initial_rate)).floor();
        let dec_ticks = (TR / a * (cr - t.final_rate)).floor();
        let mut interval = (TR / t.initial_rate).floor();
        let (mut acc_time, mut dec_time, mut acc_rate) = (interval, 0.0, t.initial_rate);
        let (mut now, mut out) = (0.0, Vec::new());
        for done in 1..=n {
            now += interval;
            out.push(now / TR);
            let done = f64::from(done);
            let rate = if done <= t.accelerate_until {
                acc_rate = if s_curve {
                    bez(t.initial_rate, cr, acc_ticks, acc_time)
                } else {
                    (t.initial_rate + (a * acc_time / TR).round()).min(t.nominal_rate)
                };
                acc_rate
            } else if done > t.decelerate_after {
                if s_curve {
                    bez(cr, t.final_rate, dec_ticks, dec_time)
                } else {
                    (acc_rate - (a * dec_time / TR).round()).max(t.final_rate)
                }
            } else {
                t.nominal_rate
            };
            interval = (TR / rate).floor();
            if done <= t.accelerate_until {
                acc_time += interval;
            } else if done > t.decelerate_after {
                dec_time += interval;
            }
        }
        out
    }

    fn pieces(t: &Trapezoid, a: f64, n: f64, s_curve: bool) -> Vec<Ramp> {
        let mut out = Vec::new();
        ramps(t, a, n, s_curve, &mut out);
        out
    }

    fn duration(r: &[Ramp]) -> f64 {
        r.iter().map(|p| p.dt_s).sum()
    }

    /// Steps made `t` s into the block.
    fn steps_at(r: &[Ramp], mut t: f64) -> f64 {
        for p in r {
            if t <= p.dt_s {
                return p.s0 + p.rate * t + 0.5 * p.accel * t * t;
            }
            t -= p.dt_s;
        }
        r.last().map_or(0.0, Ramp::s1)
    }

    /// From rest (120 steps/s, `MINIMAL_STEP_RATE`): the first step comes ⌊2 000 000/120⌋
    /// = 16666 ticks = 8.333 ms into the block, at a constant rate; the ramp (80 000
    /// steps/s²) starts from there, the rate already 120 + 80 000 · 0.008333 = 786.6
    /// steps/s. An integrated ramp would be 1 + 80 000 · 0.008333²/2 = 3.78 steps in.
    #[test]
    fn a_start_from_rest_makes_its_first_step_one_interval_at_the_initial_rate() {
        let t = trapezoid(120.0, 120.0, 8000.0, 80000.0, 1000.0);
        let r = pieces(&t, 80000.0, 1000.0, false);
        assert!((r[0].dt_s - 16666.0 / TR).abs() < 1e-15);
        assert_eq!(r[0].accel, 0.0);
        assert!((r[0].s1() - 1.0).abs() < 1e-12);
        assert_eq!(r[1].s0, 1.0);
        assert_eq!(r[1].accel, 80000.0);
        // The ramp piece starts within a few percent of the ISR's second interval's rate.
        assert!((r[1].rate - 786.6).abs() < 0.06 * 786.6, "{}", r[1].rate);
        let isr = step_by_step(&t, 80000.0, 1000, false);
        assert!((isr[0] - 0.008333).abs() < 1e-6);
    }

    /// Three accelerating steps from 1000 steps/s at 100 000 steps/s² (by hand, Marlin's
    /// integer rules): step 1 at 2000 ticks; rate 1000 + round(10⁵ · 0.001) = 1100, interval
    /// ⌊2·10⁶/1100⌋ = 1818, step 2 at 3818; rate 1000 + round(10⁵ · 0.001909) = 1191,
    /// interval 1679, step 3 at 5497 ticks = 2.7485 ms. The integrated ramp:
    /// (√(1000² + 2 · 10⁵ · 3) − 1000)/10⁵ = 2.6491 ms.
    #[test]
    fn an_accelerating_block_takes_the_isrs_time_not_the_ramps() {
        let t = Trapezoid {
            initial_rate: 1000.0,
            final_rate: 5000.0,
            nominal_rate: 5000.0,
            accelerate_until: 3.0,
            decelerate_after: 3.0,
        };
        assert_eq!(step_by_step(&t, 1e5, 3, false)[2], 5497.0 / TR);
        let r = pieces(&t, 1e5, 3.0, false);
        let d = duration(&r);
        assert!((d - 2.7485e-3).abs() < 5e-6, "{d}");
        assert!((r.last().unwrap().s1() - 3.0).abs() < 1e-12);
        assert!(r.iter().all(|p| p.accel == 0.0 || p.accel == 1e5));
    }

    /// A deceleration to a low final rate: 23 steps from 1919 steps/s toward 120 at 80 000
    /// steps/s². Integrated, the ramp would need (1919² − 120²)/160 000 = 22.9 steps, the
    /// last at a few hundred steps/s; the ISR, whose rate is the rate at each interval's
    /// start, is ahead by ½·ln(1919/u) steps and ends its block at about 700 steps/s,
    /// 1.7 ms sooner.
    #[test]
    fn a_deceleration_to_a_low_rate_ends_as_soon_as_the_isrs() {
        let t = trapezoid(1919.0, 120.0, 4511.0, 80000.0, 23.0);
        let isr = step_by_step(&t, 80000.0, 23, false);
        let end = *isr.last().unwrap();
        let r = pieces(&t, 80000.0, 23.0, false);
        let d = duration(&r);
        assert!((d - end).abs() < 40e-6, "{d} {end}");
        let continuous = 1.0 / 1919.0 + (1960.8 - 120.0) / 80000.0;
        assert!(continuous - end > 1.5e-3, "{continuous} {end}");
        let last = r.last().unwrap();
        let v_end = last.rate + last.accel * last.dt_s;
        assert!(v_end > 500.0, "{v_end}");
    }

    /// Over a grid of blocks (short and long, from rest and at speed, to rest and on, with
    /// and without plateau, trapezoid and S-curve): a few pieces make the block's steps, go
    /// no slower than 0 and never accelerate less than Marlin (a, or 1.875 a at an
    /// S-curve's middle); the block's time and the steps made at each step event are close
    /// to the step-by-step ISR's (the bounds below).
    #[test]
    fn the_pieces_follow_the_isr_step_by_step() {
        let (mut worst_t, mut worst_r, mut worst_s) = ([0.0f64; 2], [0.0f64; 2], [0.0f64; 2]);
        for &a in &[40000.0, 80000.0, 240000.0] {
            for &(ir, fr) in &[
                (120.0, 120.0),
                (800.0, 2400.0),
                (3000.0, 400.0),
                (5000.0, 5000.0),
            ] {
                for &nr in &[2000.0, 6000.0, 12000.0] {
                    for &n in &[1u32, 2, 6, 20, 60, 400, 3000] {
                        let (ir, fr) = (f64::min(ir, nr), f64::min(fr, nr));
                        let t = trapezoid(ir, fr, nr, a, f64::from(n));
                        for s_curve in [false, true] {
                            let r = pieces(&t, a, f64::from(n), s_curve);
                            let isr = step_by_step(&t, a, n, s_curve);
                            let end = *isr.last().unwrap();
                            let d = duration(&r);
                            let label = format!("{t:?} a {a} n {n} s-curve {s_curve}");
                            assert!((r.last().unwrap().s1() - f64::from(n)).abs() < 1e-9);
                            assert!(r.len() <= if s_curve { 40 } else { 8 }, "{label}");
                            let i = usize::from(s_curve);
                            worst_t[i] = worst_t[i].max((d - end).abs());
                            worst_r[i] = worst_r[i].max((d - end).abs() / end);
                            for p in &r {
                                assert!(p.rate >= 0.0 && p.rate + p.accel * p.dt_s >= -1e-9);
                                assert!(
                                    p.accel == 0.0 || p.accel.abs() >= a * (1.0 - 1e-12) || s_curve
                                );
                            }
                            // (A Bézier whose middle passes during the first step is a rate jump.)
                            let middle = 0.5 * (t.nominal_rate - t.initial_rate) / a;
                            if s_curve && t.accelerate_until > 2.0 && n > 60 && middle > 1.0 / ir {
                                let peak = r.iter().map(|p| p.accel).fold(0.0, f64::max);
                                assert!(peak >= scurve::PEAK_RATIO * a * (1.0 - 1e-12), "{label}");
                            }
                            for (k, &te) in isr.iter().enumerate() {
                                let off = (steps_at(&r, te) - (k + 1) as f64).abs();
                                worst_s[i] = worst_s[i].max(off);
                            }
                        }
                    }
                }
            }
        }
        eprintln!("worst: {worst_t:?} s, {worst_r:?} of the time, {worst_s:?} steps");
        // Measured: trapezoid 0.17 ms, 0.35 %, 0.88 steps; S-curve 0.81 ms, 1.1 %, 2.7 steps
        // (long Bézier ramps from rest at 40 000 steps/s², where the first-order lag is
        // coarsest).
        assert!(worst_t[0] < 2e-4 && worst_r[0] < 5e-3 && worst_s[0] < 1.0);
        assert!(worst_t[1] < 1e-3 && worst_r[1] < 1.5e-2 && worst_s[1] < 3.0);
    }
}
