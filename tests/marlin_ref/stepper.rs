//! How the stepper runs a block (spec §7): when its step events happen.
//!
//! Two timing models:
//!
//! * [`Timing::Discrete`] (the default): Marlin's `block_phase_isr` step by step — the first
//!   interval at `initial_rate`, then one rate per step event (accelerating while
//!   `step_events_completed <= accelerate_until`, cruising at `nominal_rate`, decelerating
//!   after `decelerate_after`), `interval = TR / rate` in integer timer ticks; the trapezoid
//!   by `STEP_MULTIPLY(time, acceleration_rate)`, the S-curve by Marlin's 32-bit integer
//!   Bézier (`_calc_bezier_curve_coeffs` / `_eval_bezier_curve`). No multi-stepping (it
//!   keeps the average rate apart from the truncation of `rate >> k`).
//! * [`Timing::Continuous`]: the block's step-rate profile integrated exactly (the spec's
//!   "continuous model", §13): the rate is min(cruise, √(initial² + 2·a·s),
//!   √(final² + 2·a·(n − s))) at step s; with the S-curve each ramp follows the Bézier
//!   v0 + (v1 − v0)(10τ³ − 15τ⁴ + 6τ⁵) over the trapezoid's ramp time.
//!
//! Either gives s(t), the step events done t seconds into the block, continuously: the
//! discrete model is linear between step events (step k is complete at its event), so the
//! towers, each moving `delta_i · s / n` steps, are not quantised to single steps.

use super::planner::Block;

/// The stepper's timing model.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Timing {
    /// Marlin's ISR with a `STEPPER_TIMER_RATE` of `timer_hz` (2 MHz on AVR and on the
    /// STM32 HAL).
    Discrete { timer_hz: u32 },
    /// The step-rate trapezoid (or S-curve) integrated exactly.
    Continuous,
}

impl Default for Timing {
    fn default() -> Self {
        Timing::Discrete {
            timer_hz: 2_000_000,
        }
    }
}

/// Marlin's 32-bit Bézier (stepper.cpp, the generic 32-bit `_eval_bezier_curve`).
#[derive(Clone, Copy, Debug)]
pub struct Bezier {
    a: i64,
    b: i64,
    c: i64,
    f: i64,
    av: u32,
}

impl Bezier {
    /// `_calc_bezier_curve_coeffs(v0, v1, av)`.
    pub fn new(v0: u32, v1: u32, av: u32) -> Bezier {
        let (v0, v1) = (v0 as i64, v1 as i64);
        Bezier {
            a: 768 * (v1 - v0),
            b: 1920 * (v0 - v1),
            c: 1280 * (v1 - v0),
            f: 128 * v0,
            av,
        }
    }

    /// `_eval_bezier_curve(curr_step)`: the rate at `curr_step` timer ticks.
    pub fn eval(&self, curr_step: u32) -> u32 {
        let t = self.av.wrapping_mul(curr_step) as u64;
        let mut f: u64 = t;
        f *= t;
        f >>= 32;
        f *= t;
        f >>= 32;
        let mut acc: i64 = self.f << 31;
        acc += ((f as u32) >> 1) as i64 * self.c;
        f *= t;
        f >>= 32;
        acc += ((f as u32) >> 1) as i64 * self.b;
        f *= t;
        f >>= 32;
        acc += ((f as u32) >> 1) as i64 * self.a;
        acc >>= 31 + 7;
        acc as i32 as u32
    }
}

/// `get_period_inverse(d)` on 32-bit CPUs.
fn period_inverse(d: u32) -> u32 {
    u32::MAX.checked_div(d).unwrap_or(u32::MAX)
}

/// `calc_timer_interval(rate)` on a 32-bit CPU: TR / rate (a rate of 0, which Marlin never
/// plans, is taken as 1).
fn interval(tr: u32, rate: u32) -> u32 {
    tr / rate.max(1)
}

