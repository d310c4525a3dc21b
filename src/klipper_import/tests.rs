use super::ini::strip_inline_comment;
use super::*;
use yaml_serde::Value;

const Q5: &str = include_str!("../../tests/fixtures/klipper/flsun-q5-2020.cfg");
const KOSSEL: &str = include_str!("../../tests/fixtures/klipper/anycubic-kossel-plus-2017.cfg");
const EDGE: &str = include_str!("../../tests/fixtures/klipper/edge-cases.cfg");
const CARTESIAN: &str = include_str!("../../tests/fixtures/klipper/cartesian.cfg");
const MOTION: &str = include_str!("../../tests/fixtures/klipper/motion-sections.cfg");
const Q5_PROFILE: &str = include_str!("../../machines/flsun-q5-klipper.yaml");

fn parse(p: &ImportedProfile) -> Value {
    yaml_serde::from_str(&p.yaml).unwrap_or_else(|e| panic!("bad YAML {e}:\n{}", p.yaml))
}

fn f(v: &Value, path: &str) -> f64 {
    let mut cur = v;
    for k in path.split('.') {
        cur = &cur[k];
    }
    cur.as_f64()
        .unwrap_or_else(|| panic!("{path} is not a number: {cur:?}"))
}

/// The numbers of a YAML list (none when it is not a list).
fn numbers(v: &Value) -> Vec<f64> {
    v.as_sequence()
        .map(|s| s.iter().filter_map(Value::as_f64).collect())
        .unwrap_or_default()
}

/// One of the import's notes holds `fragment`.
fn assert_note(p: &ImportedProfile, fragment: &str) {
    assert!(
        p.notes.iter().any(|n| n.contains(fragment)),
        "{fragment:?} not in {:?}",
        p.notes
    );
}

fn import(text: &str, origin: &str) -> ImportedProfile {
    import_klipper(text, origin, &ImportExtras::default())
        .unwrap_or_else(|e| panic!("import failed: {e}"))
}

#[test]
fn q5_geometry_limits_and_defaults() {
    let p = import(Q5, "printer-flsun-q5-2020.cfg");
    let v = parse(&p);
    assert_eq!(f(&v, "geometry.delta_radius_mm"), 107.5);
    assert_eq!(f(&v, "geometry.arm_length_mm"), 215.0);
    assert_eq!(f(&v, "geometry.home_z_mm"), 220.0);
    assert_eq!(f(&v, "geometry.print_radius_mm"), 100.0);
    assert_eq!(f(&v, "geometry.nozzle_offset_mm"), 0.0);
    let angles = numbers(&v["geometry"]["tower_angles_deg"]);
    assert_eq!(angles, [210.0, 330.0, 90.0]);
    assert_eq!(f(&v, "limits.max_velocity_mm_s"), 250.0);
    assert_eq!(f(&v, "limits.max_accel_mm_s2"), 3000.0);
    assert_eq!(f(&v, "limits.max_z_velocity_mm_s"), 100.0);
    // Defaults: max_z_accel = max_accel, square_corner_velocity 5, cruise ratio 0.5.
    assert_eq!(f(&v, "limits.max_z_accel_mm_s2"), 3000.0);
    assert_eq!(f(&v, "limits.square_corner_velocity_mm_s"), 5.0);
    assert_eq!(f(&v, "limits.minimum_cruise_ratio"), 0.5);
    assert_eq!(v["limits"]["edge_slowdown"], Value::Bool(true));
    assert_eq!(f(&v, "extruder.nozzle_diameter_mm"), 0.4);
    assert_eq!(f(&v, "extruder.filament_diameter_mm"), 1.75);
    assert!(
        v["extruder"]
            .get("max_extrude_only_velocity_mm_s")
            .is_none()
    );
    assert_eq!(f(&v, "sampling.period_s"), 0.001);
    assert_eq!(
        v["name"],
        Value::from("Imported from printer-flsun-q5-2020.cfg")
    );
}

