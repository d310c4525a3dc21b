use super::defaults::klipper_reach_mm;
use super::location::edit_distance;
use super::*;
use crate::path::Vec3;

const KOSSEL: &str = include_str!("../../tests/fixtures/profiles/kossel-rigid.yaml");

fn error_of(text: &str) -> String {
    Machine::from_yaml_str(text, "m.yaml")
        .unwrap_err()
        .to_string()
}

#[test]
fn the_shipped_profiles_load_with_klipper_defaults() {
    let m = Machine::from_yaml_str(KOSSEL, "kossel.yaml").unwrap();
    assert_eq!(m.limits.max_z_velocity_mm_s, 300.0);
    assert_eq!(m.limits.max_z_accel_mm_s2, 3000.0);
    // Klipper extruder.py: 300 · 4·0.4² / (π·1.75²/4) = 79.824 mm/s, ×10 for accel.
    assert!((m.extruder.max_extrude_only_velocity_mm_s - 79.824_324).abs() < 1e-5);
    assert!((m.extruder.max_extrude_only_accel_mm_s2 - 798.243_24).abs() < 1e-4);
    assert_eq!(m.geometry.tower_angles_deg, [210.0, 330.0, 90.0]);
    assert_eq!(m.gravity_m_s2, 9.81);
    assert_eq!(m.geometry.arm_length_mm, [215.0; 3]);
    let paper = Machine::from_yaml_str(include_str!("../../machines/paper.yaml"), "p").unwrap();
    assert_eq!(paper.masses.platform_kg, 0.5);
}

#[test]
fn minimal_profile_fills_every_default() {
    let text = "name: x
geometry: {delta_radius_mm: 100, arm_length_mm: [200, 201, 202], home_z_mm: 250, print_radius_mm: 80}
masses: {cart_kg: 0.2, link_kg: 0.01, platform_kg: 0.1}
limits: {max_velocity_mm_s: 200, max_accel_mm_s2: 2000}
motors: {max_force_n: 20}
";
    let m = Machine::from_yaml_str(text, "x").unwrap();
    assert_eq!(m.geometry.arm_length_mm, [200.0, 201.0, 202.0]);
    assert_eq!(m.geometry.nozzle_offset_mm, 0.0);
    assert_eq!(m.limits.square_corner_velocity_mm_s, 5.0);
    assert_eq!(m.limits.minimum_cruise_ratio, 0.5);
    assert!(m.limits.edge_slowdown);
    assert_eq!(m.extruder.nozzle_diameter_mm, 0.4);
    assert_eq!(m.extruder.filament_diameter_mm, 1.75);
    assert_eq!(m.extruder.instantaneous_corner_velocity_mm_s, 1.0);
    assert_eq!(m.sampling.period_s, 0.001);
}

#[test]
fn base_and_platform_sides_give_the_delta_radius() {
    let text = KOSSEL.replace(
        "delta_radius_mm: 105.0",
        "base_side_mm: 250.0\n  platform_side_mm: 68.1347",
    );
    let m = Machine::from_yaml_str(&text, "k").unwrap();
    // (250 − 68.1347)/√3
    assert!((m.geometry.delta_radius_mm - 105.0).abs() < 1e-4);
    let both = KOSSEL.replace(
        "delta_radius_mm: 105.0",
        "delta_radius_mm: 105\n  base_side_mm: 250",
    );
    assert!(error_of(&both).contains("not a mix"));
    let neither = KOSSEL.replace("delta_radius_mm: 105.0", "");
    assert!(error_of(&neither).contains("expected `delta_radius_mm`"));
}

#[test]
fn unknown_key_names_file_line_and_the_closest_name() {
    let e = error_of(&KOSSEL.replace("delta_radius_mm:", "delta_radus_mm:"));
    assert!(e.starts_with("m.yaml:7:"), "{e}");
    assert!(e.contains("unknown field `delta_radus_mm`"), "{e}");
    assert!(e.contains("did you mean `delta_radius_mm`?"), "{e}");
    // Nothing close: no suggestion.
    let e = error_of(&KOSSEL.replace("  edge_slowdown: true", "  zzz: 1"));
    assert!(
        e.contains("unknown field `zzz`") && !e.contains("did you mean"),
        "{e}"
    );
}

#[test]
fn wrong_type_and_missing_key_are_located() {
    let e = error_of(&KOSSEL.replace("cart_kg: 0.22", "cart_kg: heavy"));
    assert!(
        e.contains("masses.cart_kg") && e.contains("expected a number"),
        "{e}"
    );
    assert!(e.starts_with("m.yaml:"), "{e}");
    let e = error_of(&KOSSEL.replace("  home_z_mm: 290.0", ""));
    assert!(e.contains("missing field `home_z_mm`"), "{e}");
    let e = error_of(&KOSSEL.replace("arm_length_mm: 215.0", "arm_length_mm: [215, 215]"));
    assert!(e.contains("list of 3 lengths"), "{e}");
}

