//! The preprocess measurement of every kept cluster's [`CausticShare`] (`cf/share.rs`):
//! `E_c` from the cluster's forecast photons (flux over area), `E_d` by a cosine `pt` gather at a
//! few of its caustic points. Run on rank 0 after the CF product is built; its result is part of
//! the broadcast product.
//!
//! Invariants: a pure function of (scene, product, seed): each gather path's random numbers are
//! keyed by (cluster, path index), so the result does not depend on the thread count.

use crate::accel::{offset_origin, World};
use crate::cf::estimator::CausticForecast;
pub use crate::cf::share::CausticShare;
use crate::integrators::pt::PathTracer;
use crate::math::{luminance, Frame, PI};
use crate::sampling::rng::{stream, Rng};
use crate::sampling::warp::sample_cosine_hemisphere;
use crate::scene::NO_EMITTER;
use crate::transport::context::Context;
use rayon::prelude::*;

/// Points per kept cluster and cosine directions per point of the share gather.
const SHARE_POINTS: usize = 16;
const SHARE_DIRS: usize = 256;

/// The [`CausticShare`] of every kept cluster: at up to [`SHARE_POINTS`] of its caustic points
/// (evenly spaced in member order), [`SHARE_DIRS`] cosine-distributed `pt` paths, each split
/// into emission reached through a Dirac chain (`E_c`) and the rest (`E_d`); paths whose first
/// hit is an emitter are direct light and skipped. A pure function of (scene, product, seed):
/// each path's random numbers are keyed by (cluster, path index), whatever the thread count.
pub fn caustic_shares(world: &World, cf: &CausticForecast, max_depth: u32, seed: u64) -> Vec<CausticShare> {
    caustic_shares_until(world, cf, max_depth, seed, &|| false)
}

/// [`caustic_shares`], each cluster's gather ending at its next point once `stop()` holds (a
/// time box's share, a signal): its means are then over the points gathered (at least none:
/// a share of 0, an unguided cluster). The shares only steer the guiding, never the image's
/// expectation.
pub fn caustic_shares_until(
    world: &World,
    cf: &CausticForecast,
    max_depth: u32,
    seed: u64,
    stop: &(dyn Fn() -> bool + Sync),
) -> Vec<CausticShare> {
    let kept = cf.clustering.kept(cf.opts.max_rank);
    let pt = PathTracer::new(max_depth);
    kept.par_iter()
        .enumerate()
        .map(|(k, cl)| {
            let m = cl.members.len();
            let n_points = SHARE_POINTS.min(m);
            let (mut ec, mut ed) = (0.0f64, 0.0f64);
            let mut gathered = 0;
            for i in 0..n_points {
                if stop() {
                    break;
                }
                gathered += 1;
                let Some(cp) = cf.points.get(cl.members[i * m / n_points] as usize) else { continue };
                let (x, frame) = (cp.pos(), Frame::from_normal(cp.normal()));
                for j in 0..SHARE_DIRS {
                    let mut ctx = Context::new(Rng::keyed(seed, stream::GUIDE, k as u64, (i * SHARE_DIRS + j) as u64));
                    let wi = frame.to_world(sample_cosine_hemisphere([ctx.rng.next_f32(), ctx.rng.next_f32()]));
                    let o = offset_origin(x, cp.normal(), wi);
                    match world.intersect(o, wi, f32::INFINITY) {
                        Some(h) if world.scene.emitter_of(h.prim) == NO_EMITTER => {}
                        _ => continue, // escaped, or direct light
                    }
                    // cos/pdf = π for cosine sampling
                    let l = pt.trace(world, o, wi, &mut ctx);
                    ec += (PI * luminance(l.prefix_le)) as f64;
                    ed += (PI * luminance(l.rest)) as f64;
                }
            }
            let n = (gathered * SHARE_DIRS).max(1) as f64;
            // the cluster's photon flux over its area (`Cluster::density`, power / area)
            let photons = if cl.density.is_finite() { cl.density } else { 0.0 };
            CausticShare { caustic: photons, caustic_gather: (ec / n) as f32, other: (ed / n) as f32 }
        })
        .collect()
}
