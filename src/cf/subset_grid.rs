//! A voxel grid that answers the cluster map's query for a subset of its clusters (`pt-cf`'s
//! guided clusters; `iws-cf`'s kept ones) without the map's kd-tree wherever it can: an
//! acceleration only, the image is the same bit for bit. The bounds and why they are exact:
//! `docs/methods/pt-cf.md`, "Estimator" (the voxel grid).
//!
//! [`ClusterMap::query`] takes the representative `q` nearest to `x` and accepts its cluster `c`
//! iff `|x − q| ≤ reach_c` (and a normal test). A cell `V` (centre `o`, half-diagonal `h`; `d_n`,
//! `d_g` the distances from `o` to the nearest representative of any cluster and of a subset
//! cluster; `R` the subset's largest reach) is one of:
//! - **empty**: `d_g − h > min(d_n + h, R)` (no `x ∈ V` can be accepted for a subset cluster);
//! - **one cluster** `c`: its candidates, the representatives within `min(d_n + h, R) + h` of `o`,
//!   all belong to `c` and `d_n + h ≤ reach_c` (only the normal test is left);
//! - **a scan** of its candidates, smallest `(dist², cluster)` first with the map's own squared
//!   distance (`spatial::dist2`): that is the map's nearest whenever the map could accept it;
//! - **ask the map**, with more than [`MAX_CANDIDATES`] candidates; or rather, once a query
//!   falls in it, its [`SUB`]³ subcells, each one of the four kinds above by the same bounds with
//!   its own centre and half-diagonal (built on the cell's first query, a pure function of the
//!   cell, so the answers do not depend on the threads; on `sms-sphere` the caustic's cells ask
//!   the map).
//!
//! A point whose normal fails the map's normal test for every subset cluster (a wall, when the
//! guided caustics lie on a floor) is rejected before its cell is looked at.
//!
//! A build stopped early ([`SubsetGrid::build_until`]: the time box's share of the integrator's
//! build) leaves one cell over the subset's box that asks the map: as exact, only slower.
//!
//! Invariants: exact ([`SubsetGrid::cluster_at`]`(x, n_x)` = `query(x, n_x)` when that is a
//! subset cluster, else `None`; distance bounds carry a relative slack for f32 rounding, and a
//! point in the slack band around the grid asks the map; `tests` compare with the map on random
//! points and near every representative), a pure function of the map and the subset, outside
//! the grid's box always `None` (the box is the union of the subset clusters' boxes, which
//! already bound where the map can accept them).

use super::cluster_map::{ClusterMap, MIN_NORMAL_COS};
use crate::math::Vec3;
use crate::spatial::{dist2, KdTree};
use rayon::prelude::*;
use std::sync::{Arc, OnceLock};

/// The most cells along the grid's longest axis (≤ 49³ cells, built in a few ms).
const MAX_CELLS_PER_AXIS: f32 = 48.0;
/// Relative slack on the distance bounds (f32 rounding of positions and distances).
const SLACK: f32 = 1e-3;
/// The most candidates a cell scans; a cell with more asks the map's kd-tree.
pub const MAX_CANDIDATES: usize = 64;

/// Cell codes: no subset cluster here; ask the map; `SCAN | k`: scan candidate list `k`;
/// `SPLIT | k`: the subcells `k`; any other value (< `SPLIT`): that one cluster.
const EMPTY: u32 = u32::MAX;
const TREE: u32 = u32::MAX - 1;
const SCAN: u32 = 1 << 31;
const SPLIT: u32 = 1 << 30;
/// Subcells per axis of a cell that would ask the map (built on its first query).
pub const SUB: usize = 3;

