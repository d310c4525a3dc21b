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
    /// A chord of a Marlin arc (its planner reads it as one block, with a hint of the
    /// arc's remaining length); None for a straight move and for Klipper's chords.
    pub arc: Option<ArcChord>,
}

/// Where a chord of a Marlin arc lies in its arc: `plan_arc`'s planner hints.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ArcChord {
    /// The arc's radius, mm.
    pub radius_mm: f64,
    /// The arc's length in its plane after this chord, mm (0 for the last chord).
    pub remaining_mm: f64,
}

/// A change of Marlin's motion settings, taking effect for the moves after it (none of
/// these commands waits for the planner). Towers A, B, C are Marlin's X, Y, Z.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MarlinChange {
    /// M201 X Y Z E: the towers' and E's max acceleration, mm/s².
    MaxAccel([Option<f64>; 4]),
    /// M203 X Y Z E: the towers' and E's max feedrate, mm/s.
    MaxFeedrate([Option<f64>; 4]),
    /// M204: S sets print and travel, then P (print), R (retract), T (travel), mm/s².
    Accel {
        print: Option<f64>,
        retract: Option<f64>,
        travel: Option<f64>,
    },
    /// M205 X Y Z E (classic jerk, mm/s), S (min print feedrate), T (min travel feedrate).
    /// (B, the min segment time, does nothing on a delta; J is not read with classic jerk.)
    Jerk {
        jerk: [Option<f64>; 4],
        min_feedrate: Option<f64>,
        min_travel_feedrate: Option<f64>,
    },
    /// M665: the delta's settings.
    Delta(DeltaChange),
}

/// M665's parameters.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DeltaChange {
    /// S: segments per second.
    pub segments_per_second: Option<f64>,
    /// L: diagonal rod, mm.
    pub diagonal_rod_mm: Option<f64>,
    /// R: delta radius, mm.
    pub radius_mm: Option<f64>,
    /// H: delta height, mm (it sets the position at the next G28).
    pub height_mm: Option<f64>,
    /// X Y Z: tower angle trims, degrees.
    pub angle_trim_deg: [Option<f64>; 3],
    /// A B C: diagonal rod trims, mm.
    pub rod_trim_mm: [Option<f64>; 3],
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
    /// A change of Marlin's settings (the Marlin dialect only).
    Marlin {
        line: u64,
        change: MarlinChange,
    },
}

impl Event {
    /// The G-code line of the event.
    pub fn line(&self) -> u64 {
        match self {
            Event::Move(m) => m.line,
            Event::Stop { line, .. }
            | Event::Limits { line, .. }
            | Event::Shaper { line, .. }
            | Event::Marlin { line, .. } => *line,
        }
    }
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
