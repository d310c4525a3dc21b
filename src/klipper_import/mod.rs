//! Imports a Klipper linear-delta configuration (`printer.cfg`) as a machine profile: YAML
//! text in the profile's schema (docs/machine-profile.md).
//!
//! What Klipper knows is copied with the defaults Klipper applies (`klippy/toolhead.py`,
//! `klippy/kinematics/delta.py`, `klippy/kinematics/extruder.py`). What Klipper does not
//! know — the masses and the motor force — is taken from [`ImportExtras`] or left out of
//! the YAML with a `# MISSING:` comment, so the profile loader refuses the profile and names
//! the key.
//!
//! Three steps, a module each: `ini` reads Klipper's config syntax, `rules` turns the
//! values into profile keys as Klipper reads them (with the constants of
//! [`crate::machine::defaults`]), `writer` writes them as commented YAML. `[include …]` is
//! not followed; it is reported in [`ImportedProfile::notes`].

mod ini;
mod motion_rules;
mod rules;
#[cfg(test)]
mod tests;
mod writer;

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
    /// Profile YAML (docs/machine-profile.md), with comments naming where each figure came
    /// from.
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
    let cfg = ini::Config::parse(cfg_text, origin)?;
    let mut notes: Vec<String> = cfg
        .includes
        .iter()
        .map(|(line, file)| {
            format!("line {line}: [include {file}] not followed; keys from it are not imported")
        })
        .collect();
    let keys = rules::profile_keys(&cfg, extra, &mut notes)?;
    // The file's name on one line, for the YAML's comments and the default profile name.
    let origin_line = origin.replace(['\n', '\r'], " ");
    let name = extra
        .name
        .clone()
        .unwrap_or_else(|| format!("Imported from {origin_line}"));
    Ok(ImportedProfile {
        yaml: writer::write(&origin_line, &name, &keys),
        missing: writer::missing(&keys),
        notes,
    })
}

/// A number as the importer writes it, in messages and in the YAML: the shortest decimal
/// that reads back the same, and that YAML reads as a float (`250.0`, `107.5`).
fn num(x: f64) -> String {
    format!("{x:?}")
}
