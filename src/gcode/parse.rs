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

mod grammar;

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

/// Fixed-capacity list, so a parsed line needs no allocation.
#[derive(Clone, Copy, Debug)]
pub struct Fixed<T: Copy, const N: usize> {
    items: [T; N],
    len: usize,
}

impl<T: Copy, const N: usize> Fixed<T, N> {
    const fn new(fill: T) -> Self {
        Fixed {
            items: [fill; N],
            len: 0,
        }
    }

    /// Appends; false when full.
    fn push(&mut self, t: T) -> bool {
        if self.len == N {
            return false;
        }
        self.items[self.len] = t;
        self.len += 1;
        true
    }

    pub fn as_slice(&self) -> &[T] {
        &self.items[..self.len]
    }
}

const NO_WORD: Word = Word {
    letter: 0,
    value: None,
    column: 0,
};
const NO_DIAG: LineDiag = LineDiag {
    column: 0,
    severity: Severity::Warning,
    kind: DiagKind::TooManyWords,
};

/// One parsed line, borrowing its bytes.
#[derive(Clone, Copy, Debug)]
pub struct ParsedLine<'a> {
    pub command: Command<'a>,
    /// `N` line number, if given.
    pub line_number: Option<u64>,
    words: Fixed<Word, MAX_WORDS>,
    /// The whole line (for columns) and an extended command's arguments.
    line: &'a [u8],
    args: &'a [u8],
    /// Free text of M117/M118 and the file-name commands.
    pub text: Option<&'a [u8]>,
    /// The `;` comment after the `;`, or else the first `( )` comment's inside.
    pub comment: Option<&'a [u8]>,
    /// `*` checksum as written, if any.
    pub checksum: Option<u32>,
    diags: Fixed<LineDiag, MAX_DIAGS>,
}

impl<'a> ParsedLine<'a> {
    pub fn words(&self) -> &[Word] {
        self.words.as_slice()
    }

    /// An extended command's parameters, in order (read on demand: they are rare).
    pub fn params(&self) -> Params<'a> {
        Params {
            line: self.line,
            rest: self.args,
        }
    }

    pub fn diags(&self) -> &[LineDiag] {
        self.diags.as_slice()
    }

    /// The last word with this (upper-case) letter.
    pub fn word(&self, letter: u8) -> Option<&Word> {
        self.words().iter().rev().find(|w| w.letter == letter)
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
        if !self.diags.push(LineDiag {
            column,
            severity,
            kind,
        }) && severity == Severity::Error
        {
            self.diags.items[MAX_DIAGS - 1] = LineDiag {
                column,
                severity,
                kind,
            };
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
    let line = strip_terminator(line);
    let mut p = ParsedLine {
        command: Command::None,
        line_number: None,
        words: Fixed::new(NO_WORD),
        line,
        args: b"",
        text: None,
        comment: None,
        checksum: None,
        diags: Fixed::new(NO_DIAG),
    };
    let (mut code, comment, last_star) = grammar::code_and_comment(line);
    p.comment = comment;
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
                classic_words(&mut p, args);
            }
        }
        Err(_) => classic_words(&mut p, rest),
    }
    p
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
    let mut seen = 0u32; // bit per letter
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
                let bit = 1u32 << (letter - b'A');
                if seen & bit != 0 {
                    p.diag(col, Severity::Warning, DiagKind::DuplicateWord(letter));
                }
                seen |= bit;
                if !p.words.push(Word {
                    letter,
                    value,
                    column: col,
                }) {
                    p.diag(col, Severity::Warning, DiagKind::TooManyWords);
                    return;
                }
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
mod tests {
    use super::*;

    fn words(p: &ParsedLine) -> Vec<(char, Option<f64>, u32)> {
        p.words()
            .iter()
            .map(|w| (char::from(w.letter), w.value, w.column))
            .collect()
    }

    fn code(p: &ParsedLine) -> (u8, u32) {
        match p.command {
            Command::Code { letter, number, .. } => (letter, number),
            other => panic!("not a code: {other:?}"),
        }
    }

