//! `iws-cf`: IWS for L_d plus Caustic Forecasting for L_c [BAJ08 §3.2] — unbiased.
//!
//! Preprocess (rank 0, once per run, never refreshed; [`build_forecast`], which `pt-cf` reuses):
//! trace forecast light paths with targeted shooting toward the spheres around the Dirac objects
//! (one cone each, `transport::target`; or the circumsphere of the scene's `[forecast]
//! target_box`), store a `CausticPoint` at every non-specular hit whose previous vertex was
//! Dirac, cluster them and build the cluster map and forecast maps
//! (`cf::estimator::CausticForecast`). Render: at every non-specular vertex of the IWS
//! recursion, `Ĺ_c` samples directions from the photon-driven dual tables (`dual-spread` by
//! default), keeps a sample only if its first hit is Dirac, follows the chain and evaluates the
//! full estimator `L̂` at its end (spec §1, §4; the derivation: `docs/methods/iws-cf.md`).
//!
//! Options: the CF group [`CfArgs`] (shared with `pt-cf`) and `--variant baj08` ([`IwsCfArgs`]:
//! the paper's dual table, rank rule and emitter VPLs together, for its ablations).
//!
//! CLI: `forecast render scenes/cornell-box.toml --method iws-cf --time 4m`.

pub mod share;
use super::iws::caustics::{caustic_chain, CausticEstimator, Recurse, ShadingQuery};
use super::iws::{DirectLight, Iws};
use super::{Context, Integrator, MethodArgs, MethodError, MethodSpec};
use crate::accel::World;
use crate::bsdf::{self, Mode};
use crate::cf::caustic_point::CausticPoint;
use crate::cf::estimator::{CausticForecast, ForecastOptions, PreprocessStats, SplitRule, TableCache, TableKind};
use crate::cf::subset_grid::SubsetGrid;
use crate::math::{Rgb, Vec3};
use crate::profile::{CfCounts, Profile};
use crate::progress::{Muted, Phases};
use crate::sampling::rng::stream;
use crate::transport::particle::{self, Emission, MAX_VERTICES};
use crate::transport::target::Targets;
use share::caustic_shares_until;
use std::time::Instant;

/// Default forecast photons to store when neither the CLI nor the scene sets it (the paper's
/// Cornell box count).
pub const DEFAULT_FORECAST_PHOTONS: u64 = 200_000;

/// The Caustic Forecasting preprocess and table options, one group shared by `iws-cf` and
/// `pt-cf` (the CLI's names; [`MethodArgs::forecast_options`] maps them, with `iws-cf`'s
/// `--variant`, onto the domain's [`ForecastOptions`]).
#[derive(clap::Args, Clone, Debug, PartialEq, serde::Serialize)]
pub struct CfArgs {
    /// Forecast photons to store (default: the scene's [forecast] photons, else 200000; with
    /// --time, as many as about 5% of the budget allows).
    #[arg(long, value_name = "N")]
    pub forecast_photons: Option<u64>,
    /// Clusters the forecast photons are grouped into (the codebook size).
    #[arg(long, value_name = "K", default_value_t = 64, value_parser = clap::value_parser!(u32).range(1..))]
    pub clusters: u32,
    /// Clusters ranked above this are culled (their points take BSDF samples).
    #[arg(long, value_name = "R", default_value_t = 6)]
    pub max_rank: u32,
    /// Forecasters gathered per table.
    #[arg(long, value_name = "N", default_value_t = 128, value_parser = clap::value_parser!(u32).range(1..))]
    pub forecasters: u32,
    /// The most table samples (iws-cf) or continuations (pt-cf) at diffuse depth 0, fewer where
    /// the cluster reflects less; 1 deeper.
    // S0 of the energy rule S = clamp(ceil(S0·ρ_c/ρ_max), 1, S0).
    #[arg(long, value_name = "S0", default_value_t = 16, value_parser = clap::value_parser!(u32).range(1..))]
    pub split: u32,
    /// The tables are used at diffuse depths below this (deeper: BSDF sampling; 0 = never, so
    /// pt-cf renders as pt).
    #[arg(long, value_name = "D", default_value_t = 1)]
    pub table_depth: u32,
    /// Table-cache cell edge as a fraction of the cluster's radius (0 = a table per point).
    #[arg(long, value_name = "F", default_value_t = 1.0, value_parser = parse_table_cache)]
    pub table_cache: f32,
    /// The run's time budget (set by the pipeline from `--time`, not a flag): without an explicit
    /// `--forecast-photons` the preprocess then costs about [`PREPROCESS_SHARE`] of it.
    #[arg(skip)]
    #[serde(skip)]
    pub time_budget_s: Option<f64>,
    /// When the integrator's build from the product must end (set by the pipeline from its
    /// share of `--time`, not a flag): the lookup grid stops there and asks the cluster map
    /// everywhere (`SubsetGrid::build_until`, exact: the same image, slower lookups).
    #[arg(skip)]
    #[serde(skip)]
    pub build_deadline: Option<std::time::Instant>,
}

