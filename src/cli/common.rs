//! Pieces the file commands share: the machine profile, progress bars, diagnostics.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};

use anyhow::Context;
use indicatif::{MultiProgress, ProgressBar, ProgressStyle};

use super::input::Input;
use super::out::say;
use delta_gcode::machine::Machine;
use delta_gcode::report::{DiagnosticKind, Report, severity_name};

/// Files smaller than this get no progress bar: they are done before it would be seen.
const PROGRESS_MIN_BYTES: u64 = 8 << 20;

/// How many diagnostics of a file `--verbose` prints to stderr; all are in the JSON report.
const DIAGNOSTICS_SHOWN: usize = 1000;

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

    /// A bar over the bytes of `path` (reported as `name`), if it is large enough to be
    /// worth one.
    pub fn bar(&self, path: &Path, name: &str) -> Option<ProgressBar> {
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
        bar.set_prefix(name.to_string());
        Some(bar)
    }
}

/// The `--verbose` option of the file commands.
#[derive(clap::Args, Debug)]
pub struct VerboseArg {
    /// List every diagnostic (up to 1000) instead of one line per kind
    #[arg(long, short)]
    pub verbose: bool,
}

/// Prints a file's diagnostics to stderr as `file:line:column: severity: message`: one
/// line per kind, with its count and first lines, or (`verbose`) each of them.
pub fn print_diagnostics(report: &Report, verbose: bool) {
    if verbose {
        for d in report.diagnostics.iter().take(DIAGNOSTICS_SHOWN) {
            say!(
                "{}:{}:{}: {}: {}",
                report.file,
                d.line,
                d.column,
                d.severity,
                d.message
            );
        }
        let total = (report.summary.warnings + report.summary.errors) as usize;
        if total > DIAGNOSTICS_SHOWN {
            say!(
                "{}: … and {} more diagnostics (all counted in the JSON report's diagnostic_kinds)",
                report.file,
                total - DIAGNOSTICS_SHOWN
            );
        }
        return;
    }
    for k in report.diagnostic_kinds.as_slice() {
        say!("{}", diagnostic_kind_line(&report.file, k));
    }
}

/// One kind of diagnostic in one line: the first one's place and message, then how many
/// there are and their first lines.
pub fn diagnostic_kind_line(file: &str, k: &DiagnosticKind) -> String {
    let first = k.lines.first().copied().unwrap_or(0);
    let mut line = format!(
        "{file}:{first}:{}: {}: {}",
        k.column,
        severity_name(k.severity),
        k.message
    );
    if k.count > 1 {
        let lines: Vec<String> = k.lines.iter().map(u64::to_string).collect();
        let more = if k.count > k.lines.len() as u64 {
            ", …"
        } else {
            ""
        };
        line += &format!(
            " [{} times: lines {}{more}; --verbose lists each]",
            k.count,
            lines.join(", ")
        );
    }
    line
}

/// Checks a file with a progress bar of its own; a file without a single move is an
/// input error (a gate must not pass a file it did not check), its diagnostics printed
/// first (`verbose`: each).
pub fn check_with_progress(
    input: &Input,
    machine: &Machine,
    all_moves: bool,
    progress: &Progress,
    verbose: bool,
) -> anyhow::Result<Report> {
    let bar = progress.bar(&input.path, &input.name);
    let report = delta_gcode::analysis::check_file(&input.path, machine, all_moves, bar.as_ref())
        .with_context(|| format!("checking {}", input.name));
    if let Some(bar) = bar {
        bar.finish_and_clear();
    }
    let mut report = report?;
    report.file.clone_from(&input.name);
    if report.summary.moves == 0 {
        print_diagnostics(&report, verbose);
        input.refuse_no_motion(report.summary.lines, report.summary.errors)?;
    }
    Ok(report)
}
