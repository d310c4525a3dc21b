//! `delta-gcode trace FILE --machine M.yaml -o trace.csv`: one CSV row per sample.

use std::fs::File;
use std::io::{BufReader, BufWriter, Write};
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context;

use super::common::MachineArg;
use super::replace::replace_file;
use delta_gcode::analysis::{TraceRows, run as run_pipeline, trace_header};

#[derive(clap::Args, Debug)]
pub struct Args {
    /// G-code file to trace
    #[arg(value_name = "FILE")]
    pub file: PathBuf,
    #[command(flatten)]
    pub machine: MachineArg,
    /// CSV output; `-` for standard output
    #[arg(long, short, value_name = "CSV")]
    pub output: PathBuf,
}

pub fn run(args: &Args) -> anyhow::Result<ExitCode> {
    let machine = args.machine.load()?;
    let write = |w: &mut (dyn Write + Send)| -> std::io::Result<()> {
        let input = BufReader::with_capacity(1 << 16, File::open(&args.file)?);
        w.write_all(trace_header().as_bytes())?;
        let mut failure = Ok(());
        run_pipeline(
            input,
            &machine,
            TraceRows {
                motors: &machine.motors,
            },
            |r| {
                if failure.is_ok() {
                    failure = w.write_all(&r.observed);
                }
            },
            |d| {
                eprintln!(
                    "{}:{}:{}: {}",
                    args.file.display(),
                    d.line,
                    d.column,
                    d.message
                );
            },
        )?;
        failure
    };
    if args.output.as_os_str() == "-" {
        let mut out = BufWriter::with_capacity(1 << 16, std::io::stdout());
        write(&mut out)?;
        out.flush()?;
    } else {
        replace_file(&args.output, write)
            .with_context(|| format!("tracing {}", args.file.display()))?;
    }
    Ok(ExitCode::SUCCESS)
}
