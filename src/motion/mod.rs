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
        self.end_in::<false>()
    }

    /// [`Self::end`]; with `AVX2` (only in code compiled for AVX2, which runs only on a CPU
    /// with it), the three axes in one register ([`Self::end_avx2`]).
    #[inline(always)]
    pub fn end_in<const AVX2: bool>(&self) -> (Vec3, Vec3) {
        #[cfg(target_arch = "x86_64")]
        if AVX2 {
            // SAFETY: `AVX2` is set only in code compiled for AVX2, chosen at run time on a
            // CPU that has it.
            return unsafe { self.end_avx2() };
        }
        let (p, v, _) = self.at(self.dt_s);
        (p, v)
    }
}

/// A vector in memory, its three axes in the lanes of an AVX2 register, the fourth zero:
/// one masked load where setting the lanes took a load, a broadcast and two blends.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
pub(crate) fn load_lanes(v: &Vec3) -> std::arch::x86_64::__m256d {
    use std::arch::x86_64::*;
    // SAFETY: the mask reads the vector's three doubles.
    unsafe { _mm256_maskload_pd(v.as_ptr(), _mm256_set_epi64x(0, -1, -1, -1)) }
}

#[cfg(target_arch = "x86_64")]
impl Segment {
    /// [`Self::end`] with the three axes in the lanes of one AVX2 register (the fourth
    /// zero): the same operations on each axis in the same order as [`Self::at`], so the
    /// same bits.
    #[target_feature(enable = "avx2")]
    #[inline]
    fn end_avx2(&self) -> (Vec3, Vec3) {
        use std::arch::x86_64::*;
        let (p, v, a) = (
            load_lanes(&self.p),
            load_lanes(&self.v),
            load_lanes(&self.a),
        );
        let tau = self.dt_s;
        let (add, mul) = (_mm256_add_pd, _mm256_mul_pd);
        let p_end = add(
            add(p, mul(v, _mm256_set1_pd(tau))),
            mul(a, _mm256_set1_pd(0.5 * tau * tau)),
        );
        let v_end = add(v, mul(a, _mm256_set1_pd(tau)));
        let mut out = [0.0; 8];
        // SAFETY: four doubles, then four, into an array of eight.
        unsafe {
            _mm256_storeu_pd(out.as_mut_ptr(), p_end);
            _mm256_storeu_pd(out.as_mut_ptr().add(4), v_end);
        }
        (
            Vec3::new(out[0], out[1], out[2]),
            Vec3::new(out[4], out[5], out[6]),
        )
    }
}

/// Position jumps smaller than this between consecutive pieces are rounding, mm; larger
/// ones are a re-homing (G28), where the motion starts afresh.
pub const CONTINUITY_MM: f64 = 1e-6;

/// A velocity jump smaller than this (mm/s) is rounding, not a junction: two collinear
/// moves' directions differ by ~1e-16.
pub const JUMP_MIN_MM_S: f64 = 1e-9;
