//! Klipper's configuration syntax (Python `configparser` as klippy/configfile.py sets it
//! up): `[section]` headers, `key: value` or `key = value` (keys lower-cased), whole-line
//! comments starting with `#` or `;`, inline comments after whitespace, indented
//! continuation lines, and the `#*#` SAVE_CONFIG block at the end, whose values override
//! the ones above it (as Klipper does). `[include …]` is not followed; its line is kept in
//! [`Config::includes`]. Numbers are read as configfile.py's `getfloat` reads them, with
//! its bounds ([`Bound`]).

use std::collections::HashMap;

use super::{ImportError, num};

/// A number read from the config: its value and where it came from.
#[derive(Clone, Debug)]
pub(super) struct Figure {
    pub(super) value: f64,
    /// The line it was read from; None when the key is absent and a default was used.
    pub(super) line: Option<usize>,
    /// `[section] key`.
    label: String,
}

impl Figure {
    /// Where the value came from: "[section] key (line N)" when read, else `default`, the
    /// default's description.
    pub(super) fn source(&self, default: &str) -> String {
        match self.line {
            Some(l) => format!("{} (line {l})", self.label),
            None => default.to_string(),
        }
    }
}

/// The bounds of configfile.py `ConfigWrapper.getfloat` (`minval`, `maxval`, `above`,
/// `below`) as Klipper's readers use them.
#[derive(Clone, Copy, Debug)]
pub(super) enum Bound {
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

/// A `key: value` of a section; continuation lines are joined with `\n`.
#[derive(Clone, Debug)]
pub(super) struct Entry {
    pub(super) value: String,
    pub(super) line: usize,
}

/// One `[section]`; `line` is its first header's line, 0 when the section is absent.
#[derive(Debug, Default)]
pub(super) struct Section {
    name: String,
    pub(super) line: usize,
    entries: HashMap<String, Entry>,
}

impl Section {
    fn label(&self, key: &str) -> String {
        format!("[{}] {key}", self.name)
    }

    fn missing(&self, cfg: &Config, key: &str) -> ImportError {
        ImportError::MissingKey {
            origin: cfg.origin.clone(),
            line: self.line,
            section: self.name.clone(),
            key: key.to_string(),
        }
    }

    pub(super) fn required(&self, cfg: &Config, key: &str) -> Result<&Entry, ImportError> {
        self.entries.get(key).ok_or_else(|| self.missing(cfg, key))
    }

    /// The key's entry, None when it is absent.
    pub(super) fn optional(&self, key: &str) -> Option<&Entry> {
        self.entries.get(key)
    }

    /// The section's name.
    pub(super) fn name(&self) -> &str {
        &self.name
    }

    /// `[section] key`, for sources and notes.
    pub(super) fn key_label(&self, key: &str) -> String {
        self.label(key)
    }

    /// A [`ImportError::BadValue`] at the key's line (the header's when it is absent).
    pub(super) fn bad_value(&self, cfg: &Config, key: &str, message: String) -> ImportError {
        ImportError::BadValue {
            origin: cfg.origin.clone(),
            line: self.entries.get(key).map_or(self.line, |e| e.line),
            section: self.name.clone(),
            key: key.to_string(),
            message,
        }
    }

    /// The key's number, None when the key is absent.
    pub(super) fn optional_float(
        &self,
        cfg: &Config,
        key: &str,
        bound: Bound,
    ) -> Result<Option<Figure>, ImportError> {
        let Some(e) = self.entries.get(key) else {
            return Ok(None);
        };
        let bad = |message: String| self.bad_value(cfg, key, message);
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
            label: self.label(key),
        }))
    }

    /// The key's number, or `default` (None: the key is required).
    pub(super) fn float(
        &self,
        cfg: &Config,
        key: &str,
        default: Option<f64>,
        bound: Bound,
    ) -> Result<Figure, ImportError> {
        match (self.optional_float(cfg, key, bound)?, default) {
            (Some(f), _) => Ok(f),
            (None, Some(value)) => Ok(Figure {
                value,
                line: None,
                label: self.label(key),
            }),
            (None, None) => Err(self.missing(cfg, key)),
        }
    }
}

/// A parsed Klipper configuration: sections merged (later values win, as with Klipper's
/// non-strict configparser and its SAVE_CONFIG block).
pub(super) struct Config {
    /// The file's name, for messages.
    pub(super) origin: String,
    sections: HashMap<String, Section>,
    /// `[include FILE]` headers, with their lines.
    pub(super) includes: Vec<(usize, String)>,
    /// Returned for absent sections: no entries, line 0.
    empty: Section,
}

impl Config {
    /// Reads a configuration's text; `origin` names it in errors. A line that is none of a
    /// header, a `key: value`, a continuation or a comment is a syntax error at its line.
    pub(super) fn parse(text: &str, origin: &str) -> Result<Config, ImportError> {
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

    /// A required section.
    pub(super) fn section(&self, name: &str) -> Result<&Section, ImportError> {
        self.sections
            .get(name)
            .ok_or_else(|| ImportError::MissingSection {
                origin: self.origin.clone(),
                section: name.to_string(),
            })
    }

    /// A section, or an empty one (line 0) when it is absent.
    pub(super) fn optional_section(&self, name: &str) -> &Section {
        self.sections.get(name).unwrap_or(&self.empty)
    }

    /// The sections whose name passes `pred`, in the order of the file.
    pub(super) fn sections_where(&self, pred: impl Fn(&str) -> bool) -> Vec<&Section> {
        let mut found: Vec<&Section> = self.sections.values().filter(|s| pred(&s.name)).collect();
        found.sort_by_key(|s| s.line);
        found
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
pub(super) fn strip_inline_comment(s: &str) -> &str {
    let mut prev_ws = true;
    for (i, c) in s.char_indices() {
        if (c == '#' || c == ';') && prev_ws {
            return &s[..i];
        }
        prev_ws = c.is_whitespace();
    }
    s
}
