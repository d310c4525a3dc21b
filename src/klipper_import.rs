//! Imports a Klipper linear-delta configuration (`printer.cfg`) as a machine profile: YAML
//! text in the schema of DESIGN.md ("Machine profile").
//!
//! What Klipper knows is copied with the defaults Klipper applies (`klippy/toolhead.py`,
//! `klippy/kinematics/delta.py`, `klippy/kinematics/extruder.py`). What Klipper does not
//! know — the masses and the motor force — is taken from [`ImportExtras`] or left out of
//! the YAML with a `# MISSING:` comment, so the profile loader refuses the profile and names
//! the key.
//!
//! Config syntax read here is Klipper's (Python `configparser`): `[section]` headers,
//! `key: value` or `key = value`, whole-line comments starting with `#` or `;`, inline
//! comments after whitespace, indented continuation lines, and the `#*#` SAVE_CONFIG block at
//! the end, whose values override the ones above it (as Klipper does). `[include …]` is
//! not followed; it is reported in [`ImportedProfile::notes`].

use std::collections::HashMap;
use std::fmt::Write as _;

use crate::machine::defaults::{self, klipper_reach_mm};

/// The figures Klipper's configuration does not hold.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ImportExtras {
    /// Profile name; default: "Imported from ORIGIN".
    pub name: Option<String>,
    pub cart_kg: Option<f64>,
    pub link_kg: Option<f64>,
    pub platform_kg: Option<f64>,
    pub max_force_n: Option<f64>,
}

/// The produced profile.
#[derive(Clone, Debug, PartialEq)]
pub struct ImportedProfile {
    /// Profile YAML (DESIGN.md schema), with comments naming where each figure came from.
    pub yaml: String,
    /// Profile keys that could not be filled (e.g. `masses.cart_kg`); they are absent from
    /// `yaml`, so the loader refuses it until they are added.
    pub missing: Vec<String>,
    /// Remarks on the import: includes not followed, defaults and clamps applied.
    pub notes: Vec<String>,
}

/// A configuration that cannot be imported. Every variant names the origin (file).
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum ImportError {
    #[error("{origin}:{line}: {message}")]
    Syntax {
        origin: String,
        line: usize,
        message: String,
    },
    #[error(
        "{origin}:{line}: [printer] kinematics is `{found}`; only `delta` (linear delta) can be imported"
    )]
    NotDelta {
        origin: String,
        line: usize,
        found: String,
    },
    #[error("{origin}: section [{section}] is required")]
    MissingSection { origin: String, section: String },
    #[error("{origin}:{line}: [{section}] needs `{key}`")]
    MissingKey {
        origin: String,
        /// Line of the section header.
        line: usize,
        section: String,
        key: String,
    },
    #[error("{origin}:{line}: [{section}] {key}: {message}")]
    BadValue {
        origin: String,
        line: usize,
        section: String,
        key: String,
        message: String,
    },
    #[error("{origin}: {what}: {message}")]
    BadExtra {
        origin: String,
        what: String,
        message: String,
    },
}

