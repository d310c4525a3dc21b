//! Klipper's input shaper: the commanded X and Y of the nozzle are weighted sums of the
//! planned X and Y at a few time offsets (klippy/chelper/kin_shaper.c), with the shapers of
//! klippy/extras/shaper_defs.py. Z is not shaped.
//!
//! The planned motion is a chain of quadratics in time, and so is every shifted copy of it:
//! the commanded motion is again a chain of quadratics, whose breaks are the planned breaks
//! shifted by each pulse's offset. [`Shaper`] computes it as a stream.

mod pulses;
mod window;

pub use pulses::{
    AxisShaper, DEFAULT_SHAPER_DAMPING_RATIO, InputShaper, Pulses, ShaperChange, ShaperType,
};

use super::{CONTINUITY_MM, JUMP_MIN_MM_S, MAX_PHASE_CHANGES, Phase, PhaseChanges, Segment};
use crate::interval::lesser;
use crate::path::Vec3;
use window::Window;

/// A commanded piece no longer than this is left out, s: two breaks a rounding apart.
const MIN_PIECE_S: f64 = 1e-12;

/// [`Shaper::slack`] per second of the times' magnitude: 10⁻¹⁵ > 4 · 2⁻⁵³ (four roundings).
const SLACK_PER_S: f64 = 1e-15;

/// The commanded motion of a planned one, as a stream: planned pieces in, commanded pieces
/// out as soon as no later planned piece can change them. The motion before the first and
/// after the last planned piece is a rest where they start and end (Klipper's trapq).
pub struct Shaper {
    axes: [Pulses; 2],
    /// Whether each axis is shaped (its pulses are not the identity).
    shaped: [bool; 2],
    /// Both axes have the same pulses.
    same: bool,
    /// The smallest and largest offset of any pulse.
    tau_lo: f64,
    tau_hi: f64,
    /// Planned pieces still needed (the last one's end is known).
    planned: Window,
    /// Each axis's first lookup slot in `planned`, its pulses' slots that one and the next
    /// ones (0 is the planned motion itself): X's pulses, then Y's (Y's are X's when both
    /// axes have the same shaper).
    slots: [usize; 2],
    /// The slots `next_break` asks: 0 and the pulses of each distinct shaper.
    break_slots: usize,
    /// Each slot's offset, s.
    offsets: [f64; window::MAX_OFFSETS],
    /// Each slot's last answer of [`Self::next_break`], less the slot's offset: the
    /// commanded break b − τ of a planned break b (or infinity for none), still the answer
    /// while b lies beyond the time asked and, if it was no planned start, no piece came
    /// since; −∞ when it must be asked again.
    breaks: [f64; window::MAX_OFFSETS],
    /// Commanded motion is out up to here.
    t_out: f64,
    /// The part of [`Self::slack`] that does not grow with time: twice the 1e-12 after
    /// t + τ in [`Self::next_break`], and the roundings of magnitude |τ|.
    slack_s: f64,
    /// No piece has come since the start or the last re-homing.
    fresh: bool,
    /// A new configuration, for the pieces after the next one.
    pending: Option<InputShaper>,
}

impl Shaper {
    pub fn new(shaper: &InputShaper) -> Shaper {
        let axes = [Pulses::of(shaper.x), Pulses::of(shaper.y)];
        let tau_lo = axes[0].span_s().0.min(axes[1].span_s().0);
        let tau_hi = axes[0].span_s().1.max(axes[1].span_s().1);
        let mut slots = [0; 2];
        let mut offsets = [0.0; window::MAX_OFFSETS];
        let mut break_slots = 1;
        for axis in 0..2 {
            if axis == 1 && axes[0] == axes[1] {
                slots[1] = slots[0];
                break;
            }
            slots[axis] = break_slots;
            for (_, tau) in axes[axis].iter() {
                offsets[break_slots] = tau;
                break_slots += 1;
            }
        }
        Shaper {
            axes,
            shaped: axes.map(|p| p != Pulses::IDENTITY),
            same: axes[0] == axes[1],
            tau_lo,
            tau_hi,
            planned: Window::default(),
            slots,
            break_slots,
            offsets,
            breaks: [f64::NEG_INFINITY; window::MAX_OFFSETS],
            t_out: f64::NEG_INFINITY,
            slack_s: 2e-12 + SLACK_PER_S * (tau_hi - tau_lo),
            fresh: true,
            pending: None,
        }
    }

