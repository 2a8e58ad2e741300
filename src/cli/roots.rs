//! `kardia roots`.

use clap::Args;

/// Arguments of `kardia roots`.
#[derive(Debug, Args)]
pub struct RootsArgs {
    /// Coefficients c0 c1 … cn in ascending powers.
    #[arg(allow_negative_numbers = true)]
    pub coeffs: Vec<String>,
}

/// Runs `kardia roots`; returns the exit code.
pub fn run(args: RootsArgs) -> i32 {
    let _ = args;
    eprintln!("kardia roots: not implemented yet");
    2
}
