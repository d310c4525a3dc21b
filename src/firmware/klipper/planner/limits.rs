//! The speed and acceleration limits of one move, as Klipper sets them before the lookahead:
//! the toolhead's `Move.__init__` (klippy/toolhead.py), the delta kinematics' `check_move`
//! (klippy/kinematics/delta.py) and the extruder's `check_move`
//! (klippy/kinematics/extruder.py).

use crate::gcode::{LimitChange, Move};
use crate::interval::lesser;
use crate::machine::Machine;
use crate::machine::defaults::SLOW_RATIO;

use super::queue::QueuedMove;

/// Klipper treats a move whose XYZ length is below this as extrude-only (toolhead.py).
const MIN_KINEMATIC_D_MM: f64 = 1e-9;
/// The acceleration Klipper gives an extrude-only move before the extruder limits it.
const EXTRUDE_ONLY_ACCEL_MM_S2: f64 = 99_999_999.9;

/// The toolhead limits in force now; M204 / SET_VELOCITY_LIMIT change them for the moves
/// that follow (toolhead.py `set_max_velocities`, `_calc_junction_deviation`).
#[derive(Clone, Copy, Debug)]
struct Toolhead {
    max_velocity_mm_s: f64,
    max_accel_mm_s2: f64,
    square_corner_velocity_mm_s: f64,
    minimum_cruise_ratio: f64,
    /// Klipper before 2024: `max_accel_to_decel` as requested (`limits.
    /// max_accel_to_decel_mm_s2`, SET_VELOCITY_LIMIT ACCEL_TO_DECEL); None: Klipper since,
    /// `minimum_cruise_ratio`.
    accel_to_decel_mm_s2: Option<f64>,
}

impl Toolhead {
    /// scv²·(√2 − 1)/max_accel: the deviation that makes a 90° corner's junction speed
    /// equal to square_corner_velocity.
    fn junction_deviation_mm(&self) -> f64 {
        let scv = self.square_corner_velocity_mm_s;
        scv * scv * (std::f64::consts::SQRT_2 - 1.0) / self.max_accel_mm_s2
    }

    /// The pseudo-acceleration of the minimum_cruise_ratio check; before 2024 Klipper's
    /// `max_accel_to_decel`, capped by max_accel (toolhead.py `_calc_junction_deviation`
    /// of those versions): fixed when ACCEL changes, where the ratio scales with it.
    fn mcr_pseudo_accel_mm_s2(&self) -> f64 {
        match self.accel_to_decel_mm_s2 {
            Some(a2d) => a2d.min(self.max_accel_mm_s2),
            None => self.max_accel_mm_s2 * (1.0 - self.minimum_cruise_ratio),
        }
    }
}

/// Everything fixed by the profile, plus the current toolhead limits.
#[derive(Clone, Debug)]
pub(super) struct MoveLimits {
    toolhead: Toolhead,
    /// The profile's max_velocity / max_accel: delta.py reads them once, at start-up.
    config_velocity_mm_s: f64,
    config_accel_mm_s2: f64,
    max_z_velocity_mm_s: f64,
    max_z_accel_mm_s2: f64,
    /// Squared radii beyond which delta.py halves / quarters speed and accel; `None` when
    /// `limits.edge_slowdown` is off.
    edge_xy2_mm2: Option<(f64, f64)>,
    max_e_velocity_mm_s: f64,
    max_e_accel_mm_s2: f64,
}

impl MoveLimits {
    pub(super) fn new(machine: &Machine) -> Self {
        let l = &machine.limits;
        let edge_xy2_mm2 = l.edge_slowdown.then(|| {
            let slow = machine.slow_radius_mm(SLOW_RATIO);
            let very_slow = machine.slow_radius_mm(2.0 * SLOW_RATIO);
            (slow * slow, very_slow * very_slow)
        });
        MoveLimits {
            toolhead: Toolhead {
                max_velocity_mm_s: l.max_velocity_mm_s,
                max_accel_mm_s2: l.max_accel_mm_s2,
                square_corner_velocity_mm_s: l.square_corner_velocity_mm_s,
                minimum_cruise_ratio: l.minimum_cruise_ratio,
                accel_to_decel_mm_s2: l.max_accel_to_decel_mm_s2,
            },
            config_velocity_mm_s: l.max_velocity_mm_s,
            config_accel_mm_s2: l.max_accel_mm_s2,
            max_z_velocity_mm_s: l.max_z_velocity_mm_s,
            max_z_accel_mm_s2: l.max_z_accel_mm_s2,
            edge_xy2_mm2,
            max_e_velocity_mm_s: machine.extruder.max_extrude_only_velocity_mm_s,
            max_e_accel_mm_s2: machine.extruder.max_extrude_only_accel_mm_s2,
        }
    }

