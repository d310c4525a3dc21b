//! `delta-gcode annotate FILE --machine M.yaml (-o OUT | --in-place)`: the analysis written
//! into the G-code, for slicer post-processing hooks.

use std::fs::File;
use std::io::BufReader;
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context;

use super::check::EXIT_VIOLATION;
use super::common::{MachineArg, Progress, RewriteArgs, check_with_progress, print_diagnostics};
use super::replace::replace_file;
use delta_gcode::emit::emit;
use delta_gcode::report::{annotations, summary_lines, write_json, write_text};

#[derive(clap::Args, Debug)]
pub struct Args {
    /// G-code file to annotate (a slicer hook appends it to the command line)
    #[arg(value_name = "FILE")]
    pub file: PathBuf,
    #[command(flatten)]
    pub machine: MachineArg,
    #[command(flatten)]
    pub write: RewriteArgs,
    /// Exit 1 when a move exceeds a limit (a slicer then aborts the export), 2 on input errors
    #[arg(long)]
    pub strict: bool,
    /// Also write the report here: JSON if the name ends in .json, text otherwise
    #[arg(long, value_name = "PATH")]
    pub report: Option<PathBuf>,
    /// No progress bar
    #[arg(long, short)]
    pub quiet: bool,
}

pub fn run(args: &Args) -> anyhow::Result<ExitCode> {
    let machine = args.machine.load()?;
    let report = check_with_progress(&args.file, &machine, false, &Progress::new(args.quiet))?;
    print_diagnostics(&report);
    let target = args.write.target(&args.file);
    let notes = annotations(&report);
    let summary = summary_lines(&report);
    replace_file(target, |w| {
        let input = BufReader::with_capacity(1 << 16, File::open(&args.file)?);
        emit(input, w, &notes, &summary)
    })
    .with_context(|| format!("annotating {}", args.file.display()))?;
    if let Some(path) = &args.report {
        let json = path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("json"));
        replace_file(path, |w| {
            if json {
                write_json(w, std::slice::from_ref(&report))
            } else {
                write_text(w, &report)
            }
        })?;
    }
    let s = &report.summary;
    if report.failed() {
        println!(
            "delta-gcode: WARNING: {}: {} moves exceed the limits of {} (peak force A/B/C {} N, limit {:.1} N); see the '; delta-gcode' lines",
            report.file,
            s.violations,
            report.machine,
            delta_gcode::report::format_forces(&s.peak_force_n),
            report.limit_force_n
        );
    } else {
        println!(
            "delta-gcode: {}: OK on {}, peak force A/B/C {} N (limit {:.1} N)",
            report.file,
            report.machine,
            delta_gcode::report::format_forces(&s.peak_force_n),
            report.limit_force_n
        );
    }
    Ok(if args.strict && s.errors > 0 {
        ExitCode::from(super::EXIT_ERROR)
    } else if args.strict && report.failed() {
        ExitCode::from(EXIT_VIOLATION)
    } else {
        ExitCode::SUCCESS
    })
}
