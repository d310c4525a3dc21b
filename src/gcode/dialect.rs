//! The G-code dialect: which firmware reads the file, and the rules of its own that the
//! interpreter applies (arcs, Marlin's soft endstops). Built from the machine profile
//! (`Machine::dialect`); a bare [`ArcRules`] is Klipper's dialect with those arcs.

use super::arc::ArcRules;

/// The firmware whose G-code semantics the interpreter follows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FirmwareKind {
    /// Klipper's `gcode_move` (and its extended commands: SET_VELOCITY_LIMIT, …).
    Klipper,
    /// Marlin 2.1.x on a delta (M201/M203/M204/M205/M665, G90 cancelling M83, …).
    Marlin,
}

impl FirmwareKind {
    pub fn name(self) -> &'static str {
        match self {
            FirmwareKind::Klipper => "Klipper",
            FirmwareKind::Marlin => "Marlin",
        }
    }
}

/// Marlin's soft endstops on a delta (`apply_motion_limits`, motion.cpp): a target farther
/// than `radius_mm` from the Z axis is pulled in by scaling x, y *and z*; z is kept in
/// [0, `max_z_mm`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SoftEndstops {
    /// `DELTA_PRINTABLE_RADIUS` (the profile's `print_radius_mm`).
    pub radius_mm: f64,
    /// The soft maximum Z: the home height (`delta_height` less the probe's Z offset).
    pub max_z_mm: f64,
}

/// The profile's delta geometry in M665's terms (gcode/calibrate/M665.cpp), for telling the
/// user when the file's M665 says otherwise: the model keeps the profile's.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DeltaSettings {
    /// Each tower's rod, mm: Marlin's `delta_diagonal_rod` (L) plus that tower's
    /// `delta_diagonal_rod_trim` (A, B, C).
    pub rod_mm: [f64; 3],
    /// `delta_radius` (R), mm.
    pub radius_mm: f64,
    /// `delta_tower_angle_trim` (X, Y, Z): each tower's angle less its ideal 210°, 330°,
    /// 90°, degrees.
    pub angle_trim_deg: [f64; 3],
}

/// How the interpreter reads the G-code.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dialect {
    pub firmware: FirmwareKind,
    /// How G2/G3 are cut into chords.
    pub arcs: ArcRules,
    /// Marlin's soft endstops (None: Klipper, which refuses such moves instead).
    pub soft_endstops: Option<SoftEndstops>,
    /// The profile's geometry, to compare M665 with (None: not known, no comparison).
    pub delta: Option<DeltaSettings>,
}

impl Dialect {
    /// Klipper's dialect with the arcs of `[gcode_arcs]`.
    pub fn klipper(arcs: ArcRules) -> Dialect {
        Dialect {
            firmware: FirmwareKind::Klipper,
            arcs,
            soft_endstops: None,
            delta: None,
        }
    }
}

impl Default for Dialect {
    fn default() -> Self {
        Dialect::klipper(ArcRules::default())
    }
}

impl From<ArcRules> for Dialect {
    /// The dialect of the firmware these arc rules belong to. Marlin's rules without a
    /// profile have no soft endstops.
    fn from(arcs: ArcRules) -> Dialect {
        match arcs {
            ArcRules::Klipper { .. } => Dialect::klipper(arcs),
            ArcRules::Marlin { .. } => Dialect {
                firmware: FirmwareKind::Marlin,
                arcs,
                soft_endstops: None,
                delta: None,
            },
        }
    }
}

/// The flavour a slicer wrote in a comment line: Cura's `;FLAVOR:Marlin` (first line),
/// PrusaSlicer's (and its forks') `; gcode_flavor = marlin2` (in the settings at the end).
/// Returns the flavour's text, trimmed.
pub fn slicer_flavour(line: &[u8]) -> Option<&[u8]> {
    let rest = line.strip_prefix(b";")?;
    let rest = trim(rest);
    let value = if let Some(v) = strip_prefix_ci(rest, b"flavor:") {
        v
    } else {
        let v = strip_prefix_ci(rest, b"gcode_flavor")?;
        trim(v).strip_prefix(b"=")?
    };
    let value = trim(value);
    (!value.is_empty()).then_some(value)
}

/// Which firmware a slicer flavour names, if one delta-gcode models.
pub fn flavour_firmware(flavour: &[u8]) -> Option<FirmwareKind> {
    let lower = flavour.to_ascii_lowercase();
    let has = |w: &[u8]| lower.windows(w.len()).any(|x| x == w);
    if has(b"klipper") {
        Some(FirmwareKind::Klipper)
    } else if has(b"marlin") {
        Some(FirmwareKind::Marlin)
    } else {
        None
    }
}

fn trim(b: &[u8]) -> &[u8] {
    let start = b
        .iter()
        .position(|c| !c.is_ascii_whitespace())
        .unwrap_or(b.len());
    let end = b
        .iter()
        .rposition(|c| !c.is_ascii_whitespace())
        .map_or(start, |e| e + 1);
    &b[start..end.max(start)]
}

fn strip_prefix_ci<'a>(b: &'a [u8], prefix: &[u8]) -> Option<&'a [u8]> {
    (b.len() >= prefix.len() && b[..prefix.len()].eq_ignore_ascii_case(prefix))
        .then(|| &b[prefix.len()..])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slicer_flavours_are_read() {
        type Case<'a> = (&'a [u8], Option<&'a [u8]>, Option<FirmwareKind>);
        let cases: [Case; 7] = [
            (
                b";FLAVOR:Marlin\r\n",
                Some(b"Marlin"),
                Some(FirmwareKind::Marlin),
            ),
            (
                b"; gcode_flavor = marlin2\n",
                Some(b"marlin2"),
                Some(FirmwareKind::Marlin),
            ),
            (
                b"; gcode_flavor = klipper",
                Some(b"klipper"),
                Some(FirmwareKind::Klipper),
            ),
            (
                b";FLAVOR:RepRap (Marlin/Sprinter)",
                Some(b"RepRap (Marlin/Sprinter)"),
                Some(FirmwareKind::Marlin),
            ),
            (
                b"; gcode_flavor = reprapfirmware",
                Some(b"reprapfirmware"),
                None,
            ),
            (b"; generated by PrusaSlicer 2.5.0", None, None),
            (b"G1 X1 ; gcode_flavor = marlin", None, None),
        ];
        for (line, flavour, firmware) in cases {
            assert_eq!(slicer_flavour(line), flavour, "{:?}", line);
            if let Some(f) = flavour {
                assert_eq!(flavour_firmware(f), firmware);
            }
        }
    }
}
