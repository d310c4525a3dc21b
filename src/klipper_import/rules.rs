//! Klipper's rules: which keys a linear delta's configuration must hold, the defaults and
//! bounds Klipper applies when it reads them, and the profile keys they become, each with
//! its source. The keys are read in the order Klipper reads them (toolhead limits, delta
//! geometry, extruder), so the first error reported is the one Klipper would report.

use super::ini::{Bound, Config, Figure, Section};
use super::writer::{ProfileKey, Value};
use super::{ImportError, ImportExtras, motion_rules, num};
use crate::machine::defaults;

/// The profile's keys from a parsed configuration and the figures Klipper does not hold
/// (`extra`), in the order they are written; remarks on the import go to `notes`.
pub(super) fn profile_keys(
    cfg: &Config,
    extra: &ImportExtras,
    notes: &mut Vec<String>,
) -> Result<Vec<ProfileKey>, ImportError> {
    let printer = cfg.section("printer")?;
    let kin = printer.required(cfg, "kinematics")?;
    if kin.value != "delta" {
        return Err(ImportError::NotDelta {
            origin: cfg.origin.clone(),
            line: kin.line,
            found: kin.value.clone(),
        });
    }
    let limits = limits(cfg, printer)?;
    let geometry = geometry(cfg, printer, notes)?;
    let extruder = cfg.optional_section("extruder");
    if extruder.line == 0 {
        notes.push("no [extruder] section; the profile's extruder defaults apply".into());
    }
    let masses = given(
        cfg,
        "masses",
        &[
            (
                "cart_kg",
                extra.cart_kg,
                "one carriage with its rollers/bearings and belt clamp",
            ),
            ("link_kg", extra.link_kg, "one of the six arms"),
            ("platform_kg", extra.platform_kg, "effector + hotend + fans"),
        ],
    )?;
    let extruder = extruder_keys(cfg, extruder, notes)?;
    let motors = motion_rules::motors(cfg, extra, notes)?;
    let arcs = motion_rules::gcode_arcs(cfg, notes)?;
    let shaper = motion_rules::input_shaper(cfg)?;
    let sampling = vec![ProfileKey::number(
        "sampling",
        "period_s",
        defaults::SAMPLING_PERIOD_S,
        "delta-gcode default",
    )];
    Ok([
        geometry, masses, limits, extruder, motors, arcs, shaper, sampling,
    ]
    .into_iter()
    .flatten()
    .collect())
}

/// `[printer]`'s toolhead limits: max_velocity and max_accel (toolhead.py `ToolHead.__init__`,
/// required), square_corner_velocity and minimum_cruise_ratio (same, with defaults),
/// max_z_velocity and max_z_accel (delta.py `DeltaKinematics.__init__`: default and maximum
/// max_velocity, max_accel).
fn limits(cfg: &Config, printer: &Section) -> Result<Vec<ProfileKey>, ImportError> {
    let max_velocity = printer.float(cfg, "max_velocity", None, Bound::Above(0.0))?;
    let max_accel = printer.float(cfg, "max_accel", None, Bound::Above(0.0))?;
    // delta.py: default and maximum, the toolhead's limit.
    let at_most = |key, limit: &Figure| {
        printer.float(
            cfg,
            key,
            Some(limit.value),
            Bound::AboveAtMost(0.0, limit.value),
        )
    };
    let max_z_velocity = at_most("max_z_velocity", &max_velocity)?;
    let max_z_accel = at_most("max_z_accel", &max_accel)?;
    let scv = printer.float(
        cfg,
        "square_corner_velocity",
        Some(defaults::SQUARE_CORNER_VELOCITY_MM_S),
        Bound::AtLeast(0.0),
    )?;
    let (mcr, mcr_source) = minimum_cruise_ratio(cfg, printer, max_accel.value)?;
    let read =
        |key, f: &Figure, default| ProfileKey::number("limits", key, f.value, f.source(default));
    Ok(vec![
        read("max_velocity_mm_s", &max_velocity, ""),
        read("max_accel_mm_s2", &max_accel, ""),
        read("square_corner_velocity_mm_s", &scv, "Klipper default"),
        ProfileKey::number("limits", "minimum_cruise_ratio", mcr, mcr_source),
        read(
            "max_z_velocity_mm_s",
            &max_z_velocity,
            "Klipper default = max_velocity",
        ),
        read(
            "max_z_accel_mm_s2",
            &max_z_accel,
            "Klipper default = max_accel",
        ),
        ProfileKey::known(
            "limits",
            "edge_slowdown",
            "true".into(),
            "Klipper's delta always slows moves near the edge",
        ),
    ])
}

