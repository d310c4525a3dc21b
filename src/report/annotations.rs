//! The report as G-code comment lines: one after each flagged move, a block at the end.

use std::collections::BTreeMap;

use super::{Report, Violation, format_forces};
use crate::delta::TOWER_NAMES;

/// Where and when a violation happened: `(tower A, decel, t=812.304 s)`.
pub(super) fn context(v: &Violation) -> String {
    // A force violation names its tower in its message.
    if v.available_force_n.is_some() {
        format!("({}, t={:.3} s)", v.phase, v.t_s)
    } else {
        format!(
            "(tower {}, {}, t={:.3} s)",
            TOWER_NAMES[v.tower - 1],
            v.phase,
            v.t_s
        )
    }
}

/// The annotation lines to insert after each flagged input line.
pub fn annotations(report: &Report) -> BTreeMap<u64, Vec<String>> {
    let mut map: BTreeMap<u64, Vec<String>> = BTreeMap::new();
    for v in &report.violations {
        map.entry(v.line)
            .or_default()
            .push(format!("; delta-gcode: {} {}", v.message, context(v)));
    }
    map
}

/// The summary block written at the end of an annotated file.
pub fn summary_lines(report: &Report) -> Vec<String> {
    let s = &report.summary;
    let mut lines = vec![
        format!(
            "; delta-gcode summary: machine {}, force limit {:.1} N",
            report.machine, report.limit_force_n
        ),
        format!(
            "; delta-gcode: print time {:.1} s, {} moves, {} samples",
            s.print_time_s, s.moves, s.samples
        ),
        format!(
            "; delta-gcode: peak force A/B/C {} N",
            format_forces(&s.peak_force_n)
        ),
        format!(
            "; delta-gcode: violations {} (unreachable {}), {} warnings, {} errors",
            s.violations, s.unreachable, s.warnings, s.errors
        ),
    ];
    if s.violations as usize > report.violations.len() {
        lines.push(format!(
            "; delta-gcode: only the first {} violations are annotated",
            report.violations.len()
        ));
    }
    lines.push(format!(
        "; delta-gcode: result {}",
        if report.failed() { "FAIL" } else { "OK" }
    ));
    lines
}

/// The verdict in one line, for a slicer's hook (its first line on stderr): what failed, in
/// how many moves, and the worst line; or the input errors; or that the file passes, with
/// how many findings.
pub fn verdict_line(report: &Report) -> String {
    let (s, file, machine) = (&report.summary, &report.file, &report.machine);
    let first_diag = |severity: &str| {
        report
            .diagnostics
            .iter()
            .find(|d| d.severity == severity)
            .map_or_else(String::new, |d| {
                format!(", first at line {}: {}", d.line, d.message)
            })
    };
    if let Some(v) = report.worst_first().first() {
        let text = v.command.trim_end();
        let text = if text.is_empty() {
            String::new()
        } else {
            format!(" `{text}`")
        };
        return format!(
            "delta-gcode: FAIL: {file}: {} of {} moves exceed the limits of {machine}; worst: line {}{text}: {} {}",
            s.violations,
            s.moves,
            v.line,
            v.message,
            context(v)
        );
    }
    if s.errors > 0 {
        return format!(
            "delta-gcode: ERROR: {file}: {} input errors (those lines were skipped){}",
            s.errors,
            first_diag("error")
        );
    }
    let use_ = s.peak_use.iter().copied().fold(0.0, f64::max);
    let mut line = format!(
        "delta-gcode: OK: {file}: all {} moves within the limits of {machine} (motor use at most {:.0}%)",
        s.moves,
        100.0 * use_
    );
    if s.warnings > 0 {
        let kinds = report.diagnostic_kinds.as_slice().len();
        line += &format!(
            "; {} warnings ({kinds} {}){}",
            s.warnings,
            if kinds == 1 { "kind" } else { "kinds" },
            first_diag("warning")
        );
    }
    line
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::tests::sample_report;

    #[test]
    fn flagged_moves_get_the_design_format() {
        let a = annotations(&sample_report());
        assert_eq!(
            a[&20],
            [
                "; delta-gcode: OVER force: tower A needs 31.2 N, its motor gives 30.0 N at 120 mm/s (decel, t=2.500 s)"
            ]
        );
        assert!(a[&30][0].starts_with(
            "; delta-gcode: UNREACHABLE at X200.000 Y0.000 Z0.000: tower B: arm too short"
        ));
        assert_eq!(a.len(), 2);
    }

    #[test]
    fn summary_block_lines_are_ours() {
        let lines = summary_lines(&sample_report());
        assert!(lines.iter().all(|l| l.starts_with("; delta-gcode")));
        assert_eq!(
            lines.last().map(String::as_str),
            Some("; delta-gcode: result FAIL")
        );
    }
}