/// Reads `cfg_text` (a Klipper `printer.cfg`; `origin` names it in errors and comments) and
/// produces the machine profile.
pub fn import_klipper(
    cfg_text: &str,
    origin: &str,
    extra: &ImportExtras,
) -> Result<ImportedProfile, ImportError> {
    let cfg = Config::parse(cfg_text, origin)?;
    let mut notes: Vec<String> = cfg
        .includes
        .iter()
        .map(|(line, file)| {
            format!("line {line}: [include {file}] not followed; keys from it are not imported")
        })
        .collect();

    // [printer]
    let printer = cfg.section("printer")?;
    let kin = printer.required(&cfg, "kinematics")?;
    if kin.value != "delta" {
        return Err(ImportError::NotDelta {
            origin: origin.to_string(),
            line: kin.line,
            found: kin.value.clone(),
        });
    }
    let max_velocity = printer.float(&cfg, "max_velocity", None, Bound::Above(0.0))?;
    let max_accel = printer.float(&cfg, "max_accel", None, Bound::Above(0.0))?;
    let max_z_velocity = printer.float(
        &cfg,
        "max_z_velocity",
        Some(max_velocity.value),
        Bound::AboveAtMost(0.0, max_velocity.value),
    )?;
    let max_z_accel = printer.float(
        &cfg,
        "max_z_accel",
        Some(max_accel.value),
        Bound::AboveAtMost(0.0, max_accel.value),
    )?;
    let scv = printer.float(
        &cfg,
        "square_corner_velocity",
        Some(defaults::SQUARE_CORNER_VELOCITY_MM_S),
        Bound::AtLeast(0.0),
    )?;
    let mcr = minimum_cruise_ratio(&cfg, printer, max_accel.value)?;
    let radius = printer.float(&cfg, "delta_radius", None, Bound::Above(0.0))?;
    let print_radius =
        printer.float(&cfg, "print_radius", Some(radius.value), Bound::Above(0.0))?;

    // [stepper_a] .. [stepper_c]: B and C default to A's arm length and endstop.
    let steppers = [
        cfg.section("stepper_a")?,
        cfg.optional_section("stepper_b"),
        cfg.optional_section("stepper_c"),
    ];
    let arm_bound = Bound::Above(radius.value);
    let arm_a = steppers[0].float(&cfg, "arm_length", None, arm_bound)?;
    let endstop_a = steppers[0].float(&cfg, "position_endstop", None, Bound::Any)?;
    let mut arms = [arm_a.clone(), arm_a.clone(), arm_a.clone()];
    let mut endstops = [endstop_a.clone(), endstop_a.clone(), endstop_a.clone()];
    let mut angles: [Figure; 3] = Default::default();
    for (i, s) in steppers.iter().enumerate() {
        if i > 0 {
            arms[i] = s.float(&cfg, "arm_length", Some(arm_a.value), arm_bound)?;
            endstops[i] = s.float(&cfg, "position_endstop", Some(endstop_a.value), Bound::Any)?;
        }
        angles[i] = s.float(
            &cfg,
            "angle",
            Some(defaults::TOWER_ANGLES_DEG[i]),
            Bound::Any,
        )?;
    }
    // Klipper's build height is the lowest endstop (delta.py `max_z`); the nozzle reaches it
    // at x = y = 0 only when all endstops agree.
    let home_z = endstops
        .iter()
        .map(|e| e.value)
        .fold(f64::INFINITY, f64::min);
    if endstops.iter().any(|e| e.value != home_z) {
        notes.push(format!(
            "position_endstop differs per tower ({}, {}, {}); home_z_mm is the lowest, Klipper's maximum build height",
            num(endstops[0].value),
            num(endstops[1].value),
            num(endstops[2].value)
        ));
    }
    let min_arm = arms.iter().map(|a| a.value).fold(f64::INFINITY, f64::min);
    let reach = klipper_reach_mm(min_arm, radius.value);
    if reach <= 0.0 {
        return Err(ImportError::BadValue {
            origin: origin.to_string(),
            line: radius.line.unwrap_or(printer.line),
            section: "printer".into(),
            key: "delta_radius".into(),
            message: format!(
                "arms of {} mm reach no build area at delta_radius {}",
                num(min_arm),
                num(radius.value)
            ),
        });
    }
    // Rounded down to 0.01 mm, so it stays inside Klipper's limit.
    let print_radius_mm = print_radius.value.min((reach * 100.0).floor() / 100.0);
    let print_radius_src = if print_radius_mm < print_radius.value {
        notes.push(format!(
            "print_radius {} clamped to {} mm, the radius where Klipper's delta stops moves (a carriage 12x faster than the nozzle)",
            num(print_radius.value),
            num(print_radius_mm)
        ));
        format!(
            "{}; clamped to Klipper's reach limit",
            print_radius.source("[printer] print_radius", "Klipper default = delta_radius")
        )
    } else {
        print_radius.source("[printer] print_radius", "Klipper default = delta_radius")
    };

    let extruder = cfg.optional_section("extruder");
    if extruder.line == 0 {
        notes.push("no [extruder] section; the profile's extruder defaults apply".into());
    }

    // Extras.
    let check_extra = |what: &str, v: Option<f64>| -> Result<Option<f64>, ImportError> {
        match v {
            Some(x) if !(x.is_finite() && x > 0.0) => Err(ImportError::BadExtra {
                origin: origin.to_string(),
                what: what.to_string(),
                message: format!("must be a positive number, got {x}"),
            }),
            other => Ok(other),
        }
    };
    let cart = check_extra("masses.cart_kg", extra.cart_kg)?;
    let link = check_extra("masses.link_kg", extra.link_kg)?;
    let platform = check_extra("masses.platform_kg", extra.platform_kg)?;
    let force = check_extra("motors.max_force_n", extra.max_force_n)?;

    // YAML.
    let mut missing = Vec::new();
    let mut y = String::new();
    let origin_c = one_line(origin);
    let name = extra
        .name
        .clone()
        .unwrap_or_else(|| format!("Imported from {origin_c}"));
    let name_q = serde_json::to_string(&name).unwrap_or_else(|_| "\"imported\"".into());
    let _ = writeln!(
        y,
        "# Machine profile imported from the Klipper configuration {origin_c}"
    );
    let _ = writeln!(
        y,
        "# by delta-gcode's Klipper importer. Line numbers refer to that file."
    );
    let _ = writeln!(y, "name: {name_q}");
    let _ = writeln!(y, "geometry:");
    let _ = writeln!(
        y,
        "  delta_radius_mm: {}  # {}",
        num(radius.value),
        radius.source("[printer] delta_radius", "")
    );
    if arms.iter().all(|a| a.value == arm_a.value) {
        let _ = writeln!(
            y,
            "  arm_length_mm: {}  # {}",
            num(arm_a.value),
            arm_a.source("[stepper_a] arm_length", "")
        );
    } else {
        let _ = writeln!(
            y,
            "  arm_length_mm: [{}, {}, {}]  # [stepper_a..c] arm_length (B, C default to A)",
            num(arms[0].value),
            num(arms[1].value),
            num(arms[2].value)
        );
    }
    let _ = writeln!(
        y,
        "  nozzle_offset_mm: 0.0  # Klipper has none: its kinematics put the arm joints' plane at the nozzle"
    );
    let _ = writeln!(
        y,
        "  tower_angles_deg: [{}, {}, {}]  # [stepper_a..c] angle (Klipper defaults 210, 330, 90)",
        num(angles[0].value),
        num(angles[1].value),
        num(angles[2].value)
    );
    let _ = writeln!(
        y,
        "  home_z_mm: {}  # lowest [stepper_a..c] position_endstop (Klipper's max_z)",
        num(home_z)
    );
    let _ = writeln!(
        y,
        "  print_radius_mm: {}  # {}",
        num(print_radius_mm),
        print_radius_src
    );

    let mass_keys = [
        (
            "cart_kg",
            cart,
            "one carriage with its rollers/bearings and belt clamp",
        ),
        ("link_kg", link, "one of the six arms"),
        ("platform_kg", platform, "effector + hotend + fans"),
    ];
    write_estimated_section(&mut y, &mut missing, "masses", &mass_keys);

    let _ = writeln!(y, "limits:");
    let _ = writeln!(
        y,
        "  max_velocity_mm_s: {}  # {}",
        num(max_velocity.value),
        max_velocity.source("[printer] max_velocity", "")
    );
    let _ = writeln!(
        y,
        "  max_accel_mm_s2: {}  # {}",
        num(max_accel.value),
        max_accel.source("[printer] max_accel", "")
    );
    let _ = writeln!(
        y,
        "  square_corner_velocity_mm_s: {}  # {}",
        num(scv.value),
        scv.source("[printer] square_corner_velocity", "Klipper default")
    );
    let _ = writeln!(y, "  minimum_cruise_ratio: {}  # {}", num(mcr.0), mcr.1);
    let _ = writeln!(
        y,
        "  max_z_velocity_mm_s: {}  # {}",
        num(max_z_velocity.value),
        max_z_velocity.source("[printer] max_z_velocity", "Klipper default = max_velocity")
    );
    let _ = writeln!(
        y,
        "  max_z_accel_mm_s2: {}  # {}",
        num(max_z_accel.value),
        max_z_accel.source("[printer] max_z_accel", "Klipper default = max_accel")
    );
    let _ = writeln!(
        y,
        "  edge_slowdown: true  # Klipper's delta always slows moves near the edge"
    );

    if extruder.line > 0 {
        let nozzle = extruder.float(&cfg, "nozzle_diameter", None, Bound::Above(0.0))?;
        let filament = extruder.float(&cfg, "filament_diameter", None, Bound::Above(0.0))?;
        let _ = writeln!(y, "extruder:");
        let _ = writeln!(
            y,
            "  nozzle_diameter_mm: {}  # {}",
            num(nozzle.value),
            nozzle.source("[extruder] nozzle_diameter", "")
        );
        let _ = writeln!(
            y,
            "  filament_diameter_mm: {}  # {}",
            num(filament.value),
            filament.source("[extruder] filament_diameter", "")
        );
        for (key, out, bound) in [
            (
                "max_extrude_only_velocity",
                "max_extrude_only_velocity_mm_s",
                Bound::Above(0.0),
            ),
            (
                "max_extrude_only_accel",
                "max_extrude_only_accel_mm_s2",
                Bound::Above(0.0),
            ),
            (
                "instantaneous_corner_velocity",
                "instantaneous_corner_velocity_mm_s",
                Bound::AtLeast(0.0),
            ),
        ] {
            match extruder.optional_float(&cfg, key, bound)? {
                Some(f) => {
                    let _ = writeln!(
                        y,
                        "  {out}: {}  # {}",
                        num(f.value),
                        f.source(&format!("[extruder] {key}"), "")
                    );
                }
                None => {
                    let _ = writeln!(
                        y,
                        "  # {out}: not set; the loader applies Klipper's default"
                    );
                }
            }
        }
    }

    let motor_keys = [(
        "max_force_n",
        force,
        "peak |Q_i| a carriage motor may deliver",
    )];
    write_estimated_section(&mut y, &mut missing, "motors", &motor_keys);

    let _ = writeln!(y, "sampling:");
    let _ = writeln!(
        y,
        "  period_s: {}  # delta-gcode default",
        num(defaults::SAMPLING_PERIOD_S)
    );

    Ok(ImportedProfile {
        yaml: y,
        missing,
        notes,
    })
}

