//! The report for a person: the verdict, the worst moves, then the totals.

use std::io::{self, Write};

use super::{Report, format_forces};
use crate::delta::TOWER_NAMES;

/// Shares of the available force beyond this are shown as "more than": a motor past its
/// top speed has none left, and the share is then meaningless.
const MAX_SHARE_SHOWN: f64 = 10.0;

/// How many of the worst moves the text report lists.
const WORST_SHOWN: usize = 10;

/// `1:02:03`
fn clock(t_s: f64) -> String {
    let t = t_s.max(0.0).round() as u64;
    format!("{}:{:02}:{:02}", t / 3600, t / 60 % 60, t % 60)
}

pub fn write_text(out: &mut (impl Write + ?Sized), report: &Report) -> io::Result<()> {
    let s = &report.summary;
    let limit = report.limit_force_n;
    if report.failed() {
        writeln!(
            out,
            "{}: FAIL, {} of {} moves exceed the limits of {} (force limit {limit:.1} N)",
            report.file, s.violations, s.moves, report.machine
        )?;
    } else if s.errors > 0 {
        // Lines with errors were skipped: the moves checked are not the whole file.
        writeln!(
            out,
            "{}: ERROR, {} input errors (lines skipped); the {} moves read are within the limits of {} (force limit {limit:.1} N)",
            report.file, s.errors, s.moves, report.machine
        )?;
    } else {
        writeln!(
            out,
            "{}: OK, all {} moves within the limits of {} (force limit {limit:.1} N)",
            report.file, s.moves, report.machine
        )?;
    }
    for note in &report.notes {
        writeln!(out, "  note: {note}")?;
    }
    let worst = report.worst_first();
    if !worst.is_empty() {
        writeln!(out)?;
        writeln!(
            out,
            "  {:>8}  {:<15}  {:>9}  {:<6}  {:>10}  problem / command",
            "line", "force A/B/C (N)", "margin", "phase", "t (s)"
        )?;
        for v in worst.iter().take(WORST_SHOWN) {
            let t = v.tower - 1;
            let margin = match (v.available_force_n, v.peak_force_n) {
                (Some(available), Some(f)) => format!("{:+.1} N", available[t] - f[t]),
                _ => String::from("-"),
            };
            let what = format!("{}: {}", v.message, v.command.trim_end());
            writeln!(
                out,
                "  {:>8}  {:<15}  {:>9}  {:<6}  {:>10.3}  {}",
                v.line,
                v.peak_force_n.as_ref().map_or("-".into(), format_forces),
                margin,
                v.phase.as_str(),
                v.t_s,
                what
            )?;
        }
        if worst.len() > WORST_SHOWN {
            writeln!(out, "  … and {} more", s.violations as usize - WORST_SHOWN)?;
        }
    }
    writeln!(out)?;
    writeln!(
        out,
        "  print time    {} ({:.1} s), {} moves, {} samples, {} lines",
        clock(s.print_time_s),
        s.print_time_s,
        s.moves,
        s.samples,
        s.lines
    )?;
    writeln!(
        out,
        "  peak force    A {:.1} N (line {}), B {:.1} N (line {}), C {:.1} N (line {})",
        s.peak_force_n[0],
        s.peak_line[0],
        s.peak_force_n[1],
        s.peak_line[1],
        s.peak_force_n[2],
        s.peak_line[2],
    )?;
    let t = (0..3)
        .max_by(|&a, &b| s.peak_use[a].total_cmp(&s.peak_use[b]))
        .unwrap_or(0);
    // Past its top speed a motor gives nothing: any force is too much.
    let share = if s.peak_use[t] < MAX_SHARE_SHOWN {
        format!("at most {:.0}%", 100.0 * s.peak_use[t])
    } else {
        format!("more than {:.0}%", 100.0 * MAX_SHARE_SHOWN)
    };
    writeln!(
        out,
        "  motor use     {share} of the force a motor can give at its speed (tower {}, line {})",
        TOWER_NAMES[t], s.peak_use_line[t]
    )?;
    if s.warnings + s.errors > 0 {
        writeln!(
            out,
            "  input         {} warnings, {} errors",
            s.warnings, s.errors
        )?;
    }
    write_recommendation(out, report)
}

