//! The grammar of one line, as nom parsers over the complete line (`&[u8]`).
//!
//! A parser that fails only says "not this": the error type is `()`. What is wrong with a
//! line is a token of its own ([`Token::Unexpected`], [`Value::Bad`], the `Err` of an
//! [`Arg`]), located by the slice it starts at; [`super::parse_line`] strings the parsers
//! together and turns their tokens into the command, words, parameters and diagnostics.
//!
//! Two primitives are our own. [`byte`] matches one byte: nom's `char`, `one_of`,
//! `satisfy` and `anychar` yield a `char` and, on `&[u8]`, step over a byte from 0x80 up
//! as if it were two (the length of its UTF-8 form), which is wrong for raw bytes and
//! panics at the end of a line. [`digits`] reads a run of digits and its value in one
//! pass, the innermost loop of the parser: `fold_many0(byte(digit), ..)` does the same
//! with 1.4 % more instructions and 15 % more branch misses over the whole parse
//! (cachegrind, the 27.8 MB bunny), `digit0` and a second pass with 9 % and 34 % more.
//! The search for a line's comment or checksum is memchr's, many bytes at a time (nom's
//! `take_till` looks at one byte per step: 2.4 % of `check`'s instructions). A classic
//! command's tokens ([`blank_token`], [`value`], [`numeral`]) are read by hand, the
//! innermost loop of the parser; their nom form is the reference their tests hold them
//! to (docs/gcode.md). Everything else is nom's.

use nom::{
    IResult, Parser,
    branch::alt,
    bytes::complete::{take_till, take_while, take_while_m_n, take_while1},
    character::complete::{digit1, space0},
    combinator::{eof, not, opt, recognize, rest},
    sequence::{delimited, preceded, separated_pair, terminated},
};

use super::{DiagKind, MAX_NUMBER};

type Res<'a, T> = IResult<&'a [u8], T, ()>;

fn is_space(c: u8) -> bool {
    c == b' ' || c == b'\t'
}

fn is_letter(c: u8) -> bool {
    c.is_ascii_alphabetic()
}

/// One byte satisfying `pred` (see the module documentation).
#[inline]
fn byte(pred: impl Fn(u8) -> bool) -> impl Fn(&[u8]) -> Res<'_, u8> {
    move |i| match i.split_first() {
        Some((&c, rest)) if pred(c) => Ok((rest, c)),
        _ => Err(nom::Err::Error(())),
    }
}

/// The byte `b`.
#[inline]
fn byte_eq(b: u8) -> impl Fn(&[u8]) -> Res<'_, u8> {
    byte(move |c| c == b)
}

// ---- The line: code part, comment, checksum, line number ----

/// `code [";" comment]`: the code part ends at the first `;`, the comment is the rest.
/// With it, where the code part's last `*` is: the only place a checksum can start.
#[inline]
pub(super) fn code_and_comment(line: &[u8]) -> (&[u8], Option<&[u8]>, Option<usize>) {
    // One pass to the first `;` or `*` (memchr's, many bytes at a time); a second one only
    // after a `*` (rare).
    match crate::gcode::scan::find2(line, b';', b'*').map(|i| line.split_at(i)) {
        None => (line, None, None),
        Some((code, [b';', comment @ ..])) => (code, Some(comment), None),
        _ => {
            let (comment, code) = match (take_till(|c| c == b';'), byte_eq(b';')).parse(line) {
                Ok((comment, (code, _))) => (Some(comment), code),
                Err(_) => (None, line),
            };
            (code, comment, code.iter().rposition(|&c| c == b'*'))
        }
    }
}

/// `"*" digits` closing the code part (at most 9 digits, then only whitespace): the
/// checksum as written. Tried at the code part's last `*`.
pub(super) fn checksum(i: &[u8]) -> Res<'_, u32> {
    let digits = take_while_m_n(1, 9, |c: u8| c.is_ascii_digit());
    terminated(preceded(byte_eq(b'*'), digits), (space0, eof))
        .map(small_int)
        .parse(i)
}

