//! The default back end's traversal kernel: closest hit and occlusion in a compressed 8-wide BVH
//! (the CWBVH layout of Ylitie et al. 2017, as obvhs builds it), on plain arrays.
//!
//! Contract: `Bvh8::new(nodes, tris, other)` takes the nodes (`Node`, field for field obvhs'
//! `CwBvhNode`), each primitive slot's triangle in obvhs' `RtTriangle` form (`v0`, `e1 = v0 − v1`,
//! `e2 = v2 − v0`, `ng = e1 × e2`) and which slots are not triangles (`other`: tested by the
//! caller's closure, e.g. an analytic sphere). `closest` returns the slot and t of the nearest hit
//! with t in [0, tmax] (`<` against the best so far), `occluded` whether any slot has one.
//!
//! Invariants (why the hits equal obvhs' `traverse!` with `obvhs::node_hits` and `tri_t`, bit for
//! bit, ties included):
//! - the visiting order is `traverse!`'s: a node's hit leaves' slots from the highest hit-mask bit
//!   down, then its inner children from the highest bit down, depth first, with obvhs' 32-entry
//!   group stack (saturating, as its `StackStack`);
//! - the node test is `node_hits`' arithmetic (the same operations in the same order per lane);
//! - a node's hit slots are tested 8 at a time (AVX2) with `tri_t`'s per-lane arithmetic (glam's
//!   `cross` is fused where the build has FMA, its `dot` is `(x + y) + z`), every lane against the
//!   best t at the chunk's start; the chunk's smallest t below the best wins, the highest slot among
//!   equal ones, which is what testing them one by one from the highest down keeps;
//! - triangle arrays are structure of arrays in slot order, padded by 8 lanes so that a chunk's
//!   load never leaves them; slots in `other` hold NaN triangles (no lane of theirs hits);
//! - rays: unit direction with −0.0 components already turned into +0.0 (`Ray8::new` does it).

/// A compressed 8-wide node, obvhs' `CwBvhNode` field for field: the children's boxes quantized
/// to 8 bits in the frame (`p`, 2^(`e` − 127) per unit), `meta` (per child: inner, or the leaf's
/// slot offset and count), where the inner children and the leaf slots start.
#[derive(Clone, Copy, Debug, Default)]
#[repr(C, align(64))]
pub struct Node {
    /// The frame's origin.
    pub p: [f32; 3],
    /// The frame's scale per axis as a biased exponent.
    pub e: [u8; 3],
    /// Which children are inner nodes.
    pub imask: u8,
    /// Index of the first inner child.
    pub child_base: u32,
    /// Slot of the first leaf primitive.
    pub prim_base: u32,
    /// Per child: obvhs' meta byte.
    pub meta: [u8; 8],
    /// Children's quantized boxes: min x, max x, min y, max y, min z, max z.
    pub q: [[u8; 8]; 6],
}

/// A ray as the kernel reads it: origin, direction, obvhs' safe inverse direction, octant.
#[derive(Clone, Copy, Debug)]
pub struct Ray8 {
    o: [f32; 3],
    d: [f32; 3],
    inv: [f32; 3],
    oct_inv4: u32,
}

/// obvhs' `safe_inverse`.
#[inline(always)]
fn safe_inverse(x: f32) -> f32 {
    if x.abs() <= f32::EPSILON {
        x.signum() / f32::EPSILON
    } else {
        1.0 / x
    }
}

impl Ray8 {
    /// The ray from `o` along unit `d` (−0.0 components turned into +0.0).
    #[inline(always)]
    pub fn new(o: [f32; 3], d: [f32; 3]) -> Ray8 {
        let d = d.map(|x| x + 0.0);
        let oct_inv4 = (if d[0] < 0.0 { 0 } else { 0x0404_0404 })
            | (if d[1] < 0.0 { 0 } else { 0x0202_0202 })
            | (if d[2] < 0.0 { 0 } else { 0x0101_0101 });
        Ray8 { o, d, inv: d.map(safe_inverse), oct_inv4 }
    }

