//! The carriage motors, from the profile's `motors` section to what the model needs: the
//! force a motor can give at the belt (constant, or against speed), the rotor's inertia seen
//! as a mass on the carriage and the motor's stiffness at the carriage
//! (docs/machine-profile.md, `motors`). Two forms: `max_force_n` given, or a motor (its
//! holding torque, or a `model` of the motor table) on a toothed pulley, derated by a safety
//! factor, with the electrical figures when the force falls with speed.

use super::motor_table::{self, MotorSpec};
use super::schema::RawMotors;
use super::validate::Range;
use super::{Invalid, Motors, defaults};
use crate::motor::{StepperCurve, StepperFigures, rotor_teeth};

/// Pitch radius of a toothed pulley, m: its pitch circle is `teeth` belt pitches long,
/// r = teeth · pitch / (2π).
pub fn pulley_pitch_radius_m(teeth: u32, belt_pitch_mm: f64) -> f64 {
    f64::from(teeth) * belt_pitch_mm * 1e-3 / std::f64::consts::TAU
}

/// The rotor's inertia J seen at the carriage, kg: the rotor turns at q̇/r, so its kinetic
/// energy ½·J·(q̇/r)² is that of a mass J/r² moving with the carriage.
fn reflected_mass_kg(rotor_inertia_kg_m2: f64, radius_m: f64) -> f64 {
    rotor_inertia_kg_m2 / (radius_m * radius_m)
}

/// The magnetic stiffness of a hybrid stepper seen at its carriage, N/m: the torque near a
/// held position is T·sin(N_r·θ), whose slope at θ = 0 is T·N_r (N·m/rad); through the
/// pulley, k_m = T·N_r / r².
pub fn motor_stiffness_n_m(torque_nm: f64, step_angle_deg: f64, radius_m: f64) -> f64 {
    torque_nm * rotor_teeth(step_angle_deg) / (radius_m * radius_m)
}

/// Either `max_force_n`, or a motor (`holding_torque_nm` or `model`) + `safety_factor` on a
/// pulley (`pulley_teeth` × `belt_pitch_mm`, or `rotation_distance_mm`); the rotor inertia,
/// if given, reflected through the same pulley. On a bad combination or figure returns the
/// key and what is wrong.
pub(super) fn resolve(raw: &RawMotors) -> Result<Motors, Invalid> {
    let radius_m = pulley_radius_m(raw)?;
    let needs_pulley = |key: &str| {
        radius_m.ok_or_else(|| {
            Invalid::new(
                format!("motors.{key}"),
                format!(
                    "needs `pulley_teeth` (and `belt_pitch_mm`, default {} for GT2) or \
                     `rotation_distance_mm` to convert it at the belt",
                    defaults::BELT_PITCH_MM
                ),
            )
        })
    };
    let spec = match &raw.model {
        Some(name) => Some(motor_table::find(name).ok_or_else(|| unknown_model(name))?),
        None => None,
    };
    // The key that names the motor's torque, for the messages.
    let torque_key = if raw.holding_torque_nm.is_some() || spec.is_none() {
        "holding_torque_nm"
    } else {
        "model"
    };
    let holding_torque = raw.holding_torque_nm.or(spec.map(|s| s.holding_torque_nm));
    let torque_form = match (raw.max_force_n, holding_torque, raw.safety_factor) {
        (Some(f), None, None) => {
            let keys = raw.torque_form_keys();
            if let Some((key, _)) = keys.iter().find(|(_, given)| *given) {
                return Err(Invalid::new(
                    format!("motors.{key}"),
                    "used only with the torque form (`holding_torque_nm` or `model`, with \
                     `safety_factor`), not with `max_force_n`",
                ));
            }
            return finish_force_form(raw, f, radius_m, needs_pulley);
        }
        (Some(_), _, _) => {
            return Err(Invalid::new(
                "motors",
                "expected either `max_force_n` alone or `holding_torque_nm` (or `model`) \
                 together with `safety_factor` and `pulley_teeth`, not a mix",
            ));
        }
        (None, Some(torque), Some(safety)) => {
            let r = needs_pulley(torque_key)?;
            Range::Positive.check("motors.holding_torque_nm", torque)?;
            Range::AtLeastOne.check("motors.safety_factor", safety)?;
            (torque, safety, r)
        }
        (None, Some(_), None) => {
            return Err(Invalid::new(
                format!("motors.{torque_key}"),
                "needs `safety_factor` (holding torque / allowed torque: the torque lost at \
                 speed, micro-stepping, margin)",
            ));
        }
        (None, None, Some(_)) => {
            return Err(Invalid::new(
                "motors.safety_factor",
                "needs `holding_torque_nm` (or a `model`)",
            ));
        }
        (None, None, None) => {
            return Err(Invalid::new(
                "motors",
                "expected `max_force_n`, or `holding_torque_nm` (or `model`) + \
                 `safety_factor` + `pulley_teeth`",
            ));
        }
    };
    finish_torque_form(raw, spec, torque_form)
}

