//! The profile keys of firmware, arcs, shaper, drive and the motors' electrical figures:
//! good values resolve, each bad one is an error naming the file, line, column and key.

use super::*;
use crate::motion::shaper::{AxisShaper, ShaperType};

const KOSSEL: &str = include_str!("../../tests/fixtures/profiles/kossel-rigid.yaml");

/// The test Kossel (tests/fixtures/profiles/kossel-rigid.yaml) without its `drive` (so the physical default applies), followed
/// by `extra`.
fn kossel_with(extra: &str) -> String {
    let mut out = String::new();
    let mut in_drive = false;
    for line in KOSSEL.lines() {
        if !line.starts_with([' ', '#']) {
            in_drive = line.starts_with("drive:");
        }
        if !in_drive {
            out.push_str(line);
            out.push('\n');
        }
    }
    out + extra
}

/// [`kossel_with`] with its `motors` section replaced by `motors`.
fn with_motors(motors: &str) -> String {
    let text = kossel_with("");
    let start = text.find("motors:").unwrap();
    let end = text.find("sampling:").unwrap();
    format!("{}motors:\n{motors}{}", &text[..start], &text[end..])
}

fn load(text: &str) -> Machine {
    Machine::from_yaml_str(text, "m.yaml").unwrap_or_else(|e| panic!("{e}\n{text}"))
}

/// The error of `text` holds `fragment` and is located on the first line that starts
/// (after its indent) with `on_line`, at a column.
fn assert_error(text: &str, fragment: &str, on_line: &str) {
    let e = Machine::from_yaml_str(text, "m.yaml")
        .unwrap_err()
        .to_string();
    assert!(e.contains(fragment), "{fragment:?} not in {e}");
    let line = text
        .lines()
        .position(|l| l.trim_start().starts_with(on_line.trim_start()))
        .unwrap_or_else(|| panic!("{on_line:?} not in the text"))
        + 1;
    assert!(
        e.starts_with(&format!("m.yaml:{line}:")),
        "{e} (line {line})"
    );
}

#[test]
fn gcode_arcs_resolution() {
    let m = load(&kossel_with(""));
    assert_eq!(m.arc_rules, ArcRules::Klipper { resolution_mm: 1.0 });
    let m = load(&kossel_with("gcode_arcs:\n  resolution: 0.25\n"));
    assert_eq!(
        m.arc_rules,
        ArcRules::Klipper {
            resolution_mm: 0.25
        }
    );
    for bad in ["0", "-1", ".nan", ".inf"] {
        let text = kossel_with(&format!("gcode_arcs: {{resolution: {bad}}}\n"));
        assert_error(
            &text,
            "gcode_arcs.resolution: expected a finite number > 0",
            "gcode_arcs",
        );
    }
    assert_error(
        &kossel_with("gcode_arcs:\n  resolutoin: 1\n"),
        "did you mean `resolution`?",
        "resolutoin",
    );
    assert_error(
        &kossel_with("gcode_arcs:\n  resolution: fine\n"),
        "gcode_arcs.resolution: invalid type",
        "resolution: fine",
    );
}