    /// Origin.
    pub fn origin(&self) -> [f32; 3] {
        self.o
    }

    /// Direction (−0.0 turned into +0.0).
    pub fn dir(&self) -> [f32; 3] {
        self.d
    }
}

/// One slot's triangle in obvhs' `RtTriangle` form.
#[derive(Clone, Copy, Debug)]
pub struct Tri {
    /// First vertex.
    pub v0: [f32; 3],
    /// v0 − v1.
    pub e1: [f32; 3],
    /// v2 − v0.
    pub e2: [f32; 3],
    /// e1 × e2.
    pub ng: [f32; 3],
}

/// The kernel's arrays.
pub struct Bvh8 {
    nodes: Vec<Node>,
    slots: Slots,
}

/// The primitive slots as the 8-wide triangle test reads them (shared with `super::wide`).
pub struct Slots {
    /// v0, e1, e2, ng, each x, y, z: 12 arrays of `slots + 8` entries.
    soa: [Vec<f32>; 12],
    other: Vec<bool>,
    any_other: bool,
}

const LANES: usize = 8;
/// obvhs' `node::EPSILON`: the floor of a child's entry distance.
const EPSILON: f32 = 0.0001;
/// obvhs' traversal stack size.
const STACK: usize = 32;

impl Bvh8 {
    /// The kernel over `nodes` (root first) and the slots' triangles; `other[s]`: slot `s` is not a
    /// triangle (its entry of `tris` is ignored).
    pub fn new(nodes: Vec<Node>, tris: &[Tri], other: Vec<bool>) -> Bvh8 {
        Bvh8 { nodes, slots: Slots::new(tris, other) }
    }

    /// Closest hit in [0, tmax]: (slot, t). `other(slot, tmax)` is the distance to a non-triangle
    /// slot in (0, tmax), or ∞.
    #[inline]
    pub fn closest(&self, ray: &Ray8, tmax: f32, mut other: impl FnMut(usize, f32) -> f32) -> Option<(usize, f32)> {
        let mut best = usize::MAX;
        let mut cur = tmax;
        self.traverse(ray, &mut cur, |bvh, base, bits, cur| {
            let (t, s) = bvh.slots.leaf_chunk(ray, base, bits, *cur, &mut other);
            if t < *cur {
                *cur = t;
                best = s;
            }
            false
        });
        (cur < tmax).then_some((best, cur))
    }

    /// Whether anything lies in [0, tmax] (`other` as for `closest`); stops at the first hit.
    #[inline]
    pub fn occluded(&self, ray: &Ray8, tmax: f32, mut other: impl FnMut(usize, f32) -> f32) -> bool {
        let mut cur = tmax;
        let mut hit = false;
        self.traverse(ray, &mut cur, |bvh, base, bits, cur| {
            hit = bvh.slots.leaf_chunk(ray, base, bits, *cur, &mut other).0 < *cur;
            hit
        });
        hit
    }