/// The pulley's pitch radius, m: `pulley_teeth` × `belt_pitch_mm`, or Klipper's
/// `rotation_distance_mm` (the belt travel of one turn); None when neither is given.
fn pulley_radius_m(raw: &RawMotors) -> Result<Option<f64>, Invalid> {
    match (
        raw.pulley_teeth,
        raw.belt_pitch_mm,
        raw.rotation_distance_mm,
    ) {
        (Some(_), _, Some(_)) => Err(Invalid::new(
            "motors.rotation_distance_mm",
            "expected either `pulley_teeth` (with `belt_pitch_mm`) or `rotation_distance_mm`, \
             not both",
        )),
        (Some(teeth), pitch, None) => {
            let pitch = pitch.unwrap_or(defaults::BELT_PITCH_MM);
            Range::Positive.check("motors.belt_pitch_mm", pitch)?;
            if teeth == 0 {
                return Err(Invalid::new("motors.pulley_teeth", "expected at least 1"));
            }
            Ok(Some(pulley_pitch_radius_m(teeth, pitch)))
        }
        (None, Some(_), _) => Err(Invalid::new(
            "motors.belt_pitch_mm",
            "given without `pulley_teeth`",
        )),
        (None, None, Some(d)) => {
            Range::Positive.check("motors.rotation_distance_mm", d)?;
            Ok(Some(d * 1e-3 / std::f64::consts::TAU))
        }
        (None, None, None) => Ok(None),
    }
}

/// `motors.model` names no motor of the table: the closest name and the list.
fn unknown_model(name: &str) -> Invalid {
    let names: Vec<&str> = motor_table::MOTORS.iter().map(|m| m.name).collect();
    let lower = name.to_ascii_lowercase();
    // A name cut short (the maker's suffix left out) or mistyped.
    let prefix_of = names
        .iter()
        .find(|n| !lower.is_empty() && n.starts_with(&lower));
    let hint = prefix_of
        .or_else(|| {
            names
                .iter()
                .map(|n| (super::location::edit_distance(&lower, n), n))
                .filter(|&(d, n)| d <= n.len() / 3)
                .min_by_key(|&(d, _)| d)
                .map(|(_, n)| n)
        })
        .map(|n| format!(" (did you mean `{n}`?)"))
        .unwrap_or_default();
    Invalid::new(
        "motors.model",
        format!(
            "unknown motor `{name}`{hint}; the table has {}",
            names.join(", ")
        ),
    )
}

/// The force form: the constant limit, and the rotor when a pulley is given for it.
fn finish_force_form(
    raw: &RawMotors,
    max_force_n: f64,
    radius_m: Option<f64>,
    needs_pulley: impl Fn(&str) -> Result<f64, Invalid>,
) -> Result<Motors, Invalid> {
    let reflected_mass_kg = match raw.rotor_inertia_kg_m2 {
        Some(j) => {
            let r = needs_pulley("rotor_inertia_kg_m2")?;
            Range::NonNegative.check("motors.rotor_inertia_kg_m2", j)?;
            reflected_mass_kg(j, r)
        }
        None => 0.0,
    };
    if radius_m.is_some() && raw.rotor_inertia_kg_m2.is_none() {
        let key = if raw.pulley_teeth.is_some() {
            "pulley_teeth"
        } else {
            "rotation_distance_mm"
        };
        return Err(Invalid::new(
            format!("motors.{key}"),
            "used only with `holding_torque_nm` (or `model`) or `rotor_inertia_kg_m2`",
        ));
    }
    Ok(Motors {
        max_force_n,
        reflected_mass_kg,
        curve: None,
        stiffness_n_m: None,
        model: None,
    })
}

