//! The builder of `super::WideBvh`'s tree: binned SAH, top down, straight into 8-wide nodes.
//!
//! A node starts as one child holding its whole range; the child of largest surface area is split
//! by a binned SAH (`BINS` bins per axis over the centroids, fewer below `BINS` primitives) until the node has 8 children or
//! every child is a leaf (Embree's and pbrt's wide-BVH collapse, done while building). A range
//! becomes a leaf when it has at most `MAX_LEAF` primitives and the SAH finds no split cheaper
//! than testing them all. Ranges whose centroids coincide are split at the median by count, and
//! past `MEDIAN_DEPTH` binary splits every split is a median split, so that the depth (and the
//! traversal stack) stays bounded: at most `MEDIAN_DEPTH + 32` levels.
//!
//! Invariants of the output: node 0 is the root (when there is a primitive); a node's leaf
//! children's primitives are consecutive slots from `prim_base`, at most 64 (8 children × 8), and
//! `child[i]` of a leaf is its first slot's offset from `prim_base` | its count << 8; an inner
//! child's `child[i]` is its node index (> the parent's); an empty child has the box (+∞, −∞);
//! each child's box is the union of its primitives' boxes widened by `PAD` (relative) on each side.

use super::Node;
use crate::math::Vec3;

/// Bins per axis.
const BINS: usize = 32;
/// Most primitives in a leaf.
pub(super) const MAX_LEAF: usize = 8;
/// The SAH cost of a node visit in units of one primitive test.
const C_NODE: f32 = 1.0;
/// Boxes are widened by this fraction of their largest coordinate's magnitude (a few ulps): the
/// triangle test accepts points a rounding error outside a triangle, and a ray along an axis
/// meets a box's face exactly (see `super`'s header).
const PAD: f32 = 4.0 * f32::EPSILON;
/// Binary splits after which every split is a median split.
const MEDIAN_DEPTH: u32 = 48;
/// The deepest a tree can be (`MEDIAN_DEPTH` + log2 of 2^32 primitives).
pub(super) const MAX_DEPTH: usize = MEDIAN_DEPTH as usize + 32;

#[derive(Clone, Copy)]
struct Prim {
    lo: Vec3,
    hi: Vec3,
    id: u32,
}

impl Prim {
    fn centroid(&self) -> Vec3 {
        (self.lo + self.hi) * 0.5
    }
}

#[derive(Clone, Copy)]
struct Bounds {
    lo: Vec3,
    hi: Vec3,
}

impl Bounds {
    const EMPTY: Bounds = Bounds { lo: Vec3::splat(f32::INFINITY), hi: Vec3::splat(f32::NEG_INFINITY) };
    fn grow(&mut self, lo: Vec3, hi: Vec3) {
        self.lo = self.lo.min(lo);
        self.hi = self.hi.max(hi);
    }
    /// Half the surface area.
    fn area(&self) -> f32 {
        let d = (self.hi - self.lo).max(Vec3::ZERO);
        d.x * d.y + d.y * d.z + d.z * d.x
    }
    fn of(prims: &[Prim]) -> (Bounds, Bounds) {
        let (mut b, mut c) = (Bounds::EMPTY, Bounds::EMPTY);
        for p in prims {
            b.grow(p.lo, p.hi);
            c.grow(p.centroid(), p.centroid());
        }
        (b, c)
    }
}

/// A child range during the build: `prims[start..end]`, its box, binary depth, and whether it is
/// final (a leaf the SAH chose).
#[derive(Clone, Copy)]
struct Range {
    start: usize,
    end: usize,
    b: Bounds,
    /// The box of the centroids.
    cb: Bounds,
    depth: u32,
    leaf: bool,
}

struct Builder {
    prims: Vec<Prim>,
    nodes: Vec<Node>,
    slot_prim: Vec<u32>,
}

/// The tree over `bounds` (one box per primitive, finite): its nodes and each slot's primitive.
pub(super) fn build(bounds: &[(Vec3, Vec3)]) -> (Vec<Node>, Vec<u32>) {
    if bounds.is_empty() {
        return (Vec::new(), Vec::new());
    }
    let prims = bounds.iter().enumerate().map(|(i, &(lo, hi))| Prim { lo, hi, id: i as u32 }).collect();
    let mut b =
        Builder { prims, nodes: Vec::with_capacity(bounds.len() / 4), slot_prim: Vec::with_capacity(bounds.len()) };
    let (bb, cb) = Bounds::of(&b.prims);
    b.node(Range { start: 0, end: bounds.len(), b: bb, cb, depth: 0, leaf: false });
    (b.nodes, b.slot_prim)
}

