//! `iws`: Instant radiosity with bias compensation ("IWS", Kollig & Keller 2004 [KK04]; spec §1,
//! §2), the `L_d` half of the [BAJ08] split, with a pluggable caustic term `L_c`.
//!
//! At a non-specular point `x` the estimator is (spec §1)
//! `L̂(x,ω_o,d) = Le(x) + D(x,ω_o) + VPL_b(x,ω_o) + C(x,ω_o,d) + Ĺ_c(x,ω_o,d)`:
//! - `D`: the emitters' direct light by NEE (`--direct nee`, the default: one light sample and
//!   shadow ray, never clamped; `transport::direct`). The point lights are then only the light
//!   paths' surface vertices, and `C` drops emitter hits. With `--direct vpl` (the paper) `D = 0`
//!   and the emitter vertices are point lights clamped like the rest, `C` recovering their
//!   clamped part (why NEE: `docs/methods/iws.md`, "Departures from the spec").
//! - `VPL_b = Σ_v W_v·e_v·min(G,b)·V·f` over the pass's point lights (spec §2), with
//!   `G = |n_x·ŵ||n_y·ŵ|/r²` on **geometric** normals; Dirac surfaces block VPL shadow rays;
//!   scene point lights are never clamped (their `G = |n_x·ŵ|/r²`).
//! - `C`: one BSDF-sampled ray with weight `(G−b)/G` when `G > b`, limited to
//!   `t_max = sqrt(cosθ_x/b)`; 0 on a miss or a Dirac hit; at a non-specular hit (or, with
//!   `--direct vpl`, an emitter: `Le` is recovered here because emitter VPLs are clamped) it
//!   recurses into `L̂` with `d+1`, with Russian roulette at `d+1 ≥ 2` (spec §4 "Termination").
//! - `Ĺ_c`: a [`CausticEstimator`] (`integrators::iws::caustics`); `iws` uses [`NoCaustics`] (L_c
//!   omitted by design), `iws-pm` a photon map, `iws-cf` Caustic Forecasting.
//!
//! Invariants: the same `G` function in `min(G,b)` and `(G−b)/G` (spec §10); every `b > 0` is
//! unbiased; camera rays follow Dirac chains (Fresnel-weighted choice) to the first
//! non-specular vertex. The only cut is the 64-vertex / 64-diffuse-depth safety cap.
//! The point lights come from `integrators::iws::vpl`; chains from `transport::dirac`; roulette from
//! `transport::roulette`; timings go to the worker's `profile::Profile`.
//! Shading normals: the eye side carries `|ŵ·n_s|/|ŵ·n_g|` and indirect VPLs the adjoint factor
//! `|ω_in·n_s|/|ω_in·n_g|` (Veach eq. 5.19), so `G` itself stays geometric.

pub mod caustics;
pub mod vpl;

use super::{CameraEstimate, Context, Integrator, MethodArgs, MethodError, MethodSpec};
use crate::accel::{offset_origin, ray_epsilon, Hit, World};
use crate::bsdf::{self, Mode, ShadingPoint};
use crate::math::{Rgb, Vec3, PI};
use crate::profile::{Phase, Profile};
use crate::progress::Phases;
use crate::scene::{Material, NO_EMITTER};
use crate::transport::dirac::{environment, follow_dirac_chain, prefix_emission};
use crate::transport::direct;
use crate::transport::light_select::{LightSelector, RisParams, MAX_CANDIDATES, MAX_SURVIVORS};
use crate::transport::particle::MAX_VERTICES;
use crate::transport::roulette::{q_recursion, roulette};
use caustics::{CausticEstimator, NoCaustics, Recurse, ShadingQuery};
use std::time::Instant;
use vpl::{generate_vpls, Vpl, VplKind};