/// A grid over the boxes of a subset of kept clusters: per cell, what the cluster map can answer
/// there for a subset cluster.
#[derive(Clone, Debug, Default)]
pub struct SubsetGrid {
    lo: Vec3,
    inv_cell: f32,
    dims: [usize; 3],
    cells: Vec<u32>,
    /// Candidate list `k` is `candidates[scans[k].0..scans[k].1]`: (position, cluster).
    scans: Vec<(u32, u32)>,
    candidates: Vec<([f32; 3], u32)>,
    /// Per kept cluster: in the subset.
    in_subset: Vec<bool>,
    /// The subset clusters' mean normals.
    normals: Vec<Vec3>,
    /// Per `SPLIT` cell: its centre and its subcells, built on its first query.
    split: Vec<(Vec3, OnceLock<Subcells>)>,
    /// What a subcell's build reads (shared by the clones of the grid).
    reps: Option<Arc<Reps>>,
    /// A cell's edge and half-diagonal (the latter with its slack).
    cell: f32,
    half_diag: f32,
}

/// A cell level's candidate lists: `scans[k]` is the range of `candidates` (position, cluster)
/// that `SCAN | k` scans.
type Lists<'a> = (&'a [(u32, u32)], &'a [([f32; 3], u32)]);

/// The `SUB`³ subcells of one cell: their codes (never `SPLIT`; `SCAN | k` indexes `scans`).
#[derive(Clone, Debug)]
struct Subcells {
    codes: [u32; SUB * SUB * SUB],
    scans: Vec<(u32, u32)>,
    candidates: Vec<([f32; 3], u32)>,
}

/// The representatives a cell's answer is built from: all (with their clusters), as a tree, the
/// subset's as a tree, and the subset's largest reach.
#[derive(Debug)]
struct Reps {
    reps: Vec<([f32; 3], u32)>,
    all: KdTree,
    guided: KdTree,
    reach: f32,
}

/// The cells of a [`SubsetGrid`] by how they answer (`pt-cf`'s JSON report).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct GridKinds {
    /// All cells.
    pub cells: usize,
    /// Cells where no subset cluster can be accepted.
    pub empty: usize,
    /// Cells whose every point lies in one cluster (only its normal test is left).
    pub one: usize,
    /// Cells that scan a candidate list.
    pub scan: usize,
    /// Cells with more than [`MAX_CANDIDATES`] candidates (their subcells answer, built on
    /// their first query; the map's kd-tree where a subcell has more).
    pub tree: usize,
    /// Candidates stored over all scanned cells.
    pub candidates: usize,
}

/// A cell's answer while the grid is built.
enum Built {
    Code(u32),
    Scan(Vec<([f32; 3], u32)>),
}

/// What the cell builder reads: the map, its representatives and the subset.
struct Builder<'a> {
    map: &'a ClusterMap,
    r: &'a Reps,
    in_subset: &'a [bool],
}

/// Where a point falls: outside the grid (no subset cluster), in its slack band, or in a cell
/// (and its subcell, were the cell split).
enum Place {
    Outside,
    Band,
    Cell(usize, usize),
}

impl SubsetGrid {
    /// The grid of the kept clusters `subset` of `map` (an empty subset never contains a point).
    pub fn build(map: &ClusterMap, subset: &[usize]) -> Self {
        Self::build_until(map, subset, &|| false)
    }

