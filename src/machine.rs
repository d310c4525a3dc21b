//! The machine profile (YAML, see docs/machine-profile.md), resolved: every default filled,
//! every figure checked. The rest of the program reads only this resolved form.

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

#[derive(Clone, Debug, PartialEq)]
pub struct Motors {
    /// Allowed peak |Q_i| per carriage, N.
    pub max_force_n: f64,
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