/// IWS parameters (shared by `iws`, `iws-pm` and `iws-cf`).
#[derive(clap::Args, Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct IwsArgs {
    /// Clamp bound b of the point lights (0 = pure bias compensation, inf = no clamping; any b
    /// is unbiased; default: 0.25·π·N over the scene's diffuse and glossy area, N = --vpl-paths).
    // The spec §2 default, `default_bound`.
    #[arg(long, value_name = "B", value_parser = parse_bound)]
    pub bound: Option<f32>,
    /// Light paths per pass, whose vertices are the pass's point lights.
    #[arg(long, value_name = "N", default_value_t = 32, value_parser = clap::value_parser!(u32).range(1..))]
    pub vpl_paths: u32,
    /// Point lights drawn per shading point as candidates, in proportion to their power
    /// (0 = every point light once).
    // RIS candidates M per reservoir.
    #[arg(long, value_name = "M", default_value_t = 8, value_parser = clap::value_parser!(u32).range(0..=(MAX_CANDIDATES as i64)))]
    pub ris_candidates: u32,
    /// Candidates kept per shading point, one shadow ray each.
    // RIS survivors K, from one shared candidate set.
    #[arg(long, value_name = "K", default_value_t = 2, value_parser = clap::value_parser!(u32).range(1..=(MAX_SURVIVORS as i64)))]
    pub ris_survivors: u32,
    /// The light sources' direct light: nee (a light sample and a shadow ray per vertex, never
    /// clamped) or vpl (as point lights clamped like the others, the papers' choice).
    #[arg(long, value_enum, default_value_t = DirectLight::Nee)]
    pub direct: DirectLight,
}

/// Which lobes of a vertex's material an estimate owns (spec §1 "Mixed materials"): all of
/// them where the camera or a Dirac chain arrives, only the non-Dirac ones where a compensation
/// ray arrives (light leaving by a Dirac lobe is `L_c`'s).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Lobes {
    All,
    NonDirac,
}

/// Where the IWS estimator gets the direct light of the scene's emitters (area and point lights).
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
// The values are described in `--direct`'s help: a value's doc comment would be its help text,
// which turns `render --help` into its long format.
#[allow(missing_docs)]
pub enum DirectLight {
    // Next-event estimation (`transport::direct`, light sampling only: an emitter ∝ power, a
    // point on it, one shadow ray); the point lights are then only the light paths' surface
    // vertices, and the compensation ray adds nothing when it hits an emitter.
    Nee,
    // [KK04, BAJ08]: the light paths' emitter vertices are point lights clamped by `b`, and the
    // compensation ray recovers the clamped emission when it hits an emitter.
    Vpl,
}

impl IwsArgs {
    /// The RIS parameters (ranges checked; the error names the option).
    pub fn ris(&self) -> Result<RisParams, MethodError> {
        RisParams::new(self.ris_candidates, self.ris_survivors, true)
            .map_err(|e| MethodError::option("--ris-candidates/--ris-survivors", e))
    }
}

/// Refuses `--direct vpl` (also `iws-cf --variant baj08`) in a scene with a spot, directional
/// or environment light: the emitter point lights have no direction profile nor a point at
/// infinity yet, so their direct light would be wrong or missing (docs/limitations.md).
pub fn check_direct(world: &World, args: &MethodArgs) -> Result<(), MethodError> {
    let s = &world.scene;
    if args.iws.direct == DirectLight::Vpl && (s.has_infinite_lights() || s.has_spot_lights()) {
        return Err(MethodError::option(
            "--direct",
            "`vpl` does not yet render spot, directional or environment lights (their emitter point lights are \
             not modelled); use --direct nee",
        ));
    }
    Ok(())
}

impl IwsArgs {
    /// The limits of `crate::param_limits`.
    pub fn validate(&self) -> Result<(), MethodError> {
        MethodError::check_limit(&crate::param_limits::VPL_PATHS, "--vpl-paths", self.vpl_paths.into())
    }
}

fn parse_bound(s: &str) -> Result<f32, String> {
    let t = s.trim();
    let b = if t.eq_ignore_ascii_case("inf") {
        f32::INFINITY
    } else {
        t.parse::<f32>().map_err(|_| format!("bad bound `{s}`"))?
    };
    if b.is_nan() || b < 0.0 {
        return Err(format!("bound `{s}` must be >= 0 (or `inf`)"));
    }
    Ok(b)
}

impl MethodSpec for Iws {
    type Product = ();
    fn preprocess(_: &World, _: &MethodArgs, _: u64, _: &dyn Phases) -> Result<(), MethodError> {
        Ok(())
    }
    fn build(world: &World, args: &MethodArgs, _: ()) -> Result<Box<dyn Integrator>, MethodError> {
        args.iws.ris()?;
        check_direct(world, args)?;
        Ok(Box::new(Iws::new(world, args, Box::new(NoCaustics))))
    }
}

