//! The pipeline on several threads gives exactly what one thread gives: the same report and
//! the same trace, byte for byte, whatever the number of threads (`DELTA_GCODE_THREADS`: 1,
//! the whole pipeline on one thread; 2, its two lanes; more, helpers of the model stage).

mod common;

use common::*;

fn run_with_threads(threads: &str, args: &[&str]) -> Vec<u8> {
    let o = bin()
        .args(args)
        .env("DELTA_GCODE_THREADS", threads)
        .output()
        .expect("runs");
    assert!(o.status.code().is_some_and(|c| c < 2), "{}", stderr(&o));
    o.stdout
}

#[test]
fn reports_and_traces_do_not_depend_on_the_thread_count() {
    let cube = repo("samples/calib-cube_cura413_kossel-mini.gcode")
        .display()
        .to_string();
    let over = repo("samples/over-limit.gcode").display().to_string();
    let machine = repo("machines/kossel.yaml").display().to_string();
    // The cube's 8716 moves span several batches of the model stage.
    let check = [
        "check",
        &cube,
        &over,
        "-m",
        &machine,
        "--format",
        "json",
        "--all-moves",
        "-q",
    ];
    let one = run_with_threads("1", &check);
    assert!(one.len() > 100_000, "{} bytes", one.len());
    assert_eq!(one, run_with_threads("2", &check));
    assert_eq!(one, run_with_threads("4", &check));
    let trace = ["trace", &cube, "-m", &machine, "-o", "-"];
    let one = run_with_threads("1", &trace);
    assert!(one.len() > 1_000_000, "{} bytes", one.len());
    assert_eq!(one, run_with_threads("2", &trace));
    assert_eq!(one, run_with_threads("4", &trace));
}

#[test]
fn a_shaped_check_does_not_depend_on_the_thread_count() {
    // With an input shaper the firmware is the larger stage, and the drive stage runs on
    // the model's lane (docs/architecture.md); the batches, recycled between the stages,
    // carry the same pieces.
    let dir = tempfile::tempdir().expect("temp dir");
    let profile = dir.path().join("kossel-shaper.yaml");
    let base = std::fs::read_to_string(repo("machines/kossel.yaml")).expect("profile");
    std::fs::write(
        &profile,
        base + "\ninput_shaper:\n  shaper_type: mzv\n  shaper_freq_x: 40\n  shaper_freq_y: 36\n",
    )
    .expect("write profile");
    let cube = repo("samples/calib-cube_cura413_kossel-mini.gcode")
        .display()
        .to_string();
    let profile = profile.display().to_string();
    let check = [
        "check",
        &cube,
        "-m",
        &profile,
        "--format",
        "json",
        "--all-moves",
        "-q",
    ];
    let one = run_with_threads("1", &check);
    assert!(one.len() > 100_000, "{} bytes", one.len());
    assert_eq!(one, run_with_threads("2", &check));
    assert_eq!(one, run_with_threads("3", &check));
}
