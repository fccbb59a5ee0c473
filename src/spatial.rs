//! A static 3-D kd-tree over points, used by the CF cluster map and forecast maps ([BAJ08 §3.2]
//! "cluster map" / "forecast maps", spec §3) and by photon-map gathers.
//!
//! Layout: a flat node array (children of node `i` are `i + 1` and `right`), built by a median split on
//! the widest axis of each node's bounding box until a node holds at most [`LEAF_SIZE`] points. Points
//! are stored permuted into leaf order next to their item id (a `u32` chosen by the caller, by default
//! the index into the input slice), so the tree is self-contained and serializable with bitcode.
//!
//! Invariants: for an inner node with axis `d` and value `s`, every point of the left subtree has
//! `p[d] ≤ s` and every point of the right subtree has `p[d] ≥ s`. Queries allocate nothing (the
//! traversal stack is a fixed array; depth ≤ 64 for any `u32` count); "within r²" means `dist² ≤ r²`;
//! k-nearest results are the k smallest `(dist², id)` pairs, so ties resolve deterministically.
//! Points with non-finite coordinates are stored but never returned by a finite query; empty trees and
//! NaN queries return nothing.

// `!(x > 0.0)`-style tests are deliberate: they are true for NaN (degenerate input is rejected).
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use std::cell::Cell;

/// Maximum number of points in a leaf.
pub const LEAF_SIZE: usize = 8;
const STACK: usize = 64;
const LEAF: u8 = 3;

/// One node of the flat tree.
#[derive(Clone, Copy, Debug, PartialEq, bitcode::Encode, bitcode::Decode)]
struct Node {
    /// Split coordinate (inner nodes).
    split: f32,
    /// Inner: index of the right child. Leaf: first slot of its points.
    a: u32,
    /// Leaf: one past the last slot. Inner: unused.
    b: u32,
    /// Split axis 0..3, or `LEAF`.
    axis: u8,
}

/// Static kd-tree over 3-D points labelled by `u32` ids.
#[derive(Clone, Debug, Default, PartialEq, bitcode::Encode, bitcode::Decode)]
pub struct KdTree {
    nodes: Vec<Node>,
    points: Vec<[f32; 3]>,
    ids: Vec<u32>,
}

/// Squared distance as every query of the tree computes it (callers that must reproduce a
/// query's `(dist², id)` order bit for bit use this one).
#[inline]
pub fn dist2(a: &[f32; 3], b: &[f32; 3]) -> f32 {
    let (x, y, z) = (a[0] - b[0], a[1] - b[1], a[2] - b[2]);
    x * x + y * y + z * z
}

impl KdTree {
    /// Builds a tree over `points`; item ids are indices into `points`.
    pub fn build(points: &[[f32; 3]]) -> Self {
        let ids = (0..points.len() as u32).collect();
        Self::build_with_ids(points.to_vec(), ids)
    }

    /// Builds a tree over `points[i]` labelled `ids[i]` (extra entries of the longer vector are dropped).
    pub fn build_with_ids(points: Vec<[f32; 3]>, ids: Vec<u32>) -> Self {
        let n = points.len().min(ids.len());
        let mut items: Vec<([f32; 3], u32)> = points.into_iter().zip(ids).take(n).collect();
        let mut nodes = Vec::with_capacity(2 * n / LEAF_SIZE + 1);
        if n > 0 {
            build_rec(&mut items, 0, &mut nodes);
        }
        KdTree { nodes, points: items.iter().map(|x| x.0).collect(), ids: items.iter().map(|x| x.1).collect() }
    }

