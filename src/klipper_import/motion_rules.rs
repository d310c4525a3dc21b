//! Klipper's rules for the sections that shape the motion and the motors: `[gcode_arcs]`
//! (gcode_arcs.py), `[input_shaper]` (input_shaper.py, shaper_defs.py), the steppers'
//! `rotation_distance`, `gear_ratio` and `full_steps_per_rotation` (stepper.py
//! `parse_step_distance`) and the TMC drivers' `run_current` (tmc2130.py, tmc2208.py, …).

use super::ini::{Bound, Config, Section};
use super::writer::{ProfileKey, Value};
use super::{ImportError, ImportExtras, num};
use crate::machine::{SHAPER_NAMES, defaults};
use crate::motion::shaper::ShaperType;

/// `[gcode_arcs] resolution`; without the section a note: Klipper refuses G2/G3 then.
pub(super) fn gcode_arcs(
    cfg: &Config,
    notes: &mut Vec<String>,
) -> Result<Vec<ProfileKey>, ImportError> {
    let arcs = cfg.optional_section("gcode_arcs");
    if arcs.line == 0 {
        notes.push(
            "no [gcode_arcs]: Klipper refuses G2/G3 without it; the profile cuts arcs at the \
             default resolution"
                .into(),
        );
        return Ok(Vec::new());
    }
    Ok(vec![
        match arcs.optional_float(cfg, "resolution", Bound::Above(0.0))? {
            Some(f) => ProfileKey::number("gcode_arcs", "resolution", f.value, f.source("")),
            None => loader_default("gcode_arcs", "resolution"),
        },
    ])
}

/// `[input_shaper]` as input_shaper.py reads it (`InputShaperParams.__init__`): each
/// axis's type known to Klipper (plain names only), its damping ratio within 0 and the
/// type's maximum, its frequency ≥ 0. The keys given are written as they are.
pub(super) fn input_shaper(cfg: &Config) -> Result<Vec<ProfileKey>, ImportError> {
    let sec = cfg.optional_section("input_shaper");
    if sec.line == 0 {
        return Ok(Vec::new());
    }
    let mut keys = Vec::new();
    let type_of = |key: &'static str| -> Result<Option<(ShaperType, String)>, ImportError> {
        let Some(e) = sec.optional(key) else {
            return Ok(None);
        };
        let name = e.value.trim();
        let kind = ShaperType::from_name(name).filter(|k| k.name() == name);
        match kind {
            Some(k) => Ok(Some((
                k,
                format!("{} (line {})", sec.key_label(key), e.line),
            ))),
            None => Err(sec.bad_value(
                cfg,
                key,
                format!(
                    "`{name}` is not a shaper delta-gcode knows: Klipper's are {} (written \
                     without parameters)",
                    SHAPER_NAMES.join(", ")
                ),
            )),
        }
    };
    let common = type_of("shaper_type")?;
    if let Some((kind, source)) = &common {
        keys.push(ProfileKey::known(
            "input_shaper",
            "shaper_type",
            kind.name().into(),
            source,
        ));
    }
    for axis in ["x", "y"] {
        let (type_key, freq_key, damping_key) = match axis {
            "x" => ("shaper_type_x", "shaper_freq_x", "damping_ratio_x"),
            _ => ("shaper_type_y", "shaper_freq_y", "damping_ratio_y"),
        };
        let own = type_of(type_key)?;
        if let Some((kind, source)) = &own {
            keys.push(ProfileKey::known(
                "input_shaper",
                type_key,
                kind.name().into(),
                source,
            ));
        }
        // Klipper's default type, mzv.
        let default = ShaperType::from_name(defaults::SHAPER_TYPE).unwrap_or(ShaperType::Mzv);
        let kind = own.or(common.clone()).map_or(default, |(k, _)| k);
        let max = kind.max_damping_ratio();
        // Klipper reads the damping ratio, then the frequency.
        let damping = sec.optional_float(cfg, damping_key, Bound::AtLeast(0.0))?;
        if let Some(f) = damping.as_ref().filter(|f| f.value > max) {
            return Err(sec.bad_value(
                cfg,
                damping_key,
                format!(
                    "{} is above {max}, the most Klipper accepts for shaper `{}`",
                    num(f.value),
                    kind.name()
                ),
            ));
        }
        let freq = sec.optional_float(cfg, freq_key, Bound::AtLeast(0.0))?;
        for (key, f) in [(freq_key, freq), (damping_key, damping)] {
            if let Some(f) = f {
                keys.push(ProfileKey::number(
                    "input_shaper",
                    key,
                    f.value,
                    f.source(""),
                ));
            }
        }
    }
    if keys.is_empty() {
        keys.push(loader_default("input_shaper", "shaper_freq_x"));
    }
    Ok(keys)
}

/// The TMC drivers Klipper configures with `run_current` (klippy/extras/tmc*.py).
const TMC_DRIVERS: [&str; 6] = [
    "tmc2130", "tmc2208", "tmc2209", "tmc2240", "tmc2660", "tmc5160",
];

