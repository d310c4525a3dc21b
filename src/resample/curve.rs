//! Curves parameterised by u ∈ [0, 1], the paper's Taylor step on them (eq. 19, generalised
//! to accelerating motion) and the nozzle's velocity and acceleration along them.

use crate::path::{Jet, Path, Vec3};

/// A curve p(u), u ∈ [0, 1], with its first two derivatives (bed frame, mm).
pub trait Curve {
    /// p(u), dp/du and d²p/du² together.
    fn jet(&self, u: f64) -> Jet;

    /// Position p(u).
    #[inline(always)]
    fn point(&self, u: f64) -> Vec3 {
        self.jet(u).p
    }
    /// dp/du.
    #[inline(always)]
    fn d1(&self, u: f64) -> Vec3 {
        self.jet(u).d1
    }
    /// d²p/du².
    #[inline(always)]
    fn d2(&self, u: f64) -> Vec3 {
        self.jet(u).d2
    }
}

impl Curve for Path {
    #[inline(always)]
    fn jet(&self, u: f64) -> Jet {
        Path::jet(self, u)
    }
}

/// The paper's Taylor step (eq. 19), generalised to accelerating motion, from a fixed
/// point: the nozzle at parameter u (where the curve's derivatives are `jet`) moving at speed
/// v with tangential acceleration a_t. With u̇ = v/|p'| and ü = a_t/|p'| − v²·(p'·p'')/|p'|⁴,
/// the second-order Taylor series gives u(dt) = u + dt·u̇ + dt²/2·ü, clamped to [0, 1].
/// For a_t = 0 it is eq. 19 itself. A point where p' = 0 does not move.
///
/// It is exact for lines and circular (helical) arcs, whose |p'| is constant and p'·p''
/// zero, for a step of any length.
#[derive(Clone, Copy, Debug)]
pub struct TaylorStep {
    u: f64,
    udot: f64,
    uddot: f64,
}

impl TaylorStep {
    #[inline(always)]
    pub fn new(jet: &Jet, u: f64, v_mm_s: f64, a_t_mm_s2: f64) -> Self {
        let n2 = jet.d1.norm_squared();
        if n2 == 0.0 {
            return TaylorStep {
                u,
                udot: 0.0,
                uddot: 0.0,
            };
        }
        let inv_n = 1.0 / n2.sqrt();
        let inv_n2 = inv_n * inv_n;
        TaylorStep {
            u,
            udot: v_mm_s * inv_n,
            uddot: a_t_mm_s2 * inv_n - v_mm_s * v_mm_s * jet.d1.dot(&jet.d2) * (inv_n2 * inv_n2),
        }
    }

    /// The parameter `dt_s` after the starting point.
    #[inline(always)]
    pub fn at(&self, dt_s: f64) -> f64 {
        (self.u + dt_s * self.udot + 0.5 * dt_s * dt_s * self.uddot).clamp(0.0, 1.0)
    }
}

/// One Taylor step of `dt_s` from u: [`TaylorStep`].
#[inline(always)]
pub fn taylor_step(jet: &Jet, u: f64, v_mm_s: f64, a_t_mm_s2: f64, dt_s: f64) -> f64 {
    TaylorStep::new(jet, u, v_mm_s, a_t_mm_s2).at(dt_s)
}

/// The unit tangent T = p'/|p'| of a curve at one point and the part of p'' across it,
/// scaled: what the nozzle's velocity and acceleration there are made of (zero where p' = 0).
#[derive(Clone, Copy, Debug)]
pub struct Frame {
    tangent: Vec3,
    normal_part: Vec3,
    inv_n2: f64,
}

impl Frame {
    #[inline(always)]
    pub fn new(jet: &Jet) -> Frame {
        let n2 = jet.d1.norm_squared();
        if n2 == 0.0 {
            return Frame {
                tangent: Vec3::zeros(),
                normal_part: Vec3::zeros(),
                inv_n2: 0.0,
            };
        }
        let inv_n = 1.0 / n2.sqrt();
        let tangent = jet.d1 * inv_n;
        Frame {
            tangent,
            normal_part: jet.d2 - tangent * jet.d2.dot(&tangent),
            inv_n2: inv_n * inv_n,
        }
    }

