//! A file's diagnostics grouped by kind: one entry per kind of message, with its count
//! and its first lines, so that a warning on every other line (a Marlin file's `M204 P…`
//! read for Klipper) is one line of the report, not a thousand that bury the rest.
//!
//! The kind of a diagnostic is its severity and its message with every number in it
//! blanked: `checksum mismatch: the line says *43, its bytes give *42` is one kind whatever
//! the numbers.

use std::collections::HashMap;

use serde::Serialize;

use super::MAX_LISTED;
use crate::gcode::{Diagnostic, Severity};

/// The lines of each kind kept (all are counted).
pub const KIND_LINES: usize = 5;

/// At most this many kinds are told apart; the diagnostics of further kinds are counted
/// in the last one (a file of random text could make a kind per line).
const MAX_KINDS: usize = 1000;

/// The message of the kind that counts the diagnostics of the kinds past [`MAX_KINDS`].
const OTHER_KINDS: &str = "diagnostics of other kinds";

/// The diagnostics of one kind.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct DiagnosticKind {
    #[serde(serialize_with = "serialize_severity")]
    pub severity: Severity,
    /// The message of the first one.
    pub message: String,
    /// How many there are.
    pub count: u64,
    /// The lines of the first [`KIND_LINES`], in file order; `column` is the first one's.
    pub lines: Vec<u64>,
    pub column: u32,
    /// The message with its numbers blanked.
    #[serde(skip)]
    key: String,
}

/// The kinds of a file's diagnostics, in the order their first ones stand.
#[derive(Clone, Debug, Default)]
pub struct DiagnosticKinds {
    kinds: Vec<DiagnosticKind>,
    index: HashMap<(bool, String), usize>,
    /// A kind whose message is the last diagnostic's (never the kinds beyond
    /// [`MAX_KINDS`]): a diagnostic with the same severity and message is of that kind, and
    /// a file's diagnostics come in runs of one message (a Marlin file's `M204 P…` on every
    /// other line), so most find their kind without their key made and hashed.
    last: Option<usize>,
}

/// The severity's name in reports.
pub fn severity_name(s: Severity) -> &'static str {
    match s {
        Severity::Warning => "warning",
        Severity::Error => "error",
    }
}

fn serialize_severity<S: serde::Serializer>(s: &Severity, to: S) -> Result<S::Ok, S::Error> {
    to.serialize_str(severity_name(*s))
}

/// A message with its numbers blanked: what its kind is.
fn kind_key(message: &str) -> String {
    let mut key = String::with_capacity(message.len());
    let mut in_number = false;
    for c in message.chars() {
        let digit = c.is_ascii_digit() || (in_number && c == '.');
        if !(digit && in_number) {
            key.push(if digit { '#' } else { c });
        }
        in_number = digit;
    }
    key
}

impl DiagnosticKinds {
    pub fn add(&mut self, d: &Diagnostic) {
        let i = match self.last {
            Some(i)
                if self.kinds[i].severity == d.severity && self.kinds[i].message == d.message =>
            {
                i
            }
            _ => self.kind_of(d),
        };
        let k = &mut self.kinds[i];
        k.count += 1;
        if k.lines.len() < KIND_LINES && k.lines.last() != Some(&d.line) {
            k.lines.push(d.line);
        }
    }

    /// The index of the kind of `d`, added if it is new: past [`MAX_KINDS`] kinds, a new
    /// kind's diagnostics are counted in one for all the others.
    fn kind_of(&mut self, d: &Diagnostic) -> usize {
        let key = (d.severity == Severity::Error, kind_key(&d.message));
        if let Some(&i) = self.index.get(&key) {
            // Remembered only where the kind's message is this one: not the others' kind.
            if self.kinds[i].message == d.message {
                self.last = Some(i);
            }
            return i;
        }
        let mut kind = DiagnosticKind {
            severity: d.severity,
            message: d.message.clone(),
            count: 0,
            lines: Vec::new(),
            column: d.column,
            key: key.1,
        };
        if self.kinds.len() >= MAX_KINDS {
            kind.message = OTHER_KINDS.to_string();
            kind.key = String::new();
        } else {
            self.last = Some(self.kinds.len());
        }
        self.kind(kind)
    }

    /// The index of the kind of `new`, added (as it is) if it is not there yet.
    fn kind(&mut self, new: DiagnosticKind) -> usize {
        let next = self.kinds.len();
        let i = *self
            .index
            .entry((new.severity == Severity::Error, new.key.clone()))
            .or_insert(next);
        if i == next {
            self.kinds.push(new);
        }
        i
    }

    /// Takes in the kinds of other diagnostics of the same file.
    pub fn merge(&mut self, other: DiagnosticKinds) {
        for theirs in other.kinds {
            let (count, lines) = (theirs.count, theirs.lines.clone());
            let i = self.kind(DiagnosticKind {
                count: 0,
                lines: Vec::new(),
                ..theirs
            });
            let k = &mut self.kinds[i];
            k.count += count;
            k.lines.extend(lines);
            k.lines.sort_unstable();
            k.lines.dedup();
            k.lines.truncate(KIND_LINES);
        }
        // In the order of their first lines again.
        self.kinds.sort_by_key(|k| k.lines.first().copied());
        self.index = (self.kinds.iter().enumerate())
            .map(|(i, k)| ((k.severity == Severity::Error, k.key.clone()), i))
            .collect();
        self.last = None;
    }

    /// The kinds, in the order their first diagnostics stand in the file.
    pub fn as_slice(&self) -> &[DiagnosticKind] {
        &self.kinds
    }
}

impl Serialize for DiagnosticKinds {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        self.kinds.serialize(s)
    }
}

