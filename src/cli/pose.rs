//! `delta-gcode pose`: the model at one nozzle state, or the direct kinematics of three
//! carriage heights.

use std::process::ExitCode;

use anyhow::Context;
use serde_json::json;

use super::common::{Format, MachineArg, text_or_json};
use super::out::put;
use delta_gcode::delta::TOWER_NAMES;
use delta_gcode::path::Vec3;

#[derive(clap::Args, Debug)]
#[command(allow_negative_numbers = true)]
pub struct Args {
    #[command(flatten)]
    pub machine: MachineArg,
    /// Nozzle position X Y Z, mm (bed frame).
    #[arg(
        num_args = 3,
        value_names = ["X", "Y", "Z"],
        required_unless_present = "carriages",
        conflicts_with = "carriages"
    )]
    pub position: Vec<f64>,
    /// Nozzle velocity, mm/s.
    #[arg(long, value_name = "VX,VY,VZ", value_parser = parse_triple, allow_hyphen_values = true)]
    pub velocity: Option<[f64; 3]>,
    /// Nozzle acceleration, mm/s².
    #[arg(long, value_name = "AX,AY,AZ", value_parser = parse_triple, allow_hyphen_values = true)]
    pub accel: Option<[f64; 3]>,
    /// Carriage heights Q1,Q2,Q3 (mm): run the direct kinematics instead.
    #[arg(
        long,
        value_name = "Q1,Q2,Q3",
        value_parser = parse_triple,
        allow_hyphen_values = true,
        conflicts_with_all = ["velocity", "accel"]
    )]
    pub carriages: Option<[f64; 3]>,
    /// Output format
    #[arg(long, default_value = "text", value_parser = text_or_json())]
    pub format: Format,
}

/// Parses "a,b,c" into three finite numbers.
fn parse_triple(s: &str) -> Result<[f64; 3], String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    let [a, b, c] = parts[..] else {
        return Err(format!(
            "expected three comma-separated numbers, found {s:?}"
        ));
    };
    let num = |t: &str| match t.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(format!("{t:?} is not a finite number")),
    };
    Ok([num(a)?, num(b)?, num(c)?])
}

pub fn run(args: &Args) -> anyhow::Result<ExitCode> {
    let machine = args.machine.load()?;
    let model = machine.model();
    if let Some(q) = args.carriages {
        let p = model
            .forward(q)
            .context("the carriage heights have no nozzle position")?;
        match args.format {
            Format::Json => put!("{}", json!({"q_mm": q, "position_mm": [p.x, p.y, p.z]})),
            Format::Text | Format::Github => {
                put!("machine: {}", machine.name);
                put!("carriages (mm): {:.4} {:.4} {:.4}", q[0], q[1], q[2]);
                put!("position_mm: x {:.4}  y {:.4}  z {:.4}", p.x, p.y, p.z);
            }
        }
        return Ok(ExitCode::SUCCESS);
    }
    let [x, y, z] = args.position[..] else {
        anyhow::bail!("expected the nozzle position X Y Z");
    };
    if ![x, y, z].iter().all(|v| v.is_finite()) {
        anyhow::bail!("the nozzle position must be finite numbers");
    }
    let pos = Vec3::new(x, y, z);
    let vel = Vec3::from(args.velocity.unwrap_or_default());
    let acc = Vec3::from(args.accel.unwrap_or_default());
    let s = model
        .evaluate(pos, vel, acc)
        .with_context(|| format!("nozzle position ({x}, {y}, {z}) mm is unreachable"))?;
    // The force each motor can give at its carriage's speed.
    let available = s.dq_mm_s.map(|v| machine.motors.available_force_n(v));
    match args.format {
        Format::Json => {
            /// The model's state and the force each motor can give at its carriage's speed.
            #[derive(serde::Serialize)]
            struct PoseJson<'a, S: serde::Serialize> {
                #[serde(flatten)]
                state: &'a S,
                available_force_n: [f64; 3],
            }
            let out = PoseJson {
                state: &s,
                available_force_n: available,
            };
            put!("{}", serde_json::to_string(&out)?);
        }
        Format::Text | Format::Github => {
            put!("machine: {}", machine.name);
            put!(
                "nozzle mm: {x:.4} {y:.4} {z:.4}   mm/s: {:.3} {:.3} {:.3}   mm/s²: {:.1} {:.1} {:.1}",
                vel.x,
                vel.y,
                vel.z,
                acc.x,
                acc.y,
                acc.z
            );
            put!(
                "{:<22}{:>14}{:>14}{:>14}",
                "tower",
                TOWER_NAMES[0],
                TOWER_NAMES[1],
                TOWER_NAMES[2]
            );
            let rows: [(&str, [f64; 3]); 7] = [
                ("carriage q (mm)", s.q_mm),
                ("velocity dq (mm/s)", s.dq_mm_s),
                ("accel ddq (mm/s²)", s.ddq_mm_s2),
                ("force Q (N)", s.force_n),
                ("available (N)", available),
                ("lambda (N/m)", s.lambda),
                ("arm tension (N)", s.arm_tension_n),
            ];
            for (label, v) in rows {
                put!("{label:<22}{:>14.4}{:>14.4}{:>14.4}", v[0], v[1], v[2]);
            }
            put!(
                "power ΣQ·dq: {:.6} W   d(K+U)/dt: {:.6} W",
                s.power_w,
                s.energy_rate_w
            );
            put!(
                "kinetic: {:.6} J   potential: {:.6} J",
                s.kinetic_j,
                s.potential_j
            );
            put!("Jx condition (Frobenius): {:.3}", s.jx_condition);
            let limit = machine.motors.max_force_n;
            if s.force_n.iter().any(|f| f.abs() > limit) {
                put!("over the motor limit of {limit} N");
            }
        }
    }
    Ok(ExitCode::SUCCESS)
}