#[test]
fn impossible_machines_are_rejected_with_the_key() {
    let cases = [
        (
            "arm_length_mm: 215.0",
            "arm_length_mm: 180",
            "geometry.arm_length_mm",
        ),
        ("home_z_mm: 290.0", "home_z_mm: -1", "geometry.home_z_mm"),
        ("cart_kg: 0.22", "cart_kg: 0", "masses.cart_kg"),
        ("max_force_n: 25.0", "max_force_n: -5", "motors.max_force_n"),
        ("period_s: 0.001", "period_s: 0", "sampling.period_s"),
        (
            "max_accel_mm_s2: 3000",
            "max_accel_mm_s2: .nan",
            "limits.max_accel_mm_s2",
        ),
        (
            "minimum_cruise_ratio: 0.5",
            "minimum_cruise_ratio: 1.5",
            "limits.minimum_cruise_ratio",
        ),
    ];
    for (from, to, key) in cases {
        let text = KOSSEL.replace(from, to);
        assert_ne!(text, KOSSEL, "{from}");
        let e = error_of(&text);
        assert!(e.contains(key), "{e}");
        // Located at the key's line.
        let line = text
            .lines()
            .position(|l| l.trim_start().starts_with(to))
            .unwrap()
            + 1;
        assert!(
            e.starts_with(&format!("m.yaml:{line}:")),
            "{e} (line {line})"
        );
    }
}

/// KOSSEL with its `motors` section replaced.
fn with_motors(motors: &str) -> String {
    let start = KOSSEL.find("motors:").unwrap();
    let end = KOSSEL.find("sampling:").unwrap();
    format!("{}motors:\n{motors}{}", &KOSSEL[..start], &KOSSEL[end..])
}

#[test]
fn motor_torque_form_gives_the_force_and_the_rotor_its_reflected_mass() {
    // GT2 20T: pitch circle 40 mm, r = 40/(2π) = 6.366 mm. 0.4 N·m / r / 2 = 10π N.
    // NEMA 17 rotor 54 g·cm² = 5.4e-6 kg·m²: J/r² = 5.4e-6 · (2π/0.04)² = 0.133240 kg.
    let text = with_motors(
        "  holding_torque_nm: 0.4\n  pulley_teeth: 20\n  safety_factor: 2.0\n  \
         rotor_inertia_kg_m2: 5.4e-6\n",
    );
    let m = Machine::from_yaml_str(&text, "m").unwrap();
    assert!((m.motors.max_force_n - 31.415_926_5).abs() < 1e-6);
    assert!((m.motors.reflected_mass_kg - 0.133_240).abs() < 1e-6);
    // HTD3 16T, pitch 3 mm: r = 48/(2π) = 7.639 mm; 1.2 N·m / r / 3 = 52.36 N.
    let text = with_motors(
        "  holding_torque_nm: 1.2\n  pulley_teeth: 16\n  belt_pitch_mm: 3\n  \
         safety_factor: 3\n",
    );
    let m = Machine::from_yaml_str(&text, "m").unwrap();
    assert!((m.motors.max_force_n - 52.359_878).abs() < 1e-5);
    assert_eq!(m.motors.reflected_mass_kg, 0.0);
    // The force form with a rotor: the pulley is needed for J/r² only.
    let text =
        with_motors("  max_force_n: 25\n  pulley_teeth: 20\n  rotor_inertia_kg_m2: 5.4e-6\n");
    let m = Machine::from_yaml_str(&text, "m").unwrap();
    assert_eq!(m.motors.max_force_n, 25.0);
    assert!((m.motors.reflected_mass_kg - 0.133_240).abs() < 1e-6);
    // The shipped profiles have no rotor term.
    let k = Machine::from_yaml_str(KOSSEL, "k").unwrap();
    assert_eq!(k.motors.reflected_mass_kg, 0.0);
}

