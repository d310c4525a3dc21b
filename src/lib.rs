//! delta-gcode: plans slicer G-code the way Klipper does and runs the Lagrangian dynamic
//! model of a prismatic delta robot over it, to find the force each carriage motor must give.
//!
//! The command line is the binary's (`src/main.rs`, `src/cli`); this library is the
//! pipeline. Pipeline (one module per stage, joined only by plain data types):
//! `gcode` (lines → [`gcode::Event`]) → `planner` ([`planner::PlannedMove`]) →
//! `resample` ([`resample::Sample`]) → `delta` (forces) → `report` → `emit`.

pub mod analysis;
pub mod delta;
pub mod emit;
pub mod firmware;
pub mod gcode;
pub mod interval;
pub mod klipper_import;
pub mod machine;
pub mod motion;
pub mod motor;
pub mod path;
pub mod plot;
pub mod report;
pub mod resample;
pub mod tune;
