//! End-to-end tests of `check`, `annotate` and `trace` on the shipped samples.

mod common;

use common::*;
use std::fs;

const KOSSEL: &str = "machines/kossel.yaml";
const PAPER: &str = "machines/paper.yaml";

fn path(p: &str) -> String {
    repo(p).display().to_string()
}

#[test]
fn exit_codes_mean_something() {
    let ok = run(&[
        "check",
        &path("samples/calib-cube_cura413_kossel-mini.gcode"),
        "-m",
        &path(KOSSEL),
    ]);
    assert_eq!(ok.status.code(), Some(0), "{}{}", stdout(&ok), stderr(&ok));
    assert!(stdout(&ok).contains(": OK"), "{}", stdout(&ok));

    let over = run(&[
        "check",
        &path("samples/over-limit.gcode"),
        "-m",
        &path(KOSSEL),
    ]);
    assert_eq!(
        over.status.code(),
        Some(1),
        "{}{}",
        stdout(&over),
        stderr(&over)
    );
    assert!(stdout(&over).contains("FAIL"), "{}", stdout(&over));

    let missing = run(&["check", "no-such-file.gcode", "-m", &path(KOSSEL)]);
    assert_eq!(missing.status.code(), Some(2));
    assert!(
        stderr(&missing).contains("no-such-file.gcode"),
        "{}",
        stderr(&missing)
    );

    let usage = run(&["check", "--frobnicate"]);
    assert_eq!(usage.status.code(), Some(2));
}

#[test]
fn json_report_follows_the_design_schema() {
    let o = run(&[
        "check",
        &path("samples/over-limit.gcode"),
        "-m",
        &path(KOSSEL),
        "--format",
        "json",
        "--all-moves",
    ]);
    assert_eq!(o.status.code(), Some(1));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("JSON");
    assert!(v["machine"].as_str().is_some());
    assert!(v["limit_force_n"].as_f64().is_some());
    let s = &v["summary"];
    for key in ["lines", "moves", "samples", "violations", "unreachable"] {
        assert!(s[key].as_u64().is_some(), "summary.{key}");
    }
    assert!(s["print_time_s"].as_f64().is_some());
    assert_eq!(s["peak_use"].as_array().map(Vec::len), Some(3));
    assert_eq!(s["peak_force_n"].as_array().map(Vec::len), Some(3));
    let viol = v["violations"].as_array().expect("violations");
    assert!(!viol.is_empty());
    for x in viol {
        assert_eq!(x["kind"], "force");
        assert!(
            ["accel", "cruise", "decel", "corner"].contains(&x["phase"].as_str().unwrap_or(""))
        );
        let tower = x["tower"].as_u64().expect("tower");
        assert!((1..=3).contains(&tower));
        // More force needed than the motor can give at that instant, at that speed.
        let t = (tower - 1) as usize;
        let f = x["peak_force_n"][t].as_f64().expect("force");
        let a = x["available_force_n"][t].as_f64().expect("available");
        assert!(f > a, "{x}");
    }
    let moves = v["moves"].as_array().expect("--all-moves lists moves");
    assert_eq!(moves.len() as u64, s["moves"].as_u64().unwrap_or(0));

    // Two files: an array, in argument order.
    let two = run(&[
        "check",
        &path("samples/over-limit.gcode"),
        &path("samples/calib-cube_cura413_kossel-mini.gcode"),
        "-m",
        &path(KOSSEL),
        "--format",
        "json",
    ]);
    let arr: serde_json::Value = serde_json::from_slice(&two.stdout).expect("JSON");
    let files: Vec<&str> = arr
        .as_array()
        .expect("array")
        .iter()
        .filter_map(|r| r["file"].as_str())
        .collect();
    assert!(
        files[0].ends_with("over-limit.gcode") && files[1].ends_with("kossel-mini.gcode"),
        "{files:?}"
    );
}

#[test]
fn github_format_annotates_lines() {
    let o = run(&[
        "check",
        &path("samples/over-limit.gcode"),
        "-m",
        &path(KOSSEL),
        "--format",
        "github",
    ]);
    assert_eq!(o.status.code(), Some(1));
    let out = stdout(&o);
    assert!(
        out.lines()
            .any(|l| l.starts_with("::error file=") && l.contains(",line=")),
        "{out}"
    );
}

