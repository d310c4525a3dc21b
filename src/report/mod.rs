//! Per-move statistics and the report, with its text, JSON, GitHub and annotation writers.
//! The writers only format a [`Report`]; they compute nothing.

mod annotations;
mod diagnostics;
mod footprint;
mod github;
mod stats;
mod text;

pub use annotations::{annotations, summary_lines, verdict_line};
pub use diagnostics::{DiagnosticKind, DiagnosticKinds, DiagnosticLog, KIND_LINES, severity_name};
pub use github::write_github;
pub use stats::{MoveStats, NEAR_SINGULAR_RATIO, PathChecks, Problem, RunForces, Worst, share};
pub use text::write_text;

use serde::Serialize;

use crate::delta::TOWER_NAMES;
use crate::gcode::{Diagnostic, Severity};
use crate::interval::greater;
use crate::resample::Phase;

/// At most this many violations and diagnostics are kept in detail; all are counted.
pub const MAX_LISTED: usize = 10_000;

/// The outcome of checking one file: the JSON report (docs/report.md).
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    pub file: String,
    pub machine: String,
    pub limit_force_n: f64,
    /// The profile's `geometry.arm_magnet_hold_n`, N.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub arm_magnet_hold_n: Option<f64>,
    pub summary: Summary,
    pub violations: Vec<Violation>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub moves: Option<Vec<MoveEntry>>,
    pub diagnostics: Vec<DiagnosticEntry>,
    /// The diagnostics grouped by kind, each with its count and first lines.
    pub diagnostic_kinds: DiagnosticKinds,
    /// What the report says of the file as a whole (that it seems sliced for another
    /// printer).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub notes: Vec<String>,
    #[serde(skip)]
    footprint: footprint::Footprint,
    /// A failing file: the limits under which it passes (verified by re-planning).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub recommendation: Option<Recommendation>,
    /// A failing file with no recommendation: why none (a move no limit helps).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub recommendation_error: Option<String>,
}

/// Limits under which a file passes, and its print time with them (`tune`). For a Marlin
/// profile the three limits are the largest M204 P/T, the towers' jerk (M205 X/Y/Z) and
/// the towers' feedrate (M203 X/Y/Z), spelled out in `marlin`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Recommendation {
    pub max_accel_mm_s2: f64,
    pub square_corner_velocity_mm_s: f64,
    pub max_velocity_mm_s: f64,
    pub print_time_s: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub marlin: Option<MarlinRecommendation>,
}

/// Marlin's settings under which a file passes (each at most this, on every tower).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MarlinRecommendation {
    /// M204 P and T, mm/s².
    pub print_accel_mm_s2: f64,
    pub travel_accel_mm_s2: f64,
    /// M205 X Y Z: the towers' classic jerk, mm/s.
    pub jerk_mm_s: f64,
    /// M203 X Y Z: the towers' max feedrate, mm/s.
    pub max_feedrate_mm_s: f64,
    /// The commands that set them, e.g. `M204 P1800 T1800`.
    pub commands: Vec<String>,
}

impl Recommendation {
    /// The limits as the firmware's commands: Marlin's M204, M205, M203, or Klipper's
    /// `SET_VELOCITY_LIMIT`.
    pub fn commands(&self) -> String {
        match &self.marlin {
            Some(m) => m.commands.join(", "),
            None => format!(
                "ACCEL={} SQUARE_CORNER_VELOCITY={} VELOCITY={}",
                self.max_accel_mm_s2, self.square_corner_velocity_mm_s, self.max_velocity_mm_s
            ),
        }
    }
}

#[derive(Clone, Debug, Default, Serialize)]
pub struct Summary {
    pub lines: u64,
    pub moves: u64,
    pub samples: u64,
    pub print_time_s: f64,
    pub peak_force_n: [f64; 3],
    /// Line of each tower's peak.
    pub peak_line: [u64; 3],
    /// Time of each tower's peak, s.
    pub peak_t_s: [f64; 3],
    /// Per tower, the largest share of the force its motor can give that a move asked
    /// (|Q_i| / available at that carriage speed; above 1 the motor skips steps), and the
    /// line.
    pub peak_use: [f64; 3],
    pub peak_use_line: [u64; 3],
    /// Largest pull of each parallelogram on the platform (both rods), N.
    pub peak_tension_n: [f64; 3],
    /// Moves over the force available, unreachable, above home or outside the print
    /// radius.
    pub violations: u64,
    pub unreachable: u64,
    pub warnings: u64,
    pub errors: u64,
}

