//! The search for limits that pass: check, see why each flagged move is over, lower the
//! limit that causes it by what the physics says, re-plan and re-check the whole file, until
//! nothing is over. Limits only go down, each time by at least [`MIN_STEP`], down to
//! [`FLOOR`]: the search ends.
//!
//! Why a move is over, and what to lower:
//! - the motor's torque-speed curve (`motor::StepperCurve`): the force asked would be
//!   available at a lower carriage speed → the velocity, scaled by the speed at which the
//!   curve gives that force over the speed it ran at;
//! - a corner (phase `corner`): the velocity jump scales with the square-corner velocity
//!   (in Klipper `jd·accel = scv²(√2−1)`: M204 alone never changes a corner) → the scv;
//! - accelerating or braking: the force is affine in the nozzle's acceleration (eq. 14:
//!   `M(q)q̈ + C(q, q̇)q̇ + G(q)`) → the acceleration, from the ratio, then by the secant
//!   through two passes (the affine law solved exactly);
//! - cruising at constant nozzle speed: the carriages' accelerations go as the speed
//!   squared → the velocity, by the square root of the ratio.
//!
//! For a Marlin profile the same three limits are Marlin's (`held`): M204 P/T, the towers'
//! classic jerk M205 X/Y/Z (a junction's jump in tower speeds scales with it), the towers'
//! feedrate M203 X/Y/Z (the carriage speed itself: the curve's speed is the cap, and a
//! move's limit is at most the fastest its carriages ran).

use std::collections::{BTreeMap, VecDeque};
use std::fs::File;
use std::io::BufReader;
use std::path::Path;

use anyhow::Context;

use crate::emit::WithoutOurs;
use crate::gcode::{Diagnostic, Severity};
use crate::machine::{Machine, Motors};
use crate::motion::Phase;
use crate::report::{MoveStats, Report};

use super::held::Held;
use super::limits::{Added, CapEdit, Segments, Toolhead, limits_of, segments};

/// The share of the available force the search aims at: a little below all of it.
pub const TARGET: f64 = 0.97;
/// Each lowering takes a limit to at most this share of what it was.
pub const MIN_STEP: f64 = 0.97;
/// Below these the search gives up: a move that still does not pass cannot be made to.
pub const FLOOR: Toolhead = Toolhead {
    accel_mm_s2: 100.0,
    scv_mm_s: 0.1,
    velocity_mm_s: 5.0,
};
/// Passes before the search gives up.
const MAX_PASSES: usize = 40;
/// The most moves on either side of a flagged move that its caps spread to.
const MAX_SPREAD: usize = 8;

/// Which limit a move over the force it may ask is lowered by.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Cause {
    Accel,
    Corner,
    Speed,
}

impl Cause {
    pub const ALL: [Cause; 3] = [Cause::Accel, Cause::Corner, Cause::Speed];

    pub fn value(self, t: &Toolhead) -> f64 {
        match self {
            Cause::Accel => t.accel_mm_s2,
            Cause::Corner => t.scv_mm_s,
            Cause::Speed => t.velocity_mm_s,
        }
    }

    pub fn set(self, t: &mut Toolhead, v: f64) {
        match self {
            Cause::Accel => t.accel_mm_s2 = v,
            Cause::Corner => t.scv_mm_s = v,
            Cause::Speed => t.velocity_mm_s = v,
        }
    }

    /// A limit lowered to a round figure, not below the floor: accel to 10 mm/s², scv to
    /// 0.1 mm/s, velocity to 1 mm/s.
    pub fn round_down(self, v: f64) -> f64 {
        let step = match self {
            Cause::Accel => 10.0,
            Cause::Corner => 0.1,
            Cause::Speed => 1.0,
        };
        // Whole steps, printed as they are computed (e.g. 3.7, not 3.7000000000000006).
        let r = ((v / step).floor() * step * 10.0).round() / 10.0;
        r.max(self.value(&FLOOR))
    }
}

/// What a search may lower, and how it reads Marlin's corners.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rules {
    /// No limit goes below this; a limit at infinity is not lowered at all.
    pub floor: Toolhead,
    /// Marlin's junctions through a drive of this angular frequency (rad/s): see
    /// [`wanted`].
    pub jump_omega: Option<f64>,
    /// Passes before the search gives up.
    pub max_passes: usize,
}

