//! Whole moves offered to the run's peaks before any of their samples: a box of all a
//! move's samples, the boxes of a few consecutive moves joined and offered to one bound
//! (docs/performance.md, "Sixth session").

use super::{Floor, MoveChecker, Scratch};
use crate::analysis::observe::Observer;
use crate::analysis::sequence::MoveWork;
use crate::delta::ForceBounds;
use crate::interval::lesser;
use crate::motion::drive::Response;
use crate::report::share;
use crate::resample::{Fit, PieceWork, SPARSE_MIN_SAMPLES, StateBox, move_samples, piece_raw};

use super::MAX_SAMPLES_PER_PIECE;

/// A move of at most this many pieces is offered in the box of [`Fit::Swing`] at once; one
/// of more, first in that of [`Fit::Envelope`] (docs/performance.md).
const SWING_FIRST_PIECES: usize = 4;

/// The fewest and the most moves whose boxes are joined and offered to one bound first
/// ([`MoveChecker::let_go_whole`]): a group twice as large after one that went on its
/// first bound, half as large after one that did not (hot and cool stretches of a print
/// come in runs). On the first 5 MB of the corpus's bunny, 96.8 k bounds where groups of 4
/// always took 100.7 k (docs/performance.md).
const WHOLE_GROUP: (usize, usize) = (1, 8);

/// What the halving of kept groups works on ([`MoveChecker::let_go_group`]): the moves'
/// boxes, their decisions marked in place, the batch's pieces and lines, the run's peaks.
struct Offers<'a> {
    whole: &'a mut [Option<WholeMove>],
    pieces: &'a [PieceWork],
    moves: &'a [MoveWork],
    run: &'a Floor,
}

/// A move offered whole to the run's peaks: the box of all its samples, how many, the fit
/// of its accelerations, and whether a bound let it go.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct WholeMove {
    states: StateBox,
    pub(super) count: u64,
    fit: Fit,
    pub(super) let_go: bool,
}