    /// [`SubsetGrid::build`], its z slices built while `stop` is false; once it is true, the grid
    /// is one cell over the subset's box that asks the map (exact, as every cell is).
    pub fn build_until(map: &ClusterMap, subset: &[usize], stop: &(dyn Fn() -> bool + Sync)) -> Self {
        let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
        for &c in subset {
            if let Some((a, b)) = map.bounds(c) {
                (lo, hi) = (lo.min(a), hi.max(b));
            }
        }
        let mut in_subset = vec![false; map.n_clusters()];
        for &c in subset {
            if let Some(f) = in_subset.get_mut(c) {
                *f = true;
            }
        }
        let reps: Vec<([f32; 3], u32)> = map.representatives().map(|(c, p)| (p, c)).collect();
        let guided: Vec<[f32; 3]> = reps.iter().filter(|r| in_subset[r.1 as usize]).map(|r| r.0).collect();
        let extent = hi - lo;
        if guided.is_empty() || !extent.is_finite() {
            return SubsetGrid::default();
        }
        let cell = (extent.max_element() / MAX_CELLS_PER_AXIS).max(1e-6);
        let dims = (extent / cell).to_array().map(|e| (e.ceil() as usize).clamp(1, MAX_CELLS_PER_AXIS as usize + 1));
        let reach = subset.iter().map(|&c| map.reach(c)).fold(0.0f32, f32::max);
        let all = KdTree::build(&reps.iter().map(|r| r.0).collect::<Vec<_>>());
        let r = Arc::new(Reps { reps, all, guided: KdTree::build(&guided), reach });
        let b = Builder { map, r: &r, in_subset: &in_subset };
        let half_diag = 0.5 * cell * 3f32.sqrt() * (1.0 + SLACK);
        // one z slice per task: the answers are a pure function of the cell, whatever the threads
        let slices: Vec<Option<Vec<Built>>> = (0..dims[2])
            .into_par_iter()
            .map(|k| {
                if stop() {
                    return None;
                }
                let mut out = Vec::new();
                let slice = (0..dims[1]).flat_map(move |j| (0..dims[0]).map(move |i| (i, j)));
                Some(
                    slice
                        .map(|(i, j)| {
                            let o = lo + (Vec3::new(i as f32, j as f32, k as f32) + 0.5) * cell;
                            b.cell(o, half_diag, &mut out)
                        })
                        .collect(),
                )
            })
            .collect();
        if slices.iter().any(Option::is_none) {
            // one cell that asks the map, over a cube holding the subset's box
            let cell = extent.max_element().max(1e-6);
            let normals = subset.iter().map(|&c| map.normal(c)).collect();
            let cells = vec![TREE];
            return SubsetGrid { lo, inv_cell: 1.0 / cell, dims: [1; 3], cells, in_subset, normals, ..Self::default() };
        }
        let built: Vec<Built> = slices.into_iter().flatten().flatten().collect();
        let (mut cells, mut scans, mut candidates) = (Vec::with_capacity(built.len()), Vec::new(), Vec::new());
        let mut split = Vec::new();
        for (idx, a) in built.into_iter().enumerate() {
            cells.push(match a {
                Built::Code(TREE) => {
                    let (i, j, k) = (idx % dims[0], idx / dims[0] % dims[1], idx / (dims[0] * dims[1]));
                    split.push((lo + (Vec3::new(i as f32, j as f32, k as f32) + 0.5) * cell, OnceLock::new()));
                    SPLIT | (split.len() as u32 - 1)
                }
                Built::Code(c) => c,
                Built::Scan(list) => push_scan(&mut scans, &mut candidates, list),
            });
        }
        let normals = subset.iter().map(|&c| map.normal(c)).collect();
        let reps = Some(r);
        SubsetGrid {
            lo,
            inv_cell: 1.0 / cell,
            dims,
            cells,
            scans,
            candidates,
            in_subset,
            normals,
            split,
            reps,
            cell,
            half_diag,
        }
    }

    /// The subcells of `SPLIT` cell `k` (built now on its first query).
    #[cold]
    fn build_subcells(&self, map: &ClusterMap, k: usize) -> Subcells {
        let mut sub = Subcells { codes: [TREE; SUB * SUB * SUB], scans: Vec::new(), candidates: Vec::new() };
        let (Some(r), Some((o, _))) = (&self.reps, self.split.get(k)) else { return sub };
        let b = Builder { map, r, in_subset: &self.in_subset };
        let (edge, h) = (self.cell / SUB as f32, self.half_diag / SUB as f32);
        let mut out = Vec::new();
        for (s, code) in sub.codes.iter_mut().enumerate() {
            let v = Vec3::new((s % SUB) as f32, (s / SUB % SUB) as f32, (s / (SUB * SUB)) as f32);
            let c = *o - 0.5 * self.cell + (v + 0.5) * edge;
            *code = match b.cell(c, h, &mut out) {
                Built::Code(c) => c,
                Built::Scan(list) => push_scan(&mut sub.scans, &mut sub.candidates, list),
            };
        }
        sub
    }

