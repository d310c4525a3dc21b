//! Samples of one piece of the actual motion.
//!
//! A piece is sampled at its start (the right limit there), at every grid point k·Ts
//! strictly inside it, and at its end (the left limit) when the state jumps there. The union
//! over consecutive pieces has every grid point once.

use super::{Phase, Sample, SampleSink, StateBox};
use crate::interval::{Interval, greater};
use crate::motion::drive::{DriveStep, Lag, LagWalk, ROUND, Response};
use crate::motion::{MAX_PHASE_CHANGES, PhaseChanges, Segment};
use crate::path::Vec3;

/// The rigid model's junction impulses around one piece: each junction's velocity jump
/// spread evenly over a box from half a piece before it to half a piece after it, each half
/// at most half a period, [t_j − min(Ts, d_in)/2, t_j + min(Ts, d_out)/2]. A corner between
/// long pieces shows Δv/Ts; boxes of neighbouring junctions tile the time line, so no
/// instant counts two junctions or none.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Kicks {
    /// Acceleration added in the start junction's half box, mm/s².
    pub start: Vec3,
    /// Acceleration added in the end junction's half box, mm/s².
    pub end: Vec3,
}

/// Half a junction's box on the side of a piece (part) lasting `d_s`: half of it, at most
/// half a period.
#[inline(always)]
fn half_box(d_s: f64, period_s: f64) -> f64 {
    0.5 * d_s.max(0.0).min(period_s)
}

impl Kicks {
    /// The impulses of `seg`, with the jumps at its start and end and its neighbours'
    /// durations (of their parts next to it, [`Segment::first_part_s`] and
    /// [`Segment::last_part_s`], as of `seg`'s own).
    pub fn around(
        seg: &Segment,
        jump_in: Vec3,
        prev_dt_s: f64,
        jump_out: Vec3,
        next_dt_s: f64,
        period_s: f64,
    ) -> Kicks {
        let half = |d: f64| half_box(d, period_s);
        let (first, last) = (half(seg.first_part_s()), half(seg.last_part_s()));
        let density = |dv: Vec3, width: f64| {
            if width > 0.0 {
                dv / width
            } else {
                Vec3::zeros()
            }
        };
        Kicks {
            start: density(jump_in, half(prev_dt_s) + first),
            end: density(jump_out, last + half(next_dt_s)),
        }
    }

    /// Where on `seg` the impulses act: before the end of the start junction's half box,
    /// from the start of the end junction's. Made when sampling, not kept with the piece
    /// (a piece's work stays within 240 bytes, [`PieceWork`]).
    #[inline(always)]
    fn boxes(self, seg: &Segment, period_s: f64) -> KickBoxes {
        let half = |d: f64| half_box(d, period_s);
        KickBoxes {
            kicks: self,
            calm_from_s: seg.t0_s + half(seg.first_part_s()),
            calm_to_s: seg.t0_s + seg.dt_s - half(seg.last_part_s()),
        }
    }
}

/// [`Kicks`] on a piece's time line ([`Kicks::boxes`]).
struct KickBoxes {
    kicks: Kicks,
    calm_from_s: f64,
    calm_to_s: f64,
}

impl KickBoxes {
    /// The acceleration the impulses add at `t`.
    #[inline(always)]
    fn at(&self, t: f64) -> Vec3 {
        if t < self.calm_from_s {
            self.kicks.start
        } else if t >= self.calm_to_s {
            self.kicks.end
        } else {
            Vec3::zeros()
        }
    }
}

/// One piece of the actual motion, with what its sampling needs to know of its neighbours.
/// At most 240 bytes: a batch holds thousands, and a larger one is copied by a call to
/// `memcpy` where this one is copied inline (+1.5 % of a shaped run's instructions at 256).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PieceWork {
    pub commanded: Segment,
    /// The drive's lag at the start (zero with the rigid model).
    pub lag: Lag,
    /// What the piece's end holds: the lag there, or the rigid model's impulses.
    pub edge: Edge,
    /// Sample the left limit at the end: the state jumps there.
    pub end_sample: bool,
    /// Until this time the samples are in a `Corner`: just after a junction's jump.
    pub corner_until_s: f64,
}

