//! The planned pieces the shaper still looks at, with a cursor per pulse offset.
//!
//! The shaper asks, for each pulse, which planned piece is in force at t + τ and where the
//! next planned break after t + τ is, with t only growing (kin_shaper.c walks its trapq the
//! same way, `move_get_coord` moving from the last move it used). Each cursor therefore moves
//! forward by the pieces it passes instead of bisecting the window at every question: the
//! same answers as a bisection of the pieces in time order.

use super::MIN_PIECE_S;
use super::pulses::MAX_PULSES;
use crate::motion::{MAX_PHASE_CHANGES, Phase, PhaseChanges, Segment};
use crate::path::Vec3;

/// Dropped pieces are removed from the vector once there are at least this many.
const COMPACT_MIN: usize = 64;

/// The most offsets looked up: the planned motion itself and every pulse of both axes.
pub const MAX_OFFSETS: usize = 1 + 2 * MAX_PULSES;

/// Planned pieces in time order, with a forward-only cursor per offset. An index it
/// hands out is into its pieces, valid until the next [`Self::pop_front`] or
/// [`Self::clear`].
pub struct Window {
    /// The pieces from `head` on; those before it are dropped, and removed from the vector
    /// a batch at a time ([`Self::pop_front`]): indexing stays a plain slice lookup, where a
    /// ring buffer's wraps around at every question.
    pieces: Vec<Segment>,
    /// Each piece's start and end, apart: the cursors walk these, 16 bytes a piece where a
    /// `Segment` is 104.
    times: Vec<[f64; 2]>,
    /// Whether each piece runs on from the one before for the axes the shaper leaves as
    /// planned (`Shaper::runs_on`): its start breaks no commanded axis.
    runs_on: Vec<bool>,
    head: usize,
    /// The first piece's end while a later piece is pushed, else +∞: the shaper's drop
    /// test at each commanded piece is one comparison, not a count, a lookup and its
    /// check (−0.9 % of a shaped run's instructions).
    droppable_before_s: f64,
    /// Per offset: the first piece that started after the last `next_start` question.
    starts: [usize; MAX_OFFSETS],
}

impl Default for Window {
    fn default() -> Window {
        Window {
            pieces: Vec::new(),
            times: Vec::new(),
            runs_on: Vec::new(),
            head: 0,
            droppable_before_s: f64::INFINITY,
            starts: [0; MAX_OFFSETS],
        }
    }
}

impl Window {
    /// Adds the next piece, which runs on from the last or not (`runs_on`).
    pub fn push(&mut self, seg: Segment, runs_on: bool) {
        self.times.push([seg.t0_s, seg.t1_s()]);
        self.runs_on.push(runs_on);
        self.pieces.push(seg);
        if self.len() == 2 {
            self.droppable_before_s = self.times[self.head][1];
        }
    }

    /// Whether the piece at `i` runs on from the one before (None past the last).
    #[inline(always)]
    pub fn runs_on(&self, i: usize) -> Option<bool> {
        self.runs_on.get(i).copied()
    }

    /// The start of the piece at `i`, or past the last the last one's end if it lies
    /// after `t` (else +∞): the planned motion's next break after `t`, `i` being the
    /// first piece starting after it.
    #[inline(always)]
    pub fn start_or_end(&self, i: usize, t: f64) -> f64 {
        match self.times.get(i) {
            Some(s) => s[0],
            None => (self.head < self.times.len())
                .then(|| self.times[self.times.len() - 1][1])
                .filter(|&b| b > t)
                .unwrap_or(f64::INFINITY),
        }
    }

    /// The starts of the pieces after `i` before `t`, with their phases: each runs on
    /// from the one before, and there are at most [`MAX_PHASE_CHANGES`] of them
    /// (`Shaper::next_break` breaks at the next). A start less than `MIN_PIECE_S` before
    /// the next (or `t`) is left out, as the shaper leaves out such a piece.
    #[inline(always)]
    pub fn changes(&self, i: usize, t: f64) -> (PhaseChanges, [Phase; MAX_PHASE_CHANGES]) {
        let mut changes = PhaseChanges::NONE;
        let mut phases = PhaseChanges::NO_PHASES;
        let mut n = 0;
        let after = self.pieces.get(i + 1..).unwrap_or_default();
        let mut starts = after.iter().take_while(|s| s.t0_s < t).peekable();
        while let Some(s) = starts.next() {
            let next = starts.peek().map_or(t, |s| s.t0_s);
            if next - s.t0_s > MIN_PIECE_S && n < MAX_PHASE_CHANGES {
                (changes.at_s[n], phases[n]) = (s.t0_s, s.phase);
                n += 1;
            }
        }
        (changes, phases)
    }

