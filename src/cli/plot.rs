//! `delta-gcode plot TRACE.csv... -o OUT.svg --column f1_n [--sum f1_n,f2_n,f3_n] …`:
//! chosen trace columns against time (or another column), one series per file and column.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, bail};

use delta_gcode::delta::{self, DeltaModel};
use delta_gcode::machine::Machine;
use delta_gcode::path::Vec3;
use delta_gcode::plot::{HLine, LineChart, Series, line_chart_svg, read_trace_columns};

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Trace CSV files (`delta-gcode trace`)
    #[arg(value_name = "TRACE.csv", required = true)]
    pub traces: Vec<PathBuf>,
    /// SVG output
    #[arg(long, short, value_name = "OUT.svg")]
    pub output: PathBuf,
    /// A column to plot (repeatable)
    #[arg(long = "column", value_name = "NAME")]
    pub columns: Vec<String>,
    /// The sum of comma-separated columns, e.g. f1_n,f2_n,f3_n (repeatable)
    #[arg(long = "sum", value_name = "A,B,...")]
    pub sums: Vec<String>,
    /// The difference A − B of two columns, e.g. energy_rate_w,power_w (repeatable)
    #[arg(long = "diff", value_name = "A,B")]
    pub diffs: Vec<String>,
    /// Legend name of each file, in order (default: the file name)
    #[arg(long = "label", value_name = "TEXT")]
    pub labels: Vec<String>,
    /// A horizontal reference line, VALUE or VALUE:LEGEND (repeatable)
    #[arg(long = "hline", value_name = "VALUE[:LEGEND]", value_parser = parse_hline, allow_hyphen_values = true)]
    pub hlines: Vec<(f64, String)>,
    /// The x column
    #[arg(long, value_name = "NAME", default_value = "t_s")]
    pub x: String,
    /// Scale each file's x to 0..1 (the fraction of the run, to compare speeds)
    #[arg(long)]
    pub normalize_x: bool,
    /// Keep only the samples of these G-code lines: A..B, A.. or ..B (inclusive)
    #[arg(long, value_name = "RANGE", value_parser = parse_lines)]
    pub lines: Option<(u64, u64)>,
    /// Keep only the samples whose (scaled) x is in A..B, A.. or ..B, e.g. 0.02..0.98
    #[arg(long, value_name = "RANGE", value_parser = parse_x_range, allow_hyphen_values = true)]
    pub x_range: Option<(f64, f64)>,
    /// Add d(K+U)/dt differenced in time: K + U of each sample from its nozzle position
    /// and velocity with this machine's model, central differences between samples (an
    /// independent check of power_w, eq. 20)
    #[arg(long, value_name = "M.yaml")]
    pub energy_slope: Option<PathBuf>,
    /// The chart's title
    #[arg(long, default_value = "")]
    pub title: String,
    /// The y axis name
    #[arg(long, value_name = "TEXT", default_value = "")]
    pub y_label: String,
}

/// `A..B`, `A..` or `..B` → inclusive bounds, an open end taking its bound from `open`;
/// each given end must parse and pass `valid`.
fn parse_range<T: std::str::FromStr + Copy>(
    s: &str,
    open: (T, T),
    valid: impl Fn(&T) -> bool,
) -> Result<(T, T), String> {
    let (a, b) = s
        .split_once("..")
        .ok_or_else(|| format!("expected A..B, A.. or ..B, found `{s}`"))?;
    let bound = |t: &str, default: T| {
        if t.is_empty() {
            return Ok(default);
        }
        t.parse::<T>()
            .ok()
            .filter(&valid)
            .ok_or_else(|| format!("expected a number, found `{t}`"))
    };
    Ok((bound(a, open.0)?, bound(b, open.1)?))
}

fn parse_lines(s: &str) -> Result<(u64, u64), String> {
    parse_range(s, (0, u64::MAX), |_| true)
}

fn parse_x_range(s: &str) -> Result<(f64, f64), String> {
    parse_range(s, (f64::NEG_INFINITY, f64::INFINITY), |v: &f64| {
        v.is_finite()
    })
}