/// With a drive response, the lag at a piece's end ([`DriveStep::end`]); with the rigid
/// model, the junctions' impulses around it. One or the other, in the same space: a batch
/// holds thousands of pieces.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Edge {
    End(Lag),
    Kicks(Kicks),
}

const _: () = assert!(std::mem::size_of::<PieceWork>() <= 240);

impl PieceWork {
    /// The work of the commanded piece `commanded`, with what the drive made of it: the lag
    /// at its end, no end sample. Its successor may change both (the sequencer's
    /// `close_last`: the end sample at a jump, the rigid model's impulses).
    #[inline(always)]
    pub fn new(commanded: Segment, step: &DriveStep, corner_until_s: f64) -> PieceWork {
        PieceWork {
            commanded,
            lag: step.lag,
            edge: Edge::End(step.end),
            end_sample: false,
            corner_until_s,
        }
    }

    /// The rigid model's impulses (none with a drive response).
    fn kicks(&self) -> Kicks {
        match self.edge {
            Edge::Kicks(k) => k,
            Edge::End(_) => Kicks::default(),
        }
    }

    /// Calls `f` with each part of the piece between its phase changes
    /// ([`Segment::changes`]) as a piece of its own: the pieces the shaper made before its
    /// pieces ran on through a line's phases, sampled as they were (a part's start is a
    /// sample). With a drive, each part's lag from the piece's start (`response`).
    fn parts(&self, response: Option<&Response>, mut f: impl FnMut(&PieceWork)) {
        let seg = &self.commanded;
        let c = &seg.changes;
        let mut part = *self;
        (part.commanded.changes, part.commanded.later_phases) =
            (PhaseChanges::NONE, PhaseChanges::NO_PHASES);
        part.end_sample = false;
        for i in 0..=MAX_PHASE_CHANGES {
            let next = c.at_s.get(i).copied().unwrap_or(f64::INFINITY);
            if next.is_finite() {
                let tau = next - seg.t0_s;
                part.commanded.dt_s = next - part.commanded.t0_s;
                let lag = response.map(|r| r.lag_at(&self.lag, seg.a, tau));
                if let Some(lag) = lag {
                    part.edge = Edge::End(lag);
                }
                f(&part);
                let (p, v, _) = seg.at(tau);
                part.commanded.t0_s = next;
                (part.commanded.p, part.commanded.v) = (p, v);
                part.commanded.phase = seg.later_phases[i];
                part.lag = lag.unwrap_or(self.lag);
            } else {
                part.commanded.dt_s = seg.t1_s() - part.commanded.t0_s;
                part.edge = self.edge;
                part.end_sample = self.end_sample;
                f(&part);
                return;
            }
        }
    }
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
    if let Some(r) = response
        && out.whole_pieces()
    {
        let count = piece_samples(work, period_s);
        if count >= SPARSE_MIN_SAMPLES
            && out.skip(&piece_states(work, r, period_s, Fit::Swing), count)
        {
            return;
        }
    }
    let boxes = work.kicks().boxes(&work.commanded, period_s);
    if work.commanded.changes.at_s[0].is_finite() {
        sample_parts(work, response, &boxes, period_s, out);
    } else {
        sample_part(work, response, &boxes, period_s, out);
    }
}

/// [`sample_piece`] of a piece with phase changes, part by part ([`PieceWork::parts`]):
/// out of line, the common piece's loop stays as it was.
#[inline(never)]
fn sample_parts(
    work: &PieceWork,
    response: Option<&Response>,
    boxes: &KickBoxes,
    period_s: f64,
    out: &mut impl SampleSink,
) {
    work.parts(response, |part| {
        sample_part(part, response, boxes, period_s, out);
    });
}

