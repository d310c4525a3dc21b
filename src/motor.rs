//! The force a carriage motor can give at a carriage speed: the phasor model of a
//! current-chopped hybrid stepper (docs/machine-profile.md, "The motor model").
//!
//! The driver holds the phase current at its setting (peak I_pk = √2 · run current, RMS)
//! until the supply voltage V no longer can: the winding's resistance R, its reactance
//! ω_e·L and the back-EMF E = k_e·ω take the whole of V,
//!
//! V² = (I·R + E)² + (ω_e·L·I)²,
//!
//! ω = v / r the rotor's speed (carriage speed v, pulley pitch radius r), ω_e = N_r·ω its
//! electrical speed (N_r = 360° / (4 · step angle) rotor teeth, 50 for 1.8°), k_e =
//! T_hold / (√2 · I_rated) the torque (and back-EMF) constant. The current is
//! I = min(I_pk, I_V), I_V the positive root of the equation above (0 once E ≥ V), the torque
//! T = k_e · I and the force at the belt T / r / safety factor.
//!
//! [`StepperCurve`] holds the constants of one motor on one pulley, so that
//! [`StepperCurve::available_force_n`], evaluated for every sample, is a few multiplications
//! and one square root, without allocation.

/// A stepper motor's figures and how it is driven, as the profile gives them (SI units but
/// the millimetres of the pulley and the millihenries of the data sheets).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepperFigures {
    /// Holding torque with both phases at the rated current, N·m.
    pub holding_torque_nm: f64,
    /// Rated current per phase, A (the data sheet's "A/phase").
    pub rated_current_a: f64,
    /// The driver's current setting, A RMS (Klipper's `run_current`).
    pub run_current_a: f64,
    /// Phase resistance, Ω.
    pub resistance_ohm: f64,
    /// Phase inductance, mH.
    pub inductance_mh: f64,
    /// The driver's supply voltage, V.
    pub supply_voltage_v: f64,
    /// Full-step angle, degrees (1.8 or 0.9).
    pub step_angle_deg: f64,
    /// Pitch radius of the motor pulley, mm (Klipper's rotation_distance / 2π).
    pub pulley_radius_mm: f64,
    /// Holding torque / allowed torque (≥ 1).
    pub safety_factor: f64,
}

impl StepperFigures {
    /// N_r, the rotor's teeth: 360° / (4 · step angle), 50 for a 1.8° motor.
    pub fn rotor_teeth(&self) -> f64 {
        rotor_teeth(self.step_angle_deg)
    }

    /// k_e = T_hold / (√2 · I_rated), N·m/A and V·s/rad: the rated current flows in both
    /// phases at holding, a current vector of √2 · I_rated.
    pub fn torque_constant(&self) -> f64 {
        self.holding_torque_nm / (std::f64::consts::SQRT_2 * self.rated_current_a)
    }

    /// I_pk = √2 · run current: the peak of the sine the driver makes of its RMS setting.
    pub fn peak_current_a(&self) -> f64 {
        std::f64::consts::SQRT_2 * self.run_current_a
    }
}

/// N_r = 360° / (4 · step angle): a full step is a quarter of a rotor tooth pitch.
pub fn rotor_teeth(step_angle_deg: f64) -> f64 {
    360.0 / (4.0 * step_angle_deg)
}

/// The force a motor can give at its carriage against the carriage's speed, with its
/// constants precomputed (see the module's documentation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepperCurve {
    /// The force up to the knee, N: k_e · min(I_pk, V/R) / r / safety.
    plateau_n: f64,
    /// N per A of phase current: k_e / r / safety.
    force_per_amp: f64,
    /// Back-EMF per carriage speed, V per mm/s: k_e / r.
    emf_per_speed: f64,
    /// Reactance per carriage speed, Ω per mm/s: N_r · L / r.
    reactance_per_speed: f64,
    resistance_ohm: f64,
    supply_v2: f64,
    knee_mm_s: f64,
    zero_mm_s: f64,
}

