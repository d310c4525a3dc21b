//! One planned move through the model: resampled, a block of samples at a time through the
//! vectorised forces, and each block's runs handed to the observers.

use crate::delta::{BLOCK, DeltaModel, ForceBlock, StateBlock};
use crate::machine::Machine;
use crate::planner::PlannedMove;
use crate::report::{MoveStats, NEAR_SINGULAR_RATIO, Problem};
use crate::resample::{Phase, Sample, SampleSink, sample_move};

use super::MoveResult;
use super::observe::{Evaluated, Observer, Verdict, unreachable};

/// Tolerance on the print radius and the bed, mm: rounding in slicer output.
const GEOMETRY_TOLERANCE_MM: f64 = 1e-3;

/// A move longer than this many sampling periods (2.8 h at 1 kHz) is not sampled: only its
/// ends are checked. Nothing printable lasts that long; a feed rate near zero or a huge
/// coordinate does, and would otherwise keep the check busy for hours.
const MAX_SAMPLES_PER_MOVE: f64 = 1e7;

/// Checks planned moves against one machine, for the verdict and for `observer`. Shared
/// between threads; each thread brings its own [`Scratch`].
pub struct MoveChecker<'m, O> {
    machine: &'m Machine,
    model: DeltaModel,
    observer: O,
}

impl<'m, O: Observer> MoveChecker<'m, O> {
    pub fn new(machine: &'m Machine, observer: O) -> Self {
        MoveChecker {
            machine,
            model: machine.model(),
            observer,
        }
    }

    /// Checks consecutive planned moves, appending one result per move to `out`: each move
    /// resampled, its samples gathered into blocks (which span moves, so that the vectorised
    /// forces run on full blocks) and each block's runs handed to the verdict and the
    /// observer. `prev` and `next` are the moves around the run (None at the start or end of
    /// the file).
    pub fn check_run(
        &self,
        scratch: &mut Scratch,
        prev: Option<&PlannedMove>,
        moves: &[PlannedMove],
        next: Option<&PlannedMove>,
        out: &mut Vec<MoveResult<O::PerMove>>,
    ) {
        let period_s = self.machine.sampling.period_s;
        scratch.len = 0;
        for (i, mv) in moves.iter().enumerate() {
            let before = if i == 0 { prev } else { moves.get(i - 1) };
            let after = if i + 1 == moves.len() {
                next
            } else {
                moves.get(i + 1)
            };
            let end = mv.path.end();
            let slot = out.len();
            out.push(MoveResult {
                stats: Verdict.start(mv.line),
                observed: self.observer.start(mv.line),
                end_xy_mm: [end.x, end.y],
            });
            let stats = &mut out[slot].stats;
            self.check_geometry(mv, stats);
            if mv.duration_s() > MAX_SAMPLES_PER_MOVE * period_s {
                self.check_ends_only(mv, stats);
                continue;
            }
            let mut sink = MoveSink {
                checker: self,
                scratch: &mut *scratch,
                out: &mut *out,
                slot,
            };
            sample_move(before, mv, after, period_s, &mut sink);
        }
        self.flush(scratch, out);
    }

    /// A move too long to sample: flagged, and its ends checked.
    fn check_ends_only(&self, mv: &PlannedMove, stats: &mut MoveStats) {
        stats.flag(Problem::NotSampled {
            duration_s: mv.duration_s(),
        });
        for (u, t_s) in [(0.0, mv.t0_s), (1.0, mv.t0_s + mv.duration_s())] {
            let pos = mv.path.point(u);
            if let Err(e) = self.model.inverse(pos) {
                stats.flag(unreachable(e, t_s, pos));
            }
        }
    }