/// [`sample_piece`] of a piece without phase changes, not offered whole; with the rigid
/// model, the impulses where the whole piece has them (`boxes`).
#[inline(always)]
fn sample_part(
    work: &PieceWork,
    response: Option<&Response>,
    boxes: &KickBoxes,
    period_s: f64,
    out: &mut impl SampleSink,
) {
    let seg = &work.commanded;
    let (t0, t1) = (seg.t0_s, seg.t1_s());
    // With a drive, the phase from the corner's end; without, from the impulses.
    let phase = |t: f64, kick: bool| {
        if kick || t < work.corner_until_s {
            Phase::Corner
        } else {
            seg.phase
        }
    };
    let state = |t: f64, left: bool| -> Sample {
        let tau = t - t0;
        let (p, v, a) = seg.at(tau);
        let (pos, vel, acc, kick) = match response {
            Some(r) => {
                // At the start the lag is the piece's own (what `lag_at` gives at τ = 0).
                let lag = if tau == 0.0 {
                    work.lag
                } else {
                    r.lag_at(&work.lag, seg.a, tau)
                };
                (p + lag.e, v + lag.de, r.acceleration(&lag), false)
            }
            None => {
                let k = if left { boxes.kicks.end } else { boxes.at(t) };
                (p, v, a + k, k != Vec3::zeros())
            }
        };
        Sample {
            t_s: t,
            line: seg.line,
            phase: phase(t, kick),
            pos_mm: pos,
            vel_mm_s: vel,
            acc_mm_s2: acc,
            cmd_pos_mm: p,
        }
    };
    out.sample(state(t0, false));
    let mut k = first_inside(t0, period_s);
    match response {
        // The grid points by the lag's fixed step (`Response::walk`): no exp or sin/cos per
        // sample.
        Some(r) if (k as f64 * period_s) < t1 => {
            let t = k as f64 * period_s;
            let mut walk = r.walk(&work.lag, seg.a, t - t0, period_s);
            // Smallest k with k·Ts ≥ t1: the grid points inside are k..end.
            let end = first_grid_index(t1, period_s);
            let grid = Grid {
                work,
                response: r,
                period_s,
            };
            if end - k >= SPARSE_MIN_PIECE && out.sparse() {
                // The first drive period rings from the piece's start (a junction, an
                // acceleration step): sampled, its bound would not pass.
                let settled = (k + (r.period_s() / period_s) as i64).min(end);
                grid.sample(&mut walk, k, settled, out);
                grid.sparse(&mut walk, settled, end, out);
            } else {
                grid.sample(&mut walk, k, end, out);
            }
        }
        _ => loop {
            let t = k as f64 * period_s;
            if t >= t1 {
                break;
            }
            out.sample(state(t, false));
            k += 1;
        },
    }
    if work.end_sample && t1 > t0 {
        out.sample(state(t1, true));
    }
}

/// How many samples [`sample_piece`] takes of `work`: its start, its phase changes, the grid
/// points inside, its end when asked.
pub fn piece_samples(work: &PieceWork, period_s: f64) -> u64 {
    let t0 = work.commanded.t0_s;
    samples_within(work, first_inside(t0, period_s), period_s).0
}

/// [`piece_samples`] of consecutive pieces, summed (a box of a whole move is offered with
/// its count).
///
/// A chain of pieces each starting where the one before it ends, each of positive length,
/// has one start sample a piece, its phase changes' and end samples, and the grid points
/// strictly inside the chain but for those on which a piece starts (they are that piece's
/// start): two grid indices for the chain instead of one a piece, each read off t/Ts when
/// that is not near an integer ([`grid_ceil`]). Whether a start lies on a grid point is
/// asked exactly only when its t/Ts is near an integer. The chain's times rise, so its
/// starts' t/Ts lie between its ends': when both are below [`GRID_NEAR_MAX`], so are all
/// of them, and the pieces need not ask; a chain beyond goes piece by piece, as does any
/// other.
///
/// None when a piece lasts longer than `longest_s` (a whole move's box is offered only when
/// every piece is sampled): asked in the same pass, one loop over the pieces where two
/// mispredicted their ends on the bunny's moves of one to four pieces.
pub fn move_samples(works: &[PieceWork], period_s: f64, longest_s: f64) -> Option<u64> {
    let Some((first, rest)) = works.split_first() else {
        return Some(0);
    };
    let inv = 1.0 / period_s;
    let (start, mut end) = (first.commanded.t0_s, first.commanded.t1_s());
    let mut sampled = first.commanded.dt_s <= longest_s;
    let mut chain = end > start;
    let mut ends = u64::from(first.end_sample) + change_samples(&first.commanded, period_s);
    let mut on_grid = 0;
    for w in rest {
        let (t0, t1) = (w.commanded.t0_s, w.commanded.t1_s());
        // Without a branch per piece: the fallback and long pieces are rare.
        sampled &= w.commanded.dt_s <= longest_s;
        chain &= (t0 == end) & (t1 > t0);
        ends += u64::from(w.end_sample) + change_samples(&w.commanded, period_s);
        if grid_ceil(t0 * inv).is_none() {
            on_grid += u64::from(first_grid_index(t0, period_s) as f64 * period_s == t0);
        }
        end = t1;
    }
    if !sampled {
        return None;
    }
    let (q0, q1) = (start * inv, end * inv);
    if !(chain && q0.abs() < GRID_NEAR_MAX && q1.abs() < GRID_NEAR_MAX) {
        return Some(piece_by_piece(works, period_s));
    }
    let from = grid_ceil(q0).unwrap_or_else(|| first_inside(start, period_s));
    let to = grid_ceil(q1).unwrap_or_else(|| first_grid_index(end, period_s));
    Some(works.len() as u64 + ends + (to - from).max(0) as u64 - on_grid)
}