impl<O: Observer> MoveChecker<'_, O> {
    /// Decides, before any sample, which moves of a call the run's peaks let go whole
    /// (`scratch.whole`, one entry per move): each move's box of all its samples, the
    /// boxes of a few consecutive offered moves ([`WHOLE_GROUP`]) joined and offered to one bound,
    /// a group the bound keeps halved and each half offered again, down to single moves.
    /// Most groups go on one bound, so most moves cost a box and a fraction of a bound.
    pub(super) fn let_go_whole(
        &self,
        scratch: &mut Scratch,
        pieces: &[PieceWork],
        moves: &[MoveWork],
        run: &Floor,
    ) {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU has AVX2, checked just above.
            return unsafe {
                if self.machine.input_shaper.x.is_none() && self.machine.input_shaper.y.is_none() {
                    self.let_go_whole_avx2::<true>(scratch, pieces, moves, run)
                } else {
                    self.let_go_whole_avx2::<false>(scratch, pieces, moves, run)
                }
            };
        }
        self.let_go_whole_generic::<false, false>(scratch, pieces, moves, run)
    }

    /// [`Self::let_go_whole_generic`] compiled for AVX2: the boxes' three-axis sums in one
    /// register instead of two (−3.7 % instructions of a run, about −2 % CPU time without
    /// a shaper and −5 % with one, docs/performance.md). The same operations in the same
    /// order (Rust fuses no multiply-add unasked), so the same boxes bit for bit.
    ///
    /// With `SWING` (chosen without an input shaper), the swing's three axes in one
    /// register as well ([`Response::acceleration_range`]): −2.6 % of a default run's
    /// instructions. A shaper's pieces mostly fit one window, where that kernel's call
    /// costs more than it saves, and its call site alone made the shaped run's pass 1.1 %
    /// dearer (docs/performance.md, nineteenth session).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn let_go_whole_avx2<const SWING: bool>(
        &self,
        scratch: &mut Scratch,
        pieces: &[PieceWork],
        moves: &[MoveWork],
        run: &Floor,
    ) {
        self.let_go_whole_generic::<true, SWING>(scratch, pieces, moves, run)
    }

    /// [`Self::let_go_whole`] for any x86-64; `AVX2` where it is inlined into its AVX2
    /// copy, whose halving of kept groups is then compiled for AVX2 too, and `SWING` (the
    /// swing's AVX2 lanes) only with `AVX2`.
    #[inline(always)]
    fn let_go_whole_generic<const AVX2: bool, const SWING: bool>(
        &self,
        scratch: &mut Scratch,
        pieces: &[PieceWork],
        moves: &[MoveWork],
        run: &Floor,
    ) {
        let mut whole = std::mem::take(&mut scratch.whole);
        let mut offered = std::mem::take(&mut scratch.offered);
        whole.clear();
        offered.clear();
        for (idx, m) in moves.iter().enumerate() {
            let works = pieces.get(m.first..m.first + m.count).unwrap_or_default();
            // Not `bool::then`: its closure was left out of line (2.5 % more instructions).
            let w = if m.split {
                None
            } else {
                self.whole_box::<SWING>(works)
            };
            if w.is_some() {
                offered.push(idx);
            }
            whole.push(w);
        }
        let (fewest, most) = WHOLE_GROUP;
        let mut size = most;
        let mut rest = &offered[..];
        let mut offers = Offers {
            whole: &mut whole,
            pieces,
            moves,
            run,
        };
        while !rest.is_empty() {
            let (group, after) = rest.split_at(size.min(rest.len()));
            size = if self.let_go_group::<AVX2, SWING>(&mut offers, group) {
                (2 * size).min(most)
            } else {
                (size / 2).max(fewest)
            };
            rest = after;
        }
        scratch.whole = whole;
        scratch.offered = offered;
    }

    /// Offers the joined boxes of the moves `group` (indices in `offers.whole`) to one
    /// bound; if it keeps them, each half of the group, down to single moves, which get
    /// the swing's box as a second chance when theirs was the envelope's. Whether the first
    /// bound let the whole group go. With `AVX2` (only where the CPU has it), by
    /// [`Self::halve_avx2`]: a recursion is not inlined into its caller, and so was
    /// compiled for the baseline (−0.8 % of a run's instructions; docs/performance.md,
    /// seventeenth session).
    #[inline(always)]
    fn let_go_group<const AVX2: bool, const SWING: bool>(
        &self,
        offers: &mut Offers,
        group: &[usize],
    ) -> bool {
        #[cfg(target_arch = "x86_64")]
        if AVX2 {
            // SAFETY: AVX2 is set only in `let_go_whole_avx2` and below it, which run
            // only on a CPU with it.
            return unsafe { self.halve_avx2::<SWING>(offers, group) };
        }
        self.halve(offers, group)
    }

    /// [`Self::let_go_group`] for any x86-64. Out of line, as its AVX2 copy: LLVM inlined
    /// the AVX2 copy's first call into the whole-move pass, 1.8 % more instructions.
    #[inline(never)]
    fn halve(&self, offers: &mut Offers, group: &[usize]) -> bool {
        self.halving::<false, false>(offers, group)
    }

    /// [`Self::let_go_group`] compiled for AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    #[inline(never)]
    fn halve_avx2<const SWING: bool>(&self, offers: &mut Offers, group: &[usize]) -> bool {
        self.halving::<true, SWING>(offers, group)
    }

    /// The body of [`Self::halve`] and [`Self::halve_avx2`]: the group offered, and if it
    /// is kept, each half in turn.
    #[inline(always)]
    fn halving<const AVX2: bool, const SWING: bool>(
        &self,
        offers: &mut Offers,
        group: &[usize],
    ) -> bool {
        if let Some(went) = self.offer_group::<SWING>(offers, group) {
            return went;
        }
        let (a, b) = group.split_at(group.len() / 2);
        self.let_go_group::<AVX2, SWING>(offers, a);
        self.let_go_group::<AVX2, SWING>(offers, b);
        false
    }

    /// The joined boxes of the moves `group` offered to one bound: whether it let them go,
    /// or None for a group of several moves it kept, to be halved. A single move it kept
    /// gets the swing's box as a second chance when its box was the envelope's (false all
    /// the same: its group was kept).
    #[inline(always)]
    fn offer_group<const SWING: bool>(&self, offers: &mut Offers, group: &[usize]) -> Option<bool> {
        let Offers {
            whole,
            pieces,
            moves,
            run,
        } = offers;
        // Joined in place, over references: each box is 144 bytes, and copying them
        // through `map` and `reduce` called memmove for each.
        let mut boxes = group.iter().filter_map(|&i| whole[i].as_ref());
        let Some(first) = boxes.next() else {
            return Some(true);
        };
        let mut joined = first.states;
        for w in boxes {
            joined.join_in_place(&w.states);
        }
        if self.below_run(&joined, run) {
            for &i in group {
                if let Some(w) = &mut whole[i] {
                    w.let_go = true;
                }
            }
            return Some(true);
        }
        let [i] = *group else {
            return None;
        };
        if let (Some(w), Some(r)) = (&mut whole[i], &self.response)
            && w.fit == Fit::Envelope
        {
            let m = &moves[i];
            let works = pieces.get(m.first..m.first + m.count).unwrap_or_default();
            w.let_go = self.below_run(&self.move_states::<SWING>(works, r, Fit::Swing), run);
        }
        Some(false)
    }

    /// A box of all the samples of a move's pieces, to be offered whole: None when some
    /// piece is too long to sample or the move has too few samples to pay for a bound.
    /// A move of few pieces gets the swing's box at once; one of many (an input shaper's),
    /// the envelope's, which lets it go most of the time.
    #[inline(always)]
    fn whole_box<const SWING: bool>(&self, works: &[PieceWork]) -> Option<WholeMove> {
        let r = self.response.as_ref()?;
        let period_s = self.machine.sampling.period_s;
        // None unless every piece is sampled.
        let count = move_samples(works, period_s, MAX_SAMPLES_PER_PIECE * period_s)?;
        if count < SPARSE_MIN_SAMPLES || works.is_empty() {
            return None;
        }
        let fit = if works.len() <= SWING_FIRST_PIECES {
            Fit::Swing
        } else {
            Fit::Envelope
        };
        Some(WholeMove {
            states: self.move_states::<SWING>(works, r, fit),
            count,
            fit,
            let_go: false,
        })
    }

    /// The join of the boxes of a move's pieces (not empty), slacked once.
    #[inline(always)]
    fn move_states<const SWING: bool>(
        &self,
        works: &[PieceWork],
        r: &Response,
        fit: Fit,
    ) -> StateBox {
        let period_s = self.machine.sampling.period_s;
        let mut raw = piece_raw::<SWING>(&works[0], r, period_s, fit);
        for w in &works[1..] {
            raw = raw.join(&piece_raw::<SWING>(w, r, period_s, fit));
        }
        raw.slacked()
    }

    /// Whether the bounds over `states` (`DeltaModel::bound`: every state of the box a
    /// valid pose, |Q_i|, the share of the available force and the tension, each with its
    /// margin) are below the run's peaks and below a violation (a share of 1, the magnets'
    /// hold), strictly, on every tower: then none of its samples could change the run's
    /// peaks or make a violation.
    fn below_run(&self, states: &StateBox, run: &Floor) -> bool {
        self.model
            .bound_below(
                &states.pos_mm,
                &states.vel_mm_s,
                &states.acc_mm_s2,
                &self.tension_limits(run),
            )
            .is_some_and(|b| self.bounds_below_run(&b, run))
    }

    /// The tensions a bound must stay below on each tower to leave the run's peaks as they
    /// are: the run's own, and the magnets' hold.
    pub(super) fn tension_limits(&self, run: &Floor) -> [f64; 3] {
        std::array::from_fn(|i| lesser(run.tension_n[i], self.hold_n))
    }

    /// [`Self::below_run`] of the bounds over a box that `DeltaModel::bound_below` gave
    /// under [`Self::tension_limits`]: their tensions are below those already, and only the
    /// forces and the shares are compared.
    pub(super) fn bounds_below_run(&self, b: &ForceBounds, run: &Floor) -> bool {
        (0..3).all(|i| {
            b.force_n[i] < run.force_n[i] && self.most_share(b, i) < lesser(run.share[i], 1.0)
        })
    }

    /// The largest share of the available force tower `i` may be asked within bounds `b`:
    /// the available force falls with the carriage speed, so it is least at the bound.
    pub(super) fn most_share(&self, b: &ForceBounds, i: usize) -> f64 {
        let available = self.machine.motors.available_force_n(b.speed_mm_s[i]);
        share(b.force_n[i], available)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::{Batch, MoveResult, sequence};
    use crate::interval::Interval;
    use crate::machine::Machine;
    use crate::machine::test_support::kossel_machine;
    use crate::motion::drive::{Drive, Spring};
    use crate::motion::shaper::{AxisShaper, ShaperType};
    use crate::resample::sample_piece;

    /// The fixture's moves in one batch (no line split).
    fn batch(machine: &Machine) -> Batch {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/tests/fixtures/ps25_bunny_head.gcode"
        );
        let gcode = std::fs::read(path).expect("fixture");
        let mut batches = Vec::new();
        sequence(&gcode[..], machine, usize::MAX, |_| {}, |b| batches.push(b)).expect("reads");
        batches.remove(0)
    }

    /// A sprung machine, shaped or not.
    fn machine(shaped: bool) -> Machine {
        let mut machine = kossel_machine();
        machine.drive = Drive::Spring(Spring {
            frequency_hz: 55.0,
            damping_ratio: 0.08,
        });
        if shaped {
            machine.input_shaper.x = Some(AxisShaper {
                kind: ShaperType::Mzv,
                freq_hz: 40.0,
                damping_ratio: 0.1,
            });
            machine.input_shaper.y = machine.input_shaper.x;
        }
        machine
    }

    /// A move's box (its pieces' boxes joined, slacked once) holds every sample of the move,
    /// in both fits, on every move of the fixture with and without a shaper.
    #[test]
    fn a_moves_box_holds_its_samples() {
        for shaped in [false, true] {
            let machine = machine(shaped);
            let b = batch(&machine);
            let checker = MoveChecker::new(&machine, ());
            let r = checker.response.as_ref().expect("a drive");
            let period_s = machine.sampling.period_s;
            let mut samples = 0;
            for m in b.moves.iter().filter(|m| m.count > 0) {
                let works = &b.pieces[m.first..m.first + m.count];
                for fit in [Fit::Envelope, Fit::Swing] {
                    let states = checker.move_states::<false>(works, r, fit);
                    let mut check = |s: crate::resample::Sample| {
                        samples += 1;
                        for i in 0..3 {
                            let inside = |x: Interval, v: f64| x.lo <= v && v <= x.hi;
                            assert!(inside(states.pos_mm[i], s.pos_mm[i]), "line {}", m.line);
                            assert!(inside(states.vel_mm_s[i], s.vel_mm_s[i]), "line {}", m.line);
                            assert!(
                                inside(states.acc_mm_s2[i], s.acc_mm_s2[i]),
                                "line {}",
                                m.line
                            );
                        }
                    };
                    for w in works {
                        sample_piece(w, Some(r), period_s, &mut check);
                    }
                }
            }
            assert!(samples > 10_000, "{samples}");
        }
    }

    /// The AVX2 build of the decision (the boxes and the halving of kept groups, with and
    /// without the swing's lanes) gives the baseline's boxes and decisions bit for bit,
    /// with and without a shaper (run's peaks at 0.9 of the dense ones, so that both
    /// outcomes occur).
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn avx2_decides_as_the_baseline() {
        if !std::arch::is_x86_feature_detected!("avx2") {
            return;
        }
        for shaped in [false, true] {
            let machine = machine(shaped);
            let b = batch(&machine);
            let checker = MoveChecker::new(&machine, ());
            let mut scratch = Box::<Scratch>::default();
            let run = run_at(&machine, &b, 0.9);
            checker.let_go_whole_generic::<false, false>(&mut scratch, &b.pieces, &b.moves, &run);
            let baseline = scratch.whole.clone();
            let went = baseline.iter().flatten().filter(|w| w.let_go).count();
            assert!(went > 50 && went < baseline.len(), "{went} went");
            // SAFETY: the CPU has AVX2, checked above.
            unsafe { checker.let_go_whole_avx2::<false>(&mut scratch, &b.pieces, &b.moves, &run) };
            assert_eq!(scratch.whole, baseline);
            // With the swing's lanes too (SAFETY: as above).
            unsafe { checker.let_go_whole_avx2::<true>(&mut scratch, &b.pieces, &b.moves, &run) };
            assert_eq!(scratch.whole, baseline);
        }
    }

    /// The run's peaks at `share` of the dense ones of batch `b`.
    fn run_at(machine: &Machine, b: &Batch, share: f64) -> Floor {
        let mut scratch = Box::<Scratch>::default();
        let mut dense: Vec<MoveResult<()>> = Vec::new();
        let dense_checker = MoveChecker::new(machine, ()).dense();
        dense_checker.check_moves(&mut scratch, &b.pieces, &b.moves, &mut dense);
        let mut run = Floor::default();
        for r in &dense {
            for i in 0..3 {
                run.force_n[i] = run.force_n[i].max(share * r.stats.peak_force_n[i]);
                run.share[i] = run.share[i].max(share * r.stats.worst[i].ratio);
                run.tension_n[i] = run.tension_n[i].max(share * r.stats.peak_tension_n[i]);
            }
        }
        run
    }

    /// Every move a bound lets go in its own box goes with the groups too (halving a group
    /// loses none), and every move the groups let go is below the run's peaks in its dense
    /// samples (a group's bound holds each of its moves). The run's peaks are 0.9 of the
    /// dense ones, so that some moves go and some do not; with and without a shaper (whose
    /// moves of many pieces get the swing's box as a second chance).
    #[test]
    fn groups_let_go_what_single_moves_do_and_only_what_is_below() {
        for shaped in [false, true] {
            let machine = machine(shaped);
            let b = batch(&machine);
            let checker = MoveChecker::new(&machine, ());
            let mut scratch = Box::<Scratch>::default();
            let mut dense: Vec<MoveResult<()>> = Vec::new();
            let dense_checker = MoveChecker::new(&machine, ()).dense();
            dense_checker.check_moves(&mut scratch, &b.pieces, &b.moves, &mut dense);
            let run = run_at(&machine, &b, 0.9);
            checker.let_go_whole(&mut scratch, &b.pieces, &b.moves, &run);
            let r = checker.response.as_ref().expect("a drive");
            let (mut went, mut kept, mut second) = (0, 0, 0);
            for (i, w) in scratch.whole.iter().enumerate() {
                let Some(w) = w else { continue };
                let m = &b.moves[i];
                let works = &b.pieces[m.first..m.first + m.count];
                let alone = checker.below_run(&w.states, &run)
                    || (w.fit == Fit::Envelope
                        && checker
                            .below_run(&checker.move_states::<false>(works, r, Fit::Swing), &run));
                second += usize::from(w.fit == Fit::Envelope);
                assert!(!alone || w.let_go, "line {}: lost by the groups", m.line);
                if w.let_go {
                    went += 1;
                    let s = &dense[i].stats;
                    assert_eq!(s.samples, w.count, "line {}", m.line);
                    for t in 0..3 {
                        assert!(s.peak_force_n[t] < run.force_n[t], "line {}", m.line);
                        assert!(s.worst[t].ratio < run.share[t], "line {}", m.line);
                        assert!(s.peak_tension_n[t] < run.tension_n[t], "line {}", m.line);
                    }
                } else {
                    kept += 1;
                }
            }
            eprintln!("shaped {shaped}: {went} went, {kept} kept, {second} of many pieces");
            assert!(
                went > 50 && kept > 10,
                "shaped {shaped}: {went} went, {kept} kept"
            );
            assert!(!shaped || second > 100, "{second} moves of many pieces");
        }
    }
}
