//! `drive`: how the nozzle follows the commanded motion, given (`rigid`, or a spring's
//! frequency and damping ratio) or, when the profile has no `drive`, the physical default
//! derived from the motors, the belts and the masses (docs/machine-profile.md, "The default
//! drive").
//!
//! The default: each carriage is held by its motor's magnetic stiffness k_m in series with
//! its belt k_b; through the delta's Jacobian J = ∂q/∂x at the bed centre the carriages'
//! stiffness and the masses give the nozzle's stiffness and mass matrices
//! K = Jᵀ·diag(k)·J and M = (m_plat + 3·m_link)·I + Jᵀ·diag(m_cart + m_link + J_rotor/r²)·J;
//! the drive's frequency is that of the mode along X, √λ / 2π with λ the eigenvalue of
//! M⁻¹K whose mode points along X.

use nalgebra::{Matrix3, Vector3};
use serde::Deserialize;

use super::validate::Range;
use super::{Invalid, Machine, defaults, motor};
use crate::delta::Unreachable;
use crate::motion::drive::{Drive, Spring};
use crate::path::Vec3;

/// `drive` as written: `rigid`, or a mapping.
pub(super) enum RawDrive {
    Rigid,
    Spring(RawSpring),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawSpring {
    frequency_hz: f64,
    #[serde(default = "drive_damping_ratio")]
    damping_ratio: f64,
}

fn drive_damping_ratio() -> f64 {
    defaults::DRIVE_DAMPING_RATIO
}

impl<'de> Deserialize<'de> for RawDrive {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = RawDrive;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("`rigid` or a mapping with `frequency_hz` (and `damping_ratio`)")
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<RawDrive, E> {
                match v {
                    "rigid" => Ok(RawDrive::Rigid),
                    _ => Err(E::invalid_value(serde::de::Unexpected::Str(v), &self)),
                }
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(self, map: A) -> Result<RawDrive, A::Error> {
                let d = serde::de::value::MapAccessDeserializer::new(map);
                RawSpring::deserialize(d).map(RawDrive::Spring)
            }
        }
        d.deserialize_any(V)
    }
}

impl RawDrive {
    /// The drive: rigid, or a spring with frequency > 0 and damping in [0, 1).
    pub(super) fn resolve(&self) -> Result<Drive, Invalid> {
        let s = match self {
            RawDrive::Rigid => return Ok(Drive::Rigid),
            RawDrive::Spring(s) => s,
        };
        Range::Positive.check("drive.frequency_hz", s.frequency_hz)?;
        if !(0.0..1.0).contains(&s.damping_ratio) {
            return Err(Invalid::new(
                "drive.damping_ratio",
                format!(
                    "expected a number in [0, 1), found {}: the drive's response is computed \
                     in closed form for an underdamped spring (damping ratio below 1), as \
                     belts and steppers are",
                    s.damping_ratio
                ),
            ));
        }
        Ok(Drive::Spring(Spring {
            frequency_hz: s.frequency_hz,
            damping_ratio: s.damping_ratio,
        }))
    }
}

/// The physical default of `drive` and how it was found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DefaultDrive {
    pub spring: Spring,
    /// k_m, the motor's magnetic stiffness at the carriage, N/m.
    pub motor_stiffness_n_m: f64,
    /// The motor is not in the profile (`max_force_n` form): k_m is the typical motor's
    /// ([`defaults::TYPICAL_HOLDING_TORQUE_NM`] on [`defaults::TYPICAL_PULLEY_TEETH`]).
    pub typical_motor: bool,
    /// The belt length taken, mm: the carriage's travel from the bed centre to home.
    pub belt_length_mm: f64,
    /// k_b = E·A / length, N/m.
    pub belt_stiffness_n_m: f64,
    /// k_m and k_b in series, N/m.
    pub carriage_stiffness_n_m: f64,
    /// The X mode's mass, kg, and stiffness, N/m (φᵀMφ, φᵀKφ with φ_x = 1).
    pub mass_kg: f64,
    pub stiffness_n_m: f64,
}

