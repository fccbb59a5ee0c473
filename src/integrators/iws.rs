//! `iws`: Instant radiosity with bias compensation ("IWS", Kollig & Keller 2004 [KK04]; spec §1,
//! §2), the `L_d` half of the [BAJ08] split, with a pluggable caustic term `L_c`.
//!
//! At a non-specular point `x` the estimator is (spec §1)
//! `L̂(x,ω_o,d) = Le(x) + VPL_b(x,ω_o) + C(x,ω_o,d) + Ĺ_c(x,ω_o,d)`:
//! - `VPL_b = Σ_v W_v·e_v·min(G,b)·V·f` over the pass's point lights (spec §2), with
//!   `G = |n_x·ŵ||n_y·ŵ|/r²` on **geometric** normals; Dirac surfaces block VPL shadow rays;
//!   scene point lights are never clamped (their `G = |n_x·ŵ|/r²`).
//! - `C`: one BSDF-sampled ray with weight `(G−b)/G` when `G > b`, limited to
//!   `t_max = sqrt(cosθ_x/b)`; 0 on a miss or a Dirac hit; at a non-specular hit (or an
//!   emitter: `Le` is recovered here because direct VPLs are clamped) it recurses into `L̂` with
//!   `d+1`, with Russian roulette at `d+1 ≥ 2` (spec §4 "Termination").
//! - `Ĺ_c`: a [`CausticEstimator`]; `iws` uses [`NoCaustics`] (L_c omitted by design),
//!   `iws-pm` a photon map, `iws-cf` Caustic Forecasting. [`BsdfCaustics`] is the plain
//!   unbiased BSDF-sampled `L_c` (used by tests to check that the split is complete).
//!
//! Invariants: the same `G` function in `min(G,b)` and `(G−b)/G` (spec §10); every `b > 0` is
//! unbiased; camera rays follow Dirac chains (Fresnel-weighted choice) to the first
//! non-specular vertex. The only cut is the 64-vertex / 64-diffuse-depth safety cap.
//! Shading normals: the eye side carries `|ŵ·n_s|/|ŵ·n_g|` and indirect VPLs the adjoint factor
//! `|ω_in·n_s|/|ω_in·n_g|` (Veach eq. 5.19), so `G` itself stays geometric.

use super::Integrator;
use crate::accel::{offset_origin, ray_epsilon, Hit, World};
use crate::bsdf::{self, Mode, ShadingPoint};
use crate::math::{luminance, Rgb, Vec3, PI};
use crate::sampling::rng::{stream, Rng};
use crate::scene::{Material, NO_EMITTER};
use crate::transport::particle::{self, Emission, EmitterVertex, ParticleVisitor, SurfaceVertex, MAX_VERTICES};
use std::cell::Cell;
use std::sync::atomic::{AtomicU64, Ordering::Relaxed};
use std::time::Instant;

/// Chain vertices after which Russian roulette may end a Dirac chain (as `pt`).
const CHAIN_RR_VERTICES: u32 = 5;

/// Full estimator `L̂(y, ω_o, d)` at a hit, given to caustic estimators so that Dirac chains
/// ending at a non-specular vertex can recurse (spec §1 "Chain following").
pub trait Recurse {
    /// `L̂(y→ω_o)` at `hit` with diffuse depth `depth`: `Le` on emitters, the full estimator at
    /// non-specular hits, 0 on Dirac hits.
    fn l_hat(&self, world: &World, hit: &Hit, wo: Vec3, depth: u32, rng: &mut Rng) -> Rgb;
}

/// The caustic term `Ĺ_c(x, ω_o, d)` plugged into the IWS recursion (spec §1).
pub trait CausticEstimator: Send + Sync {
    /// Short name for the stats.
    fn name(&self) -> &'static str;
    /// One estimate of `L_c` at the non-specular point `x` (material `m`) toward `wo`, at
    /// diffuse depth `depth`; `full` evaluates `L̂` at chain ends.
    #[allow(clippy::too_many_arguments)]
    fn estimate(
        &self,
        world: &World,
        x: &ShadingPoint,
        m: &Material,
        wo: Vec3,
        depth: u32,
        rng: &mut Rng,
        full: &dyn Recurse,
    ) -> Rgb;
    /// Statistics for the JSON report.
    fn stats(&self) -> serde_json::Value {
        serde_json::json!({})
    }
}

/// `Ĺ_c = 0`: the plain `iws` method ("Total Without Caustics").
pub struct NoCaustics;

