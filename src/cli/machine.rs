//! `delta-gcode machine`: validates a machine profile and prints its derived figures.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::Context;
use serde_json::{Value, json};

use super::common::{Format, text_or_json};
use super::out::put;
use delta_gcode::delta::TOWER_NAMES;
use delta_gcode::gcode::ArcRules;
use delta_gcode::machine::defaults::{self, SLOW_RATIO};
use delta_gcode::machine::{DefaultDrive, Firmware, Machine};
use delta_gcode::motion::drive::Drive;
use delta_gcode::motion::shaper::AxisShaper;
use delta_gcode::path::Vec3;
use delta_gcode::plot::{HLine, LineChart, Series, line_chart_svg};

/// Carriage speeds of the motor table in `machine`'s output, mm/s.
const CURVE_SPEEDS_MM_S: [f64; 7] = [0.0, 100.0, 200.0, 300.0, 400.0, 500.0, 600.0];

#[derive(clap::Args, Debug)]
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
pub struct Args {
    #[command(subcommand)]
    pub action: Option<Action>,
    /// Machine profile (YAML).
    #[arg(value_name = "M.yaml", required = true)]
    pub profile: Option<PathBuf>,
    /// Output format
    #[arg(long, default_value = "text", value_parser = text_or_json())]
    pub format: Format,
    /// Write the motor's force against carriage speed as SVG into DIR (STEM-motor.svg), and
    /// maps of the largest acceleration over the print disc at rest and at a print speed
    /// (STEM-accel-rest.svg, STEM-accel-speed.svg)
    #[arg(long, value_name = "DIR")]
    pub plot: Option<PathBuf>,
}

#[derive(clap::Subcommand, Debug)]
pub enum Action {
    /// Write a machine profile from a Klipper delta configuration (printer.cfg).
    ImportKlipper(super::import_klipper::Args),
}

