//! Where a profile error is. The YAML parser's errors (syntax, unknown key, wrong type,
//! missing key) carry their line and column and the dotted key; an unknown key gets the
//! closest valid name. The errors found after parsing carry only the dotted key, which
//! [`locate_key`] finds in the text.

use super::ProfileError;

/// Turns a YAML parser error into a [`ProfileError::Schema`], adding the closest valid name
/// to an unknown key.
pub(super) fn schema_error(e: &yaml_serde::Error, origin: &str) -> ProfileError {
    let mut message = e.to_string();
    if let Some(at) = message.rfind(" at line ") {
        message.truncate(at);
    }
    message = message.replace("expected f64", "expected a number");
    if let Some(hint) = suggest_field(&message) {
        message.push_str(&format!(" (did you mean `{hint}`?)"));
    }
    ProfileError::Schema {
        origin: origin.to_string(),
        location: e.location().map(|l| (l.line(), l.column())),
        message,
    }
}

/// The closest valid name to an unknown key, from serde's own wording (the derive's
/// `deny_unknown_fields` calls `serde::de::Error::unknown_field`): "unknown field `x`,
/// expected `a`" or "unknown field `x`, expected one of `a`, `b`". The valid names are the
/// schema's and hold no backtick; the unknown one may, so it ends at the last "`, expected".
fn suggest_field(message: &str) -> Option<String> {
    let (_, rest) = message.split_once("unknown field `")?;
    let at = rest.rfind("`, expected ")?;
    let (unknown, expected) = (&rest[..at], &rest[at + "`, expected ".len()..]);
    expected
        .split('`')
        .skip(1)
        .step_by(2)
        .map(|name| (edit_distance(unknown, name), name))
        .filter(|&(d, name)| d <= name.len().max(unknown.len()) / 2)
        .min_by_key(|&(d, _)| d)
        .map(|(_, name)| name.to_string())
}

/// Levenshtein distance (insert, delete, substitute), on chars.
pub(super) fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut diag = row[0];
        row[0] = i + 1;
        for (j, &cb) in b.iter().enumerate() {
            let next = (diag + usize::from(ca != cb))
                .min(row[j] + 1)
                .min(row[j + 1] + 1);
            diag = row[j + 1];
            row[j + 1] = next;
        }
    }
    row[b.len()]
}

/// Line and column (1-based) of a dotted key such as `geometry.arm_length_mm` in the YAML
/// text: the section at indent 0, then the key indented below it or inside a flow mapping
/// (`masses: {cart_kg: 0.2, …}`); the section's line when the key is not written (a
/// default). Best effort: validation runs on the parsed values, which carry no position.
pub(super) fn locate_key(text: &str, dotted: &str) -> Option<(usize, usize)> {
    let mut parts = dotted.split('.');
    let first = parts.next()?;
    let second = parts.next();
    let mut section_line = None;
    for (n, line) in text.lines().enumerate() {
        let trimmed = line.trim_start();
        let indent = line.len() - trimmed.len();
        if indent == 0 && !trimmed.is_empty() && !trimmed.starts_with('#') {
            if section_line.is_some() {
                break;
            }
            if is_key(trimmed, first) {
                let Some(key) = second else {
                    return Some((n + 1, 1));
                };
                section_line = Some(n + 1);
                if let Some(col) = flow_key_column(line, key) {
                    return Some((n + 1, col));
                }
            }
        } else if let (Some(_), Some(key)) = (section_line, second) {
            if is_key(trimmed, key) {
                return Some((n + 1, indent + 1));
            }
            if let Some(col) = flow_key_column(line, key) {
                return Some((n + 1, col));
            }
        }
    }
    section_line.map(|l| (l, 1))
}

/// Whether `trimmed` (a line without its indent) starts with the key `k`.
fn is_key(trimmed: &str, k: &str) -> bool {
    trimmed
        .strip_prefix(k)
        .is_some_and(|r| r.trim_start().starts_with(':'))
}

/// The 1-based column of `key:` inside a flow mapping on `line` (after `{` or `,`), before
/// any comment.
fn flow_key_column(line: &str, key: &str) -> Option<usize> {
    let code = line.find(" #").map_or(line, |at| &line[..at]);
    let mut from = 0;
    while let Some(at) = code[from..].find(key).map(|i| i + from) {
        let before = code[..at].trim_end();
        if (before.ends_with('{') || before.ends_with(',')) && is_key(&code[at..], key) {
            return Some(code[..at].chars().count() + 1);
        }
        from = at + key.len();
    }
    None
}
