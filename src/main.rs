//! The `kardia` binary: installs the Ctrl-C handling, hands the command line to the library and
//! exits with its code.
//!
//! Ctrl-C (SIGINT; also SIGTERM and SIGHUP) cancels the render in progress, which stops within
//! one tile, removes its unfinished output and exits with code 130. A second Ctrl-C exits at
//! once.

fn main() {
    let interrupt = kardia::pipeline::CancelToken::new();
    let on_signal = interrupt.clone();
    let installed = ctrlc::set_handler(move || {
        if on_signal.is_cancelled() {
            std::process::exit(kardia::cli::INTERRUPTED);
        }
        on_signal.cancel();
    });
    if let Err(e) = installed {
        eprintln!("kardia: warning: Ctrl-C will not clean up: {e}");
    }
    std::process::exit(kardia::cli::main(&interrupt));
}
