//! GitHub Actions workflow commands (`::error file=…,line=…::…`), so a CI job annotates
//! the pull request.

use std::io::{self, Write};

use super::annotations::context;
use super::{Report, format_forces, severity_name};

/// Escapes a workflow command's message (`%`, CR, LF).
fn escape_data(s: &str) -> String {
    s.replace('%', "%25")
        .replace('\r', "%0D")
        .replace('\n', "%0A")
}

/// Escapes a workflow command's property value (also `:` and `,`).
fn escape_property(s: &str) -> String {
    escape_data(s).replace(':', "%3A").replace(',', "%2C")
}

pub fn write_github(out: &mut (impl Write + ?Sized), report: &Report) -> io::Result<()> {
    let file = escape_property(&report.file);
    for v in &report.violations {
        writeln!(
            out,
            "::error file={file},line={},title={}::{}",
            v.line,
            escape_property(&format!("delta-gcode {}", v.kind)),
            escape_data(&format!("{} {}", v.message, context(v)))
        )?;
    }
    // One annotation per kind of diagnostic, at its first line.
    for k in report.diagnostic_kinds.as_slice() {
        let times = match k.count {
            1 => String::new(),
            n => format!(" ({n} times, first lines {:?})", k.lines),
        };
        writeln!(
            out,
            "::{} file={file},line={},col={}::{}{times}",
            severity_name(k.severity),
            k.lines.first().copied().unwrap_or(0),
            k.column,
            escape_data(&k.message)
        )?;
    }
    for note in &report.notes {
        writeln!(out, "::warning file={file}::{}", escape_data(note))?;
    }
    let s = &report.summary;
    writeln!(
        out,
        "::notice file={file},title=delta-gcode::{} on {}: {} violations, peak force A/B/C {} N (limit {:.1} N), print time {:.1} s",
        escape_data(&report.file),
        escape_data(&report.machine),
        s.violations,
        format_forces(&s.peak_force_n),
        report.limit_force_n,
        s.print_time_s
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::tests::sample_report;

    #[test]
    fn one_error_per_violation_and_a_notice() {
        let mut r = sample_report();
        r.file = "dir,x/a:b.gcode".into();
        let mut buf = Vec::new();
        write_github(&mut buf, &r).unwrap();
        let text = String::from_utf8(buf).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines.len(), 3);
        assert!(lines[0].starts_with(
            "::error file=dir%2Cx/a%3Ab.gcode,line=20,title=delta-gcode force::OVER force"
        ));
        assert!(lines[1].contains(",line=30,"));
        assert!(lines[2].starts_with("::notice "));
    }

    #[test]
    fn messages_are_escaped() {
        assert_eq!(escape_data("50%\nx"), "50%25%0Ax");
    }
}
