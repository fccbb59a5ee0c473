//! `CausticForecast`: the built CF product (caustic points, clustering, cluster map, forecast
//! maps, search radius) and the CF estimator Ĺ_c at a non-specular point [BAJ08 §3.2; spec §4].
//!
//! At x: query the cluster map. Outside a kept cluster: S_cos = 1 BSDF sample. Inside: gather
//! up to n forecasters within r, build the 32×16 table T1 (weights lum(Φ)·f·μ, the paper's) and
//! T2 on its empty bins ([`TableKind`]: `DualSpread`, or the paper's `Dual` with `--variant
//! baj08`), sample each `S` times ([`CausticForecast::split_for`]: at d = 0 the energy rule, or the
//! paper's rank rule with `--variant baj08`; 1 deeper) and SUM the two estimates. The caller's
//! `g(ωi)` returns the integrand f·cos·1[first hit Dirac]·L̂; any table is a valid pdf, so the
//! estimate is unbiased whatever the photons are. The derivation: `docs/methods/iws-cf.md`.
//!
//! Invariants: S depends only on the cluster (its density or rank) and the diffuse depth, never
//! on samples;
//! the product is identical after a bitcode round trip (it is what rank 0 broadcasts).
//! The [`TableCache`] (`table_cache.rs`) is an explicit object owned by the estimator and shared
//! by all worker threads: a cached entry is a pure function of its key, so sharing it changes
//! no image. [`CausticForecast::tables_in`] caches flat-shaded points only (the tables must cover
//! the point's hemisphere); [`CausticForecast::guide_tables`], for a caller that mixes them with
//! the BSDF, caches every non-Dirac point by the bin of its shading normal.

use super::caustic_point::CausticPoint;
use super::cluster::{cluster_points, Clustering};
use super::cluster_map::{ClusterMap, DEFAULT_REPRESENTATIVES};
use super::direction_table::{ForecastTables, TableMode};
use super::forecast_map::{search_radius, ForecastMaps};
use super::share::CausticShare;
use super::subset_grid::SubsetGrid;
pub use super::table_cache::TableCache;
use super::table_cache::{cell_of, normal_bin, normal_key, CellSizes, TableMemo, NORMAL_BIN_TAG};
use crate::bsdf::{self, Mode};
use crate::math::{luminance, Frame, Rgb, Vec3};
use crate::profile::Phase;
use crate::progress::Phases;
use crate::transport::context::{Context, ShadingQuery};
use std::sync::Arc;
use std::time::Instant;

/// Splitting rule of `iws-cf` at diffuse depth 0 (`Energy`, the default; `Rank` with `--variant
/// baj08`); 1 sample per table deeper. Both are functions of the point's cluster and the depth
/// only, so the estimator stays unbiased.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, bitcode::Encode, bitcode::Decode)]
pub enum SplitRule {
    /// The paper's rank rule `S = max(1, S0 >> rank)`.
    Rank,
    /// From the cluster's measured energy density: `S = clamp(⌈S0·ρ_c/ρ_max⌉, 1, S0)` (the
    /// default: the rank rule's exclusive prefix puts dim clusters at rank 0 too, 22 of
    /// `cornell-box`'s 64 with densities 0.06–3.5, and splits their chains as the brightest).
    #[default]
    Energy,
}

/// The energy rule: `clamp(⌈s0·ρ/ρ_max⌉, 1, s0)` continuations at diffuse depth 0 in a cluster
/// of energy density `density` (the split rule of `iws-cf` and `pt-cf`); 1 where the densities
/// are not usable, never 0 (a zero split would drop the light).
#[inline]
pub fn energy_split(s0: u32, density: f32, max: f32) -> usize {
    let s0 = s0.max(1) as f32;
    // finite ρ and 0 < ρ_max < ∞: never NaN (an overflow is +∞, clamped to s0)
    let s = if max > 0.0 && max.is_finite() && density.is_finite() { (s0 * density / max).ceil() } else { 1.0 };
    s.clamp(1.0, s0) as usize
}

/// The paper's rank rule: `max(1, s0 >> rank)` continuations at diffuse depth 0 in a cluster of
/// rank `rank` (`iws-cf --variant baj08`).
#[inline]
pub fn rank_split(s0: u32, rank: u32) -> usize {
    (s0 >> rank.min(31)).max(1) as usize
}

