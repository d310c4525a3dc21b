//! The per-line parser. Its grammar is nom combinators over the line's bytes, in
//! `parse/grammar.rs`; this file holds the parsed line's types and [`parse_line`], which
//! strings the grammar's parsers together and turns what they return into the command,
//! words, parameters and diagnostics (duplicates, exponents, capacities, severities).
//! Numbers are read by an exact fast path with fast-float2 behind it. It borrows the line
//! and allocates nothing: words and diagnostics live in fixed arrays, extended parameters
//! are read again on demand.
//!
//! Grammar of one line (case-insensitive letters; columns are 1-based byte offsets):
//! ```text
//! line     = ws [ "N" digits ws ] [ command rest ] [ "*" digits ] ws [ ";" comment ]
//! command  = letter number          (G1, M204, T0, G29.1: classic)
//!          | name                   (two or more of A-Z 0-9 _ starting with two letters
//!                                    or an underscore: SET_VELOCITY_LIMIT, extended)
//! classic  = { ws word | ws "(" text ")" }     word = letter [ ws number ]
//! extended = { ws KEY "=" ( VALUE | '"' text '"' | "'" text "'" ) }
//! number   = [ "+" | "-" ] digits [ "." digits ] | [ "+" | "-" ] "." digits
//! ```
//! `M117`/`M118`, M486 (object labels) and Marlin's file-name commands (M23, M28, M30, M32,
//! M928) take the rest
//! of the line up to `;` as free text, as Klipper reads them. A `*` followed by digits ends
//! the command part: the checksum, XOR of every byte before the `*`.

mod common;
mod grammar;

use arrayvec::ArrayVec;
use nom::combinator::iterator;

use super::Severity;
use grammar::{Head, Token, Value, number};

/// Most words kept per classic line; more is a warning.
pub const MAX_WORDS: usize = 16;
/// Most diagnostics kept per line.
pub const MAX_DIAGS: usize = 4;
/// Largest magnitude accepted for a number; larger is a malformed number.
pub const MAX_NUMBER: f64 = 1e9;

/// A classic word: `X-.5` is `{ letter: b'X', value: Some(-0.5) }`; `X` alone has no value.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Word {
    /// Upper-case ASCII letter.
    pub letter: u8,
    pub value: Option<f64>,
    /// Column of the letter.
    pub column: u32,
}

/// An extended command's `KEY=VALUE` parameter (quotes removed from a quoted value).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Param<'a> {
    pub key: &'a [u8],
    pub value: &'a [u8],
    /// Column of the key.
    pub column: u32,
}

/// The command a line starts with.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Command<'a> {
    /// A blank or comment-only line.
    None,
    /// Letter and number: `G1` is `{ letter: b'G', number: 1, subcode: None }`.
    Code {
        letter: u8,
        number: u32,
        subcode: Option<u32>,
        column: u32,
    },
    /// A Klipper extended command, as written (compare with `eq_ignore_ascii_case`).
    Extended { name: &'a [u8], column: u32 },
}

/// What went wrong on a line, without allocating; [`LineDiag::message`] words it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DiagKind {
    /// `*` checksum differs from the XOR of the bytes before it.
    Checksum { computed: u8, written: u32 },
    /// A value that is not a number (`X1.2.3`, `X-`, `Xabc`).
    MalformedNumber,
    /// A number beyond ±[`MAX_NUMBER`] (`X1000000000000`).
    NumberOutOfRange,
    /// `e`/`E` right after a number (`F1.2e3`) starts an E word.
    ExponentReadAsE,
    /// A character that starts no word.
    UnexpectedChar(u8),
    /// `(` without `)`.
    UnclosedParen,
    /// A letter given twice; the last one is used.
    DuplicateWord(u8),
    /// More than [`MAX_WORDS`] words.
    TooManyWords,
    /// An extended-command argument without `=`.
    ExpectedKeyValue,
    /// A quote without its closing quote.
    UnclosedQuote,
}