    /// Number of stored points.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// True when the tree holds no point.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Iterates over all stored `(id, position)` pairs (in leaf order).
    pub fn items(&self) -> impl Iterator<Item = (u32, [f32; 3])> + '_ {
        self.ids.iter().copied().zip(self.points.iter().copied())
    }

    /// Nearest stored point to `p`: `(id, dist²)`, the smallest `(dist², id)`. `None` for an empty
    /// tree or a non-finite query.
    pub fn nearest(&self, p: [f32; 3]) -> Option<(u32, f32)> {
        self.nearest_within(p, f32::INFINITY)
    }

    /// The smallest `(dist², id)` with `dist² ≤ r2`, as `(id, dist²)`; `None` when no point is
    /// that close (a bounded search: it never looks beyond `r2`).
    pub fn nearest_within(&self, p: [f32; 3], r2: f32) -> Option<(u32, f32)> {
        if !(r2 >= 0.0) {
            return None;
        }
        let mut best: Option<(u32, f32)> = None;
        let bound = Cell::new(r2);
        self.traverse(&p, &bound, |id, d2| {
            let better = match best {
                None => d2 <= bound.get(),
                Some((bid, bd)) => d2 < bd || (d2 == bd && id < bid),
            };
            if better {
                bound.set(d2);
                best = Some((id, d2));
            }
        });
        best
    }

    /// True when some stored point has `dist² ≤ r2`: `nearest_within(p, r2).is_some()`, but the
    /// search stops at the first such point (the forecast maps' margin test).
    pub fn any_within(&self, p: [f32; 3], r2: f32) -> bool {
        if !(r2 >= 0.0) {
            return false;
        }
        let bound = Cell::new(r2);
        let mut found = false;
        self.traverse(&p, &bound, |_, d2| {
            if !found && d2 <= r2 {
                found = true;
                bound.set(-1.0); // every remaining node has a lower bound ≥ 0: prune them all
            }
        });
        found
    }

    /// The `k` nearest points with `dist² ≤ r2`, written to `out` as `(dist², id)` sorted by distance
    /// (ties by id). `out` is cleared first and used as a max-heap during the search; nothing else is
    /// allocated.
    pub fn k_nearest_within(&self, p: [f32; 3], k: usize, r2: f32, out: &mut Vec<(f32, u32)>) {
        out.clear();
        if k == 0 || !(r2 >= 0.0) {
            return;
        }
        out.reserve(k.min(self.len()));
        // Max-heap keyed by (dist², id); the bound is the heap top once full, else r2.
        let bound = Cell::new(r2);
        let key = |e: &(f32, u32)| (e.0, e.1);
        self.traverse(&p, &bound, |id, d2| {
            if !(d2 <= bound.get()) {
                return;
            }
            if out.len() < k {
                out.push((d2, id));
                let mut c = out.len() - 1;
                while c > 0 {
                    let parent = (c - 1) / 2;
                    if key(&out[parent]) < key(&out[c]) {
                        out.swap(parent, c);
                        c = parent;
                    } else {
                        break;
                    }
                }
            } else {
                if (d2, id) >= key(&out[0]) {
                    return;
                }
                out[0] = (d2, id);
                let (mut c, n) = (0usize, out.len());
                loop {
                    let (l, r) = (2 * c + 1, 2 * c + 2);
                    let mut m = c;
                    if l < n && key(&out[l]) > key(&out[m]) {
                        m = l;
                    }
                    if r < n && key(&out[r]) > key(&out[m]) {
                        m = r;
                    }
                    if m == c {
                        break;
                    }
                    out.swap(c, m);
                    c = m;
                }
            }
            if out.len() == k {
                bound.set(out[0].0);
            }
        });
        out.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    }

    /// Calls `f(id, position)` for every stored point inside the closed box `[lo, hi]`.
    pub fn for_each_in_box(&self, lo: [f32; 3], hi: [f32; 3], mut f: impl FnMut(u32, [f32; 3])) {
        if self.nodes.is_empty() {
            return;
        }
        let mut stack = [0u32; STACK];
        let mut sp = 1usize;
        while sp > 0 {
            sp -= 1;
            let node = self.nodes[stack[sp] as usize];
            let ni = stack[sp];
            if node.axis == LEAF {
                for s in node.a as usize..node.b as usize {
                    let q = self.points[s];
                    if (0..3).all(|d| q[d] >= lo[d] && q[d] <= hi[d]) {
                        f(self.ids[s], q);
                    }
                }
                continue;
            }
            let d = node.axis as usize;
            // Left holds p[d] ≤ split, right p[d] ≥ split; `!(a > b)` descends on NaN.
            if !(lo[d] > node.split) && sp < STACK {
                stack[sp] = ni + 1;
                sp += 1;
            }
            if !(hi[d] < node.split) && sp < STACK {
                stack[sp] = node.a;
                sp += 1;
            }
        }
    }

    /// Calls `f(id, dist²)` for every stored point with `dist² ≤ r2` (in no particular order).
    pub fn for_each_within(&self, p: [f32; 3], r2: f32, mut f: impl FnMut(u32, f32)) {
        if !(r2 >= 0.0) {
            return;
        }
        self.traverse(&p, &Cell::new(r2), |id, d2| {
            if d2 <= r2 {
                f(id, d2)
            }
        });
    }

    /// Depth-first traversal, near child first; a far child is visited when its plane distance² is ≤
    /// the current `bound` (which `visit` may shrink). `visit` sees every candidate point.
    #[inline]
    fn traverse(&self, p: &[f32; 3], bound: &Cell<f32>, mut visit: impl FnMut(u32, f32)) {
        if self.nodes.is_empty() || !p.iter().all(|c| c.is_finite()) {
            return;
        }
        // Stack of (node, plane distance² lower bound).
        let mut stack = [(0u32, 0.0f32); STACK];
        let mut sp = 1usize;
        while sp > 0 {
            sp -= 1;
            let (mut ni, lb) = stack[sp];
            if lb > bound.get() {
                continue;
            }
            loop {
                let node = self.nodes[ni as usize];
                if node.axis == LEAF {
                    for s in node.a as usize..node.b as usize {
                        let d2 = dist2(&self.points[s], p);
                        visit(self.ids[s], d2);
                    }
                    break;
                }
                let diff = p[node.axis as usize] - node.split;
                let (near, far) = if diff < 0.0 { (ni + 1, node.a) } else { (node.a, ni + 1) };
                let d2 = diff * diff;
                // `!(d2 > bound)` also descends when the split is NaN (fail open, never skip).
                if !(d2 > bound.get()) && sp < STACK {
                    stack[sp] = (far, d2);
                    sp += 1;
                }
                ni = near;
            }
        }
    }
}