    /// Applies an M204 / SET_VELOCITY_LIMIT: the values Klipper accepts
    /// ([`LimitChange::accepted`]).
    pub(super) fn apply(&mut self, change: &LimitChange) {
        let t = &mut self.toolhead;
        let c = change.accepted();
        t.max_velocity_mm_s = c.velocity_mm_s.unwrap_or(t.max_velocity_mm_s);
        t.max_accel_mm_s2 = c.accel_mm_s2.unwrap_or(t.max_accel_mm_s2);
        t.square_corner_velocity_mm_s = c
            .square_corner_velocity_mm_s
            .unwrap_or(t.square_corner_velocity_mm_s);
        t.minimum_cruise_ratio = c.minimum_cruise_ratio.unwrap_or(t.minimum_cruise_ratio);
        // Only the Klipper that reads it: newer ones ignore ACCEL_TO_DECEL.
        if t.accel_to_decel_mm_s2.is_some() && c.accel_to_decel_mm_s2.is_some() {
            t.accel_to_decel_mm_s2 = c.accel_to_decel_mm_s2;
        }
    }

    /// The move with all its limits, handed to `queue`; nothing for a move that moves
    /// nothing (Klipper drops it) or has a non-finite coordinate (the G-code stage reports
    /// those). A feed that is not a positive number is taken as unlimited (max_velocity caps
    /// it). (Handed on, not returned: an `Option` of the move was one more copy of it, 0.50 %
    /// of an unshaped run's instructions.)
    pub(super) fn queued_move(&self, m: &Move, queue: impl FnOnce(QueuedMove)) {
        let t = &self.toolhead;
        // One comparison: +∞ is its own unlimited speed, and NaN fails it. (With a test of
        // finiteness as well, the two became a dozen instructions on the bits: 0.35 % of an
        // unshaped run's instructions.)
        let speed = if m.feed_mm_s > 0.0 {
            m.feed_mm_s
        } else {
            f64::INFINITY
        };
        // A finite length has finite ends: an infinite or NaN coordinate makes the difference
        // of the ends, and so the length, infinite or NaN. (Testing each coordinate as well
        // was 0.54 % of an unshaped run's instructions.)
        let path_d = m.path.length_mm();
        if !path_d.is_finite() || !m.e_mm.is_finite() {
            return;
        }
        let kinematic = path_d >= MIN_KINEMATIC_D_MM;
        let (move_d, velocity, accel) = if kinematic {
            (
                path_d,
                lesser(speed, t.max_velocity_mm_s),
                t.max_accel_mm_s2,
            )
        } else {
            // An extrude-only move: the extruder's limits below cap it.
            (m.e_mm.abs(), speed, EXTRUDE_ONLY_ACCEL_MM_S2)
        };
        // Also below a nanometre: nothing to plan, and squares of such lengths underflow.
        // (Finite: the length or |E|, both tested above.)
        if move_d < MIN_KINEMATIC_D_MM {
            return;
        }
        let mut q = QueuedMove::new(
            m,
            kinematic,
            move_d,
            velocity,
            accel,
            t.junction_deviation_mm(),
            t.mcr_pseudo_accel_mm_s2(),
        );
        if kinematic {
            self.limit_delta(m, &mut q);
        }
        if m.e_mm != 0.0 {
            self.limit_extruder(m, &mut q);
        }
        // Limits divided by an extrusion ratio far beyond any G-code's (|E| ~ 1e300) leave a
        // speed whose square, or an acceleration that, underflows: nothing can be planned,
        // not even in finite time.
        let v = q.max_cruise_v2.sqrt();
        let plannable = q.max_cruise_v2 > 0.0
            && q.accel_mm_s2 > 0.0
            && (q.move_d_mm / v).is_finite()
            && (v / q.accel_mm_s2).is_finite();
        if plannable {
            queue(q);
        }
    }

