//! The planned pieces the shaper still looks at, with a cursor per pulse offset.
//!
//! The shaper asks, for each pulse, which planned piece is in force at t + τ and where the
//! next planned break after t + τ is, with t only growing (kin_shaper.c walks its trapq the
//! same way, `move_get_coord` moving from the last move it used). Each cursor therefore moves
//! forward by the pieces it passes instead of bisecting the window at every question: the
//! same answers as a bisection of the pieces in time order.

use std::collections::VecDeque;

use super::pulses::MAX_PULSES;
use crate::motion::Segment;

/// The most offsets looked up: the planned motion itself and every pulse of both axes.
pub const MAX_OFFSETS: usize = 1 + 2 * MAX_PULSES;

/// Planned pieces in time order, with a forward-only cursor per offset.
#[derive(Default)]
pub struct Window {
    pieces: VecDeque<Segment>,
    /// The count of pieces ever dropped: a cursor is an index into everything ever pushed.
    dropped: usize,
    /// Per offset: the first piece that started after the last `next_start` question.
    starts: [usize; MAX_OFFSETS],
    /// Per offset: the first piece that ended after the last `in_force` question.
    ends: [usize; MAX_OFFSETS],
}

impl Window {
    pub fn push(&mut self, seg: Segment) {
        self.pieces.push_back(seg);
    }

    pub fn front(&self) -> Option<&Segment> {
        self.pieces.front()
    }

    pub fn back(&self) -> Option<&Segment> {
        self.pieces.back()
    }

    pub fn len(&self) -> usize {
        self.pieces.len()
    }

    pub fn get(&self, i: usize) -> Option<&Segment> {
        self.pieces.get(i)
    }

    pub fn pop_front(&mut self) {
        if self.pieces.pop_front().is_some() {
            self.dropped += 1;
        }
    }

    /// Drops every piece; the questions start again from the next piece pushed.
    pub fn clear(&mut self) {
        self.dropped += self.pieces.len();
        self.pieces.clear();
        self.starts = [self.dropped; MAX_OFFSETS];
        self.ends = [self.dropped; MAX_OFFSETS];
    }

    /// The index (in the window) of the first piece starting after `t`, asked for offset
    /// `k` with `t` never smaller than at its last question (since the last `clear`).
    pub fn next_start(&mut self, k: usize, t: f64) -> usize {
        let mut i = self.starts[k].max(self.dropped) - self.dropped;
        while self.pieces.get(i).is_some_and(|s| s.t0_s <= t) {
            i += 1;
        }
        self.starts[k] = i + self.dropped;
        i
    }

    /// The index of the first piece ending after `t` (the piece in force at `t` if it has
    /// started), asked for offset `k` with `t` never decreasing, as for `next_start`.
    pub fn in_force(&mut self, k: usize, t: f64) -> usize {
        let mut i = self.ends[k].max(self.dropped) - self.dropped;
        while self.pieces.get(i).is_some_and(|s| s.t1_s() <= t) {
            i += 1;
        }
        self.ends[k] = i + self.dropped;
        i
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::motion::Phase;
    use crate::path::Vec3;

    fn piece(t0_s: f64, dt_s: f64) -> Segment {
        Segment {
            t0_s,
            dt_s,
            p: Vec3::zeros(),
            v: Vec3::zeros(),
            a: Vec3::zeros(),
            line: 0,
            phase: Phase::Cruise,
        }
    }

    /// Every answer of the cursors is the bisection's, over pushes, drops and a clear.
    #[test]
    fn cursors_answer_as_a_bisection_does() {
        let mut w = Window::default();
        let mut t0 = 0.0;
        let push = |w: &mut Window, t0: &mut f64, n: usize| {
            for i in 0..n {
                let dt = 0.001 * (1 + (i * 7) % 5) as f64;
                w.push(piece(*t0, dt));
                *t0 += dt;
            }
        };
        push(&mut w, &mut t0, 40);
        let bisect_start = |w: &Window, t: f64| w.pieces.partition_point(|s| s.t0_s <= t);
        let bisect_end = |w: &Window, t: f64| w.pieces.partition_point(|s| s.t1_s() <= t);
        let offsets = [0.0, -0.004, 0.0031, 0.012];
        let mut t = -0.01;
        let mut checked = 0;
        while t < t0 + 0.02 {
            for (k, tau) in offsets.iter().enumerate() {
                assert_eq!(
                    w.next_start(k, t + tau),
                    bisect_start(&w, t + tau),
                    "{t} {tau}"
                );
                assert_eq!(w.in_force(k, t + tau), bisect_end(&w, t + tau), "{t} {tau}");
                checked += 1;
            }
            if w.front().is_some_and(|s| s.t1_s() < t - 0.005) {
                w.pop_front();
            }
            if checked == 200 {
                push(&mut w, &mut t0, 20);
            }
            t += 0.00037;
        }
        assert!(w.dropped > 10, "{}", w.dropped);
        w.clear();
        push(&mut w, &mut t0, 3);
        assert_eq!(w.len(), 3);
        assert_eq!(w.next_start(0, t0 - 0.5), bisect_start(&w, t0 - 0.5));
    }
}