/// `[printer] minimum_cruise_ratio` as toolhead.py `ToolHead.__init__` reads it: given;
/// else from the deprecated `max_accel_to_decel` (1 − min(1, a2d/max_accel)); else the
/// default. Returns the ratio and its source.
fn minimum_cruise_ratio(
    cfg: &Config,
    printer: &Section,
    max_accel: f64,
) -> Result<(f64, String), ImportError> {
    if let Some(f) =
        printer.optional_float(cfg, "minimum_cruise_ratio", Bound::AtLeastBelow(0.0, 1.0))?
    {
        return Ok((f.value, f.source("")));
    }
    if let Some(f) = printer.optional_float(cfg, "max_accel_to_decel", Bound::Above(0.0))? {
        let mcr = 1.0 - (f.value / max_accel).min(1.0);
        return Ok((
            mcr,
            format!(
                "1 - max_accel_to_decel/max_accel, from the deprecated [printer] max_accel_to_decel (line {})",
                f.line.unwrap_or(0)
            ),
        ));
    }
    Ok((defaults::MINIMUM_CRUISE_RATIO, "Klipper default".into()))
}

/// The delta's geometry as delta.py `DeltaKinematics.__init__` reads it: `[printer]`
/// delta_radius and print_radius (default delta_radius), `[stepper_a..c]` arm_length and
/// position_endstop (B and C default to A's) and angle. Klipper's build height is the
/// lowest endstop (`max_z`), and its print radius is at most its reach
/// ([`defaults::klipper_reach_mm`]).
fn geometry(
    cfg: &Config,
    printer: &Section,
    notes: &mut Vec<String>,
) -> Result<Vec<ProfileKey>, ImportError> {
    let radius = printer.float(cfg, "delta_radius", None, Bound::Above(0.0))?;
    let print_radius = printer.float(cfg, "print_radius", Some(radius.value), Bound::Above(0.0))?;
    let steppers = [
        cfg.section("stepper_a")?,
        cfg.optional_section("stepper_b"),
        cfg.optional_section("stepper_c"),
    ];
    let arm_bound = Bound::Above(radius.value);
    let arm_a = steppers[0].float(cfg, "arm_length", None, arm_bound)?;
    let endstop_a = steppers[0].float(cfg, "position_endstop", None, Bound::Any)?;
    let mut arms = [arm_a.value; 3];
    let mut endstops = [endstop_a.value; 3];
    let mut angles = defaults::TOWER_ANGLES_DEG;
    for (i, s) in steppers.iter().enumerate() {
        if i > 0 {
            arms[i] = s
                .float(cfg, "arm_length", Some(arm_a.value), arm_bound)?
                .value;
            endstops[i] = s
                .float(cfg, "position_endstop", Some(endstop_a.value), Bound::Any)?
                .value;
        }
        angles[i] = s.float(cfg, "angle", Some(angles[i]), Bound::Any)?.value;
    }
    // The nozzle reaches the lowest endstop at x = y = 0 only when all endstops agree.
    let home_z = endstops.iter().copied().fold(f64::INFINITY, f64::min);
    if endstops.iter().any(|&e| e != home_z) {
        notes.push(format!(
            "position_endstop differs per tower ({}, {}, {}); home_z_mm is the lowest, Klipper's maximum build height",
            num(endstops[0]),
            num(endstops[1]),
            num(endstops[2])
        ));
    }
    let min_arm = arms.iter().copied().fold(f64::INFINITY, f64::min);
    let reach = defaults::klipper_reach_mm(min_arm, radius.value);
    if reach <= 0.0 {
        return Err(ImportError::BadValue {
            origin: cfg.origin.clone(),
            line: radius.line.unwrap_or(printer.line),
            section: "printer".into(),
            key: "delta_radius".into(),
            message: format!(
                "arms of {} mm reach no build area at delta_radius {}",
                num(min_arm),
                num(radius.value)
            ),
        });
    }
    // Rounded down to 0.01 mm, so it stays inside Klipper's limit.
    let print_radius_mm = print_radius.value.min((reach * 100.0).floor() / 100.0);
    let mut print_radius_source = print_radius.source("Klipper default = delta_radius");
    if print_radius_mm < print_radius.value {
        notes.push(format!(
            "print_radius {} clamped to {} mm, the radius where Klipper's delta stops moves (a carriage {}x faster than the nozzle)",
            num(print_radius.value),
            num(print_radius_mm),
            defaults::REACH_RATIO
        ));
        print_radius_source.push_str("; clamped to Klipper's reach limit");
    }
    let arm_length = if arms.iter().all(|&a| a == arm_a.value) {
        ProfileKey::number("geometry", "arm_length_mm", arm_a.value, arm_a.source(""))
    } else {
        ProfileKey::towers(
            "geometry",
            "arm_length_mm",
            arms,
            "[stepper_a..c] arm_length (B, C default to A)",
        )
    };
    let [a, b, c] = defaults::TOWER_ANGLES_DEG;
    Ok(vec![
        ProfileKey::number(
            "geometry",
            "delta_radius_mm",
            radius.value,
            radius.source(""),
        ),
        arm_length,
        ProfileKey::number(
            "geometry",
            "nozzle_offset_mm",
            0.0,
            "Klipper has none: its kinematics put the arm joints' plane at the nozzle",
        ),
        ProfileKey::towers(
            "geometry",
            "tower_angles_deg",
            angles,
            format!("[stepper_a..c] angle (Klipper defaults {a}, {b}, {c})"),
        ),
        ProfileKey::number(
            "geometry",
            "home_z_mm",
            home_z,
            "lowest [stepper_a..c] position_endstop (Klipper's max_z)",
        ),
        ProfileKey::number(
            "geometry",
            "print_radius_mm",
            print_radius_mm,
            print_radius_source,
        ),
    ])
}

