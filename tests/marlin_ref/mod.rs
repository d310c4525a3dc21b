//! An independent, slow, plain reference of how Marlin 2.1.2.x moves a linear delta, for
//! tests: what the carriages are commanded to do, in time.
//!
//! Source of truth: the research spec `marlin-delta-spec.md` (segmentation, MIN_STEPS,
//! per-tower limits, classic jerk, the block-buffer look-ahead, trapezoids, S-curve, arcs,
//! G-code state), checked against Marlin 2.1.2.5's `planner.cpp`, `stepper.cpp`,
//! `motion.cpp`, `G2_G3.cpp`, `G92.cpp`, `M200-M205.cpp`. It shares no code with the
//! production planner.
//!
//! What it models:
//! * G-code: G0/G1, G2/G3 (I/J and R forms), G4 (sync + dwell), G28 (sync; the nozzle is
//!   declared at (0, 0, home z): the homing moves are not simulated), G90/G91, M82/M83
//!   (G90 resets E to absolute), G92 (workspace shift for X/Y/Z, E set with a sync block),
//!   M201/M203/M204/M205 (X Y Z = towers A B C), M211 S, M220 S/B/R, M221 S, M400, M665
//!   (geometry, segments/s; un-homes), M109/M190 (the queue runs dry while the heater
//!   waits; the wait itself is not counted). Everything else is ignored.
//! * The radius clamp (which scales Z too) and the Z clamp [0, home z] when homed with
//!   soft endstops on; unreachable moves dropped when not homed.
//! * The delta segmenter: plain (`line_to_destination_kinematic`, the default) or UBL's
//!   (leveling inactive), see [`Segmenter`]. Arc chords are single blocks.
//! * The planner block: steps by lround of the IK, MIN_STEPS_PER_SEGMENT dropping (the
//!   steps move into the next block, the time is lost), E-only length, M221 flow, minimum
//!   feedrates, per-tower M203 limits (speed factor, truncated nominal rate), M204 P/R/T
//!   and per-axis M201 limits in integer steps/s², classic jerk on tower speeds (A, B, C, E
//!   in order, the safe-speed override), MINIMUM_PLANNER_SPEED.
//! * The look-ahead as Marlin runs it with a CPU that is never the bottleneck: at most
//!   BLOCK_BUFFER_SIZE − 1 blocks queued, the first block starts when the queue is full,
//!   each block's profile is frozen when it starts, Marlin's reverse and forward passes
//!   with its `planned` pointer, sync blocks taking a slot, arcs' safe exit speed hints.
//! * The stepper: see [`stepper`] — Marlin's ISR timing (default) or the continuous
//!   step-rate profile; trapezoid or S-curve.
//!
//! Arithmetic: f64 throughout, where Marlin's planner computes in f32. The choice is
//! deliberate: the reference should be plainly right, and f32's effects are far below what
//! it is compared at (a carriage height in f32 is good to 2e-5 mm against a step of
//! 0.0125 mm; only a step target within ~1e-5 steps of .5 could round the other way, one
//! step for one segment). Integer rules Marlin applies on purpose are kept: lround of step
//! targets, ceil/floor of rates and ramp steps, uint32 truncations, integer timer ticks.
//!
//! What it leaves out: multi-stepping, AVR's timer tables, LIN_ADVANCE
//! (K = 0 in the example configs), bed leveling corrections, the first-move delay
//! (BLOCK_DELAY_FOR_1ST_MOVE) and any CPU starvation, the homing moves, heater waits,
//! PREVENT_COLD/LENGTHY_EXTRUSION, firmware retraction, inches (G20), NO_MOTION_BEFORE_HOMING
//! unless asked ([`Options`]).

#[cfg(test)]
mod hand_cases;
pub mod kinematics;
pub mod line;
pub mod motion;
pub mod planner;
pub mod stepper;

use delta_gcode::machine::{Firmware, Machine};

use kinematics::Delta;
use motion::Printer;
use planner::{Executed, Planner, Settings};
pub use stepper::Timing;

/// Which delta segmenter Marlin was built with.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Segmenter {
    /// `line_to_destination_kinematic`: floor(S · L_xyz / F) segments (spec §3.2).
    #[default]
    Plain,
    /// `AUTO_BED_LEVELING_UBL` (leveling off): min(lround(S · L_xy / F), lround(L_xy / 0.1))
    /// segments (spec §3.3).
    Ubl,
}

/// Choices the profile does not make.
#[derive(Clone, Copy, Debug)]
pub struct Options {
    pub segmenter: Segmenter,
    pub timing: Timing,
    /// `NO_MOTION_BEFORE_HOMING`: G0–G3 refused while unhomed (after M665).
    pub no_motion_before_homing: bool,
    /// The machine is homed at the start (the nozzle is at (0, 0, home z) before any G28).
    pub start_homed: bool,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            segmenter: Segmenter::Plain,
            timing: Timing::default(),
            no_motion_before_homing: false,
            start_homed: true,
        }
    }
}

