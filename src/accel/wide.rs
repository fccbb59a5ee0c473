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
//! - `inv` is 1/d, with |d| < 1e-20 (and ±0) replaced by ±1e20, so every slab distance is finite
//!   or ±∞ (empty children's (+∞, −∞) boxes), never NaN;
//! - the stack holds (node, entry distance) pairs; a popped node whose entry lies beyond the best
//!   t (scaled as above) is skipped; its depth bound is `build::MAX_DEPTH` levels of 7 entries.

mod build;

use super::bvh8::{Ray8, Slots, Tri};
use crate::math::Vec3;
use crate::scene::Scene;

/// An 8-wide node: the children's boxes as 8 lanes per bound (min x, max x, min y, max y, min z,
/// max z), each child's node index (inner) or slot mask from `prim_base` (leaf), which children
/// are inner.
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
        b: [[f32::INFINITY; 8], [f32::NEG_INFINITY; 8], [f32::INFINITY; 8], [f32::NEG_INFINITY; 8], [f32::INFINITY; 8], [
            f32::NEG_INFINITY;
            8
        ]],
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
        let inv = d.map(|x| if x.abs() < 1e-20 { 1e20f32.copysign(x) } else { 1.0 / x });
        Slab { o: ray.origin(), inv, neg: d.map(|x| (x < 0.0) as usize) }
    }
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
                    let [v0, v1, v2] = scene.triangles[p as usize].p;
                    // obvhs' `RtTriangle` form, with glam's (fused where FMA) cross product
                    let (e1, e2) = (glam::Vec3A::from(v0 - v1), glam::Vec3A::from(v2 - v0));
                    Tri { v0: v0.to_array(), e1: e1.to_array(), e2: e2.to_array(), ng: e1.cross(e2).to_array() }
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
            let mut leaves = 0u32;
            let mut lh = hit & !node.inner;
            while lh != 0 {
                leaves |= node.child[lh.trailing_zeros() as usize];
                lh &= lh - 1;
            }
            while leaves != 0 {
                let lo = leaves.trailing_zeros();
                let bits = (leaves >> lo) & 0xff;
                leaves &= !(0xffu32.wrapping_shl(lo));
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
        let tn = _mm256_max_ps(_mm256_max_ps(x0, y0), _mm256_max_ps(z0, _mm256_setzero_ps()));
        let tf = _mm256_min_ps(_mm256_min_ps(x1, y1), _mm256_min_ps(z1, s(tmax)));
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