    /// Where `x` falls, after the normal test (`Outside` when no subset cluster can accept `n_x`).
    #[inline]
    fn place(&self, x: Vec3, n_x: Vec3) -> Place {
        if self.cells.is_empty() || !self.normals.iter().any(|n| n_x.dot(*n) >= MIN_NORMAL_COS - SLACK) {
            return Place::Outside;
        }
        let u = (x - self.lo) * self.inv_cell;
        let (mut idx, mut sub, mut band) = ([0usize; 3], [0usize; 3], false);
        for a in 0..3 {
            let n = self.dims[a] as f32;
            // outside the box (or NaN): no subset cluster's box holds x
            if !(u[a] >= -SLACK * n && u[a] <= n * (1.0 + SLACK)) {
                return Place::Outside;
            }
            band |= !(u[a] >= 0.0 && u[a] < n);
            idx[a] = (u[a].max(0.0) as usize).min(self.dims[a] - 1);
            // the subcell of a split cell (its bounds carry the slack that covers this rounding)
            sub[a] = (((u[a] - idx[a] as f32) * SUB as f32).max(0.0) as usize).min(SUB - 1);
        }
        if band {
            return Place::Band;
        }
        let cell = (idx[2] * self.dims[1] + idx[1]) * self.dims[0] + idx[0];
        Place::Cell(cell, (sub[2] * SUB + sub[1]) * SUB + sub[0])
    }

    /// False when `ClusterMap::query(x, n_x)` cannot return a cluster of the subset.
    #[inline]
    pub fn may_contain(&self, x: Vec3, n_x: Vec3) -> bool {
        match self.place(x, n_x) {
            Place::Outside => false,
            Place::Band => true,
            Place::Cell(i, _) => self.cells[i] != EMPTY,
        }
    }

    /// `map.query(x, n_x)` when that is a subset cluster, else `None` (`map` is the map the grid
    /// was built from): the cell's (or its subcell's) answer, a scan of its candidates, or the
    /// map's kd-tree.
    #[inline]
    pub fn cluster_at(&self, map: &ClusterMap, x: Vec3, n_x: Vec3) -> Option<usize> {
        let (code, sub) = match self.place(x, n_x) {
            Place::Outside => return None,
            Place::Band => (TREE, 0),
            Place::Cell(i, sub) => (self.cells[i], sub),
        };
        if code != EMPTY && code != TREE && code & (SCAN | SPLIT) == SPLIT {
            let k = (code & !SPLIT) as usize;
            let s = self.split[k].1.get_or_init(|| self.build_subcells(map, k));
            return self.answer(map, s.codes[sub], (&s.scans, &s.candidates), (x, n_x));
        }
        self.answer(map, code, (&self.scans, &self.candidates), (x, n_x))
    }

    /// The answer at `(x, n_x)` of a cell (or subcell) of code `code` (never `SPLIT`), whose
    /// candidate lists are `lists`.
    #[inline(always)]
    fn answer(&self, map: &ClusterMap, code: u32, (scans, candidates): Lists, (x, n_x): (Vec3, Vec3)) -> Option<usize> {
        let (c, d2) = match code {
            EMPTY => return None,
            TREE => return map.query(x, n_x).filter(|&c| self.in_subset[c]),
            s if s & SCAN != 0 => {
                let (a, b) = scans[(s & !SCAN) as usize];
                nearest(&candidates[a as usize..b as usize], x)?
            }
            // every x of the cell is within reach of its nearest representative, of cluster c
            c => return (n_x.dot(map.normal(c as usize)) >= MIN_NORMAL_COS).then_some(c as usize),
        };
        (self.in_subset[c] && map.accepts(c, d2, n_x)).then_some(c)
    }

