//! Statics (eq. 15-17) and workspace figures for the `machine` command.

use super::DeltaModel;
use crate::path::Vec3;

impl DeltaModel {
    /// Static actuator forces at a nozzle position, eq. 15 (eq. 14 with no motion), N.
    pub fn static_forces_n(&self, nozzle_mm: Vec3) -> Result<[f64; 3], super::Unreachable> {
        self.evaluate(nozzle_mm, Vec3::zeros(), Vec3::zeros())
            .map(|s| s.force_n)
    }

    /// Total weight of the suspended masses, the sum of the static forces anywhere
    /// (eq. 17): (6 m_link + m_plat + 3 m_cart) g, N.
    pub fn suspended_weight_n(&self) -> f64 {
        (3.0 * self.carriage_weight_kg + self.platform_kg) * self.gravity_m_s2
    }

    /// The largest static force on any carriage over the disc of `radius_mm` on the bed
    /// (polar scan, 1° and radius/100 steps; static forces do not depend on z). Returns the
    /// force (N), where it occurs and the tower (0 = A). Points the model cannot reach are
    /// skipped.
    pub fn max_static_force_n(&self, radius_mm: f64) -> Option<(f64, Vec3, usize)> {
        const RINGS: usize = 100;
        let mut best: Option<(f64, Vec3, usize)> = None;
        for ring in 0..=RINGS {
            let r = radius_mm * ring as f64 / RINGS as f64;
            let steps = if ring == 0 { 1 } else { 360 };
            for k in 0..steps {
                let (s, c) = (k as f64).to_radians().sin_cos();
                let p = Vec3::new(r * c, r * s, 0.0);
                let Ok(f) = self.static_forces_n(p) else {
                    continue;
                };
                for (i, fi) in f.iter().enumerate() {
                    if best.is_none_or(|b| fi.abs() > b.0) {
                        best = Some((fi.abs(), p, i));
                    }
                }
            }
        }
        best
    }

    /// Radius of the largest disc centred on the Z axis that the nozzle can reach at height
    /// `z_mm`: every arm's radicand stays positive (r < l_i − R) and no carriage rises above
    /// its homed height. A carriage's height depends only on the distance d to its tower
    /// line, z + PQ + √(l² − d²), and over a disc of radius r that distance is at least
    /// |R − r|, which gives r ≤ R − √(l² − h²) with h = home_z − z + √(l² − R²) when h < l.
    /// 0 when even the centre is out of reach.
    pub fn reachable_radius_mm(&self, z_mm: f64) -> f64 {
        let big_r = self.delta_radius_mm;
        let mut radius = f64::INFINITY;
        for i in 0..3 {
            let l2 = self.arm2_mm2[i];
            let mut r = self.arm_mm[i] - big_r;
            // Height of the top above this z, as the vertical arm component it allows.
            let h = self.top_mm[i] - self.nozzle_offset_mm - z_mm;
            if h < 0.0 {
                return 0.0;
            }
            if h * h < l2 {
                r = r.min(big_r - (l2 - h * h).sqrt());
            }
            radius = radius.min(r);
        }
        radius.max(0.0)
    }
}

impl DeltaModel {
    /// The highest nozzle z at which the whole disc of `radius_mm` is reachable (the
    /// inverse of [`DeltaModel::reachable_radius_mm`] on the carriage-top constraint):
    /// min_i [home_z + √(l_i² − R²) − √(l_i² − (R − r)²)], mm.
    pub fn full_disc_top_mm(&self, radius_mm: f64) -> f64 {
        let d = self.delta_radius_mm - radius_mm;
        (0..3)
            .map(|i| {
                let l2 = self.arm2_mm2[i];
                self.top_mm[i] - self.nozzle_offset_mm - (l2 - d * d).max(0.0).sqrt()
            })
            .fold(f64::INFINITY, f64::min)
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_support::kossel;
    use super::*;

    /// Whether every point of the circle of `r` at height `z` is reachable (brute force).
    fn circle_reachable(m: &DeltaModel, r: f64, z: f64) -> bool {
        (0..720).all(|k| {
            let th = (k as f64 * 0.5).to_radians();
            m.inverse(Vec3::new(r * th.cos(), r * th.sin(), z)).is_ok()
        })
    }

    #[test]
    fn reachable_radius_agrees_with_the_inverse_kinematics() {
        let m = kossel();
        for z in [0.0, 50.0, 150.0, 250.0, 285.0] {
            let r = m.reachable_radius_mm(z);
            assert!(r > 0.0, "z {z}");
            assert!(circle_reachable(&m, r * 0.999, z), "z {z} r {r}");
            assert!(!circle_reachable(&m, r * 1.001 + 1e-3, z), "z {z} r {r}");
        }
        // At the homed height only the centre is left, and nothing above it.
        assert!(m.reachable_radius_mm(290.0) < 1e-6);
        assert_eq!(m.reachable_radius_mm(300.0), 0.0);
    }

    #[test]
    fn full_disc_top_inverts_reachable_radius() {
        let m = kossel();
        for r in [10.0, 50.0, 85.0] {
            let z = m.full_disc_top_mm(r);
            assert!(z > 0.0 && z < 290.0);
            assert!((m.reachable_radius_mm(z) - r).abs() < 1e-6, "r {r} z {z}");
        }
    }

    #[test]
    fn max_static_force_is_off_centre_and_above_the_centre_value() {
        let m = kossel();
        let (f, at, _) = m.max_static_force_n(85.0).unwrap();
        let centre = m.static_forces_n(Vec3::zeros()).unwrap();
        assert!(f > centre.iter().fold(0.0, |a: f64, b| a.max(*b)));
        assert!(at.norm() > 80.0);
    }
}
