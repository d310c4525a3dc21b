//! The drive's response: the actual motion of the nozzle, each Cartesian axis following
//! the commanded one through a spring and a damper,
//!
//! ẍ = ω²(x_c − x) + 2ζω(ẋ_c − ẋ),
//!
//! ω = 2π·`drive.frequency_hz`, ζ = `drive.damping_ratio`. With the lag e = x − x_c, over a
//! commanded piece of constant acceleration a_c this is ë + 2ζω ė + ω² e = −a_c: the lag
//! settles towards −a_c/ω² as a damped oscillation, in closed form. At a junction the
//! commanded velocity jumps and the actual does not: ė jumps by minus the commanded jump,
//! and the actual acceleration −ω²e − 2ζω ė by 2ζω times the jump: a finite force where the
//! rigid model has an impulse.

mod swing;
mod turn;

pub(crate) use turn::ROUND;

use super::{Axes, CONTINUITY_MM, Lanes, Segment};
use crate::path::Vec3;
use swing::Windows;

/// How the nozzle follows the commanded motion.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Drive {
    /// The paper's rigid model: actual = commanded.
    Rigid,
    /// A spring and damper per axis.
    Spring(Spring),
}

/// The drive's natural frequency and damping ratio (0 ≤ ζ < 1: an underdamped drive, as
/// belts and steppers are).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spring {
    pub frequency_hz: f64,
    pub damping_ratio: f64,
}

/// The actual motion's lag behind the commanded one, per axis: e = x − x_c (mm) and
/// ė (mm/s).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Lag {
    pub e: Vec3,
    pub de: Vec3,
}

/// The spring's constants: ω, σ = ζω, ω_d = ω√(1 − ζ²).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Response {
    omega: f64,
    omega2: f64,
    sigma: f64,
    omega_d: f64,
    /// −1/ω² (the lag a constant acceleration settles to, per mm/s²) and 1/ω_d, computed
    /// once: a division per use was on the critical path of every piece's lag and box.
    to_e: f64,
    inv_wd: f64,
    /// The step h of [`Self::walk`] set by [`Self::with_step`], s, and its transition matrix.
    step: Option<(f64, [[f64; 2]; 2])>,
    /// The windows of [`Self::acceleration_range`].
    windows: Windows,
}

impl Response {
    pub fn new(s: &Spring) -> Response {
        let omega = std::f64::consts::TAU * s.frequency_hz;
        let zeta = s.damping_ratio;
        let omega_d = omega * (1.0 - zeta * zeta).sqrt();
        let mut r = Response {
            omega,
            omega2: omega * omega,
            sigma: zeta * omega,
            omega_d,
            to_e: -1.0 / (omega * omega),
            inv_wd: 1.0 / omega_d,
            step: None,
            windows: Windows::default(),
        };
        r.windows = Windows::new(&r);
        r
    }

    /// The same response, with the transition matrix of [`Self::walk`] over `h_s` computed
    /// once (a walk with that step then costs no exp or sin/cos).
    pub fn with_step(self, h_s: f64) -> Response {
        Response {
            step: Some((h_s, self.transition(h_s))),
            ..self
        }
    }

    /// The matrix turning the free part (u, u̇) of the lag by `h_s` (see [`LagWalk`]).
    fn transition(&self, h_s: f64) -> [[f64; 2]; 2] {
        let (s, c) = (self.omega_d * h_s).sin_cos();
        let decay = (-self.sigma * h_s).exp();
        let s_wd = s / self.omega_d * decay;
        [
            [(c + self.sigma * s / self.omega_d) * decay, s_wd],
            [
                -self.omega2 * s_wd,
                (c - self.sigma * s / self.omega_d) * decay,
            ],
        ]
    }

    /// The natural period 2π/ω, s.
    pub fn period_s(&self) -> f64 {
        std::f64::consts::TAU / self.omega
    }

    /// The lag `tau_s` into a commanded piece of acceleration `a_c` (mm/s²), from `start`
    /// at its beginning.
    #[inline(always)]
    pub fn lag_at(&self, start: &Lag, a_c: Vec3, tau_s: f64) -> Lag {
        let (e, de) = self.lag_after(start.e, start.de, a_c, self.turn(tau_s));
        Lag { e, de }
    }

