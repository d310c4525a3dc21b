//! The per-line parser, written with nom; numbers by an exact fast path with fast-float2
//! behind it (see `number`). It borrows the line and allocates nothing: words and
//! diagnostics live in fixed arrays, extended parameters are read on demand.
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
//! `M117`/`M118` (and Marlin's file-name commands M23, M28, M30, M32, M928) take the rest
//! of the line up to `;` as free text, as Klipper reads them. A `*` followed by digits ends
//! the command part: the checksum, XOR of every byte before the `*`.

use nom::{
    IResult,
    bytes::complete::{take_while, take_while1},
};

use super::Severity;

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

type Res<'a, T> = IResult<&'a [u8], T>;

fn is_space(c: u8) -> bool {
    c == b' ' || c == b'\t'
}

fn spaces(i: &[u8]) -> Res<'_, &[u8]> {
    take_while(is_space)(i)
}

fn name(i: &[u8]) -> Res<'_, &[u8]> {
    take_while1(|c: u8| c.is_ascii_alphanumeric() || c == b'_')(i)
}

/// Token of an extended command: up to whitespace, `=` or `;`.
fn key(i: &[u8]) -> Res<'_, &[u8]> {
    take_while1(|c: u8| !is_space(c) && c != b'=' && c != b';')(i)
}

fn bare_value(i: &[u8]) -> Res<'_, &[u8]> {
    take_while(|c: u8| !is_space(c) && c != b';')(i)
}

/// Powers of ten exactly representable in an f64.
const POW10: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
    1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
];

/// A number: `[+-] digits [. digits]` (at least one digit), recognised and read in one
/// pass (nom's parser shape: rest of the input, then the value). The value is `None`
/// without a digit or beyond [`MAX_NUMBER`].
///
/// Up to 15 digits the mantissa and the power of ten are exact in an f64, so one division
/// gives the correctly rounded value (Clinger's fast path, the one fast-float2 takes
/// first too, without its general set-up); longer numbers go to fast-float2.
fn number(i: &[u8]) -> (&[u8], Option<f64>) {
    let (neg, mut k) = match i.first() {
        Some(b'-') => (true, 1),
        Some(b'+') => (false, 1),
        _ => (false, 0),
    };
    let mut m: u64 = 0;
    let mut digits = 0usize;
    while let Some(&c) = i.get(k)
        && c.is_ascii_digit()
    {
        m = m.wrapping_mul(10).wrapping_add(u64::from(c - b'0'));
        digits += 1;
        k += 1;
    }
    let mut frac = 0usize;
    if i.get(k) == Some(&b'.') {
        k += 1;
        while let Some(&c) = i.get(k)
            && c.is_ascii_digit()
        {
            m = m.wrapping_mul(10).wrapping_add(u64::from(c - b'0'));
            digits += 1;
            frac += 1;
            k += 1;
        }
    }
    let (text, rest) = i.split_at(k);
    if digits == 0 {
        return (rest, None);
    }
    let v = if digits <= 15 {
        let v = m as f64 / POW10[frac];
        if neg { -v } else { v }
    } else {
        match fast_float2::parse::<f64, _>(text) {
            Ok(v) => v,
            Err(_) => return (rest, None),
        }
    };
    (rest, (v.abs() <= MAX_NUMBER).then_some(v))
}

