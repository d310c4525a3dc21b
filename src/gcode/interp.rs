//! The modal interpreter: parsed lines in, [`Event`]s out, in line order.
//!
//! Modal state as Klipper's `gcode_move` keeps it: absolute/relative XYZ (G90/G91), E
//! relative when either G91 or M83 is in force, G92 offsets per axis (also E), units
//! (G20/G21), the feed (F, mm/min, default 1500 = Klipper's 25 mm/s), the M220 and M221
//! factors. Positions in events are machine positions in the bed frame: G92 shifts the
//! G-code coordinates, not the nozzle. Before any G28 the nozzle is at the home position,
//! unless a G92 before the first G28 or move says where it is.

use super::arc::{ArcRules, Chords, Plane};
use super::parse::{Command, ParsedLine, param_f64, parse_line};
use super::reader::BUFFER_BYTES;
use super::{Diagnostic, Event, LimitChange, Move, Severity};
use crate::motion::shaper::{ShaperChange, ShaperType};
use crate::path::{Path, Vec3};

/// Feed before the first F, mm/min (Klipper's default speed, 25 mm/s).
pub const DEFAULT_FEED_MM_MIN: f64 = 1500.0;

/// Firmware retraction (G10/G11). Defaults are Marlin's (`RETRACT_LENGTH` 3 mm at
/// 45 mm/s, recover 0 mm extra at 8 mm/s), since Klipper's default length is 0;
/// `SET_RETRACTION` (Klipper) and `M207`/`M208` (Marlin) change them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Retraction {
    pub length_mm: f64,
    pub speed_mm_s: f64,
    pub unretract_extra_mm: f64,
    pub unretract_speed_mm_s: f64,
}

impl Default for Retraction {
    fn default() -> Self {
        Retraction {
            length_mm: 3.0,
            speed_mm_s: 45.0,
            unretract_extra_mm: 0.0,
            unretract_speed_mm_s: 8.0,
        }
    }
}

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
    arc_rules: ArcRules,
    retraction: Retraction,
    retracted: bool,
    /// M221: filament per E unit (Klipper's `extrude_factor`).
    extrude_factor: f64,
    /// Where the machine is is known: after the first G28 or move. Before, a G92 says
    /// where the nozzle is instead of shifting coordinates.
    placed: bool,
    stats: ReadStats,
}

const AXES: [u8; 3] = [b'X', b'Y', b'Z'];

