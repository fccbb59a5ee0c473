//! Tests of `cf::subset_grid`: the grid's answers are the cluster map's query restricted to the
//! subset, exactly (random points, near representatives, the slack band, split cells, a stopped
//! build).

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
                CausticPoint::new(Vec3::new(blob + 0.3 * a, 0.0, 0.3 * b), Vec3::Y, Vec3::Y, Vec3::splat(1.0 + blob))
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
                        assert!(may, "subset {subset:?}: x = {x} accepted for cluster {c} but rejected by the grid");
                    }
                }
            }
        }
        assert!(inside > 100, "subset {subset:?}: only {inside} points inside");
        // the grid must be worth its build: a single cluster leaves most points out
        if subset.len() == 1 {
            assert!(rejected > 300_000, "subset {subset:?}: only {rejected} of 600k rejected (fill {})", grid.fill());
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
