//! The default back end: an 8-wide BVH of our own over every triangle and analytic sphere, with
//! float child boxes (`build`: binned SAH, collapsed to 8 children per node while building),
//! traced near to far; triangles 8 at a time by `super::bvh8::Slots` (the AVX2 Möller–Trumbore).
//!
//! Contract: `closest` returns the primitive (id as in `Scene`) and t of the nearest hit with
//! t ∈ [0, tmax) — triangles by `bvh8`'s triangle test, spheres by `super::sphere_t` in (0, tmax);
//! `occluded` whether there is any, stopping at the first. Among hits at exactly equal t, which one
//! is returned depends on the tree (the first found in traversal order; in one leaf chunk the
//! highest slot).
//!
//! Invariants:
//! - the node test never culls a child whose box the ray meets in [0, cur]: the slab distances are
//!   `(b − o) · inv` (three roundings, so within γ3 of the exact ones), and the far end is compared
//!   after scaling by 1 + 2γ3 (pbrt's robust slab test), with the entry floored at 0 (no 1e-4
//!   floor as in obvhs' CWBVH);
//! - `inv` is 1/d (+∞ for a zero component: `Ray8` turned −0.0 into +0.0); a slab distance is NaN
//!   only where the ray lies in the slab's plane (0 · ∞), and such a slab drops out of the node
//!   test (the ray is inside it), so rays along an axis hit flat boxes they lie in;
//! - child boxes are their primitives' boxes widened by 4 ulps (`build::PAD`); a hit that the
//!   triangle test reports outside that box (a ray running along the triangle's plane, where its
//!   t is rounding) may be missed: the one difference from brute force that the tests allow;
//! - the stack holds (node, entry distance) pairs; a popped node whose entry lies beyond the best
//!   t (scaled as above) is skipped; its depth bound is `build::MAX_DEPTH` levels of 7 entries.

mod build;

use super::bvh8::{Ray8, Slots, Tri};
use crate::math::Vec3;
use crate::scene::Scene;

/// An 8-wide node: the children's boxes as 8 lanes per bound (min x, max x, min y, max y, min z,
/// max z), each child's node index (inner) or first slot's offset from `prim_base` | count << 8
/// (leaf), which children are inner.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub(super) struct Node {
    b: [[f32; 8]; 6],
    child: [u32; 8],
    prim_base: u32,
    inner: u32,
}

impl Node {
    const EMPTY: Node = Node {
        b: [
            [f32::INFINITY; 8],
            [f32::NEG_INFINITY; 8],
            [f32::INFINITY; 8],
            [f32::NEG_INFINITY; 8],
            [f32::INFINITY; 8],
            [f32::NEG_INFINITY; 8],
        ],
        child: [0; 8],
        prim_base: 0,
        inner: 0,
    };
}

/// 1 + 2γ3 (pbrt's `gamma(3)`, u = 2^-24), rounded up: the far slab distance's scale.
const FAR_SCALE: f32 = 1.0 + 2.0 * (3.0 * f32::EPSILON / 2.0) / (1.0 - 3.0 * f32::EPSILON / 2.0) + f32::EPSILON;
/// Traversal stack entries.
const STACK: usize = build::MAX_DEPTH * 7 + 8;

/// The ray as the node test reads it.
#[derive(Clone, Copy)]
struct Slab {
    o: [f32; 3],
    inv: [f32; 3],
    /// Per axis, 0 when the direction is ≥ 0 (near bound = min), 1 otherwise.
    neg: [usize; 3],
}

impl Slab {
    #[inline(always)]
    fn new(ray: &Ray8) -> Slab {
        let d = ray.dir();
        let inv = d.map(|x| 1.0 / x);
        Slab { o: ray.origin(), inv, neg: d.map(|x| (x < 0.0) as usize) }
    }
}

