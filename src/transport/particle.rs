//! The one particle (light-path) tracer behind the preprocesses' and passes' light paths: IWS
//! point lights (VPLs), the caustic photon map and the caustic forecasters; `pt-cf`'s light
//! paths launch with its [`Emission`] samplers and bounce with the same roulette.
//!
//! A path is launched from a light picked with probability `P_ℓ ∝ power`, at a point `y0` with
//! area pdf `p_A` (`Scene::sample_emitter_point`), in a direction drawn by an [`Emission`]
//! sampler (cosine for area lights, uniform sphere for point lights, the cone for spot lights);
//! a light at infinity (directional, environment) starts it on the disk of the scene's bounding
//! sphere perpendicular to its direction ([`emit`], `scene::BoundingSphere::disk_origin`). It then bounces by BSDF
//! sampling in `Mode::Importance` (no η² scaling, adjoint shading-normal correction) and reports
//! events to a [`ParticleVisitor`] (spec §2 "VPL generation", §6 "Caustic map"):
//! - [`EmitterVertex`]: the direct point light at `y0`, weight `W0 = 1/(N·P_ℓ·p_A)` (spec §2;
//!   `p_A = 1` for point lights);
//! - [`SurfaceVertex`]: every non-specular hit, also after Dirac bounces, with `β/N`. A vertex
//!   with `prev_dirac` is a **caustic point** (spec §1/§6: "previous vertex Dirac").
//!
//! Invariants: every weight is normalised by the number of paths **launched** (`n_paths`), not
//! by the number of events; nothing is reported at Dirac vertices; randomness is a pure function
//! of (seed, stream, pass, path index). Russian roulette uses `q = min(1, lum(f·|cos|/p))` (spec
//! §2, pbrt-v2 `igi.cpp`); the only cut is the documented 64-vertex safety cap ([`MAX_VERTICES`]),
//! whose truncated energy is below `Π q ≤ 0.95^64`-scale for any physical scene. A path ends at
//! a Dirac vertex whose two ends see two shading normals ([`reciprocal`]): the transport it
//! would carry on is none that `pt` measures.

use super::roulette::{q_particle, roulette};
use super::target::{Cones, Targets};
use crate::accel::{offset_origin, Hit, World};
use crate::bsdf::{self, Mode, ShadingPoint};
use crate::math::{Frame, Rgb, Vec3};
use crate::sampling::rng::Rng;
use crate::sampling::warp::{cosine_hemisphere_pdf, sample_cosine_hemisphere};
use crate::scene::{LightRef, Material, PointLight, Scene, NO_EMITTER};

/// Safety cap on vertices per light path (documented truncation; RR does the real work).
pub const MAX_VERTICES: u32 = 64;

/// How the first direction of a light path is drawn.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Emission {
    /// The light's own: cosine-weighted hemisphere around the emitter normal (area lights),
    /// uniform sphere (point lights) or cone (spot lights); lights at infinity always draw their
    /// own direction ([`emit`]).
    #[default]
    Cosine,
    /// Uniform over the cones subtended by a few spheres around the Dirac objects
    /// (`transport::target`): targeted shooting for caustic forecasters only, never for VPLs
    /// [BAJ08 §3.2]; a light at infinity starts its paths in the spheres' shadows instead. Falls back to `Cosine` when the light point is inside a sphere. The pdf is
    /// the true one, so forecaster powers stay physically weighted (spec §3).
    Targeted(Targets),
}

impl Emission {
    /// Samples a launch direction from `y`, with normal `n` on an area light (`point: None`) or
    /// from the point or spot light `point`; returns `(ω, pdf_w)`, or `None` when the sampler
    /// produced no usable direction.
    #[inline]
    pub fn sample_dir(&self, y: Vec3, n: Vec3, point: Option<&PointLight>, u: [f32; 2]) -> Option<(Vec3, f32)> {
        if let Some(cones) = self.cones(y) {
            return cones.sample(u);
        }
        if let Some(pl) = point {
            Some(pl.sample_dir(u))
        } else {
            let l = sample_cosine_hemisphere(u);
            let pdf_w = cosine_hemisphere_pdf(l.z);
            (pdf_w > 0.0).then(|| (Frame::from_normal(n).to_world(l), pdf_w))
        }
    }

