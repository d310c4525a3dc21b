//! Every shipped machine profile loads, and every shipped sample checks on it.

mod common;

use common::*;

#[test]
fn every_shipped_profile_is_valid_and_checks_every_sample() {
    let samples: Vec<String> = std::fs::read_dir(repo("samples"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "gcode"))
        .map(|p| p.display().to_string())
        .collect();
    assert!(samples.len() >= 5, "{samples:?}");
    let mut n = 0;
    let mut marlin = 0;
    for entry in std::fs::read_dir(repo("machines")).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "yaml") {
            continue;
        }
        n += 1;
        let p = path.display().to_string();
        let m = run(&["machine", &p]);
        assert_eq!(m.status.code(), Some(0), "{p}: {}", stderr(&m));
        if stdout(&m).contains("\nfirmware: marlin:") {
            marlin += 1;
        }
        for sample in &samples {
            // Exit 0 or 1 (a verdict), never 2 (an input or profile error).
            let c = run(&["check", sample, "-m", &p, "--format", "json"]);
            assert!(
                matches!(c.status.code(), Some(0 | 1)),
                "{p} {sample}: {}",
                stderr(&c)
            );
            let v: serde_json::Value = serde_json::from_slice(&c.stdout).unwrap();
            let moves = v["summary"]["moves"].as_u64().unwrap_or(0);
            assert!(moves > 0, "{p} {sample}");
            if sample.ends_with("calib-cube_cura413_kossel-mini.gcode") {
                assert!(moves > 8000, "{p}: {moves} moves");
            }
        }
    }
    assert!(n >= 8, "{n} profiles");
    // The FLSUN Q5 and the Kossel Linear Plus with their Marlin settings.
    assert!(marlin >= 2, "{marlin} Marlin profiles");
}

#[test]
fn marlin_profiles_check_a_real_marlin_file() {
    // The FLSUN Q5's own start code (a Marlin file: the helix G3) on both Marlin profiles.
    let q5 = repo("tests/fixtures/flsun_q5_start.gcode")
        .display()
        .to_string();
    for m in ["flsun-q5.yaml", "anycubic-kossel-linear-plus.yaml"] {
        let p = repo(&format!("machines/{m}")).display().to_string();
        let c = run(&["check", &q5, "-m", &p, "--format", "json"]);
        assert!(
            matches!(c.status.code(), Some(0 | 1)),
            "{m}: {}",
            stderr(&c)
        );
        let v: serde_json::Value = serde_json::from_slice(&c.stdout).unwrap();
        assert!(v["summary"]["moves"].as_u64().unwrap_or(0) > 100, "{m}");
    }
}

/// A profile with every new key: a Marlin firmware, arcs, a shaper, the LDO motor with its
/// electrical figures.
const LDO: &str = "name: LDO test
geometry: {delta_radius_mm: 105, arm_length_mm: 215, home_z_mm: 290, print_radius_mm: 85}
masses: {cart_kg: 0.09, link_kg: 0.012, platform_kg: 0.1}
limits: {max_velocity_mm_s: 300, max_accel_mm_s2: 3000}
motors:
  model: ldo-42sth48-2004ac
  rotation_distance_mm: 40
  safety_factor: 1
  run_current_a: 1.2
  supply_voltage_v: 24
firmware: marlin
marlin: {e_steps_per_mm: 93}
gcode_arcs: {resolution: 0.5}
input_shaper: {shaper_type_x: mzv, shaper_freq_x: 40.2, shaper_type_y: ei, shaper_freq_y: 45.6}
";

fn write_profile(dir: &std::path::Path, text: &str) -> String {
    let p = dir.join("ldo.yaml");
    std::fs::write(&p, text).unwrap();
    p.display().to_string()
}

