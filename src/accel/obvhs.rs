//! The obvhs back end (the default, and the only obvhs user): one CWBVH over the AABBs of every
//! triangle and analytic sphere, traversed by the kernel in `super::bvh8`.
//!
//! `medium_build`, made robust to coincident primitives in `build`. Triangles are reordered into
//! BVH slot order (obvhs' `RtTriangle` form, handed to the kernel as arrays), so traversal needs no
//! indirection; spheres are tested analytically (`super::sphere_t`) in the kernel's callback for
//! non-triangle slots. The traversal that the kernel replaced (obvhs' `traverse!` with obvhs' own node test and
//! `tri_t` one slot at a time) stays here under `cfg(test)` as the reference that the kernel's
//! hits are compared with, bit for bit.
//!
//! Invariants: the boxes handed in are finite and within `scene::MAX_EXTENT` (`World::build`
//! checked them: obvhs panics otherwise); queries return `(primitive id as in Scene, t)` with t in
//! the closed range [0, tmax] for triangles and the open range (0, tmax) for spheres; directions are
//! unit length; −0.0 direction components are turned into +0.0 before traversal (obvhs' node test
//! misreads −0.0).

mod build;

use super::bvh8::{Bvh8, Node, Ray8, Tri};
use crate::math::{Vec3, Vec3A};
use crate::scene::Scene;
#[cfg(test)]
use glam::UVec2;
use obvhs::aabb::Aabb;
use obvhs::cwbvh::node::CwBvhNode;
#[cfg(test)]
use obvhs::cwbvh::CwBvh;
#[cfg(test)]
use obvhs::ray::Ray;
use obvhs::rt_triangle::RtTriangle;
use obvhs::triangle::Triangle as ObvTriangle;
use obvhs::BvhBuildParams;

/// The CWBVH handed to the traversal kernel (`super::bvh8`), with each slot's primitive id.
pub(super) struct ObvhsBvh {
    kernel: Bvh8,
    slot_prim: Vec<u32>,
    ntri: u32,
    /// The CWBVH and its `RtTriangle`s, for the reference traversal the tests compare with.
    #[cfg(test)]
    reference: (CwBvh, Vec<RtTriangle>),
}

impl ObvhsBvh {
    /// Builds over `bounds` (one (lo, hi) per primitive, triangles then spheres, checked finite).
    pub(super) fn build(scene: &Scene, bounds: &[(Vec3, Vec3)]) -> ObvhsBvh {
        let ntri = scene.ntri();
        let aabbs: Vec<Aabb> = bounds.iter().map(|&(lo, hi)| Aabb::new(Vec3A::from(lo), Vec3A::from(hi))).collect();
        let bvh = build::build_cwbvh(&aabbs, BvhBuildParams::medium_build());
        let slot_prim: Vec<u32> = bvh.primitive_indices.clone();
        let dummy = ObvTriangle { v0: Vec3A::ZERO, v1: Vec3A::X, v2: Vec3A::Y };
        let slot_tri: Vec<RtTriangle> = slot_prim
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
        let a = |v: Vec3A| v.to_array();
        let tris: Vec<Tri> =
            slot_tri.iter().map(|t| Tri { v0: a(t.v0), e1: a(t.e1), e2: a(t.e2), ng: a(t.ng) }).collect();
        let other = slot_prim.iter().map(|&p| p >= ntri).collect();
        let nodes = bvh.nodes.iter().map(kernel_node).collect();
        let nodes = if slot_prim.is_empty() { Vec::new() } else { nodes };
        ObvhsBvh {
            kernel: Bvh8::new(nodes, &tris, other),
            slot_prim,
            ntri,
            #[cfg(test)]
            reference: (bvh, slot_tri),
        }
    }

    /// The distance to a sphere slot in (0, tmax), or ∞.
    #[inline(always)]
    fn sphere_t(&self, scene: &Scene, ray: &Ray8, slot: usize, tmax: f32) -> f32 {
        let s = &scene.spheres[(self.slot_prim[slot] - self.ntri) as usize];
        super::sphere_t(s.center, s.radius, ray.origin().into(), ray.dir().into(), 0.0, tmax)
    }