    /// The solid-angle pdf with which [`Emission::sample_dir`] draws `w` (arguments as there):
    /// the cones' pdf (0 outside them), or the fallback's (`pt-cf`'s camera-side MIS weight
    /// against its light paths).
    pub fn pdf_dir(&self, y: Vec3, n: Vec3, point: Option<&PointLight>, w: Vec3) -> f32 {
        if let Some(cones) = self.cones(y) {
            return cones.pdf(w);
        }
        if let Some(pl) = point {
            pl.pdf_dir(w)
        } else {
            cosine_hemisphere_pdf(n.dot(w)).max(0.0)
        }
    }

    /// Where a light path from a light at infinity along `d` starts, and its area pdf: the
    /// bounding sphere's disk (`Cosine`), or the spheres' shadows on its plane (`Targeted`,
    /// `Targets::sample_beam`).
    #[inline]
    pub fn beam_origin(&self, s: &Scene, d: Vec3, u: [f32; 2]) -> (Vec3, f32) {
        match self {
            Emission::Cosine => s.bsphere.disk_origin(d, u),
            Emission::Targeted(t) => t.sample_beam(s.bsphere.center - d * s.bsphere.radius, d, u),
        }
    }

    /// The area pdf with which [`Emission::beam_origin`] starts a path along `d` on the line
    /// through `p`.
    #[inline]
    pub fn beam_pdf(&self, s: &Scene, d: Vec3, p: Vec3) -> f32 {
        match self {
            Emission::Cosine => 1.0 / s.bsphere.disk_area(),
            Emission::Targeted(t) => t.beam_pdf(s.bsphere.center - d * s.bsphere.radius, d, p),
        }
    }

    /// The targeted cones seen from `y` (`None`: not targeted, or `y` inside a sphere).
    #[inline]
    fn cones(&self, y: Vec3) -> Option<Cones> {
        match self {
            Emission::Targeted(t) => t.cones(y),
            Emission::Cosine => None,
        }
    }
}

/// A light's emission for one light path, the one formula of every light path's start
/// (`launch` here, `pt-cf`'s light side): the light vertex, and the first ray with its β.
#[derive(Clone, Copy, Debug)]
pub struct Emitted {
    /// The light vertex at a point (area, point and spot lights; `None` at infinity) and its
    /// `P_ℓ·p_A` (`p_A = 1` for a point light).
    pub vertex: Option<(EmitterVertex, f32)>,
    /// The first ray and `β1` (`None`: the direction sample failed or carries nothing).
    pub ray: Option<(Vec3, Vec3, Rgb)>,
    /// For an area light, `P_ℓ·p_A·p_σ/cos θ0` of the ray, for the environment `P_ℓ·p_disk·p_σ`
    /// (`pt-cf`'s MIS); `None` for lights the camera side never hits (point, spot, directional).
    pub density: Option<f32>,
}

