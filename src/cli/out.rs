//! Standard output and standard error that a closed pipe does not break.
//!
//! `delta-gcode check FILE | head -1`: once `head` has its line it closes the pipe, and
//! every later write fails with EPIPE (Rust ignores SIGPIPE, so the process is not killed;
//! `println!` would panic). Here a closed standard output ends the output quietly: the
//! writes that follow are dropped, the command finishes and exits with the code it would
//! have had (for `check`, its verdict; docs/ci-gate.md). A long output (`trace -o -`) asks
//! [`Stdout::closed`] to stop early.

use std::io::{self, ErrorKind, StdoutLock, Write};

/// Writes a line to standard error, ignoring failures (a closed pipe there too).
macro_rules! say {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stderr().lock(), $($arg)*);
    }};
}
pub(crate) use say;

/// Standard output, locked; see the module documentation.
pub struct Stdout {
    inner: StdoutLock<'static>,
    closed: bool,
}

/// Standard output for a command's results.
pub fn stdout() -> Stdout {
    Stdout {
        inner: io::stdout().lock(),
        closed: false,
    }
}

impl Stdout {
    /// The reader went away: nothing written from now on reaches anyone.
    pub fn closed(&self) -> bool {
        self.closed
    }

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
