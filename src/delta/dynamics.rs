//! Velocities and accelerations of the carriages (eq. 7-8), the Lagrange multipliers and
//! actuator forces (eq. 13-14), energy and power (eq. 20).

use serde::Serialize;

use super::kinematics::{MIN_RADICAND_MM2, TOP_TOLERANCE_MM, cofactors, dot};
use super::{DeltaModel, Unreachable};
use crate::interval::greater;
use crate::path::Vec3;

const MM: f64 = 1e-3;

/// The model at one nozzle state. Carriage quantities in mm, mm/s, mm/s²; forces in N;
/// λ in N/m (the closure equations Γ_i are in m²); energies in J, powers in W.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct DynState {
    /// Carriage heights (eq. 6), mm.
    pub q_mm: [f64; 3],
    /// Carriage velocities (eq. 7), mm/s.
    pub dq_mm_s: [f64; 3],
    /// Carriage accelerations (eq. 8), mm/s².
    pub ddq_mm_s2: [f64; 3],
    /// Actuator forces Q_i (eq. 14), N, positive upwards.
    pub force_n: [f64; 3],
    /// Lagrange multipliers λ_i (eq. 13), N/m.
    pub lambda: [f64; 3],
    /// Each parallelogram's pull on the platform towards its carriage, both rods together,
    /// N, positive in tension: the constraint force λ_i·∂Γ_i/∂P = 2λ_i·(A_i − P), of
    /// magnitude 2|λ_i|·l.
    pub arm_tension_n: [f64; 3],
    /// Kinetic energy of the lumped masses, J.
    pub kinetic_j: f64,
    /// Potential energy, bed (z = 0) reference, J.
    pub potential_j: f64,
    /// Σ Q_i q̇_i, the right side of eq. 20, W.
    pub power_w: f64,
    /// d(K + U)/dt from the kinematics alone, the left side of eq. 20, W.
    pub energy_rate_w: f64,
    /// Condition number of Jx in the Frobenius norm, ‖Jx‖_F·‖Jx⁻¹‖_F (between κ₂ and 3κ₂).
    pub jx_condition: f64,
}

/// The forces and the energy balance at one nozzle state, computed without a branch so
/// that a block of states vectorises. When `ok` is false (the pose is unreachable, Jx is
/// singular or an input is not finite) the other fields are meaningless, though never used.
#[derive(Clone, Copy)]
struct Core {
    ok: bool,
    q: [f64; 3],
    dq: [f64; 3],
    ddq: [f64; 3],
    force: [f64; 3],
    /// Jx⁻ᵀ (p̈ + g e_z), 1/mm · m/s².
    w: [f64; 3],
    cof: [[f64; 3]; 3],
    inv_det: f64,
    power_w: f64,
    energy_rate_w: f64,
}