/// ⌈q⌉ of q = t/Ts (computed `t * (1.0 / Ts)`) more than [`GRID_NEAR`] from an integer and
/// of magnitude below [`GRID_NEAR_MAX`] (the caller's to ask): then both the smallest k
/// with k·Ts ≥ t and the smallest with k·Ts > t, as the grid's times are computed
/// (`k as f64 * Ts`), as [`first_grid_index`] and [`first_inside`] find them by their
/// loops. None when q is near an integer. The integer by adding and taking off 1.5·2^52,
/// read off the sum's last bits (a saturating conversion takes six instructions more).
#[inline(always)]
fn grid_ceil(q: f64) -> Option<i64> {
    let shifted = q + ROUND;
    let nearest = shifted - ROUND;
    // Not `!(… <= GRID_NEAR)`: a NaN is near, asked exactly.
    if (q - nearest).abs() > GRID_NEAR {
        let k = shifted.to_bits() as i64 - ROUND.to_bits() as i64;
        Some(k + i64::from(nearest < q))
    } else {
        None
    }
}

/// How close t/Ts must come to an integer for [`move_samples`] to ask whether t is on the
/// grid, and the largest t/Ts below which that is enough (above, it goes piece by piece):
/// below it t·(1/Ts) is within 3e-7 of t/Ts, and k·Ts within 1.2e-7·Ts of its exact
/// value, so a t/Ts farther than this from an integer is at least 7e-7 from one and
/// neither rounding can bring a grid time to the other side of t.
const GRID_NEAR: f64 = 1e-6;
const GRID_NEAR_MAX: f64 = 1e9;

/// [`move_samples`] a piece at a time: where a piece starts exactly where the one before it
/// ends, its first grid point inside comes from that end's grid index.
fn piece_by_piece(works: &[PieceWork], period_s: f64) -> u64 {
    let mut count = 0;
    let mut end: Option<(f64, i64)> = None;
    for w in works {
        let t0 = w.commanded.t0_s;
        let first = match end {
            Some((t1, k)) if t1 == t0 => first_after(k, t0, period_s),
            _ => first_inside(t0, period_s),
        };
        let (n, k) = samples_within(w, first, period_s);
        count += n;
        end = Some((w.commanded.t1_s(), k));
    }
    count
}

/// The samples of `work` whose first grid point inside is `first`; with the grid index at
/// its end ([`first_grid_index`]).
#[inline(always)]
fn samples_within(work: &PieceWork, first: i64, period_s: f64) -> (u64, i64) {
    let seg = &work.commanded;
    let (t0, t1) = (seg.t0_s, seg.t1_s());
    let end = first_grid_index(t1, period_s);
    let inside = (end - first).max(0) as u64;
    let n = 1 + change_samples(seg, period_s) + inside + u64::from(work.end_sample && t1 > t0);
    (n, end)
}

