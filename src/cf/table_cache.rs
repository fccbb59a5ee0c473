//! The CF table cache [spec §9 "caching tables per cluster cell"]: the
//! direction tables of a cacheable point are those of its cache key, built once and shared by
//! every worker thread. Cacheable: flat-shaded non-Dirac points for `iws-cf` (which samples the
//! tables alone, so their hemisphere must be the point's: normal part = the bits of `n_g`), and
//! every non-Dirac point for `pt-cf` (whose BSDF share covers what the tables miss: normal part
//! = the [`normal_bin`] of the lit-side shading normal, the tables built around the bin's centre,
//! which is also the frame the caller samples and evaluates them in).
//!
//! The key is (cluster, cell, normal part): the kept cluster `c` found at the point itself (the
//! cluster map's membership test), and `c`'s cell of edge `F·r_c`, where
//! `r_c = min(r, sqrt(n/(π ρ_c)))` is the radius that holds n forecasters at the cluster's own
//! photon density `ρ_c = N_c/A_c`. The tables of a cell are built once, at its centre, from `c`'s
//! forecast map. So a small, dense caustic gets small cells and a wide, faint cluster large ones,
//! instead of one cell size from the global radius r, which the faint clusters dominate
//! (measured: `results/2026-12-01-option-tables.md`, `--table-cache`).
//!
//! Invariants: every entry is a pure function of its key, never of random numbers or of the
//! thread that built it (two threads may race to build the same entry; both results are equal),
//! so the estimator stays unbiased and the image does not depend on the thread count. A full
//! shard is cleared, which only costs rebuilds.

use super::cluster::Clustering;
use super::direction_table::ForecastTables;
use crate::math::Vec3;
use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hash, Hasher};
use std::sync::{Arc, RwLock};

/// Shards per map (threads rarely contend on one lock).
const SHARDS: usize = 64;
/// Entries per shard before it is cleared (bounds memory).
const SHARD_CAP: usize = 1 << 13;

/// Cell edges of the cache, part of the broadcast CF product.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, bitcode::Encode, bitcode::Decode)]
pub struct CellSizes {
    /// Cell edge `F·r_c` of each kept cluster, by cluster index (empty: no cache).
    pub edge: Vec<f32>,
}

impl CellSizes {
    /// Edges for cache fraction `f` (0 disables the cache), search radius `r` and `n`
    /// forecasters per table.
    pub fn new(clustering: &Clustering, max_rank: u32, (r, n, f): (f32, usize, f32)) -> CellSizes {
        if !(f > 0.0 && r > 0.0 && r.is_finite()) {
            return CellSizes::default();
        }
        let edge = clustering
            .kept(max_rank)
            .iter()
            .map(|c| {
                let rho = c.count() as f64 / c.area as f64;
                let rc = (n as f64 / (std::f64::consts::PI * rho)).sqrt() as f32;
                f * if rc.is_finite() && rc > 0.0 { rc.min(r) } else { r }
            })
            .collect();
        CellSizes { edge }
    }

    /// Whether the cache is on.
    pub fn enabled(&self) -> bool {
        !self.edge.is_empty()
    }

    /// JSON figures: the range of cell edges.
    pub fn json(&self) -> serde_json::Value {
        let (lo, hi) = self.range();
        serde_json::json!({ "edge_min": lo, "edge_max": hi })
    }

    /// (min, max) cell edge, for reports.
    pub fn range(&self) -> (f32, f32) {
        let lo = self.edge.iter().copied().fold(f32::INFINITY, f32::min);
        let hi = self.edge.iter().copied().fold(0.0, f32::max);
        if self.edge.is_empty() {
            (0.0, 0.0)
        } else {
            (lo, hi)
        }
    }
}

/// Integer cell of `p` for edge `edge`, and the cell's centre.
pub fn cell_of(p: Vec3, edge: f32) -> ([i32; 3], Vec3) {
    let q = (p / edge).floor();
    ([q.x as i32, q.y as i32, q.z as i32], (q + Vec3::splat(0.5)) * edge)
}

/// Bit pattern of a normal (cells on the two sides of a thin wall never share tables).
pub fn normal_key(n: Vec3) -> [u32; 3] {
    n.to_array().map(f32::to_bits)
}

/// Normal bins per cube-face edge of [`normal_bin`]: a bin spans at most 2/33 rad ≈ 3.5° on each
/// axis, so its centre is within ≈ 2.5° of every normal in it; odd, so that the axes (the normals
/// of most flat walls) are bin centres and keep their own frame.
pub const NORMAL_BINS: u32 = 33;

/// First word of the normal part of a key made by [`normal_bin`] (the bits of a NaN, which no
/// [`normal_key`] of a unit normal has).
pub const NORMAL_BIN_TAG: u32 = u32::MAX;

