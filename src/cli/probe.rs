//! `kardia probe`.

use clap::Args;
use std::path::PathBuf;

/// Arguments of `kardia probe`.
#[derive(Debug, Args)]
pub struct ProbeArgs {
    /// Scene file.
    pub scene: PathBuf,
}

/// Runs `kardia probe`; returns the exit code.
pub fn run(args: ProbeArgs) -> i32 {
    let _ = args;
    eprintln!("kardia probe: not implemented yet");
    1
}