impl DeltaModel {
    /// Everything the check needs (eq. 6-8, 14, 20) at a nozzle position, velocity and
    /// acceleration (mm, mm/s, mm/s²), branch-free. Closed forms throughout: Jq is diagonal,
    /// and Jx⁻ᵀ comes from the cross products of Jx's rows (the arm vectors), so nothing is
    /// factorised or allocated.
    #[inline(always)]
    fn core(&self, pos_mm: Vec3, v: [f64; 3], a: [f64; 3]) -> Core {
        let p = self.platform_mm(pos_mm);
        let radicand = self.radicands(p);
        // Clamped so that an unreachable lane computes finite garbage, flagged by `ok`.
        let q = [
            p[2] + greater(radicand[0], MIN_RADICAND_MM2).sqrt(),
            p[2] + greater(radicand[1], MIN_RADICAND_MM2).sqrt(),
            p[2] + greater(radicand[2], MIN_RADICAND_MM2).sqrt(),
        ];
        let rows = self.jx_rows(p, q);
        let (cof, det) = cofactors(&rows);
        // A NaN or infinity anywhere makes the sum non-finite (so does a sum beyond 1e308,
        // which no printer asks for): one test instead of nine. `&`, not `&&`: no branch.
        let ok = (p[0] + p[1] + p[2] + v[0] + v[1] + v[2] + a[0] + a[1] + a[2]).is_finite()
            & (radicand[0] >= MIN_RADICAND_MM2)
            & (radicand[1] >= MIN_RADICAND_MM2)
            & (radicand[2] >= MIN_RADICAND_MM2)
            & (q[0] - self.top_mm[0] <= TOP_TOLERANCE_MM)
            & (q[1] - self.top_mm[1] <= TOP_TOLERANCE_MM)
            & (q[2] - self.top_mm[2] <= TOP_TOLERANCE_MM)
            & (det.abs() > self.singular_det_mm3);
        let g = self.gravity_m_s2;
        // Jx⁻ᵀ (p̈ + g e_z), in 1/mm · m/s² (eq. 13-14).
        let b = [a[0] * MM, a[1] * MM, a[2] * MM + g];
        let jq = [rows[0][2], rows[1][2], rows[2][2]]; // q_i − z_P > 0
        let inv_det = 1.0 / det;
        let inv_jq = [1.0 / jq[0], 1.0 / jq[1], 1.0 / jq[2]];
        let w = [
            dot(cof[0], b) * inv_det,
            dot(cof[1], b) * inv_det,
            dot(cof[2], b) * inv_det,
        ];
        let mut dq = [0.0; 3];
        let mut ddq = [0.0; 3];
        let mut force = [0.0; 3];
        for i in 0..3 {
            // eq. 7: q̇_i = (Jx ṗ)_i / Jq_ii.
            dq[i] = dot(rows[i], v) * inv_jq[i];
            // eq. 8: q̈_i = ((Jx p̈)_i − (ẋ² + ẏ² + (ż − q̇_i)²)) / Jq_ii.
            let dz = v[2] - dq[i];
            ddq[i] = (dot(rows[i], a) - (v[0] * v[0] + v[1] * v[1] + dz * dz)) * inv_jq[i];
            // eq. 14 (Jq Jx⁻ᵀ is dimensionless: mm · 1/mm).
            // The carriage's inertia and weight differ by the reflected rotor mass.
            force[i] = self.carriage_inertia_kg * ddq[i] * MM
                + self.carriage_weight_kg * g
                + self.platform_kg * jq[i] * w[i];
        }
        let (mi, mw, mp) = (
            self.carriage_inertia_kg,
            self.carriage_weight_kg,
            self.platform_kg,
        );
        let power_w = dot(force, dq) * MM;
        // eq. 20, left side: d/dt of K and U (see `evaluate`).
        let energy_rate_w = (mi * dot(dq, ddq) + mp * dot(v, a)) * MM * MM
            + g * (mw * (dq[0] + dq[1] + dq[2]) + mp * v[2]) * MM;
        Core {
            ok,
            q,
            dq,
            ddq,
            force,
            w,
            cof,
            inv_det,
            power_w,
            energy_rate_w,
        }
    }

    /// The full model at a nozzle position, velocity and acceleration (mm, mm/s, mm/s²).
    /// Inlined, so that a caller that reads only some outputs pays only for them.
    #[inline(always)]
    pub fn evaluate(
        &self,
        pos_mm: Vec3,
        vel_mm_s: Vec3,
        acc_mm_s2: Vec3,
    ) -> Result<DynState, Unreachable> {
        let v = [vel_mm_s.x, vel_mm_s.y, vel_mm_s.z];
        let a = [acc_mm_s2.x, acc_mm_s2.y, acc_mm_s2.z];
        let c = self.core(pos_mm, v, a);
        if !c.ok {
            return Err(self.why_not(pos_mm, vel_mm_s, acc_mm_s2));
        }
        let (q, dq, p_z) = (c.q, c.dq, self.platform_mm(pos_mm)[2]);
        let (mi, mw, mp, g) = (
            self.carriage_inertia_kg,
            self.carriage_weight_kg,
            self.platform_kg,
            self.gravity_m_s2,
        );
        // K with the carriages' inertia, U with their weight (the rotor adds only to K).
        let kinetic_j = 0.5 * (mi * dot(dq, dq) + mp * dot(v, v)) * MM * MM;
        let potential_j = g * (mw * (q[0] + q[1] + q[2]) + mp * p_z) * MM;
        let arm2_sum = self.arm2_mm2[0] + self.arm2_mm2[1] + self.arm2_mm2[2];
        let cof = &c.cof;
        let inv_f2 = (dot(cof[0], cof[0]) + dot(cof[1], cof[1]) + dot(cof[2], cof[2]))
            * c.inv_det
            * c.inv_det;
        // eq. 13, Jx in m: Jx⁻ᵀ in 1/m = 1000 × its value in 1/mm.
        let lambda = c.w.map(|w| 0.5 * mp * w / MM);
        Ok(DynState {
            q_mm: q,
            dq_mm_s: dq,
            ddq_mm_s2: c.ddq,
            force_n: c.force,
            lambda,
            arm_tension_n: [0, 1, 2].map(|i| self.arm_tension_n(i, c.w[i])),
            kinetic_j,
            potential_j,
            power_w: c.power_w,
            energy_rate_w: c.energy_rate_w,
            jx_condition: (arm2_sum * inv_f2).sqrt(),
        })
    }

