//! G-code problems and pathological files through `check`: each problem is reported with
//! file:line:column (diagnostics, on stderr) or as a violation of its line (the report), is
//! counted, and gives the documented exit code: 2 for an input error, 1 for a move over a
//! limit, unreachable, above home or outside the print radius, else 0.

mod common;

use common::*;
use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::Output;
use std::time::{Duration, Instant};

const KOSSEL: &str = "machines/kossel.yaml";

/// Writes `gcode` to `t.gcode` in a new temporary directory.
fn file_with(gcode: &[u8]) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("t.gcode");
    fs::write(&f, gcode).unwrap();
    (dir, f)
}

fn check_path(f: &Path, machine: &Path, extra: &[&str]) -> Output {
    let mut args = vec![
        "check",
        f.to_str().unwrap(),
        "-m",
        machine.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    let o = run(&args);
    assert!(!stderr(&o).contains("panicked"), "{}", stderr(&o));
    o
}

/// `check` on `gcode`: exit code, stdout, stderr.
fn check(gcode: &[u8]) -> (Option<i32>, String, String) {
    let (_dir, f) = file_with(gcode);
    let o = check_path(&f, &repo(KOSSEL), &[]);
    (o.status.code(), stdout(&o), stderr(&o))
}

/// `check --format json` on `gcode`: exit code and the report, with every number finite.
fn check_json(gcode: &[u8]) -> (Option<i32>, serde_json::Value) {
    let (_dir, f) = file_with(gcode);
    let o = check_path(&f, &repo(KOSSEL), &["--format", "json"]);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("a JSON report");
    assert_finite(&v);
    (o.status.code(), v)
}

fn assert_finite(v: &serde_json::Value) {
    match v {
        serde_json::Value::Null => panic!("null (a NaN?) in the report"),
        serde_json::Value::Number(n) => assert!(n.as_f64().is_some_and(f64::is_finite)),
        serde_json::Value::Array(a) => a.iter().for_each(assert_finite),
        serde_json::Value::Object(o) => o.values().for_each(assert_finite),
        _ => {}
    }
}

/// The one violation of a report: its line, kind and message.
fn only_violation(v: &serde_json::Value) -> (u64, String, String) {
    let list = v["violations"].as_array().expect("violations");
    assert_eq!(list.len(), 1, "{v:#}");
    assert_eq!(v["summary"]["violations"], 1);
    let x = &list[0];
    (
        x["line"].as_u64().unwrap(),
        x["kind"].as_str().unwrap().to_string(),
        x["message"].as_str().unwrap().to_string(),
    )
}

// ---- Problems in the G-code -------------------------------------------------------------

#[test]
fn malformed_number_in_a_motion_command() {
    let (code, out, err) = check(b"G28\nG1 Z10 F3000\nG1 X1.2.3 Y4\n");
    assert_eq!(code, Some(2), "{err}");
    assert!(
        err.contains("t.gcode:3:5: error: malformed number: expected digits"),
        "{err}"
    );
    assert!(out.contains("t.gcode: ERROR, 1 input errors"), "{out}");
    assert!(out.contains("0 warnings, 1 errors"), "{out}");
    // Out of range is its own message.
    let (code, _, err) = check(format!("G28\nG1 X1{}\n", "0".repeat(300)).as_bytes());
    assert_eq!(code, Some(2), "{err}");
    assert!(
        err.contains("t.gcode:2:5: error: number out of range: at most 1e9"),
        "{err}"
    );
}

#[test]
fn arc_whose_start_and_end_radii_disagree() {
    // Centre (13, 0) from I3: start radius 3, the end (20, 0) is 7 from it. Klipper runs it
    // without a word: the chords follow the start radius, the last one goes to the end.
    let gcode = b"G28\nG1 X10 Y0 Z10 F3000\nG2 X20 Y0 I3 J0\n";
    let (code, _, err) = check(gcode);
    assert!(!err.contains("warning"), "{err}");
    assert_eq!(code, Some(0), "{err}");
}

#[test]
fn pose_out_of_reach() {
    // x = 150: 240.9 mm from tower A (at 210°, 105 mm), the arm is 215 mm. The move also
    // leaves the print disc; the more severe problem is the one reported.
    let (code, v) = check_json(b"G28\nG1 Z10 F3000\nG1 X150 Y0\n");
    assert_eq!(code, Some(1));
    let (line, kind, message) = only_violation(&v);
    assert_eq!((line, kind.as_str()), (3, "unreachable"));
    assert!(message.starts_with("UNREACHABLE at X"), "{message}");
    assert!(message.contains("tower A: arm too short"), "{message}");
    assert_eq!(v["summary"]["unreachable"], 1);
    assert_eq!(v["violations"][0]["tower"], 1);
    let (_, out, _) = check(b"G28\nG1 Z10 F3000\nG1 X150 Y0\n");
    assert!(out.contains("FAIL, 1 of 2 moves"), "{out}");
    assert!(out.contains("UNREACHABLE"), "{out}");
}

#[test]
fn carriage_above_its_home() {
    let (code, v) = check_json(b"G28\nG1 X0 Y0 Z300 F3000\n");
    assert_eq!(code, Some(1));
    let (line, kind, message) = only_violation(&v);
    assert_eq!((line, kind.as_str()), (2, "above_home"));
    assert!(
        message.starts_with("ABOVE HOME tower A: carriage"),
        "{message}"
    );
    assert_eq!(v["summary"]["unreachable"], 0);
}

#[test]
fn move_outside_the_print_radius() {
    let (code, v) = check_json(b"G28\nG1 Z10 F3000\nG1 X80 Y60\n");
    assert_eq!(code, Some(1));
    let (line, kind, message) = only_violation(&v);
    assert_eq!((line, kind.as_str()), (3, "outside_radius"));
    assert_eq!(message, "OUTSIDE print radius: 100.00 mm > 85.00 mm");
    // Within the slicer's rounding (1 µm) it is not flagged.
    let (code, v) = check_json(b"G28\nG1 Z10 F3000\nG1 X85.0009 Y0\n");
    assert_eq!(code, Some(0), "{v:#}");
}

#[test]
fn zero_or_negative_feed() {
    let (code, out, err) = check(b"G28\nG1 Z10 F0\nG1 X10 F-100\nG1 X20\n");
    assert_eq!(code, Some(2), "{err}");
    // One line for both, with its count and lines.
    assert!(
        err.contains("t.gcode:2:8: error: F must be a positive speed")
            && err.contains("[2 times: lines 2, 3; --verbose lists each]"),
        "{err}"
    );
    // The moves still run at the previous feed (25 mm/s) and are counted.
    assert!(out.contains("3 moves"), "{out}");
    assert!(out.contains("0 warnings, 2 errors"), "{out}");
}

#[test]
fn m204_with_a_non_positive_value() {
    let (code, _, err) = check(b"G28\nM204 S0\nM204 S-5\nM204 P0 T100\nM204 P100 T-1\n");
    assert_eq!(code, Some(2), "{err}");
    for expected in [
        "t.gcode:2:6: error: M204 S must be positive [2 times: lines 2, 3;",
        "t.gcode:4:6: error: M204 P must be positive",
        "t.gcode:5:11: error: M204 T must be positive",
    ] {
        assert!(err.contains(expected), "{expected:?} not in {err}");
    }
    let (_, v) = check_json(b"G28\nM204 S0\nG1 Z10 F3000\n");
    assert_eq!(v["summary"]["errors"], 1);
}

/// kossel.yaml with arms 0.01 mm longer than delta_radius + print_radius: at the edge of
/// the disc opposite a tower that tower's arms are almost flat (1.95 mm rise over 190 mm).
fn flat_arm_machine(dir: &Path) -> PathBuf {
    let text = fs::read_to_string(repo(KOSSEL)).unwrap();
    let p = dir.join("flat.yaml");
    fs::write(
        &p,
        text.replacen("arm_length_mm: 215.0", "arm_length_mm: 190.01", 1),
    )
    .unwrap();
    p
}

#[test]
fn near_singular_pose() {
    // (73.61, 42.5) is 85 mm from the centre, opposite tower A: 190 mm from it, so tower
    // A's arms rise 1.95 mm over 190 mm (0.6° from flat). Jq_A = q_A − z_P → 0: the
    // inverse-kinematic singularity, where the carriage outruns the nozzle.
    let dir = tempfile::tempdir().unwrap();
    let machine = flat_arm_machine(dir.path());
    let m = machine.to_str().unwrap();
    let pose = |extra: &[&str]| -> serde_json::Value {
        let mut args = vec![
            "pose",
            "--machine",
            m,
            "--format",
            "json",
            "73.61",
            "42.5",
            "10",
        ];
        args.extend_from_slice(extra);
        let o = run(&args);
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
        serde_json::from_slice(&o.stdout).unwrap()
    };
    let rest = pose(&[]);
    let rise_a = rest["q_mm"][0].as_f64().unwrap() - 10.0;
    assert!(rise_a > 0.0 && rise_a < 2.2, "{rest}");
    // Jx (arm directions) stays well conditioned: its condition number does not see this
    // singularity, so a warning must look at Jq (the arm's rise), not at jx_condition.
    assert!(rest["jx_condition"].as_f64().unwrap() < 5.0, "{rest}");
    // At 11.5 mm/s towards the tower the carriage runs at ~1000 mm/s and needs ~114 N.
    let moving = pose(&["--velocity", "10,5.77,0"]);
    let dq_a = moving["dq_mm_s"][0].as_f64().unwrap();
    assert!(dq_a.abs() > 80.0 * 11.5, "{moving}");
    assert!(
        moving["force_n"][0].as_f64().unwrap().abs() > 100.0,
        "{moving}"
    );
    // `check` of a slow move into that pose: finite, and a near-singular warning at its
    // line (tower A's carriage at ~97× the nozzle speed), exit 0 as the force stays under
    // the limit while the nozzle decelerates into the pose.
    let f = dir.path().join("t.gcode");
    fs::write(&f, b"G28\nG1 Z10 F3000\nG1 X73.61 Y42.5 F600\n").unwrap();
    let o = check_path(&f, &machine, &["--format", "json"]);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_finite(&v);
    assert!(matches!(o.status.code(), Some(0 | 1)), "{}", stderr(&o));
    assert_eq!(v["summary"]["peak_line"][0], 3);
    assert_eq!(v["summary"]["warnings"], 1, "{v:#}");
    let d = &v["diagnostics"][0];
    assert_eq!(d["line"], 3);
    let msg = d["message"].as_str().unwrap_or_default();
    assert!(
        msg.starts_with("near-singular pose: tower A arm 0."),
        "{msg}"
    );
    assert!(msg.contains("× the nozzle speed"), "{msg}");
    // The same path on the shipped profile stays far from flat: no warning.
    let o = check_path(&f, &repo(KOSSEL), &["--format", "json"]);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["summary"]["warnings"], 0, "{v:#}");
}

