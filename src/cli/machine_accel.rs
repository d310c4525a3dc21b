//! `machine`'s map of where the machine is weak: the largest acceleration each point of the
//! print disc can take in its worst direction, at rest and at a print speed
//! (`tune::capacity`), as a table by radius and as SVG maps over the disc.

use std::path::Path;

use serde_json::{Value, json};

use super::out::put;
use delta_gcode::machine::Machine;
use delta_gcode::path::Vec3;
use delta_gcode::plot::bed_map_svg;
use delta_gcode::tune::capacity::max_accel_mm_s2;

/// The print speed of the map, mm/s (or the profile's max_velocity when lower).
const PRINT_SPEED_MM_S: f64 = 100.0;
/// Radii of the table, as shares of the print radius.
const RADII: [f64; 5] = [0.0, 0.25, 0.5, 0.75, 1.0];
/// Points around each ring of the table.
const RING_POINTS: usize = 72;
/// Points across the disc's diameter on the maps.
const MAP_POINTS: usize = 61;

/// The speeds of the map: at rest and at the print speed, mm/s.
fn speeds(machine: &Machine) -> [f64; 2] {
    [0.0, PRINT_SPEED_MM_S.min(machine.limits.max_velocity_mm_s)]
}

/// Per radius of [`RADII`] and per speed, the weakest point of the ring (at the bed),
/// mm/s²; None where some point is out of reach.
fn table(machine: &Machine) -> Vec<(f64, [Option<f64>; 2])> {
    let model = machine.model();
    let r_print = machine.geometry.print_radius_mm;
    RADII
        .iter()
        .map(|share| {
            let r = share * r_print;
            let n = if r == 0.0 { 1 } else { RING_POINTS };
            let at = |speed: f64| {
                (0..n)
                    .map(|k| {
                        let th = std::f64::consts::TAU * k as f64 / n as f64;
                        let p = Vec3::new(r * th.cos(), r * th.sin(), 0.0);
                        max_accel_mm_s2(&model, &machine.motors, p, speed)
                    })
                    .try_fold(f64::INFINITY, |w, a| a.map(|a| w.min(a)))
            };
            let [rest, moving] = speeds(machine);
            (r, [at(rest), at(moving)])
        })
        .collect()
}

pub fn print_text(machine: &Machine) {
    let [_, v] = speeds(machine);
    put!(
        "largest acceleration in the worst direction at the bed (profile max_accel {} mm/s²):",
        machine.limits.max_accel_mm_s2
    );
    put!("  radius mm     at rest mm/s²   at {v:.0} mm/s mm/s²");
    let cell = |a: Option<f64>| a.map_or_else(|| "unreachable".to_string(), |a| format!("{a:.0}"));
    for (r, [rest, moving]) in table(machine) {
        put!("  {r:>9.1} {:>15} {:>18}", cell(rest), cell(moving));
    }
}

pub fn json(machine: &Machine) -> Value {
    let t = table(machine);
    json!({
        "speed_mm_s": speeds(machine),
        "radius_mm": t.iter().map(|r| r.0).collect::<Vec<_>>(),
        "at_rest_mm_s2": t.iter().map(|r| r.1[0]).collect::<Vec<_>>(),
        "at_speed_mm_s2": t.iter().map(|r| r.1[1]).collect::<Vec<_>>(),
    })
}

/// STEM-accel-rest.svg and STEM-accel-speed.svg: each point of the disc coloured by the
/// profile's max_accel over the largest acceleration it can take (above 1, in reds:
/// max_accel is too much there).
pub fn plot(machine: &Machine, dir: &Path, stem: &str) -> anyhow::Result<()> {
    let model = machine.model();
    let r_print = machine.geometry.print_radius_mm;
    let max_accel = machine.limits.max_accel_mm_s2;
    for (name, speed) in ["rest", "speed"].into_iter().zip(speeds(machine)) {
        let mut points = Vec::new();
        for i in 0..MAP_POINTS {
            for j in 0..MAP_POINTS {
                let at = |k: usize| r_print * (2.0 * k as f64 / (MAP_POINTS - 1) as f64 - 1.0);
                let p = Vec3::new(at(i), at(j), 0.0);
                if p.x.hypot(p.y) > r_print {
                    continue;
                }
                let use_ = max_accel_mm_s2(&model, &machine.motors, p, speed)
                    .map_or(f64::INFINITY, |a| max_accel / a);
                points.push((p.x, p.y, use_));
            }
        }
        let title = format!(
            "{}: max_accel {max_accel} mm/s² over the largest acceleration, worst direction, at {speed:.0} mm/s",
            machine.name
        );
        bed_map_svg(
            &dir.join(format!("{stem}-accel-{name}.svg")),
            &title,
            &points,
            r_print,
        )?;
    }
    Ok(())
}
