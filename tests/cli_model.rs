//! The `pose` and `machine` commands end to end.

use assert_cmd::Command;

const KOSSEL: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/machines/kossel.yaml");
const PAPER: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/machines/paper.yaml");

fn cmd() -> Command {
    Command::cargo_bin("delta-gcode").unwrap()
}

fn json_of(args: &[&str]) -> serde_json::Value {
    let out = cmd().args(args).output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

fn triple(v: &serde_json::Value, key: &str) -> [f64; 3] {
    let a = v[key]
        .as_array()
        .unwrap_or_else(|| panic!("no {key} in {v}"));
    [0, 1, 2].map(|i| a[i].as_f64().unwrap())
}

#[test]
fn pose_json_has_the_documented_keys() {
    let v = json_of(&[
        "pose",
        "--machine",
        PAPER,
        "10",
        "20",
        "0.2",
        "--format",
        "json",
    ]);
    for key in ["q_mm", "dq_mm_s", "ddq_mm_s2", "force_n", "lambda"] {
        triple(&v, key);
    }
    for key in ["power_w", "energy_rate_w", "jx_condition"] {
        assert!(v[key].as_f64().is_some(), "{key} in {v}");
    }
    // At rest the forces carry the suspended weight (eq. 17): 13.44 N for the paper.
    let sum: f64 = triple(&v, "force_n").iter().sum();
    assert!((sum - 13.4397).abs() < 1e-9, "{sum}");
}

#[test]
fn negative_numbers_need_no_double_dash() {
    let v = json_of(&[
        "pose",
        "--machine",
        KOSSEL,
        "-10",
        "-20.5",
        "0.2",
        "--velocity",
        "-100,50,0",
        "--accel",
        "-3000,0,-5",
        "--format",
        "json",
    ]);
    let dq = triple(&v, "dq_mm_s");
    assert!(dq.iter().any(|d| d.abs() > 1.0), "{v}");
    let (p, e) = (
        v["power_w"].as_f64().unwrap(),
        v["energy_rate_w"].as_f64().unwrap(),
    );
    assert!((p - e).abs() < 1e-9 * (1.0 + p.abs()), "{p} vs {e}");
}

#[test]
fn carriages_run_the_direct_kinematics_back_to_the_pose() {
    let v = json_of(&[
        "pose",
        "--machine",
        KOSSEL,
        "-30",
        "25",
        "10",
        "--format",
        "json",
    ]);
    let q = triple(&v, "q_mm");
    let qs = format!("{},{},{}", q[0], q[1], q[2]);
    let back = json_of(&[
        "pose",
        "--machine",
        KOSSEL,
        "--carriages",
        &qs,
        "--format",
        "json",
    ]);
    let p = triple(&back, "position_mm");
    for (a, b) in p.iter().zip([-30.0, 25.0, 10.0]) {
        assert!((a - b).abs() < 1e-9, "{p:?}");
    }
}

#[test]
fn unreachable_pose_is_an_input_error() {
    let out = cmd()
        .args(["pose", "--machine", KOSSEL, "0", "-300", "0"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("unreachable") && err.contains("tower"),
        "{err}"
    );
    let out = cmd()
        .args(["pose", "--machine", KOSSEL, "--carriages", "0,0,1000"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn machine_prints_the_derived_figures() {
    let out = cmd().args(["machine", PAPER]).output().unwrap();
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    for needle in [
        "13.440 N",
        "eq. 16",
        "4.480",
        "half speed beyond r = 98.97 mm",
    ] {
        assert!(text.contains(needle), "{needle} in\n{text}");
    }
    // Off the centre a carriage carries more than at the centre (eq. 15 against eq. 16).
    let v = json_of(&["machine", KOSSEL, "--format", "json"]);
    let centre = v["static_force_centre_n"][0].as_f64().unwrap();
    assert!(
        v["max_static_force_n"].as_f64().unwrap() > 1.2 * centre,
        "{v}"
    );
}

#[test]
fn bad_profile_is_reported_with_file_line_and_suggestion() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.yaml");
    let text = std::fs::read_to_string(KOSSEL)
        .unwrap()
        .replace("print_radius_mm:", "print_radios_mm:");
    std::fs::write(&path, text).unwrap();
    let out = cmd().arg("machine").arg(&path).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("bad.yaml:"), "{err}");
    assert!(err.contains("did you mean `print_radius_mm`?"), "{err}");
}