/// The samples at a piece's phase changes: each is a part's start ([`PieceWork::parts`]),
/// but for one on a grid point, which is among the grid points inside. Whether a change is
/// on one is asked exactly only when its t/Ts is near an integer ([`grid_ceil`]).
#[inline(always)]
fn change_samples(seg: &Segment, period_s: f64) -> u64 {
    // Most pieces have none (every piece without a shaper): one test for them.
    if !seg.changes.at_s[0].is_finite() {
        return 0;
    }
    let off_grid = |&c: &f64| {
        let q = c * (1.0 / period_s);
        c.is_finite()
            && ((q.abs() < GRID_NEAR_MAX && grid_ceil(q).is_some())
                || first_grid_index(c, period_s) as f64 * period_s != c)
    };
    seg.changes.at_s.iter().filter(|c| off_grid(c)).count() as u64
}

/// How closely a box of a whole piece fits its actual accelerations.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Fit {
    /// The lag's ringing envelope over the piece ([`Response::ringing`]): cheap.
    Envelope,
    /// The actual acceleration's swing over the piece ([`Response::acceleration_range`]):
    /// a few hundred instructions more a piece, and let go more often (docs/performance.md).
    Swing,
}

/// A box holding the states of every sample [`sample_piece`] takes of `work` with the drive
/// `response` (see [`piece_samples`]).
pub fn piece_states(work: &PieceWork, response: &Response, period_s: f64, fit: Fit) -> StateBox {
    piece_raw::<false>(work, response, period_s, fit).slacked()
}

/// [`piece_states`] before its rounding slack: the boxes of a move's pieces are joined so,
/// and the join slacked once ([`RawBox::slacked`]).
///
/// `AVX2` only in code compiled for AVX2, which runs only on a CPU with it (the swing's
/// lanes, [`Response::acceleration_range`]).
#[inline(always)]
pub(crate) fn piece_raw<const AVX2: bool>(
    work: &PieceWork,
    response: &Response,
    period_s: f64,
    fit: Fit,
) -> RawBox {
    let grid = Grid {
        work,
        response,
        period_s,
    };
    grid.raw::<AVX2>(0.0, work.commanded.dt_s, fit)
}

/// A box of states before the slack for rounding, with the ringing amplitudes the slack
/// grows with (position, velocity, acceleration, per axis).
#[derive(Clone, Copy, Debug)]
pub struct RawBox {
    states: StateBox,
    ring: [Vec3; 3],
}

impl RawBox {
    /// The smallest raw box holding both: each slacked box lies in the join's, slacked.
    #[inline(always)]
    pub fn join(&self, o: &RawBox) -> RawBox {
        RawBox {
            states: self.states.join(&o.states),
            // Amplitudes, never NaN: a plain comparison, not nalgebra's `sup`.
            ring: std::array::from_fn(|q| self.ring[q].zip_map(&o.ring[q], greater)),
        }
    }

    /// Widened by the rounding of the sampled states (the commanded polynomial, the lag's
    /// walk, τ = k·Ts − t0 at large t): [`STATE_SLACK`] and [`STATE_SLACK_REL`] of the
    /// range's magnitude and the ringing, far below anything physical.
    #[inline(always)]
    pub fn slacked(&self) -> StateBox {
        let slack =
            |x: Interval, ring: f64| x.widen(STATE_SLACK + STATE_SLACK_REL * (x.mag() + ring));
        let s = &self.states;
        StateBox {
            pos_mm: std::array::from_fn(|i| slack(s.pos_mm[i], self.ring[0][i])),
            vel_mm_s: std::array::from_fn(|i| slack(s.vel_mm_s[i], self.ring[1][i])),
            acc_mm_s2: std::array::from_fn(|i| slack(s.acc_mm_s2[i], self.ring[2][i])),
        }
    }
}

/// The first grid index strictly after `t0`: the piece's first grid point inside.
fn first_inside(t0: f64, period_s: f64) -> i64 {
    first_after(first_grid_index(t0, period_s), t0, period_s)
}

/// [`first_inside`] of `t0`, from its [`first_grid_index`] `k`.
#[inline(always)]
fn first_after(k: i64, t0: f64, period_s: f64) -> i64 {
    if k as f64 * period_s <= t0 { k + 1 } else { k }
}