#[test]
fn annotate_keeps_every_input_byte_and_is_idempotent() {
    let dir = tempfile::tempdir().unwrap();
    let input = repo("samples/over-limit.gcode");
    let once = dir.path().join("once.gcode");
    let twice = dir.path().join("twice.gcode");
    let o = run(&[
        "annotate",
        &input.display().to_string(),
        "-m",
        &path(KOSSEL),
        "-o",
        &once.display().to_string(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(
        stderr(&o).starts_with("delta-gcode: FAIL: "),
        "{}",
        stderr(&o)
    );
    let annotated = fs::read(&once).unwrap();
    let original = fs::read(&input).unwrap();
    assert_ne!(annotated, original);
    assert!(String::from_utf8_lossy(&annotated).contains("; delta-gcode: OVER force"));
    assert_eq!(strip_ours(&annotated), original);
    let o = run(&[
        "annotate",
        &once.display().to_string(),
        "-m",
        &path(KOSSEL),
        "-o",
        &twice.display().to_string(),
    ]);
    assert_eq!(o.status.code(), Some(0));
    assert_eq!(fs::read(&twice).unwrap(), annotated);

    // --strict turns the warning into exit 1.
    let o = run(&[
        "annotate",
        &input.display().to_string(),
        "-m",
        &path(KOSSEL),
        "-o",
        &twice.display().to_string(),
        "--strict",
    ]);
    assert_eq!(o.status.code(), Some(1));
}

#[test]
fn annotate_in_place_and_report_beside_it() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("cube.gcode");
    let original = fs::read(repo("samples/calib-cube_cura413_kossel-mini.gcode")).unwrap();
    fs::write(&file, &original).unwrap();
    let report = dir.path().join("cube.json");
    let o = run(&[
        "annotate",
        &file.display().to_string(),
        "-m",
        &path(KOSSEL),
        "--in-place",
        "--report",
        &report.display().to_string(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let annotated = fs::read(&file).unwrap();
    assert_eq!(strip_ours(&annotated), original);
    assert!(String::from_utf8_lossy(&annotated).contains("; delta-gcode summary"));
    let v: serde_json::Value = serde_json::from_slice(&fs::read(&report).unwrap()).unwrap();
    assert_eq!(v["summary"]["violations"], 0);
}

#[cfg(unix)]
#[test]
fn failed_in_place_write_leaves_the_input_untouched() {
    // A file-size limit makes the write fail half way (SIGXFSZ ignored, so write() fails).
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("cube.gcode");
    let original = fs::read(repo("samples/calib-cube_cura413_kossel-mini.gcode")).unwrap();
    fs::write(&file, &original).unwrap();
    let script = format!(
        "trap '' XFSZ; ulimit -f 64; exec '{}' annotate --in-place -m '{}' '{}'",
        env!("CARGO_BIN_EXE_delta-gcode"),
        path(KOSSEL),
        file.display()
    );
    let o = std::process::Command::new("sh")
        .arg("-c")
        .arg(&script)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("cube.gcode"), "{}", stderr(&o));
    assert_eq!(fs::read(&file).unwrap(), original);
    assert_eq!(
        fs::read_dir(dir.path()).unwrap().count(),
        1,
        "no temporary file left"
    );
}

#[test]
fn slicer_hook_as_prusaslicer_runs_it() {
    // PrusaSlicer runs the configured line with the G-code path appended, through a shell.
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("part.gcode.pp");
    let original = fs::read(repo("samples/over-limit.gcode")).unwrap();
    fs::write(&file, &original).unwrap();
    let line = format!(
        "'{}' annotate --in-place --machine '{}'",
        env!("CARGO_BIN_EXE_delta-gcode"),
        path(KOSSEL)
    );
    let o = std::process::Command::new("sh")
        .arg("-c")
        .arg(format!("{line} '{}'", file.display()))
        .env("SLIC3R_PP_OUTPUT_NAME", dir.path().join("part.gcode"))
        .output()
        .unwrap();
    assert_eq!(
        o.status.code(),
        Some(0),
        "a non-zero exit aborts the export: {}",
        stderr(&o)
    );
    // The verdict first on stderr (what PrusaSlicer shows of a hook that fails).
    assert!(
        stderr(&o).starts_with("delta-gcode: FAIL: "),
        "{}",
        stderr(&o)
    );
    let annotated = fs::read(&file).unwrap();
    assert_eq!(strip_ours(&annotated), original);
    assert!(String::from_utf8_lossy(&annotated).contains("; delta-gcode: OVER force"));
}

/// The trace of a sample on machines/paper.yaml: its header and rows.
fn paper_trace(sample: &str) -> (Vec<String>, Vec<Vec<f64>>) {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("t.csv");
    let o = run(&[
        "trace",
        &path(sample),
        "-m",
        &path(PAPER),
        "-o",
        &csv.display().to_string(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    read_trace(&fs::read_to_string(&csv).unwrap())
}

#[test]
fn lissajous_at_low_speed_sums_to_the_suspended_weight() {
    // The paper's Fig. 4 (bottom): at 10 mm/s ΣQ_i is the weight of the suspended masses,
    // (6·0.02 + 0.5 + 3·0.25) kg · 9.81 m/s² = 13.44 N (eq. 17).
    let (header, rows) = paper_trace("samples/lissajous_10.gcode");
    let col = |name: &str| header.iter().position(|h| h == name).expect(name);
    let (f1, f2, f3, line, t) = (
        col("f1_n"),
        col("f2_n"),
        col("f3_n"),
        col("line"),
        col("t_s"),
    );
    let weight = (6.0 * 0.02 + 0.5 + 3.0 * 0.25) * 9.81;
    // The path: from line 7 on (after the travel to its start), at constant speed once the
    // nozzle has accelerated to 10 mm/s (within 1 ms at 20 m/s²) and until it brakes.
    let on = |r: &&Vec<f64>| r[line] >= 7.0;
    let start = rows.iter().find(on).map_or(0.0, |r| r[t]) + 0.005;
    let end = rows.iter().rev().find(on).map_or(0.0, |r| r[t]) - 0.005;
    let mut on_path = 0;
    for r in &rows {
        if r[line] < 7.0 || r[t] < start || r[t] > end {
            continue;
        }
        on_path += 1;
        let sum = r[f1] + r[f2] + r[f3];
        assert!(
            (sum - weight).abs() < 0.005 * weight,
            "t={} sum={sum}",
            r[0]
        );
    }
    assert!(on_path > 10_000, "{on_path} samples on the path");
}

#[test]
fn trace_power_equals_the_energy_rate() {
    // eq. 20, the paper's Fig. 5, checked against the energy computed here from the trace's
    // own columns and differentiated numerically: K = ½ m_c Σ q̇² + ½ m_p |v|²,
    // U = g (m_c Σ q + m_p z_P), with the paper's masses (paper.yaml).
    let (header, rows) = paper_trace("samples/lissajous_200.gcode");
    let col = |name: &str| header.iter().position(|h| h == name).expect(name);
    let (m_c, m_p, g) = (0.25 + 0.02, 0.5 + 3.0 * 0.02, 9.81);
    let energy = |r: &Vec<f64>| {
        let mm = 1e-3;
        let dq2: f64 = ["dq1_mm_s", "dq2_mm_s", "dq3_mm_s"]
            .iter()
            .map(|c| (r[col(c)] * mm).powi(2))
            .sum();
        let v2: f64 = ["vx_mm_s", "vy_mm_s", "vz_mm_s"]
            .iter()
            .map(|c| (r[col(c)] * mm).powi(2))
            .sum();
        let q: f64 = ["q1_mm", "q2_mm", "q3_mm"]
            .iter()
            .map(|c| r[col(c)] * mm)
            .sum();
        0.5 * m_c * dq2 + 0.5 * m_p * v2 + g * (m_c * q + m_p * r[col("z_mm")] * mm)
    };
    let (t, power, rate) = (col("t_s"), col("power_w"), col("energy_rate_w"));
    let scale = rows.iter().map(|r| r[power].abs()).fold(0.0, f64::max);
    for r in &rows {
        assert!(
            (r[power] - r[rate]).abs() <= 1e-9 * scale.max(1.0),
            "t={}",
            r[t]
        );
    }
    // The grid samples on the path (line 7 on), three in a row one period apart: the energy's
    // central difference against the power in the middle.
    let on_grid =
        |r: &&Vec<f64>| r[col("line")] >= 7.0 && ((r[t] * 1e3).round() - r[t] * 1e3).abs() < 1e-6;
    let mut grid: Vec<&Vec<f64>> = rows.iter().filter(on_grid).collect();
    grid.dedup_by(|a, b| (a[t] - b[t]).abs() < 1e-9);
    // Away from the phase boundaries: the path's first and last 20 ms accelerate from and
    // brake to rest.
    let (first, last) = (
        grid.first().map_or(0.0, |r| r[t]),
        grid.last().map_or(0.0, |r| r[t]),
    );
    grid.retain(|r| r[t] > first + 0.02 && r[t] < last - 0.02);
    let mut compared = 0;
    let mut worst: f64 = 0.0;
    for w in grid.windows(3) {
        let (a, b, c) = (w[0], w[1], w[2]);
        if ((c[t] - a[t]) - 2e-3).abs() > 1e-9 {
            continue;
        }
        let numeric = (energy(c) - energy(a)) / (c[t] - a[t]);
        worst = worst.max((numeric - b[power]).abs());
        compared += 1;
    }
    assert!(compared > 1000, "{compared}");
    assert!(worst < 0.02 * scale, "worst {worst} W of {scale} W");
}

#[test]
fn plot_writes_forces_and_bed_map() {
    let dir = tempfile::tempdir().unwrap();
    let o = run(&[
        "check",
        &path("samples/over-limit.gcode"),
        "-m",
        &path(KOSSEL),
        "--plot",
        &dir.path().display().to_string(),
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    for name in ["over-limit-forces.svg", "over-limit-bed.svg"] {
        let svg = fs::read_to_string(dir.path().join(name)).unwrap();
        assert!(
            svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"),
            "{name}"
        );
        assert!(!svg.contains("NaN"), "{name}");
    }
    // The forces plot is centred on the worst violation (line 12, tower B, at t = 4.101 s).
    let forces = fs::read_to_string(dir.path().join("over-limit-forces.svg")).unwrap();
    assert!(forces.contains("t = 4.101 s"), "title");
}
