//! The obvhs back end (the default, and the only obvhs user): one CWBVH over the AABBs of every
//! triangle and analytic sphere.
//!
//! `medium_build`, made robust to coincident primitives in `build`. Triangles are reordered into
//! BVH slot order as `RtTriangle`s, so traversal needs no indirection; spheres are tested
//! analytically (`super::sphere_t`) in the traversal callback.
//!
//! Invariants: the boxes handed in are finite and within `scene::MAX_EXTENT` (`World::build`
//! checked them: obvhs panics otherwise); queries return `(primitive id as in Scene, t)` with t in
//! the closed range [0, tmax] for triangles and the open range (0, tmax) for spheres; directions are
//! unit length; −0.0 direction components are turned into +0.0 before traversal (obvhs' node test
//! misreads −0.0).

mod build;

use crate::math::{Vec3, Vec3A};
use crate::scene::Scene;
use obvhs::aabb::Aabb;
use obvhs::cwbvh::CwBvh;
use obvhs::ray::{Ray, RayHit};
use obvhs::rt_triangle::RtTriangle;
use obvhs::triangle::Triangle as ObvTriangle;
use obvhs::BvhBuildParams;

/// The CWBVH with the triangles in slot order.
pub(super) struct ObvhsBvh {
    bvh: CwBvh,
    slot_tri: Vec<RtTriangle>,
    slot_prim: Vec<u32>,
    ntri: u32,
}

impl ObvhsBvh {
    /// Builds over `bounds` (one (lo, hi) per primitive, triangles then spheres, checked finite).
    pub(super) fn build(scene: &Scene, bounds: &[(Vec3, Vec3)]) -> ObvhsBvh {
        let ntri = scene.ntri();
        let aabbs: Vec<Aabb> = bounds.iter().map(|&(lo, hi)| Aabb::new(Vec3A::from(lo), Vec3A::from(hi))).collect();
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
        ObvhsBvh { bvh, slot_tri, slot_prim, ntri }
    }

    #[inline]
    fn prim_t(&self, scene: &Scene, r: &Ray, slot: usize) -> f32 {
        let p = self.slot_prim[slot];
        if p < self.ntri {
            tri_t(&self.slot_tri[slot], r)
        } else {
            let s = &scene.spheres[(p - self.ntri) as usize];
            super::sphere_t(s.center, s.radius, r.origin.into(), r.direction.into(), r.tmin, r.tmax)
        }
    }

    /// Closest hit along `origin + t·dir`, t ∈ (0, tmax): (primitive id, t).
    #[inline]
    pub(super) fn closest(&self, scene: &Scene, origin: Vec3, dir: Vec3, tmax: f32) -> Option<(u32, f32)> {
        if self.slot_prim.is_empty() {
            return None;
        }
        // + 0.0 turns −0.0 components into +0.0 (obvhs' node test misreads −0.0)
        let ray = Ray::new(origin.into(), (dir + Vec3::ZERO).into(), 0.0, tmax);
        let mut hit = RayHit::none();
        if !self.bvh.ray_traverse(ray, &mut hit, |r, slot| self.prim_t(scene, r, slot)) {
            return None;
        }
        Some((self.slot_prim[hit.primitive_id as usize], hit.t))
    }

    /// True if anything blocks the segment (0, tmax) along unit `dir`.
    #[inline]
    pub(super) fn occluded(&self, scene: &Scene, origin: Vec3, dir: Vec3, tmax: f32) -> bool {
        if self.slot_prim.is_empty() || tmax <= 0.0 {
            return false;
        }
        let ray = Ray::new(origin.into(), (dir + Vec3::ZERO).into(), 0.0, tmax);
        !self.bvh.ray_traverse_miss(ray, |r, slot| self.prim_t(scene, r, slot))
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
