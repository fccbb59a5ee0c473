//! `pt`'s diffuse vertices sixteen at a time: the wavefront (`pt::wavefront`) queues each vertex
//! on a `Material::Diffuse` surface, in a scene whose lights are all triangle emitters, into the
//! lanes of [`Lanes`], which compute their next-event estimate and their cosine-weighted direction
//! as loops over structure-of-arrays records that LLVM runs as 16-wide vectors.
//!
//! The lanes own no formula: each lane calls the scalar code's own functions
//! (`bsdf::diffuse`, `transport::direct::{toward, light_pdf_w, area_light_value}`,
//! `accel::shadow_segment`, `sampling::warp`), written without early returns for this purpose. A
//! new diffuse-like BSDF is written once, in its `bsdf/` file, and runs here by calling it.
//!
//! Invariants (why the image is the scalar loop's bit for bit, `tests/wavefront.rs`):
//! - the random numbers are drawn by the caller in the scalar order (the light pick, the point on
//!   the light, the BSDF's three), from the path's own stream;
//! - a branch that returns `None` in the scalar code is a lane mask here, and a lane whose mask
//!   is off adds `β·0`, as the scalar code does.

use super::vertex::SurfaceVertex;
use crate::accel::{shadow_segment, Ray, World};
use crate::bsdf::{diffuse, BsdfSample, ShadingPoint};
use crate::math::{Rgb, Vec3};
use crate::sampling::rng::Rng;
use crate::sampling::warp::{sample_triangle, triangle_point};
use crate::scene::LightRef;
use crate::scene::Triangle;
use crate::transport::direct::{self, LightSample};

/// Lanes per record.
pub(crate) const W: usize = 16;
type L = [f32; W];

/// A `Vec3` per lane.
#[derive(Clone, Copy, Default)]
struct V3 {
    x: L,
    y: L,
    z: L,
}

impl V3 {
    #[inline(always)]
    fn get(&self, j: usize) -> Vec3 {
        Vec3::new(self.x[j], self.y[j], self.z[j])
    }
    #[inline(always)]
    fn set(&mut self, j: usize, v: Vec3) {
        (self.x[j], self.y[j], self.z[j]) = (v.x, v.y, v.z);
    }
}

/// One diffuse vertex, as the scalar shade loop hands it over.
pub(crate) struct Vertex<'a> {
    /// The wavefront's live index of the path.
    pub k: u32,
    /// Position, geometric and shading normal.
    pub sp: ShadingPoint,
    /// Toward the previous vertex.
    pub wo: Vec3,
    /// The diffuse reflectance.
    pub albedo: Rgb,
    /// The picked emitter's triangle, its light-pick pmf and radiance.
    pub light: &'a Triangle,
    pub pmf: f32,
    pub le: Rgb,
    /// The point on the light's two uniforms, then the BSDF's first two.
    pub u_light: [f32; 2],
    pub u_bsdf: [f32; 2],
}

impl<'a> Vertex<'a> {
    /// The record of live path `k`'s vertex `v` (of reflectance `albedo`), its numbers drawn from
    /// `rng` in the scalar order: the light pick, the point on the light, then the BSDF's three
    /// (`direct::light_sample_mis`, then `bsdf::sample`). Requires `pt::wavefront::lanes_apply`.
    #[inline(always)]
    pub fn draw(world: &'a World, k: usize, v: &SurfaceVertex, albedo: Rgb, rng: &mut Rng) -> Self {
        let s = &world.scene;
        let (li, pmf, _) = s.light_pick.sample(rng.next_f32());
        let u_light = rng.next_2d();
        let u = rng.next_3d();
        let LightRef::Area(e) = s.lights[li] else { unreachable!("lanes_apply checked the lights") };
        let em = &s.emitters[e as usize];
        Vertex {
            k: k as u32,
            sp: v.sp,
            wo: v.wo,
            albedo,
            light: &s.triangles[em.prim as usize],
            pmf,
            le: em.radiance,
            u_light,
            u_bsdf: [u[0], u[1]],
        }
    }
}

/// Sixteen queued vertices and, after `run`, their NEE samples and scattered directions.
#[derive(Default)]
pub(crate) struct Lanes {
    /// Lanes filled.
    pub n: usize,
    /// Live index of each lane's path.
    pub k: [u32; W],
    p: V3,
    ng: V3,
    ns: V3,
    wo: V3,
    albedo: V3,
    y0: V3,
    y1: V3,
    y2: V3,
    ny: V3,
    area: L,
    pmf: L,
    le: V3,
    u_light: [L; 2],
    u_bsdf: [L; 2],
    nee_ok: [bool; W],
    value: V3,
    shadow_o: V3,
    shadow_d: V3,
    shadow_t: L,
    bsdf_ok: [bool; W],
    wi: V3,
    pdf_w: L,
}

