//! SVG charts of a trace (plotters, SVG backend only: no system font is needed, the text is
//! left to the SVG viewer).
//!
//! [`line_chart_svg`] draws any series against a common x axis (the `plot` subcommand);
//! [`force_time_svg`] and [`bed_map_svg`] are the two figures of `check --plot`.

mod bed;
mod chart;
mod trace_csv;

use std::path::Path;

use anyhow::Context;

pub use bed::{bed_map_string, bed_map_svg};
pub use chart::{HLine, LineChart, Series, line_chart_string};
pub use trace_csv::read_trace_columns;

use crate::delta::TOWER_NAMES;

/// Writes a [`LineChart`] to `path` as SVG.
pub fn line_chart_svg(path: &Path, chart: &LineChart) -> anyhow::Result<()> {
    write_svg(path, &line_chart_string(chart)?)
}

/// The three carriage forces against time, with the motor limit (and its negative when a
/// force pulls downwards).
pub fn force_time_svg(
    path: &Path,
    title: &str,
    t_s: &[f64],
    forces_n: &[[f64; 3]],
    limit_n: f64,
) -> anyhow::Result<()> {
    write_svg(path, &force_time_string(title, t_s, forces_n, limit_n)?)
}

/// [`force_time_svg`] into a string.
pub fn force_time_string(
    title: &str,
    t_s: &[f64],
    forces_n: &[[f64; 3]],
    limit_n: f64,
) -> anyhow::Result<String> {
    anyhow::ensure!(
        t_s.len() == forces_n.len(),
        "{} times for {} force triples",
        t_s.len(),
        forces_n.len()
    );
    let series: Vec<Series> = (0..3)
        .map(|i| Series {
            name: format!("Q{} (tower {})", i + 1, TOWER_NAMES[i]),
            points: t_s.iter().zip(forces_n).map(|(&t, f)| (t, f[i])).collect(),
        })
        .collect();
    let mut hlines = vec![HLine {
        y: limit_n,
        name: format!("limit {limit_n} N"),
    }];
    if forces_n.iter().flatten().any(|&f| f < 0.0) {
        hlines.push(HLine {
            y: -limit_n,
            name: format!("limit −{limit_n} N"),
        });
    }
    line_chart_string(&LineChart {
        title,
        x_desc: "t (s)",
        y_desc: "carriage force (N)",
        series: &series,
        hlines: &hlines,
    })
}

fn write_svg(path: &Path, svg: &str) -> anyhow::Result<()> {
    std::fs::write(path, svg).with_context(|| format!("writing {}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The checks every written SVG must pass.
    pub(crate) fn assert_valid_svg(svg: &str) {
        assert!(svg.contains("<svg"), "no <svg element");
        assert!(svg.trim_end().ends_with("</svg>"), "unterminated");
        assert!(
            !svg.contains("NaN") && !svg.contains("inf"),
            "non-finite number"
        );
    }

    #[test]
    fn force_time_draws_three_towers_and_the_limit() {
        let t: Vec<f64> = (0..500).map(|k| k as f64 * 0.01).collect();
        let f: Vec<[f64; 3]> = t
            .iter()
            .map(|t| [4.0 + t.sin(), 4.5 + t.cos(), 5.0 - 20.0 * (3.0 * t).sin()])
            .collect();
        let svg = force_time_string("test", &t, &f, 12.5).unwrap();
        assert_valid_svg(&svg);
        for name in [
            "Q1 (tower A)",
            "Q2 (tower B)",
            "Q3 (tower C)",
            "limit 12.5 N",
        ] {
            assert!(svg.contains(name), "{name}");
        }
        // Q3 goes below zero: the negative limit is drawn too.
        assert!(svg.contains("limit −12.5 N"));
        // Each tower's curve in its colour (Tableau blue, red, green).
        for colour in ["#1F77B4", "#D62728", "#2CA02C"] {
            let stroke = format!("<polyline fill=\"none\" opacity=\"1\" stroke=\"{colour}\"");
            assert!(
                svg.matches(&stroke).count() >= 2,
                "{colour}: curve and legend"
            );
        }
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("f.svg");
        force_time_svg(&path, "test", &t, &f, 12.5).unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), svg);
        // Mismatched lengths are an error, not a panic.
        assert!(force_time_string("x", &t[..3], &f, 1.0).is_err());
        // A missing directory is a clear error.
        let e = force_time_svg(&dir.path().join("no/f.svg"), "x", &t, &f, 1.0).unwrap_err();
        assert!(format!("{e:#}").contains("writing"), "{e:#}");
    }
}
