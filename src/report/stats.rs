//! Per-move statistics: the peak force on each tower and what went wrong, gathered sample
//! by sample.

use serde::Serialize;

use super::ViolationKind;
use crate::interval::greater;
use crate::resample::Phase;

/// Why a move cannot be run as planned (besides asking too much force).
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Problem {
    /// The pose is out of the arms' reach (eq. 6 has no real root).
    /// `tower` is the tower at fault, when there is one (not for a singular Jx).
    Unreachable {
        t_s: f64,
        tower: Option<usize>,
        pos_mm: [f64; 3],
        reason: String,
    },
    /// A carriage would rise above its homed height (the top of its travel).
    AboveHome {
        t_s: f64,
        tower: usize,
        over_mm: f64,
    },
    /// The nozzle goes below the bed (Klipper's delta refuses z < 0).
    BelowBed { z_mm: f64 },
    /// The nozzle leaves the print disc.
    OutsideRadius { radius_mm: f64, limit_mm: f64 },
    /// The move lasts so long that sampling it would take hours (F near zero, a huge
    /// coordinate, an arc of a million turns): only its ends were checked.
    NotSampled { duration_s: f64 },
}

impl Problem {
    /// The kind of violation this problem makes.
    pub fn kind(&self) -> ViolationKind {
        match self {
            Problem::Unreachable { .. } => ViolationKind::Unreachable,
            Problem::AboveHome { .. } => ViolationKind::AboveHome,
            Problem::BelowBed { .. } => ViolationKind::BelowBed,
            Problem::OutsideRadius { .. } => ViolationKind::OutsideRadius,
            Problem::NotSampled { .. } => ViolationKind::NotSampled,
        }
    }

    /// A pose the model cannot take (out of reach, a carriage above its top): the move's
    /// forces mean nothing and are not reported.
    pub fn unreachable(&self) -> bool {
        matches!(
            self,
            Problem::Unreachable { .. } | Problem::AboveHome { .. }
        )
    }

    /// Rank among the problems of one move: the higher one is reported.
    fn severity(&self) -> u8 {
        match self {
            Problem::Unreachable { .. } => 4,
            Problem::AboveHome { .. } => 3,
            Problem::BelowBed { .. } => 2,
            Problem::OutsideRadius { .. } => 1,
            Problem::NotSampled { .. } => 0,
        }
    }
}

/// What one move asked of the motors.
#[derive(Clone, Debug, PartialEq)]
pub struct MoveStats {
    /// 1-based source line.
    pub line: u64,
    pub samples: u64,
    /// Largest |Q_i| per tower over the move's samples, N.
    pub peak_force_n: [f64; 3],
    /// When each tower's peak happened, s.
    pub peak_t_s: [f64; 3],
    pub peak_phase: [Phase; 3],
    /// Per tower, the instant its motor was asked the largest share of the force it can
    /// give at that carriage speed.
    pub worst: [Worst; 3],
    /// The phase of each tower's [`Worst`] instant. Kept apart from it, beside
    /// `peak_phase`: in each `Worst` it left 7 bytes of padding, which LLVM filled by
    /// copying stack temporaries into every move's result as it was made.
    pub worst_phase: [Phase; 3],
    /// Largest pull of each parallelogram on the platform (positive: tension), N, and when.
    pub peak_tension_n: [f64; 3],
    pub peak_tension_t_s: [f64; 3],
    /// The fastest any carriage ran, |q̇_i| mm/s.
    pub peak_speed_mm_s: f64,
    /// What the checks of its path and poses found.
    pub checks: PathChecks,
}

