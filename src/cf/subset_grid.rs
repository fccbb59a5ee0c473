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
#[path = "subset_grid_tests.rs"]
mod tests;
