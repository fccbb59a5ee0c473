//! `pt-cf`'s light side: light paths connected to the pinhole camera, MIS-combined with the
//! camera paths by the balance heuristic with counts (Veach ch. 10; the weights, the splat's
//! importance `W = 1/(A_pix cos³θ_c)` and their derivation: `docs/methods/pt-cf.md`, "Light
//! paths").
//!
//! Path class C = `L S+ (S|D)* D E`: light paths whose first vertex after the emitter is Dirac,
//! ending at a non-Dirac vertex `x1` the camera sees. NEE never samples C, so exactly two
//! techniques do: the camera side (a `pt-cf` path through `x1` that reaches the emitter through a
//! Dirac chain, weight `w_E`) and this one (the light subpath connected to the camera, `w_L`),
//! with `w_L + w_E = 1`; every other class keeps `pt-cf`'s weights. A point light has `p_E = 0`:
//! `w_L = 1`, and the light side alone renders its caustics.
//!
//! Each pass traces `N_L` light paths (`--light-paths`, or the pipeline's pilot), path `i` from
//! `Rng::keyed(seed, stream::LIGHT_PATHS, pass, i)`, launched with the CF preprocess's targeted
//! emission and bounced in importance mode with the particle tracer's roulette.
//!
//! Invariants: light paths run in chunks of [`CHUNK`] in parallel and their splats are added in
//! chunk order into a dense per-pass image that `render::render_passes` adds to each pixel's
//! camera sample, so a pass's pixel value is still one i.i.d. sample (the variance layer and the
//! checkpoints stay valid) and the image does not depend on threads or ranks. A pass cut by its
//! `Stop` (the time box, a signal) yields no splats at all: `N_L` is in every MIS weight, so
//! a part of a pass's paths is no estimator, and the cut pass is discarded whole
//! (`render::trace_passes`). Assumed: `x1` and the light lie in the same medium.

use crate::accel::{offset_origin, take_ray_counts, Hit, World};
use crate::bsdf::{self, Mode, ShadingPoint};
use crate::integrators::{Context, LightSplats};
use crate::interrupt::Stop;
use crate::math::{Rgb, Vec3};
use crate::sampling::rng::{stream, Rng};
use crate::scene::{Camera, Material, NO_EMITTER};
use crate::transport::particle::{emit, reciprocal, Emission};
use crate::transport::roulette::{q_particle, roulette};
use rayon::prelude::*;

/// Light paths per parallel work item.
pub const CHUNK: u64 = 1024;
/// Chunks traced in parallel before their splats are summed (in chunk order): a pass holds at
/// most `BATCH · CHUNK` paths' splats at once.
const BATCH: u64 = 256;

/// Light paths per pass per pixel of an integrator built without a count and without the
/// pipeline's pilot (`pipeline::light_pilot`, which picks the count of every render that does
/// not give `--light-paths`), and of a render with no light side, where the count does not
/// matter. Of the fixed counts, ½ per pixel had the lowest geometric-mean noise over the 11
/// crops of the four measured scenes (`results/2026-12-05-targeted-cones.md`).
pub const PATHS_PER_PIXEL: f64 = 0.5;

/// The light side's settings.
#[derive(Clone, Copy, Debug)]
pub struct LightSide {
    /// `--light-paths`, or the pipeline's pilot's count (`None`, outside the pipeline:
    /// [`PATHS_PER_PIXEL`] × the pixel count).
    pub paths: Option<u64>,
    /// The CF preprocess's targeted emission.
    pub emission: Emission,
    /// `--max-depth`.
    pub max_depth: u32,
}

/// The most light paths per pixel a pass may trace (`--light-paths`): a pass then costs about as
/// many camera passes, so that one pass stays a small part of any time box and a signal is
/// honoured within about a pass (the pilot picks 1/8 to 2).
pub const MAX_PATHS_PER_PIXEL: u64 = 16;
/// The most light paths per pass at any resolution (about 0.1 s on one core).
pub const MAX_PATHS_FLOOR: u64 = 1 << 16;