/// A diagnostic of one line, located by column.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LineDiag {
    pub column: u32,
    pub severity: Severity,
    pub kind: DiagKind,
}

impl LineDiag {
    pub fn message(&self) -> String {
        match self.kind {
            DiagKind::Checksum { computed, written } => {
                format!("checksum mismatch: the line says *{written}, its bytes give *{computed}")
            }
            DiagKind::MalformedNumber => {
                "malformed number: expected digits with an optional sign and decimal point"
                    .to_string()
            }
            DiagKind::NumberOutOfRange => {
                format!("number out of range: at most {MAX_NUMBER:e} in magnitude")
            }
            DiagKind::ExponentReadAsE => "`e` right after a number starts an E word (exponents \
                 are not G-code; Marlin 2 and Klipper read it the same way)"
                .to_string(),
            DiagKind::UnexpectedChar(c) => {
                format!("unexpected character {:?}; skipped", char::from(c))
            }
            DiagKind::UnclosedParen => "`(` comment without `)`: comment to end of line".into(),
            DiagKind::DuplicateWord(c) => {
                format!("{} given twice; the last one is used", char::from(c))
            }
            DiagKind::TooManyWords => {
                format!("more than {MAX_WORDS} words; the rest is ignored")
            }
            DiagKind::ExpectedKeyValue => "expected KEY=VALUE; skipped".to_string(),
            DiagKind::UnclosedQuote => "quote without its closing quote".to_string(),
        }
    }
}

/// One parsed line, borrowing its bytes.
#[derive(Clone, Debug)]
pub struct ParsedLine<'a> {
    pub command: Command<'a>,
    /// `N` line number, if given.
    pub line_number: Option<u64>,
    /// Fixed capacity, so a parsed line needs no allocation; uninitialised until pushed,
    /// so it costs nothing to make (an array filled with a blank word was 600 bytes to copy
    /// per line).
    words: ArrayVec<Word, MAX_WORDS>,
    /// The whole line (for columns) and an extended command's arguments.
    line: &'a [u8],
    args: &'a [u8],
    /// Free text of M117/M118 and the file-name commands.
    pub text: Option<&'a [u8]>,
    /// The `;` comment after the `;`, or else the first `( )` comment's inside.
    pub comment: Option<&'a [u8]>,
    /// `*` checksum as written, if any.
    pub checksum: Option<u32>,
    diags: ArrayVec<LineDiag, MAX_DIAGS>,
    /// Per letter (A first), 1 + the index in `words` of its last word kept, 0 without one:
    /// [`Self::word`] without a search (the interpreter asks five letters of every move), by
    /// one bounds check (0 wraps past the end), where a bit per letter and the index were
    /// two tests for each letter asked and two updates for each word kept (−0.3 % of an
    /// unshaped run's instructions).
    slots: [u8; 26],
}

impl<'a> ParsedLine<'a> {
    pub fn words(&self) -> &[Word] {
        &self.words
    }

    /// An extended command's parameters, in order (read on demand: they are rare).
    pub fn params(&self) -> Params<'a> {
        Params {
            line: self.line,
            rest: self.args,
        }
    }

    pub fn diags(&self) -> &[LineDiag] {
        &self.diags
    }

    /// The last word with this (upper-case) letter.
    #[inline]
    pub fn word(&self, letter: u8) -> Option<&Word> {
        let slot = self.slots.get(usize::from(letter.wrapping_sub(b'A')))?;
        self.words.get(usize::from(*slot).wrapping_sub(1))
    }

    /// The value of the last word with this letter, if it has one.
    pub fn value(&self, letter: u8) -> Option<f64> {
        self.word(letter).and_then(|w| w.value)
    }

    /// The last parameter with this key (case-insensitive).
    pub fn param(&self, key: &str) -> Option<Param<'a>> {
        self.params()
            .filter(|p| p.key.eq_ignore_ascii_case(key.as_bytes()))
            .last()
    }

    /// Whether the command is `letter number` (e.g. `is(b'G', 1)`), without a subcode.
    pub fn is(&self, letter: u8, number: u32) -> bool {
        matches!(self.command, Command::Code { letter: l, number: n, subcode: None, .. }
            if l == letter && n == number)
    }

    pub fn has_error(&self) -> bool {
        self.diags().iter().any(|d| d.severity == Severity::Error)
    }

    fn diag(&mut self, column: u32, severity: Severity, kind: DiagKind) {
        // Past the capacity, later diagnostics of the line are dropped; an error replaces
        // the last warning so that it is never lost.
        let diag = LineDiag {
            column,
            severity,
            kind,
        };
        if let Err(full) = self.diags.try_push(diag)
            && severity == Severity::Error
        {
            self.diags[MAX_DIAGS - 1] = full.element();
        }
    }
}

