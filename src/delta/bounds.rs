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

/// The towers side by side: lanes 0, 1 and 2 are towers A, B and C, and lane 3 repeats
/// lane 0, so that the three fill one AVX2 register and the fourth never fails a check.
const LANES: usize = 4;

/// A value per tower, as [`LANES`] lanes ([`Towers`] takes it).
fn tower_values(f: impl Fn(usize) -> f64) -> [f64; LANES] {
    [f(0), f(1), f(2), f(0)]
}

/// An interval per tower. Every operation is [`Interval`]'s, lane by lane: each tower gets
/// the bits the same formula gives it alone, and the compiler works the lanes in one
/// vector (eq. 6-8 and 13-14 for the three towers at once).
#[derive(Clone, Copy, Debug)]
struct Towers {
    lo: [f64; LANES],
    hi: [f64; LANES],
}

impl Towers {
    /// The same interval for every tower.
    #[inline(always)]
    fn splat(x: Interval) -> Towers {
        Towers {
            lo: [x.lo; LANES],
            hi: [x.hi; LANES],
        }
    }

    /// Lane `l`'s interval.
    #[inline(always)]
    fn at(&self, l: usize) -> Interval {
        Interval {
            lo: self.lo[l],
            hi: self.hi[l],
        }
    }

    #[inline(always)]
    fn map(self, f: impl Fn(Interval) -> Interval) -> Towers {
        self.zip(self, |x, _| f(x))
    }

    #[inline(always)]
    fn zip(self, o: Towers, f: impl Fn(Interval, Interval) -> Interval) -> Towers {
        let mut out = self;
        for l in 0..LANES {
            let r = f(self.at(l), o.at(l));
            (out.lo[l], out.hi[l]) = (r.lo, r.hi);
        }
        out
    }

    /// Whether `f` holds on some tower's interval (with its lane), every lane tried.
    #[inline(always)]
    fn any(&self, f: impl Fn(Interval, usize) -> bool) -> bool {
        (0..LANES).fold(false, |any, l| any | f(self.at(l), l))
    }

    /// Each tower's value of `k` less its interval.
    #[inline(always)]
    fn taken_from(self, k: &[f64; LANES]) -> Towers {
        self.zip(Towers { lo: *k, hi: *k }, |x, k| k - x)
    }

    /// Each tower's interval times its value of `k`.
    #[inline(always)]
    fn scaled(self, k: &[f64; LANES]) -> Towers {
        self.zip(Towers { lo: *k, hi: *k }, |x, k| x * k.lo)
    }

    /// Tower i gets tower (i + n) mod 3's interval.
    #[inline(always)]
    fn turned(self, n: usize) -> Towers {
        let lane = |l: usize| (l % 3 + n) % 3;
        Towers {
            lo: std::array::from_fn(|l| self.lo[lane(l)]),
            hi: std::array::from_fn(|l| self.hi[lane(l)]),
        }
    }

    /// 1/x per tower, or None when some tower's interval holds zero.
    #[inline(always)]
    fn recip(self) -> Option<Towers> {
        if self.any(|x, _| x.recip().is_none()) {
            return None;
        }
        Some(self.map(|x| x.recip().unwrap_or(x)))
    }
}

impl std::ops::Add for Towers {
    type Output = Towers;
    #[inline(always)]
    fn add(self, o: Towers) -> Towers {
        self.zip(o, |a, b| a + b)
    }
}

impl std::ops::Sub for Towers {
    type Output = Towers;
    #[inline(always)]
    fn sub(self, o: Towers) -> Towers {
        self.zip(o, |a, b| a - b)
    }
}

impl Towers {
    /// Each tower's interval times its interval of `r`, whose values are all positive
    /// ([`Interval::times_positive`]).
    #[inline(always)]
    fn times_positive(self, r: Towers) -> Towers {
        self.zip(r, Interval::times_positive)
    }
}

impl std::ops::Mul for Towers {
    type Output = Towers;
    #[inline(always)]
    fn mul(self, o: Towers) -> Towers {
        self.zip(o, |a, b| a * b)
    }
}