    /// How many cells answer in each way, and the candidates stored (reported).
    pub fn kinds(&self) -> GridKinds {
        let mut k = GridKinds { cells: self.cells.len(), candidates: self.candidates.len(), ..GridKinds::default() };
        for &c in &self.cells {
            match c {
                EMPTY => k.empty += 1,
                TREE => k.tree += 1,
                c if c & (SCAN | SPLIT) == SPLIT => k.tree += 1,
                c if c & SCAN != 0 => k.scan += 1,
                _ => k.one += 1,
            }
        }
        k
    }

    /// The share of the grid's cells that may contain a subset cluster (reported).
    pub fn fill(&self) -> f64 {
        if self.cells.is_empty() {
            return 0.0;
        }
        self.cells.iter().filter(|&&c| c != EMPTY).count() as f64 / self.cells.len() as f64
    }
}

/// Appends candidate list `list` to `(scans, candidates)`; its code.
fn push_scan(scans: &mut Vec<(u32, u32)>, candidates: &mut Vec<([f32; 3], u32)>, list: Vec<([f32; 3], u32)>) -> u32 {
    let s = candidates.len() as u32;
    candidates.extend(list);
    scans.push((s, candidates.len() as u32));
    SCAN | (scans.len() as u32 - 1)
}

/// The smallest `(dist², cluster)` of `list` from `x` (the kd-tree's order), as (cluster, dist²).
#[inline]
fn nearest(list: &[([f32; 3], u32)], x: Vec3) -> Option<(usize, f32)> {
    let x = x.to_array();
    let mut best: Option<(u32, f32)> = None;
    for &(p, c) in list {
        let d2 = dist2(&p, &x);
        let better = match best {
            None => d2 <= f32::INFINITY, // as the tree: a NaN distance is never a nearest
            Some((bc, bd)) => d2 < bd || (d2 == bd && c < bc),
        };
        if better {
            best = Some((c, d2));
        }
    }
    best.map(|(c, d2)| (c as usize, d2))
}

/// Distance bound `d` of a cell with half-diagonal `h`, grown by the slack that covers f32
/// rounding (every bound of `Builder::cell` goes through it).
#[inline]
fn padded(d: f32, h: f32) -> f32 {
    d * (1.0 + SLACK) + SLACK * h
}

/// Representatives fetched per cell before pruning (a cell with more asks the tree).
const FETCH: usize = 4 * MAX_CANDIDATES;
/// The nearest representatives to a cell's centre tried as dominators of the others.
const DOMINATORS: usize = 4;

/// The 8 corners of the cube of centre `o` and half-edge `a`, in f64.
fn corners(o: Vec3, a: f32) -> [[f64; 3]; 8] {
    std::array::from_fn(|k| {
        let s = |b: usize| if k >> b & 1 == 1 { 1.0 } else { -1.0 };
        [0, 1, 2].map(|t| f64::from(o[t]) + s(t) * f64::from(a))
    })
}

/// True when every point of the box with `corners` is nearer to `d` than to `r` by a relative
/// margin that f32 distances cannot erase (the set nearer to `d` is a half-space, so the corners
/// decide).
fn dominates(d: &[f32; 3], r: &[f32; 3], corners: &[[f64; 3]; 8]) -> bool {
    corners.iter().all(|c| {
        let sq = |p: &[f32; 3]| (0..3).map(|t| (c[t] - f64::from(p[t])).powi(2)).sum::<f64>();
        let (dr, dd) = (sq(r), sq(d));
        dr - dd > 1e-4 * dr + 1e-12
    })
}