/// A piece with fewer grid points inside than this is sampled whole: bounding it costs
/// about what sampling it does.
const SPARSE_MIN_PIECE: i64 = 64;

/// Fewer samples than this, offered whole (a piece, a move), are computed without a bound
/// first: boxes of fewer are let go too rarely to pay for their bound. Instructions of
/// `check` on the first 5 MB of the corpus's bunny with the towers' bounds side by side
/// (default drive): 2, 4, 5, 6, 8 and 11 give 1.2158, 1.2157, 1.2158, 1.2165, 1.2232 and
/// 1.2438 G (8 was best when a bound cost a third more; docs/performance.md).
pub const SPARSE_MIN_SAMPLES: u64 = 4;

/// The shortest run of grid points a sparse evaluation bounds: shorter ones are sampled.
const SPARSE_MIN_RUN: i64 = 32;

/// A state box is widened by this much, absolute (mm, mm/s, mm/s²), and relative to the
/// box and the ringing: the rounding of the sampled states (the commanded polynomial, the
/// lag's walk, τ = k·Ts − t0 at large t), far below anything physical.
const STATE_SLACK: f64 = 1e-6;
const STATE_SLACK_REL: f64 = 1e-9;

/// The grid points inside a piece with a drive response, the lag walked from one to the
/// next.
struct Grid<'a> {
    work: &'a PieceWork,
    response: &'a Response,
    period_s: f64,
}

impl Grid<'_> {
    /// Samples grid points `k..end`, `walk` at `k`, and leaves `walk` at `end`.
    #[inline(always)]
    fn sample(&self, walk: &mut LagWalk, k: i64, end: i64, out: &mut impl SampleSink) {
        let seg = &self.work.commanded;
        for k in k..end {
            let t = k as f64 * self.period_s;
            let (p, v, _) = seg.at(t - seg.t0_s);
            let lag = walk.lag();
            out.sample(Sample {
                t_s: t,
                line: seg.line,
                phase: if t < self.work.corner_until_s {
                    Phase::Corner
                } else {
                    seg.phase
                },
                pos_mm: p + lag.e,
                vel_mm_s: v + lag.de,
                acc_mm_s2: self.response.acceleration(&lag),
                cmd_pos_mm: p,
            });
            walk.advance();
        }
    }

    /// Grid points `k..end` in time order, sparsely: a run whose state box the sink lets go
    /// ([`SampleSink::skip`]) is stepped over (the walk still steps through it, so the
    /// samples after it are the ones dense sampling computes, bit for bit); a run it keeps
    /// is halved and each half tried again, down to [`SPARSE_MIN_RUN`], then sampled.
    fn sparse(&self, walk: &mut LagWalk, k: i64, end: i64, out: &mut impl SampleSink) {
        let n = end - k;
        if n >= SPARSE_MIN_RUN {
            if out.skip(&self.states(k, end - 1), n as u64) {
                for _ in 0..n {
                    walk.advance();
                }
                return;
            }
            if n >= 2 * SPARSE_MIN_RUN {
                let mid = k + n / 2;
                self.sparse(walk, k, mid, out);
                self.sparse(walk, mid, end, out);
                return;
            }
        }
        self.sample(walk, k, end, out);
    }

    /// A box holding the actual state at grid points `first..=last` ([`Self::span`]).
    pub(super) fn states(&self, first: i64, last: i64) -> StateBox {
        let tau = |k: i64| k as f64 * self.period_s - self.work.commanded.t0_s;
        self.span(tau(first), tau(last), Fit::Envelope)
    }

    /// A box holding the actual state at every τ in [ta, tb] of the piece (s from its
    /// start): the commanded polynomial's range (its ends and, for the position, its
    /// vertex) plus the lag's ringing from `ta` on ([`Response::ringing`]); with
    /// [`Fit::Swing`], for the whole piece only (ta = 0, tb its duration), the
    /// acceleration's swing over it instead ([`Response::acceleration_range`]). Before the
    /// slack for rounding ([`RawBox::slacked`]).
    #[inline(always)]
    fn raw<const AVX2: bool>(&self, ta: f64, tb: f64, fit: Fit) -> RawBox {
        let work = self.work;
        let seg = &work.commanded;
        // At 0 the piece's own start (a whole piece's box, where `ta` is the constant 0):
        // p + v·0 + a·0 is p but for the sign of a zero.
        let (pa, va) = if ta == 0.0 {
            (seg.p, seg.v)
        } else {
            let (p, v, _) = seg.at(ta);
            (p, v)
        };
        let (pb, vb, _) = seg.at(tb);
        let ring = self.response.ringing(&work.lag, seg.a, ta);
        let pos = |i: usize| {
            let mut pos = Interval::hull(pa[i], pb[i]);
            // The parabola's vertex, where the velocity changes sign inside the run: only
            // when the ends' velocities have opposite signs is the division paid (the vertex
            // a rounding away from an end, which this may miss, is within the slack).
            if va[i] * vb[i] < 0.0 {
                let tv = -seg.v[i] / seg.a[i];
                if tv > ta && tv < tb {
                    let pv = seg.p[i] + seg.v[i] * tv + seg.a[i] * (0.5 * tv * tv);
                    pos = pos.join(Interval::point(pv));
                }
            }
            (pos + ring.e_p[i]).widen(ring.u[i])
        };
        let acc = match (fit, &work.edge) {
            (Fit::Swing, Edge::End(end)) => self
                .response
                .acceleration_range::<AVX2>(&work.lag, end, seg.a, seg.dt_s, ring.acc),
            _ => std::array::from_fn(|i| Interval::around(ring.acc_p[i], ring.acc[i])),
        };
        RawBox {
            states: StateBox {
                // Not `array::from_fn`: its closure was called out of line, its captures through
                // memory.
                pos_mm: [pos(0), pos(1), pos(2)],
                vel_mm_s: std::array::from_fn(|i| Interval::hull(va[i], vb[i]).widen(ring.du[i])),
                acc_mm_s2: acc,
            },
            ring: [ring.u, ring.du, ring.acc],
        }
    }

    /// [`Self::raw`], slacked.
    fn span(&self, ta: f64, tb: f64, fit: Fit) -> StateBox {
        self.raw::<false>(ta, tb, fit).slacked()
    }
}