/// Table layout (`iws-cf`: `DualSpread`, or `Dual` with `--variant baj08`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, bitcode::Encode, bitcode::Decode)]
pub enum TableKind {
    /// CF dual table (T1 + T2 on the empty bins, summed) [BAJ08].
    Dual,
    /// Dual table whose T2 follows the forecasters spread by [`SPREAD`] = (tent half-width in
    /// bins, f·cos share) over the empty bins next to them (`TableMode::DualSpread`).
    #[default]
    DualSpread,
}

/// `(radius, alpha)` of the default `DualSpread` table: a tent two bins wide each way, half of T2
/// on the f·cos fill (screened on the crop cameras: `results/rejected/table.md`).
pub const SPREAD: (f32, f32) = (2.0, 0.5);

/// CF parameters (defaults: spec §5).
#[derive(Clone, Debug, PartialEq, serde::Serialize, bitcode::Encode, bitcode::Decode)]
pub struct ForecastOptions {
    /// Codebook size k.
    pub clusters: usize,
    /// Clusters with rank > max_rank are culled.
    pub max_rank: u32,
    /// Forecasters gathered per table (n).
    pub gather: usize,
    /// Table layout.
    pub table: TableKind,
    /// Splitting at diffuse depth 0 for rank 0 (S = max(1, S0 >> rank)).
    pub s0: u32,
    /// Splitting rule.
    pub split_rule: SplitRule,
    /// Table cache cell edge as a fraction of the cluster's own radius r_c (0 disables the
    /// cache). Flat-shaded, non-Dirac points reuse the tables of their cell (`table_cache.rs`):
    /// a deterministic function of x, so still unbiased (spec §9 "caching tables per cluster cell").
    pub cache_cell: f32,
    /// Photon tables are used at diffuse depths d < table_depth; deeper, one BSDF sample
    /// (S_cos = 1, spec §4). The dual table doubles the samples per vertex, so tables at every
    /// depth make the recursion branch; the choice depends on d only, so it stays unbiased.
    pub table_depth: u32,
}

impl Default for ForecastOptions {
    fn default() -> Self {
        ForecastOptions {
            clusters: 64,
            max_rank: 6,
            gather: 128,
            table: TableKind::DualSpread,
            s0: 16,
            split_rule: SplitRule::Energy,
            cache_cell: 1.0,
            table_depth: 1,
        }
    }
}

/// Preprocess figures in the paper's Table 1 layout.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, bitcode::Encode, bitcode::Decode)]
pub struct PreprocessStats {
    /// Light paths launched.
    pub paths: u64,
    /// Forecast photons (caustic points) stored.
    pub stored: u64,
    /// Seconds tracing photons.
    pub tracing_s: f64,
    /// Seconds clustering.
    pub clustering_s: f64,
    /// Seconds building the cluster map and forecast maps.
    pub kdtree_s: f64,
    /// Clusters found.
    pub clusters: u64,
    /// Clusters kept (rank ≤ max_rank).
    pub clusters_kept: u64,
    /// Fraction of caustic energy in kept clusters.
    pub energy_kept: f64,
    /// Forecast-map search radius r.
    pub radius: f32,
    /// Fraction of light paths launched by targeted shooting that left a caustic point.
    pub yield_per_path: f64,
    /// Forecast photons asked for (see `photon_rule`).
    pub photons_requested: u64,
    /// Why that count: `cli`, `scene` / `default` (no budget), or `budget` (5% of `--time`
    /// from a pilot run, capped by the scene's count).
    pub photon_rule: String,
    /// Pilot run: preprocess seconds per stored photon (0 without a pilot).
    pub pilot_s_per_photon: f64,
    /// Seconds measuring the clusters' caustic shares.
    pub shares_s: f64,
}

/// The CF product broadcast from rank 0.
#[derive(Clone, Debug, PartialEq, bitcode::Encode, bitcode::Decode)]
pub struct CausticForecast {
    /// Options used.
    pub opts: ForecastOptions,
    /// Caustic points (forecasters).
    pub points: Vec<CausticPoint>,
    /// Clusters, ranked.
    pub clustering: Clustering,
    /// Membership structure.
    pub cluster_map: ClusterMap,
    /// Per-cluster kd-trees.
    pub maps: ForecastMaps,
    /// Search radius r (0 when no cluster is kept).
    pub radius: f32,
    /// Table-cache cell edges.
    pub cells: CellSizes,
    /// Caustic share of each kept cluster (empty until the preprocess measures them).
    pub shares: Vec<CausticShare>,
    /// Preprocess figures.
    pub stats: PreprocessStats,
}

