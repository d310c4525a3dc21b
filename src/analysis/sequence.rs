//! The sequential part of the pipeline after the firmware: commanded pieces → actual pieces
//! (the drive's lag at each start) → the work of sampling them, grouped by G-code line
//! with the checks of the line's moves. All of it is cheap per piece; the sampling itself
//! runs in parallel afterwards.

use std::collections::VecDeque;

use crate::gcode::Move;
use crate::machine::Machine;
#[cfg(target_arch = "x86_64")]
use crate::motion::Avx2Axes;
use crate::motion::drive::{Drive, DriveStage, DriveStep, Response};
use crate::motion::{Axes, JUMP_MIN_MM_S, Segment};
use crate::path::Vec3;
use crate::report::{MoveStats, PathChecks};
use crate::resample::{Edge, Kicks, PieceWork};

use super::Observer;
use super::move_check::MoveChecker;

/// The actual motion's pieces of one G-code line (in a batch's piece list), with what the
/// checks of its planned moves found.
#[derive(Clone, Debug)]
pub struct MoveWork {
    /// Counts the lines' groups: the parts of one group split between batches share it.
    pub group: u64,
    /// 1-based source line.
    pub line: u64,
    /// What the checks of the line's planned moves found.
    pub checks: PathChecks,
    /// Where the line's last planned move ends on the bed, mm.
    pub end_xy_mm: [f64; 2],
    /// Its pieces: `pieces[first..first + count]` of the batch. The sequencer counts the
    /// group it is building when it closes ([`Sequencer::count_open_group`]).
    pub first: usize,
    pub count: usize,
    /// A part of a line split between batches (the results join the parts).
    pub split: bool,
}

impl MoveWork {
    /// The statistics the line's sampling starts from: its checks, no samples yet. Inlined,
    /// as are [`MoveStats::new`] and `Worst::default`: the results of
    /// `MoveChecker::check_moves` are then written in place, not built on the stack and
    /// copied (−0.35 % of an unshaped run's instructions with them).
    #[inline(always)]
    pub fn stats(&self) -> MoveStats {
        MoveStats {
            checks: self.checks.clone(),
            ..MoveStats::new(self.line)
        }
    }
}

/// Work for the parallel stage: pieces and the lines they belong to, in time order.
#[derive(Clone, Debug, Default)]
pub struct Batch {
    pub pieces: Vec<PieceWork>,
    pub moves: Vec<MoveWork>,
}

/// The drive keeps ringing after the motion ends: its last piece is followed by a rest of
/// this many drive periods.
const SETTLE_PERIODS: f64 = 2.0;

/// Planned moves in; batches of piece work out.
pub struct Sequencer {
    period_s: f64,
    response: Option<Response>,
    drive: DriveStage,
    /// The batch's last piece is open: the next piece tells its end (the end sample, the
    /// rigid model's impulses), see [`Self::close_last`].
    open: bool,
    /// With the rigid model, what closing the open piece needs besides its successor.
    /// Only its impulses ask it and the duration below ([`Kicks::around`]), so a sprung
    /// drive does not keep them (with the piece's work pushed before its line's group is
    /// opened, whose call kept the drive's lags in memory: −0.9 % / −1.7 % of a run's
    /// instructions without and with a shaper, docs/performance.md).
    rigid_open: Open,
    /// With the rigid model, the duration of the last piece's last part (its last phase), s.
    last_dt: f64,
    corner_until_s: f64,
    /// Lines whose planned moves were checked but whose pieces have not come yet.
    checked: VecDeque<Checked>,
    batch: Batch,
    /// An emptied batch handed back (see [`Self::recycle`]), to be filled next.
    spare: Option<Batch>,
    group: u64,
    /// The commanded motion's first start and last end, s.
    span_s: Option<(f64, f64)>,
}

/// What closing the batch's last piece needs besides its successor, with the rigid model
/// ([`Sequencer::close_last`]).
#[derive(Clone, Copy, Default)]
struct Open {
    /// The commanded velocity jump at its start, mm/s.
    jump: Vec3,
    /// The duration of the piece before it, s.
    prev_dt: f64,
}

/// What the checks on a move's path found (see [`checks`]), with where it ends on the bed.
#[derive(Clone, Debug)]
pub struct Checked {
    pub line: u64,
    pub checks: PathChecks,
    pub end_xy_mm: [f64; 2],
}