/// `[printer] minimum_cruise_ratio` as toolhead.py reads it: given; else from the deprecated
/// `max_accel_to_decel` (1 − min(1, a2d/max_accel)); else 0.5.
fn minimum_cruise_ratio(
    cfg: &Config,
    printer: &Section,
    max_accel: f64,
) -> Result<(f64, String), ImportError> {
    if let Some(f) =
        printer.optional_float(cfg, "minimum_cruise_ratio", Bound::AtLeastBelow(0.0, 1.0))?
    {
        return Ok((f.value, f.source("[printer] minimum_cruise_ratio", "")));
    }
    if let Some(f) = printer.optional_float(cfg, "max_accel_to_decel", Bound::Above(0.0))? {
        let mcr = 1.0 - (f.value / max_accel).min(1.0);
        return Ok((
            mcr,
            format!(
                "1 - max_accel_to_decel/max_accel, from the deprecated [printer] max_accel_to_decel (line {})",
                f.line.unwrap_or(0)
            ),
        ));
    }
    Ok((defaults::MINIMUM_CRUISE_RATIO, "Klipper default".into()))
}

/// Writes a section of figures Klipper does not know; absent ones become `# MISSING:`
/// comments (and entries of `missing`), so the loader names them.
fn write_estimated_section(
    y: &mut String,
    missing: &mut Vec<String>,
    section: &str,
    keys: &[(&str, Option<f64>, &str)],
) {
    if keys.iter().all(|(_, v, _)| v.is_none()) {
        let _ = writeln!(y, "{section}: {{}}  # nothing known, see below");
    } else {
        let _ = writeln!(y, "{section}:");
    }
    for (key, value, what) in keys {
        match value {
            Some(v) => {
                let _ = writeln!(
                    y,
                    "  {key}: {}  # {what}; given to the importer, not in the Klipper config",
                    num(*v)
                );
            }
            None => {
                let _ = writeln!(
                    y,
                    "  # MISSING: {section}.{key} — {what}; not in a Klipper config, add it (estimate or measure)"
                );
                missing.push(format!("{section}.{key}"));
            }
        }
    }
}

