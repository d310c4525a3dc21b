//! A Marlin profile plans as Marlin: the first 3000 lines of a real PrusaSlicer `marlin2`
//! file run through the whole pipeline, diagnostics speak Marlin, a file sliced for another
//! flavour gets one warning, and the trace's commanded carriages lie on Marlin's steps.

mod common;

use common::*;

const MARLIN: &str = "tests/fixtures/profiles/kossel-marlin.yaml";
const KLIPPER: &str = "tests/fixtures/profiles/kossel-rigid.yaml";

fn check_json(gcode: &str, profile: &str) -> serde_json::Value {
    let o = run(&[
        "check",
        gcode,
        "-m",
        &repo(profile).display().to_string(),
        "--format",
        "json",
    ]);
    assert!(matches!(o.status.code(), Some(0 | 1)), "{}", stderr(&o));
    serde_json::from_slice(&o.stdout).unwrap()
}

fn messages(v: &serde_json::Value) -> Vec<String> {
    v["diagnostics"]
        .as_array()
        .unwrap()
        .iter()
        .map(|d| d.to_string())
        .collect()
}

#[test]
fn a_real_marlin2_file_runs_through_marlins_planner() {
    let file = repo("tests/fixtures/marlin2_bunny_head.gcode")
        .display()
        .to_string();
    let v = check_json(&file, MARLIN);
    let s = &v["summary"];
    assert_eq!(s["errors"], 0, "{:?}", messages(&v));
    assert!(s["moves"].as_u64().unwrap() > 2500);
    // M204 P (dozens of them), M201, M203, M205: Marlin's, read without a word.
    assert_eq!(s["warnings"], 0, "{:?}", messages(&v));
    let marlin_time = s["print_time_s"].as_f64().unwrap();
    // The same file planned by Klipper warns about M204 P and takes another time.
    let k = check_json(&file, KLIPPER);
    assert!(k["summary"]["warnings"].as_u64().unwrap() > 10);
    assert!(messages(&k)[0].contains("M204"));
    let klipper_time = k["summary"]["print_time_s"].as_f64().unwrap();
    assert!(marlin_time > 0.5 * klipper_time && marlin_time < 1.5 * klipper_time);
    assert!(
        (marlin_time - klipper_time).abs() > 1.0,
        "{marlin_time} {klipper_time}"
    );
}

#[test]
fn a_file_for_another_flavour_gets_one_warning() {
    let dir = tempfile::tempdir().unwrap();
    let moves = "G28\nG1 Z10 F3000\nG1 X10 Y5 E1 F1200\nG1 X0 Y0 E2\n";
    for (flavour, profile, firmware) in [
        ("; gcode_flavor = klipper", MARLIN, "Marlin"),
        (";FLAVOR:Marlin", KLIPPER, "Klipper"),
        ("; gcode_flavor = marlin2", KLIPPER, "Klipper"),
    ] {
        let p = dir.path().join("f.gcode");
        std::fs::write(&p, format!("{flavour}\n{moves}{flavour}\n")).unwrap();
        let v = check_json(&p.display().to_string(), profile);
        let m = messages(&v);
        assert_eq!(m.len(), 1, "{m:?}");
        assert!(m[0].contains("flavour") && m[0].contains(firmware), "{m:?}");
    }
    // The matching flavour: nothing.
    let p = dir.path().join("g.gcode");
    std::fs::write(&p, format!("; gcode_flavor = marlin2\n{moves}")).unwrap();
    assert!(messages(&check_json(&p.display().to_string(), MARLIN)).is_empty());
}

