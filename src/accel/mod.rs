//! `World`: the scene plus its ray-tracing acceleration structure (the only obvhs user).
//!
//! One CWBVH (obvhs, `medium_build`, made robust to coincident primitives in `build`) over the
//! AABBs of every triangle and analytic sphere. `World::build` refuses primitives whose box is not
//! finite or leaves the scene extent limit (`scene::MAX_EXTENT`): obvhs panics on such boxes, and
//! the loader should have rejected them already (this is the last line of defence).
//! Triangles are reordered into BVH slot order as `RtTriangle`s, so traversal needs no indirection.
//! Closest-hit and occlusion queries; ray counts are kept in thread-local counters
//! (`take_ray_counts`).
//!
//! Invariants: directions passed in are unit length (the sphere test relies on it); hit normals
//! are unit; `Hit::ns` lies on the side of `Hit::ng`; primitive ids follow `Scene` (triangles, then
//! spheres).

use crate::math::{Vec3, Vec3A};
use crate::scene::Scene;
mod build;

use obvhs::aabb::Aabb;
use obvhs::cwbvh::CwBvh;
use obvhs::ray::{Ray, RayHit};
use obvhs::rt_triangle::RtTriangle;
use obvhs::triangle::Triangle as ObvTriangle;
use obvhs::BvhBuildParams;
use std::cell::Cell;

thread_local! {
    static RAY_COUNTS: Cell<(u64, u64)> = const { Cell::new((0, 0)) };
}

#[inline]
fn count(closest: u64, shadow: u64) {
    RAY_COUNTS.with(|c| {
        let (a, b) = c.get();
        c.set((a + closest, b + shadow));
    });
}

/// Returns and resets this thread's (closest-hit, shadow) ray counts.
pub fn take_ray_counts() -> (u64, u64) {
    RAY_COUNTS.with(|c| c.replace((0, 0)))
}

/// A surface hit.
#[derive(Clone, Copy, Debug)]
pub struct Hit {
    /// Ray parameter.
    pub t: f32,
    /// Position.
    pub p: Vec3,
    /// Unit geometric normal as the shape defines it.
    pub ng: Vec3,
    /// Unit shading normal (on the `ng` side).
    pub ns: Vec3,
    /// Primitive id.
    pub prim: u32,
}

/// Offset for spawning rays off a surface at `p`, scaled by the coordinates' magnitude.
#[inline]
pub fn ray_epsilon(p: Vec3) -> f32 {
    1e-4 * p.abs().max_element().max(1.0)
}

/// A ray origin moved off the surface toward the side `dir` leaves on.
#[inline]
pub fn offset_origin(p: Vec3, ng: Vec3, dir: Vec3) -> Vec3 {
    let e = ray_epsilon(p);
    if dir.dot(ng) >= 0.0 {
        p + e * ng
    } else {
        p - e * ng
    }
}

/// Why `World::build` refused a scene.
#[derive(Clone, Debug, PartialEq)]
pub enum BuildError {
    /// A primitive's bounding box is not finite or leaves `[-MAX_EXTENT, MAX_EXTENT]³`.
    OutOfRange {
        /// Primitive id (triangles, then spheres).
        prim: u32,
        /// Box minimum.
        lo: [f32; 3],
        /// Box maximum.
        hi: [f32; 3],
    },
    /// More primitives than 32-bit ids can name.
    TooManyPrimitives(usize),
}

impl std::fmt::Display for BuildError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            BuildError::OutOfRange { prim, lo, hi } => write!(
                f,
                "cannot build the BVH: primitive {prim} has bounds {lo:?}..{hi:?}, outside the scene extent limit \
                 |coordinate| <= {:e}",
                crate::scene::MAX_EXTENT
            ),
            BuildError::TooManyPrimitives(n) => write!(f, "cannot build the BVH: {n} primitives (at most 2^32 - 2)"),
        }
    }
}

impl std::error::Error for BuildError {}

/// The scene with its BVH.
pub struct World {
    /// The scene.
    pub scene: Scene,
    bvh: CwBvh,
    slot_tri: Vec<RtTriangle>,
    slot_prim: Vec<u32>,
    /// BVH build time in seconds.
    pub build_secs: f64,
}