/// Everything a run produced.
#[derive(Debug)]
pub struct Run {
    /// The blocks in the order the stepper ran them, with their start times.
    pub executed: Vec<Executed>,
    /// Segments dropped (fewer than MIN_STEPS_PER_SEGMENT steps).
    pub dropped: usize,
    /// Moves refused or dropped by the G-code layer.
    pub refused: usize,
    /// `current_position` at the end (native x, y, z, e).
    pub final_position: [f64; 4],
    pub spm: [f64; 4],
    pub s_curve: bool,
    pub timing: Timing,
}

/// The Marlin settings of a profile.
pub fn settings(m: &Machine) -> Settings {
    let Firmware::Marlin(mm) = &m.firmware else {
        panic!("marlin_ref needs a profile with `firmware: marlin`");
    };
    Settings {
        spm: [
            mm.steps_per_mm,
            mm.steps_per_mm,
            mm.steps_per_mm,
            mm.e_steps_per_mm,
        ],
        max_feedrate: mm.max_feedrate_mm_s,
        max_accel: mm.max_accel_mm_s2,
        print_accel: mm.print_accel_mm_s2,
        retract_accel: mm.retract_accel_mm_s2,
        travel_accel: mm.travel_accel_mm_s2,
        jerk: mm.jerk_mm_s,
        min_feedrate: 0.0,
        min_travel_feedrate: 0.0,
        flow_percent: 100,
        min_steps_per_segment: mm.min_steps_per_segment,
        minimum_planner_speed: mm.minimum_planner_speed_mm_s,
        block_buffer_size: mm.block_buffer_size as usize,
        s_curve: mm.s_curve,
    }
}

/// Runs `gcode` through the reference; the queue is flushed at the end.
pub fn simulate(gcode: &[u8], m: &Machine, opts: &Options) -> Run {
    let settings = settings(m);
    let Firmware::Marlin(mm) = &m.firmware else {
        unreachable!()
    };
    let spm = settings.spm;
    let s_curve = settings.s_curve;
    let planner = Planner::new(settings, opts.timing);
    let mut p = Printer::new(
        planner,
        Delta::from_geometry(&m.geometry),
        mm.segments_per_second,
        opts,
    );
    for raw in gcode.split(|&b| b == b'\n') {
        if let Some(l) = line::parse_line(raw) {
            p.execute(&l);
        }
    }
    p.planner.synchronize();
    Run {
        executed: std::mem::take(&mut p.planner.executed),
        dropped: p.planner.dropped,
        refused: p.refused,
        final_position: p.current,
        spm,
        s_curve,
        timing: opts.timing,
    }
}

impl Run {
    /// t = 0: the start of the first block the stepper ran (global clock, s).
    pub fn start_s(&self) -> f64 {
        self.executed.first().map_or(0.0, |e| e.start_s)
    }

    /// The print time: from the start of the first block to the end of the last one
    /// (E-only blocks, and dwells between blocks, included), s.
    pub fn print_time_s(&self) -> f64 {
        self.executed
            .last()
            .map_or(0.0, |e| e.start_s + e.duration_s - self.start_s())
    }

    /// The commanded carriage heights (mm, towers A, B, C) at each of `times` (s from
    /// [`Run::start_s`], ascending). Before the first block: where it starts; between
    /// blocks and after the last: where the last one ended.
    pub fn heights_at(&self, times: &[f64]) -> Vec<[f64; 3]> {
        let mm = |steps: [f64; 3]| [0, 1, 2].map(|i| steps[i] / self.spm[i]);
        let Some(first) = self.executed.first() else {
            return Vec::new();
        };
        let t0 = first.start_s;
        let start = [0, 1, 2].map(|i| first.block.start[i] as f64);
        let mut out = Vec::with_capacity(times.len());
        // The block running at the time: the last one started at or before it (blocks
        // are in time order); found by bisection for the first time, then walked.
        let started = |t: f64| self.executed.partition_point(|e| e.start_s <= t);
        let mut next = times.first().map_or(0, |&t| started(t0 + t));
        let mut motion: Option<(usize, stepper::BlockMotion)> = None;
        for &t in times {
            let t = t0 + t;
            while next < self.executed.len() && self.executed[next].start_s <= t {
                next += 1;
            }
            let Some(k) = next.checked_sub(1) else {
                out.push(mm(start));
                continue;
            };
            let e = &self.executed[k];
            let b = &e.block;
            let local = t - e.start_s;
            let done = if local >= e.duration_s {
                b.n as f64
            } else {
                if motion.as_ref().is_none_or(|(i, _)| *i != k) {
                    motion = Some((k, stepper::BlockMotion::new(b, self.s_curve, self.timing)));
                }
                let (_, bm) = motion.as_ref().expect("set above");
                bm.steps_at(local).clamp(0.0, b.n as f64)
            };
            // Bresenham: each tower moves in proportion to the step events done.
            out.push(mm([0, 1, 2].map(|i| {
                b.start[i] as f64 + b.delta[i] as f64 * done / b.n as f64
            })));
        }
        out
    }

    /// The commanded carriage heights every `period` s from t = 0 to the end of the last
    /// block.
    pub fn sample(&self, period: f64) -> Vec<(f64, [f64; 3])> {
        let count = (self.print_time_s() / period + 1e-9).floor() as usize + 1;
        let times: Vec<f64> = (0..count).map(|j| j as f64 * period).collect();
        let q = self.heights_at(&times);
        times.into_iter().zip(q).collect()
    }
}