    #[test]
    fn line_number_and_good_checksum() {
        // Checksum by hand: XOR of the bytes of "N123 G1 X10 Y20".
        let body = b"N123 G1 X10 Y20";
        let cs = body.iter().fold(0u8, |a, b| a ^ b);
        let line = format!("N123 G1 X10 Y20*{cs}\n");
        let p = parse_line(line.as_bytes());
        assert_eq!(p.line_number, Some(123));
        assert_eq!(p.checksum, Some(u32::from(cs)));
        assert_eq!(code(&p), (b'G', 1));
        assert_eq!(words(&p), vec![('X', Some(10.0), 9), ('Y', Some(20.0), 13)]);
        assert!(p.diags().is_empty(), "{:?}", p.diags());
    }

    #[test]
    fn wrong_checksum_is_a_warning_at_the_star() {
        let p = parse_line(b"N123 G1 X10 Y20*43");
        let cs = b"N123 G1 X10 Y20".iter().fold(0u8, |a, b| a ^ b);
        assert_eq!(cs, 42);
        assert_eq!(
            p.diags(),
            &[LineDiag {
                column: 16,
                severity: Severity::Warning,
                kind: DiagKind::Checksum {
                    computed: cs,
                    written: 43
                }
            }]
        );
        assert_eq!(p.value(b'Y'), Some(20.0));
    }

    #[test]
    fn t_is_a_parameter_of_m204_and_m104() {
        let p = parse_line(b"M204 P1500 T3000");
        assert_eq!(code(&p), (b'M', 204));
        assert_eq!(p.value(b'P'), Some(1500.0));
        assert_eq!(p.value(b'T'), Some(3000.0));
        let p = parse_line(b"M104 S215 T1");
        assert_eq!(code(&p), (b'M', 104));
        assert_eq!(p.value(b'T'), Some(1.0));
    }

    #[test]
    fn tool_change_is_a_command() {
        let p = parse_line(b"T0\n");
        assert_eq!(code(&p), (b'T', 0));
        assert!(p.words().is_empty());
    }

    #[test]
    fn m117_free_text_until_semicolon() {
        let p = parse_line(b"M117 text X1 (y) ; with semicolons; more\r\n");
        assert_eq!(code(&p), (b'M', 117));
        assert_eq!(p.text, Some(&b"text X1 (y)"[..]));
        assert!(p.words().is_empty());
        assert_eq!(p.comment, Some(&b" with semicolons; more"[..]));
        assert!(p.diags().is_empty());
        let p = parse_line(b"M118 E1 hello");
        assert_eq!(p.text, Some(&b"E1 hello"[..]));
    }

    #[test]
    fn m486_object_labels_are_text() {
        for line in [
            &b"M486 Acylinder_d40.stl"[..],
            b"M486 S0",
            b"M486 S-1",
            b"M486 T3",
        ] {
            let p = parse_line(line);
            assert_eq!(code(&p), (b'M', 486));
            assert!(p.diags().is_empty(), "{line:?}");
        }
    }

    #[test]
    fn exponent_e_starts_an_e_word_with_a_warning() {
        let p = parse_line(b"G1 F1.2e3");
        assert_eq!(words(&p), vec![('F', Some(1.2), 4), ('E', Some(3.0), 8)]);
        assert_eq!(p.diags().len(), 1);
        assert_eq!(p.diags()[0].kind, DiagKind::ExponentReadAsE);
        assert_eq!(p.diags()[0].column, 8);
        // With a space it is an ordinary E word.
        assert!(parse_line(b"G1 F1.2 E3").diags().is_empty());
    }

    #[test]
    fn letters_without_values() {
        let p = parse_line(b"G28 X Y");
        assert_eq!(code(&p), (b'G', 28));
        assert_eq!(words(&p), vec![('X', None, 5), ('Y', None, 7)]);
        assert!(p.diags().is_empty());
    }

    #[test]
    fn inline_paren_comment() {
        let p = parse_line(b"G1 (move) X1 (fast)");
        assert_eq!(words(&p), vec![('X', Some(1.0), 11)]);
        assert_eq!(p.comment, Some(&b"move"[..]));
        let p = parse_line(b"G1 X1 (open");
        assert_eq!(p.diags()[0].kind, DiagKind::UnclosedParen);
    }

