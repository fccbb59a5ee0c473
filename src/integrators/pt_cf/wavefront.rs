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

use super::{Branches, Guide, GuidedPathTracer, PathState};
use crate::accel::{Ray, World};
use crate::bsdf::BsdfSample;
use crate::cf::mixture::DefensiveMixture;
use crate::integrators::pt::lanes::{Vertex, W};
use crate::integrators::pt::wavefront::Wave;
use crate::integrators::pt::{vertex, SurfaceVertex};
use crate::integrators::{CameraEstimate, Context};
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

/// A guided vertex of path `live`: the vertex `v` and its guide `g`.
struct GuidedVertex<'a> {
    live: Live,
    v: SurfaceVertex<'a>,
    g: Guide,
}

impl GuidedPathTracer {
    /// `trace` for every ray of `rays`, path `i` drawing from `rngs[i]`; `out[i]` is bit for bit
    /// `trace(rays[i])` with `ctx.rng = rngs[i]`. Requires no `--path-filter`. While one of its
    /// vertices is shaded, a path's stream is `ctx.rng` (swapped in and out), as in `trace`.
    pub(super) fn trace_batch(
        &self,
        world: &World,
        rays: &[Ray],
        rngs: &mut [Rng],
        cw: &mut CfWave,
        ctx: &mut Context,
        out: &mut Vec<CameraEstimate>,
    ) {
        debug_assert!(self.filter.is_none() && rays.len() == rngs.len());
        cw.wave.start(world, rays, |i| Live { i, st: PathState::camera(rays[i as usize]) }, out);
        // as `trace`: after the last vertex, its BSDF ray only for the emitter it may reach
        for depth in 0..=self.max_depth {
            if cw.wave.live.is_empty() {
                break;
            }
            cw.wave.intersect(world, depth, depth < self.max_depth);
            for k in 0..cw.wave.live.len() {
                let i = cw.wave.live[k].i as usize;
                std::mem::swap(&mut ctx.rng, &mut rngs[i]);
                let full = self.shade(world, cw, k, ctx, out);
                std::mem::swap(&mut ctx.rng, &mut rngs[i]);
                if full {
                    self.flush(cw, rngs, ctx, out);
                }
            }
            if cw.wave.lanes.n > 0 {
                self.flush(cw, rngs, ctx, out);
            }
            cw.wave.finish_bounce(world, out);
        }
    }

    /// One vertex of live path `k` (the body of `trace`'s loop), drawing from `ctx.rng`. An
    /// unguided diffuse vertex draws its numbers and goes to the lanes; true when they are full.
    fn shade(&self, world: &World, cw: &mut CfWave, k: usize, ctx: &mut Context, out: &mut [CameraEstimate]) -> bool {
        let (s, w) = (&world.scene, &mut cw.wave);
        let i = w.live[k].i;
        let Some(found) = w.hits[k] else {
            self.add_escaped(world, &w.live[k].st, ctx, &mut out[i as usize]);
            return false;
        };
        let hit = world.hit_at(&w.rays[k], found);
        if s.emitter_of(hit.prim) != NO_EMITTER {
            self.add_emitted(world, &w.live[k].st, &hit, ctx, &mut out[i as usize]);
            return false; // emitters reflect nothing
        }
        if w.live[k].st.vertex >= self.max_depth {
            return false; // the cap: this ray was traced for the emitter it may reach
        }
        let (m, sp) = world.shade(&hit, -w.live[k].st.walk.d);
        // the state is updated in place, not copied out and back (a copy right after a field's
        // store stalls on store forwarding)
        let v = self.enter(&mut w.live[k].st, &m, sp, &hit);
        if let Some(g) = self.guide_of(&w.live[k].st, &v, ctx) {
            let live = w.live[k];
            self.guided(world, w, GuidedVertex { live, v, g }, ctx, out);
            return false;
        }
        // the lanes run the untilted Lambertian BSDF: a normal-mapped point takes the scalar path
        if let (true, Material::Diffuse { albedo }, true) = (w.lanes_on, m, v.sp.n0 == v.sp.ns) {
            w.live[k].st.diffuse += 1;
            cw.t[w.lanes.n] = hit.t;
            return w.lanes.push(Vertex::draw(world, k, &v, albedo, &mut ctx.rng));
        }
        let mut st = w.live[k].st;
        let beta = st.walk.t.beta;
        let nee = |ls| w.queue_nee(i, beta, ls, out);
        let Some(bs) = vertex(world, &v, &mut ctx.rng, nee) else { return false };
        st.diffuse += u32::from(!m.is_dirac());
        self.leave_c(world, &mut st, &hit, &v, &bs);
        self.step(w, Live { i, st }, &bs, &v, ctx);
        false
    }

