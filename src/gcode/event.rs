//! The plain data the G-code stage hands to the planner.

use crate::motion::shaper::ShaperChange;
use crate::path::{Path, Vec3};

/// One commanded segment (G0/G1/G2/G3, G10/G11, an E-only G1), with its source line.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Move {
    /// 1-based line number in the input file.
    pub line: u64,
    /// Nozzle path in the bed frame, mm. An E-only move is a zero-length line.
    pub path: Path,
    /// Extruder (filament) motion of this move, mm; negative for a retract.
    pub e_mm: f64,
    /// Requested speed, mm/s: the modal F (mm/min) / 60, times the M220 factor.
    pub feed_mm_s: f64,
    /// The G92 offset in force: machine position = the file's coordinates + this, mm.
    pub offset_mm: Vec3,
}

/// A change of the planner's limits, taking effect at the line where it stands
/// (M204 resolved as Klipper reads it, or SET_VELOCITY_LIMIT).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LimitChange {
    pub velocity_mm_s: Option<f64>,
    pub accel_mm_s2: Option<f64>,
    pub square_corner_velocity_mm_s: Option<f64>,
    pub minimum_cruise_ratio: Option<f64>,
    /// ACCEL_TO_DECEL, which only Klipper before 2024 reads (a profile with
    /// `limits.max_accel_to_decel_mm_s2`).
    pub accel_to_decel_mm_s2: Option<f64>,
}

impl LimitChange {
    /// The values Klipper accepts (toolhead.py `cmd_SET_VELOCITY_LIMIT`): velocity, accel
    /// and ACCEL_TO_DECEL finite and above 0, scv finite and at least 0, the cruise ratio
    /// in [0, 1); the others left out (the G-code stage reports them).
    pub fn accepted(&self) -> LimitChange {
        let positive = |v: Option<f64>| v.filter(|x| x.is_finite() && *x > 0.0);
        LimitChange {
            velocity_mm_s: positive(self.velocity_mm_s),
            accel_mm_s2: positive(self.accel_mm_s2),
            square_corner_velocity_mm_s: self
                .square_corner_velocity_mm_s
                .filter(|x| x.is_finite() && *x >= 0.0),
            minimum_cruise_ratio: self.minimum_cruise_ratio.filter(|x| (0.0..1.0).contains(x)),
            accel_to_decel_mm_s2: positive(self.accel_to_decel_mm_s2),
        }
    }
}

/// What one G-code line asks of the machine, in the order the lines stand.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Event {
    Move(Move),
    /// The toolhead comes to rest and the lookahead is flushed (G4, M400, G28).
    /// `dwell_s` is added to the print time (G4 P/S).
    Stop {
        line: u64,
        dwell_s: f64,
    },
    Limits {
        line: u64,
        change: LimitChange,
    },
    /// Klipper's SET_INPUT_SHAPER: the shaper for the moves that follow (the toolhead has
    /// come to rest just before: a `Stop` precedes it).
    Shaper {
        line: u64,
        change: ShaperChange,
    },
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Severity {
    Warning,
    Error,
}

/// A problem found in the input, tied to its place: 1-based line and column.
#[derive(Clone, Debug, PartialEq)]
pub struct Diagnostic {
    pub line: u64,
    pub column: u32,
    pub severity: Severity,
    pub message: String,
}
