//! Long work run from Python: the work runs on a thread of its own while the calling thread
//! waits without the GIL, taking it back every [`POLL`] to check for signals (Ctrl-C, a
//! notebook's stop button) and to report progress. On a signal the work's cancel token is
//! cancelled, the work is awaited (a render stops within a tile) and the signal's exception
//! (`KeyboardInterrupt`) is raised.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Mutex;
use std::time::Duration;

use kardia::pipeline::{CancelToken, Renderer};
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;

/// How often the waiting thread takes the GIL to check for signals and report progress.
pub(crate) const POLL: Duration = Duration::from_millis(50);

/// What the work shares with the waiting thread: the cancel token and a progress count.
#[derive(Default)]
pub(crate) struct Watch {
    /// Cancelled on a signal (or a failing progress callback).
    pub cancel: CancelToken,
    /// Units of work done so far (pixels, for a render), updated by the work.
    pub done: AtomicU64,
}

/// Runs `work` on a thread of its own and waits for it with the GIL released, checking for
/// signals every [`POLL`]: a signal cancels `watch.cancel`, waits for the work to return and
/// raises the signal's exception. `progress(done, total)`, when given, is called (with the
/// GIL) whenever `watch.done` changed, and once at the end; an exception it raises cancels the
/// work too. A panic in the work is a `RuntimeError`, never a crash.
pub(crate) fn run_interruptible<T: Send>(
    py: Python<'_>,
    watch: &Watch,
    total: u64,
    progress: Option<&Bound<'_, PyAny>>,
    work: impl FnOnce() -> T + Send,
) -> PyResult<T> {
    let finished = AtomicBool::new(false);
    let waiting = std::thread::current();
    std::thread::scope(|scope| {
        let handle = scope.spawn(|| {
            let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(work));
            finished.store(true, Ordering::Release);
            waiting.unpark();
            result
        });
        let mut reported = u64::MAX;
        let stop = loop {
            py.detach(|| {
                if !finished.load(Ordering::Acquire) {
                    std::thread::park_timeout(POLL);
                }
            });
            let done = watch.done.load(Ordering::Relaxed);
            if let Some(callback) = progress {
                if done != reported {
                    reported = done;
                    if let Err(e) = callback.call1((done.min(total), total)) {
                        break Some(e);
                    }
                }
            }
            if let Err(e) = py.check_signals() {
                break Some(e);
            }
            if finished.load(Ordering::Acquire) {
                break None;
            }
        };
        if stop.is_some() {
            watch.cancel.cancel();
        }
        let joined = py.detach(|| handle.join());
        if let Some(e) = stop {
            return Err(e);
        }
        match joined {
            Ok(Ok(value)) => Ok(value),
            Ok(Err(panic)) | Err(panic) => Err(PyRuntimeError::new_err(format!(
                "kardia failed unexpectedly (a bug, please report it): {}",
                panic_text(&panic)
            ))),
        }
    })
}

/// The message of a panic's payload.
fn panic_text(panic: &Box<dyn std::any::Any + Send>) -> String {
    if let Some(s) = panic.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = panic.downcast_ref::<String>() {
        s.clone()
    } else {
        "a panic".into()
    }
}

/// Renderers not in use, with their thread counts (0: one thread per core). A render takes
/// one of its thread count or starts one, and gives it back after; so renders from several
/// Python threads at once each have their own threads, and a sequence of renders reuses them.
static IDLE_RENDERERS: Mutex<Vec<(usize, Renderer)>> = Mutex::new(Vec::new());

/// At most this many idle renderers are kept.
const MAX_IDLE: usize = 4;

/// A renderer of `threads` threads (0: one per core), idle or new.
pub(crate) fn take_renderer(threads: usize) -> PyResult<Renderer> {
    let mut idle = IDLE_RENDERERS.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(i) = idle.iter().position(|(t, _)| *t == threads) {
        return Ok(idle.swap_remove(i).1);
    }
    drop(idle);
    Renderer::new(threads).map_err(crate::errors::pool_error)
}

/// Keeps `renderer` (of `threads` threads) for the next render.
pub(crate) fn give_back(threads: usize, renderer: Renderer) {
    let mut idle = IDLE_RENDERERS.lock().unwrap_or_else(|e| e.into_inner());
    if idle.len() < MAX_IDLE {
        idle.push((threads, renderer));
    }
}