impl CausticForecast {
    /// Clusters the caustic points and builds the maps, reporting the phases "clustering" and
    /// "building forecast maps" to `phases` (display only).
    pub fn build(
        points: Vec<CausticPoint>,
        opts: ForecastOptions,
        seed: u64,
        mut stats: PreprocessStats,
        phases: &dyn Phases,
    ) -> Self {
        let t = Instant::now();
        let phase = phases.phase("clustering", None);
        let clustering = cluster_points(&points, opts.clusters, seed);
        phase.finish();
        stats.clustering_s = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let phase = phases.phase("building forecast maps", None);
        let radius = search_radius(&clustering, opts.max_rank, opts.gather).unwrap_or(0.0);
        let cluster_map = ClusterMap::build(&points, &clustering, opts.max_rank, DEFAULT_REPRESENTATIVES, radius);
        let maps = ForecastMaps::build(&points, &clustering, opts.max_rank, radius);
        phase.finish();
        stats.kdtree_s = t.elapsed().as_secs_f64();
        let kept = clustering.kept(opts.max_rank);
        stats.stored = points.len() as u64;
        stats.clusters = clustering.clusters.len() as u64;
        stats.clusters_kept = kept.len() as u64;
        let kept_power: f64 = kept.iter().map(|c| c.power as f64).sum();
        stats.energy_kept = if clustering.total_power > 0.0 { kept_power / clustering.total_power } else { 0.0 };
        stats.radius = radius;
        let cells = CellSizes::new(&clustering, opts.max_rank, (radius, opts.gather, opts.cache_cell));
        CausticForecast { opts, points, clustering, cluster_map, maps, radius, cells, shares: Vec::new(), stats }
    }

    /// Splitting factor S(rank, d) (spec §4): max(1, S0 >> rank) at d = 0, else 1.
    #[inline]
    pub fn split_count(&self, rank: u32, depth: u32) -> usize {
        if depth == 0 {
            rank_split(self.opts.s0, rank)
        } else {
            1
        }
    }

    /// Splitting factor of cluster `c` at depth `depth` under `opts.split_rule`.
    pub fn split_for(&self, c: usize, depth: u32) -> usize {
        let cl = &self.clustering.clusters[c];
        match self.opts.split_rule {
            SplitRule::Rank => self.split_count(cl.rank, depth),
            SplitRule::Energy if depth == 0 => {
                // the clusters are sorted by density, descending (`Clustering::clusters`)
                energy_split(self.opts.s0, cl.density, self.clustering.clusters[0].density)
            }
            SplitRule::Energy => 1,
        }
    }

    /// Gathers forecasters around `at` in cluster `c` (scratch `buf`) and builds the tables in
    /// `frame`.
    fn build_tables(
        &self,
        (c, at, frame): (usize, Vec3, &Frame),
        buf: &mut Vec<(f32, u32)>,
        weight: impl Fn(&CausticPoint, Vec3) -> f32,
        brdf_cos: impl Fn(Vec3) -> f32,
    ) -> ForecastTables {
        self.maps.gather(c, at, self.opts.gather, self.radius, buf);
        let photons = buf.iter().filter_map(|&(_, id)| {
            let cp = self.points.get(id as usize)?;
            let local = frame.to_local(cp.wi());
            // [spec §4] skip photons from below: also stops thin-wall leaks
            (local.z > 0.0).then(|| (local, weight(cp, local)))
        });
        let mode = match self.opts.table {
            TableKind::Dual => TableMode::Dual,
            TableKind::DualSpread => TableMode::DualSpread { radius: SPREAD.0, alpha: SPREAD.1 },
        };
        ForecastTables::build(photons, brdf_cos, mode)
    }

