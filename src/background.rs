//! Work nobody is waiting for, kept out of the way of work someone is: lowering the
//! operating system's scheduling priority of the calling thread.
//!
//! The explorer runs a saved image, a page's refinement and a mesh beside the first frames of
//! a view someone is dragging. Its own scheduler makes those frames go first among its render
//! threads ([`crate::pipeline::Priority`]), but the browser, the input events and the
//! network that carry a drag to the server run outside it, on the same cores: threads at the
//! lowest priority let them (and anything else on the machine) run first, and take the
//! cores whenever they are idle.

/// The niceness given to background threads: the lowest priority of the normal scheduling
/// classes (Linux weight 15, against 1024 for niceness 0, so such a thread gets about 1.5 %
/// of a core that a normal thread also wants, and all of an idle one).
pub const BACKGROUND_NICENESS: i32 = 19;

/// Lowers the calling thread's priority to [`BACKGROUND_NICENESS`] (it stays so for the rest
/// of the thread's life: raising it back needs privileges). On Linux only (niceness there is
/// per thread); elsewhere nothing is done. Returns whether the thread now runs at that
/// niceness.
pub fn lower_this_thread() -> bool {
    #[cfg(target_os = "linux")]
    {
        // SAFETY: `gettid` and `setpriority` read and change only the calling thread's
        // scheduling attributes; no memory is passed.
        let done = unsafe {
            let tid = libc::gettid();
            libc::setpriority(libc::PRIO_PROCESS, tid as libc::id_t, BACKGROUND_NICENESS)
        };
        done == 0
    }
    #[cfg(not(target_os = "linux"))]
    {
        false
    }
}

/// The calling thread's niceness (Linux; `None` elsewhere or when it cannot be read).
pub fn this_thread_niceness() -> Option<i32> {
    #[cfg(target_os = "linux")]
    {
        // SAFETY: as in `lower_this_thread`; `getpriority` may return −1 legitimately, so
        // errno is cleared first and checked after.
        unsafe {
            *libc::__errno_location() = 0;
            let tid = libc::gettid();
            let nice = libc::getpriority(libc::PRIO_PROCESS, tid as libc::id_t);
            (*libc::__errno_location() == 0).then_some(nice)
        }
    }
    #[cfg(not(target_os = "linux"))]
    {
        None
    }
}

/// Runs `work` on a new thread of [`BACKGROUND_NICENESS`] and returns its result (the
/// calling thread waits; a panic of `work` is passed on). For a blocking task of a server
/// that would otherwise run at full priority on one of its shared threads, whose priority
/// cannot be raised back afterwards.
pub fn run_in_background<T: Send>(work: impl FnOnce() -> T + Send) -> T {
    std::thread::scope(|scope| {
        let thread = std::thread::Builder::new()
            .name("kardia-background".into())
            .spawn_scoped(scope, || {
                lower_this_thread();
                work()
            })
            .expect("a thread can be started");
        match thread.join() {
            Ok(value) => value,
            Err(panic) => std::panic::resume_unwind(panic),
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    #[cfg(target_os = "linux")]
    fn a_background_thread_runs_at_the_lowest_priority_and_others_do_not() {
        let before = this_thread_niceness().expect("readable on Linux");
        let inside = run_in_background(this_thread_niceness);
        assert_eq!(inside, Some(BACKGROUND_NICENESS));
        // Only that thread was lowered, not the caller (nor the process).
        assert_eq!(this_thread_niceness(), Some(before));
        let plain = std::thread::spawn(this_thread_niceness).join().unwrap();
        assert_eq!(plain, Some(before));
    }

    #[test]
    fn background_work_returns_its_value_and_passes_a_panic_on() {
        assert_eq!(run_in_background(|| 6 * 7), 42);
        let caught = std::panic::catch_unwind(|| run_in_background(|| panic!("inner")));
        assert!(caught.is_err());
    }
}
