//! The carriage motors, from the profile's `motors` section to what the model needs: the
//! allowed force at the belt and the rotor's inertia seen as a mass on the carriage
//! (docs/machine-profile.md, `motors`). Two forms: `max_force_n` given, or a motor's
//! holding torque on a toothed pulley, derated by a safety factor.

use super::schema::RawMotors;
use super::validate::Range;
use super::{Invalid, Motors, defaults};

/// Pitch radius of a toothed pulley, m: its pitch circle is `teeth` belt pitches long,
/// r = teeth · pitch / (2π).
pub fn pulley_pitch_radius_m(teeth: u32, belt_pitch_mm: f64) -> f64 {
    f64::from(teeth) * belt_pitch_mm * 1e-3 / std::f64::consts::TAU
}

/// The force a motor may ask of its belt, N: the holding torque at the pulley's pitch
/// radius r, divided by the safety factor, torque / r / safety.
fn belt_force_n(holding_torque_nm: f64, radius_m: f64, safety_factor: f64) -> f64 {
    holding_torque_nm / radius_m / safety_factor
}

/// The rotor's inertia J seen at the carriage, kg: the rotor turns at q̇/r, so its kinetic
/// energy ½·J·(q̇/r)² is that of a mass J/r² moving with the carriage.
fn reflected_mass_kg(rotor_inertia_kg_m2: f64, radius_m: f64) -> f64 {
    rotor_inertia_kg_m2 / (radius_m * radius_m)
}

/// Either `max_force_n`, or `holding_torque_nm` + `safety_factor` on a pulley of
/// `pulley_teeth` × `belt_pitch_mm`; the rotor inertia, if given, reflected through the
/// same pulley. On a bad combination or figure returns the key and what is wrong.
pub(super) fn resolve(raw: &RawMotors) -> Result<Motors, Invalid> {
    let radius_m = match (raw.pulley_teeth, raw.belt_pitch_mm) {
        (Some(teeth), pitch) => {
            let pitch = pitch.unwrap_or(defaults::BELT_PITCH_MM);
            Range::Positive.check("motors.belt_pitch_mm", pitch)?;
            if teeth == 0 {
                return Err(Invalid::new("motors.pulley_teeth", "expected at least 1"));
            }
            Some(pulley_pitch_radius_m(teeth, pitch))
        }
        (None, Some(_)) => {
            return Err(Invalid::new(
                "motors.belt_pitch_mm",
                "given without `pulley_teeth`",
            ));
        }
        (None, None) => None,
    };
    let needs_pulley = |key: &str| {
        radius_m.ok_or_else(|| {
            Invalid::new(
                format!("motors.{key}"),
                format!(
                    "needs `pulley_teeth` (and `belt_pitch_mm`, default {} for GT2) to convert \
                     it at the belt",
                    defaults::BELT_PITCH_MM
                ),
            )
        })
    };
    let max_force_n = match (raw.max_force_n, raw.holding_torque_nm, raw.safety_factor) {
        (Some(f), None, None) => f,
        (Some(_), _, _) => {
            return Err(Invalid::new(
                "motors",
                "expected either `max_force_n` alone or `holding_torque_nm` together with \
                 `safety_factor` and `pulley_teeth`, not a mix",
            ));
        }
        (None, Some(torque), Some(safety)) => {
            let r = needs_pulley("holding_torque_nm")?;
            Range::Positive.check("motors.holding_torque_nm", torque)?;
            Range::AtLeastOne.check("motors.safety_factor", safety)?;
            belt_force_n(torque, r, safety)
        }
        (None, Some(_), None) => {
            return Err(Invalid::new(
                "motors.holding_torque_nm",
                "needs `safety_factor` (holding torque / allowed torque: the torque lost at \
                 speed, micro-stepping, margin)",
            ));
        }
        (None, None, Some(_)) => {
            return Err(Invalid::new(
                "motors.safety_factor",
                "needs `holding_torque_nm`",
            ));
        }
        (None, None, None) => {
            return Err(Invalid::new(
                "motors",
                "expected `max_force_n`, or `holding_torque_nm` + `safety_factor` + \
                 `pulley_teeth`",
            ));
        }
    };
    let reflected_mass_kg = match raw.rotor_inertia_kg_m2 {
        Some(j) => {
            let r = needs_pulley("rotor_inertia_kg_m2")?;
            Range::NonNegative.check("motors.rotor_inertia_kg_m2", j)?;
            reflected_mass_kg(j, r)
        }
        None => 0.0,
    };
    if radius_m.is_some() && raw.holding_torque_nm.is_none() && raw.rotor_inertia_kg_m2.is_none() {
        return Err(Invalid::new(
            "motors.pulley_teeth",
            "used only with `holding_torque_nm` or `rotor_inertia_kg_m2`",
        ));
    }
    Ok(Motors {
        max_force_n,
        reflected_mass_kg,
    })
}