/// Commands whose argument is free text. M486 (object cancelling) is among them: its
/// `A` names an object (`M486 Acylinder_d40.stl`, PrusaSlicer), and none of its words moves
/// the machine.
fn takes_text(letter: u8, number: u32) -> bool {
    letter == b'M' && matches!(number, 23 | 28 | 30 | 32 | 117 | 118 | 486 | 928)
}

/// Whether a malformed number is an error for this command (motion and positioning) or
/// only a warning (the line does not move the machine).
fn is_motion(command: &Command) -> bool {
    matches!(
        command,
        Command::Code {
            letter: b'G',
            number: 0..=3 | 92,
            subcode: None,
            ..
        }
    )
}

/// Strips a trailing LF or CRLF.
pub fn strip_terminator(line: &[u8]) -> &[u8] {
    let l = line.strip_suffix(b"\n").unwrap_or(line);
    l.strip_suffix(b"\r").unwrap_or(l)
}

/// 1-based column of `rest`, a sub-slice of `line`.
fn column(line: &[u8], rest: &[u8]) -> u32 {
    (rest.as_ptr() as usize - line.as_ptr() as usize + 1) as u32
}

/// Parses one line (with or without its terminator).
pub fn parse_line(line: &[u8]) -> ParsedLine<'_> {
    let mut p = ParsedLine::blank(line);
    p.parse();
    p
}