impl Machine {
    /// The drive this machine gets when its profile has none: see the module's
    /// documentation. Fails only when the bed centre is unreachable.
    pub fn default_drive(&self) -> Result<DefaultDrive, Unreachable> {
        let (motor_stiffness_n_m, typical_motor) = match self.motors.stiffness_n_m {
            Some(k) => (k, false),
            None => (typical_motor_stiffness_n_m(), true),
        };
        // The carriage's travel from the bed centre (z = 0) to home is home_z.
        let belt_length_mm = self.geometry.home_z_mm;
        let belt_stiffness_n_m = defaults::GT2_6MM_BELT_EA_N / (belt_length_mm * 1e-3);
        let k = 1.0 / (1.0 / motor_stiffness_n_m + 1.0 / belt_stiffness_n_m);
        let jac = self.jacobian_at_bed_centre()?;
        let m = &self.masses;
        let carriage_kg = m.cart_kg + m.link_kg + self.motors.reflected_mass_kg;
        let mass = Matrix3::identity() * (m.platform_kg + 3.0 * m.link_kg)
            + jac.transpose() * jac * carriage_kg;
        let stiffness = jac.transpose() * jac * k;
        let phi = x_mode(&mass, &stiffness);
        let (mass_kg, stiffness_n_m) = (phi.dot(&(mass * phi)), phi.dot(&(stiffness * phi)));
        Ok(DefaultDrive {
            spring: Spring {
                frequency_hz: (stiffness_n_m / mass_kg).sqrt() / std::f64::consts::TAU,
                damping_ratio: defaults::DRIVE_DAMPING_RATIO,
            },
            motor_stiffness_n_m,
            typical_motor,
            belt_length_mm,
            belt_stiffness_n_m,
            carriage_stiffness_n_m: k,
            mass_kg,
            stiffness_n_m,
        })
    }

    /// J = ∂q/∂x (dimensionless) at the nozzle (0, 0, 0): column j holds the carriage
    /// velocities of a unit nozzle velocity along axis j (eq. 7, q̇ = J ẋ).
    pub(super) fn jacobian_at_bed_centre(&self) -> Result<Matrix3<f64>, Unreachable> {
        let model = self.model();
        let mut jac = Matrix3::zeros();
        for j in 0..3 {
            let mut v = Vec3::zeros();
            v[j] = 1.0;
            let s = model.evaluate(Vec3::zeros(), v, Vec3::zeros())?;
            for i in 0..3 {
                jac[(i, j)] = s.dq_mm_s[i];
            }
        }
        Ok(jac)
    }
}

/// k_m of [`defaults::TYPICAL_HOLDING_TORQUE_NM`] at 1.8° on a GT2 pulley of
/// [`defaults::TYPICAL_PULLEY_TEETH`], N/m.
pub fn typical_motor_stiffness_n_m() -> f64 {
    let r = motor::pulley_pitch_radius_m(defaults::TYPICAL_PULLEY_TEETH, defaults::BELT_PITCH_MM);
    motor::motor_stiffness_n_m(
        defaults::TYPICAL_HOLDING_TORQUE_NM,
        defaults::STEP_ANGLE_DEG,
        r,
    )
}

/// The mode of K φ = λ M φ that points most along X, scaled to φ_x = 1. M is symmetric
/// positive definite: with M = L·Lᵀ, the modes are L⁻ᵀ times the eigenvectors of the
/// symmetric L⁻¹·K·L⁻ᵀ.
fn x_mode(mass: &Matrix3<f64>, stiffness: &Matrix3<f64>) -> Vector3<f64> {
    let fallback = Vector3::x();
    let Some(chol) = mass.cholesky() else {
        return fallback;
    };
    let l = chol.l();
    let (Some(l_inv), Some(lt_inv)) = (l.try_inverse(), l.transpose().try_inverse()) else {
        return fallback;
    };
    let eigen = (l_inv * stiffness * lt_inv).symmetric_eigen();
    let modes = (0..3).map(|k| lt_inv * eigen.eigenvectors.column(k));
    let along_x = |v: &Vector3<f64>| v.x.abs() / v.norm();
    modes
        .max_by(|a, b| along_x(a).total_cmp(&along_x(b)))
        .filter(|v| v.x != 0.0)
        .map_or(fallback, |v| v / v.x)
}
