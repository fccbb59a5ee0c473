//! `pt` as a wavefront over a batch of camera rays (a tile): the same estimator as
//! `PathTracer::trace`, path by path and bit for bit, with the rays of each bounce traced in one
//! batch (`World::intersect_batch`) and the shadow rays of each bounce in another
//! (`World::occluded_batch`): Embree then pays its per-call cost once per 16-ray packet
//! instead of once per ray (issue #33, `results/2026-12-04-core-wavefront.md`,
//! `results/2026-12-05-embree-packets.md`).
//!
//! Invariants (why it is bit-identical to the scalar loop): each path draws from its own stream
//! (`rngs[i]`) in the scalar order (NEE's numbers, then the BSDF's, then roulette's); a path's
//! contributions are added in the scalar order (the emitter hit of bounce k, then NEE at k, then
//! bounce k + 1); NEE's contribution is `β·value` when its segment is unoccluded and `β·0`
//! otherwise, as `sample_light` returns; paths never interact. `--path-filter` runs the scalar
//! loop (`Integrator::estimate_batch`'s default).

use super::path::{emitter_hit, PathTracer};
use super::path_lanes::{Lanes, Vertex};
use super::CameraEstimate;
use crate::accel::{offset_origin, BatchScratch, Ray, World};
use crate::bsdf::{self, BsdfSample, Mode, ShadingPoint};
use crate::math::Rgb;
use crate::sampling::rng::Rng;
use crate::scene::{LightRef, Material, Scene, NO_EMITTER};
use crate::transport::direct;
use crate::transport::roulette::Throughput;

/// One live path of the wavefront.
#[derive(Clone, Copy)]
struct Live {
    /// Index of the camera ray (and of its stream and estimate).
    i: u32,
    /// Its throughput (with roulette's η² scale).
    t: Throughput,
    /// No non-Dirac vertex yet.
    prefix: bool,
    /// The last direction was sampled from a Dirac lobe.
    prev_delta: bool,
    /// The last direction's solid-angle pdf.
    prev_pdf_w: f32,
}

/// Per-batch buffers, reused across bounces and, through `Context::take_scratch`, across the
/// batches of a worker (a bounce never has more rays than the batch).
#[derive(Default)]
pub(super) struct Wave {
    live: Vec<Live>,
    rays: Vec<Ray>,
    /// The closest hits of `rays` as (primitive, t) (`World::hit_at` builds the record).
    hits: Vec<Option<(u32, f32)>>,
    next_live: Vec<Live>,
    next_rays: Vec<Ray>,
    /// NEE of this bounce: (path index, β at the vertex, the unoccluded value).
    nee: Vec<(u32, Rgb, Rgb)>,
    shadow: Vec<Ray>,
    occluded: Vec<bool>,
    /// The diffuse vertices of this bounce, sixteen at a time (`path_lanes`).
    lanes: Box<Lanes>,
    /// Whether the lanes apply to this batch's scene (`lanes_apply`).
    lanes_on: bool,
    scratch: BatchScratch,
}

impl Wave {
    /// Empties every buffer and makes room for `n` paths.
    fn reset(&mut self, n: usize) {
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
    }
}

impl PathTracer {
    /// `trace` for every ray of `rays`, path `i` drawing from `rngs[i]`; `out[i]` is bit for bit
    /// `trace(rays[i])` (the module's invariants). Requires no `--path-filter`.
    pub(super) fn trace_batch(
        &self,
        world: &World,
        (rays, rngs): (&[Ray], &mut [Rng]),
        w: &mut Wave,
        out: &mut Vec<CameraEstimate>,
    ) {
        debug_assert!(self.filter.is_none() && rays.len() == rngs.len());
        out.clear();
        out.resize(rays.len(), CameraEstimate::default());
        let start = Live { i: 0, t: Throughput::new(Rgb::ONE), prefix: true, prev_delta: true, prev_pdf_w: 0.0 };
        w.reset(rays.len());
        w.lanes_on = lanes_apply(&world.scene);
        w.live.extend((0..rays.len() as u32).map(|i| Live { i, ..start }));
        w.rays.extend_from_slice(rays);
        for depth in 0..self.max_depth {
            if w.live.is_empty() {
                break;
            }
            // the camera rays (depth 0) of a pass group run pixel by pixel, side by side
            world.intersect_batch(&w.rays, &mut w.scratch, &mut w.hits, depth == 0);
            for k in 0..w.live.len() {
                if self.shade(world, w, k, depth, rngs, out) {
                    self.flush(w, depth, rngs, out);
                }
            }
            if w.lanes.n > 0 {
                self.flush(w, depth, rngs, out);
            }
            world.occluded_batch(&w.shadow, &mut w.scratch, &mut w.occluded);
            for (&(i, beta, value), &blocked) in w.nee.iter().zip(&w.occluded) {
                out[i as usize].rest += beta * if blocked { Rgb::ZERO } else { value };
            }
            w.nee.clear();
            w.shadow.clear();
            std::mem::swap(&mut w.live, &mut w.next_live);
            std::mem::swap(&mut w.rays, &mut w.next_rays);
            w.next_live.clear();
            w.next_rays.clear();
        }
    }