/// `ws ["N" digits ws]` (either case): the line number, if any (wrapping, as the
/// firmware's counter), and the input after it.
#[inline]
pub(super) fn line_start(code: &[u8]) -> (&[u8], Option<u64>) {
    let number = preceded(byte(|c| c == b'N' || c == b'n'), digit1).map(|d: &[u8]| {
        d.iter().fold(0u64, |a, &d| {
            a.wrapping_mul(10).wrapping_add(u64::from(d - b'0'))
        })
    });
    match preceded(space0, opt(terminated(number, space0))).parse(code) {
        Ok(ok) => ok,
        Err(_) => (code, None), // every part is optional: unreachable
    }
}

// ---- The command ----

/// A line's command, as written.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Head<'a> {
    /// `G1`, `M204`, `G29.1`: letter (upper case), number, subcode.
    Code {
        letter: u8,
        number: u32,
        subcode: Option<u32>,
    },
    /// `SET_VELOCITY_LIMIT`, `_MACRO`.
    Extended(&'a [u8]),
}

/// `letter digits ["." digits]` (classic) or an extended name.
#[inline]
pub(super) fn command(i: &[u8]) -> Res<'_, Head<'_>> {
    let code = (
        byte(is_letter),
        digit1,
        opt(preceded(byte_eq(b'.'), digit1)),
    )
        .map(|(letter, number, subcode)| Head::Code {
            letter: letter.to_ascii_uppercase(),
            number: small_int(number),
            subcode: subcode.map(small_int),
        });
    alt((code, extended_name.map(Head::Extended))).parse(i)
}

/// Word characters (`A-Z a-z 0-9 _`) starting with `_` or with two letters (a letter and
/// `_` will do): `SET_VELOCITY_LIMIT`, `M_X`, `_CLIENT_MACRO`.
fn extended_name(i: &[u8]) -> Res<'_, &[u8]> {
    let is_name_char = |c: u8| c.is_ascii_alphanumeric() || c == b'_';
    let start = alt((
        byte_eq(b'_'),
        terminated(byte(is_letter), byte(|c| is_letter(c) || c == b'_')),
    ));
    recognize((start, take_while(is_name_char))).parse(i)
}

/// Digits to a number, saturating (command numbers are small).
fn small_int(digits: &[u8]) -> u32 {
    digits.iter().fold(0u32, |a, &d| {
        a.saturating_mul(10).saturating_add(u32::from(d - b'0'))
    })
}

/// The free text of M117 and its kind: everything after one space, without trailing
/// whitespace.
pub(super) fn free_text(i: &[u8]) -> &[u8] {
    i.strip_prefix(b" ").unwrap_or(i).trim_ascii_end()
}

// ---- A classic command's words ----

/// A token of a classic command's argument list.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Token<'a> {
    /// A letter (upper case) and its value.
    Word { letter: u8, value: Value<'a> },
    /// `"(" inside ")"`, or without `)` when `closed` is false (then to the end).
    Comment { inside: &'a [u8], closed: bool },
    /// A byte that starts no token.
    Unexpected(u8),
}

/// The value of a word.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Value<'a> {
    /// No number after the letter: `G28 X Y`.
    None,
    Number(f64),
    /// Not a number in range, skipped up to whitespace; `text` starts where it starts.
    Bad {
        text: &'a [u8],
        kind: DiagKind,
    },
}

/// Blanks (spaces and tabs, nom's `space0`): how many start `i`.
#[inline(always)]
fn blanks(i: &[u8]) -> usize {
    i.iter().take_while(|&&c| is_space(c)).count()
}

