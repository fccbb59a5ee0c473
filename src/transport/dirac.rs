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
//!
//! The chain follower intersects and shades through a [`Tracer`]: [`Direct`] (the world, every
//! integrator's path) or [`RayMemo`] (the emission-split probe's repeats answered from memory);
//! both give the same values and draw the same random numbers, bit for bit.

use super::particle::MAX_VERTICES;
use super::roulette::Throughput;
use crate::accel::{offset_origin, Hit, World};
use crate::bsdf::{self, Material, Mode, ShadingPoint};
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
    follow_chain(world, &mut Direct, hit, d, beta, cap.min(MAX_VERTICES), rng)
}

/// How a chain follower intersects and shades: [`Direct`] asks the world every time (every
/// integrator's path); [`RayMemo`] answers a ray it has seen from memory (the emission-split
/// probe, which traces the same chains many times). Both answer exactly what `World::intersect`
/// (unbounded) and `World::shade` answer, bit for bit.
pub trait Tracer {
    /// `world.intersect(origin, dir, ∞)`.
    fn intersect(&mut self, world: &World, origin: Vec3, dir: Vec3) -> Option<Hit>;
    /// `world.shade(hit, wo)`.
    fn shade(&mut self, world: &World, hit: &Hit, wo: Vec3) -> (Material, ShadingPoint);
}

/// The world's own intersection and shading, inlined (no state, no overhead).
pub struct Direct;

impl Tracer for Direct {
    #[inline(always)]
    fn intersect(&mut self, world: &World, origin: Vec3, dir: Vec3) -> Option<Hit> {
        world.intersect(origin, dir, f32::INFINITY)
    }
    #[inline(always)]
    fn shade(&mut self, world: &World, hit: &Hit, wo: Vec3) -> (Material, ShadingPoint) {
        world.shade(hit, wo)
    }
}

/// A memo of intersections keyed by the ray's bits (origin, direction) and of shadings keyed by
/// the hit's and `wo`'s bits: exact by construction, as both are deterministic functions of
/// those bits. For rays traced many times over (the probe's chains from one lattice point: the
/// same camera ray, mostly the same Fresnel choices); [`RayMemo::clear`] between unrelated
/// rays. Holds at most [`RayMemo::CAPACITY`] of each (linear search); beyond, it asks the world.
#[derive(Default)]
pub struct RayMemo {
    rays: Vec<([u32; 6], Option<Hit>)>,
    shades: Vec<([u32; 14], Material, ShadingPoint)>,
}

impl RayMemo {
    /// The most rays (and shadings) remembered.
    pub const CAPACITY: usize = 64;

    /// Forgets everything (the memo is only worth it within one lattice point's chains).
    pub fn clear(&mut self) {
        self.rays.clear();
        self.shades.clear();
    }
}

fn bits3(v: Vec3) -> [u32; 3] {
    v.to_array().map(f32::to_bits)
}

impl Tracer for RayMemo {
    fn intersect(&mut self, world: &World, origin: Vec3, dir: Vec3) -> Option<Hit> {
        let ([a, b, c], [x, y, z]) = (bits3(origin), bits3(dir));
        let key = [a, b, c, x, y, z];
        if let Some(&(_, hit)) = self.rays.iter().find(|(k, _)| *k == key) {
            return hit;
        }
        let hit = world.intersect(origin, dir, f32::INFINITY);
        if self.rays.len() < Self::CAPACITY {
            self.rays.push((key, hit));
        }
        hit
    }

    fn shade(&mut self, world: &World, hit: &Hit, wo: Vec3) -> (Material, ShadingPoint) {
        let mut key = [0; 14];
        key[0] = hit.t.to_bits();
        key[1] = hit.prim;
        key[2..5].copy_from_slice(&bits3(hit.p));
        key[5..8].copy_from_slice(&bits3(hit.ng));
        key[8..11].copy_from_slice(&bits3(hit.ns));
        key[11..14].copy_from_slice(&bits3(wo));
        if let Some(&(_, m, sp)) = self.shades.iter().find(|(k, ..)| *k == key) {
            return (m, sp);
        }
        let (m, sp) = world.shade(hit, wo);
        if self.shades.len() < Self::CAPACITY {
            self.shades.push((key, m, sp));
        }
        (m, sp)
    }
}

/// [`follow_dirac_chain`] with the cap `cap` as given (`pt`'s `--max-depth` may exceed 64).
fn follow_chain<T: Tracer>(
    world: &World,
    tracer: &mut T,
    mut hit: Hit,
    mut d: Vec3,
    beta: Rgb,
    cap: u32,
    rng: &mut Rng,
) -> Option<(Option<Hit>, Vec3, Rgb)> {
    let s = &world.scene;
    let mut t = Throughput::new(beta);
    for v in 0..cap {
        // a chain ends on an emitter or a non-Dirac BSDF: whether the BSDF is Dirac is its
        // stored variant's (textures set parameters, never the variant), so the point is shaded
        // (its textures read) only where it may go on; there `shade` may still give `Black` (a
        // one-sided mirror seen from behind)
        if s.emitter_of(hit.prim) != NO_EMITTER || !s.material_of(hit.prim).is_dirac() {
            return Some((Some(hit), d, t.beta));
        }
        let (m, sp) = tracer.shade(world, &hit, -d);
        if !m.is_dirac() {
            return Some((Some(hit), d, t.beta));
        }
        let u = rng.next_3d();
        let bs = bsdf::sample(&m, &sp, -d, u, Mode::Radiance)?;
        if !t.scatter(&bs, v, rng) {
            return None;
        }
        d = bs.wi;
        match tracer.intersect(world, offset_origin(hit.p, hit.ng, d), d) {
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
    prefix_emission_with(world, &mut Direct, origin, dir, cap, rng)
}

/// [`prefix_emission`] intersecting and shading through `tracer` (the same value, bit for bit,
/// and the same random numbers drawn, for every [`Tracer`]).
#[inline]
pub fn prefix_emission_with<T: Tracer>(
    world: &World,
    tracer: &mut T,
    origin: Vec3,
    dir: Vec3,
    cap: u32,
    rng: &mut Rng,
) -> Rgb {
    let Some(hit) = tracer.intersect(world, origin, dir) else {
        return if cap > 0 { environment(world, dir) } else { Rgb::ZERO };
    };
    let Some((z, d, beta)) = follow_chain(world, tracer, hit, dir, Rgb::ONE, cap, rng) else { return Rgb::ZERO };
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