#[test]
fn input_shaper_keys_as_klipper_reads_them() {
    assert_eq!(load(&kossel_with("")).input_shaper, InputShaper::default());
    let text = kossel_with(
        "input_shaper:\n  shaper_type_x: mzv\n  shaper_freq_x: 40.2\n  shaper_type_y: ei\n  \
         shaper_freq_y: 45.6\n  damping_ratio_x: 0.05\n",
    );
    let s = load(&text).input_shaper;
    let axis = |kind, freq_hz, damping_ratio| {
        Some(AxisShaper {
            kind,
            freq_hz,
            damping_ratio,
        })
    };
    assert_eq!(s.x, axis(ShaperType::Mzv, 40.2, 0.05));
    assert_eq!(s.y, axis(ShaperType::Ei, 45.6, 0.1));
    // `shaper_type` sets both; an axis's own type wins; frequency 0 (the default) is off.
    let s = load(&kossel_with(
        "input_shaper:\n  shaper_type: 2HUMP_EI\n  shaper_type_y: zv\n  shaper_freq_x: 50\n  \
         shaper_freq_y: 0\n",
    ))
    .input_shaper;
    assert_eq!(s.x, axis(ShaperType::TwoHumpEi, 50.0, 0.1));
    assert_eq!(s.y, None);
    // Klipper's default type is mzv.
    let s = load(&kossel_with("input_shaper: {shaper_freq_y: 30}\n")).input_shaper;
    assert_eq!(s.y, axis(ShaperType::Mzv, 30.0, 0.1));
    // A damping ratio at the type's maximum is accepted (Klipper's maxval).
    let s = load(&kossel_with(
        "input_shaper: {shaper_type: 3hump_ei, shaper_freq_x: 60, damping_ratio_x: 0.2}\n",
    ))
    .input_shaper;
    assert_eq!(s.x, axis(ShaperType::ThreeHumpEi, 60.0, 0.2));
}

#[test]
fn input_shaper_errors() {
    let cases = [
        (
            "input_shaper:\n  shaper_type_x: mvz\n  shaper_freq_x: 40\n",
            "input_shaper.shaper_type_x: unknown shaper type `mvz` (did you mean `mzv`?)",
            "shaper_type_x",
        ),
        // Klipper checks the type even of an axis left unshaped.
        (
            "input_shaper:\n  shaper_type: spline\n",
            "input_shaper.shaper_type: unknown shaper type `spline`, expected one of zv, mzv",
            "shaper_type",
        ),
        (
            "input_shaper:\n  shaper_type: ei\n  damping_ratio_y: 0.5\n",
            "input_shaper.damping_ratio_y: 0.5 is above 0.4",
            "damping_ratio_y",
        ),
        (
            "input_shaper:\n  shaper_type_x: 2hump_ei\n  damping_ratio_x: 0.31\n",
            "above 0.3, the most Klipper accepts for shaper `2hump_ei`",
            "damping_ratio_x",
        ),
        (
            "input_shaper:\n  damping_ratio_x: -0.1\n",
            "input_shaper.damping_ratio_x: expected a finite number >= 0",
            "damping_ratio_x",
        ),
        (
            "input_shaper: {shaper_freq_x: -40}\n",
            "input_shaper.shaper_freq_x: expected a finite number >= 0",
            "input_shaper",
        ),
        (
            "input_shaper:\n  shaper_freq: 40\n",
            "unknown field `shaper_freq`",
            "shaper_freq",
        ),
    ];
    for (extra, fragment, on_line) in cases {
        assert_error(&kossel_with(extra), fragment, on_line);
    }
}

#[test]
fn drive_rigid_or_a_spring() {
    assert_eq!(load(&kossel_with("drive: rigid\n")).drive, Drive::Rigid);
    let m = load(&kossel_with(
        "drive:\n  frequency_hz: 60\n  damping_ratio: 0.05\n",
    ));
    let spring = |frequency_hz, damping_ratio| {
        Drive::Spring(crate::motion::drive::Spring {
            frequency_hz,
            damping_ratio,
        })
    };
    assert_eq!(m.drive, spring(60.0, 0.05));
    assert_eq!(m.drive_default, None);
    // Damping 0.1 when left out.
    let m = load(&kossel_with("drive: {frequency_hz: 45}\n"));
    assert_eq!(m.drive, spring(45.0, 0.1));
    let cases = [
        (
            "drive: stiff\n",
            "drive: invalid value: string \"stiff\", expected `rigid`",
        ),
        ("drive: [60]\n", "drive: invalid type: sequence"),
        (
            "drive: {frequency_hz: 0}\n",
            "drive.frequency_hz: expected a finite number > 0",
        ),
        (
            "drive: {frequency_hz: .nan}\n",
            "drive.frequency_hz: expected a finite",
        ),
        (
            "drive: {frequency_hz: 60, damping_ratio: 1.0}\n",
            "drive.damping_ratio: expected a number in [0, 1), found 1: the drive's response \
             is computed in closed form for an underdamped spring",
        ),
        (
            "drive: {frequency_hz: 60, damping_ratio: -0.1}\n",
            "drive.damping_ratio",
        ),
        (
            "drive: {frequency_hz: 60, damping: 0.1}\n",
            "unknown field `damping`",
        ),
        (
            "drive: {damping_ratio: 0.1}\n",
            "drive: missing field `frequency_hz`",
        ),
    ];
    for (extra, fragment) in cases {
        assert_error(&kossel_with(extra), fragment, "drive");
    }
}

