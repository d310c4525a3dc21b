//! `delta-gcode machine import-klipper printer.cfg`: a machine profile from a Klipper delta
//! configuration; masses and the motor limit come from flags, or are listed as missing (the
//! motor's pulley, step angle and driver current come from the configuration).

use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context;

use super::out::say;
use super::replace::replace_file;
use delta_gcode::klipper_import::{ImportExtras, import_klipper};

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Klipper configuration (printer.cfg) with `[printer] kinematics: delta`
    #[arg(value_name = "printer.cfg")]
    pub config: PathBuf,
    /// Write the profile here instead of standard output
    #[arg(long, short, value_name = "M.yaml")]
    pub output: Option<PathBuf>,
    /// Profile name
    #[arg(long)]
    pub name: Option<String>,
    /// Mass of one carriage, kg (not in a Klipper config)
    #[arg(long, value_name = "KG")]
    pub cart_kg: Option<f64>,
    /// Mass of one of the six arms, kg
    #[arg(long, value_name = "KG")]
    pub link_kg: Option<f64>,
    /// Mass of the effector with the hotend, kg
    #[arg(long, value_name = "KG")]
    pub platform_kg: Option<f64>,
    /// Allowed peak force per carriage, N
    #[arg(long, value_name = "N")]
    pub max_force_n: Option<f64>,
}

pub fn run(args: &Args) -> anyhow::Result<ExitCode> {
    let origin = args.config.display().to_string();
    let text =
        std::fs::read_to_string(&args.config).with_context(|| format!("cannot read {origin}"))?;
    let extras = ImportExtras {
        name: args.name.clone(),
        cart_kg: args.cart_kg,
        link_kg: args.link_kg,
        platform_kg: args.platform_kg,
        max_force_n: args.max_force_n,
    };
    let imported = import_klipper(&text, &origin, &extras)?;
    match &args.output {
        Some(path) => replace_file(path, |w| w.write_all(imported.yaml.as_bytes()))?,
        None => std::io::stdout().write_all(imported.yaml.as_bytes())?,
    }
    for note in &imported.notes {
        say!("delta-gcode: note: {note}");
    }
    if !imported.missing.is_empty() {
        say!(
            "delta-gcode: the profile is incomplete, missing {}: `check` refuses it until they \
             are added (--cart-kg, --link-kg, --platform-kg; for the motors --max-force-n, or \
             `model` and `safety_factor` in the file)",
            imported.missing.join(", ")
        );
    }
    Ok(ExitCode::SUCCESS)
}