/// The diagnostics of one run as the reader hands them over: the first [`MAX_LISTED`] kept
/// whole, every one counted and grouped by kind. Memory stays bounded on a file with a
/// warning on every line.
#[derive(Debug, Default)]
pub struct DiagnosticLog {
    pub(super) listed: Vec<Diagnostic>,
    pub(super) unlisted_warnings: u64,
    pub(super) unlisted_errors: u64,
    pub(super) kinds: DiagnosticKinds,
}

impl DiagnosticLog {
    pub fn push(&mut self, d: Diagnostic) {
        self.kinds.add(&d);
        match d.severity {
            _ if self.listed.len() < MAX_LISTED => self.listed.push(d),
            Severity::Warning => self.unlisted_warnings += 1,
            Severity::Error => self.unlisted_errors += 1,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn warn(line: u64, message: &str) -> Diagnostic {
        Diagnostic {
            line,
            column: 1,
            severity: Severity::Warning,
            message: message.into(),
        }
    }

    #[test]
    fn numbers_do_not_make_a_kind() {
        assert_eq!(
            kind_key("checksum mismatch: the line says *43, its bytes give *42"),
            "checksum mismatch: the line says *#, its bytes give *#"
        );
        assert_eq!(kind_key("more than 1.5 mm"), "more than # mm");
        assert_eq!(kind_key("M204 S must be positive"), "M# S must be positive");
    }

    #[test]
    fn one_entry_per_kind_with_its_count_and_first_lines() {
        let mut k = DiagnosticKinds::default();
        for line in [3, 5, 8, 13, 21, 34, 55] {
            k.add(&warn(line, "M204 with only P or only T is ignored"));
        }
        k.add(&warn(4, "checksum mismatch: *1 vs *2"));
        k.add(&warn(9, "checksum mismatch: *7 vs *9"));
        k.add(&Diagnostic {
            severity: Severity::Error,
            ..warn(6, "M204 with only P or only T is ignored")
        });
        let kinds = k.as_slice();
        assert_eq!(kinds.len(), 3);
        assert_eq!(kinds[0].count, 7);
        assert_eq!(kinds[0].lines, [3, 5, 8, 13, 21]);
        assert_eq!(
            (kinds[1].count, kinds[1].message.as_str()),
            (2, "checksum mismatch: *1 vs *2")
        );
        assert_eq!((kinds[2].severity, kinds[2].count), (Severity::Error, 1));
    }

    #[test]
    fn merged_kinds_add_up_and_stand_in_file_order() {
        let mut a = DiagnosticKinds::default();
        a.add(&warn(40, "near-singular pose: tower A arm 4.1° from flat"));
        a.add(&warn(90, "negative dwell; no dwell"));
        let mut b = DiagnosticKinds::default();
        b.add(&warn(7, "negative dwell; no dwell"));
        b.add(&warn(60, "near-singular pose: tower B arm 2.0° from flat"));
        a.merge(b);
        let kinds = a.as_slice();
        assert_eq!(kinds.len(), 3);
        assert_eq!((kinds[0].lines.clone(), kinds[0].count), (vec![7, 90], 2));
        assert_eq!(kinds[1].lines, [40]);
        assert_eq!(kinds[2].lines, [60]);
    }

    #[test]
    fn kinds_are_bounded() {
        let mut k = DiagnosticKinds::default();
        // Names without digits, each of its own kind.
        let name = |i: u64| {
            format!(
                "{}{}",
                char::from(b'a' + (i % 26) as u8),
                "z".repeat(i as usize / 26)
            )
        };
        for i in 0..(MAX_KINDS as u64 + 50) {
            k.add(&warn(
                i + 1,
                &format!("unsupported shaper type `{}`", name(i)),
            ));
        }
        assert_eq!(k.as_slice().len(), MAX_KINDS + 1);
        let other = &k.as_slice()[MAX_KINDS];
        assert_eq!((other.message.as_str(), other.count), (OTHER_KINDS, 50));
        // A kind told apart before the cap is still counted in its own, whether its message
        // comes again as it was or with other numbers, after the others' kind or not.
        let first = "unsupported shaper type `a`";
        k.add(&warn(2000, first));
        k.add(&warn(2001, first));
        k.add(&warn(2002, "unsupported shaper type `b`"));
        k.add(&warn(
            2003,
            "unsupported shaper type `zzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzz`",
        ));
        let kinds = k.as_slice();
        assert_eq!((kinds[0].count, kinds[1].count), (3, 2));
        assert_eq!(kinds[MAX_KINDS].count, 51);
        let total: u64 = kinds.iter().map(|k| k.count).sum();
        assert_eq!(total, MAX_KINDS as u64 + 54);
    }

    /// A message that comes again counts in its kind, however the messages before it ran.
    #[test]
    fn a_repeated_message_finds_its_kind() {
        let mut k = DiagnosticKinds::default();
        for (line, message) in [
            (1, "a 1"),
            (2, "a 1"),
            (3, "b"),
            (4, "a 1"),
            (5, "a 2"),
            (6, "a 1"),
        ] {
            k.add(&warn(line, message));
        }
        k.add(&Diagnostic {
            severity: Severity::Error,
            ..warn(7, "a 1")
        });
        k.add(&warn(8, "a 1"));
        let kinds = k.as_slice();
        let counts: Vec<_> = kinds.iter().map(|k| (k.severity, k.count)).collect();
        assert_eq!(
            counts,
            [
                (Severity::Warning, 6),
                (Severity::Warning, 1),
                (Severity::Error, 1)
            ]
        );
        assert_eq!(kinds[0].lines, [1, 2, 4, 5, 6]);
    }
}
