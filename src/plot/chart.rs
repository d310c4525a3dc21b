//! Line charts: series against a shared x axis, a legend, optional horizontal lines.

use plotters::prelude::*;

/// One curve. Points need not be finite: non-finite ones are left out (never drawn as NaN).
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    /// Legend entry.
    pub name: String,
    /// (x, y) in increasing x.
    pub points: Vec<(f64, f64)>,
}

/// A horizontal reference line across the whole chart (a limit, an expected value).
#[derive(Clone, Debug, PartialEq)]
pub struct HLine {
    pub y: f64,
    /// Legend entry.
    pub name: String,
}

/// What [`line_chart_string`] draws.
#[derive(Clone, Copy, Debug)]
pub struct LineChart<'a> {
    pub title: &'a str,
    pub x_desc: &'a str,
    pub y_desc: &'a str,
    pub series: &'a [Series],
    pub hlines: &'a [HLine],
}

const SIZE_PX: (u32, u32) = (960, 540);
/// Points kept per series: 4 per bucket (see [`decimate`]), a bucket per pixel column.
const BUCKETS: usize = SIZE_PX.0 as usize;

/// Tableau 10: distinct on white and for the common colour-vision deficiencies.
const PALETTE: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(23, 190, 207),
];
/// Reference lines: black, then greys.
const HLINE_COLOURS: [RGBColor; 3] = [
    RGBColor(0, 0, 0),
    RGBColor(110, 110, 110),
    RGBColor(170, 170, 170),
];

/// Renders the chart as an SVG document.
pub fn line_chart_string(chart: &LineChart) -> anyhow::Result<String> {
    let series: Vec<(&str, Vec<(f64, f64)>)> = chart
        .series
        .iter()
        .map(|s| (s.name.as_str(), decimate(&finite(&s.points), BUCKETS)))
        .collect();
    let hlines: Vec<&HLine> = chart.hlines.iter().filter(|h| h.y.is_finite()).collect();
    // plotters places ticks badly on spans near the f64 resolution (1e-16 W residuals):
    // such values are drawn scaled by a power of ten, named in the axis description.
    let biggest = series
        .iter()
        .flat_map(|(_, p)| p.iter().map(|p| p.1.abs()))
        .chain(hlines.iter().map(|h| h.y.abs()))
        .fold(0.0, f64::max);
    let exponent = if biggest > 0.0 && !(1e-6..1e9).contains(&biggest) {
        biggest.log10().floor() as i32
    } else {
        0
    };
    let y_scale = 10f64.powi(-exponent);
    let series: Vec<(&str, Vec<(f64, f64)>)> = series
        .into_iter()
        .map(|(n, p)| (n, p.into_iter().map(|(x, y)| (x, y * y_scale)).collect()))
        .collect();
    let y_desc = if exponent == 0 {
        chart.y_desc.to_string()
    } else {
        format!("{} (×1e{exponent})", chart.y_desc)
    };
    let xs = series.iter().flat_map(|(_, p)| p.iter().map(|p| p.0));
    let ys = series.iter().flat_map(|(_, p)| p.iter().map(|p| p.1));
    let (x0, x1) = padded_range(xs, 0.0);
    let hline_ys = hlines.iter().map(|h| h.y * y_scale);
    let (y0, y1) = padded_range(ys.chain(hline_ys), 0.05);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, SIZE_PX).into_drawing_area();
        root.fill(&WHITE)?;
        let mut ctx = ChartBuilder::on(&root)
            .caption(chart.title, ("sans-serif", 22))
            .margin(12)
            .x_label_area_size(45)
            .y_label_area_size(75)
            .build_cartesian_2d(x0..x1, y0..y1)?;
        ctx.configure_mesh()
            .x_desc(chart.x_desc)
            .y_desc(&y_desc)
            .x_label_formatter(&|v| tick_label(*v, x1 - x0))
            .y_label_formatter(&|v| tick_label(*v, y1 - y0))
            .light_line_style(RGBColor(235, 235, 235))
            .label_style(("sans-serif", 14))
            .draw()?;
        for (i, (name, points)) in series.into_iter().enumerate() {
            let colour = PALETTE[i % PALETTE.len()];
            ctx.draw_series(LineSeries::new(points, colour.stroke_width(2)))?
                .label(name)
                .legend(move |(x, y)| {
                    PathElement::new([(x, y), (x + 20, y)], colour.stroke_width(3))
                });
        }
        for (i, h) in hlines.into_iter().enumerate() {
            let colour = HLINE_COLOURS[i.min(HLINE_COLOURS.len() - 1)];
            ctx.draw_series(LineSeries::new(
                [(x0, h.y), (x1, h.y)],
                colour.stroke_width(1),
            ))?
            .label(h.name.as_str())
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], colour.stroke_width(1)));
        }
        ctx.configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .background_style(WHITE.mix(0.85))
            .border_style(RGBColor(160, 160, 160))
            .label_font(("sans-serif", 14))
            .draw()?;
        root.present()?;
    }
    Ok(svg)
}