#[test]
fn motor_form_errors_name_the_key_and_its_line() {
    // (motors section, key in the message, text on the reported line)
    let cases = [
        (
            "  max_force_n: 25\n  holding_torque_nm: 0.4\n  safety_factor: 2\n",
            "motors: expected either `max_force_n` alone",
            "motors:",
        ),
        (
            "  pulley_teeth: 20\n",
            "motors: expected `max_force_n`",
            "motors:",
        ),
        (
            "  holding_torque_nm: 0.4\n  pulley_teeth: 20\n",
            "motors.holding_torque_nm: needs `safety_factor`",
            "  holding_torque_nm",
        ),
        (
            "  max_force_n: 25\n  safety_factor: 2\n",
            "motors: expected either",
            "motors:",
        ),
        (
            "  holding_torque_nm: 0.4\n  safety_factor: 2\n",
            "motors.holding_torque_nm: needs `pulley_teeth`",
            "  holding_torque_nm",
        ),
        (
            "  holding_torque_nm: 0.4\n  pulley_teeth: 20\n  safety_factor: 0.5\n",
            "motors.safety_factor: expected a finite number >= 1",
            "  safety_factor",
        ),
        (
            "  holding_torque_nm: -0.4\n  pulley_teeth: 20\n  safety_factor: 2\n",
            "motors.holding_torque_nm: expected a finite number > 0",
            "  holding_torque_nm",
        ),
        (
            "  holding_torque_nm: 0.4\n  pulley_teeth: 0\n  safety_factor: 2\n",
            "motors.pulley_teeth: expected at least 1",
            "  pulley_teeth",
        ),
        (
            "  max_force_n: 25\n  pulley_teeth: 20\n  belt_pitch_mm: 0\n  \
             rotor_inertia_kg_m2: 1e-6\n",
            "motors.belt_pitch_mm: expected a finite number > 0",
            "  belt_pitch_mm",
        ),
        (
            "  max_force_n: 25\n  belt_pitch_mm: 2\n",
            "motors.belt_pitch_mm: given without `pulley_teeth`",
            "  belt_pitch_mm",
        ),
        (
            "  max_force_n: 25\n  rotor_inertia_kg_m2: 5.4e-6\n",
            "motors.rotor_inertia_kg_m2: needs `pulley_teeth`",
            "  rotor_inertia_kg_m2",
        ),
        (
            "  max_force_n: 25\n  pulley_teeth: 20\n  rotor_inertia_kg_m2: -1\n",
            "motors.rotor_inertia_kg_m2: expected a finite number >= 0",
            "  rotor_inertia_kg_m2",
        ),
        (
            "  max_force_n: 25\n  pulley_teeth: 20\n",
            "motors.pulley_teeth: used only with",
            "  pulley_teeth",
        ),
    ];
    for (motors, message, on_line) in cases {
        let text = with_motors(motors);
        let e = error_of(&text);
        assert!(e.contains(message), "{e}");
        let line = text.lines().position(|l| l.starts_with(on_line)).unwrap() + 1;
        assert!(
            e.starts_with(&format!("m.yaml:{line}:")),
            "{e} (line {line})"
        );
    }
    // A fractional tooth count is a schema error at its line.
    let e = error_of(&with_motors(
        "  holding_torque_nm: 0.4\n  pulley_teeth: 20.5\n  safety_factor: 2\n",
    ));
    assert!(e.contains("motors.pulley_teeth"), "{e}");
}

/// The paper's machine with and without a rotor of reflected mass 0.13324 kg.
fn paper_models() -> (DeltaModel, DeltaModel, f64) {
    let paper = include_str!("../../machines/paper.yaml");
    let plain = Machine::from_yaml_str(paper, "p").unwrap();
    let rotor = paper.replace(
        "max_force_n: 40.0",
        "max_force_n: 40.0\n  pulley_teeth: 20\n  rotor_inertia_kg_m2: 5.4e-6",
    );
    let rotor = Machine::from_yaml_str(&rotor, "p").unwrap();
    let m_r = rotor.motors.reflected_mass_kg;
    assert!(m_r > 0.13);
    (plain.model(), rotor.model(), m_r)
}

#[test]
fn the_rotor_adds_inertia_to_the_carriage_but_no_weight() {
    let (plain, rotor, m_r) = paper_models();
    let states = [
        (Vec3::new(0.0, 0.0, 0.0), Vec3::zeros(), Vec3::zeros()),
        (Vec3::new(40.0, -20.0, 10.0), Vec3::zeros(), Vec3::zeros()),
        (
            Vec3::new(40.0, -20.0, 10.0),
            Vec3::new(150.0, -80.0, 5.0),
            Vec3::new(-3000.0, 1200.0, 400.0),
        ),
        (
            Vec3::new(-30.0, 50.0, 100.0),
            Vec3::new(0.0, 200.0, 0.0),
            Vec3::new(8000.0, 0.0, 0.0),
        ),
    ];
    for (p, v, a) in states {
        let s0 = plain.evaluate(p, v, a).unwrap();
        let s1 = rotor.evaluate(p, v, a).unwrap();
        for i in 0..3 {
            // Q = (m_c + m_r) q̈ + m_c g + …: the difference is m_r q̈ (q̈ in m/s²).
            let expected = m_r * s0.ddq_mm_s2[i] * 1e-3;
            let diff = s1.force_n[i] - s0.force_n[i];
            assert!(
                (diff - expected).abs() < 1e-12 * (1.0 + s0.force_n[i].abs()),
                "{diff} vs {expected}"
            );
        }
        // Same weight: same potential energy, and at rest the same (static) forces.
        assert_eq!(s0.potential_j, s1.potential_j);
    }
    assert_eq!(
        plain.suspended_weight_n(),
        rotor.suspended_weight_n(),
        "eq. 17 counts weight only"
    );
}

