//! `delta-gcode annotate FILE --machine M.yaml (-o OUT | --in-place)`: the analysis written
//! into the G-code, for slicer post-processing hooks.

use std::fs::File;
use std::io::{BufReader, BufWriter, Write};
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, bail};

use super::check::EXIT_VIOLATION;
use super::common::{MachineArg, Progress, VerboseArg, check_with_progress, print_diagnostics};
use super::input::{Input, is_stdin};
use super::out::{say, stdout};
use super::replace::replace_file;
use delta_gcode::emit::emit;
use delta_gcode::report::{annotations, summary_lines, verdict_line, write_json, write_text};

#[derive(clap::Args, Debug)]
pub struct Args {
    /// G-code file to annotate (a slicer hook appends it to the command line); `-` reads
    /// standard input (then with -o)
    #[arg(value_name = "FILE")]
    pub file: PathBuf,
    #[command(flatten)]
    pub machine: MachineArg,
    /// Write the annotated G-code here; `-` for standard output
    #[arg(long, short, value_name = "OUT", required_unless_present = "in_place")]
    pub output: Option<PathBuf>,
    /// Replace FILE by its annotated version (whole or not at all)
    #[arg(long, conflicts_with = "output")]
    pub in_place: bool,
    /// Exit 1 when a move exceeds a limit (a slicer then aborts the export), 2 on input errors
    #[arg(long)]
    pub strict: bool,
    /// Also write the report here: JSON if the name ends in .json, text otherwise
    #[arg(long, value_name = "PATH")]
    pub report: Option<PathBuf>,
    /// No progress bar
    #[arg(long, short)]
    pub quiet: bool,
    #[command(flatten)]
    pub verbose: VerboseArg,
}

pub fn run(args: &Args) -> anyhow::Result<ExitCode> {
    if args.in_place && is_stdin(&args.file) {
        bail!("--in-place needs a file, not standard input: give -o OUT");
    }
    let machine = args.machine.load()?;
    let input = Input::open(&args.file)?;
    let report = check_with_progress(
        &input,
        &machine,
        false,
        &Progress::new(args.quiet),
        args.verbose.verbose,
    )?;
    // The verdict first: a slicer shows the start of a failing hook's stderr.
    say!("{}", verdict_line(&report));
    for note in &report.notes {
        say!("delta-gcode: note: {note}");
    }
    if report.failed() || report.summary.errors > 0 || args.verbose.verbose {
        print_diagnostics(&report, args.verbose.verbose);
    }
    let notes = annotations(&report);
    let summary = summary_lines(&report);
    let annotate = |w: &mut (dyn Write + Send)| {
        let from = BufReader::with_capacity(1 << 16, File::open(&input.path)?);
        emit(from, w, &notes, &summary)
    };
    match &args.output {
        Some(out) if is_stdin(out) => {
            let mut out = BufWriter::with_capacity(1 << 16, stdout());
            annotate(&mut out).and_then(|()| out.flush())
        }
        .with_context(|| format!("annotating {}", input.name))?,
        target => replace_file(target.as_ref().unwrap_or(&args.file), annotate)
            .with_context(|| format!("annotating {}", input.name))?,
    }
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
    Ok(if args.strict && report.summary.errors > 0 {
        ExitCode::from(super::EXIT_ERROR)
    } else if args.strict && report.failed() {
        ExitCode::from(EXIT_VIOLATION)
    } else {
        ExitCode::SUCCESS
    })
}