/// The timer ticks (from the block's start) of each of its `n` step events, as Marlin's
/// ISR times them (spec §7.2, §7.3).
pub fn step_ticks(b: &Block, s_curve: bool, tr: u32) -> Vec<u64> {
    let t = &b.trap;
    let n = b.n;
    let accel = b.accel_steps.max(1) as f64;
    // S-curve phase times (planner.cpp): uint32(TR/accel · (cruise − initial)), the
    // difference in uint32 (a negative one wraps; ARM saturates the huge float).
    let rate_factor = tr as f64 / accel;
    let phase_time = |hi: u32, lo: u32| -> u32 {
        super::planner::to_u32(rate_factor * hi.wrapping_sub(lo) as f64)
    };
    let acceleration_time = phase_time(t.cruise_rate, t.initial_rate);
    let deceleration_time = phase_time(t.cruise_rate, t.final_rate);
    // Trapezoid: acceleration_rate = uint32(accel · 2^24 / TR).
    let acceleration_rate =
        super::planner::to_u32(b.accel_steps as f64 * ((1u64 << 24) as f64 / tr as f64)) as u64;
    let step_multiply =
        |time: u32| -> u32 { ((time as u64 * acceleration_rate + 0x80_0000) >> 24) as u32 };

    let mut bezier = Bezier::new(
        t.initial_rate,
        t.cruise_rate,
        period_inverse(acceleration_time),
    );
    let mut bezier_2nd_half = false;
    let mut acc_step_rate = t.initial_rate;
    let mut acceleration_time_ticks: u32 = 0;
    let mut deceleration_time_ticks: u32 = 0;
    let mut ticks_nominal: Option<u32> = None;

    // Block load: the first interval at initial_rate.
    let mut iv = interval(tr, t.initial_rate);
    acceleration_time_ticks = acceleration_time_ticks.wrapping_add(iv);

    let mut out = Vec::with_capacity(n as usize);
    let mut now: u64 = 0;
    for completed in 1..=n {
        now += iv as u64;
        out.push(now);
        if completed >= n {
            break;
        }
        if completed <= t.accelerate_until {
            let rate = if s_curve {
                if acceleration_time_ticks < acceleration_time {
                    bezier.eval(acceleration_time_ticks)
                } else {
                    t.cruise_rate
                }
            } else {
                acc_step_rate =
                    (step_multiply(acceleration_time_ticks) + t.initial_rate).min(b.nominal_rate);
                acc_step_rate
            };
            iv = interval(tr, rate);
            acceleration_time_ticks = acceleration_time_ticks.wrapping_add(iv);
        } else if completed > t.decelerate_after {
            let rate = if s_curve {
                if !bezier_2nd_half {
                    bezier = Bezier::new(
                        t.cruise_rate,
                        t.final_rate,
                        period_inverse(deceleration_time),
                    );
                    bezier_2nd_half = true;
                    t.cruise_rate
                } else if deceleration_time_ticks < deceleration_time {
                    bezier.eval(deceleration_time_ticks)
                } else {
                    t.final_rate
                }
            } else {
                let dv = step_multiply(deceleration_time_ticks);
                if dv < acc_step_rate {
                    (acc_step_rate - dv).max(t.final_rate)
                } else {
                    t.final_rate
                }
            };
            iv = interval(tr, rate);
            deceleration_time_ticks = deceleration_time_ticks.wrapping_add(iv);
        } else {
            iv = *ticks_nominal.get_or_insert_with(|| interval(tr, b.nominal_rate));
        }
    }
    out
}

/// One ramp (or cruise) of the continuous profile: the rate goes from `v0` to `v1`
/// (steps/s) in `dur` seconds.
#[derive(Clone, Copy, Debug)]
pub struct Phase {
    pub dur: f64,
    pub v0: f64,
    pub v1: f64,
}

/// The Bézier's velocity fraction b(τ) = 10τ³ − 15τ⁴ + 6τ⁵.
pub fn bezier_fraction(tau: f64) -> f64 {
    let t = tau.clamp(0.0, 1.0);
    t * t * t * (10.0 - 15.0 * t + 6.0 * t * t)
}

/// ∫₀^τ b = 2.5τ⁴ − 3τ⁵ + τ⁶.
pub fn bezier_integral(tau: f64) -> f64 {
    let t = tau.clamp(0.0, 1.0);
    t.powi(4) * (2.5 - 3.0 * t + t * t)
}

impl Phase {
    /// Steps done `t` seconds into the phase (0 ≤ t ≤ dur).
    pub fn steps_at(&self, t: f64, s_curve: bool) -> f64 {
        if self.dur <= 0.0 {
            return 0.0;
        }
        let dv = self.v1 - self.v0;
        if s_curve {
            self.v0 * t + dv * self.dur * bezier_integral(t / self.dur)
        } else {
            self.v0 * t + dv * t * t / (2.0 * self.dur)
        }
    }

