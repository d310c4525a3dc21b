//! Samples of one piece of the actual motion.
//!
//! A piece is sampled at its start (the right limit there), at every grid point k·Ts
//! strictly inside it, and at its end (the left limit) when the state jumps there. The union
//! over consecutive pieces has every grid point once.

use super::{Phase, Sample, SampleSink};
use crate::motion::drive::{ActualPiece, Response};
use crate::path::Vec3;

/// A velocity jump smaller than this (mm/s) is rounding, not a junction: two collinear
/// moves' directions differ by ~1e-16.
pub const JUMP_MIN_MM_S: f64 = 1e-9;

/// The rigid model's junction impulses around one piece: each junction's velocity jump
/// spread evenly over a box from half a piece before it to half a piece after it, each half
/// at most half a period, [t_j − min(Ts, d_in)/2, t_j + min(Ts, d_out)/2]. A corner between
/// long pieces shows Δv/Ts; boxes of neighbouring junctions tile the time line, so no
/// instant counts two junctions or none.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Kicks {
    /// Acceleration added before `calm_from_s` (the start junction's), mm/s².
    pub start: Vec3,
    /// Acceleration added from `calm_to_s` on (the end junction's), mm/s².
    pub end: Vec3,
    pub calm_from_s: f64,
    pub calm_to_s: f64,
}

impl Kicks {
    /// The impulses of a piece from `t0` lasting `dt`, with the jumps at its start and end
    /// and its neighbours' durations.
    pub fn around(
        t0_s: f64,
        dt_s: f64,
        jump_in: Vec3,
        prev_dt_s: f64,
        jump_out: Vec3,
        next_dt_s: f64,
        period_s: f64,
    ) -> Kicks {
        let half = |d: f64| 0.5 * d.max(0.0).min(period_s);
        let own = half(dt_s);
        let density = |dv: Vec3, width: f64| {
            if width > 0.0 {
                dv / width
            } else {
                Vec3::zeros()
            }
        };
        Kicks {
            start: density(jump_in, half(prev_dt_s) + own),
            end: density(jump_out, own + half(next_dt_s)),
            calm_from_s: t0_s + own,
            calm_to_s: t0_s + dt_s - own,
        }
    }

    /// The acceleration the impulses add at `t`.
    #[inline(always)]
    fn at(&self, t: f64) -> Vec3 {
        if t < self.calm_from_s {
            self.start
        } else if t >= self.calm_to_s {
            self.end
        } else {
            Vec3::zeros()
        }
    }
}

/// One piece of the actual motion, with what its sampling needs to know of its neighbours.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PieceWork {
    pub piece: ActualPiece,
    /// The rigid model's junction impulses (zero with a drive response).
    pub kicks: Kicks,
    /// Sample the left limit at the end: the state jumps there.
    pub end_sample: bool,
    /// Until this time the samples are in a `Corner`: just after a junction's jump.
    pub corner_until_s: f64,
}

/// Samples of `work` (see the module doc) on the grid of `period_s`, which must be positive
/// and finite; `response` is the drive's (None: the rigid model).
pub fn sample_piece(
    work: &PieceWork,
    response: Option<&Response>,
    period_s: f64,
    out: &mut impl SampleSink,
) {
    if !(period_s > 0.0 && period_s.is_finite()) {
        return;
    }
    let seg = &work.piece.commanded;
    let (t0, t1) = (seg.t0_s, seg.t1_s());
    let state = |t: f64, left: bool| -> Sample {
        let tau = t - t0;
        let (p, v, a) = seg.at(tau);
        let (pos, vel, acc, kick) = match response {
            Some(r) => {
                let lag = r.lag_at(&work.piece.lag, seg.a, tau);
                (p + lag.e, v + lag.de, r.acceleration(&lag), false)
            }
            None => {
                let k = if left {
                    work.kicks.end
                } else {
                    work.kicks.at(t)
                };
                (p, v, a + k, k != Vec3::zeros())
            }
        };
        let phase = if kick || t < work.corner_until_s {
            Phase::Corner
        } else {
            seg.phase
        };
        Sample {
            t_s: t,
            line: seg.line,
            phase,
            pos_mm: pos,
            vel_mm_s: vel,
            acc_mm_s2: acc,
            cmd_pos_mm: p,
        }
    };
    out.sample(state(t0, false));
    let mut k = first_grid_index(t0, period_s);
    if k as f64 * period_s <= t0 {
        k += 1;
    }
    loop {
        let t = k as f64 * period_s;
        if t >= t1 {
            break;
        }
        out.sample(state(t, false));
        k += 1;
    }
    if work.end_sample && t1 > t0 {
        out.sample(state(t1, true));
    }
}

/// Smallest k with k·Ts ≥ t (the grid time is always computed as `k as f64 * period_s`).
fn first_grid_index(t: f64, period_s: f64) -> i64 {
    // ⌈t/Ts⌉ without `f64::ceil`, a library call on baseline x86-64.
    let q = t / period_s;
    let mut k = q as i64;
    if (k as f64) < q {
        k += 1;
    }
    while (k as f64) * period_s < t {
        k += 1;
    }
    while ((k - 1) as f64) * period_s >= t {
        k -= 1;
    }
    k
}