/// What a flagged move did wrong; the JSON report's `kind`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ViolationKind {
    /// More force than the motor can give.
    Force,
    /// An arm pulls harder than its magnetic joints hold.
    ArmTension,
    Unreachable,
    AboveHome,
    BelowBed,
    OutsideRadius,
    NotSampled,
}

impl ViolationKind {
    /// The name in reports (as in the JSON).
    pub fn as_str(self) -> &'static str {
        match self {
            ViolationKind::Force => "force",
            ViolationKind::ArmTension => "arm_tension",
            ViolationKind::Unreachable => "unreachable",
            ViolationKind::AboveHome => "above_home",
            ViolationKind::BelowBed => "below_bed",
            ViolationKind::OutsideRadius => "outside_radius",
            ViolationKind::NotSampled => "not_sampled",
        }
    }
}

impl std::fmt::Display for ViolationKind {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

impl Serialize for ViolationKind {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.as_str())
    }
}

#[derive(Clone, Debug, Serialize)]
pub struct Violation {
    pub line: u64,
    pub kind: ViolationKind,
    /// Kind `force`: the force each tower needed at its worst instant (the one closest to,
    /// or furthest beyond, what its motor gives); other kinds: the move's peak forces; none
    /// for a move out of reach (`unreachable`, `above_home`). N.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub peak_force_n: Option<[f64; 3]>,
    /// Kind `force`: the force each motor could give at that instant, at that carriage
    /// speed, N.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub available_force_n: Option<[f64; 3]>,
    /// 1-based tower (1 = A) of the worst force, or of the problem.
    pub tower: usize,
    pub t_s: f64,
    pub phase: Phase,
    pub message: String,
    /// The G-code line itself, filled in by [`Report::set_commands`].
    #[serde(skip_serializing_if = "String::is_empty")]
    pub command: String,
}

#[derive(Clone, Debug, Serialize)]
pub struct MoveEntry {
    pub line: u64,
    /// None for a move out of reach.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub peak_force_n: Option<[f64; 3]>,
}

#[derive(Clone, Debug, Serialize)]
pub struct DiagnosticEntry {
    pub line: u64,
    pub column: u32,
    pub severity: &'static str,
    pub message: String,
}

impl Report {
    pub fn new(file: &str, machine: &str, limit_force_n: f64, all_moves: bool) -> Self {
        Report {
            file: file.to_string(),
            machine: machine.to_string(),
            limit_force_n,
            arm_magnet_hold_n: None,
            summary: Summary::default(),
            violations: Vec::new(),
            moves: all_moves.then(Vec::new),
            diagnostics: Vec::new(),
            diagnostic_kinds: DiagnosticKinds::default(),
            notes: Vec::new(),
            footprint: footprint::Footprint::default(),
            recommendation: None,
            recommendation_error: None,
        }
    }

    /// Takes one move's statistics, in file order. A move out of reach adds no force: its
    /// samples near the edge of the reach ask for forces that mean nothing. Inlined into
    /// the run's per-move callback, whose frame it then shares.
    #[inline(always)]
    pub fn add_move(&mut self, m: &MoveStats) {
        if self.add_peaks(m) {
            self.add_rest(m);
        }
    }

    /// The part of [`Self::add_move`] every move needs: its count, samples and peaks.
    /// Returns whether the move has more to report ([`Self::add_rest`]): its entry in the
    /// list of moves, a flag. Nearly no move has, so the per-move callback's common path
    /// makes no call and saves no register: its frame saved all six callee-saved registers
    /// for the rare paths (−0.28 % of a default run's instructions, −0.13 % shaped).
    #[inline(always)]
    pub fn add_peaks(&mut self, m: &MoveStats) -> bool {
        let reachable = m.reachable();
        let s = &mut self.summary;
        s.moves += 1;
        s.samples += m.samples;
        for i in (0..3).filter(|_| reachable) {
            if m.peak_force_n[i] > s.peak_force_n[i] {
                s.peak_force_n[i] = m.peak_force_n[i];
                s.peak_line[i] = m.line;
                s.peak_t_s[i] = m.peak_t_s[i];
            }
            s.peak_tension_n[i] = greater(m.peak_tension_n[i], s.peak_tension_n[i]);
            if m.worst[i].ratio > s.peak_use[i] {
                s.peak_use[i] = m.worst[i].ratio;
                s.peak_use_line[i] = m.line;
            }
        }
        self.moves.is_some() || self.has_flags(m)
    }

    /// Whether a move may have something to flag ([`Self::add_flags`]).
    #[inline(always)]
    fn has_flags(&self, m: &MoveStats) -> bool {
        let checks = &m.checks;
        checks.problem.is_some()
            || checks.near_singular.is_some()
            || m.over_force()
            || self.arm_magnet_hold_n.is_some()
    }

