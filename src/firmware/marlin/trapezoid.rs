//! A block's step-rate profile: `Planner::calculate_trapezoid_for_block` (planner.cpp)
//! sets the initial, cruise and final rates and the steps where acceleration ends and
//! deceleration starts; the stepper (`Stepper::block_phase_isr`) ramps the rate over those
//! steps, as [`super::isr`] times it. Rates in steps/s of the dominant axis.

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

/// The rate a constant step rate really runs at: the stepper's interval is a whole number of
/// timer ticks, `STEPPER_TIMER_RATE / rate` truncated (`Stepper::calc_timer_interval`), so
/// the steps come slightly fast (up to rate/TR: 0.2 % at 4000 steps/s).
pub fn ticked_rate(rate: f64) -> f64 {
    let tr = f64::from(MARLIN_STEPPER_TIMER_RATE_HZ);
    let ticks = (tr / rate).floor();
    if ticks >= 1.0 { tr / ticks } else { rate }
}