    /// Closest hit along `origin + t·dir`, t ∈ (0, tmax): (primitive id, t).
    #[inline]
    pub(super) fn closest(&self, scene: &Scene, origin: Vec3, dir: Vec3, tmax: f32) -> Option<(u32, f32)> {
        let ray = Ray8::new(origin.to_array(), dir.to_array());
        let (slot, t) = self.kernel.closest(&ray, tmax, |s, tm| self.sphere_t(scene, &ray, s, tm))?;
        Some((self.slot_prim[slot], t))
    }

    /// True if anything blocks the segment (0, tmax) along unit `dir`.
    #[inline]
    pub(super) fn occluded(&self, scene: &Scene, origin: Vec3, dir: Vec3, tmax: f32) -> bool {
        if tmax <= 0.0 {
            return false;
        }
        let ray = Ray8::new(origin.to_array(), dir.to_array());
        self.kernel.occluded(&ray, tmax, |s, tm| self.sphere_t(scene, &ray, s, tm))
    }
}

/// obvhs' CWBVH node as the kernel's `Node`, field for field.
fn kernel_node(n: &CwBvhNode) -> Node {
    Node {
        p: n.p.to_array(),
        e: n.e,
        imask: n.imask,
        child_base: n.child_base_idx,
        prim_base: n.primitive_base_idx,
        meta: n.child_meta,
        q: [n.child_min_x, n.child_max_x, n.child_min_y, n.child_max_y, n.child_min_z, n.child_max_z],
    }
}

/// The traversal the kernel replaced (obvhs' `traverse!` with obvhs' own node test,
/// `CwBvhNode::intersect_ray`, and `tri_t`), kept as the tests' reference for the kernel's hits.
#[cfg(test)]
impl ObvhsBvh {
    fn prim_t(&self, scene: &Scene, r: &Ray, slot: usize) -> f32 {
        let p = self.slot_prim[slot];
        if p < self.ntri {
            tri_t(&self.reference.1[slot], r)
        } else {
            let s = &scene.spheres[(p - self.ntri) as usize];
            super::sphere_t(s.center, s.radius, r.origin.into(), r.direction.into(), r.tmin, r.tmax)
        }
    }

    pub(super) fn closest_reference(&self, scene: &Scene, origin: Vec3, dir: Vec3, tmax: f32) -> Option<(u32, f32)> {
        if self.slot_prim.is_empty() {
            return None;
        }
        let ray = Ray::new(origin.into(), (dir + Vec3::ZERO).into(), 0.0, tmax);
        let bvh = &self.reference.0;
        let mut r = ray;
        let mut best = u32::MAX;
        let mut state = bvh.new_traversal(ray.direction);
        let mut node;
        obvhs::traverse!(bvh, node, state, node.intersect_ray(&r, state.oct_inv4), {
            let t = self.prim_t(scene, &r, state.primitive_id as usize);
            if t < r.tmax {
                best = state.primitive_id;
                r.tmax = t;
            }
        });
        (r.tmax < ray.tmax).then(|| (self.slot_prim[best as usize], r.tmax))
    }

    pub(super) fn occluded_reference(&self, scene: &Scene, origin: Vec3, dir: Vec3, tmax: f32) -> bool {
        if self.slot_prim.is_empty() || tmax <= 0.0 {
            return false;
        }
        let ray = Ray::new(origin.into(), (dir + Vec3::ZERO).into(), 0.0, tmax);
        let bvh = &self.reference.0;
        let mut state = bvh.new_traversal(ray.direction);
        let mut node;
        let mut hit = false;
        'outer: {
            obvhs::traverse!(bvh, node, state, node.intersect_ray(&ray, state.oct_inv4), {
                if self.prim_t(scene, &ray, state.primitive_id as usize) < ray.tmax {
                    hit = true;
                    break 'outer;
                }
            });
        }
        hit
    }
}

/// Möller–Trumbore on obvhs' precomputed triangle with inclusive edge tests: unlike
/// `RtTriangle::intersect` (which rejects −0.0 barycentrics by sign bit), a ray through an edge
/// shared by two triangles hits one of them (no pinhole leaks at quad diagonals).
#[cfg(test)]
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

#[cfg(test)]
mod tests {
    use super::super::bvh8::node_hits;
    use super::super::test_rays::{load, rays, spheres_and_soup, Lcg};
    use super::*;