    fn live(&self) -> &[Segment] {
        &self.pieces[self.head..]
    }

    pub fn front(&self) -> Option<&Segment> {
        self.live().first()
    }

    pub fn back(&self) -> Option<&Segment> {
        self.live().last()
    }

    pub fn len(&self) -> usize {
        self.pieces.len() - self.head
    }

    /// Drops the first pieces while they end before `t` and a later one follows.
    #[inline(always)]
    pub fn drop_ended_before(&mut self, t: f64) {
        while self.droppable_before_s < t {
            self.pop_front();
        }
    }

    fn pop_front(&mut self) {
        if self.head < self.pieces.len() {
            self.head += 1;
            self.droppable_before_s = match self.len() {
                2.. => self.times[self.head][1],
                _ => f64::INFINITY,
            };
            // The dropped pieces go once they are as many as the live ones: each piece is
            // moved at most once on average.
            if self.head >= COMPACT_MIN && self.head >= self.len() {
                self.compact();
            }
        }
    }

    /// Removes the dropped pieces from the vectors. Out of line: inlined, its setup (the
    /// cursors copied aside) ran at every commanded piece, where the shaper asks whether to
    /// drop one (−1.2 % of a shaped run's instructions, docs/performance.md).
    #[cold]
    #[inline(never)]
    fn compact(&mut self) {
        self.pieces.drain(..self.head);
        self.times.drain(..self.head);
        self.runs_on.drain(..self.head);
        for c in &mut self.starts {
            *c = c.saturating_sub(self.head);
        }
        self.head = 0;
    }

    /// Drops every piece; the questions start again from the next piece pushed.
    pub fn clear(&mut self) {
        self.pieces.clear();
        self.times.clear();
        self.runs_on.clear();
        self.head = 0;
        self.droppable_before_s = f64::INFINITY;
        self.starts = [0; MAX_OFFSETS];
    }

    /// The index of the first piece starting after `t`, asked for offset `k` with `t`
    /// never smaller than at its last question (since the last `clear`).
    #[inline(always)]
    pub fn next_start(&mut self, k: usize, t: f64) -> usize {
        let mut i = self.starts[k].max(self.head);
        while self.times.get(i).is_some_and(|s| s[0] <= t) {
            i += 1;
        }
        self.starts[k] = i;
        i
    }

    /// The piece in force at `t` for offset `k`, with its index: the last one started by then,
    /// None before the first or after the last has ended. Between two pieces it is the
    /// earlier one: inside the window pieces touch, but a move's pieces end where their
    /// durations' sum says, and the next move starts where its own duration says, an ulp
    /// or so apart, and the earlier piece holds there to within rounding (a rest there
    /// instead, from the window's end, made a spurious jump of the commanded motion).
    ///
    /// No search: `k`'s [`Self::next_start`] cursor must have been asked last for a time
    /// at or before `t` with no piece starting in between, as the shaper asks it right after
    /// its breaks (`Shaper::next_break`), whose cursors move only there. (Pieces that start
    /// in between, for the offset 0 the starts a commanded piece runs on through, leave the
    /// answer the piece in force at the time last asked.)
    #[inline(always)]
    pub fn planned_at(&self, k: usize, t: f64) -> Option<(usize, &Segment)> {
        self.in_force(self.starts[k], t)
    }

    /// Whether offset `k`'s cursor has passed every piece's start.
    #[inline(always)]
    pub fn passed_all(&self, k: usize) -> bool {
        self.starts[k] >= self.pieces.len()
    }

    /// The cursors of `n` offsets from `first` on.
    #[inline(always)]
    pub fn cursors(&self, first: usize, n: usize) -> &[usize] {
        &self.starts[first..first + n]
    }

    /// [`Self::planned_at`] for the offset whose cursor is `next`: the piece's index and
    /// the piece.
    #[inline(always)]
    pub fn in_force(&self, next: usize, t: f64) -> Option<(usize, &Segment)> {
        if next <= self.head {
            return None;
        }
        // A piece starts later: the one before holds until then (branches, not one
        // condition: the common case first, 1.9 % fewer instructions of a shaped run).
        // The pieces' count, not the times' (the same): then the piece's lookup needs no
        // second bounds check (with the one test of the live pieces in `state`, −0.5 % of a
        // shaped run's instructions, docs/performance.md). The piece is looked up in each
        // branch and handed out, not its index looked up again where the branches join,
        // which LLVM checked again (−0.43 %).
        let len = self.pieces.len();
        if next < len {
            return Some((next - 1, &self.pieces[next - 1]));
        }
        // The last piece, if it still holds: its end from the piece, not from the times,
        // whose lookup LLVM checked (the pulse of the largest offset takes this branch at
        // nearly every commanded piece: −0.38 % of a shaped run's instructions).
        if next > len {
            return None;
        }
        let last = &self.pieces[next - 1];
        (last.t1_s() > t).then_some((next - 1, last))
    }