    /// The tables of a cacheable point in cluster `c`: a pure function of `c`, its cell in
    /// that cluster's grid and the normal part `nk` of the key, built around the normal `n`
    /// (`table_cache.rs`). Cached tables are weighted by lum(Φ)·cos and the cosine: independent
    /// of ωo, they serve every non-Dirac BSDF (exact for Lambert).
    fn cached_tables(
        &self,
        cache: &TableCache,
        (c, p): (usize, Vec3),
        (nk, n): ([u32; 3], Vec3),
        ctx: &mut Context,
    ) -> Arc<ForecastTables> {
        let (cell, centre) = cell_of(p, self.cells.edge[c]);
        let key = (c as u32, cell, nk);
        if let Some(t) = cache.get_memo(&key, ctx.memo::<TableMemo>()) {
            ctx.profile.cf.cache_hits += 1;
            return t;
        }
        let t0 = Instant::now();
        let w = |cp: &CausticPoint, l: Vec3| cp.energy() * l.z;
        let tables = Arc::new(self.build_tables((c, centre, &Frame::from_normal(n)), &mut ctx.knn, w, |l| l.z));
        ctx.profile.cf.tables_built += 1;
        ctx.profile.cf.cdf_ns += t0.elapsed().as_nanos() as u64;
        cache.insert_memo(key, tables.clone(), ctx.memo::<TableMemo>());
        tables
    }

    /// The tables of cluster `c` at a point that is not cached (in the shading frame `frame`).
    fn point_tables(&self, c: usize, q: &ShadingQuery, frame: &Frame, ctx: &mut Context) -> Arc<ForecastTables> {
        let (sp, m, wo) = (q.x, q.m, q.wo);
        let t0 = Instant::now();
        let w = |cp: &CausticPoint, l: Vec3| {
            let f = luminance(bsdf::eval(m, sp, wo, cp.wi(), Mode::Radiance));
            cp.energy() * f * l.z
        };
        let brdf_cos = |l: Vec3| luminance(bsdf::eval(m, sp, wo, frame.to_world(l), Mode::Radiance)) * l.z;
        let t = self.build_tables((c, sp.p, frame), &mut ctx.knn, w, brdf_cos);
        ctx.profile.cf.tables_built += 1;
        ctx.profile.cf.cdf_ns += t0.elapsed().as_nanos() as u64;
        Arc::new(t)
    }

    /// The lit-side normals `(ng, ns)` at `q` (flipped to `q.wo`'s side).
    pub fn lit_normals(q: &ShadingQuery) -> (Vec3, Vec3) {
        let sp = q.x;
        if q.wo.dot(sp.ng) >= 0.0 {
            (sp.ng, sp.ns)
        } else {
            (-sp.ng, -sp.ns)
        }
    }

    /// The kept cluster at `q` (the cluster map's membership test with the lit-side normal), or
    /// `None` outside every kept cluster (and when no cluster is kept). With `grid` (a
    /// [`SubsetGrid`] of this map) only its subset's clusters are returned, the same answers
    /// found mostly without the map's kd-tree.
    pub fn cluster_at(&self, q: &ShadingQuery, ctx: &mut Context, grid: Option<&SubsetGrid>) -> Option<usize> {
        if self.radius <= 0.0 {
            return None;
        }
        let t = ctx.profile.start(Phase::CfTable);
        let (x, n_x) = (q.x.p, Self::lit_normals(q).0);
        let c = match grid {
            Some(g) => g.cluster_at(&self.cluster_map, x, n_x),
            None => self.cluster_map.query(x, n_x),
        };
        ctx.profile.record(Phase::CfTable, t);
        c
    }

    /// The grid over every kept cluster ([`SubsetGrid`]: `cluster_at` with it is `cluster_at`
    /// without it, faster).
    pub fn kept_grid(&self) -> SubsetGrid {
        self.kept_grid_until(&|| false)
    }

    /// [`CausticForecast::kept_grid`] until `stop` (`SubsetGrid::build_until`).
    pub fn kept_grid_until(&self, stop: &(dyn Fn() -> bool + Sync)) -> SubsetGrid {
        SubsetGrid::build_until(&self.cluster_map, &(0..self.cluster_map.n_clusters()).collect::<Vec<_>>(), stop)
    }

    /// The tables of kept cluster `c` at `q` and their frame (z = the normal on `q.wo`'s side).
    /// `cache` serves flat-shaded, non-Dirac points; the result is a pure function of the point
    /// (never of random numbers), so any caller stays unbiased.
    pub fn tables_in(
        &self,
        c: usize,
        q: &ShadingQuery,
        ctx: &mut Context,
        cache: Option<&TableCache>,
    ) -> (Arc<ForecastTables>, Frame) {
        let (sp, m) = (q.x, q.m);
        let (ng, ns) = Self::lit_normals(q);
        let cacheable = self.cells.enabled() && !m.is_dirac() && sp.ns == sp.ng;
        let cache = cache.filter(|_| cacheable);
        // cached tables live in the frame of the geometric normal (equal to ns there)
        let frame = if cache.is_some() { Frame::from_normal(ng) } else { Frame::from_normal(ns) };
        let t_table = ctx.profile.start(Phase::CfTable);
        let tables = match cache {
            Some(cache) => self.cached_tables(cache, (c, sp.p), (normal_key(ng), ng), ctx),
            None => self.point_tables(c, q, &frame, ctx),
        };
        ctx.profile.record(Phase::CfTable, t_table);
        (tables, frame)
    }

