//! Bounds of the forces over a box of nozzle states: eq. 6-8 and 13-14 evaluated in
//! interval arithmetic, for the sparse evaluation (docs/performance.md). Whatever state of
//! the box the model is evaluated at, its |Q_i|, |q̇_i| and arm tension lie within what
//! [`DeltaModel::bound`] returns (up to rounding, which [`BOUND_MARGIN`] covers), and every
//! state of the box is a valid pose.

use super::DeltaModel;
use crate::interval::Interval;

const MM: f64 = 1e-3;

/// Relative margin a bound gets before it is compared with a computed value: far above the
/// rounding of the interval evaluation and of the sampled states (about 1e-13 relative),
/// far below anything physical.
pub const BOUND_MARGIN: f64 = 1e-6;

/// The absolute part of the margin, in the unit of the bound (N, mm/s): rounding near zero.
const BOUND_MARGIN_ABS: f64 = 1e-9;

/// A box proves a pose valid only with this much room, mm: the arm's rise above the
/// platform at least this (eq. 6's radicand well above zero), each carriage this far below
/// its top.
const POSE_ROOM_MM: f64 = 1e-3;

/// No state is bounded with a coordinate beyond this (mm, mm/s, mm/s²; NaN is not below
/// it): nothing physical comes near, and below it no interval product overflows.
const LARGEST_INPUT: f64 = 1e9;

/// What the model can give at any state of a box, per tower.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ForceBounds {
    /// At least the largest |Q_i| (eq. 14), N.
    pub force_n: [f64; 3],
    /// At least the largest |q̇_i| (eq. 7), mm/s.
    pub speed_mm_s: [f64; 3],
    /// At least the largest arm tension 2λ_i·l_i (eq. 13), N.
    pub tension_n: [f64; 3],
}

/// An interval version of a 3-vector.
type IVec = [Interval; 3];

