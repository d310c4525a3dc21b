//! The shapers of Klipper's klippy/extras/shaper_defs.py and their pulses as
//! klippy/chelper/kin_shaper.c applies them.

/// The shaper types of Klipper's `shaper_defs.py`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShaperType {
    Zv,
    Mzv,
    Zvd,
    Ei,
    TwoHumpEi,
    ThreeHumpEi,
}

/// shaper_defs.py `SHAPER_VIBRATION_REDUCTION`: the EI shapers' vibration tolerance is its
/// inverse.
const SHAPER_VIBRATION_REDUCTION: f64 = 20.0;

/// shaper_defs.py `DEFAULT_DAMPING_RATIO`.
pub const DEFAULT_SHAPER_DAMPING_RATIO: f64 = 0.1;

impl ShaperType {
    /// The type of Klipper's `shaper_type` name (case-insensitive, as `SET_INPUT_SHAPER`).
    pub fn from_name(name: &str) -> Option<ShaperType> {
        Some(match name.to_ascii_lowercase().as_str() {
            "zv" => ShaperType::Zv,
            "mzv" => ShaperType::Mzv,
            "zvd" => ShaperType::Zvd,
            "ei" => ShaperType::Ei,
            "2hump_ei" => ShaperType::TwoHumpEi,
            "3hump_ei" => ShaperType::ThreeHumpEi,
            _ => return None,
        })
    }

    /// Klipper's name of the type.
    pub fn name(self) -> &'static str {
        match self {
            ShaperType::Zv => "zv",
            ShaperType::Mzv => "mzv",
            ShaperType::Zvd => "zvd",
            ShaperType::Ei => "ei",
            ShaperType::TwoHumpEi => "2hump_ei",
            ShaperType::ThreeHumpEi => "3hump_ei",
        }
    }

    /// shaper_defs.py `INPUT_SHAPERS[].max_damping_ratio`.
    pub fn max_damping_ratio(self) -> f64 {
        match self {
            ShaperType::Zv | ShaperType::Mzv | ShaperType::Zvd => 0.99,
            ShaperType::Ei => 0.4,
            ShaperType::TwoHumpEi => 0.3,
            ShaperType::ThreeHumpEi => 0.2,
        }
    }

    /// The pulses as shaper_defs.py defines them: amplitudes A_i (not normalised) and
    /// times T_i ≥ 0, increasing, s.
    pub fn pulses(self, freq_hz: f64, damping_ratio: f64) -> (Vec<f64>, Vec<f64>) {
        let dr = damping_ratio;
        let df = (1.0 - dr * dr).sqrt();
        let t_d = 1.0 / (freq_hz * df);
        let k = (-dr * std::f64::consts::PI / df).exp();
        match self {
            // get_zv_shaper
            ShaperType::Zv => (vec![1.0, k], vec![0.0, 0.5 * t_d]),
            // get_mzv_shaper with its defaults n = 3, t = 0.75: the classic MZV, whose
            // amplitudes 1 − 1/√2, (√2 − 1)·K, (1 − 1/√2)·K² the least-squares system of
            // get_mzv_coeffs reproduces, with K = exp(−0.75·ζπ/√(1−ζ²)).
            ShaperType::Mzv => {
                let k = (-0.75 * dr * std::f64::consts::PI / df).exp();
                let a1 = 1.0 - std::f64::consts::FRAC_1_SQRT_2;
                let a2 = (std::f64::consts::SQRT_2 - 1.0) * k;
                (vec![a1, a2, a1 * k * k], vec![0.0, 0.375 * t_d, 0.75 * t_d])
            }
            // get_zvd_shaper
            ShaperType::Zvd => (vec![1.0, 2.0 * k, k * k], vec![0.0, 0.5 * t_d, t_d]),
            // get_ei_shaper
            ShaperType::Ei => {
                let v = 1.0 / SHAPER_VIBRATION_REDUCTION;
                let a1 = (0.24968 + 0.24961 * v)
                    + ((0.80008 + 1.23328 * v) + (0.49599 + 3.17316 * v) * dr) * dr;
                let a3 = (0.25149 + 0.21474 * v)
                    + ((-0.83249 + 1.41498 * v) + (0.85181 - 4.90094 * v) * dr) * dr;
                let t2 = 0.4999
                    + (((0.46159 + 8.57843 * v) * v)
                        + (((4.26169 - 108.644 * v) * v) + ((1.75601 + 336.989 * v) * v) * dr)
                            * dr)
                        * dr;
                (vec![a1, 1.0 - a1 - a3, a3], vec![0.0, t2 * t_d, t_d])
            }
            // get_2hump_ei_shaper
            ShaperType::TwoHumpEi => from_expansion(
                freq_hz,
                dr,
                &[
                    [0.0, 0.0, 0.0, 0.0],
                    [0.49890, 0.16270, -0.54262, 6.16180],
                    [0.99748, 0.18382, -1.58270, 8.17120],
                    [1.49920, -0.09297, -0.28338, 1.85710],
                ],
                &[
                    [0.16054, 0.76699, 2.26560, -1.22750],
                    [0.33911, 0.45081, -2.58080, 1.73650],
                    [0.34089, -0.61533, -0.68765, 0.42261],
                    [0.15997, -0.60246, 1.00280, -0.93145],
                ],
            ),
            // get_3hump_ei_shaper
            ShaperType::ThreeHumpEi => from_expansion(
                freq_hz,
                dr,
                &[
                    [0.0, 0.0, 0.0, 0.0],
                    [0.49974, 0.23834, 0.44559, 12.4720],
                    [0.99849, 0.29808, -2.36460, 23.3990],
                    [1.49870, 0.10306, -2.01390, 17.0320],
                    [1.99960, -0.28231, 0.61536, 5.40450],
                ],
                &[
                    [0.11275, 0.76632, 3.29160, -1.44380],
                    [0.23698, 0.61164, -2.57850, 4.85220],
                    [0.30008, -0.19062, -2.14560, 0.13744],
                    [0.23775, -0.73297, 0.46885, -2.08650],
                    [0.11244, -0.45439, 0.96382, -1.46000],
                ],
            ),
        }
    }
}

