//! `delta-gcode fix FILE --machine M.yaml (-o OUT | --in-place)`: the G-code with the
//! firmware's limit commands added around the moves that need them, so that every move
//! passes; checked again before it is written. `fix - -o -` is a filter: standard input to
//! standard output, the report on stderr.

use std::fs::File;
use std::io::{BufReader, BufWriter, Write};
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context;
use serde::Serialize;

use super::check::EXIT_VIOLATION;
use super::common::{Format, MachineArg, text_or_json};
use super::input::{Input, is_stdin};
use super::out::{say, stdout};
use super::replace::replace_file;
use delta_gcode::emit::{Drop, emit_with};
use delta_gcode::report::{Recommendation, Report, write_text};
use delta_gcode::tune::{FixPlan, Unfixable, plan_fix};

#[derive(clap::Args, Debug)]
pub struct Args {
    /// G-code file to fix (a slicer hook appends it to the command line); `-` reads
    /// standard input (then with -o)
    #[arg(value_name = "FILE")]
    pub file: PathBuf,
    #[command(flatten)]
    pub machine: MachineArg,
    /// Write the fixed G-code here; `-` for standard output (the report then goes to
    /// stderr)
    #[arg(long, short, value_name = "OUT", required_unless_present = "in_place")]
    pub output: Option<PathBuf>,
    /// Replace FILE by its fixed version (whole or not at all)
    #[arg(long, conflicts_with = "output")]
    pub in_place: bool,
    /// Output format: text or json
    #[arg(long, value_parser = text_or_json(), default_value = "text")]
    pub format: Format,
}

/// The JSON of a fix.
#[derive(Serialize)]
struct FixReport<'a> {
    file: String,
    output: String,
    /// Limit commands added.
    commands: usize,
    /// Whether they cap only the moves that need it (else the whole file).
    local: bool,
    original_print_time_s: f64,
    print_time_s: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    recommendation: Option<Recommendation>,
    /// The check of the fixed file.
    check: &'a Report,
}

pub fn run(args: &Args) -> anyhow::Result<ExitCode> {
    if args.in_place && is_stdin(&args.file) {
        anyhow::bail!("--in-place needs a file, not standard input: give -o OUT");
    }
    let machine = args.machine.load()?;
    let input = Input::open(&args.file)?;
    let name = &input.name;
    let plan = match plan_fix(&input.path, &machine) {
        Ok(p) => p,
        Err(e) if e.is::<Unfixable>() => {
            say!("delta-gcode: fix: {name}: {e:#}");
            return Ok(ExitCode::from(EXIT_VIOLATION));
        }
        Err(e) => return Err(e.context(format!("fixing {name}"))),
    };
    let target = args.output.as_deref().unwrap_or(&args.file);
    let to_stdout = is_stdin(target);
    let mut additions = plan.additions.clone();
    additions.summary = summary_lines(&plan);
    // The fixed file, checked as the firmware will read it before it replaces anything.
    let dir = match target.parent() {
        _ if to_stdout => std::env::temp_dir(),
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let mut tmp = tempfile::Builder::new()
        .prefix(".delta-gcode-fix.")
        .tempfile_in(&dir)
        .with_context(|| format!("cannot create a temporary file in {}", dir.display()))?;
    let from = BufReader::with_capacity(1 << 16, File::open(&input.path)?);
    emit_with(from, tmp.as_file_mut(), &additions, Drop::All)
        .with_context(|| format!("fixing {name}"))?;
    let mut report = delta_gcode::analysis::check_file(tmp.path(), &machine, false, None)?;
    report.file = if to_stdout {
        STDOUT_NAME.to_string()
    } else {
        target.display().to_string()
    };
    if report.failed() {
        anyhow::bail!("internal error: the fixed {name} does not pass; nothing written");
    }
    let copy_fixed = |w: &mut (dyn Write + Send)| {
        let mut fixed = File::open(tmp.path())?;
        std::io::copy(&mut fixed, w).map(|_| ())
    };
    if to_stdout {
        let mut out = BufWriter::with_capacity(1 << 16, stdout());
        copy_fixed(&mut out)
            .and_then(|()| out.flush())
            .context("writing the fixed G-code to standard output")?;
    } else {
        replace_file(target, copy_fixed)
            .with_context(|| format!("writing {}", target.display()))?;
    }
    // The report: on stdout, or on stderr when stdout carries the G-code.
    let mut out: Box<dyn Write> = if to_stdout {
        Box::new(std::io::stderr().lock())
    } else {
        Box::new(stdout())
    };
    match args.format {
        Format::Json => {
            let r = FixReport {
                file: name.clone(),
                output: report.file.clone(),
                commands: plan.commands,
                local: plan.local,
                original_print_time_s: plan.original_print_time_s,
                print_time_s: report.summary.print_time_s,
                recommendation: plan.recommendation.clone(),
                check: &report,
            };
            serde_json::to_writer_pretty(&mut out, &r)?;
            writeln!(out)?;
        }
        _ => {
            for l in summary_lines(&plan) {
                writeln!(out, "{}", l.trim_start_matches("; "))?;
            }
            write_text(&mut out, &report)?;
        }
    }
    out.flush()?;
    Ok(ExitCode::SUCCESS)
}

/// How the report names standard output.
const STDOUT_NAME: &str = "<stdout>";

/// The notes at the end of the fixed file: what was added and what it costs.
fn summary_lines(plan: &FixPlan) -> Vec<String> {
    let mut lines = vec![format!(
        "; delta-gcode fix: {} limit commands added ({}), print time {:.1} s (was {:.1} s)",
        plan.commands,
        if plan.local {
            "around the moves that need them"
        } else {
            "over the whole file: quicker than slowing only some moves"
        },
        plan.print_time_s,
        plan.original_print_time_s
    )];
    if let Some(r) = &plan.recommendation {
        lines.push(format!(
            "; delta-gcode fix: with {} over the whole file it would take {:.1} s",
            r.commands(),
            r.print_time_s
        ));
    }
    lines
}