    /// What [`Self::add_peaks`] left of a move: its entry in the list of moves, its flags.
    #[cold]
    #[inline(never)]
    pub fn add_rest(&mut self, m: &MoveStats) {
        let reachable = m.reachable();
        if let Some(moves) = &mut self.moves {
            moves.push(MoveEntry {
                line: m.line,
                peak_force_n: reachable.then_some(m.peak_force_n),
            });
        }
        if self.has_flags(m) {
            self.add_flags(m, reachable);
        }
    }

    /// What [`Self::add_move`] reports of a move besides its peaks: a near-singular pose,
    /// a violation. Out of line, with the formatting of their messages: `add_move`'s frame
    /// was that of both, and its worst tower found for every move (−0.3 % of a default
    /// run's instructions).
    #[inline(never)]
    fn add_flags(&mut self, m: &MoveStats, reachable: bool) {
        if let Some((tower, ratio)) = m.checks.near_singular.filter(|_| reachable) {
            let angle = (1.0 / ratio).atan().to_degrees();
            self.add_diagnostic(&Diagnostic {
                line: m.line,
                column: 1,
                severity: Severity::Warning,
                message: format!(
                    "near-singular pose: tower {} arm {angle:.1}° from flat, carriage up to {ratio:.1}× the nozzle speed",
                    TOWER_NAMES[tower]
                ),
            });
        }
        if let Some(v) = self.violation_of(m) {
            self.summary.violations += 1;
            if v.kind == ViolationKind::Unreachable {
                self.summary.unreachable += 1;
            }
            if self.violations.len() < MAX_LISTED {
                self.violations.push(v);
            }
        }
    }

    fn violation_of(&self, m: &MoveStats) -> Option<Violation> {
        let worst = m.worst_tower();
        let (kind, tower, t_s, message) = match m.checks.problem.as_deref() {
            Some(
                p @ Problem::Unreachable {
                    t_s,
                    tower,
                    pos_mm,
                    reason,
                },
            ) => (
                p.kind(),
                tower.unwrap_or(worst),
                *t_s,
                format!(
                    "UNREACHABLE at X{:.3} Y{:.3} Z{:.3}: {reason}",
                    pos_mm[0] - m.checks.offset_mm[0],
                    pos_mm[1] - m.checks.offset_mm[1],
                    pos_mm[2] - m.checks.offset_mm[2]
                ),
            ),
            Some(
                p @ Problem::AboveHome {
                    t_s,
                    tower,
                    over_mm,
                },
            ) => (
                p.kind(),
                *tower,
                *t_s,
                format!(
                    "ABOVE HOME tower {}: carriage {over_mm:.3} mm above its homed height",
                    TOWER_NAMES[*tower]
                ),
            ),
            Some(
                p @ Problem::OutsideRadius {
                    radius_mm,
                    limit_mm,
                },
            ) => (
                p.kind(),
                worst,
                m.peak_t_s[worst],
                format!("OUTSIDE print radius: {radius_mm:.2} mm > {limit_mm:.2} mm"),
            ),
            Some(p @ Problem::BelowBed { z_mm }) => (
                p.kind(),
                worst,
                m.peak_t_s[worst],
                format!("BELOW the bed: z = {z_mm:.3} mm"),
            ),
            Some(p @ Problem::NotSampled { duration_s }) => (
                p.kind(),
                worst,
                m.peak_t_s[worst],
                format!(
                    "NOT SAMPLED: the move lasts {duration_s:.0} s; only its ends were checked"
                ),
            ),
            None if m.over_force() => {
                let tower = m.worst_use_tower();
                let w = &m.worst[tower];
                return Some(Violation {
                    line: m.line,
                    kind: ViolationKind::Force,
                    peak_force_n: Some(m.worst.map(|w| w.force_n)),
                    available_force_n: Some(m.worst.map(|w| w.available_n)),
                    tower: tower + 1,
                    t_s: w.t_s,
                    phase: m.worst_phase[tower],
                    message: format!(
                        "OVER force: tower {} needs {:.1} N, its motor gives {:.1} N at {:.0} mm/s",
                        TOWER_NAMES[tower], w.force_n, w.available_n, w.speed_mm_s
                    ),
                    command: String::new(),
                });
            }
            None => {
                let hold = self.arm_magnet_hold_n?;
                let pull = m.peak_tension_n;
                let tower = (0..3).max_by(|&a, &b| pull[a].total_cmp(&pull[b]))?;
                if pull[tower] <= hold {
                    return None;
                }
                (
                    ViolationKind::ArmTension,
                    tower,
                    m.peak_tension_t_s[tower],
                    format!(
                        "ARM LETS GO: tower {}'s arms pull {:.1} N, their magnets hold {hold:.1} N",
                        TOWER_NAMES[tower], pull[tower]
                    ),
                )
            }
        };
        let phase = m.peak_phase[worst];
        let reachable = !m
            .checks
            .problem
            .as_deref()
            .is_some_and(Problem::unreachable);
        Some(Violation {
            line: m.line,
            kind,
            peak_force_n: reachable.then_some(m.peak_force_n),
            available_force_n: None,
            tower: tower + 1,
            t_s,
            phase,
            message,
            command: String::new(),
        })
    }