/// The checks on a move's path, before its pieces come ([`Sequencer::checked`] takes them).
pub fn checks<O: Observer>(checker: &MoveChecker<O>, m: &Move) -> Checked {
    let mut checks = PathChecks {
        offset_mm: m.offset_mm.into(),
        ..PathChecks::default()
    };
    checker.check_geometry(&m.path, &mut checks);
    let end = m.path.end();
    Checked {
        line: m.line,
        checks,
        end_xy_mm: [end.x, end.y],
    }
}

impl Sequencer {
    pub fn new(machine: &Machine) -> Self {
        Sequencer {
            period_s: machine.sampling.period_s,
            response: match &machine.drive {
                Drive::Rigid => None,
                Drive::Spring(s) => Some(Response::new(s)),
            },
            drive: DriveStage::new(&machine.drive),
            open: false,
            rigid_open: Open::default(),
            last_dt: 0.0,
            corner_until_s: f64::NEG_INFINITY,
            checked: VecDeque::new(),
            batch: Batch::default(),
            spare: None,
            group: 0,
            span_s: None,
        }
    }

    /// Takes the checks of moves of the G-code (before their pieces come, and in the order
    /// of the moves), leaving `checks` empty.
    pub fn checked(&mut self, checks: &mut Vec<Checked>) {
        self.checked.extend(checks.drain(..));
    }