#[inline(always)]
fn dot(a: &IVec, b: &IVec) -> Interval {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

#[inline(always)]
fn cross(a: &IVec, b: &IVec) -> IVec {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

impl DeltaModel {
    /// Bounds of the forces, carriage speeds and tensions over every nozzle state with its
    /// position, velocity and acceleration in the given boxes (mm, mm/s, mm/s²), widened by
    /// [`BOUND_MARGIN`]; None unless every state of the box is provably a valid pose (in
    /// reach with room, below the tops, Jx far from singular, finite). The same formulas as
    /// [`DeltaModel::evaluate`] (eq. 6-8, 13-14), with Jq_ii = √radicand_i, which does not
    /// depend on z. Compiled for AVX2 as well as the baseline, chosen at run time: the same
    /// operations in the same order, so the same bounds bit for bit (as `forces_block`).
    pub fn bound(&self, pos_mm: &IVec, vel_mm_s: &IVec, acc_mm_s2: &IVec) -> Option<ForceBounds> {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU has AVX2, checked just above.
            return unsafe { self.bound_avx2(pos_mm, vel_mm_s, acc_mm_s2) };
        }
        self.bound_generic(pos_mm, vel_mm_s, acc_mm_s2)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn bound_avx2(&self, pos_mm: &IVec, vel_mm_s: &IVec, acc_mm_s2: &IVec) -> Option<ForceBounds> {
        self.bound_generic(pos_mm, vel_mm_s, acc_mm_s2)
    }

    #[inline(always)]
    fn bound_generic(
        &self,
        pos_mm: &IVec,
        vel_mm_s: &IVec,
        acc_mm_s2: &IVec,
    ) -> Option<ForceBounds> {
        // Finite and far from overflow, so that no product below is 0·∞ (a NaN); without a
        // branch per value (a chained iterator's branches cost a mispredicted one a call).
        let mut finite = true;
        for q in [pos_mm, vel_mm_s, acc_mm_s2] {
            for i in q {
                finite &= (i.lo.abs() <= LARGEST_INPUT) & (i.hi.abs() <= LARGEST_INPUT);
            }
        }
        if !finite {
            return None;
        }
        let z = pos_mm[2] + self.nozzle_offset_mm;
        let mut rows = [[Interval::point(0.0); 3]; 3];
        for (i, row) in rows.iter_mut().enumerate() {
            let dx = Interval::point(self.towers_mm[i][0]) - pos_mm[0];
            let dy = Interval::point(self.towers_mm[i][1]) - pos_mm[1];
            let radicand = Interval::point(self.arm2_mm2[i]) - (dx.sqr() + dy.sqr());
            // eq. 6: the rise √radicand, and the carriage q = z + rise below its top.
            if radicand.lo < POSE_ROOM_MM * POSE_ROOM_MM {
                return None;
            }
            let rise = radicand.sqrt();
            if (z + rise).hi > self.top_mm[i] - POSE_ROOM_MM {
                return None;
            }
            *row = [dx, dy, rise];
        }
        let cof = [
            cross(&rows[1], &rows[2]),
            cross(&rows[2], &rows[0]),
            cross(&rows[0], &rows[1]),
        ];
        let det = dot(&rows[0], &cof[0]);
        if det.lo <= 2.0 * self.singular_det_mm3 && det.hi >= -2.0 * self.singular_det_mm3 {
            return None;
        }
        let inv_det = det.recip()?;
        let g = self.gravity_m_s2;
        let b = [acc_mm_s2[0] * MM, acc_mm_s2[1] * MM, acc_mm_s2[2] * MM + g];
        let v = vel_mm_s;
        let horizontal2 = v[0].sqr() + v[1].sqr();
        let widen = |x: Interval| x.widen(BOUND_MARGIN * x.mag() + BOUND_MARGIN_ABS);
        let mut out = ForceBounds {
            force_n: [0.0; 3],
            speed_mm_s: [0.0; 3],
            tension_n: [0.0; 3],
        };
        for i in 0..3 {
            let inv_jq = rows[i][2].recip()?;
            // eq. 13: w_i = (Jx⁻ᵀ (p̈ + g e_z))_i.
            let w = dot(&cof[i], &b) * inv_det;
            // eq. 7 and 8.
            let dq = dot(&rows[i], v) * inv_jq;
            let dz = v[2] - dq;
            let ddq = (dot(&rows[i], acc_mm_s2) - (horizontal2 + dz.sqr())) * inv_jq;
            // eq. 14, as `core` writes it.
            let force = ddq * (self.carriage_inertia_kg * MM)
                + self.carriage_weight_kg * g
                + rows[i][2] * w * self.platform_kg;
            let tension = w * (self.platform_kg * self.arm_mm[i]);
            out.force_n[i] = widen(force).mag();
            out.speed_mm_s[i] = widen(dq).mag();
            out.tension_n[i] = widen(tension).hi;
        }
        let finite = |x: &[f64; 3]| x.iter().all(|v| v.is_finite());
        (finite(&out.force_n) && finite(&out.speed_mm_s) && finite(&out.tension_n)).then_some(out)
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_support::{Rng, kossel, workspace_points};
    use super::*;
    use crate::path::Vec3;
    use proptest::prelude::*;

    /// A box of states around a point: `size` mm, `size`·100 mm/s and `size`·1e4 mm/s² wide
    /// per coordinate, with a point of it chosen by `t` (∈ [0, 1]³ per quantity).
    fn boxed(centre: [Vec3; 3], size: f64, t: [[f64; 3]; 3]) -> ([IVec; 3], [Vec3; 3]) {
        let scale = [size, 100.0 * size, 1e4 * size];
        let mut boxes = [[Interval::point(0.0); 3]; 3];
        let mut point = [Vec3::zeros(); 3];
        for q in 0..3 {
            for k in 0..3 {
                let lo = centre[q][k] - 0.5 * scale[q];
                boxes[q][k] = Interval {
                    lo,
                    hi: lo + scale[q],
                };
                point[q][k] = lo + t[q][k] * scale[q];
            }
        }
        (boxes, point)
    }

    fn unit3() -> impl Strategy<Value = [[f64; 3]; 3]> {
        proptest::array::uniform3(proptest::array::uniform3(0.0..=1.0f64))
    }

    proptest! {
        /// A bound that is ever below the model at a state of its box fails.
        #[test]
        fn the_model_at_any_state_of_a_box_is_within_its_bound(
            x in -80.0..80.0f64, y in -80.0..80.0f64, z in 0.0..250.0f64,
            vel in proptest::array::uniform3(-300.0..300.0f64),
            acc in proptest::array::uniform3(-2e4..2e4f64),
            size in 1e-6..2.0f64, t in unit3(),
        ) {
            let m = kossel();
            let centre = [Vec3::new(x, y, z), Vec3::from(vel), Vec3::from(acc)];
            let ([p, v, a], [ps, vs, as_]) = boxed(centre, size, t);
            // The CPU's vector build and the baseline agree bit for bit.
            prop_assert_eq!(m.bound(&p, &v, &a), m.bound_generic(&p, &v, &a));
            let Some(b) = m.bound(&p, &v, &a) else { return Ok(()) };
            let s = m.evaluate(ps, vs, as_).expect("a bounded box holds valid poses");
            for i in 0..3 {
                prop_assert!(s.force_n[i].abs() <= b.force_n[i], "Q{i} {} > {}", s.force_n[i], b.force_n[i]);
                prop_assert!(s.dq_mm_s[i].abs() <= b.speed_mm_s[i]);
                prop_assert!(s.arm_tension_n[i] <= b.tension_n[i]);
            }
        }
    }

    #[test]
    fn a_small_box_is_bounded_tightly_and_an_unreachable_one_not_at_all() {
        let m = kossel();
        let mut rng = Rng(5);
        for p in workspace_points().step_by(5) {
            let v = Vec3::new(rng.range(-200.0, 200.0), rng.range(-200.0, 200.0), 5.0);
            let a = Vec3::new(rng.range(-3e3, 3e3), rng.range(-3e3, 3e3), 0.0);
            let ([pb, vb, ab], _) = boxed([p, v, a], 1e-9, [[0.5; 3]; 3]);
            let b = m.bound(&pb, &vb, &ab).expect("in reach");
            let s = m.evaluate(p, v, a).unwrap();
            for i in 0..3 {
                let q = s.force_n[i].abs();
                assert!(
                    b.force_n[i] >= q && b.force_n[i] <= q * 1.001 + 1e-6,
                    "{i} {q}"
                );
            }
        }
        // Beyond the arms' reach, and straddling it: no bound.
        let far = [
            Interval::point(300.0),
            Interval::point(0.0),
            Interval::point(10.0),
        ];
        let zero = [Interval::point(0.0); 3];
        assert_eq!(m.bound(&far, &zero, &zero), None);
        // NaN or huge inputs, where a product could be 0·∞: no bound.
        let centre = [
            Interval::point(0.0),
            Interval::point(0.0),
            Interval::point(100.0),
        ];
        for bad in [f64::NAN, 2e9, f64::INFINITY] {
            let v = [
                Interval { lo: 0.0, hi: bad },
                Interval::point(0.0),
                Interval::point(0.0),
            ];
            assert_eq!(m.bound(&centre, &v, &zero), None, "{bad}");
            assert_eq!(m.bound(&centre, &zero, &v), None, "{bad}");
        }
        assert!(m.bound(&centre, &zero, &zero).is_some());
        let top = [
            Interval::point(0.0),
            Interval::point(0.0),
            Interval::hull(200.0, 400.0),
        ];
        assert_eq!(m.bound(&top, &zero, &zero), None);
    }
}