/// The motors' figures a Klipper configuration holds: tower A's belt travel per motor turn
/// (`rotation_distance` over `gear_ratio`), its step angle (`full_steps_per_rotation`) and
/// its driver's `run_current`. With `max_force_n` given they are written as comments (the
/// force form does not take them); without it, with the motor and the safety factor listed
/// as missing.
pub(super) fn motors(
    cfg: &Config,
    extra: &ImportExtras,
    notes: &mut Vec<String>,
) -> Result<Vec<ProfileKey>, ImportError> {
    let steppers = [
        cfg.section("stepper_a")?,
        cfg.optional_section("stepper_b"),
        cfg.optional_section("stepper_c"),
    ];
    let mut figures = Vec::new();
    if let Some((travel, source)) = belt_travel(cfg, steppers[0], notes)? {
        for s in &steppers[1..] {
            if let Some((other, _)) = belt_travel(cfg, s, &mut Vec::new())?
                && other != travel
            {
                notes.push(format!(
                    "[{}] moves {} mm per motor turn, tower A {}: the profile takes A's",
                    s.name(),
                    num(other),
                    num(travel)
                ));
            }
        }
        figures.push(ProfileKey::number(
            "motors",
            "rotation_distance_mm",
            travel,
            source,
        ));
    } else {
        notes.push(
            "[stepper_a] has no rotation_distance: the motor's pulley is not imported".into(),
        );
    }
    if let Some(f) =
        steppers[0].optional_float(cfg, "full_steps_per_rotation", Bound::AtLeast(1.0))?
    {
        if f.value.fract() != 0.0 || f.value % 4.0 != 0.0 {
            return Err(steppers[0].bad_value(
                cfg,
                "full_steps_per_rotation",
                format!("must be a whole multiple of 4, got {}", num(f.value)),
            ));
        }
        let source = format!("360 / {}", f.source(""));
        figures.push(ProfileKey::number(
            "motors",
            "step_angle_deg",
            360.0 / f.value,
            source,
        ));
    }
    let drivers = cfg.sections_where(|name| {
        TMC_DRIVERS
            .iter()
            .any(|d| name.strip_prefix(d) == Some(" stepper_a"))
    });
    if let Some(driver) = drivers.first()
        && let Some(f) = driver.optional_float(cfg, "run_current", Bound::Above(0.0))?
    {
        figures.push(ProfileKey::number(
            "motors",
            "run_current_a",
            f.value,
            format!("{}, A RMS", f.source("")),
        ));
    }
    if let Some(force) = extra.max_force_n {
        let mut keys = vec![super::rules::given_number(
            cfg,
            "motors",
            "max_force_n",
            force,
            "peak |Q_i| a carriage motor may deliver",
        )?];
        keys.extend(figures.into_iter().map(ProfileKey::commented));
        return Ok(keys);
    }
    figures.push(ProfileKey {
        section: "motors",
        key: "model",
        value: Value::Missing {
            what: "the carriage motor: a `model` of the motor table (docs/machine-profile.md), \
                   or its `holding_torque_nm` (and `rated_current_a` with run_current_a); or \
                   replace this section by `max_force_n` alone, a constant limit",
        },
    });
    figures.push(ProfileKey {
        section: "motors",
        key: "safety_factor",
        value: Value::Missing {
            what: "holding torque / allowed torque, >= 1 (1 with `supply_voltage_v`: the force \
                   against speed is then modelled)",
        },
    });
    Ok(figures)
}

/// A stepper's belt travel per motor turn, mm: `rotation_distance` divided by the product of
/// `gear_ratio`'s ratios (stepper.py `parse_gear_ratio`), and its source; None without
/// `rotation_distance`.
fn belt_travel(
    cfg: &Config,
    s: &Section,
    notes: &mut Vec<String>,
) -> Result<Option<(f64, String)>, ImportError> {
    let Some(rd) = s.optional_float(cfg, "rotation_distance", Bound::Above(0.0))? else {
        return Ok(None);
    };
    let Some(gear) = s.optional("gear_ratio") else {
        return Ok(Some((rd.value, rd.source(""))));
    };
    let mut ratio = 1.0;
    for pair in gear.value.split(',') {
        let parsed = pair.split_once(':').and_then(|(a, b)| {
            let (a, b) = (a.trim().parse::<f64>().ok()?, b.trim().parse::<f64>().ok()?);
            (a > 0.0 && b > 0.0 && a.is_finite() && b.is_finite()).then_some(a / b)
        });
        let Some(r) = parsed else {
            return Err(s.bad_value(
                cfg,
                "gear_ratio",
                format!(
                    "expected ratios like `80:16, 60:16`, found `{}`",
                    gear.value
                ),
            ));
        };
        ratio *= r;
    }
    notes.push(format!(
        "[{}] gear_ratio {}: the motor turns {} times per rotation_distance",
        s.name(),
        gear.value,
        num(ratio)
    ));
    Ok(Some((
        rd.value / ratio,
        format!(
            "{} / gear_ratio {} (line {})",
            rd.source(""),
            num(ratio),
            gear.line
        ),
    )))
}

/// A key the loader fills with Klipper's default.
fn loader_default(section: &'static str, key: &'static str) -> ProfileKey {
    ProfileKey {
        section,
        key,
        value: Value::LoaderDefault,
    }
}
