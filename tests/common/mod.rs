//! Shared helpers of the end-to-end tests: run the binary, read the repository's files.
#![allow(dead_code)] // each test crate uses its own subset

pub mod fix;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// A file of the repository, by its path from the top.
pub fn repo(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(path)
}

pub fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_delta-gcode"))
}

/// Runs delta-gcode with `args`; returns the output.
pub fn run(args: &[&str]) -> Output {
    bin().args(args).output().expect("delta-gcode runs")
}

pub fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Drops the lines delta-gcode adds (`; delta-gcode…`), keeping every other byte.
pub fn strip_ours(bytes: &[u8]) -> Vec<u8> {
    bytes
        .split_inclusive(|b| *b == b'\n')
        .filter(|l| !l.starts_with(b"; delta-gcode"))
        .flatten()
        .copied()
        .collect()
}

/// Parses a trace CSV into its header and rows of numbers.
pub fn read_trace(text: &str) -> (Vec<String>, Vec<Vec<f64>>) {
    let mut lines = text.lines();
    let header = lines
        .next()
        .unwrap_or_default()
        .split(',')
        .map(str::to_string)
        .collect();
    let rows = lines
        .map(|l| {
            l.split(',')
                .map(|v| v.parse::<f64>().expect("a number"))
                .collect()
        })
        .collect();
    (header, rows)
}