#[test]
fn missing_masses_and_force_are_listed_and_left_out() {
    let p = import(Q5, "q5.cfg");
    assert_eq!(
        p.missing,
        [
            "masses.cart_kg",
            "masses.link_kg",
            "masses.platform_kg",
            "motors.model",
            "motors.safety_factor"
        ]
    );
    let v = parse(&p);
    // An empty mapping, so the loader's message names the first missing field.
    assert_eq!(v["masses"], Value::Mapping(Default::default()));
    // The motor's pulley is Klipper's; the motor itself is missing.
    assert_eq!(f(&v, "motors.rotation_distance_mm"), 40.0);
    assert!(v["motors"].get("max_force_n").is_none());
    for key in &p.missing {
        assert!(p.yaml.contains(&format!("# MISSING: {key} —")), "{key}");
    }
}

#[test]
fn extras_fill_the_profile() {
    let extra = ImportExtras {
        name: Some("My \"Q5\"".into()),
        cart_kg: Some(0.1),
        link_kg: None,
        platform_kg: Some(0.13),
        max_force_n: Some(31.0),
    };
    let p = import_klipper(Q5, "q5.cfg", &extra).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(p.missing, ["masses.link_kg"]);
    let v = parse(&p);
    assert_eq!(v["name"], Value::from("My \"Q5\""));
    assert_eq!(f(&v, "masses.cart_kg"), 0.1);
    assert_eq!(f(&v, "masses.platform_kg"), 0.13);
    assert!(v["masses"].get("link_kg").is_none());
    assert_eq!(f(&v, "motors.max_force_n"), 31.0);
}

#[test]
fn bad_extra_is_an_error() {
    let extra = ImportExtras {
        cart_kg: Some(-0.1),
        ..Default::default()
    };
    let err = import_klipper(Q5, "q5.cfg", &extra).err();
    assert!(
        matches!(err, Some(ImportError::BadExtra { ref what, .. }) if what == "masses.cart_kg"),
        "{err:?}"
    );
}

/// The shipped FLSUN Q5 profile holds the same geometry and limits as the import of
/// Klipper's Q5 configuration (both come from config/printer-flsun-q5-2020.cfg).
#[test]
fn shipped_q5_profile_agrees_with_the_import() {
    let shipped: Value = yaml_serde::from_str(Q5_PROFILE)
        .unwrap_or_else(|e| panic!("machines/flsun-q5-klipper.yaml: {e}"));
    let v = parse(&import(Q5, "q5.cfg"));
    for path in [
        "geometry.delta_radius_mm",
        "geometry.arm_length_mm",
        "geometry.home_z_mm",
        "geometry.print_radius_mm",
        "geometry.nozzle_offset_mm",
        "limits.max_velocity_mm_s",
        "limits.max_accel_mm_s2",
        "limits.square_corner_velocity_mm_s",
        "limits.minimum_cruise_ratio",
        "limits.max_z_velocity_mm_s",
        "limits.max_z_accel_mm_s2",
        "extruder.nozzle_diameter_mm",
        "extruder.filament_diameter_mm",
        "motors.rotation_distance_mm",
    ] {
        assert_eq!(f(&shipped, path), f(&v, path), "{path}");
    }
}

#[test]
fn kossel_print_radius_defaults_to_klipper_reach() {
    // No print_radius: Klipper's default is delta_radius (134.4), then clamped to where a
    // carriage moves 12x the nozzle: 12 * 269 / sqrt(145) - 134.4 = 133.6708 (by hand),
    // rounded down to 0.01 mm.
    let p = import(KOSSEL, "kossel.cfg");
    let v = parse(&p);
    assert_eq!(f(&v, "geometry.print_radius_mm"), 133.67);
    assert_eq!(f(&v, "geometry.delta_radius_mm"), 134.4);
    assert_eq!(f(&v, "geometry.arm_length_mm"), 269.0);
    assert_eq!(f(&v, "geometry.home_z_mm"), 295.6);
    assert_eq!(f(&v, "limits.max_velocity_mm_s"), 500.0);
    assert_eq!(f(&v, "limits.max_z_velocity_mm_s"), 200.0);
    assert_note(&p, "clamped");
}