pub fn run(args: &Args) -> anyhow::Result<ExitCode> {
    let profile = match (&args.action, &args.profile) {
        (Some(Action::ImportKlipper(import)), _) => return super::import_klipper::run(import),
        (None, Some(profile)) => profile,
        (None, None) => anyhow::bail!("a machine profile (M.yaml) is required"),
    };
    let machine = Machine::load(profile)?;
    let model = machine.model();
    let g = &machine.geometry;
    let centre = model.static_forces_n(Vec3::zeros())?;
    let (max_static, max_at, max_tower) = model
        .max_static_force_n(g.print_radius_mm)
        .ok_or_else(|| anyhow::anyhow!("the print disc is unreachable"))?;
    let home_q = model.home_carriages_mm();
    let reach_bed = model.reachable_radius_mm(0.0);
    let reach_home = model.reachable_radius_mm(g.home_z_mm);
    let full_disc_top = model.full_disc_top_mm(g.print_radius_mm);
    let slow = machine.slow_radius_mm(SLOW_RATIO);
    let very_slow = machine.slow_radius_mm(2.0 * SLOW_RATIO);
    let weight = model.suspended_weight_n();
    let limit = machine.motors.max_force_n;
    match args.format {
        Format::Json => {
            let v = json!({
                "name": machine.name,
                "delta_radius_mm": g.delta_radius_mm,
                "reachable_radius_bed_mm": reach_bed,
                "reachable_radius_home_mm": reach_home,
                "full_print_disc_up_to_z_mm": full_disc_top,
                "home_carriages_mm": home_q,
                "static_force_centre_n": centre,
                "max_static_force_n": max_static,
                "max_static_force_at_mm": [max_at.x, max_at.y],
                "max_static_force_tower": max_tower + 1,
                "suspended_weight_n": weight,
                "slow_radius_mm": slow,
                "very_slow_radius_mm": very_slow,
                "edge_slowdown": machine.limits.edge_slowdown,
                "max_extrude_only_velocity_mm_s": machine.extruder.max_extrude_only_velocity_mm_s,
                "max_extrude_only_accel_mm_s2": machine.extruder.max_extrude_only_accel_mm_s2,
                "max_force_n": limit,
                "firmware": machine.firmware.name(),
                "marlin": match &machine.firmware {
                    Firmware::Marlin(m) => json!(m),
                    Firmware::Klipper => Value::Null,
                },
                "gcode_arcs": arcs_json(&machine),
                "input_shaper": {
                    "x": machine.input_shaper.x.map(shaper_json),
                    "y": machine.input_shaper.y.map(shaper_json),
                },
                "drive": drive_json(&machine),
                "motor": motor_json(&machine),
                "max_accel_map": super::machine_accel::json(&machine),
            });
            put!("{v}");
        }
        Format::Text | Format::Github => {
            let l = &machine.limits;
            let e = &machine.extruder;
            put!("{}: profile OK ({})", machine.name, profile.display());
            put!(
                "geometry: delta radius {:.3} mm, arms {:.3}/{:.3}/{:.3} mm, nozzle offset {:.3} mm",
                g.delta_radius_mm,
                g.arm_length_mm[0],
                g.arm_length_mm[1],
                g.arm_length_mm[2],
                g.nozzle_offset_mm
            );
            put!(
                "reachable radius: {reach_bed:.2} mm at the bed, {reach_home:.2} mm at home z = {:.2} mm; \
                 the print disc (r = {:.2} mm) is whole up to z = {full_disc_top:.2} mm",
                g.home_z_mm,
                g.print_radius_mm
            );
            put!(
                "home carriages: {:.3} / {:.3} / {:.3} mm (towers A/B/C)",
                home_q[0],
                home_q[1],
                home_q[2]
            );
            put!(
                "static force at the centre (eq. 16): {:.3} / {:.3} / {:.3} N",
                centre[0],
                centre[1],
                centre[2]
            );
            put!(
                "largest static force on the print disc (eq. 15): {max_static:.3} N, tower {} at ({:.1}, {:.1}) mm",
                TOWER_NAMES[max_tower],
                max_at.x,
                max_at.y
            );
            put!("suspended weight (eq. 17): {weight:.3} N");
            put!(
                "edge slowdown (Klipper delta.py){}: half speed beyond r = {slow:.2} mm, quarter beyond r = {very_slow:.2} mm",
                if l.edge_slowdown { "" } else { ", disabled" }
            );
            put!(
                "limits: {} mm/s, {} mm/s², z {} mm/s, {} mm/s², square corner {} mm/s, min cruise ratio {}",
                l.max_velocity_mm_s,
                l.max_accel_mm_s2,
                l.max_z_velocity_mm_s,
                l.max_z_accel_mm_s2,
                l.square_corner_velocity_mm_s,
                l.minimum_cruise_ratio
            );
            put!(
                "extruder: extrude-only {:.2} mm/s, {:.1} mm/s², corner {} mm/s",
                e.max_extrude_only_velocity_mm_s,
                e.max_extrude_only_accel_mm_s2,
                e.instantaneous_corner_velocity_mm_s
            );
            put!(
                "motor limit: {limit:.2} N per carriage ({:.0} % used by the worst static pose); rotor mass seen at the belt {:.4} kg; sampling {} s; g = {} m/s²",
                100.0 * max_static / limit,
                machine.motors.reflected_mass_kg,
                machine.sampling.period_s,
                machine.gravity_m_s2
            );
            print_additions(&machine);
            super::machine_accel::print_text(&machine);
        }
    }
    if let Some(dir) = &args.plot {
        let stem = profile
            .file_stem()
            .map_or_else(|| "machine".into(), |s| s.to_string_lossy().into_owned());
        let path = dir.join(format!("{stem}-motor.svg"));
        std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
        plot_motor(&machine, &path)?;
        super::machine_accel::plot(&machine, dir, &stem)?;
    }
    Ok(ExitCode::SUCCESS)
}

