//! The modal interpreter: parsed lines in, [`Event`]s out, in line order.
//!
//! Modal state as Klipper's `gcode_move` keeps it: absolute/relative XYZ (G90/G91), E
//! relative when either G91 or M83 is in force, G92 offsets per axis (also E), units
//! (G20/G21), the feed (F, mm/min, default 1500 = Klipper's 25 mm/s), the M220 and M221
//! factors. Positions in events are machine positions in the bed frame: G92 shifts the
//! G-code coordinates, not the nozzle. Before any G28 the nozzle is at the home position,
//! unless a G92 before the first G28 or move says where it is.
//!
//! In Marlin's dialect ([`Dialect`]) the same state follows Marlin 2.1.x (gcode.cpp,
//! motion.cpp): one relative bit per axis, so G90 makes E absolute again (cancelling M83),
//! M82 after G91 makes E absolute, G91 makes E relative; F ≤ 0 is ignored; a bare G92 does
//! nothing and G28 clears the G92 offsets; the feed before the first F is 4000 mm/min;
//! M204 P/R/T, M201, M203, M205 and M665 are Marlin's settings ([`Event::Marlin`]); targets
//! are clamped by the soft endstops (`apply_motion_limits`: beyond the printable radius x,
//! y *and z* are scaled), and a target out of reach while unhomed (after M665) or with
//! soft endstops off (M211 S0) drops the move; arcs are `plan_arc`'s ([`super::arc::MarlinChords`], `arcs.rs`),
//! relative and R-form ones included. Klipper's extended commands are noted once and ignored.

mod arcs;
mod klipper_commands;
mod retract;
mod soft_endstops;

pub use klipper_commands::M204_P_OR_T_IGNORED;
pub use retract::Retraction;

use super::arc::Plane;
use super::dialect::{self, Dialect, FirmwareKind};
use super::parse::{Command, ParsedLine};
use super::reader::BUFFER_BYTES;
use super::{ArcChord, Diagnostic, Event, LimitChange, MarlinChange, Move, Severity, marlin};
use crate::path::{Path, Vec3};
use klipper_commands::{m204, set_input_shaper, set_velocity_limit};

/// Feed before the first F, mm/min (Klipper's default speed, 25 mm/s).
pub const DEFAULT_FEED_MM_MIN: f64 = 1500.0;

/// Marlin's feed before the first F, mm/min (`DEFAULT_FEEDRATE_MM_M`).
const MARLIN_DEFAULT_FEED_MM_MIN: f64 = crate::machine::defaults::MARLIN_DEFAULT_FEEDRATE_MM_MIN;

/// Counts gathered while reading.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ReadStats {
    pub lines: u64,
    pub bytes: u64,
    /// `Event::Move`s sent (each chord of an arc is one).
    pub moves: u64,
    /// G2/G3 commands run.
    pub arcs: u64,
    pub stops: u64,
    pub limit_changes: u64,
    /// Commands passed through without interpretation (temperatures, fans, macros, …).
    pub unknown_commands: u64,
    pub warnings: u64,
    pub errors: u64,
    /// Lines longer than the reader's buffer: copied, not interpreted.
    pub truncated_lines: u64,
}

/// The modal state between lines.
#[derive(Clone, Debug)]
pub struct Interpreter {
    home: Vec3,
    /// Machine position of the nozzle, mm.
    pos: Vec3,
    /// G92: machine = G-code coordinate + offset.
    offset: Vec3,
    /// Machine E position, mm of filament.
    e_pos: f64,
    e_offset: f64,
    absolute: bool,
    absolute_e: bool,
    /// mm per G-code length unit: 1 (G21) or 25.4 (G20).
    unit_mm: f64,
    feed_mm_min: f64,
    speed_factor: f64,
    plane: Plane,
    dialect: Dialect,
    retraction: Retraction,
    retracted: bool,
    /// M221: filament per E unit (Klipper's `extrude_factor`).
    extrude_factor: f64,
    /// Where the machine is is known: after the first G28 or move. Before, a G92 says
    /// where the nozzle is instead of shifting coordinates.
    placed: bool,
    /// Marlin: the axes are homed (G28; M665 un-homes): the soft endstops act only then.
    homed: bool,
    /// Marlin: M211 S0/S1.
    soft_endstops_on: bool,
    /// Marlin: M220 B.
    saved_speed_factor: f64,
    /// A Klipper command has been noted as ignored by Marlin (once per file).
    klipper_noted: bool,
    /// A slicer's flavour line has been read (only the first counts).
    flavour_read: bool,
    stats: ReadStats,
}