#[test]
fn firmware_and_marlin_defaults() {
    let m = load(&kossel_with(""));
    assert_eq!(m.firmware, Firmware::Klipper);
    assert_eq!(
        load(&kossel_with("firmware: klipper\n")).firmware,
        Firmware::Klipper
    );
    let Firmware::Marlin(marlin) = load(&kossel_with("firmware: marlin\n")).firmware else {
        panic!("marlin");
    };
    // Marlin's config/default, the towers at its X figures.
    assert_eq!(marlin.steps_per_mm, 80.0);
    assert_eq!(marlin.e_steps_per_mm, 500.0);
    assert_eq!(marlin.segments_per_second, 200.0);
    assert_eq!(marlin.max_feedrate_mm_s, [300.0, 300.0, 300.0, 25.0]);
    assert_eq!(marlin.max_accel_mm_s2, [3000.0, 3000.0, 3000.0, 10000.0]);
    assert_eq!(marlin.print_accel_mm_s2, 3000.0);
    assert_eq!(marlin.retract_accel_mm_s2, 3000.0);
    assert_eq!(marlin.travel_accel_mm_s2, 3000.0);
    assert_eq!(marlin.jerk_mm_s, [10.0, 10.0, 10.0, 5.0]);
    assert!(!marlin.s_curve);
    assert_eq!(marlin.block_buffer_size, 16);
    assert_eq!(marlin.min_steps_per_segment, 6);
    assert_eq!(marlin.min_segment_time_us, 20000);
    assert_eq!(marlin.minimum_planner_speed_mm_s, 0.05);
    // The FLSUN Q5's Marlin example (Configurations 2.1.2.4, Q5-nano_v1).
    let text = kossel_with(
        "firmware: marlin\nmarlin:\n  e_steps_per_mm: 428\n  max_feedrate_mm_s: [200, 200, 200, 200]\n  \
         max_accel_mm_s2: [1000, 1000, 1000, 1000]\n  print_accel_mm_s2: 1000\n  \
         retract_accel_mm_s2: 1000\n  travel_accel_mm_s2: 1000\n  s_curve: true\n  \
         block_buffer_size: 64\n  min_steps_per_segment: 1\n",
    );
    let Firmware::Marlin(q5) = load(&text).firmware else {
        panic!("marlin");
    };
    assert_eq!(q5.e_steps_per_mm, 428.0);
    assert_eq!(q5.max_accel_mm_s2, [1000.0; 4]);
    assert!(q5.s_curve);
    assert_eq!(q5.block_buffer_size, 64);
    assert_eq!(q5.min_steps_per_segment, 1);
    assert_eq!(q5.steps_per_mm, 80.0);
}

