//! SIGINT and SIGTERM, for the commands that write a sequence of frames (`irad render`,
//! `irad reference`): the first signal
//! sets a flag that the frame loop reads between frames (the frame in flight is finished and
//! written, then the run writes what a finished run writes, marked interrupted, and exits
//! with status 130); a second signal exits at once, leaving the files already in place.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, OnceLock};

/// The exit status of a run stopped by a signal (128 + SIGINT, as shells report it).
pub const EXIT_STATUS: i32 = 130;

static FLAG: OnceLock<Arc<AtomicBool>> = OnceLock::new();

/// Routes SIGINT and SIGTERM to the flag (once per process; later calls do nothing).
pub fn install() -> std::io::Result<()> {
    if FLAG.get().is_some() {
        return Ok(());
    }
    let flag = Arc::new(AtomicBool::new(false));
    #[cfg(unix)]
    for sig in [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM] {
        // Registered first, so that it sees the flag as the earlier signal left it: set, the
        // process exits at once.
        signal_hook::flag::register_conditional_shutdown(sig, EXIT_STATUS, flag.clone())?;
        signal_hook::flag::register(sig, flag.clone())?;
    }
    let _ = FLAG.set(flag);
    Ok(())
}

/// Whether a signal asked the run to stop.
pub fn requested() -> bool {
    FLAG.get().is_some_and(|f| f.load(Ordering::SeqCst))
}

/// The error a run stopped by a signal ends with, once it has written its files.
#[derive(Debug, thiserror::Error)]
#[error("interrupted: stopped after {done} of {planned} frames; {what}")]
pub struct Interrupted {
    pub done: u32,
    pub planned: u32,
    /// What the run wrote before stopping.
    pub what: String,
}