const AXES: [u8; 3] = [b'X', b'Y', b'Z'];

impl Interpreter {
    /// A fresh interpreter with the nozzle at `home_mm`, G90, M82, G21, G17, reading as
    /// `dialect`'s firmware does (a bare [`ArcRules`] is Klipper's dialect).
    pub fn new(home_mm: Vec3, dialect: impl Into<Dialect>) -> Self {
        let dialect = dialect.into();
        Interpreter {
            home: home_mm,
            pos: home_mm,
            offset: Vec3::zeros(),
            e_pos: 0.0,
            e_offset: 0.0,
            absolute: true,
            absolute_e: true,
            unit_mm: 1.0,
            feed_mm_min: match dialect.firmware {
                FirmwareKind::Klipper => DEFAULT_FEED_MM_MIN,
                FirmwareKind::Marlin => MARLIN_DEFAULT_FEED_MM_MIN,
            },
            speed_factor: 1.0,
            plane: Plane::Xy,
            dialect,
            retraction: Retraction::default(),
            retracted: false,
            extrude_factor: 1.0,
            placed: false,
            homed: true,
            soft_endstops_on: true,
            saved_speed_factor: 1.0,
            klipper_noted: false,
            flavour_read: false,
            stats: ReadStats::default(),
        }
    }

    /// Uses these firmware-retraction settings from now on.
    pub fn set_retraction(&mut self, r: Retraction) {
        self.retraction = r;
    }

    /// Machine position of the nozzle after the lines so far, mm.
    pub fn position_mm(&self) -> Vec3 {
        self.pos
    }

    pub fn stats(&self) -> ReadStats {
        self.stats
    }

    fn feed_mm_s(&self) -> f64 {
        self.feed_mm_min / 60.0 * self.speed_factor
    }

    /// Interprets one line (its bytes with or without terminator; `truncated` when the
    /// reader cut an overlong line).
    pub fn line(
        &mut self,
        number: u64,
        bytes: &[u8],
        truncated: bool,
        on_event: &mut impl FnMut(Event),
        on_diag: &mut impl FnMut(Diagnostic),
    ) {
        self.stats.lines += 1;
        let mut d = Diags {
            line: number,
            on_diag,
            warnings: 0,
            errors: 0,
        };
        self.line_inner(bytes, truncated, on_event, &mut d);
        self.stats.warnings += d.warnings;
        self.stats.errors += d.errors;
    }

    fn line_inner(
        &mut self,
        bytes: &[u8],
        truncated: bool,
        on_event: &mut impl FnMut(Event),
        d: &mut Diags<impl FnMut(Diagnostic)>,
    ) {
        if truncated {
            self.stats.truncated_lines += 1;
            d.warn(
                BUFFER_BYTES as u32 + 1,
                format!(
                    "line longer than {} KiB: copied through, not interpreted",
                    BUFFER_BYTES / 1024
                ),
            );
            return;
        }
        if !self.flavour_read && bytes.first() == Some(&b';') {
            self.flavour(bytes, d);
        }
        let mut p = ParsedLine::blank(bytes);
        p.parse();
        for diag in p.diags() {
            d.push(diag.column, diag.severity, diag.message());
        }
        if p.has_error() {
            return;
        }
        let mut ev = Events {
            line: d.line,
            on_event,
        };
        self.command(&p, &mut ev, d);
    }

    fn marlin(&self) -> bool {
        self.dialect.firmware == FirmwareKind::Marlin
    }