    /// The tables of kept cluster `c` at `q` for a caller that draws them in a mixture with the
    /// BSDF (`pt-cf`'s defensive mixture, whose BSDF share covers every direction the tables
    /// miss): with the cache on, every non-Dirac point (smooth or normal-mapped shading too)
    /// takes the tables of its key (cluster, cell, [`normal_bin`] of the lit-side shading
    /// normal), built at the cell's centre around the bin's centre normal, which is also the
    /// frame returned. A pure function of the key, so sampling and `pdf_w` use one table and the
    /// image does not depend on the threads. Without the cache: [`Self::tables_in`].
    pub fn guide_tables(
        &self,
        c: usize,
        q: &ShadingQuery,
        ctx: &mut Context,
        cache: &TableCache,
    ) -> (Arc<ForecastTables>, Frame) {
        if !self.cells.enabled() || q.m.is_dirac() {
            return self.tables_in(c, q, ctx, None);
        }
        let (bin, n) = normal_bin(Self::lit_normals(q).1);
        let t_table = ctx.profile.start(Phase::CfTable);
        let tables = self.cached_tables(cache, (c, q.x.p), ([NORMAL_BIN_TAG, bin, 0], n), ctx);
        ctx.profile.record(Phase::CfTable, t_table);
        (tables, Frame::from_normal(n))
    }

    /// Ĺ_c at `q`. `g(ωi, w, ctx)` returns one sample's contribution: the integrand
    /// f·|cos|·1[first hit Dirac]·L̂ (world ωi) times its estimator weight `w` (1/pdf, over the
    /// sample count), so that a roulette inside `g` sees the sample's whole weight.
    /// `cache` enables the table cache for Lambertian, flat-shaded points; `grid`, the
    /// [`CausticForecast::kept_grid`], speeds up the cluster lookup (same answers).
    pub fn estimate(
        &self,
        q: &ShadingQuery,
        ctx: &mut Context,
        (cache, grid): (Option<&TableCache>, Option<&SubsetGrid>),
        mut g: impl FnMut(Vec3, f32, &mut Context) -> Rgb,
    ) -> Rgb {
        ctx.profile.cf.queries += 1;
        let (sp, m, wo) = (q.x, q.m, q.wo);
        let found = if q.depth >= self.opts.table_depth { None } else { self.cluster_at(q, ctx, grid) };
        let found = found.map(|c| (c, self.tables_in(c, q, ctx, cache)));
        let Some((c, (tables, frame))) = found else {
            // outside valid clusters: one BSDF (cosine for Lambert) sample
            ctx.profile.cf.samples += 1;
            let u = ctx.rng.next_3d();
            let Some(bs) = bsdf::sample(m, sp, wo, u, Mode::Radiance) else { return Rgb::ZERO };
            // a mixed material's Dirac lobe is not L_c's integrand (spec §1)
            if bs.is_delta || bs.pdf_w <= 0.0 {
                return Rgb::ZERO;
            }
            return g(bs.wi, 1.0 / bs.pdf_w, ctx);
        };
        ctx.profile.cf.inside += 1;
        let s = self.split_for(c, q.depth);
        let mut samples = Vec::with_capacity(2 * s);
        tables.for_each_sample(s, &mut ctx.rng, |ts| samples.push(ts));
        ctx.profile.cf.samples += samples.len() as u64;
        // [BAJ08 §3.2] each table is sampled S times and the two estimates are added
        samples.iter().map(|ts| g(frame.to_world(ts.dir), ts.weight, ctx)).fold(Rgb::ZERO, |a, b| a + b)
    }

    /// Encodes for the broadcast.
    pub fn to_bytes(&self) -> Vec<u8> {
        bitcode::encode(self)
    }