    /// `traverse!`'s loop. `leaf(bvh, base, bits, cur)` tests slots `base + i` for the set bits
    /// `i` of `bits` (< 2^8), updates `cur`, and returns true to stop.
    #[inline(always)]
    fn traverse(&self, ray: &Ray8, cur: &mut f32, mut leaf: impl FnMut(&Bvh8, usize, u32, &mut f32) -> bool) {
        if self.nodes.is_empty() {
            return;
        }
        let mut stack = [(0u32, 0u32); STACK];
        let mut sp = 0usize;
        let mut group = (0u32, 0x8000_0000u32);
        loop {
            let mut prims = (0u32, 0u32);
            if group.1 & 0xff00_0000 != 0 {
                let hits = group.1;
                let bit = 31 - hits.leading_zeros();
                group.1 &= !(1u32 << bit);
                if group.1 & 0xff00_0000 != 0 {
                    stack[sp] = group;
                    sp = (sp + 1).min(STACK - 1);
                }
                let slot = (bit - 24) ^ (ray.oct_inv4 & 0xff);
                let rel = (hits & !(0xffff_ffffu32 << slot)).count_ones();
                let node = &self.nodes[(group.0 + rel) as usize];
                let mask = node_hits(node, ray, *cur);
                prefetch_children(&self.nodes, node.child_base, mask >> 24);
                group = (node.child_base, (mask & 0xff00_0000) | node.imask as u32);
                prims = (node.prim_base, mask & 0x00ff_ffff);
            } else {
                group = (0, 0);
            }
            // the slots from the highest bit down, 8 at a time
            while prims.1 != 0 {
                let hi = 31 - prims.1.leading_zeros();
                let lo = hi.saturating_sub(LANES as u32 - 1);
                let bits = (prims.1 >> lo) & 0xff;
                prims.1 &= !(0xffu32 << lo);
                if leaf(self, (prims.0 + lo) as usize, bits, cur) {
                    return;
                }
            }
            if group.1 & 0xff00_0000 == 0 {
                if sp == 0 {
                    break;
                }
                sp -= 1;
                group = stack[sp];
            }
        }
    }
}

impl Slots {
    /// The slots' triangles; `other[s]`: slot `s` is not a triangle (its entry of `tris` is
    /// ignored).
    pub fn new(tris: &[Tri], other: Vec<bool>) -> Slots {
        assert_eq!(tris.len(), other.len());
        let n = tris.len();
        let mut soa: [Vec<f32>; 12] = std::array::from_fn(|_| vec![f32::NAN; n + LANES]);
        for (s, (t, &o)) in tris.iter().zip(&other).enumerate() {
            if o {
                continue;
            }
            for k in 0..3 {
                soa[k][s] = t.v0[k];
                soa[3 + k][s] = t.e1[k];
                soa[6 + k][s] = t.e2[k];
                soa[9 + k][s] = t.ng[k];
            }
        }
        let any_other = other.iter().any(|&o| o);
        let mut other = other;
        other.resize(n + LANES, false);
        Slots { soa, other, any_other }
    }

    /// The slots `base + i` for the set bits `i` of `bits` against [0, cur]: the smallest t (∞ if
    /// none below `cur`... or a t ≥ cur) and its slot, the highest slot among equal t.
    #[inline(always)]
    pub fn leaf_chunk(
        &self,
        ray: &Ray8,
        base: usize,
        bits: u32,
        cur: f32,
        other: &mut impl FnMut(usize, f32) -> f32,
    ) -> (f32, usize) {
        let mut t = self.tri_chunk(ray, base, cur);
        if self.any_other {
            for (i, ti) in t.iter_mut().enumerate() {
                if bits & (1 << i) != 0 && self.other[base + i] {
                    *ti = other(base + i, cur);
                }
            }
        }
        smallest(&t, bits, base)
    }

