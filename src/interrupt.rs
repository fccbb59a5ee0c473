//! Ctrl-C and SIGTERM during `forecast render`: the first signal cuts the pass group in flight
//! (within a tile or a chunk of light paths; the cut passes are discarded whole,
//! `render::trace_passes`), and the outputs (image, JSON, the checkpoint if checkpoints are on) are written as at the end of a
//! time box, with `interrupted: true` and `complete: false` in the JSON and exit status 130; a
//! second signal exits at once. While nothing is finished yet (loading, the BVH, the probe, the
//! preprocess, the pilot, the first round of passes: [`Interrupt::nothing_to_save`]) a signal
//! exits at once with status 130 and writes nothing, since there is nothing to save. Phases
//! that run against a deadline poll a [`Stop`] (the signal or the deadline, whichever comes
//! first). The `ctrlc` crate lives behind this module.
//!
//! Invariants: the flag only ever goes from unset to set; under MPI the ranks agree on it once
//! per round (`distributed::agree_round`), so a signal to any rank stops every rank after the
//! same round and the finished passes stay one contiguous range.

use std::sync::atomic::{AtomicBool, AtomicU32, Ordering};
use std::sync::Arc;
use std::time::Instant;

/// Exit status of a render that was interrupted (128 + SIGINT, as shells report it).
pub const EXIT_INTERRUPTED: u8 = 130;

/// The signals received so far, shared with the handler thread; a clone sees the same count.
/// `Interrupt::default()` is one no signal reaches (library use, tests).
#[derive(Clone, Debug, Default)]
pub struct Interrupt(Arc<AtomicU32>, Arc<AtomicBool>);

impl Interrupt {
    /// Installs the process's SIGINT/SIGTERM handler (once per process: a second call is an
    /// error) and returns the flag it sets.
    pub fn install() -> Result<Interrupt, String> {
        let flag = Interrupt::default();
        let (seen, nothing) = (flag.0.clone(), flag.1.clone());
        ctrlc::set_handler(move || {
            if seen.fetch_add(1, Ordering::SeqCst) > 0 {
                std::process::exit(EXIT_INTERRUPTED.into());
            }
            if nothing.load(Ordering::SeqCst) {
                eprintln!("\ninterrupted before the first pass was finished: nothing was written");
                std::process::exit(EXIT_INTERRUPTED.into());
            }
            eprintln!(
                "\ninterrupted: dropping the passes in flight, then writing the passes done (again to quit at once)"
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

    /// While `true`, the process's handler ([`Interrupt::install`]) exits at once at a signal:
    /// the render has finished nothing it could save (set by a one-process render until its
    /// first round of passes is done; never under MPI, whose ranks must leave together).
    pub fn nothing_to_save(&self, yes: bool) {
        self.1.store(yes, Ordering::SeqCst);
    }
}

/// When a phase must stop: a signal, or its deadline (`None`: none). Polled by the phases that
/// can end early with what they have (the probe, the photon tracing, the pilots).
#[derive(Clone, Debug, Default)]
pub struct Stop {
    interrupt: Interrupt,
    at: Option<Instant>,
}

impl Stop {
    /// Never stops (library use, tests, renders without a budget and no signal handler).
    pub fn never() -> Stop {
        Stop::default()
    }

    /// Stops at a signal to `interrupt` or at `at`.
    pub fn new(interrupt: &Interrupt, at: Option<Instant>) -> Stop {
        Stop { interrupt: interrupt.clone(), at }
    }

    /// The same signal with another deadline.
    pub fn until(&self, at: Option<Instant>) -> Stop {
        Stop { interrupt: self.interrupt.clone(), at }
    }

    /// The deadline, if any.
    pub fn deadline(&self) -> Option<Instant> {
        self.at
    }

    /// True once the signal has come or the deadline has passed.
    pub fn is_due(&self) -> bool {
        self.interrupt.is_set() || self.at.is_some_and(|a| Instant::now() >= a)
    }

    /// True once a signal has come.
    pub fn signalled(&self) -> bool {
        self.interrupt.is_set()
    }
}