/// The cube-map bin of a unit normal `n` and the bin's centre (a unit vector): the dominant axis
/// and its sign choose the face, the other two coordinates over the dominant one, each in
/// [-1, 1], are cut into [`NORMAL_BINS`] equal steps. A pure function of `n`; the centre lies in
/// its own bin. The key's normal part is `[NORMAL_BIN_TAG, bin, 0]`.
pub fn normal_bin(n: Vec3) -> (u32, Vec3) {
    let a = n.abs().to_array();
    // dominant axis, ties to the lower index (deterministic); a NaN or zero normal: +z
    let axis = if a[0] >= a[1] && a[0] >= a[2] {
        0
    } else if a[1] >= a[2] {
        1
    } else {
        2
    };
    let v = n.to_array();
    let (d, b, c) = (v[axis], v[(axis + 1) % 3], v[(axis + 2) % 3]);
    let q = NORMAL_BINS as f32;
    let step = |x: f32| {
        let t = if d.abs() > 0.0 { x / d.abs() } else { 0.0 };
        let t = if t.is_finite() { t } else { 0.0 };
        (((t.clamp(-1.0, 1.0) + 1.0) * 0.5 * q) as u32).min(NORMAL_BINS - 1)
    };
    let (neg, ib, ic) = (u32::from(d < 0.0), step(b), step(c));
    let face = 2 * axis as u32 + neg;
    let key = (face * NORMAL_BINS + ib) * NORMAL_BINS + ic;
    let mid = |i: u32| -1.0 + (i as f32 + 0.5) * 2.0 / q;
    let mut w = [0.0f32; 3];
    w[axis] = if neg == 1 { -1.0 } else { 1.0 };
    w[(axis + 1) % 3] = mid(ib);
    w[(axis + 2) % 3] = mid(ic);
    (key, Vec3::from_array(w).normalize())
}

/// Cache key: (cluster, cell, normal part): the bits of a flat point's normal ([`normal_key`]) or
/// `[NORMAL_BIN_TAG, bin, 0]` for a [`normal_bin`].
pub type CellKey = (u32, [i32; 3], [u32; 3]);

/// The table cache of one CF estimator, shared by every worker thread: a sharded concurrent
/// map whose values are pure functions of their keys.
pub struct TableCache {
    shards: Vec<RwLock<Shard>>,
    /// This cache's identity for the workers' memos ([`TableMemo`]).
    id: Arc<()>,
}

/// A key with its hash, computed once per lookup (shard choice and map probe share it).
#[derive(Clone, Copy, PartialEq, Eq)]
struct Hashed {
    hash: u64,
    key: CellKey,
}

impl Hash for Hashed {
    fn hash<H: Hasher>(&self, h: &mut H) {
        h.write_u64(self.hash);
    }
}

impl Hashed {
    /// The multiply-rotate hash of the `FxHash` recipe over the key's seven words (std's SipHash
    /// cost 2% of a `pt-cf` render; a cache of our own keys needs no DoS resistance).
    fn new(key: CellKey) -> Hashed {
        let (c, cell, n) = key;
        let words = [c, cell[0] as u32, cell[1] as u32, cell[2] as u32, n[0], n[1], n[2]];
        let hash =
            words.iter().fold(0u64, |h, &w| (h.rotate_left(5) ^ u64::from(w)).wrapping_mul(0x517c_c1b7_2722_0a95));
        Hashed { hash, key }
    }
}

/// The identity hasher over a [`Hashed`] key's precomputed hash.
#[derive(Default)]
struct PassThrough(u64);

impl Hasher for PassThrough {
    fn write(&mut self, _: &[u8]) {
        unreachable!("only Hashed keys are hashed")
    }
    fn write_u64(&mut self, h: u64) {
        self.0 = h;
    }
    fn finish(&self) -> u64 {
        self.0
    }
}

type Shard = HashMap<Hashed, Arc<ForecastTables>, BuildHasherDefault<PassThrough>>;

impl Default for TableCache {
    fn default() -> Self {
        TableCache { shards: (0..SHARDS).map(|_| RwLock::new(Shard::default())).collect(), id: Arc::new(()) }
    }
}

/// Entries of a worker's [`TableMemo`] (direct-mapped by the key's hash).
const MEMO: usize = 1024;

/// A worker's memo of the shared [`TableCache`]'s answers (kept in `Context::memo`): the
/// tables of the keys it looked up last, one per slot of the key's hash. A table is a pure
/// function of its key, so the memo returns what the cache would; it saves the shard's lock,
/// the map's probe and a shared reference count's cache line on the hot path.
#[derive(Default)]
pub struct TableMemo {
    slots: Vec<Option<(Hashed, Arc<ForecastTables>)>>,
    /// The cache whose answers the slots hold (its identity: held, so never reused by another).
    cache: Option<Arc<()>>,
}

