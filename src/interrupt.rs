//! Ctrl-C and SIGTERM during `forecast render`: the first signal ends the
//! render after the pass group in flight (about a second, `schedule::GROUP_SECS`), and the
//! outputs (image, JSON, the checkpoint if checkpoints are on) are written as at the end of a
//! time box, with `interrupted: true` in the JSON and exit status 130; a second signal exits at
//! once. The `ctrlc` crate lives behind this module.
//!
//! Invariants: the flag only ever goes from unset to set; under MPI the ranks agree on it once
//! per round (`distributed::agree_round`), so a signal to any rank stops every rank after the
//! same round and the finished passes stay one contiguous range.

use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::Arc;

/// Exit status of a render that was interrupted (128 + SIGINT, as shells report it).
pub const EXIT_INTERRUPTED: u8 = 130;

/// The signals received so far, shared with the handler thread; a clone sees the same count.
/// `Interrupt::default()` is one no signal reaches (library use, tests).
#[derive(Clone, Debug, Default)]
pub struct Interrupt(Arc<AtomicU32>);

impl Interrupt {
    /// Installs the process's SIGINT/SIGTERM handler (once per process: a second call is an
    /// error) and returns the flag it sets.
    pub fn install() -> Result<Interrupt, String> {
        let flag = Interrupt::default();
        let seen = flag.0.clone();
        ctrlc::set_handler(move || {
            if seen.fetch_add(1, Ordering::SeqCst) > 0 {
                std::process::exit(EXIT_INTERRUPTED.into());
            }
            eprintln!(
                "\ninterrupted: finishing the passes in flight, then writing what is done (again to quit at once)"
            );
        })
        .map_err(|e| format!("cannot install the Ctrl-C/SIGTERM handler: {e}"))?;
        Ok(flag)
    }

    /// True once a signal has arrived.
    pub fn is_set(&self) -> bool {
        self.0.load(Ordering::SeqCst) > 0
    }

    /// Sets the flag as a signal would (tests; an embedding program's own stop button).
    pub fn raise(&self) {
        self.0.fetch_add(1, Ordering::SeqCst);
    }
}