/// `iws-cf`'s own options.
#[derive(clap::Args, Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct IwsCfArgs {
    /// The paper's own choices together, for its ablations: baj08 = the dual table without
    /// spread, the rank splitting rule S = max(1, S0 >> rank) and the light sources as clamped
    /// point lights (--direct vpl, so it excludes --direct).
    #[arg(long, value_enum, conflicts_with = "direct")]
    pub variant: Option<Variant>,
}

/// A named set of `iws-cf` choices (`--variant`).
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
// The values are described in `--variant`'s help: a value's doc comment would be its help text,
// which turns `render --help` into its long format.
#[allow(missing_docs)]
pub enum Variant {
    // [BAJ08] as published: `TableKind::Dual`, `SplitRule::Rank`, `DirectLight::Vpl`.
    Baj08,
}

/// Share of the `--time` budget the CF preprocess aims at (issue #11).
pub const PREPROCESS_SHARE: f64 = 0.05;
/// Stored photons of the pilot run that measures the preprocess cost per photon.
pub const PILOT_PHOTONS: u64 = 5_000;
/// The fewest photons of any budget (and the least pilot's).
pub const LEAST_BUDGET_PHOTONS: u64 = PILOT_PHOTONS / 10;
/// The pilot's stored photons per second of budget (between [`LEAST_BUDGET_PHOTONS`] and
/// [`PILOT_PHOTONS`]).
pub const PILOT_PHOTONS_PER_S: f64 = 100.0;
/// Fewest photons the budget rule picks (the tables need some forecasters to be useful), as long
/// as they cost at most 4× [`PREPROCESS_SHARE`] of the budget (a budget of a few seconds gets
/// fewer: every phase stays inside `--time`, `pipeline::budget`).
pub const MIN_BUDGET_PHOTONS: u64 = 10_000;

/// `--table-cache F`: a finite F ≥ 0 (NaN, negative and infinite cells are refused).
fn parse_table_cache(s: &str) -> Result<f32, String> {
    let f: f32 = s.trim().parse().map_err(|e| format!("`{s}` is not a number: {e}"))?;
    if f.is_finite() && f >= 0.0 {
        Ok(f)
    } else {
        Err(format!("the cell edge must be a finite number >= 0 (0 = a table per point), got {s}"))
    }
}

impl MethodArgs {
    /// The domain options of the CF preprocess and tables: the shared group's, with `iws-cf`'s
    /// `--variant`'s table and split rule.
    pub fn forecast_options(&self) -> ForecastOptions {
        let c = &self.cf;
        let baj08 = self.iwscf.variant == Some(Variant::Baj08);
        ForecastOptions {
            clusters: c.clusters as usize,
            max_rank: c.max_rank,
            gather: c.forecasters as usize,
            table: if baj08 { TableKind::Dual } else { TableKind::DualSpread },
            s0: c.split,
            split_rule: if baj08 { SplitRule::Rank } else { SplitRule::Energy },
            cache_cell: c.table_cache.max(0.0),
            table_depth: c.table_depth,
        }
    }
}