    /// The tension of parallelogram `i`, 2λ_i·l_i (λ_i of eq. 13 in N/m, l in m), from
    /// w_i = (Jx⁻ᵀ (p̈ + g e_z))_i in 1/mm · m/s²: λ_i = ½·(m_plat + 3 m_link)·w_i/mm.
    #[inline(always)]
    fn arm_tension_n(&self, i: usize, w: f64) -> f64 {
        self.platform_kg * w * self.arm_mm[i]
    }

    /// Why [`Self::core`] found a state invalid.
    #[cold]
    fn why_not(&self, pos_mm: Vec3, vel_mm_s: Vec3, acc_mm_s2: Vec3) -> Unreachable {
        match self.inverse(pos_mm) {
            Err(e) => e,
            Ok(_) if !(vel_mm_s.iter().chain(acc_mm_s2.iter())).all(|x| x.is_finite()) => {
                Unreachable::NotFinite
            }
            Ok(_) => Unreachable::Singular,
        }
    }

    /// Actuator forces (eq. 14), carriage velocities (eq. 7) and arm tensions (eq. 13) over
    /// a block of states,
    /// the first `len` lanes (the lanes after them, up to a multiple of eight, are computed
    /// too, from whatever they hold, and mean nothing). Compiled for AVX-512 and AVX2 as well
    /// as the baseline, chosen at run time: the same operations in the same order, so the
    /// results are the same bit for bit whichever runs.
    pub fn forces_block(&self, states: &StateBlock, len: usize, out: &mut ForceBlock) {
        // Whole vectors only: no scalar remainder loop.
        let lanes = len.next_multiple_of(8).min(BLOCK);
        #[cfg(target_arch = "x86_64")]
        {
            if std::arch::is_x86_feature_detected!("avx512f") {
                // SAFETY: the CPU has AVX-512F, checked just above.
                unsafe { self.forces_block_avx512(states, lanes, out) };
                return;
            }
            if std::arch::is_x86_feature_detected!("avx2") {
                // SAFETY: the CPU has AVX2, checked just above.
                unsafe { self.forces_block_avx2(states, lanes, out) };
                return;
            }
        }
        self.forces_block_generic(states, lanes, out);
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f")]
    fn forces_block_avx512(&self, states: &StateBlock, lanes: usize, out: &mut ForceBlock) {
        self.forces_block_generic(states, lanes, out);
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn forces_block_avx2(&self, states: &StateBlock, lanes: usize, out: &mut ForceBlock) {
        self.forces_block_generic(states, lanes, out);
    }

    #[inline(always)]
    fn forces_block_generic(&self, s: &StateBlock, lanes: usize, out: &mut ForceBlock) {
        for j in 0..lanes.min(BLOCK) {
            let c = self.core(
                Vec3::new(s.pos_mm[0][j], s.pos_mm[1][j], s.pos_mm[2][j]),
                [s.vel_mm_s[0][j], s.vel_mm_s[1][j], s.vel_mm_s[2][j]],
                [s.acc_mm_s2[0][j], s.acc_mm_s2[1][j], s.acc_mm_s2[2][j]],
            );
            out.force_n[0][j] = c.force[0];
            out.force_n[1][j] = c.force[1];
            out.force_n[2][j] = c.force[2];
            out.dq_mm_s[0][j] = c.dq[0];
            out.dq_mm_s[1][j] = c.dq[1];
            out.dq_mm_s[2][j] = c.dq[2];
            for i in 0..3 {
                out.tension_n[i][j] = self.arm_tension_n(i, c.w[i]);
            }
            out.ok[j] = c.ok;
        }
    }
}

/// States handed to [`DeltaModel::forces_block`] at a time.
pub const BLOCK: usize = 128;

/// A block of nozzle states, one array per coordinate (so that lanes vectorise): mm, mm/s,
/// mm/s².
#[derive(Clone, Debug)]
pub struct StateBlock {
    pub pos_mm: [[f64; BLOCK]; 3],
    pub vel_mm_s: [[f64; BLOCK]; 3],
    pub acc_mm_s2: [[f64; BLOCK]; 3],
}

/// What [`DeltaModel::forces_block`] finds for each state of a block.
#[derive(Clone, Debug)]
pub struct ForceBlock {
    /// Q_i (eq. 14), N.
    pub force_n: [[f64; BLOCK]; 3],
    /// q̇_i (eq. 7), mm/s: what the motor's available force depends on.
    pub dq_mm_s: [[f64; BLOCK]; 3],
    /// Each parallelogram's tension, 2λ_i·l_i (eq. 13), N.
    pub tension_n: [[f64; BLOCK]; 3],
    /// False where the state has no valid pose: [`DeltaModel::evaluate`] says why.
    pub ok: [bool; BLOCK],
}

impl Default for StateBlock {
    fn default() -> Self {
        StateBlock {
            pos_mm: [[0.0; BLOCK]; 3],
            vel_mm_s: [[0.0; BLOCK]; 3],
            acc_mm_s2: [[0.0; BLOCK]; 3],
        }
    }
}

impl Default for ForceBlock {
    fn default() -> Self {
        ForceBlock {
            force_n: [[0.0; BLOCK]; 3],
            dq_mm_s: [[0.0; BLOCK]; 3],
            tension_n: [[0.0; BLOCK]; 3],
            ok: [false; BLOCK],
        }
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::{Matrix3, Matrix6, Vector6};

    use super::super::Geometry;
    use super::super::test_support::{
        GRAVITY_M_S2, KOSSEL, PAPER_MASSES, Rng, kossel, workspace_points,
    };
    use super::*;

    fn paper_equal_arms() -> DeltaModel {
        let g = Geometry {
            arm_length_mm: [215.0; 3],
            ..KOSSEL
        };
        DeltaModel::new(&g, &PAPER_MASSES, GRAVITY_M_S2)
    }

    /// Nozzle on the parabola p0 + v t + a t²/2 and its carriage heights by eq. 6 alone.
    fn q_at(m: &DeltaModel, p0: Vec3, v: Vec3, a: Vec3, t: f64) -> [f64; 3] {
        m.inverse(p0 + v * t + a * (0.5 * t * t)).unwrap()
    }

    /// Random states over the workspace: (position, velocity, acceleration).
    fn random_states(n: usize) -> Vec<(Vec3, Vec3, Vec3)> {
        let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
        let all = workspace_points().count();
        workspace_points()
            .step_by((all / n).max(1))
            .map(|p| {
                let mut r3 =
                    |s: f64| Vec3::new(rng.range(-s, s), rng.range(-s, s), rng.range(-s, s));
                (p, r3(300.0), r3(20000.0))
            })
            .collect()
    }

    #[test]
    #[allow(clippy::needless_range_loop)] // i, k index Γ, the rows and the coordinates
    fn jacobians_are_half_the_gradients_of_the_closure_equations() {
        // Γ_i = l_i² − |P − A_i|² differentiated by central differences.
        let m = kossel();
        let gamma = |p: [f64; 3], q: [f64; 3], i: usize| {
            let t = m.towers_mm[i];
            m.arm2_mm2[i] - (p[0] - t[0]).powi(2) - (p[1] - t[1]).powi(2) - (p[2] - q[i]).powi(2)
        };
        let h = 1e-4;
        for pos in workspace_points().step_by(7) {
            let q = m.inverse(pos).unwrap();
            let p = m.platform_mm(pos);
            let rows = m.jx_rows(p, q);
            for i in 0..3 {
                for k in 0..3 {
                    let (mut pp, mut pm) = (p, p);
                    pp[k] += h;
                    pm[k] -= h;
                    let jx = 0.5 * (gamma(pp, q, i) - gamma(pm, q, i)) / (2.0 * h);
                    assert!(
                        (jx - rows[i][k]).abs() < 1e-6,
                        "Jx[{i}][{k}] {jx} vs {}",
                        rows[i][k]
                    );
                    let (mut qp, mut qm) = (q, q);
                    qp[k] += h;
                    qm[k] -= h;
                    let jq = -0.5 * (gamma(p, qp, i) - gamma(p, qm, i)) / (2.0 * h);
                    let expected = if i == k { rows[i][2] } else { 0.0 };
                    assert!(
                        (jq - expected).abs() < 1e-6,
                        "Jq[{i}][{k}] {jq} vs {expected}"
                    );
                }
            }
        }
    }

    #[test]
    fn eq7_and_eq8_match_finite_differences_of_the_inverse_kinematics() {
        let m = kossel();
        let h = 1e-4;
        for (p, v, a) in random_states(400) {
            let s = m.evaluate(p, v, a).unwrap();
            let (qp, q0, qm) = (
                q_at(&m, p, v, a, h),
                q_at(&m, p, v, a, 0.0),
                q_at(&m, p, v, a, -h),
            );
            for i in 0..3 {
                let dq = (qp[i] - qm[i]) / (2.0 * h);
                let ddq = (qp[i] - 2.0 * q0[i] + qm[i]) / (h * h);
                assert!(
                    (dq - s.dq_mm_s[i]).abs() < 1e-4 * (1.0 + dq.abs()),
                    "dq {dq} vs {}",
                    s.dq_mm_s[i]
                );
                // Truncation h²/12·q'''' grows with the acceleration scale.
                let tol = 1e-4 * ddq.abs() + 1e-6 * (a.norm() + v.norm_squared());
                assert!(
                    (ddq - s.ddq_mm_s2[i]).abs() < tol,
                    "ddq {ddq} vs {}",
                    s.ddq_mm_s2[i]
                );
                // eq. 3: Jx ṗ = Jq q̇ with the differenced q̇.
                let rows = m.jx_rows(m.platform_mm(p), s.q_mm);
                let lhs = dot(rows[i], [v.x, v.y, v.z]);
                let tol = 1e-6 * 215.0 * (v.norm() + dq.abs()) + 1e-9;
                assert!(
                    (lhs - rows[i][2] * dq).abs() < tol,
                    "{lhs} vs {}",
                    rows[i][2] * dq
                );
            }
        }
    }

    #[test]
    fn forces_match_a_direct_solve_of_the_lagrange_equations() {
        // eq. 9-11 built independently: generalised coordinates (q1, q2, q3, x, y, z) in m,
        // M = diag(m_c, m_c, m_c, m_p, m_p, m_p), gravity F = ∂U/∂q, constraint gradients
        // ∂Γ_i/∂q by finite differences, accelerations of q by differencing eq. 6.
        let m = kossel();
        let (mc, mp, g) = (0.25 + 0.02, 0.5 + 0.06, 9.81);
        let h = 1e-4;
        for (p, v, a) in random_states(300) {
            let s = m.evaluate(p, v, a).unwrap();
            let (qp, q0, qm) = (
                q_at(&m, p, v, a, h),
                q_at(&m, p, v, a, 0.0),
                q_at(&m, p, v, a, -h),
            );
            let ddq = [0, 1, 2].map(|i| (qp[i] - 2.0 * q0[i] + qm[i]) / (h * h) * 1e-3);
            let pc = m.platform_mm(p).map(|x| x * 1e-3);
            let qs = q0.map(|x| x * 1e-3);
            let coords = Vector6::new(qs[0], qs[1], qs[2], pc[0], pc[1], pc[2]);
            let gamma = |c: &Vector6<f64>, i: usize| {
                let t = m.towers_mm[i];
                (m.arm_mm[i] * 1e-3).powi(2)
                    - (c[3] - t[0] * 1e-3).powi(2)
                    - (c[4] - t[1] * 1e-3).powi(2)
                    - (c[5] - c[i]).powi(2)
            };
            let mut lhs = Matrix6::zeros();
            let eps = 1e-7;
            for j in 0..6 {
                for i in 0..3 {
                    let (mut cp, mut cm) = (coords, coords);
                    cp[j] += eps;
                    cm[j] -= eps;
                    lhs[(j, i)] = (gamma(&cp, i) - gamma(&cm, i)) / (2.0 * eps);
                }
                if j < 3 {
                    lhs[(j, 3 + j)] = 1.0;
                }
            }
            let mass = Vector6::new(mc, mc, mc, mp, mp, mp);
            let acc = Vector6::new(ddq[0], ddq[1], ddq[2], a.x * 1e-3, a.y * 1e-3, a.z * 1e-3);
            let gravity = Vector6::new(mc * g, mc * g, mc * g, 0.0, 0.0, mp * g);
            let rhs = mass.component_mul(&acc) + gravity;
            let x = lhs.lu().solve(&rhs).unwrap();
            for i in 0..3 {
                let (lam, q) = (x[i], x[3 + i]);
                assert!(
                    (q - s.force_n[i]).abs() < 1e-5 * (1.0 + q.abs()),
                    "Q{i} {q} vs {}",
                    s.force_n[i]
                );
                assert!(
                    (lam - s.lambda[i]).abs() < 1e-5 * (1.0 + lam.abs()),
                    "λ{i} {lam} vs {}",
                    s.lambda[i]
                );
                // The constraint's force on the platform, λ_i·∂Γ_i/∂(x, y, z) from the
                // solve, against the arm: along it, towards the carriage when positive.
                let force = Vec3::new(lhs[(3, i)], lhs[(4, i)], lhs[(5, i)]) * lam;
                let t = m.towers_mm[i];
                let to_carriage =
                    Vec3::new(t[0] * 1e-3 - pc[0], t[1] * 1e-3 - pc[1], qs[i] - pc[2]);
                let along = force.dot(&to_carriage.normalize());
                assert!(
                    (along - s.arm_tension_n[i]).abs() < 1e-5 * (1.0 + along.abs()),
                    "tension {i}: {along} vs {}",
                    s.arm_tension_n[i]
                );
                assert!((force.norm() - along.abs()).abs() < 1e-6 * (1.0 + along.abs()));
            }
        }
    }

    #[test]
    fn eq16_static_forces_at_the_centre() {
        let m = paper_equal_arms();
        let expected = 9.81 * (2.0 * 0.02 + 0.25 + 0.5 / 3.0);
        for z in [0.0, 100.0, 250.0] {
            let f = m.static_forces_n(Vec3::new(0.0, 0.0, z)).unwrap();
            for fi in f {
                assert!((fi - expected).abs() < 1e-12, "{fi} vs {expected}");
            }
        }
    }

    #[test]
    fn eq17_static_forces_sum_to_the_suspended_weight() {
        for m in [kossel(), paper_equal_arms()] {
            assert!((m.suspended_weight_n() - 13.4397).abs() < 1e-9);
            for p in workspace_points() {
                let f = m.static_forces_n(p).unwrap();
                assert!(
                    (f.iter().sum::<f64>() - 13.4397).abs() < 1e-9,
                    "{f:?} at {p:?}"
                );
            }
        }
        // Off centre the forces differ (the test above is not trivially symmetric).
        let f = paper_equal_arms()
            .static_forces_n(Vec3::new(60.0, 0.0, 0.0))
            .unwrap();
        assert!((f[0] - f[1]).abs() > 0.1);
    }

    /// A smooth random trajectory: per axis a sum of two sines around a centre.
    struct Trajectory {
        centre: Vec3,
        amp: [[f64; 2]; 3],
        omega: [[f64; 2]; 3],
        phase: [[f64; 2]; 3],
    }

    impl Trajectory {
        fn random(rng: &mut Rng) -> Self {
            let mut pick =
                |lo: f64, hi: f64| [(); 3].map(|()| [rng.range(lo, hi), rng.range(lo, hi)]);
            let amp = pick(5.0, 25.0);
            let omega = pick(2.0, 40.0);
            let phase = pick(0.0, 6.3);
            let centre = Vec3::new(
                rng.range(-30.0, 30.0),
                rng.range(-30.0, 30.0),
                rng.range(60.0, 150.0),
            );
            Trajectory {
                centre,
                amp,
                omega,
                phase,
            }
        }
        /// Position, velocity, acceleration at t.
        fn at(&self, t: f64) -> (Vec3, Vec3, Vec3) {
            let (mut p, mut v, mut a) = (self.centre, Vec3::zeros(), Vec3::zeros());
            for k in 0..3 {
                for j in 0..2 {
                    let (amp, w, f) = (self.amp[k][j], self.omega[k][j], self.phase[k][j]);
                    let (s, c) = (w * t + f).sin_cos();
                    p[k] += amp * s;
                    v[k] += amp * w * c;
                    a[k] -= amp * w * w * s;
                }
            }
            (p, v, a)
        }
    }

    #[test]
    fn eq20_energy_rate_equals_actuator_power_along_random_trajectories() {
        let m = kossel();
        let mut rng = Rng(42);
        for _ in 0..20 {
            let traj = Trajectory::random(&mut rng);
            let energy = |t: f64| {
                let (p, v, a) = traj.at(t);
                let s = m.evaluate(p, v, a).unwrap();
                s.kinetic_j + s.potential_j
            };
            for k in 0..200 {
                let t = k as f64 * 0.005;
                let (p, v, a) = traj.at(t);
                let s = m.evaluate(p, v, a).unwrap();
                let scale = s.power_w.abs().max(s.energy_rate_w.abs()).max(1e-3);
                assert!((s.power_w - s.energy_rate_w).abs() < 1e-6 * scale, "{s:?}");
                // And the energy itself, differenced in time: an independent check of the
                // velocities and accelerations that power_w is built from.
                let h = 2e-6;
                let de = (energy(t + h) - energy(t - h)) / (2.0 * h);
                let tol = 1e-6 * (s.power_w.abs() + 1.0);
                assert!((de - s.power_w).abs() < tol, "{de} vs {}", s.power_w);
            }
        }
    }

    #[test]
    fn condition_number_brackets_the_two_norm_one() {
        let m = kossel();
        for p in workspace_points() {
            let s = m.evaluate(p, Vec3::zeros(), Vec3::zeros()).unwrap();
            let rows = m.jx_rows(m.platform_mm(p), s.q_mm);
            let jx = Matrix3::from_fn(|i, k| rows[i][k]);
            let sv = jx.singular_values();
            let k2 = sv.max() / sv.min();
            assert!(
                s.jx_condition >= k2 * (1.0 - 1e-12) && s.jx_condition <= 3.0 * k2,
                "{} vs {k2}",
                s.jx_condition
            );
        }
    }

    #[test]
    fn no_nan_for_non_finite_input() {
        let m = kossel();
        let bad = Vec3::new(f64::NAN, 0.0, 0.0);
        assert!(m.evaluate(Vec3::zeros(), bad, Vec3::zeros()).is_err());
        assert!(m.evaluate(Vec3::zeros(), Vec3::zeros(), bad).is_err());
    }

    #[test]
    fn a_block_gives_the_forces_of_evaluate_bit_for_bit() {
        // Random states, with unreachable, above-top and non-finite lanes among them; a
        // partial block; every instruction set this CPU has against the baseline.
        let m = kossel();
        let mut states = StateBlock::default();
        let all = random_states(BLOCK);
        for (j, &(p, v, a)) in all.iter().take(BLOCK).enumerate() {
            let p = match j % 16 {
                3 => Vec3::new(0.0, -400.0, 10.0), // arm too short
                7 => Vec3::new(0.0, 0.0, 400.0),   // above the top
                11 => Vec3::new(f64::NAN, 0.0, 0.0),
                _ => p,
            };
            let a = if j % 16 == 13 {
                Vec3::new(0.0, f64::INFINITY, 0.0)
            } else {
                a
            };
            for k in 0..3 {
                states.pos_mm[k][j] = p[k];
                states.vel_mm_s[k][j] = v[k];
                states.acc_mm_s2[k][j] = a[k];
            }
        }
        let len = BLOCK - 5;
        let mut fast = ForceBlock::default();
        m.forces_block(&states, len, &mut fast);
        let mut base = ForceBlock::default();
        m.forces_block_generic(&states, len, &mut base);
        let mut bad = 0;
        for j in 0..len {
            let at = |c: &[[f64; BLOCK]; 3]| Vec3::new(c[0][j], c[1][j], c[2][j]);
            let s = m.evaluate(
                at(&states.pos_mm),
                at(&states.vel_mm_s),
                at(&states.acc_mm_s2),
            );
            assert_eq!(fast.ok[j], s.is_ok(), "lane {j}: {s:?}");
            assert_eq!(base.ok[j], fast.ok[j]);
            let Ok(s) = s else {
                bad += 1;
                continue;
            };
            for i in 0..3 {
                assert_eq!(fast.force_n[i][j].to_bits(), s.force_n[i].to_bits());
                assert_eq!(base.force_n[i][j].to_bits(), s.force_n[i].to_bits());
            }
            for i in 0..3 {
                assert_eq!(fast.dq_mm_s[i][j].to_bits(), s.dq_mm_s[i].to_bits());
                assert_eq!(base.dq_mm_s[i][j].to_bits(), s.dq_mm_s[i].to_bits());
                assert_eq!(fast.tension_n[i][j].to_bits(), s.arm_tension_n[i].to_bits());
                assert_eq!(base.tension_n[i][j].to_bits(), s.arm_tension_n[i].to_bits());
            }
        }
        assert!(bad >= 4 * (len / 16), "{bad} invalid lanes");
    }
}