    /// `tri_t` of the 8 slots from `base` with tmin 0 and tmax `cur` (NaN slots give ∞).
    #[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
    #[inline(always)]
    fn tri_chunk(&self, ray: &Ray8, base: usize, cur: f32) -> [f32; LANES] {
        use std::arch::x86_64::*;
        debug_assert!(base + LANES <= self.soa[0].len());
        // SAFETY: AVX2 (and FMA where used) are enabled at compile time (the cfgs); the loads read
        // 8 floats from `base`, within the arrays (padded by 8 lanes, and `base` is a slot).
        unsafe {
            let ld = |k: usize| _mm256_loadu_ps(self.soa[k].as_ptr().add(base));
            let s = _mm256_set1_ps;
            let (dx, dy, dz) = (s(ray.d[0]), s(ray.d[1]), s(ray.d[2]));
            let cx = _mm256_sub_ps(ld(0), s(ray.o[0]));
            let cy = _mm256_sub_ps(ld(1), s(ray.o[1]));
            let cz = _mm256_sub_ps(ld(2), s(ray.o[2]));
            // r = d × c as glam's `cross`: (a.zxy·b − b.zxy·a).zxy, the second product fused
            #[cfg(target_feature = "fma")]
            let nms = |a: __m256, b: __m256, c: __m256| _mm256_fnmadd_ps(a, b, c);
            #[cfg(not(target_feature = "fma"))]
            let nms = |a: __m256, b: __m256, c: __m256| _mm256_sub_ps(c, _mm256_mul_ps(a, b));
            let rx = nms(cy, dz, _mm256_mul_ps(dy, cz));
            let ry = nms(cz, dx, _mm256_mul_ps(dz, cx));
            let rz = nms(cx, dy, _mm256_mul_ps(dx, cy));
            let dot = |ax: __m256, ay: __m256, az: __m256, bx: __m256, by: __m256, bz: __m256| {
                _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(ax, bx), _mm256_mul_ps(ay, by)), _mm256_mul_ps(az, bz))
            };
            let (nx, ny, nz) = (ld(9), ld(10), ld(11));
            let det = dot(nx, ny, nz, dx, dy, dz);
            let inv_det = _mm256_div_ps(s(1.0), det);
            let u = _mm256_mul_ps(dot(rx, ry, rz, ld(6), ld(7), ld(8)), inv_det);
            let v = _mm256_mul_ps(dot(rx, ry, rz, ld(3), ld(4), ld(5)), inv_det);
            let tt = _mm256_mul_ps(dot(nx, ny, nz, cx, cy, cz), inv_det);
            let zero = _mm256_setzero_ps();
            let ok = _mm256_and_ps(
                _mm256_cmp_ps::<_CMP_NEQ_OQ>(det, zero),
                _mm256_and_ps(_mm256_cmp_ps::<_CMP_GE_OQ>(u, zero), _mm256_cmp_ps::<_CMP_GE_OQ>(v, zero)),
            );
            let ok = _mm256_and_ps(ok, _mm256_cmp_ps::<_CMP_LE_OQ>(_mm256_add_ps(u, v), s(1.0)));
            let ok = _mm256_and_ps(ok, _mm256_cmp_ps::<_CMP_GE_OQ>(tt, zero));
            let ok = _mm256_and_ps(ok, _mm256_cmp_ps::<_CMP_LE_OQ>(tt, s(cur)));
            let t = _mm256_blendv_ps(s(f32::INFINITY), tt, ok);
            let mut out = [0.0f32; LANES];
            _mm256_storeu_ps(out.as_mut_ptr(), t);
            out
        }
    }

    /// The portable form: `tri_t` lane by lane.
    #[cfg(not(all(target_arch = "x86_64", target_feature = "avx2")))]
    #[inline(always)]
    fn tri_chunk(&self, ray: &Ray8, base: usize, cur: f32) -> [f32; LANES] {
        std::array::from_fn(|i| {
            let g = |k: usize| self.soa[k][base + i];
            tri_t(
                &Tri {
                    v0: [g(0), g(1), g(2)],
                    e1: [g(3), g(4), g(5)],
                    e2: [g(6), g(7), g(8)],
                    ng: [g(9), g(10), g(11)],
                },
                ray,
                cur,
            )
        })
    }
}