    /// Shapes the pieces from the next one on with `shaper` (SET_INPUT_SHAPER; the toolhead
    /// is at rest). The motion so far ends as the old shaper has it, until the new one
    /// starts.
    pub fn reconfigure(&mut self, shaper: &InputShaper) {
        self.pending = Some(*shaper);
    }

    /// Whether the commanded motion is the planned one.
    pub fn is_identity(&self) -> bool {
        self.shaped == [false; 2]
    }

    /// Whether [`Self::push`] hands each planned piece on as it is, now and for the next
    /// piece (no shaper, none pending).
    pub fn passes_through(&self) -> bool {
        self.pending.is_none() && self.is_identity()
    }

    /// Takes the next planned piece; hands on the commanded pieces now final. A piece that
    /// does not start where the last ended (a re-homing) ends the motion so far first.
    pub fn push(&mut self, seg: Segment, out: &mut impl FnMut(Segment)) {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU has AVX2, checked just above.
            return unsafe { self.push_avx2(seg, out) };
        }
        self.push_baseline(seg, out)
    }

    /// [`Self::push_generic`] for any x86-64, out of line: the check above and a call are
    /// then all that [`Self::push`] is, and the closure that calls it for each planned
    /// piece is inlined where the pieces are made, not called with a copy of each (−0.43 %
    /// of a shaped run's instructions, docs/performance.md).
    #[inline(never)]
    fn push_baseline(&mut self, seg: Segment, out: &mut impl FnMut(Segment)) {
        self.push_generic(seg, out)
    }

    /// [`Self::push_generic`] compiled for AVX2: the planned pieces' three axes in one
    /// register instead of two (−1.9 % of a shaped run's instructions, docs/performance.md).
    /// The same operations in the same order (Rust fuses no multiply-add unasked), so the
    /// same pieces bit for bit (test `avx2_shapes_as_the_baseline`).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn push_avx2(&mut self, seg: Segment, out: &mut impl FnMut(Segment)) {
        self.push_generic(seg, out)
    }

    /// [`Self::push`]'s work.
    #[inline(always)]
    fn push_generic(&mut self, seg: Segment, out: &mut impl FnMut(Segment)) {
        if let Some(new) = self.pending.take() {
            let next = Shaper::new(&new);
            self.finish_until(seg.t0_s - next.tau_hi, out);
            *self = next;
        }
        if self.is_identity() {
            out(seg);
            return;
        }
        // The last piece's end, found once for both questions (−0.6 % of a shaped run's
        // instructions, docs/performance.md).
        let mut runs_on = false;
        if let Some(last) = self.planned.back() {
            let end = last.end();
            if (seg.p - end.0).norm() > CONTINUITY_MM {
                self.finish_until(seg.t0_s, out);
            } else {
                runs_on = self.runs_on(last, end, &seg);
            }
        }
        if self.fresh {
            // The motion shaped from a rest starts when the last pulse first sees it.
            self.t_out = seg.t0_s - self.tau_hi;
            self.fresh = false;
        }
        let known_s = seg.t1_s();
        // A slot without a later planned start saw the end of the last piece, or nothing:
        // it must be asked again. The others' breaks, planned starts, stay.
        for slot in 1..self.break_slots {
            if self.planned.passed_all(slot) {
                self.breaks[slot] = f64::NEG_INFINITY;
            }
        }
        self.planned.push(seg, runs_on);
        self.emit_until(known_s - self.tau_hi, out);
    }

    /// The end of the planned motion: hands on the rest of the commanded motion, until the
    /// first pulse has seen the final rest.
    pub fn finish(&mut self, out: &mut impl FnMut(Segment)) {
        self.finish_until(f64::INFINITY, out);
    }

    /// Ends the motion so far, at the latest at `t_limit_s` (the start of what follows).
    fn finish_until(&mut self, t_limit_s: f64, out: &mut impl FnMut(Segment)) {
        if let Some(last) = self.planned.back() {
            let end = (last.t1_s() - self.tau_lo).min(t_limit_s);
            self.emit_until(end, out);
        }
        self.planned.clear();
        self.breaks = [f64::NEG_INFINITY; window::MAX_OFFSETS];
        self.fresh = true;
    }

    /// Hands on the commanded motion from `t_out` to `t_end`, a piece between each two
    /// consecutive breaks.
    #[inline(always)]
    fn emit_until(&mut self, t_end: f64, out: &mut impl FnMut(Segment)) {
        let slack = self.slack(t_end);
        while self.t_out < t_end {
            let ta = self.t_out;
            let (next, runs_on) = self.next_break(ta, slack);
            let tb = lesser(next, t_end);
            if tb - ta > MIN_PIECE_S {
                out(self.piece(ta, tb, runs_on));
            }
            self.t_out = tb;
            self.drop_unneeded();
        }
    }

    /// The first break of the commanded motion after `t` (never smaller than at the last
    /// call): a planned break b seen by a pulse of offset τ is at b − τ; the planned breaks
    /// themselves (offset 0) break the unshaped axes, and name the line and its phase.
    ///
    /// A pulse's break is found again only once `t` has passed it (or a piece came when it
    /// was the end of the last): the first planned start after t + τ is still the one found
    /// for an earlier t as long as it lies beyond t + τ, since the starts before it lay
    /// before the earlier t + τ, and a piece that comes starts after it. Asking again only
    /// those slots (not all at each piece that comes), the bookkeeping by slices and the
    /// flag below: −0.5 % of a shaped run's instructions (docs/performance.md).
    ///
    /// A planned start of the same line that the unshaped axes run on through
    /// ([`Self::runs_on`]) is no break: the piece runs on, and names the starts it passes
    /// ([`PhaseChanges`], at most [`MAX_PHASE_CHANGES`]; their samples are taken as
    /// before). The flag returned tells whether it runs on through one (else it names
    /// none).
    ///
    /// A slot is asked again when its commanded break b − τ lies at or before t + `slack`
    /// ([`Self::slack`]): whenever b lies at or before t + τ + 1e-12 as computed, and at
    /// times also just after, where the question gives the same answer again (its cursor
    /// stays on the start b). So the test needs neither the slot's offset nor an addition
    /// of its own (−0.4 % of a shaped run's instructions, docs/performance.md).
    #[inline(always)]
    fn next_break(&mut self, t: f64, slack: f64) -> (f64, bool) {
        let mut best = f64::INFINITY;
        let n = self.break_slots;
        let (breaks, offsets) = (&mut self.breaks[..n], &self.offsets[..n]);
        let due = t + slack;
        for slot in 1..n {
            if breaks[slot] <= due {
                let tau = offsets[slot];
                // Breaks of the planned motion after t + τ: the pieces' starts and the end.
                let want = t + tau + 1e-12;
                let i = self.planned.next_start(slot, want);
                breaks[slot] = self.planned.start_or_end(i, want) - tau;
            }
            // Never NaN (a time, or ±∞ less a finite offset): a plain comparison.
            best = lesser(best, breaks[slot]);
        }
        // The planned motion's own starts before the pulses' first break: asked each time,
        // as the starts passed count from `t`.
        let want = t + 1e-12;
        let i = self.planned.next_start(0, want);
        for n in 0..=MAX_PHASE_CHANGES {
            let b = self.planned.start_or_end(i + n, want);
            if b >= best || n == MAX_PHASE_CHANGES || self.planned.runs_on(i + n) != Some(true) {
                return (lesser(best, b), n > 0);
            }
        }
        (best, true)
    }

    /// How far after a time t between `t_out` and `t_end` a slot's commanded break b − τ
    /// may lie when b lies at or before t + τ + 1e-12 (each as rounded): 1e-12 and four
    /// roundings, each at most 2⁻⁵³ of |t| + |τ| (with |τ| at most the offsets' span),
    /// with room to spare ([`SLACK_PER_S`]; the span's part is [`Self::slack_s`]).
    #[inline(always)]
    fn slack(&self, t_end: f64) -> f64 {
        self.slack_s + SLACK_PER_S * (self.t_out.abs() + t_end.abs())
    }

    /// Whether the axes the shaper leaves as planned (Z, and X or Y if unshaped) run on
    /// from `last` (which ends at `end`) into `next`, the planned piece after it, of the same
    /// line: same acceleration, no jump. Then the commanded motion does not break there.
    #[inline(always)]
    fn runs_on(&self, last: &Segment, end: (Vec3, Vec3), next: &Segment) -> bool {
        let moving = |s: &Segment| matches!(s.phase, Phase::Accel | Phase::Cruise | Phase::Decel);
        let (p, v) = end;
        let unshaped = [!self.shaped[0], !self.shaped[1], true];
        last.line == next.line
            && moving(last)
            && moving(next)
            && (0..3).filter(|&k| unshaped[k]).all(|k| {
                last.a[k] == next.a[k]
                    && (v[k] - next.v[k]).abs() <= JUMP_MIN_MM_S
                    && (p[k] - next.p[k]).abs() <= CONTINUITY_MM
            })
    }

    /// The commanded piece over [ta, tb), inside which no pulse crosses a planned break
    /// (`ta` never smaller than at the last call); `runs_on` as [`Self::next_break`] said.
    #[inline(always)]
    fn piece(&self, ta: f64, tb: f64, runs_on: bool) -> Segment {
        let mid = 0.5 * (ta + tb);
        let planned = &self.planned;
        // The planned piece in force at `ta`: slot 0's cursor was last asked there.
        let own = planned.planned_at(0, mid);
        // The planned state is taken in each branch: there LLVM leaves out what the pulses
        // replace (X and Y when both have the same shaper: −1.1 % of a shaped run's
        // instructions, docs/performance.md).
        let (mut p, mut v, mut a);
        if self.same && self.shaped[0] {
            // Both axes in one pass over the pulses (the same sums, in the same order, as one
            // axis at a time).
            (p, v, a) = planned.state(own, ta);
            let [ps, vs, as_] = self.pulse_sum(0, ta, mid);
            (p.x, p.y, v.x, v.y, a.x, a.y) = (ps[0], ps[1], vs[0], vs[1], as_[0], as_[1]);
        } else {
            (p, v, a) = planned.state(own, ta);
            for axis in 0..2 {
                if self.shaped[axis] {
                    let [ps, vs, as_] = self.pulse_sum(axis, ta, mid);
                    (p[axis], v[axis], a[axis]) = (ps[axis], vs[axis], as_[axis]);
                }
            }
        }
        let none = (PhaseChanges::NONE, PhaseChanges::NO_PHASES);
        let (line, phase, (changes, later_phases)) = match own {
            Some((i, s)) if runs_on => (s.line, s.phase, planned.changes(i, tb)),
            Some((_, s)) => (s.line, s.phase, none),
            None => {
                let s = planned.front().or(planned.back());
                (s.map_or(0, |s| s.line), Phase::Rest, none)
            }
        };
        Segment {
            t0_s: ta,
            dt_s: tb - ta,
            p,
            v,
            a,
            line,
            phase,
            later_phases,
            changes,
        }
    }

    /// Σ a_i · planned(ta + τ_i) over `axis`'s pulses, in X and Y: position, velocity and
    /// acceleration at the start of the commanded piece over [ta, tb) (`mid` its middle,
    /// where each pulse's planned piece is looked up).
    ///
    /// The pulses' cursors are taken as one slice, checked once, not looked up slot by slot
    /// (−1.1 % of a shaped run's instructions, docs/performance.md).
    #[inline(always)]
    fn pulse_sum(&self, axis: usize, ta: f64, mid: f64) -> [[f64; 2]; 3] {
        let mut sum = [[0.0; 2]; 3];
        let pulses = &self.axes[axis];
        let cursors = self.planned.cursors(self.slots[axis], pulses.count());
        for ((w, tau), &next) in pulses.iter().zip(cursors) {
            let s = self.planned.in_force(next, mid + tau);
            let (ps, vs, as_) = self.planned.state(s, ta + tau);
            for k in 0..2 {
                sum[0][k] += w * ps[k];
                sum[1][k] += w * vs[k];
                sum[2][k] += w * as_[k];
            }
        }
        sum
    }

    /// Drops the planned pieces no pulse will look at again.
    #[inline(always)]
    fn drop_unneeded(&mut self) {
        self.planned.drop_ended_before(self.t_out + self.tau_lo);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::motion::Phase;
    use crate::path::Vec3;

    /// A planned chain: from rest, accelerate along X, cruise, a corner into Y (velocity
    /// jump), decelerate to rest; a Z move meanwhile.
    fn planned_chain() -> Vec<Segment> {
        let seg = |t0: f64, dt: f64, p: [f64; 3], v: [f64; 3], a: [f64; 3]| Segment {
            t0_s: t0,
            dt_s: dt,
            p: Vec3::from(p),
            v: Vec3::from(v),
            a: Vec3::from(a),
            line: (t0 * 1000.0) as u64,
            phase: Phase::Cruise,
            later_phases: PhaseChanges::NO_PHASES,
            changes: PhaseChanges::NONE,
        };
        let mut out = vec![seg(
            0.1,
            0.04,
            [0.0, 0.0, 5.0],
            [0.0, 0.0, 0.0],
            [2500.0, 0.0, 10.0],
        )];
        let chain = |out: &mut Vec<Segment>, dt: f64, v: [f64; 3], a: [f64; 3]| {
            let last = *out.last().unwrap();
            let (p, _) = last.end();
            out.push(seg(last.t1_s(), dt, [p.x, p.y, p.z], v, a));
        };
        chain(&mut out, 0.03, [100.0, 0.0, 0.4], [0.0, 0.0, 0.0]);
        chain(&mut out, 0.02, [0.0, 80.0, 0.0], [0.0, 0.0, 0.0]);
        chain(&mut out, 0.032, [0.0, 80.0, 0.0], [0.0, -2500.0, 0.0]);
        out
    }

    /// The same shaper on X and Y, damping ratio 0.1.
    fn both_axes(kind: ShaperType, freq_hz: f64) -> InputShaper {
        let axis = AxisShaper {
            kind,
            freq_hz,
            damping_ratio: 0.1,
        };
        InputShaper {
            x: Some(axis),
            y: Some(axis),
        }
    }

    /// The planned position at t, directly (rest before and after).
    fn planned_at(chain: &[Segment], t: f64) -> Vec3 {
        let first = chain[0];
        if t < first.t0_s {
            return first.p;
        }
        match chain.iter().find(|s| t < s.t1_s()) {
            Some(s) => s.at(t - s.t0_s).0,
            None => chain[chain.len() - 1].end().0,
        }
    }

    #[test]
    fn commanded_pieces_are_the_weighted_sum_of_shifted_planned_positions() {
        let shaper = InputShaper {
            x: Some(AxisShaper {
                kind: ShaperType::Mzv,
                freq_hz: 40.0,
                damping_ratio: 0.1,
            }),
            y: Some(AxisShaper {
                kind: ShaperType::ThreeHumpEi,
                freq_hz: 55.0,
                damping_ratio: 0.05,
            }),
        };
        let chain = planned_chain();
        let mut s = Shaper::new(&shaper);
        let mut out = Vec::new();
        for seg in &chain {
            s.push(*seg, &mut |c| out.push(c));
        }
        s.finish(&mut |c| out.push(c));
        // Contiguous in time and position; each piece a quadratic.
        for w in out.windows(2) {
            assert!((w[0].t1_s() - w[1].t0_s).abs() < 1e-12);
            assert!((w[0].end().0 - w[1].p).norm() < 1e-9);
        }
        let (px, py) = (Pulses::of(shaper.x), Pulses::of(shaper.y));
        let (first, last) = (out[0], out[out.len() - 1]);
        assert!((first.t0_s - (0.1 - px.span_s().1.max(py.span_s().1))).abs() < 1e-12);
        let end = chain[chain.len() - 1].t1_s() - px.span_s().0.min(py.span_s().0);
        assert!((last.t1_s() - end).abs() < 1e-12);
        assert_convolution(&chain, &shaper, &out);
    }

    /// At many instants, the commanded pieces `out` of `chain` against the convolution
    /// computed directly.
    fn assert_convolution(chain: &[Segment], shaper: &InputShaper, out: &[Segment]) {
        let (px, py) = (Pulses::of(shaper.x), Pulses::of(shaper.y));
        let (first, last) = (out[0], out[out.len() - 1]);
        for k in 0..=2000 {
            let t = first.t0_s + (last.t1_s() - first.t0_s) * k as f64 / 2000.0;
            let piece = out.iter().find(|c| t < c.t1_s()).unwrap_or(&last);
            let got = piece.at(t - piece.t0_s).0;
            let conv = |p: &Pulses, axis: usize| -> f64 {
                p.iter()
                    .map(|(a, tau)| a * planned_at(chain, t + tau)[axis])
                    .sum()
            };
            let want = Vec3::new(conv(&px, 0), conv(&py, 1), planned_at(chain, t).z);
            assert!((got - want).norm() < 1e-9, "t = {t}: {got} vs {want}");
        }
    }

    /// Two lines, each from rest through accel, cruise and decel to rest: the first in X
    /// and Y (Z constant), the second climbing in Z too (Z's acceleration changes with the
    /// phase). A piece runs on through the first line's planned breaks, which break no
    /// commanded axis, naming the phases it passes into; through the second's it does not.
    /// Every planned break and every pulse's shifted break is still a piece's start or a
    /// phase change of one (the samples there are as before), and each instant is named
    /// by the planned phase in force then.
    #[test]
    fn a_lines_phases_run_on_in_one_piece_and_are_named() {
        let shaper = both_axes(ShaperType::Mzv, 45.0);
        let mut chain: Vec<Segment> = Vec::new();
        let mut p = Vec3::new(0.0, 0.0, 0.3);
        let mut t = 1.0;
        for (line, dir) in [(7, Vec3::new(0.6, 0.8, 0.0)), (8, Vec3::new(0.6, 0.0, 0.8))] {
            let phases = [
                (Phase::Accel, 0.031, 0.0, 2000.0),
                (Phase::Cruise, 0.047, 62.0, 0.0),
                (Phase::Decel, 0.031, 62.0, -2000.0),
            ];
            for (phase, dt, v, a) in phases {
                let seg = Segment {
                    t0_s: t,
                    dt_s: dt,
                    p,
                    v: dir * v,
                    a: dir * a,
                    line,
                    phase,
                    later_phases: PhaseChanges::NO_PHASES,
                    changes: PhaseChanges::NONE,
                };
                chain.push(seg);
                (p, t) = (seg.end().0, seg.t1_s());
            }
        }
        let mut s = Shaper::new(&shaper);
        let mut out = Vec::new();
        for seg in &chain {
            s.push(*seg, &mut |c| out.push(c));
        }
        s.finish(&mut |c| out.push(c));
        assert_convolution(&chain, &shaper, &out);
        // Each planned start and the end, seen by the motion itself and by each pulse.
        let pulses = Pulses::of(shaper.x);
        let offsets = std::iter::once(0.0).chain(pulses.iter().map(|(_, tau)| tau));
        let planned_breaks: Vec<f64> = (chain.iter().map(|s| s.t0_s)).chain([t]).collect();
        let mut breaks: Vec<f64> = offsets
            .flat_map(|tau| planned_breaks.iter().map(move |b| b - tau))
            .collect();
        breaks.sort_by(f64::total_cmp);
        breaks.dedup_by(|a, b| *a - *b <= MIN_PIECE_S);
        let starts_and_changes = |out: &[Segment]| {
            let mut at: Vec<f64> = out.iter().map(|c| c.t0_s).collect();
            at.extend(
                out.iter()
                    .flat_map(|c| c.changes.at_s)
                    .filter(|c| c.is_finite()),
            );
            at.sort_by(f64::total_cmp);
            at
        };
        let got = starts_and_changes(&out);
        let inside = |b: &&f64| **b > out[0].t0_s + 1e-9 && **b < t - pulses.span_s().0 - 1e-9;
        let want: Vec<f64> = breaks.iter().filter(inside).copied().collect();
        let got_inside: Vec<f64> = got.iter().filter(inside).copied().collect();
        assert_eq!(got_inside.len(), want.len(), "{got_inside:?} {want:?}");
        for (g, w) in got_inside.iter().zip(&want) {
            assert!((g - w).abs() < 1e-9, "{got_inside:?} {want:?}");
        }
        // The first line's two inner breaks run on; the second's do not.
        let changed: Vec<f64> = out
            .iter()
            .flat_map(|c| c.changes.at_s)
            .filter(|c| c.is_finite())
            .collect();
        assert_eq!(changed, [chain[1].t0_s, chain[2].t0_s]);
        assert!(
            out.iter()
                .all(|c| c.changes == PhaseChanges::NONE || c.line == 7)
        );
        // Each instant named by the planned phase then (away from breaks).
        let phase_at = |c: &Segment, t: f64| {
            let n = c.changes.at_s.iter().filter(|&&b| b <= t).count();
            if n == 0 {
                c.phase
            } else {
                c.later_phases[n - 1]
            }
        };
        for k in 0..=3000 {
            let at = chain[0].t0_s + (t - chain[0].t0_s) * k as f64 / 3000.0;
            if breaks.iter().any(|b| (b - at).abs() < 1e-9) {
                continue;
            }
            let planned = chain.iter().find(|s| at < s.t1_s()).unwrap_or(&chain[5]);
            let piece = out
                .iter()
                .find(|c| at < c.t1_s())
                .unwrap_or(&out[out.len() - 1]);
            assert_eq!(phase_at(piece, at), planned.phase, "{at}");
            assert_eq!(piece.line, planned.line, "{at}");
        }
    }

    /// Late in a print (t ≈ 9000 s, where an ulp is 2e-12 s) a move's pieces end where
    /// their durations' sum says and the next move starts where its own duration says, an
    /// ulp or so apart (here two), and commanded breaks of two pulses fall as far apart
    /// (here at every move: each piece lasts the two pulses' spacing). The slivers between them are
    /// commanded pieces too, and none may jump: the planned velocity never does here, so
    /// neither may the commanded one.
    #[test]
    fn slivers_between_moves_do_not_jump() {
        let shaper = both_axes(ShaperType::Zv, 40.0);
        let (lo, hi) = Pulses::of(shaper.x).span_s();
        let dt = hi - lo;
        let dir = Vec3::new(0.6, 0.8, 0.0);
        let mut s = Shaper::new(&shaper);
        let mut out = Vec::new();
        // From rest to 50 mm/s, moves of three pieces (up by 1000 mm/s², cruise, down),
        // to rest: the velocity never jumps.
        let (up, cruise) = (50.0 / dt, 50.0 + 1000.0 * dt);
        let mut moves = vec![vec![(0.0, up)]];
        moves.extend((0..400).map(|_| vec![(50.0, 1000.0), (cruise, 0.0), (cruise, -1000.0)]));
        moves.push(vec![(50.0, -up)]);
        let (mut move_t0, mut p) = (9000.0, Vec3::zeros());
        for (line, pieces) in moves.iter().enumerate() {
            let mut t = move_t0;
            for &(v0, a) in pieces {
                let seg = Segment {
                    t0_s: t,
                    dt_s: dt,
                    p,
                    v: dir * v0,
                    a: dir * a,
                    line: line as u64,
                    phase: Phase::Cruise,
                    later_phases: PhaseChanges::NO_PHASES,
                    changes: PhaseChanges::NONE,
                };
                s.push(seg, &mut |c| out.push(c));
                p = seg.end().0;
                t += dt;
            }
            // The next move two ulps after this one's last piece.
            move_t0 = f64::from_bits(t.to_bits() + 2);
        }
        s.finish(&mut |c| out.push(c));
        let slivers = out.iter().filter(|c| c.dt_s < 1e-9).count();
        assert!(slivers > 50, "{slivers} slivers of {}", out.len());
        for w in out.windows(2) {
            let (p_end, v_end) = w[0].end();
            assert!((p_end - w[1].p).norm() < 1e-9, "{:?} {:?}", w[0], w[1]);
            assert!((v_end - w[1].v).norm() < 1e-6, "{:?} {:?}", w[0], w[1]);
        }
    }

    /// The AVX2 build of the shaper and the baseline give the same commanded pieces, bit
    /// for bit (their `Debug` text shows every float's shortest round trip, and tells −0
    /// from 0), over a chain with a corner, a Z move and a re-homing, with shapers of 2 to
    /// 6 pulses, the same or different on X and Y.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn avx2_shapes_as_the_baseline() {
        if !std::arch::is_x86_feature_detected!("avx2") {
            return;
        }
        let mut chain = planned_chain();
        let end = chain[chain.len() - 1];
        // A re-homing: the motion goes on from elsewhere.
        chain.extend(planned_chain().into_iter().map(|mut s| {
            s.t0_s += end.t1_s() + 0.5;
            s.p += Vec3::new(7.0, -3.0, 1.0);
            s
        }));
        let kinds = [
            ShaperType::Zv,
            ShaperType::Mzv,
            ShaperType::Ei,
            ShaperType::ThreeHumpEi,
        ];
        for (i, &x) in kinds.iter().enumerate() {
            for &y in &kinds[i..] {
                let axis = |kind, freq_hz| {
                    Some(AxisShaper {
                        kind,
                        freq_hz,
                        damping_ratio: 0.1,
                    })
                };
                let shaper = InputShaper {
                    x: axis(x, 41.0),
                    y: axis(y, 37.5),
                };
                let run = |avx2: bool| {
                    let mut s = Shaper::new(&shaper);
                    let mut out = Vec::new();
                    for seg in &chain {
                        if avx2 {
                            // SAFETY: the CPU has AVX2, checked above.
                            unsafe { s.push_avx2(*seg, &mut |c| out.push(c)) };
                        } else {
                            s.push_generic(*seg, &mut |c| out.push(c));
                        }
                    }
                    s.finish(&mut |c| out.push(c));
                    format!("{out:?}")
                };
                let baseline = run(false);
                assert!(baseline.len() > 10_000, "{x:?} {y:?}");
                assert_eq!(run(true), baseline, "{x:?} {y:?}");
            }
        }
    }

    /// Whenever a planned break b lies at or before t + τ + 1e-12 as computed, so that
    /// `next_break` must ask its slot again, b − τ lies at or before t + `slack` as
    /// computed: over times from a millisecond to 10⁹ s, the offsets of a slow shaper
    /// (seconds), and breaks a few ulps either side of the limit.
    #[test]
    fn the_slack_covers_every_break_to_ask_again() {
        let mut s = Shaper::new(&both_axes(ShaperType::ThreeHumpEi, 0.7));
        assert!(s.tau_hi - s.tau_lo > 2.0);
        let mut seed = 0x2545_f491_4f6c_dd1d_u64;
        let mut asked = 0;
        for _ in 0..200_000 {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            // Every other time just below a power of two, where t + τ rounds in the next
            // binade's coarser steps; then with no time after it (the least slack).
            let (t, t_end) = if seed.is_multiple_of(2) {
                let t = 10f64.powf(-3.0 + 12.0 * (seed % 1_000_000) as f64 / 1e6);
                (t, t * (1.0 + (seed >> 40) as f64 / (1u64 << 24) as f64))
            } else {
                let power = 2f64.powi((seed % 40) as i32 - 10);
                let t = f64::from_bits(power.to_bits() - (seed >> 50) % 64 - 1);
                (t, t)
            };
            s.t_out = t;
            let slack = s.slack(t_end);
            for at in [t, t_end] {
                for &tau in &s.offsets[1..s.break_slots] {
                    let want = at + tau + 1e-12;
                    for ulps in -3..=3_i64 {
                        let b = f64::from_bits(want.to_bits().wrapping_add_signed(ulps));
                        if b <= want {
                            asked += 1;
                            assert!(b - tau <= at + slack, "{at} {tau} {b}");
                        }
                    }
                }
            }
        }
        assert!(asked > 1_000_000, "{asked}");
    }

    #[test]
    fn no_shaper_hands_on_the_planned_pieces() {
        let chain = planned_chain();
        let mut s = Shaper::new(&InputShaper::default());
        assert!(s.is_identity());
        let mut out = Vec::new();
        for seg in &chain {
            s.push(*seg, &mut |c| out.push(c));
        }
        s.finish(&mut |c| out.push(c));
        assert_eq!(out, chain);
    }
}