impl CausticEstimator for NoCaustics {
    fn name(&self) -> &'static str {
        "none"
    }
    fn estimate(
        &self,
        _: &World,
        _: &ShadingPoint,
        _: &Material,
        _: Vec3,
        _: u32,
        _: &mut Rng,
        _: &dyn Recurse,
    ) -> Rgb {
        Rgb::ZERO
    }
    fn stats(&self) -> serde_json::Value {
        serde_json::json!({ "caustics": "omitted (L_c not estimated)" })
    }
}

/// Unbiased `Ĺ_c` by one BSDF-sampled direction: it counts only if the first hit is Dirac
/// (spec §1), then follows the chain and evaluates `L̂` at its end (what CF does outside kept
/// clusters, spec §4). Noisy but exact; used to test the completeness of the split.
pub struct BsdfCaustics;

impl CausticEstimator for BsdfCaustics {
    fn name(&self) -> &'static str {
        "bsdf"
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
        let u = [rng.next_f32(), rng.next_f32(), rng.next_f32()];
        let Some(bs) = bsdf::sample(m, x, wo, u, Mode::Radiance) else {
            return Rgb::ZERO;
        };
        caustic_chain(world, x, bs.wi, bs.weight, depth, rng, full)
    }
}

/// The L_c integrand along `wi` from `x`, times `weight` (f·|cos|/p or f·|cos|): 0 unless the
/// first hit is Dirac (spec §1: L_d owns diffuse and emitter first hits); else RR, the Dirac
/// chain, and `L̂` at its end with diffuse depth + 1.
pub fn caustic_chain(
    world: &World,
    x: &ShadingPoint,
    wi: Vec3,
    weight: Rgb,
    depth: u32,
    rng: &mut Rng,
    full: &dyn Recurse,
) -> Rgb {
    let Some(hit) = world.intersect(offset_origin(x.p, x.ng, wi), wi, f32::INFINITY) else {
        return Rgb::ZERO;
    };
    if world.scene.emitter_of(hit.prim) != NO_EMITTER || !world.scene.material_of(hit.prim).is_dirac() {
        return Rgb::ZERO;
    }
    let Some(w) = rr_weight(weight, depth + 1, rng) else {
        return Rgb::ZERO;
    };
    match follow_dirac_chain(world, hit, wi, w, MAX_VERTICES, rng) {
        Some((z, d, beta)) => beta * full.l_hat(world, &z, -d, depth + 1, rng),
        None => Rgb::ZERO,
    }
}

/// Russian roulette on a recursive `L̂` call (spec §4 "Termination"): at `depth ≥ 2`,
/// survive with `q = clamp(lum(weight), 0.05, 0.95)` and return `weight/q`.
#[inline]
pub fn rr_weight(weight: Rgb, depth: u32, rng: &mut Rng) -> Option<Rgb> {
    if depth < 2 {
        return Some(weight);
    }
    let q = luminance(weight).clamp(0.05, 0.95);
    (rng.next_f32() < q).then(|| weight / q)
}

/// Follows a Dirac chain from `hit` (reached along `d`) with throughput `beta`: Fresnel-weighted
/// choice at glass, RR after [`CHAIN_RR_VERTICES`]. Returns the first non-Dirac hit (possibly an
/// emitter), the direction that reached it and the throughput; `None` on escape, absorption or
/// the vertex cap `cap` (at most [`MAX_VERTICES`]).
pub fn follow_dirac_chain(
    world: &World,
    mut hit: Hit,
    mut d: Vec3,
    mut beta: Rgb,
    cap: u32,
    rng: &mut Rng,
) -> Option<(Hit, Vec3, Rgb)> {
    let s = &world.scene;
    for v in 0..cap.min(MAX_VERTICES) {
        let m = s.material_of(hit.prim);
        if s.emitter_of(hit.prim) != NO_EMITTER || !m.is_dirac() {
            return Some((hit, d, beta));
        }
        let sp = ShadingPoint { p: hit.p, ng: hit.ng, ns: hit.ns };
        let u = [rng.next_f32(), rng.next_f32(), rng.next_f32()];
        let bs = bsdf::sample(m, &sp, -d, u, Mode::Radiance)?;
        beta *= bs.weight;
        if v + 1 >= CHAIN_RR_VERTICES {
            let q = beta.max_element().min(0.95);
            if q <= 0.0 || rng.next_f32() >= q {
                return None;
            }
            beta /= q;
        }
        d = bs.wi;
        hit = world.intersect(offset_origin(hit.p, hit.ng, d), d, f32::INFINITY)?;
    }
    None
}

