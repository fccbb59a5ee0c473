//! `pt-cf`: `pt` guided by the Caustic Forecasting tables and MIS-combined with light paths
//! (beyond BAJ08, which combines CF with IWS only). Derivations: `docs/methods/pt-cf.md`.
//!
//! Estimator. Exactly `pt` (`pt::vertex`) except at the guided vertices: non-Dirac hits at
//! diffuse depth `d < --table-depth` inside a guided kept cluster `k` (`CausticForecast::
//! cluster_at`, then `guide_tables` through the shared `TableCache`). There the continuation is
//! drawn from the defensive mixture `q(ω) = c_k·p_BSDF(ω) + (1−c_k)·p_CF(ω)` (`cf::mixture`),
//! `c_k = max(c, 1 − s_k)` from the cluster's caustic share `s_k` (`cf::share`), and at `d = 0`
//! split into `n` continuations (`--split`, `n` a function of the cluster only). NEE is
//! MIS-weighted against `n·q`, the pdf really used. The light side (`light`) adds the paths
//! `L S+ (S|D)* D E` from the lights, each weighted against the camera side's technique.
//!
//! Invariants: the tables are a pdf only (any photons give an unbiased image); `c = 1` draws
//! exactly `pt`'s random numbers and is `pt` bit for bit; outside guided clusters every vertex is
//! a `pt` vertex; the MIS weights of every technique pair sum to 1; the image does not depend on
//! threads or ranks. The preprocess product is `iws-cf`'s plus the caustic shares. Options: the
//! CF group (`iws_cf::CfArgs`, shared with `iws-cf`), `--path-filter` (`pt`'s) and [`PtCfArgs`].

pub mod light;
mod wavefront;

use super::iws_cf::{targeted_emission, IwsCf};
use super::pt::path_class::{kept, PathClass, PathFilter};
use super::pt::{vertex, SurfaceVertex, Walk};
use super::{CameraEstimate, Context, Integrator, LightSplats, LightTracer, MethodArgs, MethodError, MethodSpec};
use crate::accel::{Hit, Ray, World};
use crate::bsdf::{self, BsdfSample, ShadingPoint};
use crate::cf::cluster::Cluster;
use crate::cf::direction_table::ForecastTables;
use crate::cf::estimator::{energy_split, CausticForecast, TableCache};
use crate::cf::mixture::{DefensiveMixture, MixtureWeights};
use crate::cf::share::{min_share, parse_min_share};
use crate::cf::subset_grid::SubsetGrid;
use crate::math::{Frame, Rgb, Vec3};
use crate::profile::Profile;
use crate::progress::Phases;
use crate::sampling::rng::Rng;
use crate::scene::{Camera, Material, NO_EMITTER};
use crate::transport::context::ShadingQuery;
use crate::transport::direct;
use crate::transport::particle::reciprocal;
use light::{CameraPdf, LightSide};
use std::sync::Arc;

/// `pt-cf`'s own options (the CF preprocess and table options are the group shared with
/// `iws-cf`: `--forecast-photons`, `--clusters`, `--split`, `--table-depth`, …).
#[derive(clap::Args, Clone, Debug, PartialEq, serde::Serialize)]
pub struct PtCfArgs {
    /// The BSDF's share c of the guided vertices' directions, the tables' 1 − c; 0 < c ≤ 1
    /// (1 = pt). A cluster's share is at least 1 − its caustic share.
    // q = c·p_BSDF + (1−c)·p_CF; per cluster c_k = max(c, 1 − s_k) from its caustic share s_k.
    #[arg(long, value_name = "C", default_value_t = 0.3, value_parser = parse_guide_fraction)]
    pub guide_fraction: f32,
    /// Clusters whose caustic share of the indirect light is below this are not guided.
    #[arg(long, value_name = "S", default_value_t = 0.5, value_parser = parse_min_share)]
    pub guide_min_share: f32,
    /// Light paths per pass connected to the camera for the caustics, weighted against the
    /// camera paths (0 = none; at most 16 per pixel or 65536; default: a pilot render picks 1/8
    /// to 2 per pixel).
    // The caustics L S+ (S|D)* D E, MIS-weighted; 0 leaves the camera side alone.
    #[arg(long, value_name = "N")]
    pub light_paths: Option<u64>,
    /// Vertices whose BSDF is one microfacet lobe alone (roughconductor, roughdielectric) with
    /// roughness below this are not guided (pt vertices); 0 guides them all.
    // The tables are lobe-blind: at a narrow lobe their share of the directions is wasted.
    #[arg(long, value_name = "ALPHA", default_value_t = GUIDE_MIN_ALPHA, value_parser = parse_min_alpha)]
    pub guide_min_alpha: f32,
}