    /// A slicer's flavour comment (`;FLAVOR:Marlin`, `; gcode_flavor = klipper`): one
    /// warning when it names another firmware than the profile's.
    fn flavour(&mut self, bytes: &[u8], d: &mut Diags<impl FnMut(Diagnostic)>) {
        let Some(flavour) = dialect::slicer_flavour(super::parse::strip_terminator(bytes)) else {
            return;
        };
        self.flavour_read = true;
        let ours = self.dialect.firmware;
        if dialect::flavour_firmware(flavour) == Some(ours) {
            return;
        }
        let text = String::from_utf8_lossy(flavour);
        let what = match ours {
            FirmwareKind::Klipper => {
                "the moves are planned as Klipper runs them (Klipper ignores M201, M203 and \
                 M205, and reads M204 its own way)"
            }
            FirmwareKind::Marlin => {
                "the moves are planned as Marlin runs them (Marlin ignores Klipper's extended \
                 commands)"
            }
        };
        d.warn(
            1,
            format!(
                "the file was sliced for the `{text}` flavour, but the machine profile's \
                 firmware is {}: {what}; check the slicer's G-code flavour or the profile's \
                 `firmware`",
                ours.name()
            ),
        );
    }

    fn command(
        &mut self,
        p: &ParsedLine,
        ev: &mut Events<impl FnMut(Event)>,
        d: &mut Diags<impl FnMut(Diagnostic)>,
    ) {
        let (letter, number, column) = match p.command {
            Command::None => return,
            Command::Code {
                letter,
                number,
                subcode: None,
                column,
            } => (letter, number, column),
            Command::Code { .. } => {
                self.stats.unknown_commands += 1;
                return;
            }
            Command::Extended { name, .. } => {
                if self.marlin() {
                    self.stats.unknown_commands += 1;
                    if !self.klipper_noted {
                        self.klipper_noted = true;
                        d.warn(
                            1,
                            format!(
                                "{} is Klipper's: Marlin ignores it (and the other extended \
                                 commands of this file, not noted again)",
                                String::from_utf8_lossy(name)
                            ),
                        );
                    }
                } else if name.eq_ignore_ascii_case(b"SET_VELOCITY_LIMIT") {
                    let change = set_velocity_limit(p, d);
                    self.limits(change, ev);
                } else if name.eq_ignore_ascii_case(b"SET_INPUT_SHAPER") {
                    // input_shaper.py flushes the toolhead (flush_step_generation) first.
                    let change = set_input_shaper(p, d);
                    self.stop(0.0, ev);
                    (ev.on_event)(Event::Shaper {
                        line: ev.line,
                        change,
                    });
                } else if name.eq_ignore_ascii_case(b"TEMPERATURE_WAIT") {
                    self.stop(0.0, ev);
                } else if name.eq_ignore_ascii_case(b"SET_RETRACTION") {
                    self.set_retraction_params(p, d);
                } else {
                    self.stats.unknown_commands += 1;
                }
                return;
            }
        };
        let marlin = self.marlin();
        match (letter, number) {
            (b'G', 0 | 1) => self.linear(p, ev, d),
            (b'G', 2 | 3) if marlin => self.marlin_arc(p, number == 2, column, ev, d),
            (b'G', 2 | 3) => self.arc(p, number == 2, column, ev, d),
            (b'G', 4) => {
                let dwell_s = match (p.word(b'S'), p.word(b'P')) {
                    (Some(s), _) => s.value.map(|v| (v, s.column)),
                    (None, Some(w)) => w.value.map(|v| (v / 1000.0, w.column)),
                    (None, None) => None,
                };
                let dwell_s = match dwell_s {
                    Some((v, _)) if v >= 0.0 => v,
                    Some((_, c)) => {
                        d.warn(c, "negative dwell; no dwell".into());
                        0.0
                    }
                    None => 0.0,
                };
                self.stop(dwell_s, ev);
            }
            (b'G', 10) if p.word(b'L').is_none() && p.word(b'P').is_none() => {
                if !self.retracted {
                    self.retracted = true;
                    let (len, v) = (self.retraction.length_mm, self.retraction.speed_mm_s);
                    self.extrude_only(-len, v * self.speed_factor, ev);
                }
            }
            (b'G', 11) => {
                if self.retracted {
                    self.retracted = false;
                    let r = self.retraction;
                    let e = r.length_mm + r.unretract_extra_mm;
                    self.extrude_only(e, r.unretract_speed_mm_s * self.speed_factor, ev);
                }
            }
            // Marlin's arcs are in XY (CNC_WORKSPACE_PLANES is off by default).
            (b'G', 17..=19) if marlin => self.stats.unknown_commands += 1,
            (b'G', 17) => self.plane = Plane::Xy,
            (b'G', 18) => self.plane = Plane::Xz,
            (b'G', 19) => self.plane = Plane::Yz,
            (b'G', 20) => self.unit_mm = 25.4,
            (b'G', 21) => self.unit_mm = 1.0,
            (b'G', 28) => {
                self.stop(0.0, ev);
                self.pos = self.home;
                self.placed = true;
                if marlin {
                    // G28 clears the homed axes' position_shift; the machine is homed.
                    self.offset = Vec3::zeros();
                    self.homed = true;
                }
            }
            (b'G', 90) => {
                self.absolute = true;
                if marlin {
                    // Marlin clears every relative bit, E's (set by M83) too.
                    self.absolute_e = true;
                }
            }
            (b'G', 91) => {
                self.absolute = false;
                if marlin {
                    self.absolute_e = false;
                }
            }
            (b'G', 92) => self.set_position(p),
            (b'M', 82) => self.absolute_e = true,
            (b'M', 83) => self.absolute_e = false,
            (b'M', 201 | 203) if marlin => {
                let change = marlin::axis_limits(p, number == 203, self.unit_mm, d);
                self.marlin_change(change, ev);
            }
            (b'M', 204) if marlin => {
                let change = marlin::m204(p, self.unit_mm, d);
                self.marlin_change(change, ev);
            }
            (b'M', 205) if marlin => {
                let change = marlin::m205(p, self.unit_mm, d);
                self.marlin_change(change, ev);
            }
            (b'M', 665) if marlin => {
                let change = marlin::m665(p, self.unit_mm, self.dialect.delta.as_ref(), d);
                self.marlin_change(Some(MarlinChange::Delta(change)), ev);
                if self.homed {
                    self.homed = false;
                    d.warn(
                        column,
                        "M665 un-homes Marlin: until the next G28 moves are not clamped to the \
                         printable radius, a move out of it is dropped, and with \
                         NO_MOTION_BEFORE_HOMING (the FLSUN Q5's configuration) every move is \
                         refused"
                            .into(),
                    );
                }
            }
            (b'M', 211) if marlin => {
                if let Some(s) = p.value(b'S') {
                    self.soft_endstops_on = s != 0.0;
                }
            }
            (b'M', 204) => {
                let change = m204(p, column, d);
                self.limits(change, ev);
            }
            (b'M', 207 | 208) => self.m207_m208(p, number == 207),
            (b'M', 220) if marlin => {
                // Marlin: B backs the factor up, R restores it, S sets it; alone it reports.
                if p.word(b'B').is_some() {
                    self.saved_speed_factor = self.speed_factor;
                }
                if p.word(b'R').is_some() {
                    self.speed_factor = self.saved_speed_factor;
                }
                if let Some(w) = p.word(b'S') {
                    match w.value {
                        Some(v) if v > 0.0 => self.speed_factor = v / 100.0,
                        _ => d.error(w.column, "M220 S must be a positive percentage".into()),
                    }
                }
            }
            (b'M', 220) => match p.word(b'S') {
                None => self.speed_factor = 1.0,
                Some(w) => match w.value {
                    Some(v) if v > 0.0 => self.speed_factor = v / 100.0,
                    _ => d.error(w.column, "M220 S must be a positive percentage".into()),
                },
            },
            // M400, and the heater waits: Klipper's wait_for_temperature asks the toolhead
            // for its last move time, which flushes the lookahead. (Marlin's M109/M190 do not
            // wait for the planner, but no line is read until the heater is ready: the queue
            // runs empty, which is the same.)
            (b'M', 400 | 109 | 190) => self.stop(0.0, ev),
            (b'M', 221) => match p.word(b'S') {
                None if marlin => {}
                None => self.extrude_factor = 1.0,
                Some(w) => match w.value {
                    Some(v) if v > 0.0 => self.extrude_factor = v / 100.0,
                    _ => d.error(w.column, "M221 S must be a positive percentage".into()),
                },
            },
            _ => self.stats.unknown_commands += 1,
        }
    }

