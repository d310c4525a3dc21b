//! A plain G-code line reader: `[N123] G1 X10 Y-2.5 E.3 F1200 [*cs] [; comment]`.
//!
//! Letters are read in either case (as upper case). A value is `[+-]digits[.digits]` (or
//! `.digits`); like Marlin's `value_float`, an `E` or `e` ends a number (`F1.2e3` is F1.2,
//! then E3). A letter without a number has no value (`seenval` is false). A letter given
//! twice: the last one counts.

/// One command line.
#[derive(Clone, Debug, PartialEq)]
pub struct Line {
    /// `G`, `M` or `T`.
    pub letter: u8,
    pub number: u32,
    /// `G92.1` → Some(1).
    pub sub: Option<u32>,
    /// The parameters, in order.
    pub words: Vec<(u8, Option<f64>)>,
}

impl Line {
    /// Marlin's `seenval(letter)`: the value of the last `letter` word that has one.
    pub fn val(&self, letter: u8) -> Option<f64> {
        self.words
            .iter()
            .rev()
            .find(|(l, _)| *l == letter)
            .and_then(|(_, v)| *v)
    }

    /// Marlin's `seen(letter)`.
    pub fn seen(&self, letter: u8) -> bool {
        self.words.iter().any(|(l, _)| *l == letter)
    }

    /// Marlin's `seen_any()`.
    pub fn any(&self) -> bool {
        !self.words.is_empty()
    }
}

/// A number at the start of `s`: its value and how many bytes it took.
fn read_number(s: &[u8]) -> Option<(f64, usize)> {
    let mut i = 0;
    if i < s.len() && (s[i] == b'+' || s[i] == b'-') {
        i += 1;
    }
    let digits_start = i;
    while i < s.len() && s[i].is_ascii_digit() {
        i += 1;
    }
    let mut digits = i - digits_start;
    if i < s.len() && s[i] == b'.' {
        i += 1;
        let frac = i;
        while i < s.len() && s[i].is_ascii_digit() {
            i += 1;
        }
        digits += i - frac;
    }
    if digits == 0 {
        return None;
    }
    let text = std::str::from_utf8(&s[..i]).ok()?;
    text.parse::<f64>().ok().map(|v| (v, i))
}

/// Reads one line; None for blank, comment-only or unreadable lines.
pub fn parse_line(raw: &[u8]) -> Option<Line> {
    // Drop the comment and the checksum.
    let end = raw
        .iter()
        .position(|&b| b == b';' || b == b'*')
        .unwrap_or(raw.len());
    let text: Vec<u8> = raw[..end].iter().map(|b| b.to_ascii_uppercase()).collect();
    let mut i = 0;
    let skip_blank = |i: &mut usize| {
        while *i < text.len() && (text[*i] == b' ' || text[*i] == b'\t' || text[*i] == b'\r') {
            *i += 1;
        }
    };
    skip_blank(&mut i);
    // Line number.
    if i < text.len() && text[i] == b'N' {
        i += 1;
        while i < text.len() && text[i].is_ascii_digit() {
            i += 1;
        }
        skip_blank(&mut i);
    }
    if i >= text.len() {
        return None;
    }
    let letter = text[i];
    if !matches!(letter, b'G' | b'M' | b'T') {
        return None;
    }
    i += 1;
    let start = i;
    while i < text.len() && text[i].is_ascii_digit() {
        i += 1;
    }
    if i == start {
        return None;
    }
    let number: u32 = std::str::from_utf8(&text[start..i]).ok()?.parse().ok()?;
    let mut sub = None;
    if i < text.len() && text[i] == b'.' {
        let s = i + 1;
        let mut j = s;
        while j < text.len() && text[j].is_ascii_digit() {
            j += 1;
        }
        if j > s {
            sub = std::str::from_utf8(&text[s..j]).ok()?.parse().ok();
            i = j;
        }
    }
    let mut words = Vec::new();
    while i < text.len() {
        let c = text[i];
        if c.is_ascii_uppercase() {
            i += 1;
            // Spaces may stand between a letter and its number.
            let mut j = i;
            while j < text.len() && text[j] == b' ' {
                j += 1;
            }
            match read_number(&text[j..]) {
                Some((v, len)) => {
                    words.push((c, Some(v)));
                    i = j + len;
                }
                None => words.push((c, None)),
            }
        } else {
            i += 1;
        }
    }
    Some(Line {
        letter,
        number,
        sub,
        words,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_words() {
        let l = parse_line(b"N12 g1 x10 Y-2.5 E.3 F1200*55 ; hi").unwrap();
        assert_eq!(l.letter, b'G');
        assert_eq!(l.number, 1);
        assert_eq!(l.val(b'X'), Some(10.0));
        assert_eq!(l.val(b'Y'), Some(-2.5));
        assert_eq!(l.val(b'E'), Some(0.3));
        assert_eq!(l.val(b'F'), Some(1200.0));
        let l = parse_line(b"G1 F1.2e3").unwrap();
        assert_eq!(l.val(b'F'), Some(1.2));
        assert_eq!(l.val(b'E'), Some(3.0));
        let l = parse_line(b"G92.1").unwrap();
        assert_eq!(l.sub, Some(1));
        assert!(parse_line(b"; only a comment").is_none());
        let l = parse_line(b"G28 X").unwrap();
        assert!(l.seen(b'X'));
        assert_eq!(l.val(b'X'), None);
    }
}
