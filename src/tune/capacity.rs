//! Where the machine is weak: the largest nozzle acceleration a point of the print disc can
//! take in its worst direction, at rest or at a print speed, from the model (eq. 14) and
//! the motor's force at each carriage's speed. The picture for choosing `max_accel` and
//! `print_radius`.
//!
//! At a fixed pose and velocity the forces are affine in the nozzle's acceleration
//! (eq. 14: `M(q)q̈ + C(q, q̇)q̇ + G(q)`, q̈ affine in the nozzle's acceleration, eq. 8):
//! `Q(a·d) = Q(0) + a·k(d)`. So each tower bounds `a` exactly, without a search:
//! `|Q_i(0) + a·k_i| ≤ F_i`, F_i the force its motor gives at its carriage's speed.

use crate::delta::DeltaModel;
use crate::machine::Motors;
use crate::path::Vec3;

/// Directions tried in the plane of the bed (every 5°; each both ways).
const DIRECTIONS: usize = 36;
/// The acceleration of the probe evaluation, mm/s² (any: the law is affine).
const PROBE_MM_S2: f64 = 1000.0;

/// The largest acceleration, mm/s², that the nozzle at `pos_mm` can take in its worst
/// horizontal direction while moving at `speed_mm_s` along that direction (speeding up or
/// braking), every motor within the force it gives at its carriage's speed. 0 where even
/// a = 0 is too much; None where the pose is out of reach.
pub fn max_accel_mm_s2(
    model: &DeltaModel,
    motors: &Motors,
    pos_mm: Vec3,
    speed_mm_s: f64,
) -> Option<f64> {
    let mut worst = f64::INFINITY;
    for k in 0..DIRECTIONS {
        // Half a turn: the velocity both ways is the same set as the acceleration both ways
        // with the velocity reversed.
        let th = std::f64::consts::PI * k as f64 / DIRECTIONS as f64;
        for dir in [1.0, -1.0] {
            let d = Vec3::new(th.cos(), th.sin(), 0.0) * dir;
            let v = d * speed_mm_s;
            let base = model.evaluate(pos_mm, v, Vec3::zeros()).ok()?;
            let probe = model.evaluate(pos_mm, v, d * PROBE_MM_S2).ok()?;
            for i in 0..3 {
                let avail = motors.available_force_n(base.dq_mm_s[i]);
                let f0 = base.force_n[i];
                let slope = (probe.force_n[i] - f0) / PROBE_MM_S2;
                // Speeding up (a > 0) and braking (a < 0) along d.
                for s in [slope, -slope] {
                    let bound = if f0.abs() > avail {
                        0.0
                    } else if s > 0.0 {
                        (avail - f0) / s
                    } else if s < 0.0 {
                        (avail + f0) / -s
                    } else {
                        f64::INFINITY
                    };
                    worst = worst.min(bound);
                }
            }
        }
    }
    Some(worst)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::machine::test_support::kossel_machine;

    #[test]
    fn the_bound_is_where_a_motor_reaches_its_force() {
        let machine = kossel_machine();
        let model = machine.model();
        let motors = &machine.motors;
        let pos = Vec3::new(40.0, -25.0, 5.0);
        for speed in [0.0, 100.0] {
            let a = max_accel_mm_s2(&model, motors, pos, speed).unwrap();
            assert!(a > 0.0 && a.is_finite());
            // An independent scan: every direction at a just below the bound is within
            // every motor's force; some direction at a just above is not.
            let within = |acc: f64| {
                (0..720).all(|k| {
                    let th = std::f64::consts::TAU * k as f64 / 720.0;
                    let d = Vec3::new(th.cos(), th.sin(), 0.0);
                    [1.0, -1.0].iter().all(|s| {
                        let st = model.evaluate(pos, d * speed, d * (s * acc)).unwrap();
                        (0..3).all(|i| {
                            st.force_n[i].abs() <= motors.available_force_n(st.dq_mm_s[i]) + 1e-9
                        })
                    })
                })
            };
            assert!(within(0.999 * a), "{speed}: {a}");
            assert!(!within(1.05 * a), "{speed}: {a}");
        }
        // Out of reach: none.
        assert!(max_accel_mm_s2(&model, motors, Vec3::new(400.0, 0.0, 0.0), 0.0).is_none());
    }
}
