//! Progress of `kardia render` on stderr: a bar on a terminal; without one (a farm job's log),
//! a plain line every few seconds saying the frame, the percentage done and the time left;
//! nothing with `--quiet`.

use std::io::IsTerminal;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// Seconds between two plain progress lines when `--progress-every` is not given.
pub const DEFAULT_INTERVAL_SECONDS: f64 = 5.0;

/// Where progress goes: a bar, plain lines, or nowhere. Shared by the render's worker
/// threads (`inc` is called after each tile).
pub enum Progress {
    /// A terminal: indicatif's bar, redrawn in place.
    Bar(indicatif::ProgressBar),
    /// No terminal: a line now and then.
    Lines(Lines),
    /// `--quiet`.
    Hidden,
}

/// Plain progress lines, at most one per interval.
pub struct Lines {
    total: u64,
    done: AtomicU64,
    started: Instant,
    interval: Duration,
    /// When the last line was printed, and what is being rendered ("frame 3 (2 of 4)").
    state: Mutex<(Instant, String)>,
}

impl Progress {
    /// Progress over `total` pixels: a bar when stderr is a terminal, else plain lines every
    /// `interval_seconds` (≥ 0; 0 prints after every tile), nothing when `quiet`.
    pub fn new(quiet: bool, total: u64, interval_seconds: f64, bar_template: &str) -> Self {
        if quiet {
            return Progress::Hidden;
        }
        if std::io::stderr().is_terminal() {
            let bar = indicatif::ProgressBar::with_draw_target(
                Some(total),
                indicatif::ProgressDrawTarget::stderr(),
            );
            if let Ok(style) = indicatif::ProgressStyle::with_template(bar_template) {
                bar.set_style(style);
            }
            return Progress::Bar(bar);
        }
        let now = Instant::now();
        Progress::Lines(Lines {
            total: total.max(1),
            done: AtomicU64::new(0),
            started: now,
            interval: Duration::from_secs_f64(interval_seconds.max(0.0)),
            state: Mutex::new((now, String::from("rendering"))),
        })
    }

    /// Says what is being rendered now (a bar shows it beside the bar; lines start with it).
    pub fn set_message(&self, message: String) {
        match self {
            Progress::Bar(bar) => bar.set_message(message),
            Progress::Lines(lines) => {
                if let Ok(mut state) = lines.state.lock() {
                    state.1 = message;
                }
            }
            Progress::Hidden => {}
        }
    }

    /// Counts `pixels` more as done; a plain line is printed when the interval has passed.
    pub fn inc(&self, pixels: u64) {
        match self {
            Progress::Bar(bar) => bar.inc(pixels),
            Progress::Lines(lines) => lines.inc(pixels),
            Progress::Hidden => {}
        }
    }

    /// Removes the bar (plain lines stay as they are in the log).
    pub fn finish(&self) {
        if let Progress::Bar(bar) = self {
            bar.finish_and_clear();
        }
    }
}

impl Lines {
    /// The count is read and the line printed while the lock is held, so lines come in the
    /// order of their counts: two threads finishing tiles together never print 95 % after
    /// 100 %.
    fn inc(&self, pixels: u64) {
        self.inc_with(pixels, |line| eprintln!("{line}"));
    }

    /// As `inc`, handing the line (if one is due) to `print` while the lock is held.
    fn inc_with(&self, pixels: u64, mut print: impl FnMut(String)) {
        self.done.fetch_add(pixels, Ordering::Relaxed);
        let now = Instant::now();
        let Ok(mut state) = self.state.lock() else {
            return;
        };
        if now.duration_since(state.0) < self.interval {
            return;
        }
        state.0 = now;
        let done = self.done.load(Ordering::Relaxed);
        print(progress_line(
            &state.1,
            done,
            self.total,
            now - self.started,
        ));
    }
}

/// One plain progress line: `kardia: frame 3 (2 of 4): 37%, 12 s elapsed, eta 20 s`.
pub fn progress_line(what: &str, done: u64, total: u64, elapsed: Duration) -> String {
    let done = done.min(total);
    let fraction = done as f64 / total.max(1) as f64;
    let eta = if done == 0 {
        "unknown".to_string()
    } else {
        seconds(elapsed.as_secs_f64() * (1.0 - fraction) / fraction)
    };
    format!(
        "kardia: {what}: {:.0}%, {} elapsed, eta {eta}",
        100.0 * fraction,
        seconds(elapsed.as_secs_f64())
    )
}

/// "42 s", "3 min 05 s", "2 h 07 min".
fn seconds(s: f64) -> String {
    let s = s.round() as u64;
    if s < 60 {
        format!("{s} s")
    } else if s < 3600 {
        format!("{} min {:02} s", s / 60, s % 60)
    } else {
        format!("{} h {:02} min", s / 3600, (s % 3600) / 60)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_say_what_how_far_and_how_long() {
        let line = progress_line("frame 3 (2 of 4)", 250, 1000, Duration::from_secs(10));
        assert_eq!(
            line,
            "kardia: frame 3 (2 of 4): 25%, 10 s elapsed, eta 30 s"
        );
        let start = progress_line("rendering", 0, 1000, Duration::from_secs(1));
        assert!(start.ends_with("eta unknown"), "{start}");
        let long = progress_line("rendering", 1, 1000, Duration::from_secs(10));
        assert!(long.ends_with("eta 2 h 46 min"), "{long}");
        assert_eq!(seconds(185.0), "3 min 05 s");
    }

    #[test]
    fn lines_from_many_threads_come_in_the_order_of_their_counts() {
        let now = Instant::now();
        let lines = Lines {
            total: 64_000,
            done: AtomicU64::new(0),
            started: now,
            interval: Duration::ZERO,
            state: Mutex::new((now, String::from("rendering"))),
        };
        let printed = Mutex::new(Vec::new());
        std::thread::scope(|scope| {
            for _ in 0..4 {
                scope.spawn(|| {
                    for _ in 0..1000 {
                        lines.inc_with(16, |line| printed.lock().unwrap().push(line));
                    }
                });
            }
        });
        let percents: Vec<f64> = printed
            .into_inner()
            .unwrap()
            .iter()
            .map(|l| {
                let p = l.split(": ").nth(2).unwrap().split('%').next().unwrap();
                p.parse().unwrap()
            })
            .collect();
        assert_eq!(percents.len(), 4000);
        assert!(percents.windows(2).all(|w| w[0] <= w[1]), "out of order");
        assert_eq!(percents.last(), Some(&100.0));
    }
}
