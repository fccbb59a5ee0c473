//! `iws-cf`: IWS for L_d plus Caustic Forecasting for L_c [BAJ08 §3.2] — unbiased.
//!
//! Preprocess (rank 0, once per run, never refreshed): trace forecast light paths with targeted
//! shooting toward the bounding sphere of the Dirac objects (or the scene's
//! `[forecast] target_box`), store a `CausticPoint` at every non-specular hit whose previous
//! vertex was Dirac, cluster them and build the cluster map and forecast maps
//! (`forecast::estimator::CausticForecast`). Render: at every non-specular vertex of the IWS
//! recursion, `Ĺ_c` samples directions from the photon-driven tables (dual table by default),
//! keeps a sample only if its first hit is Dirac, follows the chain and evaluates the full
//! estimator `L̂` at its end (spec §1, §4).
//!
//! CLI: `forecast render scenes/cornell-box.toml --method iws-cf --time 4m`.

use super::iws::{caustic_chain, CausticEstimator, Recurse};
use crate::accel::World;
use crate::bsdf::{self, ShadingPoint};
use crate::forecast::caustic_point::CausticPoint;
use crate::forecast::estimator::{
    new_cache_owner, CausticForecast, ForecastCounters, ForecastOptions, PreprocessStats,
};
use crate::math::{Rgb, Vec3};
use crate::sampling::rng::{stream, Rng};
use crate::scene::Material;
use crate::transport::particle::{self, Emission, MAX_VERTICES};
use std::time::Instant;

/// Default forecast photons to store when neither the CLI nor the scene sets it (the paper's
/// Cornell box count).
pub const DEFAULT_FORECAST_PHOTONS: u64 = 200_000;

/// Give up after this many light paths per requested forecaster (scenes without caustics).
const PATH_FACTOR: u64 = 100;

/// The targeted emission for forecasters: the bounding sphere of the target box.
pub fn targeted_emission(world: &World) -> Emission {
    let target = world.scene.forecast_target.or_else(|| world.scene.dirac_bounds());
    match target {
        Some((lo, hi)) => {
            let center = 0.5 * (lo + hi);
            let radius = (0.5 * (hi - lo).length()).max(1e-6);
            Emission::Targeted { center, radius }
        }
        None => Emission::Cosine,
    }
}

/// Traces forecast photons: returns the caustic points (flux normalised by paths launched),
/// the number of paths, and the tracing time.
pub fn trace_forecasters(world: &World, emission: Emission, target: u64, seed: u64) -> (Vec<CausticPoint>, u64, f64) {
    let t0 = Instant::now();
    let max_paths = target.saturating_mul(PATH_FACTOR).max(particle::BLOCK);
    let (verts, paths) = particle::collect_caustic_vertices(world, emission, target, max_paths, seed, stream::FORECAST);
    let inv = if paths > 0 { 1.0 / paths as f32 } else { 0.0 };
    let points =
        verts.iter().map(|v| CausticPoint::new(v.p, v.n, v.w_in, v.beta * inv)).filter(|c| c.is_finite()).collect();
    (points, paths, t0.elapsed().as_secs_f64())
}

/// The CF preprocess (spec §3).
pub fn build_forecast(world: &World, target: u64, opts: ForecastOptions, seed: u64) -> CausticForecast {
    let emission = targeted_emission(world);
    let (points, paths, tracing_s) = trace_forecasters(world, emission, target, seed);
    let stats = PreprocessStats {
        paths,
        tracing_s,
        yield_per_path: if paths > 0 { points.len() as f64 / paths as f64 } else { 0.0 },
        ..Default::default()
    };
    CausticForecast::build(points, opts, seed, stats)
}

/// `Ĺ_c` by Caustic Forecasting, plugged into the IWS recursion.
pub struct ForecastCaustics {
    /// The broadcast product.
    pub cf: CausticForecast,
    counters: ForecastCounters,
    cache_owner: u64,
}

impl ForecastCaustics {
    /// Wraps a product.
    pub fn new(cf: CausticForecast) -> Self {
        ForecastCaustics { cf, counters: ForecastCounters::default(), cache_owner: new_cache_owner() }
    }
}

impl CausticEstimator for ForecastCaustics {
    fn name(&self) -> &'static str {
        "caustic-forecasting"
    }

    fn estimate(
        &self,
        world: &World,
        x: &ShadingPoint,
        m: &Material,
        wo: Vec3,
        depth: u32,
        rng: &mut Rng,
        full: &dyn Recurse,
    ) -> Rgb {
        if depth + 1 >= MAX_VERTICES {
            return Rgb::ZERO;
        }
        // g(ωi) = f·|cos|·1[first hit Dirac]·(chain throughput)·L̂(chain end)
        let g = |wi: Vec3, rng: &mut Rng| -> Rgb {
            let f = bsdf::eval(m, x, wo, wi);
            if f == Rgb::ZERO {
                return Rgb::ZERO;
            }
            caustic_chain(world, x, wi, f * wi.dot(x.ns).abs(), depth, rng, full)
        };
        self.cf.estimate(x, m, wo, depth, rng, &self.counters, Some(self.cache_owner), g)
    }

    fn stats(&self) -> serde_json::Value {
        serde_json::json!({
            "caustics": "caustic forecasting (unbiased)",
            "preprocess": self.cf.stats,
            "options": self.cf.opts,
            "render": self.counters.json(),
        })
    }
}