/// What the checks of a move found apart from its forces: its problems and how close it
/// came to a singular pose. A fraction of [`MoveStats`]' size: the sequential stages carry
/// these from the checks of a line's planned moves to the sampling of its pieces.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PathChecks {
    /// The most severe geometric problem found, if any (boxed: rare, and the checks of
    /// every move are carried through the sequential stages).
    pub problem: Option<Box<Problem>>,
    /// Near a singular pose: the tower (0 = A) whose carriage moves fastest relative to the
    /// nozzle, and that speed ratio, when it exceeds [`NEAR_SINGULAR_RATIO`].
    pub near_singular: Option<(usize, f64)>,
    /// The line's G92 offset: positions are reported as the file writes them, machine
    /// position − offset, mm.
    pub offset_mm: [f64; 3],
}

impl PathChecks {
    /// Records a problem. A move keeps its most severe one (unreachable, then above home,
    /// then outside the radius), the first of that kind: a move that leaves the print disc
    /// and then the arms' reach is reported unreachable.
    pub fn flag(&mut self, problem: Problem) {
        if self
            .problem
            .as_ref()
            .is_none_or(|p| problem.severity() > p.severity())
        {
            self.problem = Some(Box::new(problem));
        }
    }

    /// Records a near-singular pose of `tower` at `ratio`, if it is the closest yet.
    pub fn near(&mut self, tower: usize, ratio: f64) {
        if self.near_singular.is_none_or(|(_, r)| ratio > r) {
            self.near_singular = Some((tower, ratio));
        }
    }

    /// Takes in the checks of a later part of the same move (or line): the most severe
    /// problem, the closest approach to a singular pose, the later offset.
    pub fn merge(&mut self, later: &PathChecks) {
        self.offset_mm = later.offset_mm;
        if let Some(p) = &later.problem {
            self.flag(Problem::clone(p));
        }
        if let Some((tower, ratio)) = later.near_singular {
            self.near(tower, ratio);
        }
    }
}

/// Below this an available force counts as this (N): the share of a motor with no force
/// left stays a finite number (for JSON).
const MIN_AVAILABLE_N: f64 = 1e-3;

/// The share of what a motor can give that a force asks, |Q| / available (N, N): above 1
/// the motor skips steps. No force available (a motor beyond its top speed) and some asked
/// is a large finite share, a violation.
#[inline(always)]
pub fn share(force_n: f64, available_n: f64) -> f64 {
    force_n.abs() / greater(available_n, MIN_AVAILABLE_N)
}

/// The instant a tower's motor was asked the largest share of what it can give.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Worst {
    /// |Q_i| / available force: above 1, the motor skips steps.
    pub ratio: f64,
    /// |Q_i| then, N.
    pub force_n: f64,
    /// The force the motor can give at that carriage speed, N.
    pub available_n: f64,
    /// |q̇_i| then, mm/s.
    pub speed_mm_s: f64,
    pub t_s: f64,
}

impl Default for Worst {
    /// Inlined, as [`MoveStats::new`].
    #[inline(always)]
    fn default() -> Self {
        Worst {
            ratio: 0.0,
            force_n: 0.0,
            available_n: 0.0,
            speed_mm_s: 0.0,
            t_s: 0.0,
        }
    }
}