/// Shortest round-trip decimal that YAML reads as a float (`250.0`, `107.5`).
fn num(x: f64) -> String {
    format!("{x:?}")
}

fn one_line(s: &str) -> String {
    s.replace(['\n', '\r'], " ")
}

/// A number read from the config, with its line (None when a default was used).
#[derive(Clone, Debug, Default)]
struct Figure {
    value: f64,
    line: Option<usize>,
}

impl Figure {
    /// Comment text: "KEY (line N)" when read, else the default's description.
    fn source(&self, key: &str, default: &str) -> String {
        match self.line {
            Some(l) => format!("{key} (line {l})"),
            None => default.to_string(),
        }
    }
}

#[derive(Clone, Copy, Debug)]
enum Bound {
    Any,
    Above(f64),
    AtLeast(f64),
    AboveAtMost(f64, f64),
    AtLeastBelow(f64, f64),
}

impl Bound {
    fn check(self, x: f64) -> Result<(), String> {
        let ok = match self {
            Bound::Any => true,
            Bound::Above(a) => x > a,
            Bound::AtLeast(a) => x >= a,
            Bound::AboveAtMost(a, b) => x > a && x <= b,
            Bound::AtLeastBelow(a, b) => x >= a && x < b,
        };
        if ok {
            return Ok(());
        }
        Err(match self {
            Bound::Any => String::new(),
            Bound::Above(a) => format!("must be above {}, got {}", num(a), num(x)),
            Bound::AtLeast(a) => format!("must be at least {}, got {}", num(a), num(x)),
            Bound::AboveAtMost(a, b) => {
                format!(
                    "must be above {} and at most {}, got {}",
                    num(a),
                    num(b),
                    num(x)
                )
            }
            Bound::AtLeastBelow(a, b) => {
                format!(
                    "must be at least {} and below {}, got {}",
                    num(a),
                    num(b),
                    num(x)
                )
            }
        })
    }
}

