//! The G-code named on the command line: a file, or `-` for standard input; refused when it
//! is not G-code (compressed, a 3D model, binary G-code, binary data: `gcode::sniff`) or
//! has no motion.

use std::fs::File;
use std::io::{self, Read};
use std::path::{Path, PathBuf};

use anyhow::{Context, bail};

use delta_gcode::gcode::{SNIFF_BYTES, sniff};

/// How reports name standard input.
pub const STDIN_NAME: &str = "<stdin>";

/// A G-code input, ready to be read (as often as needed) from `path`.
pub struct Input {
    /// The file, or a temporary copy of standard input or a pipe (the analysis reads its
    /// input twice: once to check it, once for the text of the flagged lines or to
    /// annotate it).
    pub path: PathBuf,
    /// The name reports give it: the path as given, or [`STDIN_NAME`].
    pub name: String,
    /// The copy of standard input or a pipe, removed when the input is dropped.
    _copy: Option<tempfile::TempPath>,
}

impl Input {
    /// Opens the input `arg` names (`-`: standard input) and looks at its first bytes.
    /// Standard input and a pipe (`<(xz -dc part.gcode.xz)`) are copied first: they can
    /// be read only once.
    pub fn open(arg: &Path) -> anyhow::Result<Input> {
        let name = arg.display().to_string();
        let input = if is_stdin(arg) {
            Input::copied(&mut io::stdin().lock(), STDIN_NAME.to_string())?
        } else if std::fs::metadata(arg).is_ok_and(|m| !m.is_file() && !m.is_dir()) {
            let mut pipe = File::open(arg).with_context(|| format!("cannot open {name}"))?;
            Input::copied(&mut pipe, name)?
        } else {
            Input {
                path: arg.to_path_buf(),
                name,
                _copy: None,
            }
        };
        input.refuse_non_gcode()?;
        Ok(input)
    }

    /// `from` copied into a private temporary file, removed when the input is dropped.
    fn copied(from: &mut impl Read, name: String) -> anyhow::Result<Input> {
        let mut copy = tempfile::Builder::new()
            .prefix("delta-gcode-input.")
            .tempfile()
            .with_context(|| format!("cannot create a temporary file for {name}"))?;
        io::copy(from, copy.as_file_mut()).with_context(|| format!("cannot read {name}"))?;
        Ok(Input {
            path: copy.path().to_path_buf(),
            name,
            _copy: Some(copy.into_temp_path()),
        })
    }

    /// The name of its plots: the file's stem, or `stdin`.
    pub fn stem(&self) -> String {
        if self.name == STDIN_NAME {
            return "stdin".to_string();
        }
        self.path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default()
    }

    /// An input error when the first bytes are not text G-code.
    fn refuse_non_gcode(&self) -> anyhow::Result<()> {
        let name = &self.name;
        let file = File::open(&self.path).with_context(|| format!("cannot open {name}"))?;
        let len = file.metadata().ok().map(|m| m.len());
        let mut head = Vec::with_capacity(SNIFF_BYTES);
        file.take(SNIFF_BYTES as u64)
            .read_to_end(&mut head)
            .with_context(|| format!("cannot read {name}"))?;
        if let Some(kind) = sniff(&head, len) {
            bail!("{}", kind.message(name));
        }
        Ok(())
    }

    /// An input error when the analysis found no move: an empty file, comments only,
    /// settings only. A gate must not pass a file it did not check.
    pub fn refuse_no_motion(&self, lines: u64, errors: u64) -> anyhow::Result<()> {
        let name = &self.name;
        if lines == 0 {
            bail!("{name} is empty: there is no G-code to check");
        }
        let skipped = match errors {
            0 => String::new(),
            1 => " (1 line with an error was skipped)".to_string(),
            n => format!(" ({n} lines with errors were skipped)"),
        };
        bail!(
            "{name} has no motion: none of its {lines} lines moves the nozzle{skipped}; is it the G-code you meant?"
        )
    }
}

/// Whether a FILE argument names standard input.
pub fn is_stdin(arg: &Path) -> bool {
    arg.as_os_str() == "-"
}

/// Refuses `-` given more than once: standard input can be read only once.
pub fn stdin_at_most_once(files: &[PathBuf]) -> anyhow::Result<()> {
    if files.iter().filter(|f| is_stdin(f)).count() > 1 {
        bail!("`-` (standard input) can be given only once");
    }
    Ok(())
}