/// `VALUE` or `VALUE:LEGEND` (the legend defaults to the value).
fn parse_hline(s: &str) -> Result<(f64, String), String> {
    let (value, legend) = s.split_once(':').unwrap_or((s, s));
    match value.trim().parse::<f64>() {
        Ok(v) if v.is_finite() => Ok((v, legend.to_string())),
        _ => Err(format!("expected a number, found `{value}`")),
    }
}

/// One curve to draw: its legend name and the columns it adds (+1) or subtracts (−1).
struct Expr {
    name: String,
    terms: Vec<(String, f64)>,
}

fn exprs(args: &Args) -> anyhow::Result<Vec<Expr>> {
    let list = |s: &str| -> Vec<String> { s.split(',').map(|c| c.trim().to_string()).collect() };
    let mut out: Vec<Expr> = args
        .columns
        .iter()
        .map(|c| Expr {
            name: c.clone(),
            terms: vec![(c.clone(), 1.0)],
        })
        .collect();
    for s in &args.sums {
        let cols = list(s);
        out.push(Expr {
            name: cols.join(" + "),
            terms: cols.into_iter().map(|c| (c, 1.0)).collect(),
        });
    }
    for s in &args.diffs {
        let cols = list(s);
        let [a, b] = <[String; 2]>::try_from(cols).map_err(|c| {
            anyhow::anyhow!("--diff {s}: expected two columns A,B, found {}", c.len())
        })?;
        out.push(Expr {
            name: format!("{a} − {b}"),
            terms: vec![(a, 1.0), (b, -1.0)],
        });
    }
    if out.is_empty() {
        bail!("nothing to plot: give --column, --sum or --diff");
    }
    Ok(out)
}

/// Trace columns of the nozzle state, for the energy slope.
const STATE_COLUMNS: [&str; 10] = [
    "t_s", "x_mm", "y_mm", "z_mm", "vx_mm_s", "vy_mm_s", "vz_mm_s", "ax_mm_s2", "ay_mm_s2",
    "az_mm_s2",
];

pub fn run(args: &Args) -> anyhow::Result<ExitCode> {
    let exprs = exprs(args)?;
    if args.labels.len() > args.traces.len() {
        bail!(
            "{} labels for {} files",
            args.labels.len(),
            args.traces.len()
        );
    }
    let model = match &args.energy_slope {
        Some(path) => {
            let machine = Machine::load(path)?;
            Some((machine.model(), machine.sampling.period_s))
        }
        None => None,
    };
    // Every column any curve needs, read once per file.
    let mut needed: Vec<&str> = vec![args.x.as_str(), "line"];
    let state: &[&str] = if model.is_some() { &STATE_COLUMNS } else { &[] };
    let terms = exprs
        .iter()
        .flat_map(|e| e.terms.iter().map(|(c, _)| c.as_str()));
    for c in terms.chain(state.iter().copied()) {
        if !needed.contains(&c) {
            needed.push(c);
        }
    }
    let col = |name: &str| needed.iter().position(|n| *n == name).unwrap_or(0);
    let mut series = Vec::new();
    for (k, path) in args.traces.iter().enumerate() {
        let label = args.labels.get(k).cloned().unwrap_or_else(|| {
            path.file_name().map_or_else(
                || path.display().to_string(),
                |n| n.to_string_lossy().into(),
            )
        });
        let columns = read_trace_columns(path, &needed)?;
        let (x, line) = (&columns[0], &columns[1]);
        let (lo, hi) = args.lines.unwrap_or((0, u64::MAX));
        let in_lines: Vec<usize> = (0..x.len())
            .filter(|&i| (lo as f64..=hi as f64).contains(&line[i]))
            .collect();
        let (x0, x1) = match (in_lines.first(), in_lines.last()) {
            (Some(&a), Some(&b)) => (x[a], x[b]),
            _ => bail!("{}: no sample in the chosen lines", path.display()),
        };
        let scale_x = |v: f64| {
            if args.normalize_x && x1 > x0 {
                (v - x0) / (x1 - x0)
            } else {
                v
            }
        };
        let (xa, xb) = args.x_range.unwrap_or((f64::NEG_INFINITY, f64::INFINITY));
        let kept: Vec<usize> = in_lines
            .into_iter()
            .filter(|&i| (xa..=xb).contains(&scale_x(x[i])))
            .collect();
        if kept.is_empty() {
            bail!("{}: no sample in the chosen x range", path.display());
        }
        let name_of = |what: &str, count: usize| match (args.traces.len(), count) {
            (1, 1) if !args.labels.is_empty() => label.clone(),
            (1, _) => what.to_string(),
            (_, 1) => label.clone(),
            _ => format!("{label}: {what}"),
        };
        let count = exprs.len() + usize::from(model.is_some());
        for e in &exprs {
            let idx: Vec<(usize, f64)> = e.terms.iter().map(|(c, s)| (col(c), *s)).collect();
            let points = kept
                .iter()
                .map(|&i| {
                    let y = idx.iter().map(|&(c, sign)| sign * columns[c][i]).sum();
                    (scale_x(x[i]), y)
                })
                .collect();
            series.push(Series {
                name: name_of(&e.name, count),
                points,
            });
        }
        if let Some((model, period_s)) = &model {
            let state: Vec<&Vec<f64>> = STATE_COLUMNS.iter().map(|c| &columns[col(c)]).collect();
            let slope = energy_slope_of_rows(model, &state, &kept, 0.5 * period_s)
                .with_context(|| format!("energy of {}", path.display()))?;
            let points = slope.into_iter().map(|(i, y)| (scale_x(x[i]), y)).collect();
            series.push(Series {
                name: name_of("d(K+U)/dt, differenced", count),
                points,
            });
        }
    }
    let hlines: Vec<HLine> = args
        .hlines
        .iter()
        .map(|(y, name)| HLine {
            y: *y,
            name: name.clone(),
        })
        .collect();
    let x_desc = if args.normalize_x {
        format!("fraction of the run ({} scaled to 0..1)", args.x)
    } else {
        args.x.clone()
    };
    line_chart_svg(
        &args.output,
        &LineChart {
            title: &args.title,
            x_desc: &x_desc,
            y_desc: &args.y_label,
            series: &series,
            hlines: &hlines,
        },
    )
    .with_context(|| format!("plotting {}", args.output.display()))?;
    Ok(ExitCode::SUCCESS)
}

