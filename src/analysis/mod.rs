//! The pipeline over one G-code stream: reader → interpreter → planner → planned pieces →
//! input shaper → drive (sequential) → sampler + delta model + observers (in parallel over
//! batches of pieces, results back in file order).

use std::cell::RefCell;
use std::collections::{BTreeSet, HashMap};
use std::fs::File;
use std::io::{self, BufRead, BufReader, Read};
use std::path::Path;
use std::sync::{Mutex, PoisonError};

use anyhow::Context;
use indicatif::ProgressBar;

use crate::firmware;
use crate::gcode::{self, Diagnostic, Event, ReadStats};
use crate::machine::{Firmware, Machine};
use crate::path::Vec3;
use crate::report::{DiagnosticLog, MoveStats, Report};
use crew::Crew;
use lanes::{Drive, Lanes, Model, STEP_PIECES, Steps};

mod crew;
mod lanes;
mod move_check;
mod observe;
mod sequence;
mod trace;

pub use move_check::{DENSE_ENV, MoveChecker, Scratch};
pub use observe::{Evaluated, Observer, RunPeaks, Verdict, Window};
pub use sequence::{Batch, Checked, MoveWork, Sequencer, checks};
pub use trace::{TraceRow, TraceRows, TraceWindow, trace_header};

/// The progress bar's move count is updated this often.
const PROGRESS_EVERY_MOVES: u64 = 4096;

/// Pieces of the actual motion handed to the parallel stage at a time.
const BATCH: usize = 8192;

/// A batch of fewer chunks than this wakes no helper thread (on more than two cores; the
/// other lane takes chunks whenever it is free). Marlin's batches hold a few hundred moves
/// of ~40 pieces (1–5 chunks; Klipper's 11–14 with an input shaper, 44–49 without): the
/// model stage's work is then well below the firmware's, which bounds the run, and a helper
/// woken for each batch took the firmware's core (the bunny with the Q5 profile: 4.12 →
/// 3.68 s, docs/performance.md).
const HELP_MIN_CHUNKS: usize = 8;

/// Consecutive moves checked as one part of a batch (their samples share the model's blocks).
const CHUNK: usize = 64;

/// What the model found for one G-code line's motion: the verdict's statistics and what
/// the run's observer kept of it.
pub struct MoveResult<P> {
    /// The line's group in the run (see [`MoveWork::group`]).
    pub group: u64,
    pub stats: MoveStats,
    pub observed: P,
    /// Where the move ends on the bed, mm.
    pub end_xy_mm: [f64; 2],
}

/// Totals of one run, besides the per-move results.
pub struct RunTotals {
    pub read: ReadStats,
    /// The commanded motion's duration, s.
    pub print_time_s: f64,
}

/// Runs the pipeline over `input`. `on_move` gets every G-code line's result in file order
/// (the verdict's statistics and what `observer` kept), where it lies: it may take out what
/// it keeps. `on_diag` gets every diagnostic of the reader.
///
/// The reader, interpreter and firmware run on this thread; the drive stage and the
/// sampling, the model and the observers on whichever of this thread and one other has
/// room (`lanes`), each batch's chunks shared between them and any further helpers
/// ([`THREADS_ENV`]). So the sequential stages overlap the parallel one, and memory stays
/// bounded.
pub fn run<R: Read, O: Observer>(
    input: R,
    machine: &Machine,
    observer: O,
    on_move: impl FnMut(&mut MoveResult<O::PerMove>) + Send,
    on_diag: impl FnMut(Diagnostic),
) -> io::Result<RunTotals> {
    run_edited(input, machine, observer, &mut pass_on, on_move, on_diag)
}

/// Hands an event on unchanged: the edit of a plain run.
fn pass_on(event: &Event, to_firmware: &mut dyn FnMut(&Event)) {
    to_firmware(event);
}