impl<'a> ParsedLine<'a> {
    /// The line, not parsed yet: [`Self::parse`] fills it in place. (A hot caller uses the
    /// two in place of [`parse_line`]: a parsed line is 608 bytes, and returning one built
    /// in a local copied them all once more per line.)
    pub fn blank(line: &'a [u8]) -> ParsedLine<'a> {
        ParsedLine {
            command: Command::None,
            line_number: None,
            words: ArrayVec::new_const(),
            line: strip_terminator(line),
            args: b"",
            text: None,
            comment: None,
            checksum: None,
            diags: ArrayVec::new_const(),
            slots: [0; 26],
        }
    }

    /// Parses the line given to [`Self::blank`]: a common line in one pass
    /// ([`Self::parse_common`], inlined into the caller: the call was 0.41 % of an
    /// unshaped run's instructions), any other by the grammar.
    #[inline(always)]
    pub fn parse(&mut self) {
        if !self.parse_common(self.line) {
            self.parse_uncommon();
        }
    }

    /// Parses a line that is not a common one, by the grammar.
    #[inline(never)]
    fn parse_uncommon(&mut self) {
        let (code, comment, last_star) = grammar::code_and_comment(self.line);
        self.comment = comment;
        self.parse_grammar(code, last_star);
    }

    /// Parses the line by the grammar, from its code part and the place of its last `*`
    /// ([`grammar::code_and_comment`]; the comment is kept).
    fn parse_grammar(&mut self, mut code: &'a [u8], last_star: Option<usize>) {
        let line = self.line;
        let p = self;
        if let Some(star) = last_star
            && let Ok((_, written)) = grammar::checksum(&code[star..])
        {
            let computed = line[..star].iter().fold(0u8, |a, &b| a ^ b);
            p.checksum = Some(written);
            if u32::from(computed) != written {
                let kind = DiagKind::Checksum { computed, written };
                p.diag((star + 1) as u32, Severity::Warning, kind);
            }
            code = &code[..star];
        }
        let (rest, line_number) = grammar::line_start(code);
        p.line_number = line_number;
        match grammar::command(rest) {
            Ok((args, Head::Extended(name))) => {
                p.command = Command::Extended {
                    name,
                    column: column(line, name),
                };
                p.args = args;
                for arg in iterator(args, grammar::argument) {
                    if let Err((at, kind)) = arg {
                        p.diag(column(line, at), Severity::Warning, kind);
                    }
                }
            }
            Ok((
                args,
                Head::Code {
                    letter,
                    number,
                    subcode,
                },
            )) => {
                p.command = Command::Code {
                    letter,
                    number,
                    subcode,
                    column: column(line, rest),
                };
                if subcode.is_none() && takes_text(letter, number) {
                    p.text = Some(grammar::free_text(args));
                } else {
                    classic_words(p, args);
                }
            }
            Err(_) => classic_words(p, rest),
        }
    }
}

/// The words of a classic command, `( )` comments in between, with their diagnostics.
#[inline(always)]
fn classic_words<'a>(p: &mut ParsedLine<'a>, args: &'a [u8]) {
    let line = p.line;
    let severity = if is_motion(&p.command) {
        Severity::Error
    } else {
        Severity::Warning
    };
    let mut after_number = false; // the previous token was a number, no blank since
    let mut rest = args;
    while let Ok((r, (blank, (at, token)))) = grammar::blank_token(rest) {
        rest = r;
        let col = column(line, at);
        after_number &= !blank;
        match token {
            Token::Comment { inside, closed } => {
                p.comment.get_or_insert(inside);
                if !closed {
                    p.diag(col, Severity::Warning, DiagKind::UnclosedParen);
                    return;
                }
                after_number = false;
            }
            Token::Unexpected(c) => {
                p.diag(col, Severity::Warning, DiagKind::UnexpectedChar(c));
                after_number = false;
            }
            Token::Word { letter, value } => {
                if after_number && letter == b'E' {
                    p.diag(col, Severity::Warning, DiagKind::ExponentReadAsE);
                }
                after_number = matches!(value, Value::Number(_));
                let value = match value {
                    Value::None => None,
                    Value::Number(v) => Some(v),
                    Value::Bad { text, kind } => {
                        p.diag(column(line, text), severity, kind);
                        None
                    }
                };
                // The letters kept so far: a word that is not kept ends the line's words.
                let slot = usize::from(letter - b'A');
                if p.slots[slot] != 0 {
                    p.diag(col, Severity::Warning, DiagKind::DuplicateWord(letter));
                }
                let word = Word {
                    letter,
                    value,
                    column: col,
                };
                if p.words.try_push(word).is_err() {
                    p.diag(col, Severity::Warning, DiagKind::TooManyWords);
                    return;
                }
                p.slots[slot] = p.words.len() as u8;
            }
        }
    }
}

/// Iterator over an extended command's parameters; malformed ones are skipped.
#[derive(Clone, Debug)]
pub struct Params<'a> {
    line: &'a [u8],
    rest: &'a [u8],
}

impl<'a> Iterator for Params<'a> {
    type Item = Param<'a>;

    fn next(&mut self) -> Option<Param<'a>> {
        loop {
            let (rest, arg) = grammar::argument(self.rest).ok()?;
            self.rest = rest;
            if let Ok((key, value)) = arg {
                return Some(Param {
                    key,
                    value,
                    column: column(self.line, key),
                });
            }
        }
    }
}

/// Parses an extended parameter's value as a number (`None` if it is not one).
pub fn param_f64(value: &[u8]) -> Option<f64> {
    match number(value) {
        (b"", v) => v,
        _ => None,
    }
}

#[cfg(test)]
mod tests;