#[test]
fn firmware_errors() {
    assert_error(
        &kossel_with("firmware: repetier\n"),
        "firmware: unknown variant `repetier`, expected `klipper` or `marlin`",
        "firmware",
    );
    assert_error(
        &kossel_with("marlin:\n  steps_per_mm: 80\n"),
        "marlin: Marlin's settings are used only with `firmware: marlin`",
        "marlin:",
    );
    assert_error(
        &kossel_with("firmware: klipper\nmarlin: {}\n"),
        "used only with `firmware: marlin`",
        "marlin:",
    );
    let cases = [
        (
            "steps_per_mm: 0",
            "marlin.steps_per_mm: expected a finite number > 0",
        ),
        (
            "e_steps_per_mm: -93",
            "marlin.e_steps_per_mm: expected a finite number > 0",
        ),
        ("segments_per_second: 0", "marlin.segments_per_second"),
        (
            "max_feedrate_mm_s: [300, 300, 0, 25]",
            "marlin.max_feedrate_mm_s: expected",
        ),
        (
            "max_feedrate_mm_s: [300, 300, 300]",
            "marlin.max_feedrate_mm_s: invalid length 3",
        ),
        (
            "max_accel_mm_s2: [3000, 3000, 3000, -1]",
            "marlin.max_accel_mm_s2: expected",
        ),
        ("print_accel_mm_s2: 0", "marlin.print_accel_mm_s2"),
        ("retract_accel_mm_s2: .nan", "marlin.retract_accel_mm_s2"),
        ("travel_accel_mm_s2: -3000", "marlin.travel_accel_mm_s2"),
        (
            "jerk_mm_s: [10, 10, -1, 5]",
            "marlin.jerk_mm_s: expected a finite number >= 0",
        ),
        ("s_curve: maybe", "marlin.s_curve: invalid type"),
        (
            "block_buffer_size: 12",
            "marlin.block_buffer_size: expected a power of 2 up to 64",
        ),
        ("block_buffer_size: 128", "marlin.block_buffer_size"),
        (
            "block_buffer_size: 16.5",
            "marlin.block_buffer_size: invalid type",
        ),
        (
            "min_steps_per_segment: 0",
            "marlin.min_steps_per_segment: expected at least 1",
        ),
        ("min_segment_time_us: -1", "marlin.min_segment_time_us"),
        (
            "minimum_planner_speed_mm_s: -0.05",
            "marlin.minimum_planner_speed_mm_s",
        ),
        ("jerk_mm: [10, 10, 10, 5]", "did you mean `jerk_mm_s`?"),
    ];
    for (line, fragment) in cases {
        let text = kossel_with(&format!("firmware: marlin\nmarlin:\n  {line}\n"));
        let e = Machine::from_yaml_str(&text, "m.yaml")
            .unwrap_err()
            .to_string();
        assert!(e.contains(fragment), "{fragment:?} not in {e}");
        // The key's line is the one after `marlin:`.
        let at = text.lines().position(|l| l == "marlin:").unwrap() + 2;
        assert!(e.starts_with(&format!("m.yaml:{at}:")), "{e} (line {at})");
    }
}

#[test]
fn motor_model_fills_the_motor_and_keys_override_it() {
    // LDO-42STH48-2004AC on rotation_distance 40 (r = 6.366198 mm): 0.59 / r = 92.6770 N;
    // its rotor, 68 g·cm², reflects 6.8e-6 / r² = 0.167783 kg; its stiffness at the belt
    // 0.59 × 50 / r² = 727 883 N/m.
    let m = load(&with_motors(
        "  model: LDO-42STH48-2004AC\n  rotation_distance_mm: 40\n  safety_factor: 1\n",
    ));
    let motors = &m.motors;
    assert_eq!(motors.model, Some("ldo-42sth48-2004ac"));
    assert!((motors.max_force_n - 92.676_98).abs() < 1e-4);
    assert!((motors.reflected_mass_kg - 0.167_783).abs() < 1e-6);
    assert!((motors.stiffness_n_m.unwrap() - 727_883.3).abs() < 0.1);
    assert_eq!(motors.curve, None);
    assert_eq!(motors.available_force_n(1e4), motors.max_force_n);
    // The same on pulley_teeth 20 (GT2), with the torque and the rotor given instead.
    let m = load(&with_motors(
        "  model: ldo-42sth48-2004ac\n  holding_torque_nm: 0.4\n  pulley_teeth: 20\n  \
         safety_factor: 2\n  rotor_inertia_kg_m2: 0\n",
    ));
    assert!((m.motors.max_force_n - 0.4 / 0.006_366_198 / 2.0).abs() < 1e-4);
    assert_eq!(m.motors.reflected_mass_kg, 0.0);
    // A 0.9° motor is twice as stiff for the same torque (N_r = 100).
    let m = load(&with_motors(
        "  model: ldo-42sth48-2004mac\n  rotation_distance_mm: 40\n  safety_factor: 1\n",
    ));
    let k = 0.49 * 100.0 / (0.04 / std::f64::consts::TAU).powi(2);
    assert!((m.motors.stiffness_n_m.unwrap() / k - 1.0).abs() < 1e-12);
}

