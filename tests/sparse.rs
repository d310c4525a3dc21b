//! The sparse evaluation (docs/performance.md) gives the statistics of dense sampling:
//! every move's peaks, when and in which phase, its worst share of the available force, its
//! tension, its problems and its sample count, bit for bit; and the same report.

mod common;

use common::*;
use delta_gcode::analysis::{MoveChecker, MoveResult, Scratch, sequence};
use delta_gcode::machine::Machine;
use delta_gcode::report::MoveStats;

/// Each line's statistics from a run of `checker` over `gcode`, and the samples skipped.
fn stats(machine: &Machine, gcode: &[u8], dense: bool) -> (Vec<MoveStats>, u64) {
    let checker = MoveChecker::new(machine, ());
    let checker = if dense { checker.dense() } else { checker };
    let mut scratch = Box::<Scratch>::default();
    let mut merged: Vec<MoveResult<()>> = Vec::new();
    sequence(
        gcode,
        machine,
        8192,
        |_| {},
        |b| {
            let mut out = Vec::new();
            checker.check_moves(&mut scratch, &b.pieces, &b.moves, &mut out);
            for r in out {
                match merged.last_mut() {
                    Some(last) if last.group == r.group => last.stats.merge(&r.stats),
                    _ => merged.push(r),
                }
            }
        },
    )
    .expect("reads");
    (
        merged.into_iter().map(|r| r.stats).collect(),
        checker.skipped_samples(),
    )
}

/// The kossel profile, with `extra` YAML appended.
fn kossel(extra: &str) -> Machine {
    let text = std::fs::read_to_string(repo("machines/kossel.yaml")).expect("profile") + extra;
    Machine::from_yaml_str(&text, "kossel").expect("valid profile")
}

/// Sparse against dense on one file and profile: identical statistics; returns the share of
/// the samples skipped.
fn compare(machine: &Machine, gcode: &[u8], name: &str) -> f64 {
    let (dense, none) = stats(machine, gcode, true);
    assert_eq!(none, 0, "dense skips nothing");
    let (sparse, skipped) = stats(machine, gcode, false);
    assert_eq!(sparse.len(), dense.len(), "{name}");
    for (s, d) in sparse.iter().zip(&dense) {
        assert_eq!(s, d, "{name}: line {}", d.line);
    }
    let total: u64 = dense.iter().map(|m| m.samples).sum();
    skipped as f64 / total as f64
}

const SHAPER: &str =
    "\ninput_shaper:\n  shaper_type: mzv\n  shaper_freq_x: 40\n  shaper_freq_y: 40\n";
const SOFT_DRIVE: &str = "\ndrive:\n  frequency_hz: 25\n  damping_ratio: 0.03\n";

#[test]
fn sparse_statistics_are_the_dense_ones_on_real_files() {
    let files = [
        "samples/calib-cube_cura413_kossel-mini.gcode",
        "samples/over-limit.gcode",
        "tests/fixtures/ps25_bunny_head.gcode",
        "tests/fixtures/ps29_arcs_exclude.gcode",
        "tests/fixtures/marlin2_bunny_head.gcode",
    ];
    let mut skipped = 0.0f64;
    for extra in ["", SHAPER, SOFT_DRIVE] {
        let machine = kossel(extra);
        for f in files {
            let gcode = std::fs::read(repo(f)).expect("fixture");
            let share = compare(&machine, &gcode, f);
            eprintln!(
                "{f} {extra:?}: {:.1} % of the samples skipped",
                100.0 * share
            );
            skipped = skipped.max(share);
        }
    }
    // Not vacuous: the sparse evaluation does skip runs of these files.
    assert!(skipped > 0.1, "{skipped}");
}

#[test]
fn the_report_is_the_same_with_the_dense_evaluation_forced() {
    let machine = repo("machines/kossel.yaml").display().to_string();
    let run = |dense: bool| {
        let mut cmd = bin();
        cmd.args([
            "check",
            "-m",
            &machine,
            "--format",
            "json",
            "--all-moves",
            "-q",
        ])
        .arg(repo("samples/calib-cube_cura413_kossel-mini.gcode"))
        .arg(repo("samples/over-limit.gcode"));
        if dense {
            cmd.env(delta_gcode::analysis::DENSE_ENV, "1");
        } else {
            cmd.env_remove(delta_gcode::analysis::DENSE_ENV);
        }
        let o = cmd.output().expect("runs");
        assert!(o.status.code().is_some_and(|c| c < 2), "{}", stderr(&o));
        o.stdout
    };
    let sparse = run(false);
    assert!(sparse.len() > 100_000);
    assert_eq!(sparse, run(true));
}

/// The whole corpus: `DELTA_GCODE_CORPUS=/path/to/corpus cargo test --release --test sparse
/// -- --ignored` (each `*.gcode.xz` decompressed with `xz`).
#[test]
#[ignore]
fn sparse_statistics_are_the_dense_ones_on_the_corpus() {
    let dir = std::env::var("DELTA_GCODE_CORPUS").expect("DELTA_GCODE_CORPUS names the corpus");
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .expect("corpus directory")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.to_string_lossy().ends_with(".gcode.xz"))
        .collect();
    files.sort();
    assert!(!files.is_empty());
    for extra in ["", SHAPER] {
        let machine = kossel(extra);
        for f in &files {
            let o = std::process::Command::new("xz")
                .arg("-dc")
                .arg(f)
                .output()
                .expect("xz runs");
            let name = f.display().to_string();
            let share = compare(&machine, &o.stdout, &name);
            eprintln!(
                "{name} {extra:?}: {:.1} % of the samples skipped",
                100.0 * share
            );
        }
    }
}
