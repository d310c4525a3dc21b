//! The lookahead queue: junction speeds (toolhead.py `Move.calc_junction`), the backward
//! and forward passes of `LookAheadQueue.flush`, and the trapezoids (`Move.set_junction`).
//!
//! Speeds are tracked squared (`_v2`, mm²/s²) as Klipper does. `delta_v2` = 2·d·accel is the
//! most the squared speed can change over a move.

use std::collections::VecDeque;

use crate::gcode::Move;
// The squared speeds are never NaN: plain comparisons, not `f64::min`'s NaN handling (1.1 %
// of a run's instructions, docs/performance.md, eighteenth session).
use crate::interval::{greater, lesser};
use crate::path::{Path, Vec3};

use super::PlannedMove;

/// toolhead.py `LOOKAHEAD_FLUSH_TIME`: a lazy flush is tried after this much (minimum)
/// move time has been queued since the last one.
const LOOKAHEAD_FLUSH_TIME_S: f64 = 0.150;
/// toolhead.py `BUFFER_TIME_HIGH`: the first lazy flush after the queue was emptied.
const BUFFER_TIME_HIGH_S: f64 = 1.0;
/// Default longest queue, moves. Past it the older half is planned as if the toolhead had
/// to stop at the end of the queue (see docs/planner.md, "Queue cap").
pub(super) const DEFAULT_MAX_QUEUE: usize = 16_384;

/// One move in the lookahead, with its limits.
///
/// A new move's limits are applied ([`Self::limit_speed`], `MoveLimits::limit_delta` and
/// `limit_extruder`) and its junction found ([`Self::calc_junction`]) by functions inlined
/// into the planner's step, so that it stays in registers until it is written into the
/// queue: with any of them called, it was built on the stack and copied into the queue by a
/// call to `memcpy` (0.6 % of an unshaped run's instructions, docs/performance.md).
#[derive(Clone, Copy, Debug)]
pub(super) struct QueuedMove {
    line: u64,
    path: Path,
    e_mm: f64,
    pub(super) kinematic: bool,
    pub(super) move_d_mm: f64,
    /// The path's unit direction (zero for an extrude-only move): once per move, where the
    /// junctions took it twice (as each move's and as the next one's predecessor), and the
    /// pieces once more (0.43 % of an unshaped run's instructions).
    dir: Vec3,
    pub(super) accel_mm_s2: f64,
    junction_deviation_mm: f64,
    pub(super) max_cruise_v2: f64,
    delta_v2: f64,
    mcr_delta_v2: f64,
    /// E / move_d: the extruder's axis ratio (±1 for an extrude-only move).
    pub(super) e_ratio: f64,
    /// The junction limit into this move from everything but the two acceleration chains
    /// (geometry, extruder, both cruise speeds); 0 when either move is not kinematic.
    junction_cap_v2: f64,
    max_start_v2: f64,
    max_mcr_start_v2: f64,
    min_move_t_s: f64,
}

impl QueuedMove {
    pub(super) fn new(
        m: &Move,
        kinematic: bool,
        move_d_mm: f64,
        velocity_mm_s: f64,
        accel_mm_s2: f64,
        junction_deviation_mm: f64,
        mcr_pseudo_accel_mm_s2: f64,
    ) -> Self {
        QueuedMove {
            line: m.line,
            path: m.path,
            e_mm: m.e_mm,
            kinematic,
            move_d_mm,
            dir: if kinematic {
                m.path.unit(move_d_mm)
            } else {
                Vec3::zeros()
            },
            accel_mm_s2,
            junction_deviation_mm,
            max_cruise_v2: velocity_mm_s * velocity_mm_s,
            delta_v2: 2.0 * move_d_mm * accel_mm_s2,
            mcr_delta_v2: 2.0 * move_d_mm * mcr_pseudo_accel_mm_s2,
            e_ratio: m.e_mm / move_d_mm,
            junction_cap_v2: 0.0,
            max_start_v2: 0.0,
            max_mcr_start_v2: 0.0,
            min_move_t_s: move_d_mm / velocity_mm_s,
        }
    }

