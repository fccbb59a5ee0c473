//! `pt-cf`'s camera side as a wavefront over a batch of camera rays, on `pt::wavefront`'s
//! buffers: the estimator of `GuidedPathTracer::trace`, path by path and bit for bit, with each
//! bounce's rays traced in one batch, its shadow rays in another, its unguided vertices run by
//! `pt::vertex` and the diffuse ones sixteen at a time (`pt::lanes`).
//!
//! Invariants (why it is bit-identical to `trace`, `tests/wavefront.rs`):
//! - each path draws from its own stream in `trace`'s order; a path's contributions are added in
//!   `trace`'s order (the emitter hit of bounce k, NEE at k, then bounce k + 1);
//! - a guided vertex is `trace`'s guided vertex with its NEE shadow ray queued; a split vertex
//!   (diffuse depth 0, `n > 1` continuations) runs `trace`'s own NEE and `GuidedPathTracer::split`
//!   on the spot, on the path's stream, so its branches are scalar paths;
//! - an unguided diffuse vertex goes to the lanes as in `pt`'s wavefront, and its MIS ratio
//!   against the light paths (`track_mis`) is updated from the lane's result;
//! - `--path-filter` runs `trace` ray by ray (`estimate_each`).

use super::{Guide, GuidedPathTracer, PathState};
use crate::accel::{Ray, World};
use crate::bsdf::{BsdfSample, ShadingPoint};
use crate::cf::mixture::DefensiveMixture;
use crate::integrators::pt::lanes::{Vertex, W};
use crate::integrators::pt::vertex;
use crate::integrators::pt::wavefront::Wave;
use crate::integrators::{CameraEstimate, Context};
use crate::math::Vec3;
use crate::sampling::rng::Rng;
use crate::scene::{Material, NO_EMITTER};
use crate::transport::direct;

/// One live path: its camera ray's index (of its stream and estimate) and its state.
#[derive(Clone, Copy)]
pub(super) struct Live {
    i: u32,
    st: PathState,
}

/// The wavefront's buffers (kept in `Context::scratch` between batches).
#[derive(Default)]
pub(super) struct CfWave {
    wave: Wave<Live>,
    /// The hit distance of each queued lane's vertex (its MIS ratio at vertex 0).
    t: [f32; W],
}

/// A vertex's material, point, direction toward the previous vertex and distance from it.
type At<'a> = (&'a Material, &'a ShadingPoint, Vec3, f32);

impl GuidedPathTracer {
    /// `trace` for every ray of `rays`, path `i` drawing from `rngs[i]`; `out[i]` is bit for bit
    /// `trace(rays[i])` with `ctx.rng = rngs[i]`. Requires no `--path-filter`.
    pub(super) fn trace_batch(
        &self,
        world: &World,
        (rays, rngs): (&[Ray], &mut [Rng]),
        cw: &mut CfWave,
        ctx: &mut Context,
        out: &mut Vec<CameraEstimate>,
    ) {
        debug_assert!(self.filter.is_none() && rays.len() == rngs.len());
        let w = &mut cw.wave;
        w.start(world, rays, |i| Live { i, st: PathState::camera(rays[i as usize]) }, out);
        for depth in 0..self.max_depth {
            if w.live.is_empty() {
                break;
            }
            w.intersect(world, depth);
            for k in 0..w.live.len() {
                if self.shade(world, (w, &mut cw.t), k, (rngs, ctx), out) {
                    self.flush(w, &cw.t, (rngs, ctx), out);
                }
            }
            if w.lanes.n > 0 {
                self.flush(w, &cw.t, (rngs, ctx), out);
            }
            w.finish_bounce(world, out);
        }
    }