#[derive(Clone, Debug)]
struct Entry {
    value: String,
    line: usize,
}

/// One `[section]`; `line` is its first header's line, 0 when the section is absent.
#[derive(Debug, Default)]
struct Section {
    name: String,
    line: usize,
    entries: HashMap<String, Entry>,
}

impl Section {
    fn missing(&self, cfg: &Config, key: &str) -> ImportError {
        ImportError::MissingKey {
            origin: cfg.origin.clone(),
            line: self.line,
            section: self.name.clone(),
            key: key.to_string(),
        }
    }

    fn required(&self, cfg: &Config, key: &str) -> Result<&Entry, ImportError> {
        self.entries.get(key).ok_or_else(|| self.missing(cfg, key))
    }

    fn optional_float(
        &self,
        cfg: &Config,
        key: &str,
        bound: Bound,
    ) -> Result<Option<Figure>, ImportError> {
        let Some(e) = self.entries.get(key) else {
            return Ok(None);
        };
        let bad = |message: String| ImportError::BadValue {
            origin: cfg.origin.clone(),
            line: e.line,
            section: self.name.clone(),
            key: key.to_string(),
            message,
        };
        let value: f64 = e
            .value
            .trim()
            .parse()
            .ok()
            .filter(|v: &f64| v.is_finite())
            .ok_or_else(|| bad(format!("expected a number, found `{}`", e.value)))?;
        bound.check(value).map_err(bad)?;
        Ok(Some(Figure {
            value,
            line: Some(e.line),
        }))
    }