#[test]
fn motor_curve_from_the_profile_matches_the_hand_computation() {
    // The colleague's case (src/motor.rs): 55.6062 N to 433.76 mm/s, 43.3922 N at 500.
    let ldo = "  model: ldo-42sth48-2004ac\n  rotation_distance_mm: 40\n  safety_factor: 1\n  \
               run_current_a: 1.2\n  supply_voltage_v: 24\n";
    let m = load(&with_motors(ldo));
    let c = m.motors.curve.expect("a curve");
    assert!((m.motors.max_force_n - 55.6062).abs() < 5e-5);
    assert!((m.motors.available_force_n(-300.0) - 55.6062).abs() < 5e-5);
    assert!((m.motors.available_force_n(500.0) - 43.3922).abs() < 5e-5);
    assert!((c.knee_speed_mm_s() - 433.76).abs() < 5e-3);
    // The same motor given figure by figure, on a 20-tooth GT2 pulley.
    let by_hand = load(&with_motors(
        "  holding_torque_nm: 0.59\n  rated_current_a: 2.0\n  run_current_a: 1.2\n  \
         resistance_ohm: 1.4\n  inductance_mh: 3.0\n  supply_voltage_v: 24\n  \
         step_angle_deg: 1.8\n  pulley_teeth: 20\n  safety_factor: 1\n",
    ));
    assert_eq!(
        by_hand.motors.curve.map(|c| c.knee_speed_mm_s()),
        Some(c.knee_speed_mm_s())
    );
    assert_eq!(by_hand.motors.reflected_mass_kg, 0.0);
    // Run current without the voltage: the standstill torque scales, 0.59 × 1.2/2.0.
    let m = load(&with_motors(
        "  model: ldo-42sth48-2004ac\n  rotation_distance_mm: 40\n  safety_factor: 1\n  \
         run_current_a: 1.2\n",
    ));
    assert!((m.motors.max_force_n - 55.6062).abs() < 5e-5);
    assert_eq!(m.motors.curve, None);
    // An explicit resistance overrides the model's: R = 1.6 Ω gives 42.6395 N at 500 mm/s.
    let m = load(&with_motors(&format!("{ldo}  resistance_ohm: 1.6\n")));
    assert!((m.motors.available_force_n(500.0) - 42.6395).abs() < 5e-4);
}

