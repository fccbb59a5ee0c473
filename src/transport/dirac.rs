//! Following Dirac (mirror, glass) chains with the Fresnel-weighted choice, shared by the IWS
//! family (camera rays and `L_c` chains, spec §1 "Chain following"). `pt` and the particle
//! tracer walk Dirac vertices inside their own path loops with the same BSDF sampling and the
//! same roulette rule (`transport::roulette`).
//!
//! [`prefix_emission`] estimates `E`, the emission a camera ray reaches along its Dirac prefix,
//! for the extra rays of emission splitting (`render::pixel`). Invariant the splitting's
//! unbiasedness rests on: every integrator's `CameraEstimate::prefix_le` is an estimate of the
//! same `E` with the same truncation: weight 1 (no MIS on a Dirac prefix), the BSDF's own
//! sampling, roulette from vertex [`RR_FROM_VERTEX`](super::roulette::RR_FROM_VERTEX) on
//! β·etaScale ([`Throughput`], as `pt`'s), one-sided emitters, and the integrator's own vertex cap
//! (`Integrator::prefix_cap`).

use super::particle::MAX_VERTICES;
use super::roulette::Throughput;
use crate::accel::{offset_origin, Hit, World};
use crate::bsdf::{self, Mode};
use crate::math::{Rgb, Vec3};
use crate::sampling::rng::Rng;
use crate::scene::NO_EMITTER;

/// Follows a Dirac chain from `hit` (reached along `d`) with throughput `beta`: Fresnel-weighted
/// choice at glass, roulette as `pt`'s ([`Throughput::scatter`], from vertex [`RR_FROM_VERTEX`](super::roulette::RR_FROM_VERTEX)).
/// Returns the first non-Dirac hit (possibly an emitter; `None` where the chain escapes to the
/// environment), the direction that reached it and the throughput; `None` on absorption or the
/// vertex cap `cap` (at most [`MAX_VERTICES`]).
pub fn follow_dirac_chain(
    world: &World,
    hit: Hit,
    d: Vec3,
    beta: Rgb,
    cap: u32,
    rng: &mut Rng,
) -> Option<(Option<Hit>, Vec3, Rgb)> {
    follow_chain(world, hit, d, beta, cap.min(MAX_VERTICES), rng)
}

/// [`follow_dirac_chain`] with the cap `cap` as given (`pt`'s `--max-depth` may exceed 64).
fn follow_chain(
    world: &World,
    mut hit: Hit,
    mut d: Vec3,
    beta: Rgb,
    cap: u32,
    rng: &mut Rng,
) -> Option<(Option<Hit>, Vec3, Rgb)> {
    let s = &world.scene;
    let mut t = Throughput::new(beta);
    for v in 0..cap {
        // a surface whose material is not Dirac ends the chain before it is shaded (no texture
        // lookups): `shade` keeps the material's kind, or gives black behind a one-sided one
        if s.emitter_of(hit.prim) != NO_EMITTER || !s.material_of(hit.prim).is_dirac() {
            return Some((Some(hit), d, t.beta));
        }
        let (m, sp) = world.shade(&hit, -d);
        if !m.is_dirac() {
            return Some((Some(hit), d, t.beta));
        }
        let u = rng.next_3d();
        let bs = bsdf::sample(&m, &sp, -d, u, Mode::Radiance)?;
        if !t.scatter(&bs, v, rng) {
            return None;
        }
        d = bs.wi;
        match world.intersect(offset_origin(hit.p, hit.ng, d), d, f32::INFINITY) {
            Some(next) => hit = next,
            // as `pt`'s loop, which sees a miss only while it has vertices left
            None => return (v + 1 < cap).then_some((None, d, t.beta)),
        }
    }
    None
}

/// `E`, the emission a camera ray sees along its Dirac prefix: the first hit if it is an
/// emitter's front, or the emitter at the end of a mirror/glass chain from it, times the chain's
/// throughput (one unbiased estimate, the chain followed as [`follow_dirac_chain`] but up to
/// `cap` vertices as given, the integrator's `prefix_cap`), or the environment where it escapes;
/// zero when the prefix ends on a non-specular surface, is absorbed or reaches the cap. The
/// pixel sampler averages it over extra camera rays (`render::pixel`, `--emission-split`).
pub fn prefix_emission(world: &World, origin: Vec3, dir: Vec3, cap: u32, rng: &mut Rng) -> Rgb {
    let Some(hit) = world.intersect(origin, dir, f32::INFINITY) else {
        return if cap > 0 { environment(world, dir) } else { Rgb::ZERO };
    };
    let Some((z, d, beta)) = follow_chain(world, hit, dir, Rgb::ONE, cap, rng) else { return Rgb::ZERO };
    let Some(z) = z else { return beta * environment(world, d) };
    let e = world.scene.emitter_of(z.prim);
    if e == NO_EMITTER || z.ng.dot(-d) <= 0.0 {
        return Rgb::ZERO; // one-sided emission
    }
    beta * world.scene.emitters[e as usize].radiance
}

/// The environment's radiance along `d` (0 without one): what a ray that escapes sees, unweighted
/// (the Dirac prefixes and the IWS family, where no other strategy reaches it).
#[inline]
pub fn environment(world: &World, d: Vec3) -> Rgb {
    world.scene.environment.as_ref().map_or(Rgb::ZERO, |e| e.radiance(d))
}
