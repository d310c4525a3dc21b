//! The trace CSV: one row per sample, its columns defined once by [`TraceRow`].

use serde::Serialize;

use super::observe::{Evaluated, Observer};
use crate::delta::DeltaModel;
use crate::machine::Motors;

/// One row of the trace CSV: the nozzle's actual state at one sample, the carriages'
/// (eq. 6-8), the commanded carriage heights, the forces (eq. 14) and both sides of the
/// energy balance (eq. 20). Field names are the column names; each figure is written with
/// the precision it has (its `serialize_with`): times to the µs, lengths and speeds to the
/// µm and µm/s, power to the mW, accelerations to 0.1 mm/s², forces to 0.1 mN.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct TraceRow {
    #[serde(serialize_with = "micro")]
    pub t_s: f64,
    pub line: u64,
    #[serde(serialize_with = "milli")]
    pub x_mm: f64,
    #[serde(serialize_with = "milli")]
    pub y_mm: f64,
    #[serde(serialize_with = "milli")]
    pub z_mm: f64,
    #[serde(serialize_with = "milli")]
    pub vx_mm_s: f64,
    #[serde(serialize_with = "milli")]
    pub vy_mm_s: f64,
    #[serde(serialize_with = "milli")]
    pub vz_mm_s: f64,
    #[serde(serialize_with = "tenth")]
    pub ax_mm_s2: f64,
    #[serde(serialize_with = "tenth")]
    pub ay_mm_s2: f64,
    #[serde(serialize_with = "tenth")]
    pub az_mm_s2: f64,
    #[serde(serialize_with = "milli")]
    pub q1_mm: f64,
    #[serde(serialize_with = "milli")]
    pub q2_mm: f64,
    #[serde(serialize_with = "milli")]
    pub q3_mm: f64,
    /// The commanded carriage heights: what the firmware's steps encode.
    #[serde(serialize_with = "milli")]
    pub q1_cmd_mm: f64,
    #[serde(serialize_with = "milli")]
    pub q2_cmd_mm: f64,
    #[serde(serialize_with = "milli")]
    pub q3_cmd_mm: f64,
    #[serde(serialize_with = "milli")]
    pub dq1_mm_s: f64,
    #[serde(serialize_with = "milli")]
    pub dq2_mm_s: f64,
    #[serde(serialize_with = "milli")]
    pub dq3_mm_s: f64,
    #[serde(serialize_with = "tenth")]
    pub ddq1_mm_s2: f64,
    #[serde(serialize_with = "tenth")]
    pub ddq2_mm_s2: f64,
    #[serde(serialize_with = "tenth")]
    pub ddq3_mm_s2: f64,
    #[serde(serialize_with = "tenth_milli")]
    pub f1_n: f64,
    #[serde(serialize_with = "tenth_milli")]
    pub f2_n: f64,
    #[serde(serialize_with = "tenth_milli")]
    pub f3_n: f64,
    /// The force each motor can give at its carriage's speed.
    #[serde(serialize_with = "tenth_milli")]
    pub f1_avail_n: f64,
    #[serde(serialize_with = "tenth_milli")]
    pub f2_avail_n: f64,
    #[serde(serialize_with = "tenth_milli")]
    pub f3_avail_n: f64,
    /// Each parallelogram's tension (both rods), positive when it pulls the platform.
    #[serde(serialize_with = "tenth_milli")]
    pub t1_n: f64,
    #[serde(serialize_with = "tenth_milli")]
    pub t2_n: f64,
    #[serde(serialize_with = "tenth_milli")]
    pub t3_n: f64,
    #[serde(serialize_with = "milli")]
    pub power_w: f64,
    #[serde(serialize_with = "milli")]
    pub energy_rate_w: f64,
}

/// `value` with `decimals` decimals, without the sign of a zero (`-0.000` is `0.000`).
struct Fixed {
    value: f64,
    decimals: usize,
}

impl std::fmt::Display for Fixed {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let text = format!("{:.*}", self.decimals, self.value);
        match text.strip_prefix('-') {
            Some(digits) if digits.bytes().all(|b| b == b'0' || b == b'.') => f.write_str(digits),
            _ => f.write_str(&text),
        }
    }
}

