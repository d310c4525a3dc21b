//! The shipped Marlin profiles hold the figures docs/printers.md gives with their sources
//! (Marlin's example configurations), and the loader reads them as written.

mod common;

use common::*;
use yaml_serde::Value;

/// Each shipped Marlin profile and the heading of its section in docs/printers.md.
const PROFILES: [(&str, &str); 2] = [
    ("machines/flsun-q5.yaml", "## FLSUN Q5 with Marlin"),
    (
        "machines/anycubic-kossel-linear-plus.yaml",
        "## Anycubic Kossel Linear Plus with Marlin",
    ),
];

/// A figure as the table writes it: a number, a list of numbers or a switch.
#[derive(Debug, PartialEq)]
enum Figure {
    Number(f64),
    List(Vec<f64>),
    Switch(bool),
}

fn parse_figure(text: &str) -> Figure {
    let t = text.trim();
    match t {
        "true" => return Figure::Switch(true),
        "false" => return Figure::Switch(false),
        _ => {}
    }
    if let Some(inner) = t.strip_prefix('[').and_then(|r| r.strip_suffix(']')) {
        return Figure::List(
            inner
                .split(',')
                .map(|v| v.trim().parse().unwrap_or_else(|e| panic!("{t:?}: {e}")))
                .collect(),
        );
    }
    Figure::Number(t.parse().unwrap_or_else(|e| panic!("{t:?}: {e}")))
}

fn from_value(v: &Value) -> Option<Figure> {
    if let Some(b) = v.as_bool() {
        return Some(Figure::Switch(b));
    }
    if let Some(x) = v.as_f64() {
        return Some(Figure::Number(x));
    }
    let list: Option<Vec<f64>> = v.as_sequence()?.iter().map(Value::as_f64).collect();
    list.map(Figure::List)
}

fn lookup<'a>(v: &'a Value, path: &str) -> &'a Value {
    path.split('.').fold(v, |cur, k| &cur[k])
}

/// The (profile key, profile value) rows of the section under `heading`.
fn documented(doc: &str, heading: &str) -> Vec<(String, Figure)> {
    let start = doc
        .find(heading)
        .unwrap_or_else(|| panic!("{heading:?} not in docs/printers.md"));
    let section = &doc[start + heading.len()..];
    let section = &section[..section.find("\n## ").unwrap_or(section.len())];
    section
        .lines()
        .filter(|l| l.starts_with("| `"))
        .filter_map(|l| {
            let cells: Vec<&str> = l.trim_matches('|').split('|').collect();
            assert_eq!(cells.len(), 5, "{l}");
            // A key cell starts with the key; "—" (with any words after it) has none.
            let key = cells[3].trim().strip_prefix('`')?.split('`').next()?;
            Some((key.to_string(), parse_figure(cells[4])))
        })
        .collect()
}

/// A key the schema does not hold yet, written as a comment (`  # ubl: true`).
fn commented(text: &str, leaf: &str) -> Option<Figure> {
    text.lines().find_map(|l| {
        let rest = l.trim_start().strip_prefix('#')?.trim_start();
        let value = rest.strip_prefix(leaf)?.strip_prefix(':')?;
        Some(parse_figure(value.split('#').next().unwrap_or_default()))
    })
}

#[test]
fn marlin_profiles_hold_the_documented_figures() {
    let doc = std::fs::read_to_string(repo("docs/printers.md")).unwrap();
    for (path, heading) in PROFILES {
        let text = std::fs::read_to_string(repo(path)).unwrap();
        let yaml: Value = yaml_serde::from_str(&text).unwrap();
        let o = run(&[
            "machine",
            &repo(path).display().to_string(),
            "--format",
            "json",
        ]);
        assert_eq!(o.status.code(), Some(0), "{path}: {}", stderr(&o));
        let loaded: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!(loaded["firmware"], "marlin", "{path}");
        let rows = documented(&doc, heading);
        assert!(rows.len() >= 30, "{path}: {} rows", rows.len());
        for (key, want) in &rows {
            let leaf = key.rsplit('.').next().unwrap_or(key);
            let got = from_value(lookup(&yaml, key)).or_else(|| commented(&text, leaf));
            assert_eq!(got.as_ref(), Some(want), "{path}: {key}");
            if let Some(m) = key.strip_prefix("marlin.") {
                // The loader keeps each Marlin figure as written (a key it does not know
                // yet is the commented one above, absent here).
                let v = &loaded["marlin"][m];
                if !v.is_null() {
                    let got = match want {
                        Figure::Switch(_) => v.as_bool().map(Figure::Switch),
                        Figure::Number(_) => v.as_f64().map(Figure::Number),
                        Figure::List(_) => v
                            .as_array()
                            .and_then(|a| a.iter().map(|x| x.as_f64()).collect())
                            .map(Figure::List),
                    };
                    assert_eq!(got.as_ref(), Some(want), "{path}: loaded {key}");
                } else {
                    assert!(lookup(&yaml, key).is_null(), "{path}: {key} not loaded");
                }
            }
        }
        // Every figure of the profile's `marlin` and `geometry` is in the table.
        for section in ["marlin", "geometry"] {
            let keys = yaml[section].as_mapping().unwrap();
            for k in keys.keys().filter_map(Value::as_str) {
                let full = format!("{section}.{k}");
                if full == "geometry.nozzle_offset_mm" {
                    continue; // 0: Marlin's kinematics have no such offset
                }
                assert!(
                    rows.iter().any(|(key, _)| *key == full),
                    "{path}: {full} not documented"
                );
            }
        }
    }
}

#[test]
fn the_table_parser_reads_what_it_must() {
    // The parser the test above relies on, on rows written by hand.
    let doc = "## X\n| `A` | 1 | C.h:1 | `marlin.ubl` ³ | true |\n\
               | `B` | {1, 2} | C.h:2 | `marlin.jerk_mm_s` | [10, 10, 10, 5] |\n\
               | `C` | 3 | C.h:3 | — | — |\n| `E` | 5 | C.h:5 | — (in `C`) | — |\n## Y\n| `D` | 4 | C.h:4 | `a.b` | 4 |\n";
    assert_eq!(
        documented(doc, "## X"),
        vec![
            ("marlin.ubl".to_string(), Figure::Switch(true)),
            (
                "marlin.jerk_mm_s".to_string(),
                Figure::List(vec![10.0, 10.0, 10.0, 5.0])
            ),
        ]
    );
    let text = "marlin:\n  s_curve: true\n  # ubl: true   # C.h:1917\n  # n_arc_correction: 25\n";
    assert_eq!(commented(text, "ubl"), Some(Figure::Switch(true)));
    assert_eq!(
        commented(text, "n_arc_correction"),
        Some(Figure::Number(25.0))
    );
    assert_eq!(commented(text, "s_curve"), None);
}