    /// What [`Self::lag_at`] needs of τ: sin and cos of ω_dτ (by [`turn::sin_cos`]),
    /// e^(−στ).
    #[inline(always)]
    fn turn(&self, tau_s: f64) -> Turn {
        let (sin, cos) = turn::sin_cos(self.omega_d * tau_s);
        Turn {
            sin,
            cos,
            decay: (-self.sigma * tau_s).exp(),
        }
    }

    /// [`Self::lag_at`] for the τ of `turn`, from the lag (`e`, `de`), in axes `A`
    /// ([`Axes`]): with AVX2 the three axes in one register, the same operations on each
    /// in the same order, so the same bits (test
    /// `the_stage_gives_the_closed_form_bit_for_bit_through_its_memo`; −0.3 % / −0.75 % of
    /// a run's instructions without and with a shaper, docs/performance.md).
    #[inline(always)]
    fn lag_after<A: Axes>(&self, e: A, de: A, a_c: A, turn: Turn) -> (A, A) {
        let Turn {
            sin: s,
            cos: c,
            decay,
        } = turn;
        // u = e − e_p with e_p = −a_c/ω², the lag the constant acceleration settles to.
        let e_p = a_c * self.to_e;
        let u0 = e - e_p;
        let du0 = de;
        let inv_wd = self.inv_wd;
        let u = (u0 * c + (du0 + u0 * self.sigma) * (s * inv_wd)) * decay;
        let du = (du0 * c - (du0 * self.sigma + u0 * self.omega2) * (s * inv_wd)) * decay;
        (e_p + u, du)
    }

    /// The lag at `t0_s + tau0_s`, `t0_s + tau0_s + h_s`, … into a commanded piece of
    /// acceleration `a_c`, from `start` at `t0_s`: [`Self::lag_at`] at the first instant, then
    /// one fixed linear step per instant instead of an exp and a sin/cos.
    pub fn walk(&self, start: &Lag, a_c: Vec3, tau0_s: f64, h_s: f64) -> LagWalk {
        let first = self.lag_at(start, a_c, tau0_s);
        let e_p = a_c * self.to_e;
        LagWalk {
            e_p,
            u: first.e - e_p,
            du: first.de,
            step: match self.step {
                Some((h, m)) if h == h_s => m,
                _ => self.transition(h_s),
            },
        }
    }

    /// How far the lag rings from `tau_s` into a commanded piece of acceleration `a_c` on,
    /// from `start` at its beginning: the free part u = e − e_p of [`Self::lag_at`] and its
    /// rate are damped sinusoids e^(−στ)(C cos ω_dτ + D sin ω_dτ), so from `tau_s` on each
    /// is at most e^(−σ·tau_s)·√(C² + D²) in magnitude, per axis; likewise ω²u + 2σu̇, by
    /// which the actual acceleration differs from −ω²e_p = a_c.
    ///
    /// Inlined: a whole piece's box asks it at τ = 0 (no exp), and its five vectors stay in
    /// registers (out of line, 8 % of a shaped run's worker instructions more).
    #[inline(always)]
    pub fn ringing(&self, start: &Lag, a_c: Vec3, tau_s: f64) -> Ringing {
        let e_p = a_c * self.to_e;
        let u0 = start.e - e_p;
        // u = e^(−στ)(C cos ω_dτ + D sin ω_dτ) = e^(−στ)·R·cos(ω_dτ − φ), R = √(C² + D²),
        // C = u0, D = (u̇0 + σu0)/ω_d (see `lag_at`). Its rate and ω²u + 2σu̇ are the same
        // damped sinusoid turned and scaled: amplitudes R·√(σ² + ω_d²) = ωR and
        // R·√((ω² − 2σ²)² + 4σ²ω_d²) = ω²R. One square root per axis.
        let d = (start.de + u0 * self.sigma) * self.inv_wd;
        // From the start (a whole piece) the decay is 1: no exp.
        let decay = if tau_s > 0.0 {
            (-self.sigma * tau_s).exp()
        } else {
            1.0
        };
        let u = u0.zip_map(&d, |c, d| (c * c + d * d).sqrt() * decay);
        Ringing {
            e_p,
            acc_p: e_p * (-self.omega2),
            u,
            du: u * self.omega,
            acc: u * self.omega2,
        }
    }

