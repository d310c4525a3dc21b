//! Marlin's setting commands, read as Marlin 2.1.x reads them (gcode/config/M200-M205.cpp,
//! gcode/calibrate/M665.cpp): each parameter given sets its setting for the moves after it.
//! On a delta, X, Y and Z are towers A, B and C.

use super::interp::Diags;
use super::parse::ParsedLine;
use super::{DeltaChange, DeltaSettings, Diagnostic, MarlinChange};

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

/// M665 S L R H X Y Z A B C. With the profile's geometry, a warning for each part of it
/// the line sets otherwise: delta-gcode keeps modelling the profile's.
pub(super) fn m665(
    p: &ParsedLine,
    unit: f64,
    profile: Option<&DeltaSettings>,
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
    let change = DeltaChange {
        segments_per_second: positive(p, "M665", b'S', 1.0, d),
        diagonal_rod_mm: positive(p, "M665", b'L', unit, d),
        radius_mm: positive(p, "M665", b'R', unit, d),
        height_mm: positive(p, "M665", b'H', unit, d),
        angle_trim_deg: [b'X', b'Y', b'Z'].map(|a| number(a, d)),
        rod_trim_mm: [b'A', b'B', b'C'].map(|a| number(a, d).map(|v| v * unit)),
    };
    if let Some(profile) = profile {
        for (letter, what) in differences(&change, profile) {
            let column = p.word(letter).map_or(1, |w| w.column);
            d.warn(
                column,
                format!(
                    "M665 {}: {what}; delta-gcode plans and models the profile's geometry \
                     (set the profile's geometry to the printer's calibration)",
                    char::from(letter)
                ),
            );
        }
    }
    change
}

/// Below this a calibration value is the profile's, mm or degrees (M665 prints 3 decimals).
const SAME_GEOMETRY: f64 = 0.0005;

/// Each parameter of an M665 that states another geometry than the profile's: its letter
/// and what differs. The rods are L plus the line's trims (0 where it gives none, Marlin's
/// default `DELTA_DIAGONAL_ROD_TRIM_TOWER`); trims without L are not compared. H is not
/// compared: the home height it gives is `delta_height` less the probe's Z offset
/// (`set_axis_is_at_home`), which the profile does not state apart.
fn differences(c: &DeltaChange, profile: &DeltaSettings) -> Vec<(u8, String)> {
    let differs = |a: f64, b: f64| (a - b).abs() > SAME_GEOMETRY;
    let list = |v: &[f64; 3]| v.map(|x| format!("{x:.3}")).join(", ");
    let mut out = Vec::new();
    if let Some(l) = c.diagonal_rod_mm {
        let rods: [f64; 3] = std::array::from_fn(|i| l + c.rod_trim_mm[i].unwrap_or(0.0));
        if (0..3).any(|i| differs(rods[i], profile.rod_mm[i])) {
            out.push((
                b'L',
                format!(
                    "the file's diagonal rods (L plus trims A, B, C) are {} mm, the profile's \
                     geometry.arm_length_mm {} mm",
                    list(&rods),
                    list(&profile.rod_mm)
                ),
            ));
        }
    }
    if let Some(r) = c.radius_mm.filter(|&r| differs(r, profile.radius_mm)) {
        out.push((
            b'R',
            format!(
                "the file's delta radius is {r:.3} mm, the profile's geometry.delta_radius_mm \
                 {:.3} mm",
                profile.radius_mm
            ),
        ));
    }
    let trims = c.angle_trim_deg;
    if (0..3).any(|i| trims[i].is_some_and(|t| differs(t, profile.angle_trim_deg[i]))) {
        let file = std::array::from_fn(|i| trims[i].unwrap_or(profile.angle_trim_deg[i]));
        let letter = [b'X', b'Y', b'Z'][(0..3).find(|&i| trims[i].is_some()).unwrap_or(0)];
        out.push((
            letter,
            format!(
                "the file's tower angle trims are {}°, the profile's geometry.tower_angles_deg \
                 less 210°, 330°, 90° are {}°",
                list(&file),
                list(&profile.angle_trim_deg)
            ),
        ));
    }
    out
}
