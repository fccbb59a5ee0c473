//! The integrators behind one small trait, and the method registry: the [`methods!`] table
//! below is the only list of methods and the only place a method's name is written.
//!
//! A method is one file plus one line in that table. Its file owns
//! - its parameters: a `#[derive(clap::Args, serde::Serialize)]` group, flattened into the
//!   command line (`--method` and every flag) and into the JSON report's `options`;
//! - its one-off preprocess product ([`MethodSpec::Product`], `()` when there is none), built on
//!   rank 0, reporting its phases to a [`Phases`] passed down by the pipeline (display only);
//!   [`Method::preprocess`] encodes it with bitcode and [`Method::build`] decodes the
//!   broadcast bytes, in one generic place;
//! - its construction ([`MethodSpec::build`]).
//!
//! An integrator is a pure estimator of radiance along a camera ray. It never sees threads,
//! tiles, MPI or files: per-worker state (random stream, scratch, counters) arrives in the
//! explicit [`Context`]; `begin_pass` refreshes per-pass data (IWS point lights) from random
//! streams keyed by (seed, pass).

pub mod auto;
pub mod caustic_share;
pub mod caustics;
pub mod path_class;
pub mod vpl;

pub use auto::MethodChoice;
pub use caustics::{BsdfCaustics, CausticEstimator, NoCaustics, Recurse, ShadingQuery};

use crate::accel::World;
use crate::math::{Rgb, Vec3};
use crate::profile::Profile;
use crate::progress::{Hidden, Phases};
pub use crate::transport::context::Context;

/// One estimate along a camera ray, split at the ray's first non-Dirac vertex so that the
/// pixel sampler can average the first part over several cheap rays (`render`,
/// `--emission-split`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CameraEstimate {
    /// `E`: the emission reached along the ray's Dirac prefix (the first hit, or the end of a
    /// mirror/glass chain from it), throughput included.
    pub prefix_le: Rgb,
    /// `L − E`: everything found at and beyond the first non-Dirac vertex.
    pub rest: Rgb,
}

impl CameraEstimate {
    /// The whole estimate `L = E + (L − E)`.
    #[inline]
    pub fn total(self) -> Rgb {
        self.prefix_le + self.rest
    }
}

/// A radiance estimator.
pub trait Integrator: Send + Sync {
    /// Per-pass refresh; randomness must come from (seed, pass) only.
    fn begin_pass(&mut self, _world: &World, _seed: u64, _pass: u64) {}
    /// One estimate of the radiance arriving at `origin` from direction `dir` (unit), drawing
    /// from `ctx.rng`, split into its Dirac-prefix emission and the rest. Contract (emission
    /// splitting is unbiased only under it): `prefix_le` estimates the same `E` as
    /// `transport::dirac::prefix_emission` with [`Integrator::prefix_cap`]: weight 1, the BSDF's
    /// own Dirac sampling, `pt`'s roulette, one-sided emitters.
    fn estimate(&self, world: &World, origin: Vec3, dir: Vec3, ctx: &mut Context) -> CameraEstimate;
    /// The vertex cap of the camera's Dirac prefix in [`Integrator::estimate`] (the extra rays of
    /// emission splitting use the same).
    fn prefix_cap(&self) -> u32;
    /// The whole estimate ([`Integrator::estimate`] summed).
    fn radiance(&self, world: &World, origin: Vec3, dir: Vec3, ctx: &mut Context) -> Rgb {
        self.estimate(world, origin, dir, ctx).total()
    }
    /// Method-specific statistics for the JSON report; `profile` is the run's summed
    /// per-worker profile.
    fn stats(&self, _profile: &Profile) -> serde_json::Value {
        serde_json::json!({})
    }
}

/// One method: its preprocess and its construction (its parameters are its field of
/// [`MethodArgs`]; a method reads the groups it shares, e.g. the IWS ones).
pub trait MethodSpec {
    /// The one-off preprocess product, broadcast from rank 0 (`()` when there is none).
    type Product: bitcode::Encode + bitcode::DecodeOwned;
    /// Runs the preprocess (rank 0 only), reporting its phases to `phases` (display only).
    fn preprocess(world: &World, args: &MethodArgs, seed: u64, phases: &dyn Phases) -> Result<Self::Product, String>;
    /// Builds the integrator from the (broadcast) product.
    fn build(world: &World, args: &MethodArgs, product: Self::Product) -> Result<Box<dyn Integrator>, String>;
}

/// Parameters of a method that has none of its own.
#[derive(clap::Args, Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct NoArgs {}