/// Commands whose argument is free text.
fn takes_text(letter: u8, number: u32) -> bool {
    letter == b'M' && matches!(number, 23 | 28 | 30 | 32 | 117 | 118 | 928)
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
    let col = |rest: &[u8]| column(line, rest);

    // The code part ends at the first `;`; a `*digits` at its end is the checksum.
    let semi = line.iter().position(|&c| c == b';');
    let mut code = &line[..semi.unwrap_or(line.len())];
    if let Some(comment_start) = semi {
        p.comment = Some(&line[comment_start + 1..]);
    }
    if let Some(star) = code.iter().rposition(|&c| c == b'*') {
        let after = &code[star + 1..];
        let digits_end = after
            .iter()
            .position(|c| !c.is_ascii_digit())
            .unwrap_or(after.len());
        let tail_blank = after[digits_end..].iter().all(|&c| is_space(c));
        if digits_end > 0 && tail_blank && digits_end <= 9 {
            let written = after[..digits_end]
                .iter()
                .fold(0u32, |a, &d| a * 10 + u32::from(d - b'0'));
            let computed = line[..star].iter().fold(0u8, |a, &b| a ^ b);
            p.checksum = Some(written);
            if u32::from(computed) != written {
                p.diag(
                    (star + 1) as u32,
                    Severity::Warning,
                    DiagKind::Checksum { computed, written },
                );
            }
            code = &line[..star];
        }
    }

    let (mut rest, _) = spaces(code).unwrap_or((code, b""));
    // N line number.
    if let [b'N' | b'n', d, ..] = rest
        && d.is_ascii_digit()
    {
        let (r, digits) =
            take_while1::<_, _, nom::error::Error<&[u8]>>(|c: u8| c.is_ascii_digit())(&rest[1..])
                .unwrap_or((&rest[1..], b""));
        p.line_number = Some(digits.iter().fold(0u64, |a, &d| {
            a.wrapping_mul(10).wrapping_add(u64::from(d - b'0'))
        }));
        rest = spaces(r).map(|(r, _)| r).unwrap_or(r);
    }

    // The command.
    let start_col = col(rest);
    match rest {
        [c, d, ..] if c.is_ascii_alphabetic() && (d.is_ascii_alphabetic() || *d == b'_') => {
            extended(&mut p, line, rest);
            return p;
        }
        [b'_', ..] => {
            extended(&mut p, line, rest);
            return p;
        }
        [c, d, ..] if c.is_ascii_alphabetic() && d.is_ascii_digit() => {
            let (r, digits) =
                take_while1::<_, _, nom::error::Error<&[u8]>>(|c: u8| c.is_ascii_digit())(
                    &rest[1..],
                )
                .unwrap_or((&rest[1..], b""));
            let (r, subcode) = match r {
                [b'.', d, ..] if d.is_ascii_digit() => {
                    let (r2, sub) =
                        take_while1::<_, _, nom::error::Error<&[u8]>>(|c: u8| c.is_ascii_digit())(
                            &r[1..],
                        )
                        .unwrap_or((&r[1..], b""));
                    (r2, Some(small_int(sub)))
                }
                _ => (r, None),
            };
            let letter = c.to_ascii_uppercase();
            let number = small_int(digits);
            p.command = Command::Code {
                letter,
                number,
                subcode,
                column: start_col,
            };
            if subcode.is_none() && takes_text(letter, number) {
                let t = r.strip_prefix(b" ").unwrap_or(r);
                p.text = Some(t.trim_ascii_end());
                return p;
            }
            rest = r;
        }
        _ => {}
    }
    classic_words(&mut p, line, rest);
    p
}

/// 1-based column of `rest`, a sub-slice of `line`.
fn column(line: &[u8], rest: &[u8]) -> u32 {
    (rest.as_ptr() as usize - line.as_ptr() as usize + 1) as u32
}

/// Digits to a number, saturating (command numbers are small).
fn small_int(digits: &[u8]) -> u32 {
    digits.iter().fold(0u32, |a, &d| {
        a.saturating_mul(10).saturating_add(u32::from(d - b'0'))
    })
}

