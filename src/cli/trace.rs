//! `delta-gcode trace FILE --machine M.yaml -o trace.csv`: one CSV row per sample, in a
//! window of lines or times if asked.

use std::fs::File;
use std::io::{self, BufReader, BufWriter, Write};
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, bail};

use super::common::{MachineArg, VerboseArg, print_diagnostics};
use super::input::{Input, is_stdin};
use super::out::stdout;
use super::replace::replace_file;
use delta_gcode::analysis::{TraceRows, TraceWindow, run as run_pipeline, trace_header};
use delta_gcode::machine::Machine;
use delta_gcode::report::Report;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// G-code file to trace; `-` reads standard input
    #[arg(value_name = "FILE")]
    pub file: PathBuf,
    #[command(flatten)]
    pub machine: MachineArg,
    /// CSV output; `-` for standard output
    #[arg(long, short, value_name = "CSV")]
    pub output: PathBuf,
    /// Only the samples of this G-code line and after
    #[arg(long, value_name = "LINE")]
    pub from_line: Option<u64>,
    /// Only the samples of this G-code line and before
    #[arg(long, value_name = "LINE")]
    pub to_line: Option<u64>,
    /// Only the samples from this time on (s from the start of the print)
    #[arg(long, value_name = "SECONDS", allow_negative_numbers = true)]
    pub from_s: Option<f64>,
    /// Only the samples up to this time (s)
    #[arg(long, value_name = "SECONDS", allow_negative_numbers = true)]
    pub to_s: Option<f64>,
    #[command(flatten)]
    pub verbose: VerboseArg,
}

impl Args {
    /// The window the options select; an empty one is a usage error.
    fn window(&self) -> anyhow::Result<TraceWindow> {
        let all = TraceWindow::default();
        let w = TraceWindow {
            lines: (
                self.from_line.unwrap_or(all.lines.0),
                self.to_line.unwrap_or(all.lines.1),
            ),
            t_s: (
                self.from_s.unwrap_or(all.t_s.0),
                self.to_s.unwrap_or(all.t_s.1),
            ),
        };
        if w.lines.0 > w.lines.1 {
            bail!("--from-line {} is after --to-line {}", w.lines.0, w.lines.1);
        }
        // Also refuses NaN.
        if w.t_s.0.partial_cmp(&w.t_s.1).is_none_or(|o| o.is_gt()) {
            bail!("--from-s {} is not before --to-s {}", w.t_s.0, w.t_s.1);
        }
        Ok(w)
    }
}

pub fn run(args: &Args) -> anyhow::Result<ExitCode> {
    let window = args.window()?;
    let machine = args.machine.load()?;
    let input = Input::open(&args.file)?;
    // Counted and grouped as `check` does, printed at the end.
    let mut report = Report::new(
        &input.name,
        &machine.name,
        machine.motors.max_force_n,
        false,
    );
    let rows = TraceRows::new(&machine.motors).within(window);
    let written = if is_stdin(&args.output) {
        let mut out = BufWriter::with_capacity(1 << 16, stdout());
        write_trace(&mut out, &input, &machine, rows, &mut report).and_then(|()| out.flush())
    } else {
        replace_file(&args.output, |w| {
            write_trace(w, &input, &machine, rows, &mut report)?;
            // No motion: no trace file either.
            match report.summary.moves {
                0 => Err(io::Error::other("no motion")),
                _ => Ok(()),
            }
        })
        .map_err(|e| io::Error::other(format!("{e:#}")))
    };
    print_diagnostics(&report, args.verbose.verbose);
    if report.summary.moves == 0 {
        input.refuse_no_motion(report.summary.lines, report.summary.errors)?;
    }
    written.with_context(|| format!("tracing {}", input.name))?;
    Ok(ExitCode::SUCCESS)
}

/// The trace of `input` into `w`; its diagnostics and counts into `report`.
fn write_trace(
    w: &mut (dyn Write + Send),
    input: &Input,
    machine: &Machine,
    rows: TraceRows,
    report: &mut Report,
) -> io::Result<()> {
    let from = BufReader::with_capacity(1 << 16, File::open(&input.path)?);
    w.write_all(trace_header().as_bytes())?;
    let mut failure = Ok(());
    let totals = run_pipeline(
        from,
        machine,
        rows,
        |r| {
            if failure.is_ok() {
                failure = w.write_all(&r.observed);
            }
        },
        |d| report.add_diagnostic(&d),
    )?;
    report.summary.lines = totals.read.lines;
    report.summary.moves = totals.read.moves;
    failure
}