impl StepperCurve {
    /// The curve of a motor; the figures must be finite and positive (the inductance may
    /// be 0), as the profile's checks ensure.
    pub fn new(f: &StepperFigures) -> StepperCurve {
        let k_e = f.torque_constant();
        let r = f.pulley_radius_mm;
        let emf_per_speed = k_e / r;
        let reactance_per_speed = f.rotor_teeth() * f.inductance_mh * 1e-3 / r;
        let force_per_amp = k_e / (r * 1e-3) / f.safety_factor;
        let (rr, v) = (f.resistance_ohm, f.supply_voltage_v);
        let i_pk = f.peak_current_a();
        // The knee: the speed where I_V = I_pk, the positive root of
        // (e² + (x·I_pk)²)·s² + 2·I_pk·R·e·s + (I_pk·R)² − V² = 0, e and x per mm/s.
        // None when V/R ≤ I_pk: the voltage limits the current even at standstill.
        let c = (i_pk * rr).powi(2) - v * v;
        let (knee_mm_s, i_plateau) = if c < 0.0 {
            let a = emf_per_speed.powi(2) + (reactance_per_speed * i_pk).powi(2);
            let b = 2.0 * i_pk * rr * emf_per_speed;
            (-2.0 * c / (b + (b * b - 4.0 * a * c).sqrt()), i_pk)
        } else {
            (0.0, v / rr)
        };
        StepperCurve {
            plateau_n: force_per_amp * i_plateau,
            force_per_amp,
            emf_per_speed,
            reactance_per_speed,
            resistance_ohm: rr,
            supply_v2: v * v,
            knee_mm_s,
            // E = V: ω = V / k_e.
            zero_mm_s: v / emf_per_speed,
        }
    }

    /// The force the motor can give its carriage at `carriage_speed_mm_s` (either sign), N.
    #[inline]
    pub fn available_force_n(&self, carriage_speed_mm_s: f64) -> f64 {
        let s = carriage_speed_mm_s.abs();
        if s <= self.knee_mm_s {
            return self.plateau_n;
        }
        if s >= self.zero_mm_s {
            return 0.0;
        }
        // a·I² + b·I + c = 0 with a = R² + X², b = 2·R·E, c = E² − V² < 0; its positive
        // root, written without the cancellation of −b + √(b² − 4ac).
        let e = self.emf_per_speed * s;
        let x = self.reactance_per_speed * s;
        let r = self.resistance_ohm;
        let a = r * r + x * x;
        let b = 2.0 * r * e;
        let c = e * e - self.supply_v2;
        let i_v = -2.0 * c / (b + (b * b - 4.0 * a * c).sqrt());
        self.force_per_amp * i_v
    }

    /// The force below the knee, N (the driver's current reached).
    pub fn plateau_force_n(&self) -> f64 {
        self.plateau_n
    }

    /// The carriage speed above which the supply voltage limits the current, mm/s.
    pub fn knee_speed_mm_s(&self) -> f64 {
        self.knee_mm_s
    }

    /// The carriage speed at which the back-EMF equals the supply voltage and the model's
    /// force is 0, mm/s.
    pub fn zero_force_speed_mm_s(&self) -> f64 {
        self.zero_mm_s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// LDO-42STH48-2004AC (0.59 N·m, 2.0 A, 1.4 Ω,
    /// 3.0 mH, 1.8°) at 1.2 A RMS from 24 V on a GT2 20-tooth pulley, safety factor 1.
    fn ldo() -> StepperFigures {
        StepperFigures {
            holding_torque_nm: 0.59,
            rated_current_a: 2.0,
            run_current_a: 1.2,
            resistance_ohm: 1.4,
            inductance_mh: 3.0,
            supply_voltage_v: 24.0,
            step_angle_deg: 1.8,
            pulley_radius_mm: 40.0 / std::f64::consts::TAU,
            safety_factor: 1.0,
        }
    }

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol
    }

