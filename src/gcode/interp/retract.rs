//! Firmware retraction (G10/G11) and the commands that set it: Klipper's SET_RETRACTION,
//! Marlin's M207/M208.

use super::super::Diagnostic;
use super::super::parse::{ParsedLine, param_f64};
use super::{Diags, Interpreter};

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

impl Interpreter {
    /// Marlin's M207 (retract: S length, F feed mm/min) and M208 (recover: S extra
    /// length, F feed mm/min).
    pub(super) fn m207_m208(&mut self, p: &ParsedLine, retract: bool) {
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

    pub(super) fn set_retraction_params(
        &mut self,
        p: &ParsedLine,
        d: &mut Diags<impl FnMut(Diagnostic)>,
    ) {
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