    /// toolhead.py `Move.limit_speed`.
    #[inline(always)] // see `QueuedMove`
    pub(super) fn limit_speed(&mut self, speed_mm_s: f64, accel_mm_s2: f64) {
        let v2 = speed_mm_s * speed_mm_s;
        if v2 < self.max_cruise_v2 {
            self.max_cruise_v2 = v2;
            self.min_move_t_s = self.move_d_mm / speed_mm_s;
        }
        self.accel_mm_s2 = lesser(self.accel_mm_s2, accel_mm_s2);
        self.delta_v2 = 2.0 * self.move_d_mm * self.accel_mm_s2;
        self.mcr_delta_v2 = lesser(self.mcr_delta_v2, self.delta_v2);
    }

    /// toolhead.py `Move.calc_junction`. `icv` is the extruder's
    /// instantaneous_corner_velocity.
    #[inline(always)] // see `QueuedMove`
    fn calc_junction(&mut self, prev: &QueuedMove, icv_mm_s: f64) {
        self.junction_cap_v2 = if self.kinematic && prev.kinematic {
            self.geometric_cap_v2(prev, icv_mm_s)
        } else {
            0.0
        };
        self.chain(prev);
    }

    #[inline(always)] // see `QueuedMove`
    fn geometric_cap_v2(&self, prev: &QueuedMove, icv_mm_s: f64) -> f64 {
        // extruder.py calc_junction: a change of extrusion ratio is an instantaneous
        // change of extruder speed, capped by instantaneous_corner_velocity.
        let diff_r = self.e_ratio - prev.e_ratio;
        let extruder_v2 = if diff_r != 0.0 {
            (icv_mm_s / diff_r.abs()).powi(2)
        } else {
            self.max_cruise_v2
        };
        let mut cap = lesser(lesser(extruder_v2, self.max_cruise_v2), prev.max_cruise_v2);
        // The "approximated centripetal velocity" of a virtual arc of deviation
        // junction_deviation tangent to both moves; θ is the angle between the reversed
        // incoming direction and the outgoing one (π for a straight continuation).
        let cos_theta = -prev.dir.dot(&self.dir);
        let sin_half = greater(0.5 * (1.0 - cos_theta), 0.0).sqrt();
        let cos_half = greater(0.5 * (1.0 + cos_theta), 0.0).sqrt();
        let one_minus_sin_half = 1.0 - sin_half;
        if one_minus_sin_half > 0.0 && cos_half > 0.0 {
            let r_jd = sin_half / one_minus_sin_half;
            let move_jd_v2 = r_jd * self.junction_deviation_mm * self.accel_mm_s2;
            let prev_jd_v2 = r_jd * prev.junction_deviation_mm * prev.accel_mm_s2;
            // The virtual arc must touch each move no further than its middle:
            // v² ≤ ½·d·accel·tan(θ/2) = delta_v2·¼·tan(θ/2).
            let quarter_tan_half = 0.25 * sin_half / cos_half;
            let move_c_v2 = self.delta_v2 * quarter_tan_half;
            let prev_c_v2 = prev.delta_v2 * quarter_tan_half;
            cap = lesser(
                lesser(lesser(lesser(cap, move_jd_v2), prev_jd_v2), move_c_v2),
                prev_c_v2,
            );
        }
        cap
    }

    /// The acceleration chains: no faster at the start than the previous move could reach
    /// (at full accel, and at the minimum_cruise_ratio pseudo-accel).
    fn chain(&mut self, prev: &QueuedMove) {
        self.max_start_v2 = lesser(self.junction_cap_v2, prev.max_start_v2 + prev.delta_v2);
        self.max_mcr_start_v2 =
            lesser(self.max_start_v2, prev.max_mcr_start_v2 + prev.mcr_delta_v2);
    }