    #[test]
    fn lowercase_and_leading_point() {
        let p = parse_line(b"g1 x-.5 y+.25 e.1");
        assert_eq!(code(&p), (b'G', 1));
        assert_eq!(
            words(&p),
            vec![
                ('X', Some(-0.5), 4),
                ('Y', Some(0.25), 9),
                ('E', Some(0.1), 15)
            ]
        );
        assert!(p.diags().is_empty());
    }

    #[test]
    fn compact_words_without_spaces() {
        let p = parse_line(b"G1X10Y-2.5Z.3");
        assert_eq!(code(&p), (b'G', 1));
        assert_eq!(
            words(&p),
            vec![
                ('X', Some(10.0), 3),
                ('Y', Some(-2.5), 6),
                ('Z', Some(0.3), 11)
            ]
        );
    }

    #[test]
    fn crlf_and_non_utf8_comment() {
        let p = parse_line(b"G1 X1 ; caf\xe9 \xff\r\n");
        assert_eq!(p.value(b'X'), Some(1.0));
        assert_eq!(p.comment, Some(&b" caf\xe9 \xff"[..]));
        assert!(p.diags().is_empty());
    }

    #[test]
    fn thumbnail_lines_are_comments() {
        for l in [
            &b"; thumbnail begin 16x16 520\n"[..],
            b"; iVBORw0KGgoAAAANSUhEUgAAABAAAAAQCAYAAAAf8/9hAAAA+0lEQVR4nGNgGAWjYBSMglEw\n",
            b"; thumbnail end\n",
        ] {
            let p = parse_line(l);
            assert_eq!(p.command, Command::None);
            assert!(p.comment.is_some() && p.diags().is_empty());
        }
    }

    #[test]
    fn extended_commands() {
        let p = parse_line(b"SET_VELOCITY_LIMIT ACCEL=3000");
        assert!(
            matches!(p.command, Command::Extended { name, column: 1 } if name == b"SET_VELOCITY_LIMIT")
        );
        let a = p.param("accel").unwrap();
        assert_eq!((a.value, a.column), (&b"3000"[..], 20));
        assert_eq!(param_f64(a.value), Some(3000.0));

        let p = parse_line(b"EXCLUDE_OBJECT_DEFINE NAME=a CENTER=1,2 POLYGON=[[0,0],[1,1]] ; c\n");
        assert!(
            matches!(p.command, Command::Extended { name, .. } if name == b"EXCLUDE_OBJECT_DEFINE")
        );
        let kv: Vec<(&[u8], &[u8])> = p.params().map(|p| (p.key, p.value)).collect();
        assert_eq!(
            kv,
            vec![
                (&b"NAME"[..], &b"a"[..]),
                (b"CENTER", b"1,2"),
                (b"POLYGON", b"[[0,0],[1,1]]")
            ]
        );
        assert_eq!(param_f64(b"1,2"), None);
        let p = parse_line(b"exclude_object_start NAME=\"my part.stl\"");
        assert_eq!(p.param("NAME").unwrap().value, b"my part.stl");
        let p = parse_line(b"EXCLUDE_OBJECT_END NAME='plate 1'");
        assert_eq!(p.param("NAME").unwrap().value, b"plate 1");
        let p = parse_line(b"PRINT_START OOPS EXTRUDER=210");
        assert_eq!(p.diags()[0].kind, DiagKind::ExpectedKeyValue);
        assert_eq!(p.diags()[0].column, 13);
        assert_eq!(p.param("EXTRUDER").unwrap().value, b"210");
    }

    #[test]
    fn helix_arc_line() {
        let p = parse_line(b"G3 X0 Y-98 I98 Z0.2 E40");
        assert_eq!(code(&p), (b'G', 3));
        assert_eq!(
            words(&p),
            vec![
                ('X', Some(0.0), 4),
                ('Y', Some(-98.0), 7),
                ('I', Some(98.0), 12),
                ('Z', Some(0.2), 16),
                ('E', Some(40.0), 21)
            ]
        );
    }