/// A triangle in `bvh8::Tri`'s form (obvhs' `RtTriangle`: the cross product is glam's, fused
/// where the build has FMA).
fn tri([v0, v1, v2]: [Vec3; 3]) -> Tri {
    let (e1, e2) = (glam::Vec3A::from(v0 - v1), glam::Vec3A::from(v2 - v0));
    Tri { v0: v0.to_array(), e1: e1.to_array(), e2: e2.to_array(), ng: e1.cross(e2).to_array() }
}

/// The built tree and each slot's primitive.
pub(super) struct WideBvh {
    nodes: Vec<Node>,
    slots: Slots,
    slot_prim: Vec<u32>,
    ntri: u32,
}

impl WideBvh {
    /// Builds over `bounds` (one (lo, hi) per primitive, triangles then spheres, checked finite).
    pub(super) fn build(scene: &Scene, bounds: &[(Vec3, Vec3)]) -> WideBvh {
        let ntri = scene.ntri();
        let (nodes, slot_prim) = build::build(bounds);
        let tris: Vec<Tri> = slot_prim
            .iter()
            .map(|&p| {
                if p < ntri {
                    tri(scene.triangles[p as usize].p)
                } else {
                    Tri { v0: [0.0; 3], e1: [0.0; 3], e2: [0.0; 3], ng: [0.0; 3] }
                }
            })
            .collect();
        let other = slot_prim.iter().map(|&p| p >= ntri).collect();
        WideBvh { nodes, slots: Slots::new(&tris, other), slot_prim, ntri }
    }

    /// The distance to a sphere slot in (0, tmax), or ∞.
    #[inline(always)]
    fn sphere_t(&self, scene: &Scene, ray: &Ray8, slot: usize, tmax: f32) -> f32 {
        let s = &scene.spheres[(self.slot_prim[slot] - self.ntri) as usize];
        super::sphere_t(s.center, s.radius, ray.origin().into(), ray.dir().into(), 0.0, tmax)
    }

    /// Closest hit along `origin + t·dir`, t ∈ [0, tmax): (primitive id, t).
    #[inline]
    pub(super) fn closest(&self, scene: &Scene, origin: Vec3, dir: Vec3, tmax: f32) -> Option<(u32, f32)> {
        let ray = Ray8::new(origin.to_array(), dir.to_array());
        let mut best = usize::MAX;
        let mut cur = tmax;
        self.traverse::<true>(&ray, &mut cur, |slots, base, bits, cur| {
            let (t, s) = slots.leaf_chunk(&ray, base, bits, *cur, &mut |s, tm| self.sphere_t(scene, &ray, s, tm));
            if t < *cur {
                *cur = t;
                best = s;
            }
            false
        });
        (cur < tmax).then(|| (self.slot_prim[best], cur))
    }

    /// True if anything blocks the segment [0, tmax) along unit `dir`.
    #[inline]
    pub(super) fn occluded(&self, scene: &Scene, origin: Vec3, dir: Vec3, tmax: f32) -> bool {
        if tmax <= 0.0 {
            return false;
        }
        let ray = Ray8::new(origin.to_array(), dir.to_array());
        let mut cur = tmax;
        let mut hit = false;
        self.traverse::<false>(&ray, &mut cur, |slots, base, bits, cur| {
            hit = slots.leaf_chunk(&ray, base, bits, *cur, &mut |s, tm| self.sphere_t(scene, &ray, s, tm)).0 < *cur;
            hit
        });
        hit
    }

