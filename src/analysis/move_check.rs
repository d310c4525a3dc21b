//! The moves' pieces through the model: sampled, a block of samples at a time through the
//! vectorised forces, and each block's runs handed to the observers.

use std::sync::atomic::{AtomicU64, Ordering};

use crate::delta::{BLOCK, DeltaModel, ForceBlock, StateBlock};
use crate::machine::Machine;
use crate::motion::Segment;
use crate::motion::drive::{Drive, Response};
use crate::path::Path;
use crate::report::{MoveStats, NEAR_SINGULAR_RATIO, Problem, share};
use crate::resample::{
    Phase, PieceWork, Sample, SampleSink, StateBox, peak_candidates, sample_piece,
};

use super::MoveResult;
use super::observe::{Evaluated, Observer, Verdict, unreachable};
use super::sequence::MoveWork;

/// Tolerance on the print radius and the bed, mm: rounding in slicer output.
const GEOMETRY_TOLERANCE_MM: f64 = 1e-3;

/// A piece longer than this many sampling periods (2.8 h at 1 kHz) is not sampled: only its
/// ends are checked. Nothing printable lasts that long; a feed rate near zero or a huge
/// coordinate does, and would otherwise keep the check busy for hours.
const MAX_SAMPLES_PER_PIECE: f64 = 1e7;

/// Set (to anything) in the environment, `check` samples every piece densely: the sparse
/// evaluation off (docs/performance.md), for comparisons.
pub const DENSE_ENV: &str = "DELTA_GCODE_DENSE";

/// A move is seeded for a sparse evaluation (its peak candidates computed first) when one
/// of its pieces lasts this many sampling periods: shorter pieces are sampled whole.
const SEED_MIN_PERIODS: f64 = 64.0;

/// Checks moves against one machine, for the verdict and for `observer`. Shared between
/// threads; each thread brings its own [`Scratch`].
pub struct MoveChecker<'m, O = ()> {
    machine: &'m Machine,
    model: DeltaModel,
    response: Option<Response>,
    observer: O,
    /// Runs of samples whose bounds stay below the move's peaks are counted, not computed
    /// (see [`SampleSink::skip`]): with a drive response, an observer that does not need
    /// every sample, and no [`DENSE_ENV`].
    sparse: bool,
    /// Samples left uncomputed so far (all threads).
    skipped: AtomicU64,
}

impl<'m, O: Observer> MoveChecker<'m, O> {
    pub fn new(machine: &'m Machine, observer: O) -> Self {
        let response = match &machine.drive {
            Drive::Rigid => None,
            Drive::Spring(s) => Some(Response::new(s).with_step(machine.sampling.period_s)),
        };
        MoveChecker {
            machine,
            model: machine.model(),
            sparse: response.is_some()
                && !observer.every_sample()
                && std::env::var_os(DENSE_ENV).is_none(),
            response,
            observer,
            skipped: AtomicU64::new(0),
        }
    }

    /// Samples a sparse evaluation has counted without computing them so far.
    pub fn skipped_samples(&self) -> u64 {
        self.skipped.load(Ordering::Relaxed)
    }

    /// The same checker, every sample computed (no sparse evaluation).
    pub fn dense(self) -> Self {
        MoveChecker {
            sparse: false,
            ..self
        }
    }

    /// The observer the checker feeds.
    pub fn observer(&self) -> &O {
        &self.observer
    }

    /// Samples the pieces of consecutive moves of a batch, appending one result per move
    /// to `out`: the samples gathered into blocks (which span moves, so that the vectorised
    /// forces run on full blocks) and each block's runs handed to the verdict and the
    /// observer.
    pub fn check_moves(
        &self,
        scratch: &mut Scratch,
        pieces: &[PieceWork],
        moves: &[MoveWork],
        out: &mut Vec<MoveResult<O::PerMove>>,
    ) {
        let period_s = self.machine.sampling.period_s;
        scratch.len = 0;
        for m in moves {
            let slot = out.len();
            out.push(MoveResult {
                group: m.group,
                stats: m.stats.clone(),
                observed: self.observer.start(m.stats.line),
                end_xy_mm: m.end_xy_mm,
            });
            let works = pieces.get(m.first..m.first + m.count).unwrap_or_default();
            let floor = self.floor(works);
            for work in works {
                let seg = &work.piece.commanded;
                if seg.dt_s > MAX_SAMPLES_PER_PIECE * period_s {
                    self.check_ends_only(seg, &mut out[slot].stats);
                    continue;
                }
                let mut sink = MoveSink {
                    checker: self,
                    scratch: &mut *scratch,
                    out: &mut *out,
                    slot,
                    floor: floor.as_ref(),
                };
                sample_piece(work, self.response.as_ref(), period_s, &mut sink);
            }
        }
        self.flush(scratch, out);
    }

