//! The energy balance of eq. 20 where it can fail: the total energy K + U of sampled
//! states, differenced in time, against the power Σ Q_i q̇_i. (The analytic dE/dt of
//! `DeltaModel::evaluate` equals Σ Q_i q̇_i by construction, for any state; only a time
//! difference of K + U along a trajectory tests the forces.)

use super::{DeltaModel, Unreachable};
use crate::path::Vec3;

impl DeltaModel {
    /// Kinetic plus potential energy of the lumped masses at a nozzle position and
    /// velocity (mm, mm/s), J.
    pub fn energy_j(&self, pos_mm: Vec3, vel_mm_s: Vec3) -> Result<f64, Unreachable> {
        let s = self.evaluate(pos_mm, vel_mm_s, Vec3::zeros())?;
        Ok(s.kinetic_j + s.potential_j)
    }
}

/// d(K+U)/dt by central differences, W: for each sample k (times `t_s`, energies
/// `energy_j`) with neighbours at least `min_gap_s` before and after it, (index k, slope).
/// The neighbours differenced are the nearest samples at least `min_gap_s` away, so extra
/// samples at junctions and phase boundaries (a fraction of a period apart, or at the same
/// time) do not divide a velocity jump by a tiny interval.
pub fn energy_slope(t_s: &[f64], energy_j: &[f64], min_gap_s: f64) -> Vec<(usize, f64)> {
    let n = t_s.len().min(energy_j.len());
    let t = |k: usize| t_s[k];
    let (mut before, mut after) = (0, 0);
    let mut out = Vec::with_capacity(n);
    for k in 0..n {
        while before + 1 < k && t(k) - t(before + 1) >= min_gap_s {
            before += 1;
        }
        after = after.max(k);
        while after < n && t(after) - t(k) < min_gap_s {
            after += 1;
        }
        if after == n {
            break;
        }
        if t(k) - t(before) >= min_gap_s {
            out.push((
                k,
                (energy_j[after] - energy_j[before]) / (t(after) - t(before)),
            ));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::super::test_support::kossel;
    use super::*;

    #[test]
    fn energy_slope_matches_the_power_on_a_smooth_trajectory() {
        // Samples every 1 ms plus an extra one 10 µs after each (as at a junction), on
        // x = 40 sin 9t, y = 30 cos 7t, z = 20 + 10 t: the differenced energy must be the
        // model's power to the truncation of a 2 ms central difference.
        let model = kossel();
        let (mut t, mut energy, mut power) = (Vec::new(), Vec::new(), Vec::new());
        for k in 0..400 {
            for tk in [k as f64 * 1e-3, k as f64 * 1e-3 + 1e-5] {
                let (s9, c9, s7, c7) = (
                    (9.0 * tk).sin(),
                    (9.0 * tk).cos(),
                    (7.0 * tk).sin(),
                    (7.0 * tk).cos(),
                );
                let p = Vec3::new(40.0 * s9, 30.0 * c7, 20.0 + 10.0 * tk);
                let v = Vec3::new(360.0 * c9, -210.0 * s7, 10.0);
                let a = Vec3::new(-3240.0 * s9, -1470.0 * c7, 0.0);
                t.push(tk);
                energy.push(model.energy_j(p, v).unwrap());
                power.push(model.evaluate(p, v, a).unwrap().power_w);
            }
        }
        let slope = energy_slope(&t, &energy, 0.5e-3);
        assert!(slope.len() > 700, "{}", slope.len());
        let scale = power.iter().fold(0.0_f64, |m, p| m.max(p.abs()));
        for (i, s) in slope {
            assert!(
                (s - power[i]).abs() < 2e-3 * scale,
                "sample {i}: {s} vs {}",
                power[i]
            );
        }
    }

    #[test]
    fn a_wrong_force_shows_in_the_slope() {
        // The same trajectory with the energy of a platform 10 % heavier: the slope no
        // longer matches the power (the check can fail).
        let model = kossel();
        let heavy = DeltaModel {
            platform_kg: model.platform_kg * 1.1,
            ..model
        };
        let (mut t, mut energy, mut power) = (Vec::new(), Vec::new(), Vec::new());
        for k in 0..200 {
            let tk = k as f64 * 1e-3;
            let p = Vec3::new(40.0 * (9.0 * tk).sin(), 0.0, 20.0 + 10.0 * tk);
            let v = Vec3::new(360.0 * (9.0 * tk).cos(), 0.0, 10.0);
            let a = Vec3::new(-3240.0 * (9.0 * tk).sin(), 0.0, 0.0);
            t.push(tk);
            energy.push(heavy.energy_j(p, v).unwrap());
            power.push(model.evaluate(p, v, a).unwrap().power_w);
        }
        let worst = energy_slope(&t, &energy, 0.5e-3)
            .into_iter()
            .map(|(i, s)| (s - power[i]).abs())
            .fold(0.0, f64::max);
        assert!(worst > 0.01, "{worst}");
    }
}