impl MethodArgs {
    /// These arguments with `--variant`'s choices outside the CF group applied (`baj08`: the
    /// emitters' light as clamped point lights, `--direct vpl`): what `iws-cf` renders with and
    /// the report records.
    pub fn with_variant(&self) -> MethodArgs {
        let mut a = self.clone();
        if a.iwscf.variant == Some(Variant::Baj08) {
            a.iws.direct = DirectLight::Vpl;
        }
        a
    }
}

impl CfArgs {
    /// The limits of `crate::param_limits` (the scene's `forecast.photons` has the same).
    pub fn validate(&self) -> Result<(), MethodError> {
        use crate::param_limits::{FORECAST_PHOTONS, SPLIT};
        if let Some(n) = self.forecast_photons {
            MethodError::check_limit(&FORECAST_PHOTONS, "--forecast-photons", n)?;
        }
        MethodError::check_limit(&SPLIT, "--split", self.split.into())
    }

    /// Forecast photons to store: the CLI's, else the scene's, else [`DEFAULT_FORECAST_PHOTONS`].
    pub fn target_photons(&self, world: &World) -> u64 {
        self.forecast_photons.or(world.scene.forecast_photons).unwrap_or(DEFAULT_FORECAST_PHOTONS)
    }
}

/// The `iws-cf` method: IWS with Caustic Forecasting as `Ĺ_c`.
pub struct IwsCf;

impl MethodSpec for IwsCf {
    type Product = CausticForecast;
    fn preprocess(
        world: &World,
        args: &MethodArgs,
        seed: u64,
        phases: &dyn Phases,
    ) -> Result<CausticForecast, MethodError> {
        Ok(preprocess_forecast(world, args, seed, phases))
    }
    fn build(world: &World, args: &MethodArgs, cf: CausticForecast) -> Result<Box<dyn Integrator>, MethodError> {
        crate::integrators::iws::check_direct(world, &args.with_variant())?;
        let caustics = ForecastCaustics::new_until(cf, args.cf.build_deadline);
        Ok(Box::new(Iws::new(world, &args.with_variant(), Box::new(caustics))))
    }
}

/// The targeted emission for forecasters [BAJ08 §3.2]: the cones of the circumsphere of the
/// scene's `forecast.target_box` if it has one, else of the spheres around the Dirac objects
/// (`Scene::dirac_spheres`, `transport::target`).
pub fn targeted_emission(world: &World) -> Emission {
    let s = &world.scene;
    let spheres = match s.forecast_target {
        Some((lo, hi)) => vec![(0.5 * (lo + hi), (0.5 * (hi - lo).length()).max(1e-6))],
        None => s.dirac_spheres(),
    };
    Targets::new(&spheres).map_or(Emission::Cosine, Emission::Targeted)
}

/// Traces forecast photons: returns the caustic points (flux normalised by paths launched),
/// the number of paths, and the tracing time. `stored(n)` follows the count (display only).
pub fn trace_forecasters(
    world: &World,
    emission: Emission,
    target: u64,
    seed: u64,
    stored: &dyn Fn(u64) -> bool,
) -> (Vec<CausticPoint>, u64, f64) {
    let t0 = Instant::now();
    let (verts, paths) = particle::collect_caustic_points(world, emission, target, seed, stream::FORECAST, stored);
    let points = verts.iter().map(|v| CausticPoint::new(v.p, v.n, v.w_in, v.beta)).filter(|c| c.is_finite()).collect();
    (points, paths, t0.elapsed().as_secs_f64())
}