/// The most light paths per pass for a `width × height` image: [`MAX_PATHS_PER_PIXEL`] per
/// pixel, at least [`MAX_PATHS_FLOOR`].
pub fn max_paths(width: u32, height: u32) -> u64 {
    (MAX_PATHS_PER_PIXEL * width as u64 * height as u64).max(MAX_PATHS_FLOOR)
}

/// Light paths per pass without a count and without the pilot: [`PATHS_PER_PIXEL`] × the pixel count.
pub fn default_paths(width: u32, height: u32) -> u64 {
    (PATHS_PER_PIXEL * width as f64 * height as f64).ceil() as u64
}

impl LightSide {
    /// Light paths per pass for `camera`'s image.
    pub fn n_paths(&self, camera: &Camera) -> u64 {
        self.paths.unwrap_or_else(|| default_paths(camera.width, camera.height))
    }
}

/// `1/(A_pix cos³θ_c)` for the unit direction `d` from the camera (0 behind it): the pinhole's
/// importance per solid angle, and the camera's solid-angle density of a pixel sample.
#[inline]
pub fn pinhole_importance(camera: &Camera, d: Vec3) -> f32 {
    let c = d.dot(camera.forward);
    if c <= 0.0 {
        return 0.0;
    }
    let side = camera.pixel_side();
    1.0 / (side * side * c * c * c)
}

/// `N_L · P_ℓ p_A(y0) p_e(ω0)/|cos θ_y0|` for the camera path's emitter hit `hit` along `d`, 0
/// when the light side cannot draw it (outside the cone, back side).
fn light_start_density(world: &World, light: &LightSide, n_l: u64, hit: &Hit, d: Vec3) -> f32 {
    let s = &world.scene;
    let em = s.emitter_of(hit.prim);
    let cos_y0 = hit.ng.dot(-d);
    if em == NO_EMITTER || cos_y0 <= 0.0 {
        return 0.0;
    }
    let p_a = 1.0 / s.emitters[em as usize].area;
    let p_e = light.emission.pdf_dir(hit.p, hit.ng, None, -d);
    n_l as f32 * s.light_pick.pmf(em as usize) * p_a * p_e / cos_y0
}

/// The camera side's weight `w_E = 1/(1 + r)` of a path of C that hits the emitter at `hit`
/// along `d` after a Dirac vertex, `ratio` the running product of the camera path
/// ([`first_ratio`], [`next_ratio`]).
pub fn camera_weight(world: &World, light: &LightSide, camera: &Camera, hit: &Hit, d: Vec3, ratio: f32) -> f32 {
    weight_e(ratio, light_start_density(world, light, light.n_paths(camera), hit, d))
}

/// `N_L · P_ℓ p_σ(ω) p_disk` for a camera path whose last ray `(o, d)` escapes to the
/// environment: the light side's density of its start (a direction of the environment's
/// sampler, the point of the bounding sphere's disk, or of the targeted shadows, on the ray's
/// line: `particle::emit`, `Emission::beam_pdf`), which takes the place of `p_A p_e/|cos θ_y0|`
/// (the beam's étendue `dA⊥ dω` is what a Dirac chain conserves); 0 without an environment.
fn environment_start_density(world: &World, light: &LightSide, n_l: u64, (o, d): (Vec3, Vec3)) -> f32 {
    let s = &world.scene;
    match (s.environment_light(), &s.environment) {
        (Some(li), Some(env)) => n_l as f32 * s.light_pick.pmf(li) * env.pdf_w(d) * light.emission.beam_pdf(s, -d, o),
        _ => 0.0,
    }
}

/// [`camera_weight`] for a path of C whose last ray `(o, d)` escapes to the environment.
pub fn camera_weight_escaped(world: &World, light: &LightSide, camera: &Camera, ray: (Vec3, Vec3), ratio: f32) -> f32 {
    weight_e(ratio, environment_start_density(world, light, light.n_paths(camera), ray))
}

/// `w_E = 1/(1 + ratio·density)`; 1 where the light side cannot draw the path (`density` 0).
fn weight_e(ratio: f32, density: f32) -> f32 {
    if density <= 0.0 {
        return 1.0; // the light side cannot draw this path
    }
    let r = ratio * density;
    if r.is_finite() {
        1.0 / (1.0 + r)
    } else {
        0.0
    }
}

