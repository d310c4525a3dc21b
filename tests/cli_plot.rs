//! The `plot` command end to end, on a trace written by `trace`.

use std::path::Path;

use assert_cmd::Command;

const PAPER: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/machines/paper.yaml");

fn cmd() -> Command {
    Command::cargo_bin("delta-gcode").unwrap()
}

/// A short square at z = 0.2 traced with the paper's machine.
fn small_trace(dir: &Path) -> std::path::PathBuf {
    let gcode = dir.join("square.gcode");
    std::fs::write(
        &gcode,
        "G28\nG90\nG0 X0 Y0 Z0.2 F6000\nG1 X30 F3000\nG1 Y30\nG1 X0\nG1 Y0\n",
    )
    .unwrap();
    let csv = dir.join("square.csv");
    cmd()
        .args(["trace", gcode.to_str().unwrap(), "-m", PAPER, "-o"])
        .arg(&csv)
        .assert()
        .success();
    csv
}

fn assert_valid_svg(svg: &str) {
    assert!(svg.starts_with("<svg"), "{}", &svg[..svg.len().min(200)]);
    assert!(svg.trim_end().ends_with("</svg>"));
    assert!(!svg.contains("NaN") && !svg.contains("inf"));
}

#[test]
fn plot_draws_columns_sums_differences_and_reference_lines() {
    let dir = tempfile::tempdir().unwrap();
    let csv = small_trace(dir.path());
    let svg = dir.path().join("out.svg");
    cmd()
        .arg("plot")
        .arg(&csv)
        .arg(&csv)
        .args(["--label", "first", "--label", "second"])
        .args(["--column", "f1_n", "--sum", "f1_n,f2_n,f3_n"])
        .args([
            "--diff",
            "energy_rate_w,power_w",
            "--hline",
            "13.4397:weight (eq. 17)",
        ])
        .args(["--energy-slope", PAPER, "--lines", "4.."])
        .args(["--title", "Square", "--y-label", "N or W", "-o"])
        .arg(&svg)
        .assert()
        .success();
    let text = std::fs::read_to_string(&svg).unwrap();
    assert_valid_svg(&text);
    for legend in [
        "first: f1_n",
        "second: f1_n + f2_n + f3_n",
        "first: energy_rate_w − power_w",
        "second: d(K+U)/dt, differenced",
        "weight (eq. 17)",
        "Square",
        "N or W",
    ] {
        assert!(text.contains(legend), "{legend}");
    }
}

#[test]
fn normalized_x_runs_from_zero_to_one() {
    let dir = tempfile::tempdir().unwrap();
    let csv = small_trace(dir.path());
    let svg = dir.path().join("n.svg");
    cmd()
        .arg("plot")
        .arg(&csv)
        .args([
            "--column",
            "f3_n",
            "--normalize-x",
            "--x-range",
            "0.1..0.9",
            "-o",
        ])
        .arg(&svg)
        .assert()
        .success();
    let text = std::fs::read_to_string(&svg).unwrap();
    assert_valid_svg(&text);
    assert!(text.contains("fraction of the run"));
    assert!(text.contains("\n0.500\n"), "a tick at 0.5");
}

#[test]
fn bad_requests_exit_2_with_the_file_and_line() {
    let dir = tempfile::tempdir().unwrap();
    let csv = small_trace(dir.path());
    let svg = dir.path().join("x.svg");
    let out = cmd()
        .arg("plot")
        .arg(&csv)
        .args(["--column", "f4_n", "-o"])
        .arg(&svg)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("square.csv:1: no column `f4_n`"), "{err}");
    assert!(!svg.exists(), "nothing written on error");

    let out = cmd()
        .arg("plot")
        .arg(&csv)
        .arg("-o")
        .arg(&svg)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("nothing to plot"));

    let out = cmd()
        .arg("plot")
        .arg(&csv)
        .args(["--diff", "f1_n", "-o"])
        .arg(&svg)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("expected two columns"));

    let bad = dir.path().join("bad.csv");
    std::fs::write(&bad, "t_s,line,f1_n\n0,1,2\n0.1,1,oops\n").unwrap();
    let out = cmd()
        .arg("plot")
        .arg(&bad)
        .args(["--column", "f1_n", "-o"])
        .arg(&svg)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("bad.csv:3:7: column `f1_n`"), "{err}");
}
