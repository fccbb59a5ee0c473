//! Per-cluster forecast maps and the search-radius heuristic ([BAJ08 §3.2] "per-cluster kd-trees called
//! forecast maps containing the caustic points within the cluster and up to a surrounding epsilon";
//! "maximum search radius r … to find approximately n neighboring photons in regions of average
//! density"; spec §3 "Forecast maps", "Search radius").
//!
//! For each kept cluster `c` the map holds its members plus every caustic point within `ε = r` of a
//! member whose normal satisfies `n_i·n̄_c > 0.5` (the epsilon margin), keyed by the global point index.
//! `search_radius` gives `r = sqrt(n/(π ρ̄))` with `ρ̄ = Σ_kept N_c / Σ_kept A_c`.
//!
//! Invariants: gathers return global point indices sorted by distance, at most `n_max`, all within
//! `r`; nothing allocates beyond the caller's buffer; an unknown cluster index gathers nothing.
//! Building is parallel over clusters but deterministic. Serializable with bitcode.

// `!(x > 0.0)`-style tests are deliberate: they are true for NaN (degenerate input is rejected).
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::caustic_point::CausticPoint;
use super::cluster::Clustering;
use crate::math::Vec3;
use crate::spatial::KdTree;
use rayon::prelude::*;

/// Minimum (strict) `n_i·n̄_c` for margin photons.
pub const MARGIN_NORMAL_COS: f32 = 0.5;

/// Search radius `r = sqrt(n / (π ρ̄))`, `ρ̄ = Σ N_c / Σ A_c` over kept clusters (spec §3).
/// `None` when no cluster is kept or the areas/counts are degenerate.
pub fn search_radius(clustering: &Clustering, max_rank: u32, n: usize) -> Option<f32> {
    let kept = clustering.kept(max_rank);
    let count: f64 = kept.iter().map(|c| c.count() as f64).sum();
    let area: f64 = kept.iter().map(|c| c.area as f64).sum();
    if !(count > 0.0 && area > 0.0) || n == 0 {
        return None;
    }
    let rho = count / area;
    let r = (n as f64 / (std::f64::consts::PI * rho)).sqrt() as f32;
    (r.is_finite() && r > 0.0).then_some(r)
}

/// One kd-tree of forecasters per kept cluster.
#[derive(Clone, Debug, Default, PartialEq, bitcode::Encode, bitcode::Decode)]
pub struct ForecastMaps {
    /// The margin ε = r used at build time.
    pub margin: f32,
    maps: Vec<KdTree>,
}

impl ForecastMaps {
    /// Builds one map per kept cluster (rank ≤ `max_rank`) with margin `ε = r`.
    pub fn build(points: &[CausticPoint], clustering: &Clustering, max_rank: u32, r: f32) -> Self {
        let kept = clustering.kept(max_rank);
        let r = if r.is_finite() { r.max(0.0) } else { 0.0 };
        let all: Vec<[f32; 3]> = points.iter().map(|p| p.p).collect();
        let global = KdTree::build(&all);
        let r2 = r * r;
        let maps = kept
            .par_iter()
            .enumerate()
            .map(|(ci, c)| {
                let nbar = c.normal_v();
                let mut ids: Vec<u32> = c.members.iter().copied().filter(|&m| (m as usize) < points.len()).collect();
                if r2 > 0.0 && !ids.is_empty() {
                    // Epsilon margin: non-members within r of a member, with n_i·n̄_c > 0.5. Candidates
                    // come from the members' bbox grown by r; each is tested against the member tree,
                    // so the work scales with the cluster's neighbourhood, not with members × n.
                    let members =
                        KdTree::build_with_ids(ids.iter().map(|&i| points[i as usize].p).collect(), ids.clone());
                    let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
                    for &m in &ids {
                        for d in 0..3 {
                            lo[d] = lo[d].min(points[m as usize].p[d] - r);
                            hi[d] = hi[d].max(points[m as usize].p[d] + r);
                        }
                    }
                    global.for_each_in_box(lo, hi, |i, p| {
                        if clustering.labels.get(i as usize).copied() == Some(ci as u32) {
                            return; // a member (labels index kept clusters in the same order)
                        }
                        if points[i as usize].normal().normalize_or_zero().dot(nbar) > MARGIN_NORMAL_COS
                            && members.any_within(p, r2)
                        {
                            ids.push(i);
                        }
                    });
                }
                ids.sort_unstable();
                ids.dedup();
                let pos = ids.iter().map(|&i| points[i as usize].p).collect();
                KdTree::build_with_ids(pos, ids)
            })
            .collect();
        ForecastMaps { margin: r, maps }
    }