/// The camera path's ratio after `x1` (first hit at distance `t` along the camera ray `d0`, wo
/// toward the camera, continuation `wi` drawn with pdf `q`): `t²·A_pix cos³θ_c · c⁺/(c⁻ q)`.
pub fn first_ratio(camera: &Camera, d0: Vec3, t: f32, ng: Vec3, (wo, wi): (Vec3, Vec3), q: f32) -> f32 {
    let w = pinhole_importance(camera, d0);
    let den = w * ng.dot(wo).abs() * q;
    if den > 0.0 {
        t * t * ng.dot(wi).abs() / den
    } else {
        f32::INFINITY
    }
}

/// The factor of a later non-Dirac camera vertex: `p^L c⁺/(c⁻ q)`, `p^L` the light side's
/// BSDF pdf of `wo` given `wi`.
pub fn next_ratio(m: &Material, sp: &ShadingPoint, (wo, wi): (Vec3, Vec3), q: f32) -> f32 {
    let p_l = bsdf::pdf_w(m, sp, wi, wo);
    let den = sp.ng.dot(wo).abs() * q;
    if den > 0.0 {
        p_l * sp.ng.dot(wi).abs() / den
    } else {
        f32::INFINITY
    }
}

/// A non-Dirac vertex of a light path before the connected one.
#[derive(Clone, Copy)]
struct Vertex {
    sp: ShadingPoint,
    m: Material,
    /// Toward the light side.
    w_in: Vec3,
    /// The sampled direction (toward the camera side).
    w_out: Vec3,
    /// Its pdf (importance-mode BSDF sampling).
    pdf_l: f32,
}

/// A light path's start: its ray, β and `P_ℓ p_A p_e/|cos θ_y0|` (`None` for a point light,
/// which the camera side never samples).
struct Start {
    o: Vec3,
    d: Vec3,
    beta: Rgb,
    density: Option<f32>,
}

/// The launch of `transport::particle` (same random numbers: light, point, direction; the
/// same emission, `particle::emit`).
fn launch(world: &World, emission: Emission, rng: &mut Rng) -> Option<Start> {
    let s = &world.scene;
    let (li, pmf, _) = s.light_pick.sample(rng.next_f32());
    if pmf <= 0.0 {
        return None;
    }
    let (u_pos, u_dir) = (rng.next_2d(), rng.next_2d());
    let e = emit(s, emission, li, pmf, u_pos, u_dir);
    let (o, d, beta) = e.ray?;
    Some(Start { o, d, beta, density: e.density })
}

/// The camera side's pdf of drawing `wi` at a non-Dirac vertex of diffuse depth `depth` seen
/// from `wo` (the light paths' MIS weight needs it; `pt-cf`'s camera side implements it).
pub trait CameraPdf: Sync {
    /// That pdf, per unit solid angle.
    fn camera_pdf_w(&self, sp: &ShadingPoint, m: &Material, wo_wi: (Vec3, Vec3), depth: u32, ctx: &mut Context) -> f32;
}

/// What one chunk of light paths produced.
struct Chunk {
    splats: Vec<(u32, Rgb)>,
    nonfinite: u64,
    closest: u64,
    shadow: u64,
}

