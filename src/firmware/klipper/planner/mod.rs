//! Klipper's motion planner: speed limits, junction speeds, lookahead and trapezoids.
//!
//! It follows klippy/toolhead.py (`Move`, `LookAheadQueue`), klippy/kinematics/delta.py
//! (`check_move`) and klippy/kinematics/extruder.py (`check_move`, `calc_junction`); the
//! model and every deviation are in docs/planner.md.

mod limits;
mod queue;
#[cfg(test)]
mod tests;

use crate::gcode::Event;
use crate::machine::Machine;
use crate::path::{Path, Vec3};

use limits::MoveLimits;
use queue::Lookahead;

/// One move with its trapezoidal velocity profile along the path (mm, s).
///
/// The profile runs over the planned distance `distance_mm`: the path length for a
/// kinematic move, |E| for an extrude-only move (whose nozzle stands still).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlannedMove {
    /// 1-based source line.
    pub line: u64,
    pub path: Path,
    /// Extruder motion, mm.
    pub e_mm: f64,
    /// False for an extrude-only move: the nozzle stands still at `path.start()`.
    pub kinematic: bool,
    pub distance_mm: f64,
    /// The path's unit direction, [`Path::dir`] (zero for an extrude-only move).
    pub dir: Vec3,
    pub start_v_mm_s: f64,
    pub cruise_v_mm_s: f64,
    pub end_v_mm_s: f64,
    /// Magnitude of the acceleration in the accel and decel phases.
    pub accel_mm_s2: f64,
    pub accel_t_s: f64,
    pub cruise_t_s: f64,
    pub decel_t_s: f64,
    /// Print time at the start of the move.
    pub t0_s: f64,
}

impl PlannedMove {
    pub fn duration_s(&self) -> f64 {
        self.accel_t_s + self.cruise_t_s + self.decel_t_s
    }
}

/// The streaming planner: events in, in file order; planned moves out, in file order, as
/// soon as no later move can change their plan.
#[derive(Debug)]
pub struct Planner {
    limits: MoveLimits,
    lookahead: Lookahead,
}

impl Planner {
    pub fn new(machine: &Machine) -> Planner {
        Planner {
            limits: MoveLimits::new(machine),
            lookahead: Lookahead::new(machine.extruder.instantaneous_corner_velocity_mm_s),
        }
    }

    /// Takes the next event; hands `out` the moves whose plan is now final, in order.
    /// Takes the event by reference: an `Event` is large, and taken by value each was
    /// copied by a call to `memcpy`.
    pub fn push(&mut self, event: &Event, out: &mut impl FnMut(PlannedMove)) {
        match event {
            Event::Move(m) => {
                let lookahead = &mut self.lookahead;
                self.limits.queued_move(m, |q| lookahead.add(q, out));
            }
            Event::Stop { dwell_s, .. } => {
                self.lookahead.flush_all(out);
                if dwell_s.is_finite() && *dwell_s > 0.0 {
                    self.lookahead.print_time_s += dwell_s;
                }
            }
            Event::Limits { change, .. } => self.limits.apply(change),
            // The shaper acts after planning; the Stop before it has flushed the lookahead.
            Event::Shaper { .. } => {}
            // Marlin's settings do not reach Klipper (the interpreter emits them only in
            // Marlin's dialect).
            Event::Marlin { .. } => {}
        }
    }

    /// End of the input: plans and hands `out` every move still queued.
    pub fn finish(&mut self, out: &mut impl FnMut(PlannedMove)) {
        self.lookahead.flush_all(out);
    }

    /// Print time of the moves handed on so far, dwells included, s.
    pub fn print_time_s(&self) -> f64 {
        self.lookahead.print_time_s
    }

    /// Moves waiting in the lookahead queue (at most [`Planner::MAX_QUEUE`]).
    pub fn queued(&self) -> usize {
        self.lookahead.len()
    }

    /// The lookahead queue's cap, moves: past it the older half is planned as if the
    /// toolhead had to stop after the last queued move.
    pub const MAX_QUEUE: usize = queue::DEFAULT_MAX_QUEUE;
}