// ---- Pathological files -------------------------------------------------------------------

#[test]
fn empty_file() {
    // Nothing to check is an input error: a gate must not pass a file it did not check.
    let (code, out, err) = check(b"");
    assert_eq!(code, Some(2), "{err}");
    assert!(out.is_empty(), "{out}");
    assert!(
        err.contains("t.gcode is empty: there is no G-code to check"),
        "{err}"
    );
}

#[test]
fn comments_only() {
    let (code, out, err) = check(b"; generated by nothing\n(a paren comment)\n;\r\n\n");
    assert_eq!(code, Some(2), "{err}");
    assert!(out.is_empty(), "{out}");
    assert!(
        err.contains("t.gcode has no motion: none of its 4 lines moves the nozzle"),
        "{err}"
    );
    // Settings and homing without a move are no motion either; errors are counted.
    let (code, _, err) = check(b"G28\nM204 S3000\nG1 X1.2.3\n");
    assert_eq!(code, Some(2), "{err}");
    assert!(
        err.contains("none of its 3 lines moves the nozzle (1 line with an error was skipped)"),
        "{err}"
    );
}

#[test]
fn one_50_mb_line_without_a_newline() {
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("long.gcode");
    {
        let mut w = std::io::BufWriter::new(fs::File::create(&f).unwrap());
        w.write_all(b"G28\nG1 Z10 F3000\nG1 X1").unwrap();
        let piece = b" X1 Y2 Z3 E4 ; some text";
        for _ in 0..(50 << 20) / piece.len() {
            w.write_all(piece).unwrap();
        }
    }
    let start = Instant::now();
    let o = check_path(&f, &repo(KOSSEL), &[]);
    let took = start.elapsed();
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("long.gcode:3:131073: warning: line longer than 128 KiB"),
        "{}",
        stderr(&o)
    );
    assert!(
        stdout(&o).contains("1 moves, ") && stdout(&o).contains(" samples, 3 lines"),
        "{}",
        stdout(&o)
    );
    // Annotated, it comes back byte for byte with the summary after it.
    let out = dir.path().join("out.gcode");
    let a = run(&[
        "annotate",
        f.to_str().unwrap(),
        "-m",
        repo(KOSSEL).to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(a.status.code(), Some(0), "{}", stderr(&a));
    let original = fs::read(&f).unwrap();
    let annotated = fs::read(&out).unwrap();
    let mut back = Vec::new();
    delta_gcode::emit::strip(&annotated[..], &mut back).unwrap();
    assert!(
        back == original,
        "stripping the annotations gives the input back"
    );
    assert!(annotated.starts_with(&original));
    eprintln!("50 MB line: check {took:?}");
}

/// Deterministic junk (xorshift), no file in the repository.
fn junk(n: usize, mut seed: u64) -> Vec<u8> {
    (0..n)
        .map(|_| {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 24) as u8
        })
        .collect()
}