/// Recursively builds the subtree over `items` (whose first slot is `offset`) and returns its node index.
fn build_rec(items: &mut [([f32; 3], u32)], offset: usize, nodes: &mut Vec<Node>) -> u32 {
    let idx = nodes.len() as u32;
    let n = items.len();
    if n <= LEAF_SIZE {
        nodes.push(Node { split: 0.0, a: offset as u32, b: (offset + n) as u32, axis: LEAF });
        return idx;
    }
    // Widest axis of the finite bounding box (NaN coordinates are ignored by min/max).
    let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
    for (p, _) in items.iter() {
        for d in 0..3 {
            lo[d] = lo[d].min(p[d]);
            hi[d] = hi[d].max(p[d]);
        }
    }
    let ext = |d: usize| if hi[d] >= lo[d] { hi[d] - lo[d] } else { 0.0 };
    let axis = (0..3).fold(0, |best, d| if ext(d) > ext(best) { d } else { best });
    let mid = n / 2;
    items.select_nth_unstable_by(mid, |a, b| a.0[axis].total_cmp(&b.0[axis]));
    let split = items[mid].0[axis];
    // Always splitting at the median index keeps the depth at log2(n / LEAF_SIZE), even for
    // coincident points; the ≤ / ≥ invariant holds because select_nth orders around `mid`.
    // NaN compares greater than everything under total_cmp, so the left half has no NaN above `split`
    // unless split itself is NaN; then pruning never happens on that axis (comparisons fail open).
    nodes.push(Node { split, a: 0, b: 0, axis: axis as u8 });
    let (left, right) = items.split_at_mut(mid);
    build_rec(left, offset, nodes);
    let r = build_rec(right, offset + mid, nodes);
    nodes[idx as usize].a = r;
    idx
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::rng::{stream, Rng};

    fn random_points(n: usize, seed: u64) -> Vec<[f32; 3]> {
        let mut r = Rng::keyed(seed, stream::MISC, 0, 0);
        (0..n).map(|_| [r.next_f32(), r.next_f32(), r.next_f32()]).collect()
    }

    fn brute_knn(pts: &[[f32; 3]], p: [f32; 3], k: usize, r2: f32) -> Vec<f32> {
        let mut d: Vec<f32> = pts.iter().map(|q| dist2(q, &p)).filter(|&d| d <= r2).collect();
        d.sort_by(f32::total_cmp);
        d.truncate(k);
        d
    }

    fn check_against_brute(pts: &[[f32; 3]], seed: u64) {
        let tree = KdTree::build(pts);
        assert_eq!(tree.len(), pts.len());
        let queries = random_points(200, seed + 1000);
        let mut out = Vec::new();
        for (qi, q) in queries.iter().enumerate() {
            let q = [q[0] * 1.2 - 0.1, q[1] * 1.2 - 0.1, q[2] * 1.2 - 0.1];
            let bn = pts.iter().map(|x| dist2(x, &q)).fold(f32::INFINITY, f32::min);
            match tree.nearest(q) {
                Some((id, d2)) => {
                    assert_eq!(d2, bn);
                    assert_eq!(dist2(&pts[id as usize], &q), d2);
                    // ties go to the smallest id
                    let first = pts.iter().position(|x| dist2(x, &q) == bn).unwrap();
                    assert_eq!(id as usize, first);
                }
                None => assert!(pts.is_empty()),
            }
            // the bounded search: the nearest within r2, or nothing when every point is farther
            let r2n = [0.0, 0.001, 0.01, 0.1][qi % 4];
            let within = tree.nearest_within(q, r2n);
            assert_eq!(within, tree.nearest(q).filter(|&(_, d2)| d2 <= r2n));
            assert_eq!(tree.any_within(q, r2n), within.is_some());
            let k = [1, 5, 8, 32, 1000][qi % 5];
            let r2 = [0.001, 0.01, 0.1, f32::INFINITY][qi % 4];
            tree.k_nearest_within(q, k, r2, &mut out);
            let got: Vec<f32> = out.iter().map(|e| e.0).collect();
            assert_eq!(got, brute_knn(pts, q, k, r2));
            for &(d2, id) in &out {
                assert_eq!(dist2(&pts[id as usize], &q), d2);
            }
            let mut ids = Vec::new();
            tree.for_each_within(q, r2.min(0.05), |id, d2| {
                assert!(d2 <= r2.min(0.05));
                ids.push(id)
            });
            ids.sort();
            let brute: Vec<u32> =
                (0..pts.len() as u32).filter(|&i| dist2(&pts[i as usize], &q) <= r2.min(0.05)).collect();
            assert_eq!(ids, brute);
        }
    }

    #[test]
    fn matches_brute_force_on_random_points() {
        check_against_brute(&random_points(5000, 1), 1);
        check_against_brute(&random_points(9, 2), 2);
        check_against_brute(&random_points(1, 3), 3);
    }

    #[test]
    fn matches_brute_force_on_degenerate_input() {
        check_against_brute(&[], 4);
        check_against_brute(&vec![[0.5, 0.5, 0.5]; 1000], 5);
        let plane: Vec<[f32; 3]> = random_points(2000, 6).into_iter().map(|p| [p[0], 0.25, p[2]]).collect();
        check_against_brute(&plane, 6);
        let line: Vec<[f32; 3]> = random_points(2000, 7).into_iter().map(|p| [p[0], 0.5, 0.5]).collect();
        check_against_brute(&line, 7);
        // Duplicated points: k > n and exact ties.
        let mut dup = random_points(50, 8);
        dup.extend_from_within(..);
        check_against_brute(&dup, 8);
    }

    #[test]
    fn custom_ids_nan_and_empty_queries() {
        let pts = random_points(100, 9);
        let ids: Vec<u32> = (0..100).map(|i| 1000 + i).collect();
        let tree = KdTree::build_with_ids(pts.clone(), ids);
        let (id, _) = tree.nearest(pts[17]).unwrap();
        assert_eq!(id, 1017);
        assert!(tree.nearest([f32::NAN, 0.0, 0.0]).is_none());
        let mut out = vec![(1.0, 1)];
        tree.k_nearest_within([0.5; 3], 0, 1.0, &mut out);
        assert!(out.is_empty());
        tree.k_nearest_within([0.5; 3], 4, f32::NAN, &mut out);
        assert!(out.is_empty());
        let empty = KdTree::build(&[]);
        assert!(empty.nearest([0.0; 3]).is_none());
        // Points with NaN coordinates never match and do not break other queries.
        let mut bad = pts.clone();
        bad[3] = [f32::NAN, 0.1, 0.1];
        let t = KdTree::build(&bad);
        let (id, _) = t.nearest(pts[40]).unwrap();
        assert_eq!(id, 40);
    }

    #[test]
    fn box_query_matches_brute_force() {
        for pts in [random_points(3000, 11), vec![[0.5; 3]; 100], Vec::new()] {
            let tree = KdTree::build(&pts);
            let boxes = random_points(100, 12);
            for b in boxes.chunks(2) {
                let lo = [b[0][0].min(b[1][0]), b[0][1].min(b[1][1]), b[0][2].min(b[1][2])];
                let hi = [b[0][0].max(b[1][0]), b[0][1].max(b[1][1]), b[0][2].max(b[1][2])];
                let mut got = Vec::new();
                tree.for_each_in_box(lo, hi, |id, _| got.push(id));
                got.sort();
                let want: Vec<u32> = (0..pts.len() as u32)
                    .filter(|&i| (0..3).all(|d| pts[i as usize][d] >= lo[d] && pts[i as usize][d] <= hi[d]))
                    .collect();
                assert_eq!(got, want);
            }
            let mut all = 0;
            tree.for_each_in_box([0.0; 3], [1.0; 3], |_, _| all += 1);
            assert_eq!(all, pts.len());
        }
    }

    #[test]
    fn serialization_round_trip() {
        let tree = KdTree::build(&random_points(1000, 10));
        let bytes = bitcode::encode(&tree);
        let back: KdTree = bitcode::decode(&bytes).unwrap();
        assert_eq!(back, tree);
    }
}
