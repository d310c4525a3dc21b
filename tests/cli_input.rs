//! What the command line takes in and gives out (issue 16): input that is not G-code is an
//! input error that says what it is; `-` is standard input; a closed pipe is no panic;
//! created files follow the umask; `-m` everywhere; diagnostics grouped by kind and worded
//! for the profile's firmware; the hook's verdict first on stderr.

mod common;

use common::*;
use std::fs;
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Output, Stdio};

const KOSSEL: &str = "machines/kossel.yaml";
const OVER: &str = "samples/over-limit.gcode";

fn kossel() -> String {
    repo(KOSSEL).to_string_lossy().into_owned()
}

/// `bytes` in `dir/name`.
fn file_in(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let f = dir.join(name);
    fs::write(&f, bytes).unwrap();
    f
}

/// Runs delta-gcode with `args` and `input` on standard input.
fn run_with_stdin(args: &[&str], input: &[u8]) -> Output {
    let mut child = bin()
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut stdin = child.stdin.take().unwrap();
    let input = input.to_vec();
    let feeder = std::thread::spawn(move || {
        let _ = stdin.write_all(&input);
    });
    let out = child.wait_with_output().unwrap();
    feeder.join().unwrap();
    out
}

/// `command f -m kossel.yaml extra…`.
fn on_kossel(command: &str, f: &Path, extra: &[&str]) -> Output {
    let k = kossel();
    let mut args = vec![command, f.to_str().unwrap(), "-m", &k];
    args.extend_from_slice(extra);
    let o = run(&args);
    assert!(!stderr(&o).contains("panicked"), "{}", stderr(&o));
    o
}

/// `check f -m kossel.yaml extra…`.
fn check_with(f: &Path, extra: &[&str]) -> Output {
    on_kossel("check", f, extra)
}

fn check_file(f: &Path) -> Output {
    check_with(f, &[])
}

/// `check f -m kossel.yaml --format json`: the report.
fn check_json(f: &Path) -> serde_json::Value {
    serde_json::from_slice(&check_with(f, &["--format", "json"]).stdout).unwrap()
}

// ---- 1. Input that is not G-code ----------------------------------------------------------

fn gzip_of(bytes: &[u8]) -> Vec<u8> {
    // A stored (uncompressed) deflate block is still gzip: the magic is what counts.
    let mut v = vec![0x1f, 0x8b, 8, 0, 0, 0, 0, 0, 0, 3];
    v.extend_from_slice(&[1, bytes.len() as u8, 0, !(bytes.len() as u8), 0xff]);
    v.extend_from_slice(bytes);
    v.extend_from_slice(&[0; 8]);
    v
}

fn binary_stl(triangles: u32) -> Vec<u8> {
    let mut v = b"solid made by a CAD program".to_vec();
    v.resize(80, b' ');
    v.extend_from_slice(&triangles.to_le_bytes());
    for i in 0..triangles {
        for k in 0..12 {
            v.extend_from_slice(&((i * 12 + k) as f32).to_le_bytes());
        }
        v.extend_from_slice(&[0, 0]);
    }
    v
}