#[test]
fn binary_junk() {
    // Not text: an input error that says so, never a pass.
    for seed in [1, 2, 3] {
        let (code, out, err) = check(&junk(256 << 10, seed));
        assert_eq!(code, Some(2), "{err}");
        assert!(out.is_empty(), "{out}");
        assert!(err.contains("t.gcode is binary data, not G-code"), "{err}");
    }
    // Junk text (its control characters made printable) with G-code letters in it gets to
    // the interpreter and the planner.
    let mut mixed = Vec::new();
    for (i, chunk) in junk(64 << 10, 9).chunks(7).enumerate() {
        mixed.extend_from_slice(format!("G1 X{} Y{} Z{} ", i % 50, i % 30, 5 + i % 7).as_bytes());
        mixed.extend(
            chunk
                .iter()
                .map(|&b| if b < 0x20 || b == 0x7f { b'?' } else { b }),
        );
        mixed.push(b'\n');
    }
    let (code, v) = check_json(&mixed);
    assert!(matches!(code, Some(0..=2)), "{code:?}");
    assert!(v["summary"]["moves"].as_u64().unwrap() > 100, "{v:#}");
}

#[test]
fn zero_length_moves() {
    let gcode = b"G28\nG1 Z10 F3000\nG1 Z10\nG1 X0 Y0 Z10\nG0 X0\nG1 E0\nG91\nG1 X0 Y0 Z0\nG2 X0 Y0 I0 J0\n";
    let (code, out, err) = check(gcode);
    // The last line is an error (an arc without a centre offset, and in relative mode);
    // the others move nothing and are dropped, as Klipper drops them.
    assert!(
        err.contains("t.gcode:9:1: error: G2/G3 does not support relative move mode"),
        "{err}"
    );
    assert_eq!(code, Some(2));
    assert!(out.contains("1 moves"), "{out}");
    let (code, out, _) = check(&gcode[..gcode.len() - 16]);
    assert_eq!(code, Some(0), "{out}");
    assert!(out.contains("OK, all 1 moves"), "{out}");
}