    /// One vertex of live path `k` (the body of `trace`'s loop): its emitter hit, its NEE
    /// sample (queued with its shadow ray), its BSDF sample and roulette (queued as the next ray).
    /// Where the lanes apply, a diffuse vertex draws its numbers and goes to `w.lanes` instead;
    /// true when that record is full.
    #[inline]
    fn shade(
        &self,
        world: &World,
        w: &mut Wave,
        k: usize,
        depth: u32,
        rngs: &mut [Rng],
        out: &mut [CameraEstimate],
    ) -> bool {
        let s = &world.scene;
        let (mut p, d) = (w.live[k], w.rays[k].d);
        let (i, rng) = (p.i as usize, &mut rngs[p.i as usize]);
        let Some(found) = w.hits[k] else { return false };
        let hit = world.hit_at(&w.rays[k], found);
        if s.emitter_of(hit.prim) != NO_EMITTER {
            if let Some((le, mis)) = emitter_hit(world, &hit, d, p.prev_delta, p.prev_pdf_w) {
                let l = &mut out[i];
                *if p.prefix { &mut l.prefix_le } else { &mut l.rest } += p.t.beta * le * mis;
            }
            return false; // emitters reflect nothing
        }
        let m = s.material_of(hit.prim);
        let sp = ShadingPoint { p: hit.p, ng: hit.ng, ns: hit.ns };
        let wo = -d;
        if let (true, &Material::Diffuse { albedo }) = (w.lanes_on, m) {
            w.live[k].prefix = false;
            // light_sample_mis's numbers, then bsdf::sample's
            let (li, pmf, _) = s.light_pick.sample(rng.next_f32());
            let u_light = rng.next_2d();
            let u = [rng.next_f32(), rng.next_f32(), rng.next_f32()];
            let LightRef::Area(e) = s.lights[li] else { unreachable!("lanes_apply checked the lights") };
            let em = &s.emitters[e as usize];
            let light = &s.triangles[em.prim as usize];
            let (p, ng, ns) = (sp.p, sp.ng, sp.ns);
            let v = Vertex {
                k: k as u32,
                p,
                ng,
                ns,
                wo,
                albedo,
                light,
                pmf,
                le: em.radiance,
                u_light,
                u_bsdf: [u[0], u[1]],
            };
            return w.lanes.push(v);
        }
        if !m.is_dirac() {
            p.prefix = false;
            match direct::light_sample_mis(world, &sp, m, wo, rng, |wi| bsdf::pdf_w(m, &sp, wo, wi)) {
                Some(ls) => {
                    w.nee.push((p.i, p.t.beta, ls.value));
                    w.shadow.push(ls.shadow);
                }
                None => out[i].rest += p.t.beta * Rgb::ZERO,
            }
        }
        let u = [rng.next_f32(), rng.next_f32(), rng.next_f32()];
        let Some(bs) = bsdf::sample(m, &sp, wo, u, Mode::Radiance) else { return false };
        if !p.t.scatter(&bs, depth, rng) {
            return false;
        }
        p.prev_delta = bs.is_delta;
        p.prev_pdf_w = bs.pdf_w;
        w.next_live.push(p);
        w.next_rays.push(Ray { o: offset_origin(hit.p, hit.ng, bs.wi), d: bs.wi, tmax: f32::INFINITY });
        false
    }

    /// Runs the queued diffuse vertices and finishes each as `shade` does: its NEE queued (or
    /// `β·0` added), its scattering and roulette.
    fn flush(&self, w: &mut Wave, depth: u32, rngs: &mut [Rng], out: &mut [CameraEstimate]) {
        w.lanes.run();
        for j in 0..w.lanes.n {
            let (mut p, r) = (w.live[w.lanes.k[j] as usize], w.lanes.out(j));
            match r.nee {
                Some((value, shadow)) => {
                    w.nee.push((p.i, p.t.beta, value));
                    w.shadow.push(shadow);
                }
                None => out[p.i as usize].rest += p.t.beta * Rgb::ZERO,
            }
            let Some((wi, pdf_w)) = r.bsdf else { continue };
            let bs = BsdfSample { wi, weight: r.albedo, pdf_w, is_delta: false, eta: 1.0 };
            if !p.t.scatter(&bs, depth, &mut rngs[p.i as usize]) {
                continue;
            }
            (p.prev_delta, p.prev_pdf_w) = (false, pdf_w);
            w.next_live.push(p);
            w.next_rays.push(Ray { o: offset_origin(r.p, r.ng, wi), d: wi, tmax: f32::INFINITY });
        }
        w.lanes.n = 0;
    }
}

/// Whether the lanes apply: every light is a triangle emitter (`path_lanes` samples those).
fn lanes_apply(s: &Scene) -> bool {
    s.lights.iter().all(|l| matches!(*l, LightRef::Area(e) if s.emitters[e as usize].prim < s.ntri()))
}
