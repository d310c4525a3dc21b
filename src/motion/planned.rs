//! The planned motion as pieces: each planned move's trapezoid, a piece per phase, along
//! its straight line; a rest wherever the toolhead waits (an extrude-only move, a dwell).

use super::{Phase, PhaseChanges, Segment};
use crate::firmware::klipper::planner::PlannedMove;
use crate::path::Vec3;

/// Planned moves in, in time order; the planned motion out as contiguous pieces.
#[derive(Clone, Debug, Default)]
pub struct PlannedPieces {
    /// The end of the last move handed in, and its line.
    last: Option<(f64, Vec3, u64)>,
}

impl PlannedPieces {
    pub fn new() -> Self {
        Self::default()
    }

    /// The pieces of `mv`, after a rest filling any time since the previous move.
    pub fn push(&mut self, mv: &PlannedMove, out: &mut impl FnMut(Segment)) {
        let start = mv.path.start();
        if let Some((t_end, p_end, line)) = self.last
            && mv.t0_s > t_end
            && p_end == start
        {
            out(Segment::rest(t_end, mv.t0_s - t_end, p_end, line));
        }
        self.last = Some((mv.t0_s + mv.duration_s(), mv.path.end(), mv.line));
        if !mv.kinematic {
            if mv.duration_s() > 0.0 {
                out(Segment::rest(mv.t0_s, mv.duration_s(), start, mv.line));
            }
            return;
        }
        let dir = mv.dir;
        let a = mv.accel_mm_s2;
        let mut t = mv.t0_s;
        let mut s = 0.0;
        for (dt, v0, acc, phase) in [
            (mv.accel_t_s, mv.start_v_mm_s, a, Phase::Accel),
            (mv.cruise_t_s, mv.cruise_v_mm_s, 0.0, Phase::Cruise),
            (mv.decel_t_s, mv.cruise_v_mm_s, -a, Phase::Decel),
        ] {
            if dt > 0.0 {
                out(Segment {
                    t0_s: t,
                    dt_s: dt,
                    p: start + dir * s,
                    v: dir * v0,
                    a: dir * acc,
                    line: mv.line,
                    phase,
                    later_phases: PhaseChanges::NO_PHASES,
                    changes: PhaseChanges::NONE,
                });
                s += v0 * dt + 0.5 * acc * dt * dt;
                t += dt;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::path::Path;

    fn mv(line: u64, from: Vec3, to: Vec3, t0: f64, v: [f64; 3], a: f64) -> PlannedMove {
        let d = (to - from).norm();
        let (ta, td) = ((v[1] - v[0]) / a, (v[1] - v[2]) / a);
        let (da, dd) = (
            (v[1] * v[1] - v[0] * v[0]) / (2.0 * a),
            (v[1] * v[1] - v[2] * v[2]) / (2.0 * a),
        );
        PlannedMove {
            line,
            path: Path::line(from, to),
            e_mm: 0.0,
            kinematic: true,
            distance_mm: d,
            dir: (to - from) / d,
            start_v_mm_s: v[0],
            cruise_v_mm_s: v[1],
            end_v_mm_s: v[2],
            accel_mm_s2: a,
            accel_t_s: ta,
            cruise_t_s: (d - da - dd) / v[1],
            decel_t_s: td,
            t0_s: t0,
        }
    }

    #[test]
    fn a_trapezoid_is_three_pieces_that_meet_and_end_on_the_line() {
        let (from, to) = (Vec3::new(0.0, 0.0, 1.0), Vec3::new(30.0, 40.0, 1.0));
        let m = mv(5, from, to, 0.5, [0.0, 100.0, 20.0], 2000.0);
        let mut pieces = Vec::new();
        PlannedPieces::new().push(&m, &mut |s| pieces.push(s));
        assert_eq!(pieces.len(), 3);
        for w in pieces.windows(2) {
            let (p, v) = w[0].end();
            assert!((p - w[1].p).norm() < 1e-12 && (v - w[1].v).norm() < 1e-12);
            assert!((w[0].t1_s() - w[1].t0_s).abs() < 1e-15);
        }
        let last = pieces[2];
        let (p, v) = last.end();
        assert!((p - to).norm() < 1e-9, "{p}");
        assert!((v.norm() - 20.0).abs() < 1e-9);
        assert!((last.t1_s() - (m.t0_s + m.duration_s())).abs() < 1e-15);
    }

    #[test]
    fn a_dwell_is_a_rest_and_an_extrude_only_move_stands_still() {
        let (a, b) = (Vec3::zeros(), Vec3::new(10.0, 0.0, 0.0));
        let first = mv(1, a, b, 0.0, [0.0, 50.0, 0.0], 5000.0);
        let t1 = first.duration_s();
        let retract = PlannedMove {
            line: 2,
            path: Path::line(b, b),
            kinematic: false,
            t0_s: t1 + 0.25,
            ..mv(2, a, b, 0.0, [0.0, 30.0, 0.0], 1000.0)
        };
        let mut pieces = Vec::new();
        let mut planned = PlannedPieces::new();
        planned.push(&first, &mut |s| pieces.push(s));
        planned.push(&retract, &mut |s| pieces.push(s));
        let rests: Vec<&Segment> = pieces.iter().filter(|s| s.phase == Phase::Rest).collect();
        assert_eq!(rests.len(), 2);
        assert_eq!((rests[0].t0_s, rests[0].dt_s, rests[0].line), (t1, 0.25, 1));
        assert_eq!(rests[1].t0_s, t1 + 0.25);
        assert_eq!(rests[1].p, b);
    }
}
