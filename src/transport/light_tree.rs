//! Point-light selection by a light tree (Conty Estevez & Kulla 2018, "Importance Sampling of
//! Many Lights with Adaptive Tree Splitting"; the bounds of Walter et al. 2005, "Lightcuts").
//!
//! The alternative to RIS (`transport::light_select`) for issue #11 item 2. A binary tree over the
//! pass's point lights (median splits of the positions, built once per pass) stores per node the
//! box of its lights' positions, their total reflected power `Φ_N` (RGB) and a cone bounding the *lines* of
//! their normals (axis `a`, half-angle `θ_n`: `|n·w|` and `|-n·w|` alike, as `G` takes `|cos|`).
//! At a shading point `x` (normal `n_x`) one traversal picks a light: at each inner node the child
//! `N` is taken with probability `I_N/(I_L + I_R)`, with the bound `I_N = Σ_rgb(Φ_N·t)·min(b, c_x·c_y/d²)`,
//! `t` the receiver's colour
//! (for a single light its exact `Φ·min(G, b)`, or 0 where the caller's target `p̂`, its
//! unshadowed contribution, is 0; the BSDFs are left out at every level, so the scale is one): `c_x ≥ |n_x·ŵ|` and `c_y ≥ |n_y·ŵ|` over every direction `ŵ` from
//! `x` into the node's bounding sphere and every normal in its cone, `d` the distance from `x` to
//! the node's box (`b = ∞` for nodes holding unclamped lights). The estimate of `Σ_i F_i·V_i` is
//! `F(y)·V(y)/(K·P(y))` averaged over `K` independent traversals, `P(y)` the product of the branch
//! probabilities.
//!
//! Unbiasedness: `P(i) > 0` wherever `F_i ≠ 0`, because every bound is ≥ the largest `p̂` in its
//! node up to the BSDFs (never 0 where some light of the node has `p̂ > 0`), and a light's own `p̂`
//! is > 0 wherever its `F` is (the caller's contract, as for RIS). Small angular and distance slack
//! keeps the bounds conservative under rounding. When both children's importances are 0 no light
//! can contribute and the traversal returns nothing (an exact 0).
//!
//! Invariants: two 32-bit words per traversal (one 53-bit uniform, remapped at each level), so the
//! number of random words depends only on `K`; the tree is a pure function of the lights, so the
//! selection is a pure function of (lights, point, words); lights with non-positive or non-finite
//! or negative power are left out (they carry none).

use super::light_select::Selected;
use crate::math::{Rgb, Vec3};
use crate::sampling::rng::Rng;

/// One light as the tree sees it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TreeLight {
    /// Position.
    pub p: Vec3,
    /// Geometric normal (any sign); ignored when `omni`.
    pub n: Vec3,
    /// The light's reflected power per channel (Φ times its reflectance colour): a node's
    /// importance at a point scales with `Σ_rgb power·tint`, `tint` the receiver's colour.
    pub power: Rgb,
    /// `G` of this light is clamped by `b`.
    pub clamped: bool,
    /// The light's `G` has no `cos θ_y` factor (a point light): its cone is the whole sphere.
    pub omni: bool,
}

/// A node: the bounds of its lights, and either one light (`light`) or two children.
#[derive(Clone, Copy, Debug)]
struct Node {
    lo: Vec3,
    hi: Vec3,
    /// Centre and radius (with slack) of the box's bounding sphere.
    centre: Vec3,
    radius: f32,
    /// Axis of the cone of normal lines.
    axis: Vec3,
    /// cos and sin of the cone's half-angle θ_n (`cos_n = 0`, `sin_n = 1` for the whole sphere).
    cos_n: f32,
    sin_n: f32,
    power: Rgb,
    /// Every light of the node is clamped.
    clamped: bool,
    /// The light's index when a leaf, else `u32::MAX`.
    light: u32,
    /// Children (valid when not a leaf).
    left: u32,
    right: u32,
}

