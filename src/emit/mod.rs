//! The emitter: input lines byte-for-byte, with our lines added: `; delta-gcode` notes
//! (`annotate`) and limit commands ending in `; delta-gcode` (`fix`).
//!
//! Guarantees:
//! - Every input line that is not ours (see [`is_ours`] and [`Drop`]) is written
//!   byte-for-byte, in order, streamed piece by piece (a line of any length is never held
//!   whole).
//! - Our lines from an earlier run are dropped, so annotating (or fixing) twice equals
//!   doing it once, and [`strip`] of the output gives the input back. `annotate` drops only
//!   the notes (lines starting with [`PREFIX`]) and keeps `fix`'s commands as input;
//!   `fix` and `strip` drop both.
//! - Before input line N come the strings of `before[N]`, after it those of `after[N]`, each
//!   as its own line ended with the terminator of the line before it (line N's own for
//!   `after`); then the `summary` lines, ended with the last line's terminator. Line
//!   numbers are those of the input as read (old lines of ours count), the numbering of
//!   [`crate::gcode::interpret`]; numbers of dropped or missing lines are ignored.
//! - An input whose last line has no terminator: our lines still follow it, so that line
//!   gets the terminator of the other lines (the first one found; LF when there is none) and the output ends with the
//!   marker line [`NO_FINAL_NEWLINE`]. Dropping our lines then also drops the terminator
//!   in front of a marker that ends the file, which gives the input back. Nothing to add:
//!   nothing changes.

use std::collections::BTreeMap;
use std::io::{self, ErrorKind, Read, Write};

use crate::gcode::ChunkReader;

/// Every line we add starts with this.
pub const PREFIX: &[u8] = b"; delta-gcode";

/// The last line of an output whose input ended without a line terminator.
pub const NO_FINAL_NEWLINE: &str =
    "; delta-gcode: the input ended without a newline after the line above this block";

/// Which of our lines in the input are dropped (and which the added lines may be).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Drop {
    /// The notes, lines starting with [`PREFIX`] (`annotate`: `fix`'s commands are input to
    /// it).
    Notes,
    /// The notes and the commands `fix` added, lines ending with [`PREFIX`] (`fix`, `strip`).
    All,
}

/// Whether a line is ours, from its first piece (`whole`: that piece is the whole line; our
/// commands are always short enough to be).
pub fn is_ours(first_piece: &[u8], whole: bool, drop: Drop) -> bool {
    first_piece.starts_with(PREFIX)
        || (drop == Drop::All
            && whole
            && strip_term(first_piece).trim_ascii_end().ends_with(PREFIX))
}

/// The lines to add to an input (see the module documentation).
#[derive(Clone, Debug, Default)]
pub struct Additions {
    pub before: BTreeMap<u64, Vec<String>>,
    pub after: BTreeMap<u64, Vec<String>>,
    pub summary: Vec<String>,
}

/// Writes `input` to `output` with annotations after their lines and the summary at the
/// end (see the module documentation). Every string must start with `; delta-gcode` and
/// hold no line break; otherwise nothing is written and the error is `InvalidInput`.
pub fn emit<R: Read, W: Write>(
    input: R,
    output: W,
    annotations: &BTreeMap<u64, Vec<String>>,
    summary: &[String],
) -> io::Result<()> {
    let add = Additions {
        before: BTreeMap::new(),
        after: annotations.clone(),
        summary: summary.to_vec(),
    };
    emit_with(input, output, &add, Drop::Notes)
}