    pub fn add_diagnostic(&mut self, d: &Diagnostic) {
        self.diagnostic_kinds.add(d);
        self.list_diagnostic(d);
    }

    /// Takes in the diagnostics of the reader (after the moves' own).
    pub fn add_diagnostics(&mut self, log: DiagnosticLog) {
        for d in &log.listed {
            self.list_diagnostic(d);
        }
        self.summary.warnings += log.unlisted_warnings;
        self.summary.errors += log.unlisted_errors;
        self.diagnostic_kinds.merge(log.kinds);
    }

    /// Counts a diagnostic, and lists it while fewer than [`MAX_LISTED`] are.
    fn list_diagnostic(&mut self, d: &Diagnostic) {
        match d.severity {
            Severity::Warning => self.summary.warnings += 1,
            Severity::Error => self.summary.errors += 1,
        }
        if self.diagnostics.len() < MAX_LISTED {
            self.diagnostics.push(DiagnosticEntry {
                line: d.line,
                column: d.column,
                severity: diagnostics::severity_name(d.severity),
                message: d.message.clone(),
            });
        }
    }

    /// Lines of the listed violations, to look up their text.
    pub fn violation_lines(&self) -> Vec<u64> {
        self.violations.iter().map(|v| v.line).collect()
    }

    /// Fills in each violation's G-code text; `lookup` gives a line's text by number.
    pub fn set_commands(&mut self, mut lookup: impl FnMut(u64) -> Option<String>) {
        for v in &mut self.violations {
            if let Some(text) = lookup(v.line) {
                v.command = text;
            }
        }
    }

    /// Whether anything exceeded a limit or could not be reached.
    pub fn failed(&self) -> bool {
        self.summary.violations > 0
    }

    /// The violations, worst first: problems before forces, then by force needed / force
    /// available.
    pub fn worst_first(&self) -> Vec<&Violation> {
        let mut v: Vec<&Violation> = self.violations.iter().collect();
        let key = |v: &Violation| match (v.available_force_n, v.peak_force_n) {
            (Some(a), Some(f)) => (0..3)
                .map(|i| f[i] / a[i].max(f64::MIN_POSITIVE))
                .fold(0.0_f64, f64::max),
            _ => f64::INFINITY,
        };
        v.sort_by(|a, b| key(b).total_cmp(&key(a)).then(a.line.cmp(&b.line)));
        v
    }
}

/// `31.2/12.0/9.8`
pub fn format_forces(f: &[f64; 3]) -> String {
    format!("{:.1}/{:.1}/{:.1}", f[0], f[1], f[2])
}