    /// The kernel's `node_hits` gives obvhs' `intersect_ray` mask, bit for bit, at every node of a
    /// BVH over random boxes, for random rays of every octant (axis-parallel and zero components
    /// among them) and finite and infinite segments.
    #[test]
    fn node_test_is_obvhs_node_test() {
        let mut lcg = Lcg(0x9e37_79b9_7f4a_7c15);
        let mut rnd = move || lcg.f();
        let aabbs: Vec<Aabb> = (0..3000)
            .map(|_| {
                let c = Vec3A::new(rnd(), rnd(), rnd()) * 20.0 - 10.0;
                let h = Vec3A::new(rnd(), rnd(), rnd()) * 0.5;
                Aabb::new(c - h, c + h)
            })
            .collect();
        let bvh = build::build_cwbvh(&aabbs, BvhBuildParams::medium_build());
        assert!(bvh.nodes.len() > 100);
        let mut checked = 0u64;
        for i in 0..400 {
            let mut d = Vec3A::new(rnd(), rnd(), rnd()) * 2.0 - 1.0;
            if i % 7 == 0 {
                d.x = 0.0;
            }
            if i % 11 == 0 {
                d = Vec3A::new(0.0, 0.0, if i % 2 == 0 { 1.0 } else { -1.0 });
            }
            let d = d.normalize();
            let o = Vec3A::new(rnd(), rnd(), rnd()) * 30.0 - 15.0;
            let tmax = if i % 3 == 0 { f32::INFINITY } else { rnd() * 30.0 };
            let ray = Ray::new(o, d, 0.0, tmax);
            let oct = bvh.new_traversal(ray.direction).oct_inv4;
            let ray8 = Ray8::new(o.to_array(), d.to_array());
            for n in &bvh.nodes {
                let (ours, theirs) = (node_hits(&kernel_node(n), &ray8, tmax), n.intersect_ray(&ray, oct));
                assert_eq!(ours, theirs, "ray {i}: {ours:#034b} against {theirs:#034b}");
                checked += (theirs != 0) as u64;
            }
        }
        assert!(checked > 1000, "only {checked} nodes hit");
    }

    /// The kernel's closest hits and occlusion against the traversal it replaced, bit for bit
    /// (primitive, t's bits, the occlusion answer), on `n` rays: from random points of the scene's
    /// box, from points on its triangles (a surface's own hit at t ≈ 0), along random, axis-parallel
    /// and −0.0-component directions, with tmax 0, ∞ and random. Returns the rays that hit.
    fn same_hits(scene: &Scene, n: usize, seed: u64) -> usize {
        let b = super::super::bounds(scene);
        let bvh = ObvhsBvh::build(scene, &b);
        let mut hits = 0;
        for (i, o, d, tmax) in rays(scene, &b, n, seed) {
            let (ours, theirs) = (bvh.closest(scene, o, d, tmax), bvh.closest_reference(scene, o, d, tmax));
            let bits = |h: Option<(u32, f32)>| h.map(|(p, t)| (p, t.to_bits()));
            assert_eq!(bits(ours), bits(theirs), "ray {i}: o {o:?} d {d:?} tmax {tmax}");
            let (ours, theirs) = (bvh.occluded(scene, o, d, tmax), bvh.occluded_reference(scene, o, d, tmax));
            assert_eq!(ours, theirs, "ray {i} (occlusion): o {o:?} d {d:?} tmax {tmax}");
            hits += theirs as usize;
        }
        hits
    }

    /// The kernel on `ring` (12k triangles): 1M rays.
    #[test]
    fn kernel_hits_equal_reference_ring() {
        let hits = same_hits(&load("scenes/ring.toml"), 1_000_000, 1);
        assert!(hits > 100_000, "{hits}");
    }

    /// The kernel on the pool (45k triangles of a scene written by others): 1M rays.
    #[test]
    fn kernel_hits_equal_reference_pool() {
        let hits = same_hits(&load("scenes/external/sms-pool/scene.xml"), 1_000_000, 2);
        assert!(hits > 100_000, "{hits}");
    }

    /// A random-triangle soup (overlapping, slivers, coincident copies) and spheres among
    /// triangles (the cornell box's and 200 random ones): 1M rays each.
    #[test]
    fn kernel_hits_equal_reference_soup_and_spheres() {
        let (scene, with_soup) = spheres_and_soup();
        let with_spheres = same_hits(&scene, 1_000_000, 4);
        let soup_hits = same_hits(&with_soup, 1_000_000, 5);
        assert!(with_spheres > 100_000 && soup_hits > 100_000, "{with_spheres} {soup_hits}");
    }
}