impl World {
    /// Builds the BVH over the scene's primitives; refuses boxes that are not finite or exceed
    /// `scene::MAX_EXTENT` (obvhs would panic on them).
    pub fn build(scene: Scene) -> Result<World, BuildError> {
        let t0 = std::time::Instant::now();
        let nprim = scene.triangles.len() + scene.spheres.len();
        if nprim >= u32::MAX as usize - 1 {
            return Err(BuildError::TooManyPrimitives(nprim));
        }
        let ntri = scene.ntri();
        let mut aabbs: Vec<Aabb> = scene
            .triangles
            .iter()
            .map(|t| {
                let lo = t.p[0].min(t.p[1]).min(t.p[2]);
                let hi = t.p[0].max(t.p[1]).max(t.p[2]);
                Aabb::new(Vec3A::from(lo), Vec3A::from(hi))
            })
            .collect();
        aabbs.extend(scene.spheres.iter().map(|s| {
            Aabb::new(Vec3A::from(s.center - Vec3::splat(s.radius)), Vec3A::from(s.center + Vec3::splat(s.radius)))
        }));
        if let Some(i) = aabbs
            .iter()
            .position(|b| !crate::scene::within_extent(b.min.into()) || !crate::scene::within_extent(b.max.into()))
        {
            let b = aabbs[i];
            return Err(BuildError::OutOfRange { prim: i as u32, lo: b.min.to_array(), hi: b.max.to_array() });
        }
        let bvh = build::build_cwbvh(&aabbs, BvhBuildParams::medium_build());
        let slot_prim: Vec<u32> = bvh.primitive_indices.clone();
        let dummy = ObvTriangle { v0: Vec3A::ZERO, v1: Vec3A::X, v2: Vec3A::Y };
        let slot_tri = slot_prim
            .iter()
            .map(|&p| {
                if p < ntri {
                    let t = &scene.triangles[p as usize];
                    RtTriangle::from(&ObvTriangle { v0: t.p[0].into(), v1: t.p[1].into(), v2: t.p[2].into() })
                } else {
                    RtTriangle::from(&dummy)
                }
            })
            .collect();
        Ok(World { scene, bvh, slot_tri, slot_prim, build_secs: t0.elapsed().as_secs_f64() })
    }

    #[inline]
    fn prim_t(&self, r: &Ray, slot: usize) -> f32 {
        let p = self.slot_prim[slot];
        let ntri = self.scene.ntri();
        if p < ntri {
            tri_t(&self.slot_tri[slot], r)
        } else {
            let s = &self.scene.spheres[(p - ntri) as usize];
            sphere_t(s.center, s.radius, r)
        }
    }

    /// Closest hit along `origin + t·dir`, t ∈ (0, tmax); `dir` must be unit length.
    pub fn intersect(&self, origin: Vec3, dir: Vec3, tmax: f32) -> Option<Hit> {
        count(1, 0);
        if self.slot_prim.is_empty() {
            return None;
        }
        // + 0.0 turns −0.0 components into +0.0 (obvhs' node test misreads −0.0)
        let ray = Ray::new(origin.into(), (dir + Vec3::ZERO).into(), 0.0, tmax);
        let mut hit = RayHit::none();
        if !self.bvh.ray_traverse(ray, &mut hit, |r, slot| self.prim_t(r, slot)) {
            return None;
        }
        let slot = hit.primitive_id as usize;
        let prim = self.slot_prim[slot];
        let t = hit.t;
        let p = origin + t * dir;
        let ntri = self.scene.ntri();
        if prim < ntri {
            let tri = &self.scene.triangles[prim as usize];
            let ns = match &tri.n {
                Some(n) => {
                    let (b1, b2) = barycentrics(tri.p, p);
                    let v = (1.0 - b1 - b2) * n[0] + b1 * n[1] + b2 * n[2];
                    let v = v.normalize_or_zero();
                    if v.dot(tri.ng) > 1e-4 {
                        v
                    } else {
                        tri.ng
                    }
                }
                None => tri.ng,
            };
            Some(Hit { t, p, ng: tri.ng, ns, prim })
        } else {
            let s = &self.scene.spheres[(prim - ntri) as usize];
            let mut n = ((p - s.center) / s.radius).normalize();
            if s.inward {
                n = -n;
            }
            // re-project onto the surface to limit error growth along Dirac chains
            let p = s.center + (p - s.center).normalize() * s.radius;
            Some(Hit { t, p, ng: n, ns: n, prim })
        }
    }

