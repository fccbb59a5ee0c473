//! Profiling outside the math: per-thread counters and phase timers.
//!
//! A [`Profile`] lives in each worker's `transport::context::Context`; integrators bracket a
//! phase with [`Stopwatch::start`] / [`Profile::record`] and count events, the render loop sums
//! the per-tile profiles (`render::PassCounters::profile`) and the pipeline hands the run's total
//! to `Integrator::stats`. Nothing here is global or thread-local, and nothing feeds back into an
//! estimate: timings never change an image.

use std::time::Instant;

/// A timed phase of the radiance estimate.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Phase {
    /// A whole camera sample (`Integrator::radiance`).
    Radiance,
    /// IWS point-light gathering (`VPL_b`).
    Gather,
    /// The caustic term `Ĺ_c` (nested recursion included).
    Caustics,
}

/// Counters and phase times of one worker (or their sum).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct Profile {
    /// Camera samples estimated.
    pub samples: u64,
    /// IWS bias-compensation rays traced.
    pub compensation_rays: u64,
    /// Nanoseconds in [`Phase::Radiance`].
    pub radiance_ns: u64,
    /// Nanoseconds in [`Phase::Gather`].
    pub gather_ns: u64,
    /// Nanoseconds in [`Phase::Caustics`].
    pub caustics_ns: u64,
}

/// The start of a timed phase.
#[derive(Clone, Copy, Debug)]
pub struct Stopwatch(Instant);

impl Stopwatch {
    /// Starts timing.
    #[inline]
    pub fn start() -> Stopwatch {
        Stopwatch(Instant::now())
    }
}

impl Profile {
    /// Adds the time since `since` to `phase`.
    #[inline]
    pub fn record(&mut self, phase: Phase, since: Stopwatch) {
        let ns = since.0.elapsed().as_nanos() as u64;
        match phase {
            Phase::Radiance => self.radiance_ns += ns,
            Phase::Gather => self.gather_ns += ns,
            Phase::Caustics => self.caustics_ns += ns,
        }
    }

    /// Adds another profile.
    pub fn add(&mut self, o: &Profile) {
        self.samples += o.samples;
        self.compensation_rays += o.compensation_rays;
        self.radiance_ns += o.radiance_ns;
        self.gather_ns += o.gather_ns;
        self.caustics_ns += o.caustics_ns;
    }

    /// Seconds in `phase`.
    pub fn secs(&self, phase: Phase) -> f64 {
        let ns = match phase {
            Phase::Radiance => self.radiance_ns,
            Phase::Gather => self.gather_ns,
            Phase::Caustics => self.caustics_ns,
        };
        ns as f64 * 1e-9
    }
}