impl TableMemo {
    /// Empties the memo unless it holds `cache`'s answers (a worker may serve another cache).
    fn serve(&mut self, cache: &TableCache) {
        if !self.cache.as_ref().is_some_and(|c| Arc::ptr_eq(c, &cache.id)) {
            self.slots.clear();
            self.cache = Some(cache.id.clone());
        }
    }

    fn slot(k: &Hashed) -> usize {
        (k.hash >> 48) as usize % MEMO
    }

    fn get(&self, k: &Hashed) -> Option<&Arc<ForecastTables>> {
        match self.slots.get(Self::slot(k)) {
            Some(Some((key, t))) if key == k => Some(t),
            _ => None,
        }
    }

    fn put(&mut self, k: Hashed, t: &Arc<ForecastTables>) {
        if self.slots.is_empty() {
            self.slots.resize(MEMO, None);
        }
        self.slots[Self::slot(&k)] = Some((k, t.clone()));
    }
}

impl TableCache {
    /// [`TableCache::get`] through the worker's `memo`: its entry when it holds `k`, else the
    /// cache's (then kept in the memo).
    pub fn get_memo(&self, k: &CellKey, memo: &mut TableMemo) -> Option<Arc<ForecastTables>> {
        let h = Hashed::new(*k);
        memo.serve(self);
        if let Some(t) = memo.get(&h) {
            return Some(t.clone());
        }
        let t = self.get(k)?;
        memo.put(h, &t);
        Some(t)
    }

    /// [`TableCache::insert`], also into the worker's `memo`.
    pub fn insert_memo(&self, k: CellKey, t: Arc<ForecastTables>, memo: &mut TableMemo) {
        memo.serve(self);
        memo.put(Hashed::new(k), &t);
        self.insert(k, t);
    }

    fn shard(&self, k: &Hashed) -> &RwLock<Shard> {
        // middle bits: the map itself uses the low ones (bucket) and the top seven (tag)
        &self.shards[(k.hash >> 32) as usize % SHARDS]
    }

    /// The cell's tables, if cached.
    pub fn get(&self, k: &CellKey) -> Option<Arc<ForecastTables>> {
        let k = Hashed::new(*k);
        self.shard(&k).read().unwrap_or_else(|e| e.into_inner()).get(&k).cloned()
    }

