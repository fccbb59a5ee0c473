//! `pt` as a wavefront over a batch of camera rays (a tile): the estimator of
//! `PathTracer::trace`, path by path and bit for bit, with the rays of each bounce traced in one
//! batch (`World::intersect_batch`) and the shadow rays of each bounce in another
//! (`World::occluded_batch`), so that Embree pays its per-call cost once per 16-ray packet.
//! Every vertex is `pt::vertex` (or, for a diffuse one, `pt::lanes`); measured in
//! `results/2026-12-04-core-wavefront.md`.
//!
//! Invariants (why it is bit-identical to the scalar loop, `tests/wavefront.rs`): each path draws
//! from its own stream (`rngs[i]`) in the scalar order (NEE's numbers, then the BSDF's, then
//! roulette's); a path's contributions are added in the scalar order (the emitter hit of bounce
//! k, then NEE at k, then bounce k + 1); NEE's contribution is `β·value` when its segment is
//! unoccluded and `β·0` otherwise, as `direct::unoccluded` returns; paths never interact.
//! `--path-filter` runs the scalar loop (`Integrator::estimate_batch`'s default).

use super::lanes::{Lanes, Vertex};
use super::vertex::{vertex, SurfaceVertex, Walk};
use crate::accel::{BatchScratch, Ray, World};
use crate::integrators::CameraEstimate;
use crate::math::{Rgb, Vec3};
use crate::sampling::rng::Rng;
use crate::scene::{LightRef, Material, Scene, NO_EMITTER};
use crate::transport::direct::LightSample;
use crate::transport::roulette::Throughput;

/// One live path of the wavefront.
#[derive(Clone, Copy)]
pub(crate) struct Live {
    /// Index of the camera ray (and of its stream and estimate).
    i: u32,
    /// The path's `Walk` without its ray, which is the bounce's `Wave::rays[k]` (a live path is
    /// copied in and out at every vertex: 32 bytes, not 56).
    t: Throughput,
    prev_delta: bool,
    prev_pdf_w: f32,
    /// No non-Dirac vertex yet.
    prefix: bool,
}

impl Live {
    /// A camera path's state.
    fn camera(i: u32) -> Live {
        let w = Walk::camera(Ray { o: Vec3::ZERO, d: Vec3::ZERO, tmax: f32::INFINITY });
        Live { i, t: w.t, prev_delta: w.prev_delta, prev_pdf_w: w.prev_pdf_w, prefix: true }
    }

    /// The path's `Walk` along its bounce's `ray`.
    #[inline(always)]
    fn walk(&self, ray: &Ray) -> Walk {
        Walk { o: ray.o, d: ray.d, t: self.t, prev_delta: self.prev_delta, prev_pdf_w: self.prev_pdf_w }
    }

    /// The path after its `Walk` moved on to `w`.
    #[inline(always)]
    fn moved(self, w: &Walk) -> Live {
        Live { t: w.t, prev_delta: w.prev_delta, prev_pdf_w: w.prev_pdf_w, ..self }
    }
}

/// Per-batch buffers, reused across bounces and, through `Context::take_scratch`, across the
/// batches of a worker (a bounce never has more rays than the batch). `P`: a live path's state
/// (`Live` here, `pt-cf`'s own in `pt_cf::wavefront`).
pub(crate) struct Wave<P = Live> {
    pub(crate) live: Vec<P>,
    pub(crate) rays: Vec<Ray>,
    /// The closest hits of `rays` as (primitive, t) (`World::hit_at` builds the record).
    pub(crate) hits: Vec<Option<(u32, f32)>>,
    pub(crate) next_live: Vec<P>,
    pub(crate) next_rays: Vec<Ray>,
    /// NEE of this bounce: (path index, β at the vertex, the unoccluded value).
    nee: Vec<(u32, Rgb, Rgb)>,
    shadow: Vec<Ray>,
    occluded: Vec<bool>,
    /// The diffuse vertices of this bounce, sixteen at a time (`pt::lanes`).
    pub(crate) lanes: Box<Lanes>,
    /// Whether the lanes apply to this batch's scene (`lanes_apply`).
    pub(crate) lanes_on: bool,
    scratch: BatchScratch,
}