/// Writes `input` to `output` without our lines of `drop`, with the lines of `add` (see
/// the module documentation). Every added string must be one line that `drop` would drop;
/// otherwise nothing is written and the error is `InvalidInput`.
pub fn emit_with<R: Read, W: Write>(
    input: R,
    output: W,
    add: &Additions,
    drop: Drop,
) -> io::Result<()> {
    let annotations = &add.after;
    let summary = &add.summary[..];
    let all = add.before.values().chain(annotations.values()).flatten();
    for s in all.chain(summary) {
        if !is_ours(s.as_bytes(), true, drop) || s.contains(['\n', '\r']) {
            return Err(io::Error::new(
                ErrorKind::InvalidInput,
                format!("an added line must be ours (`; delta-gcode`) and one line: {s:?}"),
            ));
        }
    }
    let mut out = io::BufWriter::with_capacity(1 << 16, output);
    let mut chunks = ChunkReader::new(input);
    // The first terminator of a kept line followed by another kept line, for lines that
    // have none of their own (the last line's may be our addition, see NO_FINAL_NEWLINE).
    let mut default_term: Option<&'static [u8]> = None;
    // The last kept line: its number and terminator, not yet written.
    let mut pending: Option<(u64, &'static [u8])> = None;
    let mut dropping = false;
    // The terminator of our end-of-file marker, when it is the last line read.
    let mut marker_last: Option<&'static [u8]> = None;

    while let Some(c) = chunks.next_chunk()? {
        let term = terminator(c.bytes, c.last);
        if c.first {
            dropping = is_ours(c.bytes, c.last, drop);
            marker_last = None;
            if !dropping {
                let before_term = match pending {
                    Some((_, t)) => t,
                    None if !term.is_empty() => term,
                    None => b"\n",
                };
                if let Some((_, t)) = pending {
                    default_term = default_term.or(Some(t));
                    flush_pending(&mut out, &mut pending, annotations)?;
                }
                write_lines(
                    &mut out,
                    add.before.get(&c.line).into_iter().flatten(),
                    before_term,
                )?;
            }
        }
        if dropping {
            if c.last && c.first && strip_term(c.bytes) == NO_FINAL_NEWLINE.as_bytes() {
                marker_last = Some(term);
            }
            continue;
        }
        out.write_all(&c.bytes[..c.bytes.len() - term.len()])?;
        if c.last {
            pending = Some((c.line, term));
        }
    }

    let default_term = default_term.unwrap_or(b"\n");
    if let (Some((n, term)), Some(added)) = (pending, marker_last)
        && term.ends_with(added)
    {
        // Our marker ends the input: the terminator after the last kept line was ours
        // (what is left of it, a CR, was the line's own).
        out.write_all(&term[..term.len() - added.len()])?;
        pending = Some((n, b""));
    }
    match pending {
        // The input's last line had a terminator: write it, then our lines after it.
        Some((n, term)) if !term.is_empty() => {
            out.write_all(term)?;
            write_lines(&mut out, annotations.get(&n).into_iter().flatten(), term)?;
            write_lines(&mut out, summary.iter(), term)?;
        }
        // No terminator after the last line.
        Some((n, _)) => {
            let ours = annotations.get(&n).into_iter().flatten().chain(summary);
            if ours.clone().next().is_some() {
                out.write_all(default_term)?;
                write_lines(&mut out, ours, default_term)?;
                out.write_all(NO_FINAL_NEWLINE.as_bytes())?;
                out.write_all(default_term)?;
            }
        }
        None => write_lines(&mut out, summary.iter(), default_term)?,
    }
    out.flush()
}

/// Drops the lines an earlier run of `annotate` or `fix` added: `strip(emit(x)) == x`.
pub fn strip<R: Read, W: Write>(input: R, output: W) -> io::Result<()> {
    emit_with(input, output, &Additions::default(), Drop::All)
}

/// The input with our lines (of `fix` and `annotate`) made empty: what `fix` plans, the
/// same motion as the input had before any run of ours, with the same line numbers.
pub struct WithoutOurs<R> {
    chunks: ChunkReader<R>,
    /// Bytes of the current piece not yet read.
    out: Vec<u8>,
    pos: usize,
    dropping: bool,
}

impl<R: Read> WithoutOurs<R> {
    pub fn new(input: R) -> Self {
        WithoutOurs {
            chunks: ChunkReader::new(input),
            out: Vec::new(),
            pos: 0,
            dropping: false,
        }
    }
}

impl<R: Read> Read for WithoutOurs<R> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        while self.pos == self.out.len() {
            self.out.clear();
            self.pos = 0;
            let Some(c) = self.chunks.next_chunk()? else {
                return Ok(0);
            };
            if c.first {
                self.dropping = is_ours(c.bytes, c.last, Drop::All);
            }
            if self.dropping {
                self.out.extend_from_slice(terminator(c.bytes, c.last));
            } else {
                self.out.extend_from_slice(c.bytes);
            }
        }
        let n = buf.len().min(self.out.len() - self.pos);
        buf[..n].copy_from_slice(&self.out[self.pos..self.pos + n]);
        self.pos += n;
        Ok(n)
    }
}