/// The torque form: `(holding torque, safety factor, pulley radius in m)` checked; the
/// electrical figures (given, or the model's), the force and its curve, the stiffness.
fn finish_torque_form(
    raw: &RawMotors,
    spec: Option<&'static MotorSpec>,
    (holding_torque_nm, safety_factor, radius_m): (f64, f64, f64),
) -> Result<Motors, Invalid> {
    let pick = |given: Option<f64>, of_model: Option<f64>| given.or(of_model);
    let rated = pick(raw.rated_current_a, spec.map(|s| s.rated_current_a));
    let resistance = pick(raw.resistance_ohm, spec.map(|s| s.resistance_ohm));
    let inductance = pick(raw.inductance_mh, spec.map(|s| s.inductance_mh));
    let step_angle_deg = pick(raw.step_angle_deg, spec.map(|s| s.step_angle_deg))
        .unwrap_or(defaults::STEP_ANGLE_DEG);
    Range::Positive.check("motors.step_angle_deg", step_angle_deg)?;
    // Figures given without what they serve are mistakes.
    if raw.rated_current_a.is_some() && raw.run_current_a.is_none() {
        return Err(Invalid::new(
            "motors.rated_current_a",
            "used only with `run_current_a`",
        ));
    }
    let electrical = [
        ("resistance_ohm", raw.resistance_ohm),
        ("inductance_mh", raw.inductance_mh),
    ];
    for (key, given) in electrical {
        if given.is_some() && raw.supply_voltage_v.is_none() {
            return Err(Invalid::new(
                format!("motors.{key}"),
                "used only with `supply_voltage_v` (the force falling with speed)",
            ));
        }
    }
    // The torque at standstill: the holding torque, scaled to the run current.
    let torque_nm = match raw.run_current_a {
        Some(run) => {
            let rated = rated.ok_or_else(|| {
                Invalid::new(
                    "motors.run_current_a",
                    "needs `rated_current_a` (or a `model`): the torque scales with run / rated",
                )
            })?;
            Range::Positive.check("motors.rated_current_a", rated)?;
            Range::Positive.check("motors.run_current_a", run)?;
            if run > rated {
                return Err(Invalid::new(
                    "motors.run_current_a",
                    format!(
                        "{run} A RMS is above the rated {rated} A: the torque would exceed \
                         the holding torque (the motor saturates)"
                    ),
                ));
            }
            holding_torque_nm * run / rated
        }
        None => holding_torque_nm,
    };
    let curve = match raw.supply_voltage_v {
        Some(v) => {
            let missing = |key: &str| {
                Invalid::new(
                    "motors.supply_voltage_v",
                    format!(
                        "needs `{key}`: the force against speed needs `run_current_a`, and \
                         `rated_current_a`, `resistance_ohm` and `inductance_mh` given or \
                         from a `model`"
                    ),
                )
            };
            let run = raw.run_current_a.ok_or_else(|| missing("run_current_a"))?;
            let rated = rated.ok_or_else(|| missing("rated_current_a"))?;
            let resistance = resistance.ok_or_else(|| missing("resistance_ohm"))?;
            let inductance = inductance.ok_or_else(|| missing("inductance_mh"))?;
            Range::Positive.check("motors.supply_voltage_v", v)?;
            Range::Positive.check("motors.resistance_ohm", resistance)?;
            Range::NonNegative.check("motors.inductance_mh", inductance)?;
            Some(StepperCurve::new(&StepperFigures {
                holding_torque_nm,
                rated_current_a: rated,
                run_current_a: run,
                resistance_ohm: resistance,
                inductance_mh: inductance,
                supply_voltage_v: v,
                step_angle_deg,
                pulley_radius_mm: radius_m * 1e3,
                safety_factor,
            }))
        }
        None => None,
    };
    let reflected_mass_kg = match raw.rotor_inertia_kg_m2 {
        Some(j) => {
            Range::NonNegative.check("motors.rotor_inertia_kg_m2", j)?;
            reflected_mass_kg(j, radius_m)
        }
        None => spec
            .and_then(|s| s.rotor_inertia_kg_m2)
            .map_or(0.0, |j| reflected_mass_kg(j, radius_m)),
    };
    Ok(Motors {
        // Below the knee the curve's force; it is less than torque / r / safety only when
        // the supply cannot drive the run current through the winding at standstill.
        max_force_n: curve.map_or(torque_nm / radius_m / safety_factor, |c| {
            c.plateau_force_n()
        }),
        reflected_mass_kg,
        curve,
        stiffness_n_m: Some(motor_stiffness_n_m(torque_nm, step_angle_deg, radius_m)),
        model: spec.map(|s| s.name),
    })
}
