//! A progress line on stderr for work that takes more than a second: nothing for shorter work,
//! then `label [=====>    ] 45%  1.2 s, about 1.5 s left`, redrawn in place at most ten times a
//! second on a terminal, or a line at each quarter when stderr is redirected. Thread-safe:
//! workers call `add` from anywhere.

use std::io::{IsTerminal, Write};
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

/// Nothing is shown for work shorter than this.
const QUIET: Duration = Duration::from_secs(1);
/// Redraws at most this often.
const REDRAW: Duration = Duration::from_millis(100);

pub struct Progress {
    label: String,
    total: usize,
    done: AtomicUsize,
    start: Instant,
    /// When the line was last drawn, and the last quarter reported (redirected output); `None`
    /// until something was shown.
    shown: Mutex<Option<(Instant, usize)>>,
    terminal: bool,
}

impl Progress {
    pub fn new(label: &str, total: usize) -> Self {
        Progress {
            label: label.to_string(),
            total: total.max(1),
            done: AtomicUsize::new(0),
            start: Instant::now(),
            shown: Mutex::new(None),
            terminal: std::io::stderr().is_terminal(),
        }
    }

    /// Records `n` more units done, and redraws if it is time.
    pub fn add(&self, n: usize) {
        let done = self.done.fetch_add(n, Ordering::Relaxed) + n;
        let elapsed = self.start.elapsed();
        if elapsed < QUIET {
            return;
        }
        // Whoever holds the lock draws; the others just count.
        let Ok(mut shown) = self.shown.try_lock() else {
            return;
        };
        let quarter = 4 * done / self.total;
        let due = match *shown {
            None => true,
            Some((at, q)) if self.terminal => at.elapsed() >= REDRAW || q != quarter,
            // The last quarter is the line `finish` prints.
            Some((_, q)) => q != quarter && quarter < 4,
        };
        if due {
            self.draw(done, elapsed, false);
            *shown = Some((Instant::now(), quarter));
        }
    }

    /// Ends the line (when one was shown) and returns the elapsed time.
    pub fn finish(&self) -> Duration {
        let elapsed = self.start.elapsed();
        if let Ok(shown) = self.shown.lock()
            && shown.is_some()
        {
            self.draw(self.done.load(Ordering::Relaxed), elapsed, true);
        }
        elapsed
    }

    fn draw(&self, done: usize, elapsed: Duration, last: bool) {
        let frac = (done as f64 / self.total as f64).min(1.0);
        let width = 30;
        let filled = (frac * width as f64) as usize;
        let bar: String = (0..width)
            .map(|k| match k.cmp(&filled) {
                std::cmp::Ordering::Less => '=',
                std::cmp::Ordering::Equal => '>',
                std::cmp::Ordering::Greater => ' ',
            })
            .collect();
        let secs = elapsed.as_secs_f64();
        let left = if frac > 0.0 && !last {
            format!(", about {:.1} s left", secs * (1.0 - frac) / frac)
        } else {
            String::new()
        };
        let line = format!(
            "{} [{bar}] {:3.0}%  {secs:.1} s{left}",
            self.label,
            100.0 * frac
        );
        let mut err = std::io::stderr().lock();
        if self.terminal {
            let _ = write!(err, "\r{line}\x1b[K");
            if last {
                let _ = writeln!(err);
            }
        } else {
            let _ = writeln!(err, "{line}");
        }
        let _ = err.flush();
    }
}