    /// Velocity and acceleration of a nozzle moving forward along the curve at speed
    /// `v_mm_s` with tangential acceleration `a_t_mm_s2`: velocity v·T, acceleration
    /// a_t·T + v²/|p'|²·(p'' − (p''·T)·T), the second term being the centripetal v²·κ along
    /// the principal normal. Zero where p' = 0.
    #[inline(always)]
    pub fn motion(&self, v_mm_s: f64, a_t_mm_s2: f64) -> (Vec3, Vec3) {
        let vel = self.tangent * v_mm_s;
        let acc = self.tangent * a_t_mm_s2 + self.normal_part * (v_mm_s * v_mm_s * self.inv_n2);
        (vel, acc)
    }
}

/// The paper's Lissajous path (eq. 18): x = x0·sin(ω_x·u + φ_x), y = y0·sin(ω_y·u + φ_y),
/// z constant.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lissajous {
    pub x0_mm: f64,
    pub y0_mm: f64,
    pub wx: f64,
    pub wy: f64,
    pub phx: f64,
    pub phy: f64,
    pub z_mm: f64,
}

impl Lissajous {
    /// The paper's path: ω_x = 6π, ω_y = 4π, φ_x = π/2, φ_y = 0, amplitude `amp_mm` on
    /// both axes, at height `z_mm`.
    pub fn paper(amp_mm: f64, z_mm: f64) -> Self {
        use std::f64::consts::{FRAC_PI_2, PI};
        Lissajous {
            x0_mm: amp_mm,
            y0_mm: amp_mm,
            wx: 6.0 * PI,
            wy: 4.0 * PI,
            phx: FRAC_PI_2,
            phy: 0.0,
            z_mm,
        }
    }
}

impl Curve for Lissajous {
    fn jet(&self, u: f64) -> Jet {
        let (sx, cx) = (self.wx * u + self.phx).sin_cos();
        let (sy, cy) = (self.wy * u + self.phy).sin_cos();
        let (ax, ay) = (self.x0_mm, self.y0_mm);
        Jet {
            p: Vec3::new(ax * sx, ay * sy, self.z_mm),
            d1: Vec3::new(ax * self.wx * cx, ay * self.wy * cy, 0.0),
            d2: Vec3::new(
                -ax * self.wx * self.wx * sx,
                -ay * self.wy * self.wy * sy,
                0.0,
            ),
        }
    }
}