/// The pass's light splats for `camera` (see the module docs).
pub fn light_splats<P: CameraPdf>(
    pt: &P,
    light: &LightSide,
    world: &World,
    camera: &Camera,
    (seed, pass): (u64, u64),
    stop: &Stop,
) -> Option<LightSplats> {
    let n = light.n_paths(camera);
    let mut out = LightSplats {
        image: vec![Rgb::ZERO; camera.width as usize * camera.height as usize],
        ..LightSplats::default()
    };
    // batches of chunks, so that a pass's pending splats stay bounded whatever `n`
    let n_chunks = n.div_ceil(CHUNK);
    for first in (0..n_chunks).step_by(BATCH as usize) {
        let chunks: Vec<Option<Chunk>> = (first..(first + BATCH).min(n_chunks))
            .into_par_iter()
            .map(|c| {
                // the deadline or a signal: the pass is cut (a chunk is a fraction of a second)
                if stop.is_due() {
                    return None;
                }
                let _ = take_ray_counts();
                let mut ctx = Context::new(Rng::keyed(seed, stream::LIGHT_PATHS, pass, u64::MAX));
                let mut t = Tracer { pt, light, world, camera, n, splats: Vec::new(), nonfinite: 0, verts: Vec::new() };
                for i in c * CHUNK..((c + 1) * CHUNK).min(n) {
                    t.path(Rng::keyed(seed, stream::LIGHT_PATHS, pass, i), &mut ctx);
                }
                let (closest, shadow) = take_ray_counts();
                Some(Chunk { splats: t.splats, nonfinite: t.nonfinite, closest, shadow })
            })
            .collect();
        if chunks.iter().any(Option::is_none) {
            return None;
        }
        for c in chunks.into_iter().flatten() {
            for (p, v) in c.splats {
                out.image[p as usize] += v;
            }
            out.nonfinite += c.nonfinite;
            out.closest_rays += c.closest;
            out.shadow_rays += c.shadow;
        }
    }
    Some(out)
}

/// One chunk's light tracer.
struct Tracer<'a, P> {
    pt: &'a P,
    light: &'a LightSide,
    world: &'a World,
    camera: &'a Camera,
    /// `N_L`.
    n: u64,
    splats: Vec<(u32, Rgb)>,
    /// Splats dropped as non-finite (counted in the pass's `nonfinite`, as camera estimates are).
    nonfinite: u64,
    /// The current path's non-Dirac vertices so far (scratch).
    verts: Vec<Vertex>,
}

impl<'a, P: CameraPdf> Tracer<'a, P> {
    /// Traces one light path, splatting at its vertices of C.
    fn path(&mut self, mut rng: Rng, ctx: &mut Context) {
        let s = &self.world.scene;
        self.verts.clear();
        let Some(Start { mut o, mut d, mut beta, density }) = launch(self.world, self.light.emission, &mut rng) else {
            return;
        };
        // the camera side reaches the emitter from at most `max_depth` surface vertices
        for depth in 1..=self.light.max_depth {
            let Some(hit) = self.world.intersect(o, d, f32::INFINITY) else { return };
            if s.emitter_of(hit.prim) != NO_EMITTER {
                return; // emitters absorb
            }
            let w_in = -d;
            if depth == 1 {
                // a first vertex with no Dirac lobe ends the path (below) before it is shaded:
                // `shade` keeps the material's kind (or gives black behind a one-sided surface)
                let kind = s.material_of(hit.prim);
                if !kind.is_dirac() && !kind.has_mixed_lobes() {
                    return;
                }
            }
            let (m, sp) = self.world.shade(&hit, w_in);
            let m = &m;
            // C is defined by the lobe each vertex sampled (spec §1): its first vertex left by a
            // Dirac lobe, its later non-Dirac ones connected by their non-Dirac lobes
            if !m.is_dirac() {
                if depth == 1 && !m.has_mixed_lobes() {
                    return; // not a path of C
                }
                if depth > 1 {
                    self.connect(&sp, m, w_in, beta, density, ctx);
                }
            }
            let u = rng.next_3d();
            let Some(bs) = bsdf::sample(m, &sp, w_in, u, Mode::Importance) else { return };
            if bs.is_delta && !reciprocal(self.world, &hit, &sp, bs.wi) {
                return; // no transport `pt` measures (`reciprocal`)
            }
            if depth == 1 && !bs.is_delta {
                return; // not a path of C
            }
            let Some(w) = roulette(bs.weight, q_particle(bs.weight), &mut rng) else { return };
            if !bs.is_delta {
                self.verts.push(Vertex { sp, m: *m, w_in, w_out: bs.wi, pdf_l: bs.pdf_w });
            }
            beta *= w;
            o = offset_origin(hit.p, hit.ng, bs.wi);
            d = bs.wi;
        }
    }