    /// Position, velocity and acceleration at `t` on the piece in force (extended as a
    /// polynomial), or at rest before the first / after the last piece (Klipper's trapq).
    #[inline(always)]
    pub fn state(&self, in_force: Option<(usize, &Segment)>, t: f64) -> (Vec3, Vec3, Vec3) {
        match in_force {
            Some((_, s)) => s.at(t - s.t0_s),
            None => {
                let rest = |p: Vec3| (p, Vec3::zeros(), Vec3::zeros());
                // One test of the live pieces, not two Options: the shaper makes it once per
                // commanded piece, outside its pulses' loop.
                match self.live() {
                    [first, ..] if t < first.t0_s => rest(first.p),
                    [.., last] => rest(last.end().0),
                    [] => rest(Vec3::zeros()),
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::motion::{Phase, PhaseChanges};

    fn piece(t0_s: f64, dt_s: f64) -> Segment {
        Segment {
            t0_s,
            dt_s,
            p: Vec3::zeros(),
            v: Vec3::zeros(),
            a: Vec3::zeros(),
            line: 0,
            phase: Phase::Cruise,
            later_phases: PhaseChanges::NO_PHASES,
            changes: PhaseChanges::NONE,
        }
    }

    /// Every answer of the cursors is the bisection's, over pushes (each batch after a gap
    /// in time), drops and a clear: the first piece starting after a time, and the piece in
    /// force at that time and at a later one before the next start (in a gap, the piece
    /// before it).
    #[test]
    fn cursors_answer_as_a_bisection_does() {
        let mut w = Window::default();
        let mut t0 = 0.0;
        let push = |w: &mut Window, t0: &mut f64, n: usize| {
            *t0 += 0.0023;
            for i in 0..n {
                let dt = 0.001 * (1 + (i * 7) % 5) as f64;
                w.push(piece(*t0, dt), false);
                *t0 += dt;
            }
        };
        push(&mut w, &mut t0, 40);
        let bisect_start = |w: &Window, t: f64| w.head + w.live().partition_point(|s| s.t0_s <= t);
        let bisect_in_force = |w: &Window, t: f64| {
            let i = (w.head + w.live().partition_point(|s| s.t0_s <= t)).checked_sub(1)?;
            let last = i + 1 == w.pieces.len();
            (i >= w.head && !(last && w.pieces[i].t1_s() <= t)).then_some(i)
        };
        let offsets = [0.0, -0.004, 0.0031, 0.012];
        let mut t = -0.01;
        let (mut checked, mut compactions, mut dropped) = (0, 0, 0);
        let (mut in_force, mut gaps) = (0, 0);
        while t < t0 + 0.02 {
            for (k, tau) in offsets.iter().enumerate() {
                assert_eq!(
                    w.next_start(k, t + tau),
                    bisect_start(&w, t + tau),
                    "{t} {tau}"
                );
                let i = w.next_start(k, t + tau);
                let next = w.pieces.get(i).map_or(t0 + 1.0, |s| s.t0_s);
                for at in [t + tau, 0.5 * (t + tau + next)] {
                    assert_eq!(
                        w.planned_at(k, at).map(|(i, _)| i),
                        bisect_in_force(&w, at),
                        "{t} {tau} {at}"
                    );
                    let before = w.planned_at(k, at).map(|(_, s)| s);
                    in_force += usize::from(before.is_some());
                    gaps += usize::from(before.is_some_and(|s| s.t1_s() <= at));
                }
                checked += 1;
            }
            if w.front().is_some_and(|s| s.t1_s() < t - 0.005) {
                let head = w.head;
                w.pop_front();
                dropped += 1;
                compactions += usize::from(w.head < head);
            }
            // Pieces keep coming for a while: the dropped ones are removed from the vector
            // several times.
            if checked % 200 == 0 && checked <= 4000 {
                push(&mut w, &mut t0, 20);
            }
            t += 0.00037;
        }
        assert!(dropped > 3 * COMPACT_MIN, "{dropped}");
        assert!(compactions > 2, "{compactions}");
        assert!(
            in_force > 1000 && gaps > 10,
            "{in_force} in force, {gaps} in gaps"
        );
        w.clear();
        push(&mut w, &mut t0, 3);
        assert_eq!(w.len(), 3);
        assert_eq!(w.next_start(0, t0 - 0.5), bisect_start(&w, t0 - 0.5));
    }
}