/// The emission of light `li` (picked with probability `pmf`) from the uniforms `u_pos` (the
/// point, or the disk point of a light at infinity) and `u_dir` (the direction). Spec §2:
/// `β1 = Le·cosθ0/(P_ℓ·p_A·p_σ)` (area), `I(ω)/(P_ℓ·p_σ)` (point, spot), `E·πr²/P_ℓ`
/// (directional), `L(−ω)·πr²/(P_ℓ·p_σ)` (environment, `ω` drawn by its sampler toward the
/// environment, the ray along `−ω` from the bounding sphere's disk). The vertex's `weight` is
/// left 1 (the caller normalises).
pub fn emit(s: &Scene, emission: Emission, li: usize, pmf: f32, u_pos: [f32; 2], u_dir: [f32; 2]) -> Emitted {
    let none = Emitted { vertex: None, ray: None, density: None };
    match s.lights[li] {
        LightRef::Area(e) => {
            let (y, n, pdf_a) = s.sample_emitter_point(e, u_pos);
            if pdf_a <= 0.0 {
                return none;
            }
            let le = s.emitters[e as usize].radiance;
            let v = EmitterVertex { p: y, n, weight: 1.0, emission: le, point: false };
            let mut out = Emitted { vertex: Some((v, pmf * pdf_a)), ..none };
            let Some((w, pdf_w)) = emission.sample_dir(y, n, None, u_dir) else { return out };
            let cos0 = n.dot(w);
            if cos0 <= 0.0 {
                return out;
            }
            let p = pmf * pdf_a * pdf_w;
            out.ray = Some((offset_origin(y, n, w), w, le * (cos0 / p)));
            out.density = Some(p / cos0);
            out
        }
        LightRef::Point(i) => {
            let pl = &s.point_lights[i as usize];
            let p = pl.position;
            let v = EmitterVertex { p, n: Vec3::ZERO, weight: 1.0, emission: pl.intensity, point: true };
            let mut out = Emitted { vertex: Some((v, pmf)), ..none };
            let Some((w, pdf_w)) = emission.sample_dir(p, Vec3::Z, Some(pl), u_dir) else { return out };
            let i = pl.intensity_toward(w);
            if pdf_w > 0.0 && i != Rgb::ZERO {
                out.ray = Some((p, w, i / (pmf * pdf_w)));
            }
            out
        }
        LightRef::Directional(i) => {
            let dl = &s.directional_lights[i as usize];
            let (o, pdf_a) = emission.beam_origin(s, dl.d, u_pos);
            if pdf_a <= 0.0 {
                return none;
            }
            Emitted { ray: Some((o, dl.d, dl.irradiance / (pmf * pdf_a))), ..none }
        }
        LightRef::Environment => {
            let Some(env) = &s.environment else { return none };
            let Some((w, pdf_w)) = env.sample(u_dir) else { return none };
            let (o, pdf_a) = emission.beam_origin(s, -w, u_pos);
            if pdf_a <= 0.0 {
                return none;
            }
            let p = pmf * pdf_a * pdf_w;
            Emitted { ray: Some((o, -w, env.radiance(w) / p)), density: Some(p), ..none }
        }
    }
}

/// The light-source vertex of a path: a "direct point light" (spec §2).
#[derive(Clone, Copy, Debug)]
pub struct EmitterVertex {
    /// Position `y0`.
    pub p: Vec3,
    /// Emitting-side geometric normal (unused for point lights).
    pub n: Vec3,
    /// `W0 = 1/(N·P_ℓ·p_A)` (`p_A` = 1 for point lights).
    pub weight: f32,
    /// Emitted radiance `Le` (area lights) or intensity `I` (point lights).
    pub emission: Rgb,
    /// True for a point light (never clamped by IWS).
    pub point: bool,
}

/// A non-specular hit of a light path (an indirect VPL; a caustic point if `prev_dirac`).
#[derive(Clone, Copy, Debug)]
pub struct SurfaceVertex<'a> {
    /// Position.
    pub p: Vec3,
    /// Geometric normal as the shape defines it.
    pub ng: Vec3,
    /// Shading normal (on the `ng` side).
    pub ns: Vec3,
    /// Shading normal before a normal map (`ShadingPoint::n0`).
    pub n0: Vec3,
    /// Material at the hit (never Dirac).
    pub material: &'a Material,
    /// Direction toward the previous vertex (unit, away from the surface).
    pub w_in: Vec3,
    /// Path throughput `β/N` (flux carried, normalised by the paths launched).
    pub beta: Rgb,
    /// The previous vertex was Dirac (a caustic point, spec §1).
    pub prev_dirac: bool,
    /// Index of this vertex on the path (1 = first hit after the light).
    pub depth: u32,
}