    /// The actual acceleration of a lag: ẍ = −ω²e − 2ζω ė (mm/s²).
    #[inline(always)]
    pub fn acceleration(&self, lag: &Lag) -> Vec3 {
        lag.e * (-self.omega2) - lag.de * (2.0 * self.sigma)
    }
}

/// The lag at equally spaced instants of one commanded piece (see [`Response::walk`]).
/// Between instants the free part u = e − e_p, with its rate, turns by the spring's
/// transition matrix over the step h,
///
/// (u, u̇)(τ + h) = e^(−σh) [[cos ω_d h + σ sin ω_d h/ω_d, sin ω_d h/ω_d],
///                          [−ω² sin ω_d h/ω_d, cos ω_d h − σ sin ω_d h/ω_d]] (u, u̇)(τ),
///
/// the closed form of [`Response::lag_at`] composed with itself. Rounding grows by about
/// one unit in the last place of u per step while u itself decays.
#[derive(Clone, Copy, Debug)]
pub struct LagWalk {
    e_p: Vec3,
    u: Vec3,
    du: Vec3,
    step: [[f64; 2]; 2],
}

impl LagWalk {
    /// The lag at the current instant.
    #[inline(always)]
    pub fn lag(&self) -> Lag {
        Lag {
            e: self.e_p + self.u,
            de: self.du,
        }
    }

    /// On to the next instant.
    #[inline(always)]
    pub fn advance(&mut self) {
        let [[a, b], [c, d]] = self.step;
        let (u, du) = (self.u, self.du);
        self.u = u * a + du * b;
        self.du = u * c + du * d;
    }
}

/// The lag's bounds from an instant of a piece on (see [`Response::ringing`]): per axis
/// e ∈ e_p ± u, ė ∈ ±du, the actual acceleration ∈ acc_p ± acc.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ringing {
    /// The lag the piece's acceleration settles to, −a_c/ω², mm.
    pub e_p: Vec3,
    /// The actual acceleration once settled, −ω²e_p, mm/s².
    pub acc_p: Vec3,
    pub u: Vec3,
    pub du: Vec3,
    pub acc: Vec3,
}

/// What the drive makes of a commanded piece ([`DriveStage::push`]): with the piece, the
/// actual motion over it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DriveStep {
    /// The lag at the start, after the junction's velocity jump.
    pub lag: Lag,
    /// The lag at the end, before the next junction's jump: [`Response::lag_at`] at the
    /// piece's duration (zero with the rigid model).
    pub end: Lag,
    /// The commanded velocity jump at the start (the junction), mm/s: none after a
    /// re-homing.
    pub jump: Vec3,
    /// Whether the piece starts where the previous one ended (not after a re-homing; the
    /// first piece does).
    pub continuous: bool,
}

/// The exp and sin/cos of a duration τ ([`Response::turn`]).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Turn {
    sin: f64,
    cos: f64,
    decay: f64,
}

/// Slots of [`DriveStage`]'s memo of [`Response::turn`] by piece duration: on the corpus's
/// bunny 79 % of the pieces find their duration there with an input shaper (its pulses cut
/// the moves at the same offsets) and 30 % without (docs/performance.md).
const TURN_MEMO_BITS: u32 = 12;
const TURN_MEMO: usize = 1 << TURN_MEMO_BITS;

/// The memo's slot of a duration's bits: their product with 2^64/φ, its top bits (Knuth's
/// multiplicative hashing). Two instructions where three shifts and xors took seven, and
/// as few misses (on the bunny's first 5 MB 351.6 k against 353.5 k of 1.61 M pieces with
/// the MZV shaper, 336.3 k against 336.1 k of 478 k without; 313.7 k and 283.3 k of the
/// durations are new). A shaper's durations are mostly alike in their low bits: a mask of
/// those missed 1.60 M times.
#[inline(always)]
fn memo_slot(bits: u64) -> usize {
    (bits.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> (u64::BITS - TURN_MEMO_BITS)) as usize
}

