//! The CF cluster map ([BAJ08 §3.2] "Caustic points near centroids of the remaining clusters … are added
//! to a kd-tree called the cluster map"; spec §3 "Cluster map").
//!
//! For each kept cluster `c` (rank ≤ R_max, the prefix `clustering.clusters[..n_kept]`) the map stores
//! its `m` members nearest the 6-D feature centroid, labelled `c`. A query at `(x, n_x)` takes the
//! nearest representative `q` and accepts its cluster iff `|x − q| ≤ R_c + r` and `n_x·n̄_c ≥ 0.5`.
//!
//! Invariants: only efficiency depends on this structure, never correctness (a `None` means cosine
//! sampling). Returned indices are kept-cluster indices, equal to indices into `clustering.clusters`.
//! Deterministic; serializable with bitcode; an empty map answers `None`.

// `!(x > 0.0)`-style tests are deliberate: they are true for NaN (degenerate input is rejected).
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::caustic_point::CausticPoint;
use super::cluster::Clustering;
use crate::math::Vec3;
use crate::spatial::KdTree;

/// Default number of representatives per cluster (spec §5).
pub const DEFAULT_REPRESENTATIVES: usize = 32;
/// Minimum `n_x·n̄_c` for a valid cluster.
pub const MIN_NORMAL_COS: f32 = 0.5;

/// Cluster-membership lookup structure.
#[derive(Clone, Debug, Default, PartialEq, bitcode::Encode, bitcode::Decode)]
pub struct ClusterMap {
    /// Representatives, item id = kept-cluster index.
    tree: KdTree,
    /// Per kept cluster: acceptance distance R_c + r.
    reach: Vec<f32>,
    /// Per kept cluster: mean normal n̄_c.
    normals: Vec<[f32; 3]>,
    /// Per kept cluster: the box of its representatives grown by its reach (no point outside
    /// it can be accepted for that cluster).
    boxes: Vec<([f32; 3], [f32; 3])>,
}

impl ClusterMap {
    /// Builds the map over the clusters with rank ≤ `max_rank`, `m` representatives each, search
    /// radius `r` (added to R_c in the validity test).
    pub fn build(points: &[CausticPoint], clustering: &Clustering, max_rank: u32, m: usize, r: f32) -> Self {
        let kept = clustering.kept(max_rank);
        let r = if r.is_finite() { r.max(0.0) } else { 0.0 };
        let (mut pos, mut ids) = (Vec::new(), Vec::new());
        let mut boxes = Vec::with_capacity(kept.len());
        let mut scratch: Vec<(f32, u32)> = Vec::new();
        for (ci, c) in kept.iter().enumerate() {
            // m members nearest the 6-D centroid (ties by index, so deterministic).
            scratch.clear();
            scratch.extend(c.members.iter().filter_map(|&i| {
                let p = points.get(i as usize)?;
                let f = clustering.feature(p);
                let d: f32 = (0..6).map(|t| (f[t] - c.feature[t]).powi(2)).sum();
                Some((d, i))
            }));
            if m < scratch.len() {
                scratch.select_nth_unstable_by(m, |a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
                scratch.truncate(m);
            }
            let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
            for &(_, i) in &scratch {
                let p = points[i as usize].p;
                (lo, hi) = (lo.min(Vec3::from_array(p)), hi.max(Vec3::from_array(p)));
                pos.push(p);
                ids.push(ci as u32);
            }
            let reach = Vec3::splat(c.radius + r);
            boxes.push(((lo - reach).to_array(), (hi + reach).to_array()));
        }
        ClusterMap {
            tree: KdTree::build_with_ids(pos, ids),
            reach: kept.iter().map(|c| c.radius + r).collect(),
            normals: kept.iter().map(|c| c.normal).collect(),
            boxes,
        }
    }

    /// False when `query(x, ·)` cannot return cluster `c` (x outside the box of `c`'s
    /// representatives grown by its reach): an O(1) test that lets a caller interested in a few
    /// clusters skip the tree.
    #[inline]
    pub fn may_accept(&self, c: usize, x: Vec3) -> bool {
        self.boxes
            .get(c)
            .is_some_and(|(lo, hi)| x.cmpge(Vec3::from_array(*lo)).all() && x.cmple(Vec3::from_array(*hi)).all())
    }

    /// The box of cluster `c`'s representatives grown by its reach (`may_accept`'s box).
    pub fn bounds(&self, c: usize) -> Option<(Vec3, Vec3)> {
        self.boxes.get(c).map(|(lo, hi)| (Vec3::from_array(*lo), Vec3::from_array(*hi)))
    }

    /// Cluster `c`'s acceptance distance `R_c + r` (0 for an unknown cluster).
    pub fn reach(&self, c: usize) -> f32 {
        self.reach.get(c).copied().unwrap_or(0.0)
    }

    /// Cluster `c`'s mean normal `n̄_c` (zero for an unknown cluster).
    pub fn normal(&self, c: usize) -> Vec3 {
        self.normals.get(c).map_or(Vec3::ZERO, |n| Vec3::from_array(*n))
    }

    /// Every representative as `(kept-cluster index, position)`.
    pub fn representatives(&self) -> impl Iterator<Item = (u32, [f32; 3])> + '_ {
        self.tree.items()
    }

    /// The representative nearest to `x` (any cluster) as `(cluster, dist²)`, as `query` finds it.
    pub fn nearest_representative(&self, x: Vec3) -> Option<(u32, f32)> {
        self.tree.nearest(x.to_array())
    }