/// The IWS integrator with a pluggable caustic estimator.
pub struct Iws {
    params: IwsArgs,
    /// Safety cap on camera-chain vertices.
    max_depth: u32,
    /// The clamp bound in use.
    b: f32,
    vpls: Vec<Vpl>,
    /// The pass's RIS source (∝ VPL power); `None` when no point light has power.
    selector: Option<LightSelector>,
    ris: RisParams,
    caustics: Box<dyn CausticEstimator>,
    passes: u64,
    vpls_total: u64,
    vpl_trace_ns: u64,
}

/// The spec §2 default bound `b = κ·π·N/A_D` with `κ = 0.25` (one clamped Lambertian VPL adds
/// at most ~17% of the mean radiance at ρ≈0.7). Infinite when the scene has no non-specular area.
pub fn default_bound(world: &World, vpl_paths: u32) -> f32 {
    let a_d = world.scene.non_specular_area();
    if a_d > 0.0 {
        0.25 * PI * vpl_paths as f32 / a_d
    } else {
        f32::INFINITY
    }
}

impl Iws {
    /// An IWS integrator with `args.iws` and the cap `args.settings`, and caustic term `caustics`.
    /// A negative or NaN `bound` is replaced by the default.
    pub fn new(world: &World, args: &MethodArgs, caustics: Box<dyn CausticEstimator>) -> Iws {
        let params = args.iws;
        let b = match params.bound {
            Some(b) if b >= 0.0 => b,
            _ => default_bound(world, params.vpl_paths.max(1)),
        };
        // 0 (a Mitsuba `max_depth` of 1): the emitters seen directly, as `pt`
        let max_depth = args.settings.cap();
        // out-of-range RIS parameters (API use; the CLI checks them) fall back to the nearest valid
        let ris = RisParams::new(
            params.ris_candidates.min(MAX_CANDIDATES),
            params.ris_survivors.clamp(1, MAX_SURVIVORS),
            true,
        )
        .expect("clamped RIS parameters are valid");
        Iws {
            params,
            max_depth,
            b,
            vpls: Vec::new(),
            selector: None,
            ris,
            caustics,
            passes: 0,
            vpls_total: 0,
            vpl_trace_ns: 0,
        }
    }

    /// One VPL's bounded contribution `Φ·f·min(G,b)·f_y` without visibility (the RIS target).
    #[inline]
    fn unshadowed(&self, x: &ShadingPoint, m: &Material, wo: Vec3, v: &Vpl) -> Rgb {
        let d = v.p - x.p;
        let r2 = d.length_squared();
        if r2 <= 0.0 {
            return Rgb::ZERO;
        }
        let w = d / r2.sqrt();
        let f = bsdf::eval(m, x, wo, w, Mode::Radiance);
        if f == Rgb::ZERO {
            return Rgb::ZERO;
        }
        let cos_x = x.ng.dot(w).abs();
        if cos_x <= 0.0 {
            return Rgb::ZERO;
        }
        // eye-side shading-normal factor
        let shade_x = w.dot(x.ns).abs() / cos_x;
        // spec §2: G = |n_x·ŵ||n_y·ŵ|/r² on geometric normals; min(G, b) except point lights
        let (e, g) = match v.kind {
            VplKind::Point => (Rgb::ONE, cos_x / r2),
            VplKind::Area => {
                let cos_y = v.ng.dot(-w);
                if cos_y <= 0.0 {
                    return Rgb::ZERO; // one-sided emitter
                }
                (Rgb::ONE, (cos_x * cos_y / r2).min(self.b))
            }
            VplKind::Surface(my) => {
                let sy = ShadingPoint { n0: v.n0, ..ShadingPoint::new(v.p, v.ng, v.ns) };
                let fy = bsdf::eval(&my, &sy, v.w_in, -w, Mode::Importance); // real BSDF, one-sided checks
                let cin_g = v.w_in.dot(v.ng).abs();
                if fy == Rgb::ZERO || cin_g <= 0.0 {
                    return Rgb::ZERO;
                }
                let adj = v.w_in.dot(v.ns).abs() / cin_g; // Veach eq. 5.19
                (fy * adj, (cos_x * v.ng.dot(w).abs() / r2).min(self.b))
            }
        };
        if g <= 0.0 {
            return Rgb::ZERO;
        }
        v.power * e * f * (g * shade_x)
    }

