//! The moves' pieces through the model: sampled, a block of samples at a time through the
//! vectorised forces, and each block's runs handed to the observers.

use std::sync::atomic::{AtomicU64, Ordering};

use crate::delta::{BLOCK, DeltaModel, ForceBlock, StateBlock};
use crate::interval::greater;
use crate::machine::Machine;
use crate::motion::Segment;
use crate::motion::drive::{Drive, Response};
use crate::path::Path;
use crate::report::{MoveStats, NEAR_SINGULAR_RATIO, PathChecks, Problem, share};
use crate::resample::{
    Phase, PieceWork, Sample, SampleSink, StateBox, peak_candidates, sample_piece,
};

use super::MoveResult;
use super::observe::{Evaluated, Observer, Verdict, unreachable};
use super::sequence::MoveWork;

mod whole;

use whole::WholeMove;

/// Tolerance on the print radius and the bed, mm: rounding in slicer output.
const GEOMETRY_TOLERANCE_MM: f64 = 1e-3;

/// The squared distance from which a squared distance is within a relative 1e-9 of
/// `limit2` or past it: the exact test on the distance itself can only hold then (the
/// squares' rounding is a few units in the last place).
fn near_from(limit2: f64) -> f64 {
    limit2 * (1.0 - 1e-9)
}

/// The vertical lines whose horizontal distance from a path [`MoveChecker::check_geometry`]
/// screens: the bed's axis (the print radius), then each tower's pull point (the carriage
/// speed ratio); each with the squared distance from which it takes the exact test
/// ([`near_from`]).
#[derive(Clone, Copy, Debug)]
struct Screen {
    x: [f64; 4],
    y: [f64; 4],
    near2: [f64; 4],
}

impl Screen {
    fn new(machine: &Machine, model: &DeltaModel) -> Self {
        let outside_mm = machine.geometry.print_radius_mm + GEOMETRY_TOLERANCE_MM;
        let towers = model.towers_xy_mm();
        let mut screen = Screen {
            x: [0.0; 4],
            y: [0.0; 4],
            near2: [near_from(outside_mm * outside_mm); 4],
        };
        for (tower, xy) in towers.into_iter().enumerate() {
            screen.x[tower + 1] = xy[0];
            screen.y[tower + 1] = xy[1];
            screen.near2[tower + 1] =
                near_from(model.speed_ratio_dist2_mm2(tower, NEAR_SINGULAR_RATIO));
        }
        screen
    }
}

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
    /// The run's peaks so far, when the observer needs only those and the violations
    /// ([`Observer::move_peaks`]): pieces whose bounds stay below them are not computed.
    run_floor: Option<RunFloor>,
    /// The arm tension above which a move is a violation (N; infinite without magnets).
    hold_n: f64,
    screen: Screen,
}