#[test]
fn a_million_tiny_segments() {
    // A spiral of 1 000 000 segments of 0.02 mm at 50 mm/s: 20 m, 400 s of printing.
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("tiny.gcode");
    {
        let mut w = std::io::BufWriter::new(fs::File::create(&f).unwrap());
        writeln!(w, "G28\nG1 Z5 F3000\nG1 X20 Y0").unwrap();
        let (mut angle, mut e) = (0.0f64, 0.0f64);
        for i in 0..1_000_000u32 {
            let r = 20.0 + 40.0 * f64::from(i) / 1e6;
            angle += 0.02 / r;
            e += 0.001;
            writeln!(
                w,
                "G1 X{:.4} Y{:.4} E{e:.3}",
                r * angle.cos(),
                r * angle.sin()
            )
            .unwrap();
        }
    }
    let start = Instant::now();
    let o = check_path(&f, &repo(KOSSEL), &["--format", "json"]);
    let took = start.elapsed();
    assert!(matches!(o.status.code(), Some(0 | 1)), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_finite(&v);
    assert_eq!(v["summary"]["moves"], 1_000_002);
    assert_eq!(v["summary"]["errors"], 0);
    eprintln!("a million segments: check {took:?}");
    assert!(took < Duration::from_secs(60), "{took:?}");
}

#[test]
fn huge_coordinates() {
    // 1e300 written out: a clean error at its column, nothing planned from it.
    let (code, out, err) =
        check(format!("G28\nG1 Z10 F3000\nG1 X1{} Y0\n", "0".repeat(300)).as_bytes());
    assert_eq!(code, Some(2), "{err}");
    assert!(
        err.contains("t.gcode:3:5: error: number out of range"),
        "{err}"
    );
    assert!(out.contains("1 moves"), "{out}");
    // `1e300` is X1 then E300 (no exponents in G-code), with a warning.
    let (code, v) = check_json(b"G28\nG1 Z10 F3000\nG1 X1e300\n");
    assert_eq!(v["summary"]["warnings"], 1);
    assert!(matches!(code, Some(0 | 1)));
    // Far out of reach (100 m up): a violation, no NaN.
    let start = Instant::now();
    let (code, v) = check_json(b"G28\nG1 Z10 F3000\nG1 X0 Y100000 Z100000 F18000\n");
    assert_eq!(code, Some(1));
    let (line, kind, _) = only_violation(&v);
    assert_eq!((line, kind.as_str()), (3, "unreachable"), "{v:#}");
    eprintln!("huge coordinates: check {:?}", start.elapsed());
}

// ---- Moves too long to sample: checked at their ends, reported, never a hang ------------

/// Runs `check` on `gcode` and asserts it finishes within `limit` with exit code `code`.
fn finishes_within(gcode: &[u8], limit: Duration, code: i32) {
    let (_dir, f) = file_with(gcode);
    let mut child = bin()
        .args(["check", f.to_str().unwrap(), "-m"])
        .arg(repo(KOSSEL))
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while start.elapsed() < limit {
        if let Some(status) = child.try_wait().unwrap() {
            assert_eq!(status.code(), Some(code), "{status}");
            return;
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    panic!("check did not finish within {limit:?}");
}

#[test]
fn a_move_of_a_billion_mm_finishes() {
    finishes_within(
        b"G28\nG1 Z10 F18000\nG1 X999999999\n",
        Duration::from_secs(10),
        1, // unreachable
    );
}

#[test]
fn a_very_slow_feed_finishes() {
    // Not sampled: a violation.
    finishes_within(
        b"G28\nG1 Z10 F0.001\nG1 X50 Y50\n",
        Duration::from_secs(10),
        1,
    );
}

#[test]
fn an_arc_of_a_billion_turns_finishes() {
    finishes_within(
        b"G28\nG1 Z10 X10 F3000\nG2 X10 Y0 I-5 J0 P999999999\n",
        Duration::from_secs(10),
        0, // Klipper ignores P (with a warning): one turn
    );
}

#[test]
fn a_move_too_long_to_sample_is_a_violation() {
    // 50·√2 mm at 0.001 mm/min lasts 4.2e6 s: checked at its ends, flagged, exit 1.
    let (code, v) = check_json(b"G28\nG1 Z10 F3000\nG1 X50 Y50 F0.001\n");
    assert_eq!(code, Some(1), "{v:#}");
    let (line, kind, _) = only_violation(&v);
    assert_eq!((line, kind.as_str()), (3, "not_sampled"), "{v:#}");
}

#[test]
fn below_the_bed_is_a_violation() {
    let (code, v) = check_json(b"G28\nG1 Z10 F3000\nG1 Z-5\n");
    assert_eq!(code, Some(1), "{v:#}");
    let (line, kind, _) = only_violation(&v);
    assert_eq!((line, kind.as_str()), (3, "below_bed"), "{v:#}");
}