/// The CF preprocess of a run (used by every CF method): the photon count is `--forecast-photons`
/// as given; else, with a time budget `T`, `min(cap, 0.05·T / cost)` where `cost` is the seconds
/// per stored photon of a [`PILOT_PHOTONS`] pilot preprocess (with the lookup grid the
/// integrator builds from the product) and `cap` the scene's (or default)
/// count; else the scene's count. Any count leaves the image unbiased (the tables are a pdf).
/// The rule and the pilot's cost go into `stats`. Phases: "pilot" (its own phases hidden), then
/// those of [`build_forecast`], then "caustic shares" (`share::caustic_shares`).
pub fn preprocess_forecast(world: &World, args: &MethodArgs, seed: u64, phases: &dyn Phases) -> CausticForecast {
    let cap = args.cf.target_photons(world);
    let (n, rule, cost) = match (args.cf.forecast_photons, args.cf.time_budget_s) {
        (Some(n), _) => (n, "cli", 0.0),
        (None, Some(t)) if t.is_finite() && t > 0.0 && cap > PILOT_PHOTONS => {
            let phase = phases.phase("pilot", None);
            let t0 = Instant::now();
            // a short budget gets a smaller pilot (its clustering and grid cost with the photons)
            let m = ((PILOT_PHOTONS_PER_S * t) as u64).clamp(LEAST_BUDGET_PHOTONS, PILOT_PHOTONS);
            let pilot = build_forecast(world, m, args.forecast_options(), seed ^ 0x0050_494c_4f54, &Muted(phases));
            // the integrators' lookup grid over the kept clusters, built from the product after
            // the broadcast, grows with the photons too: its cost is part of theirs
            let _grid = pilot.kept_grid_until(&|| phases.stop());
            let cost = t0.elapsed().as_secs_f64() / pilot.stats.stored.max(1) as f64;
            phase.finish();
            // the floor only while it costs at most 4 shares (a short budget gets fewer, but never
            // fewer than the least pilot)
            let want = PREPROCESS_SHARE * t / cost.max(1e-12);
            let want = want.max((MIN_BUDGET_PHOTONS as f64).min(4.0 * want)).max(LEAST_BUDGET_PHOTONS as f64);
            ((want as u64).min(cap), "budget", cost)
        }
        (None, _) if world.scene.forecast_photons.is_some() => (cap, "scene", 0.0),
        (None, _) => (cap, "default", 0.0),
    };
    let mut cf = build_forecast(world, n, args.forecast_options(), seed, phases);
    let t0 = Instant::now();
    let phase = phases.phase("caustic shares", None);
    cf.shares = caustic_shares_until(world, &cf, args.settings.cap(), seed, &|| phases.stop());
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
    let (points, paths, tracing_s) = trace_forecasters(world, emission, target, seed, &|n| {
        tracing.set(n);
        !phases.stop()
    });
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
    /// The cluster-map lookup's grid over every kept cluster.
    grid: SubsetGrid,
}

impl ForecastCaustics {
    /// Wraps a product.
    pub fn new(cf: CausticForecast) -> Self {
        Self::new_until(cf, None)
    }

    /// [`ForecastCaustics::new`], its grid built until `deadline` (then exact but coarse).
    pub fn new_until(cf: CausticForecast, deadline: Option<std::time::Instant>) -> Self {
        let grid = cf.kept_grid_until(&|| deadline.is_some_and(|d| Instant::now() >= d));
        ForecastCaustics { grid, cf, cache: TableCache::default() }
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
            let f = bsdf::eval(q.m, q.x, q.wo, wi, Mode::Radiance);
            if f == Rgb::ZERO {
                return Rgb::ZERO;
            }
            caustic_chain(world, q, wi, f * (wi.dot(q.x.ns).abs() * w), ctx, full)
        };
        self.cf.estimate(q, ctx, (Some(&self.cache), Some(&self.grid)), g)
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
