//! The motors a profile can name with `motors.model` (docs/machine-profile.md, "The motor
//! table"): each a data sheet's figures, with its source.
//!
//! A Rust table rather than a YAML file: the compiler checks every figure's type, nothing
//! is parsed (or can fail to parse) at run time, and each figure stays next to the comment
//! that names its source. The table's tests check the names and figures.

/// One motor's data-sheet figures.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MotorSpec {
    /// The name `motors.model` takes (lower case; matched without regard to case).
    pub name: &'static str,
    /// Holding torque, both phases at the rated current, N·m.
    pub holding_torque_nm: f64,
    /// Rated current per phase, A.
    pub rated_current_a: f64,
    /// Phase resistance, Ω.
    pub resistance_ohm: f64,
    /// Phase inductance, mH.
    pub inductance_mh: f64,
    /// Full-step angle, degrees.
    pub step_angle_deg: f64,
    /// Rotor inertia, kg·m² (data sheets give g·cm²: 1 g·cm² = 1e-7 kg·m²).
    pub rotor_inertia_kg_m2: Option<f64>,
}

/// g·cm² in kg·m².
const G_CM2: f64 = 1e-7;

/// The shipped motor table.
pub const MOTORS: &[MotorSpec] = &[
    // LDO Motors drawing "LDO-42STH48-2004AC" Rev A (2020-11-12),
    // LDOMotors/ldo-stepper-datasheets @ fdc453d: 1.8° ±5 %, "DC 2.0A / Phase",
    // 1.4 Ω ±20 %, 3.0 mH ±20 %, 5.9 kgf·cm (59 N·cm), rotor 68 g·cm² REF.
    // (klipper_tmc_autotune's motor_database.cfg lists 1.6 Ω; LDO's drawing says 1.4.)
    MotorSpec {
        name: "ldo-42sth48-2004ac",
        holding_torque_nm: 0.59,
        rated_current_a: 2.0,
        resistance_ohm: 1.4,
        inductance_mh: 3.0,
        step_angle_deg: 1.8,
        rotor_inertia_kg_m2: Some(68.0 * G_CM2),
    },
    // LDO Motors drawing "LDO-42STH48-2004MAC" Rev A, same repository: the 0.9° twin of
    // the above; 4.9 kgf·cm, 2.0 A, 1.4 Ω, 2.8 mH, 68 g·cm².
    MotorSpec {
        name: "ldo-42sth48-2004mac",
        holding_torque_nm: 0.49,
        rated_current_a: 2.0,
        resistance_ohm: 1.4,
        inductance_mh: 2.8,
        step_angle_deg: 0.9,
        rotor_inertia_kg_m2: Some(68.0 * G_CM2),
    },
    // 17HS4401, the generic 40 mm NEMA 17, as MotionKing rates it (the part number's
    // origin; gist robertcedwards/3b47f0d5af4cdd30dad80279c71fd15a, "17HS4401 1.8 40 1.7
    // 1.5 2.8 40 2.2 54 4 280"): 1.8°, 1.7 A, 1.5 Ω, 2.8 mH, 40 N·cm, 54 g·cm². Other
    // makers' 17HS4401 differ (Usongshine: 1.5 A, 2.4 Ω, 3.7 mH, 0.42 N·m).
    MotorSpec {
        name: "motionking-17hs4401",
        holding_torque_nm: 0.40,
        rated_current_a: 1.7,
        resistance_ohm: 1.5,
        inductance_mh: 2.8,
        step_angle_deg: 1.8,
        rotor_inertia_kg_m2: Some(54.0 * G_CM2),
    },
    // The FLSUN Q5's A/B/C motor, "FLSUN STEP MOTOR 42SHDC4047Z-23SY": Zhongshan
    // Shengyang drawing 42BYGH440-B-23HDN (vincios/q5-klipper @ 53bb4a8, files/Motor
    // 42SHDC4047Z-23SY Parameter Diagram.pdf): 1.8° ±0.09°, DC 1.0 A/phase, 1.9 Ω ±10 %,
    // 3.6 mH ±20 %, holding torque ≥ 300 mN·m, rotor 57 g·cm².
    MotorSpec {
        name: "flsun-42shdc4047z-23sy",
        holding_torque_nm: 0.30,
        rated_current_a: 1.0,
        resistance_ohm: 1.9,
        inductance_mh: 3.6,
        step_angle_deg: 1.8,
        rotor_inertia_kg_m2: Some(57.0 * G_CM2),
    },
    // StepperOnline 17HS19-2004S1 (48 mm): 59 N·cm, 2.0 A, 1.4 Ω, 3.0 mH ±20 % (product
    // page; klipper_tmc_autotune `omc-17hs19-2004s1`), rotor 82 g·cm² (the Voron wiki's
    // stepper table, as copied in TheDevMinerTV/stepper-simulator).
    MotorSpec {
        name: "omc-17hs19-2004s1",
        holding_torque_nm: 0.59,
        rated_current_a: 2.0,
        resistance_ohm: 1.4,
        inductance_mh: 3.0,
        step_angle_deg: 1.8,
        rotor_inertia_kg_m2: Some(82.0 * G_CM2),
    },
    // StepperOnline 17HE19-2004S: 0.55 N·m, 2.0 A, 1.3 Ω, 2.4 mH ±20 % (StepperOnline's
    // figures, rlneumiller/2StageCompoundCycloidalTorqueCalculator @ dccc9db,
    // OtherSpecs_17HE19-2004S.txt); the motor of the published pull-out curve the model is
    // compared with. Rotor inertia not published there.
    MotorSpec {
        name: "omc-17he19-2004s",
        holding_torque_nm: 0.55,
        rated_current_a: 2.0,
        resistance_ohm: 1.3,
        inductance_mh: 2.4,
        step_angle_deg: 1.8,
        rotor_inertia_kg_m2: None,
    },
    // StepperOnline 17HM19-2004S, 0.9°: 0.46 N·m, 2.0 A, 1.45 Ω, 4.0 mH
    // (klipper_tmc_autotune `omc-17hm19-2004s`), 82 g·cm² (the Voron wiki's table).
    MotorSpec {
        name: "omc-17hm19-2004s",
        holding_torque_nm: 0.46,
        rated_current_a: 2.0,
        resistance_ohm: 1.45,
        inductance_mh: 4.0,
        step_angle_deg: 0.9,
        rotor_inertia_kg_m2: Some(82.0 * G_CM2),
    },
];