    /// True if anything blocks the open segment (0, tmax) along unit `dir`.
    pub fn occluded(&self, origin: Vec3, dir: Vec3, tmax: f32) -> bool {
        count(0, 1);
        if self.slot_prim.is_empty() || tmax <= 0.0 {
            return false;
        }
        let ray = Ray::new(origin.into(), (dir + Vec3::ZERO).into(), 0.0, tmax);
        !self.bvh.ray_traverse_miss(ray, |r, slot| self.prim_t(r, slot))
    }

    /// Visibility between surface points `a` (normal `na`) and `b` (normal `nb`).
    pub fn visible(&self, a: Vec3, na: Vec3, b: Vec3, nb: Vec3) -> bool {
        let d = b - a;
        let dist = d.length();
        if dist <= 0.0 {
            return false;
        }
        let dir = d / dist;
        let o = offset_origin(a, na, dir);
        let target = offset_origin(b, nb, -dir);
        let seg = target - o;
        let len = seg.length();
        !self.occluded(o, seg / len.max(1e-30), len)
    }
}

/// Möller–Trumbore on obvhs' precomputed triangle with inclusive edge tests: unlike
/// `RtTriangle::intersect` (which rejects −0.0 barycentrics by sign bit), a ray through an edge
/// shared by two triangles hits one of them (no pinhole leaks at quad diagonals).
#[inline]
fn tri_t(t: &RtTriangle, ray: &Ray) -> f32 {
    let c = t.v0 - ray.origin;
    let r = ray.direction.cross(c);
    let det = t.ng.dot(ray.direction);
    if det == 0.0 {
        return f32::INFINITY;
    }
    let inv_det = 1.0 / det;
    let u = r.dot(t.e2) * inv_det;
    let v = r.dot(t.e1) * inv_det;
    if u >= 0.0 && v >= 0.0 && u + v <= 1.0 {
        let tt = t.ng.dot(c) * inv_det;
        if tt >= ray.tmin && tt <= ray.tmax {
            return tt;
        }
    }
    f32::INFINITY
}

/// Barycentric (b1, b2) of `p` in triangle `t` (b0 = 1 − b1 − b2).
#[inline]
fn barycentrics(t: [Vec3; 3], p: Vec3) -> (f32, f32) {
    let (e1, e2, d) = (t[1] - t[0], t[2] - t[0], p - t[0]);
    let (d00, d01, d11) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
    let (d20, d21) = (d.dot(e1), d.dot(e2));
    let den = d00 * d11 - d01 * d01;
    if den.abs() < 1e-30 {
        return (1.0 / 3.0, 1.0 / 3.0);
    }
    ((d11 * d20 - d01 * d21) / den, (d00 * d21 - d01 * d20) / den)
}

/// Ray–sphere distance in [tmin, tmax], or ∞ (unit direction; Ray Tracing Gems ch. 7 form).
#[inline]
fn sphere_t(c: Vec3, r: f32, ray: &Ray) -> f32 {
    let o = Vec3::from(ray.origin);
    let d = Vec3::from(ray.direction);
    let f = o - c;
    let b = -f.dot(d);
    let l = f + b * d;
    let disc = r * r - l.dot(l);
    if disc < 0.0 {
        return f32::INFINITY;
    }
    let cc = f.dot(f) - r * r;
    let q = b + b.signum() * disc.sqrt();
    let (mut t0, mut t1) = if q == 0.0 { (0.0, 0.0) } else { (cc / q, q) };
    if t0 > t1 {
        std::mem::swap(&mut t0, &mut t1);
    }
    if t0 > ray.tmin && t0 < ray.tmax {
        t0
    } else if t1 > ray.tmin && t1 < ray.tmax {
        t1
    } else {
        f32::INFINITY
    }
}
