//! The machine profile (YAML, see docs/machine-profile.md), resolved: every default filled,
//! every figure checked. The rest of the program reads only this resolved form.

use std::path::Path;

use serde::Deserialize;

use crate::delta::{self, DeltaModel, TOWER_NAMES};
use crate::path::Vec3;

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
    /// Allowed peak |Q_i| per carriage, N: given, or holding torque / pulley pitch radius /
    /// safety factor.
    pub max_force_n: f64,
    /// The rotor's inertia reflected to the carriage, J/r² (r the pulley pitch radius), kg;
    /// 0 when no `rotor_inertia_kg_m2` is given. It adds to the carriage's inertia, not to
    /// its weight.
    pub reflected_mass_kg: f64,
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
        let raw: RawMachine = yaml_serde::from_str(text).map_err(|e| schema_error(&e, origin))?;
        let machine = raw.resolve().and_then(|m| m.validate().map(|()| m));
        machine.map_err(|(key, message)| ProfileError::Invalid {
            origin: origin.to_string(),
            location: locate_key(text, &key),
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

    /// Klipper's delta edge limit (`kinematics/delta.py`, `ratio_to_xy` with
    /// half_min_step_dist = 0): the nozzle radius beyond which some carriage can move
    /// `ratio` times faster than the nozzle, ratio·√(l²/(ratio²+1)) − delta_radius, with the
    /// shortest arm. Klipper halves speed beyond ratio 3 and quarters it beyond ratio 6.
    pub fn slow_radius_mm(&self, ratio: f64) -> f64 {
        let g = &self.geometry;
        let l = g
            .arm_length_mm
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min);
        ratio * (l * l / (ratio * ratio + 1.0)).sqrt() - g.delta_radius_mm
    }

    /// Checks every figure; on failure returns the dotted key and what is wrong.
    fn validate(&self) -> Result<(), (String, String)> {
        let g = &self.geometry;
        let err = |key: &str, msg: String| Err((key.to_string(), msg));
        let positive: [(&str, f64); 14] = [
            ("geometry.delta_radius_mm", g.delta_radius_mm),
            ("geometry.print_radius_mm", g.print_radius_mm),
            ("masses.cart_kg", self.masses.cart_kg),
            ("masses.link_kg", self.masses.link_kg),
            ("masses.platform_kg", self.masses.platform_kg),
            ("limits.max_velocity_mm_s", self.limits.max_velocity_mm_s),
            ("limits.max_accel_mm_s2", self.limits.max_accel_mm_s2),
            (
                "limits.max_z_velocity_mm_s",
                self.limits.max_z_velocity_mm_s,
            ),
            ("limits.max_z_accel_mm_s2", self.limits.max_z_accel_mm_s2),
            (
                "extruder.nozzle_diameter_mm",
                self.extruder.nozzle_diameter_mm,
            ),
            (
                "extruder.filament_diameter_mm",
                self.extruder.filament_diameter_mm,
            ),
            ("motors.max_force_n", self.motors.max_force_n),
            ("sampling.period_s", self.sampling.period_s),
            ("gravity_m_s2", self.gravity_m_s2),
        ];
        for (key, v) in positive {
            if !(v.is_finite() && v > 0.0) {
                return err(key, format!("expected a finite number > 0, found {v}"));
            }
        }
        // A shorter period makes every move millions of samples: the run would seem to hang.
        let period = self.sampling.period_s;
        if !(MIN_PERIOD_S..=MAX_PERIOD_S).contains(&period) {
            return err(
                "sampling.period_s",
                format!(
                    "expected a period between {MIN_PERIOD_S} and {MAX_PERIOD_S} s, found {period}"
                ),
            );
        }
        let extruder = [
            (
                "extruder.max_extrude_only_velocity_mm_s",
                self.extruder.max_extrude_only_velocity_mm_s,
            ),
            (
                "extruder.max_extrude_only_accel_mm_s2",
                self.extruder.max_extrude_only_accel_mm_s2,
            ),
        ];
        for (key, v) in extruder {
            if !(v.is_finite() && v > 0.0) {
                return err(key, format!("expected a finite number > 0, found {v}"));
            }
        }
        let non_negative = [
            ("geometry.nozzle_offset_mm", g.nozzle_offset_mm),
            (
                "limits.square_corner_velocity_mm_s",
                self.limits.square_corner_velocity_mm_s,
            ),
            (
                "extruder.instantaneous_corner_velocity_mm_s",
                self.extruder.instantaneous_corner_velocity_mm_s,
            ),
        ];
        for (key, v) in non_negative {
            if !(v.is_finite() && v >= 0.0) {
                return err(key, format!("expected a finite number >= 0, found {v}"));
            }
        }
        let mcr = self.limits.minimum_cruise_ratio;
        if !(mcr.is_finite() && (0.0..1.0).contains(&mcr)) {
            return err(
                "limits.minimum_cruise_ratio",
                format!("expected a number in [0, 1), found {mcr}"),
            );
        }
        if g.tower_angles_deg.iter().any(|a| !a.is_finite()) {
            return err("geometry.tower_angles_deg", "expected finite angles".into());
        }
        let reach = g.delta_radius_mm + g.print_radius_mm;
        for (i, &l) in g.arm_length_mm.iter().enumerate() {
            if !(l.is_finite() && l > reach) {
                return err(
                    "geometry.arm_length_mm",
                    format!(
                        "arm of tower {} is {l} mm, it must be longer than delta_radius + \
                         print_radius = {reach} mm or the arms lie flat inside the print disc",
                        TOWER_NAMES[i]
                    ),
                );
            }
        }
        if !(g.home_z_mm.is_finite() && g.home_z_mm > 0.0) {
            return err(
                "geometry.home_z_mm",
                format!("home must be above the bed (z > 0), found {}", g.home_z_mm),
            );
        }
        if let Err(e) = self.model().inverse(Vec3::new(0.0, 0.0, g.home_z_mm)) {
            return err("geometry.home_z_mm", format!("home is unreachable: {e}"));
        }
        Ok(())
    }
}