/// d(K+U)/dt of the rows `kept` (row index, W): K + U of each row from the model at its
/// nozzle state (`state`: the [`STATE_COLUMNS`]), differenced in time by
/// [`delta::energy_slope`].
fn energy_slope_of_rows(
    model: &DeltaModel,
    state: &[&Vec<f64>],
    kept: &[usize],
    min_gap_s: f64,
) -> anyhow::Result<Vec<(usize, f64)>> {
    let v3 = |i: usize, c: usize| Vec3::new(state[c][i], state[c + 1][i], state[c + 2][i]);
    let energy: Vec<f64> = kept
        .iter()
        .map(|&i| {
            model
                .energy_j(v3(i, 1), v3(i, 4))
                .with_context(|| format!("at t = {} s", state[0][i]))
        })
        .collect::<anyhow::Result<_>>()?;
    let t: Vec<f64> = kept.iter().map(|&i| state[0][i]).collect();
    Ok(delta::energy_slope(&t, &energy, min_gap_s)
        .into_iter()
        .map(|(k, slope)| (kept[k], slope))
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn line_ranges_parse_with_open_ends() {
        assert_eq!(parse_lines("7..20"), Ok((7, 20)));
        assert_eq!(parse_lines("7.."), Ok((7, u64::MAX)));
        assert_eq!(parse_lines("..9"), Ok((0, 9)));
        assert!(parse_lines("7").is_err());
        assert!(parse_lines("a..3").is_err());
        assert_eq!(parse_x_range("-1..0.5"), Ok((-1.0, 0.5)));
        assert_eq!(parse_x_range("..2"), Ok((f64::NEG_INFINITY, 2.0)));
        assert!(parse_x_range("1..inf").is_err());
        assert_eq!(parse_hline("-40"), Ok((-40.0, "-40".into())));
        assert_eq!(parse_hline("13.4:weight"), Ok((13.4, "weight".into())));
        assert!(parse_hline("x:y").is_err());
    }
}