/// `blanks token`: whether there were blanks, where the token starts (all of it), the
/// token. Fails only at the end of the input. The token's first byte tells which it is:
/// a word after a letter, a comment after `(`, else an unexpected byte. By hand, the
/// innermost loop of the parser: as nom's `alt` of the three, each tried in turn, and
/// its sequences, the words took two fifths of the parser's instructions (docs/gcode.md).
#[inline(always)]
pub(super) fn blank_token(i: &[u8]) -> Res<'_, (bool, (&[u8], Token<'_>))> {
    let skipped = blanks(i);
    let at = &i[skipped..];
    let (rest, token) = match at.split_first() {
        None => return Err(nom::Err::Error(())),
        Some((&c, after)) if is_letter(c) => {
            let (rest, value) = value(&after[blanks(after)..]);
            let letter = c.to_ascii_uppercase();
            (rest, Token::Word { letter, value })
        }
        Some((b'(', inside)) => {
            let close = memchr::memchr(b')', inside);
            let end = close.unwrap_or(inside.len());
            let comment = Token::Comment {
                inside: &inside[..end],
                closed: close.is_some(),
            };
            (&inside[(end + 1).min(inside.len())..], comment)
        }
        Some((&c, after)) => (after, Token::Unexpected(c)),
    };
    let token_text = &at[..at.len() - rest.len()];
    Ok((rest, (skipped > 0, (token_text, token))))
}

/// A word's value: a number ending at whitespace, `(`, a letter or the end of the code
/// part; nothing when no number starts here. Anything else that starts like a number
/// (`1.2.3`, `-`, `1:2`), and a number beyond [`MAX_NUMBER`], is bad and skipped up to
/// whitespace.
#[inline(always)]
fn value(i: &[u8]) -> (&[u8], Value<'_>) {
    if !matches!(i.first(), Some(b'0'..=b'9' | b'+' | b'-' | b'.')) {
        return (i, Value::None);
    }
    let runs_on = |c: u8| !(is_space(c) || c == b'(' || is_letter(c));
    let (rest, n) = numeral(i);
    let kind = match rest.first() {
        Some(&c) if runs_on(c) => DiagKind::MalformedNumber,
        _ if n.has_digits() => match n.value() {
            Some(v) => return (rest, Value::Number(v)),
            None => DiagKind::NumberOutOfRange,
        },
        _ => DiagKind::MalformedNumber,
    };
    let text = &i[..i.iter().position(|&c| is_space(c)).unwrap_or(i.len())];
    (&i[text.len()..], Value::Bad { text, kind })
}

// ---- Numbers ----

/// `[+-] digits ["." digits]` in its parts; every part may be empty (then it is no number).
#[derive(Clone, Copy, Debug)]
struct Numeral<'a> {
    negative: bool,
    int: Digits,
    frac: Digits,
    /// All of it.
    text: &'a [u8],
}

/// A run of decimal digits: how many, and their value (wrapping: exact up to 19 digits).
#[derive(Clone, Copy, Debug, Default)]
struct Digits {
    count: usize,
    value: u64,
}

impl Digits {
    #[inline]
    fn push(self, digit: u8) -> Digits {
        Digits {
            count: self.count + 1,
            value: self
                .value
                .wrapping_mul(10)
                .wrapping_add(u64::from(digit - b'0')),
        }
    }
}

/// Digits, valued as they are recognised (one pass); the input after them.
#[inline(always)]
fn digits(i: &[u8]) -> (&[u8], Digits) {
    let mut d = Digits::default();
    for &c in i {
        if !c.is_ascii_digit() {
            break;
        }
        d = d.push(c);
    }
    (&i[d.count..], d)
}

/// `[+-] digits ["." digits]`, every part optional (then no number: see
/// [`Numeral::has_digits`]); the input after it. By hand, like [`digits`]: the innermost
/// token of every word, where nom's `consumed((opt(sign), digits, opt(preceded(".",
/// digits))))` and `terminated(.., not(..))` cost a fifth of the parser's instructions
/// (docs/gcode.md).
#[inline(always)]
fn numeral(i: &[u8]) -> (&[u8], Numeral<'_>) {
    let (negative, unsigned) = match i.split_first() {
        Some((b'-', rest)) => (true, rest),
        Some((b'+', rest)) => (false, rest),
        _ => (false, i),
    };
    let (rest, int) = digits(unsigned);
    let (rest, frac) = match rest.split_first() {
        Some((b'.', after)) => digits(after),
        _ => (rest, Digits::default()),
    };
    let text = &i[..i.len() - rest.len()];
    (
        rest,
        Numeral {
            negative,
            int,
            frac,
            text,
        },
    )
}

