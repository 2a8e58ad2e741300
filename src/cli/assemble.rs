//! `kardia assemble`: joins part files (`kardia render --tile I/N` or `--region`) into the
//! whole image, byte for byte the file a single render writes.

use std::path::PathBuf;

use clap::Args;

use crate::tiles;

/// Arguments of `kardia assemble`.
#[derive(Debug, Args, Clone, PartialEq)]
pub struct AssembleArgs {
    /// The part files, in any order (all PNG or all EXR).
    #[arg(required = true)]
    pub parts: Vec<PathBuf>,
    /// The whole image to write (.png for PNG parts, .exr for EXR parts).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Print nothing but errors.
    #[arg(short, long)]
    pub quiet: bool,
}

/// Runs `kardia assemble`; returns the exit code (0 joined and written, 1 refused or failed:
/// then nothing is written).
pub fn run(args: AssembleArgs) -> i32 {
    match tiles::assemble(&args.parts, &args.output) {
        Ok(()) => {
            if !args.quiet {
                eprintln!(
                    "kardia: {} part{} → {}",
                    args.parts.len(),
                    if args.parts.len() == 1 { "" } else { "s" },
                    args.output.display()
                );
            }
            0
        }
        Err(e) => {
            eprintln!("{:?}", miette::Report::new(e));
            1
        }
    }
}
