//! `delta-gcode machine`: validates a machine profile and prints its derived figures.

use std::path::PathBuf;
use std::process::ExitCode;

use serde_json::json;

use super::common::{Format, text_or_json};
use delta_gcode::delta::TOWER_NAMES;
use delta_gcode::machine::Machine;
use delta_gcode::machine::defaults::SLOW_RATIO;
use delta_gcode::path::Vec3;

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
            });
            println!("{v}");
        }
        Format::Text | Format::Github => {
            let l = &machine.limits;
            let e = &machine.extruder;
            println!("{}: profile OK ({})", machine.name, profile.display());
            println!(
                "geometry: delta radius {:.3} mm, arms {:.3}/{:.3}/{:.3} mm, nozzle offset {:.3} mm",
                g.delta_radius_mm,
                g.arm_length_mm[0],
                g.arm_length_mm[1],
                g.arm_length_mm[2],
                g.nozzle_offset_mm
            );
            println!(
                "reachable radius: {reach_bed:.2} mm at the bed, {reach_home:.2} mm at home z = {:.2} mm; \
                 the print disc (r = {:.2} mm) is whole up to z = {full_disc_top:.2} mm",
                g.home_z_mm, g.print_radius_mm
            );
            println!(
                "home carriages: {:.3} / {:.3} / {:.3} mm (towers A/B/C)",
                home_q[0], home_q[1], home_q[2]
            );
            println!(
                "static force at the centre (eq. 16): {:.3} / {:.3} / {:.3} N",
                centre[0], centre[1], centre[2]
            );
            println!(
                "largest static force on the print disc (eq. 15): {max_static:.3} N, tower {} at ({:.1}, {:.1}) mm",
                TOWER_NAMES[max_tower], max_at.x, max_at.y
            );
            println!("suspended weight (eq. 17): {weight:.3} N");
            println!(
                "edge slowdown (Klipper delta.py){}: half speed beyond r = {slow:.2} mm, quarter beyond r = {very_slow:.2} mm",
                if l.edge_slowdown { "" } else { ", disabled" }
            );
            println!(
                "limits: {} mm/s, {} mm/s², z {} mm/s, {} mm/s², square corner {} mm/s, min cruise ratio {}",
                l.max_velocity_mm_s,
                l.max_accel_mm_s2,
                l.max_z_velocity_mm_s,
                l.max_z_accel_mm_s2,
                l.square_corner_velocity_mm_s,
                l.minimum_cruise_ratio
            );
            println!(
                "extruder: extrude-only {:.2} mm/s, {:.1} mm/s², corner {} mm/s",
                e.max_extrude_only_velocity_mm_s,
                e.max_extrude_only_accel_mm_s2,
                e.instantaneous_corner_velocity_mm_s
            );
            println!(
                "motor limit: {limit:.2} N per carriage ({:.0} % used by the worst static pose); rotor mass seen at the belt {:.4} kg; sampling {} s; g = {} m/s²",
                100.0 * max_static / limit,
                machine.motors.reflected_mass_kg,
                machine.sampling.period_s,
                machine.gravity_m_s2
            );
        }
    }
    Ok(ExitCode::SUCCESS)
}
