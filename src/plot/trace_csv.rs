//! Reading columns of a trace CSV (`delta-gcode trace`).

use std::io::BufRead;
use std::path::Path;

use anyhow::{Context, bail};

/// Reads the named columns of a trace CSV, in the order asked; every row must have every
/// column as a number. Errors name the file, line and column.
pub fn read_trace_columns(path: &Path, names: &[&str]) -> anyhow::Result<Vec<Vec<f64>>> {
    let file = std::fs::File::open(path).with_context(|| format!("opening {}", path.display()))?;
    read_columns(
        std::io::BufReader::new(file),
        &path.display().to_string(),
        names,
    )
}

fn read_columns(
    input: impl BufRead,
    origin: &str,
    names: &[&str],
) -> anyhow::Result<Vec<Vec<f64>>> {
    let mut input = input;
    let read_error = || format!("reading {origin}");
    let mut header = String::new();
    if input.read_line(&mut header).with_context(read_error)? == 0 {
        bail!("{origin}: empty file, expected a trace CSV header");
    }
    let fields: Vec<&str> = header.trim_end().split(',').collect();
    let index: Vec<usize> = names
        .iter()
        .map(|name| {
            fields.iter().position(|f| f == name).with_context(|| {
                format!(
                    "{origin}:1: no column `{name}` (the columns are {})",
                    fields.join(", ")
                )
            })
        })
        .collect::<anyhow::Result<_>>()?;
    let mut out = vec![Vec::new(); names.len()];
    // One buffer for every row: nothing is allocated per line but the values kept.
    let mut line = String::new();
    for line_no in 2.. {
        line.clear();
        if input.read_line(&mut line).with_context(read_error)? == 0 {
            break;
        }
        if line.trim().is_empty() {
            continue;
        }
        let (mut count, mut col) = (0, 1);
        for (i, text) in line.trim_end().split(',').enumerate() {
            for (k, _) in index.iter().enumerate().filter(|(_, w)| **w == i) {
                match text.parse::<f64>() {
                    Ok(v) if v.is_finite() => out[k].push(v),
                    _ => bail!(
                        "{origin}:{line_no}:{col}: column `{}`: expected a finite number, \
                         found `{text}`",
                        names[k]
                    ),
                }
            }
            col += text.len() + 1;
            count = i + 1;
        }
        if count != fields.len() {
            bail!(
                "{origin}:{line_no}: {count} fields, the header has {}",
                fields.len()
            );
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn columns_come_back_in_the_order_asked() {
        let text = "t_s,line,f1_n\n0,6,1.5\n0.001,7,-2e-3\n\n";
        let c = read_columns(text.as_bytes(), "t.csv", &["f1_n", "t_s"]).unwrap();
        assert_eq!(c, vec![vec![1.5, -0.002], vec![0.0, 0.001]]);
    }

    #[test]
    fn errors_name_file_line_column_and_what_was_expected() {
        let e = read_columns("t_s,f1_n\n0,1\n".as_bytes(), "t.csv", &["f9_n"]).unwrap_err();
        assert_eq!(
            e.to_string(),
            "t.csv:1: no column `f9_n` (the columns are t_s, f1_n)"
        );
        let e = read_columns("t_s,f1_n\n0,1\n1,x\n".as_bytes(), "t.csv", &["f1_n"]).unwrap_err();
        assert_eq!(
            e.to_string(),
            "t.csv:3:3: column `f1_n`: expected a finite number, found `x`"
        );
        let e = read_columns("t_s,f1_n\n0,NaN\n".as_bytes(), "t.csv", &["f1_n"]).unwrap_err();
        assert!(e.to_string().contains("found `NaN`"), "{e}");
        let e = read_columns("t_s,f1_n\n0\n".as_bytes(), "t.csv", &["t_s"]).unwrap_err();
        assert_eq!(e.to_string(), "t.csv:2: 1 fields, the header has 2");
        let e = read_columns("".as_bytes(), "t.csv", &["t_s"]).unwrap_err();
        assert!(e.to_string().contains("empty file"), "{e}");
    }
}