fn fixed<S: serde::Serializer>(value: f64, decimals: usize, s: S) -> Result<S::Ok, S::Error> {
    s.collect_str(&Fixed { value, decimals })
}

/// s to the µs.
fn micro<S: serde::Serializer>(v: &f64, s: S) -> Result<S::Ok, S::Error> {
    fixed(*v, 6, s)
}

/// mm to the µm, mm/s to the µm/s, W to the mW.
fn milli<S: serde::Serializer>(v: &f64, s: S) -> Result<S::Ok, S::Error> {
    fixed(*v, 3, s)
}

/// mm/s² to 0.1 mm/s².
fn tenth<S: serde::Serializer>(v: &f64, s: S) -> Result<S::Ok, S::Error> {
    fixed(*v, 1, s)
}

/// N to 0.1 mN.
fn tenth_milli<S: serde::Serializer>(v: &f64, s: S) -> Result<S::Ok, S::Error> {
    fixed(*v, 4, s)
}

/// Which samples the trace keeps: those of the lines `lines` (inclusive) and the times
/// `t_s` (inclusive), s. The default keeps all.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TraceWindow {
    pub lines: (u64, u64),
    pub t_s: (f64, f64),
}

impl Default for TraceWindow {
    fn default() -> Self {
        TraceWindow {
            lines: (0, u64::MAX),
            t_s: (f64::NEG_INFINITY, f64::INFINITY),
        }
    }
}

impl TraceWindow {
    fn keeps(&self, line: u64, t_s: f64) -> bool {
        (self.lines.0..=self.lines.1).contains(&line) && (self.t_s.0..=self.t_s.1).contains(&t_s)
    }
}

/// The header line of the trace CSV (with its newline), from [`TraceRow`]'s fields.
pub fn trace_header() -> String {
    let mut w = csv::Writer::from_writer(Vec::new());
    // Serialising a row into a writer with headers writes the header first; only it is kept.
    let _ = w.serialize(TraceRow::default());
    let bytes = w.into_inner().unwrap_or_default();
    let text = String::from_utf8_lossy(&bytes);
    text.lines()
        .next()
        .map_or_else(String::new, |h| format!("{h}\n"))
}

/// The trace rows of each move, as CSV text (no header). A pose the model cannot take has
/// no row: the statistics flag it.
pub struct TraceRows<'m> {
    /// The motors, for the force available at each carriage's speed.
    motors: &'m Motors,
    window: TraceWindow,
}

impl<'m> TraceRows<'m> {
    /// Every sample's row.
    pub fn new(motors: &'m Motors) -> Self {
        TraceRows {
            motors,
            window: TraceWindow::default(),
        }
    }

    /// Only the rows within `window`.
    pub fn within(self, window: TraceWindow) -> Self {
        TraceRows { window, ..self }
    }
}

