//! The command line: argument parsing and printing only; all work is done by the library
//! (rendering by [`crate::pipeline`]). Each subcommand lives in its own file with its
//! arguments and its `run`.

/// `println!` to standard output that never panics: when the reader has gone
/// (`kardia mesh … | head`), the rest of the printing is dropped quietly and the command's
/// work and exit code stand (`println!` would panic on the broken pipe).
macro_rules! outln {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stdout().lock(), $($arg)*);
    }};
}

mod assemble;
mod convert;
mod explore;
mod frames;
mod mesh;
mod probe;
mod progress;
mod render;
mod roots;

use crate::pipeline::CancelToken;
use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};

pub use render::INTERRUPTED;

/// kardia: a ray tracer for the implicit heart and other algebraic surfaces.
#[derive(Debug, Parser)]
#[command(name = "kardia", version, about, long_about = None)]
pub struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Render a scene to PNG or OpenEXR (the default when no subcommand is given).
    Render(render::RenderArgs),
    /// Print the distinct real roots of a polynomial in an interval.
    Roots(roots::RootsArgs),
    /// Intersect rays read from stdin (or a camera pixel) with a scene; print JSON Lines.
    Probe(probe::ProbeArgs),
    /// Explore scenes and equations live in the browser (a local web server).
    Explore(explore::ExploreArgs),
    /// Join part files (rendered with --tile or --region) into the whole image.
    Assemble(assemble::AssembleArgs),
    /// Write kardia's scene text for a SURFER .jsurf or surf .pic file.
    Convert(convert::ConvertArgs),
    /// Mesh a scene's HEART and IMPLICIT objects (or an equation) as a printable solid.
    Mesh(mesh::MeshArgs),
}

/// The command line, parsed; `--version` also names the code path this process takes
/// ([`crate::cpu::path_name`]), so a bug report says whether AVX2 ran.
fn parse_command_line() -> Cli {
    let long_version = format!(
        "{} (code path: {}; {}=baseline selects the baseline)",
        env!("CARGO_PKG_VERSION"),
        crate::cpu::path_name(),
        crate::cpu::ENV_VAR
    );
    // Made once per process; clap keeps `&'static` texts.
    let long_version: &'static str = Box::leak(long_version.into_boxed_str());
    let matches = Cli::command().long_version(long_version).get_matches();
    Cli::from_arg_matches(&matches).unwrap_or_else(|e| e.exit())
}

/// Runs the command line and returns the process exit code. `interrupt` is the binary's
/// Ctrl-C: once cancelled, a render in progress stops within a tile, writes nothing and the
/// code is [`INTERRUPTED`] (the library installs no signal handler).
pub fn main(interrupt: &CancelToken) -> i32 {
    let cli = parse_command_line();
    match cli.command {
        None => render::run(render::RenderArgs::default(), interrupt),
        Some(Command::Render(a)) => render::run(a, interrupt),
        Some(Command::Roots(a)) => roots::run(a),
        Some(Command::Probe(a)) => probe::run(a),
        Some(Command::Explore(a)) => explore::run(a, interrupt),
        Some(Command::Assemble(a)) => assemble::run(a),
        Some(Command::Convert(a)) => convert::run(a),
        Some(Command::Mesh(a)) => mesh::run(a),
    }
}