/// What a point light is.
#[derive(Clone, Copy, Debug, PartialEq)]
enum VplKind {
    /// On an area emitter: profile `Le`, clamped.
    Area,
    /// A scene point light: intensity, never clamped.
    Point,
    /// At a non-specular light-path vertex: profile `f(y, ω_in, ·)`, clamped.
    Surface(Material),
}

/// One point light of a pass.
#[derive(Clone, Copy, Debug)]
struct Vpl {
    p: Vec3,
    ng: Vec3,
    ns: Vec3,
    w_in: Vec3,
    /// `W0·Le`, `W0·I` or `β/N`.
    power: Rgb,
    kind: VplKind,
}

#[derive(Default)]
struct VplCollector(Vec<Vpl>);

impl ParticleVisitor for VplCollector {
    fn emitter(&mut self, v: &EmitterVertex) {
        let kind = if v.point { VplKind::Point } else { VplKind::Area };
        self.0.push(Vpl { p: v.p, ng: v.n, ns: v.n, w_in: v.n, power: v.emission * v.weight, kind });
    }
    fn surface(&mut self, v: &SurfaceVertex) -> bool {
        if !v.material.is_black() {
            let kind = VplKind::Surface(*v.material);
            self.0.push(Vpl { p: v.p, ng: v.ng, ns: v.ns, w_in: v.w_in, power: v.beta, kind });
        }
        true
    }
}

/// IWS parameters (see `MethodOptions`).
#[derive(Clone, Copy, Debug)]
pub struct IwsParams {
    /// Light paths per pass `N`.
    pub vpl_paths: u32,
    /// Clamp bound `b` (None: spec §2 default `0.25·π·N/A_D`).
    pub bound: Option<f32>,
    /// VPLs evaluated at diffuse depth ≥ 1 (uniform subset with replacement, weight `N_v/m`; 0: all).
    pub vpl_subset: u32,
    /// Safety cap on camera-chain vertices.
    pub max_depth: u32,
}

thread_local! {
    /// Per-thread (compensation rays, gather ns, caustic ns) of the current sample.
    static LOCAL: Cell<(u64, u64, u64)> = const { Cell::new((0, 0, 0)) };
}

#[inline]
fn bump(comp: u64, gather_ns: u64, caustic_ns: u64) {
    LOCAL.with(|c| {
        let (a, b, d) = c.get();
        c.set((a + comp, b + gather_ns, d + caustic_ns));
    });
}

/// The IWS integrator with a pluggable caustic estimator.
pub struct Iws {
    name: &'static str,
    params: IwsParams,
    /// The clamp bound in use.
    b: f32,
    vpls: Vec<Vpl>,
    caustics: Box<dyn CausticEstimator>,
    passes: AtomicU64,
    vpls_total: AtomicU64,
    vpl_trace_ns: AtomicU64,
    samples: AtomicU64,
    comp_rays: AtomicU64,
    gather_ns: AtomicU64,
    caustic_ns: AtomicU64,
    radiance_ns: AtomicU64,
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
    /// An IWS integrator named `name` (`iws`, `iws-pm`, ...) with caustic term `caustics`.
    /// A negative or NaN `bound` is replaced by the default.
    pub fn new(name: &'static str, world: &World, params: IwsParams, caustics: Box<dyn CausticEstimator>) -> Iws {
        let b = match params.bound {
            Some(b) if b >= 0.0 => b,
            _ => default_bound(world, params.vpl_paths.max(1)),
        };
        Iws {
            name,
            params,
            b,
            vpls: Vec::new(),
            caustics,
            passes: AtomicU64::new(0),
            vpls_total: AtomicU64::new(0),
            vpl_trace_ns: AtomicU64::new(0),
            samples: AtomicU64::new(0),
            comp_rays: AtomicU64::new(0),
            gather_ns: AtomicU64::new(0),
            caustic_ns: AtomicU64::new(0),
            radiance_ns: AtomicU64::new(0),
        }
    }

    /// The clamp bound `b` in use.
    pub fn bound(&self) -> f32 {
        self.b
    }

    /// Number of point lights in the current pass.
    pub fn vpl_count(&self) -> usize {
        self.vpls.len()
    }