#[test]
fn edge_cases() {
    let p = import(EDGE, "edge.cfg");
    let v = parse(&p);
    // SAVE_CONFIG block overrides [printer] delta_radius and [stepper_c] arm_length.
    assert_eq!(f(&v, "geometry.delta_radius_mm"), 139.25);
    let arms = numbers(&v["geometry"]["arm_length_mm"]);
    assert_eq!(arms, [300.0, 301.0, 299.5]);
    let angles = numbers(&v["geometry"]["tower_angles_deg"]);
    assert_eq!(angles, [209.5, 330.25, 90.0]);
    // Endstops 310 / 310 (default from A) / 309.5: the lowest.
    assert_eq!(f(&v, "geometry.home_z_mm"), 309.5);
    assert_eq!(f(&v, "geometry.print_radius_mm"), 120.0);
    assert_eq!(f(&v, "limits.max_accel_mm_s2"), 4000.0); // upper-case key
    assert_eq!(f(&v, "limits.max_velocity_mm_s"), 300.0); // `=` separator
    assert_eq!(f(&v, "limits.minimum_cruise_ratio"), 0.75); // 1 - 1000/4000
    assert_eq!(f(&v, "limits.square_corner_velocity_mm_s"), 8.0);
    assert_eq!(f(&v, "limits.max_z_velocity_mm_s"), 300.0);
    assert_eq!(f(&v, "extruder.nozzle_diameter_mm"), 0.6);
    assert_eq!(f(&v, "extruder.max_extrude_only_velocity_mm_s"), 120.0);
    assert_eq!(f(&v, "extruder.instantaneous_corner_velocity_mm_s"), 2.5);
    assert!(v["extruder"].get("max_extrude_only_accel_mm_s2").is_none());
    assert_note(&p, "[include mainsail.cfg]");
    assert_note(&p, "position_endstop differs");
}

#[test]
fn non_delta_is_an_error_with_line() {
    let err = import_klipper(CARTESIAN, "cart.cfg", &ImportExtras::default()).err();
    assert_eq!(
        err,
        Some(ImportError::NotDelta {
            origin: "cart.cfg".into(),
            line: 5,
            found: "cartesian".into()
        })
    );
    let msg = err.map(|e| e.to_string()).unwrap_or_default();
    assert!(msg.starts_with("cart.cfg:5:"), "{msg}");
}

#[test]
fn bad_number_names_line_and_key() {
    let text = "[printer]\nkinematics: delta\nmax_velocity: fast\n";
    let err = import_klipper(text, "p.cfg", &ImportExtras::default()).err();
    assert!(
        matches!(&err, Some(ImportError::BadValue { line: 3, key, .. }) if key == "max_velocity"),
        "{err:?}"
    );
    let nan = "[printer]\nkinematics: delta\nmax_velocity: nan\n";
    assert!(matches!(
        import_klipper(nan, "p.cfg", &ImportExtras::default()),
        Err(ImportError::BadValue { line: 3, .. })
    ));
}

#[test]
fn missing_required_keys_and_sections() {
    let no_arm = "[printer]\nkinematics: delta\nmax_velocity: 300\nmax_accel: 3000\ndelta_radius: 100\n\n[stepper_a]\nposition_endstop: 250\n";
    assert_eq!(
        import_klipper(no_arm, "p.cfg", &ImportExtras::default()).err(),
        Some(ImportError::MissingKey {
            origin: "p.cfg".into(),
            line: 7,
            section: "stepper_a".into(),
            key: "arm_length".into()
        })
    );
    let no_stepper =
        "[printer]\nkinematics: delta\nmax_velocity: 300\nmax_accel: 3000\ndelta_radius: 100\n";
    assert!(matches!(
        import_klipper(no_stepper, "p.cfg", &ImportExtras::default()),
        Err(ImportError::MissingSection { ref section, .. }) if section == "stepper_a"
    ));
    assert!(matches!(
        import_klipper("", "p.cfg", &ImportExtras::default()),
        Err(ImportError::MissingSection { ref section, .. }) if section == "printer"
    ));
}

#[test]
fn klipper_bounds_are_enforced() {
    let base =
        "[printer]\nkinematics: delta\nmax_velocity: 300\nmax_accel: 3000\ndelta_radius: 100\n";
    // Arm not longer than the radius (delta.py: arm_length above=radius).
    let short = format!("{base}[stepper_a]\narm_length: 100\nposition_endstop: 250\n");
    assert!(matches!(
        import_klipper(&short, "p.cfg", &ImportExtras::default()),
        Err(ImportError::BadValue { line: 7, ref key, .. }) if key == "arm_length"
    ));
    // max_z_velocity above max_velocity (delta.py: maxval=max_velocity).
    let fast_z = base.replace("delta_radius", "max_z_velocity: 301\ndelta_radius");
    let fast_z = format!("{fast_z}[stepper_a]\narm_length: 250\nposition_endstop: 250\n");
    assert!(matches!(
        import_klipper(&fast_z, "p.cfg", &ImportExtras::default()),
        Err(ImportError::BadValue { line: 5, ref key, .. }) if key == "max_z_velocity"
    ));
}