/// The drive as a stream: commanded pieces in, in time order; each with the lag at its
/// start out. Cheap (one closed-form step per piece), so it runs sequentially ahead of the
/// sampling.
#[derive(Clone, Debug)]
pub struct DriveStage {
    response: Option<Response>,
    /// The lag, e and ė, in lanes: with AVX2 one load and one store each a piece (as
    /// `Vec3`s, their axes were set in lanes, taken out and stored one by one).
    lag: [Lanes; 2],
    /// The previous piece's commanded end position and velocity, likewise.
    prev_end: Option<[Lanes; 2]>,
    /// [`Response::turn`] of recent pieces' durations, by the duration's bits (a slot
    /// holds a duration and its turn, so what it gives is what the turn computes). Of a
    /// fixed size, so that a slot's index needs no bounds check; unused with the rigid model.
    memo: Box<[(u64, Turn); TURN_MEMO]>,
}

impl DriveStage {
    pub fn new(drive: &Drive) -> DriveStage {
        let response = match drive {
            Drive::Rigid => None,
            Drive::Spring(s) => Some(Response::new(s)),
        };
        // The turn of a zero duration, in each slot: sin 0, cos 1, e^0.
        let zero = Turn {
            sin: 0.0,
            cos: 1.0,
            decay: 1.0,
        };
        debug_assert!(response.is_none_or(|r| r.turn(0.0) == zero));
        let memo = match vec![(0.0f64.to_bits(), zero); TURN_MEMO]
            .into_boxed_slice()
            .try_into()
        {
            Ok(memo) => memo,
            Err(_) => unreachable!("the memo is built with its size"),
        };
        DriveStage {
            response,
            lag: Default::default(),
            prev_end: None,
            memo,
        }
    }

    /// The lags at the start and end of the next commanded piece. A piece that does not
    /// start where the previous ended (a re-homing) starts from rest on the command.
    ///
    /// Inlined into the sequencer: its result is then built where it is used. In axes `A`
    /// ([`Axes`]): with AVX2 the continuity test, the jump and the lag's turn on whole
    /// registers.
    #[inline(always)]
    pub(crate) fn push<A: Axes>(&mut self, seg: &Segment) -> DriveStep {
        // The turn's memo first: a miss calls exp, and no vector of the piece is live across
        // that call yet (spilled and loaded again, −0.27 % of a default run's instructions).
        let turn = self.response.as_ref().map(|r| {
            let bits = seg.dt_s.to_bits();
            let slot = &mut self.memo[memo_slot(bits)];
            if slot.0 != bits {
                *slot = (bits, r.turn(seg.dt_s));
            }
            slot.1
        });
        // The lag in locals, written back once: updated in place, its three components
        // were stored in parts and loaded again across them, which the processor cannot
        // forward from its store buffer (a stall of a dozen cycles a piece).
        let (mut e, mut de) = (A::get(&self.lag[0]), A::get(&self.lag[1]));
        let v = A::load(&seg.v);
        let (jump, continuous) = match &self.prev_end {
            Some([p, pv]) if (A::load(&seg.p) - A::get(p)).norm() <= CONTINUITY_MM => {
                (v - A::get(pv), true)
            }
            Some(_) => {
                (e, de) = (A::zero(), A::zero());
                (A::zero(), false)
            }
            None => (v, true),
        };
        if self.response.is_some() {
            de = de - jump;
        }
        let start = Lag {
            e: e.vec3(),
            de: de.vec3(),
        };
        if let (Some(r), Some(turn)) = (&self.response, turn) {
            (e, de) = r.lag_after(e, de, A::load(&seg.a), turn);
        }
        e.put(&mut self.lag[0]);
        de.put(&mut self.lag[1]);
        let (p_end, v_end) = seg.end_in::<A>();
        let prev = self.prev_end.insert(Default::default());
        p_end.put(&mut prev[0]);
        v_end.put(&mut prev[1]);
        DriveStep {
            lag: start,
            end: Lag {
                e: e.vec3(),
                de: de.vec3(),
            },
            jump: jump.vec3(),
            continuous,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::motion::{Phase, PhaseChanges};

    /// ẍ = ω²(x_c − x) + 2ζω(ẋ_c − ẋ) integrated numerically: classic RK4 on (x, ẋ) from
    /// rest at x = 0, with the commanded motion a function of time. Calls `on(t, x, ẋ, ẍ)`
    /// after each step.
    fn rk4(
        spring: &Spring,
        cmd: impl Fn(f64) -> (f64, f64),
        t_end: f64,
        dt: f64,
        mut on: impl FnMut(f64, f64, f64, f64),
    ) {
        let w = std::f64::consts::TAU * spring.frequency_hz;
        let z = spring.damping_ratio;
        let f = |t: f64, x: f64, v: f64| {
            let (xc, vc) = cmd(t);
            w * w * (xc - x) + 2.0 * z * w * (vc - v)
        };
        let (mut t, mut x, mut v) = (0.0, 0.0, 0.0);
        while t < t_end {
            let (k1x, k1v) = (v, f(t, x, v));
            let (k2x, k2v) = (
                v + 0.5 * dt * k1v,
                f(t + 0.5 * dt, x + 0.5 * dt * k1x, v + 0.5 * dt * k1v),
            );
            let (k3x, k3v) = (
                v + 0.5 * dt * k2v,
                f(t + 0.5 * dt, x + 0.5 * dt * k2x, v + 0.5 * dt * k2v),
            );
            let (k4x, k4v) = (v + dt * k3v, f(t + dt, x + dt * k3x, v + dt * k3v));
            x += dt / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x);
            v += dt / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
            t += dt;
            on(t, x, v, f(t, x, v));
        }
    }

    /// [`DriveStage::push`] in AVX2 lanes, compiled for AVX2 (as the sequencer's is).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn push_avx2(stage: &mut DriveStage, seg: &Segment) -> DriveStep {
        stage.push::<crate::motion::Avx2Axes>(seg)
    }