/// The commanded carriage heights lie on the straight tower-space line between whole
/// steps: at a Z-only move's samples all three carriages move together, and where a block
/// ends the heights are whole steps (80 steps/mm) above or below home.
/// An M665 that states another geometry than the profile's is told, once per parameter
/// that differs; one that states the profile's (or only S, or H) is not.
#[test]
fn an_m665_with_another_geometry_is_told() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("m665.gcode");
    let profile = delta_gcode::machine::Machine::load(&repo(MARLIN)).unwrap();
    let g = &profile.geometry;
    let same = format!(
        "M665 L{} R{} H123 X{} S100\n",
        g.arm_length_mm[0],
        g.delta_radius_mm,
        g.tower_angles_deg[0] - 210.0
    );
    let other = "M665 L300 R90.5 Y0.25 A0.5\n";
    std::fs::write(
        &p,
        format!("G28\n{same}G28\n{other}G28\nG1 X10 Y5 Z10 F3000\n"),
    )
    .unwrap();
    let m = messages(&check_json(&p.display().to_string(), MARLIN));
    let about = |letter: &str| {
        m.iter()
            .filter(|m| m.contains(&format!("M665 {letter}:")))
            .count()
    };
    assert_eq!((about("L"), about("R"), about("Y")), (1, 1, 1), "{m:?}");
    assert_eq!(
        m.iter()
            .filter(|m| m.contains("M665 ") && m.contains("profile's geometry"))
            .count(),
        3,
        "{m:?}"
    );
    let rods = m.iter().find(|m| m.contains("M665 L:")).unwrap();
    assert!(rods.contains("300.500, 300.000, 300.000"), "{rods}");
    assert!(m.iter().any(|m| m.contains("\"line\":4")), "{m:?}");
}

#[test]
fn the_trace_commands_marlins_steps() {
    let dir = tempfile::tempdir().unwrap();
    let g = dir.path().join("m.gcode");
    std::fs::write(&g, "G28\nG1 Z100 F6000\nG1 X20 Y10 F3000\nG4 P100\n").unwrap();
    let out = dir.path().join("t.csv");
    let o = run(&[
        "trace",
        &g.display().to_string(),
        "-m",
        &repo(MARLIN).display().to_string(),
        "-o",
        &out.display().to_string(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let (header, rows) = read_trace(&std::fs::read_to_string(&out).unwrap());
    let col = |name: &str| header.iter().position(|h| h == name).unwrap();
    let (t, line) = (col("t_s"), col("line"));
    let q = [col("q1_cmd_mm"), col("q2_cmd_mm"), col("q3_cmd_mm")];
    let home = rows[0][q[0]];
    // (A sample where a piece ends may come a few µs before the grid sample written before
    // it.)
    for w in rows.windows(2) {
        assert!(w[1][t] >= w[0][t] - 1e-5, "{} {}", w[0][t], w[1][t]);
    }
    for r in rows.iter().filter(|r| r[line] == 2.0) {
        assert!((r[q[0]] - r[q[1]]).abs() < 1e-9 && (r[q[1]] - r[q[2]]).abs() < 1e-9);
    }
    // The dwell at the end stands on the last block's end: whole steps from home (to the
    // trace's 0.001 mm, twice: 0.08 step).
    let last = rows.last().unwrap();
    for qi in q {
        let k = (last[qi] - home) * 80.0;
        assert!((k - k.round()).abs() < 0.085, "{k}");
    }
}

#[test]
fn a_failing_file_on_a_marlin_profile_gets_no_klipper_recommendation() {
    // The Marlin test profile with a motor too weak to hold the effector up: every move
    // fails, and the recommendation (which changes Klipper's limits) says it is not made.
    let dir = tempfile::tempdir().unwrap();
    let weak = dir.path().join("weak.yaml");
    let profile = std::fs::read_to_string(repo(MARLIN)).unwrap();
    std::fs::write(
        &weak,
        profile.replace("  max_force_n: 25.0", "  max_force_n: 0.5"),
    )
    .unwrap();
    let file = repo("samples/over-limit.gcode").display().to_string();
    let o = run(&[
        "check",
        &file,
        "-m",
        &weak.display().to_string(),
        "--format",
        "json",
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(v["recommendation"].is_null(), "{}", v["recommendation"]);
    let why = v["recommendation_error"].as_str().unwrap();
    assert!(why.contains("Marlin profile"), "{why}");
}