/// The actual states at a few of the samples of `work` where a move's peaks tend to be
/// (its start, the grid points about half a drive period and a period after it, where the
/// ringing of a junction or an acceleration step overshoots, and its last grid point), as
/// dense sampling computes them up to rounding: samples of the move, so lower bounds of its
/// peaks, for a sparse evaluation to compare its bounds with. `out` gets (position,
/// velocity, acceleration).
pub fn peak_candidates(
    work: &PieceWork,
    response: &Response,
    period_s: f64,
    mut out: impl FnMut(Vec3, Vec3, Vec3),
) {
    let seg = &work.commanded;
    let (t0, t1) = (seg.t0_s, seg.t1_s());
    let lag = &work.lag;
    out(seg.p + lag.e, seg.v + lag.de, response.acceleration(lag));
    if !(period_s > 0.0 && period_s.is_finite()) {
        return;
    }
    let first = first_inside(t0, period_s);
    let end = first_grid_index(t1, period_s);
    let p = response.period_s();
    let mut last_k = None;
    for t in [t0 + 0.5 * p, t0 + p, t1] {
        let k = first_grid_index(t, period_s).min(end - 1).max(first);
        if k >= end || last_k == Some(k) {
            continue;
        }
        last_k = Some(k);
        let tau = k as f64 * period_s - t0;
        let (pc, vc, _) = seg.at(tau);
        let lag = response.lag_at(lag, seg.a, tau);
        out(pc + lag.e, vc + lag.de, response.acceleration(&lag));
    }
}

/// Smallest k with k·Ts ≥ t (the grid time is always computed as `k as f64 * period_s`).
fn first_grid_index(t: f64, period_s: f64) -> i64 {
    // ⌈t/Ts⌉ without `f64::ceil`, a library call on baseline x86-64; by the reciprocal,
    // which a caller's loop computes once (the loops below make k exact whatever q's
    // rounding).
    let q = t * (1.0 / period_s);
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

#[cfg(test)]
mod tests;