/// `--guide-min-alpha`'s default (`results/2026-12-07-glossy-caustics.md`).
pub const GUIDE_MIN_ALPHA: f32 = 0.15;

fn parse_min_alpha(s: &str) -> Result<f32, String> {
    let a: f32 = s.trim().parse().map_err(|e| format!("`{s}` is not a number: {e}"))?;
    (a >= 0.0 && a.is_finite()).then_some(a).ok_or_else(|| format!("{a} is not a roughness >= 0"))
}

impl PtCfArgs {
    /// The limits of `crate::param_limits`.
    pub fn validate(&self) -> Result<(), MethodError> {
        self.light_paths
            .map_or(Ok(()), |n| MethodError::check_limit(&crate::param_limits::LIGHT_PATHS, "--light-paths", n))
    }
}

fn parse_guide_fraction(s: &str) -> Result<f32, String> {
    let c: f32 = s.trim().parse().map_err(|e| format!("`{s}` is not a number: {e}"))?;
    MixtureWeights::guide_fraction(c).map(|_| c)
}

/// The `pt-cf` method.
pub struct PtCf;

impl MethodSpec for PtCf {
    type Product = CausticForecast;
    fn preprocess(
        world: &World,
        args: &MethodArgs,
        seed: u64,
        phases: &dyn Phases,
    ) -> Result<CausticForecast, MethodError> {
        <IwsCf as MethodSpec>::preprocess(world, args, seed, phases)
    }
    fn build(world: &World, args: &MethodArgs, g: CausticForecast) -> Result<Box<dyn Integrator>, MethodError> {
        let p = &args.ptcf;
        let c = p.guide_fraction;
        let weights = MixtureWeights::guide_fraction(c).map_err(|e| MethodError::option("--guide-fraction", e))?;
        min_share(p.guide_min_share).map_err(|e| MethodError::option("--guide-min-share", e))?;
        let n_kept = g.clustering.n_kept(g.opts.max_rank);
        if g.shares.len() != n_kept {
            let m = format!("pt-cf: {} caustic shares for {n_kept} kept clusters", g.shares.len());
            return Err(MethodError::BadProduct(m));
        }
        // the BSDF share of each kept cluster (None: a `pt` vertex there)
        let per_cluster: Vec<Option<MixtureWeights>> = g
            .shares
            .iter()
            .map(|sh| {
                let s = sh.share();
                (s >= p.guide_min_share && s > 0.0)
                    .then(|| MixtureWeights::guide_fraction(c.max(1.0 - s)).ok())
                    .flatten()
            })
            .collect();
        let guided: Vec<usize> = (0..n_kept).filter(|&c| per_cluster[c].is_some()).collect();
        let split = split_counts(&g.clustering.clusters[..n_kept], &guided, args.cf.split);
        let deadline = args.cf.build_deadline;
        let stop = || deadline.is_some_and(|d| std::time::Instant::now() >= d);
        let guided_grid = SubsetGrid::build_until(&g.cluster_map, &guided, &stop);
        Ok(Box::new(GuidedPathTracer {
            max_depth: args.settings.cap(),
            weights,
            per_cluster,
            guided,
            guided_grid,
            guide_depth: if c >= 1.0 { 0 } else { args.cf.table_depth },
            min_alpha: p.guide_min_alpha,
            split,
            split_s0: args.cf.split,
            cf: g,
            cache: TableCache::default(),
            filter: args.pt.filter()?,
            light: light_side(world, args),
        }))
    }
}