    /// The key's number, or `default` (None: the key is required).
    fn float(
        &self,
        cfg: &Config,
        key: &str,
        default: Option<f64>,
        bound: Bound,
    ) -> Result<Figure, ImportError> {
        match (self.optional_float(cfg, key, bound)?, default) {
            (Some(f), _) => Ok(f),
            (None, Some(value)) => Ok(Figure { value, line: None }),
            (None, None) => Err(self.missing(cfg, key)),
        }
    }
}

/// A parsed Klipper configuration: sections merged (later values win, as with Klipper's
/// non-strict configparser and its SAVE_CONFIG block).
struct Config {
    origin: String,
    sections: HashMap<String, Section>,
    includes: Vec<(usize, String)>,
    /// Returned for absent sections: no entries, line 0.
    empty: Section,
}

impl Config {
    fn parse(text: &str, origin: &str) -> Result<Config, ImportError> {
        let mut cfg = Config {
            origin: origin.to_string(),
            sections: HashMap::new(),
            includes: Vec::new(),
            empty: Section::default(),
        };
        let syntax = |line: usize, message: String| ImportError::Syntax {
            origin: origin.to_string(),
            line,
            message,
        };
        let mut current = Current::Start;
        // The key a continuation line extends.
        let mut last_key: Option<String> = None;
        let mut autosave = false;
        for (i, raw) in text.lines().enumerate() {
            let line_no = i + 1;
            let mut line = raw;
            if autosave {
                // Inside the SAVE_CONFIG block every line is `#*# ...`.
                let Some(rest) = line.strip_prefix("#*#") else {
                    return Err(syntax(
                        line_no,
                        "line after the SAVE_CONFIG header does not start with `#*#`".into(),
                    ));
                };
                line = rest.strip_prefix(' ').unwrap_or(rest);
                if line.starts_with("DO NOT EDIT") {
                    continue; // the second line of Klipper's SAVE_CONFIG header
                }
            } else if line.starts_with("#*#") {
                if line.contains("SAVE_CONFIG") {
                    autosave = true;
                    current = Current::Start;
                    last_key = None;
                }
                continue;
            }
            let trimmed = line.trim();
            if trimmed.is_empty() || trimmed.starts_with('#') || trimmed.starts_with(';') {
                continue;
            }
            if line.starts_with([' ', '\t']) {
                // Continuation of a multi-line value (e.g. a macro's gcode).
                match (&current, &last_key) {
                    (Current::Named(s), Some(k)) => {
                        if let Some(e) = cfg.sections.get_mut(s).and_then(|s| s.entries.get_mut(k))
                        {
                            e.value.push('\n');
                            e.value.push_str(strip_inline_comment(trimmed).trim());
                        }
                    }
                    (Current::Include, _) => {}
                    _ => {
                        return Err(syntax(
                            line_no,
                            "indented line continues no `key: value`".into(),
                        ));
                    }
                }
                continue;
            }
            let content = strip_inline_comment(trimmed).trim();
            if let Some(rest) = content.strip_prefix('[') {
                let name = rest
                    .strip_suffix(']')
                    .ok_or_else(|| {
                        syntax(line_no, format!("section header `{content}` lacks `]`"))
                    })?
                    .trim();
                if name.is_empty() {
                    return Err(syntax(line_no, "empty section name `[]`".into()));
                }
                last_key = None;
                if let Some(file) = name.strip_prefix("include ") {
                    cfg.includes.push((line_no, file.trim().to_string()));
                    current = Current::Include;
                    continue;
                }
                cfg.sections
                    .entry(name.to_string())
                    .or_insert_with(|| Section {
                        name: name.to_string(),
                        line: line_no,
                        entries: HashMap::new(),
                    });
                current = Current::Named(name.to_string());
                continue;
            }
            let split = content.find([':', '=']).ok_or_else(|| {
                syntax(line_no, format!("expected `key: value`, found `{content}`"))
            })?;
            let key = content[..split].trim().to_ascii_lowercase();
            if key.is_empty() {
                return Err(syntax(
                    line_no,
                    format!("no key before `{}`", &content[split..=split]),
                ));
            }
            let value = content[split + 1..].trim().to_string();
            match &current {
                Current::Named(s) => {
                    if let Some(sec) = cfg.sections.get_mut(s) {
                        sec.entries.insert(
                            key.clone(),
                            Entry {
                                value,
                                line: line_no,
                            },
                        );
                    }
                    last_key = Some(key);
                }
                Current::Include => last_key = None,
                Current::Start => {
                    return Err(syntax(line_no, format!("`{key}` is outside any [section]")));
                }
            }
        }
        Ok(cfg)
    }