    fn marlin_change(&mut self, change: Option<MarlinChange>, ev: &mut Events<impl FnMut(Event)>) {
        if let Some(change) = change {
            self.stats.limit_changes += 1;
            (ev.on_event)(Event::Marlin {
                line: ev.line,
                change,
            });
        }
    }

    fn stop(&mut self, dwell_s: f64, ev: &mut Events<impl FnMut(Event)>) {
        self.stats.stops += 1;
        (ev.on_event)(Event::Stop {
            line: ev.line,
            dwell_s,
        });
    }

    fn limits(&mut self, change: LimitChange, ev: &mut Events<impl FnMut(Event)>) {
        if change != LimitChange::default() {
            self.stats.limit_changes += 1;
            (ev.on_event)(Event::Limits {
                line: ev.line,
                change,
            });
        }
    }

    fn send_move(
        &mut self,
        path: Path,
        e_mm: f64,
        feed_mm_s: f64,
        ev: &mut Events<impl FnMut(Event)>,
    ) {
        self.send_chord(path, e_mm, feed_mm_s, None, ev);
    }

    fn send_chord(
        &mut self,
        path: Path,
        e_mm: f64,
        feed_mm_s: f64,
        arc: Option<ArcChord>,
        ev: &mut Events<impl FnMut(Event)>,
    ) {
        self.stats.moves += 1;
        self.placed = true;
        (ev.on_event)(Event::Move(Move {
            line: ev.line,
            path,
            e_mm,
            feed_mm_s,
            offset_mm: self.offset,
            arc,
        }));
    }