#[test]
fn input_that_is_not_gcode_is_an_input_error_saying_what_it_is() {
    let dir = tempfile::tempdir().unwrap();
    let cases: Vec<(&str, Vec<u8>, &str)> = vec![
        (
            "a.gcode.gz",
            gzip_of(b"G1 X1\n"),
            "is gzip-compressed, not G-code: decompress it first: `gunzip -k",
        ),
        (
            "a.gcode.xz",
            b"\xfd7zXZ\x00\x00\x04\xe6\xd6\xb4\x46".to_vec(),
            "is xz-compressed, not G-code: decompress it first: `xz -dk",
        ),
        (
            "a.zip",
            b"PK\x03\x04\x14\x00\x00\x00\x00\x00a.gcode".to_vec(),
            "is a zip archive, not G-code: extract the G-code first",
        ),
        (
            "a.3mf",
            b"PK\x03\x04\x14\x00\x00\x00\x08\x00[Content_Types].xml3D/3dmodel.model".to_vec(),
            "is a 3MF project (a 3D model), not G-code: slice it first",
        ),
        (
            "cube.stl",
            b"solid cube\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n".to_vec(),
            "is an STL model (ASCII), not G-code: slice it first",
        ),
        (
            "cube_bin.stl",
            binary_stl(12),
            "is an STL model (binary), not G-code: slice it first",
        ),
        (
            "a.bgcode",
            b"GCDE\x01\x00\x00\x00\x01\x00\x00\x00".to_vec(),
            "is PrusaSlicer binary G-code (.bgcode), not G-code",
        ),
        (
            "a.bin",
            (0..4096u32).map(|i| (i * 7919 % 251) as u8).collect(),
            "is binary data, not G-code",
        ),
    ];
    for (name, bytes, says) in cases {
        let f = file_in(dir.path(), name, &bytes);
        let o = check_file(&f);
        assert_eq!(o.status.code(), Some(2), "{name}: {}", stderr(&o));
        assert!(stdout(&o).is_empty(), "{name}: {}", stdout(&o));
        assert!(
            stderr(&o).contains(&format!("{name} {says}")),
            "{name}: {}",
            stderr(&o)
        );
    }
    // Binary G-code: how to turn it off in PrusaSlicer.
    let f = file_in(dir.path(), "b.bgcode", b"GCDE\x01\x00\x00\x00");
    let err = stderr(&check_file(&f));
    assert!(err.contains("\"Supports binary G-code\""), "{err}");
    // Each refused file is an input error of its own; the others are still checked.
    let good = repo(OVER);
    let o = run(&[
        "check",
        f.to_str().unwrap(),
        good.to_str().unwrap(),
        "-m",
        &kossel(),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stdout(&o).contains("over-limit.gcode: FAIL"),
        "{}",
        stdout(&o)
    );
}

#[test]
fn annotate_and_trace_refuse_it_too_and_write_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let f = file_in(dir.path(), "cube.stl", &binary_stl(4));
    let out = dir.path().join("out.gcode");
    let k = kossel();
    for args in [
        vec!["annotate", "-o", out.to_str().unwrap()],
        vec!["annotate", "--in-place", "--strict"],
        vec!["trace", "-o", out.to_str().unwrap()],
    ] {
        let mut all = args.clone();
        all.extend([f.to_str().unwrap(), "-m", &k]);
        let o = run(&all);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(
            stderr(&o).contains("is an STL model (binary)"),
            "{}",
            stderr(&o)
        );
        assert!(!out.exists(), "{args:?}");
    }
    assert_eq!(fs::read(&f).unwrap(), binary_stl(4));
    // A file without motion: no trace file.
    let comments = file_in(dir.path(), "c.gcode", b"; nothing\nM104 S200\n");
    let o = on_kossel("trace", &comments, &["-o", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("c.gcode has no motion"),
        "{}",
        stderr(&o)
    );
    assert!(!out.exists());
}

// ---- 4. Standard input, closed pipes, -m, file modes --------------------------------------

#[test]
fn dash_reads_standard_input() {
    let gcode = fs::read(repo(OVER)).unwrap();
    let file = check_file(&repo(OVER));
    let piped = run_with_stdin(&["check", "-", "-m", &kossel()], &gcode);
    assert_eq!(piped.status.code(), file.status.code());
    assert_eq!(piped.status.code(), Some(1));
    let name = repo(OVER).to_string_lossy().into_owned();
    assert_eq!(stdout(&piped), stdout(&file).replace(&name, "<stdin>"));
    // Decompressing into a pipe is the way to check a compressed file.
    let o = run_with_stdin(&["check", "-", "-m", &kossel()], &gzip_of(b"G1 X1\n"));
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("<stdin> is gzip-compressed"),
        "{}",
        stderr(&o)
    );
    // annotate - -o OUT, and -o - (standard output).
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("a.gcode");
    let o = run_with_stdin(
        &[
            "annotate",
            "-",
            "-m",
            &kossel(),
            "-o",
            out.to_str().unwrap(),
        ],
        &gcode,
    );
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let annotated = fs::read(&out).unwrap();
    assert_eq!(strip_ours(&annotated), gcode);
    let o = run_with_stdin(&["annotate", "-", "-m", &kossel(), "-o", "-"], &gcode);
    assert_eq!(o.stdout, annotated);
    // trace - -o -.
    let o = run_with_stdin(&["trace", "-", "-m", &kossel(), "-o", "-"], &gcode);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let (header, rows) = read_trace(&stdout(&o));
    assert_eq!(header[0], "t_s");
    assert!(rows.len() > 100);
    // A pipe named as a file (bash's process substitution) is read once, like `-`.
    if let Ok(o) = std::process::Command::new("bash")
        .arg("-c")
        .arg("\"$0\" check <(cat \"$1\") -m \"$2\"")
        .arg(env!("CARGO_BIN_EXE_delta-gcode"))
        .arg(repo(OVER))
        .arg(repo(KOSSEL))
        .output()
    {
        assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
        assert!(
            stdout(&o).contains(": FAIL, 5 of 12 moves"),
            "{}",
            stdout(&o)
        );
    }
    // `-` twice, or --in-place on standard input: usage errors.
    let o = run_with_stdin(&["check", "-", "-", "-m", &kossel()], &gcode);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("can be given only once"),
        "{}",
        stderr(&o)
    );
    let o = run_with_stdin(&["annotate", "-", "-m", &kossel(), "--in-place"], &gcode);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("--in-place needs a file"),
        "{}",
        stderr(&o)
    );
}

