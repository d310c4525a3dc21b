//! What the model computed, as the observers of one computation see it: the statistics
//! (the verdict), the trace rows and the forces of a plot window each reduce the same runs
//! of evaluated samples, a move's run at a time.

use std::ops::Range;

use crate::delta::{BLOCK, DeltaModel, ForceBlock, StateBlock, Unreachable};
use crate::machine::Motors;
use crate::motion::Phase;
use crate::path::Vec3;
use crate::report::{MoveStats, Problem, RunForces};

/// A run of consecutive samples of one move, evaluated in one block.
pub struct Evaluated<'a> {
    /// Source line of the move.
    pub line: u64,
    pub t_s: &'a [f64],
    pub phase: &'a [Phase],
    pub states: &'a StateBlock,
    /// The commanded positions, mm (one array per coordinate).
    pub cmd_pos_mm: &'a [[f64; crate::delta::BLOCK]; 3],
    pub forces: &'a ForceBlock,
    /// The force each motor can give at its carriage's speed (the torque-speed curve), N,
    /// per tower (see [`Verdict::available`]).
    pub available_n: &'a [[f64; BLOCK]; 3],
    /// The run's lanes in the block (and in `t_s`, `phase`).
    pub lanes: Range<usize>,
}

impl Evaluated<'_> {
    /// Position, velocity and acceleration of lane `j`, mm, mm/s, mm/s².
    pub fn state(&self, j: usize) -> (Vec3, Vec3, Vec3) {
        let v3 = |c: &[[f64; crate::delta::BLOCK]; 3]| Vec3::new(c[0][j], c[1][j], c[2][j]);
        let s = self.states;
        (v3(&s.pos_mm), v3(&s.vel_mm_s), v3(&s.acc_mm_s2))
    }

    /// The commanded position of lane `j`, mm.
    pub fn cmd_pos(&self, j: usize) -> Vec3 {
        let c = self.cmd_pos_mm;
        Vec3::new(c[0][j], c[1][j], c[2][j])
    }

    /// The forces of lane `j`, N.
    pub fn force_n(&self, j: usize) -> [f64; 3] {
        let f = &self.forces.force_n;
        [f[0][j], f[1][j], f[2][j]]
    }
}

/// A reduction of the evaluated samples, one accumulator per move. Shared between threads.
pub trait Observer: Send + Sync {
    /// What the observer keeps of one move.
    type PerMove: Send;

    /// The accumulator of the move of source line `line`, before its first sample.
    fn start(&self, line: u64) -> Self::PerMove;

    /// Takes a run of the move's evaluated samples (in time order, runs in time order).
    fn observe(&self, model: &DeltaModel, acc: &mut Self::PerMove, run: &Evaluated);

    /// Appends what was kept of a later part of the same move, taking it out of `later`
    /// (by reference: the pipeline hands each result on where it lies, not moved out).
    fn merge(&self, acc: &mut Self::PerMove, later: &mut Self::PerMove);

    /// Whether the observer needs every sample (a trace, a plot window): then none is left
    /// uncomputed by a sparse evaluation, which only the verdict's peaks allow.
    fn every_sample(&self) -> bool {
        true
    }

    /// Whether every move's own statistics must be exact. When not, only the run's peaks
    /// (the largest over its reachable moves, with their lines and instants), the sample
    /// count and the violations are (a report without `--all-moves`): a piece whose
    /// bounds stay below what other moves already reached may go uncomputed.
    fn move_peaks(&self) -> bool {
        true
    }
}

/// `O`, where only the run's peaks and the violations need be exact, not each move's own
/// statistics (see [`Observer::move_peaks`]): `RunPeaks(())` for a report without
/// `--all-moves`.
pub struct RunPeaks<O>(pub O);

impl<O: Observer> Observer for RunPeaks<O> {
    type PerMove = O::PerMove;

    fn start(&self, line: u64) -> Self::PerMove {
        self.0.start(line)
    }

    #[inline(always)]
    fn observe(&self, model: &DeltaModel, acc: &mut Self::PerMove, run: &Evaluated) {
        self.0.observe(model, acc, run);
    }

    fn merge(&self, acc: &mut Self::PerMove, later: &mut Self::PerMove) {
        self.0.merge(acc, later);
    }

    fn every_sample(&self) -> bool {
        self.0.every_sample()
    }

    fn move_peaks(&self) -> bool {
        false
    }
}

/// Observes nothing: a plain check.
impl Observer for () {
    type PerMove = ();

    fn start(&self, _: u64) {}

    #[inline(always)]
    fn observe(&self, _: &DeltaModel, _: &mut (), _: &Evaluated) {}

    fn merge(&self, _: &mut (), _: &mut ()) {}

    fn every_sample(&self) -> bool {
        false
    }
}

/// Two observers of the same runs.
impl<A: Observer, B: Observer> Observer for (A, B) {
    type PerMove = (A::PerMove, B::PerMove);

    fn start(&self, line: u64) -> Self::PerMove {
        (self.0.start(line), self.1.start(line))
    }

