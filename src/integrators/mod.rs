//! The integrators behind one small trait, and the method registry: the [`methods!`] table
//! below is the only list of methods and the only place a method's name is written.
//!
//! A method is one file plus one line in that table. Its file owns
//! - its options: a `#[derive(clap::Args, serde::Serialize)]` group, flattened into the command
//!   line; its registry line names the groups it takes (its own, and shared ones such as the
//!   IWS or the Caustic Forecasting group). A flag of another method's group is refused
//!   ([`MethodArgs::foreign_flag`]: `--clusters belongs to iws-cf/pt-cf, not pt`), and the JSON
//!   report's `options` hold only the method's groups ([`MethodOptions`]). `--max-depth` and
//!   `--emission-split` are render settings, not a method's (`settings`);
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
mod error;
pub mod settings;

// The methods, one folder each (a new one also gets its line in `methods!` below).
pub mod iws;
pub mod iws_cf;
pub mod iws_pm;
pub mod pt;
pub mod pt_cf;

pub use auto::MethodChoice;
pub use error::MethodError;
pub use iws::caustics::{BsdfCaustics, CausticEstimator, NoCaustics, Recurse, ShadingQuery};

use crate::accel::World;
use crate::math::{Rgb, Vec3};
use crate::profile::{Phase, Profile};
use crate::progress::{Hidden, Phases};
use crate::scene::Camera;
pub use crate::transport::context::Context;
pub use settings::RenderSettings;

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
    /// True when no pass depends on state that `begin_pass` sets, so that several passes may be
    /// traced in one batch (`render::render_passes`). False by default.
    fn independent_passes(&self) -> bool {
        false
    }
    /// One estimate of the radiance arriving at `origin` from direction `dir` (unit), drawing
    /// from `ctx.rng`, split into its Dirac-prefix emission and the rest. Contract (emission
    /// splitting is unbiased only under it): `prefix_le` estimates the same `E` as
    /// `transport::dirac::prefix_emission` with [`Integrator::prefix_cap`]: weight 1, the BSDF's
    /// own Dirac sampling, `pt`'s roulette, one-sided emitters.
    fn estimate(&self, world: &World, origin: Vec3, dir: Vec3, ctx: &mut Context) -> CameraEstimate;
    /// [`Integrator::estimate`] along each ray of a batch (a tile's camera rays), ray `i`
    /// drawing from `rngs[i]`: `out[i]` is bit for bit what `estimate` returns with `ctx.rng =
    /// rngs[i]`. The default is that loop; `pt` traces the batch as a wavefront
    /// (`pt::wavefront`).
    fn estimate_batch(
        &self,
        world: &World,
        rays: &[crate::accel::Ray],
        rngs: &mut [crate::sampling::rng::Rng],
        ctx: &mut Context,
        out: &mut Vec<CameraEstimate>,
    ) {
        estimate_each(self, world, rays, rngs, ctx, out);
    }
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
    /// The method's light tracer ([`LightTracer`]); `None` (the default): it traces no light paths.
    fn light_tracer(&self) -> Option<&dyn LightTracer> {
        None
    }
    /// [`Integrator::light_tracer`], mutable (to set its path count).
    fn light_tracer_mut(&mut self) -> Option<&mut dyn LightTracer> {
        None
    }
}

/// Light tracing, a capability a method may offer (as Mitsuba's `AdjointIntegrator`): paths from
/// the lights splatted to the camera, added to the camera estimates of the same pass
/// (`pt-cf`'s light side, `integrators::pt_cf::light`).
pub trait LightTracer: Send + Sync {
    /// The pass's light-traced splats: a dense row-major image of `camera`'s size added to every
    /// pixel's camera sample of pass `pass`, a pure function of (seed, pass) and the scene.
    fn light_splats(&self, world: &World, camera: &Camera, seed: u64, pass: u64) -> LightSplats {
        self.light_splats_until(world, camera, seed, pass, &crate::interrupt::Stop::never())
            .expect("light paths without a stop are all traced")
    }
    /// [`LightTracer::light_splats`] while `stop` is not due; `None` once it came due before every
    /// path was traced (the pass is cut: its splats are not an estimator without all its paths).
    fn light_splats_until(
        &self,
        world: &World,
        camera: &Camera,
        seed: u64,
        pass: u64,
        stop: &crate::interrupt::Stop,
    ) -> Option<LightSplats>;
    /// Sets the light paths per pass of the next passes, both sides' MIS weights included (the
    /// light-path pilot, `pipeline::light_pilot`, tries several counts on one integrator and its
    /// warm table cache).
    fn set_light_paths(&mut self, n: u64);
}

