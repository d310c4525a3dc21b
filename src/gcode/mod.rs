//! Reading G-code: a streaming line reader, a per-line nom parser, and the modal
//! interpreter that turns lines into [`Event`]s for the planner.

pub mod arc;
pub mod dialect;
mod event;
mod interp;
mod marlin;
pub mod parse;
pub mod reader;
mod scan;
pub mod sniff;

use std::io::Read;

pub use arc::{ArcRules, Plane};
pub use dialect::{DeltaSettings, Dialect, FirmwareKind, SoftEndstops};
pub use event::{
    ArcChord, DeltaChange, Diagnostic, Event, LimitChange, MarlinChange, Move, Severity,
};
pub use interp::{DEFAULT_FEED_MM_MIN, Interpreter, M204_P_OR_T_IGNORED, ReadStats, Retraction};
pub use parse::{Command, ParsedLine, Word, parse_line};
pub use reader::{ChunkReader, Line, LineReader};
pub use sniff::{NotGcode, SNIFF_BYTES, sniff};

use crate::path::Vec3;

/// Reads G-code from `input` line by line and interprets it, nozzle starting at
/// `home_mm` (the position after G28: `(0, 0, home_z)`), as the firmware of `dialect` reads
/// it (`Machine::dialect()`; a bare [`ArcRules`] is Klipper's dialect with those arcs).
/// Events and diagnostics go to the callbacks in line order; the counts come back at the
/// end. Only I/O fails.
pub fn interpret<R: Read>(
    input: R,
    home_mm: Vec3,
    dialect: impl Into<Dialect>,
    mut on_event: impl FnMut(Event),
    mut on_diag: impl FnMut(Diagnostic),
) -> std::io::Result<ReadStats> {
    let mut reader = LineReader::new(input);
    let mut interp = Interpreter::new(home_mm, dialect);
    while let Some(line) = reader.next_line()? {
        interp.line(
            line.number,
            line.bytes,
            line.truncated,
            &mut on_event,
            &mut on_diag,
        );
    }
    let mut stats = interp.stats();
    stats.bytes = reader.bytes_read();
    Ok(stats)
}