/// [`run`], with the interpreter's events going through `edit` on their way to the firmware:
/// it takes one event and hands on (to its second argument) the events the firmware is to
/// see instead, e.g. limit changes added before a move (`tune`). Generic, not a trait
/// object: a plain run's [`pass_on`] is then inlined. Events go by reference: an `Event` is
/// large, and each handed on by value through the `dyn` closure was copied once more
/// (0.3 % of an unshaped run's instructions).
pub fn run_edited<R: Read, O: Observer>(
    input: R,
    machine: &Machine,
    observer: O,
    edit: &mut impl FnMut(&Event, &mut dyn FnMut(&Event)),
    on_move: impl FnMut(&mut MoveResult<O::PerMove>) + Send,
    on_diag: impl FnMut(Diagnostic),
) -> io::Result<RunTotals> {
    run_on(input, machine, observer, edit, on_move, on_diag, threads())
}

/// [`run_edited`] on `threads` threads (at least this one): the firmware lane here, the
/// model lane on a second, crew helpers on the rest (`lanes`).
fn run_on<R: Read, O: Observer>(
    input: R,
    machine: &Machine,
    observer: O,
    edit: &mut impl FnMut(&Event, &mut dyn FnMut(&Event)),
    on_move: impl FnMut(&mut MoveResult<O::PerMove>) + Send,
    on_diag: impl FnMut(Diagnostic),
    threads: usize,
) -> io::Result<RunTotals> {
    let checker = MoveChecker::new(machine, observer);
    let crew = Crew::new();
    let work = |job: &Job<O::PerMove>, c: usize| {
        let n = job.batch.moves.len();
        let run = c * CHUNK..n.min((c + 1) * CHUNK);
        let mut slot = job.outs[c].lock().unwrap_or_else(PoisonError::into_inner);
        // Filled out of its slot: the slots of neighbouring chunks share cache lines, and
        // the two lanes check neighbouring chunks at once, so a vector's length written
        // in place at every move would move a line between the cores each time.
        let mut out = std::mem::take(&mut *slot);
        SCRATCH.with_borrow_mut(|scratch| {
            checker.check_moves(scratch, &job.batch.pieces, &job.batch.moves[run], &mut out);
        });
        *slot = out;
    };
    let lanes = Lanes::new(
        Drive {
            sequencer: Sequencer::new(machine),
            batch_pieces: BATCH,
        },
        Model {
            stage: ModelStage {
                checker: &checker,
                pending: None,
                outs: Vec::new(),
            },
            on_move,
        },
        &crew,
        &work,
    );
    let read = std::thread::scope(|scope| {
        for _ in 2..threads {
            scope.spawn(|| crew.help(&work));
        }
        // The helpers go when the lanes are done, even by a panic.
        let _dismiss = Dismiss(&crew);
        if threads >= 2 {
            scope.spawn(|| lanes.work());
        }
        let _guard = lanes.guard();
        let read = firmware_steps(
            input,
            machine,
            edit,
            on_diag,
            |step, last| lanes.push_step(step, last),
            || lanes.spare_step(),
        );
        lanes.work();
        read
    });
    Ok(RunTotals {
        read: read?,
        print_time_s: lanes.into_drive().sequencer.commanded_span_s(),
    })
}

/// The sequential stages over `input`: the reader and interpreter, the firmware (the
/// commanded motion) and the [`Sequencer`] (the drive, the checks, the grouping by line);
/// `on_batch` gets the work for the sampling in batches of about `batch_pieces` pieces,
/// the last one complete.
pub fn sequence<R: Read>(
    input: R,
    machine: &Machine,
    batch_pieces: usize,
    on_diag: impl FnMut(Diagnostic),
    on_batch: impl FnMut(Batch),
) -> io::Result<RunTotals> {
    sequence_edited(
        input,
        machine,
        batch_pieces,
        &mut pass_on,
        on_diag,
        on_batch,
        || None,
    )
}