/// Where a traversal runs: the shading point, its geometric normal, the receiver's colour and `b`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TreeQuery {
    /// Shading point.
    pub x: Vec3,
    /// Its geometric normal (any sign: the bound takes `|n_x·ŵ|`).
    pub nx: Vec3,
    /// The receiver's colour (e.g. albedo + specular reflectance): > 0 in every channel in which
    /// its BSDF can be (a channel that is 0 here must be 0 in every `p̂`).
    pub tint: Rgb,
    /// The clamp `b` on `G` (∞: none).
    pub b: f32,
}

/// The per-pass light tree.
#[derive(Clone, Debug)]
pub struct LightTree {
    nodes: Vec<Node>,
}

/// Relative slack on the bounding radius, absolute slack on angles (radians, via sin/cos).
const SLACK_R: f32 = 1e-4;

impl LightTree {
    /// The tree over `lights` (indices into that slice are what [`Self::select`] returns).
    /// `None` when no light has a positive, finite weight.
    pub fn new(lights: &[TreeLight]) -> Option<Self> {
        let ok = |l: &TreeLight| l.power.is_finite() && l.power.min_element() >= 0.0 && l.power.max_element() > 0.0;
        let mut ids: Vec<u32> = (0..lights.len() as u32).filter(|&i| ok(&lights[i as usize])).collect();
        if ids.is_empty() {
            return None;
        }
        let mut nodes = Vec::with_capacity(2 * ids.len());
        build(lights, &mut ids, &mut nodes);
        Some(LightTree { nodes })
    }

    /// Number of lights in the tree.
    pub fn len(&self) -> usize {
        self.nodes.len().div_ceil(2)
    }

    /// Always false (a tree has at least one light).
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// `K` independent traversals at `q`; `target(i)`
    /// returns `(p̂(i), value_i)` and `emit` receives each selected light with weight
    /// `1/(K·P(i))` (none when no light can contribute). Two words of `rng` per traversal.
    pub fn select<T: Copy>(
        &self,
        q: &TreeQuery,
        k: u32,
        rng: &mut Rng,
        mut target: impl FnMut(usize) -> (f32, T),
        mut emit: impl FnMut(Selected<T>),
    ) {
        let k = k.max(1);
        for _ in 0..k {
            let u = ((rng.next_u32() as u64) << 21 ^ (rng.next_u32() as u64 >> 11)) as f64 / (1u64 << 53) as f64;
            if let Some((index, pmf, value)) = self.traverse(q, u, &mut target) {
                emit(Selected { index, weight: (1.0 / (k as f64 * pmf)) as f32, value });
            }
        }
    }

    /// The probability that one traversal at `q` picks light `i` (0 if never).
    pub fn pmf(&self, q: &TreeQuery, i: usize, mut target: impl FnMut(usize) -> f32) -> f64 {
        let mut pmf = 1.0f64;
        let mut id = 0usize;
        loop {
            let node = &self.nodes[id];
            if node.light != u32::MAX {
                let p = target(node.light as usize);
                return if node.light as usize == i && p.is_finite() && p > 0.0 { pmf } else { 0.0 };
            }
            let (l, r) = (node.left as usize, node.right as usize);
            let il = self.importance(l, q, &mut |j| (target(j), ()));
            let ir = self.importance(r, q, &mut |j| (target(j), ()));
            if il.0 + ir.0 <= 0.0 || (il.0 + ir.0).is_nan() {
                return 0.0;
            }
            let p_left = il.0 / (il.0 + ir.0);
            let go_left = self.contains(l, i);
            pmf *= if go_left { p_left } else { 1.0 - p_left };
            id = if go_left { l } else { r };
        }
    }

