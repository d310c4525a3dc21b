//! `delta-gcode fix FILE --machine M.yaml (-o OUT | --in-place)`: the G-code with the
//! firmware's limit commands added around the moves that need them, so that every move
//! passes; checked again before it is written.

use std::fs::File;
use std::io::{BufReader, Write};
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context;
use serde::Serialize;

use super::check::EXIT_VIOLATION;
use super::common::{Format, MachineArg, RewriteArgs, text_or_json};
use super::out::{say, stdout};
use super::replace::replace_file;
use delta_gcode::emit::{Drop, emit_with};
use delta_gcode::report::{Recommendation, Report, write_text};
use delta_gcode::tune::{FixPlan, Unfixable, plan_fix};

#[derive(clap::Args, Debug)]
pub struct Args {
    /// G-code file to fix (a slicer hook appends it to the command line)
    #[arg(value_name = "FILE")]
    pub file: PathBuf,
    #[command(flatten)]
    pub machine: MachineArg,
    #[command(flatten)]
    pub write: RewriteArgs,
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
    let machine = args.machine.load()?;
    let plan = match plan_fix(&args.file, &machine) {
        Ok(p) => p,
        Err(e) if e.is::<Unfixable>() => {
            say!("delta-gcode: fix: {}: {e:#}", args.file.display());
            return Ok(ExitCode::from(EXIT_VIOLATION));
        }
        Err(e) => return Err(e.context(format!("fixing {}", args.file.display()))),
    };
    let target = args.write.target(&args.file);
    let mut additions = plan.additions.clone();
    additions.summary = summary_lines(&plan);
    // The fixed file, checked as the firmware will read it before it replaces anything.
    let dir = match target.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => std::path::Path::new("."),
    };
    let mut tmp = tempfile::Builder::new()
        .prefix(".delta-gcode-fix.")
        .tempfile_in(dir)
        .with_context(|| format!("cannot create a temporary file in {}", dir.display()))?;
    let input = BufReader::with_capacity(1 << 16, File::open(&args.file)?);
    emit_with(input, tmp.as_file_mut(), &additions, Drop::All)
        .with_context(|| format!("fixing {}", args.file.display()))?;
    let mut report = delta_gcode::analysis::check_file(tmp.path(), &machine, false, None)?;
    report.file = target.display().to_string();
    if report.failed() {
        anyhow::bail!(
            "internal error: the fixed {} does not pass; nothing written",
            args.file.display()
        );
    }
    replace_file(target, |w| {
        let mut fixed = File::open(tmp.path())?;
        std::io::copy(&mut fixed, w).map(|_| ())
    })
    .with_context(|| format!("writing {}", target.display()))?;
    let mut out = stdout();
    match args.format {
        Format::Json => {
            let r = FixReport {
                file: args.file.display().to_string(),
                output: target.display().to_string(),
                commands: plan.commands,
                local: plan.local,
                original_print_time_s: plan.original_print_time_s,
                print_time_s: report.summary.print_time_s,
                recommendation: plan.recommendation,
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
    Ok(ExitCode::SUCCESS)
}

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
