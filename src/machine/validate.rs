//! The checks on a resolved profile (docs/machine-profile.md, "Checks on the whole
//! profile"): each figure's range, from one table, then the geometry as a whole.

use super::{Invalid, Machine};
use crate::delta::TOWER_NAMES;
use crate::path::Vec3;

/// The sampling periods a profile may ask for, s (1 µs to 1 s): a shorter period makes
/// every move millions of samples and the run would seem to hang.
const MIN_PERIOD_S: f64 = 1e-6;
const MAX_PERIOD_S: f64 = 1.0;

/// What a figure must be; every range excludes NaN and infinities.
#[derive(Clone, Copy)]
pub(super) enum Range {
    /// > 0
    Positive,
    /// ≥ 0
    NonNegative,
    /// ≥ 1 (a safety factor)
    AtLeastOne,
    /// In [0, 1) (Klipper's `minimum_cruise_ratio`).
    Fraction,
    /// A sampling period the run can finish with, [`MIN_PERIOD_S`] to [`MAX_PERIOD_S`].
    Period,
}

impl Range {
    /// `Ok` when `v` is in the range, else the key and what was expected.
    pub(super) fn check(self, key: &str, v: f64) -> Result<(), Invalid> {
        let within = match self {
            Range::Positive => v > 0.0,
            Range::NonNegative => v >= 0.0,
            Range::AtLeastOne => v >= 1.0,
            Range::Fraction => (0.0..1.0).contains(&v),
            Range::Period => (MIN_PERIOD_S..=MAX_PERIOD_S).contains(&v),
        };
        if v.is_finite() && within {
            return Ok(());
        }
        let expected = match self {
            Range::Positive => "a finite number > 0".to_string(),
            Range::NonNegative => "a finite number >= 0".to_string(),
            Range::AtLeastOne => "a finite number >= 1".to_string(),
            Range::Fraction => "a number in [0, 1)".to_string(),
            Range::Period => format!("a period between {MIN_PERIOD_S} and {MAX_PERIOD_S} s"),
        };
        Err(Invalid::new(key, format!("expected {expected}, found {v}")))
    }
}

/// Checks every figure of a resolved profile; on failure returns the dotted key and what is
/// wrong. The ranges are checked in the table's order and the first failure is reported.
pub(super) fn check(m: &Machine) -> Result<(), Invalid> {
    let (g, l, e) = (&m.geometry, &m.limits, &m.extruder);
    let ranges = [
        (
            "geometry.delta_radius_mm",
            g.delta_radius_mm,
            Range::Positive,
        ),
        (
            "geometry.print_radius_mm",
            g.print_radius_mm,
            Range::Positive,
        ),
        ("masses.cart_kg", m.masses.cart_kg, Range::Positive),
        ("masses.link_kg", m.masses.link_kg, Range::Positive),
        ("masses.platform_kg", m.masses.platform_kg, Range::Positive),
        (
            "limits.max_velocity_mm_s",
            l.max_velocity_mm_s,
            Range::Positive,
        ),
        ("limits.max_accel_mm_s2", l.max_accel_mm_s2, Range::Positive),
        (
            "limits.max_z_velocity_mm_s",
            l.max_z_velocity_mm_s,
            Range::Positive,
        ),
        (
            "limits.max_z_accel_mm_s2",
            l.max_z_accel_mm_s2,
            Range::Positive,
        ),
        (
            "extruder.nozzle_diameter_mm",
            e.nozzle_diameter_mm,
            Range::Positive,
        ),
        (
            "extruder.filament_diameter_mm",
            e.filament_diameter_mm,
            Range::Positive,
        ),
        ("motors.max_force_n", m.motors.max_force_n, Range::Positive),
        ("sampling.period_s", m.sampling.period_s, Range::Positive),
        ("gravity_m_s2", m.gravity_m_s2, Range::Positive),
        ("sampling.period_s", m.sampling.period_s, Range::Period),
        (
            "extruder.max_extrude_only_velocity_mm_s",
            e.max_extrude_only_velocity_mm_s,
            Range::Positive,
        ),
        (
            "extruder.max_extrude_only_accel_mm_s2",
            e.max_extrude_only_accel_mm_s2,
            Range::Positive,
        ),
        (
            "geometry.nozzle_offset_mm",
            g.nozzle_offset_mm,
            Range::NonNegative,
        ),
        (
            "limits.square_corner_velocity_mm_s",
            l.square_corner_velocity_mm_s,
            Range::NonNegative,
        ),
        (
            "extruder.instantaneous_corner_velocity_mm_s",
            e.instantaneous_corner_velocity_mm_s,
            Range::NonNegative,
        ),
        (
            "limits.minimum_cruise_ratio",
            l.minimum_cruise_ratio,
            Range::Fraction,
        ),
    ];
    for (key, v, range) in ranges {
        range.check(key, v)?;
    }
    if let Some(a2d) = l.max_accel_to_decel_mm_s2 {
        Range::Positive.check("limits.max_accel_to_decel_mm_s2", a2d)?;
    }
    if let Some(hold) = g.arm_magnet_hold_n {
        Range::Positive.check("geometry.arm_magnet_hold_n", hold)?;
    }
    if g.tower_angles_deg.iter().any(|a| !a.is_finite()) {
        return Err(Invalid::new(
            "geometry.tower_angles_deg",
            "expected finite angles",
        ));
    }
    let reach = g.delta_radius_mm + g.print_radius_mm;
    for (i, &l) in g.arm_length_mm.iter().enumerate() {
        if !(l.is_finite() && l > reach) {
            return Err(Invalid::new(
                "geometry.arm_length_mm",
                format!(
                    "arm of tower {} is {l} mm, it must be longer than delta_radius + \
                     print_radius = {reach} mm or the arms lie flat inside the print disc",
                    TOWER_NAMES[i]
                ),
            ));
        }
    }
    if !(g.home_z_mm.is_finite() && g.home_z_mm > 0.0) {
        return Err(Invalid::new(
            "geometry.home_z_mm",
            format!("home must be above the bed (z > 0), found {}", g.home_z_mm),
        ));
    }
    if let Err(e) = m.model().inverse(Vec3::new(0.0, 0.0, g.home_z_mm)) {
        return Err(Invalid::new(
            "geometry.home_z_mm",
            format!("home is unreachable: {e}"),
        ));
    }
    Ok(())
}
