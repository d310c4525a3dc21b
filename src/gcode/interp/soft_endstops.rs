//! Marlin's soft endstops on a delta: targets clamped to the printable radius
//! (`apply_motion_limits`) and reachability (`position_is_reachable`).

use super::super::Diagnostic;
use super::{Diags, Interpreter};
use crate::path::Vec3;

impl Interpreter {
    /// Marlin's `apply_motion_limits` with soft endstops on and the machine homed: beyond
    /// the printable radius the target's x, y and z are scaled by radius / r (Z too, as
    /// Marlin does), then z is kept in [0, max z]. A warning when it changes the target.
    pub(super) fn apply_motion_limits(
        &self,
        t: Vec3,
        d: &mut Diags<impl FnMut(Diagnostic)>,
    ) -> Vec3 {
        let Some(soft) = self.dialect.soft_endstops else {
            return t;
        };
        if !(self.soft_endstops_on && self.homed) {
            return t;
        }
        let mut c = t;
        let r2 = t.x * t.x + t.y * t.y;
        if r2 > soft.radius_mm * soft.radius_mm {
            c *= soft.radius_mm / r2.sqrt();
        }
        c.z = c.z.clamp(0.0, soft.max_z_mm);
        if c != t {
            d.warn(
                1,
                format!(
                    "the target ({:.3}, {:.3}, {:.3}) is outside Marlin's soft endstops \
                     (printable radius {} mm, Z 0 to {} mm): Marlin moves to ({:.3}, {:.3}, \
                     {:.3}) instead (beyond the radius it scales X, Y and Z alike)",
                    t.x, t.y, t.z, soft.radius_mm, soft.max_z_mm, c.x, c.y, c.z
                ),
            );
        }
        c
    }

    /// Marlin's `position_is_reachable` on a delta: within the printable radius (+0.1 µm).
    pub(super) fn reachable(&self, t: Vec3) -> bool {
        self.dialect
            .soft_endstops
            .is_none_or(|s| (t.x * t.x + t.y * t.y) <= (s.radius_mm + 1e-4).powi(2))
    }
}