    #[test]
    fn the_available_force_never_rises_with_speed() {
        // The sparse evaluation bounds the share of the available force with the force at
        // the largest speed of a run: the curve must not rise anywhere, the knee included.
        for figures in [
            ldo(),
            StepperFigures {
                supply_voltage_v: 12.0,
                inductance_mh: 0.0,
                ..ldo()
            },
        ] {
            let c = StepperCurve::new(&figures);
            let top = 1.2 * c.zero_force_speed_mm_s();
            let mut last = f64::INFINITY;
            for k in 0..=200_000 {
                let f = c.available_force_n(top * k as f64 / 200_000.0);
                assert!(f <= last * (1.0 + 1e-12), "{k}: {f} > {last}");
                last = f;
            }
            let knee = c.knee_speed_mm_s();
            for x in [
                knee * (1.0 - 1e-15),
                knee,
                knee * (1.0 + 1e-15),
                knee * (1.0 + 1e-9),
            ] {
                assert!(c.available_force_n(x) <= c.plateau_force_n() * (1.0 + 1e-12));
            }
        }
    }

    #[test]
    fn ldo_matches_the_hand_computation() {
        // A colleague's hand computation: r = 6.366198 mm, k_e = 0.2085965 V·s/rad,
        // I_pk = 1.6970563 A, T = 0.354 N·m: 55.6062 N up to the knee at 433.76 mm/s;
        // I_V = 1.324296 A at 500 mm/s → 43.3922 N; 27.594 N at 600, 10.664 N at 700;
        // E = V at 732.46 mm/s.
        let c = StepperCurve::new(&ldo());
        for v in [0.0, 100.0, 200.0, 300.0, 400.0, 433.0, -300.0] {
            assert!(close(c.available_force_n(v), 55.6062, 5e-5), "{v}");
        }
        assert!(close(c.available_force_n(500.0), 43.3922, 5e-5));
        assert!(close(c.available_force_n(-500.0), 43.3922, 5e-5));
        assert!(close(c.available_force_n(600.0), 27.594, 5e-4));
        assert!(close(c.available_force_n(700.0), 10.664, 5e-4));
        assert!(close(c.knee_speed_mm_s(), 433.76, 5e-3));
        assert!(close(c.zero_force_speed_mm_s(), 732.46, 5e-3));
        assert_eq!(c.available_force_n(732.5), 0.0);
        assert_eq!(c.available_force_n(5000.0), 0.0);
        assert!(close(c.plateau_force_n(), 55.6062, 5e-5));
        // Continuous at the knee, decreasing after it.
        let k = c.knee_speed_mm_s();
        assert!(close(c.available_force_n(k * (1.0 + 1e-9)), 55.6062, 1e-4));
        let mut last = f64::INFINITY;
        for i in 0..200 {
            let f = c.available_force_n(k + 1.5 * f64::from(i));
            assert!(f <= last, "{i}");
            last = f;
        }
    }

    #[test]
    fn flsun_q5_motor_by_hand() {
        // My own case: FLSUN 42SHDC4047Z-23SY (0.30 N·m, 1.0 A, 1.9 Ω, 3.6 mH, 1.8°) at
        // 0.8 A RMS from 24 V on GT2 20T, safety factor 1.
        // r = 6.366198 mm; k_e = 0.30/√2 = 0.2121320; I_pk = 1.1313708 A;
        // plateau T = 0.2121320 × 1.1313708 = 0.24 N·m → 0.24 / 0.006366198 = 37.69911 N.
        // At 600 mm/s: ω = 0.6/0.006366198 = 94.24778 rad/s, E = k_e·ω = 19.99297 V,
        // X = 50·ω·3.6e-3 = 16.96460 Ω; a = 1.9² + X² = 291.4077, b = 2·1.9·E = 75.97330,
        // c = E² − 24² = −176.2810; I_V = (−b + √(b² − 4ac))/(2a) = 0.6582645 A < I_pk;
        // T = k_e·I_V = 0.1396390 N·m → 21.93444 N.
        // Knee (I_V = I_pk): 485.0095 mm/s; E = V at 24/k_e·r = 720.2531 mm/s.
        let c = StepperCurve::new(&StepperFigures {
            holding_torque_nm: 0.30,
            rated_current_a: 1.0,
            run_current_a: 0.8,
            resistance_ohm: 1.9,
            inductance_mh: 3.6,
            ..ldo()
        });
        assert!(close(c.plateau_force_n(), 37.69911, 1e-5));
        assert!(close(c.available_force_n(600.0), 21.93444, 1e-5));
        assert!(close(c.knee_speed_mm_s(), 485.0095, 1e-4));
        assert!(close(c.zero_force_speed_mm_s(), 720.2531, 1e-4));
    }