/// The smallest `t[i]` over the set bits `i` of `bits` and its slot `base + i`, the highest `i`
/// among equal ones (+0.0 and −0.0 equal; the lane's own value is returned); (∞, `usize::MAX`)
/// where none is below ∞. The loop from the highest lane down, as one AVX2 horizontal minimum.
#[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
#[inline(always)]
fn smallest(t: &[f32; LANES], bits: u32, base: usize) -> (f32, usize) {
    use std::arch::x86_64::*;
    // SAFETY: AVX2 is enabled at compile time (the cfg above); the load reads the 8 floats of `t`.
    let (m, eq) = unsafe {
        let lane = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
        let sel = _mm256_cmpeq_epi32(_mm256_and_si256(_mm256_set1_epi32(bits as i32), lane), lane);
        let v = _mm256_blendv_ps(_mm256_set1_ps(f32::INFINITY), _mm256_loadu_ps(t.as_ptr()), _mm256_castsi256_ps(sel));
        let m = _mm256_min_ps(v, _mm256_permute2f128_ps::<1>(v, v));
        let m = _mm256_min_ps(m, _mm256_shuffle_ps::<0b01_00_11_10>(m, m));
        let m = _mm256_min_ps(m, _mm256_shuffle_ps::<0b10_11_00_01>(m, m));
        (_mm256_cvtss_f32(m), _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_EQ_OQ>(v, m)) as u32)
    };
    if m < f32::INFINITY {
        let i = (31 - eq.leading_zeros()) as usize;
        (t[i], base + i)
    } else {
        (f32::INFINITY, usize::MAX)
    }
}

/// The portable form of `smallest`: the loop from the highest lane down.
#[cfg(not(all(target_arch = "x86_64", target_feature = "avx2")))]
#[inline(always)]
fn smallest(t: &[f32; LANES], bits: u32, base: usize) -> (f32, usize) {
    let mut best = (f32::INFINITY, usize::MAX);
    for i in (0..LANES).rev() {
        if bits & (1 << i) != 0 && t[i] < best.0 {
            best = (t[i], base + i);
        }
    }
    best
}

/// Möller–Trumbore with inclusive edges on one triangle, t in [0, tmax] or ∞: the arithmetic of
/// obvhs' `RtTriangle` on glam's `Vec3A` (the cross product fused where the build has FMA).
#[cfg(any(test, not(all(target_arch = "x86_64", target_feature = "avx2"))))]
#[inline(always)]
pub fn tri_t(t: &Tri, ray: &Ray8, tmax: f32) -> f32 {
    let (d, o) = (ray.d, ray.o);
    let c = [t.v0[0] - o[0], t.v0[1] - o[1], t.v0[2] - o[2]];
    #[cfg(target_feature = "fma")]
    let nms = |a: f32, b: f32, c: f32| (-a).mul_add(b, c);
    #[cfg(not(target_feature = "fma"))]
    let nms = |a: f32, b: f32, c: f32| c - a * b;
    let r = [nms(c[1], d[2], d[1] * c[2]), nms(c[2], d[0], d[2] * c[0]), nms(c[0], d[1], d[0] * c[1])];
    let dot = |a: [f32; 3], b: [f32; 3]| (a[0] * b[0] + a[1] * b[1]) + a[2] * b[2];
    let det = dot(t.ng, d);
    if det == 0.0 {
        return f32::INFINITY;
    }
    let inv_det = 1.0 / det;
    let u = dot(r, t.e2) * inv_det;
    let v = dot(r, t.e1) * inv_det;
    if u >= 0.0 && v >= 0.0 && u + v <= 1.0 {
        let tt = dot(t.ng, c) * inv_det;
        if tt >= 0.0 && tt <= tmax {
            return tt;
        }
    }
    f32::INFINITY
}

/// Prefetches the first nodes of the inner children (`hits`: the mask's inner bits; the children
/// lie from `child_base` on), which are visited next, depth first.
#[inline(always)]
fn prefetch_children(nodes: &[Node], child_base: u32, hits: u32) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::*;
        let n = hits.count_ones() as usize;
        let first = child_base as usize;
        if n > 0 && first + n <= nodes.len() {
            for k in 0..n {
                // SAFETY: a prefetch of an address inside the slice (checked above) reads nothing
                // and writes nothing.
                unsafe { _mm_prefetch::<_MM_HINT_T0>(nodes.as_ptr().add(first + k) as *const i8) };
            }
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (nodes, child_base, hits);
}

