//! Progress of long work on stderr: a bar on a terminal, and where stderr is not one (a log,
//! a pipe, a batch job) a plain line at most every few seconds, so no command runs silently
//! for minutes. `IRAD_PROGRESS_SECONDS` sets the plain lines' interval (default 10; 0 prints
//! at every step).

use indicatif::{ProgressBar, ProgressStyle};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// A bar of `len` steps for `what` ("render", "compare"), with a detail line that long
/// steps update (a radiosity solve's residual).
#[derive(Clone)]
pub struct Progress {
    bar: ProgressBar,
    what: String,
    /// Set where the bar is hidden: the plain lines' state.
    plain: Option<Arc<Mutex<Plain>>>,
}

struct Plain {
    start: Instant,
    last: Option<Instant>,
    every: Duration,
    detail: String,
}

/// The plain lines' interval: `IRAD_PROGRESS_SECONDS`, else 10 s.
fn interval() -> Duration {
    let secs = std::env::var("IRAD_PROGRESS_SECONDS")
        .ok()
        .and_then(|s| s.trim().parse::<f64>().ok())
        .filter(|s| s.is_finite() && *s >= 0.0)
        .unwrap_or(10.0);
    Duration::from_secs_f64(secs.min(1e6))
}

impl Progress {
    pub fn new(len: u64, what: &str) -> Progress {
        let bar = ProgressBar::new(len);
        bar.set_style(
            ProgressStyle::with_template(
                "{prefix:>12} [{elapsed_precise}] {wide_bar} {pos}/{len} (eta {eta}) {msg}",
            )
            .expect("static template"),
        );
        bar.set_prefix(what.to_string());
        let plain = bar.is_hidden().then(|| {
            Arc::new(Mutex::new(Plain {
                start: Instant::now(),
                last: None,
                every: interval(),
                detail: String::new(),
            }))
        });
        Progress {
            bar,
            what: what.to_string(),
            plain,
        }
    }

    /// `n` more steps done.
    pub fn inc(&self, n: u64) {
        self.bar.inc(n);
        self.plain_line(None);
    }

    /// What the current step is doing (empty: nothing to add).
    pub fn set_detail(&self, detail: impl Into<String>) {
        let detail = detail.into();
        self.bar.set_message(detail.clone());
        self.plain_line(Some(detail));
    }

    pub fn finish_and_clear(&self) {
        self.bar.finish_and_clear();
    }

    /// Prints a plain line when the bar is hidden and the interval has passed.
    fn plain_line(&self, detail: Option<String>) {
        let Some(plain) = &self.plain else { return };
        let Ok(mut p) = plain.lock() else { return };
        if let Some(d) = detail {
            p.detail = d;
        }
        let now = Instant::now();
        let due = p.last.map_or(now - p.start, |l| now - l) >= p.every;
        if !due {
            return;
        }
        p.last = Some(now);
        let (pos, len) = (self.bar.position(), self.bar.length().unwrap_or(0));
        let pct = (100 * pos).checked_div(len).unwrap_or(0);
        let mut line = format!(
            "{}: {pos}/{len} ({pct}%) after {:.0} s",
            self.what,
            (now - p.start).as_secs_f64()
        );
        if !p.detail.is_empty() {
            line.push_str(", ");
            line.push_str(&p.detail);
        }
        eprintln!("{line}");
    }
}