    fn observe(&self, model: &DeltaModel, acc: &mut Self::PerMove, run: &Evaluated) {
        self.0.observe(model, &mut acc.0, run);
        self.1.observe(model, &mut acc.1, run);
    }

    fn merge(&self, acc: &mut Self::PerMove, later: &mut Self::PerMove) {
        self.0.merge(&mut acc.0, &mut later.0);
        self.1.merge(&mut acc.1, &mut later.1);
    }

    fn every_sample(&self) -> bool {
        self.0.every_sample() || self.1.every_sample()
    }

    fn move_peaks(&self) -> bool {
        self.0.move_peaks() || self.1.move_peaks()
    }
}

/// An observer that may be absent.
impl<A: Observer> Observer for Option<A> {
    type PerMove = Option<A::PerMove>;

    fn start(&self, line: u64) -> Self::PerMove {
        self.as_ref().map(|a| a.start(line))
    }

    fn observe(&self, model: &DeltaModel, acc: &mut Self::PerMove, run: &Evaluated) {
        if let (Some(a), Some(acc)) = (self, acc) {
            a.observe(model, acc, run);
        }
    }

    fn merge(&self, acc: &mut Self::PerMove, later: &mut Self::PerMove) {
        if let (Some(a), Some(acc), Some(later)) = (self, acc, later) {
            a.merge(acc, later);
        }
    }

    fn every_sample(&self) -> bool {
        self.as_ref().is_some_and(A::every_sample)
    }
}

/// The forces of the samples in a time span, for a plot: (t, forces) per sample.
pub struct Window {
    pub from_s: f64,
    pub to_s: f64,
}

impl Observer for Window {
    type PerMove = Vec<(f64, [f64; 3])>;

    fn start(&self, _: u64) -> Self::PerMove {
        Vec::new()
    }

    fn observe(&self, _: &DeltaModel, acc: &mut Self::PerMove, run: &Evaluated) {
        let (j0, j1) = (run.lanes.start, run.lanes.end);
        if run.t_s[j0] > self.to_s || run.t_s[j1 - 1] < self.from_s {
            return;
        }
        for j in run.lanes.clone() {
            let t = run.t_s[j];
            if run.forces.ok[j] && t >= self.from_s && t <= self.to_s {
                acc.push((t, run.force_n(j)));
            }
        }
    }

    fn merge(&self, acc: &mut Self::PerMove, later: &mut Self::PerMove) {
        acc.append(later);
    }
}

/// The verdict's statistics: each move's peak forces, and the instant each motor was asked
/// the largest share of the force it can give at its carriage's speed (the motor's
/// torque-speed curve), when and in which phase; and the poses the model could not take.
pub struct Verdict<'m> {
    pub motors: &'m Motors,
}

impl Verdict<'_> {
    /// The force each motor can give at the carriage speeds of the first `len` lanes of
    /// `forces`, N: computed once per block for every observer of its runs.
    pub fn available(&self, forces: &ForceBlock, len: usize, out: &mut [[f64; BLOCK]; 3]) {
        for (avail, dq) in out.iter_mut().zip(&forces.dq_mm_s) {
            for (a, v) in avail[..len].iter_mut().zip(&dq[..len]) {
                *a = self.motors.available_force_n(v.abs());
            }
        }
    }
}

impl Observer for Verdict<'_> {
    type PerMove = MoveStats;

    fn start(&self, line: u64) -> MoveStats {
        MoveStats::new(line)
    }

    #[inline(always)]
    fn observe(&self, model: &DeltaModel, stats: &mut MoveStats, run: &Evaluated) {
        let (lanes, fo, available) = (run.lanes.clone(), run.forces, run.available_n);
        let forces = |j0: usize, j1: usize| RunForces {
            t_s: &run.t_s[j0..j1],
            phase: &run.phase[j0..j1],
            force_n: [0, 1, 2].map(|i| &fo.force_n[i][j0..j1]),
            available_n: [0, 1, 2].map(|i| &available[i][j0..j1]),
            speed_mm_s: [0, 1, 2].map(|i| &fo.dq_mm_s[i][j0..j1]),
            tension_n: [0, 1, 2].map(|i| &fo.tension_n[i][j0..j1]),
        };
        if fo.ok[lanes.clone()].iter().all(|&ok| ok) {
            stats.add_run(&forces(lanes.start, lanes.end));
            return;
        }
        for j in lanes {
            if fo.ok[j] {
                stats.add_run(&forces(j, j + 1));
            } else {
                let (pos, vel, acc) = run.state(j);
                if let Err(e) = model.evaluate(pos, vel, acc) {
                    stats.checks.flag(unreachable(e, run.t_s[j], pos));
                }
            }
        }
    }

    fn merge(&self, stats: &mut MoveStats, later: &mut MoveStats) {
        stats.merge(later);
    }
}

/// The problem of a pose the model cannot take.
pub(super) fn unreachable(e: Unreachable, t_s: f64, pos: Vec3) -> Problem {
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