/// `[extruder]` as extruder.py `PrinterExtruder.__init__` reads it: nozzle_diameter and
/// filament_diameter (required by Klipper; a trimmed configuration without them gets the
/// usual 0.4 and 1.75 mm, with a note); the extrude-only limits and
/// instantaneous_corner_velocity written when set, else left to the loader, which applies
/// Klipper's defaults. No keys when the section is absent.
fn extruder_keys(
    cfg: &Config,
    extruder: &Section,
    notes: &mut Vec<String>,
) -> Result<Vec<ProfileKey>, ImportError> {
    if extruder.line == 0 {
        return Ok(Vec::new());
    }
    let mut keys = Vec::new();
    for (key, out, usual) in [
        (
            "nozzle_diameter",
            "nozzle_diameter_mm",
            defaults::NOZZLE_DIAMETER_MM,
        ),
        (
            "filament_diameter",
            "filament_diameter_mm",
            defaults::FILAMENT_DIAMETER_MM,
        ),
    ] {
        keys.push(
            match extruder.optional_float(cfg, key, Bound::Above(0.0))? {
                Some(f) => ProfileKey::number("extruder", out, f.value, f.source("")),
                None => {
                    notes.push(format!(
                        "[extruder] has no {key} (Klipper requires it): the usual {} mm is taken",
                        num(usual)
                    ));
                    ProfileKey::number(
                        "extruder",
                        out,
                        usual,
                        format!("not in [extruder]: the usual {} mm", num(usual)),
                    )
                }
            },
        );
    }
    for (key, out, bound) in [
        (
            "max_extrude_only_velocity",
            "max_extrude_only_velocity_mm_s",
            Bound::Above(0.0),
        ),
        (
            "max_extrude_only_accel",
            "max_extrude_only_accel_mm_s2",
            Bound::Above(0.0),
        ),
        (
            "instantaneous_corner_velocity",
            "instantaneous_corner_velocity_mm_s",
            Bound::AtLeast(0.0),
        ),
    ] {
        keys.push(match extruder.optional_float(cfg, key, bound)? {
            Some(f) => ProfileKey::number("extruder", out, f.value, f.source("")),
            None => ProfileKey {
                section: "extruder",
                key: out,
                value: Value::LoaderDefault,
            },
        });
    }
    Ok(keys)
}

/// A section of figures Klipper does not know, `(key, value given to the importer, what it
/// is)`: each given one must be a positive number; the others are missing.
fn given(
    cfg: &Config,
    section: &'static str,
    keys: &[(&'static str, Option<f64>, &'static str)],
) -> Result<Vec<ProfileKey>, ImportError> {
    keys.iter()
        .map(|&(key, value, what)| match value {
            Some(x) => given_number(cfg, section, key, x, what),
            None => Ok(ProfileKey {
                section,
                key,
                value: Value::Missing { what },
            }),
        })
        .collect()
}

/// A figure given to the importer (`what` it is): a positive number.
pub(super) fn given_number(
    cfg: &Config,
    section: &'static str,
    key: &'static str,
    x: f64,
    what: &'static str,
) -> Result<ProfileKey, ImportError> {
    if !(x.is_finite() && x > 0.0) {
        return Err(ImportError::BadExtra {
            origin: cfg.origin.clone(),
            what: format!("{section}.{key}"),
            message: format!("must be a positive number, got {x}"),
        });
    }
    Ok(ProfileKey::number(
        section,
        key,
        x,
        format!("{what}; given to the importer, not in the Klipper config"),
    ))
}