#[test]
fn motor_errors_name_the_key_and_its_line() {
    let torque = "  holding_torque_nm: 0.4\n  rotation_distance_mm: 40\n  safety_factor: 1\n";
    let cases = [
        (
            "  model: ldo-42sth48-2004a\n  rotation_distance_mm: 40\n  safety_factor: 1\n"
                .to_string(),
            "motors.model: unknown motor `ldo-42sth48-2004a` (did you mean \
             `ldo-42sth48-2004ac`?); the table has",
            "model",
        ),
        (
            "  model: ldo-42sth48-2004ac\n  rotation_distance_mm: 40\n".to_string(),
            "motors.model: needs `safety_factor`",
            "model",
        ),
        (
            "  model: ldo-42sth48-2004ac\n  safety_factor: 1\n".to_string(),
            "motors.model: needs `pulley_teeth`",
            "model",
        ),
        (
            "  max_force_n: 30\n  model: ldo-42sth48-2004ac\n".to_string(),
            "motors: expected either `max_force_n` alone",
            "motors:",
        ),
        (
            format!("{torque}  pulley_teeth: 20\n"),
            "motors.rotation_distance_mm: expected either `pulley_teeth`",
            "rotation_distance_mm",
        ),
        (
            "  holding_torque_nm: 0.4\n  rotation_distance_mm: 0\n  safety_factor: 1\n".to_string(),
            "motors.rotation_distance_mm: expected a finite number > 0",
            "rotation_distance_mm",
        ),
        (
            "  max_force_n: 30\n  rotation_distance_mm: 40\n".to_string(),
            "motors.rotation_distance_mm: used only with",
            "rotation_distance_mm",
        ),
        (
            "  max_force_n: 30\n  run_current_a: 1\n".to_string(),
            "motors.run_current_a: used only with the torque form",
            "run_current_a",
        ),
        (
            "  max_force_n: 30\n  step_angle_deg: 0.9\n".to_string(),
            "motors.step_angle_deg: used only with the torque form",
            "step_angle_deg",
        ),
        (
            format!("{torque}  step_angle_deg: 0\n"),
            "motors.step_angle_deg: expected a finite number > 0",
            "step_angle_deg",
        ),
        (
            format!("{torque}  run_current_a: 1\n"),
            "motors.run_current_a: needs `rated_current_a`",
            "run_current_a",
        ),
        (
            format!("{torque}  rated_current_a: 1\n  run_current_a: 1.2\n"),
            "motors.run_current_a: 1.2 A RMS is above the rated 1 A",
            "run_current_a",
        ),
        (
            format!("{torque}  rated_current_a: 1\n  run_current_a: -1\n"),
            "motors.run_current_a: expected a finite number > 0",
            "run_current_a",
        ),
        (
            format!("{torque}  rated_current_a: 0\n  run_current_a: 1\n"),
            "motors.rated_current_a: expected a finite number > 0",
            "rated_current_a",
        ),
        (
            format!("{torque}  rated_current_a: 1\n"),
            "motors.rated_current_a: used only with `run_current_a`",
            "rated_current_a",
        ),
        (
            format!("{torque}  resistance_ohm: 1.4\n"),
            "motors.resistance_ohm: used only with `supply_voltage_v`",
            "resistance_ohm",
        ),
        (
            format!("{torque}  inductance_mh: 3\n"),
            "motors.inductance_mh: used only with `supply_voltage_v`",
            "inductance_mh",
        ),
        (
            format!("{torque}  supply_voltage_v: 24\n"),
            "motors.supply_voltage_v: needs `run_current_a`",
            "supply_voltage_v",
        ),
        (
            format!(
                "{torque}  rated_current_a: 2\n  run_current_a: 1\n  resistance_ohm: 1.4\n  \
                 supply_voltage_v: 24\n"
            ),
            "motors.supply_voltage_v: needs `inductance_mh`",
            "supply_voltage_v",
        ),
        (
            "  model: motionking-17hs4401\n  rotation_distance_mm: 40\n  safety_factor: 1\n  \
             run_current_a: 1\n  supply_voltage_v: 0\n"
                .to_string(),
            "motors.supply_voltage_v: expected a finite number > 0",
            "supply_voltage_v",
        ),
        (
            "  model: motionking-17hs4401\n  rotation_distance_mm: 40\n  safety_factor: 1\n  \
             run_current_a: 1\n  supply_voltage_v: 24\n  resistance_ohm: 0\n"
                .to_string(),
            "motors.resistance_ohm: expected a finite number > 0",
            "resistance_ohm",
        ),
        (
            "  model: motionking-17hs4401\n  rotation_distance_mm: 40\n  safety_factor: 1\n  \
             run_current_a: 1\n  supply_voltage_v: 24\n  inductance_mh: -3\n"
                .to_string(),
            "motors.inductance_mh: expected a finite number >= 0",
            "inductance_mh",
        ),
        (
            format!("{torque}  suply_voltage_v: 24\n"),
            "did you mean `supply_voltage_v`?",
            "suply_voltage_v",
        ),
    ];
    for (motors, fragment, on_line) in cases {
        let text = with_motors(&motors);
        // The motors section's own line for `motors:`, else the key's line below it.
        let on = if on_line == "motors:" {
            "motors:".to_string()
        } else {
            format!("  {on_line}")
        };
        assert_error(&text, fragment, &on);
    }
}