/// The sampling periods a profile may ask for, s (1 µs to 1 s).
const MIN_PERIOD_S: f64 = 1e-6;
const MAX_PERIOD_S: f64 = 1.0;

/// Turns a YAML parser error into a [`ProfileError::Schema`], adding the closest valid name
/// to an unknown key.
fn schema_error(e: &yaml_serde::Error, origin: &str) -> ProfileError {
    let mut message = e.to_string();
    if let Some(at) = message.rfind(" at line ") {
        message.truncate(at);
    }
    message = message.replace("expected f64", "expected a number");
    if let Some(hint) = suggest_field(&message) {
        message.push_str(&format!(" (did you mean `{hint}`?)"));
    }
    ProfileError::Schema {
        origin: origin.to_string(),
        location: e.location().map(|l| (l.line(), l.column())),
        message,
    }
}

/// From serde's "unknown field `x`, expected one of `a`, `b`" picks the closest name.
fn suggest_field(message: &str) -> Option<String> {
    let rest = message.split("unknown field `").nth(1)?;
    let (unknown, expected) = rest.split_once('`')?;
    expected
        .split('`')
        .skip(1)
        .step_by(2)
        .map(|name| (edit_distance(unknown, name), name))
        .filter(|&(d, name)| d <= name.len().max(unknown.len()) / 2)
        .min_by_key(|&(d, _)| d)
        .map(|(_, name)| name.to_string())
}

/// Levenshtein distance (insert, delete, substitute), on chars.
fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut diag = row[0];
        row[0] = i + 1;
        for (j, &cb) in b.iter().enumerate() {
            let next = (diag + usize::from(ca != cb))
                .min(row[j] + 1)
                .min(row[j + 1] + 1);
            diag = row[j + 1];
            row[j + 1] = next;
        }
    }
    row[b.len()]
}

/// Line and column (1-based) of a dotted key such as `geometry.arm_length_mm` in the YAML
/// text: the section at indent 0, then the key indented below it. Best effort: validation
/// runs on the parsed values, which carry no position.
fn locate_key(text: &str, dotted: &str) -> Option<(usize, usize)> {
    let mut parts = dotted.split('.');
    let first = parts.next()?;
    let second = parts.next();
    let mut in_section = false;
    for (n, line) in text.lines().enumerate() {
        let trimmed = line.trim_start();
        let indent = line.len() - trimmed.len();
        let is_key = |k: &str| {
            trimmed
                .strip_prefix(k)
                .is_some_and(|r| r.trim_start().starts_with(':'))
        };
        if indent == 0 && !trimmed.is_empty() && !trimmed.starts_with('#') {
            in_section = is_key(first);
            if in_section && second.is_none() {
                return Some((n + 1, 1));
            }
        } else if in_section && second.is_some_and(is_key) {
            return Some((n + 1, indent + 1));
        }
    }
    None
}