fn finite(points: &[(f64, f64)]) -> Vec<(f64, f64)> {
    points
        .iter()
        .copied()
        .filter(|(x, y)| x.is_finite() && y.is_finite())
        .collect()
}

/// The range of `values` widened by `pad` of its span on both sides; a point or an empty set
/// gets a unit-size range around it, so the axis is never degenerate.
fn padded_range(values: impl Iterator<Item = f64>, pad: f64) -> (f64, f64) {
    let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
        (lo.min(v), hi.max(v))
    });
    if lo > hi {
        return (0.0, 1.0);
    }
    let span = hi - lo;
    if span <= 1e-300_f64.max(1e-12 * lo.abs().max(hi.abs())) {
        let half = if lo == 0.0 { 1.0 } else { 0.1 * lo.abs() };
        return (lo - half, hi + half);
    }
    (lo - pad * span, hi + pad * span)
}

/// A tick label short enough for the axis: scientific for tiny or huge spans, else as few
/// decimals as the span needs.
fn tick_label(v: f64, span: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    if !(1e-3..1e6).contains(&span) {
        return format!("{v:.2e}");
    }
    let decimals = (2.0 - span.log10().floor()).clamp(0.0, 6.0) as usize;
    let text = format!("{v:.decimals$}");
    // A tick a rounding error below zero would read "-0.00".
    if text.trim_start_matches(['-', '0', '.']).is_empty() {
        "0".into()
    } else {
        text
    }
}