/// [`sequence`], the events edited on their way to the firmware (see [`run_edited`]), each
/// batch built in an emptied one that `spare` gives back when it has one (the memory of a
/// run then stays that of a few batches). On this thread.
fn sequence_edited<R: Read>(
    input: R,
    machine: &Machine,
    batch_pieces: usize,
    edit: &mut impl FnMut(&Event, &mut dyn FnMut(&Event)),
    on_diag: impl FnMut(Diagnostic),
    mut on_batch: impl FnMut(Batch),
    mut spare: impl FnMut() -> Option<Batch>,
) -> io::Result<RunTotals> {
    let mut sequencer = Sequencer::new(machine);
    let read = firmware_steps(
        input,
        machine,
        edit,
        on_diag,
        |mut step, last| {
            sequencer.checked(&mut step.checked);
            sequencer.drive(&step.commanded, batch_pieces, &mut spare, &mut on_batch);
            if last {
                sequencer.finish();
                on_batch(sequencer.take_batch(true));
            }
        },
        Steps::default,
    );
    Ok(RunTotals {
        read: read?,
        print_time_s: sequencer.commanded_span_s(),
    })
}

/// The firmware's side of the pipeline: reads and interprets `input`, checks each move's
/// path and plans the commanded motion, handed on in steps of about [`STEP_PIECES`]
/// pieces (`on_step(step, last)`, the last one after the end of the input, also on an
/// error), each filled from `spare()`.
fn firmware_steps<R: Read>(
    input: R,
    machine: &Machine,
    edit: &mut impl FnMut(&Event, &mut dyn FnMut(&Event)),
    mut on_diag: impl FnMut(Diagnostic),
    mut on_step: impl FnMut(Steps, bool),
    mut spare: impl FnMut() -> Steps,
) -> io::Result<ReadStats> {
    let geometry = MoveChecker::new(machine, ());
    let mut firmware = firmware::for_machine(machine);
    let home = Vec3::new(0.0, 0.0, machine.geometry.home_z_mm);
    let mut step = Steps::default();
    // Made once, not for each event: its captures were stored afresh at every call.
    let mut to_firmware = |event: &Event| {
        if let Event::Move(m) = event {
            step.checked.push(checks(&geometry, m));
        }
        firmware.push(event, &mut step.commanded);
        if step.commanded.len().max(step.checked.len()) >= STEP_PIECES {
            on_step(std::mem::replace(&mut step, spare()), false);
        }
    };
    let read = gcode::interpret(
        input,
        home,
        machine.dialect(),
        |event: Event| edit(&event, &mut to_firmware),
        |d| {
            if for_firmware(&machine.firmware, &d) {
                on_diag(d);
            }
        },
    );
    firmware.finish(&mut step.commanded);
    on_step(step, true);
    read
}

/// Whether a diagnostic of the reader holds for the profile's firmware: the one place
/// where the reader's words, written for Klipper, are sorted by firmware. Marlin honours
/// `M204 P` and `T` (print and travel acceleration), which Klipper ignores one at a time.
pub fn for_firmware(firmware: &Firmware, d: &Diagnostic) -> bool {
    match firmware {
        Firmware::Klipper => true,
        Firmware::Marlin(_) => d.message != gcode::M204_P_OR_T_IGNORED,
    }
}

thread_local! {
    /// Each model thread's sample blocks (27 KB), kept from one chunk to the next: made
    /// afresh for each chunk they cost 1.4 % of a run in memset.
    static SCRATCH: RefCell<Box<Scratch>> = RefCell::new(Box::default());
}

/// The parallel stage.
struct ModelStage<'c, 'm, O: Observer> {
    checker: &'c MoveChecker<'m, O>,
    /// The last result so far: the next batch may continue its line.
    pending: Option<MoveResult<O::PerMove>>,
    /// Each chunk's results, emptied and kept from one batch to the next: allocated afresh
    /// for each chunk, their 400-byte results were written to memory the cache did not
    /// hold (memmove was 8 % of a default run's time, docs/performance.md).
    outs: Vec<Mutex<Vec<MoveResult<O::PerMove>>>>,
}

/// A batch in the model stage's crew, with each chunk's results.
struct Job<P> {
    batch: Batch,
    outs: Vec<Mutex<Vec<MoveResult<P>>>>,
}