    fn extrude_only(&mut self, e_mm: f64, feed_mm_s: f64, ev: &mut Events<impl FnMut(Event)>) {
        if e_mm != 0.0 {
            self.e_pos += e_mm;
            self.send_move(Path::line(self.pos, self.pos), e_mm, feed_mm_s, ev);
        }
    }

    /// Applies an F word: positive F sets the feed, anything else is an error and the
    /// previous feed stays.
    #[inline(always)]
    fn feed(&mut self, p: &ParsedLine, d: &mut Diags<impl FnMut(Diagnostic)>) {
        if let Some(w) = p.word(b'F') {
            match w.value {
                Some(f) if f > 0.0 => self.feed_mm_min = f * self.unit_mm,
                _ => self.bad_feed(w.column, d),
            }
        }
    }

    /// The diagnostic of an F that is not a positive speed.
    #[cold]
    #[inline(never)]
    fn bad_feed(&self, column: u32, d: &mut Diags<impl FnMut(Diagnostic)>) {
        if self.marlin() {
            d.warn(
                column,
                "F must be a positive speed: Marlin ignores it and keeps the previous feed".into(),
            );
        } else {
            d.error(
                column,
                "F must be a positive speed (Klipper stops on it); the previous feed is kept"
                    .into(),
            );
        }
    }

    /// Target machine position of a move's X, Y, Z words. Inlined, as are [`Self::feed`] and
    /// [`Self::extrusion`], their diagnostics out of line ([`no_value`], [`Self::bad_feed`]):
    /// called, the three were 0.66 % of an unshaped run's instructions.
    #[inline(always)]
    fn target(&self, p: &ParsedLine, d: &mut Diags<impl FnMut(Diagnostic)>) -> Vec3 {
        let mut t = self.pos;
        for (i, &a) in AXES.iter().enumerate() {
            if let Some(w) = p.word(a) {
                match w.value {
                    Some(v) if self.absolute => t[i] = v * self.unit_mm + self.offset[i],
                    Some(v) => t[i] = self.pos[i] + v * self.unit_mm,
                    None => no_value(d, w.column, a),
                }
            }
        }
        t
    }

