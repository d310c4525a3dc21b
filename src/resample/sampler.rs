//! Samples of one planned move: the global grid t = k·Ts, both one-sided limits at every
//! phase boundary, the junction at the move's start and the left limit at its end.
//!
//! Ownership (so that the union over consecutive moves has no duplicate and no gap): a move
//! owns the half-open span [t0, t_end) with t_end = the next move's t0 (or t0 + duration for
//! the last move). It emits, in time order:
//! 1. the junction sample at t0 (the right limit: the move's start state, plus the impulse);
//!    a grid point exactly at t0 is this sample, not a second one;
//! 2. every grid point k·Ts with t0 < k·Ts < t_end;
//! 3. at each phase boundary tb with t0 < tb < t_end, the left limit (old phase) then the
//!    right limit (new phase), both at tb; a grid point exactly at tb is that pair;
//! 4. the left limit at t_end (the move's end state, plus the impulse of the next junction).
//!
//! The next move's junction sample is the right limit at the same instant. A move whose
//! span is empty (t_end ≤ t0) emits only its junction sample.

use super::curve::{Curve, Frame, TaylorStep};
use super::junction::{Kicks, span};
use super::schedule::{Schedule, Tick};
use super::{Phase, Sample, SampleSink};
use crate::path::{Jet, Path, Vec3};
use crate::planner::PlannedMove;

/// Samples of `mv` (see the module doc for which samples a move owns), in time order.
///
/// `prev` and `next` are the neighbouring moves (None at the start or end of a run, where
/// the nozzle is at rest). A sample's acceleration is the planned one (tangential plus
/// centripetal) plus the junction impulses: the velocity jump Δv = v_out − v_in of a
/// junction is spread evenly over a box from half a move before it to half a move after it,
/// each half at most half a period: [t_j − min(Ts, d_in)/2, t_j + min(Ts, d_out)/2]. So a
/// corner between long moves shows Δv/Ts, and a curve tessellated into moves shorter than
/// Ts shows exactly Δv/d = v²/r at every sample: the boxes of neighbouring junctions tile
/// the time line without overlapping, so no sample counts two junctions or none (a fixed
/// box of width Ts would count ⌊Ts/d⌋ or ⌈Ts/d⌉ of them, up to 40 % off). Because a box
/// never reaches past the middle of a neighbouring move, `prev` and `next` are all a move
/// needs. Pure and allocation-free.
///
/// `period_s` must be positive and finite (the machine profile guarantees it); otherwise
/// nothing is emitted.
pub fn sample_move(
    prev: Option<&PlannedMove>,
    mv: &PlannedMove,
    next: Option<&PlannedMove>,
    period_s: f64,
    out: &mut impl SampleSink,
) {
    let (t_end, kicks) = span(prev, mv, next, period_s);
    sample_span(mv, t_end, period_s, kicks, out);
}

/// A junction impulse smaller than this (as Δv/Ts) does not make a sample a `Corner`: the
/// rounding of the tangents of two collinear moves gives Δv ~ 1e-14 mm/s.
const CORNER_MIN_MM_S2: f64 = 1e-6;

/// One phase of the trapezoid: it starts at `t_s` with speed `v_mm_s` and has tangential
/// acceleration `a_mm_s2`.
#[derive(Clone, Copy)]
struct PhaseLaw {
    phase: Phase,
    t_s: f64,
    v_mm_s: f64,
    a_mm_s2: f64,
}

impl PhaseLaw {
    fn speed(&self, t: f64) -> f64 {
        (self.v_mm_s + self.a_mm_s2 * (t - self.t_s)).max(0.0)
    }
}

/// The phases of a move's trapezoid over the span it owns: the one in force at its start
/// and those that begin strictly inside (t0, t_end), in order.
struct Phases {
    first: PhaseLaw,
    bounds: [PhaseLaw; 2],
    n: usize,
}