/// Receives the events of traced light paths.
pub trait ParticleVisitor {
    /// The light vertex of each launched path.
    fn emitter(&mut self, _v: &EmitterVertex) {}
    /// Each non-specular hit. Return `false` to stop this path early (for consumers that only
    /// want the first events; stopping never changes the weights already reported).
    fn surface(&mut self, _v: &SurfaceVertex) -> bool {
        true
    }
}

/// Counters of a batch of traced paths.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct TraceCounts {
    /// Paths launched (the normaliser N).
    pub paths: u64,
    /// Emitter vertices reported.
    pub emitter_vertices: u64,
    /// Non-specular surface vertices reported.
    pub surface_vertices: u64,
    /// Of those, vertices after a Dirac vertex (caustic points).
    pub caustic_vertices: u64,
    /// Paths cut by the vertex cap.
    pub capped: u64,
    /// Paths ended at a Dirac vertex whose two ends see two shading normals ([`reciprocal`]).
    pub non_reciprocal: u64,
}

/// A batch of light paths: path `i` is a pure function of these and `i`.
#[derive(Clone, Copy, Debug)]
pub struct LightPaths {
    /// How the first direction is sampled.
    pub emission: Emission,
    /// Paths in the batch (the normaliser N).
    pub n_paths: u64,
    /// Run seed.
    pub seed: u64,
    /// Random stream (`sampling::rng::stream`).
    pub stream_id: u64,
    /// Pass (0 for one-off preprocesses).
    pub pass: u64,
}

/// Traces light path `index` of `paths` with the random stream
/// `(seed, stream_id, pass, index)` and reports its events to `visitor`.
pub fn trace_path(
    world: &World,
    paths: &LightPaths,
    index: u64,
    visitor: &mut dyn ParticleVisitor,
    counts: &mut TraceCounts,
) {
    let LightPaths { emission, n_paths, seed, stream_id, pass } = *paths;
    counts.paths += 1;
    if world.scene.lights.is_empty() || n_paths == 0 {
        return;
    }
    let mut rng = Rng::keyed(seed, stream_id, pass, index);
    let inv_n = 1.0 / n_paths as f32;
    let Some(start) = launch(&world.scene, emission, inv_n, &mut rng, visitor, counts) else {
        return;
    };
    follow(world, start, inv_n, &mut rng, visitor, counts);
}

/// The first segment of a light path: the ray leaving the light and its throughput β1.
struct Launch {
    origin: Vec3,
    dir: Vec3,
    beta: Rgb,
}

/// Picks a light (`P_ℓ ∝ power`), reports its vertex (`W0 = 1/(N·P_ℓ·p_A)`, spec §2; none for
/// a light at infinity), and draws the first ray ([`emit`]); `None` when the path carries
/// nothing.
fn launch(
    s: &Scene,
    emission: Emission,
    inv_n: f32,
    rng: &mut Rng,
    visitor: &mut dyn ParticleVisitor,
    counts: &mut TraceCounts,
) -> Option<Launch> {
    let (li, pmf, _) = s.light_pick.sample(rng.next_f32());
    if pmf <= 0.0 {
        return None;
    }
    let u_pos = rng.next_2d();
    let u_dir = rng.next_2d();
    let e = emit(s, emission, li, pmf, u_pos, u_dir);
    if let Some((mut v, p)) = e.vertex {
        v.weight = inv_n / p;
        visitor.emitter(&v);
        counts.emitter_vertices += 1;
    }
    let (origin, dir, beta) = e.ray?;
    Some(Launch { origin, dir, beta })
}