/// Walks `curve` from u = 0 to u = 1 at constant speed `v_mm_s` with eq. 19 steps of
/// `period_s`, calling `out(u)` at u = 0, after every step, and finally at u = 1 (the last
/// step is shorter). Stops after `max_steps` steps if u = 1 is not reached (returns false).
pub fn walk_constant_speed<C: Curve + ?Sized>(
    curve: &C,
    v_mm_s: f64,
    period_s: f64,
    max_steps: usize,
    out: &mut impl FnMut(f64),
) -> bool {
    let mut u = 0.0;
    out(u);
    for _ in 0..max_steps {
        u = taylor_step(&curve.jet(u), u, v_mm_s, 0.0, period_s);
        out(u);
        if u >= 1.0 {
            return true;
        }
    }
    false
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Arc length of the curve between u_a and u_b, by 8-point Gauss–Legendre on 64 panels
    /// (independent of the step law).
    pub(crate) fn arc_length<C: Curve>(c: &C, ua: f64, ub: f64) -> f64 {
        const X: [f64; 4] = [
            0.183_434_642_495_649_8,
            0.525_532_409_916_329,
            0.796_666_477_413_626_7,
            0.960_289_856_497_536_2,
        ];
        const W: [f64; 4] = [
            0.362_683_783_378_362,
            0.313_706_645_877_887_3,
            0.222_381_034_453_374_5,
            0.101_228_536_290_376_3,
        ];
        let panels = 64;
        let h = (ub - ua) / panels as f64;
        let mut s = 0.0;
        for p in 0..panels {
            let m = ua + (p as f64 + 0.5) * h;
            for i in 0..4 {
                let dx = 0.5 * h * X[i];
                s += W[i] * 0.5 * h * (c.d1(m - dx).norm() + c.d1(m + dx).norm());
            }
        }
        s
    }

    #[test]
    fn step_is_exact_on_a_line_while_accelerating() {
        let line = Path::line(Vec3::new(1.0, 2.0, 3.0), Vec3::new(31.0, -18.0, 7.0));
        let len = line.length_mm();
        let (v0, a, dt) = (20.0, 1500.0, 0.004);
        let mut u = 0.1;
        for _ in 0..5 {
            let u1 = taylor_step(&line.jet(u), u, v0, a, dt);
            // Closed form: s advances by v0·dt + a·dt²/2, s = u·len.
            let expect = u + (v0 * dt + 0.5 * a * dt * dt) / len;
            assert!((u1 - expect).abs() < 1e-14, "{u1} vs {expect}");
            u = u1;
        }
    }

    #[test]
    fn step_clamps_and_survives_degenerate_curve() {
        let line = Path::line(Vec3::zeros(), Vec3::new(1.0, 0.0, 0.0));
        assert_eq!(taylor_step(&line.jet(0.99), 0.99, 100.0, 0.0, 1.0), 1.0);
        let point = Path::line(Vec3::zeros(), Vec3::zeros());
        assert_eq!(taylor_step(&point.jet(0.3), 0.3, 100.0, 10.0, 1.0), 0.3);
        let (v, a) = Frame::new(&point.jet(0.3)).motion(100.0, 10.0);
        assert_eq!((v, a), (Vec3::zeros(), Vec3::zeros()));
    }

    #[test]
    fn lissajous_derivatives_match_finite_differences() {
        let c = Lissajous::paper(50.0, 0.0);
        let h = 1e-6;
        for &u in &[0.0, 0.13, 0.5, 0.77] {
            let fd1 = (c.point(u + h) - c.point(u - h)) / (2.0 * h);
            let fd2 = (c.d1(u + h) - c.d1(u - h)) / (2.0 * h);
            assert!((fd1 - c.d1(u)).norm() < 1e-5 * c.d1(u).norm());
            assert!((fd2 - c.d2(u)).norm() < 1e-5 * c.d2(u).norm().max(1.0));
        }
    }

    #[test]
    fn acceleration_is_tangential_plus_v2_kappa_normal() {
        // Independent: κ = |p' × p''| / |p'|³; the normal part has magnitude v²κ and is
        // perpendicular to the velocity.
        let c = Lissajous::paper(50.0, 0.0);
        let (v, at) = (80.0, -700.0);
        for &u in &[0.05, 0.21, 0.4, 0.63, 0.9] {
            let (d1, d2) = (c.d1(u), c.d2(u));
            let kappa = d1.cross(&d2).norm() / d1.norm().powi(3);
            let (vel, acc) = Frame::new(&c.jet(u)).motion(v, at);
            let t = d1.normalize();
            assert!((vel - t * v).norm() < 1e-12 * v);
            assert!((acc.dot(&t) - at).abs() < 1e-9 * at.abs());
            let an = acc - t * acc.dot(&t);
            assert!((an.norm() - v * v * kappa).abs() < 1e-9 * v * v * kappa);
        }
    }

    /// Arc-length error of one step at constant speed: |s(u+) − s(u) − v·Ts|.
    fn step_error(c: &Lissajous, u: f64, v: f64, ts: f64) -> f64 {
        let u1 = taylor_step(&c.jet(u), u, v, 0.0, ts);
        (arc_length(c, u, u1) - v * ts).abs()
    }

    #[test]
    fn lissajous_step_error_is_third_order() {
        let c = Lissajous::paper(50.0, 0.0);
        let v = 200.0;
        for &u in &[0.03, 0.11, 0.29, 0.47, 0.71] {
            let e1 = step_error(&c, u, v, 0.004);
            let e2 = step_error(&c, u, v, 0.002);
            let e3 = step_error(&c, u, v, 0.001);
            let (r1, r2) = (e1 / e2, e2 / e3);
            assert!((7.0..9.0).contains(&r1), "u={u}: {e1:e} {e2:e} ratio {r1}");
            assert!((7.0..9.0).contains(&r2), "u={u}: {e2:e} {e3:e} ratio {r2}");
        }
    }

    #[test]
    fn walk_spaces_points_by_v_ts() {
        let c = Lissajous::paper(50.0, 0.0);
        let (v, ts) = (50.0, 0.001);
        let mut prev: Option<Vec3> = None;
        let mut worst = 0.0_f64;
        let mut n = 0usize;
        let mut last_u = 0.0;
        let done = walk_constant_speed(&c, v, ts, 10_000_000, &mut |u| {
            let p = c.point(u);
            if let Some(q) = prev
                && u < 1.0
            {
                worst = worst.max(((p - q).norm() - v * ts).abs());
            }
            prev = Some(p);
            n += 1;
            last_u = u;
        });
        assert!(done);
        assert_eq!(last_u, 1.0);
        // Chords are shorter than the arc by ~ (v·Ts)³κ²/24, far below this bound.
        assert!(worst < 1e-6, "worst spacing error {worst:e}");
        let len = arc_length(&c, 0.0, 1.0);
        assert!(
            (n as f64 - len / (v * ts)).abs() < 3.0,
            "{n} points, length {len}"
        );
    }
}
