//! The `delta-gcode` command: the command line over the library's pipeline.

mod cli;

use std::process::ExitCode;

fn main() -> ExitCode {
    cli::main()
}