    /// For a sparse evaluation of a move with a long piece: lower bounds of the move's
    /// peaks from its pieces' peak candidates ([`peak_candidates`]), each a sample of the
    /// move. None when the move is sampled densely anyway.
    fn floor(&self, works: &[PieceWork]) -> Option<Floor> {
        let period_s = self.machine.sampling.period_s;
        let r = self.response.as_ref().filter(|_| self.sparse)?;
        if !works
            .iter()
            .any(|w| w.piece.commanded.dt_s >= SEED_MIN_PERIODS * period_s)
        {
            return None;
        }
        let mut floor = Floor::default();
        // Only pieces that are sampled: a candidate must be one of the move's samples.
        let sampled = works
            .iter()
            .filter(|w| w.piece.commanded.dt_s <= MAX_SAMPLES_PER_PIECE * period_s);
        for w in sampled {
            peak_candidates(w, r, period_s, |pos, vel, acc| {
                if let Ok(s) = self.model.evaluate(pos, vel, acc) {
                    for i in 0..3 {
                        let available = self.machine.motors.available_force_n(s.dq_mm_s[i]);
                        let f = &mut floor;
                        f.force_n[i] = f.force_n[i].max(s.force_n[i].abs());
                        f.share[i] = f.share[i].max(share(s.force_n[i], available));
                        f.tension_n[i] = f.tension_n[i].max(s.arm_tension_n[i]);
                        f.speed_mm_s = f.speed_mm_s.max(s.dq_mm_s[i].abs());
                    }
                }
            });
        }
        Some(floor)
    }

    /// A piece too long to sample: flagged, and its ends checked.
    fn check_ends_only(&self, seg: &Segment, stats: &mut MoveStats) {
        stats.flag(Problem::NotSampled {
            duration_s: seg.dt_s,
        });
        for t_s in [seg.t0_s, seg.t1_s()] {
            let (pos, _, _) = seg.at(t_s - seg.t0_s);
            if let Err(e) = self.model.inverse(pos) {
                stats.flag(unreachable(e, t_s, pos));
            }
        }
    }

    /// The checks on a move's path as a whole: the print disc, the bed, and how close the
    /// arms come to flat (the carriage speed ratio peaks where the path is farthest from a
    /// tower).
    pub fn check_geometry(&self, path: &Path, stats: &mut MoveStats) {
        let limit_mm = self.machine.geometry.print_radius_mm;
        let radius_mm = path.max_xy2_mm2().sqrt();
        if radius_mm > limit_mm + GEOMETRY_TOLERANCE_MM {
            stats.flag(Problem::OutsideRadius {
                radius_mm,
                limit_mm,
            });
        }
        let z_mm = path.min_z_mm();
        if z_mm < -GEOMETRY_TOLERANCE_MM {
            stats.flag(Problem::BelowBed { z_mm });
        }
        for (tower, xy) in self.model.towers_xy_mm().into_iter().enumerate() {
            let ratio = self
                .model
                .carriage_speed_ratio(tower, path.max_dist2_from_mm2(xy).sqrt());
            if ratio > NEAR_SINGULAR_RATIO && stats.near_singular.is_none_or(|(_, r)| ratio > r) {
                stats.near_singular = Some((tower, ratio));
            }
        }
    }

    /// Runs the model over the scratch block and hands it, a move's run of samples at a
    /// time, to the verdict and the observer.
    #[inline(never)] // keeps the sink's per-sample method small in the sampling loop
    fn flush(&self, scratch: &mut Scratch, out: &mut [MoveResult<O::PerMove>]) {
        let n = scratch.len;
        scratch.len = 0;
        if n == 0 {
            return;
        }
        self.model
            .forces_block(&scratch.states, n, &mut scratch.forces);
        let verdict = Verdict {
            motors: &self.machine.motors,
        };
        verdict.available(&scratch.forces, n, &mut scratch.available_n);
        let mut j0 = 0;
        while j0 < n {
            let slot = scratch.slot[j0];
            let j1 = scratch.slot[j0..n]
                .iter()
                .position(|&s| s != slot)
                .map_or(n, |k| j0 + k);
            let Some(r) = out.get_mut(slot) else {
                break;
            };
            let run = Evaluated {
                line: r.stats.line,
                t_s: &scratch.t_s,
                phase: &scratch.phase,
                states: &scratch.states,
                cmd_pos_mm: &scratch.cmd_pos_mm,
                forces: &scratch.forces,
                available_n: &scratch.available_n,
                lanes: j0..j1,
            };
            verdict.observe(&self.model, &mut r.stats, &run);
            self.observer.observe(&self.model, &mut r.observed, &run);
            j0 = j1;
        }
    }
}