#[test]
fn default_drive_of_the_kossel_by_hand() {
    // The test Kossel's figures without `drive`, its motor in the torque form
    // (0.4 N·m, 1.8°, GT2 20T; cart 0.22 kg with the rotor folded in, link 0.012 kg,
    // platform 0.10 kg, delta radius 105, arms 215, home z 290):
    //   r = 40 mm / 2π = 6.366198 mm; N_r = 360/(4·1.8) = 50;
    //   k_m = T·N_r/r² = 0.4·50/6.366198e-3² = 493 480.2 N/m;
    //   k_b = E·A/L = 19 400 N / 0.290 m = 66 896.55 N/m (belt = travel bed centre → home);
    //   k = 1/(1/k_m + 1/k_b) = 58 910.59 N/m per carriage.
    //   At the bed centre J = ∂q/∂x has rows (R cos θ_i/s, R sin θ_i/s, 1),
    //   s = √(215² − 105²) = 187.6166 mm, (R/s)² = 11025/35200 = 0.3132102; over the
    //   towers at 210/330/90°, Σ cos²θ = 3/2 and the cross terms vanish, so along X
    //   M = m_plat + 3 m_link + (3/2)(R/s)²(m_cart + m_link)
    //     = 0.136 + 0.4698153·0.232 = 0.2449972 kg,
    //   K = (3/2)(R/s)² k = 0.4698153·58 910.59 = 27 677.10 N/m,
    //   f = √(K/M)/2π = √112 969.9/2π = 53.4934 Hz.
    let text = with_motors("  holding_torque_nm: 0.4\n  pulley_teeth: 20\n  safety_factor: 2.5\n");
    let m = load(&text);
    let d = m.drive_default.expect("the default drive");
    assert!(!d.typical_motor);
    assert!((d.motor_stiffness_n_m - 493_480.2).abs() < 0.1);
    assert!((d.belt_stiffness_n_m - 66_896.55).abs() < 0.01);
    assert!((d.carriage_stiffness_n_m - 58_910.59).abs() < 0.01);
    assert!((d.mass_kg - 0.244_997_2).abs() < 1e-7);
    assert!((d.stiffness_n_m - 27_677.10).abs() < 0.01);
    assert!((d.spring.frequency_hz - 53.4934).abs() < 1e-4);
    assert_eq!(d.spring.damping_ratio, 0.1);
    assert_eq!(m.drive, Drive::Spring(d.spring));
    // The force form: the typical motor (0.40 N·m on GT2 20T), so the same figures here.
    let typical = load(&with_motors("  max_force_n: 25\n"));
    let t = typical.drive_default.unwrap();
    assert!(t.typical_motor);
    assert_eq!(t.motor_stiffness_n_m, typical_motor_stiffness_n_m());
    assert!((t.spring.frequency_hz - 53.4934).abs() < 1e-4);
    // A heavier platform lowers the frequency; a given drive has no default.
    let heavy = load(&text.replace("platform_kg: 0.10", "platform_kg: 0.50"));
    assert!(heavy.drive_default.unwrap().spring.frequency_hz < 40.0);
    assert_eq!(load(&kossel_with("drive: rigid\n")).drive_default, None);
}