/// The light side (`None`: `--light-paths 0`, a `--path-filter` diagnostic, or no light or Dirac
/// object to make a path of C).
fn light_side(world: &World, args: &MethodArgs) -> Option<LightSide> {
    let s = &world.scene;
    let useful = !s.lights.is_empty() && s.dirac_bounds().is_some() && args.pt.path_filter.is_none();
    (useful && args.ptcf.light_paths != Some(0)).then(|| LightSide {
        paths: args.ptcf.light_paths,
        emission: targeted_emission(world),
        max_depth: args.settings.cap(),
    })
}

/// Continuations at diffuse depth 0 in each kept cluster by the energy rule against the densest
/// guided cluster (a function of the cluster only, so unbiased); 1 in the unguided clusters
/// (their vertices are `pt` vertices).
fn split_counts(clusters: &[Cluster], guided: &[usize], s0: u32) -> Vec<usize> {
    let max = guided.iter().map(|&c| clusters[c].density).fold(0.0f32, f32::max);
    let mut n = vec![1; clusters.len()];
    for &c in guided {
        n[c] = energy_split(s0.max(1), clusters[c].density, max);
    }
    n
}

/// The guided path tracer; owns the product and the table cache shared by all worker threads.
pub struct GuidedPathTracer {
    max_depth: u32,
    /// `--guide-fraction`'s mixture (reported).
    weights: MixtureWeights,
    /// The mixture of each kept cluster; `None`: its vertices are `pt` vertices.
    per_cluster: Vec<Option<MixtureWeights>>,
    /// The kept clusters with a mixture.
    guided: Vec<usize>,
    /// Where the cluster map may return one of them (skips its kd-tree elsewhere).
    guided_grid: SubsetGrid,
    /// Guided diffuse depths `d < guide_depth` (0 when `c = 1`: no lookups at all).
    guide_depth: u32,
    /// `--guide-min-alpha`: single microfacet lobes rougher than this only are guided.
    min_alpha: f32,
    /// Continuations at a guided vertex of diffuse depth 0, per kept cluster (1 deeper).
    split: Vec<usize>,
    /// `--split` (reported).
    split_s0: u32,
    cf: CausticForecast,
    cache: TableCache,
    /// `--path-filter` (a diagnostic; `None`: the unbiased estimate).
    filter: Option<PathFilter>,
    /// The light paths (`integrators::pt_cf::light`); `None`: today's camera side alone.
    light: Option<LightSide>,
}

/// One path (or branch) in flight: the ray, its throughput and how the last vertex sampled it.
#[derive(Clone, Copy, Debug)]
struct PathState {
    /// The ray, β, the roulette's scales and the last direction's pdf (`prev_pdf_w` is the
    /// effective `n·q` at a guided vertex, for MIS).
    walk: Walk,
    /// Vertices traced so far.
    vertex: u32,
    /// Non-Dirac vertices traced so far (diffuse depth of the next one).
    diffuse: u32,
    /// The path's class so far (`--path-filter`).
    class: PathClass,
    /// The running MIS ratio against the light paths (`light::first_ratio`, `next_ratio`)
    /// while the path may be of class C (its first vertex non-Dirac); `None` otherwise.
    mis: Option<f32>,
}

impl PathState {
    /// A camera path starting along `ray`.
    fn camera(ray: Ray) -> Self {
        PathState { walk: Walk::camera(ray), vertex: 0, diffuse: 0, class: PathClass::default(), mis: None }
    }
}

/// The continuations of a guided vertex: the mixture they are drawn from and how many.
struct Branches<'a> {
    mix: &'a DefensiveMixture<'a>,
    n: usize,
}

