//! The machine profile (YAML, see docs/machine-profile.md), resolved: every default filled,
//! every figure checked. The rest of the program reads only this resolved form.
//!
//! The way in: [`Machine::from_yaml_str`] parses the text into the raw form of `schema`,
//! whose `resolve` fills the defaults of `defaults`, turns the motor's figures (or a motor
//! of `motor_table`) into a force (`motor`), and reads the Klipper sections (`klipper`),
//! the firmware (`marlin`) and the drive (`drive`); `validate` checks every figure; a
//! profile without `drive` then gets the physical default (`drive`); `location` gives each
//! error its file, line and column.

pub mod defaults;
mod drive;
mod klipper;
mod location;
mod marlin;
mod motor;
pub mod motor_table;
mod schema;
#[cfg(test)]
pub(crate) mod test_support;
#[cfg(test)]
mod tests;
#[cfg(test)]
mod tests_keys;
mod validate;

use crate::gcode::{ArcRules, DeltaSettings, Dialect, FirmwareKind, SoftEndstops};
use crate::motion::drive::Drive;
use crate::motion::shaper::InputShaper;
use std::path::Path;

use crate::delta::{self, DeltaModel};

pub use drive::{DefaultDrive, typical_motor_stiffness_n_m};
pub use klipper::SHAPER_NAMES;
pub use marlin::{Firmware, Marlin};
pub use motor::{motor_stiffness_n_m, pulley_pitch_radius_m};

/// Delta geometry, mm and degrees.
#[derive(Clone, Debug, PartialEq)]
pub struct Geometry {
    /// Horizontal distance from the Z axis to a tower's carriage joint line, less the
    /// effector's joint offset: (s_B − s_P)/√3 in the paper.
    pub delta_radius_mm: f64,
    /// Arm length l per tower (A, B, C).
    pub arm_length_mm: [f64; 3],
    /// PQ: nozzle tip below the platform centre P.
    pub nozzle_offset_mm: f64,
    /// Tower angles (A, B, C); the paper's 210°, 330°, 90° by default.
    pub tower_angles_deg: [f64; 3],
    /// Nozzle z after G28 at x = y = 0.
    pub home_z_mm: f64,
    pub print_radius_mm: f64,
    /// Magnetic ball joints: the pull at which one parallelogram's joints let go (both
    /// rods together), N. None: the arms do not come off.
    pub arm_magnet_hold_n: Option<f64>,
}

/// Lumped masses of Fig. 2, kg.
#[derive(Clone, Debug, PartialEq)]
pub struct Masses {
    pub cart_kg: f64,
    /// Each of the six arms.
    pub link_kg: f64,
    /// Effector + hotend.
    pub platform_kg: f64,
}

/// Klipper's toolhead limits.
#[derive(Clone, Debug, PartialEq)]
pub struct Limits {
    pub max_velocity_mm_s: f64,
    pub max_accel_mm_s2: f64,
    pub square_corner_velocity_mm_s: f64,
    pub minimum_cruise_ratio: f64,
    /// Klipper before 2024 (v0.12 and older): its `max_accel_to_decel`, mm/s², used
    /// instead of `minimum_cruise_ratio` and kept when ACCEL changes; None for Klipper since.
    pub max_accel_to_decel_mm_s2: Option<f64>,
    pub max_z_velocity_mm_s: f64,
    pub max_z_accel_mm_s2: f64,
    /// Klipper's delta edge limits (half / quarter speed near the edge).
    pub edge_slowdown: bool,
}

/// Klipper's extruder limits (klippy/kinematics/extruder.py), defaults resolved.
#[derive(Clone, Debug, PartialEq)]
pub struct Extruder {
    pub nozzle_diameter_mm: f64,
    pub filament_diameter_mm: f64,
    pub max_extrude_only_velocity_mm_s: f64,
    pub max_extrude_only_accel_mm_s2: f64,
    pub instantaneous_corner_velocity_mm_s: f64,
}