    /// One vertex of live path `k` (the body of `trace`'s loop). An unguided diffuse vertex
    /// draws its numbers and goes to the lanes; true when they are full.
    fn shade(
        &self,
        world: &World,
        (w, lane_t): (&mut Wave<Live>, &mut [f32; W]),
        k: usize,
        (rngs, ctx): (&mut [Rng], &mut Context),
        out: &mut [CameraEstimate],
    ) -> bool {
        let s = &world.scene;
        let Some(found) = w.hits[k] else { return false };
        let hit = world.hit_at(&w.rays[k], found);
        let i = w.live[k].i;
        let rng = &mut rngs[i as usize];
        if s.emitter_of(hit.prim) != NO_EMITTER {
            self.add_emitted(world, &w.live[k].st, &hit, ctx, &mut out[i as usize]);
            return false; // emitters reflect nothing
        }
        let m = s.material_of(hit.prim);
        // the state is updated in place, not copied out and back (a copy right after a field's
        // store stalls on store forwarding)
        let (sp, wo, depth) = self.enter(&mut w.live[k].st, m, &hit);
        let at = (depth, hit.p, hit.ng);
        if let Some(g) = self.guide_of(&w.live[k].st, (m, &sp, wo), ctx) {
            let st = w.live[k].st;
            self.guided(world, w, (i, st, g), (m, &sp, wo, hit.t), (rng, ctx), out);
            return false;
        }
        if let (true, &Material::Diffuse { albedo }) = (w.lanes_on, m) {
            w.live[k].st.diffuse += 1;
            lane_t[w.lanes.n] = hit.t;
            return w.lanes.push(Vertex::draw(world, k, (&sp, wo, albedo), rng));
        }
        let mut st = w.live[k].st;
        let beta = st.walk.t.beta;
        let Some(bs) = vertex(world, (m, &sp, wo), rng, |ls| w.queue_nee((i, beta), ls, out)) else { return false };
        st.diffuse += u32::from(!m.is_dirac());
        self.step(w, (i, st), (at, &bs), (m, &sp, wo, hit.t), (rng, ctx));
        false
    }

    /// A guided vertex `v` of path `i` (its guide `g`): `trace`'s, with its NEE shadow ray
    /// queued; a split vertex runs its NEE and its branches on the spot, on the path's stream.
    fn guided(
        &self,
        world: &World,
        w: &mut Wave<Live>,
        (i, mut st, g): (u32, PathState, Guide),
        v: At,
        (rng, ctx): (&mut Rng, &mut Context),
        out: &mut [CameraEstimate],
    ) {
        let (m, sp, wo, _) = v;
        let at = (st.vertex - 1, sp.p, sp.ng);
        st.diffuse += 1;
        let mix = DefensiveMixture::new(m, sp, wo, &g.tables, g.frame, g.weights);
        let n = g.n as f32;
        if g.n > 1 {
            let l = &mut out[i as usize];
            l.rest += st.walk.t.beta * direct::sample_light_mis(world, sp, m, wo, rng, |wi| n * mix.pdf_w(wi));
            std::mem::swap(&mut ctx.rng, rng);
            self.split(world, (&st, at), (&mix, g.n), v, &mut l.rest, ctx);
            std::mem::swap(&mut ctx.rng, rng);
            return;
        }
        let ls = direct::light_sample_mis(world, sp, m, wo, rng, |wi| n * mix.pdf_w(wi));
        w.queue_nee((i, st.walk.t.beta), ls, out);
        let Some(ms) = mix.sample(rng) else { return };
        st.walk.t.guided(ms.pdf_w, ms.bsdf_pdf_w);
        self.step(w, (i, st), (at, &ms.as_bsdf_sample()), v, (rng, ctx));
    }

    /// Runs the queued diffuse vertices and finishes each as `trace` does: its NEE queued, its
    /// scattering, roulette and MIS ratio.
    fn flush(
        &self,
        w: &mut Wave<Live>,
        lane_t: &[f32; W],
        (rngs, ctx): (&mut [Rng], &mut Context),
        out: &mut [CameraEstimate],
    ) {
        w.lanes.run();
        for (j, &t) in lane_t.iter().enumerate().take(w.lanes.n) {
            let (Live { i, st }, r) = (w.live[w.lanes.k[j] as usize], w.lanes.out(j));
            w.queue_nee((i, st.walk.t.beta), r.nee, out);
            let Some(bs) = r.bsdf else { continue };
            let (m, sp) = (Material::Diffuse { albedo: r.albedo }, ShadingPoint { p: r.p, ng: r.ng, ns: r.ns });
            let at = (st.vertex - 1, r.p, r.ng);
            self.step(w, (i, st), (at, &bs), (&m, &sp, r.wo, t), (&mut rngs[i as usize], ctx));
        }
        w.lanes.n = 0;
    }

    /// Applies the continuation `bs` drawn at vertex `at` (`continue_path`, then `track_mis`)
    /// and queues the path for the next bounce if it goes on.
    #[inline(always)]
    fn step(
        &self,
        w: &mut Wave<Live>,
        (i, mut st): (u32, PathState),
        (at, bs): ((u32, Vec3, Vec3), &BsdfSample),
        v: At,
        (rng, ctx): (&mut Rng, &Context),
    ) {
        if !st.walk.scatter(bs, at, rng) {
            return;
        }
        self.track_mis(&mut st, v, at.0, ctx);
        w.next_rays.push(st.walk.ray());
        w.next_live.push(Live { i, st });
    }
}
