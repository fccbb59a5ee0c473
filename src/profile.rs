//! Profiling outside the math: per-thread counters and phase timers.
//!
//! A [`Profile`] lives in each worker's `transport::context::Context`; integrators bracket a
//! phase with [`Profile::start`] / [`Profile::record`] and count events, the render loop sums
//! the per-tile profiles (`render::PassCounters::profile`) and the pipeline hands the run's total
//! to `Integrator::stats`. Nothing here is global or thread-local, and nothing feeds back into an
//! estimate: timings never change an image.
//!
//! The clock is sampled: reading it around every camera sample cost 9% of `pt` (a `perf` profile
//! of `ring`, issue #33: `__vdso_clock_gettime` 8.7%). So each phase times one call in
//! [`CLOCK_EVERY`] (the 1st, the 32nd, …, counted per phase and per worker) and counts it
//! `CLOCK_EVERY` times: the phase totals are unbiased estimates for any run of many calls, exact
//! up to the sampling error for short ones. `CLOCK_EVERY` is odd, so it shares no period with the
//! tile's 16-pixel rows.

use std::time::Instant;

/// A timed phase of the radiance estimate.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Phase {
    /// A whole camera ray's estimate (`Integrator::estimate`; the extra rays of emission
    /// splitting are [`Phase::EmissionSplit`]).
    Radiance,
    /// IWS point-light gathering (`VPL_b`).
    Gather,
    /// The caustic term `Ĺ_c` (nested recursion included).
    Caustics,
    /// The bias-compensation ray (BSDF sample and intersection; the recursion at its end is
    /// counted in its own phases).
    Compensation,
    /// CF direction-table lookup and build (cache included).
    CfTable,
    /// CF / BSDF caustic chains: the Dirac chain and the `L̂` at its end (nested, inclusive).
    CfChain,
    /// Photon-map density queries (`iws-pm`).
    PhotonQuery,
    /// The extra camera rays of `--emission-split` (their Dirac prefixes), outside [`Phase::Radiance`].
    EmissionSplit,
}

/// One call in this many of each phase reads the clock (see the module doc).
pub const CLOCK_EVERY: u32 = 31;

/// Phases in [`Phase`].
const PHASES: usize = 8;

/// Counters and phase times of one worker (or their sum).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct Profile {
    /// Calls of each phase so far, for the clock's sampling (not summed by [`Profile::add`]).
    #[serde(skip)]
    calls: [u32; PHASES],
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
    /// Nanoseconds in [`Phase::Compensation`].
    pub compensation_ns: u64,
    /// Nanoseconds in [`Phase::CfTable`].
    pub cf_table_ns: u64,
    /// Nanoseconds in [`Phase::CfChain`].
    pub cf_chain_ns: u64,
    /// Nanoseconds in [`Phase::PhotonQuery`].
    pub photon_query_ns: u64,
    /// Nanoseconds in [`Phase::EmissionSplit`].
    pub emission_split_ns: u64,
    /// Non-specular vertices at which point lights were gathered.
    pub gather_vertices: u64,
    /// Point-light shadow rays traced by the gather.
    pub gather_shadow_rays: u64,
    /// CF chains followed (directions that reached a Dirac surface).
    pub cf_chains: u64,
    /// Caustic Forecasting lookups (per thread, so no shared atomics on the hot path).
    pub cf: CfCounts,
}

/// Render-time counters of a CF estimator (`iws-cf`, `pt-cf`), summed over threads.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct CfCounts {
    /// Table lookups (`Ĺ_c` evaluations, guided-vertex queries).
    pub queries: u64,
    /// Lookups inside a kept cluster.
    pub inside: u64,
    /// Direction samples taken (splitting factor numerator).
    pub samples: u64,
    /// Nanoseconds gathering forecasters and building tables ("creating CDFs").
    pub cdf_ns: u64,
    /// Tables built.
    pub tables_built: u64,
    /// Table-cache hits.
    pub cache_hits: u64,
}

impl CfCounts {
    fn add(&mut self, o: &CfCounts) {
        self.queries += o.queries;
        self.inside += o.inside;
        self.samples += o.samples;
        self.cdf_ns += o.cdf_ns;
        self.tables_built += o.tables_built;
        self.cache_hits += o.cache_hits;
    }

    /// Fraction of lookups inside a kept cluster.
    pub fn fraction_inside(&self) -> f64 {
        self.inside as f64 / self.queries.max(1) as f64
    }

    /// Direction samples per lookup.
    pub fn samples_per_query(&self) -> f64 {
        self.samples as f64 / self.queries.max(1) as f64
    }

    /// Seconds creating CDFs (summed over threads).
    pub fn cdf_s(&self) -> f64 {
        self.cdf_ns as f64 * 1e-9
    }
}

/// The start of a timed phase: the clock's reading, or `None` for a call the sampling skips.
#[derive(Clone, Copy, Debug)]
pub struct Stopwatch(Option<Instant>);

impl Profile {
    /// Starts a call of `phase`: reads the clock on one call in [`CLOCK_EVERY`].
    #[inline]
    pub fn start(&mut self, phase: Phase) -> Stopwatch {
        let c = &mut self.calls[phase as usize];
        let timed = *c == 0;
        *c = if timed { CLOCK_EVERY - 1 } else { *c - 1 };
        Stopwatch(timed.then(Instant::now))
    }

