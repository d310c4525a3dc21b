//! `delta-gcode check FILE... --machine M.yaml`: the verdict on each file.

use std::io::{BufWriter, Write};
use std::path::PathBuf;
use std::process::ExitCode;

use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

use anyhow::Context;

use super::common::{
    Format, MachineArg, Progress, VerboseArg, check_with_progress, print_diagnostics,
};
use super::input::{Input, stdin_at_most_once};
use super::out::{say, stdout};
use delta_gcode::report::{Report, write_github, write_json, write_text};

#[derive(clap::Args, Debug)]
pub struct Args {
    /// G-code files to check (several run in parallel; reports come in this order); `-`
    /// reads standard input
    #[arg(required = true, value_name = "FILE")]
    pub files: Vec<PathBuf>,
    #[command(flatten)]
    pub machine: MachineArg,
    /// Report format: text for a person, json for scripts, github for Actions annotations
    #[arg(long, value_enum, default_value_t = Format::Text)]
    pub format: Format,
    /// List every move's peak forces in the JSON report
    #[arg(long)]
    pub all_moves: bool,
    /// No progress bar
    #[arg(long, short)]
    pub quiet: bool,
    /// No recommendation of limits that pass (it re-plans a failing file a few times)
    #[arg(long)]
    pub no_recommendation: bool,
    #[command(flatten)]
    pub verbose: VerboseArg,
    /// Write SVG plots into DIR: each file's tower forces around its worst moment
    /// (STEM-forces.svg) and a map of the bed by peak-force use (STEM-bed.svg)
    #[arg(long, value_name = "DIR")]
    pub plot: Option<PathBuf>,
}

/// Exit code 1: some move exceeds a limit or cannot be reached.
pub const EXIT_VIOLATION: u8 = 1;

pub fn run(args: &Args) -> anyhow::Result<ExitCode> {
    stdin_at_most_once(&args.files)?;
    let machine = args.machine.load()?;
    let progress = Progress::new(args.quiet);
    // Standard input is copied before the files are checked in parallel.
    let inputs: Vec<anyhow::Result<Input>> = args.files.iter().map(|f| Input::open(f)).collect();
    let results = for_each_file_in_parallel(&inputs, |input| {
        let input = input.as_ref().map_err(|e| anyhow::anyhow!("{e:#}"))?;
        let mut report = check_with_progress(
            input,
            &machine,
            args.all_moves,
            &progress,
            args.verbose.verbose,
        )?;
        if report.failed() && report.summary.errors == 0 && !args.no_recommendation {
            match delta_gcode::tune::recommend(&input.path, &machine) {
                Ok(r) => report.recommendation = Some(r),
                Err(e) => report.recommendation_error = Some(format!("{e:#}")),
            }
        }
        if let Some(dir) = &args.plot {
            super::check_plots::write_plots(input, &machine, &report, dir)
                .with_context(|| format!("plotting {}", input.name))?;
        }
        Ok(report)
    });
    let mut reports = Vec::new();
    let mut input_error = false;
    for result in results {
        match result {
            Ok(r) => {
                input_error |= r.summary.errors > 0;
                reports.push(r);
            }
            Err(e) => {
                say!("delta-gcode: error: {e:#}");
                input_error = true;
            }
        }
    }
    // Buffered: standard output alone is line-buffered, one write per line of the report
    // (139,590 system calls for `--all-moves` on a 0.3 MB file).
    let mut out = BufWriter::with_capacity(1 << 16, stdout());
    match args.format {
        Format::Json => write_json(&mut out, &reports)?,
        Format::Text => {
            for (i, r) in reports.iter().enumerate() {
                if i > 0 {
                    writeln!(out)?;
                }
                out.flush()?; // the previous report before this one's diagnostics (stderr)
                print_diagnostics(r, args.verbose.verbose);
                write_text(&mut out, r)?;
            }
        }
        Format::Github => {
            for r in &reports {
                write_github(&mut out, r)?;
            }
        }
    }
    out.flush()?;
    Ok(if input_error {
        ExitCode::from(super::EXIT_ERROR)
    } else if reports.iter().any(Report::failed) {
        ExitCode::from(EXIT_VIOLATION)
    } else {
        ExitCode::SUCCESS
    })
}

/// Runs `check` over the files on a few threads of their own, results in argument order.
///
/// Each file's pipeline has threads of its own besides (`analysis::run`); most of its
/// time is spent in them.
fn for_each_file_in_parallel<F: Sync>(
    files: &[F],
    check: impl Fn(&F) -> anyhow::Result<Report> + Sync,
) -> Vec<anyhow::Result<Report>> {
    let workers = std::thread::available_parallelism()
        .map_or(1, |n| n.get())
        .min(files.len());
    let next = AtomicUsize::new(0);
    let slots: Vec<Mutex<Option<anyhow::Result<Report>>>> =
        files.iter().map(|_| Mutex::new(None)).collect();
    std::thread::scope(|scope| {
        for _ in 0..workers {
            scope.spawn(|| {
                loop {
                    let i = next.fetch_add(1, Ordering::Relaxed);
                    let Some(file) = files.get(i) else { break };
                    let result = check(file);
                    if let Ok(mut slot) = slots[i].lock() {
                        *slot = Some(result);
                    }
                }
            });
        }
    });
    slots
        .into_iter()
        .map(|slot| {
            slot.into_inner()
                .ok()
                .flatten()
                .unwrap_or_else(|| Err(anyhow::anyhow!("internal error: a file was not checked")))
        })
        .collect()
}
