//! `check --plot DIR`: the forces of the three towers against time around the worst move,
//! and a map of the bed coloured by peak-force use.

use std::fs::File;
use std::io::BufReader;
use std::path::Path;

use anyhow::Context;

use super::input::Input;
use delta_gcode::analysis::{Window, run};
use delta_gcode::machine::Machine;
use delta_gcode::plot::{bed_map_svg, force_time_svg};
use delta_gcode::report::Report;

/// Half the time span plotted around the worst moment, s.
const HALF_WINDOW_S: f64 = 0.25;

/// Cells per side of the bed map's grid: each keeps its worst move, so the map's size does
/// not grow with the file.
const GRID: usize = 120;

/// Writes `DIR/STEM-forces.svg` and `DIR/STEM-bed.svg` for a checked file (a second pass
/// over it collects the samples around the worst moment and the bed map).
pub fn write_plots(
    input: &Input,
    machine: &Machine,
    report: &Report,
    dir: &Path,
) -> anyhow::Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let (file, stem) = (&input.path, input.stem());
    let limit = machine.motors.max_force_n;
    // The worst moment: the first of the worst violations, else the highest peak.
    let s = &report.summary;
    let worst_t = match report.worst_first().first() {
        Some(v) => v.t_s,
        None => (0..3)
            .max_by(|&a, &b| s.peak_force_n[a].total_cmp(&s.peak_force_n[b]))
            .map_or(0.0, |i| s.peak_t_s[i]),
    };
    let radius = machine.geometry.print_radius_mm;
    let cell = 2.0 * radius / GRID as f64;
    let mut grid = vec![None::<(f64, f64, f64)>; GRID * GRID];
    let mut window = Vec::new();
    let input = BufReader::with_capacity(1 << 16, File::open(file)?);
    let observer = Window {
        from_s: worst_t - HALF_WINDOW_S,
        to_s: worst_t + HALF_WINDOW_S,
    };
    run(
        input,
        machine,
        observer,
        |r| {
            window.append(&mut r.observed);
            let [x, y] = r.end_xy_mm;
            let use_ = r.stats.peak_n() / limit;
            let (i, j) = (((x + radius) / cell).floor(), ((y + radius) / cell).floor());
            if (0.0..GRID as f64).contains(&i) && (0.0..GRID as f64).contains(&j) {
                let c = &mut grid[j as usize * GRID + i as usize];
                if c.is_none_or(|(_, _, u)| use_ > u) {
                    *c = Some((x, y, use_));
                }
            }
        },
        |_| {},
    )?;
    window.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (t, f): (Vec<f64>, Vec<[f64; 3]>) = window.into_iter().unzip();
    force_time_svg(
        &dir.join(format!("{stem}-forces.svg")),
        &format!("{stem}: carriage forces around t = {worst_t:.3} s"),
        &t,
        &f,
        limit,
    )?;
    let points: Vec<(f64, f64, f64)> = grid.into_iter().flatten().collect();
    bed_map_svg(
        &dir.join(format!("{stem}-bed.svg")),
        &format!("{stem}: peak force / limit, by where moves end"),
        &points,
        radius,
    )
}