/// The text lines of the firmware, arcs, shaper, drive and motor, after the others.
fn print_additions(machine: &Machine) {
    match &machine.firmware {
        Firmware::Klipper => put!("firmware: klipper"),
        Firmware::Marlin(m) => {
            let list = |v: [f64; 4]| format!("{}/{}/{} (E {})", v[0], v[1], v[2], v[3]);
            put!(
                "firmware: marlin: {} steps/mm (E {}), {} segments/s, max feedrate {} mm/s, \
                 max accel {} mm/s², accel print {} / retract {} / travel {} mm/s², jerk {} \
                 mm/s, S-curve {}, {} blocks, min {} steps/segment, min segment time {} µs, \
                 min planner speed {} mm/s",
                m.steps_per_mm,
                m.e_steps_per_mm,
                m.segments_per_second,
                list(m.max_feedrate_mm_s),
                list(m.max_accel_mm_s2),
                m.print_accel_mm_s2,
                m.retract_accel_mm_s2,
                m.travel_accel_mm_s2,
                list(m.jerk_mm_s),
                if m.s_curve { "on" } else { "off" },
                m.block_buffer_size,
                m.min_steps_per_segment,
                m.min_segment_time_us,
                m.minimum_planner_speed_mm_s
            );
        }
    }
    match machine.dialect().arcs {
        ArcRules::Klipper { resolution_mm } => {
            put!("arcs: Klipper's [gcode_arcs], chords of {resolution_mm} mm")
        }
        ArcRules::Marlin {
            max_segment_mm,
            min_segment_mm,
            min_circle_segments,
            segments_per_sec,
            n_arc_correction,
        } => put!(
            "arcs: Marlin's plan_arc, chords of {min_segment_mm} to {max_segment_mm} mm, \
             at least {min_circle_segments} a circle, {segments_per_sec} a second (0: off), \
             exact every {n_arc_correction}"
        ),
    }
    let shaper = |s: Option<AxisShaper>| {
        s.map_or_else(
            || "off".to_string(),
            |s| {
                format!(
                    "{} at {} Hz, damping ratio {}",
                    s.kind.name(),
                    s.freq_hz,
                    s.damping_ratio
                )
            },
        )
    };
    let sh = &machine.input_shaper;
    put!("input shaper: x {}; y {}", shaper(sh.x), shaper(sh.y));
    put!("drive: {}", drive_text(machine));
    let m = &machine.motors;
    let motor = m.model.map_or_else(String::new, |n| format!("{n}, "));
    match &m.curve {
        None => put!(
            "motor: {motor}{:.2} N at any carriage speed (no electrical figures)",
            m.max_force_n
        ),
        Some(c) => {
            put!(
                "motor: {motor}force at carriage speed (current-chopped stepper model), knee \
                 {:.2} mm/s, zero force at {:.2} mm/s",
                c.knee_speed_mm_s(),
                c.zero_force_speed_mm_s()
            );
            let speeds: Vec<String> = CURVE_SPEEDS_MM_S
                .iter()
                .map(|v| format!("{v:>8.0}"))
                .collect();
            let forces: Vec<String> = CURVE_SPEEDS_MM_S
                .iter()
                .map(|&v| format!("{:>8.2}", c.available_force_n(v)))
                .collect();
            put!("  carriage speed mm/s {}", speeds.join(""));
            put!("  force N             {}", forces.join(""));
        }
    }
}

/// The drive, and where a default comes from.
fn drive_text(machine: &Machine) -> String {
    let Drive::Spring(s) = machine.drive else {
        return "rigid (given)".into();
    };
    let spring = format!(
        "spring of {:.2} Hz, damping ratio {}",
        s.frequency_hz, s.damping_ratio
    );
    let Some(d) = machine.drive_default else {
        return format!("{spring} (given)");
    };
    let motor = if d.typical_motor {
        format!(
            "a typical motor ({} N·m, 1.8°, GT2 {} teeth: the profile gives only max_force_n)",
            defaults::TYPICAL_HOLDING_TORQUE_NM,
            defaults::TYPICAL_PULLEY_TEETH
        )
    } else {
        "the motor".into()
    };
    format!(
        "{spring} (the default: no `drive` in the profile; {motor} k_m = {:.0} N/m in series \
         with {:.0} mm of 6 mm GT2 belt k_b = {:.0} N/m: {:.0} N/m per carriage; along X \
         {:.4} kg and {:.0} N/m; damping ratio typical. Measure yours (SHAPER_CALIBRATE) and \
         set `drive`)",
        d.motor_stiffness_n_m,
        d.belt_length_mm,
        d.belt_stiffness_n_m,
        d.carriage_stiffness_n_m,
        d.mass_kg,
        d.stiffness_n_m
    )
}