/// shaper_defs.py `_get_shaper_from_expansion_coeffs`: each pulse's time (in periods) and
/// amplitude as cubic polynomials of the damping ratio.
fn from_expansion(
    freq_hz: f64,
    damping_ratio: f64,
    t: &[[f64; 4]],
    a: &[[f64; 4]],
) -> (Vec<f64>, Vec<f64>) {
    let poly = |c: &[f64; 4]| {
        ((c[3] * damping_ratio + c[2]) * damping_ratio + c[1]) * damping_ratio + c[0]
    };
    let period = 1.0 / freq_hz;
    (
        a.iter().map(poly).collect(),
        t.iter().map(|c| poly(c) * period).collect(),
    )
}

/// One axis's shaper as configured: Klipper's `shaper_type_x`, `shaper_freq_x`,
/// `damping_ratio_x` (or `_y`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AxisShaper {
    pub kind: ShaperType,
    /// 0 turns the axis's shaping off, as in Klipper.
    pub freq_hz: f64,
    pub damping_ratio: f64,
}

/// The input shaper of both axes (`None`: that axis is not shaped).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct InputShaper {
    pub x: Option<AxisShaper>,
    pub y: Option<AxisShaper>,
}

/// What a SET_INPUT_SHAPER line sets (each `None` keeps the value in force).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ShaperChange {
    /// SHAPER_TYPE (both axes), SHAPER_TYPE_X, SHAPER_TYPE_Y.
    pub kind: [Option<ShaperType>; 2],
    /// SHAPER_FREQ_X, SHAPER_FREQ_Y, Hz (0 turns the axis's shaping off).
    pub freq_hz: [Option<f64>; 2],
    /// DAMPING_RATIO_X, DAMPING_RATIO_Y.
    pub damping_ratio: [Option<f64>; 2],
}

impl InputShaper {
    /// The shaper after a SET_INPUT_SHAPER: each axis's type, frequency and damping as given,
    /// the others kept (an axis that was off starts from Klipper's defaults, mzv and 0.1).
    pub fn apply(&mut self, change: &ShaperChange) {
        for (axis, slot) in [&mut self.x, &mut self.y].into_iter().enumerate() {
            let cur = slot.unwrap_or(AxisShaper {
                kind: ShaperType::Mzv,
                freq_hz: 0.0,
                damping_ratio: DEFAULT_SHAPER_DAMPING_RATIO,
            });
            let new = AxisShaper {
                kind: change.kind[axis].unwrap_or(cur.kind),
                freq_hz: change.freq_hz[axis].unwrap_or(cur.freq_hz),
                damping_ratio: change.damping_ratio[axis].unwrap_or(cur.damping_ratio),
            };
            *slot = (new.freq_hz > 0.0).then_some(new);
        }
    }
}

/// The most pulses a shaper has (3hump_ei); kin_shaper.c allows ten.
pub(super) const MAX_PULSES: usize = 5;

/// A shaper's pulses as kin_shaper.c applies them: the commanded position is
/// Σ a_i · planned(t + τ_i), the amplitudes normalised to a sum of 1 and the offsets
/// centred on their weighted mean (`init_shaper`, `shift_pulses`), so that motion at
/// constant speed is unchanged.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pulses {
    n: usize,
    a: [f64; MAX_PULSES],
    tau_s: [f64; MAX_PULSES],
}

