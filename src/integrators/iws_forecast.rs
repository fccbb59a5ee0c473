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

use super::caustic_share::caustic_shares;
use super::caustics::{caustic_chain, CausticEstimator, Recurse, ShadingQuery};
use super::iws::Iws;
use super::{Context, Integrator, MethodArgs, MethodSpec};
use crate::profile::{CfCounts, Profile};
use crate::progress::{Hidden, Phases};
use crate::accel::World;
use crate::bsdf;
use crate::forecast::caustic_point::CausticPoint;
use crate::forecast::cluster::ClusteringMethod;
use crate::forecast::estimator::{
    CausticForecast, ForecastOptions, PhotonWeight, PreprocessStats, SplitRule, TableCache,
    TableKind,
};
use crate::math::{Rgb, Vec3};
use crate::sampling::rng::stream;
use crate::transport::particle::{self, Emission, MAX_VERTICES};
use clap::builder::{PossibleValuesParser, TypedValueParser};
use serde::ser::SerializeMap;
use std::time::Instant;

/// Default forecast photons to store when neither the CLI nor the scene sets it (the paper's
/// Cornell box count).
pub const DEFAULT_FORECAST_PHOTONS: u64 = 200_000;

/// `iws-cf` parameters (the CLI's names; [`CfArgs::options`] maps them onto the domain's
/// [`ForecastOptions`]). Serialized as `forecast_photons` and `forecast` (the options).
#[derive(clap::Args, Clone, Debug, PartialEq)]
pub struct CfArgs {
    /// iws-cf: forecast photons to store (default: the scene's `[forecast] photons`, else 200k).
    #[arg(long)]
    pub forecast_photons: Option<u64>,
    /// iws-cf: clustering algorithm.
    #[arg(long, default_value = "vq", value_parser = choice(&[("vq", ClusteringMethod::Vq), ("kmeans", ClusteringMethod::KMeans)]))]
    pub clustering: ClusteringMethod,
    /// iws-cf: codebook size k (clusters).
    #[arg(long, default_value_t = 64, value_parser = clap::value_parser!(u32).range(1..))]
    pub clusters: u32,
    /// iws-cf: clusters with rank above this are culled (cosine sampling only).
    #[arg(long, default_value_t = 6)]
    pub max_rank: u32,
    /// iws-cf: forecasters gathered per table (n).
    #[arg(long, default_value_t = 128, value_parser = clap::value_parser!(u32).range(1..))]
    pub forecasters: u32,
    /// iws-cf / pt-cf: direction tables: dual-spread (default: T2 follows the spread forecasters),
    /// dual (BAJ08), dual-defensive, single (ablation) or mixture (defensive BSDF mixture).
    #[arg(long, default_value = "dual-spread", value_parser = choice(&[
        ("dual", TableKind::Dual), ("dual-defensive", TableKind::DualDefensive), ("dual-spread", TableKind::DualSpread),
        ("single", TableKind::Single), ("mixture", TableKind::Mixture),
    ]))]
    pub table: TableKind,
    /// iws-cf: photon weight in the table: lum(Φ)·f·cos (paper) or lum(Φ)·f (flux).
    #[arg(long, default_value = "paper", value_parser = choice(&[("paper", PhotonWeight::Paper), ("flux", PhotonWeight::Flux)]))]
    pub photon_weight: PhotonWeight,
    /// iws-cf: splitting factor S0 at diffuse depth 0: the most samples per table (energy rule:
    /// S = clamp(ceil(S0·ρ_c/ρ_max), 1, S0); rank rule: S = max(1, S0 >> rank)); 1 at depth >= 1.
    #[arg(long, default_value_t = 16, value_parser = clap::value_parser!(u32).range(1..))]
    pub split: u32,
    /// iws-cf: splitting rule at depth 0: the cluster's energy density (default), the paper's
    /// rank rule, or the rank rule boosted where the caustic share is >= 1/2.
    #[arg(long, default_value = "energy", value_parser = choice(&[("energy", SplitRule::Energy), ("rank", SplitRule::Rank), ("share", SplitRule::Share)]))]
    pub split_rule: SplitRule,
    /// iws-cf: table-cache cell edge as a fraction of the search radius (0 = build per point).
    #[arg(long, default_value_t = 1.0, value_parser = parse_table_cache)]
    pub table_cache: f32,
    /// iws-cf: use the photon tables at diffuse depths below this (deeper: one BSDF sample).
    #[arg(long, default_value_t = 1)]
    pub table_depth: u32,
    /// iws-cf: photon tables only in kept clusters whose caustic share is at least this (0 = all;
    /// elsewhere one BSDF sample, as outside the kept clusters).
    #[arg(long, default_value_t = 0.0, value_parser = crate::forecast::share::parse_min_share)]
    pub table_min_share: f32,
    /// The run's time budget (set by the pipeline from `--time`, not a flag): without an explicit
    /// `--forecast-photons` the preprocess then costs about [`PREPROCESS_SHARE`] of it.
    #[arg(skip)]
    pub time_budget_s: Option<f64>,
}