    /// Filament of a move's E word, mm (0 without one); advances the E position.
    #[inline(always)]
    fn extrusion(&mut self, p: &ParsedLine, d: &mut Diags<impl FnMut(Diagnostic)>) -> f64 {
        let Some(w) = p.word(b'E') else { return 0.0 };
        let Some(v) = w.value else {
            no_value(d, w.column, b'E');
            return 0.0;
        };
        let v = v * self.unit_mm;
        // Klipper: E is relative under G91 or M83. Marlin: E has its own relative bit, which
        // G90/G91 and M82/M83 set, the last one winning.
        let absolute = self.absolute_e && (self.absolute || self.marlin());
        let e = if absolute {
            v + self.e_offset - self.e_pos
        } else {
            v
        };
        self.e_pos += e;
        e * self.extrude_factor
    }

    fn linear(
        &mut self,
        p: &ParsedLine,
        ev: &mut Events<impl FnMut(Event)>,
        d: &mut Diags<impl FnMut(Diagnostic)>,
    ) {
        self.feed(p, d);
        let target = self.target(p, d);
        let e_before = self.e_pos;
        let e = self.extrusion(p, d);
        let target = if self.marlin() {
            let clamped = self.apply_motion_limits(target, d);
            // The segmenter refuses a target out of reach (the soft endstops off, or not
            // homed), E included; a move without XY change skips the check.
            let moves_xy = clamped.x != self.pos.x || clamped.y != self.pos.y;
            if moves_xy && !self.reachable(clamped) {
                d.warn(
                    1,
                    format!(
                        "the target ({:.3}, {:.3}) is outside Marlin's printable radius and the \
                         soft endstops do not act ({}): Marlin drops the move, E included",
                        clamped.x,
                        clamped.y,
                        if self.homed {
                            "M211 S0"
                        } else {
                            "not homed since M665"
                        }
                    ),
                );
                self.e_pos = e_before;
                return;
            }
            clamped
        } else {
            target
        };
        if target != self.pos || e != 0.0 {
            let feed = self.feed_mm_s();
            self.send_move(Path::line(self.pos, target), e, feed, ev);
            self.pos = target;
        }
    }

    /// G92: the current position gets the given G-code coordinates; without any axis,
    /// all of X, Y, Z, E become 0 (Klipper). Before the first G28 or move nothing says
    /// where the machine is: then the coordinates say where the nozzle is (a calibration
    /// snippet starting `G92 X0 Y0 Z20`), and stay the machine's.
    fn set_position(&mut self, p: &ParsedLine) {
        let given: [Option<f64>; 3] = AXES.map(|a| p.value(a).map(|v| v * self.unit_mm));
        let e = p.value(b'E').map(|v| v * self.unit_mm);
        // Klipper zeroes every axis on a bare G92; Marlin does nothing.
        let bare = given.iter().all(Option::is_none) && e.is_none() && !self.marlin();
        for (i, v) in given.into_iter().enumerate() {
            let v = if bare { Some(0.0) } else { v };
            if let Some(v) = v {
                if self.placed {
                    self.offset[i] = self.pos[i] - v;
                } else {
                    self.pos[i] = v;
                    self.offset[i] = 0.0;
                }
            }
        }
        if let Some(v) = e.or(bare.then_some(0.0)) {
            self.e_offset = self.e_pos - v;
        }
    }
}

/// The warning for an axis's (or E's) word without a value.
#[cold]
#[inline(never)]
fn no_value(d: &mut Diags<impl FnMut(Diagnostic)>, column: u32, axis: u8) {
    d.warn(
        column,
        format!("{} without a value is ignored", char::from(axis)),
    );
}

/// Where events of the current line go.
struct Events<'a, F> {
    line: u64,
    on_event: &'a mut F,
}

/// Where diagnostics of the current line go; counts them.
pub(super) struct Diags<'a, F> {
    line: u64,
    on_diag: &'a mut F,
    warnings: u64,
    errors: u64,
}

impl<F: FnMut(Diagnostic)> Diags<'_, F> {
    fn push(&mut self, column: u32, severity: Severity, message: String) {
        match severity {
            Severity::Warning => self.warnings += 1,
            Severity::Error => self.errors += 1,
        }
        (self.on_diag)(Diagnostic {
            line: self.line,
            column,
            severity,
            message,
        });
    }

    pub(super) fn warn(&mut self, column: u32, message: String) {
        self.push(column, Severity::Warning, message);
    }

    pub(super) fn error(&mut self, column: u32, message: String) {
        self.push(column, Severity::Error, message);
    }
}