/// Several files' reports as JSON: one object for one file, an array for several.
pub fn write_json(
    out: &mut (impl std::io::Write + ?Sized),
    reports: &[Report],
) -> std::io::Result<()> {
    match reports {
        [one] => serde_json::to_writer_pretty(&mut *out, one)?,
        many => serde_json::to_writer_pretty(&mut *out, many)?,
    }
    writeln!(out)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// One sample into a move's statistics, the motors giving 30 N at 120 mm/s.
    fn sample(m: &mut MoveStats, t: f64, phase: Phase, f: [f64; 3]) {
        m.add_run(&RunForces {
            t_s: &[t],
            phase: &[phase],
            force_n: [&[f[0]], &[f[1]], &[f[2]]],
            available_n: [&[30.0]; 3],
            speed_mm_s: [&[120.0]; 3],
            tension_n: [&[f[0]], &[f[1]], &[f[2]]],
        });
    }

    /// A report with one move within limits, one over, one unreachable.
    pub(crate) fn sample_report() -> Report {
        let mut r = Report::new("part.gcode", "Kossel", 30.0, true);
        let mut ok = MoveStats::new(10);
        sample(&mut ok, 1.0, Phase::Cruise, [10.0, 11.0, 12.0]);
        let mut over = MoveStats::new(20);
        sample(&mut over, 2.5, Phase::Decel, [31.25, -12.0, 9.8]);
        let mut far = MoveStats::new(30);
        sample(&mut far, 3.0, Phase::Accel, [1.0, 1.0, 1.0]);
        far.checks.flag(Problem::Unreachable {
            t_s: 3.0,
            tower: Some(1),
            pos_mm: [200.0, 0.0, 0.0],
            reason: "tower B: arm too short".into(),
        });
        for m in [&ok, &over, &far] {
            r.add_move(m);
        }
        r.summary.print_time_s = 3.5;
        r.summary.lines = 40;
        r
    }

    #[test]
    fn summary_and_violations() {
        let r = sample_report();
        assert_eq!(r.summary.moves, 3);
        assert_eq!(r.summary.samples, 3);
        assert_eq!(r.summary.violations, 2);
        assert_eq!(r.summary.unreachable, 1);
        assert_eq!(r.summary.peak_force_n, [31.25, 12.0, 12.0]);
        assert_eq!(r.summary.peak_line, [20, 20, 10]);
        assert_eq!(r.violations[0].kind, ViolationKind::Force);
        assert_eq!(r.violations[0].tower, 1);
        assert_eq!(
            r.violations[0].message,
            "OVER force: tower A needs 31.2 N, its motor gives 30.0 N at 120 mm/s"
        );
        assert_eq!(r.violations[0].available_force_n, Some([30.0; 3]));
        assert_eq!(r.summary.peak_use, [31.25 / 30.0, 0.4, 0.4]);
        assert_eq!(r.summary.peak_use_line, [20, 20, 10]);
        assert_eq!(r.violations[1].kind, ViolationKind::Unreachable);
        assert_eq!(r.violations[1].tower, 2);
        // Out of reach: no forces, in the violation or in the summary.
        assert_eq!(r.violations[1].peak_force_n, None);
        assert_eq!(r.moves.as_ref().map(|m| m[2].peak_force_n), Some(None));
        assert!(r.failed());
        let worst: Vec<u64> = r.worst_first().iter().map(|v| v.line).collect();
        assert_eq!(worst, [30, 20]);
    }

    #[test]
    fn an_arm_pulling_harder_than_its_magnets_is_a_violation() {
        let mut r = Report::new("part.gcode", "Q5", 30.0, false);
        r.arm_magnet_hold_n = Some(20.0);
        let mut m = MoveStats::new(5);
        sample(&mut m, 1.0, Phase::Accel, [10.0, 21.5, 12.0]);
        r.add_move(&m);
        let v = &r.violations[0];
        assert_eq!((v.kind, v.tower, v.line), (ViolationKind::ArmTension, 2, 5));
        assert!(
            v.message.contains("tower B's arms pull 21.5 N"),
            "{}",
            v.message
        );
        assert_eq!(r.summary.peak_tension_n, [10.0, 21.5, 12.0]);
        // Within the hold, or no magnets: nothing.
        let mut ok = Report::new("part.gcode", "Q5", 30.0, false);
        ok.add_move(&m);
        assert!(ok.violations.is_empty());
    }

    #[test]
    fn json_has_the_design_schema() {
        let r = sample_report();
        let mut buf = Vec::new();
        write_json(&mut buf, std::slice::from_ref(&r)).unwrap();
        let v: serde_json::Value = serde_json::from_slice(&buf).unwrap();
        for key in [
            "file",
            "machine",
            "limit_force_n",
            "summary",
            "violations",
            "moves",
        ] {
            assert!(v.get(key).is_some(), "{key}");
        }
        for key in [
            "lines",
            "moves",
            "samples",
            "print_time_s",
            "peak_force_n",
            "violations",
            "unreachable",
            "peak_use",
        ] {
            assert!(v["summary"].get(key).is_some(), "summary.{key}");
        }
        let viol = &v["violations"][0];
        assert_eq!(viol["line"], 20);
        assert_eq!(viol["kind"], "force");
        assert_eq!(viol["tower"], 1);
        assert_eq!(viol["phase"], "decel");
        assert_eq!(viol["t_s"], 2.5);
        assert_eq!(viol["available_force_n"][0], 30.0);
        assert!(v["violations"][1].get("available_force_n").is_none());
        assert_eq!(v["moves"].as_array().map(Vec::len), Some(3));
        let mut two = Vec::new();
        write_json(&mut two, &[r.clone(), r]).unwrap();
        let arr: serde_json::Value = serde_json::from_slice(&two).unwrap();
        assert_eq!(arr.as_array().map(Vec::len), Some(2));
    }
}