/// The motor named `name` (case ignored).
pub fn find(name: &str) -> Option<&'static MotorSpec> {
    MOTORS.iter().find(|m| m.name.eq_ignore_ascii_case(name))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_unique_lower_case_and_found() {
        for (i, m) in MOTORS.iter().enumerate() {
            assert_eq!(m.name, m.name.to_ascii_lowercase());
            assert!(MOTORS[..i].iter().all(|o| o.name != m.name), "{}", m.name);
            assert_eq!(find(&m.name.to_ascii_uppercase()), Some(m));
            let figures = [
                m.holding_torque_nm,
                m.rated_current_a,
                m.resistance_ohm,
                m.inductance_mh,
            ];
            assert!(figures.iter().all(|&x| x > 0.0 && x < 10.0), "{}", m.name);
            assert!([0.9, 1.8].contains(&m.step_angle_deg), "{}", m.name);
            // NEMA 17 rotors: 30-120 g·cm².
            if let Some(j) = m.rotor_inertia_kg_m2 {
                assert!((3e-6..1.2e-5).contains(&j), "{}", m.name);
            }
        }
        assert_eq!(find("no-such-motor"), None);
    }

    #[test]
    fn rated_voltage_agrees_with_the_resistance() {
        // The drawings' rated voltage is I_rated × R: LDO "DC 2.8V / Phase" at 2.0 A,
        // Shengyang "DC 1.9 V" at 1.0 A.
        let ldo = find("ldo-42sth48-2004ac").unwrap();
        assert!((ldo.rated_current_a * ldo.resistance_ohm - 2.8).abs() < 1e-12);
        let q5 = find("flsun-42shdc4047z-23sy").unwrap();
        assert!((q5.rated_current_a * q5.resistance_ohm - 1.9).abs() < 1e-12);
    }
}