/// Dismisses the crew when dropped.
struct Dismiss<'a, J: Sync>(&'a Crew<J>);

impl<J: Sync> Drop for Dismiss<'_, J> {
    fn drop(&mut self) {
        self.0.dismiss();
    }
}

/// The environment variable that sets how many threads a file's pipeline runs on (its two
/// lanes, then helpers of the model stage): a positive number; unset or anything else, one
/// per core. With 1 the whole pipeline runs on one thread.
pub const THREADS_ENV: &str = "DELTA_GCODE_THREADS";

/// The threads of a file's pipeline ([`THREADS_ENV`]).
fn threads() -> usize {
    std::env::var(THREADS_ENV)
        .ok()
        .and_then(|v| v.trim().parse::<usize>().ok())
        .filter(|&n| n > 0)
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()))
}

impl<O: Observer> ModelStage<'_, '_, O> {
    /// Samples a batch's moves over the crew, a chunk of moves at a time, and hands on
    /// their results in order, the parts of a line split between batches joined; gives
    /// the batch back. `posted` is called once other threads can claim its chunks.
    fn process(
        &mut self,
        crew: &Crew<Job<O::PerMove>>,
        work: &impl Fn(&Job<O::PerMove>, usize),
        batch: Batch,
        on_move: &mut impl FnMut(&mut MoveResult<O::PerMove>),
        posted: impl FnOnce(),
    ) -> Batch {
        let count = batch.moves.len().div_ceil(CHUNK);
        let mut outs = std::mem::take(&mut self.outs);
        if outs.len() < count {
            outs.resize_with(count, Mutex::default);
        }
        let help = count >= HELP_MIN_CHUNKS;
        let Job { batch, mut outs } = crew.run(Job { batch, outs }, count, help, work, posted);
        let results = &mut outs[..count];
        // A line is split between batches only at their boundary: the batch's first
        // result may continue the pending one, and its last may go on in the next batch,
        // so it is held back. The others are handed on where they lie: each moved out
        // and then into `on_move` was copied twice (a result is 376 bytes; 1.8 % of an
        // unshaped run's instructions).
        let last = results.iter_mut().rposition(|v| {
            !v.get_mut()
                .unwrap_or_else(PoisonError::into_inner)
                .is_empty()
        });
        let held = last.and_then(|c| {
            results[c]
                .get_mut()
                .unwrap_or_else(PoisonError::into_inner)
                .pop()
        });
        for v in results.iter_mut() {
            let v = v.get_mut().unwrap_or_else(PoisonError::into_inner);
            for r in v.iter_mut() {
                if !self.continues(r, on_move) {
                    on_move(r);
                }
            }
            v.clear();
        }
        if let Some(mut r) = held
            && !self.continues(&mut r, on_move)
        {
            self.pending = Some(r);
        }
        self.outs = outs;
        batch
    }

    /// Whether `r` goes on with the pending result's line: then it is merged into it (what
    /// the observer kept taken out of `r`). Otherwise the pending result, if any, is
    /// handed on, done.
    fn continues(
        &mut self,
        r: &mut MoveResult<O::PerMove>,
        on_move: &mut impl FnMut(&mut MoveResult<O::PerMove>),
    ) -> bool {
        match &mut self.pending {
            Some(p) if p.group == r.group => {
                p.stats.merge(&r.stats);
                self.checker
                    .observer()
                    .merge(&mut p.observed, &mut r.observed);
                true
            }
            Some(_) => {
                if let Some(mut done) = self.pending.take() {
                    on_move(&mut done);
                }
                false
            }
            None => false,
        }
    }
}

