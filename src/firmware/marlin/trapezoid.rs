//! A block's step-rate profile: `Planner::calculate_trapezoid_for_block` (planner.cpp)
//! sets the initial, cruise and final rates and the steps where acceleration ends and
//! deceleration starts; the stepper (`Stepper::block_phase_isr`) ramps the rate over those
//! steps. We integrate that ramp in continuous time (the rate's change per step interval
//! is not discretised): acceleration from `initial_rate` for `accelerate_until` steps
//! (capped at the nominal rate), cruise to `decelerate_after`, deceleration from the rate
//! reached, floored at `final_rate`. Rates in steps/s of the dominant axis.

use super::block::Block;
use crate::machine::defaults::{MARLIN_MINIMAL_STEP_RATE, MARLIN_STEPPER_TIMER_RATE_HZ};
use crate::motion::Phase;

/// One phase of a block's profile: over `dt_s` the dominant axis goes from step `s0` at
/// `rate` steps/s with `accel` steps/s².
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ramp {
    pub dt_s: f64,
    pub s0: f64,
    pub rate: f64,
    pub accel: f64,
    pub phase: Phase,
}

impl Ramp {
    /// Steps made by the end.
    pub fn s1(&self) -> f64 {
        self.s0 + self.rate * self.dt_s + 0.5 * self.accel * self.dt_s * self.dt_s
    }
}

/// The rates and step boundaries of `calculate_trapezoid_for_block`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Trapezoid {
    pub initial_rate: f64,
    pub final_rate: f64,
    pub nominal_rate: f64,
    pub accelerate_until: f64,
    pub decelerate_after: f64,
}

/// `calculate_trapezoid_for_block(block, entry / nominal_speed, exit / nominal_speed)`.
pub fn trapezoid(b: &Block, entry_mm_s: f64, exit_mm_s: f64) -> Trapezoid {
    let min_rate = f64::from(MARLIN_MINIMAL_STEP_RATE);
    let nr = b.nominal_rate;
    let initial_rate = (nr * entry_mm_s / b.nominal_speed).ceil().max(min_rate);
    let final_rate = (nr * exit_mm_s / b.nominal_speed).ceil().max(min_rate);
    let a = b.accel_steps_s2;
    let n = f64::from(b.step_events);
    let acc_f = (nr * nr - initial_rate * initial_rate) / (2.0 * a);
    let dec_f = (nr * nr - final_rate * final_rate) / (2.0 * a);
    // A negative float stored into uint32_t: 0 (ARM).
    let mut acc = acc_f.ceil().max(0.0);
    let mut dec = dec_f.floor().max(0.0);
    if n - acc - dec < 0.0 {
        acc = ((n + acc_f - dec_f) / 2.0).ceil().clamp(0.0, n);
        dec = n - acc;
    }
    Trapezoid {
        initial_rate,
        final_rate,
        nominal_rate: nr,
        accelerate_until: acc,
        decelerate_after: n - dec,
    }
}

/// The stepper's ramp over the block's `n` steps, integrated in continuous time: up to four
/// phases (acceleration, cruise, deceleration, and the rest of the deceleration at the final
/// rate when the floor is reached early), or, when the initial rate is above the nominal
/// (a block slower than `MINIMAL_STEP_RATE`), its first step at the initial rate and the
/// others at the nominal. With `s_curve`, the acceleration and deceleration phases follow
/// the Bézier ([`super::scurve`]) over the same time and steps.
pub fn ramps(t: &Trapezoid, a: f64, n: f64, s_curve: bool, out: &mut Vec<Ramp>) {
    trapezoid_ramps(t, a, n, out);
    if s_curve {
        let phases = std::mem::take(out);
        for r in &phases {
            if r.accel != 0.0 {
                super::scurve::bezier(r, out);
            } else {
                out.push(*r);
            }
        }
    }
}

fn trapezoid_ramps(t: &Trapezoid, a: f64, n: f64, out: &mut Vec<Ramp>) {
    out.clear();
    let mut s = 0.0;
    let mut push = |dt: f64, rate: f64, accel: f64, phase: Phase, s: &mut f64| {
        if dt > 0.0 && dt.is_finite() {
            let r = Ramp {
                dt_s: dt,
                s0: *s,
                rate,
                accel,
                phase,
            };
            *s = r.s1();
            out.push(r);
        }
    };
    let ir = t.initial_rate;
    let nr = t.nominal_rate;
    let tick = |r: f64| ticked_rate(r);
    if ir >= nr {
        let first = n.min(1.0);
        push(first / tick(ir), tick(ir), 0.0, Phase::Cruise, &mut s);
        push((n - first) / tick(nr), tick(nr), 0.0, Phase::Cruise, &mut s);
        return;
    }
    let peak = nr.min((ir * ir + 2.0 * a * t.accelerate_until).sqrt());
    push((peak - ir) / a, ir, a, Phase::Accel, &mut s);
    let cruise_steps = t.decelerate_after - s;
    if cruise_steps > 1e-9 {
        push(
            cruise_steps / tick(peak),
            tick(peak),
            0.0,
            Phase::Cruise,
            &mut s,
        );
    }
    let dec_steps = n - s;
    if dec_steps <= 1e-9 {
        return;
    }
    let fr = t.final_rate;
    if fr >= peak {
        // The rate jumps to the final rate (Marlin: max(rate − Δ, final_rate)).
        push(dec_steps / tick(fr), tick(fr), 0.0, Phase::Decel, &mut s);
        return;
    }
    let end = fr.max((peak * peak - 2.0 * a * dec_steps).max(0.0).sqrt());
    push((peak - end) / a, peak, -a, Phase::Decel, &mut s);
    let rest = n - s;
    if rest > 1e-9 {
        push(rest / tick(fr), tick(fr), 0.0, Phase::Decel, &mut s);
    }
}

/// The rate a constant step rate really runs at: the stepper's interval is a whole number of
/// timer ticks, `STEPPER_TIMER_RATE / rate` truncated (`Stepper::calc_timer_interval`), so
/// the steps come slightly fast (up to rate/TR: 0.2 % at 4000 steps/s).
pub fn ticked_rate(rate: f64) -> f64 {
    let tr = f64::from(MARLIN_STEPPER_TIMER_RATE_HZ);
    let ticks = (tr / rate).floor();
    if ticks >= 1.0 { tr / ticks } else { rate }
}
