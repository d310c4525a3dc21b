//! Kinematics: closure equations (eq. 2), inverse (eq. 6), direct (three spheres +
//! Newton–Raphson), Jacobians (eq. 3).

use super::{DeltaModel, Unreachable};
use crate::path::Vec3;

/// Smallest accepted radicand of eq. 6 (mm²): below it the arm is horizontal and Jq is
/// singular.
pub(super) const MIN_RADICAND_MM2: f64 = 1e-9;
/// Tolerance on the top of carriage travel, mm (rounding at the homed position).
pub(super) const TOP_TOLERANCE_MM: f64 = 1e-6;

#[inline(always)]
pub(super) fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

#[inline(always)]
pub(super) fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// The rows' cross products (r2×r3, r3×r1, r1×r2) and the determinant r1·(r2×r3) of the
/// 3×3 matrix with rows `r`: M⁻¹ has columns c_i/det, so M⁻ᵀ has rows c_i/det.
#[inline(always)]
pub(super) fn cofactors(r: &[[f64; 3]; 3]) -> ([[f64; 3]; 3], f64) {
    let c = [cross(r[1], r[2]), cross(r[2], r[0]), cross(r[0], r[1])];
    (c, dot(r[0], c[0]))
}

impl DeltaModel {
    /// Platform centre P of a nozzle position, mm.
    #[inline(always)]
    pub(super) fn platform_mm(&self, nozzle_mm: Vec3) -> [f64; 3] {
        [
            nozzle_mm.x,
            nozzle_mm.y,
            nozzle_mm.z + self.nozzle_offset_mm,
        ]
    }

    /// Inverse kinematics, eq. 6 with the '+' root (carriages above the platform): the
    /// heights q_i of the carriage joints A_i, mm.
    #[inline(always)]
    pub fn inverse(&self, nozzle_mm: Vec3) -> Result<[f64; 3], Unreachable> {
        let p = self.platform_mm(nozzle_mm);
        if !(p[0].is_finite() && p[1].is_finite() && p[2].is_finite()) {
            return Err(Unreachable::NotFinite);
        }
        // The error details are worked out only on the cold path.
        let radicand = self.radicands(p);
        if radicand.iter().any(|&r| r < MIN_RADICAND_MM2) {
            return Err(self.arm_too_short(p, radicand));
        }
        let q = [
            p[2] + radicand[0].sqrt(),
            p[2] + radicand[1].sqrt(),
            p[2] + radicand[2].sqrt(),
        ];
        if (0..3).any(|i| q[i] - self.top_mm[i] > TOP_TOLERANCE_MM) {
            return Err(self.above_top(q));
        }
        Ok(q)
    }

    /// The radicands of eq. 6, l_i² − (horizontal distance from the platform to tower i)²,
    /// mm²: the squared rise of each arm.
    #[inline(always)]
    pub(super) fn radicands(&self, p: [f64; 3]) -> [f64; 3] {
        let radicand_of = |i: usize| {
            let dx = p[0] - self.towers_mm[i][0];
            let dy = p[1] - self.towers_mm[i][1];
            self.arm2_mm2[i] - (dx * dx + dy * dy)
        };
        // Written out: `[T; N]::map` is not reliably inlined.
        [radicand_of(0), radicand_of(1), radicand_of(2)]
    }

    #[cold]
    fn arm_too_short(&self, p: [f64; 3], radicand: [f64; 3]) -> Unreachable {
        let tower = (0..3)
            .find(|&i| radicand[i] < MIN_RADICAND_MM2)
            .unwrap_or_default();
        let (dx, dy) = (
            p[0] - self.towers_mm[tower][0],
            p[1] - self.towers_mm[tower][1],
        );
        Unreachable::ArmTooShort {
            tower,
            horizontal_mm: dx.hypot(dy),
            arm_mm: self.arm_mm[tower],
        }
    }

    #[cold]
    fn above_top(&self, q: [f64; 3]) -> Unreachable {
        let tower = (0..3)
            .find(|&i| q[i] - self.top_mm[i] > TOP_TOLERANCE_MM)
            .unwrap_or_default();
        Unreachable::AboveTop {
            tower,
            over_mm: q[tower] - self.top_mm[tower],
        }
    }

    /// Rows of Jx (eq. 3): r_i = A_i − P = (B_i,x − x_P, B_i,y − y_P, q_i − z_P), mm. With
    /// Γ_i = l_i² − |P − A_i|², Jx = ½ ∂Γ/∂p and Jq = −½ ∂Γ/∂q = diag(q_i − z_P) = diag of the
    /// rows' third components; these signs give eq. 8 and eq. 13-14 exactly as printed.
    #[inline(always)]
    pub(super) fn jx_rows(&self, p: [f64; 3], q: [f64; 3]) -> [[f64; 3]; 3] {
        let t = &self.towers_mm;
        let row = |i: usize| [t[i][0] - p[0], t[i][1] - p[1], q[i] - p[2]];
        [row(0), row(1), row(2)]
    }