/// obvhs' `get_child_and_index_bits`: per child byte, its hit bits and their shift.
#[inline(always)]
fn child_and_index_bits(n: &Node, oct_inv4: u32) -> (u64, u64) {
    let oct_inv8 = oct_inv4 as u64 | (oct_inv4 as u64) << 32;
    let meta8 = u64::from_le_bytes(n.meta);
    let is_inner8 = (meta8 & (meta8 << 1)) & 0x1010_1010_1010_1010;
    let inner_mask8 = (is_inner8 >> 4) * 0xff;
    let bit_index8 = (meta8 ^ (oct_inv8 & inner_mask8)) & 0x1f1f_1f1f_1f1f_1f1f;
    let child_bits8 = (meta8 >> 5) & 0x0707_0707_0707_0707;
    (child_bits8, bit_index8)
}

/// The node's frame in the ray's parameter, as obvhs' node test computes it: per axis the scale
/// (extent × inverse direction) and offset ((p − o) × inverse direction) of the quantized
/// children's slabs, and the children's bits and indices for the ray's octant.
#[inline(always)]
fn node_frame(n: &Node, ray: &Ray8) -> ([f32; 3], [f32; 3], (u64, u64)) {
    let ext = n.e.map(|e| f32::from_bits((e as u32) << 23));
    let inv = [ext[0] * ray.inv[0], ext[1] * ray.inv[1], ext[2] * ray.inv[2]];
    let org = [(n.p[0] - ray.o[0]) * ray.inv[0], (n.p[1] - ray.o[1]) * ray.inv[1], (n.p[2] - ray.o[2]) * ray.inv[2]];
    (inv, org, child_and_index_bits(n, ray.oct_inv4))
}

/// The hit mask of the node's 8 children (obvhs' `intersect_ray` layout: inner children's bits
/// 24–31, leaf slots' bits 0–23), all 8 slab tests in one AVX2 vector.
#[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
#[inline(always)]
pub(super) fn node_hits(n: &Node, ray: &Ray8, tmax: f32) -> u32 {
    use std::arch::x86_64::*;
    let (inv, org, (child_bits8, bit_index8)) = node_frame(n, ray);
    // SAFETY: AVX2 is enabled at compile time (the cfg above); the loads read 8 bytes of [u8; 8].
    unsafe {
        let q = |a: &[u8; 8]| _mm256_cvtepi32_ps(_mm256_cvtepu8_epi32(_mm_loadl_epi64(a.as_ptr() as *const __m128i)));
        let slab = |lo: &[u8; 8], hi: &[u8; 8], neg: bool, inv: f32, org: f32| {
            let (lo, hi) = (q(lo), q(hi));
            let (near, far) = if neg { (hi, lo) } else { (lo, hi) };
            let (s, o) = (_mm256_set1_ps(inv), _mm256_set1_ps(org));
            (_mm256_add_ps(_mm256_mul_ps(near, s), o), _mm256_add_ps(_mm256_mul_ps(far, s), o))
        };
        let d = ray.d;
        let (x0, x1) = slab(&n.q[0], &n.q[1], d[0] < 0.0, inv[0], org[0]);
        let (y0, y1) = slab(&n.q[2], &n.q[3], d[1] < 0.0, inv[1], org[1]);
        let (z0, z1) = slab(&n.q[4], &n.q[5], d[2] < 0.0, inv[2], org[2]);
        let tmin = _mm256_max_ps(x0, _mm256_max_ps(y0, z0));
        let tmx = _mm256_min_ps(x1, _mm256_min_ps(y1, z1));
        let tmin = _mm256_max_ps(tmin, _mm256_set1_ps(EPSILON));
        let tmx = _mm256_min_ps(tmx, _mm256_set1_ps(tmax));
        let hit = _mm256_castps_si256(_mm256_cmp_ps::<_CMP_LE_OQ>(tmin, tmx));
        let bits = _mm256_cvtepu8_epi32(_mm_cvtsi64_si128(child_bits8 as i64));
        let index = _mm256_cvtepu8_epi32(_mm_cvtsi64_si128(bit_index8 as i64));
        let m = _mm256_and_si256(_mm256_sllv_epi32(bits, index), hit);
        let m = _mm_or_si128(_mm256_castsi256_si128(m), _mm256_extracti128_si256::<1>(m));
        let m = _mm_or_si128(m, _mm_shuffle_epi32::<0b01_00_11_10>(m));
        let m = _mm_or_si128(m, _mm_shuffle_epi32::<0b10_11_00_01>(m));
        _mm_cvtsi128_si32(m) as u32
    }
}