    /// One unbiased estimate of the direct light (NEE, with `--direct nee`) plus `VPL_b(x, ω_o)`
    /// (public for the estimator-level tests), the point lights chosen by RIS.
    pub fn gather(&self, world: &World, q: &ShadingQuery, ctx: &mut Context) -> Rgb {
        let (x, m, wo) = (q.x, q.m, q.wo);
        let n = self.vpls.len();
        let nee = self.params.direct == DirectLight::Nee;
        if n == 0 && !nee {
            return Rgb::ZERO;
        }
        let t0 = ctx.profile.start(Phase::Gather);
        ctx.profile.gather_vertices += 1;
        let mut l = Rgb::ZERO;
        if nee {
            // light sampling alone (MIS weight 1: no BSDF strategy counts emitter hits here)
            l += direct::sample_light_mis(world, x, m, wo, &mut ctx.rng, |_| 0.0);
            ctx.profile.gather_shadow_rays += 1;
        }
        if n > 0 {
            l += self.gather_vpls(world, q, ctx);
        }
        ctx.profile.record(Phase::Gather, t0);
        l
    }

    /// The exact point-light sum `Σ_v Φ·f·min(G,b)·f_y·V` over the pass's point lights, without
    /// NEE: the value the RIS gather estimates (the reference of its tests; one shadow ray per
    /// point light, so never used to render).
    pub fn gather_exact(&self, world: &World, q: &ShadingQuery) -> Rgb {
        let (x, m, wo) = (q.x, q.m, q.wo);
        let lit = |v: &&Vpl| world.visible(x.p, x.ng, v.p, v.ng);
        self.vpls
            .iter()
            .map(|v| (v, self.unshadowed(x, m, wo, v)))
            .filter(|(v, c)| *c != Rgb::ZERO && lit(v))
            .fold(Rgb::ZERO, |a, (_, c)| a + c)
    }

    /// `VPL_b` by RIS; 0 when no point light has power (then none contributes).
    fn gather_vpls(&self, world: &World, q: &ShadingQuery, ctx: &mut Context) -> Rgb {
        match &self.selector {
            Some(sel) => self.gather_ris(world, q, sel, ctx),
            None => Rgb::ZERO,
        }
    }

    /// `VPL_b` by RIS: `K` survivors of `M` power-proportional candidates, target
    /// `p̂ = Σ_rgb` of the unshadowed bounded contribution (zero exactly where it is), one shadow
    /// ray per survivor, weight `W/K` (`transport::light_select`).
    fn gather_ris(&self, world: &World, q: &ShadingQuery, sel: &LightSelector, ctx: &mut Context) -> Rgb {
        let (x, m, wo) = (q.x, q.m, q.wo);
        let mut l = Rgb::ZERO;
        let mut rays = 0u64;
        let target = |i: usize| {
            let c = self.unshadowed(x, m, wo, &self.vpls[i]);
            (c.x.max(0.0) + c.y.max(0.0) + c.z.max(0.0), c)
        };
        sel.select(&self.ris, &mut ctx.rng, target, |s| {
            rays += 1;
            let v = &self.vpls[s.index];
            if world.visible(x.p, x.ng, v.p, v.ng) {
                l += s.value * s.weight;
            }
        });
        ctx.profile.gather_shadow_rays += rays;
        l
    }