fn arcs_json(machine: &Machine) -> Value {
    // The profile's `gcode_arcs` (Klipper's); Marlin's arc settings are in `marlin`.
    let ArcRules::Klipper { resolution_mm } = machine.arc_rules else {
        return Value::Null;
    };
    json!({"resolution_mm": resolution_mm})
}

fn shaper_json(s: AxisShaper) -> Value {
    json!({"type": s.kind.name(), "freq_hz": s.freq_hz, "damping_ratio": s.damping_ratio})
}

fn drive_json(machine: &Machine) -> Value {
    match machine.drive {
        Drive::Rigid => json!({"kind": "rigid", "default": Value::Null}),
        Drive::Spring(s) => json!({
            "kind": "spring",
            "frequency_hz": s.frequency_hz,
            "damping_ratio": s.damping_ratio,
            "default": machine.drive_default.map(default_drive_json),
        }),
    }
}

fn default_drive_json(d: DefaultDrive) -> Value {
    json!({
        "typical_motor": d.typical_motor,
        "motor_stiffness_n_m": d.motor_stiffness_n_m,
        "belt_length_mm": d.belt_length_mm,
        "belt_stiffness_n_m": d.belt_stiffness_n_m,
        "carriage_stiffness_n_m": d.carriage_stiffness_n_m,
        "mass_kg": d.mass_kg,
        "stiffness_n_m": d.stiffness_n_m,
    })
}

fn motor_json(machine: &Machine) -> Value {
    let m = &machine.motors;
    json!({
        "model": m.model,
        "max_force_n": m.max_force_n,
        "reflected_mass_kg": m.reflected_mass_kg,
        "stiffness_n_m": m.stiffness_n_m,
        "curve": {
            "speed_mm_s": CURVE_SPEEDS_MM_S,
            "force_n": CURVE_SPEEDS_MM_S.map(|v| m.available_force_n(v)),
            "knee_speed_mm_s": m.curve.map(|c| c.knee_speed_mm_s()),
            "zero_force_speed_mm_s": m.curve.map(|c| c.zero_force_speed_mm_s()),
        },
    })
}

/// The motor's force against carriage speed as SVG: up to 10 % past its zero-force speed,
/// or, for a constant force, up to three times the profile's top speed (the carriage speed
/// at Klipper's edge slowdown ratio).
fn plot_motor(machine: &Machine, path: &Path) -> anyhow::Result<()> {
    let m = &machine.motors;
    let top = m
        .curve
        .map_or(SLOW_RATIO * machine.limits.max_velocity_mm_s, |c| {
            1.1 * c.zero_force_speed_mm_s()
        });
    const POINTS: usize = 400;
    let points = (0..=POINTS)
        .map(|i| {
            let v = top * i as f64 / POINTS as f64;
            (v, m.available_force_n(v))
        })
        .collect();
    let series = [Series {
        name: m.model.unwrap_or("motor").to_string(),
        points,
    }];
    let title = format!("{}: force a carriage motor can give", machine.name);
    line_chart_svg(
        path,
        &LineChart {
            title: &title,
            x_desc: "carriage speed (mm/s)",
            y_desc: "force (N)",
            series: &series,
            hlines: &[HLine {
                y: m.max_force_n,
                name: format!("low-speed force {:.1} N", m.max_force_n),
            }],
        },
    )
}
