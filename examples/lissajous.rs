//! Writes the paper's Lissajous test path (eq. 18: ω_x = 6π, ω_y = 4π, φ_x = π/2, φ_y = 0,
//! u ∈ [0, 1], amplitude 50 mm, nozzle on z = 0) as G-code: points stepped along the curve
//! with the paper's Taylor step (eq. 19) at constant speed v and period Ts = 1 ms, so they
//! are v·Ts apart (the last segment is shorter: it ends exactly at u = 1).
//!
//! The file is a motion test, not a print: no E words (M83 is set so that adding E later
//! would be relative). Header: G28, G90, M83, a travel to the start point, then one
//! `G1 X.. Y.. F..` line per point (F = v in mm/min), coordinates with 6 decimals (rounding to 4 would add direction noise of ~0.7 % of g to the 10 mm/s path).
//!
//! Usage: `cargo run --release --example lissajous -- SPEED_MM_S OUT.gcode`

use anyhow::{Context, Result, bail};
use delta_gcode::resample::{Curve, Lissajous, walk_constant_speed};
use std::io::{BufWriter, Write};

const AMPLITUDE_MM: f64 = 50.0;
const PERIOD_S: f64 = 0.001;
const TRAVEL_F_MM_MIN: f64 = 6000.0;

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [speed, out_path] = args.as_slice() else {
        bail!("usage: lissajous SPEED_MM_S OUT.gcode");
    };
    let v: f64 = speed
        .parse()
        .with_context(|| format!("speed {speed:?}: expected a number of mm/s"))?;
    if !(v > 0.0 && v.is_finite()) {
        bail!("speed {v}: expected a positive number of mm/s");
    }
    let curve = Lissajous::paper(AMPLITUDE_MM, 0.0);
    let file =
        std::fs::File::create(out_path).with_context(|| format!("cannot create {out_path}"))?;
    let mut w = BufWriter::new(file);
    let p0 = curve.point(0.0);
    writeln!(
        w,
        "; Lissajous path of the paper (eq. 18), x0 = y0 = {AMPLITUDE_MM} mm, z = 0"
    )?;
    writeln!(
        w,
        "; points stepped with eq. 19 at v = {v} mm/s, Ts = {PERIOD_S} s (spacing {} mm)",
        v * PERIOD_S
    )?;
    writeln!(w, "G28\nG90\nM83")?;
    writeln!(w, "G0 X{} Y{} Z0 F{TRAVEL_F_MM_MIN}", mm(p0.x), mm(p0.y))?;
    let f_mm_min = v * 60.0;
    let mut io: std::io::Result<()> = Ok(());
    // A generous bound on the number of steps: the path is ~ 1.1 m long.
    let max_steps = (10_000.0 / (v * PERIOD_S)) as usize;
    let done = walk_constant_speed(&curve, v, PERIOD_S, max_steps, &mut |u| {
        if u == 0.0 || io.is_err() {
            return;
        }
        let p = curve.point(u);
        io = writeln!(w, "G1 X{} Y{} F{f_mm_min}", mm(p.x), mm(p.y));
    });
    io?;
    if !done {
        bail!("the walk did not reach the end of the path");
    }
    w.flush()?;
    Ok(())
}

/// A coordinate with 6 decimals, without a "-0.000000".
fn mm(x: f64) -> String {
    let s = format!("{x:.6}");
    if s == "-0.000000" {
        "0.000000".to_string()
    } else {
        s
    }
}