    /// Bias compensation `C(x, ω_o, d)` (spec §2): one BSDF ray, weight `(G−b)/G` if `G > b`.
    /// Where the sample picks a mixed material's Dirac lobe it is not compensation but that
    /// lobe's light (spec §1 "Mixed materials"): followed when `lobes` is [`Lobes::All`], 0 when
    /// the caller owns only the non-Dirac lobes ([`Lobes::NonDirac`]).
    fn compensate(&self, world: &World, q: &ShadingQuery, lobes: Lobes, ctx: &mut Context) -> Rgb {
        let (x, m, wo, depth) = (q.x, q.m, q.wo, q.depth);
        let u = ctx.rng.next_3d();
        if depth + 1 >= MAX_VERTICES || (self.b.is_infinite() && !m.has_mixed_lobes()) {
            return Rgb::ZERO;
        }
        let t0 = ctx.profile.start(Phase::Compensation);
        let Some(bs) = bsdf::sample(m, x, wo, u, Mode::Radiance) else {
            return Rgb::ZERO;
        };
        if bs.is_delta {
            ctx.profile.record(Phase::Compensation, t0);
            return match lobes {
                Lobes::All => self.dirac_lobe(world, q, bs.wi, bs.weight, ctx),
                Lobes::NonDirac => Rgb::ZERO,
            };
        }
        if self.b.is_infinite() {
            return Rgb::ZERO;
        }
        let cos_x = x.ng.dot(bs.wi).abs();
        if cos_x <= 0.0 {
            return Rgb::ZERO;
        }
        // G > b implies r² < cosθ_x/b (pbrt-v2 maxDist); slack for the origin offset
        let t_max = if self.b > 0.0 { (cos_x / self.b).sqrt() + 2.0 * ray_epsilon(x.p) } else { f32::INFINITY };
        ctx.profile.compensation_rays += 1;
        let hit = world.intersect(offset_origin(x.p, x.ng, bs.wi), bs.wi, t_max);
        ctx.profile.record(Phase::Compensation, t0);
        let Some(hit) = hit else {
            return Rgb::ZERO;
        };
        let s = &world.scene;
        let is_emitter = s.emitter_of(hit.prim) != NO_EMITTER;
        if !is_emitter && s.material_of(hit.prim).is_dirac() {
            return Rgb::ZERO; // spec §1: that energy belongs to L_c
        }
        if is_emitter && self.params.direct == DirectLight::Nee {
            return Rgb::ZERO; // NEE holds all of the direct light; nothing was clamped
        }
        let r2 = (hit.p - x.p).length_squared();
        if r2 <= 0.0 {
            return Rgb::ZERO;
        }
        let g = cos_x * hit.ng.dot(bs.wi).abs() / r2; // the same G as in `unshadowed`
        if g.is_nan() || g <= self.b {
            return Rgb::ZERO;
        }
        let w = bs.weight * ((g - self.b) / g);
        let Some(w) = roulette(w, q_recursion(w, depth + 1), &mut ctx.rng) else {
            return Rgb::ZERO;
        };
        w * self.radiance(world, &hit, -bs.wi, depth + 1, Lobes::NonDirac, ctx)
    }

    /// The light a mixed material's Dirac lobe brings to `q` along `wi` (sample weight `w`):
    /// the Dirac chain from there and `L̂` at its end. The recursion depth grows by one, which
    /// bounds it as compensation's is.
    fn dirac_lobe(&self, world: &World, q: &ShadingQuery, wi: Vec3, w: Rgb, ctx: &mut Context) -> Rgb {
        let Some(w) = roulette(w, q_recursion(w, q.depth + 1), &mut ctx.rng) else {
            return Rgb::ZERO;
        };
        let x = q.x;
        let Some(hit) = world.intersect(offset_origin(x.p, x.ng, wi), wi, f32::INFINITY) else {
            return Rgb::ZERO;
        };
        match follow_dirac_chain(world, hit, wi, w, MAX_VERTICES, &mut ctx.rng) {
            Some((Some(z), d, beta)) => beta * self.l_hat(world, &z, -d, q.depth + 1, ctx),
            Some((None, d, beta)) => beta * environment(world, d),
            None => Rgb::ZERO,
        }
    }

    /// `L̂` at `hit` seen from `wo` over `lobes` of its material: `Le` on emitters, 0 on Dirac
    /// materials, else [`Self::at_surface`].
    fn radiance(&self, world: &World, hit: &Hit, wo: Vec3, depth: u32, lobes: Lobes, ctx: &mut Context) -> Rgb {
        let s = &world.scene;
        let e = s.emitter_of(hit.prim);
        if e != NO_EMITTER {
            // emitters reflect nothing; one-sided emission
            return if hit.ng.dot(wo) > 0.0 { s.emitters[e as usize].radiance } else { Rgb::ZERO };
        }
        let (m, sp) = world.shade(hit, wo);
        if m.is_dirac() {
            return Rgb::ZERO;
        }
        self.at_surface(world, &ShadingQuery { x: &sp, m: &m, wo, depth }, lobes, ctx)
    }