/// The registry: `Variant = "name", field: ArgsType => module::SpecType;` per method. It
/// declares the module, the [`Method`] enum (the CLI/JSON name), the [`MethodArgs`] group and
/// the dispatch of [`Method::preprocess`] and [`Method::build`].
macro_rules! methods {
    ($( $(#[$doc:meta])* $variant:ident = $name:literal, $field:ident: $args:ty => $module:ident :: $spec:ident; )*) => {
        $( pub mod $module; )*

        /// The rendering methods (`--method`).
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, clap::ValueEnum, serde::Serialize)]
        pub enum Method {
            $( $(#[$doc])* #[value(name = $name)] #[serde(rename = $name)] $variant, )*
        }

        /// Every method's parameters, one flattened group per method (CLI flags and JSON keys).
        #[derive(clap::Args, Clone, Debug, serde::Serialize)]
        pub struct MethodArgs {
            $(
                #[allow(missing_docs)]
                #[command(flatten)]
                #[serde(flatten)]
                pub $field: $args,
            )*
        }

        impl Method {
            /// Every method, in registry order.
            pub const ALL: &'static [Method] = &[$(Method::$variant),*];

            /// The command-line name.
            pub fn name(self) -> &'static str {
                match self {
                    $( Method::$variant => $name, )*
                }
            }

            /// The one-off preprocess (rank 0), encoded for the broadcast, reporting nothing.
            pub fn preprocess(self, world: &World, args: &MethodArgs, seed: u64) -> Result<Vec<u8>, String> {
                self.preprocess_reporting(world, args, seed, &Hidden)
            }

            /// [`Method::preprocess`] reporting its phases (tracing, clustering, maps, …) to
            /// `phases`; the product is the same whatever `phases` is.
            pub fn preprocess_reporting(
                self,
                world: &World,
                args: &MethodArgs,
                seed: u64,
                phases: &dyn Phases,
            ) -> Result<Vec<u8>, String> {
                match self {
                    $( Method::$variant => encode_product::<$module::$spec>(world, args, seed, phases), )*
                }
            }

            /// Builds the integrator from the broadcast product.
            pub fn build(self, world: &World, args: &MethodArgs, product: &[u8]) -> Result<Box<dyn Integrator>, String> {
                args.check_for(self)?;
                match self {
                    $( Method::$variant => build_from::<$module::$spec>(self, world, args, product), )*
                }
            }
        }
    };
}

methods! {
    /// Path tracing with NEE and MIS: the unbiased reference.
    Pt = "pt", pt: path::PtArgs => path::PathTracer;
    /// Instant radiosity with bias compensation (Le + L_d); L_c left out by design.
    Iws = "iws", iws: iws::IwsArgs => iws::Iws;
    /// IWS with a caustic photon map for L_c (biased baseline).
    IwsPm = "iws-pm", pm: photon_map::PmArgs => photon_map::IwsPm;
    /// IWS with Caustic Forecasting for L_c (BAJ08): unbiased.
    IwsCf = "iws-cf", cf: iws_forecast::CfArgs => iws_forecast::IwsCf;
    /// Path tracing whose continuation is drawn from a defensive mixture of the BSDF and the CF tables: unbiased.
    PtCf = "pt-cf", ptcf: pt_cf::PtCfArgs => pt_cf::PtCf;
}

impl Method {
    /// Parses a method name (scene files, `--methods`).
    pub fn from_name(s: &str) -> Option<Method> {
        <Method as clap::ValueEnum>::from_str(s, true).ok()
    }
}

impl MethodArgs {
    /// Refuses what `method` does not implement: `--path-filter` is the path tracers' alone.
    pub fn check_for(&self, method: Method) -> Result<(), String> {
        if !matches!(method, Method::Pt | Method::PtCf) && self.pt.path_filter.is_some() {
            return Err(format!(
                "--path-filter is a diagnostic of `pt` and `pt-cf` only; `{}` does not support it",
                method.name()
            ));
        }
        Ok(())
    }

    /// Every group's own `validate` (each method file owns its limits), before any work.
    pub fn validate(&self) -> Result<(), String> {
        self.pt.validate()?;
        self.iws.validate()?;
        self.pm.validate()?;
        self.cf.validate()
    }
}

impl Default for MethodArgs {
    /// The command-line defaults (one source: the `#[arg]` attributes).
    fn default() -> Self {
        #[derive(clap::Parser)]
        struct Defaults {
            #[command(flatten)]
            args: MethodArgs,
        }
        <Defaults as clap::Parser>::parse_from(["forecast"]).args
    }
}

fn encode_product<S: MethodSpec>(
    world: &World,
    args: &MethodArgs,
    seed: u64,
    phases: &dyn Phases,
) -> Result<Vec<u8>, String> {
    Ok(bitcode::encode(&S::preprocess(world, args, seed, phases)?))
}

fn build_from<S: MethodSpec>(
    method: Method,
    world: &World,
    args: &MethodArgs,
    product: &[u8],
) -> Result<Box<dyn Integrator>, String> {
    let p: S::Product = bitcode::decode(product).map_err(|e| {
        format!("{}: cannot decode the broadcast preprocess product ({} bytes): {e}", method.name(), product.len())
    })?;
    S::build(world, args, p)
}
