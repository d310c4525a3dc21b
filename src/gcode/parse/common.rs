//! The common line read without the grammar: a G or M code and its words, each an
//! upper-case letter and a plain number (`G1 X12.04 Y7.467 E5.58676`), a `;` comment
//! allowed. Nearly every line a slicer writes is one. Through the grammar's tokens the
//! parser took 175 M instructions on the first 5 MB of the corpus's bunny (about 960 a
//! line); with this path, which finds the `;` on its way, about 90 M (docs/gcode.md).
//! Anything else (a line number, a subcode, a lower-case letter, a letter without a
//! number, a sign other than `-`, a tab, a `(` comment, a `*`, a duplicate word, more than
//! 15 digits or more than 9 before the point, a word right after a number, more than
//! [`MAX_WORDS`] words) is declined as soon as it is seen, and the grammar reads the line:
//! whatever this keeps, the grammar keeps the same (test
//! `the_common_path_reads_what_the_grammar_reads`).

use super::grammar::decimal;
use super::{Command, MAX_NUMBER, MAX_WORDS, ParsedLine, Word, takes_text};

// Any number this path reads (at most 9 digits before the point) is within range.
const _: () = assert!(MAX_NUMBER >= 1e9);

impl<'a> ParsedLine<'a> {
    /// Reads `line` (without its terminator) if it is a common line; false, with nothing
    /// kept, if it is not. Its `;` is found on the way (a `*` before it is declined), so
    /// that a common line is read in one pass.
    #[inline(always)]
    pub(super) fn parse_common(&mut self, line: &'a [u8]) -> bool {
        let b = line;
        let n = b.len();
        let letter = match b.first() {
            Some(&c) if c.is_ascii_uppercase() && c != b'N' => c,
            _ => return false,
        };
        // The command's number: at most 9 digits (the grammar's saturating sum is exact
        // there). A subcode's `.` is declined as the first word's letter.
        let mut i = 1;
        let mut number: u32 = 0;
        while i < n && b[i].is_ascii_digit() {
            number = number * 10 + u32::from(b[i] - b'0');
            i += 1;
            if i > 10 {
                return false;
            }
        }
        if i == 1 || takes_text(letter, number) {
            return false;
        }
        self.command = Command::Code {
            letter,
            number,
            subcode: None,
            column: 1,
        };
        // The first word may follow the command's number without a blank (`G1E5`).
        skip_blanks(b, &mut i);
        loop {
            let Some(&letter) = b.get(i) else {
                return true;
            };
            if letter == b';' {
                self.comment = Some(&b[i + 1..]);
                return true;
            }
            if !letter.is_ascii_uppercase() {
                return self.decline();
            }
            let column = i as u32 + 1;
            i += 1;
            let negative = b.get(i) == Some(&b'-');
            i += usize::from(negative);
            // All the digits as one integer (wrapping past 19 digits, which is declined):
            // the fraction's digits go on from the integer part's, not valued apart and
            // joined by a multiplication (0.38 % of an unshaped run's instructions; one loop
            // for both parts, the point tested in it, was 0.7 % more).
            let mut digits = 0;
            let int_count = more_digits(b, &mut i, &mut digits);
            let frac_count = if b.get(i) == Some(&b'.') {
                i += 1;
                more_digits(b, &mut i, &mut digits)
            } else {
                0
            };
            let count = int_count + frac_count;
            // An integer part of at most 9 digits is below 10^9, within range.
            if count == 0 || count > 15 || int_count > 9 {
                return self.decline();
            }
            let value = decimal(negative, digits, frac_count);
            let slot = usize::from(letter - b'A');
            if self.slots[slot] != 0 || self.words.len() == MAX_WORDS {
                return self.decline();
            }
            self.words.push(Word {
                letter,
                value: Some(value),
                column,
            });
            self.slots[slot] = self.words.len() as u8;
            // A number ends at a blank, a `;` or the end of the line: anything else is
            // declined, a word right after it (`X1Y2`, `X1E5`, whose `E` the grammar notes as
            // no exponent) included. Slicers write a blank between words: one is taken
            // first, then any more (a loop over the blanks, the letter tested for `E` right
            // after a number, was 0.27 % of an unshaped run's instructions).
            match b.get(i) {
                Some(b' ') => i += 1,
                Some(b';') | None => {}
                Some(_) => return self.decline(),
            }
            skip_blanks(b, &mut i);
        }
    }

    /// Not a common line: what was kept of it is dropped, for the grammar to read it.
    #[cold]
    #[inline(never)]
    fn decline(&mut self) -> bool {
        self.words.clear();
        self.slots = [0; 26];
        self.command = Command::None;
        false
    }
}

/// Moves `*i` past the blanks at `b[*i]`.
#[inline(always)]
fn skip_blanks(b: &[u8], i: &mut usize) {
    while b.get(*i) == Some(&b' ') {
        *i += 1;
    }
}

/// The digits from `b[*i]` on, appended to `value` (wrapping past 19 digits in all, which
/// the caller declines); how many. `*i` moves past them.
#[inline(always)]
fn more_digits(b: &[u8], i: &mut usize, value: &mut u64) -> usize {
    let start = *i;
    while let Some(&c) = b.get(*i)
        && c.is_ascii_digit()
    {
        *value = value.wrapping_mul(10).wrapping_add(u64::from(c - b'0'));
        *i += 1;
    }
    *i - start
}

#[cfg(test)]
mod tests {
    use super::super::{LineDiag, grammar};
    use super::*;
    use proptest::prelude::*;
    use proptest::strategy::ValueTree;