/// Checks one G-code file: the whole pipeline into a [`Report`], with the text of the
/// flagged lines looked up afterwards. `progress` (a bar over the file's bytes) is optional.
pub fn check_file(
    path: &Path,
    machine: &Machine,
    all_moves: bool,
    progress: Option<&ProgressBar>,
) -> anyhow::Result<Report> {
    let file = File::open(path).with_context(|| format!("cannot open {}", path.display()))?;
    let name = path.display().to_string();
    let mut report = Report::new(&name, &machine.name, machine.motors.max_force_n, all_moves);
    report.arm_magnet_hold_n = machine.geometry.arm_magnet_hold_n;
    // The reader's diagnostics: the first MAX_LISTED kept, all counted and grouped by kind,
    // so a file with a warning on every line does not fill the memory.
    let mut diags = DiagnosticLog::default();
    let input = ProgressReader {
        inner: file,
        bar: progress,
    };
    // Report::add_move split ([`Report::add_peaks`]) so that what nearly no move needs (the
    // list of moves, flags, the progress message) is one cold call at the end: the common
    // path then makes no call and saves no register.
    let on_move = |r: &mut MoveResult<()>| {
        report.add_end_xy(r.end_xy_mm, machine.geometry.print_radius_mm);
        let more = report.add_peaks(&r.stats);
        let tick = progress.is_some() && report.summary.moves.is_multiple_of(PROGRESS_EVERY_MOVES);
        if more || tick {
            add_rest(&mut report, &r.stats, more, progress);
        }
    };
    let input = BufReader::with_capacity(1 << 16, input);
    let on_diag = |d| diags.push(d);
    // Without the list of moves, only the run's peaks and the violations need be exact.
    let totals = if all_moves {
        run(input, machine, (), on_move, on_diag)
    } else {
        run(input, machine, RunPeaks(()), on_move, on_diag)
    }
    .with_context(|| format!("cannot read {name}"))?;
    report.add_diagnostics(diags);
    report.note_footprint(machine.geometry.print_radius_mm);
    report.summary.lines = totals.read.lines;
    report.summary.print_time_s = totals.print_time_s;
    let lines = report.violation_lines();
    if !lines.is_empty() {
        let texts =
            line_texts(path, &lines).with_context(|| format!("cannot read {name} again"))?;
        report.set_commands(|line| texts.get(&line).cloned());
    }
    Ok(report)
}

/// What [`check_file`]'s per-move callback leaves out of its common path: the rest of the
/// move ([`Report::add_rest`]) if `more`, the progress message every
/// [`PROGRESS_EVERY_MOVES`] moves.
#[cold]
#[inline(never)]
fn add_rest(report: &mut Report, m: &MoveStats, more: bool, progress: Option<&ProgressBar>) {
    if more {
        report.add_rest(m);
    }
    if let Some(bar) = progress
        && report.summary.moves.is_multiple_of(PROGRESS_EVERY_MOVES)
    {
        bar.set_message(format!("{} moves", report.summary.moves));
    }
}

/// The text of the given lines (1-based), trimmed of their terminator and shortened.
fn line_texts(path: &Path, lines: &[u64]) -> io::Result<HashMap<u64, String>> {
    const SHOWN: usize = 72;
    let wanted: BTreeSet<u64> = lines.iter().copied().collect();
    let Some(&last) = wanted.last() else {
        return Ok(HashMap::new());
    };
    let mut reader = BufReader::new(File::open(path)?);
    let mut buf = Vec::new();
    let mut texts = HashMap::new();
    let mut n = 0;
    while n < last {
        buf.clear();
        if reader.read_until(b'\n', &mut buf)? == 0 {
            break;
        }
        n += 1;
        if wanted.contains(&n) {
            let text = String::from_utf8_lossy(&buf);
            let text = text.trim_end();
            let short: String = text.chars().take(SHOWN).collect();
            texts.insert(
                n,
                if short.len() < text.len() {
                    short + "…"
                } else {
                    short
                },
            );
        }
    }
    Ok(texts)
}

/// A reader that advances a progress bar by the bytes it reads.
struct ProgressReader<'a, R> {
    inner: R,
    bar: Option<&'a ProgressBar>,
}

impl<R: Read> Read for ProgressReader<'_, R> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        let n = self.inner.read(buf)?;
        if let Some(bar) = self.bar {
            bar.inc(n as u64);
        }
        Ok(n)
    }
}
