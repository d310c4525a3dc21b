//! Klipper's limit commands as it reads them: M204, SET_VELOCITY_LIMIT, SET_INPUT_SHAPER.

use super::super::parse::{ParsedLine, param_f64};
use super::super::{Diagnostic, LimitChange};
use super::Diags;
use crate::motion::shaper::{ShaperChange, ShaperType};

/// The warning of an M204 that Klipper ignores; Klipper's alone (Marlin honours P and T,
/// `analysis::for_firmware`).
pub const M204_P_OR_T_IGNORED: &str =
    "M204 with only P or only T is ignored (Klipper needs S, or both P and T)";

/// M204 as Klipper reads it: S sets the acceleration; without S both P and T are needed
/// and the smaller is used; P or T alone is ignored with a warning.
pub(super) fn m204(
    p: &ParsedLine,
    column: u32,
    d: &mut Diags<impl FnMut(Diagnostic)>,
) -> LimitChange {
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
pub(super) fn set_velocity_limit(
    p: &ParsedLine,
    d: &mut Diags<impl FnMut(Diagnostic)>,
) -> LimitChange {
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
pub(super) fn set_input_shaper(
    p: &ParsedLine,
    d: &mut Diags<impl FnMut(Diagnostic)>,
) -> ShaperChange {
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