/// The portable node test: obvhs' `intersect_ray_basic`, the same arithmetic per child.
#[cfg(not(all(target_arch = "x86_64", target_feature = "avx2")))]
#[inline(always)]
pub(super) fn node_hits(n: &Node, ray: &Ray8, tmax: f32) -> u32 {
    let (inv, org, (child_bits8, bit_index8)) = node_frame(n, ray);
    let mut mask = 0;
    for c in 0..8 {
        let mut t0 = [0.0f32; 3];
        let mut t1 = [0.0f32; 3];
        for k in 0..3 {
            let (lo, hi) = (n.q[2 * k][c] as f32, n.q[2 * k + 1][c] as f32);
            let (near, far) = if ray.d[k] < 0.0 { (hi, lo) } else { (lo, hi) };
            t0[k] = near * inv[k] + org[k];
            t1[k] = far * inv[k] + org[k];
        }
        let tmin = t0[0].max(t0[1]).max(t0[2]).max(EPSILON);
        let tmx = t1[0].min(t1[1]).min(t1[2]).min(tmax);
        if tmin <= tmx {
            let b = (child_bits8 >> (8 * c)) & 0xff;
            let i = (bit_index8 >> (8 * c)) & 0xff;
            mask |= (b << i) as u32;
        }
    }
    mask
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The 8-wide triangle test gives `tri_t`'s t lane by lane, bit for bit, on random triangles
    /// (slivers and degenerate ones among them) and rays, with finite and infinite tmax.
    #[test]
    fn chunk_is_tri_t_per_lane() {
        let mut s = 0x2545_f491_4f6c_dd1du64;
        let mut f = move || {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (s >> 40) as f32 / (1u64 << 24) as f32 * 2.0 - 1.0
        };
        let mut v = move || [f(), f(), f()];
        let sub = |a: [f32; 3], b: [f32; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
        let cross = |a: [f32; 3], b: [f32; 3]| {
            let (a, b) = (glam::Vec3A::from(a), glam::Vec3A::from(b));
            a.cross(b).to_array()
        };
        let tris: Vec<Tri> = (0..4096)
            .map(|k| {
                let (v0, v1) = (v(), v());
                let v2 = if k % 13 == 0 { v1 } else { v() };
                let (e1, e2) = (sub(v0, v1), sub(v2, v0));
                Tri { v0, e1, e2, ng: cross(e1, e2) }
            })
            .collect();
        let other = vec![false; tris.len()];
        let bvh = Slots::new(&tris, other);
        let mut found = 0;
        for k in 0..20_000 {
            let d = glam::Vec3::from(v()).normalize_or(glam::Vec3::X).to_array();
            let ray = Ray8::new(v(), d);
            let tmax = if k % 2 == 0 { f32::INFINITY } else { v()[0].abs() * 2.0 };
            let base = (k * 7) % (tris.len() - LANES);
            let t = bvh.tri_chunk(&ray, base, tmax);
            for (i, &ti) in t.iter().enumerate() {
                let want = tri_t(&tris[base + i], &ray, tmax);
                assert_eq!(ti.to_bits(), want.to_bits(), "ray {k} lane {i}");
                found += want.is_finite() as usize;
            }
        }
        assert!(found > 1000, "{found}");
    }
}
