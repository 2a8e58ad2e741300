//! The command line: argument parsing and printing only; all work is done by the library.
//! Each subcommand lives in its own file with its arguments and its `run`.

mod explore;
mod probe;
mod render;
mod roots;

use clap::{Parser, Subcommand};

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
}

/// Runs the command line and returns the process exit code.
pub fn main() -> i32 {
    let cli = Cli::parse();
    match cli.command {
        None => render::run(render::RenderArgs::default()),
        Some(Command::Render(a)) => render::run(a),
        Some(Command::Roots(a)) => roots::run(a),
        Some(Command::Probe(a)) => probe::run(a),
        Some(Command::Explore(a)) => explore::run(a),
    }
}
