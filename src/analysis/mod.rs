//! The pipeline over one G-code stream: reader → interpreter → planner (sequential) →
//! resampler + delta model + statistics (in parallel over batches of planned moves, results
//! back in file order).

use std::collections::{BTreeSet, HashMap};
use std::fs::File;
use std::io::{self, BufRead, BufReader, Read};
use std::path::Path;
use std::sync::mpsc;

use anyhow::Context;
use indicatif::ProgressBar;
use rayon::prelude::*;

use crate::gcode::{self, Diagnostic, Event, ReadStats, Severity};
use crate::machine::Machine;
use crate::planner::{PlannedMove, Planner};
use crate::report::{MAX_LISTED, MoveStats, Report};

mod move_check;
mod observe;
mod trace;

pub use move_check::{MoveChecker, Scratch};
pub use observe::{Evaluated, Observer, Verdict, Window};
pub use trace::{TraceRow, TraceRows, trace_header};

/// The progress bar's move count is updated this often.
const PROGRESS_EVERY_MOVES: u64 = 4096;

/// Planned moves handed to the parallel stage at a time.
const BATCH: usize = 4096;

/// Consecutive moves checked by one rayon task (their samples share the model's blocks).
const CHUNK: usize = 64;

/// What the model found for one planned move: the verdict's statistics and what the
/// run's observer kept of it.
pub struct MoveResult<P> {
    pub stats: MoveStats,
    pub observed: P,
    /// Where the move ends on the bed, mm.
    pub end_xy_mm: [f64; 2],
}

/// Totals of one run, besides the per-move results.
pub struct RunTotals {
    pub read: ReadStats,
    pub print_time_s: f64,
}

/// Batches in flight between the planner and the model stage: bounds the memory.
const BATCHES_IN_FLIGHT: usize = 2;

/// Runs the pipeline over `input`. `on_move` gets every planned move's result in file order
/// (the verdict's statistics and what `observer` kept), `on_diag` every diagnostic of the
/// reader.
///
/// The reader, interpreter and planner run on this thread; the model stage runs on another,
/// fed batches of planned moves through a bounded channel, and spreads each batch over the
/// rayon pool. So the sequential stages overlap the parallel one, and memory stays bounded.
pub fn run<R: Read, O: Observer>(
    input: R,
    machine: &Machine,
    observer: O,
    mut on_move: impl FnMut(MoveResult<O::PerMove>) + Send,
    on_diag: impl FnMut(Diagnostic),
) -> io::Result<RunTotals> {
    let (to_model, batches) = mpsc::sync_channel::<Vec<PlannedMove>>(BATCHES_IN_FLIGHT);
    std::thread::scope(|scope| {
        let model = scope.spawn(move || {
            let mut stage = ModelStage::new(machine, observer);
            for batch in batches {
                stage.pending.extend(batch);
                stage.process(false, &mut on_move);
            }
            stage.process(true, &mut on_move);
        });
        let mut planner = Planner::new(machine);
        let home = nalgebra::Vector3::new(0.0, 0.0, machine.geometry.home_z_mm);
        let mut planned = Vec::with_capacity(2 * BATCH);
        // A send fails only when the model stage has stopped, and then its panic is
        // re-raised by the join below.
        let read = gcode::interpret(
            input,
            home,
            |event: Event| {
                planner.push(event, &mut planned);
                if planned.len() >= BATCH {
                    let full = std::mem::replace(&mut planned, Vec::with_capacity(2 * BATCH));
                    let _ = to_model.send(full);
                }
            },
            on_diag,
        );
        planner.finish(&mut planned);
        let _ = to_model.send(planned);
        drop(to_model);
        if let Err(panic) = model.join() {
            std::panic::resume_unwind(panic);
        }
        Ok(RunTotals {
            read: read?,
            print_time_s: planner.print_time_s(),
        })
    })
}

/// The parallel stage: planned moves waiting for their model run.
struct ModelStage<'m, O> {
    checker: MoveChecker<'m, O>,
    pending: Vec<PlannedMove>,
    /// The last move processed: the previous move of the next batch's first.
    prev: Option<PlannedMove>,
}

impl<'m, O: Observer> ModelStage<'m, O> {
    fn new(machine: &'m Machine, observer: O) -> Self {
        ModelStage {
            checker: MoveChecker::new(machine, observer),
            pending: Vec::new(),
            prev: None,
        }
    }

    /// Runs the model over the pending moves. All but the last are run unless `last`: the
    /// last one's junction with the move after it is not known yet.
    fn process(&mut self, last: bool, on_move: &mut impl FnMut(MoveResult<O::PerMove>)) {
        let n = if last {
            self.pending.len()
        } else {
            self.pending.len().saturating_sub(1)
        };
        if n == 0 {
            return;
        }
        let pending = &self.pending;
        let prev = self.prev;
        let results: Vec<Vec<MoveResult<O::PerMove>>> = (0..n.div_ceil(CHUNK))
            .into_par_iter()
            .map_init(Box::<Scratch>::default, |scratch, c| {
                let run = c * CHUNK..n.min((c + 1) * CHUNK);
                let before = match run.start {
                    0 => prev.as_ref(),
                    i => pending.get(i - 1),
                };
                let mut out = Vec::with_capacity(run.len());
                let after = pending.get(run.end);
                self.checker
                    .check_run(scratch, before, &pending[run], after, &mut out);
                out
            })
            .collect();
        results.into_iter().flatten().for_each(&mut *on_move);
        self.prev = Some(self.pending[n - 1]);
        self.pending.drain(..n);
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
    // The reader's diagnostics: the first MAX_LISTED kept, the others only counted, so a file
    // with a warning on every line does not fill the memory.
    let mut diags = Vec::new();
    let (mut unlisted_warnings, mut unlisted_errors) = (0, 0);
    let input = ProgressReader {
        inner: file,
        bar: progress,
    };
    let totals = run(
        BufReader::with_capacity(1 << 16, input),
        machine,
        (),
        |r| {
            report.add_move(&r.stats);
            if let Some(bar) = progress
                && report.summary.moves.is_multiple_of(PROGRESS_EVERY_MOVES)
            {
                bar.set_message(format!("{} moves", report.summary.moves));
            }
        },
        |d| match d.severity {
            _ if diags.len() < MAX_LISTED => diags.push(d),
            Severity::Warning => unlisted_warnings += 1,
            Severity::Error => unlisted_errors += 1,
        },
    )
    .with_context(|| format!("cannot read {name}"))?;
    for d in &diags {
        report.add_diagnostic(d);
    }
    report.summary.warnings += unlisted_warnings;
    report.summary.errors += unlisted_errors;
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
