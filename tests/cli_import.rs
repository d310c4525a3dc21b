//! `machine import-klipper`: a Klipper delta printer.cfg becomes a profile the tool accepts
//! once the masses and the motor limit are known.

mod common;

use common::*;
use std::fs;

#[test]
fn imported_profile_with_masses_is_accepted() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("q5.yaml");
    let cfg = repo("tests/fixtures/klipper/flsun-q5-2020.cfg")
        .display()
        .to_string();
    let o = run(&[
        "machine",
        "import-klipper",
        &cfg,
        "-o",
        &out.display().to_string(),
        "--name",
        "My Q5",
        "--cart-kg",
        "0.2",
        "--link-kg",
        "0.015",
        "--platform-kg",
        "0.15",
        "--max-force-n",
        "30",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(!stderr(&o).contains("incomplete"), "{}", stderr(&o));
    let m = run(&["machine", &out.display().to_string()]);
    assert_eq!(m.status.code(), Some(0), "{}", stderr(&m));
    assert!(
        stdout(&m).starts_with("My Q5: profile OK"),
        "{}",
        stdout(&m)
    );
    // The Q5's geometry, as shipped in machines/flsun-q5-klipper.yaml.
    let text = fs::read_to_string(&out).unwrap();
    assert!(text.contains("delta_radius_mm: 107.5"), "{text}");
    let cube = repo("samples/calib-cube_cura413_kossel-mini.gcode")
        .display()
        .to_string();
    let c = run(&["check", &cube, "-m", &out.display().to_string()]);
    assert_eq!(c.status.code(), Some(0), "{}{}", stdout(&c), stderr(&c));
}

#[test]
fn missing_masses_are_named_and_check_refuses_the_profile() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("q5.yaml");
    let cfg = repo("tests/fixtures/klipper/flsun-q5-2020.cfg")
        .display()
        .to_string();
    let o = run(&[
        "machine",
        "import-klipper",
        &cfg,
        "-o",
        &out.display().to_string(),
    ]);
    assert_eq!(o.status.code(), Some(0));
    assert!(
        stderr(&o).contains("missing masses.cart_kg"),
        "{}",
        stderr(&o)
    );
    let text = fs::read_to_string(&out).unwrap();
    assert!(text.contains("# MISSING: masses.cart_kg"), "{text}");
    let cube = repo("samples/calib-cube_cura413_kossel-mini.gcode")
        .display()
        .to_string();
    let c = run(&["check", &cube, "-m", &out.display().to_string()]);
    assert_eq!(c.status.code(), Some(2));
    assert!(
        stderr(&c).contains("q5.yaml") && stderr(&c).contains("cart_kg"),
        "{}",
        stderr(&c)
    );
}

#[test]
fn a_cartesian_config_is_refused_with_its_line() {
    let cfg = repo("tests/fixtures/klipper/cartesian.cfg")
        .display()
        .to_string();
    let o = run(&["machine", "import-klipper", &cfg]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("cartesian.cfg:5"), "{}", stderr(&o));
}

#[test]
fn shaper_arcs_and_motor_figures_are_imported() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("m.yaml");
    let cfg = repo("tests/fixtures/klipper/motion-sections.cfg")
        .display()
        .to_string();
    let args = [
        "machine",
        "import-klipper",
        &cfg,
        "-o",
        &out.display().to_string(),
        "--cart-kg",
        "0.1",
        "--link-kg",
        "0.012",
        "--platform-kg",
        "0.12",
    ];
    let o = run(&args);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    // The motor itself is not in a Klipper config.
    assert!(
        stderr(&o).contains("missing motors.model, motors.safety_factor"),
        "{}",
        stderr(&o)
    );
    assert!(
        stderr(&o).contains("note: [extruder] has no filament_diameter"),
        "{}",
        stderr(&o)
    );
    // With the motor added, the profile loads and shows what was imported.
    let text = fs::read_to_string(&out).unwrap().replace(
        "  # MISSING: motors.model",
        "  model: omc-17hm19-2004s\n  safety_factor: 1.5\n  # was: motors.model",
    );
    fs::write(&out, text).unwrap();
    let m = run(&["machine", &out.display().to_string()]);
    assert_eq!(m.status.code(), Some(0), "{}", stderr(&m));
    let shown = stdout(&m);
    for fragment in [
        "arcs: Klipper's [gcode_arcs], chords of 0.5 mm",
        "input shaper: x mzv at 48.2 Hz, damping ratio 0.1; y ei at 40.4 Hz, damping ratio 0.08",
        "motor: omc-17hm19-2004s, ",
    ] {
        assert!(shown.contains(fragment), "{fragment:?} not in\n{shown}");
    }
    // With --max-force-n the motor's figures stay as comments and nothing is missing.
    let o = run(&[&args[..], &["--max-force-n", "30"]].concat());
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(!stderr(&o).contains("incomplete"), "{}", stderr(&o));
    let text = fs::read_to_string(&out).unwrap();
    assert!(text.contains("  # run_current_a: 1.2"), "{text}");
    let m = run(&["machine", &out.display().to_string()]);
    assert_eq!(m.status.code(), Some(0), "{}", stderr(&m));
}