impl Observer for TraceRows<'_> {
    type PerMove = Vec<u8>;

    fn start(&self, _: u64) -> Vec<u8> {
        Vec::new()
    }

    fn observe(&self, model: &DeltaModel, rows: &mut Vec<u8>, run: &Evaluated) {
        let mut w = csv::WriterBuilder::new()
            .has_headers(false)
            .from_writer(std::mem::take(rows));
        for j in run.lanes.clone() {
            if !self.window.keeps(run.line, run.t_s[j]) {
                continue;
            }
            let (p, v, a) = run.state(j);
            let Ok(st) = model.evaluate(p, v, a) else {
                continue;
            };
            // The command is where the steps are; a commanded pose out of reach (the actual
            // one was in reach) has no heights: NaN would be no number, so the actual ones.
            let q_cmd = model.inverse(run.cmd_pos(j)).unwrap_or(st.q_mm);
            let (q, dq, ddq, f) = (st.q_mm, st.dq_mm_s, st.ddq_mm_s2, st.force_n);
            let avail = dq.map(|v| self.motors.available_force_n(v.abs()));
            let tension = st.arm_tension_n;
            let _ = w.serialize(TraceRow {
                t_s: run.t_s[j],
                line: run.line,
                x_mm: p.x,
                y_mm: p.y,
                z_mm: p.z,
                vx_mm_s: v.x,
                vy_mm_s: v.y,
                vz_mm_s: v.z,
                ax_mm_s2: a.x,
                ay_mm_s2: a.y,
                az_mm_s2: a.z,
                q1_mm: q[0],
                q2_mm: q[1],
                q3_mm: q[2],
                q1_cmd_mm: q_cmd[0],
                q2_cmd_mm: q_cmd[1],
                q3_cmd_mm: q_cmd[2],
                dq1_mm_s: dq[0],
                dq2_mm_s: dq[1],
                dq3_mm_s: dq[2],
                ddq1_mm_s2: ddq[0],
                ddq2_mm_s2: ddq[1],
                ddq3_mm_s2: ddq[2],
                f1_n: f[0],
                f2_n: f[1],
                f3_n: f[2],
                f1_avail_n: avail[0],
                f2_avail_n: avail[1],
                f3_avail_n: avail[2],
                t1_n: tension[0],
                t2_n: tension[1],
                t3_n: tension[2],
                power_w: st.power_w,
                energy_rate_w: st.energy_rate_w,
            });
        }
        // Writing into a Vec cannot fail; the rows are handed back.
        *rows = w.into_inner().unwrap_or_default();
    }

    fn merge(&self, rows: &mut Vec<u8>, later: &mut Vec<u8>) {
        rows.append(later);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_figure_has_its_precision_and_no_signed_zero() {
        let row = TraceRow {
            t_s: 1.234_567_89,
            line: 7,
            x_mm: -0.000_000_000_1,
            vx_mm_s: 12.345_678,
            ax_mm_s2: -1234.567,
            f1_n: 2.718_26,
            f2_n: -1.076_388_544_627_551_8e-30,
            power_w: 0.123_456,
            ..TraceRow::default()
        };
        let mut w = csv::WriterBuilder::new()
            .has_headers(false)
            .from_writer(Vec::new());
        w.serialize(row).unwrap();
        let text = String::from_utf8(w.into_inner().unwrap()).unwrap();
        let cols: Vec<&str> = text.trim_end().split(',').collect();
        let header = trace_header();
        let names: Vec<&str> = header.trim_end().split(',').collect();
        let col = |name: &str| cols[names.iter().position(|n| *n == name).unwrap()];
        assert_eq!(cols.len(), names.len());
        assert_eq!(col("t_s"), "1.234568");
        assert_eq!(col("line"), "7");
        assert_eq!(col("x_mm"), "0.000");
        assert_eq!(col("vx_mm_s"), "12.346");
        assert_eq!(col("ax_mm_s2"), "-1234.6");
        assert_eq!(col("f1_n"), "2.7183");
        assert_eq!(col("f2_n"), "0.0000");
        assert_eq!(col("power_w"), "0.123");
        assert_eq!(col("ddq3_mm_s2"), "0.0");
    }

    #[test]
    fn a_window_keeps_its_lines_and_times_inclusive() {
        let w = TraceWindow {
            lines: (10, 20),
            t_s: (1.0, 2.0),
        };
        assert!(w.keeps(10, 1.0) && w.keeps(20, 2.0));
        assert!(!w.keeps(9, 1.5) && !w.keeps(21, 1.5) && !w.keeps(15, 0.9) && !w.keeps(15, 2.1));
        assert!(TraceWindow::default().keeps(0, -1.0));
    }

    #[test]
    fn the_header_names_every_field_in_order() {
        let h = trace_header();
        assert!(h.starts_with("t_s,line,x_mm,y_mm,z_mm,vx_mm_s"), "{h}");
        assert!(h.ends_with("t3_n,power_w,energy_rate_w\n"), "{h}");
        assert_eq!(h.split(',').count(), 34);
        assert!(h.contains(",f1_n,f2_n,f3_n,f1_avail_n,f2_avail_n,f3_avail_n,t1_n,t2_n,t3_n,"));
        assert!(
            h.contains(",q1_mm,q2_mm,q3_mm,q1_cmd_mm,q2_cmd_mm,q3_cmd_mm,"),
            "{h}"
        );
    }
}
