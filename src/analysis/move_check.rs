//! The moves' pieces through the model: sampled, a block of samples at a time through the
//! vectorised forces, and each block's runs handed to the observers.

use crate::delta::{BLOCK, DeltaModel, ForceBlock, StateBlock};
use crate::machine::Machine;
use crate::motion::Segment;
use crate::motion::drive::{Drive, Response};
use crate::path::Path;
use crate::report::{MoveStats, NEAR_SINGULAR_RATIO, Problem};
use crate::resample::{Phase, PieceWork, Sample, SampleSink, sample_piece};

use super::MoveResult;
use super::observe::{Evaluated, Observer, Verdict, unreachable};
use super::sequence::MoveWork;

/// Tolerance on the print radius and the bed, mm: rounding in slicer output.
const GEOMETRY_TOLERANCE_MM: f64 = 1e-3;

/// A piece longer than this many sampling periods (2.8 h at 1 kHz) is not sampled: only its
/// ends are checked. Nothing printable lasts that long; a feed rate near zero or a huge
/// coordinate does, and would otherwise keep the check busy for hours.
const MAX_SAMPLES_PER_PIECE: f64 = 1e7;

/// Checks moves against one machine, for the verdict and for `observer`. Shared between
/// threads; each thread brings its own [`Scratch`].
pub struct MoveChecker<'m, O = ()> {
    machine: &'m Machine,
    model: DeltaModel,
    response: Option<Response>,
    observer: O,
}

impl<'m, O: Observer> MoveChecker<'m, O> {
    pub fn new(machine: &'m Machine, observer: O) -> Self {
        MoveChecker {
            machine,
            model: machine.model(),
            response: match &machine.drive {
                Drive::Rigid => None,
                Drive::Spring(s) => Some(Response::new(s).with_step(machine.sampling.period_s)),
            },
            observer,
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
            for work in pieces.iter().skip(m.first).take(m.count) {
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
                };
                sample_piece(work, self.response.as_ref(), period_s, &mut sink);
            }
        }
        self.flush(scratch, out);
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

/// The samples of the move whose result is `out[slot]`, on their way into the blocks.
struct MoveSink<'a, 'm, O: Observer> {
    checker: &'a MoveChecker<'m, O>,
    scratch: &'a mut Scratch,
    out: &'a mut Vec<MoveResult<O::PerMove>>,
    slot: usize,
}

impl<O: Observer> SampleSink for MoveSink<'_, '_, O> {
    #[inline(always)]
    fn sample(&mut self, s: Sample) {
        self.scratch.push(&s, self.slot);
        if self.scratch.len == BLOCK {
            self.checker.flush(self.scratch, self.out);
        }
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
