//! The prismatic delta robot of the paper: kinematics (eq. 2-8) and the Lagrangian
//! dynamics (eq. 9-14), statics (eq. 15-17) and energy (eq. 20).
//!
//! Conventions (see docs/model.md): bed frame, Z up, bed at z = 0, X from tower A to
//! tower B; towers A, B, C are the paper's 1, 2, 3. Positions in mm at the interface; the
//! dynamics works in SI inside. The carriages sit above the platform (the '+' root of
//! eq. 6). The platform centre P is the nozzle plus (0, 0, PQ).

mod bounds;
mod dynamics;
mod energy;
mod kinematics;
mod statics;

pub use bounds::{BOUND_MARGIN, ForceBounds};
pub use dynamics::{BLOCK, DynState, ForceBlock, StateBlock};
pub use energy::energy_slope;

/// Tower names in order (towers 1, 2, 3 of the paper).
pub const TOWER_NAMES: [char; 3] = ['A', 'B', 'C'];

/// The robot's geometry as the model needs it, mm and degrees.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Geometry {
    /// Horizontal distance from the Z axis to a tower's carriage joint line, less the
    /// effector's joint offset: (s_B − s_P)/√3 in the paper.
    pub delta_radius_mm: f64,
    /// Arm length l per tower (A, B, C).
    pub arm_length_mm: [f64; 3],
    /// PQ: nozzle tip below the platform centre P.
    pub nozzle_offset_mm: f64,
    /// Tower angles (A, B, C); the paper's are 210°, 330°, 90°.
    pub tower_angles_deg: [f64; 3],
    /// Nozzle z after G28 at x = y = 0: the carriages are then at the top of their travel.
    pub home_z_mm: f64,
}

/// The lumped masses of Fig. 2, kg, and what the motors add to the carriages' inertia.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Masses {
    pub cart_kg: f64,
    /// Each of the six arms.
    pub link_kg: f64,
    /// Effector + hotend.
    pub platform_kg: f64,
    /// A motor rotor's inertia seen at its carriage, J/r², kg: inertia, not weight.
    pub rotor_reflected_kg: f64,
}

/// Why a nozzle position or a set of carriage heights has no configuration.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum Unreachable {
    /// Negative (or zero) radicand of eq. 6: the nozzle is farther from the tower than the
    /// arm reaches horizontally.
    #[error(
        "tower {}: arm too short, the platform is {horizontal_mm:.3} mm from the tower \
         but the arm is {arm_mm:.3} mm long",
        TOWER_NAMES[*tower]
    )]
    ArmTooShort {
        tower: usize,
        horizontal_mm: f64,
        arm_mm: f64,
    },
    /// The carriage would have to rise above its homed (endstop) height.
    #[error(
        "tower {}: carriage would be {over_mm:.3} mm above its top (homed) position",
        TOWER_NAMES[*tower]
    )]
    AboveTop { tower: usize, over_mm: f64 },
    /// Jx is singular (arms coplanar): the platform is not held.
    #[error("the arms are coplanar (Jx singular)")]
    Singular,
    /// Forward kinematics: the three spheres do not meet with the carriages above the
    /// platform.
    #[error(
        "carriage heights {:.3}, {:.3}, {:.3} mm: no platform position (the arms cannot meet)",
        q_mm[0], q_mm[1], q_mm[2]
    )]
    NoForwardSolution { q_mm: [f64; 3] },
    /// A coordinate is NaN or infinite.
    #[error("a coordinate is not a finite number")]
    NotFinite,
}

impl Unreachable {
    /// The tower at fault (0 = A), when one is.
    pub fn tower(&self) -> Option<usize> {
        match *self {
            Unreachable::ArmTooShort { tower, .. } | Unreachable::AboveTop { tower, .. } => {
                Some(tower)
            }
            _ => None,
        }
    }
}