/// One camera estimate `f` under the profile's radiance timer, counted as one sample (the path
/// tracers' [`Integrator::estimate`]).
#[inline]
pub fn profiled_estimate(ctx: &mut Context, f: impl FnOnce(&mut Context) -> CameraEstimate) -> CameraEstimate {
    let t0 = ctx.profile.start(Phase::Radiance);
    let l = f(ctx);
    ctx.profile.samples += 1;
    ctx.profile.record(Phase::Radiance, t0);
    l
}

/// A batch of `n` camera estimates `f` (a wavefront, its scratch `S` taken from and put back
/// into `ctx`), timed exactly and counted as `n` samples (the path tracers'
/// [`Integrator::estimate_batch`]).
pub fn profiled_batch<S: Default + Send + 'static>(ctx: &mut Context, n: usize, f: impl FnOnce(&mut S, &mut Context)) {
    let t0 = std::time::Instant::now();
    let mut scratch = ctx.take_scratch::<S>();
    f(&mut scratch, ctx);
    ctx.put_scratch(scratch);
    ctx.profile.samples += n as u64;
    ctx.profile.add_exact(Phase::Radiance, t0.elapsed().as_nanos() as u64);
}

/// [`Integrator::estimate_batch`]'s default: `estimate` ray by ray, `ctx.rng` swapped with
/// each ray's stream around its call.
pub fn estimate_each<I: Integrator + ?Sized>(
    integrator: &I,
    world: &World,
    rays: &[crate::accel::Ray],
    rngs: &mut [crate::sampling::rng::Rng],
    ctx: &mut Context,
    out: &mut Vec<CameraEstimate>,
) {
    out.clear();
    for (r, rng) in rays.iter().zip(rngs) {
        std::mem::swap(&mut ctx.rng, rng);
        out.push(integrator.estimate(world, r.o, r.d, ctx));
        std::mem::swap(&mut ctx.rng, rng);
    }
}

/// One pass's light-traced contributions ([`Integrator::light_splats`]).
#[derive(Clone, Debug, Default)]
pub struct LightSplats {
    /// Row-major, one value per pixel (already divided by the pass's light paths).
    pub image: Vec<Rgb>,
    /// Splats dropped because they were not finite.
    pub nonfinite: u64,
    /// Closest-hit rays traced by the light paths.
    pub closest_rays: u64,
    /// Shadow (camera-connection) rays.
    pub shadow_rays: u64,
}

/// One method: its preprocess and its construction (its parameters are its field of
/// [`MethodArgs`]; a method reads the groups it shares, e.g. the IWS ones).
pub trait MethodSpec {
    /// The one-off preprocess product, broadcast from rank 0 (`()` when there is none).
    type Product: bitcode::Encode + bitcode::DecodeOwned;
    /// Runs the preprocess (rank 0 only), reporting its phases to `phases` (display only).
    fn preprocess(
        world: &World,
        args: &MethodArgs,
        seed: u64,
        phases: &dyn Phases,
    ) -> Result<Self::Product, MethodError>;
    /// Builds the integrator from the (broadcast) product.
    fn build(world: &World, args: &MethodArgs, product: Self::Product) -> Result<Box<dyn Integrator>, MethodError>;
}

