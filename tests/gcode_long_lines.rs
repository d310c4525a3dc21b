//! A 50 MB line without a newline: read with one bounded buffer, warned about, and copied
//! whole by the emitter.

use std::collections::BTreeMap;
use std::io::{self, Read, Write};

use delta_gcode::emit::emit;
use delta_gcode::gcode::{ArcRules, Severity, interpret};
use delta_gcode::path::Vec3;

const LEN: u64 = 50 << 20;

/// `G1 X1\n` then `;` and 50 MB of `x` without a newline.
fn input() -> impl Read {
    (&b"G1 X1\n;"[..]).chain(io::repeat(b'x').take(LEN))
}

/// Counts bytes and remembers the last few.
#[derive(Default)]
struct Tail {
    n: u64,
    last: Vec<u8>,
}

impl Write for Tail {
    fn write(&mut self, b: &[u8]) -> io::Result<usize> {
        self.n += b.len() as u64;
        self.last
            .extend_from_slice(&b[b.len().saturating_sub(16)..]);
        let cut = self.last.len().saturating_sub(16);
        self.last.drain(..cut);
        Ok(b.len())
    }

    fn flush(&mut self) -> io::Result<()> {
        Ok(())
    }
}

#[test]
fn fifty_megabyte_line() {
    let mut diags = Vec::new();
    let mut events = 0;
    let stats = interpret(
        input(),
        Vec3::new(0.0, 0.0, 200.0),
        ArcRules::default(),
        |_| events += 1,
        |d| diags.push(d),
    )
    .unwrap();
    assert_eq!(stats.lines, 2);
    assert_eq!(stats.bytes, LEN + 7);
    assert_eq!((events, stats.truncated_lines), (1, 1));
    assert_eq!(diags.len(), 1);
    assert_eq!((diags[0].line, diags[0].severity), (2, Severity::Warning));

    let mut ann = BTreeMap::new();
    ann.insert(1, vec!["; delta-gcode: one".to_string()]);
    let mut out = Tail::default();
    emit(input(), &mut out, &ann, &[]).unwrap();
    assert_eq!(out.n, LEN + 7 + 19);
    assert_eq!(out.last, vec![b'x'; 16]);
}