impl Interpreter {
    /// A fresh interpreter with the nozzle at `home_mm`, G90, M82, G21, G17, arcs cut by
    /// `arc_rules`.
    pub fn new(home_mm: Vec3, arc_rules: ArcRules) -> Self {
        Interpreter {
            home: home_mm,
            pos: home_mm,
            offset: Vec3::zeros(),
            e_pos: 0.0,
            e_offset: 0.0,
            absolute: true,
            absolute_e: true,
            unit_mm: 1.0,
            feed_mm_min: DEFAULT_FEED_MM_MIN,
            speed_factor: 1.0,
            plane: Plane::Xy,
            arc_rules,
            retraction: Retraction::default(),
            retracted: false,
            extrude_factor: 1.0,
            placed: false,
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
        let p = parse_line(bytes);
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
                if name.eq_ignore_ascii_case(b"SET_VELOCITY_LIMIT") {
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
        match (letter, number) {
            (b'G', 0 | 1) => self.linear(p, ev, d),
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
            (b'G', 17) => self.plane = Plane::Xy,
            (b'G', 18) => self.plane = Plane::Xz,
            (b'G', 19) => self.plane = Plane::Yz,
            (b'G', 20) => self.unit_mm = 25.4,
            (b'G', 21) => self.unit_mm = 1.0,
            (b'G', 28) => {
                self.stop(0.0, ev);
                self.pos = self.home;
                self.placed = true;
            }
            (b'G', 90) => self.absolute = true,
            (b'G', 91) => self.absolute = false,
            (b'G', 92) => self.set_position(p),
            (b'M', 82) => self.absolute_e = true,
            (b'M', 83) => self.absolute_e = false,
            (b'M', 204) => {
                let change = m204(p, column, d);
                self.limits(change, ev);
            }
            (b'M', 207 | 208) => self.m207_m208(p, number == 207),
            (b'M', 220) => match p.word(b'S') {
                None => self.speed_factor = 1.0,
                Some(w) => match w.value {
                    Some(v) if v > 0.0 => self.speed_factor = v / 100.0,
                    _ => d.error(w.column, "M220 S must be a positive percentage".into()),
                },
            },
            // M400, and the heater waits: Klipper's wait_for_temperature asks the toolhead
            // for its last move time, which flushes the lookahead.
            (b'M', 400 | 109 | 190) => self.stop(0.0, ev),
            (b'M', 221) => match p.word(b'S') {
                None => self.extrude_factor = 1.0,
                Some(w) => match w.value {
                    Some(v) if v > 0.0 => self.extrude_factor = v / 100.0,
                    _ => d.error(w.column, "M221 S must be a positive percentage".into()),
                },
            },
            _ => self.stats.unknown_commands += 1,
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
        self.stats.moves += 1;
        self.placed = true;
        (ev.on_event)(Event::Move(Move {
            line: ev.line,
            path,
            e_mm,
            feed_mm_s,
            offset_mm: self.offset,
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
    fn feed(&mut self, p: &ParsedLine, d: &mut Diags<impl FnMut(Diagnostic)>) {
        if let Some(w) = p.word(b'F') {
            match w.value {
                Some(f) if f > 0.0 => self.feed_mm_min = f * self.unit_mm,
                _ => d.error(
                    w.column,
                    "F must be a positive speed (Klipper stops on it); the previous feed is kept"
                        .into(),
                ),
            }
        }
    }

    /// Target machine position of a move's X, Y, Z words.
    fn target(&self, p: &ParsedLine, d: &mut Diags<impl FnMut(Diagnostic)>) -> Vec3 {
        let mut t = self.pos;
        for (i, &a) in AXES.iter().enumerate() {
            if let Some(w) = p.word(a) {
                match w.value {
                    Some(v) if self.absolute => t[i] = v * self.unit_mm + self.offset[i],
                    Some(v) => t[i] = self.pos[i] + v * self.unit_mm,
                    None => d.warn(
                        w.column,
                        format!("{} without a value is ignored", char::from(a)),
                    ),
                }
            }
        }
        t
    }

    /// Filament of a move's E word, mm (0 without one); advances the E position.
    fn extrusion(&mut self, p: &ParsedLine, d: &mut Diags<impl FnMut(Diagnostic)>) -> f64 {
        let Some(w) = p.word(b'E') else { return 0.0 };
        let Some(v) = w.value else {
            d.warn(w.column, "E without a value is ignored".into());
            return 0.0;
        };
        let v = v * self.unit_mm;
        let e = if self.absolute && self.absolute_e {
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
        let e = self.extrusion(p, d);
        if target != self.pos || e != 0.0 {
            let feed = self.feed_mm_s();
            self.send_move(Path::line(self.pos, target), e, feed, ev);
            self.pos = target;
        }
    }

    /// G2/G3 as Klipper's gcode_arcs.py runs them: refused in relative mode and in R form,
    /// the centre offset from the plane's two letters (a zero offset refused), cut into
    /// chords ([`Chords::klipper`]), each an ordinary move with its share of E and the F.
    fn arc(
        &mut self,
        p: &ParsedLine,
        clockwise: bool,
        column: u32,
        ev: &mut Events<impl FnMut(Event)>,
        d: &mut Diags<impl FnMut(Diagnostic)>,
    ) {
        let ArcRules::Klipper { resolution_mm } = self.arc_rules;
        if !self.absolute {
            d.error(
                column,
                "G2/G3 does not support relative move mode (Klipper refuses it)".into(),
            );
            return;
        }
        if let Some(r) = p.word(b'R') {
            d.error(
                r.column,
                "G2/G3 does not support R moves (Klipper refuses the radius form; use I/J)".into(),
            );
            return;
        }
        let [l0, l1] = self.plane.offset_letters();
        let offset = [
            p.value(l0).unwrap_or(0.0) * self.unit_mm,
            p.value(l1).unwrap_or(0.0) * self.unit_mm,
        ];
        if offset == [0.0, 0.0] {
            d.error(
                column,
                format!(
                    "G2/G3 requires a centre offset {}{} (Klipper refuses the arc)",
                    char::from(l0),
                    char::from(l1)
                ),
            );
            return;
        }
        if let Some(w) = p.word(b'P') {
            d.warn(w.column, "P (whole turns) is ignored by Klipper".into());
        }
        self.feed(p, d);
        let target = self.target(p, d);
        // In the G-code's coordinates, as gcode_arcs.py computes (G92 shifts them).
        let chords = Chords::klipper(
            self.pos - self.offset,
            target - self.offset,
            offset,
            clockwise,
            self.plane,
            resolution_mm,
        );
        if chords.chord_count() == 0 {
            d.error(
                column,
                format!(
                    "arc too long or not finite: more than {} chords of {resolution_mm} mm",
                    super::arc::MAX_CHORDS
                ),
            );
            return;
        }
        let e_total = self.extrusion(p, d);
        self.stats.arcs += 1;
        let e_per_chord = e_total / chords.chord_count() as f64;
        let feed = self.feed_mm_s();
        for c in chords {
            let to = c + self.offset;
            self.send_move(Path::line(self.pos, to), e_per_chord, feed, ev);
            self.pos = to;
        }
        self.pos = target;
    }

    /// G92: the current position gets the given G-code coordinates; without any axis,
    /// all of X, Y, Z, E become 0 (Klipper). Before the first G28 or move nothing says
    /// where the machine is: then the coordinates say where the nozzle is (a calibration
    /// snippet starting `G92 X0 Y0 Z20`), and stay the machine's.
    fn set_position(&mut self, p: &ParsedLine) {
        let given: [Option<f64>; 3] = AXES.map(|a| p.value(a).map(|v| v * self.unit_mm));
        let e = p.value(b'E').map(|v| v * self.unit_mm);
        let bare = given.iter().all(Option::is_none) && e.is_none();
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

    /// Marlin's M207 (retract: S length, F feed mm/min) and M208 (recover: S extra
    /// length, F feed mm/min).
    fn m207_m208(&mut self, p: &ParsedLine, retract: bool) {
        let r = &mut self.retraction;
        let s = p
            .value(b'S')
            .filter(|v| *v >= 0.0)
            .map(|v| v * self.unit_mm);
        let f = p
            .value(b'F')
            .filter(|v| *v > 0.0)
            .map(|v| v * self.unit_mm / 60.0);
        if retract {
            r.length_mm = s.unwrap_or(r.length_mm);
            r.speed_mm_s = f.unwrap_or(r.speed_mm_s);
        } else {
            r.unretract_extra_mm = s.unwrap_or(r.unretract_extra_mm);
            r.unretract_speed_mm_s = f.unwrap_or(r.unretract_speed_mm_s);
        }
    }

    fn set_retraction_params(&mut self, p: &ParsedLine, d: &mut Diags<impl FnMut(Diagnostic)>) {
        let r = &mut self.retraction;
        for (key, field, positive) in [
            ("RETRACT_LENGTH", &mut r.length_mm, false),
            ("RETRACT_SPEED", &mut r.speed_mm_s, true),
            ("UNRETRACT_EXTRA_LENGTH", &mut r.unretract_extra_mm, false),
            ("UNRETRACT_SPEED", &mut r.unretract_speed_mm_s, true),
        ] {
            if let Some(q) = p.param(key) {
                match param_f64(q.value) {
                    Some(v) if v > 0.0 || (!positive && v == 0.0) => *field = v,
                    _ => d.error(q.column, format!("{key} must be a non-negative number")),
                }
            }
        }
    }
}

/// The warning of an M204 that Klipper ignores; Klipper's alone (Marlin honours P and T,
/// `analysis::for_firmware`).
pub const M204_P_OR_T_IGNORED: &str =
    "M204 with only P or only T is ignored (Klipper needs S, or both P and T)";

/// M204 as Klipper reads it: S sets the acceleration; without S both P and T are needed
/// and the smaller is used; P or T alone is ignored with a warning.
fn m204(p: &ParsedLine, column: u32, d: &mut Diags<impl FnMut(Diagnostic)>) -> LimitChange {
    let positive = |letter: u8, d: &mut Diags<_>| -> Option<Option<f64>> {
        let w = p.word(letter)?;
        match w.value {
            Some(v) if v > 0.0 => Some(Some(v)),
            _ => {
                d.error(
                    w.column,
                    format!("M204 {} must be positive", char::from(letter)),
                );
                Some(None)
            }
        }
    };
    let accel = match (positive(b'S', d), positive(b'P', d), positive(b'T', d)) {
        (Some(s), _, _) => s,
        (None, Some(Some(pv)), Some(Some(t))) => Some(pv.min(t)),
        (None, Some(_), None) | (None, None, Some(_)) => {
            d.warn(column, M204_P_OR_T_IGNORED.into());
            None
        }
        _ => None,
    };
    LimitChange {
        accel_mm_s2: accel,
        ..LimitChange::default()
    }
}

/// Klipper's SET_VELOCITY_LIMIT.
fn set_velocity_limit(p: &ParsedLine, d: &mut Diags<impl FnMut(Diagnostic)>) -> LimitChange {
    // Klipper's bounds: VELOCITY and ACCEL above 0, SQUARE_CORNER_VELOCITY at least 0,
    // MINIMUM_CRUISE_RATIO in [0, 1).
    let mut get = |key: &str, zero_ok: bool, below_one: bool| -> Option<f64> {
        let q = p.param(key)?;
        match param_f64(q.value) {
            Some(v) if (v > 0.0 || (zero_ok && v == 0.0)) && (!below_one || v < 1.0) => Some(v),
            _ => {
                d.error(q.column, format!("SET_VELOCITY_LIMIT {key}: invalid value"));
                None
            }
        }
    };
    LimitChange {
        velocity_mm_s: get("VELOCITY", false, false),
        accel_mm_s2: get("ACCEL", false, false),
        square_corner_velocity_mm_s: get("SQUARE_CORNER_VELOCITY", true, false),
        minimum_cruise_ratio: get("MINIMUM_CRUISE_RATIO", true, true),
        accel_to_decel_mm_s2: get("ACCEL_TO_DECEL", false, false),
    }
}

/// Klipper's SET_INPUT_SHAPER parameters (input_shaper.py `InputShaperParams.update`):
/// SHAPER_TYPE for both axes or SHAPER_TYPE_X/_Y, SHAPER_FREQ_X/_Y (≥ 0),
/// DAMPING_RATIO_X/_Y (≥ 0). A type Klipper does not know is an error, as in Klipper.
fn set_input_shaper(p: &ParsedLine, d: &mut Diags<impl FnMut(Diagnostic)>) -> ShaperChange {
    let mut change = ShaperChange::default();
    let kind = |key: &str, d: &mut Diags<_>| -> Option<ShaperType> {
        let q = p.param(key)?;
        let name = String::from_utf8_lossy(q.value);
        let k = ShaperType::from_name(&name);
        if k.is_none() {
            d.error(q.column, format!("{key}: unsupported shaper type `{name}`"));
        }
        k
    };
    let both = kind("SHAPER_TYPE", d);
    change.kind = [
        kind("SHAPER_TYPE_X", d).or(both),
        kind("SHAPER_TYPE_Y", d).or(both),
    ];
    let number = |key: &str, d: &mut Diags<_>| -> Option<f64> {
        let q = p.param(key)?;
        match param_f64(q.value) {
            Some(v) if v >= 0.0 => Some(v),
            _ => {
                d.error(q.column, format!("SET_INPUT_SHAPER {key}: invalid value"));
                None
            }
        }
    };
    change.freq_hz = [number("SHAPER_FREQ_X", d), number("SHAPER_FREQ_Y", d)];
    change.damping_ratio = [number("DAMPING_RATIO_X", d), number("DAMPING_RATIO_Y", d)];
    change
}

/// Where events of the current line go.
struct Events<'a, F> {
    line: u64,
    on_event: &'a mut F,
}

/// Where diagnostics of the current line go; counts them.
struct Diags<'a, F> {
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

    fn warn(&mut self, column: u32, message: String) {
        self.push(column, Severity::Warning, message);
    }

    fn error(&mut self, column: u32, message: String) {
        self.push(column, Severity::Error, message);
    }
}