    /// Decodes a broadcast product.
    pub fn from_bytes(b: &[u8]) -> Result<Self, String> {
        bitcode::decode(b).map_err(|e| format!("corrupt caustic-forecast product ({} bytes): {e}", b.len()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bsdf::ShadingPoint;
    use crate::progress::Hidden;
    use crate::sampling::rng::{stream, Rng};
    use crate::scene::Material;

    /// A 1 m² floor caustic lit from one side: one kept cluster.
    fn forecast() -> CausticForecast {
        let mut rng = Rng::keyed(7, stream::MISC, 0, 0);
        let pts: Vec<CausticPoint> = (0..4000)
            .map(|_| {
                let (a, b) = (rng.next_f32(), rng.next_f32());
                let wi = Vec3::new(0.3 * rng.next_f32(), 1.0, 0.2 * rng.next_f32()).normalize();
                CausticPoint::new(Vec3::new(a, 0.0, b), Vec3::Y, wi, Vec3::splat(1.0))
            })
            .collect();
        CausticForecast::build(pts, ForecastOptions::default(), 1, PreprocessStats::default(), &Hidden)
    }

    fn query<'a>(x: &'a ShadingPoint, m: &'a Material) -> ShadingQuery<'a> {
        ShadingQuery { x, m, wo: Vec3::Y, depth: 0 }
    }

    fn point(p: Vec3, ns: Vec3) -> ShadingPoint {
        ShadingPoint { p, ng: Vec3::Y, ns, n0: ns, s: Vec3::ZERO }
    }

    /// `guide_tables` is a pure function of (cluster, cell, normal bin): two smooth-shaded points
    /// of one cell whose normals share a bin get the same table (a cache hit) in the same frame,
    /// equal to what a fresh cache builds for either, in any order; another bin gets its own.
    #[test]
    fn guide_tables_are_a_pure_function_of_their_key() {
        let cf = forecast();
        let m = Material::Diffuse { albedo: Vec3::splat(0.5) };
        let base = Vec3::new(0.5, 0.0, 0.5);
        let mut ctx = Context::new(Rng::keyed(1, stream::MISC, 0, 0));
        let at_base = point(base, Vec3::Y);
        let c = cf.cluster_at(&query(&at_base, &m), &mut ctx, None).expect("a kept cluster");
        let edge = cf.cells.edge[c];
        let (cell, centre) = cell_of(base, edge);
        let (a, b) = (centre - Vec3::splat(0.2 * edge), centre + Vec3::splat(0.2 * edge));
        let (a, b) = (Vec3::new(a.x, 0.0, a.z), Vec3::new(b.x, 0.0, b.z));
        assert_eq!((cell_of(a, edge).0, cell_of(b, edge).0), (cell, cell));
        let (na, nb) = (Vec3::new(0.001, 1.0, 0.0).normalize(), Vec3::new(0.0, 1.0, 0.002).normalize());
        assert_eq!(normal_bin(na).0, normal_bin(nb).0);
        let tilted = Vec3::new(0.3, 1.0, 0.0).normalize();
        assert_ne!(normal_bin(tilted).0, normal_bin(na).0);
        let (spa, spb, spt) = (point(a, na), point(b, nb), point(a, tilted));
        let run = |order: &[&ShadingPoint]| {
            let (cache, mut ctx) = (TableCache::default(), Context::new(Rng::keyed(1, stream::MISC, 0, 0)));
            let out: Vec<_> = order.iter().map(|sp| cf.guide_tables(c, &query(sp, &m), &mut ctx, &cache)).collect();
            (out, ctx.profile.cf.tables_built, ctx.profile.cf.cache_hits)
        };
        let (ab, built, hits) = run(&[&spa, &spb, &spt]);
        assert_eq!((built, hits), (2, 1));
        assert!(Arc::ptr_eq(&ab[0].0, &ab[1].0));
        assert_eq!(ab[0].1.to_local(Vec3::Y), ab[1].1.to_local(Vec3::Y));
        assert!(ab[0].0.t1.is_some(), "the floor's tables hold its photons");
        let (ba, _, _) = run(&[&spt, &spb, &spa]);
        for (x, y) in [(&ab[0], &ba[2]), (&ab[1], &ba[1]), (&ab[2], &ba[0])] {
            assert_eq!(*x.0, *y.0, "a table depends on what was built before it");
            assert_eq!(x.1.to_local(Vec3::X), y.1.to_local(Vec3::X));
        }
        assert_ne!(*ab[0].0, *ab[2].0);
        // the frame is the bin centre's, not the point's normal
        assert_eq!(ab[0].1.to_local(normal_bin(na).1), Frame::from_normal(normal_bin(na).1).to_local(normal_bin(na).1));
    }
}
