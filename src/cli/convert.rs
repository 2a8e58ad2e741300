//! `kardia convert`: writes kardia's own scene text for a SURFER `.jsurf` or surf `.pic` file
//! (the text `kardia render` reads from it), checked by loading it first.

use std::io::Write;
use std::path::{Path, PathBuf};

use clap::Args;

use crate::film::AtomicFile;
use crate::formats::{self, Warning};

/// Arguments of `kardia convert`.
#[derive(Debug, Args, Clone, PartialEq)]
pub struct ConvertArgs {
    /// The file to convert (.jsurf or .pic).
    pub input: PathBuf,
    /// The scene file to write; without it, the scene goes to standard output.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Print nothing but errors (no warnings).
    #[arg(short, long)]
    pub quiet: bool,
}

/// Prints a reader's warnings about `path` to standard error, one a line.
pub(super) fn print_warnings(path: &Path, warnings: &[Warning]) {
    for w in warnings {
        eprintln!(
            "kardia: warning: {}:{}: {}",
            path.display(),
            w.line,
            w.message
        );
    }
}

/// Runs `kardia convert`; returns the exit code (0 written, 1 on any error: then nothing is
/// written).
pub fn run(args: ConvertArgs) -> i32 {
    let loaded = match formats::load(&args.input, &Default::default()) {
        Ok(l) => l,
        Err(e) => {
            eprintln!("{:?}", miette::Report::new(e));
            return 1;
        }
    };
    if !args.quiet {
        print_warnings(&args.input, &loaded.warnings);
    }
    let Some(output) = &args.output else {
        print!("{}", loaded.text);
        return 0;
    };
    let written = AtomicFile::create(output).and_then(|mut file| {
        file.write_all(loaded.text.as_bytes())
            .map_err(|e| crate::film::OutputError::Write {
                path: output.display().to_string(),
                reason: e.to_string(),
            })?;
        file.commit()
    });
    match written {
        Ok(()) => {
            if !args.quiet {
                eprintln!("kardia: {} → {}", args.input.display(), output.display());
            }
            0
        }
        Err(e) => {
            eprintln!("kardia: {e}");
            1
        }
    }
}