    /// Number of kept clusters in the map.
    pub fn n_clusters(&self) -> usize {
        self.reach.len()
    }

    /// Number of stored representatives.
    pub fn n_representatives(&self) -> usize {
        self.tree.len()
    }

    /// The kept cluster valid at `x` with (geometric, viewer-side) normal `n_x`, if any.
    pub fn query(&self, x: Vec3, n_x: Vec3) -> Option<usize> {
        let (c, d2) = self.tree.nearest(x.to_array())?;
        self.accepts(c as usize, d2, n_x).then_some(c as usize)
    }

    /// The validity test of [`ClusterMap::query`] for a nearest representative of cluster `c` at
    /// squared distance `d2` (false for an unknown cluster).
    #[inline]
    pub fn accepts(&self, c: usize, d2: f32, n_x: Vec3) -> bool {
        let (Some(&reach), Some(n)) = (self.reach.get(c), self.normals.get(c)) else { return false };
        // spec §3: valid iff |x − q| ≤ R_c + r and n_x·n̄_c ≥ 0.5.
        d2 <= reach * reach && n_x.dot(Vec3::from_array(*n)) >= MIN_NORMAL_COS
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cf::cluster::cluster_points;
    use crate::sampling::rng::{stream, Rng};

    fn scene(n: usize) -> Vec<CausticPoint> {
        // Floor blob, wall blob, a faint far blob.
        let mut r = Rng::keyed(1, stream::MISC, 0, 0);
        let mut v = Vec::new();
        for i in 0..n {
            let (a, b) = (r.next_f32(), r.next_f32());
            v.push(match i % 3 {
                0 => CausticPoint::new(Vec3::new(a, 0.0, b), Vec3::Y, Vec3::Y, Vec3::splat(1.0)),
                1 => CausticPoint::new(Vec3::new(0.0, a, b), Vec3::X, Vec3::X, Vec3::splat(1.0)),
                _ => CausticPoint::new(Vec3::new(3.0 + a, 0.0, b), Vec3::Y, Vec3::Y, Vec3::splat(1e-3)),
            });
        }
        v
    }

    /// Brute force of the same rule over the same representatives.
    fn brute(map: &ClusterMap, x: Vec3, n_x: Vec3) -> Option<usize> {
        let (mut best, mut bd) = (None, f32::INFINITY);
        for (c, p) in map.tree.items() {
            let d = (Vec3::from_array(p) - x).length_squared();
            if d < bd {
                bd = d;
                best = Some(c as usize);
            }
        }
        let c = best?;
        (bd <= map.reach[c].powi(2) && n_x.dot(Vec3::from_array(map.normals[c])) >= 0.5).then_some(c)
    }

    #[test]
    fn query_matches_brute_force_and_rules() {
        let pts = scene(6000);
        let cl = cluster_points(&pts, 12, 3);
        let max_rank = 3;
        let map = ClusterMap::build(&pts, &cl, max_rank, 32, 0.05);
        assert_eq!(map.n_clusters(), cl.n_kept(max_rank));
        assert!(map.n_representatives() <= 32 * map.n_clusters());
        let mut r = Rng::keyed(2, stream::MISC, 0, 0);
        for _ in 0..2000 {
            let x = Vec3::new(4.0 * r.next_f32() - 0.5, 1.2 * r.next_f32() - 0.1, 1.2 * r.next_f32() - 0.1);
            for n in [Vec3::Y, Vec3::X, -Vec3::Y] {
                let c = map.query(x, n);
                assert_eq!(c, brute(&map, x, n));
                // the box test never rejects a point the query accepts
                assert!(c.is_none_or(|c| map.may_accept(c, x)), "may_accept({c:?}, {x}) is false");
            }
        }
        // Floor point with the floor normal lands in a floor cluster; the wrong normal is rejected.
        let c = map.query(Vec3::new(0.5, 0.0, 0.5), Vec3::Y).expect("floor cluster");
        assert!(cl.clusters[c].normal[1] > 0.9);
        assert_eq!(map.query(Vec3::new(0.5, 0.0, 0.5), -Vec3::Y), None);
        // the boxes are tight enough to reject: far from every cluster, no box holds the point
        assert!((0..map.n_clusters()).all(|c| !map.may_accept(c, Vec3::new(50.0, 0.0, 0.0))));
        // Far away: nothing. The faint blob is culled at rank 3 when it exists as its own cluster.
        assert_eq!(map.query(Vec3::new(50.0, 0.0, 0.0), Vec3::Y), None);
        for ci in 0..map.n_clusters() {
            assert!(cl.clusters[ci].rank <= max_rank);
        }
    }

    #[test]
    fn empty_and_round_trip() {
        let empty = ClusterMap::build(&[], &Clustering::default(), 6, 32, 0.1);
        assert_eq!(empty.query(Vec3::ZERO, Vec3::Y), None);
        let pts = scene(3000);
        let cl = cluster_points(&pts, 8, 1);
        let map = ClusterMap::build(&pts, &cl, 6, 32, 0.05);
        let bytes = bitcode::encode(&map);
        let back: ClusterMap = bitcode::decode(&bytes).unwrap();
        assert_eq!(back, map);
        let bytes = bitcode::encode(&cl);
        assert_eq!(bitcode::decode::<Clustering>(&bytes).unwrap(), cl);
    }
}