// ---- The YAML schema (raw form, before defaults) -------------------------------------

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawMachine {
    name: String,
    geometry: RawGeometry,
    masses: RawMasses,
    limits: RawLimits,
    #[serde(default)]
    extruder: RawExtruder,
    motors: RawMotors,
    #[serde(default)]
    sampling: RawSampling,
    #[serde(default = "default_gravity")]
    gravity_m_s2: f64,
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
    #[serde(default = "default_tower_angles")]
    tower_angles_deg: [f64; 3],
    home_z_mm: f64,
    print_radius_mm: f64,
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
    #[serde(default = "default_scv")]
    square_corner_velocity_mm_s: f64,
    #[serde(default = "default_mcr")]
    minimum_cruise_ratio: f64,
    max_z_velocity_mm_s: Option<f64>,
    max_z_accel_mm_s2: Option<f64>,
    #[serde(default = "default_true")]
    edge_slowdown: bool,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawExtruder {
    #[serde(default = "default_nozzle")]
    nozzle_diameter_mm: f64,
    #[serde(default = "default_filament")]
    filament_diameter_mm: f64,
    max_extrude_only_velocity_mm_s: Option<f64>,
    max_extrude_only_accel_mm_s2: Option<f64>,
    #[serde(default = "default_icv")]
    instantaneous_corner_velocity_mm_s: f64,
}

impl Default for RawExtruder {
    fn default() -> Self {
        RawExtruder {
            nozzle_diameter_mm: default_nozzle(),
            filament_diameter_mm: default_filament(),
            max_extrude_only_velocity_mm_s: None,
            max_extrude_only_accel_mm_s2: None,
            instantaneous_corner_velocity_mm_s: default_icv(),
        }
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawMotors {
    max_force_n: Option<f64>,
    holding_torque_nm: Option<f64>,
    pulley_teeth: Option<u32>,
    belt_pitch_mm: Option<f64>,
    safety_factor: Option<f64>,
    rotor_inertia_kg_m2: Option<f64>,
}

/// GT2 belt pitch, mm.
const DEFAULT_BELT_PITCH_MM: f64 = 2.0;

impl RawMotors {
    /// Either `max_force_n`, or `holding_torque_nm` + `safety_factor` on a pulley of
    /// `pulley_teeth` × `belt_pitch_mm`; the rotor inertia, if given, reflected through
    /// the same pulley. On a bad combination or figure returns the key and what is wrong.
    fn resolve(&self) -> Result<Motors, (String, String)> {
        let radius_m = match (self.pulley_teeth, self.belt_pitch_mm) {
            (Some(teeth), pitch) => {
                let pitch = pitch.unwrap_or(DEFAULT_BELT_PITCH_MM);
                positive("motors.belt_pitch_mm", pitch)?;
                if teeth == 0 {
                    return Err(("motors.pulley_teeth".into(), "expected at least 1".into()));
                }
                Some(pulley_pitch_radius_m(teeth, pitch))
            }
            (None, Some(_)) => {
                return Err((
                    "motors.belt_pitch_mm".into(),
                    "given without `pulley_teeth`".into(),
                ));
            }
            (None, None) => None,
        };
        let needs_pulley = |key: &str| {
            radius_m.ok_or_else(|| {
                (
                    format!("motors.{key}"),
                    "needs `pulley_teeth` (and `belt_pitch_mm`, default 2 for GT2) to convert \
                     it at the belt"
                        .to_string(),
                )
            })
        };
        let max_force_n = match (self.max_force_n, self.holding_torque_nm, self.safety_factor) {
            (Some(f), None, None) => f,
            (Some(_), _, _) => {
                return Err((
                    "motors".into(),
                    "expected either `max_force_n` alone or `holding_torque_nm` together with \
                     `safety_factor` and `pulley_teeth`, not a mix"
                        .into(),
                ));
            }
            (None, Some(torque), Some(safety)) => {
                let r = needs_pulley("holding_torque_nm")?;
                positive("motors.holding_torque_nm", torque)?;
                if !(safety.is_finite() && safety >= 1.0) {
                    return Err((
                        "motors.safety_factor".into(),
                        format!("expected a finite number >= 1, found {safety}"),
                    ));
                }
                torque / r / safety
            }
            (None, Some(_), None) => {
                return Err((
                    "motors.holding_torque_nm".into(),
                    "needs `safety_factor` (holding torque / allowed torque: the torque lost \
                     at speed, micro-stepping, margin)"
                        .into(),
                ));
            }
            (None, None, Some(_)) => {
                return Err((
                    "motors.safety_factor".into(),
                    "needs `holding_torque_nm`".into(),
                ));
            }
            (None, None, None) => {
                return Err((
                    "motors".into(),
                    "expected `max_force_n`, or `holding_torque_nm` + `safety_factor` + \
                     `pulley_teeth`"
                        .into(),
                ));
            }
        };
        let reflected_mass_kg = match self.rotor_inertia_kg_m2 {
            Some(j) => {
                let r = needs_pulley("rotor_inertia_kg_m2")?;
                if !(j.is_finite() && j >= 0.0) {
                    return Err((
                        "motors.rotor_inertia_kg_m2".into(),
                        format!("expected a finite number >= 0, found {j}"),
                    ));
                }
                j / (r * r)
            }
            None => 0.0,
        };
        if radius_m.is_some()
            && self.holding_torque_nm.is_none()
            && self.rotor_inertia_kg_m2.is_none()
        {
            return Err((
                "motors.pulley_teeth".into(),
                "used only with `holding_torque_nm` or `rotor_inertia_kg_m2`".into(),
            ));
        }
        Ok(Motors {
            max_force_n,
            reflected_mass_kg,
        })
    }
}

/// Pitch radius of a toothed pulley, m: its pitch circle is `teeth` belt pitches long,
/// r = teeth · pitch / (2π).
pub fn pulley_pitch_radius_m(teeth: u32, belt_pitch_mm: f64) -> f64 {
    f64::from(teeth) * belt_pitch_mm * 1e-3 / std::f64::consts::TAU
}

fn positive(key: &str, v: f64) -> Result<(), (String, String)> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err((
            key.into(),
            format!("expected a finite number > 0, found {v}"),
        ))
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSampling {
    #[serde(default = "default_period")]
    period_s: f64,
}

impl Default for RawSampling {
    fn default() -> Self {
        RawSampling {
            period_s: default_period(),
        }
    }
}

fn default_gravity() -> f64 {
    9.81
}
fn default_tower_angles() -> [f64; 3] {
    [210.0, 330.0, 90.0]
}
fn default_scv() -> f64 {
    5.0
}
fn default_mcr() -> f64 {
    0.5
}
fn default_true() -> bool {
    true
}
fn default_nozzle() -> f64 {
    0.4
}
fn default_filament() -> f64 {
    1.75
}
fn default_icv() -> f64 {
    1.0
}
fn default_period() -> f64 {
    0.001
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

impl RawMachine {
    /// Fills every default; on a bad geometry form returns the key and what is wrong.
    /// The figures are validated after, on the resolved machine.
    fn resolve(self) -> Result<Machine, (String, String)> {
        let g = self.geometry;
        let delta_radius_mm = match (g.delta_radius_mm, g.base_side_mm, g.platform_side_mm) {
            (Some(r), None, None) => r,
            (None, Some(sb), Some(sp)) => (sb - sp) / 3f64.sqrt(),
            (None, None, None) => {
                return Err((
                    "geometry".into(),
                    "expected `delta_radius_mm` or `base_side_mm` + `platform_side_mm`".into(),
                ));
            }
            _ => {
                return Err((
                    "geometry".into(),
                    "expected either `delta_radius_mm` alone or `base_side_mm` together with \
                     `platform_side_mm`, not a mix"
                        .into(),
                ));
            }
        };
        let l = self.limits;
        let e = self.extruder;
        // Klipper extruder.py: def_max_extrude_ratio = 4·nozzle² / filament_area.
        let filament_area = std::f64::consts::PI * (e.filament_diameter_mm * 0.5).powi(2);
        let extrude_ratio = 4.0 * e.nozzle_diameter_mm.powi(2) / filament_area;
        Ok(Machine {
            name: self.name,
            geometry: Geometry {
                delta_radius_mm,
                arm_length_mm: g.arm_length_mm.0,
                nozzle_offset_mm: g.nozzle_offset_mm,
                tower_angles_deg: g.tower_angles_deg,
                home_z_mm: g.home_z_mm,
                print_radius_mm: g.print_radius_mm,
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
            motors: self.motors.resolve()?,
            sampling: Sampling {
                period_s: self.sampling.period_s,
            },
            gravity_m_s2: self.gravity_m_s2,
        })
    }
}

/// A machine for the unit tests of the stages after the profile.
#[cfg(test)]
pub(crate) mod test_support {
    use super::Machine;

    /// A Kossel-like machine with slightly unequal arms and a nozzle offset, so no test
    /// passes by symmetry, and the paper's masses.
    pub(crate) const KOSSEL_YAML: &str = "
name: test kossel
geometry:
  delta_radius_mm: 105
  arm_length_mm: [215.0, 215.5, 214.5]
  nozzle_offset_mm: 3
  home_z_mm: 290
  print_radius_mm: 85
masses: {cart_kg: 0.25, link_kg: 0.02, platform_kg: 0.5}
limits: {max_velocity_mm_s: 300, max_accel_mm_s2: 3000}
motors: {max_force_n: 30}
";

    pub(crate) fn kossel_machine() -> Machine {
        Machine::from_yaml_str(KOSSEL_YAML, "test").unwrap()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const KOSSEL: &str = include_str!("../machines/kossel.yaml");

    fn error_of(text: &str) -> String {
        Machine::from_yaml_str(text, "m.yaml")
            .unwrap_err()
            .to_string()
    }

    #[test]
    fn the_shipped_profiles_load_with_klipper_defaults() {
        let m = Machine::from_yaml_str(KOSSEL, "kossel.yaml").unwrap();
        assert_eq!(m.limits.max_z_velocity_mm_s, 300.0);
        assert_eq!(m.limits.max_z_accel_mm_s2, 3000.0);
        // Klipper extruder.py: 300 · 4·0.4² / (π·1.75²/4) = 79.824 mm/s, ×10 for accel.
        assert!((m.extruder.max_extrude_only_velocity_mm_s - 79.824_324).abs() < 1e-5);
        assert!((m.extruder.max_extrude_only_accel_mm_s2 - 798.243_24).abs() < 1e-4);
        assert_eq!(m.geometry.tower_angles_deg, [210.0, 330.0, 90.0]);
        assert_eq!(m.gravity_m_s2, 9.81);
        assert_eq!(m.geometry.arm_length_mm, [215.0; 3]);
        let paper = Machine::from_yaml_str(include_str!("../machines/paper.yaml"), "p").unwrap();
        assert_eq!(paper.masses.platform_kg, 0.5);
    }

    #[test]
    fn minimal_profile_fills_every_default() {
        let text = "name: x
geometry: {delta_radius_mm: 100, arm_length_mm: [200, 201, 202], home_z_mm: 250, print_radius_mm: 80}
masses: {cart_kg: 0.2, link_kg: 0.01, platform_kg: 0.1}
limits: {max_velocity_mm_s: 200, max_accel_mm_s2: 2000}
motors: {max_force_n: 20}
";
        let m = Machine::from_yaml_str(text, "x").unwrap();
        assert_eq!(m.geometry.arm_length_mm, [200.0, 201.0, 202.0]);
        assert_eq!(m.geometry.nozzle_offset_mm, 0.0);
        assert_eq!(m.limits.square_corner_velocity_mm_s, 5.0);
        assert_eq!(m.limits.minimum_cruise_ratio, 0.5);
        assert!(m.limits.edge_slowdown);
        assert_eq!(m.extruder.nozzle_diameter_mm, 0.4);
        assert_eq!(m.extruder.filament_diameter_mm, 1.75);
        assert_eq!(m.extruder.instantaneous_corner_velocity_mm_s, 1.0);
        assert_eq!(m.sampling.period_s, 0.001);
    }

    #[test]
    fn base_and_platform_sides_give_the_delta_radius() {
        let text = KOSSEL.replace(
            "delta_radius_mm: 105.0",
            "base_side_mm: 250.0\n  platform_side_mm: 68.1347",
        );
        let m = Machine::from_yaml_str(&text, "k").unwrap();
        // (250 − 68.1347)/√3
        assert!((m.geometry.delta_radius_mm - 105.0).abs() < 1e-4);
        let both = KOSSEL.replace(
            "delta_radius_mm: 105.0",
            "delta_radius_mm: 105\n  base_side_mm: 250",
        );
        assert!(error_of(&both).contains("not a mix"));
        let neither = KOSSEL.replace("delta_radius_mm: 105.0", "");
        assert!(error_of(&neither).contains("expected `delta_radius_mm`"));
    }

    #[test]
    fn unknown_key_names_file_line_and_the_closest_name() {
        let e = error_of(&KOSSEL.replace("delta_radius_mm:", "delta_radus_mm:"));
        assert!(e.starts_with("m.yaml:7:"), "{e}");
        assert!(e.contains("unknown field `delta_radus_mm`"), "{e}");
        assert!(e.contains("did you mean `delta_radius_mm`?"), "{e}");
        // Nothing close: no suggestion.
        let e = error_of(&KOSSEL.replace("  edge_slowdown: true", "  zzz: 1"));
        assert!(
            e.contains("unknown field `zzz`") && !e.contains("did you mean"),
            "{e}"
        );
    }

    #[test]
    fn wrong_type_and_missing_key_are_located() {
        let e = error_of(&KOSSEL.replace("cart_kg: 0.22", "cart_kg: heavy"));
        assert!(
            e.contains("masses.cart_kg") && e.contains("expected a number"),
            "{e}"
        );
        assert!(e.starts_with("m.yaml:"), "{e}");
        let e = error_of(&KOSSEL.replace("  home_z_mm: 290.0", ""));
        assert!(e.contains("missing field `home_z_mm`"), "{e}");
        let e = error_of(&KOSSEL.replace("arm_length_mm: 215.0", "arm_length_mm: [215, 215]"));
        assert!(e.contains("list of 3 lengths"), "{e}");
    }

    #[test]
    fn impossible_machines_are_rejected_with_the_key() {
        let cases = [
            (
                "arm_length_mm: 215.0",
                "arm_length_mm: 180",
                "geometry.arm_length_mm",
            ),
            ("home_z_mm: 290.0", "home_z_mm: -1", "geometry.home_z_mm"),
            ("cart_kg: 0.22", "cart_kg: 0", "masses.cart_kg"),
            ("max_force_n: 25.0", "max_force_n: -5", "motors.max_force_n"),
            ("period_s: 0.001", "period_s: 0", "sampling.period_s"),
            (
                "max_accel_mm_s2: 3000",
                "max_accel_mm_s2: .nan",
                "limits.max_accel_mm_s2",
            ),
            (
                "minimum_cruise_ratio: 0.5",
                "minimum_cruise_ratio: 1.5",
                "limits.minimum_cruise_ratio",
            ),
        ];
        for (from, to, key) in cases {
            let text = KOSSEL.replace(from, to);
            assert_ne!(text, KOSSEL, "{from}");
            let e = error_of(&text);
            assert!(e.contains(key), "{e}");
            // Located at the key's line.
            let line = text
                .lines()
                .position(|l| l.trim_start().starts_with(to))
                .unwrap()
                + 1;
            assert!(
                e.starts_with(&format!("m.yaml:{line}:")),
                "{e} (line {line})"
            );
        }
    }

    /// KOSSEL with its `motors` section replaced.
    fn with_motors(motors: &str) -> String {
        let start = KOSSEL.find("motors:").unwrap();
        let end = KOSSEL.find("sampling:").unwrap();
        format!("{}motors:\n{motors}{}", &KOSSEL[..start], &KOSSEL[end..])
    }

    #[test]
    fn motor_torque_form_gives_the_force_and_the_rotor_its_reflected_mass() {
        // GT2 20T: pitch circle 40 mm, r = 40/(2π) = 6.366 mm. 0.4 N·m / r / 2 = 10π N.
        // NEMA 17 rotor 54 g·cm² = 5.4e-6 kg·m²: J/r² = 5.4e-6 · (2π/0.04)² = 0.133240 kg.
        let text = with_motors(
            "  holding_torque_nm: 0.4\n  pulley_teeth: 20\n  safety_factor: 2.0\n  \
             rotor_inertia_kg_m2: 5.4e-6\n",
        );
        let m = Machine::from_yaml_str(&text, "m").unwrap();
        assert!((m.motors.max_force_n - 31.415_926_5).abs() < 1e-6);
        assert!((m.motors.reflected_mass_kg - 0.133_240).abs() < 1e-6);
        // HTD3 16T, pitch 3 mm: r = 48/(2π) = 7.639 mm; 1.2 N·m / r / 3 = 52.36 N.
        let text = with_motors(
            "  holding_torque_nm: 1.2\n  pulley_teeth: 16\n  belt_pitch_mm: 3\n  \
             safety_factor: 3\n",
        );
        let m = Machine::from_yaml_str(&text, "m").unwrap();
        assert!((m.motors.max_force_n - 52.359_878).abs() < 1e-5);
        assert_eq!(m.motors.reflected_mass_kg, 0.0);
        // The force form with a rotor: the pulley is needed for J/r² only.
        let text =
            with_motors("  max_force_n: 25\n  pulley_teeth: 20\n  rotor_inertia_kg_m2: 5.4e-6\n");
        let m = Machine::from_yaml_str(&text, "m").unwrap();
        assert_eq!(m.motors.max_force_n, 25.0);
        assert!((m.motors.reflected_mass_kg - 0.133_240).abs() < 1e-6);
        // The shipped profiles have no rotor term.
        let k = Machine::from_yaml_str(KOSSEL, "k").unwrap();
        assert_eq!(k.motors.reflected_mass_kg, 0.0);
    }

    #[test]
    fn motor_form_errors_name_the_key_and_its_line() {
        // (motors section, key in the message, text on the reported line)
        let cases = [
            (
                "  max_force_n: 25\n  holding_torque_nm: 0.4\n  safety_factor: 2\n",
                "motors: expected either `max_force_n` alone",
                "motors:",
            ),
            (
                "  pulley_teeth: 20\n",
                "motors: expected `max_force_n`",
                "motors:",
            ),
            (
                "  holding_torque_nm: 0.4\n  pulley_teeth: 20\n",
                "motors.holding_torque_nm: needs `safety_factor`",
                "  holding_torque_nm",
            ),
            (
                "  max_force_n: 25\n  safety_factor: 2\n",
                "motors: expected either",
                "motors:",
            ),
            (
                "  holding_torque_nm: 0.4\n  safety_factor: 2\n",
                "motors.holding_torque_nm: needs `pulley_teeth`",
                "  holding_torque_nm",
            ),
            (
                "  holding_torque_nm: 0.4\n  pulley_teeth: 20\n  safety_factor: 0.5\n",
                "motors.safety_factor: expected a finite number >= 1",
                "  safety_factor",
            ),
            (
                "  holding_torque_nm: -0.4\n  pulley_teeth: 20\n  safety_factor: 2\n",
                "motors.holding_torque_nm: expected a finite number > 0",
                "  holding_torque_nm",
            ),
            (
                "  holding_torque_nm: 0.4\n  pulley_teeth: 0\n  safety_factor: 2\n",
                "motors.pulley_teeth: expected at least 1",
                "  pulley_teeth",
            ),
            (
                "  max_force_n: 25\n  pulley_teeth: 20\n  belt_pitch_mm: 0\n  \
                 rotor_inertia_kg_m2: 1e-6\n",
                "motors.belt_pitch_mm: expected a finite number > 0",
                "  belt_pitch_mm",
            ),
            (
                "  max_force_n: 25\n  belt_pitch_mm: 2\n",
                "motors.belt_pitch_mm: given without `pulley_teeth`",
                "  belt_pitch_mm",
            ),
            (
                "  max_force_n: 25\n  rotor_inertia_kg_m2: 5.4e-6\n",
                "motors.rotor_inertia_kg_m2: needs `pulley_teeth`",
                "  rotor_inertia_kg_m2",
            ),
            (
                "  max_force_n: 25\n  pulley_teeth: 20\n  rotor_inertia_kg_m2: -1\n",
                "motors.rotor_inertia_kg_m2: expected a finite number >= 0",
                "  rotor_inertia_kg_m2",
            ),
            (
                "  max_force_n: 25\n  pulley_teeth: 20\n",
                "motors.pulley_teeth: used only with",
                "  pulley_teeth",
            ),
        ];
        for (motors, message, on_line) in cases {
            let text = with_motors(motors);
            let e = error_of(&text);
            assert!(e.contains(message), "{e}");
            let line = text.lines().position(|l| l.starts_with(on_line)).unwrap() + 1;
            assert!(
                e.starts_with(&format!("m.yaml:{line}:")),
                "{e} (line {line})"
            );
        }
        // A fractional tooth count is a schema error at its line.
        let e = error_of(&with_motors(
            "  holding_torque_nm: 0.4\n  pulley_teeth: 20.5\n  safety_factor: 2\n",
        ));
        assert!(e.contains("motors.pulley_teeth"), "{e}");
    }

    /// The paper's machine with and without a rotor of reflected mass 0.13324 kg.
    fn paper_models() -> (DeltaModel, DeltaModel, f64) {
        let paper = include_str!("../machines/paper.yaml");
        let plain = Machine::from_yaml_str(paper, "p").unwrap();
        let rotor = paper.replace(
            "max_force_n: 40.0",
            "max_force_n: 40.0\n  pulley_teeth: 20\n  rotor_inertia_kg_m2: 5.4e-6",
        );
        let rotor = Machine::from_yaml_str(&rotor, "p").unwrap();
        let m_r = rotor.motors.reflected_mass_kg;
        assert!(m_r > 0.13);
        (plain.model(), rotor.model(), m_r)
    }

    #[test]
    fn the_rotor_adds_inertia_to_the_carriage_but_no_weight() {
        let (plain, rotor, m_r) = paper_models();
        let states = [
            (Vec3::new(0.0, 0.0, 0.0), Vec3::zeros(), Vec3::zeros()),
            (Vec3::new(40.0, -20.0, 10.0), Vec3::zeros(), Vec3::zeros()),
            (
                Vec3::new(40.0, -20.0, 10.0),
                Vec3::new(150.0, -80.0, 5.0),
                Vec3::new(-3000.0, 1200.0, 400.0),
            ),
            (
                Vec3::new(-30.0, 50.0, 100.0),
                Vec3::new(0.0, 200.0, 0.0),
                Vec3::new(8000.0, 0.0, 0.0),
            ),
        ];
        for (p, v, a) in states {
            let s0 = plain.evaluate(p, v, a).unwrap();
            let s1 = rotor.evaluate(p, v, a).unwrap();
            for i in 0..3 {
                // Q = (m_c + m_r) q̈ + m_c g + …: the difference is m_r q̈ (q̈ in m/s²).
                let expected = m_r * s0.ddq_mm_s2[i] * 1e-3;
                let diff = s1.force_n[i] - s0.force_n[i];
                assert!(
                    (diff - expected).abs() < 1e-12 * (1.0 + s0.force_n[i].abs()),
                    "{diff} vs {expected}"
                );
            }
            // Same weight: same potential energy, and at rest the same (static) forces.
            assert_eq!(s0.potential_j, s1.potential_j);
        }
        assert_eq!(
            plain.suspended_weight_n(),
            rotor.suspended_weight_n(),
            "eq. 17 counts weight only"
        );
    }

    #[test]
    fn eq20_holds_with_the_rotor_against_an_energy_built_from_the_kinematics_alone() {
        // E(t) = ½(m_c + m_r)Σq̇² + ½ m_p |ṗ|² + g(m_c Σq + m_p z_P), with q from eq. 6 and
        // q̇ by central differences; its time derivative (differenced) must equal Σ Q_i q̇_i.
        let (_, rotor, m_r) = paper_models();
        let (mc, mp, g) = (0.25 + 0.02, 0.5 + 0.06, 9.81);
        let traj = |t: f64| {
            let w = [7.0, 11.0];
            let p = Vec3::new(
                40.0 * (w[0] * t).sin(),
                30.0 * (w[1] * t).cos(),
                20.0 + 5.0 * t,
            );
            let v = Vec3::new(
                40.0 * w[0] * (w[0] * t).cos(),
                -30.0 * w[1] * (w[1] * t).sin(),
                5.0,
            );
            let a = Vec3::new(
                -40.0 * w[0] * w[0] * (w[0] * t).sin(),
                -30.0 * w[1] * w[1] * (w[1] * t).cos(),
                0.0,
            );
            (p, v, a)
        };
        let q_m = |t: f64| rotor.inverse(traj(t).0).unwrap().map(|q| q * 1e-3);
        let energy = |t: f64| {
            let h = 1e-6;
            let (qp, qm, q) = (q_m(t + h), q_m(t - h), q_m(t));
            let (_, v, _) = traj(t);
            let dq2: f64 = (0..3).map(|i| ((qp[i] - qm[i]) / (2.0 * h)).powi(2)).sum();
            let kinetic = 0.5 * (mc + m_r) * dq2 + 0.5 * mp * (v * 1e-3).norm_squared();
            let z_p = traj(t).0.z * 1e-3;
            kinetic + g * (mc * q.iter().sum::<f64>() + mp * z_p)
        };
        for k in 0..50 {
            let t = 0.013 * k as f64;
            let (p, v, a) = traj(t);
            let s = rotor.evaluate(p, v, a).unwrap();
            let h = 1e-4;
            let de = (energy(t + h) - energy(t - h)) / (2.0 * h);
            assert!(
                (de - s.power_w).abs() < 1e-4 * (1.0 + s.power_w.abs()),
                "t={t}: {de} vs {}",
                s.power_w
            );
            assert!((s.energy_rate_w - s.power_w).abs() < 1e-9 * (1.0 + s.power_w.abs()));
        }
    }

    #[test]
    fn edit_distance_counts_single_edits() {
        assert_eq!(edit_distance("kitten", "sitting"), 3);
        assert_eq!(edit_distance("", "abc"), 3);
        assert_eq!(edit_distance("same", "same"), 0);
    }
    #[test]
    fn slow_radius_is_where_a_carriage_moves_ratio_times_faster() {
        // Nozzle on the far side of tower C (−y), moving away from it: the fastest
        // carriage-to-nozzle speed ratio at that radius.
        let machine = test_support::kossel_machine();
        let m = machine.model();
        for ratio in [3.0, 6.0] {
            let r = machine.slow_radius_mm(ratio);
            // Shortest arm (214.5 mm) is tower C's in the fixture.
            let s = m
                .evaluate(
                    Vec3::new(0.0, -r, 0.0),
                    Vec3::new(0.0, -1.0, 0.0),
                    Vec3::zeros(),
                )
                .unwrap();
            assert!(
                (s.dq_mm_s[2].abs() - ratio).abs() < 1e-9,
                "{ratio}: {:?}",
                s.dq_mm_s
            );
            // The same ratio in closed form, from the distance to tower C's pull point.
            let c = m.towers_xy_mm()[2];
            let h = (c[0] * c[0] + (c[1] + r).powi(2)).sqrt();
            assert!((m.carriage_speed_ratio(2, h) - ratio).abs() < 1e-9);
        }
        assert_eq!(m.carriage_speed_ratio(2, 214.5), f64::INFINITY);
        // Hand-computed: 3·√(214.5²/10) − 105.
        assert!((machine.slow_radius_mm(3.0) - 98.492_567).abs() < 1e-5);
    }
}
