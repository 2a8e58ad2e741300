//! `kardia explore`.

use crate::explore::{self, Options};
use crate::pipeline::CancelToken;
use clap::Args;
use std::net::IpAddr;
use std::path::PathBuf;

/// Arguments of `kardia explore`.
#[derive(Debug, Args, Clone, PartialEq)]
pub struct ExploreArgs {
    /// Scene to open first; without it, the built-in default heart (scenes/heart.scene).
    pub scene: Option<PathBuf>,
    /// Port to listen on (0: any free port).
    #[arg(long, default_value_t = 8470)]
    pub port: u16,
    /// Address to listen on. Anything but a loopback address lets other machines render.
    #[arg(long, default_value = "127.0.0.1")]
    pub host: IpAddr,
    /// Open the page in the default browser.
    #[arg(long)]
    pub open: bool,
    /// Render threads [default: one per core].
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=4096))]
    pub threads: Option<u32>,
}

/// Runs `kardia explore` until `interrupt` (Ctrl-C); returns the exit code (0 after
/// Ctrl-C, 1 on any error).
pub fn run(args: ExploreArgs, interrupt: &CancelToken) -> i32 {
    let mut options = Options {
        host: args.host,
        port: args.port,
        threads: args.threads.map_or(0, |t| t as usize),
        ..Options::default()
    };
    if let Some(path) = &args.scene {
        // Read once here: the server never reads a file a page names. A .jsurf or .pic file
        // is shown as the kardia scene it translates to.
        let loaded = match crate::formats::load(path, &Default::default()) {
            Ok(loaded) => loaded,
            Err(e) => {
                eprintln!("{:?}", miette::Report::new(e));
                return 1;
            }
        };
        super::convert::print_warnings(path, &loaded.warnings);
        options.scene_name = path.display().to_string();
        options.scene_text = loaded.text;
    }
    if !args.host.is_loopback() {
        eprintln!(
            "kardia: warning: listening on {} — any machine that can reach it can use this \
             explorer and its CPU",
            args.host
        );
    }
    let open = args.open;
    let interrupt = interrupt.clone();
    let interrupted = async move {
        while !interrupt.is_cancelled() {
            tokio::time::sleep(std::time::Duration::from_millis(50)).await;
        }
    };
    let ready = |url: &str| {
        outln!("kardia explore: {url}  (Ctrl-C stops)");
        if open {
            open_browser(url);
        }
    };
    let result = explore::run(options, ready, interrupted);
    match result {
        Ok(()) => {
            eprintln!("kardia explore: stopped");
            0
        }
        Err(e) => {
            eprintln!("kardia: {e}");
            1
        }
    }
}

/// Asks the desktop to open `url`; a failure is only reported.
fn open_browser(url: &str) {
    let opener = if cfg!(target_os = "macos") {
        "open"
    } else if cfg!(target_os = "windows") {
        "explorer"
    } else {
        "xdg-open"
    };
    if let Err(e) = std::process::Command::new(opener).arg(url).spawn() {
        eprintln!("kardia: could not open a browser ({opener}: {e}); open {url} yourself");
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Parser)]
    struct Wrapper {
        #[command(flatten)]
        args: ExploreArgs,
    }

    #[test]
    fn parses_options() {
        let a = Wrapper::try_parse_from(["explore"]).unwrap().args;
        assert_eq!((a.port, a.open, a.scene), (8470, false, None));
        assert!(a.host.is_loopback());
        let a = Wrapper::try_parse_from([
            "explore", "s.scene", "--port", "0", "--host", "0.0.0.0", "--open",
        ])
        .unwrap()
        .args;
        assert_eq!((a.port, a.open), (0, true));
        assert!(!a.host.is_loopback());
        assert!(Wrapper::try_parse_from(["explore", "--host", "example.com"]).is_err());
    }
}