/// The evaluated samples of a run, as the statistics take them: per tower the force asked
/// (N), the force available at the carriage's speed (N) and that speed (mm/s).
#[derive(Clone, Copy)]
pub struct RunForces<'a> {
    pub t_s: &'a [f64],
    pub phase: &'a [Phase],
    pub force_n: [&'a [f64]; 3],
    pub available_n: [&'a [f64]; 3],
    pub speed_mm_s: [&'a [f64]; 3],
    /// Each parallelogram's tension, N.
    pub tension_n: [&'a [f64]; 3],
}

/// A carriage moving this many times faster than the nozzle marks a near-singular pose (the
/// arm within 4.8° of flat): Klipper's delta refuses moves beyond it (4 × its SLOW_RATIO).
pub const NEAR_SINGULAR_RATIO: f64 = 12.0;

impl MoveStats {
    /// A move's statistics before its first sample. Inlined: each move's result starts
    /// from it, written in place (`MoveWork::stats`).
    #[inline(always)]
    pub fn new(line: u64) -> Self {
        MoveStats {
            line,
            samples: 0,
            peak_force_n: [0.0; 3],
            peak_t_s: [0.0; 3],
            peak_phase: [Phase::Cruise; 3],
            worst: [Worst::default(); 3],
            worst_phase: [Phase::Cruise; 3],
            peak_tension_n: [0.0; 3],
            peak_tension_t_s: [0.0; 3],
            peak_speed_mm_s: 0.0,
            checks: PathChecks::default(),
        }
    }

    /// Takes a run of evaluated samples, in time order, into the peaks: the same as adding
    /// them one by one.
    pub fn add_run(&mut self, run: &RunForces) {
        self.samples += run.t_s.len() as u64;
        for i in 0..3 {
            // One pass, branch-free: the peak force and the largest share of the available
            // force, each with the index of the first sample that reached it, as a scan
            // with a strict `>` keeps.
            let (mut peak, mut peak_at) = (self.peak_force_n[i], usize::MAX);
            let (mut ratio, mut ratio_at) = (self.worst[i].ratio, usize::MAX);
            let (mut pull, mut pull_at) = (self.peak_tension_n[i], usize::MAX);
            let (f, avail) = (run.force_n[i], run.available_n[i]);
            self.peak_speed_mm_s = run.speed_mm_s[i]
                .iter()
                .fold(self.peak_speed_mm_s, |m, v| greater(v.abs(), m));
            for (j, ((&q, &a), &t)) in f.iter().zip(avail).zip(run.tension_n[i]).enumerate() {
                let up = t > pull;
                pull = if up { t } else { pull };
                pull_at = if up { j } else { pull_at };
                let q = q.abs();
                let up = q > peak;
                peak = if up { q } else { peak };
                peak_at = if up { j } else { peak_at };
                let r = share(q, a);
                let up = r > ratio;
                ratio = if up { r } else { ratio };
                ratio_at = if up { j } else { ratio_at };
            }
            if let Some((&t, &ph)) = run.t_s.get(peak_at).zip(run.phase.get(peak_at)) {
                self.peak_force_n[i] = peak;
                self.peak_t_s[i] = t;
                self.peak_phase[i] = ph;
            }
            if let Some(&t) = run.t_s.get(pull_at) {
                self.peak_tension_n[i] = pull;
                self.peak_tension_t_s[i] = t;
            }
            if let Some((&t, &ph)) = run.t_s.get(ratio_at).zip(run.phase.get(ratio_at)) {
                self.worst[i] = Worst {
                    ratio,
                    force_n: f[ratio_at].abs(),
                    available_n: avail[ratio_at],
                    speed_mm_s: run.speed_mm_s[i][ratio_at].abs(),
                    t_s: t,
                };
                self.worst_phase[i] = ph;
            }
        }
    }

    /// Takes in the statistics of another part of the same move (a later one): the peaks
    /// (an earlier peak wins a tie), the most severe problem, the fastest carriage ratio.
    pub fn merge(&mut self, later: &MoveStats) {
        self.samples += later.samples;
        self.peak_speed_mm_s = greater(later.peak_speed_mm_s, self.peak_speed_mm_s);
        for i in 0..3 {
            if later.peak_force_n[i] > self.peak_force_n[i] {
                self.peak_force_n[i] = later.peak_force_n[i];
                self.peak_t_s[i] = later.peak_t_s[i];
                self.peak_phase[i] = later.peak_phase[i];
            }
            if later.worst[i].ratio > self.worst[i].ratio {
                self.worst[i] = later.worst[i];
                self.worst_phase[i] = later.worst_phase[i];
            }
            if later.peak_tension_n[i] > self.peak_tension_n[i] {
                self.peak_tension_n[i] = later.peak_tension_n[i];
                self.peak_tension_t_s[i] = later.peak_tension_t_s[i];
            }
        }
        self.checks.merge(&later.checks);
    }

    /// The tower (0-based) whose motor was asked the largest share of what it can give.
    pub fn worst_use_tower(&self) -> usize {
        let r = self.worst.map(|w| w.ratio);
        if r[0] >= r[1] && r[0] >= r[2] {
            0
        } else if r[1] >= r[2] {
            1
        } else {
            2
        }
    }

    /// Whether the move stays within reach: a move out of reach adds no force to a run's
    /// peaks ([`crate::report::Report::add_move`]).
    pub fn reachable(&self) -> bool {
        !self
            .checks
            .problem
            .as_deref()
            .is_some_and(Problem::unreachable)
    }

    /// Whether some motor was asked more than it can give.
    pub fn over_force(&self) -> bool {
        self.worst.iter().any(|w| w.ratio > 1.0)
    }

    /// The tower (0-based) with the largest peak.
    pub fn worst_tower(&self) -> usize {
        let p = self.peak_force_n;
        if p[0] >= p[1] && p[0] >= p[2] {
            0
        } else if p[1] >= p[2] {
            1
        } else {
            2
        }
    }

    pub fn peak_n(&self) -> f64 {
        self.peak_force_n[self.worst_tower()]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One sample's run.
    fn one(s: &mut MoveStats, t: f64, phase: Phase, f: [f64; 3], available: [f64; 3]) {
        s.add_run(&RunForces {
            t_s: &[t],
            phase: &[phase],
            force_n: [&[f[0]], &[f[1]], &[f[2]]],
            available_n: [&[available[0]], &[available[1]], &[available[2]]],
            speed_mm_s: [&[10.0 * t], &[20.0 * t], &[-30.0 * t]],
            tension_n: [&[f[0]], &[-f[1]], &[2.0 * f[2]]],
        });
    }

    #[test]
    fn peaks_keep_time_and_phase_of_the_largest_magnitude() {
        let mut s = MoveStats::new(7);
        one(&mut s, 0.0, Phase::Accel, [1.0, -5.0, 2.0], [10.0; 3]);
        one(
            &mut s,
            0.001,
            Phase::Cruise,
            [-3.0, 4.0, 2.5],
            [10.0, 4.0, 1.0],
        );
        one(
            &mut s,
            0.002,
            Phase::Decel,
            [2.0, 1.0, -2.0],
            [10.0, 0.0, 10.0],
        );
        assert_eq!(s.samples, 3);
        assert_eq!(s.peak_force_n, [3.0, 5.0, 2.5]);
        assert_eq!(s.peak_t_s, [0.001, 0.0, 0.001]);
        assert_eq!(s.peak_phase, [Phase::Cruise, Phase::Accel, Phase::Cruise]);
        assert_eq!(s.worst_tower(), 1);
        // Shares: A 0.3 at 0.001; B 1 at 0.001, then 1 N of none at 0.002 (a motor past its
        // top speed); C 2.5 at 0.001.
        assert_eq!(s.worst[0].ratio, 0.3);
        assert_eq!(s.worst[1].available_n, 0.0);
        assert_eq!((s.worst[1].force_n, s.worst[1].t_s), (1.0, 0.002));
        assert_eq!(s.worst[1].ratio, 1000.0);
        assert_eq!(s.worst[2].ratio, 2.5);
        assert_eq!(s.worst[2].speed_mm_s, 0.03);
        assert_eq!(s.worst_use_tower(), 1);
        assert!(s.over_force());
        // The largest pull (tower B pulls 5 at 0, then pushes): not the largest magnitude.
        assert_eq!(s.peak_tension_n, [2.0, 5.0, 5.0]);
        assert_eq!(s.peak_tension_t_s, [0.002, 0.0, 0.001]);
    }

    #[test]
    #[allow(clippy::needless_range_loop)] // i and k index towers and samples alike
    fn a_run_gives_the_peaks_of_a_sample_by_sample_scan() {
        // Against the plain scan: ties (the first kept), NaN (ignored), runs longer and
        // shorter than eight lanes, a peak from before the run that holds.
        let mut rng = crate::delta::test_support::Rng(11);
        for n in [1, 3, 8, 13, 64] {
            let t: Vec<f64> = (0..n).map(|k| k as f64 * 1e-3).collect();
            let phases = [Phase::Accel, Phase::Cruise, Phase::Decel, Phase::Corner];
            let phase: Vec<Phase> = (0..n).map(|k| phases[k % 4]).collect();
            let mut f: [Vec<f64>; 3] =
                [(); 3].map(|()| (0..n).map(|_| rng.range(-4.0, 4.0).round()).collect());
            f[2][n / 2] = f64::NAN;
            let a: [Vec<f64>; 3] =
                [(); 3].map(|()| (0..n).map(|_| rng.range(1.0, 5.0).round()).collect());
            let v: [Vec<f64>; 3] = [(); 3].map(|()| (0..n).map(|_| rng.range(-9.0, 9.0)).collect());
            let pull: [Vec<f64>; 3] =
                [(); 3].map(|()| (0..n).map(|_| rng.range(-2.0, 6.0).round()).collect());
            let mut run = MoveStats::new(1);
            one(
                &mut run,
                0.0,
                Phase::Accel,
                [2.0, 0.5, 0.0],
                [4.0, 4.0, 4.0],
            );
            let mut scan = run.clone();
            for k in 0..n {
                scan.samples += 1;
                for i in 0..3 {
                    if f[i][k].abs() > scan.peak_force_n[i] {
                        scan.peak_force_n[i] = f[i][k].abs();
                        scan.peak_t_s[i] = t[k];
                        scan.peak_phase[i] = phase[k];
                    }
                    scan.peak_speed_mm_s = greater(v[i][k].abs(), scan.peak_speed_mm_s);
                    if pull[i][k] > scan.peak_tension_n[i] {
                        scan.peak_tension_n[i] = pull[i][k];
                        scan.peak_tension_t_s[i] = t[k];
                    }
                    let r = f[i][k].abs() / a[i][k];
                    if r > scan.worst[i].ratio {
                        scan.worst[i] = Worst {
                            ratio: r,
                            force_n: f[i][k].abs(),
                            available_n: a[i][k],
                            speed_mm_s: v[i][k].abs(),
                            t_s: t[k],
                        };
                        scan.worst_phase[i] = phase[k];
                    }
                }
            }
            run.add_run(&RunForces {
                t_s: &t,
                phase: &phase,
                force_n: [&f[0], &f[1], &f[2]],
                available_n: [&a[0], &a[1], &a[2]],
                speed_mm_s: [&v[0], &v[1], &v[2]],
                tension_n: [&pull[0], &pull[1], &pull[2]],
            });
            assert_eq!(run, scan, "n = {n}");
        }
    }

    #[test]
    fn the_most_severe_problem_is_kept_first_of_its_kind() {
        let mut s = PathChecks::default();
        let outside = Problem::OutsideRadius {
            radius_mm: 90.0,
            limit_mm: 85.0,
        };
        s.flag(outside.clone());
        assert_eq!(s.problem.as_deref(), Some(&outside));
        let above = |t_s| Problem::AboveHome {
            t_s,
            tower: 0,
            over_mm: 1.0,
        };
        s.flag(above(0.5));
        s.flag(above(0.7));
        assert_eq!(s.problem.as_deref(), Some(&above(0.5)));
        let unreachable = Problem::Unreachable {
            t_s: 0.9,
            tower: Some(1),
            pos_mm: [300.0, 0.0, 10.0],
            reason: "arm too short".into(),
        };
        s.flag(unreachable.clone());
        s.flag(above(1.0));
        s.flag(Problem::OutsideRadius {
            radius_mm: 300.0,
            limit_mm: 85.0,
        });
        assert_eq!(s.problem.as_deref(), Some(&unreachable));
    }
}
