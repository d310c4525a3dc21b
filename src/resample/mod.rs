//! The sampler: the actual motion, piece by piece, at the instants of the global grid
//! t = k·Ts, plus each piece's start (and its end where the next starts with a jump). See
//! `docs/resampler.md`. The paper's own way of walking a path at constant speed, the Taylor
//! step of eq. 19, is in [`curve`] (the Lissajous validation of the paper's figures).

pub mod curve;
mod piece;

pub use crate::motion::Phase;
pub use curve::{Curve, Frame, Lissajous, TaylorStep, taylor_step, walk_constant_speed};
pub(crate) use piece::piece_raw;
pub use piece::{
    Edge, Fit, Kicks, PieceWork, RawBox, SPARSE_MIN_SAMPLES, move_samples, peak_candidates,
    piece_samples, piece_states, sample_piece,
};

use crate::interval::Interval;
use crate::path::Vec3;

/// Where the sampler's samples go, in time order. A closure taking a [`Sample`] is one;
/// a type of its own can have its method inlined into the sampling loop.
pub trait SampleSink {
    fn sample(&mut self, s: Sample);

    /// Whether this sink wants to be asked [`Self::skip`] (a sparse evaluation).
    #[inline(always)]
    fn sparse(&self) -> bool {
        false
    }

    /// Whether this sink wants to be asked [`Self::skip`] for whole pieces too, before
    /// their first sample (with every sample of the piece in the box and the count).
    #[inline(always)]
    fn whole_pieces(&self) -> bool {
        false
    }

    /// Whether the sampler may leave `count` consecutive grid samples of a piece
    /// uncomputed, every one of whose states lies in `states`; a sink that says yes has
    /// counted them. Asked only of a sink that is [`Self::sparse`] (or, for whole pieces,
    /// [`Self::whole_pieces`]), in time order between the samples.
    #[inline(always)]
    fn skip(&mut self, _states: &StateBox, _count: u64) -> bool {
        false
    }
}

/// A box holding the actual states of a run of samples: per coordinate, position (mm),
/// velocity (mm/s) and acceleration (mm/s²) ranges.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StateBox {
    pub pos_mm: [Interval; 3],
    pub vel_mm_s: [Interval; 3],
    pub acc_mm_s2: [Interval; 3],
}

impl StateBox {
    /// The smallest box holding both.
    #[inline(always)]
    pub fn join(&self, o: &StateBox) -> StateBox {
        let mut b = *self;
        b.join_in_place(o);
        b
    }

    /// Grows to the smallest box holding both.
    #[inline(always)]
    pub fn join_in_place(&mut self, o: &StateBox) {
        for k in 0..3 {
            self.pos_mm[k] = self.pos_mm[k].join(o.pos_mm[k]);
            self.vel_mm_s[k] = self.vel_mm_s[k].join(o.vel_mm_s[k]);
            self.acc_mm_s2[k] = self.acc_mm_s2[k].join(o.acc_mm_s2[k]);
        }
    }
}

impl<F: FnMut(Sample)> SampleSink for F {
    #[inline(always)]
    fn sample(&mut self, s: Sample) {
        self(s)
    }
}

/// The nozzle's actual state at one instant, and where the command had it (bed frame, mm,
/// s).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    pub t_s: f64,
    /// Source line of the move the sample belongs to.
    pub line: u64,
    pub phase: Phase,
    pub pos_mm: Vec3,
    pub vel_mm_s: Vec3,
    pub acc_mm_s2: Vec3,
    /// The commanded position at the same instant (what the steps encode).
    pub cmd_pos_mm: Vec3,
}
