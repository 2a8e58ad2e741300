//! The `kardia` binary: installs the signal handling, hands the command line to the library and
//! exits with its code.
//!
//! SIGINT (Ctrl-C), SIGTERM (what Slurm, Kubernetes and `kill` send) and SIGHUP cancel the
//! render in progress, which stops within one tile and removes its unfinished output; the exit
//! code is then the shell's convention for that signal, 128 + its number: 130 for SIGINT, 143
//! for SIGTERM, 129 for SIGHUP. A second signal exits at once with that code.

use std::sync::atomic::{AtomicI32, Ordering};

use kardia::pipeline::CancelToken;

/// The first signal caught (0: none yet).
static CAUGHT: AtomicI32 = AtomicI32::new(0);

/// The signals that cancel a render.
#[cfg(unix)]
const STOP_SIGNALS: [i32; 3] = [
    signal_hook::consts::SIGINT,
    signal_hook::consts::SIGTERM,
    signal_hook::consts::SIGHUP,
];
#[cfg(not(unix))]
const STOP_SIGNALS: [i32; 2] = [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM];

/// Makes each of [`STOP_SIGNALS`] cancel `interrupt` (the first one) or exit at once (any
/// later one).
fn install(interrupt: &CancelToken) -> std::io::Result<()> {
    for signal in STOP_SIGNALS {
        let token = interrupt.clone();
        // SAFETY: the action only touches atomics (the token is an `Arc<AtomicBool>`, cloned
        // here, outside the handler) and `_exit`, all async-signal-safe; it allocates nothing.
        unsafe {
            signal_hook::low_level::register(signal, move || {
                if CAUGHT
                    .compare_exchange(0, signal, Ordering::SeqCst, Ordering::SeqCst)
                    .is_err()
                {
                    signal_hook::low_level::exit(128 + signal);
                }
                token.cancel();
            })?;
        }
    }
    Ok(())
}

fn main() {
    let interrupt = CancelToken::new();
    if let Err(e) = install(&interrupt) {
        eprintln!("kardia: warning: Ctrl-C and SIGTERM will not clean up: {e}");
    }
    let code = kardia::cli::main(&interrupt);
    // The library says "interrupted"; which signal did it is known only here.
    let caught = CAUGHT.load(Ordering::SeqCst);
    let code = if code == kardia::cli::INTERRUPTED && caught != 0 {
        128 + caught
    } else {
        code
    };
    std::process::exit(code);
}
