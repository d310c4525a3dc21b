use std::process::ExitCode;

fn main() -> ExitCode {
    delta_gcode::cli::main()
}