    fn piece(t0: f64, dt: f64, p: f64, v: f64, a: f64) -> Segment {
        let x = |s: f64| Vec3::new(s, 0.0, 0.0);
        Segment {
            t0_s: t0,
            dt_s: dt,
            p: x(p),
            v: x(v),
            a: x(a),
            line: 1,
            phase: Phase::Cruise,
            later_phases: PhaseChanges::NO_PHASES,
            changes: PhaseChanges::NONE,
        }
    }

    #[test]
    fn the_stage_gives_the_closed_form_bit_for_bit_through_its_memo() {
        // Durations that repeat (found in the memo) and 10,000 distinct ones (slots
        // overwritten), against `lag_at` from each piece's start; the AVX2 lanes (where the
        // CPU has them) give the same bits.
        let spring = Spring {
            frequency_hz: 47.0,
            damping_ratio: 0.07,
        };
        let r = Response::new(&spring);
        let mut stage = DriveStage::new(&Drive::Spring(spring));
        let mut lanes = DriveStage::new(&Drive::Spring(spring));
        #[cfg(target_arch = "x86_64")]
        let avx2 = std::arch::is_x86_feature_detected!("avx2");
        #[cfg(not(target_arch = "x86_64"))]
        let avx2 = false;
        let bits = |l: &Lag| [l.e, l.de].map(|v| v.map(f64::to_bits));
        let (mut t, mut p, mut expected) = (0.0, 0.0, Lag::default());
        for k in 0..30_000u32 {
            let dt = if k % 3 == 0 {
                1e-3 * f64::from(k % 7 + 1)
            } else {
                1e-3 + 1e-7 * f64::from(k)
            };
            let a = if k % 2 == 0 { 3000.0 } else { -2000.0 };
            let s = piece(t, dt, p, 0.0, a);
            let got = stage.push::<Vec3>(&s);
            assert_eq!(got.lag, expected, "piece {k}");
            if avx2 {
                // SAFETY: the CPU has AVX2, checked above.
                let step = unsafe { push_avx2(&mut lanes, &s) };
                assert_eq!(bits(&step.end), bits(&got.end), "piece {k}");
            }
            expected = r.lag_at(&got.lag, s.a, dt);
            (t, p) = (t + dt, s.end().0.x);
            // The next piece starts at rest on the command: the lag's rate takes the jump.
            expected.de += s.end().1;
        }
    }

