//! Streaming line reader: one fixed buffer, no allocation per line, never the whole file.
//!
//! [`ChunkReader`] splits the input into pieces of lines: a line shorter than the buffer
//! comes as one piece with its terminator (LF, or CRLF kept whole); a longer line comes as
//! several pieces, each at most [`BUFFER_BYTES`] long, and the first one is always full, so
//! a prefix test on the first piece sees the line's first bytes. The emitter streams those
//! pieces through; [`LineReader`] hands the parser the first piece of each line and skips
//! the rest of an overlong one (`truncated`), so a 50 MB line without a newline costs one
//! buffer, not 50 MB.

use std::io::{self, ErrorKind, Read};

/// Size of the reader's buffer, and the longest line the parser sees whole.
pub const BUFFER_BYTES: usize = 128 * 1024;

/// A piece of one line, borrowed from the reader's buffer.
#[derive(Debug)]
pub struct Chunk<'a> {
    /// 1-based line number.
    pub line: u64,
    pub bytes: &'a [u8],
    /// This piece starts the line.
    pub first: bool,
    /// This piece ends the line (with its terminator, or at the end of the input).
    pub last: bool,
}

/// Splits a byte stream into line pieces (see the module documentation).
pub struct ChunkReader<R> {
    input: R,
    buf: Box<[u8]>,
    start: usize,
    end: usize,
    eof: bool,
    line: u64,
    /// The next piece starts a new line.
    at_line_start: bool,
    bytes_read: u64,
}

impl<R: Read> ChunkReader<R> {
    pub fn new(input: R) -> Self {
        Self::with_capacity(input, BUFFER_BYTES)
    }

    /// A reader with a buffer of `capacity` bytes (at least 2, so CRLF fits whole).
    pub fn with_capacity(input: R, capacity: usize) -> Self {
        ChunkReader {
            input,
            buf: vec![0; capacity.max(2)].into_boxed_slice(),
            start: 0,
            end: 0,
            eof: false,
            line: 0,
            at_line_start: true,
            bytes_read: 0,
        }
    }

    /// Bytes read from the input so far.
    pub fn bytes_read(&self) -> u64 {
        self.bytes_read
    }

    /// The next piece, or `None` at the end of the input. Inlined into the line reader (its
    /// result went through memory: 0.7 % of the firmware thread's instructions), the refill
    /// kept out of line.
    #[inline(always)]
    pub fn next_chunk(&mut self) -> io::Result<Option<Chunk<'_>>> {
        loop {
            let avail = &self.buf[self.start..self.end];
            if let Some(i) = super::scan::find(avail, b'\n') {
                return Ok(Some(self.take(i + 1, true)));
            }
            if self.eof {
                if avail.is_empty() {
                    return Ok(None);
                }
                let n = avail.len();
                return Ok(Some(self.take(n, true)));
            }
            if self.end - self.start == self.buf.len() {
                // A full buffer without a newline: hand it out, but keep a trailing CR
                // back so that a CRLF split over two reads stays one terminator.
                let mut n = self.buf.len();
                if self.buf[self.end - 1] == b'\r' {
                    n -= 1;
                }
                return Ok(Some(self.take(n, false)));
            }
            self.fill()?;
        }
    }

    fn take(&mut self, n: usize, last: bool) -> Chunk<'_> {
        let first = self.at_line_start;
        if first {
            self.line += 1;
        }
        self.at_line_start = last;
        let s = self.start;
        self.start += n;
        Chunk {
            line: self.line,
            bytes: &self.buf[s..s + n],
            first,
            last,
        }
    }

    /// Moves the unread bytes to the front and reads more after them.
    #[inline(never)]
    fn fill(&mut self) -> io::Result<()> {
        if self.start > 0 {
            self.buf.copy_within(self.start..self.end, 0);
            self.end -= self.start;
            self.start = 0;
        }
        loop {
            match self.input.read(&mut self.buf[self.end..]) {
                Ok(0) => {
                    self.eof = true;
                    return Ok(());
                }
                Ok(n) => {
                    self.end += n;
                    self.bytes_read += n as u64;
                    return Ok(());
                }
                Err(e) if e.kind() == ErrorKind::Interrupted => {}
                Err(e) => return Err(e),
            }
        }
    }
}