    fn section(&self, name: &str) -> Result<&Section, ImportError> {
        self.sections
            .get(name)
            .ok_or_else(|| ImportError::MissingSection {
                origin: self.origin.clone(),
                section: name.to_string(),
            })
    }

    fn optional_section(&self, name: &str) -> &Section {
        self.sections.get(name).unwrap_or(&self.empty)
    }
}

/// Where the parser is: before any header, inside an `[include]` (keys ignored), or in a
/// named section.
enum Current {
    Start,
    Include,
    Named(String),
}

/// Cuts an inline comment: `#` or `;` at the start or after whitespace (configparser's
/// `inline_comment_prefixes`, as Klipper sets them).
fn strip_inline_comment(s: &str) -> &str {
    let mut prev_ws = true;
    for (i, c) in s.char_indices() {
        if (c == '#' || c == ';') && prev_ws {
            return &s[..i];
        }
        prev_ws = c.is_whitespace();
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use yaml_serde::Value;

    const Q5: &str = include_str!("../tests/fixtures/klipper/flsun-q5-2020.cfg");
    const KOSSEL: &str = include_str!("../tests/fixtures/klipper/anycubic-kossel-plus-2017.cfg");
    const EDGE: &str = include_str!("../tests/fixtures/klipper/edge-cases.cfg");
    const CARTESIAN: &str = include_str!("../tests/fixtures/klipper/cartesian.cfg");
    const Q5_PROFILE: &str = include_str!("../machines/flsun-q5.yaml");

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
        let angles: Vec<f64> = v["geometry"]["tower_angles_deg"]
            .as_sequence()
            .map(|s| s.iter().filter_map(Value::as_f64).collect())
            .unwrap_or_default();
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
        let shipped: Value = yaml_serde::from_str(Q5_PROFILE)
            .unwrap_or_else(|e| panic!("machines/flsun-q5.yaml: {e}"));
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
        let arms: Vec<f64> = v["geometry"]["arm_length_mm"]
            .as_sequence()
            .map(|s| s.iter().filter_map(Value::as_f64).collect())
            .unwrap_or_default();
        assert_eq!(arms, [300.0, 301.0, 299.5]);
        let angles: Vec<f64> = v["geometry"]["tower_angles_deg"]
            .as_sequence()
            .map(|s| s.iter().filter_map(Value::as_f64).collect())
            .unwrap_or_default();
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
}
