//! One planned move through the model: resampled, a block of samples at a time through the
//! vectorised forces, into the move's statistics.

use std::fmt::Write as _;

use crate::delta::{BLOCK, DeltaModel, ForceBlock, StateBlock, Unreachable};
use crate::machine::Machine;
use crate::path::Vec3;
use crate::planner::PlannedMove;
use crate::report::{MoveStats, NEAR_SINGULAR_RATIO, Problem};
use crate::resample::{Phase, Sample, SampleSink, sample_move};

use super::{MoveResult, RunOptions};

/// Tolerance on the print radius and the bed, mm: rounding in slicer output.
const GEOMETRY_TOLERANCE_MM: f64 = 1e-3;

/// A move longer than this many sampling periods (2.8 h at 1 kHz) is not sampled: only its
/// ends are checked. Nothing printable lasts that long; a feed rate near zero or a huge
/// coordinate does, and would otherwise keep the check busy for hours.
const MAX_SAMPLES_PER_MOVE: f64 = 1e7;

/// Checks planned moves against one machine. Shared between threads; each thread brings
/// its own [`Scratch`].
pub struct MoveChecker<'m> {
    machine: &'m Machine,
    model: DeltaModel,
    options: RunOptions,
}

impl<'m> MoveChecker<'m> {
    pub fn new(machine: &'m Machine, options: RunOptions) -> Self {
        MoveChecker {
            machine,
            model: machine.model(),
            options,
        }
    }

    /// Checks consecutive planned moves, appending one result per move to `out`: each move
    /// resampled, its samples gathered into blocks (which span moves, so that the vectorised
    /// forces run on full blocks) and the forces reduced into the move's statistics; with a
    /// trace, every sample's row too. `prev` and `next` are the moves around the run (None at
    /// the start or end of the file).
    pub fn check_run(
        &self,
        scratch: &mut Scratch,
        prev: Option<&PlannedMove>,
        moves: &[PlannedMove],
        next: Option<&PlannedMove>,
        out: &mut Vec<MoveResult>,
    ) {
        let window_s = self
            .options
            .window_s
            .unwrap_or((f64::INFINITY, f64::NEG_INFINITY));
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
                stats: MoveStats::new(mv.line),
                trace: String::new(),
                window: Vec::new(),
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
                window_s,
            };
            sample_move(before, mv, after, period_s, &mut sink);
        }
        scratch.flush(&self.model, window_s, out);
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

    /// Appends a sample's row of the trace CSV (nothing for a pose the model cannot take:
    /// the statistics flag it).
    #[inline(never)] // as `Scratch::flush`
    fn trace_row(&self, s: &Sample, trace: &mut String) {
        let Ok(st) = self.model.evaluate(s.pos_mm, s.vel_mm_s, s.acc_mm_s2) else {
            return;
        };
        let p = &s.pos_mm;
        let v = &s.vel_mm_s;
        let a = &s.acc_mm_s2;
        let (q, dq, ddq, f) = (st.q_mm, st.dq_mm_s, st.ddq_mm_s2, st.force_n);
        // Display of f64 is the shortest text that reads back to the same value.
        let _ = writeln!(
            trace,
            "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
            s.t_s,
            s.line,
            p.x,
            p.y,
            p.z,
            v.x,
            v.y,
            v.z,
            a.x,
            a.y,
            a.z,
            q[0],
            q[1],
            q[2],
            dq[0],
            dq[1],
            dq[2],
            ddq[0],
            ddq[1],
            ddq[2],
            f[0],
            f[1],
            f[2],
            st.power_w,
            st.energy_rate_w
        );
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
}

/// The samples of the move whose result is `out[slot]`, on their way into the blocks.
struct MoveSink<'a, 'm> {
    checker: &'a MoveChecker<'m>,
    scratch: &'a mut Scratch,
    out: &'a mut Vec<MoveResult>,
    slot: usize,
    window_s: (f64, f64),
}