/// One line as the parser sees it.
#[derive(Debug)]
pub struct Line<'a> {
    /// 1-based line number.
    pub number: u64,
    /// The line's bytes with its terminator; for a truncated line, its first
    /// [`BUFFER_BYTES`] bytes.
    pub bytes: &'a [u8],
    /// The line was longer than the buffer; the rest was skipped.
    pub truncated: bool,
}

/// Yields whole lines (see the module documentation).
pub struct LineReader<R> {
    chunks: ChunkReader<R>,
    /// The previous line was truncated: skip its remaining pieces first.
    skipping: bool,
}

impl<R: Read> LineReader<R> {
    pub fn new(input: R) -> Self {
        Self::from_chunks(ChunkReader::new(input))
    }

    pub fn from_chunks(chunks: ChunkReader<R>) -> Self {
        LineReader {
            chunks,
            skipping: false,
        }
    }

    /// Bytes read from the input so far.
    pub fn bytes_read(&self) -> u64 {
        self.chunks.bytes_read()
    }

    /// The next line, or `None` at the end of the input. Inlined into the interpreter's
    /// loop, as [`ChunkReader::next_chunk`] is into it (called, its result went through
    /// memory: 0.45 % of an unshaped run's instructions).
    #[inline(always)]
    pub fn next_line(&mut self) -> io::Result<Option<Line<'_>>> {
        while self.skipping {
            match self.chunks.next_chunk()? {
                None => return Ok(None),
                Some(c) => self.skipping = !c.last,
            }
        }
        match self.chunks.next_chunk()? {
            None => Ok(None),
            Some(c) => {
                self.skipping = !c.last;
                Ok(Some(Line {
                    number: c.line,
                    bytes: c.bytes,
                    truncated: !c.last,
                }))
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A reader that returns at most `step` bytes per call, to exercise refills.
    struct Trickle<'a> {
        data: &'a [u8],
        step: usize,
    }

    impl Read for Trickle<'_> {
        fn read(&mut self, out: &mut [u8]) -> io::Result<usize> {
            let n = self.step.min(out.len()).min(self.data.len());
            out[..n].copy_from_slice(&self.data[..n]);
            self.data = &self.data[n..];
            Ok(n)
        }
    }

    fn lines(data: &[u8], cap: usize, step: usize) -> Vec<(u64, Vec<u8>, bool)> {
        let mut r =
            LineReader::from_chunks(ChunkReader::with_capacity(Trickle { data, step }, cap));
        let mut out = Vec::new();
        while let Some(l) = r.next_line().unwrap() {
            out.push((l.number, l.bytes.to_vec(), l.truncated));
        }
        out
    }

    #[test]
    fn keeps_terminators_and_last_line_without_one() {
        let got = lines(b"G1 X1\r\nG1 X2\n\nG1 X3", 64, 3);
        let want: Vec<(u64, Vec<u8>, bool)> = vec![
            (1, b"G1 X1\r\n".to_vec(), false),
            (2, b"G1 X2\n".to_vec(), false),
            (3, b"\n".to_vec(), false),
            (4, b"G1 X3".to_vec(), false),
        ];
        assert_eq!(got, want);
    }

    #[test]
    fn overlong_line_is_truncated_and_skipped() {
        let mut data = vec![b'x'; 1000];
        data.extend_from_slice(b"\nG1 X1\n");
        let got = lines(&data, 16, 7);
        assert_eq!(got.len(), 2);
        assert_eq!(got[0], (1, vec![b'x'; 16], true));
        assert_eq!(got[1], (2, b"G1 X1\n".to_vec(), false));
    }

    #[test]
    fn chunks_concatenate_to_the_input_and_crlf_is_not_split() {
        // Lines of every length around the buffer size, CRLF terminated.
        let mut data = Vec::new();
        for n in 0..40 {
            data.extend(std::iter::repeat_n(b'a', n));
            data.extend_from_slice(b"\r\n");
        }
        let mut r = ChunkReader::with_capacity(
            Trickle {
                data: &data,
                step: 5,
            },
            8,
        );
        let mut joined = Vec::new();
        let mut lines = 0;
        while let Some(c) = r.next_chunk().unwrap() {
            if c.first {
                lines += 1;
                assert_eq!(c.line, lines);
            }
            assert!(!c.bytes.ends_with(b"\r") || c.last, "CR split from its LF");
            assert!(c.last || c.bytes.len() >= 7);
            joined.extend_from_slice(c.bytes);
        }
        assert_eq!(lines, 40);
        assert_eq!(joined, data);
        assert_eq!(r.bytes_read(), data.len() as u64);
    }
}
