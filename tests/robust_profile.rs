//! A broken machine profile stops `check` with exit code 2 and a message naming the file,
//! the line and column, and the key.

mod common;

use common::*;
use std::fs;

/// Writes tests/fixtures/robust/profile.yaml (a copy of machines/kossel.yaml, so the line
/// numbers pinned here do not move when the shipped profile is edited) with `from` replaced by `to` (or the line removed when `to`
/// is empty) into a temporary directory and runs `check` with it on a sample.
fn check_with(from: &str, to: &str) -> (Option<i32>, String) {
    let text = fs::read_to_string(repo("tests/fixtures/robust/profile.yaml")).unwrap();
    assert!(text.contains(from), "{from:?} is not in profile.yaml");
    let edited = if to.is_empty() {
        text.lines()
            .filter(|l| !l.starts_with(from))
            .map(|l| format!("{l}\n"))
            .collect()
    } else {
        text.replacen(from, to, 1)
    };
    let dir = tempfile::tempdir().unwrap();
    let profile = dir.path().join("bad.yaml");
    fs::write(&profile, edited).unwrap();
    let sample = repo("samples/calib-cube_cura413_kossel-mini.gcode");
    let o = run(&[
        "check",
        sample.to_str().unwrap(),
        "-m",
        profile.to_str().unwrap(),
    ]);
    assert!(
        o.stdout.is_empty(),
        "no report on a bad profile: {}",
        stdout(&o)
    );
    (o.status.code(), stderr(&o))
}

fn assert_error(from: &str, to: &str, fragments: &[&str]) {
    let (code, err) = check_with(from, to);
    assert_eq!(code, Some(2), "{err}");
    for f in fragments {
        assert!(err.contains(f), "{f:?} not in: {err}");
    }
    assert!(!err.contains("panicked"), "{err}");
}

#[test]
fn missing_key() {
    // The YAML parser places a missing field at the first key of its section (link_kg here).
    assert_error(
        "  cart_kg: 0.22",
        "",
        &["bad.yaml:18:3: masses: missing field `cart_kg`"],
    );
}

#[test]
fn wrong_type() {
    assert_error(
        "arm_length_mm: 215.0",
        "arm_length_mm: long",
        &[
            "bad.yaml:8:18",
            "geometry.arm_length_mm",
            "invalid type: string \"long\"",
        ],
    );
    assert_error(
        "cart_kg: 0.22",
        "cart_kg: [0.22]",
        &["bad.yaml:17:", "cart_kg", "expected a number"],
    );
}

#[test]
fn unknown_key_suggests_the_closest_name() {
    assert_error(
        "arm_length_mm: 215.0",
        "arm_lenght_mm: 215.0",
        &[
            "bad.yaml:8:3",
            "unknown field `arm_lenght_mm`",
            "(did you mean `arm_length_mm`?)",
        ],
    );
    assert_error(
        "max_force_n: 25.0",
        "max_forse_n: 25.0",
        &["bad.yaml:41:3", "(did you mean `max_force_n`?)"],
    );
}

#[test]
fn impossible_geometry() {
    assert_error(
        "arm_length_mm: 215.0",
        "arm_length_mm: 150.0",
        &[
            "bad.yaml:8:3: geometry.arm_length_mm",
            "arm of tower A is 150 mm",
            "longer than delta_radius + print_radius = 190 mm",
        ],
    );
    assert_error(
        "arm_length_mm: 215.0",
        "arm_length_mm: [215.0, 215.0, 189.0]",
        &[
            "bad.yaml:8:3: geometry.arm_length_mm",
            "arm of tower C is 189 mm",
        ],
    );
    assert_error(
        "home_z_mm: 290.0",
        "home_z_mm: -5",
        &["bad.yaml:10:3: geometry.home_z_mm", "above the bed"],
    );
}

#[test]
fn negative_mass_or_force_limit() {
    assert_error(
        "cart_kg: 0.22",
        "cart_kg: -0.22",
        &[
            "bad.yaml:17:3: masses.cart_kg",
            "expected a finite number > 0, found -0.22",
        ],
    );
    assert_error(
        "platform_kg: 0.10",
        "platform_kg: 0",
        &["bad.yaml:22:3: masses.platform_kg", "> 0, found 0"],
    );
    assert_error(
        "max_force_n: 25.0",
        "max_force_n: -25",
        &["bad.yaml:41:3: motors.max_force_n", "> 0, found -25"],
    );
    assert_error(
        "max_accel_mm_s2: 3000",
        "max_accel_mm_s2: .nan",
        &["limits.max_accel_mm_s2", "found NaN"],
    );
}

#[test]
fn a_sampling_period_that_would_never_finish() {
    assert_error(
        "period_s: 0.001",
        "period_s: 1e-9",
        &[
            "bad.yaml:50:3: sampling.period_s",
            "expected a period between",
        ],
    );
}

#[test]
fn unreadable_or_not_yaml() {
    let o = run(&[
        "check",
        repo("samples/over-limit.gcode").to_str().unwrap(),
        "-m",
        "/no/such/profile.yaml",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("/no/such/profile.yaml: cannot read the machine profile"));
    assert_error("name: Kossel Mini", "name: [Kossel", &["bad.yaml:"]);
}

#[test]
fn bad_new_keys_stop_check_with_their_line() {
    // The fixture's last line is `gravity_m_s2: 9.81` (line 51); the keys go after it.
    let tail = "gravity_m_s2: 9.81";
    assert_error(
        tail,
        "gravity_m_s2: 9.81\ndrive: {frequency_hz: 60, damping_ratio: 1.5}",
        &["bad.yaml:52:", "drive.damping_ratio", "underdamped"],
    );
    assert_error(
        tail,
        "gravity_m_s2: 9.81\ndrive: stiff",
        &["bad.yaml:52:8: drive: invalid value"],
    );
    assert_error(
        tail,
        "gravity_m_s2: 9.81\nmarlin:\n  steps_per_mm: 80",
        &["bad.yaml:52:1: marlin", "only with `firmware: marlin`"],
    );
    assert_error(
        tail,
        "gravity_m_s2: 9.81\ninput_shaper:\n  shaper_type_x: mvz\n  shaper_freq_x: 40",
        &[
            "bad.yaml:53:3: input_shaper.shaper_type_x",
            "did you mean `mzv`?",
        ],
    );
    assert_error(
        tail,
        "gravity_m_s2: 9.81\ngcode_arcs: {resolution: -1}",
        &["bad.yaml:52:14: gcode_arcs.resolution"],
    );
    assert_error(
        "  max_force_n: 25.0",
        "  model: ldo-42sth48\n  rotation_distance_mm: 40\n  safety_factor: 1",
        &[
            "bad.yaml:41:3: motors.model: unknown motor `ldo-42sth48`",
            "did you mean `ldo-42sth48-2004ac`?",
        ],
    );
    assert_error(
        "  max_force_n: 25.0",
        "  model: ldo-42sth48-2004ac\n  rotation_distance_mm: 40\n  safety_factor: 1\n  \
         run_current_a: 2.5",
        &["bad.yaml:44:3: motors.run_current_a", "above the rated 2 A"],
    );
}