    /// Stores a cell's tables (a full shard is cleared first).
    pub fn insert(&self, k: CellKey, t: Arc<ForecastTables>) {
        let k = Hashed::new(k);
        let mut m = self.shard(&k).write().unwrap_or_else(|e| e.into_inner());
        if m.len() >= SHARD_CAP {
            m.clear();
        }
        m.insert(k, t);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cf::caustic_point::CausticPoint;
    use crate::cf::cluster::cluster_points;
    use crate::sampling::rng::{stream, Rng};

    /// A dense 0.1 m caustic and a faint 4 m blob: the dense cluster's cells are much smaller.
    #[test]
    fn cells_follow_each_clusters_density() {
        let mut rng = Rng::keyed(3, stream::MISC, 0, 0);
        let pts: Vec<CausticPoint> = (0..6000)
            .map(|i| {
                let (a, b) = (rng.next_f32(), rng.next_f32());
                let s = if i % 2 == 0 { 0.1 } else { 4.0 };
                let off = if i % 2 == 0 { 0.0 } else { 10.0 };
                CausticPoint::new(Vec3::new(off + s * a, 0.0, s * b), Vec3::Y, Vec3::Y, Vec3::splat(1.0))
            })
            .collect();
        let cl = cluster_points(&pts, 2, 1);
        let r = crate::cf::forecast_map::search_radius(&cl, 6, 128).unwrap();
        let cells = CellSizes::new(&cl, 6, (r, 128, 1.0));
        let (lo, hi) = cells.range();
        // 3000 points on 0.01 m² vs 16 m²: r_c ∝ 1/sqrt(ρ_c), a ratio of 40 in edge
        assert!(hi / lo > 20.0, "cell edges {lo} .. {hi}");
        assert!(hi <= r * 1.0001);
        assert_eq!(CellSizes::new(&cl, 6, (r, 128, 0.0)), CellSizes::default());
    }

    /// A worker's memo returns what its cache holds, and never another cache's tables (a worker
    /// may serve two renders); a key sharing a slot evicts, never answers for, another.
    #[test]
    fn a_memo_answers_only_for_its_cache() {
        use crate::cf::direction_table::{DirectionTable, N_BINS};
        let some = Arc::new(ForecastTables { t1: DirectionTable::from_weights(&[1.0; N_BINS]), t2: None });
        let none = Arc::new(ForecastTables { t1: None, t2: None });
        let (a, b, mut memo) = (TableCache::default(), TableCache::default(), TableMemo::default());
        let key = (3, [1, -2, 0], [NORMAL_BIN_TAG, 7, 0]);
        a.insert_memo(key, some.clone(), &mut memo);
        assert_eq!(a.get_memo(&key, &mut memo).as_deref(), Some(&*some));
        assert_eq!(b.get_memo(&key, &mut memo), None, "another cache's memo answered");
        b.insert(key, none.clone());
        assert_eq!(b.get_memo(&key, &mut memo).as_deref(), Some(&*none));
        assert_eq!(a.get_memo(&key, &mut memo).as_deref(), Some(&*some));
        // keys of one slot: each gets its own tables
        let slot = TableMemo::slot(&Hashed::new(key));
        let other = (0..).map(|c| (c, [0; 3], [0; 3])).find(|&k| k != key && TableMemo::slot(&Hashed::new(k)) == slot);
        let other = other.expect("a key in the same slot");
        a.insert_memo(other, none.clone(), &mut memo);
        assert_eq!(a.get_memo(&key, &mut memo).as_deref(), Some(&*some));
        assert_eq!(a.get_memo(&other, &mut memo).as_deref(), Some(&*none));
    }

    #[test]
    fn cell_centres_lie_in_their_cells() {
        for p in [Vec3::new(-0.3, 2.0, 7.1), Vec3::new(0.0, -1e-3, 5.5)] {
            let (k, c) = cell_of(p, 0.25);
            assert_eq!(cell_of(c, 0.25).0, k);
            assert!((c - p).abs().max_element() <= 0.125 + 1e-6);
        }
    }

    /// Every normal lands in one bin whose centre is a unit vector in that same bin and within
    /// the bin's half-diagonal (≈ 2.5°) of it; the two sides of a wall never share a bin.
    #[test]
    fn normal_bins_are_pure_and_tight() {
        let mut rng = Rng::keyed(5, stream::MISC, 0, 0);
        let max_angle = (2.0f32.sqrt() / NORMAL_BINS as f32).atan(); // half-diagonal at a face centre
        for i in 0..20_000 {
            let n = match i {
                0 => Vec3::Y,
                1 => Vec3::new(1.0, 1.0, 1.0).normalize(), // a three-way tie of axes
                2 => Vec3::new(0.0, -1.0, 0.0),
                _ => {
                    let (z, phi) = (2.0 * rng.next_f32() - 1.0, 2.0 * std::f32::consts::PI * rng.next_f32());
                    let r = (1.0 - z * z).max(0.0).sqrt();
                    Vec3::new(r * phi.cos(), r * phi.sin(), z)
                }
            };
            let (k, c) = normal_bin(n);
            assert!(k < 6 * NORMAL_BINS * NORMAL_BINS);
            assert_eq!(normal_bin(n), (k, c), "not a pure function of n");
            assert!((c.length() - 1.0).abs() < 1e-5);
            assert_eq!(normal_bin(c).0, k, "centre {c} of {n}'s bin lies in another bin");
            let angle = n.dot(c).clamp(-1.0, 1.0).acos();
            assert!(angle <= max_angle * 1.01, "{n}: {}° from its bin centre", angle.to_degrees());
            assert_ne!(normal_bin(-n).0, k);
        }
        // an axis is its bin's centre
        for n in [Vec3::X, -Vec3::Y, Vec3::Z] {
            assert_eq!(normal_bin(n).1, n);
        }
        // degenerate input gets a bin, never a panic
        for n in [Vec3::ZERO, Vec3::splat(f32::NAN), Vec3::new(f32::INFINITY, 0.0, 0.0)] {
            let (k, _) = normal_bin(n);
            assert!(k < 6 * NORMAL_BINS * NORMAL_BINS);
        }
    }

    /// The cache holds what it was given under a key and nothing under another key.
    #[test]
    fn cache_returns_its_entries_by_key() {
        let cache = TableCache::default();
        let t = Arc::new(ForecastTables { t1: None, t2: None });
        let k = (3, [1, -2, 5], [NORMAL_BIN_TAG, 17, 0]);
        assert!(cache.get(&k).is_none());
        cache.insert(k, t.clone());
        assert!(Arc::ptr_eq(&cache.get(&k).unwrap(), &t));
        assert!(cache.get(&(3, [1, -2, 5], [NORMAL_BIN_TAG, 18, 0])).is_none());
        assert!(cache.get(&(4, [1, -2, 5], [NORMAL_BIN_TAG, 17, 0])).is_none());
    }
}