/// Powers of ten exactly representable in an f64.
const POW10: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
    1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
];

/// The same up to 10^15, as integers.
const POW10_INT: [u64; 16] = {
    let mut t = [1u64; 16];
    let mut k = 1;
    while k < 16 {
        t[k] = t[k - 1] * 10;
        k += 1;
    }
    t
};

impl Numeral<'_> {
    #[inline]
    fn has_digits(&self) -> bool {
        self.int.count + self.frac.count > 0
    }

    /// The value: `None` without a digit or beyond [`MAX_NUMBER`].
    ///
    /// Up to 15 digits by [`decimal`] (Clinger's fast path, the one fast-float2 takes
    /// first too, without its general set-up); longer numbers go to fast-float2.
    #[inline]
    fn value(&self) -> Option<f64> {
        let (int, frac) = (self.int, self.frac);
        let v = match int.count + frac.count {
            0 => return None,
            1..=15 => {
                let digits = int.value * POW10_INT[frac.count] + frac.value;
                decimal(self.negative, digits, frac.count)
            }
            _ => long_number(self.text)?,
        };
        (v.abs() <= MAX_NUMBER).then_some(v)
    }
}

/// The value of a number of at most 15 digits in all: all its `digits` as one integer (the
/// mantissa, below 10^15), `frac_count` of them after the point, negative or not. The
/// mantissa and the power of ten are exact in an f64, so one division gives the correctly
/// rounded value (Clinger's fast path).
#[inline(always)]
pub(super) fn decimal(negative: bool, digits: u64, frac_count: usize) -> f64 {
    // Below 2^53: exact as an i64 and as an f64 (and the signed conversion is one
    // instruction, the unsigned one several).
    let v = digits as i64 as f64 / POW10[frac_count];
    // The sign as a bit (v >= 0), not a branch: signs come at random.
    f64::from_bits(v.to_bits() | u64::from(negative) << 63)
}

/// A number of more than 15 digits, correctly rounded by fast-float2.
#[cold]
#[inline(never)]
fn long_number(text: &[u8]) -> Option<f64> {
    fast_float2::parse::<f64, _>(text).ok()
}

/// A number: the input after `[+-] digits ["." digits]`, and its value (`None` without a
/// digit or beyond [`MAX_NUMBER`]).
pub(super) fn number(i: &[u8]) -> (&[u8], Option<f64>) {
    let (rest, n) = numeral(i);
    (rest, n.value())
}

// ---- An extended command's arguments ----

/// An extended command's argument: `(key, value)`, or what is wrong and where.
pub(super) type Arg<'a> = Result<(&'a [u8], &'a [u8]), (&'a [u8], DiagKind)>;

