//! The trace CSV: one row per sample, its columns defined once by [`TraceRow`].

use serde::Serialize;

use super::observe::{Evaluated, Observer};
use crate::delta::DeltaModel;
use crate::machine::Motors;

/// One row of the trace CSV: the nozzle's actual state at one sample, the carriages'
/// (eq. 6-8), the commanded carriage heights, the forces (eq. 14) and both sides of the
/// energy balance (eq. 20). Field names are the column names.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct TraceRow {
    pub t_s: f64,
    pub line: u64,
    pub x_mm: f64,
    pub y_mm: f64,
    pub z_mm: f64,
    pub vx_mm_s: f64,
    pub vy_mm_s: f64,
    pub vz_mm_s: f64,
    pub ax_mm_s2: f64,
    pub ay_mm_s2: f64,
    pub az_mm_s2: f64,
    pub q1_mm: f64,
    pub q2_mm: f64,
    pub q3_mm: f64,
    /// The commanded carriage heights: what the firmware's steps encode.
    pub q1_cmd_mm: f64,
    pub q2_cmd_mm: f64,
    pub q3_cmd_mm: f64,
    pub dq1_mm_s: f64,
    pub dq2_mm_s: f64,
    pub dq3_mm_s: f64,
    pub ddq1_mm_s2: f64,
    pub ddq2_mm_s2: f64,
    pub ddq3_mm_s2: f64,
    pub f1_n: f64,
    pub f2_n: f64,
    pub f3_n: f64,
    /// The force each motor can give at its carriage's speed.
    pub f1_avail_n: f64,
    pub f2_avail_n: f64,
    pub f3_avail_n: f64,
    /// Each parallelogram's tension (both rods), positive when it pulls the platform.
    pub t1_n: f64,
    pub t2_n: f64,
    pub t3_n: f64,
    pub power_w: f64,
    pub energy_rate_w: f64,
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
    pub motors: &'m Motors,
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

    fn merge(&self, rows: &mut Vec<u8>, later: Vec<u8>) {
        rows.extend(later);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
