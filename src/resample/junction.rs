//! The velocity jumps at a move's junctions, as the rigid model samples them: each jump
//! spread evenly over a box around its junction (see `sample_move`).

use crate::path::Vec3;
use crate::planner::PlannedMove;

/// The end of the span `mv` owns and its junction impulses (see `sample_move`).
pub(super) fn span(
    prev: Option<&PlannedMove>,
    mv: &PlannedMove,
    next: Option<&PlannedMove>,
    period_s: f64,
) -> (f64, Kicks) {
    let t_end = next.map_or(mv.t0_s + mv.duration_s(), |n| n.t0_s);
    let half = |d: f64| 0.5 * d.max(0.0).min(period_s);
    let own = half(t_end - mv.t0_s);
    // The start junction's box reaches `own` into this move, the end junction's `own` back.
    let start_dv = start_velocity(mv) - prev.map_or(Vec3::zeros(), end_velocity);
    let start_kick = impulse_density(start_dv, prev.map_or(0.0, |p| half(p.duration_s())) + own);
    let end_dv = next.map_or(Vec3::zeros(), start_velocity) - end_velocity(mv);
    let end_kick = impulse_density(end_dv, own + next.map_or(0.0, |n| half(n.duration_s())));
    let kicks = Kicks {
        start: start_kick,
        end: end_kick,
        calm_from_s: mv.t0_s + own,
        calm_to_s: t_end - own,
    };
    (t_end, kicks)
}

/// The junction impulses of a move: `start` before `calm_from_s`, `end` from `calm_to_s`
/// on, none in between.
#[derive(Clone, Copy)]
pub(super) struct Kicks {
    start: Vec3,
    end: Vec3,
    pub(super) calm_from_s: f64,
    pub(super) calm_to_s: f64,
}

impl Kicks {
    /// The acceleration the impulses add at time `t`.
    #[inline(always)]
    pub(super) fn at(&self, t: f64) -> Vec3 {
        if t < self.calm_from_s {
            self.start
        } else if t >= self.calm_to_s {
            self.end
        } else {
            Vec3::zeros()
        }
    }
}

/// A velocity jump spread evenly over `width_s`: the acceleration it adds (none over a
/// zero width, where there is no move to spread it over).
fn impulse_density(dv: Vec3, width_s: f64) -> Vec3 {
    if width_s > 0.0 {
        dv / width_s
    } else {
        Vec3::zeros()
    }
}

/// Velocity vector of the nozzle at the start of a move (zero for an extrude-only move).
fn start_velocity(m: &PlannedMove) -> Vec3 {
    if m.kinematic {
        m.path.start_dir() * m.start_v_mm_s
    } else {
        Vec3::zeros()
    }
}

/// Velocity vector of the nozzle at the end of a move (zero for an extrude-only move).
fn end_velocity(m: &PlannedMove) -> Vec3 {
    if m.kinematic {
        m.path.end_dir() * m.end_v_mm_s
    } else {
        Vec3::zeros()
    }
}
