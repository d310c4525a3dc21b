//! `firmware` and `marlin`: which firmware plans the moves, and Marlin's settings
//! (docs/machine-profile.md, `marlin`), each with Marlin's default where left out
//! ([`super::defaults`], `MARLIN_*`).

use serde::{Deserialize, Serialize};

use super::validate::Range;
use super::{Invalid, defaults};
use crate::gcode::ArcRules;

/// The firmware whose planner the moves follow.
#[derive(Clone, Debug, PartialEq)]
pub enum Firmware {
    /// Klipper (the default): `limits`, `gcode_arcs`, `input_shaper`.
    Klipper,
    /// Marlin 2.1.x, with its settings.
    Marlin(Marlin),
}

impl Firmware {
    /// The profile's name of the firmware.
    pub fn name(&self) -> &'static str {
        match self {
            Firmware::Klipper => "klipper",
            Firmware::Marlin(_) => "marlin",
        }
    }
}

/// Marlin's motion settings on a delta; towers A, B, C are Marlin's X, Y, Z steppers.
/// Each field names its Marlin setting; the defaults are Marlin's (towers: its X figures).
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct Marlin {
    /// `DEFAULT_AXIS_STEPS_PER_UNIT` of the towers (M92 X Y Z), steps/mm.
    pub steps_per_mm: f64,
    /// `DEFAULT_AXIS_STEPS_PER_UNIT` of E (M92 E), steps/mm.
    pub e_steps_per_mm: f64,
    /// `DEFAULT_SEGMENTS_PER_SECOND` (M665 S): moves are cut into segments of 1/S s.
    pub segments_per_second: f64,
    /// `DEFAULT_MAX_FEEDRATE` (M203) of towers A, B, C and E, mm/s.
    pub max_feedrate_mm_s: [f64; 4],
    /// `DEFAULT_MAX_ACCELERATION` (M201) of towers A, B, C and E, mm/s².
    pub max_accel_mm_s2: [f64; 4],
    /// `DEFAULT_ACCELERATION` (M204 P): printing moves, mm/s².
    pub print_accel_mm_s2: f64,
    /// `DEFAULT_RETRACT_ACCELERATION` (M204 R): E-only moves, mm/s².
    pub retract_accel_mm_s2: f64,
    /// `DEFAULT_TRAVEL_ACCELERATION` (M204 T): moves without extrusion, mm/s².
    pub travel_accel_mm_s2: f64,
    /// `DEFAULT_XJERK`/`YJERK`/`ZJERK` (towers A, B, C) and `DEFAULT_EJERK` (M205 X Y Z E,
    /// `CLASSIC_JERK`, which a delta needs), mm/s.
    pub jerk_mm_s: [f64; 4],
    /// `S_CURVE_ACCELERATION`.
    pub s_curve: bool,
    /// `BLOCK_BUFFER_SIZE`: planner blocks (a power of 2, at most 64).
    pub block_buffer_size: u32,
    /// `MIN_STEPS_PER_SEGMENT`: a segment moving no stepper this many steps is merged.
    pub min_steps_per_segment: u32,
    /// `DEFAULT_MINSEGMENTTIME` (M205 B), µs.
    pub min_segment_time_us: u32,
    /// `MINIMUM_PLANNER_SPEED`, mm/s.
    pub minimum_planner_speed_mm_s: f64,
    /// `AUTO_BED_LEVELING_UBL`: moves are cut by UBL's segmenter (the XY length, rounded,
    /// segments of at least 0.1 mm) instead of the plain delta segmenter.
    pub ubl: bool,
    /// `MAX_ARC_SEGMENT_MM`: the longest chord of a G2/G3, mm.
    pub max_arc_segment_mm: f64,
    /// `MIN_ARC_SEGMENT_MM`: the shortest chord, mm.
    pub min_arc_segment_mm: f64,
    /// `MIN_CIRCLE_SEGMENTS`: chords in a full circle at least.
    pub min_circle_segments: u32,
    /// `ARC_SEGMENTS_PER_SEC`: chords per second at the feed (0: off, chords of
    /// `max_arc_segment_mm`).
    pub arc_segments_per_sec: f64,
    /// `N_ARC_CORRECTION`: every N-th chord end is computed exactly.
    pub n_arc_correction: u32,
}

impl Marlin {
    /// `plan_arc`'s settings.
    pub fn arc_rules(&self) -> ArcRules {
        ArcRules::Marlin {
            max_segment_mm: self.max_arc_segment_mm,
            min_segment_mm: self.min_arc_segment_mm,
            min_circle_segments: self.min_circle_segments,
            segments_per_sec: self.arc_segments_per_sec,
            n_arc_correction: self.n_arc_correction,
        }
    }
}

