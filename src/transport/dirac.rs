//! Following Dirac (mirror, glass) chains with the Fresnel-weighted choice, shared by the IWS
//! family (camera rays and `L_c` chains, spec §1 "Chain following"). `pt` and the particle
//! tracer walk Dirac vertices inside their own path loops with the same BSDF sampling and the
//! same roulette rule (`transport::roulette`).

use super::particle::MAX_VERTICES;
use super::roulette::{q_max, roulette};
use crate::accel::{offset_origin, Hit, World};
use crate::bsdf::{self, Mode, ShadingPoint};
use crate::math::{Rgb, Vec3};
use crate::sampling::rng::Rng;
use crate::scene::NO_EMITTER;

/// Chain vertices after which Russian roulette may end a Dirac chain (as `pt`).
pub const CHAIN_RR_VERTICES: u32 = 5;

/// Follows a Dirac chain from `hit` (reached along `d`) with throughput `beta`: Fresnel-weighted
/// choice at glass, roulette after [`CHAIN_RR_VERTICES`]. Returns the first non-Dirac hit
/// (possibly an emitter), the direction that reached it and the throughput; `None` on escape,
/// absorption or the vertex cap `cap` (at most [`MAX_VERTICES`]).
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
            beta = roulette(beta, q_max(beta), rng)?;
        }
        d = bs.wi;
        hit = world.intersect(offset_origin(hit.p, hit.ng, d), d, f32::INFINITY)?;
    }
    None
}

/// `E`, the emission a camera ray sees along its Dirac prefix: the first hit if it is an
/// emitter's front, or the emitter at the end of a mirror/glass chain from it, times the chain's
/// throughput (one unbiased estimate, the chain followed as [`follow_dirac_chain`]); zero when
/// the prefix ends on a non-specular surface, escapes or is absorbed. The pixel sampler averages
/// it over extra camera rays (`render`, `--emission-split`).
pub fn prefix_emission(world: &World, origin: Vec3, dir: Vec3, cap: u32, rng: &mut Rng) -> Rgb {
    let Some(hit) = world.intersect(origin, dir, f32::INFINITY) else { return Rgb::ZERO };
    let Some((z, d, beta)) = follow_dirac_chain(world, hit, dir, Rgb::ONE, cap, rng) else { return Rgb::ZERO };
    let e = world.scene.emitter_of(z.prim);
    if e == NO_EMITTER || z.ng.dot(-d) <= 0.0 {
        return Rgb::ZERO; // one-sided emission
    }
    beta * world.scene.emitters[e as usize].radiance
}