/// Lower bounds of a move's peaks, per tower: |Q_i| (N), the share of the available force,
/// the arm tension (N).
#[derive(Clone, Copy, Debug, Default)]
struct Floor {
    force_n: [f64; 3],
    share: [f64; 3],
    tension_n: [f64; 3],
    /// The fastest carriage, |q̇_i| mm/s (`MoveStats::peak_speed_mm_s`).
    speed_mm_s: f64,
}

/// The samples of the move whose result is `out[slot]`, on their way into the blocks.
struct MoveSink<'a, 'm, O: Observer> {
    checker: &'a MoveChecker<'m, O>,
    scratch: &'a mut Scratch,
    out: &'a mut Vec<MoveResult<O::PerMove>>,
    slot: usize,
    /// The move's peak candidates, when it is evaluated sparsely.
    floor: Option<&'a Floor>,
}

impl<O: Observer> SampleSink for MoveSink<'_, '_, O> {
    #[inline(always)]
    fn sample(&mut self, s: Sample) {
        self.scratch.push(&s, self.slot);
        if self.scratch.len == BLOCK {
            self.checker.flush(self.scratch, self.out);
        }
    }

    fn sparse(&self) -> bool {
        self.floor.is_some()
    }

    /// A run goes uncomputed when its bounds (`DeltaModel::bound`: every state of the box a
    /// valid pose, |Q_i|, the share of the available force, the tension and the carriage
    /// speed each with their margin) are below what the move has already reached, strictly, on every tower: then
    /// none of its samples could have changed a peak, where it was, or a problem, so the
    /// statistics are the dense ones. What the move has reached: its samples so far (the
    /// block flushed first) and its peak candidates.
    fn skip(&mut self, states: &StateBox, count: u64) -> bool {
        let (Some(floor), Some(b)) = (
            self.floor,
            self.checker
                .model
                .bound(&states.pos_mm, &states.vel_mm_s, &states.acc_mm_s2),
        ) else {
            return false;
        };
        if self.scratch.len > 0 {
            self.checker.flush(self.scratch, self.out);
        }
        let Some(stats) = self.out.get_mut(self.slot).map(|r| &mut r.stats) else {
            return false;
        };
        let motors = &self.checker.machine.motors;
        let below = (0..3).all(|i| {
            // The available force falls with the carriage speed: least at the bound.
            let most_share = share(b.force_n[i], motors.available_force_n(b.speed_mm_s[i]));
            b.force_n[i] < stats.peak_force_n[i].max(floor.force_n[i])
                && most_share < stats.worst[i].ratio.max(floor.share[i])
                && b.tension_n[i] < stats.peak_tension_n[i].max(floor.tension_n[i])
                && b.speed_mm_s[i] < stats.peak_speed_mm_s.max(floor.speed_mm_s)
        });
        if below {
            stats.samples += count;
            self.checker.skipped.fetch_add(count, Ordering::Relaxed);
        }
        below
    }
}

/// One worker's samples waiting for the model, a block at a time, each with the index of
/// its move's result.
pub struct Scratch {
    len: usize,
    slot: [usize; BLOCK],
    t_s: [f64; BLOCK],
    phase: [Phase; BLOCK],
    states: StateBlock,
    cmd_pos_mm: [[f64; BLOCK]; 3],
    forces: ForceBlock,
    available_n: [[f64; BLOCK]; 3],
}

impl Default for Scratch {
    fn default() -> Self {
        Scratch {
            len: 0,
            slot: [0; BLOCK],
            t_s: [0.0; BLOCK],
            phase: [Phase::Cruise; BLOCK],
            states: StateBlock::default(),
            cmd_pos_mm: [[0.0; BLOCK]; 3],
            forces: ForceBlock::default(),
            available_n: [[0.0; BLOCK]; 3],
        }
    }
}

impl Scratch {
    /// Adds a sample of the move whose result is `out[slot]`; the caller flushes when the
    /// block is full.
    #[inline(always)]
    fn push(&mut self, s: &Sample, slot: usize) {
        let j = self.len;
        if j >= BLOCK {
            return;
        }
        self.slot[j] = slot;
        self.t_s[j] = s.t_s;
        self.phase[j] = s.phase;
        let st = &mut self.states;
        for k in 0..3 {
            st.pos_mm[k][j] = s.pos_mm[k];
            st.vel_mm_s[k][j] = s.vel_mm_s[k];
            st.acc_mm_s2[k][j] = s.acc_mm_s2[k];
            self.cmd_pos_mm[k][j] = s.cmd_pos_mm[k];
        }
        self.len = j + 1;
    }
}