impl<P> Default for Wave<P> {
    fn default() -> Self {
        Wave {
            live: Vec::new(),
            rays: Vec::new(),
            hits: Vec::new(),
            next_live: Vec::new(),
            next_rays: Vec::new(),
            nee: Vec::new(),
            shadow: Vec::new(),
            occluded: Vec::new(),
            lanes: Box::default(),
            lanes_on: false,
            scratch: BatchScratch::default(),
        }
    }
}

impl<P> Wave<P> {
    /// Empties every buffer and starts one path per camera ray (`start(i)` its state), and
    /// `out` as one zero estimate per ray.
    pub(crate) fn start(
        &mut self,
        world: &World,
        rays: &[Ray],
        start: impl Fn(u32) -> P,
        out: &mut Vec<CameraEstimate>,
    ) {
        let n = rays.len();
        out.clear();
        out.resize(n, CameraEstimate::default());
        for v in [&mut self.live, &mut self.next_live] {
            v.clear();
            v.reserve(n);
        }
        for v in [&mut self.rays, &mut self.next_rays, &mut self.shadow] {
            v.clear();
            v.reserve(n);
        }
        self.hits.clear();
        self.hits.reserve(n);
        self.nee.clear();
        self.nee.reserve(n);
        self.occluded.clear();
        self.occluded.reserve(n);
        self.lanes_on = lanes_apply(&world.scene);
        self.live.extend((0..n as u32).map(start));
        self.rays.extend_from_slice(rays);
    }

    /// Traces the bounce's rays (the camera rays, `depth` 0, of a pass group run pixel by
    /// pixel, side by side), then prefetches the texels their shading will read
    /// (`World::prefetch_shading`; the surfaces' only where `shade`, false at the bounce after
    /// the last vertex, whose hits are only checked for an emitter).
    pub(crate) fn intersect(&mut self, world: &World, depth: u32, shade: bool) {
        world.intersect_batch(&self.rays, &mut self.scratch, &mut self.hits, depth == 0);
        world.prefetch_shading(&self.rays, &self.hits, shade);
    }

    /// Queues path `i`'s NEE sample: `β·value` if its segment is unoccluded, `β·0` for `None`
    /// (as `direct::sample_light` returns), added at the end of the bounce.
    #[inline]
    pub(crate) fn queue_nee(&mut self, i: u32, beta: Rgb, ls: Option<LightSample>, out: &mut [CameraEstimate]) {
        match ls {
            Some(LightSample { value, shadow }) => {
                self.nee.push((i, beta, value));
                self.shadow.push(shadow);
            }
            None => out[i as usize].rest += beta * Rgb::ZERO,
        }
    }

    /// Ends a bounce: its shadow rays traced and their NEE added, the next bounce's paths made
    /// live.
    pub(crate) fn finish_bounce(&mut self, world: &World, out: &mut [CameraEstimate]) {
        world.occluded_batch(&self.shadow, &mut self.scratch, &mut self.occluded);
        for (&(i, beta, value), &blocked) in self.nee.iter().zip(&self.occluded) {
            out[i as usize].rest += beta * if blocked { Rgb::ZERO } else { value };
        }
        self.nee.clear();
        self.shadow.clear();
        std::mem::swap(&mut self.live, &mut self.next_live);
        std::mem::swap(&mut self.rays, &mut self.next_rays);
        self.next_live.clear();
        self.next_rays.clear();
    }
}

/// `PathTracer::trace` (vertex cap `max_depth`, no `--path-filter`) for every ray of `rays`,
/// path `i` drawing from `rngs[i]`; `out[i]` is bit for bit `trace(rays[i])` (the module's
/// invariants).
pub(crate) fn trace_batch(
    world: &World,
    max_depth: u32,
    rays: &[Ray],
    rngs: &mut [Rng],
    w: &mut Wave,
    out: &mut Vec<CameraEstimate>,
) {
    debug_assert!(rays.len() == rngs.len());
    w.start(world, rays, Live::camera, out);
    // as `trace`: after the last vertex, its BSDF ray only for the emitter it may reach
    for depth in 0..=max_depth {
        if w.live.is_empty() {
            break;
        }
        w.intersect(world, depth, depth < max_depth);
        if depth == max_depth {
            for k in 0..w.live.len() {
                emitted(world, w, k, out);
            }
            break;
        }
        for k in 0..w.live.len() {
            if shade(world, w, k, depth, rngs, out) {
                flush(w, depth, rngs, out);
            }
        }
        if w.lanes.n > 0 {
            flush(w, depth, rngs, out);
        }
        w.finish_bounce(world, out);
    }
}