    /// Whether the subtree at `id` holds light `i`.
    fn contains(&self, id: usize, i: usize) -> bool {
        let n = &self.nodes[id];
        if n.light != u32::MAX {
            return n.light as usize == i;
        }
        self.contains(n.left as usize, i) || self.contains(n.right as usize, i)
    }

    /// One traversal with the uniform `u`: (light, P(light), value), or `None`.
    fn traverse<T: Copy>(
        &self,
        q: &TreeQuery,
        mut u: f64,
        target: &mut impl FnMut(usize) -> (f32, T),
    ) -> Option<(usize, f64, T)> {
        let mut pmf = 1.0f64;
        let mut id = 0usize;
        let mut picked: Option<T> = None;
        loop {
            let node = self.nodes[id];
            if node.light != u32::MAX {
                let value = match picked {
                    Some(v) => v,
                    None => {
                        // a single-light tree: its own p̂ decides whether it contributes
                        let (p, v) = target(node.light as usize);
                        if !(p.is_finite() && p > 0.0) {
                            return None;
                        }
                        v
                    }
                };
                return Some((node.light as usize, pmf, value));
            }
            let (l, r) = (node.left as usize, node.right as usize);
            let (il, vl) = self.importance(l, q, target);
            let (ir, vr) = self.importance(r, q, target);
            let sum = il + ir;
            if sum <= 0.0 || sum.is_nan() {
                return None; // no light below can contribute
            }
            let p_left = il / sum;
            if u < p_left {
                (u, pmf, id, picked) = (u / p_left, pmf * p_left, l, vl);
            } else {
                (u, pmf, id, picked) =
                    (((u - p_left) / (1.0 - p_left)).min(1.0 - f64::EPSILON), pmf * (1.0 - p_left), r, vr);
            }
        }
    }

    /// A child's importance: the bound, and for a single light its value (0 where `p̂` is 0).
    fn importance<T: Copy>(
        &self,
        id: usize,
        q: &TreeQuery,
        target: &mut impl FnMut(usize) -> (f32, T),
    ) -> (f64, Option<T>) {
        let n = &self.nodes[id];
        if n.light != u32::MAX {
            // the same geometric bound as the inner nodes (one scale at every level: `p̂` itself
            // holds the BSDFs, which the bounds leave out), zero where the light cannot contribute
            let (p, v) = target(n.light as usize);
            return if p.is_finite() && p > 0.0 { (bound(n, q), Some(v)) } else { (0.0, None) };
        }
        (bound(n, q), None)
    }
}

/// `Σ_rgb(Φ_N·t)·min(b, c_x·c_y/d²)`: `min(b, c_x·c_y/d²)` bounds every light's `min(G, b)`.
fn bound(n: &Node, q: &TreeQuery) -> f64 {
    let (x, nx, b) = (q.x, q.nx, q.b);
    let r = n.radius;
    let dv = n.centre - x;
    let dc = dv.length();
    let gap = (n.lo - x).max(x - n.hi).max(Vec3::ZERO);
    let d2 = gap.length_squared() as f64;
    let b = if n.clamped { b as f64 } else { f64::INFINITY };
    let (cx, cy) = if dc <= r {
        (1.0, 1.0) // x inside the bounding sphere: every direction possible
    } else {
        let w = dv / dc;
        let (s_box, c_box) = (r / dc, (1.0 - (r / dc) * (r / dc)).max(0.0).sqrt());
        let cx = cos_gap(nx.dot(w).abs(), c_box, s_box);
        // the cone widens the box's angle: θ_box + θ_n
        let (ct, st) = (c_box * n.cos_n - s_box * n.sin_n, s_box * n.cos_n + c_box * n.sin_n);
        let cy = if ct <= 0.0 { 1.0 } else { cos_gap(n.axis.dot(w).abs(), ct, st) };
        (cx as f64, cy as f64)
    };
    // unclamped (b = ∞) with x in or at the box: the bound is infinite, useless for sampling; any
    // finite positive importance keeps the support, so the distance is floored at a tenth of the
    // node's radius (a single light's own distance is then its real one, to within that floor)
    let d2 = if b.is_finite() { d2 } else { d2.max(0.01 * (r as f64) * (r as f64)) };
    let g = if d2 > 0.0 { (cx * cy / d2).min(b) } else { b };
    n.power.dot(q.tint).max(0.0) as f64 * g
}