impl Builder<'_> {
    /// The answer of the cell with centre `o` and half-diagonal `h` (the module header).
    fn cell(&self, o: Vec3, h: f32, out: &mut Vec<(f32, u32)>) -> Built {
        let (Some((_, dn2)), Some((_, dg2))) =
            (self.map.nearest_representative(o), self.r.guided.nearest(o.to_array()))
        else {
            return Built::Code(TREE);
        };
        let (dn, dg) = (dn2.sqrt(), dg2.sqrt());
        if dg - h > padded((dn + h).min(self.r.reach), h) {
            return Built::Code(EMPTY);
        }
        let rc = padded((dn + h).min(self.r.reach) + h, h);
        self.r.all.k_nearest_within(o.to_array(), FETCH, rc * rc, out);
        if out.len() == FETCH {
            return Built::Code(TREE);
        }
        // a representative that one of the few nearest to o beats all over the cell is never nearest
        let corners = corners(o, h / 3f32.sqrt());
        let near: Vec<[f32; 3]> = out.iter().take(DOMINATORS).map(|&(_, i)| self.r.reps[i as usize].0).collect();
        let list: Vec<([f32; 3], u32)> = out
            .iter()
            .map(|&(_, i)| self.r.reps[i as usize])
            .filter(|r| !near.iter().any(|d| *d != r.0 && dominates(d, &r.0, &corners)))
            .collect();
        if list.len() > MAX_CANDIDATES {
            return Built::Code(TREE);
        }
        if !list.iter().any(|r| self.in_subset[r.1 as usize]) {
            return Built::Code(EMPTY);
        }
        let c0 = list[0].1;
        let one = list.iter().all(|r| r.1 == c0);
        if one && padded(dn + h, h) <= self.map.reach(c0 as usize) && c0 < SPLIT {
            return Built::Code(c0);
        }
        Built::Scan(list)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cf::caustic_point::CausticPoint;
    use crate::cf::cluster::cluster_points;
    use crate::sampling::rng::{stream, Rng};

    /// Caustic points in blobs on a floor and a wall, spread so that the reach stays small.
    fn points(n: usize) -> Vec<CausticPoint> {
        let mut r = Rng::keyed(3, stream::MISC, 0, 0);
        (0..n)
            .map(|i| {
                let (a, b) = (r.next_f32(), r.next_f32());
                let blob = (i % 6) as f32;
                if i % 2 == 0 {
                    CausticPoint::new(
                        Vec3::new(blob + 0.3 * a, 0.0, 0.3 * b),
                        Vec3::Y,
                        Vec3::Y,
                        Vec3::splat(1.0 + blob),
                    )
                } else {
                    CausticPoint::new(Vec3::new(0.0, 0.2 + 0.3 * a, blob + 0.3 * b), Vec3::X, Vec3::X, Vec3::splat(1.0))
                }
            })
            .collect()
    }

    #[test]
    fn grid_never_rejects_a_point_the_map_accepts_for_the_subset() {
        let pts = points(12_000);
        let cl = cluster_points(&pts, 24, 5);
        let map = ClusterMap::build(&pts, &cl, 63, 32, 0.05);
        let n = map.n_clusters();
        assert!(n >= 12, "{n} clusters");
        let mut r = Rng::keyed(4, stream::MISC, 1, 0);
        for subset in [vec![0usize], vec![1, 5, 7], (0..n).step_by(3).collect::<Vec<_>>(), (0..n).collect()] {
            let grid = SubsetGrid::build(&map, &subset);
            let (mut inside, mut rejected) = (0, 0);
            for t in 0..200_000 {
                // points near the caustic blobs (most) and anywhere in a larger box
                let s = if t % 4 == 0 { 8.0 } else { 6.5 };
                let x = Vec3::new(s * r.next_f32() - 0.5, 0.6 * r.next_f32() - 0.1, s * r.next_f32() - 0.5);
                let x = if t % 2 == 0 { Vec3::new(x.x, 0.0, x.z) } else { x };
                for nx in [Vec3::Y, Vec3::X, Vec3::new(0.6, 0.8, 0.0)] {
                    let may = grid.may_contain(x, nx);
                    rejected += usize::from(!may);
                    if let Some(c) = map.query(x, nx) {
                        if subset.contains(&c) {
                            inside += 1;
                            assert!(
                                may,
                                "subset {subset:?}: x = {x} accepted for cluster {c} but rejected by the grid"
                            );
                        }
                    }
                }
            }
            assert!(inside > 100, "subset {subset:?}: only {inside} points inside");
            // the grid must be worth its build: a single cluster leaves most points out
            if subset.len() == 1 {
                assert!(
                    rejected > 300_000,
                    "subset {subset:?}: only {rejected} of 600k rejected (fill {})",
                    grid.fill()
                );
            }
        }
        assert!(!SubsetGrid::build(&map, &[]).may_contain(Vec3::ZERO, Vec3::Y));
    }

    /// `cluster_at` must be `query` restricted to the subset, exactly: on random points, on points
    /// within a few cell widths of every representative (where scans and one-cluster cells
    /// answer), on the grid's slack band and for non-finite input. Every kind of cell must occur.
    #[test]
    fn cluster_at_is_the_maps_query_restricted_to_the_subset() {
        let pts = points(12_000);
        let cl = cluster_points(&pts, 24, 5);
        let map = ClusterMap::build(&pts, &cl, 63, 32, 0.05);
        let n = map.n_clusters();
        let mut r = Rng::keyed(6, stream::MISC, 2, 0);
        let reps: Vec<Vec3> = map.representatives().map(|(_, p)| Vec3::from_array(p)).collect();
        let mut total = GridKinds::default();
        for subset in [vec![0usize], vec![1, 5, 7], (0..n).step_by(3).collect::<Vec<_>>(), (0..n).collect()] {
            let grid = SubsetGrid::build(&map, &subset);
            let k = grid.kinds();
            assert_eq!(k.empty + k.one + k.scan + k.tree, k.cells);
            (total.one, total.scan, total.empty) = (total.one + k.one, total.scan + k.scan, total.empty + k.empty);
            let expect = |x: Vec3, nx: Vec3| map.query(x, nx).filter(|c| subset.contains(c));
            let mut accepted = 0;
            for t in 0..300_000 {
                let x = if t % 3 == 0 {
                    Vec3::new(8.0 * r.next_f32() - 0.5, 0.6 * r.next_f32() - 0.1, 8.0 * r.next_f32() - 0.5)
                } else {
                    // near a representative, on its surface half the time
                    let q = reps[t % reps.len()];
                    let d = Vec3::new(r.next_f32() - 0.5, r.next_f32() - 0.5, r.next_f32() - 0.5) * 0.3;
                    let on = |a: f32, v: f32| if t % 2 == 0 && a == 0.0 { 0.0 } else { v };
                    let d = Vec3::new(on(q.x, d.x), on(q.y, d.y), d.z);
                    q + d * r.next_f32()
                };
                let nx = [Vec3::Y, Vec3::X, Vec3::new(0.6, 0.8, 0.0)][t % 3];
                let got = grid.cluster_at(&map, x, nx);
                assert_eq!(got, expect(x, nx), "subset {subset:?}: x = {x}, n = {nx}");
                accepted += usize::from(got.is_some());
            }
            assert!(accepted > 1000, "subset {subset:?}: only {accepted} accepted");
            for x in [Vec3::NAN, Vec3::INFINITY, grid.lo - Vec3::splat(1e-7), grid.lo] {
                assert_eq!(grid.cluster_at(&map, x, Vec3::Y), expect(x, Vec3::Y), "x = {x}");
            }
        }
        assert!(total.one > 0 && total.scan > 0 && total.empty > 0, "{total:?}");
    }

    /// Cells with more than `MAX_CANDIDATES` candidates (many clusters, a long reach) answer by
    /// their subcells, built on their first query: still `query` restricted to the subset,
    /// exactly, and most subcells answer without the tree.
    #[test]
    fn split_cells_are_the_maps_query_too() {
        let pts = points(12_000);
        let cl = cluster_points(&pts, 64, 5);
        let map = ClusterMap::build(&pts, &cl, 63, 32, 0.5);
        let n = map.n_clusters();
        let mut r = Rng::keyed(8, stream::MISC, 4, 0);
        let reps: Vec<Vec3> = map.representatives().map(|(_, p)| Vec3::from_array(p)).collect();
        for subset in [(0..n).step_by(2).collect::<Vec<_>>(), (0..n).collect()] {
            let grid = SubsetGrid::build(&map, &subset);
            assert!(!grid.split.is_empty(), "subset {subset:?}: no cell asks the map ({:?})", grid.kinds());
            let mut accepted = 0;
            for t in 0..200_000 {
                let d = Vec3::new(r.next_f32() - 0.5, r.next_f32() - 0.5, r.next_f32() - 0.5) * 0.3;
                let q = reps[t % reps.len()];
                let x = if t % 2 == 0 { Vec3::new(q.x + d.x, q.y, q.z + d.z) } else { q + d * r.next_f32() };
                let nx = [Vec3::Y, Vec3::X, Vec3::new(0.6, 0.8, 0.0)][t % 3];
                let got = grid.cluster_at(&map, x, nx);
                assert_eq!(got, map.query(x, nx).filter(|c| subset.contains(c)), "subset {subset:?}: x = {x}");
                accepted += usize::from(got.is_some());
            }
            assert!(accepted > 1000, "subset {subset:?}: only {accepted} accepted");
            let built: Vec<&Subcells> = grid.split.iter().filter_map(|s| s.1.get()).collect();
            let codes = built.iter().flat_map(|s| s.codes.iter());
            let answered = codes.clone().filter(|&&c| c != TREE).count();
            assert!(!built.is_empty() && 2 * answered > codes.count(), "most subcells ask the map");
        }
    }

    /// A build stopped at once (a time box's end) leaves one cell that asks the map: still
    /// `query` restricted to the subset, exactly.
    #[test]
    fn a_stopped_build_is_exact_too() {
        let pts = points(12_000);
        let cl = cluster_points(&pts, 24, 5);
        let map = ClusterMap::build(&pts, &cl, 63, 32, 0.05);
        let n = map.n_clusters();
        let mut r = Rng::keyed(7, stream::MISC, 3, 0);
        let reps: Vec<Vec3> = map.representatives().map(|(_, p)| Vec3::from_array(p)).collect();
        for subset in [vec![0usize], vec![1, 5, 7], (0..n).collect::<Vec<_>>()] {
            let grid = SubsetGrid::build_until(&map, &subset, &|| true);
            assert_eq!((grid.kinds().cells, grid.kinds().tree), (1, 1), "subset {subset:?}");
            let mut accepted = 0;
            for t in 0..100_000 {
                // anywhere in a box larger than the caustics (a third), near a representative (the rest)
                let x = if t % 3 == 0 {
                    Vec3::new(8.0 * r.next_f32() - 0.5, 0.6 * r.next_f32() - 0.1, 8.0 * r.next_f32() - 0.5)
                } else {
                    let d = Vec3::new(r.next_f32() - 0.5, r.next_f32() - 0.5, r.next_f32() - 0.5) * 0.3;
                    reps[t % reps.len()] + d * r.next_f32()
                };
                let nx = [Vec3::Y, Vec3::X, Vec3::new(0.6, 0.8, 0.0)][(t / 3) % 3];
                let got = grid.cluster_at(&map, x, nx);
                assert_eq!(got, map.query(x, nx).filter(|c| subset.contains(c)), "subset {subset:?}: x = {x}");
                accepted += usize::from(got.is_some());
            }
            assert!(accepted > 100, "subset {subset:?}: only {accepted} accepted");
        }
    }
}
