//! The sparse evaluation (docs/performance.md) gives the statistics of dense sampling:
//! every move's peaks, when and in which phase, its worst share of the available force, its
//! tension, its problems and its sample count, bit for bit; and the same report.

mod common;

use common::*;
use delta_gcode::analysis::{MoveChecker, MoveResult, RunPeaks, Scratch, sequence};
use delta_gcode::machine::Machine;
use delta_gcode::report::{MoveStats, Report};

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

/// The report (JSON, as `check` without `--all-moves` writes it) of `gcode`, every sample
/// computed or only those the run's peaks need ([`RunPeaks`]), batches of `batch` pieces
/// checked `chunk` moves at a time (the run's peaks known so far rise between chunks); and
/// the samples skipped.
fn report(
    machine: &Machine,
    gcode: &[u8],
    run_peaks: bool,
    (batch, chunk): (usize, usize),
) -> (String, u64) {
    let mut report = Report::new("f", &machine.name, machine.motors.max_force_n, false);
    report.arm_magnet_hold_n = machine.geometry.arm_magnet_hold_n;
    let checker = MoveChecker::new(machine, RunPeaks(()));
    let checker = if run_peaks { checker } else { checker.dense() };
    let mut scratch = Box::<Scratch>::default();
    // The parts of a line split between batches joined, as the pipeline does.
    let mut pending: Option<MoveResult<()>> = None;
    let mut add = |r: MoveResult<()>| report.add_move(&r.stats);
    sequence(
        gcode,
        machine,
        batch,
        |_| {},
        |b| {
            let mut out = Vec::new();
            for moves in b.moves.chunks(chunk) {
                checker.check_moves(&mut scratch, &b.pieces, moves, &mut out);
            }
            for r in out {
                match &mut pending {
                    Some(p) if p.group == r.group => p.stats.merge(&r.stats),
                    _ => {
                        if let Some(done) = pending.replace(r) {
                            add(done);
                        }
                    }
                }
            }
        },
    )
    .expect("reads");
    if let Some(done) = pending {
        add(done);
    }
    let json = serde_json::to_string_pretty(&report).expect("serialises");
    (json, checker.skipped_samples())
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

/// A file with an unreachable pose, a carriage above its top and moves outside the print
/// disc among ordinary ones. The unreachable move comes first: its reachable part, near
/// the arms' reach, asks more force than any move the report counts.
const TROUBLE: &str = "G28\nG1 Z5 F6000\nG1 X150 Y0 F9000\nG1 X0 Y0\nG1 X40 Y10\n\
G1 X-40 Y30\nG1 X0 Y0 Z285\nG1 X30 Z284\nG1 X0 Z5\nG1 X89 Y0\nG1 X20 Y-30\nG1 X-30 Y20 F18000\n";

#[test]
fn run_peaks_give_the_dense_report() {
    let profile = std::fs::read_to_string(repo("machines/kossel.yaml")).expect("profile");
    let with = |from: &str, to: &str| {
        assert!(profile.contains(from));
        let text = profile.replace(from, to);
        Machine::from_yaml_str(&text, "kossel").expect("valid profile")
    };
    let machines = [
        ("kossel", kossel("")),
        ("shaper", kossel(SHAPER)),
        ("soft drive", kossel(SOFT_DRIVE)),
        // Force violations on many moves.
        (
            "weak motors",
            with("safety_factor: 1.25", "safety_factor: 9"),
        ),
        // Arms pulled off their magnets on some moves.
        (
            "magnets",
            with(
                "print_radius_mm: 85.0",
                "print_radius_mm: 85.0\n  arm_magnet_hold_n: 2.0",
            ),
        ),
    ];
    let mut files: Vec<(&str, Vec<u8>)> = [
        "samples/over-limit.gcode",
        "tests/fixtures/ps25_bunny_head.gcode",
        "tests/fixtures/ps29_arcs_exclude.gcode",
        "tests/fixtures/marlin2_bunny_head.gcode",
    ]
    .into_iter()
    .map(|f| (f, std::fs::read(repo(f)).expect("fixture")))
    .collect();
    files.push(("trouble", TROUBLE.as_bytes().to_vec()));
    let mut skipped = 0.0f64;
    let mut violations = 0;
    for (m, machine) in &machines {
        for (f, gcode) in &files {
            // The pipeline's batches and chunks; small batches split lines between them,
            // small chunks raise the run's peaks more often.
            for split in [(8192, 64), (40, 3), (2, 1)] {
                let (dense, none) = report(machine, gcode, false, split);
                assert_eq!(none, 0);
                let (sparse, n) = report(machine, gcode, true, split);
                assert_eq!(sparse, dense, "{f} with {m}, (batch, chunk) {split:?}");
                let v: serde_json::Value = serde_json::from_str(&dense).expect("json");
                let total = v["summary"]["samples"].as_u64().expect("samples");
                violations += v["summary"]["violations"].as_u64().expect("violations");
                skipped = skipped.max(n as f64 / total as f64);
            }
        }
    }
    // Not vacuous: most samples go uncomputed, and violations were found and kept.
    eprintln!(
        "skipped at most {:.1} %, {violations} violations",
        100.0 * skipped
    );
    assert!(skipped > 0.5, "{skipped}");
    assert!(violations > 100, "{violations}");
}

#[test]
fn the_report_is_the_same_with_the_dense_evaluation_forced() {
    let machine = repo("machines/kossel.yaml").display().to_string();
    let run = |dense: bool, all_moves: bool| {
        let mut cmd = bin();
        cmd.args(["check", "-m", &machine, "--format", "json", "-q"])
            .args(all_moves.then_some("--all-moves"))
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
    let sparse = run(false, true);
    assert!(sparse.len() > 100_000);
    assert_eq!(sparse, run(true, true));
    // Without the list of moves only the run's peaks and the violations need computing.
    let sparse = run(false, false);
    assert!(sparse.len() > 1_000);
    assert_eq!(sparse, run(true, false));
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