impl Default for Marlin {
    fn default() -> Self {
        Marlin {
            steps_per_mm: defaults::MARLIN_STEPS_PER_MM,
            e_steps_per_mm: defaults::MARLIN_E_STEPS_PER_MM,
            segments_per_second: defaults::MARLIN_SEGMENTS_PER_SECOND,
            max_feedrate_mm_s: defaults::MARLIN_MAX_FEEDRATE_MM_S,
            max_accel_mm_s2: defaults::MARLIN_MAX_ACCEL_MM_S2,
            print_accel_mm_s2: defaults::MARLIN_PRINT_ACCEL_MM_S2,
            retract_accel_mm_s2: defaults::MARLIN_RETRACT_ACCEL_MM_S2,
            travel_accel_mm_s2: defaults::MARLIN_TRAVEL_ACCEL_MM_S2,
            jerk_mm_s: defaults::MARLIN_JERK_MM_S,
            s_curve: defaults::MARLIN_S_CURVE,
            block_buffer_size: defaults::MARLIN_BLOCK_BUFFER_SIZE,
            min_steps_per_segment: defaults::MARLIN_MIN_STEPS_PER_SEGMENT,
            min_segment_time_us: defaults::MARLIN_MIN_SEGMENT_TIME_US,
            minimum_planner_speed_mm_s: defaults::MARLIN_MINIMUM_PLANNER_SPEED_MM_S,
            ubl: defaults::MARLIN_UBL,
            max_arc_segment_mm: defaults::MARLIN_MAX_ARC_SEGMENT_MM,
            min_arc_segment_mm: defaults::MARLIN_MIN_ARC_SEGMENT_MM,
            min_circle_segments: defaults::MARLIN_MIN_CIRCLE_SEGMENTS,
            arc_segments_per_sec: defaults::MARLIN_ARC_SEGMENTS_PER_SEC,
            n_arc_correction: defaults::MARLIN_N_ARC_CORRECTION,
        }
    }
}

/// `firmware:` as written.
#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq)]
#[serde(rename_all = "lowercase")]
pub(super) enum FirmwareName {
    #[default]
    Klipper,
    Marlin,
}

/// `firmware` and `marlin` together: `marlin` only with `firmware: marlin`.
pub(super) fn resolve(name: FirmwareName, marlin: Option<Marlin>) -> Result<Firmware, Invalid> {
    match (name, marlin) {
        (FirmwareName::Klipper, Some(_)) => Err(Invalid::new(
            "marlin",
            "Marlin's settings are used only with `firmware: marlin` (the profile's firmware \
             is klipper, the default)",
        )),
        (FirmwareName::Klipper, None) => Ok(Firmware::Klipper),
        (FirmwareName::Marlin, m) => {
            let m = m.unwrap_or_default();
            check(&m)?;
            Ok(Firmware::Marlin(m))
        }
    }
}

/// Each figure's range.
fn check(m: &Marlin) -> Result<(), Invalid> {
    let scalars = [
        ("steps_per_mm", m.steps_per_mm, Range::Positive),
        ("e_steps_per_mm", m.e_steps_per_mm, Range::Positive),
        (
            "segments_per_second",
            m.segments_per_second,
            Range::Positive,
        ),
        ("print_accel_mm_s2", m.print_accel_mm_s2, Range::Positive),
        (
            "retract_accel_mm_s2",
            m.retract_accel_mm_s2,
            Range::Positive,
        ),
        ("travel_accel_mm_s2", m.travel_accel_mm_s2, Range::Positive),
        (
            "minimum_planner_speed_mm_s",
            m.minimum_planner_speed_mm_s,
            Range::NonNegative,
        ),
        ("max_arc_segment_mm", m.max_arc_segment_mm, Range::Positive),
        ("min_arc_segment_mm", m.min_arc_segment_mm, Range::Positive),
        (
            "arc_segments_per_sec",
            m.arc_segments_per_sec,
            Range::NonNegative,
        ),
    ];
    for (key, v, range) in scalars {
        range.check(&format!("marlin.{key}"), v)?;
    }
    let lists = [
        ("max_feedrate_mm_s", m.max_feedrate_mm_s, Range::Positive),
        ("max_accel_mm_s2", m.max_accel_mm_s2, Range::Positive),
        ("jerk_mm_s", m.jerk_mm_s, Range::NonNegative),
    ];
    for (key, values, range) in lists {
        for v in values {
            range.check(&format!("marlin.{key}"), v)?;
        }
    }
    let b = m.block_buffer_size;
    if !(b.is_power_of_two() && b <= 64) {
        return Err(Invalid::new(
            "marlin.block_buffer_size",
            format!("expected a power of 2 up to 64 (Marlin's rule), found {b}"),
        ));
    }
    if m.min_arc_segment_mm > m.max_arc_segment_mm {
        return Err(Invalid::new(
            "marlin.min_arc_segment_mm",
            format!(
                "expected at most max_arc_segment_mm ({}), found {}",
                m.max_arc_segment_mm, m.min_arc_segment_mm
            ),
        ));
    }
    for (key, v) in [
        ("min_circle_segments", m.min_circle_segments),
        ("n_arc_correction", m.n_arc_correction),
    ] {
        if v == 0 {
            return Err(Invalid::new(format!("marlin.{key}"), "expected at least 1"));
        }
    }
    if m.min_steps_per_segment == 0 {
        return Err(Invalid::new(
            "marlin.min_steps_per_segment",
            "expected at least 1",
        ));
    }
    Ok(())
}