/// The carriage motors, resolved: the force limit and the rotor seen at the belt.
#[derive(Clone, Debug, PartialEq)]
pub struct Motors {
    /// Allowed peak |Q_i| per carriage at low speed, N: given, or the torque at standstill
    /// (the holding torque, scaled to the run current when given) / pulley pitch radius /
    /// safety factor; with a curve, the curve's force below its knee.
    pub max_force_n: f64,
    /// The rotor's inertia reflected to the carriage, J/r² (r the pulley pitch radius), kg;
    /// 0 without a rotor inertia (given, or the model's). It adds to the carriage's
    /// inertia, not to its weight.
    pub reflected_mass_kg: f64,
    /// The force against carriage speed, when the electrical figures are given; None: the
    /// force is `max_force_n` at any speed.
    pub curve: Option<crate::motor::StepperCurve>,
    /// The motor's magnetic stiffness at the carriage, T·N_r/r², N/m (the torque form);
    /// None in the `max_force_n` form.
    pub stiffness_n_m: Option<f64>,
    /// The motor table's name of the motor (`motors.model`).
    pub model: Option<&'static str>,
}

impl Motors {
    /// The force a motor can give its carriage at `carriage_speed_mm_s` (either sign), N:
    /// the curve's, or `max_force_n` at any speed.
    #[inline]
    pub fn available_force_n(&self, carriage_speed_mm_s: f64) -> f64 {
        match &self.curve {
            Some(c) => c.available_force_n(carriage_speed_mm_s),
            None => self.max_force_n,
        }
    }
}

#[derive(Clone, Debug, PartialEq)]
pub struct Sampling {
    /// Ts, s.
    pub period_s: f64,
}

/// A resolved machine profile.
#[derive(Clone, Debug, PartialEq)]
pub struct Machine {
    pub name: String,
    pub geometry: Geometry,
    pub masses: Masses,
    pub limits: Limits,
    pub extruder: Extruder,
    pub motors: Motors,
    pub sampling: Sampling,
    pub gravity_m_s2: f64,
    /// How G2/G3 are cut into chords (Klipper's `[gcode_arcs]`).
    pub arc_rules: ArcRules,
    /// Klipper's `[input_shaper]`.
    pub input_shaper: InputShaper,
    /// How the nozzle follows the commanded motion: the profile's `drive`, or the physical
    /// default ([`Machine::default_drive`]).
    pub drive: Drive,
    /// How the default drive was found; None when the profile gives `drive`.
    pub drive_default: Option<DefaultDrive>,
    /// The firmware whose planner the moves follow, with Marlin's settings.
    pub firmware: Firmware,
}

/// Why a machine profile cannot be used. The message names the file, the line and column
/// (when the YAML gives one), the key and what was expected.
#[derive(Debug, thiserror::Error)]
pub enum ProfileError {
    #[error("{origin}: cannot read the machine profile: {error}")]
    Io {
        origin: String,
        error: std::io::Error,
    },
    /// The YAML does not match the schema (syntax, unknown key, wrong type, missing key).
    #[error("{origin}{}: {message}", fmt_location(*.location))]
    Schema {
        origin: String,
        /// 1-based line and column.
        location: Option<(usize, usize)>,
        message: String,
    },
    /// The profile parses but describes an impossible machine.
    #[error("{origin}{}: {key}: {message}", fmt_location(*.location))]
    Invalid {
        origin: String,
        location: Option<(usize, usize)>,
        /// Dotted key, e.g. `geometry.arm_length_mm`.
        key: String,
        message: String,
    },
}

fn fmt_location(location: Option<(usize, usize)>) -> String {
    location.map_or_else(String::new, |(l, c)| format!(":{l}:{c}"))
}

