//! Klipper's motion planner: speed limits, junction speeds, lookahead and trapezoids.

use crate::path::Path;

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
