//! The three motions of the nozzle, as pieces of polynomials in time:
//!
//! - **planned**: what the firmware's planner produces, trapezoids along straight moves
//!   with instantaneous velocity changes at the junctions ([`planned`]);
//! - **commanded**: what the firmware steps, the planned motion after Klipper's input
//!   shaper ([`shaper`]); the carriage positions of this motion are a printer's step counts;
//! - **actual**: what the machine does, each Cartesian axis following the command through
//!   the drive's spring and damper ([`drive`]). Forces (eq. 14) come from this one.
//!
//! Each motion is a stream of [`Segment`]s, contiguous in time: over a segment every axis is
//! a quadratic in time. Position is continuous from one segment to the next (except where
//! the machine is re-homed); velocity may jump at a junction.

pub mod drive;
pub mod planned;
pub mod shaper;

use std::ops::{Add, Mul, Sub};

use crate::path::Vec3;

/// Where in its move a moment of the motion lies.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Phase {
    Accel,
    Cruise,
    Decel,
    /// Just after a junction's velocity jump, where the jump sets the force.
    Corner,
    /// The nozzle stands still (an extrude-only move, a dwell, before and after the print).
    Rest,
}

impl Phase {
    /// The name in reports (as in the JSON).
    pub fn as_str(self) -> &'static str {
        match self {
            Phase::Accel => "accel",
            Phase::Cruise => "cruise",
            Phase::Decel => "decel",
            Phase::Corner => "corner",
            Phase::Rest => "rest",
        }
    }
}

impl std::fmt::Display for Phase {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

impl serde::Serialize for Phase {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.as_str())
    }
}

/// A piece of a motion: over [t0, t0 + dt) the nozzle is at p + v·τ + a·τ²/2, τ = t − t0
/// (bed frame, mm, s).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Segment {
    pub t0_s: f64,
    pub dt_s: f64,
    /// Position, velocity and acceleration at t0.
    pub p: Vec3,
    pub v: Vec3,
    pub a: Vec3,
    /// The G-code line of the planned move this piece belongs to.
    pub line: u64,
    /// The phase at t0; later ones where the piece spans its line's planned phases.
    pub phase: Phase,
    /// The phases from each of `changes` on (apart from them: a struct of both would be
    /// padded to 24 bytes, and a piece's work past 240, `resample::PieceWork`).
    pub later_phases: [Phase; MAX_PHASE_CHANGES],
    pub changes: PhaseChanges,
}

/// Where a piece passes into its line's next planned phases: the shaper's commanded pieces
/// run on through a planned break of the same line that neither the shaped X and Y nor the
/// unshaped axes break at ([`shaper`]). From `at_s[i]` on the phase is the piece's
/// `later_phases[i]`; unused entries are at +∞.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PhaseChanges {
    pub at_s: [f64; MAX_PHASE_CHANGES],
}

/// The most phase changes a piece holds: a planned move's accel, cruise and decel.
pub const MAX_PHASE_CHANGES: usize = 2;

impl PhaseChanges {
    pub const NONE: PhaseChanges = PhaseChanges {
        at_s: [f64::INFINITY; MAX_PHASE_CHANGES],
    };

    /// [`Segment::later_phases`] of a piece without changes.
    pub const NO_PHASES: [Phase; MAX_PHASE_CHANGES] = [Phase::Rest; MAX_PHASE_CHANGES];
}

impl Segment {
    /// A stand-still of `dt_s` at `p` from `t0_s`.
    pub fn rest(t0_s: f64, dt_s: f64, p: Vec3, line: u64) -> Segment {
        Segment {
            t0_s,
            dt_s,
            p,
            v: Vec3::zeros(),
            a: Vec3::zeros(),
            line,
            phase: Phase::Rest,
            later_phases: PhaseChanges::NO_PHASES,
            changes: PhaseChanges::NONE,
        }
    }

    /// How long the piece stays in its phase at the start, s: its duration but for phase
    /// changes ([`PhaseChanges`]).
    pub fn first_part_s(&self) -> f64 {
        match self.changes.at_s[0] {
            c if c.is_finite() => c - self.t0_s,
            _ => self.dt_s,
        }
    }

    /// How long the piece is in its last phase, s ([`Self::first_part_s`] from the end).
    pub fn last_part_s(&self) -> f64 {
        match self.changes.at_s {
            [_, c] | [c, _] if c.is_finite() => self.t1_s() - c,
            _ => self.dt_s,
        }
    }

    /// The end of the piece, s.
    pub fn t1_s(&self) -> f64 {
        self.t0_s + self.dt_s
    }

    /// Position, velocity and acceleration τ after t0.
    #[inline(always)]
    pub fn at(&self, tau_s: f64) -> (Vec3, Vec3, Vec3) {
        (
            self.p + self.v * tau_s + self.a * (0.5 * tau_s * tau_s),
            self.v + self.a * tau_s,
            self.a,
        )
    }

    /// Position and velocity at the end (the left limit at t0 + dt).
    pub fn end(&self) -> (Vec3, Vec3) {
        let (p, v) = self.end_in::<Vec3>();
        (p, v)
    }

