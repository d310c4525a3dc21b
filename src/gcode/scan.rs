//! Finding a byte in a line: sixteen bytes at a time (SSE2, which every x86-64 has) over a
//! line's first [`SHORT`] bytes, memchr's search beyond.
//!
//! A G-code line is short (27 bytes on average in the corpus's bunny), and memchr's search,
//! made for long haystacks, pays a dispatch through a function pointer and the set-up of
//! its 32-byte loop on every call: with it for the reader's search for the line's end and
//! the parser's for its `;` or `*`, the firmware thread ran 15.2 M instructions (3.1 %) more
//! on the bunny's first 5 MB (docs/gcode.md).

/// Bytes searched sixteen at a time before memchr takes over.
const SHORT: usize = 64;

/// The first `needle` in `hay`.
#[inline(always)]
pub fn find(hay: &[u8], needle: u8) -> Option<usize> {
    search(hay, [needle, needle], |rest| memchr::memchr(needle, rest))
}

/// The first `a` or `b` in `hay`.
#[inline(always)]
pub fn find2(hay: &[u8], a: u8, b: u8) -> Option<usize> {
    search(hay, [a, b], |rest| memchr::memchr2(a, b, rest))
}

/// The first of `needles` in `hay`: its first [`SHORT`] bytes in blocks, the rest by
/// `long`.
#[inline(always)]
fn search(hay: &[u8], needles: [u8; 2], long: impl Fn(&[u8]) -> Option<usize>) -> Option<usize> {
    match blocks::first(hay, needles) {
        Ok(found) => found,
        Err(from) => long(&hay[from..]).map(|i| from + i),
    }
}

#[cfg(target_arch = "x86_64")]
mod blocks {
    use super::SHORT;
    use std::arch::x86_64::{
        __m128i, _mm_cmpeq_epi8, _mm_loadu_si128, _mm_movemask_epi8, _mm_or_si128, _mm_set1_epi8,
    };

    /// Which of the 16 bytes from `at` are either needle (bit i for byte i).
    #[inline(always)]
    fn mask(hay: &[u8], at: usize, a: __m128i, b: __m128i) -> u32 {
        let block = &hay[at..at + 16];
        // SAFETY: SSE2 is part of x86-64; `block` holds the 16 bytes read (unaligned).
        unsafe {
            let v = _mm_loadu_si128(block.as_ptr().cast::<__m128i>());
            _mm_movemask_epi8(_mm_or_si128(_mm_cmpeq_epi8(v, a), _mm_cmpeq_epi8(v, b))) as u32
        }
    }

    /// The first needle within `hay`'s first [`SHORT`] bytes (`Ok`, `None` when `hay` is no
    /// longer and holds none), or where to search on (`Err`).
    #[inline(always)]
    pub(super) fn first(hay: &[u8], [a, b]: [u8; 2]) -> Result<Option<usize>, usize> {
        if hay.len() < 16 {
            return Ok(hay.iter().position(|&c| c == a || c == b));
        }
        // SAFETY: SSE2 is part of x86-64.
        let (va, vb) = unsafe { (_mm_set1_epi8(a as i8), _mm_set1_epi8(b as i8)) };
        let end = hay.len().min(SHORT);
        let mut at = 0;
        while at + 16 <= end {
            let m = mask(hay, at, va, vb);
            if m != 0 {
                return Ok(Some(at + m.trailing_zeros() as usize));
            }
            at += 16;
        }
        if hay.len() > SHORT {
            return Err(at);
        }
        if at == hay.len() {
            return Ok(None);
        }
        // The last 16 bytes, overlapping bytes already searched (none of them a needle).
        let last = hay.len() - 16;
        let m = mask(hay, last, va, vb);
        Ok((m != 0).then(|| last + m.trailing_zeros() as usize))
    }
}

#[cfg(not(target_arch = "x86_64"))]
mod blocks {
    /// Elsewhere memchr's search from the start.
    #[inline(always)]
    pub(super) fn first(_hay: &[u8], _needles: [u8; 2]) -> Result<Option<usize>, usize> {
        Err(0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// Every length around the blocks and [`SHORT`], the needles anywhere or nowhere:
        /// the answers of a byte-by-byte search.
        #[test]
        fn finds_what_a_plain_search_finds(
            hay in proptest::collection::vec(prop_oneof![Just(b';'), Just(b'*'), Just(b'\n'),
                Just(b'G'), Just(b'1'), Just(b' ')], 0..150),
            sparse in 0usize..8,
        ) {
            // Mostly other bytes, so that the needles are often far or absent.
            let hay: Vec<u8> = hay.iter().enumerate()
                .map(|(i, &c)| if i % (sparse + 1) == 0 { c } else { b'X' })
                .collect();
            prop_assert_eq!(find(&hay, b'\n'), hay.iter().position(|&c| c == b'\n'));
            prop_assert_eq!(find2(&hay, b';', b'*'),
                hay.iter().position(|&c| c == b';' || c == b'*'));
        }
    }

    #[test]
    fn a_needle_in_each_position_of_each_length() {
        for len in 0..=2 * SHORT + 3 {
            for at in 0..len {
                let mut hay = vec![b'a'; len];
                hay[at] = b'*';
                assert_eq!(find2(&hay, b';', b'*'), Some(at), "{len} {at}");
                assert_eq!(find(&hay, b'*'), Some(at), "{len} {at}");
                hay[at] = b'\n';
                assert_eq!(find2(&hay, b';', b'*'), None, "{len} {at}");
            }
        }
    }
}