    /// delta.py `check_move`: Z moves scaled to max_z_velocity / max_z_accel; half, then a
    /// quarter, of the configured velocity and accel near the edge.
    #[inline(always)] // see `QueuedMove`
    fn limit_delta(&self, m: &Move, q: &mut QueuedMove) {
        let dz = (m.path.end().z - m.path.start().z).abs();
        if dz > 0.0 {
            let z_ratio = q.move_d_mm / dz;
            q.limit_speed(
                self.max_z_velocity_mm_s * z_ratio,
                self.max_z_accel_mm_s2 * z_ratio,
            );
        }
        if let Some((slow_xy2, very_slow_xy2)) = self.edge_xy2_mm2 {
            let extreme_xy2 = m.path.max_xy2_mm2();
            if extreme_xy2 > slow_xy2 {
                let r = if extreme_xy2 > very_slow_xy2 {
                    0.25
                } else {
                    0.5
                };
                q.limit_speed(self.config_velocity_mm_s * r, self.config_accel_mm_s2 * r);
            }
        }
    }

    /// extruder.py `check_move`: a move with no XY motion, or a retract, is capped at the
    /// extrude-only limits divided by its |E|/length ratio.
    #[inline(always)] // see `QueuedMove`
    fn limit_extruder(&self, m: &Move, q: &mut QueuedMove) {
        let no_xy = !q.kinematic || !m.path.moves_xy();
        if no_xy || q.e_ratio < 0.0 {
            let inv = 1.0 / q.e_ratio.abs();
            q.limit_speed(self.max_e_velocity_mm_s * inv, self.max_e_accel_mm_s2 * inv);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::firmware::klipper::planner::tests::machine;
    use crate::path::Path;

    #[test]
    fn slow_radii_of_a_kossel() {
        // l = 215, R = 105: 3·215/√10 − 105 = 645/3.16227766 − 105 = 98.9669;
        // 6·215/√37 − 105 = 1290/6.08276253 − 105 = 107.0747.
        let m = machine();
        assert!((m.slow_radius_mm(3.0) - 98.9669).abs() < 1e-4);
        assert!((m.slow_radius_mm(6.0) - 107.0747).abs() < 1e-4);
    }

    #[test]
    fn a_path_with_a_non_finite_number_is_dropped() {
        let limits = MoveLimits::new(&machine());
        let mv = |path| Move {
            line: 1,
            path,
            e_mm: 1.0,
            feed_mm_s: 10.0,
            offset_mm: crate::path::Vec3::zeros(),
            arc: None,
        };
        let queued = |m: &Move| {
            let mut queued = false;
            limits.queued_move(m, |_| queued = true);
            queued
        };
        let p = crate::path::Vec3::new(0.0, 0.0, 10.0);
        let far = crate::path::Vec3::new(f64::INFINITY, 0.0, 10.0);
        assert!(!queued(&mv(Path::line(p, far))));
        assert!(queued(&mv(Path::line(p, p))));
        // A retract of 1e300 mm over 10 mm: the extruder cap's speed² underflows to 0.
        let q = crate::path::Vec3::new(0.0, 10.0, 10.0);
        let huge_retract = Move {
            e_mm: -1e300,
            ..mv(Path::line(p, q))
        };
        assert!(!queued(&huge_retract));
        let retract = Move {
            e_mm: -1e6,
            ..mv(Path::line(p, q))
        };
        assert!(queued(&retract));
    }

    #[test]
    fn junction_deviation_of_defaults() {
        // 5²·(√2 − 1)/3000 = 25·0.41421356/3000 = 0.00345178 mm.
        let t = MoveLimits::new(&machine()).toolhead;
        assert!((t.junction_deviation_mm() - 0.003_451_78).abs() < 1e-8);
        assert_eq!(t.mcr_pseudo_accel_mm_s2(), 1500.0);
    }
}