    /// What a parsed line shows its readers, values by their bits (−0 is not 0).
    type Shown = (
        String,
        Option<u64>,
        Vec<(u8, Option<u64>, u32)>,
        Vec<Option<(u8, u32)>>,
        Option<Vec<u8>>,
        Option<Vec<u8>>,
        Option<u32>,
        Vec<LineDiag>,
        Vec<(Vec<u8>, Vec<u8>, u32)>,
    );

    fn shown(p: &ParsedLine) -> Shown {
        let word = |w: &Word| (w.letter, w.value.map(f64::to_bits), w.column);
        (
            format!("{:?}", p.command),
            p.line_number,
            p.words().iter().map(word).collect(),
            (b'A'..=b'Z')
                .map(|l| p.word(l).map(|w| (w.letter, w.column)))
                .collect(),
            p.text.map(<[u8]>::to_vec),
            p.comment.map(<[u8]>::to_vec),
            p.checksum,
            p.diags().to_vec(),
            p.params()
                .map(|a| (a.key.to_vec(), a.value.to_vec(), a.column))
                .collect(),
        )
    }

    /// The line read by the grammar alone, as before the common path.
    fn by_grammar(line: &[u8]) -> ParsedLine<'_> {
        let mut p = ParsedLine::blank(line);
        let (code, comment, last_star) = grammar::code_and_comment(p.line);
        p.comment = comment;
        p.parse_grammar(code, last_star);
        p
    }

    /// Whether the common path takes the line, and the same as the grammar if it does.
    fn common(line: &[u8]) -> bool {
        let mut p = ParsedLine::blank(line);
        let taken = p.parse_common(p.line);
        let whole = super::super::parse_line(line);
        assert_eq!(shown(&whole), shown(&by_grammar(line)), "{line:?}");
        if taken {
            assert_eq!(shown(&p), shown(&whole), "{line:?}");
        }
        taken
    }

    #[test]
    fn common_lines_are_taken_and_others_left_to_the_grammar() {
        for line in [
            "G1 X12.04 Y7.467 E5.58676\n",
            "G1 X-.5 Y-0 E1. F1200 ; comment * with a star\r\n",
            "G1E5",
            "G28;home",
            "G1 X1;c*5",
            "G1 X999999999.999999",
            "G92 E0 ;",
            "M204 S3000",
            "G28",
            "G1  X1   Y2  ",
            "G1 X.123456789012345 Y-123456.789012345 Z999999999",
            "G123456789 X1",
            &many(MAX_WORDS),
        ] {
            assert!(common(line.as_bytes()), "{line:?} not taken");
        }
        for line in [
            "",
            ";comment",
            " G1 X1",
            "N10 G1 X1",
            "g1 X1",
            "G X1",
            "G29.1 X1",
            "G1234567890 X1",
            "M117 Hello X1",
            "M486 Acube",
            "SET_VELOCITY_LIMIT ACCEL=3000",
            "G1 x1",
            "G1 X",
            "G1 X Y2",
            "G1\tX1",
            "G1 X+1",
            "G1 X-",
            "G1 X.",
            "G1 X1.2.3",
            "G1 X1:2",
            "G1 X1e5",
            "G1 X1E5",
            "G0 F9000 X1Y2",
            "G1 X1 (note) Y2",
            "G1 X1 X2",
            "G1 X1234567890123456",
            "G1 X1000000001",
            "G1 Z1000000000",
            "G1 X1 Y2*7",
            "G1 X\u{e9}",
            &many(MAX_WORDS + 1),
        ] {
            assert!(!common(line.as_bytes()), "{line:?} taken");
        }
    }

    /// A G1 of `n` words of different letters from A on.
    fn many(n: usize) -> String {
        let words: String = (b'A'..=b'Z')
            .take(n)
            .map(|l| format!(" {}1", char::from(l)))
            .collect();
        format!("G1{words}")
    }

    /// Bytes that make common lines and every way of not being one.
    fn piece() -> impl Strategy<Value = &'static str> {
        prop_oneof![
            8 => prop_oneof![Just(" X"), Just(" Y"), Just(" E"), Just(" F"), Just("Z"), Just("E")],
            8 => prop_oneof![Just("1"), Just("0"), Just("9"), Just("."), Just("-"), Just("12.345")],
            1 => prop_oneof![Just(" "), Just("\t"), Just("+"), Just("x"), Just("e"), Just("("),
                Just(")"), Just(";c"), Just("*"), Just("N"), Just("_"), Just("\u{e9}"),
                Just("1234567890"), Just("1234567890123456"), Just("\r"), Just("\n")],
        ]
    }

    proptest! {
        // Each case takes microseconds: many, so that rare shapes (`E` right after a
        // number, a duplicate) come up.
        #![proptest_config(ProptestConfig::with_cases(4096))]

        /// Whatever the common path takes, the grammar reads the same; and every line reads
        /// as the grammar reads it.
        #[test]
        fn the_common_path_reads_what_the_grammar_reads(
            head in prop_oneof![Just("G1"), Just("G0"), Just("M204"), Just("M117"), Just("N3 G1"),
                Just("G29.1"), Just("T0"), Just(""), Just("SET_X")],
            pieces in proptest::collection::vec(piece(), 0..14),
        ) {
            let line = format!("{head}{}", pieces.concat());
            common(line.as_bytes());
        }
    }

    /// The generated lines above are taken often enough to test the common path.
    #[test]
    fn the_generated_lines_exercise_the_common_path() {
        let mut runner = proptest::test_runner::TestRunner::deterministic();
        let lines = (Just("G1"), proptest::collection::vec(piece(), 0..14));
        let mut taken = 0;
        for _ in 0..2000 {
            let (head, pieces) = lines.new_tree(&mut runner).expect("a line").current();
            taken += usize::from(common(format!("{head}{}", pieces.concat()).as_bytes()));
        }
        assert!((200..1800).contains(&taken), "{taken} of 2000 taken");
    }
}