    /// The checks on the move's path as a whole: the print disc, the bed, and how close
    /// the arms come to flat (the carriage speed ratio peaks where the path is farthest
    /// from a tower).
    fn check_geometry(&self, mv: &PlannedMove, stats: &mut MoveStats) {
        let limit_mm = self.machine.geometry.print_radius_mm;
        let radius_mm = mv.path.max_xy2_mm2().sqrt();
        if radius_mm > limit_mm + GEOMETRY_TOLERANCE_MM {
            stats.flag(Problem::OutsideRadius {
                radius_mm,
                limit_mm,
            });
        }
        let z_mm = mv.path.min_z_mm();
        if z_mm < -GEOMETRY_TOLERANCE_MM {
            stats.flag(Problem::BelowBed { z_mm });
        }
        for (tower, xy) in self.model.towers_xy_mm().into_iter().enumerate() {
            let ratio = self
                .model
                .carriage_speed_ratio(tower, mv.path.max_dist2_from_mm2(xy).sqrt());
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
                forces: &scratch.forces,
                lanes: j0..j1,
            };
            Verdict.observe(&self.model, &mut r.stats, &run);
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
    forces: ForceBlock,
}

impl Default for Scratch {
    fn default() -> Self {
        Scratch {
            len: 0,
            slot: [0; BLOCK],
            t_s: [0.0; BLOCK],
            phase: [Phase::Cruise; BLOCK],
            states: StateBlock::default(),
            forces: ForceBlock::default(),
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
        }
        self.len = j + 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::{TraceRows, Window};
    use crate::gcode::interpret;
    use crate::machine::test_support::kossel_machine;
    use crate::path::Vec3;
    use crate::planner::Planner;

    fn plan(machine: &Machine, gcode: &str) -> Vec<PlannedMove> {
        let mut planner = Planner::new(machine);
        let mut moves = Vec::new();
        let home = Vec3::new(0.0, 0.0, machine.geometry.home_z_mm);
        interpret(
            gcode.as_bytes(),
            home,
            |e| planner.push(e, &mut moves),
            |_| {},
        )
        .unwrap();
        planner.finish(&mut moves);
        moves
    }

    #[test]
    fn moves_sharing_blocks_get_what_they_get_alone() {
        // Many short moves per block, a long move over several blocks, a move out of reach
        // (lanes the model rejects in the middle of a block), a trace and a plot window.
        let mut gcode = String::from("G28\nG1 Z5 F6000\n");
        for k in 0..40 {
            gcode += &format!("G1 X{} Y{}\n", (k % 2) as f64 * 0.7, k as f64 * 0.3);
        }
        gcode += "G1 X60 Y0 F3000\nG1 X0 Y-150\nG1 X0 Y0\nG1 X1 Y1\n";
        let machine = kossel_machine();
        let moves = plan(&machine, &gcode);
        let observer = (
            TraceRows,
            Window {
                from_s: 0.05,
                to_s: 1.5,
            },
        );
        let checker = MoveChecker::new(&machine, observer);
        let mut scratch = Box::<Scratch>::default();
        let mut together = Vec::new();
        checker.check_run(&mut scratch, None, &moves, None, &mut together);
        assert_eq!(together.len(), moves.len());
        let samples: u64 = together.iter().map(|r| r.stats.samples).sum();
        assert!(samples > 4 * BLOCK as u64, "{samples} samples");
        assert!(
            together
                .iter()
                .any(|r| matches!(r.stats.problem, Some(Problem::Unreachable { .. })))
        );
        assert!(together.iter().any(|r| !r.observed.1.is_empty()));
        for (i, r) in together.iter().enumerate() {
            let mut alone = Vec::new();
            let prev = i.checked_sub(1).map(|j| &moves[j]);
            let next = moves.get(i + 1);
            checker.check_run(&mut scratch, prev, &moves[i..=i], next, &mut alone);
            let a = &alone[0];
            assert_eq!(r.stats, a.stats, "move {i}");
            assert_eq!(r.observed, a.observed, "move {i}");
            assert_eq!(r.end_xy_mm, a.end_xy_mm);
            // The trace has one row per sample the model could take.
            let rows = r.observed.0.iter().filter(|&&b| b == b'\n').count();
            assert_eq!(rows as u64, r.stats.samples, "move {i}");
        }
    }
}