/// Runs delta-gcode with its standard output a pipe closed before it writes.
fn run_into_closed_pipe(args: &[&str]) -> Output {
    let mut child = bin()
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let mut err = String::new();
    child
        .stderr
        .take()
        .unwrap()
        .read_to_string(&mut err)
        .unwrap();
    let status = child.wait().unwrap();
    Output {
        status,
        stdout: Vec::new(),
        stderr: err.into_bytes(),
    }
}

#[test]
fn a_closed_pipe_is_no_panic_and_keeps_the_verdict() {
    let over = repo(OVER);
    let over = over.to_str().unwrap();
    for (args, code) in [
        (vec!["check", over, "-m", &kossel()], 1),
        (vec!["check", over, "-m", &kossel(), "--format", "json"], 1),
        (vec!["trace", over, "-m", &kossel(), "-o", "-"], 0),
        (vec!["annotate", over, "-m", &kossel(), "-o", "-"], 0),
        (vec!["machine", &kossel()], 0),
        (vec!["pose", "-m", &kossel(), "0", "0", "10"], 0),
    ] {
        let o = run_into_closed_pipe(&args);
        assert!(!stderr(&o).contains("panicked"), "{args:?}: {}", stderr(&o));
        assert_eq!(o.status.code(), Some(code), "{args:?}: {}", stderr(&o));
    }
}