#[test]
fn syntax_errors_name_the_line() {
    for (text, line) in [
        ("kinematics: delta\n", 1),
        ("[printer\nkinematics: delta\n", 1),
        ("[printer]\nkinematics delta\n", 2),
        ("  indented: x\n[printer]\n", 1),
        (
            "[printer]\n#*# <---------------------- SAVE_CONFIG ---------------------->\nkinematics: delta\n",
            3,
        ),
    ] {
        match import_klipper(text, "s.cfg", &ImportExtras::default()) {
            Err(ImportError::Syntax { line: l, .. }) => assert_eq!(l, line, "{text:?}"),
            other => panic!("{text:?}: {other:?}"),
        }
    }
}

#[test]
fn inline_comments() {
    assert_eq!(strip_inline_comment("delta ; x"), "delta ");
    assert_eq!(strip_inline_comment("delta # x"), "delta ");
    assert_eq!(strip_inline_comment("^ar2#x"), "^ar2#x");
    assert_eq!(strip_inline_comment("# all"), "");
    assert_eq!(strip_inline_comment("a;b"), "a;b");
}

#[test]
fn motion_sections_shaper_arcs_and_motor_figures() {
    let p = import(MOTION, "motion.cfg");
    let v = parse(&p);
    assert_eq!(f(&v, "gcode_arcs.resolution"), 0.5);
    assert_eq!(v["input_shaper"]["shaper_type_x"], Value::from("mzv"));
    assert_eq!(f(&v, "input_shaper.shaper_freq_x"), 48.2);
    assert_eq!(v["input_shaper"]["shaper_type_y"], Value::from("ei"));
    assert_eq!(f(&v, "input_shaper.shaper_freq_y"), 40.4);
    assert_eq!(f(&v, "input_shaper.damping_ratio_y"), 0.08);
    assert!(v["input_shaper"].get("damping_ratio_x").is_none());
    // rotation_distance 40, 400 full steps (0.9°), the TMC2209's run_current.
    assert_eq!(f(&v, "motors.rotation_distance_mm"), 40.0);
    assert_eq!(f(&v, "motors.step_angle_deg"), 0.9);
    assert_eq!(f(&v, "motors.run_current_a"), 1.2);
    assert!(
        p.yaml
            .contains("[tmc2209 stepper_a] run_current (line 37), A RMS")
    );
    // A trimmed [extruder]: no filament_diameter, the usual 1.75 and a note.
    assert_eq!(f(&v, "extruder.filament_diameter_mm"), 1.75);
    assert_note(&p, "[extruder] has no filament_diameter");
    assert_eq!(
        p.missing,
        [
            "masses.cart_kg",
            "masses.link_kg",
            "masses.platform_kg",
            "motors.model",
            "motors.safety_factor"
        ]
    );
    // With the masses and a motor filled in, the profile loads with the shaper, the arcs
    // and the motor's curve at the imported current and step angle.
    let extra = ImportExtras {
        cart_kg: Some(0.1),
        link_kg: Some(0.012),
        platform_kg: Some(0.12),
        ..Default::default()
    };
    let yaml = import_klipper(MOTION, "motion.cfg", &extra).unwrap().yaml;
    let yaml = yaml.replace(
        "  # MISSING: motors.model",
        "  model: ldo-42sth48-2004mac\n  safety_factor: 1\n  supply_voltage_v: 24\n  # was: motors.model",
    );
    let m = crate::machine::Machine::from_yaml_str(&yaml, "imported")
        .unwrap_or_else(|e| panic!("{e}\n{yaml}"));
    assert_eq!(
        m.arc_rules,
        crate::gcode::ArcRules::Klipper { resolution_mm: 0.5 }
    );
    assert_eq!(m.input_shaper.y.map(|s| s.damping_ratio), Some(0.08));
    assert!(m.motors.curve.is_some());
    // 0.49 N·m × 1.2/2.0 at r = 6.366198 mm: 46.1826 N below the knee.
    assert!((m.motors.max_force_n - 0.49 * 0.6 / 0.006_366_198).abs() < 1e-3);
}

