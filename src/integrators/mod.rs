//! The integrators behind one small trait, and the only registry (`Method` + `build`).
//!
//! An integrator is a pure estimator of radiance along a camera ray. It never sees threads,
//! tiles, MPI or files. `begin_pass` refreshes per-pass data (IWS point lights) from random
//! streams keyed by (seed, pass); the one-off caustic preprocess arrives already built (see
//! `preprocess`), so that rank 0 can build it and broadcast it.

pub mod iws;
pub mod iws_forecast;
mod path;
pub mod photon_map;

pub use iws::{BsdfCaustics, CausticEstimator, Iws, IwsParams, NoCaustics};
pub use iws_forecast::{build_forecast, ForecastCaustics, DEFAULT_FORECAST_PHOTONS};
pub use path::{PathTracer, RR_DEPTH};
pub use photon_map::PhotonMap;

use crate::forecast::estimator::{CausticForecast, ForecastOptions};

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
    /// Instant radiosity with bias compensation (Le + L_d); L_c left out by design.
    Iws,
    /// IWS with a caustic photon map for L_c (biased baseline).
    IwsPm,
    /// IWS with Caustic Forecasting for L_c (BAJ08): unbiased.
    IwsCf,
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
            Method::Iws => "iws",
            Method::IwsPm => "iws-pm",
            Method::IwsCf => "iws-cf",
        }
    }
}

/// Options shared by all methods (each method reads the ones it needs).
#[derive(Clone, Debug, serde::Serialize)]
pub struct MethodOptions {
    /// Safety cap on path vertices (0: the scene's `render.max_depth`).
    pub max_depth: u32,
    /// IWS clamp bound `b` (None: spec §2 default `0.25·π·N/A_D`).
    pub bound: Option<f32>,
    /// IWS light paths per pass `N` (default 32: tuned by timing, see the README).
    pub vpl_paths: u32,
    /// VPLs evaluated (uniform subset, unbiased) at diffuse depth ≥ 1; 0 = all (default 16, spec §2).
    pub vpl_subset: u32,
    /// Caustic photons to store for `iws-pm` (default 200k, the paper's Cornell count).
    pub photons: u64,
    /// Photons per photon-map estimate `k` (default 100).
    pub gather: u32,
    /// Photon-map gather radius cap (None: 2% of the scene diagonal).
    pub max_radius: Option<f32>,
    /// Forecast photons to store (None: the scene's `[forecast] photons`, else 200k).
    pub forecast_photons: Option<u64>,
    /// Caustic Forecasting parameters.
    pub forecast: ForecastOptions,
}

impl Default for MethodOptions {
    fn default() -> Self {
        MethodOptions {
            max_depth: 0,
            bound: None,
            vpl_paths: 32,
            vpl_subset: 16,
            photons: 200_000,
            gather: 100,
            max_radius: None,
            forecast_photons: None,
            forecast: ForecastOptions::default(),
        }
    }
}

impl MethodOptions {
    /// The IWS parameters these options select.
    pub fn iws_params(&self) -> IwsParams {
        IwsParams {
            vpl_paths: self.vpl_paths,
            bound: self.bound,
            vpl_subset: self.vpl_subset,
            max_depth: self.max_depth,
        }
    }
}

/// The one-off caustic preprocess, run on rank 0 only; its product is serialized so that
/// it can be broadcast (empty for methods without one).
pub fn preprocess(method: Method, world: &World, opts: &MethodOptions, seed: u64) -> Result<Vec<u8>, String> {
    match method {
        Method::Pt | Method::Iws => Ok(Vec::new()),
        Method::IwsCf => {
            let target = opts.forecast_photons.or(world.scene.forecast_photons).unwrap_or(DEFAULT_FORECAST_PHOTONS);
            Ok(build_forecast(world, target, opts.forecast.clone(), seed).to_bytes())
        }
        Method::IwsPm => {
            let pm = PhotonMap::build(world, opts.photons, opts.gather, opts.max_radius, seed);
            Ok(bitcode::encode(&pm))
        }
    }
}

/// Builds the integrator for `method` from the (broadcast) preprocess product.
pub fn build(
    method: Method,
    world: &World,
    opts: &MethodOptions,
    product: &[u8],
) -> Result<Box<dyn Integrator>, String> {
    Ok(match method {
        Method::Pt => Box::new(PathTracer { max_depth: opts.max_depth }),
        Method::Iws => Box::new(Iws::new("iws", world, opts.iws_params(), Box::new(NoCaustics))),
        Method::IwsPm => {
            let pm: PhotonMap = bitcode::decode(product).map_err(|e| {
                format!("iws-pm: cannot decode the broadcast photon map ({} bytes): {e}", product.len())
            })?;
            pm.validate()?;
            Box::new(Iws::new("iws-pm", world, opts.iws_params(), Box::new(pm)))
        }
        Method::IwsCf => {
            let cf = CausticForecast::from_bytes(product)?;
            Box::new(Iws::new("iws-cf", world, opts.iws_params(), Box::new(ForecastCaustics::new(cf))))
        }
    })
}
