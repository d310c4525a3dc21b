//! The profile as written (docs/machine-profile.md): serde's raw form, before defaults, and
//! [`RawMachine::resolve`], which fills the defaults of [`super::defaults`], picks the
//! geometry form and hands the motors to [`motor::resolve`]. Unknown keys are errors. The
//! struct names show in the parser's messages ("expected struct RawMasses").

use crate::motion::drive::Drive;
use serde::Deserialize;

use super::drive::RawDrive;
use super::klipper::{RawGcodeArcs, RawInputShaper};
use super::marlin::{FirmwareName, Marlin};
use super::{
    Extruder, Geometry, Invalid, Limits, Machine, Masses, Sampling, defaults, marlin, motor,
};

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawMachine {
    name: String,
    geometry: RawGeometry,
    masses: RawMasses,
    limits: RawLimits,
    #[serde(default)]
    extruder: RawExtruder,
    motors: RawMotors,
    #[serde(default)]
    sampling: RawSampling,
    #[serde(default = "gravity")]
    gravity_m_s2: f64,
    #[serde(default)]
    firmware: FirmwareName,
    marlin: Option<Marlin>,
    #[serde(default)]
    gcode_arcs: RawGcodeArcs,
    #[serde(default)]
    input_shaper: RawInputShaper,
    drive: Option<RawDrive>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawGeometry {
    delta_radius_mm: Option<f64>,
    base_side_mm: Option<f64>,
    platform_side_mm: Option<f64>,
    arm_length_mm: ArmLength,
    #[serde(default)]
    nozzle_offset_mm: f64,
    #[serde(default = "tower_angles")]
    tower_angles_deg: [f64; 3],
    home_z_mm: f64,
    print_radius_mm: f64,
    arm_magnet_hold_n: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawMasses {
    cart_kg: f64,
    link_kg: f64,
    platform_kg: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawLimits {
    max_velocity_mm_s: f64,
    max_accel_mm_s2: f64,
    #[serde(default = "square_corner_velocity")]
    square_corner_velocity_mm_s: f64,
    #[serde(default = "minimum_cruise_ratio")]
    minimum_cruise_ratio: f64,
    max_accel_to_decel_mm_s2: Option<f64>,
    /// Klipper's default: `max_velocity_mm_s`.
    max_z_velocity_mm_s: Option<f64>,
    /// Klipper's default: `max_accel_mm_s2`.
    max_z_accel_mm_s2: Option<f64>,
    /// Klipper's delta always slows moves near the edge.
    #[serde(default = "yes")]
    edge_slowdown: bool,
}

/// Every key optional: a missing one takes its value from [`RawExtruder::default`].
#[derive(Deserialize)]
#[serde(deny_unknown_fields, default)]
struct RawExtruder {
    nozzle_diameter_mm: f64,
    filament_diameter_mm: f64,
    /// Klipper's default: `max_velocity_mm_s` × [`defaults::extrude_only_ratio`].
    max_extrude_only_velocity_mm_s: Option<f64>,
    /// Klipper's default: `max_accel_mm_s2` × [`defaults::extrude_only_ratio`].
    max_extrude_only_accel_mm_s2: Option<f64>,
    instantaneous_corner_velocity_mm_s: f64,
}

impl Default for RawExtruder {
    fn default() -> Self {
        RawExtruder {
            nozzle_diameter_mm: defaults::NOZZLE_DIAMETER_MM,
            filament_diameter_mm: defaults::FILAMENT_DIAMETER_MM,
            max_extrude_only_velocity_mm_s: None,
            max_extrude_only_accel_mm_s2: None,
            instantaneous_corner_velocity_mm_s: defaults::INSTANTANEOUS_CORNER_VELOCITY_MM_S,
        }
    }
}

/// Either form of docs/machine-profile.md, `motors`; [`motor::resolve`] tells them apart.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawMotors {
    pub(super) max_force_n: Option<f64>,
    /// A motor of the table ([`super::motor_table`]): its figures, unless given here.
    pub(super) model: Option<String>,
    pub(super) holding_torque_nm: Option<f64>,
    pub(super) rated_current_a: Option<f64>,
    /// A RMS (Klipper's `run_current`).
    pub(super) run_current_a: Option<f64>,
    pub(super) resistance_ohm: Option<f64>,
    pub(super) inductance_mh: Option<f64>,
    pub(super) supply_voltage_v: Option<f64>,
    /// Default: [`defaults::STEP_ANGLE_DEG`].
    pub(super) step_angle_deg: Option<f64>,
    pub(super) pulley_teeth: Option<u32>,
    /// Default: [`defaults::BELT_PITCH_MM`] (GT2).
    pub(super) belt_pitch_mm: Option<f64>,
    /// Klipper's `rotation_distance`: belt travel per motor turn, instead of the pulley.
    pub(super) rotation_distance_mm: Option<f64>,
    pub(super) safety_factor: Option<f64>,
    pub(super) rotor_inertia_kg_m2: Option<f64>,
}

impl RawMotors {
    /// The keys only the torque form takes, each with whether the profile gives it.
    pub(super) fn torque_form_keys(&self) -> [(&'static str, bool); 6] {
        [
            ("rated_current_a", self.rated_current_a.is_some()),
            ("run_current_a", self.run_current_a.is_some()),
            ("resistance_ohm", self.resistance_ohm.is_some()),
            ("inductance_mh", self.inductance_mh.is_some()),
            ("supply_voltage_v", self.supply_voltage_v.is_some()),
            ("step_angle_deg", self.step_angle_deg.is_some()),
        ]
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, default)]
struct RawSampling {
    period_s: f64,
}

impl Default for RawSampling {
    fn default() -> Self {
        RawSampling {
            period_s: defaults::SAMPLING_PERIOD_S,
        }
    }
}

// serde's `default = "…"` names a function: these give the constants of `defaults`.
fn gravity() -> f64 {
    defaults::GRAVITY_M_S2
}
fn tower_angles() -> [f64; 3] {
    defaults::TOWER_ANGLES_DEG
}
fn square_corner_velocity() -> f64 {
    defaults::SQUARE_CORNER_VELOCITY_MM_S
}
fn minimum_cruise_ratio() -> f64 {
    defaults::MINIMUM_CRUISE_RATIO
}
fn yes() -> bool {
    true
}

/// `arm_length_mm`: one length for all towers or a list of three.
struct ArmLength([f64; 3]);

impl<'de> Deserialize<'de> for ArmLength {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = ArmLength;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a length in mm or a list of 3 lengths (towers A, B, C)")
            }
            fn visit_f64<E: serde::de::Error>(self, v: f64) -> Result<ArmLength, E> {
                Ok(ArmLength([v; 3]))
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<ArmLength, E> {
                self.visit_f64(v as f64)
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<ArmLength, E> {
                self.visit_f64(v as f64)
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(
                self,
                mut s: A,
            ) -> Result<ArmLength, A::Error> {
                let mut out = [0.0; 3];
                for (i, slot) in out.iter_mut().enumerate() {
                    *slot = s
                        .next_element()?
                        .ok_or_else(|| serde::de::Error::invalid_length(i, &self))?;
                }
                if s.next_element::<f64>()?.is_some() {
                    return Err(serde::de::Error::invalid_length(4, &self));
                }
                Ok(ArmLength(out))
            }
        }
        d.deserialize_any(V)
    }
}

impl RawGeometry {
    /// The paper's two geometry forms: `delta_radius_mm`, or the sides of the base and
    /// platform triangles, radius = (s_B − s_P)/√3.
    fn delta_radius_mm(&self) -> Result<f64, Invalid> {
        match (
            self.delta_radius_mm,
            self.base_side_mm,
            self.platform_side_mm,
        ) {
            (Some(r), None, None) => Ok(r),
            (None, Some(sb), Some(sp)) => Ok((sb - sp) / 3f64.sqrt()),
            (None, None, None) => Err(Invalid::new(
                "geometry",
                "expected `delta_radius_mm` or `base_side_mm` + `platform_side_mm`",
            )),
            _ => Err(Invalid::new(
                "geometry",
                "expected either `delta_radius_mm` alone or `base_side_mm` together with \
                 `platform_side_mm`, not a mix",
            )),
        }
    }
}

impl RawMachine {
    /// Fills every default; on a bad geometry or motor form returns the key and what is
    /// wrong. The figures are validated after, on the resolved machine. Without `drive`
    /// the machine's drive is rigid here and `false` is returned: the physical default
    /// ([`Machine::default_drive`]) needs the validated geometry.
    pub(super) fn resolve(self) -> Result<(Machine, bool), Invalid> {
        let g = self.geometry;
        let l = self.limits;
        let e = self.extruder;
        let extrude_ratio =
            defaults::extrude_only_ratio(e.nozzle_diameter_mm, e.filament_diameter_mm);
        let drive = self.drive.as_ref().map(RawDrive::resolve).transpose()?;
        let machine = Machine {
            name: self.name,
            geometry: Geometry {
                delta_radius_mm: g.delta_radius_mm()?,
                arm_length_mm: g.arm_length_mm.0,
                nozzle_offset_mm: g.nozzle_offset_mm,
                tower_angles_deg: g.tower_angles_deg,
                home_z_mm: g.home_z_mm,
                print_radius_mm: g.print_radius_mm,
                arm_magnet_hold_n: g.arm_magnet_hold_n,
            },
            masses: Masses {
                cart_kg: self.masses.cart_kg,
                link_kg: self.masses.link_kg,
                platform_kg: self.masses.platform_kg,
            },
            limits: Limits {
                max_velocity_mm_s: l.max_velocity_mm_s,
                max_accel_mm_s2: l.max_accel_mm_s2,
                square_corner_velocity_mm_s: l.square_corner_velocity_mm_s,
                minimum_cruise_ratio: l.minimum_cruise_ratio,
                max_accel_to_decel_mm_s2: l.max_accel_to_decel_mm_s2,
                max_z_velocity_mm_s: l.max_z_velocity_mm_s.unwrap_or(l.max_velocity_mm_s),
                max_z_accel_mm_s2: l.max_z_accel_mm_s2.unwrap_or(l.max_accel_mm_s2),
                edge_slowdown: l.edge_slowdown,
            },
            extruder: Extruder {
                nozzle_diameter_mm: e.nozzle_diameter_mm,
                filament_diameter_mm: e.filament_diameter_mm,
                max_extrude_only_velocity_mm_s: e
                    .max_extrude_only_velocity_mm_s
                    .unwrap_or(l.max_velocity_mm_s * extrude_ratio),
                max_extrude_only_accel_mm_s2: e
                    .max_extrude_only_accel_mm_s2
                    .unwrap_or(l.max_accel_mm_s2 * extrude_ratio),
                instantaneous_corner_velocity_mm_s: e.instantaneous_corner_velocity_mm_s,
            },
            motors: motor::resolve(&self.motors)?,
            sampling: Sampling {
                period_s: self.sampling.period_s,
            },
            gravity_m_s2: self.gravity_m_s2,
            firmware: marlin::resolve(self.firmware, self.marlin)?,
            arc_rules: self.gcode_arcs.resolve()?,
            input_shaper: self.input_shaper.resolve()?,
            drive: drive.unwrap_or(Drive::Rigid),
            drive_default: None,
        };
        Ok((machine, drive.is_some()))
    }
}