#[test]
fn default_drive_follows_the_x_mode_of_an_asymmetric_delta() {
    // Unequal arms and rotated towers couple the axes: the frequency is still that of
    // a mode (K φ = λ M φ), the one most along X, and between the extreme eigenvalues.
    let text = with_motors("  max_force_n: 25\n")
        .replace("arm_length_mm: 215.0", "arm_length_mm: [215, 230, 220]")
        .replace(
            "home_z_mm: 290.0",
            "home_z_mm: 290.0\n  tower_angles_deg: [200, 335, 95]",
        );
    let m = load(&text);
    let d = m.drive_default.unwrap();
    let jac = m.jacobian_at_bed_centre().unwrap();
    let masses = &m.masses;
    let mass = nalgebra::Matrix3::identity() * (masses.platform_kg + 3.0 * masses.link_kg)
        + jac.transpose() * jac * (masses.cart_kg + masses.link_kg);
    let stiffness = jac.transpose() * jac * d.carriage_stiffness_n_m;
    let lambda = (d.spring.frequency_hz * std::f64::consts::TAU).powi(2);
    // det(K − λM) = 0 at an eigenvalue.
    let det = (stiffness - mass * lambda).determinant();
    assert!(det.abs() < 1e-6 * stiffness.determinant().abs(), "{det}");
}

#[test]
fn flow_mappings_are_located_at_their_key() {
    let text = kossel_with("input_shaper: {shaper_type: ei, damping_ratio_x: 0.9}\n");
    let e = Machine::from_yaml_str(&text, "m.yaml")
        .unwrap_err()
        .to_string();
    let line = text
        .lines()
        .position(|l| l.starts_with("input_shaper"))
        .unwrap()
        + 1;
    let col = "input_shaper: {shaper_type: ei, ".len() + 1;
    assert!(e.starts_with(&format!("m.yaml:{line}:{col}:")), "{e}");
    // A key left out is placed at its section.
    let text = kossel_with("input_shaper:\n  shaper_type: ei\n");
    let text = text.replace(
        "shaper_type: ei",
        "shaper_type: ei\n  # damping_ratio_x: 0.9",
    );
    assert_eq!(
        location::locate_key(&text, "input_shaper.damping_ratio_x"),
        text.lines()
            .position(|l| l.starts_with("input_shaper"))
            .map(|l| (l + 1, 1))
    );
}

#[test]
fn shipped_drives_are_the_documented_derivation() {
    // Each shipped spring is the default of its own figures, rounded to 0.01 Hz (the QQ-S's
    // with its 16-tooth pulley, which its `max_force_n` form does not carry).
    let profiles = [
        (
            include_str!("../../machines/anycubic-kossel-linear-plus.yaml"),
            None,
        ),
        (
            include_str!("../../machines/anycubic-kossel-linear-plus-klipper.yaml"),
            None,
        ),
        (include_str!("../../machines/flsun-q5.yaml"), None),
        (include_str!("../../machines/flsun-q5-klipper.yaml"), None),
        (
            include_str!("../../machines/flsun-qqs-pro.yaml"),
            Some((
                "  max_force_n: 39.0",
                "  holding_torque_nm: 0.4\n  pulley_teeth: 16\n  safety_factor: 2",
            )),
        ),
        (include_str!("../../machines/rostock-max-v3.yaml"), None),
    ];
    for (text, swap) in profiles {
        let shipped = load(text);
        let Drive::Spring(given) = shipped.drive else {
            panic!("{}: not a spring", shipped.name);
        };
        assert_eq!(given.damping_ratio, 0.1);
        let mut bare: String = text
            .lines()
            .filter(|l| !l.starts_with("drive:"))
            .map(|l| format!("{l}\n"))
            .collect();
        if let Some((from, to)) = swap {
            bare = bare.replace(from, to);
        }
        let derived = load(&bare).drive_default.unwrap().spring;
        assert!(
            (derived.frequency_hz - given.frequency_hz).abs() < 0.006,
            "{}: {} vs {}",
            shipped.name,
            derived.frequency_hz,
            given.frequency_hz
        );
    }
}
