//! G2/G3 as each firmware cuts them into chords: Klipper's gcode_arcs.py, Marlin's
//! `plan_arc`.

use super::super::arc::{ArcRules, Chords, MarlinArc, MarlinChords};
use super::super::parse::ParsedLine;
use super::super::{ArcChord, Diagnostic, Event};
use super::{Diags, Events, Interpreter};
use crate::path::Path;

impl Interpreter {
    /// G2/G3 as Marlin's `G2_G3` and `plan_arc` run them: the destination as for G1 (G91
    /// and M83 allowed), the centre from R (the nearer centre; negative R the farther) or
    /// from I and J; chords of [`MarlinChords`], each clamped by the soft endstops, each
    /// with its share of E and the planner's hint; the position ends on the unclamped
    /// target, as Marlin's does.
    pub(super) fn marlin_arc(
        &mut self,
        p: &ParsedLine,
        clockwise: bool,
        column: u32,
        ev: &mut Events<impl FnMut(Event)>,
        d: &mut Diags<impl FnMut(Diagnostic)>,
    ) {
        self.feed(p, d);
        let target = self.target(p, d);
        let start = self.pos;
        let mut offset = [0.0, 0.0];
        if let Some(r) = p.word(b'R').and_then(|w| w.value) {
            let r = r * self.unit_mm;
            if r != 0.0 && (start.x != target.x || start.y != target.y) {
                let d2 = [(target.x - start.x) * 0.5, (target.y - start.y) * 0.5];
                let e = if clockwise ^ (r < 0.0) { -1.0 } else { 1.0 };
                let len = d2[0].hypot(d2[1]);
                let h2 = (r - len) * (r + len);
                let h = if h2 >= 0.0 { h2.sqrt() } else { 0.0 };
                offset = [d2[0] - d2[1] / len * e * h, d2[1] + d2[0] / len * e * h];
            }
        } else {
            offset = [
                p.value(b'I').unwrap_or(0.0) * self.unit_mm,
                p.value(b'J').unwrap_or(0.0) * self.unit_mm,
            ];
        }
        if offset == [0.0, 0.0] || !(offset[0].is_finite() && offset[1].is_finite()) {
            d.error(
                column,
                "G2/G3: Bad parameters (Marlin refuses the arc: it needs a centre offset I/J or \
                 a radius R)"
                    .into(),
            );
            return;
        }
        if let Some(w) = p.word(b'P') {
            d.warn(
                w.column,
                "P (whole circles) is ignored (Marlin's ARC_P_CIRCLES is off by default)".into(),
            );
        }
        let e_before = self.e_pos;
        let e_total = self.extrusion(p, d);
        let feed = self.feed_mm_s();
        match MarlinChords::plan(
            start,
            target,
            offset,
            clockwise,
            &self.dialect.arcs,
            feed,
            e_total != 0.0,
        ) {
            MarlinArc::Nothing => self.e_pos = e_before,
            MarlinArc::ExtrudeOnly => {
                self.stats.arcs += 1;
                self.send_move(Path::line(start, target), e_total, feed, ev);
                self.pos = target;
            }
            MarlinArc::Chords(chords) => {
                self.stats.arcs += 1;
                let n = chords.segments();
                let (radius, flat) = (chords.radius_mm(), chords.flat_mm());
                let e_per_chord = e_total / n as f64;
                for c in chords {
                    let to = self.apply_motion_limits(c.end, d);
                    let remaining_mm = if c.index == n {
                        0.0
                    } else {
                        flat - c.index as f64 * (flat / n as f64)
                    };
                    let hint = ArcChord {
                        radius_mm: radius,
                        remaining_mm,
                    };
                    self.send_chord(Path::line(self.pos, to), e_per_chord, feed, Some(hint), ev);
                    self.pos = to;
                }
                self.pos = target;
            }
        }
    }

    /// G2/G3 as Klipper's gcode_arcs.py runs them: refused in relative mode and in R form,
    /// the centre offset from the plane's two letters (a zero offset refused), cut into
    /// chords ([`Chords::klipper`]), each an ordinary move with its share of E and the F.
    pub(super) fn arc(
        &mut self,
        p: &ParsedLine,
        clockwise: bool,
        column: u32,
        ev: &mut Events<impl FnMut(Event)>,
        d: &mut Diags<impl FnMut(Diagnostic)>,
    ) {
        let ArcRules::Klipper { resolution_mm } = self.dialect.arcs else {
            return;
        };
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
                    super::super::arc::MAX_CHORDS
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
}