impl Phases {
    fn of(mv: &PlannedMove, t_end: f64) -> Phases {
        let t0 = mv.t0_s;
        let law = |phase, t_s, v_mm_s, a_mm_s2| PhaseLaw {
            phase,
            t_s,
            v_mm_s,
            a_mm_s2,
        };
        let laws = [
            (
                mv.accel_t_s,
                law(Phase::Accel, t0, mv.start_v_mm_s, mv.accel_mm_s2),
            ),
            (
                mv.cruise_t_s,
                law(Phase::Cruise, t0 + mv.accel_t_s, mv.cruise_v_mm_s, 0.0),
            ),
            (
                mv.decel_t_s,
                law(
                    Phase::Decel,
                    t0 + mv.accel_t_s + mv.cruise_t_s,
                    mv.cruise_v_mm_s,
                    -mv.accel_mm_s2,
                ),
            ),
        ]
        .map(|(duration_s, l)| (duration_s > 0.0, l));
        let mut first = laws.iter().find(|(on, _)| *on).map_or(laws[2].1, |l| l.1);
        let mut bounds = [first; 2];
        let mut n = 0;
        for (on, l) in laws {
            if !on || l.phase == first.phase {
                continue;
            }
            if l.t_s <= t0 {
                first = l;
            } else if l.t_s < t_end {
                bounds[n] = l;
                n += 1;
            }
        }
        Phases { first, bounds, n }
    }
}

/// A straight path as its own curve type, so that the sampling loop of a line is compiled
/// for lines: p' is then a loop constant and p'' zero, and the compiler hoists |p'| out of the
/// Taylor step. The same stepping law as every other curve.
#[derive(Clone, Copy)]
struct Line {
    start: Vec3,
    delta: Vec3,
}

impl Curve for Line {
    #[inline(always)]
    fn jet(&self, u: f64) -> Jet {
        Jet {
            p: self.start + self.delta * u,
            d1: self.delta,
            d2: Vec3::zeros(),
        }
    }
}

/// The common body: emits the move's samples over [t0, t_end] with the given junction
/// impulses, dispatching once on the kind of path.
fn sample_span(
    mv: &PlannedMove,
    t_end: f64,
    period_s: f64,
    kicks: Kicks,
    out: &mut impl SampleSink,
) {
    match mv.path {
        Path::Line { start, end } => {
            let line = Line {
                start,
                delta: end - start,
            };
            sample_curve(mv, &line, Some(line), t_end, period_s, kicks, out)
        }
        Path::Arc(_) => sample_curve(mv, &mv.path, None, t_end, period_s, kicks, out),
    }
}

/// Samples of `mv` along `curve` (its path; `straight` too when it is a line, whose plain
/// grid samples then go to the sink a run at a time).
fn sample_curve<C: Curve>(
    mv: &PlannedMove,
    curve: &C,
    straight: Option<Line>,
    t_end: f64,
    period_s: f64,
    kicks: Kicks,
    out: &mut impl SampleSink,
) {
    if !(period_s > 0.0 && period_s.is_finite()) {
        return;
    }
    let t0 = mv.t0_s;
    let phases = Phases::of(mv, t_end);
    let mut law = phases.first;
    let mut w = Walker {
        mv,
        curve,
        kicks,
        out,
        u: 0.0,
        t_s: t0,
        jet: curve.jet(0.0),
        from: TaylorStep::new(&curve.jet(0.0), 0.0, 0.0, 0.0),
        from_t_s: t0,
    };
    w.start_phase(&law);
    // The plain grid points of a line, away from the junctions, may come as runs.
    let plain =
        (straight.is_some() && mv.kinematic).then_some((kicks.calm_from_s, kicks.calm_to_s));
    let bound_times = phases.bounds.map(|l| l.t_s);
    let schedule = Schedule::new(t0, t_end, &bound_times[..phases.n], period_s, plain);
    for tick in schedule {
        match tick {
            Tick::At { t_s } => {
                w.step_to(t_s);
                w.emit(&law);
            }
            Tick::Cross { index } => {
                law = phases.bounds[index];
                w.start_phase(&law);
            }
            Tick::Run { k0, len } => {
                if let Some(line) = straight {
                    let run = LineRun {
                        mv,
                        line,
                        frame: Frame::new(&line.jet(0.0)),
                        law,
                        from: w.from,
                        from_t_s: w.from_t_s,
                        k0: k0 as f64,
                        period_s,
                    };
                    for j in 0..len {
                        w.out.sample(run.sample(j));
                    }
                    w.step_to((k0 + len as i64 - 1) as f64 * period_s);
                }
            }
        }
    }
}