    #[test]
    fn safety_factor_divides_and_a_high_resistance_caps_the_plateau() {
        let c2 = StepperCurve::new(&StepperFigures {
            safety_factor: 2.0,
            ..ldo()
        });
        let c1 = StepperCurve::new(&ldo());
        for v in [0.0, 450.0, 650.0] {
            assert!(close(
                c2.available_force_n(v),
                c1.available_force_n(v) / 2.0,
                1e-12
            ));
        }
        // 12 V over 10 Ω: 1.2 A < I_pk 1.697 A even at standstill.
        let weak = StepperCurve::new(&StepperFigures {
            resistance_ohm: 10.0,
            supply_voltage_v: 12.0,
            ..ldo()
        });
        assert_eq!(weak.knee_speed_mm_s(), 0.0);
        // k_e · V/R / r = 0.2085965 × 1.2 / 0.006366198 = 39.31951 N.
        assert!(close(weak.plateau_force_n(), 39.31951, 1e-4));
        assert!(close(weak.available_force_n(0.0), 39.31951, 1e-4));
        assert!(weak.available_force_n(1.0) < weak.plateau_force_n());
    }

    /// StepperOnline 17HE19-2004S (0.55 N·m, 2.0 A, 1.3 Ω, 2.4 mH) at 24 V and 2.2 A
    /// peak, against the pull-out torque of StepperOnline's published curve
    /// (docs/machine-profile.md, "How close the model is"): within −1 … +14 % up to
    /// 800 rpm, below the curve from 900 rpm on (the model is pessimistic there).
    #[test]
    fn the_model_against_a_published_pull_out_curve() {
        let published_ncm = [
            (100.0, 41.6),
            (200.0, 40.2),
            (300.0, 40.4),
            (400.0, 42.3),
            (500.0, 42.0),
            (600.0, 37.8),
            (700.0, 34.4),
            (800.0, 30.4),
            (900.0, 27.4),
            (1000.0, 24.2),
            (1100.0, 18.2),
            (1200.0, 14.2),
        ];
        let r_mm = 10.0; // any radius: torque = force × r
        let c = StepperCurve::new(&StepperFigures {
            holding_torque_nm: 0.55,
            rated_current_a: 2.0,
            run_current_a: 2.2 / std::f64::consts::SQRT_2,
            resistance_ohm: 1.3,
            inductance_mh: 2.4,
            supply_voltage_v: 24.0,
            step_angle_deg: 1.8,
            pulley_radius_mm: r_mm,
            safety_factor: 1.0,
        });
        for (rpm, t_ncm) in published_ncm {
            let v_mm_s = rpm / 60.0 * std::f64::consts::TAU * r_mm;
            let model_ncm = c.available_force_n(v_mm_s) * r_mm * 1e-3 * 100.0;
            let ratio = model_ncm / t_ncm;
            if rpm <= 800.0 {
                assert!((0.98..1.14).contains(&ratio), "{rpm} rpm: {ratio}");
            } else {
                assert!(ratio < 0.9, "{rpm} rpm: {ratio}");
            }
        }
    }
}