impl Rules {
    /// [`FLOOR`], and the drive's ω for a Marlin profile with a spring drive.
    pub fn of(machine: &Machine) -> Rules {
        let marlin = matches!(machine.firmware, crate::machine::Firmware::Marlin(_));
        Rules {
            floor: FLOOR,
            max_passes: MAX_PASSES,
            jump_omega: match machine.drive {
                crate::motion::drive::Drive::Spring(s) if marlin => {
                    Some(std::f64::consts::TAU * s.frequency_hz)
                }
                _ => None,
            },
        }
    }
}

/// Why one move was over, and the limit that would bring it under.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Over {
    pub cause: Cause,
    /// The limit of `cause` the move ran with, and what it should be.
    pub ran: f64,
    pub wanted: f64,
    /// Force asked over force available (or arm pull over magnet hold).
    pub ratio: f64,
}

/// The carriage speed at which the curve gives `force_n`, mm/s (bisection on the
/// decreasing part of the curve, below `speed_mm_s`).
fn speed_for_force(motors: &Motors, force_n: f64, speed_mm_s: f64) -> f64 {
    let (mut lo, mut hi) = (0.0, speed_mm_s);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if motors.available_force_n(mid) >= force_n {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

/// How to bring a move under: the cause and the wanted value of its limit, before rounding
/// (see the module documentation); another limit when that one is at its floor. `ran`: the
/// limits the move ran with; `earlier`: the same move's cause, limit and ratio in an
/// earlier pass, for the secant. None: the move is not over the force or the arms' hold.
///
/// `rules.jump_omega`: Marlin's junctions through a drive of this angular frequency (rad/s).
/// Marlin's blocks meet every 1/`segments_per_second` s with a small velocity jump, so
/// nearly every instant lies in a corner's window; a jump Δv makes a spring drive ring
/// with a peak acceleration Δv·ω, so a corner whose jerk·ω is below the acceleration is
/// the acceleration's.
pub fn wanted(
    m: &MoveStats,
    hold_n: Option<f64>,
    ran: &Toolhead,
    motors: &Motors,
    earlier: Option<(Cause, f64, f64)>,
    rules: &Rules,
) -> Option<Over> {
    let tower = m.worst_use_tower();
    let w = m.worst[tower];
    let (first, ratio, scale) = if m.over_force() {
        let plateau = motors.available_force_n(0.0);
        let needed = w.force_n / TARGET;
        if w.available_n < plateau && needed < plateau && w.speed_mm_s > 0.0 {
            let s = speed_for_force(motors, needed, w.speed_mm_s);
            (Cause::Speed, w.ratio, s / w.speed_mm_s)
        } else if m.worst_phase[tower] == Phase::Corner
            && rules
                .jump_omega
                .is_none_or(|om| ran.scv_mm_s * om >= ran.accel_mm_s2)
        {
            (Cause::Corner, w.ratio, TARGET / w.ratio)
        } else {
            // Accelerating, braking, or cruising or at rest after it while the drive
            // still rings.
            (Cause::Accel, w.ratio, TARGET / w.ratio)
        }
    } else {
        // An arm pulls harder than its magnets hold: the pull is affine in the acceleration.
        let hold = hold_n?;
        let pull = m.peak_tension_n.iter().copied().fold(0.0, f64::max);
        if pull <= hold {
            return None;
        }
        let r = pull / hold;
        (Cause::Accel, r, TARGET / r)
    };
    let order = match first {
        Cause::Corner => [Cause::Corner, Cause::Accel, Cause::Speed],
        Cause::Accel => [Cause::Accel, Cause::Speed, Cause::Corner],
        Cause::Speed => [Cause::Speed, Cause::Accel, Cause::Corner],
    };
    // The limit lowered in the earlier pass, unless lowering it did not help: then the
    // next one; and never one at its floor. The speed stays the cause while the curve
    // is (a motor past its top speed gives no force: the ratio says nothing then).
    let start = match earlier {
        Some((c, x1, r1)) if c.value(ran) < x1 => {
            let i = order.iter().position(|&o| o == c).unwrap_or(0);
            if ratio < r1 || (c == first && c == Cause::Speed) {
                i
            } else {
                i + 1
            }
        }
        _ => 0,
    };
    let cause = (start..start + 3)
        .map(|i| order[i % 3])
        .find(|c| c.value(ran) > c.value(&rules.floor))?;
    let scale = match cause {
        c if c == first => scale,
        // The speed's own force terms go as its square (eq. 14's C(q, q̇)q̇).
        Cause::Speed => (TARGET / ratio).sqrt(),
        _ => TARGET / ratio,
    };
    let x = cause.value(ran);
    let mut value = x * scale;
    if let Some((c, x1, r1)) = earlier
        && c == cause
        && c != Cause::Speed
        && x1 > x
        && r1 > ratio
    {
        // The ratio is affine in the limit (not in the speed: the motor's curve is not):
        // the line through both passes.
        // Guarded: at most twice as far as the plain ratio goes (the worst instant may
        // have moved between the passes).
        let slope = (r1 - ratio) / (x1 - x);
        value = (x - (ratio - TARGET) / slope).max(0.5 * value);
    }
    Some(Over {
        cause,
        ran: x,
        wanted: value.clamp(0.25 * x, MIN_STEP * x),
        ratio,
    })
}

/// Each flagged move's last cause, limit and ratio, for the next pass.
type History = BTreeMap<u64, (Cause, f64, f64)>;

/// One flagged move's caps, kept between passes (`fix`).
#[derive(Clone, Debug)]
struct Anchor {
    caps: Toolhead,
    spread: usize,
    /// The move lines before and after it, nearest first.
    before: Vec<u64>,
    after: Vec<u64>,
}

impl Anchor {
    /// Its caps' range: `spread` moves on either side (as many as there are).
    fn range(&self, line: u64) -> (u64, u64, Toolhead) {
        let reach = |v: &[u64]| match self.spread.min(v.len()) {
            0 => line,
            n => v[n - 1],
        };
        (reach(&self.before), reach(&self.after), self.caps)
    }
}

/// A move over in a pass: its line, why, and the move lines before and after it (nearest
/// first).
struct Flagged {
    line: u64,
    over: Over,
    before: Vec<u64>,
    after: Vec<u64>,
}

/// What one pass found.
struct Pass {
    report: Report,
    over: Vec<Flagged>,
    /// Moves over that no limit left above its floor can help.
    stuck: Vec<u64>,
    file_peak: Held,
    added: Vec<Added>,
}

/// A file whose limits passed: the caps, the limit commands they take, the print time.
#[derive(Clone, Debug)]
pub struct Passed {
    /// The caps over the whole file (the recommendation), unlimited for `fix`.
    pub global: Toolhead,
    /// The limit commands the caps take, before their moves.
    pub added: Vec<Added>,
    pub print_time_s: f64,
    /// The largest limits the file itself set (the profile's where it set none).
    pub file_peak: Held,
    /// The passes it took.
    pub passes: usize,
    /// The print time of the first pass (the file as it is, when it did not pass), s.
    pub first_print_time_s: f64,
}

/// Plans and checks `path` with caps; `fresh`: the file as it was before any `fix` (our
/// commands left out).
fn pass(
    path: &Path,
    machine: &Machine,
    segments: &Segments,
    global: Toolhead,
    history: &History,
    rules: &Rules,
) -> anyhow::Result<Pass> {
    let file = File::open(path).with_context(|| format!("cannot open {}", path.display()))?;
    let input = BufReader::with_capacity(1 << 16, WithoutOurs::new(file));
    let mut edit = CapEdit::new(machine, segments, global, true);
    let in_flight = edit.in_flight.clone();
    let name = path.display().to_string();
    let mut report = Report::new(&name, &machine.name, machine.motors.max_force_n, false);
    report.arm_magnet_hold_n = machine.geometry.arm_magnet_hold_n;
    let mut over = Vec::new();
    let mut stuck = Vec::new();
    let mut first_error: Option<Diagnostic> = None;
    // The last move lines, and the flagged moves still collecting the lines after them.
    let mut recent: VecDeque<u64> = VecDeque::new();
    let mut collecting: Vec<usize> = Vec::new();
    // Marlin's speed limit is the towers' (M203): a move ran no faster than its carriages.
    let tower_speed = matches!(machine.firmware, crate::machine::Firmware::Marlin(_));
    let totals = crate::analysis::run_edited(
        input,
        machine,
        (),
        &mut |e, out| edit.edit(e, out),
        |r| {
            let line = r.stats.line;
            let ran = limits_of(&in_flight, line).map(|mut t| {
                if tower_speed {
                    t.velocity_mm_s = t.velocity_mm_s.min(r.stats.peak_speed_mm_s);
                }
                t
            });
            for &i in &collecting {
                let f: &mut Flagged = &mut over[i];
                f.after.push(line);
            }
            collecting.retain(|&i| over[i].after.len() < MAX_SPREAD);
            let before = report.summary.violations;
            report.add_move(&r.stats);
            if report.summary.violations > before
                && r.stats.checks.problem.is_none()
                && let Some(ran) = ran
            {
                let earlier = history.get(&line).copied();
                let hold = machine.geometry.arm_magnet_hold_n;
                if let Some(o) = wanted(&r.stats, hold, &ran, &machine.motors, earlier, rules) {
                    collecting.push(over.len());
                    over.push(Flagged {
                        line,
                        over: o,
                        before: recent.iter().rev().copied().collect(),
                        after: Vec::new(),
                    });
                } else {
                    stuck.push(line);
                }
            }
            recent.push_back(line);
            if recent.len() > MAX_SPREAD {
                recent.pop_front();
            }
        },
        |d| {
            if d.severity == Severity::Error {
                first_error.get_or_insert(d);
            }
        },
    )
    .with_context(|| format!("cannot read {name}"))?;
    if let Some(d) = first_error {
        anyhow::bail!(
            "{name}:{}:{}: {} (fix the input errors first)",
            d.line,
            d.column,
            d.message
        );
    }
    report.summary.lines = totals.read.lines;
    report.summary.print_time_s = totals.print_time_s;
    Ok(Pass {
        report,
        over,
        stuck,
        file_peak: edit.file_peak,
        added: edit.added.take().unwrap_or_default(),
    })
}

/// No limits make the file pass: the move that stays over, and why.
#[derive(Debug, thiserror::Error)]
#[error("line {line} cannot be made to pass ({why}){what}")]
pub struct Unfixable {
    pub line: u64,
    why: &'static str,
    what: String,
}

fn cannot(report: &Report, line: u64, why: &'static str) -> anyhow::Error {
    let v = report.violations.iter().find(|v| v.line == line);
    let what = v.map_or_else(String::new, |v| format!(": {}", v.message));
    Unfixable { line, why, what }.into()
}

/// Searches limits under which `path` passes: one set of caps over the whole file
/// (`local` false, the recommendation) or caps over the ranges of moves that need them
/// (`fix`). Errors when a move cannot pass at any limit (unreachable, out of the disc, or
/// still over at [`FLOOR`]).
pub fn search(path: &Path, machine: &Machine, local: bool) -> anyhow::Result<Passed> {
    search_from(
        path,
        machine,
        local,
        Toolhead::UNLIMITED,
        &Rules::of(machine),
    )
}

/// [`search`] from the caps `global` over the whole file, lowering limits only down to
/// `rules.floor`.
pub fn search_from(
    path: &Path,
    machine: &Machine,
    local: bool,
    mut global: Toolhead,
    rules: &Rules,
) -> anyhow::Result<Passed> {
    let mut anchors: BTreeMap<u64, Anchor> = BTreeMap::new();
    let mut history = History::new();
    let mut first_print_time_s = None;
    for passes in 1..=rules.max_passes {
        let segs = segments(anchors.iter().map(|(&l, a)| a.range(l)));
        let p = pass(path, machine, &segs, global, &history, rules)?;
        let first = *first_print_time_s.get_or_insert(p.report.summary.print_time_s);
        if p.report.summary.errors > 0 {
            anyhow::bail!(
                "{} has input errors (line {}): fix them first",
                path.display(),
                p.report
                    .diagnostics
                    .iter()
                    .find(|d| d.severity == "error")
                    .map_or(0, |d| d.line)
            );
        }
        if let Some(v) = p.report.violations.iter().find(|v| {
            v.available_force_n.is_none() && v.kind != crate::report::ViolationKind::ArmTension
        }) {
            return Err(cannot(
                &p.report,
                v.line,
                "no limit changes where a move goes",
            ));
        }
        if p.report.summary.violations == 0 {
            return Ok(Passed {
                global,
                added: p.added,
                print_time_s: p.report.summary.print_time_s,
                file_peak: p.file_peak,
                passes,
                first_print_time_s: first,
            });
        }
        if let Some(&line) = p.stuck.first() {
            return Err(cannot(
                &p.report,
                line,
                "still over at the lowest limits tried",
            ));
        }
        if p.over.is_empty() {
            anyhow::bail!(
                "{}: moves over the limits that no limit explains",
                path.display()
            );
        }
        for Flagged {
            line,
            over: o,
            before,
            after,
        } in p.over
        {
            let value = o.cause.round_down(o.wanted);
            let earlier = history.insert(line, (o.cause, o.ran, o.ratio));
            if value >= o.ran {
                return Err(cannot(
                    &p.report,
                    line,
                    "still over at the lowest limits tried",
                ));
            }
            if local {
                let a = anchors.entry(line).or_insert_with(|| Anchor {
                    caps: Toolhead::UNLIMITED,
                    spread: 0,
                    before,
                    after,
                });
                // Lowering the move's own limit did not bring it half way: the cause is
                // in its neighbours too (the drive rings on, the lookahead brakes early).
                if let Some((c, _, r1)) = earlier
                    && c == o.cause
                    && c != Cause::Speed
                    && o.ratio > r1 - 0.5 * (r1 - TARGET)
                {
                    a.spread = (a.spread + 1).min(MAX_SPREAD);
                }
                let c = o.cause.value(&a.caps).min(value);
                o.cause.set(&mut a.caps, c);
            } else {
                let c = o.cause.value(&global).min(value);
                o.cause.set(&mut global, c);
            }
        }
    }
    anyhow::bail!(
        "{}: no limits found that pass after {} passes",
        path.display(),
        rules.max_passes
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::machine::Machine;
    use crate::machine::test_support::KOSSEL_YAML;
    use crate::report::RunForces;

    /// A move whose worst sample asked `force` of tower A at carriage speed `speed`, in
    /// `phase`, the motors giving what `motors` gives there.
    fn flagged(motors: &Motors, force: f64, speed: f64, phase: Phase) -> MoveStats {
        let mut m = MoveStats::new(7);
        let avail = motors.available_force_n(speed);
        m.add_run(&RunForces {
            t_s: &[1.0],
            phase: &[phase],
            force_n: [&[force], &[1.0], &[1.0]],
            available_n: [&[avail], &[avail], &[avail]],
            speed_mm_s: [&[speed], &[speed], &[speed]],
            tension_n: [&[0.0], &[0.0], &[0.0]],
        });
        m
    }

    const NO_MARLIN: Rules = Rules {
        floor: FLOOR,
        jump_omega: None,
        max_passes: MAX_PASSES,
    };

    const RAN: Toolhead = Toolhead {
        accel_mm_s2: 4000.0,
        scv_mm_s: 8.0,
        velocity_mm_s: 200.0,
    };

    /// The kossel of the unit tests with the torque form of the motor (a curve).
    fn curved() -> Motors {
        let yaml = KOSSEL_YAML.replace(
            "motors: {max_force_n: 30}",
            "motors: {holding_torque_nm: 0.4, rated_current_a: 1.7, run_current_a: 1.0, \
             resistance_ohm: 1.5, inductance_mh: 2.8, supply_voltage_v: 12, pulley_teeth: 20, safety_factor: 1.0}",
        );
        Machine::from_yaml_str(&yaml, "test").unwrap().motors
    }

    #[test]
    fn over_the_curve_lowers_the_velocity_to_the_speed_that_gives_the_force() {
        let motors = curved();
        let c = motors.curve.as_ref().unwrap();
        // Past the knee, asking 60 % of the plateau: the curve gives it at a lower speed.
        let speed = 0.5 * (c.knee_speed_mm_s() + c.zero_force_speed_mm_s());
        let force = 0.6 * c.plateau_force_n();
        assert!(motors.available_force_n(speed) < force);
        let o = wanted(
            &flagged(&motors, force, speed, Phase::Accel),
            None,
            &RAN,
            &motors,
            None,
            &NO_MARLIN,
        )
        .unwrap();
        assert_eq!((o.cause, o.ran), (Cause::Speed, 200.0));
        // The velocity scales as the speed: at the new speed the motor gives force/TARGET.
        let s = speed * o.wanted / 200.0;
        assert!((motors.available_force_n(s) - force / TARGET).abs() < 1e-6 * force);
    }

    #[test]
    fn corners_lower_the_scv_and_accelerations_the_accel_by_the_ratio() {
        let motors = Machine::from_yaml_str(KOSSEL_YAML, "t").unwrap().motors;
        let corner = flagged(&motors, 45.0, 10.0, Phase::Corner);
        let o = wanted(&corner, None, &RAN, &motors, None, &NO_MARLIN).unwrap();
        assert_eq!(o.cause, Cause::Corner);
        assert!((o.ratio - 1.5).abs() < 1e-12);
        assert!((o.wanted - 8.0 * TARGET / 1.5).abs() < 1e-12);
        let accel = flagged(&motors, 36.0, 10.0, Phase::Decel);
        let o = wanted(&accel, None, &RAN, &motors, None, &NO_MARLIN).unwrap();
        assert_eq!(o.cause, Cause::Accel);
        assert!((o.wanted - 4000.0 * TARGET / 1.2).abs() < 1e-9);
        // The secant: at 5000 the ratio was 1.4, at 4000 it is 1.2: the affine law reaches
        // TARGET at 4000 − (1.2 − 0.97)/(0.2/1000) = 2850.
        let o = wanted(
            &accel,
            None,
            &RAN,
            &motors,
            Some((Cause::Accel, 5000.0, 1.4)),
            &NO_MARLIN,
        )
        .unwrap();
        assert!((o.wanted - 2850.0).abs() < 1e-9, "{o:?}");
        // Lowering the accel did not help: the velocity next.
        let o = wanted(
            &accel,
            None,
            &RAN,
            &motors,
            Some((Cause::Accel, 5000.0, 1.1)),
            &NO_MARLIN,
        )
        .unwrap();
        assert_eq!(o.cause, Cause::Speed);
        // A limit at its floor is not lowered further.
        let floor = Toolhead {
            scv_mm_s: FLOOR.scv_mm_s,
            ..RAN
        };
        assert_eq!(
            wanted(&corner, None, &floor, &motors, None, &NO_MARLIN)
                .unwrap()
                .cause,
            Cause::Accel
        );
        // Within the force: nothing to do.
        assert!(
            wanted(
                &flagged(&motors, 20.0, 10.0, Phase::Accel),
                None,
                &RAN,
                &motors,
                None,
                &NO_MARLIN
            )
            .is_none()
        );
    }

    #[test]
    fn a_marlin_corner_is_the_jerk_s_only_when_its_ringing_outweighs_the_acceleration() {
        let motors = Machine::from_yaml_str(KOSSEL_YAML, "t").unwrap().motors;
        let corner = flagged(&motors, 45.0, 10.0, Phase::Corner);
        // jerk 8 mm/s through a 60 Hz drive: 8 · 377 = 3016 mm/s² of ringing.
        let omega = std::f64::consts::TAU * 60.0;
        let cause = |accel: f64| {
            let ran = Toolhead {
                accel_mm_s2: accel,
                ..RAN
            };
            wanted(
                &corner,
                None,
                &ran,
                &motors,
                None,
                &Rules {
                    jump_omega: Some(omega),
                    ..NO_MARLIN
                },
            )
            .unwrap()
            .cause
        };
        assert_eq!(cause(3000.0), Cause::Corner);
        assert_eq!(cause(3100.0), Cause::Accel);
    }

    #[test]
    fn limits_round_down_to_round_figures_above_the_floor() {
        assert_eq!(Cause::Accel.round_down(2187.9), 2180.0);
        assert_eq!(Cause::Corner.round_down(3.79), 3.7);
        assert_eq!(Cause::Speed.round_down(149.99), 149.0);
        assert_eq!(Cause::Speed.round_down(1.0), FLOOR.velocity_mm_s);
    }
}