    /// Depth first from the root; with `SORT` a node's hit inner children are visited near to
    /// far. `leaf(slots, base, bits, cur)` tests slots `base + i` for the set bits `i` of `bits`
    /// (< 2^8), updates `cur` and returns true to stop.
    #[inline(always)]
    fn traverse<const SORT: bool>(
        &self,
        ray: &Ray8,
        cur: &mut f32,
        mut leaf: impl FnMut(&Slots, usize, u32, &mut f32) -> bool,
    ) {
        if self.nodes.is_empty() {
            return;
        }
        let slab = Slab::new(ray);
        let mut stack = std::mem::MaybeUninit::<[(u32, f32); STACK]>::uninit();
        let stack = stack.as_mut_ptr() as *mut (u32, f32);
        let mut sp = 0usize;
        let mut n = 0u32;
        loop {
            let node = &self.nodes[n as usize];
            let (hit, tnear) = node_hits(node, &slab, *cur);
            // the hit leaves' slots, 8 at a time from the lowest
            let mut leaves = 0u64;
            let mut lh = hit & !node.inner;
            while lh != 0 {
                let c = node.child[lh.trailing_zeros() as usize];
                leaves |= ((1u64 << (c >> 8)) - 1) << (c & 0xff);
                lh &= lh - 1;
            }
            while leaves != 0 {
                let lo = leaves.trailing_zeros();
                let bits = ((leaves >> lo) & 0xff) as u32;
                leaves &= !(0xffu64.wrapping_shl(lo));
                if leaf(&self.slots, (node.prim_base + lo) as usize, bits, cur) {
                    return;
                }
            }
            let far = *cur * FAR_SCALE;
            let mut ih = hit & node.inner;
            // SAFETY (all stack accesses): `sp` stays below STACK (at most 7 entries per level,
            // `build::MAX_DEPTH` levels), and an entry is read only below `sp`, where it was written.
            let base = sp;
            while ih != 0 {
                let i = ih.trailing_zeros() as usize;
                ih &= ih - 1;
                if tnear[i] <= far {
                    debug_assert!(sp < STACK);
                    unsafe { stack.add(sp).write((node.child[i], tnear[i])) };
                    sp += 1;
                }
            }
            if SORT && sp - base > 1 {
                // far to near, so that the nearest is on top (insertion sort, ≤ 8 entries)
                for j in base + 1..sp {
                    let e = unsafe { stack.add(j).read() };
                    let mut k = j;
                    while k > base && unsafe { stack.add(k - 1).read() }.1 < e.1 {
                        unsafe { stack.add(k).write(stack.add(k - 1).read()) };
                        k -= 1;
                    }
                    unsafe { stack.add(k).write(e) };
                }
            }
            loop {
                if sp == 0 {
                    return;
                }
                sp -= 1;
                let (next, t) = unsafe { stack.add(sp).read() };
                if t <= *cur * FAR_SCALE {
                    n = next;
                    break;
                }
            }
        }
    }
}

/// The mask of the children whose boxes the ray meets within [0, tmax] (robustly, see the module
/// header) and their entry distances.
#[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
#[inline(always)]
fn node_hits(n: &Node, r: &Slab, tmax: f32) -> (u32, [f32; 8]) {
    use std::arch::x86_64::*;
    // SAFETY: AVX2 is enabled at compile time (the cfg above); the loads read the node's 64-byte
    // aligned [f32; 8] rows.
    unsafe {
        let ld = |k: usize| _mm256_load_ps(n.b[k].as_ptr());
        let s = _mm256_set1_ps;
        let slab = |k: usize| {
            let (o, inv) = (s(r.o[k]), s(r.inv[k]));
            let near = _mm256_mul_ps(_mm256_sub_ps(ld(2 * k + r.neg[k]), o), inv);
            let far = _mm256_mul_ps(_mm256_sub_ps(ld(2 * k + 1 - r.neg[k]), o), inv);
            (near, far)
        };
        let (x0, x1) = slab(0);
        let (y0, y1) = slab(1);
        let (z0, z1) = slab(2);
        // `max_ps(a, b)` is b where either is NaN: a NaN slab (0 · ∞) drops out of the chain
        let tn = _mm256_max_ps(x0, _mm256_max_ps(y0, _mm256_max_ps(z0, _mm256_setzero_ps())));
        let tf = _mm256_min_ps(x1, _mm256_min_ps(y1, _mm256_min_ps(z1, s(tmax))));
        let tf = _mm256_mul_ps(tf, s(FAR_SCALE));
        let hit = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(tn, tf)) as u32;
        let mut out = [0.0f32; 8];
        _mm256_storeu_ps(out.as_mut_ptr(), tn);
        (hit, out)
    }
}

