//! Delta inverse kinematics, as Marlin's `recalc_delta_settings` and `DELTA_IK` (spec §2).

use delta_gcode::machine::Geometry;

/// The delta's geometry as Marlin keeps it at run time: M665 changes it.
#[derive(Clone, Debug)]
pub struct Delta {
    /// `delta_radius` (M665 R), mm.
    pub radius: f64,
    /// `delta_diagonal_rod` (M665 L), mm. The profile's tower A arm.
    pub rod: f64,
    /// `delta_diagonal_rod_trim` (M665 A B C), mm. From the profile: each arm less tower A's.
    pub rod_trim: [f64; 3],
    /// The towers' angles, degrees: the profile's (Marlin: 210, 330, 90).
    pub base_angle_deg: [f64; 3],
    /// `delta_tower_angle_trim` (M665 X Y Z), degrees.
    pub angle_trim_deg: [f64; 3],
    /// The nozzle below the joint plane, mm: added to z.
    pub nozzle_offset: f64,
    /// The nozzle z after G28 (Marlin: `delta_height` − probe z offset, less any back-off).
    pub home_z: f64,
    /// `DELTA_PRINTABLE_RADIUS` = the radius clamp's `delta_max_radius`, mm.
    pub print_radius: f64,
    /// Tower positions (x, y), recomputed by [`Delta::recalc`].
    tower: [[f64; 2]; 3],
    /// Squared rod lengths.
    rod2: [f64; 3],
}

impl Delta {
    pub fn from_geometry(g: &Geometry) -> Delta {
        let mut d = Delta {
            radius: g.delta_radius_mm,
            rod: g.arm_length_mm[0],
            rod_trim: [0, 1, 2].map(|i| g.arm_length_mm[i] - g.arm_length_mm[0]),
            base_angle_deg: g.tower_angles_deg,
            angle_trim_deg: [0.0; 3],
            nozzle_offset: g.nozzle_offset_mm,
            home_z: g.home_z_mm,
            print_radius: g.print_radius_mm,
            tower: [[0.0; 2]; 3],
            rod2: [0.0; 3],
        };
        d.recalc();
        d
    }

    /// `recalc_delta_settings`: tower positions and squared rods.
    pub fn recalc(&mut self) {
        for t in 0..3 {
            let ang = (self.base_angle_deg[t] + self.angle_trim_deg[t]).to_radians();
            self.tower[t] = [ang.cos() * self.radius, ang.sin() * self.radius];
            let rod = self.rod + self.rod_trim[t];
            self.rod2[t] = rod * rod;
        }
    }

    /// The carriage heights (mm, in the nozzle's z frame) for the nozzle at (x, y, z):
    /// z + offset + sqrt(L² − (x − tx)² − (y − ty)²). None where an arm cannot reach.
    pub fn carriages(&self, x: f64, y: f64, z: f64) -> Option<[f64; 3]> {
        let mut q = [0.0; 3];
        for (t, qt) in q.iter_mut().enumerate() {
            let dx = self.tower[t][0] - x;
            let dy = self.tower[t][1] - y;
            let arg = self.rod2[t] - (dx * dx + dy * dy);
            if arg.is_nan() || arg < 0.0 {
                return None;
            }
            *qt = z + self.nozzle_offset + arg.sqrt();
        }
        Some(q)
    }

    /// `position_is_reachable`: x² + y² ≤ (printable radius + 0.0001)².
    pub fn reachable(&self, x: f64, y: f64) -> bool {
        let r = self.print_radius + 0.0001;
        x * x + y * y <= r * r
    }
}