#[test]
fn motor_figures_become_comments_next_to_max_force_n() {
    let extra = ImportExtras {
        max_force_n: Some(30.0),
        ..Default::default()
    };
    let p = import_klipper(MOTION, "motion.cfg", &extra).unwrap();
    let v = parse(&p);
    assert_eq!(f(&v, "motors.max_force_n"), 30.0);
    assert!(v["motors"].get("rotation_distance_mm").is_none());
    assert!(
        p.yaml
            .contains("  # rotation_distance_mm: 40.0  # [stepper_a] rotation_distance")
    );
    assert!(
        p.yaml
            .contains("  # run_current_a: 1.2  # [tmc2209 stepper_a] run_current")
    );
    assert!(
        !p.missing.iter().any(|m| m.starts_with("motors")),
        "{:?}",
        p.missing
    );
}

#[test]
fn gear_ratio_divides_the_belt_travel_and_towers_may_differ() {
    let text = MOTION
        .replacen(
            "full_steps_per_rotation: 400\n",
            "full_steps_per_rotation: 400\ngear_ratio: 60:20\n",
            1,
        )
        .replace(
            "[stepper_c]\nstep_pin: PB5\ndir_pin: PB4\nmicrosteps: 16\nrotation_distance: 40",
            "[stepper_c]\nstep_pin: PB5\ndir_pin: PB4\nmicrosteps: 16\nrotation_distance: 32",
        );
    let p = import(&text, "g.cfg");
    let v = parse(&p);
    // 40 mm per output turn, the motor turning 3 times: 13.333 mm per motor turn.
    assert!((f(&v, "motors.rotation_distance_mm") - 40.0 / 3.0).abs() < 1e-12);
    assert_note(&p, "gear_ratio 60:20");
    assert_note(&p, "[stepper_c] moves 32.0 mm per motor turn");
}

#[test]
fn motion_sections_are_checked_as_klipper_checks_them() {
    let cases = [
        (
            "shaper_type_x: mzv",
            "shaper_type_x: mzv(t=0.7)",
            "shaper_type_x",
        ),
        ("shaper_type_y: ei", "shaper_type_y: EI", "shaper_type_y"),
        (
            "damping_ratio_y: 0.08",
            "damping_ratio_y: 0.45",
            "damping_ratio_y",
        ),
        (
            "damping_ratio_y: 0.08",
            "damping_ratio_y: -0.1",
            "damping_ratio_y",
        ),
        ("shaper_freq_x: 48.2", "shaper_freq_x: -1", "shaper_freq_x"),
        ("resolution: 0.5", "resolution: 0", "resolution"),
        (
            "run_current: 1.2\nhold",
            "run_current: 0\nhold",
            "run_current",
        ),
        (
            "full_steps_per_rotation: 400\narm",
            "full_steps_per_rotation: 202\narm",
            "full_steps_per_rotation",
        ),
        (
            "rotation_distance: 40\nfull_steps_per_rotation: 400\narm",
            "rotation_distance: 40\nfull_steps_per_rotation: 400\ngear_ratio: 3\narm",
            "gear_ratio",
        ),
        (
            "nozzle_diameter: 0.4",
            "nozzle_diameter: 0",
            "nozzle_diameter",
        ),
    ];
    for (from, to, key) in cases {
        let text = MOTION.replacen(from, to, 1);
        assert_ne!(text, MOTION, "{from}");
        let line = text
            .lines()
            .position(|l| l.starts_with(&format!("{key}:")))
            .unwrap()
            + 1;
        match import_klipper(&text, "m.cfg", &ImportExtras::default()) {
            Err(e @ ImportError::BadValue { .. }) => {
                let msg = e.to_string();
                assert!(
                    msg.starts_with(&format!("m.cfg:{line}:")),
                    "{msg} (line {line})"
                );
                assert!(msg.contains(key), "{msg}");
            }
            other => panic!("{to}: {other:?}"),
        }
    }
}