#[test]
fn dash_m_is_taken_everywhere() {
    let o = run(&["pose", "-m", &kossel(), "0", "0", "10", "--format", "json"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(v["q_mm"][0].as_f64().is_some());
    let o = run(&["pose", "0", "0", "10", "-m", &kossel()]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
}

#[cfg(unix)]
#[test]
fn created_files_follow_the_umask_and_replaced_ones_keep_their_mode() {
    use std::os::unix::fs::PermissionsExt;
    let dir = tempfile::tempdir().unwrap();
    let over = repo(OVER);
    let mode = |p: &Path| fs::metadata(p).unwrap().permissions().mode() & 0o777;
    for (umask, want) in [("022", 0o644), ("027", 0o640), ("077", 0o600)] {
        let out = dir.path().join(format!("a{umask}.gcode"));
        let report = dir.path().join(format!("r{umask}.json"));
        let trace = dir.path().join(format!("t{umask}.csv"));
        let script = format!(
            "umask {umask} && \"$0\" annotate \"$1\" -m \"$2\" -o \"$3\" --report \"$4\" && \"$0\" trace \"$1\" -m \"$2\" -o \"$5\" --to-line 5"
        );
        let o = std::process::Command::new("sh")
            .arg("-c")
            .arg(script)
            .arg(env!("CARGO_BIN_EXE_delta-gcode"))
            .args([&over, &repo(KOSSEL), &out, &report, &trace])
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", stderr(&o));
        for p in [&out, &report, &trace] {
            assert_eq!(mode(p), want, "umask {umask}: {}", p.display());
        }
    }
    // In place: the original's mode stays.
    let f = dir.path().join("keep.gcode");
    fs::copy(&over, &f).unwrap();
    fs::set_permissions(&f, fs::Permissions::from_mode(0o604)).unwrap();
    let o = on_kossel("annotate", &f, &["--in-place"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(mode(&f), 0o604);
}

// ---- 2. Diagnostics grouped, worded for the firmware ---------------------------------------

fn marlin_profile(dir: &Path) -> PathBuf {
    let text = fs::read_to_string(repo(KOSSEL)).unwrap();
    file_in(
        dir,
        "marlin.yaml",
        format!("{text}\nfirmware: marlin\n").as_bytes(),
    )
}

#[test]
fn diagnostics_are_one_line_per_kind_and_verbose_lists_each() {
    let dir = tempfile::tempdir().unwrap();
    let mut g = String::from("G28\nG1 Z10 F3000\n");
    for i in 0..30 {
        g += &format!("M204 P{}\nG1 X{} Y1\n", 1000 + i, i % 5);
    }
    let f = file_in(dir.path(), "p.gcode", g.as_bytes());
    let o = check_file(&f);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let err = stderr(&o);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.ends_with("p.gcode:3:1: warning: M204 with only P or only T is ignored (Klipper needs S, or both P and T) [30 times: lines 3, 5, 7, 9, 11, …; --verbose lists each]\n"),
        "{err}"
    );
    assert!(
        stdout(&o).contains("30 warnings, 0 errors"),
        "{}",
        stdout(&o)
    );
    let o = check_with(&f, &["--verbose"]);
    assert_eq!(stderr(&o).lines().count(), 30, "{}", stderr(&o));
    // JSON: the kinds with their counts and first lines.
    let v = check_json(&f);
    let kinds = v["diagnostic_kinds"].as_array().unwrap();
    assert_eq!(kinds.len(), 1);
    assert_eq!(kinds[0]["count"], 30);
    assert_eq!(kinds[0]["severity"], "warning");
    assert_eq!(kinds[0]["lines"], serde_json::json!([3, 5, 7, 9, 11]));
    // Marlin honours M204 P: a Marlin profile gets no warning.
    let marlin = marlin_profile(dir.path());
    let o = run(&["check", f.to_str().unwrap(), "-m", marlin.to_str().unwrap()]);
    assert!(!stderr(&o).contains("M204"), "{}", stderr(&o));
    assert!(!stdout(&o).contains("warnings"), "{}", stdout(&o));
}

#[test]
fn object_labels_and_extended_commands_raise_nothing() {
    let f = repo("tests/fixtures/ps29_arcs_exclude.gcode");
    let o = check_file(&f);
    assert!(stderr(&o).is_empty(), "{}", stderr(&o));
    let dir = tempfile::tempdir().unwrap();
    let f = file_in(
        dir.path(),
        "labels.gcode",
        b"G28\nM486 T1\nM486 S0\nM486 Acylinder_d40.stl\nM117 Printing X1 D5 _\nEXCLUDE_OBJECT_START NAME=cylinder_d40.stl_id_0_copy_0\nG1 Z10 F3000\nEXCLUDE_OBJECT_END NAME=cylinder_d40.stl_id_0_copy_0\nM486 S-1\n",
    );
    let o = check_file(&f);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(stderr(&o).is_empty(), "{}", stderr(&o));
}

// ---- 3. The hook's verdict on stderr -------------------------------------------------------

#[test]
fn the_hook_says_its_verdict_first_on_stderr() {
    let dir = tempfile::tempdir().unwrap();
    let mut g = fs::read_to_string(repo(OVER)).unwrap();
    g = format!("M204 P1000\n{g}");
    let f = file_in(dir.path(), "over.gcode", g.as_bytes());
    let o = on_kossel("annotate", &f, &["--in-place", "--strict"]);
    assert_eq!(o.status.code(), Some(1));
    let err = stderr(&o);
    let first = err.lines().next().unwrap_or_default();
    assert!(
        first.starts_with("delta-gcode: FAIL: ")
            && first.contains("over.gcode: 5 of 12 moves exceed the limits of Kossel Mini; worst: line 13 `G0 X-70 Y40`: OVER force: tower B"),
        "{err}"
    );
    // The grouped diagnostics come after it.
    assert!(
        err.lines().nth(1).unwrap_or_default().contains("M204"),
        "{err}"
    );
    assert!(stdout(&o).is_empty(), "{}", stdout(&o));
    // A pass with findings: one line on stderr.
    let pass = file_in(
        dir.path(),
        "pass.gcode",
        b"G28\nM204 P100\nG1 Z10 X5 F3000\n",
    );
    let o = on_kossel("annotate", &pass, &["--in-place"]);
    assert_eq!(o.status.code(), Some(0));
    let err = stderr(&o);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.starts_with("delta-gcode: OK: ")
            && err.contains(
                "pass.gcode: all 1 moves within the limits of Kossel Mini (motor use at most "
            )
            && err.contains("%); 1 warnings (1 kind), first at line 2: M204 with only P"),
        "{err}"
    );
}

// ---- 5. Unreachable moves have no forces; a file for another printer ----------------------

#[test]
fn a_file_for_a_cartesian_bed_is_told_and_reports_no_unreachable_forces() {
    let dir = tempfile::tempdir().unwrap();
    // A part in the middle of a 220 mm Cartesian bed: moves around (110, 110).
    let mut g = String::from("G28\nG1 Z0.3 F6000\n");
    for i in 0..40 {
        let (x, y) = (
            90.0 + f64::from(i % 5) * 10.0,
            90.0 + f64::from(i / 5) * 5.0,
        );
        g += &format!("G1 X{x:.1} Y{y:.1} E{:.2} F3000\n", f64::from(i) * 0.1);
    }
    let f = file_in(dir.path(), "cartesian.gcode", g.as_bytes());
    let o = check_file(&f);
    assert_eq!(o.status.code(), Some(1));
    let out = stdout(&o);
    assert!(
        out.contains("note: the file seems sliced for another printer: 40 of its 41 moves end outside the print radius of 85 mm around X0 Y0; they span X 0.0 to 130.0 mm, Y 0.0 to 125.0 mm"),
        "{out}"
    );
    let v = check_json(&f);
    assert_eq!(v["notes"].as_array().map(Vec::len), Some(1));
    let violations = v["violations"].as_array().unwrap();
    assert!(violations.len() >= 40);
    for x in violations {
        assert_eq!(x["kind"], "unreachable", "{x}");
        assert!(x.get("peak_force_n").is_none(), "{x}");
    }
    // The peaks are those of the reachable moves: a few newtons, not thousands.
    for p in v["summary"]["peak_force_n"].as_array().unwrap() {
        assert!(p.as_f64().unwrap() < 30.0, "{v:#}");
    }
    assert_eq!(
        v["summary"]["warnings"], 0,
        "no near-singular warnings: {v:#}"
    );
}

// ---- 6. The trace's precision and windows ---------------------------------------------------

/// `trace samples/over-limit.gcode -o -` with `window` options: exit code and CSV.
fn trace_over(window: &[&str]) -> (Option<i32>, String) {
    let over = repo(OVER);
    let mut args = vec!["trace", over.to_str().unwrap(), "-m", KOSSEL, "-o", "-"];
    args.extend_from_slice(window);
    let o = bin()
        .args(&args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    (o.status.code(), stdout(&o))
}

#[test]
fn trace_figures_have_their_precision_and_windows_select() {
    let (code, text) = trace_over(&[]);
    assert_eq!(code, Some(0));
    let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
    let decimals = |name: &str| match name {
        "t_s" => 6,
        "line" => 0,
        n if n.ends_with("_mm_s2") => 1,
        n if n.ends_with("_n") => 4,
        _ => 3,
    };
    for row in text.lines().skip(1) {
        for (value, name) in row.split(',').zip(&header) {
            let places = value.split_once('.').map_or(0, |(_, d)| d.len());
            assert_eq!(places, decimals(name), "{name} = {value}");
            let zero = value.bytes().all(|b| matches!(b, b'-' | b'0' | b'.'));
            assert!(!(zero && value.starts_with('-')), "{name} = {value}");
            assert!(value.len() < 16, "{name} = {value}");
        }
    }
    let (_, all) = read_trace(&text);
    let count = |keep: &dyn Fn(&Vec<f64>) -> bool| all.iter().filter(|r| keep(r)).count();
    // A line window and a time window, inclusive.
    let (_, lines) = read_trace(&trace_over(&["--from-line", "8", "--to-line", "9"]).1);
    assert!(!lines.is_empty() && lines.len() < all.len());
    assert!(lines.iter().all(|r| (8.0..=9.0).contains(&r[1])));
    assert_eq!(lines.len(), count(&|r| (8.0..=9.0).contains(&r[1])));
    let (_, times) = read_trace(&trace_over(&["--from-s", "1.5", "--to-s", "2"]).1);
    assert!(!times.is_empty());
    assert_eq!(times.len(), count(&|r| (1.5..=2.0).contains(&r[0])));
    // An empty window is a usage error.
    assert_eq!(
        trace_over(&["--from-line", "9", "--to-line", "8"]).0,
        Some(2)
    );
}