impl<'m, O: Observer> MoveChecker<'m, O> {
    pub fn new(machine: &'m Machine, observer: O) -> Self {
        let response = match &machine.drive {
            Drive::Rigid => None,
            Drive::Spring(s) => Some(Response::new(s).with_step(machine.sampling.period_s)),
        };
        let sparse =
            response.is_some() && !observer.every_sample() && std::env::var_os(DENSE_ENV).is_none();
        let model = machine.model();
        MoveChecker {
            machine,
            screen: Screen::new(machine, &model),
            model,
            sparse,
            response,
            run_floor: (sparse && !observer.move_peaks()).then(RunFloor::default),
            hold_n: machine.geometry.arm_magnet_hold_n.unwrap_or(f64::INFINITY),
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
            run_floor: None,
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
    ///
    /// With a run floor, a move's pieces are compared with the run's peaks known when the
    /// call starts; a move some of whose samples went uncomputed and that turns out to be a
    /// violation is sampled again, densely, so that what the report says of it is exact.
    /// The run's peaks are then raised by the moves' own.
    pub fn check_moves(
        &self,
        scratch: &mut Scratch,
        pieces: &[PieceWork],
        moves: &[MoveWork],
        out: &mut Vec<MoveResult<O::PerMove>>,
    ) {
        scratch.len = 0;
        let base = out.len();
        let run = self.run_floor.as_ref().map(RunFloor::get);
        let mut revisit = std::mem::take(&mut scratch.revisit);
        if let Some(run) = &run {
            self.let_go_whole(scratch, pieces, moves, run);
        }
        // Made all at once, written in place: each pushed between the samplings was built
        // on the stack and copied in (a result is 376 bytes; −0.4 % of an unshaped run's
        // instructions).
        out.extend(moves.iter().map(|m| MoveResult {
            group: m.group,
            stats: m.stats(),
            observed: self.observer.start(m.line),
            end_xy_mm: m.end_xy_mm,
        }));
        // A move's pieces are looked up only where it is sampled: most moves go whole.
        let works = |m: &MoveWork| pieces.get(m.first..m.first + m.count).unwrap_or_default();
        for (idx, m) in moves.iter().enumerate() {
            let revisit_it = match &run {
                // A line split between batches is joined after the checks: its parts
                // could not be sampled again.
                Some(run) if !m.split => match scratch.whole.get(idx) {
                    // Nothing of it is sampled later: whether it is to be sampled again is
                    // known now, and most such moves are not kept for it (−0.9 % of a
                    // default run's instructions). Only a problem of its path flags it
                    // ([`Self::flagged`]): its peaks stay zero, no violation (a magnets'
                    // hold is positive).
                    Some(Some(w)) if w.let_go => {
                        scratch.skipped += w.count;
                        if let Some(r) = out.get_mut(base + idx) {
                            r.stats.samples += w.count;
                        }
                        m.checks.problem.is_some()
                    }
                    _ => {
                        scratch.raise.push(idx);
                        let reference = Some(Reference::Run(run));
                        self.sample_move(scratch, works(m), base + idx, out, reference)
                    }
                },
                _ => {
                    let floor = self.floor(works(m));
                    let reference = floor.as_ref().map(Reference::Move);
                    self.sample_move(scratch, works(m), base + idx, out, reference)
                }
            };
            if revisit_it {
                revisit.push(idx);
            }
        }
        self.flush(scratch, out);
        for &idx in &revisit {
            let (m, slot) = (&moves[idx], base + idx);
            if self.flagged(&out[slot].stats) {
                out[slot].stats = m.stats();
                out[slot].observed = self.observer.start(m.line);
                self.sample_move(scratch, works(m), slot, out, None);
                self.flush(scratch, out);
                // Let go whole but sampled after all: its peaks raise the run's below.
                if !m.split && matches!(scratch.whole.get(idx), Some(Some(w)) if w.let_go) {
                    scratch.raise.push(idx);
                }
            }
        }
        revisit.clear();
        scratch.revisit = revisit;
        // Once a call: an atomic addition per move, on a line both lanes write, cost a
        // cache line's trip between the cores each time.
        let skipped = std::mem::take(&mut scratch.skipped);
        if skipped > 0 {
            self.skipped.fetch_add(skipped, Ordering::Relaxed);
        }
        if let Some(floor) = &self.run_floor {
            // A move let go whole has no peaks to raise the run's with, only its count: not
            // offered to the floor (most moves go so; −0.5 % of a default run's
            // instructions). The others listed as they are sampled, so that the moves let
            // go are not visited again (−0.24 % of a default run's instructions, −0.13 % shaped). The floor
            // keeps maxima: the order it is raised in does not matter.
            for &idx in &scratch.raise {
                floor.raise(&out[base + idx].stats);
            }
        }
        scratch.raise.clear();
    }

    /// Samples one move's pieces into the blocks (its result is `out[slot]`), a sparse
    /// evaluation against `reference` if there is one; whether some samples went
    /// uncomputed.
    fn sample_move(
        &self,
        scratch: &mut Scratch,
        works: &[PieceWork],
        slot: usize,
        out: &mut Vec<MoveResult<O::PerMove>>,
        reference: Option<Reference>,
    ) -> bool {
        let period_s = self.machine.sampling.period_s;
        let mut sink = MoveSink {
            checker: self,
            scratch,
            out,
            slot,
            reference,
            skipped: false,
        };
        for work in works {
            let seg = &work.commanded;
            if seg.dt_s > MAX_SAMPLES_PER_PIECE * period_s {
                if let Some(r) = sink.out.get_mut(slot) {
                    self.check_ends_only(seg, &mut r.stats);
                }
                continue;
            }
            sample_piece(work, self.response.as_ref(), period_s, &mut sink);
        }
        sink.skipped
    }

    /// Whether the report lists a move with these statistics: a problem, a motor asked
    /// more than it gives, an arm pulled off its magnets.
    fn flagged(&self, stats: &MoveStats) -> bool {
        stats.checks.problem.is_some()
            || stats.over_force()
            || stats.peak_tension_n.iter().any(|&t| t > self.hold_n)
    }

    /// For a sparse evaluation of a move with a long piece: lower bounds of the move's
    /// peaks from its pieces' peak candidates ([`peak_candidates`]), each a sample of the
    /// move. None when the move is sampled densely anyway.
    fn floor(&self, works: &[PieceWork]) -> Option<Floor> {
        let period_s = self.machine.sampling.period_s;
        let r = self.response.as_ref().filter(|_| self.sparse)?;
        if !works
            .iter()
            .any(|w| w.commanded.dt_s >= SEED_MIN_PERIODS * period_s)
        {
            return None;
        }
        let mut floor = Floor::default();
        // Only pieces that are sampled: a candidate must be one of the move's samples.
        let sampled = works
            .iter()
            .filter(|w| w.commanded.dt_s <= MAX_SAMPLES_PER_PIECE * period_s);
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
        stats.checks.flag(Problem::NotSampled {
            duration_s: seg.dt_s,
        });
        for t_s in [seg.t0_s, seg.t1_s()] {
            let (pos, _, _) = seg.at(t_s - seg.t0_s);
            if let Err(e) = self.model.inverse(pos) {
                stats.checks.flag(unreachable(e, t_s, pos));
            }
        }
    }

    /// The checks on a move's path as a whole: the print disc, the bed, and how close the
    /// arms come to flat (the carriage speed ratio peaks where the path is farthest from a
    /// tower).
    ///
    /// Each distance is compared squared first, and its square root, the carriage speed
    /// ratio's division, taken only near or past its limit: for nearly every move none of
    /// seven square roots and three divisions (2 % of a default run's instructions). The
    /// four squared distances are screened together, their thresholds computed once
    /// ([`Screen`]), and the tests that flag anything taken out of line only when one of
    /// them may.
    pub fn check_geometry(&self, path: &Path, checks: &mut PathChecks) {
        let s = &self.screen;
        let far2: [f64; 4] = std::array::from_fn(|k| path.max_dist2_from_mm2([s.x[k], s.y[k]]));
        let near = (0..4).fold(false, |near, k| near | (far2[k] >= s.near2[k]));
        let z_mm = path.min_z_mm();
        if near || z_mm < -GEOMETRY_TOLERANCE_MM {
            self.flag_geometry(far2, z_mm, checks);
        }
    }

    /// The exact tests of [`Self::check_geometry`]: `far2` the path's squared distances
    /// from the lines of the [`Screen`], `z_mm` its lowest point.
    #[cold]
    #[inline(never)]
    fn flag_geometry(&self, far2: [f64; 4], z_mm: f64, checks: &mut PathChecks) {
        let limit_mm = self.machine.geometry.print_radius_mm;
        let outside_mm = limit_mm + GEOMETRY_TOLERANCE_MM;
        if far2[0] >= self.screen.near2[0] {
            let radius_mm = far2[0].sqrt();
            if radius_mm > outside_mm {
                checks.flag(Problem::OutsideRadius {
                    radius_mm,
                    limit_mm,
                });
            }
        }
        if z_mm < -GEOMETRY_TOLERANCE_MM {
            checks.flag(Problem::BelowBed { z_mm });
        }
        for tower in 0..3 {
            let d2 = far2[tower + 1];
            // Not `d2 < …`: a NaN distance is skipped, as the screen skips it.
            if d2
                .partial_cmp(&self.screen.near2[tower + 1])
                .is_none_or(std::cmp::Ordering::is_lt)
            {
                continue;
            }
            let ratio = self.model.carriage_speed_ratio(tower, d2.sqrt());
            if ratio > NEAR_SINGULAR_RATIO {
                checks.near(tower, ratio);
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

/// The run's peaks so far, per tower (see [`Floor`]): the largest over the reachable moves
/// checked so far, shared between the workers. Kept as the bits of non-negative floats,
/// which order as the floats do.
#[derive(Default)]
struct RunFloor {
    force_n: [AtomicU64; 3],
    share: [AtomicU64; 3],
    tension_n: [AtomicU64; 3],
}

impl RunFloor {
    fn get(&self) -> Floor {
        let get = |a: &[AtomicU64; 3]| {
            a.each_ref()
                .map(|x| f64::from_bits(x.load(Ordering::Relaxed)))
        };
        Floor {
            force_n: get(&self.force_n),
            share: get(&self.share),
            tension_n: get(&self.tension_n),
            speed_mm_s: 0.0,
        }
    }

    /// Takes a move's peaks, unless the report leaves them out (an unreachable pose).
    fn raise(&self, stats: &MoveStats) {
        if stats
            .checks
            .problem
            .as_deref()
            .is_some_and(Problem::unreachable)
        {
            return;
        }
        // Positive numbers order as their bits. The atomic maximum (a locked exchange loop)
        // only where the floor is below: it only rises, so a floor read at or above `v`
        // stays so.
        let raise = |a: &AtomicU64, v: f64| {
            if v > 0.0 && v.to_bits() > a.load(Ordering::Relaxed) {
                a.fetch_max(v.to_bits(), Ordering::Relaxed);
            }
        };
        for i in 0..3 {
            raise(&self.force_n[i], stats.peak_force_n[i]);
            raise(&self.share[i], stats.worst[i].ratio);
            raise(&self.tension_n[i], stats.peak_tension_n[i]);
        }
    }
}

/// What a sparse evaluation compares its bounds with.
#[derive(Clone, Copy)]
enum Reference<'a> {
    /// The move's own peak candidates (and its samples so far): its statistics stay exact.
    Move(&'a Floor),
    /// The run's peaks so far, from other moves ([`RunFloor`]): only the run's peaks and the
    /// violations stay exact. Whole pieces are offered too.
    Run(&'a Floor),
}

/// The samples of the move whose result is `out[slot]`, on their way into the blocks.
struct MoveSink<'a, 'm, O: Observer> {
    checker: &'a MoveChecker<'m, O>,
    scratch: &'a mut Scratch,
    out: &'a mut Vec<MoveResult<O::PerMove>>,
    slot: usize,
    /// What the bounds are compared with, when the move is evaluated sparsely.
    reference: Option<Reference<'a>>,
    /// Some samples were left uncomputed.
    skipped: bool,
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
        self.reference.is_some()
    }

    fn whole_pieces(&self) -> bool {
        matches!(self.reference, Some(Reference::Run(_)))
    }

    /// A run goes uncomputed when its bounds (`DeltaModel::bound`: every state of the box a
    /// valid pose, |Q_i|, the share of the available force, the tension and the carriage
    /// speed each with their margin) are below the reference, strictly, on every tower.
    ///
    /// Against the move's own peaks (its samples so far, the block flushed first, and its
    /// peak candidates): then none of its samples could have changed a peak, where it was,
    /// or a problem, so the statistics are the dense ones.
    ///
    /// Against the run's peaks, each also below its violation (a share of 1, the magnets'
    /// hold): then none could have changed the run's peaks or made the move a violation.
    fn skip(&mut self, states: &StateBox, count: u64) -> bool {
        let Some(reference) = self.reference else {
            return false;
        };
        let checker = self.checker;
        // The tension's limits before the bound, which stops at a tension above them
        // (`DeltaModel::bound_below`); against the move's own peaks, once its samples so
        // far are in them.
        let tension_n = match reference {
            Reference::Move(floor) => {
                if self.scratch.len > 0 {
                    checker.flush(self.scratch, self.out);
                }
                let Some(stats) = self.out.get(self.slot).map(|r| &r.stats) else {
                    return false;
                };
                std::array::from_fn(|i| greater(stats.peak_tension_n[i], floor.tension_n[i]))
            }
            Reference::Run(run) => checker.tension_limits(run),
        };
        let Some(b) = checker.model.bound_below(
            &states.pos_mm,
            &states.vel_mm_s,
            &states.acc_mm_s2,
            &tension_n,
        ) else {
            return false;
        };
        let below = match reference {
            Reference::Move(floor) => {
                let Some(stats) = self.out.get(self.slot).map(|r| &r.stats) else {
                    return false;
                };
                (0..3).all(|i| {
                    b.force_n[i] < greater(stats.peak_force_n[i], floor.force_n[i])
                        && checker.most_share(&b, i) < greater(stats.worst[i].ratio, floor.share[i])
                        && b.tension_n[i] < greater(stats.peak_tension_n[i], floor.tension_n[i])
                        && b.speed_mm_s[i] < greater(stats.peak_speed_mm_s, floor.speed_mm_s)
                })
            }
            Reference::Run(run) => checker.bounds_below_run(&b, run),
        };
        let Some(stats) = self.out.get_mut(self.slot).map(|r| &mut r.stats) else {
            return false;
        };
        if below {
            stats.samples += count;
            self.skipped = true;
            self.scratch.skipped += count;
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
    /// The moves of a call some of whose samples went uncomputed and that may be sampled
    /// again (indices in its moves): a move let go whole only when it is flagged.
    revisit: Vec<usize>,
    /// The moves of a call offered whole to the run's peaks, and which went
    /// ([`MoveChecker::let_go_whole`]); the indices of the offered ones.
    whole: Vec<Option<WholeMove>>,
    offered: Vec<usize>,
    /// The moves of a call whose peaks raise the run's ([`RunFloor`]), indices in its
    /// moves: those sampled, not let go whole.
    raise: Vec<usize>,
    /// Samples left uncomputed in the call so far, for [`MoveChecker::skipped_samples`].
    skipped: u64,
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
            revisit: Vec::new(),
            whole: Vec::new(),
            offered: Vec::new(),
            raise: Vec::new(),
            skipped: 0,
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::machine::test_support::kossel_machine;
    use crate::path::Vec3;

    /// The checks of a path the direct way: every distance's square root, every ratio.
    fn direct(checker: &MoveChecker<()>, path: &Path) -> PathChecks {
        let mut checks = PathChecks::default();
        let limit_mm = checker.machine.geometry.print_radius_mm;
        let radius_mm = path.max_xy2_mm2().sqrt();
        if radius_mm > limit_mm + GEOMETRY_TOLERANCE_MM {
            checks.flag(Problem::OutsideRadius {
                radius_mm,
                limit_mm,
            });
        }
        for (tower, xy) in checker.model.towers_xy_mm().into_iter().enumerate() {
            let d = path.max_dist2_from_mm2(xy).sqrt();
            let ratio = checker.model.carriage_speed_ratio(tower, d);
            if ratio > NEAR_SINGULAR_RATIO {
                checks.near(tower, ratio);
            }
        }
        checks
    }

    /// The squared pre-tests flag exactly what the direct tests flag, on paths ending at
    /// the print radius and at the near-singular distance from each tower, to within a few
    /// units in the last place on either side.
    #[test]
    fn squared_pretests_flag_what_the_direct_tests_do() {
        let machine = kossel_machine();
        let checker = MoveChecker::new(&machine, ());
        let r = machine.geometry.print_radius_mm + GEOMETRY_TOLERANCE_MM;
        let mut ends = Vec::new();
        for k in 0..36 {
            let (s, c) = (k as f64 * 10f64.to_radians()).sin_cos();
            ends.push(Vec3::new(r * c, r * s, 1.0));
        }
        for (tower, xy) in checker.model.towers_xy_mm().into_iter().enumerate() {
            let h = checker
                .model
                .speed_ratio_dist2_mm2(tower, NEAR_SINGULAR_RATIO)
                .sqrt();
            // Away from the tower, towards the bed's centre and beyond.
            let n = (xy[0].powi(2) + xy[1].powi(2)).sqrt();
            ends.push(Vec3::new(xy[0] * (1.0 - h / n), xy[1] * (1.0 - h / n), 1.0));
        }
        let (mut flagged, mut clear) = (0, 0);
        for end in ends {
            for ulps in -4i64..=4 {
                let scale = 1.0 + ulps as f64 * f64::EPSILON;
                let path = Path::line(Vec3::new(0.0, 0.0, 1.0), end * scale);
                let mut checks = PathChecks::default();
                checker.check_geometry(&path, &mut checks);
                let want = direct(&checker, &path);
                assert_eq!(checks, want, "{end:?} {ulps}");
                let any = want.problem.is_some() || want.near_singular.is_some();
                flagged += usize::from(any);
                clear += usize::from(!any);
            }
        }
        assert!(
            flagged > 20 && clear > 20,
            "{flagged} flagged, {clear} clear"
        );
    }
}