/// The registry. `groups`: every option group, `field: Type = "Title"` (a `#[derive(clap::Args,
/// serde::Serialize)]` struct in its method's file; the title heads its flags in `render --help`,
/// with the methods that take it: [`group_heading`]); `methods`: `Variant = "name", [groups] =>
/// module::SpecType;` per method, the groups whose options it takes. It declares the modules,
/// the [`Method`] enum (the CLI/JSON name), the [`MethodArgs`] groups, which flags belong to
/// which methods ([`MethodArgs::foreign_flag`]), the report's [`MethodOptions`] and the
/// dispatch of [`Method::preprocess`] and [`Method::build`]. A new method gets all of it from
/// its line.
macro_rules! methods {
    (
        groups { $( $(#[$gdoc:meta])* $group:ident: $gty:ty = $title:literal, )* }
        methods { $( $(#[$doc:meta])* $variant:ident = $name:literal, [$($uses:ident),*] => $module:ident :: $spec:ident; )* }
    ) => {
        /// The rendering methods (`--method`).
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, clap::ValueEnum, serde::Serialize)]
        pub enum Method {
            $( $(#[$doc])* #[value(name = $name)] #[serde(rename = $name)] $variant, )*
        }

        /// The render settings and every method's option groups (CLI flags), and which flags
        /// the command line gave explicitly (for [`MethodArgs::foreign_flag`]).
        #[derive(clap::Args, Clone, Debug)]
        pub struct MethodArgs {
            /// Settings every method reads (`--max-depth`, `--emission-split`).
            #[command(flatten, next_help_heading = RENDER_SETTINGS)]
            pub settings: RenderSettings,
            $(
                $(#[$gdoc])*
                #[command(flatten, next_help_heading = group_heading(stringify!($group)))]
                pub $group: $gty,
            )*
            /// The ids of the method options given explicitly on the command line (set by
            /// `cli` from clap's `ArgMatches::value_source`; empty for API callers, e.g.
            /// `compare`, which hands one set of flags to several methods).
            #[arg(skip)]
            pub explicit: Vec<String>,
            /// The ids of the render settings and method options the command line gave, for
            /// every command that takes them (`render`, `reference`, `compare`, `forecast-map`):
            /// they win over the scene's `[render]` options. Empty for API callers, whose values
            /// give way to the scene's.
            #[arg(skip)]
            pub given: Vec<String>,
        }

        /// The options a report records: the render settings and the chosen method's groups.
        #[derive(Clone, Debug, serde::Serialize)]
        pub struct MethodOptions {
            #[serde(flatten)]
            settings: RenderSettings,
            $(
                #[serde(flatten)]
                $group: Option<$gty>,
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

            /// The option groups (fields of [`MethodArgs`]) this method takes.
            pub fn groups(self) -> &'static [&'static str] {
                match self {
                    $( Method::$variant => &[$(stringify!($uses)),*], )*
                }
            }

            /// The one-off preprocess (rank 0), encoded for the broadcast, reporting nothing.
            pub fn preprocess(self, world: &World, args: &MethodArgs, seed: u64) -> Result<Vec<u8>, MethodError> {
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
            ) -> Result<Vec<u8>, MethodError> {
                match self {
                    $( Method::$variant => encode_product::<$module::$spec>(world, args, seed, phases), )*
                }
            }

            /// Builds the integrator from the broadcast product.
            pub fn build(
                self,
                world: &World,
                args: &MethodArgs,
                product: &[u8],
            ) -> Result<Box<dyn Integrator>, MethodError> {
                args.check_for(self)?;
                match self {
                    $( Method::$variant => build_from::<$module::$spec>(self, world, args, product), )*
                }
            }
        }

        impl MethodArgs {
            /// Every option group: its field name and its flags as `(arg id, --long)`.
            pub fn group_flags() -> Vec<(&'static str, Vec<(String, String)>)> {
                vec![$( (stringify!($group), flags_of::<$gty>()), )*]
            }

            /// Every option group's field name and title (`Caustic Forecasting`), in registry
            /// order.
            pub fn group_titles() -> &'static [(&'static str, &'static str)] {
                &[$( (stringify!($group), $title), )*]
            }

            /// The options a report records for `method`: the settings and its groups only, with
            /// `--variant`'s choices applied ([`MethodArgs::with_variant`]).
            pub fn options_for(&self, method: Method) -> MethodOptions {
                let (uses, a) = (method.groups(), self.with_variant());
                MethodOptions {
                    settings: a.settings,
                    $( $group: uses.contains(&stringify!($group)).then(|| a.$group.clone()), )*
                }
            }
        }
    };
}

methods! {
    groups {
        /// `pt`'s `--path-filter` (shared with `pt-cf`).
        pt: pt::PtArgs = "Path tracing",
        /// The IWS options (`iws`, `iws-pm`, `iws-cf`).
        iws: iws::IwsArgs = "Instant radiosity (IWS)",
        /// The photon map's (`iws-pm`).
        pm: iws_pm::PmArgs = "Photon map",
        /// The Caustic Forecasting preprocess and tables (`iws-cf`, `pt-cf`).
        cf: iws_cf::CfArgs = "Caustic Forecasting",
        /// `iws-cf`'s own (`--variant`).
        iwscf: iws_cf::IwsCfArgs = "Paper variant",
        /// `pt-cf`'s own (`--guide-*`).
        ptcf: pt_cf::PtCfArgs = "Guided path tracing",
    }
    methods {
        /// Path tracing with NEE and MIS: the unbiased reference.
        Pt = "pt", [pt] => pt::PathTracer;
        /// Instant radiosity with bias compensation (Le + L_d); L_c left out by design.
        Iws = "iws", [iws] => iws::Iws;
        /// IWS with a caustic photon map for L_c (biased baseline).
        IwsPm = "iws-pm", [iws, pm] => iws_pm::IwsPm;
        /// IWS with Caustic Forecasting for L_c (BAJ08): unbiased.
        IwsCf = "iws-cf", [iws, cf, iwscf] => iws_cf::IwsCf;
        /// Path tracing whose continuation is drawn from a defensive mixture of the BSDF and the CF tables: unbiased.
        PtCf = "pt-cf", [pt, cf, ptcf] => pt_cf::PtCf;
    }
}

/// The `--help` heading of the render settings (`settings`, and `cli`'s `--method`, `--spp`, ...).
pub const RENDER_SETTINGS: &str = "Render settings";

/// The `--help` heading of option group `group`: its title and the methods that take it, e.g.
/// `Caustic Forecasting options (iws-cf, pt-cf)` (built once; clap takes `&'static str`).
pub fn group_heading(group: &str) -> &'static str {
    static HEADINGS: std::sync::OnceLock<Vec<(&'static str, &'static str)>> = std::sync::OnceLock::new();
    let headings = HEADINGS.get_or_init(|| {
        let heading = |(g, title): &(&'static str, &str)| {
            let owners = Method::ALL.iter().filter(|m| m.groups().contains(g)).map(|m| m.name());
            let text = format!("{title} options ({})", owners.collect::<Vec<_>>().join(", "));
            (*g, &*Box::leak(text.into_boxed_str()))
        };
        MethodArgs::group_titles().iter().map(heading).collect()
    });
    headings.iter().find(|(g, _)| *g == group).map_or("Method options", |(_, h)| h)
}

/// The flags of one option group, `(arg id, --long)`, from its clap definition.
fn flags_of<T: clap::Args>() -> Vec<(String, String)> {
    T::augment_args(clap::Command::new("group"))
        .get_arguments()
        .filter_map(|a| Some((a.get_id().to_string(), format!("--{}", a.get_long()?))))
        .collect()
}

impl Method {
    /// Parses a method name (scene files, `--methods`).
    pub fn from_name(s: &str) -> Option<Method> {
        <Method as clap::ValueEnum>::from_str(s, true).ok()
    }

    /// The methods that take option group `group`, as `a/b` (e.g. `iws-cf/pt-cf`).
    fn owners(group: &str) -> String {
        Method::ALL.iter().filter(|m| m.groups().contains(&group)).map(|m| m.name()).collect::<Vec<_>>().join("/")
    }
}

/// A render setting or method option by its long name ([`MethodArgs::option_named`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct OptionName {
    /// The flag, `--clusters`.
    pub long: String,
    /// The clap id, `clusters`.
    pub id: String,
    /// Its option group (a field of [`MethodArgs`]); `None` for a render setting, which every
    /// method takes.
    pub group: Option<&'static str>,
}

impl MethodArgs {
    /// The render setting or method option named `name`: its long flag name without the dashes,
    /// with `-` or `_` between words (`guide-fraction`, `guide_fraction`), as a scene's `[render]`
    /// table names it.
    pub fn option_named(name: &str) -> Option<OptionName> {
        let long = format!("--{}", name.replace('_', "-"));
        let settings = flags_of::<RenderSettings>().into_iter().map(|f| (f, None));
        let groups =
            Self::group_flags().into_iter().flat_map(|(g, flags)| flags.into_iter().map(move |f| (f, Some(g))));
        let ((id, long), group) = settings.chain(groups).find(|((_, l), _)| *l == long)?;
        Some(OptionName { long, id, group })
    }

    /// These arguments with `flags` (`--long=value` each) parsed over them by clap, with each
    /// flag's own parser, range and conflicts: a flag given replaces its value, the others keep
    /// theirs (no defaults are applied).
    pub fn with_flags(&self, flags: &[String]) -> Result<MethodArgs, clap::Error> {
        use clap::{Args, FromArgMatches};
        let cmd = Self::augment_args(clap::Command::new("render").no_binary_name(true));
        let matches = cmd.mut_args(|a| a.default_value(None)).try_get_matches_from(flags)?;
        let mut args = self.clone();
        args.update_from_arg_matches(&matches)?;
        Ok(args)
    }

    /// The first flag in `explicit` that `method` does not take, as the error naming the methods
    /// it belongs to: `--clusters belongs to iws-cf/pt-cf, not pt`. `None` when every explicit
    /// flag is the method's (or a render setting).
    pub fn foreign_flag(method: Method, explicit: &[String]) -> Option<MethodError> {
        let uses = method.groups();
        for (group, flags) in Self::group_flags() {
            if uses.contains(&group) {
                continue;
            }
            for (id, long) in flags {
                if explicit.contains(&id) {
                    return Some(MethodError::ForeignFlag { flag: long, owners: Method::owners(group), method });
                }
            }
        }
        None
    }

    /// Refuses what `method` does not take: a flag of another method given on the command line
    /// ([`MethodArgs::foreign_flag`]), and (API callers too) a `--path-filter`, which only the
    /// methods of `pt`'s group implement.
    pub fn check_for(&self, method: Method) -> Result<(), MethodError> {
        if let Some(e) = Self::foreign_flag(method, &self.explicit) {
            return Err(e);
        }
        if self.pt.path_filter.is_some() && !method.groups().contains(&"pt") {
            return Err(MethodError::ForeignFlag {
                flag: "--path-filter".into(),
                owners: Method::owners("pt"),
                method,
            });
        }
        Ok(())
    }

    /// The emission split in use: `--emission-split`, or 1 under `--path-filter` (the split's
    /// extra rays add emission of classes `L` and `SL` that no filter sees).
    pub fn emission_split(&self) -> u32 {
        if self.pt.path_filter.is_some() {
            1
        } else {
            self.settings.emission_split
        }
    }

    /// Every group's own `validate` (each method file owns its limits), before any work.
    pub fn validate(&self) -> Result<(), MethodError> {
        self.settings.validate()?;
        self.pt.validate()?;
        self.iws.validate()?;
        self.pm.validate()?;
        self.ptcf.validate()?;
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
) -> Result<Vec<u8>, MethodError> {
    Ok(bitcode::encode(&S::preprocess(world, args, seed, phases)?))
}

fn build_from<S: MethodSpec>(
    method: Method,
    world: &World,
    args: &MethodArgs,
    product: &[u8],
) -> Result<Box<dyn Integrator>, MethodError> {
    let p: S::Product = bitcode::decode(product).map_err(|e| MethodError::Product {
        method,
        bytes: product.len(),
        reason: e.to_string(),
    })?;
    S::build(world, args, p)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each refusal's message, word for word as the command line and the scene reader print it.
    #[test]
    fn method_errors_keep_their_messages() {
        let e = MethodError::check_limit(&crate::param_limits::PHOTONS, "--photons", 0).unwrap_err();
        assert_eq!(e.to_string(), "--photons 0: photons must be at least 1 (got 0)");
        assert_eq!(MethodError::option("--path-filter", "bad classes").to_string(), "--path-filter: bad classes");
        let f = MethodArgs::foreign_flag(Method::Pt, &["clusters".to_string()]).expect("a flag of iws-cf/pt-cf");
        let want =
            MethodError::ForeignFlag { flag: "--clusters".into(), owners: "iws-cf/pt-cf".into(), method: Method::Pt };
        assert_eq!(f, want);
        assert_eq!(f.to_string(), "--clusters belongs to iws-cf/pt-cf, not pt");
        let mut a = MethodArgs::default();
        a.pt.path_filter = Some("DSL".into());
        assert_eq!(a.check_for(Method::Iws).unwrap_err().to_string(), "--path-filter belongs to pt/pt-cf, not iws");
        let p = MethodError::Product { method: Method::IwsPm, bytes: 3, reason: "eof".into() };
        assert_eq!(p.to_string(), "iws-pm: cannot decode the broadcast preprocess product (3 bytes): eof");
    }
}