    pub fn steps(&self) -> f64 {
        0.5 * (self.v0 + self.v1) * self.dur
    }
}

/// The continuous step-rate profile of a block: accel, cruise, decel (some may be empty).
pub fn continuous_phases(b: &Block) -> Vec<Phase> {
    let n = b.n as f64;
    let t = &b.trap;
    let cruise = (t.cruise_rate.max(1)) as f64;
    let vi = (t.initial_rate as f64).min(cruise);
    let vf = (t.final_rate as f64).min(cruise);
    if b.accel_steps == 0 {
        return vec![Phase {
            dur: n / cruise,
            v0: cruise,
            v1: cruise,
        }];
    }
    let a = b.accel_steps as f64;
    let s_acc = (cruise * cruise - vi * vi) / (2.0 * a);
    let s_dec = (cruise * cruise - vf * vf) / (2.0 * a);
    let ramp = |v0: f64, v1: f64| Phase {
        dur: (v1 - v0).abs() / a,
        v0,
        v1,
    };
    if s_acc + s_dec <= n {
        vec![
            ramp(vi, cruise),
            Phase {
                dur: (n - s_acc - s_dec) / cruise,
                v0: cruise,
                v1: cruise,
            },
            ramp(cruise, vf),
        ]
    } else {
        // No plateau: the ramps meet where √(vi² + 2as) = √(vf² + 2a(n − s)).
        let s_meet = ((vf * vf - vi * vi + 2.0 * a * n) / (4.0 * a)).clamp(0.0, n);
        let peak = if s_meet <= 0.0 {
            (vf * vf + 2.0 * a * n).sqrt()
        } else {
            (vi * vi + 2.0 * a * s_meet).sqrt()
        };
        let start = if s_meet <= 0.0 { peak } else { vi };
        let end = if s_meet >= n { peak } else { vf };
        vec![ramp(start, peak), ramp(peak, end)]
    }
}

/// A block's motion in time: s(t), the step events done, continuous.
#[derive(Clone, Debug)]
pub enum BlockMotion {
    /// Step event times (s from the block's start).
    Discrete {
        times: Vec<f64>,
    },
    Continuous {
        phases: Vec<Phase>,
        s_curve: bool,
    },
}

impl BlockMotion {
    pub fn new(b: &Block, s_curve: bool, timing: Timing) -> BlockMotion {
        match timing {
            Timing::Discrete { timer_hz } => BlockMotion::Discrete {
                times: step_ticks(b, s_curve, timer_hz)
                    .into_iter()
                    .map(|k| k as f64 / timer_hz as f64)
                    .collect(),
            },
            Timing::Continuous => BlockMotion::Continuous {
                phases: continuous_phases(b),
                s_curve,
            },
        }
    }

    /// Step events done `t` seconds into the block (clamped to [0, n]).
    pub fn steps_at(&self, t: f64) -> f64 {
        match self {
            BlockMotion::Discrete { times } => {
                let n = times.len();
                let k = times.partition_point(|&x| x <= t);
                if k >= n {
                    return n as f64;
                }
                let t0 = if k == 0 { 0.0 } else { times[k - 1] };
                let t1 = times[k];
                k as f64 + ((t - t0) / (t1 - t0)).clamp(0.0, 1.0)
            }
            BlockMotion::Continuous { phases, s_curve } => {
                let mut done = 0.0;
                let mut t = t.max(0.0);
                for p in phases {
                    if t < p.dur {
                        return done + p.steps_at(t, *s_curve);
                    }
                    t -= p.dur;
                    done += p.steps();
                }
                done
            }
        }
    }
}

/// The block's duration, s.
pub fn block_duration(b: &Block, s_curve: bool, timing: Timing) -> f64 {
    match timing {
        Timing::Discrete { timer_hz } => {
            step_ticks(b, s_curve, timer_hz)
                .last()
                .copied()
                .unwrap_or(0) as f64
                / timer_hz as f64
        }
        Timing::Continuous => continuous_phases(b).iter().map(|p| p.dur).sum(),
    }
}
