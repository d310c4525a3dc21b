use super::ini::strip_inline_comment;
use super::*;
use yaml_serde::Value;

const Q5: &str = include_str!("../../tests/fixtures/klipper/flsun-q5-2020.cfg");
const KOSSEL: &str = include_str!("../../tests/fixtures/klipper/anycubic-kossel-plus-2017.cfg");
const EDGE: &str = include_str!("../../tests/fixtures/klipper/edge-cases.cfg");
const CARTESIAN: &str = include_str!("../../tests/fixtures/klipper/cartesian.cfg");
const Q5_PROFILE: &str = include_str!("../../machines/flsun-q5.yaml");

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
            "motors.max_force_n"
        ]
    );
    let v = parse(&p);
    // Empty mappings, so the loader's message names the first missing field.
    assert_eq!(v["masses"], Value::Mapping(Default::default()));
    assert_eq!(v["motors"], Value::Mapping(Default::default()));
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
    let shipped: Value =
        yaml_serde::from_str(Q5_PROFILE).unwrap_or_else(|e| panic!("machines/flsun-q5.yaml: {e}"));
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
    assert!(
        p.notes.iter().any(|n| n.contains("clamped")),
        "{:?}",
        p.notes
    );
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
    assert!(
        p.notes.iter().any(|n| n.contains("[include mainsail.cfg]")),
        "{:?}",
        p.notes
    );
    assert!(
        p.notes
            .iter()
            .any(|n| n.contains("position_endstop differs")),
        "{:?}",
        p.notes
    );
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