/// The emitter hit of live path `k`, or the environment where its ray escapes (true then: the
/// path ends there).
#[inline]
fn emitted(world: &World, w: &Wave, k: usize, out: &mut [CameraEstimate]) -> bool {
    let p = w.live[k];
    let walk = p.walk(&w.rays[k]);
    let Some(found) = w.hits[k] else {
        if let Some((le, mis)) = walk.escaped(world) {
            let l = &mut out[p.i as usize];
            *if p.prefix { &mut l.prefix_le } else { &mut l.rest } += walk.t.beta * le * mis;
        }
        return true;
    };
    let hit = world.hit_at(&w.rays[k], found);
    if world.scene.emitter_of(hit.prim) == NO_EMITTER {
        return false;
    }
    if let Some((le, mis)) = walk.emitted(world, &hit) {
        let l = &mut out[p.i as usize];
        *if p.prefix { &mut l.prefix_le } else { &mut l.rest } += walk.t.beta * le * mis;
    }
    true // emitters reflect nothing
}

/// One vertex of live path `k` (the body of `trace`'s loop): its emitter hit, or `pt`'s vertex
/// with its NEE sample queued with its shadow ray and its continuation queued as the next ray.
/// Where the lanes apply, a diffuse vertex draws its numbers and goes to `w.lanes` instead; true
/// when that record is full.
#[inline]
fn shade(world: &World, w: &mut Wave, k: usize, depth: u32, rngs: &mut [Rng], out: &mut [CameraEstimate]) -> bool {
    if emitted(world, w, k, out) {
        return false;
    }
    let mut p = w.live[k];
    let mut walk = p.walk(&w.rays[k]);
    let rng = &mut rngs[p.i as usize];
    let Some(found) = w.hits[k] else { return false };
    let hit = world.hit_at(&w.rays[k], found);
    let (m, sp) = world.shade(&hit, -walk.d);
    let v = SurfaceVertex::at(&m, sp, &hit, walk.d, depth);
    // the lanes run the untilted Lambertian BSDF: a normal-mapped point takes the scalar path
    if let (true, Material::Diffuse { albedo }, true) = (w.lanes_on, m, v.sp.n0 == v.sp.ns) {
        w.live[k].prefix = false;
        return w.lanes.push(Vertex::draw(world, k, &v, albedo, rng));
    }
    p.prefix &= m.is_dirac();
    let beta = walk.t.beta;
    let nee = |ls| w.queue_nee(p.i, beta, ls, out);
    let Some(bs) = vertex(world, &v, rng, nee) else { return false };
    if walk.scatter(&bs, depth, &v.sp, rng) {
        w.next_live.push(p.moved(&walk));
        w.next_rays.push(walk.ray());
    }
    false
}

/// Runs the queued diffuse vertices and finishes each as `shade` does: its NEE queued (or `β·0`
/// added), its scattering and roulette.
fn flush(w: &mut Wave, depth: u32, rngs: &mut [Rng], out: &mut [CameraEstimate]) {
    w.lanes.run();
    for j in 0..w.lanes.n {
        let k = w.lanes.k[j] as usize;
        let (p, r) = (w.live[k], w.lanes.out(j));
        w.queue_nee(p.i, p.t.beta, r.nee, out);
        let Some(bs) = r.bsdf else { continue };
        let mut walk = p.walk(&w.rays[k]);
        if walk.scatter(&bs, depth, &r.sp, &mut rngs[p.i as usize]) {
            w.next_live.push(p.moved(&walk));
            w.next_rays.push(walk.ray());
        }
    }
    w.lanes.n = 0;
}

/// Whether the lanes apply: every light is a triangle emitter (`pt::lanes` samples those).
pub(crate) fn lanes_apply(s: &Scene) -> bool {
    s.lights.iter().all(|l| matches!(*l, LightRef::Area(e) if s.emitters[e as usize].prim < s.ntri()))
}