/// Follows a launched path through the scene: reports every non-specular hit, bounces by BSDF
/// sampling with Russian roulette, and stops at an emitter (black), on a miss, when the visitor
/// says so, or at the [`MAX_VERTICES`] cap (counted).
fn follow(
    world: &World,
    start: Launch,
    inv_n: f32,
    rng: &mut Rng,
    visitor: &mut dyn ParticleVisitor,
    counts: &mut TraceCounts,
) {
    let s = &world.scene;
    let Launch { origin: mut o, dir: mut d, mut beta } = start;
    let mut prev_dirac = false;
    for depth in 1..MAX_VERTICES {
        let Some(hit) = world.intersect(o, d, f32::INFINITY) else {
            return;
        };
        if s.emitter_of(hit.prim) != NO_EMITTER {
            return; // emitters absorb (black material)
        }
        let w_in = -d;
        let (m, sp) = world.shade(&hit, w_in);
        let m = &m;
        if !m.is_dirac() {
            let ShadingPoint { p, ng, ns, n0, .. } = sp;
            let v = SurfaceVertex { p, ng, ns, n0, material: m, w_in, beta: beta * inv_n, prev_dirac, depth };
            let keep_going = visitor.surface(&v);
            counts.surface_vertices += 1;
            counts.caustic_vertices += prev_dirac as u64;
            if !keep_going {
                return;
            }
        }
        let Some((wi, weight, is_delta)) = scatter(m, &sp, w_in, rng) else {
            return;
        };
        if is_delta && !reciprocal(world, &hit, &sp, wi) {
            counts.non_reciprocal += 1;
            return; // no transport `pt` measures ([`reciprocal`])
        }
        beta *= weight;
        prev_dirac = is_delta;
        o = offset_origin(hit.p, hit.ng, wi);
        d = wi;
    }
    counts.capped += 1;
}

/// Whether the Dirac lobe that turned `wo` into `wi` at `hit` (shading point `sp`, seen from
/// `wo`) turns `wi` back into `wo`: the shading normal seen from `wi` is `sp`'s. A normal map
/// mirrors its normal where the direction it is seen from lies on different sides of it and of
/// the untilted normal (Mitsuba's `flip_invalid_normals`, `scene::surface`), so the two ends of
/// a Dirac vertex can see two normals; a light path (which shades from the light's side) then
/// carries transport that `pt` (which shades from the camera's side) does not have. Every light
/// path ends at a vertex where this fails: the point lights, photons and forecasters here, and
/// `pt-cf`'s light side, whose camera side takes those paths instead (`pt_cf::light`). The
/// predicate is symmetric in `wo` and `wi`; without a normal map it always holds.
pub fn reciprocal(world: &World, hit: &Hit, sp: &ShadingPoint, wi: Vec3) -> bool {
    sp.ns == sp.n0 || world.shade(hit, wi).1.ns == sp.ns
}

/// One bounce of a light path: a BSDF sample in `Mode::Importance`, then Russian roulette
/// (spec §2: survival `q = min(1, lum(f·|cos|/p))`, `β ← β·(f·|cos|/p)/q`). Returns the new
/// direction, the throughput factor and whether the bounce was Dirac; `None` ends the path.
#[inline]
fn scatter(m: &Material, sp: &ShadingPoint, w_in: Vec3, rng: &mut Rng) -> Option<(Vec3, Rgb, bool)> {
    let u = rng.next_3d();
    let bs = bsdf::sample(m, sp, w_in, u, Mode::Importance)?;
    let w = roulette(bs.weight, q_particle(bs.weight), rng)?;
    Some((bs.wi, w, bs.is_delta))
}

/// Traces paths `0..n_paths` of `paths` sequentially into one visitor.
pub fn trace_paths(world: &World, paths: &LightPaths, visitor: &mut dyn ParticleVisitor) -> TraceCounts {
    let mut counts = TraceCounts::default();
    for i in 0..paths.n_paths {
        trace_path(world, paths, i, visitor, &mut counts);
    }
    counts
}

/// A caustic vertex with its raw (un-normalised) throughput.
#[derive(Clone, Copy, Debug)]
pub struct CausticVertex {
    /// Position.
    pub p: Vec3,
    /// Geometric normal on the lit side.
    pub n: Vec3,
    /// Direction toward the previous (Dirac) vertex.
    pub w_in: Vec3,
    /// Path throughput β for one launched path (divide by the paths launched).
    pub beta: Rgb,
}

/// Light paths launched per parallel block in `collect_caustic_vertices`, at most.
pub const BLOCK: u64 = 16_384;
/// Light paths launched per parallel block in `collect_caustic_vertices`, at least (a block is
/// about the vertices still wanted, so that a small target or a stop waits for no more).
pub const MIN_BLOCK: u64 = 1_024;

