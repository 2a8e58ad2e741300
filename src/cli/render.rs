//! `kardia render`.

use clap::Args;
use std::path::PathBuf;

/// Arguments of `kardia render`.
#[derive(Debug, Args, Default)]
pub struct RenderArgs {
    /// Scene file; without it, the built-in default heart scene.
    pub scene: Option<PathBuf>,
    /// Output image (.png or .exr).
    #[arg(short, long, default_value = "heart.png")]
    pub output: PathBuf,
}

/// Runs `kardia render`; returns the exit code.
pub fn run(args: RenderArgs) -> i32 {
    let _ = args;
    eprintln!("kardia render: not implemented yet");
    1
}