    /// A guided vertex: `trace`'s, with its NEE shadow ray queued; a split vertex runs its NEE
    /// and its branches on the spot, on the path's stream.
    fn guided(
        &self,
        world: &World,
        w: &mut Wave<Live>,
        gv: GuidedVertex,
        ctx: &mut Context,
        out: &mut [CameraEstimate],
    ) {
        let GuidedVertex { live: Live { i, mut st }, v, g } = gv;
        let (m, sp, wo) = (v.m, &v.sp, v.wo);
        st.diffuse += 1;
        let mix = DefensiveMixture::new(m, sp, wo, &g.tables, g.frame, g.weights);
        let n = g.n as f32;
        if g.n > 1 {
            let l = &mut out[i as usize];
            l.rest += st.walk.t.beta * direct::sample_light_mis(world, sp, m, wo, &mut ctx.rng, |wi| n * mix.pdf_w(wi));
            self.split(world, &st, &v, Branches { mix: &mix, n: g.n }, &mut l.rest, ctx);
            return;
        }
        let ls = direct::light_sample_mis(world, sp, m, wo, &mut ctx.rng, |wi| n * mix.pdf_w(wi));
        w.queue_nee(i, st.walk.t.beta, ls, out);
        let Some(ms) = mix.sample(&mut ctx.rng) else { return };
        st.walk.t.guided(ms.pdf_w, ms.bsdf_pdf_w);
        self.step(w, Live { i, st }, &ms.as_bsdf_sample(), &v, ctx);
    }

    /// Runs the queued diffuse vertices and finishes each as `trace` does: its NEE queued, its
    /// scattering, roulette and MIS ratio (each on its path's stream).
    fn flush(&self, cw: &mut CfWave, rngs: &mut [Rng], ctx: &mut Context, out: &mut [CameraEstimate]) {
        let w = &mut cw.wave;
        w.lanes.run();
        for (j, &t) in cw.t.iter().enumerate().take(w.lanes.n) {
            let (live, r) = (w.live[w.lanes.k[j] as usize], w.lanes.out(j));
            w.queue_nee(live.i, live.st.walk.t.beta, r.nee, out);
            let Some(bs) = r.bsdf else { continue };
            let m = Material::Diffuse { albedo: r.albedo };
            let v = SurfaceVertex { m: &m, sp: r.sp, wo: r.wo, t, index: live.st.vertex - 1 };
            let rng = &mut rngs[live.i as usize];
            std::mem::swap(&mut ctx.rng, rng);
            self.step(w, live, &bs, &v, ctx);
            std::mem::swap(&mut ctx.rng, rng);
        }
        w.lanes.n = 0;
    }

    /// Applies the continuation `bs` drawn at vertex `v` (`Walk::scatter`, then `track_mis`) and
    /// queues the path for the next bounce if it goes on.
    #[inline(always)]
    fn step(
        &self,
        w: &mut Wave<Live>,
        Live { i, mut st }: Live,
        bs: &BsdfSample,
        v: &SurfaceVertex,
        ctx: &mut Context,
    ) {
        if !st.walk.scatter(bs, v.index, &v.sp, &mut ctx.rng) {
            return;
        }
        self.track_mis(&mut st, v, ctx);
        w.next_rays.push(st.walk.ray());
        w.next_live.push(Live { i, st });
    }
}