impl Pulses {
    /// No shaping: one pulse of 1 at offset 0.
    pub const IDENTITY: Pulses = Pulses {
        n: 1,
        a: [1.0, 0.0, 0.0, 0.0, 0.0],
        tau_s: [0.0; MAX_PULSES],
    };

    /// The pulses of an axis's shaper (identity when it is off or its frequency is 0).
    pub fn of(shaper: Option<AxisShaper>) -> Pulses {
        let Some(s) = shaper.filter(|s| s.freq_hz > 0.0) else {
            return Pulses::IDENTITY;
        };
        let (a, t) = s.kind.pulses(s.freq_hz, s.damping_ratio);
        let sum: f64 = a.iter().sum();
        let mut p = Pulses {
            n: a.len().min(MAX_PULSES),
            a: [0.0; MAX_PULSES],
            tau_s: [0.0; MAX_PULSES],
        };
        // Reversed: the pulse of T_i looks T_i back into the planned motion.
        for i in 0..p.n {
            p.a[p.n - 1 - i] = a[i] / sum;
            p.tau_s[p.n - 1 - i] = -t[i];
        }
        let mean: f64 = (0..p.n).map(|i| p.a[i] * p.tau_s[i]).sum();
        for tau in &mut p.tau_s[..p.n] {
            *tau -= mean;
        }
        p
    }

    /// (a_i, τ_i) of each pulse, offsets increasing.
    pub fn iter(&self) -> impl Iterator<Item = (f64, f64)> + '_ {
        (0..self.n).map(|i| (self.a[i], self.tau_s[i]))
    }

    /// The number of pulses.
    pub fn count(&self) -> usize {
        self.n
    }

    /// The smallest and largest offset, s.
    pub fn span_s(&self) -> (f64, f64) {
        (self.tau_s[0], self.tau_s[self.n - 1])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Klipper's shaper_defs.py at 40 Hz, damping 0.1, printed by Klipper itself
    /// (commit 84104bb): amplitudes and times.
    const KLIPPER_40HZ: [(ShaperType, &[f64], &[f64]); 6] = [
        (
            ShaperType::Zv,
            &[1.0, 0.729247614287671],
            &[0.0, 0.0125629726907402],
        ),
        (
            ShaperType::Mzv,
            &[0.292893218813452, 0.326874150410007, 0.182398743540587],
            &[0.0, 0.00942222951805511, 0.0188444590361102],
        ),
        (
            ShaperType::Zvd,
            &[1.0, 1.45849522857534, 0.53180208294426],
            &[0.0, 0.0125629726907402, 0.0251259453814803],
        ),
        (
            ShaperType::Ei,
            &[0.35488138, 0.45299809, 0.19212053],
            &[0.0, 0.0126810037161785, 0.0251259453814803],
        ),
        (
            ShaperType::TwoHumpEi,
            &[0.2586675, 0.3601195, 0.27290311, 0.10882055],
            &[0.0, 0.01289764, 0.025205155, 0.0372231575],
        ),
        (
            ShaperType::ThreeHumpEi,
            &[0.2208542, 0.2772112, 0.25969944, 0.167055, 0.0751792],
            &[0.0, 0.0135125475, 0.025701275, 0.037647475, 0.0495731775],
        ),
    ];

    #[test]
    fn every_shaper_is_klippers() {
        for (kind, a, t) in KLIPPER_40HZ {
            let (ka, kt) = kind.pulses(40.0, 0.1);
            assert_eq!(ka.len(), a.len(), "{}", kind.name());
            for (x, y) in ka.iter().zip(a).chain(kt.iter().zip(t)) {
                assert!((x - y).abs() < 1e-12, "{}: {x} vs {y}", kind.name());
            }
            assert_eq!(ShaperType::from_name(kind.name()), Some(kind));
            assert_eq!(
                ShaperType::from_name(&kind.name().to_uppercase()),
                Some(kind)
            );
        }
        assert_eq!(ShaperType::from_name("mzv(n=4)"), None);
    }

    #[test]
    fn pulses_are_normalised_and_centred() {
        for (kind, _, _) in KLIPPER_40HZ {
            let p = Pulses::of(Some(AxisShaper {
                kind,
                freq_hz: 37.0,
                damping_ratio: 0.05,
            }));
            let sum: f64 = p.iter().map(|(a, _)| a).sum();
            let mean: f64 = p.iter().map(|(a, t)| a * t).sum();
            assert!(
                (sum - 1.0).abs() < 1e-15 && mean.abs() < 1e-15,
                "{}",
                kind.name()
            );
            let (lo, hi) = p.span_s();
            assert!(lo < 0.0 && hi > 0.0);
        }
        let off = AxisShaper {
            kind: ShaperType::Ei,
            freq_hz: 0.0,
            damping_ratio: 0.1,
        };
        assert_eq!(Pulses::of(Some(off)), Pulses::IDENTITY);
    }
}