impl Machine {
    /// Reads and resolves a profile file.
    pub fn load(path: &Path) -> Result<Machine, ProfileError> {
        let origin = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|error| ProfileError::Io {
            origin: origin.clone(),
            error,
        })?;
        Machine::from_yaml_str(&text, &origin)
    }

    /// Parses and resolves a profile; `origin` names it in error messages.
    pub fn from_yaml_str(text: &str, origin: &str) -> Result<Machine, ProfileError> {
        let raw: schema::RawMachine =
            yaml_serde::from_str(text).map_err(|e| location::schema_error(&e, origin))?;
        let machine = raw.resolve().and_then(|(mut m, drive_given)| {
            validate::check(&m)?;
            if !drive_given {
                let d = m.default_drive().map_err(|e| {
                    Invalid::new(
                        "drive",
                        format!("no `drive` given, and its default cannot be derived: {e}"),
                    )
                })?;
                m.drive = Drive::Spring(d.spring);
                m.drive_default = Some(d);
            }
            Ok(m)
        });
        machine.map_err(|Invalid { key, message }| ProfileError::Invalid {
            origin: origin.to_string(),
            location: location::locate_key(text, &key),
            key,
            message,
        })
    }

    /// The dynamic model of this machine's robot (the paper's, eq. 2-20).
    pub fn model(&self) -> DeltaModel {
        let g = &self.geometry;
        let m = &self.masses;
        DeltaModel::new(
            &delta::Geometry {
                delta_radius_mm: g.delta_radius_mm,
                arm_length_mm: g.arm_length_mm,
                nozzle_offset_mm: g.nozzle_offset_mm,
                tower_angles_deg: g.tower_angles_deg,
                home_z_mm: g.home_z_mm,
            },
            &delta::Masses {
                cart_kg: m.cart_kg,
                link_kg: m.link_kg,
                platform_kg: m.platform_kg,
                rotor_reflected_kg: self.motors.reflected_mass_kg,
            },
            self.gravity_m_s2,
        )
    }

    /// How the interpreter reads G-code for this machine: Klipper's dialect with the
    /// profile's `gcode_arcs`, or Marlin's with its `ARC_SUPPORT` settings and its soft
    /// endstops (the printable radius, Z up to the home height).
    pub fn dialect(&self) -> Dialect {
        match &self.firmware {
            Firmware::Klipper => Dialect::klipper(self.arc_rules),
            Firmware::Marlin(m) => Dialect {
                firmware: FirmwareKind::Marlin,
                arcs: m.arc_rules(),
                soft_endstops: Some(SoftEndstops {
                    radius_mm: self.geometry.print_radius_mm,
                    max_z_mm: self.geometry.home_z_mm,
                }),
                delta: Some(self.delta_settings()),
            },
        }
    }

    /// The geometry as Marlin's M665 states it: L + trim per tower, R, angle trims.
    fn delta_settings(&self) -> DeltaSettings {
        let g = &self.geometry;
        DeltaSettings {
            rod_mm: g.arm_length_mm,
            radius_mm: g.delta_radius_mm,
            angle_trim_deg: std::array::from_fn(|i| {
                g.tower_angles_deg[i] - defaults::TOWER_ANGLES_DEG[i]
            }),
        }
    }

    /// Klipper's delta edge limit ([`defaults::edge_radius_mm`], with the shortest arm): the
    /// nozzle radius beyond which some carriage can move `ratio` times faster than the
    /// nozzle. Klipper halves speed beyond [`defaults::SLOW_RATIO`] and quarters it beyond
    /// twice that.
    pub fn slow_radius_mm(&self, ratio: f64) -> f64 {
        let g = &self.geometry;
        let min_arm = g
            .arm_length_mm
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min);
        defaults::edge_radius_mm(ratio, min_arm, g.delta_radius_mm)
    }
}

/// A profile that parses but describes an impossible machine: the dotted key (e.g.
/// `geometry.arm_length_mm`) and what is wrong. [`Machine::from_yaml_str`] adds the file and
/// the key's line to make a [`ProfileError::Invalid`].
struct Invalid {
    key: String,
    message: String,
}

impl Invalid {
    fn new(key: impl Into<String>, message: impl Into<String>) -> Invalid {
        Invalid {
            key: key.into(),
            message: message.into(),
        }
    }
}