    #[test]
    fn malformed_number_in_motion_is_an_error_with_column() {
        let p = parse_line(b"G1 X1.2.3 Y4");
        assert_eq!(
            p.diags(),
            &[LineDiag {
                column: 5,
                severity: Severity::Error,
                kind: DiagKind::MalformedNumber
            }]
        );
        assert!(p.has_error());
        assert_eq!(p.word(b'X').unwrap().value, None);
        assert_eq!(p.value(b'Y'), Some(4.0));
        for bad in [&b"G1 X-"[..], b"G0 Y.", b"G1 X1:2", b"G1 X+-1"] {
            assert!(parse_line(bad).has_error(), "{:?}", bad);
        }
        // Elsewhere it is a warning.
        let p = parse_line(b"M106 S1.2.3");
        assert_eq!(p.diags()[0].severity, Severity::Warning);
        // Out of range (no overflow to infinity).
        let big = format!("G1 X{}", "9".repeat(400));
        let p = parse_line(big.as_bytes());
        assert!(p.has_error());
        assert_eq!(p.diags()[0].kind, DiagKind::NumberOutOfRange);
        assert_eq!(p.diags()[0].column, 5);
        assert!(p.diags()[0].message().contains("out of range"));
        assert_eq!(
            parse_line(b"G1 X1000000001").diags()[0].kind,
            DiagKind::NumberOutOfRange
        );
        assert!(parse_line(b"G1 X999999999").diags().is_empty());
    }

    #[test]
    fn unexpected_characters_and_duplicates() {
        let p = parse_line(b"G1 X1 # Y2 X3");
        assert_eq!(p.diags()[0].kind, DiagKind::UnexpectedChar(b'#'));
        assert_eq!(p.diags()[0].column, 7);
        assert_eq!(p.diags()[1].kind, DiagKind::DuplicateWord(b'X'));
        assert_eq!(p.value(b'X'), Some(3.0));
    }

    #[test]
    fn short_decimals_match_fast_float() {
        // Against fast-float2 (correctly rounded), over many shapes of numbers.
        let mut x: u64 = 0x9E37_79B9_7F4A_7C15;
        for _ in 0..200_000 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let int = x % 1_000_000;
            let frac_digits = (x >> 20) % 10;
            let frac = (x >> 24) % 10u64.pow(frac_digits as u32);
            let sign = ["", "-", "+"][((x >> 40) % 3) as usize];
            let t = if frac_digits == 0 {
                format!("{sign}{int}")
            } else {
                format!("{sign}{int}.{frac:0w$}", w = frac_digits as usize)
            };
            let want: f64 = fast_float2::parse(t.as_bytes()).unwrap();
            assert_eq!(number(t.as_bytes()), (&b""[..], Some(want)), "{t}");
        }
        assert_eq!(number(b".5 X"), (&b" X"[..], Some(0.5)));
        assert_eq!(number(b"-.25"), (&b""[..], Some(-0.25)));
        assert_eq!(number(b"7.Y"), (&b"Y"[..], Some(7.0)));
        assert_eq!(number(b"-"), (&b""[..], None));
        assert_eq!(number(b"."), (&b""[..], None));
        assert_eq!(number(b"1.2.3"), (&b".3"[..], Some(1.2)));
        assert_eq!(number(b"1234567890123456").1, None); // out of range
        assert_eq!(
            number(b"0.1234567890123456789").1,
            "0.1234567890123456789".parse::<f64>().ok()
        );
    }

    #[test]
    fn blank_and_comment_lines() {
        assert_eq!(parse_line(b"\n").command, Command::None);
        assert_eq!(parse_line(b"   \t\r\n").command, Command::None);
        let p = parse_line(b"  ;LAYER:3\n");
        assert_eq!(p.command, Command::None);
        assert_eq!(p.comment, Some(&b"LAYER:3"[..]));
        let p = parse_line(b"G29.1 X1");
        assert!(matches!(
            p.command,
            Command::Code {
                letter: b'G',
                number: 29,
                subcode: Some(1),
                ..
            }
        ));
    }
}