/// What `run` computed for one lane.
pub(crate) struct LaneOut {
    /// The NEE contribution and its shadow segment (`None` where the scalar code returns `None`).
    pub nee: Option<LightSample>,
    /// The sampled direction (`None` where `bsdf::sample` returns `None`).
    pub bsdf: Option<BsdfSample>,
    /// The vertex's position and normals.
    pub sp: ShadingPoint,
    /// Toward the previous vertex.
    pub wo: Vec3,
    /// The diffuse reflectance.
    pub albedo: Rgb,
}

impl Lanes {
    /// Queues `v`; true when the record is full.
    #[inline]
    pub fn push(&mut self, v: Vertex) -> bool {
        let j = self.n;
        self.k[j] = v.k;
        for (f, x) in [(&mut self.p, v.sp.p), (&mut self.ng, v.sp.ng), (&mut self.ns, v.sp.ns), (&mut self.wo, v.wo)] {
            f.set(j, x);
        }
        self.albedo.set(j, v.albedo);
        let t = v.light;
        for (f, x) in [(&mut self.y0, t.p[0]), (&mut self.y1, t.p[1]), (&mut self.y2, t.p[2]), (&mut self.ny, t.ng)] {
            f.set(j, x);
        }
        (self.area[j], self.pmf[j]) = (t.area, v.pmf);
        self.le.set(j, v.le);
        (self.u_light[0][j], self.u_light[1][j]) = (v.u_light[0], v.u_light[1]);
        (self.u_bsdf[0][j], self.u_bsdf[1][j]) = (v.u_bsdf[0], v.u_bsdf[1]);
        self.n += 1;
        self.n == W
    }

    /// Computes every lane (those past `n` hold stale values and are ignored). Not inlined: in
    /// its caller LLVM left the loops scalar; on its own it runs them 16 wide.
    #[inline(never)]
    pub fn run(&mut self) {
        for j in 0..W {
            self.nee_lane(j);
        }
        for j in 0..W {
            self.bsdf_lane(j);
        }
    }

    /// Lane `j`'s results (after `run`).
    #[inline]
    pub fn out(&self, j: usize) -> LaneOut {
        let ray = Ray { o: self.shadow_o.get(j), d: self.shadow_d.get(j), tmax: self.shadow_t[j] };
        LaneOut {
            nee: self.nee_ok[j].then(|| LightSample { value: self.value.get(j), shadow: ray }),
            bsdf: self.bsdf_ok[j].then(|| diffuse::sampled(self.albedo.get(j), self.wi.get(j), self.pdf_w[j])),
            sp: ShadingPoint::new(self.p.get(j), self.ng.get(j), self.ns.get(j)),
            wo: self.wo.get(j),
            albedo: self.albedo.get(j),
        }
    }

    /// `direct::light_sample_mis` for an area light on a triangle, at a diffuse vertex: the
    /// same formulas, called lane by lane, a rejection being a mask.
    #[inline(always)]
    fn nee_lane(&mut self, j: usize) {
        let (p, ng, ns, wo) = (self.p.get(j), self.ng.get(j), self.ns.get(j), self.wo.get(j));
        let (albedo, ny) = (self.albedo.get(j), self.ny.get(j));
        let b = sample_triangle([self.u_light[0][j], self.u_light[1][j]]);
        let y = triangle_point([self.y0.get(j), self.y1.get(j), self.y2.get(j)], b);
        let (wi, dist2, cos_l) = direct::toward(p, y, ny);
        let f = diffuse::eval(albedo, ng, ns, wo, wi);
        let pdf_light = direct::light_pdf_w(self.pmf[j], 1.0 / self.area[j], dist2, cos_l);
        let pdf_bsdf = diffuse::pdf_w(ng, ns, wo, wi);
        let (shadow, segment) = shadow_segment(p, ng, y, ny);
        let value = direct::area_light_value(self.le.get(j), f, wi.dot(ns), pdf_light, pdf_bsdf);
        // where the scalar code returns `None` (a NaN passes, as there)
        self.nee_ok[j] = !(dist2 <= 0.0 || cos_l <= 0.0 || f == Rgb::ZERO) && segment;
        self.value.set(j, value);
        self.shadow_o.set(j, shadow.o);
        self.shadow_d.set(j, shadow.d);
        self.shadow_t[j] = shadow.tmax;
    }

    /// `bsdf::sample` for `Material::Diffuse` in radiance mode (`bsdf::diffuse::sample`).
    #[inline(always)]
    fn bsdf_lane(&mut self, j: usize) {
        let u = [self.u_bsdf[0][j], self.u_bsdf[1][j]];
        let (wi, pdf_w, valid) = diffuse::sample(self.ng.get(j), self.ns.get(j), self.wo.get(j), u);
        self.bsdf_ok[j] = valid;
        self.wi.set(j, wi);
        self.pdf_w[j] = pdf_w;
    }
}