/// The nozzle's walk along one move: the curve parameter u at time `t_s` and the curve's
/// derivatives there; the Taylor step (eq. 19) from the start of the phase in force.
///
/// Each sample is one step from the phase's start, not from the sample before: for the
/// paths G-code has (lines, circular and helical arcs) the step is exact at any length (see
/// [`TaylorStep`]), so the two give the same positions, but steps from a fixed point do not
/// wait for one another (and do not accumulate rounding).
struct Walker<'a, C, O> {
    mv: &'a PlannedMove,
    curve: &'a C,
    kicks: Kicks,
    out: &'a mut O,
    u: f64,
    t_s: f64,
    jet: Jet,
    from: TaylorStep,
    from_t_s: f64,
}

impl<C: Curve, O: SampleSink> Walker<'_, C, O> {
    /// Emits the sample at the current time under `law`.
    #[inline(always)]
    fn emit(&mut self, law: &PhaseLaw) {
        let t = self.t_s;
        let motion = if self.mv.kinematic {
            Frame::new(&self.jet).motion(law.speed(t), law.a_mm_s2)
        } else {
            (Vec3::zeros(), Vec3::zeros())
        };
        let s = sample_at(self.mv, t, self.jet.p, motion, law, self.kicks.at(t));
        self.out.sample(s);
    }

    /// Starts the phase of `law` at the current time and position.
    #[inline(always)]
    fn start_phase(&mut self, law: &PhaseLaw) {
        self.from = TaylorStep::new(&self.jet, self.u, law.speed(self.t_s), law.a_mm_s2);
        self.from_t_s = self.t_s;
    }

    /// Moves the nozzle on to time `t` in the current phase.
    #[inline(always)]
    fn step_to(&mut self, t: f64) {
        if self.mv.kinematic && t != self.t_s {
            self.u = self.from.at(t - self.from_t_s);
            self.jet = self.curve.jet(self.u);
        }
        self.t_s = t;
    }
}

/// The sample of `mv` at time `t` and position `pos`, moving with `motion` (velocity,
/// acceleration) in the phase of `law`, plus the junction impulse `kick`: the one formula of
/// every sample.
#[inline(always)]
fn sample_at(
    mv: &PlannedMove,
    t: f64,
    pos: Vec3,
    motion: (Vec3, Vec3),
    law: &PhaseLaw,
    kick: Vec3,
) -> Sample {
    let phase = if kick.norm_squared() <= CORNER_MIN_MM_S2 * CORNER_MIN_MM_S2 {
        law.phase
    } else {
        Phase::Corner
    };
    Sample {
        t_s: t,
        line: mv.line,
        phase,
        pos_mm: pos,
        vel_mm_s: motion.0,
        acc_mm_s2: motion.1 + kick,
    }
}

/// Consecutive grid samples of a straight move, all in one phase and away from its
/// junctions: sample j is at t = (k0 + j)·Ts. Each is what the move's walk gives at that
/// time (the same formula), in a loop with no branch and nothing to recompute but the
/// time, the parameter and the speed (the tangent is the run's constant).
struct LineRun<'a> {
    mv: &'a PlannedMove,
    line: Line,
    frame: Frame,
    law: PhaseLaw,
    from: TaylorStep,
    from_t_s: f64,
    /// Grid index of the first sample, as a float (exact below 2⁵³).
    k0: f64,
    period_s: f64,
}

impl LineRun<'_> {
    /// Sample j of the run.
    #[inline(always)]
    fn sample(&self, j: usize) -> Sample {
        let t = (self.k0 + j as f64) * self.period_s;
        let u = self.from.at(t - self.from_t_s);
        let law = &self.law;
        let motion = self.frame.motion(law.speed(t), law.a_mm_s2);
        sample_at(self.mv, t, self.line.jet(u).p, motion, law, Vec3::zeros())
    }
}

#[cfg(test)]
mod tests;