    /// [`Self::end`] in axes `A` (the operations of [`Self::at`] in the same order, so
    /// the same bits in either).
    #[inline(always)]
    pub(crate) fn end_in<A: Axes>(&self) -> (A, A) {
        let (p, v, a) = (A::load(&self.p), A::load(&self.v), A::load(&self.a));
        let tau = self.dt_s;
        (p + v * tau + a * (0.5 * tau * tau), v + a * tau)
    }
}

/// A vector's three axes and a zero fourth, aligned: one AVX2 load or store
/// ([`Axes::get`], [`Axes::put`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C, align(32))]
pub(crate) struct Lanes([f64; 4]);

/// Three-axis vectors in registers, for code written once for a [`Vec3`] and for the lanes
/// of an AVX2 register ([`Avx2Axes`], in code compiled for AVX2): the drive stage keeps
/// its lag and the previous piece's end in [`Lanes`], so that with AVX2 its continuity
/// test, the velocity jump and the lag's turn work on whole registers.
pub(crate) trait Axes:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<f64, Output = Self>
{
    /// A vector in memory.
    fn load(v: &Vec3) -> Self;
    fn get(l: &Lanes) -> Self;
    fn put(self, l: &mut Lanes);
    fn vec3(self) -> Vec3;
    fn zero() -> Self;
    /// The Euclidean norm, as nalgebra's: √((x² + y²) + z²).
    fn norm(self) -> f64;
}

impl Axes for Vec3 {
    #[inline(always)]
    fn load(v: &Vec3) -> Self {
        *v
    }
    #[inline(always)]
    fn get(l: &Lanes) -> Self {
        Vec3::new(l.0[0], l.0[1], l.0[2])
    }
    #[inline(always)]
    fn put(self, l: &mut Lanes) {
        l.0[..3].copy_from_slice(self.as_slice());
    }
    #[inline(always)]
    fn vec3(self) -> Vec3 {
        self
    }
    #[inline(always)]
    fn zero() -> Self {
        Vec3::zeros()
    }
    #[inline(always)]
    fn norm(self) -> f64 {
        Vec3::norm(&self)
    }
}

/// The three axes in the lanes of an AVX2 register, the fourth zero: a `Vec3`'s
/// arithmetic takes two instructions (a pair and a scalar), this one. Only in code
/// compiled for AVX2, which runs only on a CPU with it (its operations are inlined there).
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy)]
pub(crate) struct Avx2Axes(std::arch::x86_64::__m256d);

#[cfg(target_arch = "x86_64")]
mod avx2_axes {
    use super::{Avx2Axes, Axes, Lanes, Vec3};
    use std::arch::x86_64::*;
    use std::ops::{Add, Mul, Sub};

    // SAFETY (each `unsafe` below): an `Avx2Axes` is used only in code compiled for AVX2,
    // chosen at run time on a CPU that has it; the loads and stores stay in their vectors.
    impl Add for Avx2Axes {
        type Output = Self;
        #[inline(always)]
        fn add(self, o: Self) -> Self {
            Avx2Axes(unsafe { _mm256_add_pd(self.0, o.0) })
        }
    }

    impl Sub for Avx2Axes {
        type Output = Self;
        #[inline(always)]
        fn sub(self, o: Self) -> Self {
            Avx2Axes(unsafe { _mm256_sub_pd(self.0, o.0) })
        }
    }

    impl Mul<f64> for Avx2Axes {
        type Output = Self;
        #[inline(always)]
        fn mul(self, k: f64) -> Self {
            Avx2Axes(unsafe { _mm256_mul_pd(self.0, _mm256_set1_pd(k)) })
        }
    }

    impl Axes for Avx2Axes {
        /// One masked load where setting the lanes took a load, a broadcast and two blends.
        #[inline(always)]
        fn load(v: &Vec3) -> Self {
            Avx2Axes(unsafe { _mm256_maskload_pd(v.as_ptr(), _mm256_set_epi64x(0, -1, -1, -1)) })
        }
        #[inline(always)]
        fn get(l: &Lanes) -> Self {
            Avx2Axes(unsafe { _mm256_load_pd(l.0.as_ptr()) })
        }
        #[inline(always)]
        fn put(self, l: &mut Lanes) {
            unsafe { _mm256_store_pd(l.0.as_mut_ptr(), self.0) }
        }
        #[inline(always)]
        fn vec3(self) -> Vec3 {
            let mut l = Lanes::default();
            self.put(&mut l);
            <Vec3 as Axes>::get(&l)
        }
        #[inline(always)]
        fn zero() -> Self {
            Avx2Axes(unsafe { _mm256_setzero_pd() })
        }
        #[inline(always)]
        fn norm(self) -> f64 {
            unsafe {
                let sq = _mm256_mul_pd(self.0, self.0);
                let xy = _mm256_castpd256_pd128(sq);
                let xy = _mm_add_sd(xy, _mm_unpackhi_pd(xy, xy));
                _mm_cvtsd_f64(_mm_add_sd(xy, _mm256_extractf128_pd(sq, 1))).sqrt()
            }
        }
    }
}

/// Position jumps smaller than this between consecutive pieces are rounding, mm; larger
/// ones are a re-homing (G28), where the motion starts afresh.
pub const CONTINUITY_MM: f64 = 1e-6;

/// A velocity jump smaller than this (mm/s) is rounding, not a junction: two collinear
/// moves' directions differ by ~1e-16.
pub const JUMP_MIN_MM_S: f64 = 1e-9;
