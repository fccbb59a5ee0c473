//! `pt`'s vertex, written once: the path state it updates ([`Walk`]) and what it does at a
//! surface ([`vertex`]). `pt`'s scalar loop, its wavefront, and `pt-cf`'s unguided vertices
//! (scalar and wavefront) all run these functions; what differs between them is only where the
//! next-event estimate goes (added at once after its shadow ray, or queued with the bounce's
//! shadow rays) and which paths are traced side by side.
//!
//! Invariants: a path draws from its own stream in this order at a vertex: NEE's light pick and
//! point (non-Dirac vertices only), the BSDF's three numbers, then roulette's one (from
//! `transport::roulette::RR_FROM_VERTEX` on). MIS pairs NEE with BSDF sampling by the power
//! heuristic on the same two pdfs at both ends (`transport::direct::emitter_hit`).

use crate::accel::{offset_origin, Hit, Ray, World};
use crate::bsdf::{self, BsdfSample, Mode, ShadingPoint};
use crate::math::{Rgb, Vec3};
use crate::sampling::rng::Rng;
use crate::scene::Material;
use crate::transport::direct::{self, LightSample};
use crate::transport::roulette::Throughput;

/// A path's vertex on a surface that is not an emitter: what its BSDF, NEE and a guide see.
#[derive(Clone, Copy, Debug)]
pub struct SurfaceVertex<'a> {
    /// Its material.
    pub m: &'a Material,
    /// Its position and normals.
    pub sp: ShadingPoint,
    /// The direction toward the previous vertex (unit).
    pub wo: Vec3,
    /// Its distance from the previous vertex.
    pub t: f32,
    /// Its index along the path (0: the camera ray's first hit).
    pub index: u32,
}

impl<'a> SurfaceVertex<'a> {
    /// The vertex `index` of a path at `hit`, reached along `d`, where the BSDF is `m` at `sp`
    /// (`World::shade`).
    #[inline(always)]
    pub fn at(m: &'a Material, sp: ShadingPoint, hit: &Hit, d: Vec3, index: u32) -> Self {
        SurfaceVertex { m, sp, wo: -d, t: hit.t, index }
    }
}

/// A path in flight: its next ray, its throughput and how its last vertex drew that ray.
#[derive(Clone, Copy, Debug)]
pub struct Walk {
    /// The next ray's origin.
    pub o: Vec3,
    /// The next ray's (unit) direction.
    pub d: Vec3,
    /// β and the roulette's scales.
    pub t: Throughput,
    /// The last direction came from a Dirac lobe (or the camera).
    pub prev_delta: bool,
    /// The solid-angle pdf the last direction was drawn with (for MIS against NEE).
    pub prev_pdf_w: f32,
}

impl Walk {
    /// A camera path starting along `ray`.
    #[inline]
    pub fn camera(ray: Ray) -> Walk {
        Walk { o: ray.o, d: ray.d, t: Throughput::new(Rgb::ONE), prev_delta: true, prev_pdf_w: 0.0 }
    }

    /// The next ray.
    #[inline]
    pub fn ray(&self) -> Ray {
        Ray { o: self.o, d: self.d, tmax: f32::INFINITY }
    }

    /// `(Le, MIS weight)` where the ray hits the front of an emitter (`direct::emitter_hit`).
    #[inline]
    pub fn emitted(&self, world: &World, hit: &Hit) -> Option<(Rgb, f32)> {
        direct::emitter_hit(world, hit, self.d, self.prev_delta, self.prev_pdf_w)
    }

    /// `(Le, MIS weight)` of the environment where the ray escapes (`direct::escaped`).
    #[inline]
    pub fn escaped(&self, world: &World) -> Option<(Rgb, f32)> {
        direct::escaped(world, self.d, self.prev_delta, self.prev_pdf_w)
    }

    /// Vertex `index` at `sp` scatters into `bs`: β·weight and roulette
    /// ([`Throughput::scatter`]), then the next ray. False when the path ends.
    #[inline]
    pub fn scatter(&mut self, bs: &BsdfSample, index: u32, sp: &ShadingPoint, rng: &mut Rng) -> bool {
        if !self.t.scatter(bs, index, rng) {
            return false;
        }
        self.prev_delta = bs.is_delta;
        self.prev_pdf_w = bs.pdf_w;
        self.o = offset_origin(sp.p, sp.ng, bs.wi);
        self.d = bs.wi;
        true
    }
}

/// `pt` at the surface vertex `v`: at a non-Dirac material, one NEE sample MIS-weighted against
/// the BSDF, before its shadow ray, handed to `nee`; then the BSDF's direction (`None`: the path
/// ends).
#[inline(always)]
pub fn vertex(
    world: &World,
    v: &SurfaceVertex,
    rng: &mut Rng,
    nee: impl FnOnce(Option<LightSample>),
) -> Option<BsdfSample> {
    let (m, sp, wo) = (v.m, &v.sp, v.wo);
    if !m.is_dirac() {
        nee(direct::light_sample_mis(world, sp, m, wo, rng, |wi| bsdf::pdf_w(m, sp, wo, wi)));
    }
    let u = rng.next_3d();
    bsdf::sample(m, sp, wo, u, Mode::Radiance)
}