/// The portable node test: the same arithmetic child by child.
#[cfg(not(all(target_arch = "x86_64", target_feature = "avx2")))]
#[inline(always)]
fn node_hits(n: &Node, r: &Slab, tmax: f32) -> (u32, [f32; 8]) {
    let mut hit = 0;
    let mut out = [0.0f32; 8];
    for c in 0..8 {
        let t = |k: usize, b: usize| (n.b[2 * k + b][c] - r.o[k]) * r.inv[k];
        let tn = t(0, r.neg[0]).max(t(1, r.neg[1])).max(t(2, r.neg[2]).max(0.0));
        let tf = t(0, 1 - r.neg[0]).min(t(1, 1 - r.neg[1])).min(t(2, 1 - r.neg[2]).min(tmax)) * FAR_SCALE;
        hit |= ((tn <= tf) as u32) << c;
        out[c] = tn;
    }
    (hit, out)
}

#[cfg(test)]
mod tests {
    use super::super::bvh8::tri_t;
    use super::super::obvhs::ObvhsBvh;
    use super::super::test_rays::{load, rays, spheres_and_soup};
    use super::*;

    /// Every primitive's distance along the ray (the back ends' per-primitive tests).
    fn brute_ts<'a>(
        scene: &'a Scene,
        tris: &'a [Tri],
        o: Vec3,
        d: Vec3,
        tmax: f32,
    ) -> impl Iterator<Item = (u32, f32)> + 'a {
        let ray = Ray8::new(o.to_array(), d.to_array());
        let (o, d) = (Vec3::from(ray.origin()), Vec3::from(ray.dir()));
        let spheres = scene.spheres.iter().map(move |s| super::super::sphere_t(s.center, s.radius, o, d, 0.0, tmax));
        tris.iter().map(move |t| tri_t(t, &ray, tmax)).chain(spheres).enumerate().map(|(i, t)| (i as u32, t))
    }

    /// Counts of `same_hits`.
    #[derive(Debug, Default)]
    struct Counts {
        hits: usize,
        /// Closest hits at the same t on another primitive than obvhs' (a tie).
        ties: usize,
        /// Closest hits at another t than obvhs' (obvhs' 1e-4 entry floor or a miss of its).
        other_t: usize,
        other_t_below_floor: usize,
        /// Occlusion answers unlike obvhs'.
        occlusion: usize,
        /// Rays compared with brute force.
        brute: usize,
        /// Closest hits (occlusion answers) that skipped an edge-on hit which brute force found.
        edge_on_skipped: usize,
        edge_on_skipped_occlusion: usize,
    }

    /// The tree's closest hits and occlusion answers against obvhs' tree (the kernel `bvh8`) on `n`
    /// rays: from random points of the scene's box, from points on its triangles (a surface's own
    /// hit at t ≈ 0), along random, axis-parallel and −0.0-component directions, with tmax 0, ∞,
    /// `f32::MAX` and random. Wherever the two differ, and on every 997th ray, the answer must be
    /// the brute-force one over all primitives (the same per-primitive tests): t to the bit, a
    /// primitive with exactly that t, nothing below it; the occlusion answer whether any
    /// primitive has t < tmax. The one exception, counted: a hit that brute force finds on a
    /// triangle whose plane the ray runs along (within 1e-5 rad; its t comes from rounding, the
    /// point lies outside the triangle's box) may be skipped.
    fn same_hits(scene: &Scene, n: usize, seed: u64) -> Counts {
        let b = super::super::bounds(scene);
        let wide = WideBvh::build(scene, &b);
        let old = ObvhsBvh::build(scene, &b);
        let tris: Vec<Tri> = scene.triangles.iter().map(|t| tri(t.p)).collect();
        let mut c = Counts::default();
        for (i, o, d, tmax) in rays(scene, &b, n, seed) {
            let (ours, theirs) = (wide.closest(scene, o, d, tmax), old.closest(scene, o, d, tmax));
            let bits = |h: Option<(u32, f32)>| h.map(|(p, t)| (p, t.to_bits()));
            let (occ, occ_old) = (wide.occluded(scene, o, d, tmax), old.occluded(scene, o, d, tmax));
            c.hits += ours.is_some() as usize;
            if bits(ours) != bits(theirs) {
                match (ours, theirs) {
                    (Some((_, a)), Some((_, b))) if a == b => c.ties += 1,
                    _ => {
                        c.other_t += 1;
                        c.other_t_below_floor += ours.is_some_and(|(_, t)| t < 1e-4) as usize;
                    }
                }
            }
            c.occlusion += (occ != occ_old) as usize;
            if bits(ours) != bits(theirs) || occ != occ_old || i % 997 == 0 {
                c.brute += 1;
                let all: Vec<(u32, f32)> = brute_ts(scene, &tris, o, d, tmax).filter(|&(_, t)| t < tmax).collect();
                let best = all.iter().map(|h| h.1).reduce(f32::min);
                let msg = format!(
                    "ray {i}: o {o:?} d {d:?} tmax {tmax}: ours {ours:?}, obvhs {theirs:?}, brute force t {best:?}"
                );
                // an edge-on hit: the ray within 1e-5 rad of the triangle's plane
                let edge_on = |p: u32| {
                    let Some(t) = tris.get(p as usize) else { return false };
                    let ng = Vec3::from(t.ng);
                    ng.dot(d).abs() < 1e-5 * ng.length()
                };
                let ours_t = ours.map_or(f32::INFINITY, |h| h.1);
                if ours.map(|h| h.1) != best {
                    // only edge-on hits (the triangle test's rounding, outside the triangle's box) skipped
                    let skipped: Vec<_> = all.iter().filter(|h| h.1 < ours_t).collect();
                    assert!(skipped.iter().all(|h| edge_on(h.0)), "{msg}: skipped {skipped:?}");
                    c.edge_on_skipped += 1;
                }
                if let Some((p, t)) = ours {
                    let tp = brute_ts(scene, &tris, o, d, tmax).nth(p as usize).unwrap().1;
                    assert_eq!(tp.to_bits(), t.to_bits(), "{msg}: the primitive's own t");
                }
                if occ != best.is_some() {
                    assert!(!occ && all.iter().all(|h| edge_on(h.0)), "{msg} (occlusion {occ})");
                    c.edge_on_skipped_occlusion += 1;
                }
            }
        }
        eprintln!("seed {seed}: {c:?}");
        c
    }

    /// `ring` (12k triangles): 1M rays.
    #[test]
    fn hits_equal_brute_force_ring() {
        let c = same_hits(&load("scenes/ring.toml"), 1_000_000, 1);
        assert!(c.hits > 100_000, "{c:?}");
    }

    /// The pool (45k triangles of a scene written by others): 1M rays.
    #[test]
    fn hits_equal_brute_force_pool() {
        let c = same_hits(&load("scenes/external/sms-pool/scene.xml"), 1_000_000, 2);
        assert!(c.hits > 100_000, "{c:?}");
    }

    /// A random-triangle soup (overlapping, slivers, coincident copies) and spheres among
    /// triangles (the cornell box's and 200 random ones): 1M rays each.
    #[test]
    fn hits_equal_brute_force_soup_and_spheres() {
        let (scene, with_soup) = spheres_and_soup();
        let with_spheres = same_hits(&scene, 1_000_000, 4);
        let soup_hits = same_hits(&with_soup, 1_000_000, 5);
        assert!(with_spheres.hits > 100_000 && soup_hits.hits > 100_000, "{with_spheres:?} {soup_hits:?}");
    }
}