    /// Ends a call of `phase` started by [`Profile::start`]: a timed call counts
    /// [`CLOCK_EVERY`] times its duration.
    #[inline]
    pub fn record(&mut self, phase: Phase, since: Stopwatch) {
        if let Some(t) = since.0 {
            *self.slot(phase) += t.elapsed().as_nanos() as u64 * CLOCK_EVERY as u64;
        }
    }

    /// Adds `ns` nanoseconds, timed exactly, to `phase` (a batch timed once, e.g. the
    /// wavefront `pt`'s tile).
    #[inline]
    pub fn add_exact(&mut self, phase: Phase, ns: u64) {
        *self.slot(phase) += ns;
    }

    fn slot(&mut self, phase: Phase) -> &mut u64 {
        match phase {
            Phase::Radiance => &mut self.radiance_ns,
            Phase::Gather => &mut self.gather_ns,
            Phase::Caustics => &mut self.caustics_ns,
            Phase::Compensation => &mut self.compensation_ns,
            Phase::CfTable => &mut self.cf_table_ns,
            Phase::CfChain => &mut self.cf_chain_ns,
            Phase::PhotonQuery => &mut self.photon_query_ns,
            Phase::EmissionSplit => &mut self.emission_split_ns,
        }
    }

    /// Adds another profile.
    pub fn add(&mut self, o: &Profile) {
        self.samples += o.samples;
        self.compensation_rays += o.compensation_rays;
        self.radiance_ns += o.radiance_ns;
        self.gather_ns += o.gather_ns;
        self.caustics_ns += o.caustics_ns;
        self.compensation_ns += o.compensation_ns;
        self.cf_table_ns += o.cf_table_ns;
        self.cf_chain_ns += o.cf_chain_ns;
        self.photon_query_ns += o.photon_query_ns;
        self.emission_split_ns += o.emission_split_ns;
        self.gather_vertices += o.gather_vertices;
        self.gather_shadow_rays += o.gather_shadow_rays;
        self.cf_chains += o.cf_chains;
        self.cf.add(&o.cf);
    }

    /// Seconds in `phase`.
    pub fn secs(&self, phase: Phase) -> f64 {
        let mut c = *self;
        *c.slot(phase) as f64 * 1e-9
    }

    /// The per-phase profile per camera sample, for the report and `forecast bench`.
    pub fn per_sample(&self) -> PhaseProfile {
        let n = self.samples.max(1) as f64;
        let us = |ns: u64| ns as f64 * 1e-3 / n;
        let exclusive = self.gather_ns + self.compensation_ns + self.cf_table_ns + self.photon_query_ns;
        PhaseProfile {
            samples: self.samples,
            total_us: us(self.radiance_ns),
            gather_us: us(self.gather_ns),
            compensation_ray_us: us(self.compensation_ns),
            cf_table_us: us(self.cf_table_ns),
            photon_query_us: us(self.photon_query_ns),
            emission_split_us: us(self.emission_split_ns),
            caustics_inclusive_us: us(self.caustics_ns),
            cf_chain_inclusive_us: us(self.cf_chain_ns),
            camera_and_rest_us: us(self.radiance_ns.saturating_sub(exclusive)),
            gather_vertices_per_sample: self.gather_vertices as f64 / n,
            shadow_rays_per_gather_vertex: self.gather_shadow_rays as f64 / self.gather_vertices.max(1) as f64,
            compensation_rays_per_sample: self.compensation_rays as f64 / n,
            cf_chains_per_sample: self.cf_chains as f64 / n,
        }
    }
}

/// CPU microseconds per camera sample in each phase (summed over threads, divided by samples).
/// `gather`, `compensation_ray`, `cf_table` and `photon_query` are exclusive leaf phases (at every
/// depth); `caustics_inclusive` and `cf_chain_inclusive` contain the nested `L̂` work (their own
/// gathers and tables too); `camera_and_rest` = total − the exclusive phases (camera rays, Dirac
/// chains, BSDF sampling, roulette, recursion overhead).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct PhaseProfile {
    /// Camera samples.
    pub samples: u64,
    /// Whole `Integrator::estimate` call.
    pub total_us: f64,
    /// Point-light gather (target evaluation, selection and shadow rays).
    pub gather_us: f64,
    /// Compensation rays (sample + intersect).
    pub compensation_ray_us: f64,
    /// CF table lookup and build.
    pub cf_table_us: f64,
    /// Photon-map queries.
    pub photon_query_us: f64,
    /// The extra camera rays of `--emission-split` (not in `total_us`).
    pub emission_split_us: f64,
    /// `Ĺ_c` including its nested `L̂`.
    pub caustics_inclusive_us: f64,
    /// CF / BSDF chains and their `L̂`.
    pub cf_chain_inclusive_us: f64,
    /// Total minus the exclusive phases.
    pub camera_and_rest_us: f64,
    /// Gather vertices per sample.
    pub gather_vertices_per_sample: f64,
    /// Shadow rays per gather vertex.
    pub shadow_rays_per_gather_vertex: f64,
    /// Compensation rays per sample.
    pub compensation_rays_per_sample: f64,
    /// CF chains per sample.
    pub cf_chains_per_sample: f64,
}
