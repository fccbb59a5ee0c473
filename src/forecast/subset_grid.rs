//! Where the cluster map cannot return one of a few clusters: a voxel grid that lets `pt-cf` skip
//! the cluster map's kd-tree at the vertices that lie in no guided cluster (issue #12; an
//! acceleration only, the image is the same bit for bit).
//!
//! [`ClusterMap::query`] takes the representative `q` nearest to `x` and accepts its cluster `c`
//! iff `|x − q| ≤ reach_c` (and a normal test). For a cell `V` of the grid with centre `o` and
//! half-diagonal `h`, let `d_n` be the distance from `o` to the nearest representative of any
//! cluster and `d_g` the distance from `o` to the nearest representative of a subset cluster.
//! For every `x ∈ V` the nearest representative is at most `d_n + h` away, and every subset
//! representative at least `d_g − h`; so if `d_g − h > min(d_n + h, R)`, `R` the largest reach of
//! the subset, no `x ∈ V` can be accepted for a subset cluster, and the cell is marked empty.
//! The map's normal test gives a second exact rejection: a point whose normal `n_x` has
//! `n_x·n̄_c < 0.5` for every subset cluster `c` (a wall, when the guided caustics lie on a floor).
//!
//! Invariants: conservative (`may_contain(x)` is true wherever `query(x, ·)` can return a subset
//! cluster, with slack for rounding; `tests` check it against the map on random points), a pure
//! function of the map and the subset, outside the grid's box always false (the box is the union
//! of the subset clusters' boxes, which already bound where the map can accept them).

use super::cluster_map::{ClusterMap, MIN_NORMAL_COS};
use crate::math::Vec3;
use crate::spatial::KdTree;
use rayon::prelude::*;

/// The most cells along the grid's longest axis (≤ 48³ cells, built in a few ms).
const MAX_CELLS_PER_AXIS: f32 = 48.0;
/// Relative slack on the distance bounds (f32 rounding of positions and distances).
const SLACK: f32 = 1e-3;

/// A grid over the boxes of a subset of kept clusters: one flag per cell, "a subset cluster may
/// be accepted somewhere in this cell".
#[derive(Clone, Debug, Default)]
pub struct SubsetGrid {
    lo: Vec3,
    inv_cell: f32,
    dims: [usize; 3],
    maybe: Vec<bool>,
    /// The subset clusters' mean normals.
    normals: Vec<Vec3>,
}

impl SubsetGrid {
    /// The grid of the kept clusters `subset` of `map` (an empty subset never contains a point).
    pub fn build(map: &ClusterMap, subset: &[usize]) -> Self {
        let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
        for &c in subset {
            if let Some((a, b)) = map.bounds(c) {
                (lo, hi) = (lo.min(a), hi.max(b));
            }
        }
        let mut reps = Vec::new();
        for (c, p) in map.representatives() {
            if subset.contains(&(c as usize)) {
                reps.push(p);
            }
        }
        let extent = hi - lo;
        if reps.is_empty() || !extent.is_finite() {
            return SubsetGrid::default();
        }
        let cell = (extent.max_element() / MAX_CELLS_PER_AXIS).max(1e-6);
        let dims = (extent / cell).to_array().map(|e| (e.ceil() as usize).clamp(1, MAX_CELLS_PER_AXIS as usize + 1));
        let reach = subset.iter().map(|&c| map.reach(c)).fold(0.0f32, f32::max);
        let guided = KdTree::build(&reps);
        let half_diag = 0.5 * cell * 3f32.sqrt() * (1.0 + SLACK);
        // one z slice per task: the flags are a pure function of the cell, whatever the threads
        let maybe: Vec<bool> = (0..dims[2])
            .into_par_iter()
            .flat_map_iter(|k| {
                let (map, guided) = (map, &guided);
                (0..dims[1]).flat_map(move |j| {
                    (0..dims[0]).map(move |i| {
                        let o = lo + (Vec3::new(i as f32, j as f32, k as f32) + 0.5) * cell;
                        cell_may_contain(map, guided, o, half_diag, reach)
                    })
                })
            })
            .collect();
        let normals = subset.iter().map(|&c| map.normal(c)).collect();
        SubsetGrid { lo, inv_cell: 1.0 / cell, dims, maybe, normals }
    }

    /// False when `ClusterMap::query(x, n_x)` cannot return a cluster of the subset.
    #[inline]
    pub fn may_contain(&self, x: Vec3, n_x: Vec3) -> bool {
        if self.maybe.is_empty() || !self.normals.iter().any(|n| n_x.dot(*n) >= MIN_NORMAL_COS - SLACK) {
            return false;
        }
        let u = (x - self.lo) * self.inv_cell;
        let mut idx = [0usize; 3];
        for a in 0..3 {
            let n = self.dims[a] as f32;
            // outside the box (or NaN): no subset cluster's box holds x
            if !(u[a] >= -SLACK * n && u[a] <= n * (1.0 + SLACK)) {
                return false;
            }
            idx[a] = (u[a].max(0.0) as usize).min(self.dims[a] - 1);
        }
        self.maybe[(idx[2] * self.dims[1] + idx[1]) * self.dims[0] + idx[0]]
    }

    /// The share of the grid's cells that may contain a subset cluster (reported).
    pub fn fill(&self) -> f64 {
        if self.maybe.is_empty() {
            return 0.0;
        }
        self.maybe.iter().filter(|&&m| m).count() as f64 / self.maybe.len() as f64
    }
}

/// The cell test of the module header: `d_g − h ≤ min(d_n + h, R)`, with slack.
fn cell_may_contain(map: &ClusterMap, guided: &KdTree, o: Vec3, h: f32, reach: f32) -> bool {
    let (Some((_, dn2)), Some((_, dg2))) = (map.nearest_representative(o), guided.nearest(o.to_array())) else {
        return true;
    };
    let (dn, dg) = (dn2.sqrt(), dg2.sqrt());
    dg - h <= (dn + h).min(reach) * (1.0 + SLACK) + SLACK * h
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::forecast::caustic_point::CausticPoint;
    use crate::forecast::cluster::cluster_points;
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
}