/// The dot product of a row of Jx (dx, dy, rise) with per-tower interval vectors, left to
/// right, the rise's product by [`Towers::times_positive`].
#[inline(always)]
fn row_dot(row: &[Towers; 3], b: &[Towers; 3]) -> Towers {
    row[0] * b[0] + row[1] * b[1] + b[2].times_positive(row[2])
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
        self.bound_below(pos_mm, vel_mm_s, acc_mm_s2, &[f64::INFINITY; 3])
    }

    /// [`Self::bound`] when every tower's tension bound is strictly below `tension_n` (N),
    /// else None, found before the carriages' speeds and forces are bounded: eq. 13 needs
    /// only the poses and the acceleration, and the forces of eq. 7, 8 and 14 are about
    /// half the work. A bound that keeps a group of whole moves is a tension above the
    /// run's in 79 % of the cases without a shaper and 96 % with one (the bunny's first
    /// 5 MB). A tension of +∞ or NaN is below no limit, so with limits of +∞ this is
    /// [`Self::bound`] itself.
    pub fn bound_below(
        &self,
        pos_mm: &IVec,
        vel_mm_s: &IVec,
        acc_mm_s2: &IVec,
        tension_n: &[f64; 3],
    ) -> Option<ForceBounds> {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU has AVX2, checked just above.
            return unsafe { self.bound_avx2(pos_mm, vel_mm_s, acc_mm_s2, tension_n) };
        }
        self.bound_generic(pos_mm, vel_mm_s, acc_mm_s2, tension_n)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn bound_avx2(
        &self,
        pos_mm: &IVec,
        vel_mm_s: &IVec,
        acc_mm_s2: &IVec,
        tension_n: &[f64; 3],
    ) -> Option<ForceBounds> {
        self.bound_generic(pos_mm, vel_mm_s, acc_mm_s2, tension_n)
    }

    #[inline(always)]
    fn bound_generic(
        &self,
        pos_mm: &IVec,
        vel_mm_s: &IVec,
        acc_mm_s2: &IVec,
        tension_limit_n: &[f64; 3],
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
        // Each tower's row of Jx (eq. 8): (dx, dy, rise), the towers side by side.
        let dx = Towers::splat(pos_mm[0]).taken_from(&tower_values(|i| self.towers_mm[i][0]));
        let dy = Towers::splat(pos_mm[1]).taken_from(&tower_values(|i| self.towers_mm[i][1]));
        let radicand = (dx.map(Interval::sqr) + dy.map(Interval::sqr))
            .taken_from(&tower_values(|i| self.arm2_mm2[i]));
        // eq. 6: the rise √radicand, and the carriage q = z + rise below its top.
        if radicand.any(|r, _| r.lo < POSE_ROOM_MM * POSE_ROOM_MM) {
            return None;
        }
        let rise = radicand.map(Interval::sqrt);
        let top = tower_values(|i| self.top_mm[i] - POSE_ROOM_MM);
        if (rise + Towers::splat(z)).any(|q, l| q.hi > top[l]) {
            return None;
        }
        // The cofactors: tower i's is the cross product of the rows of towers i + 1 and
        // i + 2. The rise is positive (its radicand at least `POSE_ROOM_MM`², just checked),
        // and so is 1/rise: their products take [`Towers::times_positive`], the general
        // product's values with a third of its comparisons (−0.7 % of a default run's
        // instructions, −0.3 % of a shaped run's, docs/performance.md).
        let row = [dx, dy, rise];
        let (a, b) = (row.map(|r| r.turned(1)), row.map(|r| r.turned(2)));
        let cof = [
            a[1].times_positive(b[2]) - b[1].times_positive(a[2]),
            b[0].times_positive(a[2]) - a[0].times_positive(b[2]),
            a[0] * b[1] - a[1] * b[0],
        ];
        let det = row_dot(&row, &cof).at(0);
        if det.lo <= 2.0 * self.singular_det_mm3 && det.hi >= -2.0 * self.singular_det_mm3 {
            return None;
        }
        let inv_det = Towers::splat(det.recip()?);
        let g = self.gravity_m_s2;
        let splat = |x: [Interval; 3]| x.map(Towers::splat);
        let b = splat([acc_mm_s2[0] * MM, acc_mm_s2[1] * MM, acc_mm_s2[2] * MM + g]);
        // eq. 13: w_i = (Jx⁻ᵀ (p̈ + g e_z))_i, and the tension first.
        let w = (cof[0] * b[0] + cof[1] * b[1] + cof[2] * b[2]) * inv_det;
        let tension = w.scaled(&tower_values(|i| self.platform_kg * self.arm_mm[i]));
        let widen = |x: Interval| x.widen(BOUND_MARGIN * x.mag() + BOUND_MARGIN_ABS);
        let tension_n = std::array::from_fn(|i| widen(tension.at(i)).hi);
        if !(0..3).fold(true, |below, i| below & (tension_n[i] < tension_limit_n[i])) {
            return None;
        }
        let inv_jq = rise.recip()?;
        let (v, acc) = (splat(*vel_mm_s), splat(*acc_mm_s2));
        let horizontal2 = Towers::splat(vel_mm_s[0].sqr() + vel_mm_s[1].sqr());
        // eq. 7 and 8.
        let dq = row_dot(&row, &v).times_positive(inv_jq);
        let dz = v[2] - dq;
        let ddq =
            (row_dot(&row, &acc) - (horizontal2 + dz.map(Interval::sqr))).times_positive(inv_jq);
        // eq. 14, as `core` writes it.
        let weight = self.carriage_weight_kg * g;
        let force = ddq
            .scaled(&[self.carriage_inertia_kg * MM; LANES])
            .map(|f| f + weight)
            + w.times_positive(rise).scaled(&[self.platform_kg; LANES]);
        let out = ForceBounds {
            force_n: std::array::from_fn(|i| widen(force.at(i)).mag()),
            speed_mm_s: std::array::from_fn(|i| widen(dq.at(i)).mag()),
            tension_n,
        };
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

    /// The bound tower by tower, as it was written before the towers went side by side
    /// (the same formulas, one [`Interval`] at a time): the reference the lanes must give
    /// bit for bit.
    fn tower_by_tower(
        m: &DeltaModel,
        pos_mm: &IVec,
        vel_mm_s: &IVec,
        acc_mm_s2: &IVec,
    ) -> Option<ForceBounds> {
        let dot = |a: &IVec, b: &IVec| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        let cross = |a: &IVec, b: &IVec| {
            [
                a[1] * b[2] - a[2] * b[1],
                a[2] * b[0] - a[0] * b[2],
                a[0] * b[1] - a[1] * b[0],
            ]
        };
        let finite = [pos_mm, vel_mm_s, acc_mm_s2]
            .iter()
            .flat_map(|q| q.iter())
            .all(|i| i.lo.abs() <= LARGEST_INPUT && i.hi.abs() <= LARGEST_INPUT);
        if !finite {
            return None;
        }
        let z = pos_mm[2] + m.nozzle_offset_mm;
        let mut rows = [[Interval::point(0.0); 3]; 3];
        for (i, row) in rows.iter_mut().enumerate() {
            let dx = Interval::point(m.towers_mm[i][0]) - pos_mm[0];
            let dy = Interval::point(m.towers_mm[i][1]) - pos_mm[1];
            let radicand = Interval::point(m.arm2_mm2[i]) - (dx.sqr() + dy.sqr());
            if radicand.lo < POSE_ROOM_MM * POSE_ROOM_MM {
                return None;
            }
            let rise = radicand.sqrt();
            if (z + rise).hi > m.top_mm[i] - POSE_ROOM_MM {
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
        if det.lo <= 2.0 * m.singular_det_mm3 && det.hi >= -2.0 * m.singular_det_mm3 {
            return None;
        }
        let inv_det = det.recip()?;
        let g = m.gravity_m_s2;
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
            let w = dot(&cof[i], &b) * inv_det;
            let dq = dot(&rows[i], v) * inv_jq;
            let dz = v[2] - dq;
            let ddq = (dot(&rows[i], acc_mm_s2) - (horizontal2 + dz.sqr())) * inv_jq;
            let force = ddq * (m.carriage_inertia_kg * MM)
                + m.carriage_weight_kg * g
                + rows[i][2] * w * m.platform_kg;
            let tension = w * (m.platform_kg * m.arm_mm[i]);
            out.force_n[i] = widen(force).mag();
            out.speed_mm_s[i] = widen(dq).mag();
            out.tension_n[i] = widen(tension).hi;
        }
        let finite = |x: &[f64; 3]| x.iter().all(|v| v.is_finite());
        (finite(&out.force_n) && finite(&out.speed_mm_s) && finite(&out.tension_n)).then_some(out)
    }

    /// A bound's values by their bits.
    fn bits(b: Option<ForceBounds>) -> Option<[[u64; 3]; 3]> {
        b.map(|b| [b.force_n, b.speed_mm_s, b.tension_n].map(|x| x.map(f64::to_bits)))
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
            // The CPU's vector build and the baseline agree bit for bit, and with the
            // towers taken one at a time.
            prop_assert_eq!(m.bound(&p, &v, &a), m.bound_generic(&p, &v, &a, &[f64::INFINITY; 3]));
            prop_assert_eq!(bits(m.bound(&p, &v, &a)), bits(tower_by_tower(&m, &p, &v, &a)));
            let Some(b) = m.bound(&p, &v, &a) else { return Ok(()) };
            let s = m.evaluate(ps, vs, as_).expect("a bounded box holds valid poses");
            for i in 0..3 {
                prop_assert!(s.force_n[i].abs() <= b.force_n[i], "Q{i} {} > {}", s.force_n[i], b.force_n[i]);
                prop_assert!(s.dq_mm_s[i].abs() <= b.speed_mm_s[i]);
                prop_assert!(s.arm_tension_n[i] <= b.tension_n[i]);
            }
        }
    }

    /// The towers side by side give what each tower gives alone, bit for bit, over boxes
    /// in reach and out of it, small and large (a swapped operand, a lane turned the wrong
    /// way or a check lost in a lane fails).
    #[test]
    fn the_towers_side_by_side_bound_as_one_at_a_time() {
        let m = kossel();
        let mut rng = Rng(11);
        let (mut some, mut none) = (0, 0);
        for k in 0..20_000 {
            let size = [1e-6, 0.1, 2.0, 20.0][k % 4];
            let centre = [
                Vec3::new(
                    rng.range(-160.0, 160.0),
                    rng.range(-160.0, 160.0),
                    rng.range(-20.0, 320.0),
                ),
                Vec3::new(
                    rng.range(-400.0, 400.0),
                    rng.range(-400.0, 400.0),
                    rng.range(-50.0, 50.0),
                ),
                Vec3::new(
                    rng.range(-3e4, 3e4),
                    rng.range(-3e4, 3e4),
                    rng.range(-3e3, 3e3),
                ),
            ];
            let t = [[rng.range(0.0, 1.0); 3]; 3];
            let ([p, v, a], _) = boxed(centre, size, t);
            let got = m.bound(&p, &v, &a);
            assert_eq!(
                bits(got),
                bits(tower_by_tower(&m, &p, &v, &a)),
                "{p:?} {v:?} {a:?}"
            );
            if got.is_some() {
                some += 1;
            } else {
                none += 1;
            }
        }
        assert!(some > 2_000 && none > 2_000, "{some} bounded, {none} not");
    }

    /// The bound under tension limits is the bound itself when every tower's tension is
    /// strictly below its limit, and None otherwise (a limit at a tower's own tension
    /// bound, just above it, or +∞).
    #[test]
    fn a_bound_under_tension_limits_is_the_bound_or_none() {
        let m = kossel();
        let mut rng = Rng(17);
        let mut some = 0;
        for k in 0..5_000 {
            let centre = [
                Vec3::new(
                    rng.range(-80.0, 80.0),
                    rng.range(-80.0, 80.0),
                    rng.range(0.0, 250.0),
                ),
                Vec3::new(rng.range(-300.0, 300.0), rng.range(-300.0, 300.0), 0.0),
                Vec3::new(
                    rng.range(-2e4, 2e4),
                    rng.range(-2e4, 2e4),
                    rng.range(-1e3, 1e3),
                ),
            ];
            let ([p, v, a], _) = boxed(centre, [1e-3, 0.5, 5.0][k % 3], [[0.5; 3]; 3]);
            let Some(b) = m.bound(&p, &v, &a) else {
                assert_eq!(m.bound_below(&p, &v, &a, &[f64::INFINITY; 3]), None);
                continue;
            };
            let tower = k % 3;
            let mut limit = [f64::INFINITY; 3];
            limit[tower] = b.tension_n[tower];
            assert_eq!(m.bound_below(&p, &v, &a, &limit), None);
            limit[tower] = b.tension_n[tower].next_up();
            assert_eq!(m.bound_below(&p, &v, &a, &limit), Some(b));
            let below = b.tension_n.map(|t| t + 1.0 + t.abs());
            assert_eq!(m.bound_below(&p, &v, &a, &below), Some(b));
            let under = b.tension_n.map(|t| t - 1.0 - t.abs());
            assert_eq!(m.bound_below(&p, &v, &a, &under), None);
            some += 1;
        }
        assert!(some > 1_000, "{some} bounded");
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
