//! The resampler: planned moves → samples on the global grid t = k·Ts (plus phase
//! boundaries and junctions), position stepped with the paper's Taylor step (eq. 19).
//! See `docs/resampler.md`.

use crate::path::Vec3;

pub mod curve;
mod junction;
mod sampler;
mod schedule;

pub use curve::{Curve, Frame, Lissajous, TaylorStep, taylor_step, walk_constant_speed};
pub use sampler::sample_move;

/// Where in its move a sample lies.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Phase {
    Accel,
    Cruise,
    Decel,
    /// Within half a period of a junction, where the velocity impulse is spread.
    Corner,
}

impl Phase {
    /// The name in reports (as in the JSON).
    pub fn as_str(self) -> &'static str {
        match self {
            Phase::Accel => "accel",
            Phase::Cruise => "cruise",
            Phase::Decel => "decel",
            Phase::Corner => "corner",
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

/// Where the resampler's samples go, in time order. A closure taking a [`Sample`] is one;
/// a type of its own can have its method inlined into the sampling loop.
pub trait SampleSink {
    fn sample(&mut self, s: Sample);
}

impl<F: FnMut(Sample)> SampleSink for F {
    #[inline(always)]
    fn sample(&mut self, s: Sample) {
        self(s)
    }
}

/// The nozzle's state at one instant (bed frame, mm, s).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    pub t_s: f64,
    /// Source line of the move the sample belongs to.
    pub line: u64,
    pub phase: Phase,
    pub pos_mm: Vec3,
    pub vel_mm_s: Vec3,
    pub acc_mm_s2: Vec3,
}
