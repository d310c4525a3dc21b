//! A planned block as pieces of the commanded motion. Inside a block the stepper's
//! Bresenham moves every tower in proportion to its step count (`pulse_phase_isr`): the
//! carriages move on a straight line in tower space, at the block's step-rate profile. A
//! [`Segment`] is a Cartesian quadratic, so the block's tower line is mapped back by the
//! forward kinematics at its ends and drawn as Cartesian chords between them: a chord's
//! carriages leave the tower line by a fraction of a micrometre on a 0.5 mm segment. Where
//! they would leave it by more than [`CHORD_TOLERANCE_MM`] (a long block near the edge),
//! the block is cut into sub-chords whose ends lie on the tower line.

use super::trapezoid::Ramp;
use crate::delta::DeltaModel;
use crate::motion::{PhaseChanges, Segment};
use crate::path::Vec3;

/// Largest allowed distance, in carriage height, between a chord's carriages and the
/// block's straight tower line, mm.
pub const CHORD_TOLERANCE_MM: f64 = 1e-4;

/// Carriage heights and their nozzle position.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    pub q_mm: [f64; 3],
    pub p: Vec3,
}

/// The block's tower line from `from` to `to`, cut into `m` chords; the pieces of the ramps
/// (in steps of the dominant axis, `n` in all) along them.
#[allow(clippy::too_many_arguments)]
pub fn emit(
    model: &DeltaModel,
    from: Pose,
    to: Pose,
    n: f64,
    ramps: &[Ramp],
    t0_s: f64,
    line: u64,
    out: &mut impl FnMut(Segment),
) {
    let chords = chord_count(model, &from, &to);
    let at = |f: f64| -> Vec3 {
        if f <= 0.0 {
            return from.p;
        }
        if f >= 1.0 {
            return to.p;
        }
        let q = std::array::from_fn(|i| from.q_mm[i] + f * (to.q_mm[i] - from.q_mm[i]));
        model.forward(q).unwrap_or(from.p + (to.p - from.p) * f)
    };
    let mut t = t0_s;
    let mut chord = 0;
    let mut a = from.p;
    let mut b = at(1.0 / chords as f64);
    for r in ramps {
        let mut tau = 0.0;
        while tau < r.dt_s {
            // The chord [s_lo, s_hi] of the steps; the piece ends at its end or the ramp's.
            let s_hi = n * (chord + 1) as f64 / chords as f64;
            let s_lo = n * chord as f64 / chords as f64;
            let end = if chord + 1 == chords {
                r.dt_s
            } else {
                time_to(r, s_hi).min(r.dt_s)
            };
            let dt = end - tau;
            if dt > 0.0 {
                let s = r.s0 + r.rate * tau + 0.5 * r.accel * tau * tau;
                let v = r.rate + r.accel * tau;
                let dir = (b - a) / (s_hi - s_lo);
                out(Segment {
                    t0_s: t + tau,
                    dt_s: dt,
                    p: a + dir * (s - s_lo),
                    v: dir * v,
                    a: dir * r.accel,
                    line,
                    phase: r.phase,
                    later_phases: PhaseChanges::NO_PHASES,
                    changes: PhaseChanges::NONE,
                });
            }
            tau = end;
            if end < r.dt_s && chord + 1 < chords {
                chord += 1;
                a = b;
                b = at((chord + 1) as f64 / chords as f64);
            } else {
                break;
            }
        }
        t += r.dt_s;
    }
}

/// Chords enough that the carriages stay within [`CHORD_TOLERANCE_MM`] of the tower line:
/// the departure grows with the square of the chord, so from the single chord's departure
/// at its middle.
fn chord_count(model: &DeltaModel, from: &Pose, to: &Pose) -> u32 {
    let mid = model.inverse((from.p + to.p) * 0.5);
    let Ok(mid) = mid else { return 1 };
    let off = (0..3)
        .map(|i| (mid[i] - 0.5 * (from.q_mm[i] + to.q_mm[i])).abs())
        .fold(0.0, f64::max);
    if off <= CHORD_TOLERANCE_MM {
        1
    } else {
        ((off / CHORD_TOLERANCE_MM).sqrt().ceil() as u32).min(1024)
    }
}

/// The time into ramp `r` at which the dominant axis reaches step `s` (∞ when it does not).
fn time_to(r: &Ramp, s: f64) -> f64 {
    let ds = s - r.s0;
    if ds <= 0.0 {
        return 0.0;
    }
    if r.accel == 0.0 {
        return if r.rate > 0.0 {
            ds / r.rate
        } else {
            f64::INFINITY
        };
    }
    let disc = r.rate * r.rate + 2.0 * r.accel * ds;
    if disc < 0.0 {
        return f64::INFINITY;
    }
    // The smaller positive root, written to avoid cancellation.
    2.0 * ds / (r.rate + disc.sqrt())
}
