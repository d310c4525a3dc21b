//! `delta-gcode check FILE... --machine M.yaml`: the verdict on each file.

use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;

use rayon::prelude::*;

use super::common::{MachineArg, Progress, check_with_progress, print_diagnostics};
use crate::report::{Report, write_github, write_json, write_text};

#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    Text,
    Json,
    Github,
}

#[derive(clap::Args, Debug)]
pub struct Args {
    /// G-code files to check (several run in parallel; reports come in this order)
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
}

/// Exit code 1: some move exceeds a limit or cannot be reached.
pub const EXIT_VIOLATION: u8 = 1;

pub fn run(args: &Args) -> anyhow::Result<ExitCode> {
    let machine = args.machine.load()?;
    let progress = Progress::new(args.quiet);
    let results: Vec<anyhow::Result<Report>> = args
        .files
        .par_iter()
        .map(|f| check_with_progress(f, &machine, args.all_moves, &progress))
        .collect();
    let mut reports = Vec::new();
    let mut input_error = false;
    for result in results {
        match result {
            Ok(r) => {
                input_error |= r.summary.errors > 0;
                reports.push(r);
            }
            Err(e) => {
                eprintln!("delta-gcode: error: {e:#}");
                input_error = true;
            }
        }
    }
    let mut out = std::io::stdout().lock();
    match args.format {
        Format::Json => write_json(&mut out, &reports)?,
        Format::Text => {
            for (i, r) in reports.iter().enumerate() {
                if i > 0 {
                    writeln!(out)?;
                }
                print_diagnostics(r);
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