    /// One VPL's bounded contribution at `x` (spec §2 `VPL_b` term, before the weight).
    #[inline]
    fn vpl_term(&self, world: &World, x: &ShadingPoint, m: &Material, wo: Vec3, v: &Vpl) -> Rgb {
        let d = v.p - x.p;
        let r2 = d.length_squared();
        if r2 <= 0.0 {
            return Rgb::ZERO;
        }
        let w = d / r2.sqrt();
        let f = bsdf::eval(m, x, wo, w);
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
                let sy = ShadingPoint { p: v.p, ng: v.ng, ns: v.ns };
                let fy = bsdf::eval(&my, &sy, v.w_in, -w); // real BSDF, one-sided checks
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
        let c = v.power * e * f * (g * shade_x);
        if c == Rgb::ZERO || !world.visible(x.p, x.ng, v.p, v.ng) {
            return Rgb::ZERO; // Dirac surfaces are opaque to VPL shadow rays (spec §1)
        }
        c
    }

    /// `VPL_b(x, ω_o)`: all VPLs at depth 0, a uniform subset (weight `N_v/m`) deeper.
    fn gather(&self, world: &World, x: &ShadingPoint, m: &Material, wo: Vec3, depth: u32, rng: &mut Rng) -> Rgb {
        let n = self.vpls.len();
        if n == 0 {
            return Rgb::ZERO;
        }
        let t0 = Instant::now();
        let m_sub = self.params.vpl_subset as usize;
        let mut l = Rgb::ZERO;
        if depth == 0 || m_sub == 0 || m_sub >= n {
            for v in &self.vpls {
                l += self.vpl_term(world, x, m, wo, v);
            }
        } else {
            // spec §2 "Cost control": unbiased uniform subset with replacement
            for _ in 0..m_sub {
                let v = &self.vpls[rng.below(n as u32) as usize];
                l += self.vpl_term(world, x, m, wo, v);
            }
            l *= n as f32 / m_sub as f32;
        }
        bump(0, t0.elapsed().as_nanos() as u64, 0);
        l
    }

    /// Bias compensation `C(x, ω_o, d)` (spec §2): one BSDF ray, weight `(G−b)/G` if `G > b`.
    fn compensate(&self, world: &World, x: &ShadingPoint, m: &Material, wo: Vec3, depth: u32, rng: &mut Rng) -> Rgb {
        let u = [rng.next_f32(), rng.next_f32(), rng.next_f32()];
        if self.b.is_infinite() || depth + 1 >= MAX_VERTICES {
            return Rgb::ZERO;
        }
        let Some(bs) = bsdf::sample(m, x, wo, u, Mode::Radiance) else {
            return Rgb::ZERO;
        };
        let cos_x = x.ng.dot(bs.wi).abs();
        if cos_x <= 0.0 {
            return Rgb::ZERO;
        }
        // G > b implies r² < cosθ_x/b (pbrt-v2 maxDist); slack for the origin offset
        let t_max = if self.b > 0.0 { (cos_x / self.b).sqrt() + 2.0 * ray_epsilon(x.p) } else { f32::INFINITY };
        bump(1, 0, 0);
        let Some(hit) = world.intersect(offset_origin(x.p, x.ng, bs.wi), bs.wi, t_max) else {
            return Rgb::ZERO;
        };
        let s = &world.scene;
        let is_emitter = s.emitter_of(hit.prim) != NO_EMITTER;
        if !is_emitter && s.material_of(hit.prim).is_dirac() {
            return Rgb::ZERO; // spec §1: that energy belongs to L_c
        }
        let r2 = (hit.p - x.p).length_squared();
        if r2 <= 0.0 {
            return Rgb::ZERO;
        }
        let g = cos_x * hit.ng.dot(bs.wi).abs() / r2; // the same G as in vpl_term
        if g.is_nan() || g <= self.b {
            return Rgb::ZERO;
        }
        let w = bs.weight * ((g - self.b) / g);
        let Some(w) = rr_weight(w, depth + 1, rng) else {
            return Rgb::ZERO;
        };
        w * self.l_hat(world, &hit, -bs.wi, depth + 1, rng)
    }