/// Writes the held terminator of the previous kept line and its annotations.
fn flush_pending<W: Write>(
    out: &mut W,
    pending: &mut Option<(u64, &'static [u8])>,
    annotations: &BTreeMap<u64, Vec<String>>,
) -> io::Result<()> {
    if let Some((n, term)) = pending.take() {
        out.write_all(term)?;
        write_lines(out, annotations.get(&n).into_iter().flatten(), term)?;
    }
    Ok(())
}

fn write_lines<'a, W: Write>(
    out: &mut W,
    lines: impl Iterator<Item = &'a String>,
    term: &[u8],
) -> io::Result<()> {
    for l in lines {
        out.write_all(l.as_bytes())?;
        out.write_all(term)?;
    }
    Ok(())
}

/// The terminator at the end of a line's last piece: CRLF, LF or nothing.
fn terminator(bytes: &[u8], last: bool) -> &'static [u8] {
    if !last {
        b""
    } else if bytes.ends_with(b"\r\n") {
        b"\r\n"
    } else if bytes.ends_with(b"\n") {
        b"\n"
    } else {
        b""
    }
}

fn strip_term(bytes: &[u8]) -> &[u8] {
    crate::gcode::parse::strip_terminator(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(input: &[u8], ann: &[(u64, &str)], summary: &[&str]) -> Vec<u8> {
        let mut map: BTreeMap<u64, Vec<String>> = BTreeMap::new();
        for (n, s) in ann {
            map.entry(*n).or_default().push(s.to_string());
        }
        let summary: Vec<String> = summary.iter().map(|s| s.to_string()).collect();
        let mut out = Vec::new();
        emit(input, &mut out, &map, &summary).unwrap();
        out
    }

    fn stripped(input: &[u8]) -> Vec<u8> {
        let mut out = Vec::new();
        strip(input, &mut out).unwrap();
        out
    }

    #[test]
    fn annotations_follow_their_line_with_its_terminator() {
        let input = b"G1 X1\r\nG1 X2\nG1 X3\n";
        let out = run(
            input,
            &[(2, "; delta-gcode: a"), (2, "; delta-gcode: b")],
            &["; delta-gcode summary"],
        );
        assert_eq!(
            out,
            b"G1 X1\r\nG1 X2\n; delta-gcode: a\n; delta-gcode: b\nG1 X3\n; delta-gcode summary\n"
        );
        assert_eq!(stripped(&out), input);
        let out = run(input, &[(1, "; delta-gcode: a")], &[]);
        assert_eq!(out, b"G1 X1\r\n; delta-gcode: a\r\nG1 X2\nG1 X3\n");
    }

    #[test]
    fn reannotating_replaces_old_lines() {
        let input = b"G1 X1\nG1 X2\n";
        let once = run(input, &[(1, "; delta-gcode: old")], &["; delta-gcode: s1"]);
        // Line numbers of the annotated file: G1 X2 is now line 3.
        let twice = run(&once, &[(1, "; delta-gcode: old")], &["; delta-gcode: s1"]);
        assert_eq!(twice, once);
        let other = run(&once, &[(3, "; delta-gcode: new")], &["; delta-gcode: s2"]);
        assert_eq!(
            other,
            b"G1 X1\nG1 X2\n; delta-gcode: new\n; delta-gcode: s2\n"
        );
    }

    #[test]
    fn last_line_without_terminator_is_recoverable() {
        let input = b"G1 X1\r\nG1 X2";
        let out = run(input, &[(2, "; delta-gcode: a")], &["; delta-gcode: s"]);
        let want = format!(
            "G1 X1\r\nG1 X2\r\n; delta-gcode: a\r\n; delta-gcode: s\r\n{NO_FINAL_NEWLINE}\r\n"
        );
        assert_eq!(out, want.as_bytes());
        assert_eq!(stripped(&out), input);
        // Idempotent.
        assert_eq!(
            run(&out, &[(2, "; delta-gcode: a")], &["; delta-gcode: s"]),
            out
        );
        // Nothing to add: unchanged.
        assert_eq!(run(input, &[], &[]), input);
        // A single line without any terminator in the file: LF.
        let out = run(b"G28", &[], &["; delta-gcode: s"]);
        assert_eq!(
            out,
            format!("G28\n; delta-gcode: s\n{NO_FINAL_NEWLINE}\n").as_bytes()
        );
        assert_eq!(stripped(&out), b"G28");
    }

    #[test]
    fn last_line_ending_in_a_lone_cr() {
        for input in [&b"a\rb\r"[..], b"G1\nx\r", b"G1\r\nx\r"] {
            let out = run(input, &[(1, "; delta-gcode: a")], &["; delta-gcode: s"]);
            assert_eq!(stripped(&out), input);
            assert_eq!(
                run(&out, &[(1, "; delta-gcode: a")], &["; delta-gcode: s"]),
                out
            );
        }
    }

    #[test]
    fn marker_in_the_middle_is_just_dropped() {
        let input = format!("G1 X1\n{NO_FINAL_NEWLINE}\nG1 X2\n");
        assert_eq!(stripped(input.as_bytes()), b"G1 X1\nG1 X2\n");
    }

    #[test]
    fn empty_input_gets_only_the_summary() {
        assert_eq!(run(b"", &[], &["; delta-gcode: s"]), b"; delta-gcode: s\n");
        assert_eq!(stripped(b"; delta-gcode: s\n"), b"");
    }

    #[test]
    fn rejects_foreign_strings() {
        let mut map = BTreeMap::new();
        map.insert(1, vec!["G1 X1".to_string()]);
        let e = emit(&b"G1\n"[..], Vec::new(), &map, &[]).unwrap_err();
        assert_eq!(e.kind(), ErrorKind::InvalidInput);
        let e = emit(
            &b"G1\n"[..],
            Vec::new(),
            &BTreeMap::new(),
            &["; delta-gcode\nG1".into()],
        )
        .unwrap_err();
        assert_eq!(e.kind(), ErrorKind::InvalidInput);
    }

    #[test]
    fn fix_commands_go_before_their_line_and_strip_away() {
        let input = b"G1 X1\r\n; delta-gcode: note\r\nSET_VELOCITY_LIMIT ACCEL=1 ; delta-gcode\r\nG1 X2\r\nG1 X3";
        let mut add = Additions::default();
        add.before
            .insert(1, vec!["SET_VELOCITY_LIMIT ACCEL=9 ; delta-gcode".into()]);
        add.before
            .insert(4, vec!["SET_VELOCITY_LIMIT ACCEL=2 ; delta-gcode".into()]);
        add.after.insert(4, vec!["; delta-gcode: after".into()]);
        let mut out = Vec::new();
        emit_with(&input[..], &mut out, &add, Drop::All).unwrap();
        let want = "SET_VELOCITY_LIMIT ACCEL=9 ; delta-gcode\r\nG1 X1\r\nSET_VELOCITY_LIMIT ACCEL=2 ; delta-gcode\r\nG1 X2\r\n; delta-gcode: after\r\nG1 X3";
        assert_eq!(String::from_utf8_lossy(&out), want);
        assert_eq!(stripped(&out), b"G1 X1\r\nG1 X2\r\nG1 X3");
        // `annotate` keeps the commands (they are its input), drops only the notes.
        assert_eq!(
            run(input, &[], &[]),
            b"G1 X1\r\nSET_VELOCITY_LIMIT ACCEL=1 ; delta-gcode\r\nG1 X2\r\nG1 X3"
        );
        // A note may not be added before a line with `Drop::Notes`, nor a command.
        let e = emit(
            &input[..],
            Vec::new(),
            &BTreeMap::from([(1, vec!["M204 S1 ; delta-gcode".into()])]),
            &[],
        );
        assert_eq!(e.unwrap_err().kind(), ErrorKind::InvalidInput);
        // Planned without our lines, with the same line numbers.
        let mut blanked = Vec::new();
        WithoutOurs::new(&input[..])
            .read_to_end(&mut blanked)
            .unwrap();
        assert_eq!(blanked, b"G1 X1\r\n\r\n\r\nG1 X2\r\nG1 X3");
    }

    #[test]
    fn long_lines_stream_through() {
        let mut input = vec![b'x'; 300_000];
        input.extend_from_slice(b"\n; delta-gcode old\n");
        input.extend(std::iter::repeat_n(b'y', 300_000));
        let out = run(&input, &[(1, "; delta-gcode: a")], &[]);
        let mut want = vec![b'x'; 300_000];
        want.extend_from_slice(b"\n; delta-gcode: a\n");
        want.extend(std::iter::repeat_n(b'y', 300_000));
        assert_eq!(out, want);
    }
}