#[test]
fn machine_shows_firmware_arcs_shaper_drive_and_the_motor_curve() {
    let dir = tempfile::tempdir().unwrap();
    let p = write_profile(dir.path(), LDO);
    let o = run(&["machine", &p]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let text = stdout(&o);
    for fragment in [
        "firmware: marlin: 80 steps/mm (E 93), 200 segments/s",
        "arcs: Klipper's [gcode_arcs], chords of 0.5 mm",
        "input shaper: x mzv at 40.2 Hz, damping ratio 0.1; y ei at 45.6 Hz, damping ratio 0.1",
        "drive: spring of 51.26 Hz, damping ratio 0.1 (the default: no `drive` in the profile",
        "motor: ldo-42sth48-2004ac, force at carriage speed (current-chopped stepper model), \
         knee 433.76 mm/s, zero force at 732.46 mm/s",
        "  force N                55.61   55.61   55.61   55.61   55.61   43.39   27.59",
    ] {
        assert!(text.contains(fragment), "{fragment:?} not in\n{text}");
    }
    let o = run(&["machine", &p, "--format", "json"]);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["firmware"], "marlin");
    assert_eq!(v["marlin"]["e_steps_per_mm"], 93.0);
    assert_eq!(v["marlin"]["block_buffer_size"], 16);
    assert_eq!(v["gcode_arcs"]["resolution_mm"], 0.5);
    assert_eq!(v["input_shaper"]["y"]["type"], "ei");
    assert_eq!(v["input_shaper"]["x"]["freq_hz"], 40.2);
    assert_eq!(v["drive"]["kind"], "spring");
    assert_eq!(v["drive"]["default"]["typical_motor"], false);
    let f = v["motor"]["curve"]["force_n"].as_array().unwrap();
    assert_eq!(f.len(), 7);
    assert!((f[5].as_f64().unwrap() - 43.3922).abs() < 5e-5);
    assert!((v["motor"]["curve"]["knee_speed_mm_s"].as_f64().unwrap() - 433.76).abs() < 5e-3);
    // The test Kossel: Klipper, no shaper, rigid drive as given, a constant force.
    let k = repo("tests/fixtures/profiles/kossel-rigid.yaml")
        .display()
        .to_string();
    let text = stdout(&run(&["machine", &k]));
    assert!(text.contains("firmware: klipper\n"), "{text}");
    assert!(text.contains("input shaper: x off; y off\n"), "{text}");
    assert!(text.contains("drive: rigid (given)\n"), "{text}");
    assert!(
        text.contains("motor: 25.00 N at any carriage speed (no electrical figures)"),
        "{text}"
    );
    let v: serde_json::Value =
        serde_json::from_slice(&run(&["machine", &k, "--format", "json"]).stdout).unwrap();
    assert_eq!(v["drive"]["kind"], "rigid");
    assert_eq!(v["marlin"], serde_json::Value::Null);
    assert_eq!(
        v["motor"]["curve"]["knee_speed_mm_s"],
        serde_json::Value::Null
    );
    assert_eq!(v["motor"]["curve"]["force_n"][6], 25.0);
    // The shipped Kossel: its motor's curve, the default drive.
    let k = repo("machines/kossel.yaml").display().to_string();
    let text = stdout(&run(&["machine", &k]));
    assert!(
        text.contains("drive: spring of 51.23 Hz, damping ratio 0.1 (the default"),
        "{text}"
    );
    assert!(text.contains("motor: motionking-17hs4401"), "{text}");
}

#[test]
fn machine_plot_writes_the_motor_curve() {
    let dir = tempfile::tempdir().unwrap();
    let p = write_profile(dir.path(), LDO);
    let out = dir.path().join("plots");
    let o = run(&["machine", &p, "--plot", &out.display().to_string()]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let svg = std::fs::read_to_string(out.join("ldo-motor.svg")).unwrap();
    assert!(svg.contains("<svg") && svg.trim_end().ends_with("</svg>"));
    assert!(svg.contains("ldo-42sth48-2004ac") && svg.contains("carriage speed (mm/s)"));
    assert!(!svg.contains("NaN"));
}

#[test]
fn pose_json_gives_the_force_available_at_each_carriage_speed() {
    let dir = tempfile::tempdir().unwrap();
    let p = write_profile(dir.path(), LDO);
    // A fast move along X: carriage speeds of a few hundred mm/s, each with its force.
    let o = run(&[
        "pose",
        "-m",
        &p,
        "10",
        "20",
        "30",
        "--velocity",
        "900,0,0",
        "--format",
        "json",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let dq = v["dq_mm_s"].as_array().unwrap();
    let avail = v["available_force_n"].as_array().unwrap();
    assert_eq!(avail.len(), 3);
    let mut slowed = 0;
    for (q, f) in dq.iter().zip(avail) {
        let (q, f) = (q.as_f64().unwrap(), f.as_f64().unwrap());
        assert!((0.0..=55.6063).contains(&f), "{q} {f}");
        if q.abs() > 433.76 {
            slowed += 1;
            assert!(f < 55.6, "{q} {f}");
        } else {
            assert!((f - 55.6062).abs() < 1e-4, "{q} {f}");
        }
    }
    assert!(slowed >= 1, "{dq:?}");
    // The existing fields keep their order; the new one comes last.
    let text = stdout(&o);
    assert!(text.starts_with("{\"q_mm\":"), "{text}");
    assert!(text.trim_end().ends_with("]}") && text.contains(",\"available_force_n\":["));
}