    /// Connects the non-Dirac vertex `sp` (light arriving from `w_in` with throughput `beta`) to
    /// the camera and splats its weighted contribution.
    fn connect(
        &mut self,
        sp: &ShadingPoint,
        m: &Material,
        w_in: Vec3,
        beta: Rgb,
        density: Option<f32>,
        ctx: &mut Context,
    ) {
        let cam = self.camera;
        let to = cam.position - sp.p;
        let dist2 = to.length_squared();
        if dist2 <= 0.0 {
            return;
        }
        let wc = to / dist2.sqrt();
        let imp = pinhole_importance(cam, -wc);
        let Some(pixel) = pixel_of(cam, sp.p) else { return };
        let cos_in = sp.ng.dot(w_in).abs();
        // f(x; toward the camera, toward the light) as radiance sees it: the adjoint BSDF of the light path
        let f = bsdf::eval(m, sp, wc, w_in, Mode::Radiance);
        if imp <= 0.0 || cos_in <= 0.0 || f == Rgb::ZERO {
            return;
        }
        let o = offset_origin(sp.p, sp.ng, wc);
        let len = (cam.position - o).length();
        if self.world.occluded(o, (cam.position - o) / len, len) {
            return;
        }
        let pt = self.pt;
        let mut q = |sp: &ShadingPoint, m: &Material, w: (Vec3, Vec3), d: u32| pt.camera_pdf_w(sp, m, w, d, ctx);
        let w_l =
            density.map_or(1.0, |p0| light_weight(self.n, &self.verts, (sp, m), (wc, w_in), p0 * dist2 / imp, &mut q));
        let corr = sp.ns.dot(w_in).abs() / cos_in;
        let v = beta * f * (w_l * corr * sp.ng.dot(wc).abs() * imp / (dist2 * self.n as f32));
        if !v.is_finite() {
            self.nonfinite += 1;
        } else if v != Rgb::ZERO {
            self.splats.push((pixel, v));
        }
    }
}

/// The camera side's pdf at a vertex: `(point, material, (wo, wi), diffuse depth) → pdf_w`.
type CameraPdfAt<'q> = dyn FnMut(&ShadingPoint, &Material, (Vec3, Vec3), u32) -> f32 + 'q;

/// `w_L = 1/(1 + 1/r)` at the connected vertex `x1` (`(wc, w_in)`: toward the camera and the
/// light) of a path with the earlier non-Dirac vertices `verts` (oldest first), `n` light paths,
/// `p0 = P_ℓ p_A p_e/|cos θ_y0| · |x1 − x0|² A_pix cos³θ_c`, and `q` the camera side's pdfs.
fn light_weight(
    n: u64,
    verts: &[Vertex],
    (sp, m): (&ShadingPoint, &Material),
    (wc, w_in): (Vec3, Vec3),
    p0: f32,
    q: &mut CameraPdfAt,
) -> f32 {
    let mut num = sp.ng.dot(wc).abs() * q(sp, m, (wc, w_in), 0);
    let mut den = n as f32 * p0 * sp.ng.dot(w_in).abs();
    for (k, v) in verts.iter().rev().enumerate() {
        num *= v.sp.ng.dot(v.w_out).abs() * q(&v.sp, &v.m, (v.w_out, v.w_in), k as u32 + 1);
        den *= v.pdf_l * v.sp.ng.dot(v.w_in).abs();
    }
    let rho = num / den;
    if rho.is_finite() {
        1.0 / (1.0 + rho)
    } else {
        0.0
    }
}

/// The row-major pixel that sees `p`, if any.
fn pixel_of(camera: &Camera, p: Vec3) -> Option<u32> {
    let (x, y) = camera.project(p)?;
    let (w, h) = (camera.width as f32, camera.height as f32);
    if !(x >= 0.0 && x < w && y >= 0.0 && y < h) {
        return None;
    }
    let (ix, iy) = ((x as u32).min(camera.width - 1), (y as u32).min(camera.height - 1));
    Some(iy * camera.width + ix)
}

#[cfg(test)]
#[path = "light_tests.rs"]
mod tests;
