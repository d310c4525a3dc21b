//! The profile's copies of Klipper sections, with Klipper's key names, defaults and bounds:
//! `gcode_arcs` (klippy/extras/gcode_arcs.py) and `input_shaper`
//! (klippy/extras/input_shaper.py, `InputShaperParams.__init__`).

use serde::Deserialize;

use super::location::edit_distance;
use super::validate::Range;
use super::{Invalid, defaults};
use crate::gcode::ArcRules;
use crate::motion::shaper::{AxisShaper, InputShaper, ShaperType};

/// `gcode_arcs`: Klipper's `[gcode_arcs]`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields, default)]
pub(super) struct RawGcodeArcs {
    /// gcode_arcs.py: `config.getfloat('resolution', 1., above=0.0)`.
    resolution: f64,
}

impl Default for RawGcodeArcs {
    fn default() -> Self {
        RawGcodeArcs {
            resolution: crate::gcode::arc::KLIPPER_ARC_RESOLUTION_MM,
        }
    }
}

impl RawGcodeArcs {
    pub(super) fn resolve(&self) -> Result<ArcRules, Invalid> {
        Range::Positive.check("gcode_arcs.resolution", self.resolution)?;
        Ok(ArcRules::Klipper {
            resolution_mm: self.resolution,
        })
    }
}

/// `input_shaper`: Klipper's `[input_shaper]`, the same keys.
#[derive(Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawInputShaper {
    /// Both axes' type, unless `shaper_type_x` / `_y` is given; default mzv.
    shaper_type: Option<String>,
    shaper_type_x: Option<String>,
    shaper_type_y: Option<String>,
    /// Hz; 0 (the default) leaves the axis unshaped.
    shaper_freq_x: Option<f64>,
    shaper_freq_y: Option<f64>,
    damping_ratio_x: Option<f64>,
    damping_ratio_y: Option<f64>,
}

/// Klipper's shaper names (shaper_defs.py `INPUT_SHAPERS`), in its order.
pub const SHAPER_NAMES: [&str; 6] = ["zv", "mzv", "zvd", "ei", "2hump_ei", "3hump_ei"];

impl RawInputShaper {
    /// Each axis as input_shaper.py reads it: the type (`shaper_type_x`, else
    /// `shaper_type`, else mzv) must be one of Klipper's, the damping ratio (default 0.1)
    /// within 0 and the type's `max_damping_ratio`, the frequency ≥ 0; a frequency of 0
    /// leaves the axis unshaped.
    pub(super) fn resolve(&self) -> Result<InputShaper, Invalid> {
        let s = self;
        Ok(InputShaper {
            x: axis(
                "x",
                (&s.shaper_type_x, &s.shaper_type),
                s.shaper_freq_x,
                s.damping_ratio_x,
            )?,
            y: axis(
                "y",
                (&s.shaper_type_y, &s.shaper_type),
                s.shaper_freq_y,
                s.damping_ratio_y,
            )?,
        })
    }
}

fn axis(
    axis: &str,
    (own_type, common_type): (&Option<String>, &Option<String>),
    freq_hz: Option<f64>,
    damping_ratio: Option<f64>,
) -> Result<Option<AxisShaper>, Invalid> {
    let (type_key, name) = match (own_type, common_type) {
        (Some(t), _) => (format!("input_shaper.shaper_type_{axis}"), t.as_str()),
        (None, Some(t)) => ("input_shaper.shaper_type".to_string(), t.as_str()),
        (None, None) => (String::new(), defaults::SHAPER_TYPE),
    };
    let kind = ShaperType::from_name(name).ok_or_else(|| unknown_type(type_key, name))?;
    let damping_key = format!("input_shaper.damping_ratio_{axis}");
    let damping = damping_ratio.unwrap_or(defaults::SHAPER_DAMPING_RATIO);
    Range::NonNegative.check(&damping_key, damping)?;
    let max = kind.max_damping_ratio();
    if damping > max {
        return Err(Invalid::new(
            damping_key,
            format!(
                "{damping} is above {max}, the most Klipper accepts for shaper `{}` \
                 (shaper_defs.py max_damping_ratio)",
                kind.name()
            ),
        ));
    }
    let freq_key = format!("input_shaper.shaper_freq_{axis}");
    let freq = freq_hz.unwrap_or(0.0);
    Range::NonNegative.check(&freq_key, freq)?;
    Ok((freq > 0.0).then_some(AxisShaper {
        kind,
        freq_hz: freq,
        damping_ratio: damping,
    }))
}

/// A shaper name Klipper does not know, with the closest one.
fn unknown_type(key: String, name: &str) -> Invalid {
    let lower = name.to_ascii_lowercase();
    let hint = SHAPER_NAMES
        .iter()
        .map(|n| (edit_distance(&lower, n), n))
        .filter(|&(d, n)| d <= n.len().max(lower.len()).div_ceil(2))
        // Ties go to the name of the same length (a swap of two letters counts 2).
        .min_by_key(|&(d, n)| (d, n.len().abs_diff(lower.len())))
        .map(|(_, n)| format!(" (did you mean `{n}`?)"))
        .unwrap_or_default();
    Invalid::new(
        key,
        format!(
            "unknown shaper type `{name}`{hint}, expected one of {}",
            SHAPER_NAMES.join(", ")
        ),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_klipper_name_is_a_shaper_type() {
        for name in SHAPER_NAMES {
            let kind = ShaperType::from_name(name).unwrap();
            assert_eq!(kind.name(), name);
        }
    }
}