    /// Number of maps (kept clusters).
    pub fn len(&self) -> usize {
        self.maps.len()
    }

    /// True when there is no map.
    pub fn is_empty(&self) -> bool {
        self.maps.is_empty()
    }

    /// Number of forecasters stored for `cluster` (0 if out of range).
    pub fn cluster_size(&self, cluster: usize) -> usize {
        self.maps.get(cluster).map_or(0, |m| m.len())
    }

    /// The tree of `cluster`, if any (item ids are global point indices).
    pub fn map(&self, cluster: usize) -> Option<&KdTree> {
        self.maps.get(cluster)
    }

    /// Gathers the `n_max` forecasters of `cluster` nearest to `x` within radius `r` into `out` as
    /// `(dist², global point index)`, nearest first. `out` is cleared first.
    pub fn gather(&self, cluster: usize, x: Vec3, n_max: usize, r: f32, out: &mut Vec<(f32, u32)>) {
        match self.maps.get(cluster) {
            Some(m) if r.is_finite() && r >= 0.0 => m.k_nearest_within(x.to_array(), n_max, r * r, out),
            _ => out.clear(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cf::cluster::cluster_points;
    use crate::math::PI;
    use crate::sampling::rng::{stream, Rng};

    fn scene(n: usize) -> Vec<CausticPoint> {
        let mut r = Rng::keyed(4, stream::MISC, 0, 0);
        (0..n)
            .map(|i| {
                let (a, b) = (r.next_f32(), r.next_f32());
                if i % 2 == 0 {
                    CausticPoint::new(Vec3::new(a, 0.0, b), Vec3::Y, Vec3::Y, Vec3::splat(1.0))
                } else {
                    CausticPoint::new(Vec3::new(0.0, a, b), Vec3::X, Vec3::X, Vec3::splat(0.5))
                }
            })
            .collect()
    }

    #[test]
    fn maps_match_brute_force_definition_and_gather() {
        let pts = scene(8000);
        let cl = cluster_points(&pts, 16, 5);
        let max_rank = 4;
        let r = search_radius(&cl, max_rank, 64).unwrap();
        // 8000 points on two unit squares: ρ̄ ≈ 4000 per unit area → r ≈ sqrt(64/(π·4000)) ≈ 0.071.
        assert!((r / (64.0f32 / (PI * 4000.0)).sqrt() - 1.0).abs() < 0.3, "{r}");
        let maps = ForecastMaps::build(&pts, &cl, max_rank, r);
        assert_eq!(maps.len(), cl.n_kept(max_rank));
        for (ci, c) in cl.kept(max_rank).iter().enumerate() {
            // Brute-force membership: members ∪ {i: ∃ member within r, n_i·n̄_c > 0.5}.
            let n = c.normal_v();
            let mut want: Vec<u32> = (0..pts.len() as u32)
                .filter(|&i| {
                    c.members.binary_search(&i).is_ok()
                        || (pts[i as usize].normal().dot(n) > 0.5
                            && c.members
                                .iter()
                                .any(|&m| (pts[m as usize].pos() - pts[i as usize].pos()).length_squared() <= r * r))
                })
                .collect();
            want.sort();
            let mut got: Vec<u32> = maps.map(ci).unwrap().items().map(|x| x.0).collect();
            got.sort();
            assert_eq!(got, want, "cluster {ci}");
            // Gather equals brute-force k-nearest within r over that set.
            let mut out = Vec::new();
            let x = c.centroid_v() + Vec3::new(0.01, 0.0, -0.02);
            maps.gather(ci, x, 32, r, &mut out);
            let mut d: Vec<f32> =
                want.iter().map(|&i| (pts[i as usize].pos() - x).length_squared()).filter(|&d| d <= r * r).collect();
            d.sort_by(f32::total_cmp);
            d.truncate(32);
            assert_eq!(out.iter().map(|e| e.0).collect::<Vec<_>>(), d);
        }
        let mut out = vec![(0.0, 0)];
        maps.gather(999, Vec3::ZERO, 8, r, &mut out);
        assert!(out.is_empty());
    }

    #[test]
    fn degenerate_and_round_trip() {
        assert_eq!(search_radius(&Clustering::default(), 6, 128), None);
        let m = ForecastMaps::build(&[], &Clustering::default(), 6, 0.1);
        assert!(m.is_empty());
        let pts = scene(2000);
        let cl = cluster_points(&pts, 8, 2);
        let r = search_radius(&cl, 6, 32).unwrap();
        let maps = ForecastMaps::build(&pts, &cl, 6, r);
        let bytes = bitcode::encode(&maps);
        assert_eq!(bitcode::decode::<ForecastMaps>(&bytes).unwrap(), maps);
    }
}