/// Traces light paths 0, 1, 2, … (stream `(seed, stream_id, 0, i)`) until `target` caustic
/// vertices (non-specular hits after a Dirac vertex) are collected or `max_paths` are launched.
/// Returns the vertices of whole paths `0..P` and `P`, the normaliser: deterministic for any
/// thread count, since blocks run in parallel but are concatenated in path order, and for any
/// block size (a block holds about the vertices still wanted, between [`MIN_BLOCK`] and
/// [`BLOCK`] paths; `max_paths` is rounded up to whole [`BLOCK`]s, as whole blocks of `BLOCK`
/// traced it). `stored(n)` is told the vertices collected so far after every block, and the
/// tracing ends there when it returns `false` (a deadline or a signal: the paths `0..P` launched
/// so far are whole, so the normaliser stays `P`).
pub fn collect_caustic_vertices(
    world: &World,
    emission: Emission,
    target: u64,
    max_paths: u64,
    seed: u64,
    stream_id: u64,
    stored: &dyn Fn(u64) -> bool,
) -> (Vec<CausticVertex>, u64) {
    use rayon::prelude::*;
    struct Collect(Vec<CausticVertex>);
    impl ParticleVisitor for Collect {
        fn surface(&mut self, v: &SurfaceVertex) -> bool {
            if v.prev_dirac && !v.material.is_black() {
                let n = if v.ng.dot(v.w_in) >= 0.0 { v.ng } else { -v.ng };
                self.0.push(CausticVertex { p: v.p, n, w_in: v.w_in, beta: v.beta });
            }
            true
        }
    }
    let mut out = Vec::new();
    let mut paths = 0u64;
    if world.scene.dirac_bounds().is_none() {
        return (out, 0);
    }
    let max_paths = max_paths.div_ceil(BLOCK).saturating_mul(BLOCK);
    while target > 0 && (out.len() as u64) < target && paths < max_paths {
        let start = paths;
        let n = (target - out.len() as u64).clamp(MIN_BLOCK, BLOCK).min(max_paths - start);
        let block: Vec<Vec<CausticVertex>> = (start..start + n)
            .into_par_iter()
            .map(|i| {
                let mut c = Collect(Vec::new());
                let mut counts = TraceCounts::default();
                // n_paths = 1: raw β, normalised by the caller with the paths kept
                let batch = LightPaths { emission, n_paths: 1, seed, stream_id, pass: 0 };
                trace_path(world, &batch, i, &mut c, &mut counts);
                c.0
            })
            .collect();
        for list in block {
            paths += 1;
            out.extend(list);
            if out.len() as u64 >= target {
                break;
            }
        }
        if !stored(out.len() as u64) {
            break;
        }
    }
    (out, paths)
}

/// Light paths launched per requested caustic point before the collector gives up (scenes where
/// caustics are rare or absent).
pub const PATH_FACTOR: u64 = 100;

/// The one caustic-point collector of the photon map and the forecasters: traces light paths
/// (stream `(seed, stream_id, 0, i)`) until `target` caustic vertices are stored or
/// `PATH_FACTOR·target` paths are launched, and normalises each vertex's throughput by the
/// paths launched `P` (spec §6 ⚠: never by the number stored). Returns the vertices and `P`.
pub fn collect_caustic_points(
    world: &World,
    emission: Emission,
    target: u64,
    seed: u64,
    stream_id: u64,
    stored: &dyn Fn(u64) -> bool,
) -> (Vec<CausticVertex>, u64) {
    let max_paths = target.saturating_mul(PATH_FACTOR).max(BLOCK);
    let (mut verts, paths) = collect_caustic_vertices(world, emission, target, max_paths, seed, stream_id, stored);
    let inv = if paths > 0 { 1.0 / paths as f32 } else { 0.0 };
    for v in &mut verts {
        v.beta *= inv;
    }
    (verts, paths)
}
