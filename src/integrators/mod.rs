//! The integrators behind one small trait, and the only registry (`Method` + `build`).
//!
//! An integrator is a pure estimator of radiance along a camera ray. It never sees threads,
//! tiles, MPI or files. `begin_pass` refreshes per-pass data (IWS point lights) from random
//! streams keyed by (seed, pass); the one-off caustic preprocess arrives already built (see
//! `preprocess`), so that rank 0 can build it and broadcast it.

mod path;

pub use path::{PathTracer, RR_DEPTH};

use crate::accel::World;
use crate::math::{Rgb, Vec3};
use crate::sampling::rng::Rng;

/// A radiance estimator.
pub trait Integrator: Send + Sync {
    /// Short method name (as on the command line).
    fn name(&self) -> &'static str;
    /// Per-pass refresh; randomness must come from (seed, pass) only.
    fn begin_pass(&mut self, _world: &World, _seed: u64, _pass: u64) {}
    /// One estimate of the radiance arriving at `origin` from direction `dir` (unit).
    fn radiance(&self, world: &World, origin: Vec3, dir: Vec3, rng: &mut Rng) -> Rgb;
    /// Method-specific statistics for the JSON report.
    fn stats(&self) -> serde_json::Value {
        serde_json::json!({})
    }
}

/// The rendering methods (`--method`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// Path tracing with NEE and MIS: the unbiased reference.
    Pt,
}

impl Method {
    /// Parses a scene-file method name.
    pub fn from_name(s: &str) -> Option<Method> {
        <Method as clap::ValueEnum>::from_str(s, true).ok()
    }
    /// The command-line name.
    pub fn name(&self) -> &'static str {
        match self {
            Method::Pt => "pt",
        }
    }
}

/// Options shared by all methods (each method reads the ones it needs).
#[derive(Clone, Debug, serde::Serialize)]
pub struct MethodOptions {
    /// Safety cap on path vertices (0: the scene's `render.max_depth`).
    pub max_depth: u32,
}

impl Default for MethodOptions {
    fn default() -> Self {
        MethodOptions { max_depth: 0 }
    }
}

/// The one-off caustic preprocess, run on rank 0 only; its product is serialized so that
/// it can be broadcast (empty for methods without one).
pub fn preprocess(method: Method, _world: &World, _opts: &MethodOptions, _seed: u64) -> Result<Vec<u8>, String> {
    match method {
        Method::Pt => Ok(Vec::new()),
    }
}

/// Builds the integrator for `method` from the (broadcast) preprocess product.
pub fn build(method: Method, _world: &World, opts: &MethodOptions, _product: &[u8]) -> Result<Box<dyn Integrator>, String> {
    Ok(match method {
        Method::Pt => Box::new(PathTracer { max_depth: opts.max_depth }),
    })
}