/// The guide at one vertex: tables, their frame, the mixture weights and the split count.
struct Guide {
    tables: Arc<ForecastTables>,
    frame: Frame,
    weights: MixtureWeights,
    n: usize,
}

impl GuidedPathTracer {
    /// A microfacet lobe alone, narrower than `--guide-min-alpha`: a `pt` vertex.
    #[inline(always)]
    fn narrow_lobe(&self, m: &Material) -> bool {
        m.lobe_alpha().is_some_and(|a| a < self.min_alpha)
    }

    /// The guide at a non-Dirac vertex, or `None` for a `pt` vertex (a pure function of it).
    #[inline(always)]
    fn guide_at(&self, q: &ShadingQuery, ctx: &mut Context) -> Option<Guide> {
        if q.depth >= self.guide_depth {
            return None;
        }
        ctx.profile.cf.queries += 1;
        // the guided clusters' grid answers the cluster map's query for them (`SubsetGrid`)
        let c = self.cf.cluster_at(q, ctx, Some(&self.guided_grid))?;
        let weights = self.per_cluster.get(c).copied().flatten()?;
        // the (rare) guide itself out of line: a `None` stays in registers
        self.guide_in(c, weights, q, ctx)
    }

    /// The guide in guided cluster `c` (its mixture `weights`) at `q`, or `None` where its
    /// tables are empty.
    #[inline(never)]
    fn guide_in(&self, c: usize, weights: MixtureWeights, q: &ShadingQuery, ctx: &mut Context) -> Option<Guide> {
        let (tables, frame) = self.cf.guide_tables(c, q, ctx, &self.cache);
        if tables.t1.is_none() && tables.t2.is_none() {
            return None;
        }
        ctx.profile.cf.inside += 1;
        let n = if q.depth == 0 { self.split.get(c).copied().unwrap_or(1) } else { 1 };
        ctx.profile.cf.samples += n as u64;
        Some(Guide { tables, frame, weights, n })
    }

    /// Updates the path's MIS ratio after its vertex `v` drew the continuation now in `st`.
    #[inline(always)]
    fn track_mis(&self, st: &mut PathState, v: &SurfaceVertex, ctx: &Context) {
        let (Some(_), Some(cam)) = (&self.light, &ctx.camera) else { return };
        let (m, sp, wo, t) = (v.m, &v.sp, v.wo, v.t);
        if st.walk.prev_delta {
            return; // a Dirac lobe: a vertex of the chain, outside the ratio (spec §1, by lobe)
        }
        if v.index == 0 {
            st.mis = Some(light::first_ratio(cam, -wo, t, sp.ng, (wo, st.walk.d), st.walk.prev_pdf_w));
        } else if let Some(r) = st.mis {
            st.mis = Some(r * light::next_ratio(m, sp, (wo, st.walk.d), st.walk.prev_pdf_w));
        }
    }

    /// Takes `st` out of class C where its Dirac vertex `v` (at `hit`) drew `bs` toward a
    /// direction that sees another shading normal (`transport::particle::reciprocal`): the
    /// light side draws no such path, so the camera side's weight there is 1.
    #[inline(always)]
    fn leave_c(&self, world: &World, st: &mut PathState, hit: &Hit, v: &SurfaceVertex, bs: &BsdfSample) {
        if bs.is_delta && st.mis.is_some() && self.light.is_some() && !reciprocal(world, hit, &v.sp, bs.wi) {
            st.mis = None;
        }
    }

    /// The camera side's MIS weight of an emitter hit against the light paths: `w_E` on a path of
    /// class C (first vertex non-Dirac, the emitter reached from a Dirac vertex), 1 otherwise.
    #[inline]
    fn camera_weight(&self, world: &World, st: &PathState, hit: &Hit, ctx: &Context) -> f32 {
        match (&self.light, &ctx.camera, st.mis) {
            (Some(light), Some(cam), Some(ratio)) if st.walk.prev_delta && st.vertex <= light.max_depth => {
                light::camera_weight(world, light, cam, hit, st.walk.d, ratio)
            }
            _ => 1.0,
        }
    }