#[test]
fn eq20_holds_with_the_rotor_against_an_energy_built_from_the_kinematics_alone() {
    // E(t) = ½(m_c + m_r)Σq̇² + ½ m_p |ṗ|² + g(m_c Σq + m_p z_P), with q from eq. 6 and
    // q̇ by central differences; its time derivative (differenced) must equal Σ Q_i q̇_i.
    let (_, rotor, m_r) = paper_models();
    let (mc, mp, g) = (0.25 + 0.02, 0.5 + 0.06, 9.81);
    let traj = |t: f64| {
        let w = [7.0, 11.0];
        let p = Vec3::new(
            40.0 * (w[0] * t).sin(),
            30.0 * (w[1] * t).cos(),
            20.0 + 5.0 * t,
        );
        let v = Vec3::new(
            40.0 * w[0] * (w[0] * t).cos(),
            -30.0 * w[1] * (w[1] * t).sin(),
            5.0,
        );
        let a = Vec3::new(
            -40.0 * w[0] * w[0] * (w[0] * t).sin(),
            -30.0 * w[1] * w[1] * (w[1] * t).cos(),
            0.0,
        );
        (p, v, a)
    };
    let q_m = |t: f64| rotor.inverse(traj(t).0).unwrap().map(|q| q * 1e-3);
    let energy = |t: f64| {
        let h = 1e-6;
        let (qp, qm, q) = (q_m(t + h), q_m(t - h), q_m(t));
        let (_, v, _) = traj(t);
        let dq2: f64 = (0..3).map(|i| ((qp[i] - qm[i]) / (2.0 * h)).powi(2)).sum();
        let kinetic = 0.5 * (mc + m_r) * dq2 + 0.5 * mp * (v * 1e-3).norm_squared();
        let z_p = traj(t).0.z * 1e-3;
        kinetic + g * (mc * q.iter().sum::<f64>() + mp * z_p)
    };
    for k in 0..50 {
        let t = 0.013 * k as f64;
        let (p, v, a) = traj(t);
        let s = rotor.evaluate(p, v, a).unwrap();
        let h = 1e-4;
        let de = (energy(t + h) - energy(t - h)) / (2.0 * h);
        assert!(
            (de - s.power_w).abs() < 1e-4 * (1.0 + s.power_w.abs()),
            "t={t}: {de} vs {}",
            s.power_w
        );
        assert!((s.energy_rate_w - s.power_w).abs() < 1e-9 * (1.0 + s.power_w.abs()));
    }
}

#[test]
fn edit_distance_counts_single_edits() {
    assert_eq!(edit_distance("kitten", "sitting"), 3);
    assert_eq!(edit_distance("", "abc"), 3);
    assert_eq!(edit_distance("same", "same"), 0);
}
#[test]
fn slow_radius_is_where_a_carriage_moves_ratio_times_faster() {
    // Nozzle on the far side of tower C (−y), moving away from it: the fastest
    // carriage-to-nozzle speed ratio at that radius.
    let machine = test_support::kossel_machine();
    let m = machine.model();
    for ratio in [3.0, 6.0] {
        let r = machine.slow_radius_mm(ratio);
        // Shortest arm (214.5 mm) is tower C's in the fixture.
        let s = m
            .evaluate(
                Vec3::new(0.0, -r, 0.0),
                Vec3::new(0.0, -1.0, 0.0),
                Vec3::zeros(),
            )
            .unwrap();
        assert!(
            (s.dq_mm_s[2].abs() - ratio).abs() < 1e-9,
            "{ratio}: {:?}",
            s.dq_mm_s
        );
        // The same ratio in closed form, from the distance to tower C's pull point.
        let c = m.towers_xy_mm()[2];
        let h = (c[0] * c[0] + (c[1] + r).powi(2)).sqrt();
        assert!((m.carriage_speed_ratio(2, h) - ratio).abs() < 1e-9);
    }
    assert_eq!(m.carriage_speed_ratio(2, 214.5), f64::INFINITY);
    // Hand-computed: 3·√(214.5²/10) − 105.
    assert!((machine.slow_radius_mm(3.0) - 98.492_567).abs() < 1e-5);
}

#[test]
fn reach_is_below_arm_minus_radius() {
    for (arm, r) in [(215.0, 107.5), (300.0, 10.0), (269.0, 134.4)] {
        let reach = klipper_reach_mm(arm, r);
        assert!(
            reach < arm - r && reach > 0.99 * arm - r,
            "{arm} {r} {reach}"
        );
    }
}