    /// Estimator at a non-specular, non-emitting point.
    fn at_surface(&self, world: &World, q: &ShadingQuery, lobes: Lobes, ctx: &mut Context) -> Rgb {
        if q.m.is_black() {
            return Rgb::ZERO;
        }
        let mut l = self.gather(world, q, ctx);
        l += self.compensate(world, q, lobes, ctx);
        let t0 = ctx.profile.start(Phase::Caustics);
        let lc = self.caustics.estimate(world, q, ctx, self);
        ctx.profile.record(Phase::Caustics, t0);
        l + lc
    }
}

impl Recurse for Iws {
    fn l_hat(&self, world: &World, hit: &Hit, wo: Vec3, depth: u32, ctx: &mut Context) -> Rgb {
        self.radiance(world, hit, wo, depth, Lobes::All, ctx)
    }
}

impl Integrator for Iws {
    fn begin_pass(&mut self, world: &World, seed: u64, pass: u64) {
        let t0 = Instant::now();
        generate_vpls(world, self.params.vpl_paths as u64, seed, pass, &mut self.vpls);
        if self.params.direct == DirectLight::Nee {
            // the emitters' own vertices are NEE's (the surface VPLs' weights do not depend on them)
            self.vpls.retain(|v| matches!(v.kind, VplKind::Surface(_)));
        }
        let power = |v: &Vpl| v.power.x.max(0.0) + v.power.y.max(0.0) + v.power.z.max(0.0);
        self.selector = LightSelector::new(&self.vpls.iter().map(power).collect::<Vec<_>>());
        self.passes += 1;
        self.vpls_total += self.vpls.len() as u64;
        self.vpl_trace_ns += t0.elapsed().as_nanos() as u64;
    }

    fn estimate(&self, world: &World, origin: Vec3, dir: Vec3, ctx: &mut Context) -> CameraEstimate {
        let t0 = ctx.profile.start(Phase::Radiance);
        let mut l = CameraEstimate::default();
        if self.max_depth == 0 {
            // no surface vertex: the emitters (one-sided) and the environment seen directly
            l.prefix_le = prefix_emission(world, origin, dir, 1, &mut ctx.rng);
        } else if let Some(hit) = world.intersect(origin, dir, f32::INFINITY) {
            // the camera ray follows Dirac chains to the first non-specular vertex (spec §1)
            match follow_dirac_chain(world, hit, dir, Rgb::ONE, self.max_depth, &mut ctx.rng) {
                Some((Some(z), d, beta)) => {
                    let v = beta * self.l_hat(world, &z, -d, 0, ctx);
                    *if world.scene.emitter_of(z.prim) != NO_EMITTER { &mut l.prefix_le } else { &mut l.rest } = v;
                }
                Some((None, d, beta)) => l.prefix_le = beta * environment(world, d),
                None => {}
            }
        } else {
            l.prefix_le = environment(world, dir);
        }
        ctx.profile.samples += 1;
        ctx.profile.record(Phase::Radiance, t0);
        l
    }

    fn prefix_cap(&self) -> u32 {
        self.max_depth.clamp(1, MAX_VERTICES) // as `follow_dirac_chain`; cap 0 as `estimate`
    }

    fn stats(&self, profile: &Profile) -> serde_json::Value {
        let passes = self.passes.max(1) as f64;
        let samples = profile.samples.max(1) as f64;
        let total = profile.secs(Phase::Radiance);
        let (gather, caustic) = (profile.secs(Phase::Gather), profile.secs(Phase::Caustics));
        serde_json::json!({
            "b": self.b,
            "b_default": self.params.bound.is_none(),
            "vpl_paths_per_pass": self.params.vpl_paths,
            "direct": self.params.direct,
            "ris": self.ris,
            "profile_per_sample": profile.per_sample(),
            "point_lights_per_pass": self.vpls_total as f64 / passes,
            "compensation_rays_per_sample": profile.compensation_rays as f64 / samples,
            "timing_note": "cpu_s are summed over worker threads; compensation_and_rest = radiance - gather - caustics (caustics includes nested recursion for recursive L_c estimators)",
            "vpl_trace_s_per_pass": self.vpl_trace_ns as f64 * 1e-9 / passes,
            "radiance_cpu_s": total,
            "gather_cpu_s": gather,
            "caustics_cpu_s": caustic,
            "compensation_and_rest_cpu_s": (total - gather - caustic).max(0.0),
            "caustic_estimator": self.caustics.name(),
            "caustics": self.caustics.stats(profile),
        })
    }
}
