//! Marlin's setting commands, read as Marlin 2.1.x reads them (gcode/config/M200-M205.cpp,
//! gcode/calibrate/M665.cpp): each parameter given sets its setting for the moves after it.
//! On a delta, X, Y and Z are towers A, B and C.

use super::interp::Diags;
use super::parse::ParsedLine;
use super::{DeltaChange, Diagnostic, MarlinChange};

/// The value of `letter` when given and accepted by `ok` (`what` says what is expected); an
/// error otherwise, and the setting is kept.
fn checked(
    p: &ParsedLine,
    command: &str,
    letter: u8,
    unit: f64,
    (ok, what): (fn(f64) -> bool, &str),
    d: &mut Diags<impl FnMut(Diagnostic)>,
) -> Option<f64> {
    let w = p.word(letter)?;
    match w.value {
        Some(v) if v.is_finite() && ok(v) => Some(v * unit),
        _ => {
            d.error(
                w.column,
                format!(
                    "{command} {} must be {what}; the setting is kept",
                    char::from(letter)
                ),
            );
            None
        }
    }
}

/// A number > 0 (Marlin would take any number, but a zero or negative limit stops its
/// planner).
fn positive(
    p: &ParsedLine,
    command: &str,
    letter: u8,
    unit: f64,
    d: &mut Diags<impl FnMut(Diagnostic)>,
) -> Option<f64> {
    checked(
        p,
        command,
        letter,
        unit,
        (|v| v > 0.0, "a positive number"),
        d,
    )
}

/// A number ≥ 0 (jerk, minimum feedrates).
fn non_negative(
    p: &ParsedLine,
    command: &str,
    letter: u8,
    unit: f64,
    d: &mut Diags<impl FnMut(Diagnostic)>,
) -> Option<f64> {
    checked(p, command, letter, unit, (|v| v >= 0.0, "a number >= 0"), d)
}

const AXES: [u8; 4] = [b'X', b'Y', b'Z', b'E'];

/// M201 (max acceleration) or M203 (max feedrate, mm/s), X Y Z E.
pub(super) fn axis_limits(
    p: &ParsedLine,
    m203: bool,
    unit: f64,
    d: &mut Diags<impl FnMut(Diagnostic)>,
) -> Option<MarlinChange> {
    let command = if m203 { "M203" } else { "M201" };
    let v = AXES.map(|a| positive(p, command, a, unit, d));
    if v.iter().all(Option::is_none) {
        return None;
    }
    Some(if m203 {
        MarlinChange::MaxFeedrate(v)
    } else {
        MarlinChange::MaxAccel(v)
    })
}

/// M204: S sets print and travel acceleration, then P, R and T, each its own.
pub(super) fn m204(
    p: &ParsedLine,
    unit: f64,
    d: &mut Diags<impl FnMut(Diagnostic)>,
) -> Option<MarlinChange> {
    let s = positive(p, "M204", b'S', unit, d);
    let print = positive(p, "M204", b'P', unit, d).or(s);
    let retract = positive(p, "M204", b'R', unit, d);
    let travel = positive(p, "M204", b'T', unit, d).or(s);
    (print.is_some() || retract.is_some() || travel.is_some()).then_some(MarlinChange::Accel {
        print,
        retract,
        travel,
    })
}

/// M205: X Y Z E jerk, S and T minimum feedrates. B (SLOWDOWN's minimum segment time) is
/// compiled out on a delta, J (junction deviation) is not read with the classic jerk a delta
/// needs: both are noted once per line.
pub(super) fn m205(
    p: &ParsedLine,
    unit: f64,
    d: &mut Diags<impl FnMut(Diagnostic)>,
) -> Option<MarlinChange> {
    let jerk = AXES.map(|a| non_negative(p, "M205", a, unit, d));
    let min_feedrate = non_negative(p, "M205", b'S', unit, d);
    let min_travel_feedrate = non_negative(p, "M205", b'T', unit, d);
    if let Some(w) = p.word(b'J') {
        d.warn(
            w.column,
            "M205 J (junction deviation) is ignored: Marlin on a delta needs CLASSIC_JERK".into(),
        );
    }
    let any =
        jerk.iter().any(Option::is_some) || min_feedrate.is_some() || min_travel_feedrate.is_some();
    any.then_some(MarlinChange::Jerk {
        jerk,
        min_feedrate,
        min_travel_feedrate,
    })
}

/// M665 S L R H X Y Z A B C.
pub(super) fn m665(
    p: &ParsedLine,
    unit: f64,
    d: &mut Diags<impl FnMut(Diagnostic)>,
) -> DeltaChange {
    let number = |letter: u8, d: &mut Diags<_>| -> Option<f64> {
        let w = p.word(letter)?;
        match w.value {
            Some(v) if v.is_finite() => Some(v),
            _ => {
                d.error(
                    w.column,
                    format!("M665 {} needs a number", char::from(letter)),
                );
                None
            }
        }
    };
    DeltaChange {
        segments_per_second: positive(p, "M665", b'S', 1.0, d),
        diagonal_rod_mm: positive(p, "M665", b'L', unit, d),
        radius_mm: positive(p, "M665", b'R', unit, d),
        height_mm: positive(p, "M665", b'H', unit, d),
        angle_trim_deg: [b'X', b'Y', b'Z'].map(|a| number(a, d)),
        rod_trim_mm: [b'A', b'B', b'C'].map(|a| number(a, d).map(|v| v * unit)),
    }
}