    /// The camera side's MIS weight of a ray that escapes to the environment against the light
    /// paths (as [`Self::camera_weight`]).
    #[inline]
    fn escape_weight(&self, world: &World, st: &PathState, ctx: &Context) -> f32 {
        match (&self.light, &ctx.camera, st.mis) {
            (Some(light), Some(cam), Some(ratio)) if st.walk.prev_delta && st.vertex <= light.max_depth => {
                light::camera_weight_escaped(world, light, cam, (st.walk.o, st.walk.d), ratio)
            }
            _ => 1.0,
        }
    }

    /// Adds to `l` the environment's radiance where `st`'s ray escapes, weighted as
    /// [`Self::add_emitted`].
    #[inline]
    fn add_escaped(&self, world: &World, st: &PathState, ctx: &Context, l: &mut CameraEstimate) {
        if let Some((le, w)) = st.walk.escaped(world) {
            let w = w * self.escape_weight(world, st, ctx);
            let v = self.kept(st.class, st.walk.t.beta * le * w);
            *if st.diffuse == 0 { &mut l.prefix_le } else { &mut l.rest } += v;
        }
    }

    /// A contribution `v` reaching the light from `class`, or 0 if `--path-filter` drops it.
    #[inline]
    fn kept(&self, class: PathClass, v: Rgb) -> Rgb {
        kept(self.filter.as_ref(), class, v)
    }

    /// Adds to `l` the emission `st` reaches at the emitter `hit`, weighted by MIS against NEE
    /// and against the light paths (to `prefix_le` while no non-Dirac vertex came before).
    #[inline]
    fn add_emitted(&self, world: &World, st: &PathState, hit: &Hit, ctx: &Context, l: &mut CameraEstimate) {
        if let Some((le, w)) = st.walk.emitted(world, hit) {
            let w = w * self.camera_weight(world, st, hit, ctx);
            let v = self.kept(st.class, st.walk.t.beta * le * w);
            *if st.diffuse == 0 { &mut l.prefix_le } else { &mut l.rest } += v;
        }
    }

