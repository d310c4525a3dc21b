//! Writes the imported profile: YAML in the profile's schema (docs/machine-profile.md),
//! every key with a comment naming its source. One loop over the keys, in order; a section
//! starts where the keys' section changes.

use super::num;

/// One key of the profile, in the order it is written.
pub(super) struct ProfileKey {
    pub(super) section: &'static str,
    pub(super) key: &'static str,
    pub(super) value: Value,
}

/// A key's value, or why it is left out.
pub(super) enum Value {
    /// `key: yaml  # source`.
    Known { yaml: String, source: String },
    /// Not in the config: a comment, and the profile loader applies Klipper's default.
    LoaderDefault,
    /// Known, but not used by the profile's form: `# key: yaml  # source`, for the user to
    /// take up (the motor's figures next to `max_force_n`).
    Commented { yaml: String, source: String },
    /// Not known to Klipper and not given to the importer: a `# MISSING:` comment saying
    /// what it is, and an entry of [`super::ImportedProfile::missing`], so that the loader
    /// refuses the profile until it is added.
    Missing { what: &'static str },
}

impl ProfileKey {
    pub(super) fn known(
        section: &'static str,
        key: &'static str,
        yaml: String,
        source: impl Into<String>,
    ) -> ProfileKey {
        let source = source.into();
        ProfileKey {
            section,
            key,
            value: Value::Known { yaml, source },
        }
    }

    /// The same key, written as a comment.
    pub(super) fn commented(self) -> ProfileKey {
        let value = match self.value {
            Value::Known { yaml, source } => Value::Commented { yaml, source },
            other => other,
        };
        ProfileKey { value, ..self }
    }

    /// A number, with its source.
    pub(super) fn number(
        section: &'static str,
        key: &'static str,
        value: f64,
        source: impl Into<String>,
    ) -> ProfileKey {
        ProfileKey::known(section, key, num(value), source)
    }

    /// A list of three numbers (towers A, B, C), with its source.
    pub(super) fn towers(
        section: &'static str,
        key: &'static str,
        [a, b, c]: [f64; 3],
        source: impl Into<String>,
    ) -> ProfileKey {
        let yaml = format!("[{}, {}, {}]", num(a), num(b), num(c));
        ProfileKey::known(section, key, yaml, source)
    }
}

/// The profile's YAML: a header naming the configuration `origin`, the profile's `name`,
/// then the keys by section. A section with no known key is written `{}`, an empty
/// mapping, so that the loader names its first missing key.
pub(super) fn write(origin: &str, name: &str, keys: &[ProfileKey]) -> String {
    let name = serde_json::to_string(name).unwrap_or_else(|_| "\"imported\"".into());
    let mut lines = vec![
        format!("# Machine profile imported from the Klipper configuration {origin}"),
        "# by delta-gcode's Klipper importer. Line numbers refer to that file.".to_string(),
        format!("name: {name}"),
    ];
    for section in keys.chunk_by(|a, b| a.section == b.section) {
        let title = section[0].section;
        if section
            .iter()
            .any(|k| matches!(k.value, Value::Known { .. }))
        {
            lines.push(format!("{title}:"));
        } else {
            lines.push(format!("{title}: {{}}  # nothing known, see below"));
        }
        for ProfileKey { key, value, .. } in section {
            lines.push(match value {
                Value::Known { yaml, source } => format!("  {key}: {yaml}  # {source}"),
                Value::Commented { yaml, source } => format!(
                    "  # {key}: {yaml}  # {source}; for the torque form, not with max_force_n"
                ),
                Value::LoaderDefault => {
                    format!("  # {key}: not set; the loader applies Klipper's default")
                }
                Value::Missing { what } => format!(
                    "  # MISSING: {title}.{key} — {what}; not in a Klipper config, add it \
                     (estimate or measure)"
                ),
            });
        }
    }
    lines.push(String::new());
    lines.join("\n")
}

/// The dotted keys left out as missing.
pub(super) fn missing(keys: &[ProfileKey]) -> Vec<String> {
    keys.iter()
        .filter(|k| matches!(k.value, Value::Missing { .. }))
        .map(|k| format!("{}.{}", k.section, k.key))
        .collect()
}