    /// Takes the commanded pieces of a step, in order; each time `batch_pieces` pieces wait
    /// closed, hands the batch on (`on_batch`), the next one built in the batch `spare`
    /// gives back if it has one ([`Self::recycle`]).
    pub fn drive(
        &mut self,
        commanded: &[Segment],
        batch_pieces: usize,
        spare: &mut impl FnMut() -> Option<Batch>,
        on_batch: &mut impl FnMut(Batch),
    ) {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU has AVX2, checked just above.
            return unsafe { self.drive_avx2(commanded, batch_pieces, spare, on_batch) };
        }
        self.drive_generic::<Vec3>(commanded, batch_pieces, spare, on_batch)
    }

    /// [`Self::drive_generic`] compiled for AVX2: the drive's lag and the pieces' work
    /// with their three-axis vectors in wider registers (−2.4 % of a run's instructions
    /// without a shaper, −3.7 % with one; docs/performance.md, seventeenth session; it
    /// was inlined into its lane's loop, compiled for baseline x86-64). The same operations
    /// in the same order (Rust fuses no multiply-add unasked), so the same batches bit for
    /// bit (test `the_avx2_drive_stage_builds_the_baseline_batches`).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn drive_avx2(
        &mut self,
        commanded: &[Segment],
        batch_pieces: usize,
        spare: &mut impl FnMut() -> Option<Batch>,
        on_batch: &mut impl FnMut(Batch),
    ) {
        self.drive_generic::<Avx2Axes>(commanded, batch_pieces, spare, on_batch)
    }

    /// [`Self::drive`] for any x86-64, in axes `A` (in code compiled for AVX2, the drive's
    /// vectors in AVX2 lanes, [`DriveStage::push`]).
    #[inline(always)]
    fn drive_generic<A: Axes>(
        &mut self,
        commanded: &[Segment],
        batch_pieces: usize,
        spare: &mut impl FnMut() -> Option<Batch>,
        on_batch: &mut impl FnMut(Batch),
    ) {
        // The commanded span from the step's ends, not piece by piece (−0.5 % / −0.8 % of a
        // run's instructions without and with a shaper, docs/performance.md).
        if let (Some(first), Some(last)) = (commanded.first(), commanded.last()) {
            let start = self.span_s.map_or(first.t0_s, |(start, _)| start);
            self.span_s = Some((start, last.t1_s()));
        }
        let mut rest = commanded;
        while !rest.is_empty() {
            // Each piece adds one to the pieces waiting closed, but the first into a batch
            // with no open piece: so many more fill the batch, taken without asking after
            // each (−0.3 % of a shaped run's instructions, docs/performance.md).
            let fill = batch_pieces
                .saturating_sub(self.pending_pieces())
                .saturating_add(usize::from(!self.open));
            let (now, later) = rest.split_at(fill.clamp(1, rest.len()));
            for c in now {
                self.piece::<A>(c);
            }
            rest = later;
            if self.pending_pieces() >= batch_pieces {
                if let Some(b) = spare() {
                    self.recycle(b);
                }
                on_batch(self.take_batch(false));
            }
        }
    }

    /// The next commanded piece, through the drive: the last one closed, this one added.
    /// Inlined into the drive stage's loop: a call per piece cost 2 % of that stage's
    /// instructions with a shaper.
    #[inline(always)]
    fn piece<A: Axes>(&mut self, c: &Segment) {
        let step = self.drive.push::<A>(c);
        // Whether the velocity jumps at the piece's start: the last piece's end sample and
        // this one's corner ask the same (a jump is zero where the motion is not continuous).
        let jumps = step.jump.norm() > JUMP_MIN_MM_S;
        self.close_last(Some((c, &step, jumps)));
        self.add(c, &step, jumps);
    }

    /// The end of the motion: the drive's settling, the last piece, the lines checked
    /// that had no piece.
    pub fn finish(&mut self) {
        if let (Some(r), Some(last)) = (
            &self.response,
            self.batch.pieces.last().filter(|_| self.open),
        ) {
            let seg = last.commanded;
            let (p, _) = seg.end();
            let settle = Segment::rest(seg.t1_s(), SETTLE_PERIODS * r.period_s(), p, seg.line);
            self.piece::<Vec3>(&settle);
        }
        self.close_last(None);
        self.merge_checked_into_open();
        self.count_open_group(self.batch.pieces.len());
        while let Some(c) = self.checked.pop_front() {
            self.open_group(c, self.batch.pieces.len());
        }
    }

    /// The commanded motion's duration so far (its first start to its last end), s.
    pub fn commanded_span_s(&self) -> f64 {
        self.span_s.map_or(0.0, |(a, b)| b - a)
    }

    /// Hands out the batch built so far. Unless `complete`, its last line may go on: the
    /// next batch starts with a part of the same group, which the results join; the open
    /// piece (its end not known yet) goes on in it.
    pub fn take_batch(&mut self, complete: bool) -> Batch {
        self.count_open_group(self.batch.pieces.len());
        let next = self.spare.take().unwrap_or_default();
        let mut batch = std::mem::replace(&mut self.batch, next);
        if !complete && let Some(open) = batch.moves.last_mut() {
            let carried = self.open.then(|| batch.pieces.pop()).flatten();
            open.split = true;
            open.count -= usize::from(carried.is_some());
            let checks = PathChecks {
                offset_mm: open.checks.offset_mm,
                ..PathChecks::default()
            };
            self.batch.moves.push(MoveWork {
                group: open.group,
                line: open.line,
                checks,
                end_xy_mm: open.end_xy_mm,
                first: 0,
                count: usize::from(carried.is_some()),
                split: true,
            });
            self.batch.pieces.extend(carried);
        }
        batch
    }

    /// Takes back a batch the sampling is done with: the next batch is built in its
    /// memory, so that a run reuses a few buffers instead of allocating one per batch.
    fn recycle(&mut self, mut batch: Batch) {
        batch.pieces.clear();
        batch.moves.clear();
        self.spare = Some(batch);
    }

    /// Pieces waiting in the batch, closed.
    fn pending_pieces(&self) -> usize {
        self.batch.pieces.len() - usize::from(self.open)
    }

    /// Closes the batch's last piece, now that its successor `next` (the commanded piece,
    /// what the drive made of it, and whether the velocity jumps there) is known, or that
    /// there is none: its end sample where the velocity jumps there, and with the rigid
    /// model the impulses around it.
    #[inline(always)]
    fn close_last(&mut self, next: Option<(&Segment, &DriveStep, bool)>) {
        let (true, Some(last)) = (std::mem::take(&mut self.open), self.batch.pieces.last_mut())
        else {
            return;
        };
        let (jump_out, next, jumps) = match next {
            Some((c, step, jumps)) if step.continuous => (step.jump, Some(c), jumps),
            _ => (Vec3::zeros(), None, false),
        };
        last.end_sample = jumps;
        if self.response.is_none() {
            let next_dt = next.map_or(0.0, Segment::first_part_s);
            let accel_step = next.is_some_and(|c| last.commanded.a != c.a);
            let seg = &last.commanded;
            last.edge = Edge::Kicks(Kicks::around(
                seg,
                self.rigid_open.jump,
                self.rigid_open.prev_dt,
                jump_out,
                next_dt,
                self.period_s,
            ));
            last.end_sample |= accel_step;
        }
    }

    /// Adds the sampling work of the commanded piece `c`, with what the drive made of it,
    /// to its line's group; open until its successor comes. The work is pushed first and
    /// the group opened after it: no vector of the drive is live across that call.
    #[inline(always)]
    fn add(&mut self, c: &Segment, step: &DriveStep, jumps: bool) {
        if jumps {
            self.corner_until_s = match &self.response {
                Some(r) => c.t0_s + 0.5 * r.period_s(),
                None => f64::NEG_INFINITY,
            };
        }
        self.open = true;
        if self.response.is_none() {
            self.rigid_open = Open {
                jump: step.jump,
                prev_dt: self.last_dt,
            };
            self.last_dt = c.last_part_s();
        }
        self.batch
            .pieces
            .push(PieceWork::new(*c, step, self.corner_until_s));
        let line = c.line;
        if self.batch.moves.last().is_none_or(|m| m.line != line) {
            let first = self.batch.pieces.len() - 1;
            // The common line: the next line checked, with no checks left of the open
            // group's line (they come before the new line's) and no line without pieces
            // before it. Here, not in `open_line`'s call (−0.6 % of a run's instructions
            // without a shaper, docs/performance.md).
            if self.checked.front().is_some_and(|c| c.line == line)
                && let Some(c) = self.checked.pop_front()
            {
                self.count_open_group(first);
                self.open_group(c, first);
                self.merge_checked_into_open();
            } else {
                self.open_line(line, first);
            }
        }
    }

    /// Counts the pieces of the group being built, the batch's last, up to `end`: the
    /// batch's pieces from its first belong to it. Counted once, when the group closes,
    /// not as each piece comes (−0.4 % of a shaped run's instructions, docs/performance.md).
    fn count_open_group(&mut self, end: usize) {
        if let Some(m) = self.batch.moves.last_mut() {
            m.count = end - m.first;
        }
    }

    /// The checks of further planned moves of the open group's line (an arc's chords after
    /// its first) go into it: when the group closes (a piece of another line comes, the motion
    /// ends), since a move's checks come before its pieces. (A group split between batches
    /// gets them in its last part; the results join the parts.)
    #[inline(always)]
    fn merge_checked_into_open(&mut self) {
        let Some(open) = self.batch.moves.last_mut() else {
            return;
        };
        while self.checked.front().is_some_and(|c| c.line == open.line) {
            if let Some(c) = self.checked.pop_front() {
                open.checks.merge(&c.checks);
                open.end_xy_mm = c.end_xy_mm;
            }
        }
    }

    /// Starts the group of `line` at the batch's piece `first` (the open group closed
    /// before it), after the groups of the lines checked before it that have no piece;
    /// the checks of its own planned moves merged into it.
    fn open_line(&mut self, line: u64, first: usize) {
        // Every check of the open group's line has come: its pieces have all come.
        self.count_open_group(first);
        self.merge_checked_into_open();
        while self.checked.front().is_some_and(|c| c.line < line) {
            if let Some(c) = self.checked.pop_front() {
                self.open_group(c, first);
            }
        }
        // Its first planned move's checks as they are (most lines have one planned move).
        let own = match self.checked.front() {
            Some(c) if c.line == line => self.checked.pop_front(),
            _ => None,
        };
        let mut open = own.unwrap_or_else(|| Checked {
            line,
            checks: PathChecks::default(),
            end_xy_mm: self.batch.moves.last().map_or([0.0; 2], |m| m.end_xy_mm),
        });
        while self.checked.front().is_some_and(|c| c.line == line) {
            if let Some(c) = self.checked.pop_front() {
                open.checks.merge(&c.checks);
                open.end_xy_mm = c.end_xy_mm;
            }
        }
        self.open_group(open, first);
    }

    #[inline(always)]
    fn open_group(&mut self, c: Checked, first: usize) {
        self.group += 1;
        self.batch.moves.push(MoveWork {
            group: self.group,
            line: c.line,
            checks: c.checks,
            end_xy_mm: c.end_xy_mm,
            first,
            count: 0,
            split: false,
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::{MoveResult, Observer, Scratch, TraceRows, Window};
    use crate::gcode::{ArcRules, interpret};
    use crate::machine::test_support::kossel_machine;
    use crate::motion::drive::Spring;
    use crate::motion::shaper::{AxisShaper, ShaperType};

    /// A shaped, sprung machine and a file of short moves, an arc, a move out of reach.
    fn setup() -> (Machine, String) {
        let mut machine = kossel_machine();
        machine.input_shaper.x = Some(AxisShaper {
            kind: ShaperType::Mzv,
            freq_hz: 40.0,
            damping_ratio: 0.1,
        });
        machine.drive = Drive::Spring(Spring {
            frequency_hz: 55.0,
            damping_ratio: 0.08,
        });
        let mut gcode = String::from("G28\nG1 Z5 F6000\n");
        for k in 0..40 {
            gcode += &format!("G1 X{} Y{}\n", (k % 2) as f64 * 0.7, k as f64 * 0.3);
        }
        gcode += "G2 X10 Y12 I5 J0\nG1 X60 Y0 F3000\nG1 X0 Y-150\nG1 X0 Y0\nG4 P50\nG1 X1 Y1\n";
        (machine, gcode)
    }

    fn batches(machine: &Machine, gcode: &str, batch_pieces: usize) -> Vec<Batch> {
        let mut out = Vec::new();
        crate::analysis::sequence(
            gcode.as_bytes(),
            machine,
            batch_pieces,
            |_| {},
            |b| out.push(b),
        )
        .unwrap();
        out
    }

    /// The G-code lines with moves, in order (an arc's chords are one).
    fn move_lines(machine: &Machine, gcode: &str) -> Vec<u64> {
        let mut lines = Vec::new();
        let home = Vec3::new(0.0, 0.0, machine.geometry.home_z_mm);
        interpret(
            gcode.as_bytes(),
            home,
            ArcRules::default(),
            |e| {
                if let crate::gcode::Event::Move(m) = e {
                    lines.push(m.line);
                }
            },
            |_| {},
        )
        .unwrap();
        lines.dedup();
        lines
    }

    #[test]
    fn pieces_are_contiguous_and_each_line_is_one_group() {
        let (machine, gcode) = setup();
        let whole = batches(&machine, &gcode, usize::MAX);
        assert_eq!(whole.len(), 1);
        let b = &whole[0];
        for w in b.pieces.windows(2) {
            let (a, c) = (w[0].commanded, w[1].commanded);
            assert!((a.t1_s() - c.t0_s).abs() < 1e-9, "{a:?} {c:?}");
            assert!((a.end().0 - c.p).norm() < 1e-9);
        }
        // One group per line with motion, in file order, covering every piece once.
        let lines: Vec<u64> = b.moves.iter().map(|m| m.line).collect();
        assert_eq!(lines, move_lines(&machine, &gcode));
        assert_eq!(
            b.moves.iter().map(|m| m.count).sum::<usize>(),
            b.pieces.len()
        );
        for m in &b.moves {
            for p in &b.pieces[m.first..m.first + m.count] {
                assert_eq!(p.commanded.line, m.line);
            }
        }
        // The arc (line 43) has many chords, all in its group; the move out of reach
        // (line 45) is flagged by its check.
        let arc = b.moves.iter().find(|m| m.line == 43).unwrap();
        assert!(arc.count > 5);
        let far = b.moves.iter().find(|m| m.line == 45).unwrap();
        assert!(far.checks.problem.is_some());
    }

    #[test]
    fn a_piece_is_the_same_whatever_batch_it_ends() {
        // The open piece a batch boundary falls after goes on in the next batch, closed
        // there by its successor: the pieces of small batches, end to end, are those of one
        // batch (end samples, the rigid model's impulses), sprung and rigid.
        let (mut machine, gcode) = setup();
        for rigid in [false, true] {
            if rigid {
                machine.drive = Drive::Rigid;
            }
            let whole = batches(&machine, &gcode, usize::MAX).remove(0).pieces;
            let small = batches(&machine, &gcode, 7);
            assert!(small.len() > 3, "{} batches", small.len());
            // Each batch but the last holds its 7 pieces closed.
            for b in &small[..small.len() - 1] {
                assert_eq!(b.pieces.len(), 7, "rigid {rigid}");
            }
            let joined: Vec<PieceWork> = small.into_iter().flat_map(|b| b.pieces).collect();
            assert_eq!(joined, whole, "rigid {rigid}");
            assert!(whole.iter().any(|w| w.end_sample), "rigid {rigid}");
        }
    }

    /// The AVX2 build of the drive stage and the baseline build the same batches, bit for
    /// bit (their `Debug` text shows every float's shortest round trip, and tells −0 from
    /// 0), sprung and rigid, over small batches, a re-homing, shaped pieces and an arc.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn the_avx2_drive_stage_builds_the_baseline_batches() {
        if !std::arch::is_x86_feature_detected!("avx2") {
            return;
        }
        let (mut machine, gcode) = setup();
        for rigid in [false, true] {
            if rigid {
                machine.drive = Drive::Rigid;
            }
            let mut commanded: Vec<Segment> = batches(&machine, &gcode, usize::MAX)[0]
                .pieces
                .iter()
                .map(|w| w.commanded)
                .collect();
            // A re-homing: the motion goes on from elsewhere.
            let end = commanded[commanded.len() - 1].t1_s();
            let again: Vec<Segment> = commanded[..20]
                .iter()
                .map(|&c| Segment {
                    t0_s: c.t0_s + end + 0.5,
                    p: c.p + Vec3::new(3.0, -2.0, 1.0),
                    ..c
                })
                .collect();
            commanded.extend(again);
            let run = |avx2: bool| {
                let mut sequencer = Sequencer::new(&machine);
                let mut out = Vec::new();
                let mut on_batch = |b: Batch| out.push(format!("{b:?}"));
                for step in commanded.chunks(13) {
                    let (spare, batch_pieces) = (&mut || None, 7);
                    if avx2 {
                        // SAFETY: the CPU has AVX2, checked above.
                        unsafe { sequencer.drive_avx2(step, batch_pieces, spare, &mut on_batch) };
                    } else {
                        sequencer.drive_generic::<Vec3>(step, batch_pieces, spare, &mut on_batch);
                    }
                }
                sequencer.finish();
                on_batch(sequencer.take_batch(true));
                out
            };
            let baseline = run(false);
            assert!(
                baseline.len() > 20,
                "rigid {rigid}: {} batches",
                baseline.len()
            );
            assert_eq!(run(true), baseline, "rigid {rigid}");
        }
    }

    #[test]
    fn batches_built_in_recycled_ones_are_the_same() {
        // Each batch built in the memory of an earlier one, handed back still full: the
        // same pieces and lines as batches built afresh.
        let (machine, gcode) = setup();
        let fresh = batches(&machine, &gcode, 7);
        assert!(fresh.len() > 3, "{} batches", fresh.len());
        let spares = std::sync::Mutex::new(Vec::new());
        let mut recycled = Vec::new();
        super::super::sequence_edited(
            gcode.as_bytes(),
            &machine,
            7,
            &mut super::super::pass_on,
            |_| {},
            |b| {
                spares.lock().unwrap().push(b.clone());
                recycled.push(b);
            },
            || spares.lock().unwrap().pop(),
        )
        .unwrap();
        assert_eq!(recycled.len(), fresh.len());
        for (k, (a, b)) in recycled.iter().zip(&fresh).enumerate() {
            assert_eq!(
                format!("{:?}", a.moves),
                format!("{:?}", b.moves),
                "batch {k}"
            );
            assert_eq!(a.pieces, b.pieces, "batch {k}");
        }
    }

    #[test]
    fn moves_sharing_blocks_and_batches_get_what_they_get_alone() {
        let (machine, gcode) = setup();
        let observer = (
            TraceRows::new(&machine.motors),
            Window {
                from_s: 0.05,
                to_s: 1.5,
            },
        );
        let checker = MoveChecker::new(&machine, observer);
        let mut scratch = Box::<Scratch>::default();
        let whole = &batches(&machine, &gcode, usize::MAX)[0];
        let mut together: Vec<MoveResult<_>> = Vec::new();
        checker.check_moves(&mut scratch, &whole.pieces, &whole.moves, &mut together);
        assert!(together.iter().map(|r| r.stats.samples).sum::<u64>() > 4000);
        for (i, r) in together.iter().enumerate() {
            let mut alone = Vec::new();
            checker.check_moves(&mut scratch, &whole.pieces, &whole.moves[i..=i], &mut alone);
            assert_eq!(r.stats, alone[0].stats, "move {i}");
            assert_eq!(r.observed, alone[0].observed, "move {i}");
            // One trace row per sample the model could take.
            let rows = r.observed.0.iter().filter(|&&b| b == b'\n').count();
            assert_eq!(rows as u64, r.stats.samples, "move {i}");
        }
        // Small batches split lines; their parts, merged, give the same results.
        let mut merged: Vec<MoveResult<_>> = Vec::new();
        for b in batches(&machine, &gcode, 7) {
            let mut out = Vec::new();
            checker.check_moves(&mut scratch, &b.pieces, &b.moves, &mut out);
            for mut r in out {
                match merged.last_mut() {
                    Some(last) if last.group == r.group => {
                        last.stats.merge(&r.stats);
                        checker
                            .observer()
                            .merge(&mut last.observed, &mut r.observed);
                    }
                    _ => merged.push(r),
                }
            }
        }
        assert_eq!(merged.len(), together.len());
        for (a, b) in merged.iter().zip(&together) {
            assert_eq!(a.stats, b.stats);
            assert_eq!(a.observed, b.observed);
        }
    }
}
