//! Pieces the file commands share: the machine profile, progress bars, diagnostics.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};

use anyhow::Context;
use indicatif::{MultiProgress, ProgressBar, ProgressStyle};

use delta_gcode::machine::Machine;
use delta_gcode::report::Report;

/// Files smaller than this get no progress bar: they are done before it would be seen.
const PROGRESS_MIN_BYTES: u64 = 8 << 20;

/// How many diagnostics of a file are printed to stderr; all are in the JSON report.
const DIAGNOSTICS_SHOWN: usize = 20;

/// Output formats: text for a person, JSON for scripts, GitHub Actions workflow commands
/// for CI annotations (file reports only: `check`).
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    Text,
    Json,
    Github,
}

/// The `--format` values of the commands that report no file (`pose`, `machine`): text or
/// JSON.
pub fn text_or_json() -> impl clap::builder::TypedValueParser<Value = Format> {
    use clap::ValueEnum;
    use clap::builder::TypedValueParser;
    clap::builder::PossibleValuesParser::new(["text", "json"])
        .map(|s| Format::from_str(&s, true).unwrap_or(Format::Text))
}

/// The `--machine` option.
#[derive(clap::Args, Debug)]
pub struct MachineArg {
    /// Machine profile (YAML), e.g. machines/kossel.yaml
    #[arg(long, short, value_name = "M.yaml")]
    pub machine: PathBuf,
}

impl MachineArg {
    pub fn load(&self) -> anyhow::Result<Machine> {
        Ok(Machine::load(&self.machine)?)
    }
}

/// Where a command that rewrites a G-code file writes it: `-o OUT` or `--in-place`.
#[derive(clap::Args, Debug)]
pub struct RewriteArgs {
    /// Write the new G-code here
    #[arg(long, short, value_name = "OUT", required_unless_present = "in_place")]
    pub output: Option<PathBuf>,
    /// Replace FILE by its new version (whole or not at all)
    #[arg(long, conflicts_with = "output")]
    pub in_place: bool,
}

impl RewriteArgs {
    /// The file to write: OUT, or `file` itself.
    pub fn target<'a>(&'a self, file: &'a Path) -> &'a Path {
        self.output.as_deref().unwrap_or(file)
    }
}

/// Progress bars on stderr, one per large file, only when stderr is a terminal.
pub struct Progress {
    multi: Option<MultiProgress>,
}

impl Progress {
    pub fn new(quiet: bool) -> Self {
        let show = !quiet && std::io::stderr().is_terminal();
        Progress {
            multi: show.then(MultiProgress::new),
        }
    }

    /// A bar over the bytes of `path`, if it is large enough to be worth one.
    pub fn bar(&self, path: &Path) -> Option<ProgressBar> {
        let multi = self.multi.as_ref()?;
        let len = std::fs::metadata(path).ok()?.len();
        if len < PROGRESS_MIN_BYTES {
            return None;
        }
        let style = ProgressStyle::with_template(
            "{prefix} [{bar:30}] {bytes}/{total_bytes} {bytes_per_sec}, {msg} ETA {eta}",
        )
        .ok()?
        .progress_chars("=> ");
        let bar = multi.add(ProgressBar::new(len).with_style(style));
        bar.set_prefix(path.display().to_string());
        Some(bar)
    }
}

/// Prints a file's diagnostics to stderr as `file:line:column: severity: message`.
pub fn print_diagnostics(report: &Report) {
    for d in report.diagnostics.iter().take(DIAGNOSTICS_SHOWN) {
        eprintln!(
            "{}:{}:{}: {}: {}",
            report.file, d.line, d.column, d.severity, d.message
        );
    }
    let total = (report.summary.warnings + report.summary.errors) as usize;
    if total > DIAGNOSTICS_SHOWN {
        eprintln!(
            "{}: … and {} more diagnostics",
            report.file,
            total - DIAGNOSTICS_SHOWN
        );
    }
}

/// Checks a file with a progress bar of its own.
pub fn check_with_progress(
    path: &Path,
    machine: &Machine,
    all_moves: bool,
    progress: &Progress,
) -> anyhow::Result<Report> {
    let bar = progress.bar(path);
    let report = delta_gcode::analysis::check_file(path, machine, all_moves, bar.as_ref())
        .with_context(|| format!("checking {}", path.display()));
    if let Some(bar) = bar {
        bar.finish_and_clear();
    }
    report
}