    #[test]
    fn the_closed_form_is_the_integrated_equation_through_a_jump_and_a_ramp() {
        // From rest: a velocity step to 50 mm/s at t = 0 held 20 ms, then −2500 mm/s² for
        // 20 ms (to rest), then rest; against RK4 at 1 µs on the same equation.
        let spring = Spring {
            frequency_hz: 60.0,
            damping_ratio: 0.08,
        };
        let pieces = [
            piece(0.0, 0.02, 0.0, 50.0, 0.0),
            piece(0.02, 0.02, 1.0, 50.0, -2500.0),
            piece(0.04, 0.06, 1.5, 0.0, 0.0),
        ];
        let mut stage = DriveStage::new(&Drive::Spring(spring));
        let actual: Vec<DriveStep> = pieces.iter().map(|s| stage.push::<Vec3>(s)).collect();
        let r = Response::new(&spring);
        let on_piece = |t: f64| pieces.iter().rposition(|s| s.t0_s <= t).unwrap_or(0);
        let closed = |t: f64| {
            let (a, seg) = (&actual[on_piece(t)], &pieces[on_piece(t)]);
            let tau = t - seg.t0_s;
            let (pc, vc, _) = seg.at(tau);
            let lag = r.lag_at(&a.lag, seg.a, tau);
            (pc.x + lag.e.x, vc.x + lag.de.x, r.acceleration(&lag).x)
        };
        let cmd = |t: f64| {
            let (p, v, _) = pieces[on_piece(t)].at(t - pieces[on_piece(t)].t0_s);
            (p.x, v.x)
        };
        let (mut worst, mut peak, mut n) = ([0.0_f64; 3], 0.0_f64, 0);
        rk4(&spring, cmd, 0.1, 1e-6, |t, x, v, a| {
            n += 1;
            if n % 97 == 0 {
                let (xc, vc, ac) = closed(t);
                worst[0] = worst[0].max((xc - x).abs());
                worst[1] = worst[1].max((vc - v).abs());
                worst[2] = worst[2].max((ac - a).abs());
                peak = peak.max(a.abs());
            }
        });
        // A 50 mm/s jump through a 60 Hz, ζ = 0.08 drive: 2ζω·Δv right after the jump
        // (the largest acceleration of all here), within 1e-6 of the integration.
        let w = std::f64::consts::TAU * 60.0;
        assert!(peak > 2.0 * 0.08 * w * 50.0 * 0.99, "{peak}");
        assert!(
            worst[0] < 1e-9 && worst[1] < 1e-6 && worst[2] < 1e-3,
            "{worst:?}"
        );
    }

    #[test]
    fn the_walk_is_the_closed_form_at_each_step() {
        // 20,000 steps of 1 ms (a 20 s piece, the longest the corpus has is shorter)
        // through a lightly damped drive, from a lag that rings: every step against
        // `lag_at` at the same instant, within rounding relative to the ringing's size.
        let r = Response::new(&Spring {
            frequency_hz: 37.0,
            damping_ratio: 0.02,
        });
        let start = Lag {
            e: Vec3::new(0.02, -0.01, 0.003),
            de: Vec3::new(-40.0, 25.0, 3.0),
        };
        let a_c = Vec3::new(1500.0, -700.0, 0.0);
        let (tau0, h) = (0.000_37, 0.001);
        let mut walk = r.walk(&start, a_c, tau0, h);
        assert_eq!(
            r.with_step(h).walk(&start, a_c, tau0, h).step,
            walk.step,
            "the matrix computed once is the one computed each time"
        );
        for k in 0..20_000 {
            let exact = r.lag_at(&start, a_c, tau0 + k as f64 * h);
            let got = walk.lag();
            assert!((got.e - exact.e).norm() < 1e-14, "{k}: {got:?} {exact:?}");
            assert!((got.de - exact.de).norm() < 1e-11, "{k}: {got:?} {exact:?}");
            let (ga, ea) = (r.acceleration(&got), r.acceleration(&exact));
            assert!((ga - ea).norm() < 1e-8, "{k}: {ga} {ea}");
            walk.advance();
        }
    }

