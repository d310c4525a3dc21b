//! `delta-gcode strip FILE (-o OUT | --in-place)`: the G-code without the lines `annotate`
//! and `fix` added, byte for byte the file they were given.

use std::fs::File;
use std::io::BufReader;
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context;

use super::common::RewriteArgs;
use super::replace::replace_file;
use delta_gcode::emit::strip;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// G-code file that `annotate` or `fix` wrote
    #[arg(value_name = "FILE")]
    pub file: PathBuf,
    #[command(flatten)]
    pub write: RewriteArgs,
}

pub fn run(args: &Args) -> anyhow::Result<ExitCode> {
    let target = args.write.target(&args.file);
    replace_file(target, |w| {
        let input = BufReader::with_capacity(1 << 16, File::open(&args.file)?);
        strip(input, w)
    })
    .with_context(|| format!("stripping {}", args.file.display()))?;
    Ok(ExitCode::SUCCESS)
}