/// What to change: the limits under which the file passes, or why there are none.
fn write_recommendation(out: &mut (impl Write + ?Sized), report: &Report) -> io::Result<()> {
    if let Some(r) = &report.recommendation {
        let base = report.summary.print_time_s;
        let slower = if base > 0.0 {
            format!(", {:+.1} %", 100.0 * (r.print_time_s - base) / base)
        } else {
            String::new()
        };
        let (units, change) = if r.marlin.is_some() {
            (
                "",
                "set them in Marlin (Configuration.h, or send them and M500) where they are higher, and cap the file's own M204 / M205 / M203;",
            )
        } else {
            (
                " (mm/s², mm/s, mm/s)",
                "lower printer.cfg's max_accel, square_corner_velocity, max_velocity where they are higher, and cap the file's own M204 / SET_VELOCITY_LIMIT;",
            )
        };
        writeln!(out)?;
        writeln!(
            out,
            "  passes with   {}{units}: print time {} ({:.1} s{slower})",
            r.commands(),
            clock(r.print_time_s),
            r.print_time_s
        )?;
        writeln!(out, "                at most: {change}")?;
        writeln!(
            out,
            "                or `delta-gcode fix` slows only the moves that need it"
        )?;
    } else if let Some(why) = &report.recommendation_error {
        writeln!(out)?;
        writeln!(out, "  no limits pass: {why}")?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::tests::sample_report;

    #[test]
    fn worst_moves_then_totals() {
        let mut r = sample_report();
        r.set_commands(|line| (line == 20).then(|| "G1 X10 Y20 F9000".to_string()));
        let mut buf = Vec::new();
        write_text(&mut buf, &r).unwrap();
        let text = String::from_utf8(buf).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert!(
            lines[0].starts_with("part.gcode: FAIL, 2 of 3 moves"),
            "{text}"
        );
        // The unreachable move first, then the force violation with its margin and command.
        assert!(lines[3].trim_start().starts_with("30 "), "{text}");
        assert!(lines[4].contains("-1.2 N"), "{text}");
        assert!(
            lines[4].contains(
                "tower A needs 31.2 N, its motor gives 30.0 N at 120 mm/s: G1 X10 Y20 F9000"
            ),
            "{text}"
        );
        assert!(text.contains("print time    0:00:04 (3.5 s)"), "{text}");
        assert!(
            text.contains("motor use     at most 104% of the force a motor can give at its speed (tower A, line 20)"),
            "{text}"
        );
    }

    #[test]
    fn recommendation_with_its_cost() {
        let mut r = sample_report();
        r.recommendation = Some(crate::report::Recommendation {
            max_accel_mm_s2: 2180.0,
            square_corner_velocity_mm_s: 5.0,
            max_velocity_mm_s: 250.0,
            print_time_s: 3.85,
            marlin: None,
        });
        let mut buf = Vec::new();
        write_text(&mut buf, &r).unwrap();
        let text = String::from_utf8(buf).unwrap();
        assert!(
            text.contains("passes with   ACCEL=2180 SQUARE_CORNER_VELOCITY=5 VELOCITY=250 (mm/s², mm/s, mm/s): print time 0:00:04 (3.9 s, +10.0 %)"),
            "{text}"
        );
        let mut m = r.recommendation.clone().unwrap();
        m.marlin = Some(crate::report::MarlinRecommendation {
            print_accel_mm_s2: 2180.0,
            travel_accel_mm_s2: 2000.0,
            jerk_mm_s: 5.0,
            max_feedrate_mm_s: 250.0,
            commands: vec!["M204 P2180 T2000".into(), "M205 X5 Y5 Z5".into()],
        });
        r.recommendation = Some(m);
        let mut buf = Vec::new();
        write_text(&mut buf, &r).unwrap();
        let text = String::from_utf8(buf).unwrap();
        assert!(
            text.contains(
                "passes with   M204 P2180 T2000, M205 X5 Y5 Z5: print time 0:00:04 (3.9 s, +10.0 %)"
            ),
            "{text}"
        );
        assert!(
            text.contains("cap the file's own M204 / M205 / M203"),
            "{text}"
        );
        r.recommendation = None;
        r.recommendation_error = Some("line 30 cannot be made to pass".into());
        let mut buf = Vec::new();
        write_text(&mut buf, &r).unwrap();
        let text = String::from_utf8(buf).unwrap();
        assert!(
            text.contains("  no limits pass: line 30 cannot be made to pass"),
            "{text}"
        );
    }

    #[test]
    fn input_errors_are_not_ok() {
        let mut r = Report::new("bad.gcode", "M", 25.0, false);
        r.add_diagnostic(&crate::gcode::Diagnostic {
            line: 2,
            column: 5,
            severity: crate::gcode::Severity::Error,
            message: "malformed number".into(),
        });
        let mut buf = Vec::new();
        write_text(&mut buf, &r).unwrap();
        let text = String::from_utf8(buf).unwrap();
        assert!(
            text.starts_with("bad.gcode: ERROR, 1 input errors (lines skipped)"),
            "{text}"
        );
        assert!(!text.contains("OK"), "{text}");
    }

    #[test]
    fn clock_format() {
        assert_eq!(clock(3723.4), "1:02:03");
        assert_eq!(clock(59.6), "0:01:00");
    }
}