/// Words of a classic command, `( )` comments in between.
fn classic_words<'a>(p: &mut ParsedLine<'a>, line: &'a [u8], mut rest: &'a [u8]) {
    let col = |rest: &[u8]| column(line, rest);
    let motion = is_motion(&p.command);
    let mut seen = 0u32; // bit per letter
    let mut after_number = false; // the previous token was a number, no space since
    loop {
        let (r, sp) = spaces(rest).unwrap_or((rest, b""));
        if !sp.is_empty() {
            after_number = false;
        }
        rest = r;
        let Some(&c) = rest.first() else { return };
        if c == b'(' {
            let close = rest.iter().position(|&b| b == b')');
            let inside = &rest[1..close.unwrap_or(rest.len())];
            if p.comment.is_none() {
                p.comment = Some(inside);
            }
            if close.is_none() {
                p.diag(col(rest), Severity::Warning, DiagKind::UnclosedParen);
                return;
            }
            rest = &rest[inside.len() + 2..];
            after_number = false;
            continue;
        }
        if !c.is_ascii_alphabetic() {
            p.diag(col(rest), Severity::Warning, DiagKind::UnexpectedChar(c));
            rest = &rest[1..];
            after_number = false;
            continue;
        }
        let letter = c.to_ascii_uppercase();
        let letter_col = col(rest);
        if letter == b'E' && after_number {
            p.diag(letter_col, Severity::Warning, DiagKind::ExponentReadAsE);
        }
        let (r, _) = spaces(&rest[1..]).unwrap_or((&rest[1..], b""));
        let mut value = None;
        after_number = false;
        rest = if matches!(r.first(), Some(b'0'..=b'9' | b'+' | b'-' | b'.')) {
            let value_col = col(r);
            let (r2, num) = number(r);
            // A number ends at whitespace, a letter, `(` or the end.
            let ends_well = matches!(r2.first(), None | Some(b' ' | b'\t' | b'('))
                || r2.first().is_some_and(u8::is_ascii_alphabetic);
            match num {
                Some(v) if ends_well => {
                    value = Some(v);
                    after_number = true;
                    r2
                }
                _ => {
                    let sev = if motion {
                        Severity::Error
                    } else {
                        Severity::Warning
                    };
                    // Digits that end well but give no value: too large.
                    let text = &r[..r.len() - r2.len()];
                    let kind = if ends_well && text.iter().any(u8::is_ascii_digit) {
                        DiagKind::NumberOutOfRange
                    } else {
                        DiagKind::MalformedNumber
                    };
                    p.diag(value_col, sev, kind);
                    // Skip the bad token.
                    let n = r2.iter().position(|&b| is_space(b)).unwrap_or(r2.len());
                    &r2[n..]
                }
            }
        } else {
            r
        };
        let bit = 1u32 << (letter - b'A');
        if seen & bit != 0 {
            p.diag(
                letter_col,
                Severity::Warning,
                DiagKind::DuplicateWord(letter),
            );
        }
        seen |= bit;
        if !p.words.push(Word {
            letter,
            value,
            column: letter_col,
        }) {
            p.diag(letter_col, Severity::Warning, DiagKind::TooManyWords);
            return;
        }
    }
}

/// A Klipper extended command: name, then `KEY=VALUE` parameters (checked here, stored
/// as text and read again by [`ParsedLine::params`]).
fn extended<'a>(p: &mut ParsedLine<'a>, line: &'a [u8], rest: &'a [u8]) {
    let Ok((rest, n)) = name(rest) else {
        return;
    };
    p.command = Command::Extended {
        name: n,
        column: column(line, n),
    };
    p.args = rest;
    let mut rest = rest;
    while let Some((r, item)) = next_param(line, rest) {
        rest = r;
        if let Err((col, kind)) = item {
            p.diag(col, Severity::Warning, kind);
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
            let (rest, item) = next_param(self.line, self.rest)?;
            self.rest = rest;
            if let Ok(p) = item {
                return Some(p);
            }
        }
    }
}

type ParamItem<'a> = Result<Param<'a>, (u32, DiagKind)>;

/// The next `KEY=VALUE` of `rest` (a sub-slice of `line`), or the problem at its place;
/// `None` at the end.
fn next_param<'a>(line: &'a [u8], rest: &'a [u8]) -> Option<(&'a [u8], ParamItem<'a>)> {
    let rest = spaces(rest).map(|(r, _)| r).unwrap_or(rest);
    if rest.is_empty() {
        return None;
    }
    let key_col = column(line, rest);
    let Ok((r, k)) = key(rest) else {
        // Only `=` can start here.
        let r = bare_value(rest).map(|(r, _)| r).unwrap_or(&rest[1..]);
        return Some((r, Err((key_col, DiagKind::ExpectedKeyValue))));
    };
    let Some(r) = r.strip_prefix(b"=") else {
        return Some((r, Err((key_col, DiagKind::ExpectedKeyValue))));
    };
    let (r, value) = if let [quote @ (b'"' | b'\''), q @ ..] = r {
        match q.iter().position(|c| c == quote) {
            Some(end) => (&q[end + 1..], &q[..end]),
            None => {
                return Some((
                    &q[q.len()..],
                    Err((column(line, r), DiagKind::UnclosedQuote)),
                ));
            }
        }
    } else {
        bare_value(r).unwrap_or((r, b""))
    };
    Some((
        r,
        Ok(Param {
            key: k,
            value,
            column: key_col,
        }),
    ))
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