    /// toolhead.py `Move.set_junction`: the trapezoid through the three squared speeds.
    fn planned(&self, start_v2: f64, cruise_v2: f64, end_v2: f64, t0_s: f64) -> PlannedMove {
        let half_inv_accel = 0.5 / self.accel_mm_s2;
        let accel_d = (cruise_v2 - start_v2) * half_inv_accel;
        let decel_d = (cruise_v2 - end_v2) * half_inv_accel;
        // Rounding can leave a cruise of -1e-15 mm; a time is never negative.
        let cruise_d = greater(self.move_d_mm - accel_d - decel_d, 0.0);
        let (start_v, cruise_v, end_v) = (start_v2.sqrt(), cruise_v2.sqrt(), end_v2.sqrt());
        PlannedMove {
            line: self.line,
            path: self.path,
            e_mm: self.e_mm,
            kinematic: self.kinematic,
            distance_mm: self.move_d_mm,
            dir: self.dir,
            start_v_mm_s: start_v,
            cruise_v_mm_s: cruise_v,
            end_v_mm_s: end_v,
            accel_mm_s2: self.accel_mm_s2,
            accel_t_s: accel_d / ((start_v + cruise_v) * 0.5),
            cruise_t_s: cruise_d / cruise_v,
            decel_t_s: decel_d / ((end_v + cruise_v) * 0.5),
            t0_s,
        }
    }
}

/// What the backward pass found for one move.
#[derive(Clone, Copy, Debug, Default)]
struct Junctions {
    start_v2: f64,
    /// `None`: the move cannot accelerate; the forward pass gives it the previous cruise.
    cruise_v2: Option<f64>,
    next_start_v2: f64,
}

/// How much of the queue a flush plans and hands on.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Flush {
    /// Only the moves whose plan no later move can change.
    Lazy,
    /// Everything: the toolhead comes to rest after the last move.
    All,
    /// The older half, planned as if the toolhead stopped after the last queued move.
    OlderHalf,
}

/// The lookahead queue and the print time of the moves already handed on.
#[derive(Debug)]
pub(super) struct Lookahead {
    queue: VecDeque<QueuedMove>,
    /// Scratch space of the backward pass, reused between flushes.
    junctions: Vec<Junctions>,
    flush_budget_s: f64,
    /// Cruise speed² of the last move handed on, 0 after the toolhead came to rest.
    last_cruise_v2: f64,
    pub(super) max_queue: usize,
    /// Off only in tests: plan the whole input at once, the reference for the lazy flush.
    pub(super) lazy: bool,
    pub(super) print_time_s: f64,
    icv_mm_s: f64,
}

impl Lookahead {
    pub(super) fn new(icv_mm_s: f64) -> Self {
        Lookahead {
            queue: VecDeque::new(),
            junctions: Vec::new(),
            flush_budget_s: BUFFER_TIME_HIGH_S,
            last_cruise_v2: 0.0,
            max_queue: DEFAULT_MAX_QUEUE,
            lazy: true,
            print_time_s: 0.0,
            icv_mm_s,
        }
    }

    pub(super) fn len(&self) -> usize {
        self.queue.len()
    }

    /// toolhead.py `LookAheadQueue.add_move`, then a lazy flush when enough time is queued,
    /// and the cap.
    pub(super) fn add(&mut self, mut m: QueuedMove, out: &mut impl FnMut(PlannedMove)) {
        if let Some(prev) = self.queue.back() {
            m.calc_junction(prev, self.icv_mm_s);
            self.flush_budget_s -= m.min_move_t_s;
        }
        self.queue.push_back(m);
        if !self.lazy {
            return;
        }
        if self.flush_budget_s <= 0.0 {
            self.flush(Flush::Lazy, out);
        }
        if self.queue.len() >= self.max_queue {
            self.flush(Flush::OlderHalf, out);
        }
    }

    /// Plans and hands on every queued move; the toolhead ends at rest.
    pub(super) fn flush_all(&mut self, out: &mut impl FnMut(PlannedMove)) {
        self.flush(Flush::All, out);
        self.flush_budget_s = BUFFER_TIME_HIGH_S;
    }

