//! `pt`: unidirectional path tracing, the unbiased reference.
//!
//! Next-event estimation with MIS (power heuristic) for area lights, point lights by NEE only,
//! BSDF sampling for every material, Dirac chains followed with the Fresnel-weighted choice, and
//! Russian roulette from the 5th bounce (survival min(max β·etaScale, 0.95), as Mitsuba and
//! pbrt-v4: `transport::roulette::Throughput`).
//! `max_depth` (default 64 vertices) is a safety cap only: with RR the truncated energy is far
//! below the noise (results/2026-11-30-roulette.md). The cap N keeps every path of N surface
//! vertices whole, NEE at the N-th and the emitter its BSDF sample reaches (the two halves of
//! its MIS): paths of at most N + 1 segments, Mitsuba's `max_depth` N + 1.
//!
//! `--path-filter` (a biased diagnostic, off by default) keeps only some path classes
//! (`integrators::pt::path_class`); without it the estimator is exactly the above.
//!
//! CLI: `forecast render scenes/cornell-box.toml --method pt --spp 64`.

pub mod lanes;
pub mod path_class;
mod vertex;
pub mod wavefront;

pub use vertex::{vertex, SurfaceVertex, Walk};

use super::{CameraEstimate, Context, Integrator, MethodArgs, MethodError, MethodSpec};
use crate::accel::{Ray, World};
use crate::math::{Rgb, Vec3};
use crate::profile::Profile;
use crate::progress::Phases;
use crate::sampling::rng::Rng;
use crate::scene::NO_EMITTER;
use crate::transport::direct;
use path_class::{kept, PathClass, PathFilter};

/// `pt`'s options (shared with `pt-cf`): `--path-filter`, the path tracers' diagnostic. The
/// vertex cap and the emission split are render settings (`integrators::settings`).
#[derive(clap::Args, Clone, Debug, PartialEq, serde::Serialize)]
pub struct PtArgs {
    /// A biased diagnostic: render only the light paths of these classes, e.g. DSL,DD* (D a
    /// diffuse or glossy vertex, S a chain of mirror or glass vertices, L the light, * anything
    /// after); turns the emission split off.
    // The classes are `path_class`'s; one camera ray per sample.
    #[arg(long, value_name = "CLASSES", value_parser = path_class::check_filter)]
    pub path_filter: Option<String>,
}

impl PtArgs {
    /// `--path-filter`, parsed (`None` when not given).
    pub fn filter(&self) -> Result<Option<PathFilter>, MethodError> {
        self.path_filter
            .as_deref()
            .map(PathFilter::parse)
            .transpose()
            .map_err(|e| MethodError::option("--path-filter", e))
    }

    /// A `--path-filter` that parses.
    pub fn validate(&self) -> Result<(), MethodError> {
        self.filter().map(|_| ())
    }
}

impl MethodSpec for PathTracer {
    type Product = ();
    fn preprocess(_: &World, _: &MethodArgs, _: u64, _: &dyn Phases) -> Result<(), MethodError> {
        Ok(())
    }
    fn build(_: &World, args: &MethodArgs, _: ()) -> Result<Box<dyn Integrator>, MethodError> {
        Ok(Box::new(PathTracer { max_depth: args.settings.cap(), filter: args.pt.filter()? }))
    }
}

/// The path tracer.
pub struct PathTracer {
    /// Safety cap on path vertices.
    pub max_depth: u32,
    /// `--path-filter`: the path classes kept (`None`: all, the unbiased estimate).
    pub filter: Option<PathFilter>,
}

impl Integrator for PathTracer {
    /// Every pass is a pure function of (seed, pass, pixel) and the preprocess: no `begin_pass`.
    fn independent_passes(&self) -> bool {
        true
    }

    fn estimate(&self, world: &World, origin: Vec3, dir: Vec3, ctx: &mut Context) -> CameraEstimate {
        super::profiled_estimate(ctx, |ctx| self.trace(world, origin, dir, ctx))
    }

    fn estimate_batch(
        &self,
        world: &World,
        rays: &[Ray],
        rngs: &mut [Rng],
        ctx: &mut Context,
        out: &mut Vec<CameraEstimate>,
    ) {
        if self.filter.is_some() {
            return super::estimate_each(self, world, rays, rngs, ctx, out);
        }
        super::profiled_batch(ctx, rays.len(), |wave, _| {
            wavefront::trace_batch(world, self.max_depth, rays, rngs, wave, out)
        });
    }

    /// `max_depth` + 1: the estimate reaches the emitter through up to `max_depth` Dirac vertices
    /// (its last vertex's BSDF ray), and `prefix_emission` counts the emitter as a vertex.
    fn prefix_cap(&self) -> u32 {
        self.max_depth.saturating_add(1)
    }

    fn stats(&self, profile: &Profile) -> serde_json::Value {
        serde_json::json!({ "profile_per_sample": profile.per_sample() })
    }
}

impl PathTracer {
    /// `pt` without a filter (the reference estimator).
    pub fn new(max_depth: u32) -> Self {
        PathTracer { max_depth, filter: None }
    }

    /// A contribution `v` reaching the light from `class`, or 0 if `--path-filter` drops it.
    #[inline]
    fn kept(&self, class: PathClass, v: Rgb) -> Rgb {
        kept(self.filter.as_ref(), class, v)
    }

    /// `pt`'s estimate along the ray `(origin, dir)`, emission reached before any non-Dirac
    /// vertex in `prefix_le`, the rest in `rest` (also the CF preprocess's caustic-share gather,
    /// `integrators::iws_cf::share`).
    pub fn trace(&self, world: &World, origin: Vec3, dir: Vec3, ctx: &mut Context) -> CameraEstimate {
        let s = &world.scene;
        let rng = &mut ctx.rng;
        let mut w = Walk::camera(Ray { o: origin, d: dir, tmax: f32::INFINITY });
        let mut l = CameraEstimate::default();
        let mut prefix = true; // no non-Dirac vertex yet
        let mut class = PathClass::default();
        // `max_depth` surface vertices, then the ray the last one's BSDF drew, for the emitter it
        // may reach (the other half of that vertex's NEE MIS): paths of max_depth + 1 segments
        for depth in 0..=self.max_depth {
            let Some(hit) = world.intersect(w.o, w.d, f32::INFINITY) else {
                if let Some((le, mis)) = w.escaped(world) {
                    *if prefix { &mut l.prefix_le } else { &mut l.rest } += self.kept(class, w.t.beta * le * mis);
                }
                break;
            };
            if s.emitter_of(hit.prim) != NO_EMITTER {
                if let Some((le, mis)) = w.emitted(world, &hit) {
                    *if prefix { &mut l.prefix_le } else { &mut l.rest } += self.kept(class, w.t.beta * le * mis);
                }
                break; // emitters reflect nothing
            }
            if depth == self.max_depth {
                break;
            }
            let (m, sp) = world.shade(&hit, -w.d);
            let v = SurfaceVertex::at(&m, sp, &hit, w.d, depth);
            class.push(m.is_dirac());
            prefix &= m.is_dirac();
            // a filtered-out sample still draws its random numbers (filters partition the image)
            let beta = w.t.beta;
            let nee = |ls| l.rest += self.kept(class, beta * direct::unoccluded(world, ls));
            let Some(bs) = vertex(world, &v, rng, nee) else { break };
            if !w.scatter(&bs, depth, &v.sp, rng) {
                break;
            }
        }
        l
    }
}