    /// Estimator at a non-specular, non-emitting point.
    fn at_surface(&self, world: &World, x: &ShadingPoint, m: &Material, wo: Vec3, depth: u32, rng: &mut Rng) -> Rgb {
        if m.is_black() {
            return Rgb::ZERO;
        }
        let mut l = self.gather(world, x, m, wo, depth, rng);
        l += self.compensate(world, x, m, wo, depth, rng);
        let t0 = Instant::now();
        let lc = self.caustics.estimate(world, x, m, wo, depth, rng, self);
        bump(0, 0, t0.elapsed().as_nanos() as u64);
        l + lc
    }
}

impl Recurse for Iws {
    fn l_hat(&self, world: &World, hit: &Hit, wo: Vec3, depth: u32, rng: &mut Rng) -> Rgb {
        let s = &world.scene;
        let e = s.emitter_of(hit.prim);
        if e != NO_EMITTER {
            // emitters reflect nothing; one-sided emission
            return if hit.ng.dot(wo) > 0.0 { s.emitters[e as usize].radiance } else { Rgb::ZERO };
        }
        let m = s.material_of(hit.prim);
        if m.is_dirac() {
            return Rgb::ZERO;
        }
        let sp = ShadingPoint { p: hit.p, ng: hit.ng, ns: hit.ns };
        self.at_surface(world, &sp, m, wo, depth, rng)
    }
}

impl Integrator for Iws {
    fn name(&self) -> &'static str {
        self.name
    }

    fn begin_pass(&mut self, world: &World, seed: u64, pass: u64) {
        let t0 = Instant::now();
        let mut c = VplCollector(std::mem::take(&mut self.vpls));
        c.0.clear();
        let n = self.params.vpl_paths as u64;
        particle::trace_paths(world, Emission::Cosine, n, seed, stream::VPL, pass, &mut c);
        self.vpls = c.0;
        self.passes.fetch_add(1, Relaxed);
        self.vpls_total.fetch_add(self.vpls.len() as u64, Relaxed);
        self.vpl_trace_ns.fetch_add(t0.elapsed().as_nanos() as u64, Relaxed);
    }

    fn radiance(&self, world: &World, origin: Vec3, dir: Vec3, rng: &mut Rng) -> Rgb {
        let t0 = Instant::now();
        LOCAL.with(|c| c.set((0, 0, 0)));
        let cap = if self.params.max_depth == 0 { MAX_VERTICES } else { self.params.max_depth };
        let mut l = Rgb::ZERO;
        if let Some(hit) = world.intersect(origin, dir, f32::INFINITY) {
            // the camera ray follows Dirac chains to the first non-specular vertex (spec §1)
            if let Some((z, d, beta)) = follow_dirac_chain(world, hit, dir, Rgb::ONE, cap, rng) {
                l = beta * self.l_hat(world, &z, -d, 0, rng);
            }
        }
        let (comp, g_ns, c_ns) = LOCAL.with(|c| c.get());
        self.samples.fetch_add(1, Relaxed);
        self.comp_rays.fetch_add(comp, Relaxed);
        self.gather_ns.fetch_add(g_ns, Relaxed);
        self.caustic_ns.fetch_add(c_ns, Relaxed);
        self.radiance_ns.fetch_add(t0.elapsed().as_nanos() as u64, Relaxed);
        l
    }

    fn stats(&self) -> serde_json::Value {
        let passes = self.passes.load(Relaxed).max(1) as f64;
        let samples = self.samples.load(Relaxed).max(1) as f64;
        let ns = |a: &AtomicU64| a.load(Relaxed) as f64 * 1e-9;
        let (total, gather, caustic) = (ns(&self.radiance_ns), ns(&self.gather_ns), ns(&self.caustic_ns));
        serde_json::json!({
            "b": self.b,
            "b_default": self.params.bound.is_none(),
            "vpl_paths_per_pass": self.params.vpl_paths,
            "vpl_subset_deeper": self.params.vpl_subset,
            "point_lights_per_pass": self.vpls_total.load(Relaxed) as f64 / passes,
            "compensation_rays_per_sample": self.comp_rays.load(Relaxed) as f64 / samples,
            "timing_note": "cpu_s are summed over worker threads; compensation_and_rest = radiance - gather - caustics (caustics includes nested recursion for recursive L_c estimators)",
            "vpl_trace_s_per_pass": ns(&self.vpl_trace_ns) / passes,
            "radiance_cpu_s": total,
            "gather_cpu_s": gather,
            "caustics_cpu_s": caustic,
            "compensation_and_rest_cpu_s": (total - gather - caustic).max(0.0),
            "caustic_estimator": self.caustics.name(),
            "caustics": self.caustics.stats(),
        })
    }
}