    /// Direct kinematics: the nozzle position for carriage heights `q_mm`, by three-sphere
    /// intersection (the lower of the two points, carriages above the platform), refined by
    /// two Newton–Raphson steps on eq. 2.
    pub fn forward(&self, q_mm: [f64; 3]) -> Result<Vec3, Unreachable> {
        if !q_mm.iter().all(|q| q.is_finite()) {
            return Err(Unreachable::NotFinite);
        }
        let none = Unreachable::NoForwardSolution { q_mm };
        let t = &self.towers_mm;
        let a = [0, 1, 2].map(|i| [t[i][0], t[i][1], q_mm[i]]);
        // Subtracting sphere 1 from spheres 2 and 3 leaves two planes n_k·P = d_k.
        let n1 = [a[1][0] - a[0][0], a[1][1] - a[0][1], a[1][2] - a[0][2]];
        let n2 = [a[2][0] - a[0][0], a[2][1] - a[0][1], a[2][2] - a[0][2]];
        let half = |i: usize| {
            0.5 * (dot(a[i], a[i]) - dot(a[0], a[0]) - self.arm2_mm2[i] + self.arm2_mm2[0])
        };
        let (d1, d2) = (half(1), half(2));
        let u = cross(n1, n2);
        let uu = dot(u, u);
        if uu < 1e-12 {
            return Err(none);
        }
        // A point of the planes' intersection line P0 + s·u.
        let (c1, c2) = (cross(n2, u), cross(u, n1));
        let p0 = [0, 1, 2].map(|k| (d1 * c1[k] + d2 * c2[k]) / uu);
        let w = [p0[0] - a[0][0], p0[1] - a[0][1], p0[2] - a[0][2]];
        let wu = dot(w, u);
        let disc = wu * wu - uu * (dot(w, w) - self.arm2_mm2[0]);
        if disc < 0.0 {
            return Err(none);
        }
        let root = disc.sqrt();
        let (s1, s2) = ((-wu - root) / uu, (-wu + root) / uu);
        let s = if p0[2] + s1 * u[2] <= p0[2] + s2 * u[2] {
            s1
        } else {
            s2
        };
        let mut p = [0, 1, 2].map(|k| p0[k] + s * u[k]);
        for _ in 0..2 {
            let rows = [0, 1, 2].map(|i| [p[0] - a[i][0], p[1] - a[i][1], p[2] - a[i][2]]);
            let f = [0, 1, 2].map(|i| 0.5 * (dot(rows[i], rows[i]) - self.arm2_mm2[i]));
            let (c, det) = cofactors(&rows);
            if det.abs() < 1e-12 {
                break;
            }
            for k in 0..3 {
                p[k] -= (c[0][k] * f[0] + c[1][k] * f[1] + c[2][k] * f[2]) / det;
            }
        }
        if !p.iter().all(|v| v.is_finite())
            || (0..3).any(|i| q_mm[i] - p[2] < MIN_RADICAND_MM2.sqrt())
        {
            return Err(none);
        }
        Ok(Vec3::new(p[0], p[1], p[2] - self.nozzle_offset_mm))
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_support::{kossel, workspace_points};
    use super::*;

    #[test]
    fn inverse_then_forward_round_trip_over_the_workspace() {
        let m = kossel();
        let mut n = 0;
        for p in workspace_points() {
            let q = m.inverse(p).unwrap();
            let back = m.forward(q).unwrap();
            assert!((back - p).norm() < 1e-9, "{p:?} -> {q:?} -> {back:?}");
            n += 1;
        }
        assert!(n > 500);
    }

    #[test]
    fn inverse_satisfies_the_closure_equations() {
        // eq. 2 written with s_B, s_P for the default tower angles.
        let m = kossel();
        let r = 105.0_f64;
        let s = r * 3f64.sqrt(); // s_B − s_P
        for p in workspace_points() {
            let q = m.inverse(p).unwrap();
            let (x, y, z) = (p.x, p.y, p.z + 3.0);
            let g = [
                (x + s / 2.0).powi(2) + (y + s / (2.0 * 3f64.sqrt())).powi(2) + (z - q[0]).powi(2),
                (x - s / 2.0).powi(2) + (y + s / (2.0 * 3f64.sqrt())).powi(2) + (z - q[1]).powi(2),
                x * x + (y - s / 3f64.sqrt()).powi(2) + (z - q[2]).powi(2),
            ];
            for (i, gi) in g.iter().enumerate() {
                let l = [215.0, 215.5, 214.5][i];
                assert!((gi - l * l).abs() < 1e-8, "{gi}");
                assert!(q[i] > z);
            }
        }
    }

    #[test]
    fn the_model_can_be_shared_between_threads() {
        fn shared<T: Send + Sync + Clone>() {}
        shared::<DeltaModel>();
        shared::<Unreachable>();
    }

    #[test]
    fn unreachable_points_are_errors_naming_the_tower() {
        let m = kossel();
        // Far beyond tower C's reach, on the far side from C (towards −y).
        let e = m.inverse(Vec3::new(0.0, -200.0, 0.0)).unwrap_err();
        assert_eq!(e.tower(), Some(2), "{e}");
        assert!(e.to_string().contains("tower C"));
        // Above the top of the carriages.
        let e = m.inverse(Vec3::new(0.0, 0.0, 400.0)).unwrap_err();
        assert!(matches!(e, Unreachable::AboveTop { .. }), "{e}");
        // Moving towards tower C at home height lifts carriage C above its top.
        let home = m.home_carriages_mm();
        assert!(m.inverse(Vec3::new(0.0, 0.0, 290.0)).unwrap() == home);
        let e = m.inverse(Vec3::new(0.0, 5.0, 290.0)).unwrap_err();
        assert_eq!(e.tower(), Some(2));
        assert_eq!(
            m.inverse(Vec3::new(f64::NAN, 0.0, 0.0)),
            Err(Unreachable::NotFinite)
        );
        // Forward kinematics: carriages too far apart for the arms to meet.
        let e = m.forward([0.0, 0.0, 1000.0]).unwrap_err();
        assert!(matches!(e, Unreachable::NoForwardSolution { .. }));
        assert!(m.forward([f64::INFINITY, 0.0, 0.0]).is_err());
    }
}