/// `cos(max(0, θ − α))` for `cos θ = c ∈ [0, 1]` and `α` given by its cos/sin, with slack.
#[inline]
fn cos_gap(c: f32, cos_a: f32, sin_a: f32) -> f32 {
    if c >= cos_a {
        return 1.0; // θ ≤ α
    }
    let s = (1.0 - c * c).max(0.0).sqrt();
    (c * cos_a + s * sin_a + 1e-4).min(1.0)
}

/// Builds the subtree over `ids` into `nodes`; returns its index.
fn build(lights: &[TreeLight], ids: &mut [u32], nodes: &mut Vec<Node>) -> u32 {
    let id = nodes.len() as u32;
    let (lo, hi) = ids.iter().fold((Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)), |(lo, hi), &i| {
        let p = lights[i as usize].p;
        (lo.min(p), hi.max(p))
    });
    let power = ids.iter().map(|&i| lights[i as usize].power).sum();
    let clamped = ids.iter().all(|&i| lights[i as usize].clamped);
    let (axis, cos_n, sin_n) = line_cone(lights, ids);
    let centre = 0.5 * (lo + hi);
    let radius = 0.5 * (hi - lo).length() * (1.0 + SLACK_R) + 1e-6 * (1.0 + centre.abs().max_element());
    let node = Node { lo, hi, centre, radius, axis, cos_n, sin_n, power, clamped, light: u32::MAX, left: 0, right: 0 };
    nodes.push(node);
    if ids.len() == 1 {
        nodes[id as usize].light = ids[0];
        return id;
    }
    // median split along the box's longest axis (ties by index: a pure function of the lights)
    let ext = hi - lo;
    let a = if ext.x >= ext.y && ext.x >= ext.z {
        0
    } else if ext.y >= ext.z {
        1
    } else {
        2
    };
    let mid = ids.len() / 2;
    ids.select_nth_unstable_by(mid, |&i, &j| {
        let (pi, pj) = (lights[i as usize].p[a], lights[j as usize].p[a]);
        pi.total_cmp(&pj).then(i.cmp(&j))
    });
    let (left_ids, right_ids) = ids.split_at_mut(mid);
    let left = build(lights, left_ids, nodes);
    let right = build(lights, right_ids, nodes);
    (nodes[id as usize].left, nodes[id as usize].right) = (left, right);
    id
}

/// The cone of normal *lines* of `ids`: axis, cos θ_n, sin θ_n (the whole sphere for omni
/// lights or degenerate normals).
fn line_cone(lights: &[TreeLight], ids: &[u32]) -> (Vec3, f32, f32) {
    const WHOLE: (Vec3, f32, f32) = (Vec3::Z, 0.0, 1.0);
    let first = lights[ids[0] as usize].n;
    let mut sum = Vec3::ZERO;
    for &i in ids {
        let l = &lights[i as usize];
        if l.omni || !l.n.is_finite() || l.n.length_squared() <= 0.0 {
            return WHOLE;
        }
        sum += if l.n.dot(first) < 0.0 { -l.n } else { l.n };
    }
    let Some(axis) = sum.try_normalize() else { return WHOLE };
    let cos_n = ids.iter().map(|&i| axis.dot(lights[i as usize].n.normalize()).abs()).fold(1.0f32, f32::min);
    // slack: a slightly wider cone keeps the bound conservative under rounding
    let cos_n = (cos_n - 1e-4).max(0.0);
    (axis, cos_n, (1.0 - cos_n * cos_n).max(0.0).sqrt())
}
