//! Standard output and standard error that a closed pipe does not break.
//!
//! `delta-gcode check FILE | head -1`: once `head` has its line it closes the pipe, and
//! every later write fails with EPIPE (Rust ignores SIGPIPE, so the process is not killed;
//! `println!` would panic). Here a closed standard output ends the output quietly: the
//! writes that follow are dropped, the command finishes and exits with the code it would
//! have had (for `check`, its verdict; docs/ci-gate.md).

use std::io::{self, ErrorKind, Write};

/// Writes a line to standard error, ignoring failures (a closed pipe there too).
macro_rules! say {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stderr().lock(), $($arg)*);
    }};
}
pub(crate) use say;

/// Writes a line to standard output, ignoring failures (`println!` panics on a closed
/// pipe).
macro_rules! put {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stdout(), $($arg)*);
    }};
}
pub(crate) use put;

/// Standard output (not locked, so that a writer on another thread may own it; buffer
/// it); see the module documentation.
pub struct Stdout {
    inner: io::Stdout,
    closed: bool,
}

/// Standard output for a command's results.
pub fn stdout() -> Stdout {
    Stdout {
        inner: io::stdout(),
        closed: false,
    }
}

impl Stdout {
    fn absorb<T>(&mut self, r: io::Result<T>, done: T) -> io::Result<T> {
        match r {
            Err(e) if e.kind() == ErrorKind::BrokenPipe => {
                self.closed = true;
                Ok(done)
            }
            r => r,
        }
    }
}

impl Write for Stdout {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        if self.closed {
            return Ok(buf.len());
        }
        let r = self.inner.write(buf);
        self.absorb(r, buf.len())
    }

    fn flush(&mut self) -> io::Result<()> {
        if self.closed {
            return Ok(());
        }
        let r = self.inner.flush();
        self.absorb(r, ())
    }
}