impl SampleSink for MoveSink<'_, '_> {
    #[inline(always)]
    fn sample(&mut self, s: Sample) {
        if self.checker.options.trace
            && let Some(r) = self.out.get_mut(self.slot)
        {
            self.checker.trace_row(&s, &mut r.trace);
        }
        self.scratch.push(&s, self.slot);
        if self.scratch.len == BLOCK {
            let model = &self.checker.model;
            self.scratch.flush(model, self.window_s, self.out);
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

    /// Runs the model over the block and empties it into the results, a move's run of
    /// samples at a time. `window_s`: keep the forces of the samples in this span (s).
    #[inline(never)] // keeps the sink's per-sample method small in the sampling loop
    fn flush(&mut self, model: &DeltaModel, window_s: (f64, f64), out: &mut [MoveResult]) {
        let n = self.len;
        self.len = 0;
        if n == 0 {
            return;
        }
        model.forces_block(&self.states, n, &mut self.forces);
        let (st, fo) = (&self.states, &self.forces);
        let mut j0 = 0;
        while j0 < n {
            let slot = self.slot[j0];
            let j1 = self.slot[j0..n]
                .iter()
                .position(|&s| s != slot)
                .map_or(n, |k| j0 + k);
            let Some(r) = out.get_mut(slot) else {
                break;
            };
            let run = j0..j1;
            if fo.ok[run.clone()].iter().all(|&ok| ok) {
                let f = &fo.force_n;
                r.stats.add_run(
                    &self.t_s[run.clone()],
                    &self.phase[run.clone()],
                    [&f[0][run.clone()], &f[1][run.clone()], &f[2][run.clone()]],
                    &fo.energy_residual_w[run.clone()],
                );
            } else {
                for j in run.clone() {
                    let v3 = |c: &[[f64; BLOCK]; 3]| Vec3::new(c[0][j], c[1][j], c[2][j]);
                    let pos = v3(&st.pos_mm);
                    let f = [fo.force_n[0][j], fo.force_n[1][j], fo.force_n[2][j]];
                    if fo.ok[j] {
                        r.stats
                            .add(self.t_s[j], self.phase[j], f, fo.energy_residual_w[j]);
                    } else if let Err(e) = model.evaluate(pos, v3(&st.vel_mm_s), v3(&st.acc_mm_s2))
                    {
                        r.stats.flag(unreachable(e, self.t_s[j], pos));
                    }
                }
            }
            if self.t_s[j0] <= window_s.1 && self.t_s[j1 - 1] >= window_s.0 {
                for j in run {
                    let t = self.t_s[j];
                    if fo.ok[j] && t >= window_s.0 && t <= window_s.1 {
                        r.window
                            .push((t, [fo.force_n[0][j], fo.force_n[1][j], fo.force_n[2][j]]));
                    }
                }
            }
            j0 = j1;
        }
    }
}

/// The problem of a pose the model cannot take.
fn unreachable(e: Unreachable, t_s: f64, pos: Vec3) -> Problem {
    match e {
        Unreachable::AboveTop { tower, over_mm } => Problem::AboveHome {
            t_s,
            tower,
            over_mm,
        },
        e => Problem::Unreachable {
            t_s,
            tower: e.tower(),
            pos_mm: [pos.x, pos.y, pos.z],
            reason: e.to_string(),
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gcode::interpret;
    use crate::machine::test_support::kossel_machine;
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
        let options = RunOptions {
            trace: true,
            window_s: Some((0.05, 1.5)),
        };
        let checker = MoveChecker::new(&machine, options);
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
        assert!(together.iter().any(|r| !r.window.is_empty()));
        for (i, r) in together.iter().enumerate() {
            let mut alone = Vec::new();
            let prev = i.checked_sub(1).map(|j| &moves[j]);
            let next = moves.get(i + 1);
            checker.check_run(&mut scratch, prev, &moves[i..=i], next, &mut alone);
            let a = &alone[0];
            assert_eq!(r.stats, a.stats, "move {i}");
            assert_eq!(r.trace, a.trace, "move {i}");
            assert_eq!(r.window, a.window, "move {i}");
            assert_eq!(r.end_xy_mm, a.end_xy_mm);
            // The trace has one row per sample the model could take.
            assert_eq!(r.trace.lines().count() as u64, r.stats.samples, "move {i}");
        }
    }
}