/// The delta robot of one machine profile: geometry and lumped masses (Fig. 2). Plain data,
/// `Copy`; every method works on the stack.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DeltaModel {
    /// Horizontal position of each tower's carriage joint line, reduced by the platform
    /// joint offset: (B_i − P_i offset) in the paper, mm.
    towers_mm: [[f64; 2]; 3],
    delta_radius_mm: f64,
    arm_mm: [f64; 3],
    arm2_mm2: [f64; 3],
    /// PQ, mm.
    nozzle_offset_mm: f64,
    /// Carriage heights at G28 home, the top of their travel, mm.
    top_mm: [f64; 3],
    /// m_cart + m_link (Fig. 2), the weight on each carriage, kg.
    carriage_weight_kg: f64,
    /// m_cart + m_link + the motor rotor's reflected mass J/r², the inertia of each
    /// carriage, kg. The rotor turns about a fixed axis: it adds inertia, not weight.
    carriage_inertia_kg: f64,
    /// m_plat + 3 m_link (Fig. 2), kg.
    platform_kg: f64,
    gravity_m_s2: f64,
    /// |det Jx| at or below which Jx counts as singular: 1e-9 · l_1 l_2 l_3, mm³.
    singular_det_mm3: f64,
}

impl DeltaModel {
    pub fn new(g: &Geometry, m: &Masses, gravity_m_s2: f64) -> DeltaModel {
        let towers_mm = g.tower_angles_deg.map(|a| {
            let (s, c) = a.to_radians().sin_cos();
            [g.delta_radius_mm * c, g.delta_radius_mm * s]
        });
        let mut model = DeltaModel {
            towers_mm,
            delta_radius_mm: g.delta_radius_mm,
            arm_mm: g.arm_length_mm,
            arm2_mm2: g.arm_length_mm.map(|l| l * l),
            nozzle_offset_mm: g.nozzle_offset_mm,
            top_mm: [f64::INFINITY; 3],
            carriage_weight_kg: m.cart_kg + m.link_kg,
            carriage_inertia_kg: m.cart_kg + m.link_kg + m.rotor_reflected_kg,
            platform_kg: m.platform_kg + 3.0 * m.link_kg,
            gravity_m_s2,
            singular_det_mm3: 1e-9 * g.arm_length_mm.iter().product::<f64>(),
        };
        // With an infinite top the inverse cannot fail on AboveTop; an arm too short for
        // home leaves the top infinite (the profile validation reports that case).
        if let Ok(top) = model.inverse(crate::path::Vec3::new(0.0, 0.0, g.home_z_mm)) {
            model.top_mm = top;
        }
        model
    }

    /// Carriage heights at G28 home, nozzle at (0, 0, home_z), mm.
    pub fn home_carriages_mm(&self) -> [f64; 3] {
        self.top_mm
    }

    /// Where each tower's arm pulls from, horizontally (the carriage joint line less the
    /// platform joint offset), mm: the nozzle's horizontal distance from it sets the arm's tilt.
    pub fn towers_xy_mm(&self) -> [[f64; 2]; 3] {
        self.towers_mm
    }

    /// How many times faster than the nozzle a tower's carriage moves for a horizontal nozzle
    /// motion away from the tower, with the platform `horizontal_mm` from it: h/√(l² − h²),
    /// the cotangent of the arm's angle above the horizontal (from eq. 7 with ż = 0). Infinite
    /// when the arm lies flat or cannot reach.
    pub fn carriage_speed_ratio(&self, tower: usize, horizontal_mm: f64) -> f64 {
        let rise2 = self.arm2_mm2[tower] - horizontal_mm * horizontal_mm;
        if rise2 > 0.0 {
            horizontal_mm / rise2.sqrt()
        } else {
            f64::INFINITY
        }
    }

    /// The squared horizontal distance from a tower at which [`Self::carriage_speed_ratio`]
    /// reaches `ratio`: h/√(l² − h²) = r where h² = l²·r²/(1 + r²) (mm²). Nearer, the
    /// ratio is smaller.
    pub fn speed_ratio_dist2_mm2(&self, tower: usize, ratio: f64) -> f64 {
        self.arm2_mm2[tower] * (ratio * ratio / (1.0 + ratio * ratio))
    }
}

#[cfg(test)]
pub(crate) mod test_support;