    #[test]
    fn the_ringing_bounds_the_lag_at_every_later_instant() {
        // Against the closed form and the walk, at and after each bound's instant; and the
        // bound is reached within a period (not loose by more than the decay over it).
        let r = Response::new(&Spring {
            frequency_hz: 51.0,
            damping_ratio: 0.1,
        });
        let start = Lag {
            e: Vec3::new(0.02, -0.01, 0.003),
            de: Vec3::new(-40.0, 25.0, 3.0),
        };
        let a_c = Vec3::new(3000.0, -700.0, 0.0);
        let h = 1e-4;
        for from in [0.0, 0.0031, 0.017, 0.2] {
            let b = r.ringing(&start, a_c, from);
            let mut walk = r.walk(&start, a_c, from, h);
            // Per axis, the largest |u|, |u̇| and |ω²u + 2σu̇| reached in the first period,
            // each with its decay since `from` taken out.
            let mut reached = [[0.0f64; 3]; 3];
            for k in 0..4000 {
                let tau = from + k as f64 * h;
                for lag in [r.lag_at(&start, a_c, tau), walk.lag()] {
                    let u = lag.e - b.e_p;
                    let dacc = r.acceleration(&lag) - b.acc_p;
                    for i in 0..3 {
                        let slack = |x: f64| 1e-12 * (1.0 + x);
                        assert!(u[i].abs() <= b.u[i] + slack(b.u[i]), "{from} {k} u");
                        assert!(lag.de[i].abs() <= b.du[i] + slack(b.du[i]), "{from} {k}");
                        assert!(dacc[i].abs() <= b.acc[i] + slack(b.acc[i]), "{from} {k}");
                        if tau < from + r.period_s() {
                            let undecay = (r.sigma * (tau - from)).exp();
                            for (q, x) in [u[i], lag.de[i], dacc[i]].into_iter().enumerate() {
                                reached[q][i] = reached[q][i].max(x.abs() * undecay);
                            }
                        }
                    }
                }
                walk.advance();
            }
            // Each amplitude is reached within a period, once its decay is taken out: none
            // is loose (ω·R and ω²·R for the rate and the acceleration, exactly).
            for (q, bound) in [b.u, b.du, b.acc].iter().enumerate() {
                for i in 0..3 {
                    assert!(reached[q][i] >= bound[i] * 0.999, "{from} {q} {i}");
                }
            }
            // Settled: the actual acceleration is the command's.
            assert!((b.acc_p - a_c).norm() < 1e-9 * a_c.norm());
        }
    }

    #[test]
    fn a_constant_acceleration_settles_to_its_lag() {
        // Under a constant commanded acceleration the lag settles to −a/ω² and the actual
        // acceleration to the commanded one.
        let spring = Spring {
            frequency_hz: 40.0,
            damping_ratio: 0.3,
        };
        let r = Response::new(&spring);
        let a = Vec3::new(3000.0, -1000.0, 0.0);
        let lag = r.lag_at(&Lag::default(), a, 1.0);
        let w2 = (std::f64::consts::TAU * 40.0_f64).powi(2);
        assert!((lag.e - a * (-1.0 / w2)).norm() < 1e-12);
        assert!((r.acceleration(&lag) - a).norm() < 1e-6);
        assert!((r.period_s() - 0.025).abs() < 1e-15);
    }

    #[test]
    fn a_rigid_drive_has_no_lag_and_a_rehoming_resets_it() {
        let mut rigid = DriveStage::new(&Drive::Rigid);
        let a = rigid.push::<Vec3>(&piece(0.0, 0.01, 0.0, 10.0, 0.0));
        assert_eq!(a.lag, Lag::default());
        assert_eq!(a.jump, Vec3::new(10.0, 0.0, 0.0));
        let mut spring = DriveStage::new(&Drive::Spring(Spring {
            frequency_hz: 50.0,
            damping_ratio: 0.1,
        }));
        spring.push::<Vec3>(&piece(0.0, 0.01, 0.0, 10.0, 0.0));
        // 0.1 mm further than the first piece ends: a re-homing, from rest on the command.
        let b = spring.push::<Vec3>(&piece(0.01, 0.01, 0.2, 0.0, 0.0));
        assert_eq!(b.lag, Lag::default());
        assert_eq!(b.jump, Vec3::zeros());
    }
}