    /// Enters the non-emitter vertex `hit` (material `m`) of `st`, counting it.
    #[inline(always)]
    fn enter<'m>(&self, st: &mut PathState, m: &'m Material, sp: ShadingPoint, hit: &Hit) -> SurfaceVertex<'m> {
        let v = SurfaceVertex::at(m, sp, hit, st.walk.d, st.vertex);
        st.vertex += 1;
        st.class.push(m.is_dirac());
        v
    }

    /// The guide at the vertex `v` that `st` entered: `None` at a Dirac vertex and at a `pt`
    /// vertex. (Not a field of `enter`'s result: a `None` then stays out of memory.)
    #[inline(always)]
    fn guide_of(&self, st: &PathState, v: &SurfaceVertex, ctx: &mut Context) -> Option<Guide> {
        if v.m.is_dirac() || self.narrow_lobe(v.m) {
            return None;
        }
        self.guide_at(&ShadingQuery { x: &v.sp, m: v.m, wo: v.wo, depth: st.diffuse }, ctx)
    }

    /// Radiance along `st` (a whole path, or one branch of a split).
    fn trace(&self, world: &World, mut st: PathState, ctx: &mut Context) -> CameraEstimate {
        let s = &world.scene;
        let mut l = CameraEstimate::default();
        // as `pt`: `max_depth` surface vertices, then the ray the last one drew, for the emitter
        // it may reach (the other half of that vertex's NEE MIS)
        loop {
            let Some(hit) = world.intersect(st.walk.o, st.walk.d, f32::INFINITY) else {
                self.add_escaped(world, &st, ctx, &mut l);
                break;
            };
            if s.emitter_of(hit.prim) != NO_EMITTER {
                self.add_emitted(world, &st, &hit, ctx, &mut l);
                break; // emitters reflect nothing
            }
            if st.vertex >= self.max_depth {
                break;
            }
            let (m, sp) = world.shade(&hit, -st.walk.d);
            let v = self.enter(&mut st, &m, sp, &hit);
            let Some(g) = self.guide_of(&st, &v, ctx) else {
                // a `pt` vertex
                let (beta, class) = (st.walk.t.beta, st.class);
                let nee = |ls| l.rest += self.kept(class, beta * direct::unoccluded(world, ls));
                let Some(bs) = vertex(world, &v, &mut ctx.rng, nee) else { break };
                st.diffuse += u32::from(!m.is_dirac());
                self.leave_c(world, &mut st, &hit, &v, &bs);
                if !st.walk.scatter(&bs, v.index, &v.sp, &mut ctx.rng) {
                    break;
                }
                self.track_mis(&mut st, &v, ctx);
                continue;
            };
            st.diffuse += 1;
            let (m, sp, wo) = (v.m, &v.sp, v.wo);
            let mix = DefensiveMixture::new(m, sp, wo, &g.tables, g.frame, g.weights);
            let n = g.n as f32;
            let nee = st.walk.t.beta * direct::sample_light_mis(world, sp, m, wo, &mut ctx.rng, |wi| n * mix.pdf_w(wi));
            l.rest += self.kept(st.class, nee);
            if g.n == 1 {
                let Some(ms) = mix.sample(&mut ctx.rng) else { break };
                st.walk.t.guided(ms.pdf_w, ms.bsdf_pdf_w);
                if !st.walk.scatter(&ms.as_bsdf_sample(), v.index, sp, &mut ctx.rng) {
                    break;
                }
                self.track_mis(&mut st, &v, ctx);
                continue;
            }
            self.split(world, &st, &v, Branches { mix: &mix, n: g.n }, &mut l.rest, ctx);
            break;
        }
        l
    }

    /// Splitting: `b.n` independent continuations of `st` at vertex `v` drawn from `b.mix`, each
    /// with weight 1/n, their radiance added to `rest` one by one.
    fn split(&self, world: &World, st: &PathState, v: &SurfaceVertex, b: Branches, rest: &mut Rgb, ctx: &mut Context) {
        let (mix, n) = (b.mix, b.n);
        let nf = n as f32;
        for _ in 0..n {
            let Some(ms) = mix.sample(&mut ctx.rng) else { continue };
            let mut b = *st;
            let bs = BsdfSample { weight: ms.weight * (1.0 / nf), pdf_w: nf * ms.pdf_w, ..ms.as_bsdf_sample() };
            // roulette sees the branch as one BSDF-sampled path (`Throughput::guided`)
            b.walk.t.guided(bs.pdf_w, ms.bsdf_pdf_w);
            if b.walk.scatter(&bs, v.index, &v.sp, &mut ctx.rng) {
                self.track_mis(&mut b, v, ctx);
                *rest += self.trace(world, b, ctx).total();
            }
        }
    }
}

impl CameraPdf for GuidedPathTracer {
    /// The BSDF's pdf, or `n·q` of the guided mixture with its split count `n`.
    fn camera_pdf_w(
        &self,
        sp: &ShadingPoint,
        m: &Material,
        (wo, wi): (Vec3, Vec3),
        depth: u32,
        ctx: &mut Context,
    ) -> f32 {
        let guide = if self.narrow_lobe(m) { None } else { self.guide_at(&ShadingQuery { x: sp, m, wo, depth }, ctx) };
        match guide {
            Some(g) => g.n as f32 * DefensiveMixture::new(m, sp, wo, &g.tables, g.frame, g.weights).pdf_w(wi),
            None => bsdf::pdf_w(m, sp, wo, wi),
        }
    }
}

impl LightTracer for GuidedPathTracer {
    fn light_splats_until(
        &self,
        world: &World,
        camera: &Camera,
        seed: u64,
        pass: u64,
        stop: &crate::interrupt::Stop,
    ) -> Option<LightSplats> {
        match &self.light {
            Some(light) => light::light_splats(self, light, world, camera, (seed, pass), stop),
            None => Some(LightSplats::default()),
        }
    }

