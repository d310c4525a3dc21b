//! The command line: one module per subcommand, each with its clap `Args` and `run`.

mod annotate;
mod check;
mod check_plots;
mod common;
mod fix;
mod import_klipper;
mod input;
mod machine;
mod machine_accel;
mod out;
mod plot;
mod pose;
mod replace;
mod strip;
mod trace;

use std::process::ExitCode;

use clap::{Parser, Subcommand};
use out::say;

/// Finds the moves in delta-printer G-code that ask a carriage motor for more force than
/// it can give.
#[derive(Parser, Debug)]
#[command(name = "delta-gcode", version, about)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Check G-code files: exit 0 within limits, 1 when a move exceeds one, 2 on errors.
    Check(check::Args),
    /// Write the analysis into the G-code (for slicer post-processing hooks).
    Annotate(annotate::Args),
    /// Add the firmware's limit commands around the moves that need them, so that every
    /// move passes.
    Fix(fix::Args),
    /// Remove the lines `annotate` and `fix` added.
    Strip(strip::Args),
    /// One CSV row per sample: nozzle and carriage motion, forces, power.
    Trace(trace::Args),
    /// The model at one nozzle state: carriages, their velocities and accelerations, forces.
    Pose(pose::Args),
    /// Validate a machine profile and print its derived figures.
    Machine(machine::Args),
    /// Plot trace columns (CSV from `trace`) against time as SVG.
    Plot(plot::Args),
}

/// Exit code for a usage, input or profile error.
pub const EXIT_ERROR: u8 = 2;

pub fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            let _ = e.print();
            return if e.use_stderr() {
                ExitCode::from(EXIT_ERROR)
            } else {
                ExitCode::SUCCESS
            };
        }
    };
    let result = match &cli.command {
        Command::Check(args) => check::run(args),
        Command::Annotate(args) => annotate::run(args),
        Command::Fix(args) => fix::run(args),
        Command::Strip(args) => strip::run(args),
        Command::Trace(args) => trace::run(args),
        Command::Pose(args) => pose::run(args),
        Command::Machine(args) => machine::run(args),
        Command::Plot(args) => plot::run(args),
    };
    match result {
        Ok(code) => code,
        Err(e) => {
            say!("delta-gcode: error: {e:#}");
            ExitCode::from(EXIT_ERROR)
        }
    }
}