/// Share of the `--time` budget the CF preprocess aims at (issue #11).
pub const PREPROCESS_SHARE: f64 = 0.05;
/// Stored photons of the pilot run that measures the preprocess cost per photon.
pub const PILOT_PHOTONS: u64 = 5_000;
/// Fewest photons the budget rule picks (the tables need some forecasters to be useful).
pub const MIN_BUDGET_PHOTONS: u64 = 10_000;

/// A clap parser for a domain enum from its (name, value) table (the enums stay free of clap).
pub(crate) fn choice<T: Clone + Send + Sync + 'static>(
    table: &'static [(&'static str, T)],
) -> impl TypedValueParser<Value = T> {
    PossibleValuesParser::new(table.iter().map(|(n, _)| *n))
        .map(move |s| table.iter().find(|(n, _)| *n == s).map_or_else(|| table[0].1.clone(), |(_, v)| v.clone()))
}

/// `--table-cache F`: a finite F ≥ 0 (NaN, negative and infinite cells are refused).
fn parse_table_cache(s: &str) -> Result<f32, String> {
    let f: f32 = s.trim().parse().map_err(|e| format!("`{s}` is not a number: {e}"))?;
    if f.is_finite() && f >= 0.0 {
        Ok(f)
    } else {
        Err(format!("the cell edge must be a finite number >= 0 (0 = a table per point), got {s}"))
    }
}

impl CfArgs {
    /// The domain options these arguments select.
    pub fn options(&self) -> ForecastOptions {
        ForecastOptions {
            clusters: self.clusters as usize,
            clustering: self.clustering,
            max_rank: self.max_rank,
            gather: self.forecasters as usize,
            table: self.table,
            photon_weight: self.photon_weight,
            s0: self.split,
            split_rule: self.split_rule,
            cache_cell: self.table_cache.max(0.0),
            table_depth: self.table_depth,
            table_min_share: self.table_min_share,
        }
    }

    /// The limits of `crate::param_limits` (the scene's `forecast.photons` has the same).
    pub fn validate(&self) -> Result<(), String> {
        let photons = self.forecast_photons.map_or(Ok(()), |n| {
            crate::param_limits::FORECAST_PHOTONS.check_flag("--forecast-photons", n)
        });
        photons.and_then(|()| crate::param_limits::SPLIT.check_flag("--split", self.split.into()))
    }

    /// Forecast photons to store: the CLI's, else the scene's, else [`DEFAULT_FORECAST_PHOTONS`].
    pub fn target_photons(&self, world: &World) -> u64 {
        self.forecast_photons.or(world.scene.forecast_photons).unwrap_or(DEFAULT_FORECAST_PHOTONS)
    }
}

impl serde::Serialize for CfArgs {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut m = s.serialize_map(Some(2))?;
        m.serialize_entry("forecast_photons", &self.forecast_photons)?;
        m.serialize_entry("forecast", &self.options())?;
        m.end()
    }
}

/// The `iws-cf` method: IWS with Caustic Forecasting as `Ĺ_c`.
pub struct IwsCf;

impl MethodSpec for IwsCf {
    type Product = CausticForecast;
    fn preprocess(world: &World, args: &MethodArgs, seed: u64, phases: &dyn Phases) -> Result<CausticForecast, String> {
        Ok(preprocess_forecast(world, args, seed, phases))
    }
    fn build(world: &World, args: &MethodArgs, cf: CausticForecast) -> Result<Box<dyn Integrator>, String> {
        Ok(Box::new(Iws::new(world, args, Box::new(ForecastCaustics::new(cf)))))
    }
}

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
/// the number of paths, and the tracing time. `stored(n)` follows the count (display only).
pub fn trace_forecasters(
    world: &World,
    emission: Emission,
    target: u64,
    seed: u64,
    stored: &dyn Fn(u64),
) -> (Vec<CausticPoint>, u64, f64) {
    let t0 = Instant::now();
    let (verts, paths) = particle::collect_caustic_points(world, emission, target, seed, stream::FORECAST, stored);
    let points = verts.iter().map(|v| CausticPoint::new(v.p, v.n, v.w_in, v.beta)).filter(|c| c.is_finite()).collect();
    (points, paths, t0.elapsed().as_secs_f64())
}