/// Keeps, in each of `buckets` equal x intervals, the first, lowest, highest and last point
/// (the M4 reduction): the drawn line is the same at one bucket per pixel column, peaks
/// included, with at most 4 points per bucket. Points must be in increasing x.
pub(crate) fn decimate(points: &[(f64, f64)], buckets: usize) -> Vec<(f64, f64)> {
    if points.len() <= 4 * buckets {
        return points.to_vec();
    }
    let (x0, x1) = (points[0].0, points[points.len() - 1].0);
    let width = (x1 - x0) / buckets as f64;
    let bucket_of = |x: f64| (((x - x0) / width) as usize).min(buckets - 1);
    let mut out = Vec::with_capacity(4 * buckets);
    let mut start = 0;
    while start < points.len() {
        let b = bucket_of(points[start].0);
        let end = start
            + points[start..]
                .iter()
                .position(|p| bucket_of(p.0) != b)
                .unwrap_or(points.len() - start);
        let chunk = &points[start..end];
        let lowest = (0..chunk.len()).fold(0, |m, k| if chunk[k].1 < chunk[m].1 { k } else { m });
        let highest = (0..chunk.len()).fold(0, |m, k| if chunk[k].1 > chunk[m].1 { k } else { m });
        let mut keep = [0, lowest, highest, chunk.len() - 1];
        keep.sort_unstable();
        let mut last = usize::MAX;
        for k in keep {
            if k != last {
                out.push(chunk[k]);
                last = k;
            }
        }
        start = end;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plot::tests::assert_valid_svg;

    #[test]
    fn decimation_keeps_every_peak_and_the_ends() {
        let points: Vec<(f64, f64)> = (0..100_000)
            .map(|k| {
                let x = k as f64 * 1e-3;
                (x, (7.0 * x).sin() + if k == 54_321 { 5.0 } else { 0.0 })
            })
            .collect();
        let d = decimate(&points, 500);
        assert!(d.len() <= 2000, "{}", d.len());
        assert_eq!(d[0], points[0]);
        assert_eq!(d[d.len() - 1], points[points.len() - 1]);
        assert!(d.contains(&points[54_321]), "the spike survives");
        let min = points.iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
        assert!(d.iter().any(|p| p.1 == min));
        assert!(d.windows(2).all(|w| w[0].0 < w[1].0), "order kept");
        // Short series are untouched.
        assert_eq!(decimate(&points[..100], 500), points[..100].to_vec());
    }

    #[test]
    fn ranges_are_never_degenerate() {
        assert_eq!(padded_range([].into_iter(), 0.05), (0.0, 1.0));
        assert_eq!(padded_range([0.0, 0.0].into_iter(), 0.05), (-1.0, 1.0));
        let (lo, hi) = padded_range([13.4].into_iter(), 0.05);
        assert!(lo < 13.4 && hi > 13.4);
        assert_eq!(padded_range([0.0, 10.0].into_iter(), 0.1), (-1.0, 11.0));
    }

    #[test]
    fn tick_labels_fit_the_span() {
        assert_eq!(tick_label(12.5, 40.0), "12.5");
        assert_eq!(tick_label(100.0, 400.0), "100");
        assert_eq!(tick_label(3e-13, 1e-12), "3.00e-13");
        assert_eq!(tick_label(0.0, 1e-12), "0");
        assert_eq!(tick_label(-1e-17, 1.2), "0");
        assert_eq!(tick_label(-0.2, 1.2), "-0.20");
    }

    #[test]
    fn chart_has_every_series_in_its_legend_and_no_nan() {
        let series = [
            Series {
                name: "alpha".into(),
                points: vec![(0.0, 1.0), (1.0, f64::NAN), (2.0, 3.0)],
            },
            Series {
                name: "beta".into(),
                points: vec![(0.0, 2.0), (2.0, 2.5)],
            },
        ];
        let hlines = [HLine {
            y: 2.75,
            name: "ref".into(),
        }];
        let svg = line_chart_string(&LineChart {
            title: "T",
            x_desc: "t (s)",
            y_desc: "y",
            series: &series,
            hlines: &hlines,
        })
        .unwrap();
        assert_valid_svg(&svg);
        for text in ["alpha", "beta", "ref", "t (s)", ">\nT\n</text>"] {
            assert!(svg.contains(text), "{text}");
        }
        // Residuals at the f64 resolution are drawn scaled, the scale named on the axis.
        let tiny = [Series {
            name: "residual".into(),
            points: vec![(0.0, 3e-16), (1.0, -5e-16), (2.0, 8e-16)],
        }];
        let svg = line_chart_string(&LineChart {
            title: "",
            x_desc: "",
            y_desc: "W",
            series: &tiny,
            hlines: &[],
        })
        .unwrap();
        assert_valid_svg(&svg);
        assert!(svg.contains("W (×1e-16)"));
        // Empty input: an empty frame, still valid.
        let svg = line_chart_string(&LineChart {
            title: "",
            x_desc: "",
            y_desc: "",
            series: &[],
            hlines: &[],
        })
        .unwrap();
        assert_valid_svg(&svg);
    }
}