    fn set_light_paths(&mut self, n: u64) {
        if let Some(l) = &mut self.light {
            l.paths = Some(n);
        }
    }
}

impl Integrator for GuidedPathTracer {
    /// Every pass is a pure function of (seed, pass, pixel) and the preprocess: no `begin_pass`.
    fn independent_passes(&self) -> bool {
        true
    }

    fn estimate(&self, world: &World, origin: Vec3, dir: Vec3, ctx: &mut Context) -> CameraEstimate {
        let camera = PathState::camera(Ray { o: origin, d: dir, tmax: f32::INFINITY });
        super::profiled_estimate(ctx, |ctx| self.trace(world, camera, ctx))
    }

    /// The wavefront (`pt_cf::wavefront`), bit for bit `estimate` ray by ray; `--path-filter` runs
    /// `estimate` ray by ray.
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
        super::profiled_batch(ctx, rays.len(), |wave: &mut wavefront::CfWave, ctx| {
            self.trace_batch(world, rays, rngs, wave, ctx, out)
        });
    }

    /// `max_depth` + 1: the estimate reaches the emitter through up to `max_depth` Dirac vertices
    /// (its last vertex's BSDF ray), and `prefix_emission` counts the emitter as a vertex.
    fn prefix_cap(&self) -> u32 {
        self.max_depth.saturating_add(1)
    }

    fn light_tracer(&self) -> Option<&dyn LightTracer> {
        self.light.is_some().then_some(self as &dyn LightTracer)
    }

    fn light_tracer_mut(&mut self) -> Option<&mut dyn LightTracer> {
        if self.light.is_some() {
            Some(self)
        } else {
            None
        }
    }

    fn stats(&self, profile: &Profile) -> serde_json::Value {
        let c = &profile.cf;
        serde_json::json!({
            "profile_per_sample": profile.per_sample(),
            "guide": {
                "fraction_bsdf": self.weights.bsdf,
                "depth": self.guide_depth,
                "min_alpha": self.min_alpha,
                "split_s0": self.split_s0,
                "split_per_cluster": self.split,
                "lookups": c.queries,
                "fraction_inside_clusters": c.fraction_inside(),
                "guided_grid_fill": self.guided_grid.fill(),
                "guided_grid_cells": self.guided_grid.kinds(),
                "mean_continuations_per_lookup": c.samples_per_query(),
                "creating_cdfs_s": c.cdf_s(),
                "tables_built": c.tables_built,
                "table_cache_hits": c.cache_hits,
            },
            "shares": {
                "guided_clusters": self.guided.len(),
                "gather_s": self.cf.stats.shares_s,
                "per_cluster": self.cf.shares,
            },
            "preprocess": self.cf.stats,
            "cache_cells": self.cf.cells.json(),
            "options": self.cf.opts,
            "light_paths": self.light.map(|l| serde_json::json!({
                "per_pass": l.paths,
                "per_pixel_without_pilot": light::PATHS_PER_PIXEL,
                "emission": format!("{:?}", l.emission),
            })),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cluster(density: f32, rank: u32) -> Cluster {
        let z = [0.0; 3];
        Cluster {
            centroid: z,
            normal: z,
            feature: [0.0; 6],
            power: density,
            area: 1.0,
            density,
            radius: 0.0,
            rank,
            members: vec![0],
        }
    }

    /// ρ_max is the densest *guided* cluster's (the densest kept cluster is unguided here), and
    /// the unguided get 1.
    #[test]
    fn split_counts_follow_the_guided_clusters() {
        let k = [cluster(4.0, 0), cluster(2.0, 0), cluster(1.0, 1), cluster(0.01, 2)];
        let guided = [1, 2, 3];
        assert_eq!(split_counts(&k, &guided, 16), vec![1, 16, 8, 1]);
    }
}