/// The CF preprocess of a run (used by every CF method): the photon count is `--forecast-photons`
/// as given; else, with a time budget `T`, `min(cap, 0.05·T / cost)` where `cost` is the seconds
/// per stored photon of a [`PILOT_PHOTONS`] pilot preprocess and `cap` the scene's (or default)
/// count; else the scene's count. Any count leaves the image unbiased (the tables are a pdf).
/// The rule and the pilot's cost go into `stats`. Phases: "pilot" (its own phases hidden), then
/// those of [`build_forecast`], then "caustic shares" (`caustic_share::caustic_shares`).
pub fn preprocess_forecast(world: &World, args: &MethodArgs, seed: u64, phases: &dyn Phases) -> CausticForecast {
    let cap = args.cf.target_photons(world);
    let (n, rule, cost) = match (args.cf.forecast_photons, args.cf.time_budget_s) {
        (Some(n), _) => (n, "cli", 0.0),
        (None, Some(t)) if t.is_finite() && t > 0.0 && cap > PILOT_PHOTONS => {
            let phase = phases.phase("pilot", None);
            let t0 = Instant::now();
            let pilot = build_forecast(world, PILOT_PHOTONS, args.cf.options(), seed ^ 0x0050_494c_4f54, &Hidden);
            let cost = t0.elapsed().as_secs_f64() / pilot.stats.stored.max(1) as f64;
            phase.finish();
            let want = (PREPROCESS_SHARE * t / cost.max(1e-12)).max(MIN_BUDGET_PHOTONS as f64);
            ((want as u64).min(cap), "budget", cost)
        }
        (None, _) if world.scene.forecast_photons.is_some() => (cap, "scene", 0.0),
        (None, _) => (cap, "default", 0.0),
    };
    let mut cf = build_forecast(world, n, args.cf.options(), seed, phases);
    let t0 = Instant::now();
    let phase = phases.phase("caustic shares", None);
    cf.shares = caustic_shares(world, &cf, args.pt.cap(), seed);
    phase.finish();
    cf.stats.shares_s = t0.elapsed().as_secs_f64();
    cf.stats.photons_requested = n;
    cf.stats.photon_rule = rule.to_string();
    cf.stats.pilot_s_per_photon = cost;
    cf
}

/// The CF preprocess (spec §3) for `target` stored photons. Phases: "tracing forecast photons"
/// (stored / requested), then those of [`CausticForecast::build`].
pub fn build_forecast(
    world: &World,
    target: u64,
    opts: ForecastOptions,
    seed: u64,
    phases: &dyn Phases,
) -> CausticForecast {
    let emission = targeted_emission(world);
    let tracing = phases.phase("tracing forecast photons", Some(target));
    let (points, paths, tracing_s) = trace_forecasters(world, emission, target, seed, &|n| tracing.set(n));
    tracing.finish();
    let stats = PreprocessStats {
        paths,
        tracing_s,
        yield_per_path: if paths > 0 { points.len() as f64 / paths as f64 } else { 0.0 },
        ..Default::default()
    };
    CausticForecast::build(points, opts, seed, stats, phases)
}

/// `Ĺ_c` by Caustic Forecasting, plugged into the IWS recursion; owns the product and the
/// table cache shared by all worker threads.
pub struct ForecastCaustics {
    /// The broadcast product.
    pub cf: CausticForecast,
    cache: TableCache,
}

impl ForecastCaustics {
    /// Wraps a product.
    pub fn new(cf: CausticForecast) -> Self {
        ForecastCaustics { cf, cache: TableCache::default() }
    }
}

impl CausticEstimator for ForecastCaustics {
    fn name(&self) -> &'static str {
        "caustic-forecasting"
    }

    fn estimate(&self, world: &World, q: &ShadingQuery, ctx: &mut Context, full: &dyn Recurse) -> Rgb {
        if q.depth + 1 >= MAX_VERTICES {
            return Rgb::ZERO;
        }
        // g(ωi)·w = f·|cos|·w·1[first hit Dirac]·(chain throughput)·L̂(chain end); the chain's
        // roulette sees the whole sample weight f·|cos|·w (on f·|cos| alone, q ≤ albedo/π would
        // kill ~85% of the chains at depth ≥ 1 and give the survivors ×7: fireflies)
        let g = |wi: Vec3, w: f32, ctx: &mut Context| -> Rgb {
            let f = bsdf::eval(q.m, q.x, q.wo, wi);
            if f == Rgb::ZERO {
                return Rgb::ZERO;
            }
            caustic_chain(world, q, wi, f * (wi.dot(q.x.ns).abs() * w), ctx, full)
        };
        self.cf.estimate(q, ctx, Some(&self.cache), g)
    }

    fn stats(&self, profile: &Profile) -> serde_json::Value {
        serde_json::json!({
            "caustics": "caustic forecasting (unbiased)",
            "preprocess": self.cf.stats,
            "cache_cells": self.cf.cells.json(),
            "options": self.cf.opts,
            "render": cf_render_json(&profile.cf),
        })
    }
}

/// JSON figures of the render-time CF counters: fraction inside clusters, mean splitting
/// factor, CDF seconds (summed over threads).
fn cf_render_json(c: &CfCounts) -> serde_json::Value {
    serde_json::json!({
        "lc_queries": c.queries,
        "fraction_inside_clusters": c.fraction_inside(),
        "mean_splitting_factor": c.samples_per_query(),
        "creating_cdfs_s": c.cdf_s(),
        "tables_built": c.tables_built,
        "table_cache_hits": c.cache_hits,
    })
}