/// `blanks (KEY=VALUE | KEY="quoted value" | KEY='quoted value')`. An argument without `=`
/// is skipped up to whitespace; a quote without its closing quote takes the rest. Fails
/// only at the end of the input.
pub(super) fn argument(i: &[u8]) -> Res<'_, Arg<'_>> {
    // A key runs up to whitespace, `=` or `;`; so does a bare value (which may be empty).
    let key = || take_while1(|c: u8| !is_space(c) && c != b'=' && c != b';');
    let bare = |c: u8| !is_space(c) && c != b';';
    let quoted = |q| delimited(byte_eq(q), take_till(move |c| c == q), byte_eq(q));
    let value = alt((
        quoted(b'"'),
        quoted(b'\''),
        preceded(not(byte(|c| c == b'"' || c == b'\'')), take_while(bare)),
    ));
    let pair = separated_pair(key(), byte_eq(b'='), value).map(Ok);
    let unclosed = preceded((key(), byte_eq(b'=')), rest);
    let unclosed = unclosed.map(|quote| Err((quote, DiagKind::UnclosedQuote)));
    let no_equals = take_while1(bare).map(|at| Err((at, DiagKind::ExpectedKeyValue)));
    preceded(space0, alt((pair, unclosed, no_equals))).parse(i)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nom::combinator::consumed;
    use proptest::prelude::*;

    /// Digits as a nom parser.
    fn nom_digits(i: &[u8]) -> Res<'_, Digits> {
        Ok(digits(i))
    }

    /// A word's value in nom's combinators, as [`value`] had it before it was written by
    /// hand.
    fn nom_value(i: &[u8]) -> Res<'_, Value<'_>> {
        if !matches!(i, [b'0'..=b'9' | b'+' | b'-' | b'.', ..]) {
            return Ok((i, Value::None));
        }
        let runs_on = |c: u8| !(is_space(c) || c == b'(' || is_letter(c));
        let sign = byte(|c| c == b'+' || c == b'-');
        let numeral = consumed((
            opt(sign),
            nom_digits,
            opt(preceded(byte_eq(b'.'), nom_digits)),
        ))
        .map(|(text, (sign, int, frac))| Numeral {
            negative: sign == Some(b'-'),
            int,
            frac: frac.unwrap_or_default(),
            text,
        });
        let kind = match terminated(numeral, not(byte(runs_on))).parse(i) {
            Ok((rest, n)) if n.has_digits() => match n.value() {
                Some(v) => return Ok((rest, Value::Number(v))),
                None => DiagKind::NumberOutOfRange,
            },
            _ => DiagKind::MalformedNumber,
        };
        take_till(is_space)
            .map(|text| Value::Bad { text, kind })
            .parse(i)
    }

    /// The token grammar in nom's combinators, as [`blank_token`] had it before it was
    /// written by hand: the reference it is held to.
    fn nom_blank_token(i: &[u8]) -> Res<'_, (bool, (&[u8], Token<'_>))> {
        let comment = preceded(
            byte_eq(b'('),
            (take_till(|c| c == b')'), opt(byte_eq(b')'))),
        )
        .map(|(inside, close)| Token::Comment {
            inside,
            closed: close.is_some(),
        });
        let word = (byte(is_letter), space0, nom_value).map(|(letter, _, value)| Token::Word {
            letter: letter.to_ascii_uppercase(),
            value,
        });
        let unexpected = byte(|_| true).map(Token::Unexpected);
        let token = alt((word, comment, unexpected));
        (space0.map(|b: &[u8]| !b.is_empty()), consumed(token)).parse(i)
    }

    proptest! {
        /// Token after token, the hand-written scanner reads any line of G-code's bytes
        /// (words, signs, points, comments open and closed, tabs, bytes from 0x80 up) as
        /// nom's combinators do: the same tokens, values, diagnostics and rest.
        #[test]
        fn tokens_are_those_of_the_nom_grammar(
            line in proptest::collection::vec(
                prop_oneof![
                    Just(b'G'), Just(b'x'), Just(b'Y'), Just(b'E'), Just(b'e'), Just(b'F'),
                    Just(b'0'), Just(b'1'), Just(b'9'), Just(b'.'), Just(b'-'), Just(b'+'),
                    Just(b' '), Just(b'\t'), Just(b'('), Just(b')'), Just(b':'), Just(b'_'),
                    Just(0xC3u8), any::<u8>(),
                ],
                0..40,
            )
        ) {
            let mut rest: &[u8] = &line;
            loop {
                let ours = blank_token(rest);
                let theirs = nom_blank_token(rest);
                prop_assert_eq!(&ours, &theirs, "at {:?}", String::from_utf8_lossy(rest));
                let Ok((r, _)) = ours else { break };
                rest = r;
            }
        }
    }

    /// Long numbers, at the edges of the fast path (15 digits) and of the range.
    #[test]
    fn numbers_read_as_the_nom_grammar_reads_them() {
        for text in [
            "X123456789012345",
            "X1234567890123456",
            "X.000000000000001",
            "X-1e",
            "X1000000000",
            "X1000000001",
            "X-.5",
            "X+.",
            "X.",
            "X-",
            "X1.2.3",
            "X12(c)Y3",
            "X1 Y",
        ] {
            let i = text.as_bytes();
            assert_eq!(blank_token(i), nom_blank_token(i), "{text}");
        }
    }
}