    /// toolhead.py `LookAheadQueue.flush`. The backward pass finds each move's largest start
    /// speed assuming a stop after the last queued move; the forward pass gives the moves
    /// that cannot accelerate the cruise speed of the move before them.
    ///
    /// A lazy flush hands on the moves before a boundary that later moves can no longer
    /// change: Klipper's (a move whose minimum_cruise_ratio start is capped by its own
    /// limits, behind another peak), plus ours, that the boundary's real start speed is
    /// capped by its junction limit and not by how fast it could still decelerate.
    fn flush(&mut self, mode: Flush, out: &mut impl FnMut(PlannedMove)) {
        self.flush_budget_s = LOOKAHEAD_FLUSH_TIME_S;
        let n = self.queue.len();
        if n == 0 {
            return;
        }
        self.junctions.clear();
        self.junctions.resize(n, Junctions::default());
        let mut seeking = mode == Flush::Lazy;
        let mut flush_count = n;
        let (mut next_start_v2, mut next_mcr_start_v2, mut peak_cruise_v2) = (0.0, 0.0, 0.0);
        let mut pending = 0usize;
        let mut boundary_final = false;
        for i in (0..n).rev() {
            let m = &self.queue[i];
            let reachable_start_v2 = next_start_v2 + m.delta_v2;
            let start_v2 = lesser(m.max_start_v2, reachable_start_v2);
            let reach_mcr_start_v2 = next_mcr_start_v2 + m.mcr_delta_v2;
            let mcr_start_v2 = lesser(m.max_mcr_start_v2, reach_mcr_start_v2);
            pending += 1;
            let mut cruise_v2 = None;
            if mcr_start_v2 < reach_mcr_start_v2 {
                // This move can accelerate.
                if mcr_start_v2 + m.mcr_delta_v2 > next_mcr_start_v2 || pending > 1 {
                    // It can also decelerate, or it is a full accel after a full decel:
                    // a peak.
                    if seeking && peak_cruise_v2 > 0.0 && boundary_final {
                        flush_count = i + pending;
                        seeking = false;
                    }
                    peak_cruise_v2 = (mcr_start_v2 + reach_mcr_start_v2) * 0.5;
                }
                cruise_v2 = Some(lesser(
                    lesser((start_v2 + reachable_start_v2) * 0.5, m.max_cruise_v2),
                    peak_cruise_v2,
                ));
                pending = 0;
                boundary_final = m.max_start_v2 <= reachable_start_v2;
            }
            self.junctions[i] = Junctions {
                start_v2,
                cruise_v2,
                next_start_v2,
            };
            next_start_v2 = start_v2;
            next_mcr_start_v2 = mcr_start_v2;
        }
        match mode {
            Flush::Lazy if seeking => {}
            Flush::Lazy | Flush::All => {
                self.hand_on(flush_count, out);
            }
            Flush::OlderHalf => {
                let end_v2 = self.hand_on(n / 2, out);
                self.rejoin(end_v2);
            }
        }
    }

    /// The forward pass over the first `count` moves, which leave the queue. Returns the
    /// end speed² of the last one.
    fn hand_on(&mut self, count: usize, out: &mut impl FnMut(PlannedMove)) -> f64 {
        let mut prev_cruise_v2 = self.last_cruise_v2;
        let mut end_v2 = 0.0;
        for (m, j) in self.queue.iter().zip(&self.junctions).take(count) {
            let cruise_v2 = j.cruise_v2.unwrap_or(lesser(prev_cruise_v2, j.start_v2));
            end_v2 = lesser(j.next_start_v2, cruise_v2);
            let p = m.planned(
                lesser(j.start_v2, cruise_v2),
                cruise_v2,
                end_v2,
                self.print_time_s,
            );
            self.print_time_s += p.duration_s();
            out(p);
            prev_cruise_v2 = cruise_v2;
        }
        self.queue.drain(..count);
        self.last_cruise_v2 = if self.queue.is_empty() {
            0.0
        } else {
            prev_cruise_v2
        };
        end_v2
    }

    /// After a forced hand-on the next move must start no faster than the last one ended,
    /// and the acceleration chains that depend on it are recomputed. (A lazy boundary's
    /// start speed is final already.)
    fn rejoin(&mut self, end_v2: f64) {
        let Some(first) = self.queue.front_mut() else {
            return;
        };
        first.max_start_v2 = lesser(first.max_start_v2, end_v2);
        first.max_mcr_start_v2 = lesser(first.max_mcr_start_v2, end_v2);
        for i in 1..self.queue.len() {
            let prev = self.queue[i - 1];
            self.queue[i].chain(&prev);
        }
    }
}