impl Builder {
    /// Builds the node over `r` (and its subtree); returns its index.
    fn node(&mut self, r: Range) -> u32 {
        let mut kids = vec![r];
        while kids.len() < 8 {
            let Some(k) = (0..kids.len())
                .filter(|&k| !kids[k].leaf && kids[k].end - kids[k].start > 1)
                .max_by(|&a, &b| kids[a].b.area().total_cmp(&kids[b].b.area()))
            else {
                break;
            };
            match self.split(kids[k]) {
                Some((a, b)) => {
                    kids[k] = a;
                    kids.push(b);
                }
                None => kids[k].leaf = true,
            }
        }
        let index = self.nodes.len() as u32;
        self.nodes.push(Node::EMPTY);
        let mut node = Node::EMPTY;
        node.prim_base = self.slot_prim.len() as u32;
        for (i, c) in kids.iter().enumerate() {
            for k in 0..3 {
                let (lo, hi) = (c.b.lo[k], c.b.hi[k]);
                let pad = PAD * lo.abs().max(hi.abs());
                node.b[2 * k][i] = lo - pad;
                node.b[2 * k + 1][i] = hi + pad;
            }
            let n = c.end - c.start;
            if n <= MAX_LEAF {
                let off = self.slot_prim.len() as u32 - node.prim_base;
                node.child[i] = off | (n as u32) << 8;
                self.slot_prim.extend(self.prims[c.start..c.end].iter().map(|p| p.id));
            }
        }
        for (i, c) in kids.iter().enumerate() {
            if c.end - c.start > MAX_LEAF {
                node.inner |= 1 << i;
                node.child[i] = self.node(Range { leaf: false, ..*c });
            }
        }
        self.nodes[index as usize] = node;
        index
    }

    /// Splits `r` in two by the binned SAH (or the median); `None` when it should be a leaf.
    fn split(&mut self, r: Range) -> Option<(Range, Range)> {
        let n = r.end - r.start;
        let prims = &mut self.prims[r.start..r.end];
        let cb = r.cb;
        let ext = cb.hi - cb.lo;
        // per axis and bin: box, centroid box, count (one pass over the primitives)
        // (fewer bins for small ranges: there, the sweep over the bins cost more than the binning)
        let nb = BINS.min(n.max(4));
        let mut bins = [[(Bounds::EMPTY, Bounds::EMPTY, 0usize); BINS]; 3];
        let k =
            Vec3::from_array(std::array::from_fn(
                |a| {
                    if ext[a] > 0.0 {
                        nb as f32 * (1.0 - 1e-6) / ext[a]
                    } else {
                        0.0
                    }
                },
            ));
        let bin = |c: f32, a: usize| (((c - cb.lo[a]) * k[a]) as usize).min(nb - 1);
        if r.depth < MEDIAN_DEPTH {
            for p in prims.iter() {
                let c = p.centroid();
                for (a, bins) in bins.iter_mut().enumerate() {
                    let b = &mut bins[bin(c[a], a)];
                    b.0.grow(p.lo, p.hi);
                    b.1.grow(c, c);
                    b.2 += 1;
                }
            }
        }
        // (cost, axis, last bin of the left side)
        let mut best: Option<(f32, usize, usize)> = None;
        for (axis, bins) in bins.iter().enumerate() {
            if ext[axis] <= 0.0 || r.depth >= MEDIAN_DEPTH {
                continue;
            }
            let mut right = [0.0f32; BINS];
            let (mut rb, mut rn) = (Bounds::EMPTY, 0usize);
            for i in (1..nb).rev() {
                rb.grow(bins[i].0.lo, bins[i].0.hi);
                rn += bins[i].2;
                right[i] = rb.area() * rn as f32;
            }
            let (mut lb, mut ln) = (Bounds::EMPTY, 0usize);
            for i in 0..nb - 1 {
                lb.grow(bins[i].0.lo, bins[i].0.hi);
                ln += bins[i].2;
                if ln == 0 || ln == n {
                    continue;
                }
                let cost = lb.area() * ln as f32 + right[i + 1];
                if best.is_none_or(|b| cost < b.0) {
                    best = Some((cost, axis, i));
                }
            }
        }
        let d = r.depth + 1;
        let range =
            |start: usize, end: usize, (b, cb): (Bounds, Bounds)| Range { start, end, b, cb, depth: d, leaf: false };
        match best {
            Some((cost, axis, last)) => {
                if n <= MAX_LEAF && n as f32 <= C_NODE + cost / r.b.area().max(f32::MIN_POSITIVE) {
                    return None;
                }
                let mid = partition(prims, |p| bin(p.centroid()[axis], axis) <= last);
                let side = |bins: &[(Bounds, Bounds, usize)]| {
                    let (mut b, mut c) = (Bounds::EMPTY, Bounds::EMPTY);
                    for x in bins {
                        b.grow(x.0.lo, x.0.hi);
                        c.grow(x.1.lo, x.1.hi);
                    }
                    (b, c)
                };
                let (lo, hi) = (side(&bins[axis][..=last]), side(&bins[axis][last + 1..nb]));
                Some((range(r.start, r.start + mid, lo), range(r.start + mid, r.end, hi)))
            }
            None if n <= MAX_LEAF => None,
            None => {
                // coincident centroids, or past MEDIAN_DEPTH: the median along the widest axis
                let axis = if ext.x >= ext.y && ext.x >= ext.z {
                    0
                } else if ext.y >= ext.z {
                    1
                } else {
                    2
                };
                let mid = n / 2;
                prims.select_nth_unstable_by(mid, |a, b| a.centroid()[axis].total_cmp(&b.centroid()[axis]));
                let (lo, hi) = (Bounds::of(&prims[..mid]), Bounds::of(&prims[mid..]));
                Some((range(r.start, r.start + mid, lo), range(r.start + mid, r.end, hi)))
            }
        }
    }
}

/// Moves the `left` elements first; returns how many there are.
fn partition(v: &mut [Prim], left: impl Fn(&Prim) -> bool) -> usize {
    let mut i = 0;
    for j in 0..v.len() {
        if left(&v[j]) {
            v.swap(i, j);
            i += 1;
        }
    }
    i
}
