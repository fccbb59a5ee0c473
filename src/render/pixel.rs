//! How one pixel sample is drawn: one jittered camera ray, or emission splitting
//! (`--emission-split K`) in the pixels where light sources have edges or images (beyond the
//! paper; the derivation and the tests: `docs/emission-split.md`).
//!
//! Estimator. In a split pixel a sample takes `K` camera rays and adds `E`, the emission each
//! sees along its Dirac prefix (`transport::dirac::prefix_emission`: the first hit, or a short
//! mirror/glass chain), to `L − E` of one of them, continued by the integrator
//! (`Integrator::estimate` returns `E` and `L − E` apart). Where the probe mapped the pixel
//! (`probe::CellMap`, density `q` per unit pixel area), the continued ray `r_0` is uniform over
//! the pixel, the other `K − 1` are drawn from `q` (stratified over its cumulative table), and
//! `L̂ = Σ_i E(r_i) / (1 + (K−1)·q(r_i)) + (L − E)(r_0)`: the balance heuristic of the two
//! techniques. Without a map (`PixelSampler::everywhere`, or a pixel the probe's time ran out
//! for) the `K` rays sit at N-rooks positions (ray `k` in column stratum `k` and row stratum
//! `rows[k]`, a uniform random permutation), `J` uniform of them is continued, and
//! `L̂ = (1/K)·Σ_k E(r_k) + (L − E)(r_J)`. Which pixels, and their maps: `probe`.
//!
//! Invariants: `L̂` is unbiased for any `K` and any map (the contract on `E` is
//! `transport::dirac`'s); the split set and the maps are pure functions of the scene, the camera,
//! the resolution and the cap (`probe`), never of the samples, so they cannot bias; `K = 1` draws
//! exactly the random numbers of the plain sampler and traces no probe.
//! Measurements: `results/CONCLUSIONS.md`, "Emission splitting and its probe".

use super::probe::{cell_maps, probe_edges, CellMap};
use super::Context;
use crate::accel::{Ray, World};
use crate::integrators::{CameraEstimate, Integrator};
use crate::interrupt::Stop;
use crate::math::Rgb;
use crate::profile::Phase;
use crate::sampling::qmc::SamplerKind;
use crate::sampling::rng::{stream, Rng};
use crate::scene::Camera;
use crate::transport::dirac::prefix_emission;
use crate::transport::particle::MAX_VERTICES;
use std::time::Instant;

/// The most camera rays per pixel sample (`--emission-split`), owned by the render settings.
pub use crate::integrators::settings::MAX_EMISSION_SPLIT;

/// What the probe found, for the JSON report.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct SplitStats {
    /// Camera rays per pixel sample in the split pixels (`--emission-split`).
    pub emission_split: u32,
    /// Pixels split (light-source edges found by the probe).
    pub split_pixels: u64,
    /// Their fraction of the image.
    pub split_fraction: f64,
    /// Wall seconds of the probe (before the first pass; on every rank).
    pub probe_s: f64,
    /// Whether the probe stopped at its share of the time box (or a signal) before the last
    /// band: the pixels of the bands not probed are not split (fewer split pixels, no bias).
    pub probe_stopped: bool,
}

/// Draws pixel samples: the camera, the split `K`, the Dirac-chain cap of the extra rays (the
/// integrator's) and the pixels to split.
#[derive(Clone, Debug)]
pub struct PixelSampler<'a> {
    camera: &'a Camera,
    k: u32,
    cap: u32,
    /// Row-major, one flag per pixel; empty when `k = 1`.
    split: Vec<bool>,
    /// The split pixels' maps, by pixel index (ascending); a split pixel without one is split
    /// uniformly (N-rooks).
    maps: Vec<(u64, CellMap)>,
    stats: SplitStats,
    /// The workers' contexts and buffers, kept from one call of `render::camera_tiles` to the
    /// next (capacity only): made afresh per call, their growth cost 5% of `pt`'s CPU time on
    /// `ring` in page faults (`results/2026-12-05-diffuse-lanes.md`).
    workers: Pool<Worker>,
    /// The tiles' sample buffers, kept from one call to the next as the workers are.
    outs: Pool<Vec<Rgb>>,
    /// Camera streams led by a scrambled Sobol prefix (`sampling::qmc`), or PCG alone.
    sobol: bool,
}

/// Values kept for reuse across calls; a clone of the sampler starts with none.
struct Pool<T>(std::sync::Mutex<Vec<T>>);

impl<T> Pool<T> {
    fn take(&self) -> Option<T> {
        self.0.lock().ok()?.pop()
    }
    fn put(&self, items: impl IntoIterator<Item = T>) {
        if let Ok(mut v) = self.0.lock() {
            v.extend(items);
        }
    }
}

impl<T> Default for Pool<T> {
    fn default() -> Self {
        Pool(std::sync::Mutex::new(Vec::new()))
    }
}

impl<T> Clone for Pool<T> {
    fn clone(&self) -> Self {
        Pool::default()
    }
}

impl<T> std::fmt::Debug for Pool<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Pool")
    }
}

/// A worker's context, tile buffers and pixel list (`render::camera_tiles`).
pub struct Worker {
    /// Its context (rng rekeyed per tile, profile taken per tile).
    pub ctx: Context,
    /// `sample_tile`'s buffers.
    pub buf: TileBuffers,
    /// The tile's pixels as (x, y, index).
    pub px: Vec<(usize, usize, u64)>,
}

/// The buffers of [`PixelSampler::sample_tile`], kept by a worker from one tile to the next
/// (capacity only).
#[derive(Default)]
pub struct TileBuffers {
    /// The camera streams' [`Rng::pass_key`] of each pass.
    keys: Vec<u64>,
    rays: Vec<Ray>,
    rngs: Vec<Rng>,
    slots: Vec<usize>,
    est: Vec<CameraEstimate>,
}

/// Passes whose camera rays `camera_lanes` draws at once.
const LANES: usize = 16;

/// The camera rays and streams of pixel `(x, y)` in the passes `passes` keyed by `keys` (at
/// most [`LANES`]), pass `j` in lane `j`, led by the Sobol prefix of seed `sobol` if any:
/// what one pass at a time draws (`Rng::indexed`, the prefix, the jitter, `Camera::direction`),
/// operation for operation. Without a prefix and for 4 passes or more, as loops over the lanes
/// that LLVM runs as vectors (`results/2026-12-05-diffuse-lanes.md`); otherwise one at a time
/// (a few passes, as in the IWS family's, or the prefix's jitter, drawn lane by lane anyway).
/// Not inlined, so that it stays vectorized.
#[inline(never)]
fn camera_lanes(
    cam: &Camera,
    (keys, passes, sobol): (&[u64], &[u64], Option<u64>),
    (x, y, pixel): (usize, usize, u64),
    rays: &mut Vec<Ray>,
    rngs: &mut Vec<Rng>,
) {
    let n = keys.len();
    if n < LANES / 4 || sobol.is_some() {
        for (&key, &pass) in keys.iter().zip(passes) {
            let mut rng = camera_stream(Rng::indexed(key, pixel), sobol, pass, pixel);
            let [jx, jy] = rng.next_2d();
            rays.push(Ray { o: cam.position, d: cam.direction(x as f32 + jx, y as f32 + jy), tmax: f32::INFINITY });
            rngs.push(rng);
        }
        return;
    }
    // lanes past n repeat the last key; only the first n are kept
    let keys: [u64; LANES] = std::array::from_fn(|j| keys[j.min(n - 1)]);
    let (st, u) = Rng::indexed_2d_lanes(&keys, pixel);
    let mut d = [crate::math::Vec3::ZERO; LANES];
    for j in 0..LANES {
        d[j] = cam.direction(x as f32 + u[j][0], y as f32 + u[j][1]);
    }
    rays.extend(d[..n].iter().map(|&d| Ray { o: cam.position, d, tmax: f32::INFINITY }));
    rngs.extend(st.into_iter().take(n));
}

/// Pass `pass`'s camera stream `pcg` of pixel `pixel`, led by its Sobol prefix under seed
/// `sobol` if any.
#[inline]
fn camera_stream(pcg: Rng, sobol: Option<u64>, pass: u64, pixel: u64) -> Rng {
    match sobol {
        Some(seed) => pcg.with_qmc(Rng::qmc_key(seed, pass, pixel), pass),
        None => pcg,
    }
}

impl<'a> PixelSampler<'a> {
    /// A kept worker, or `None` (the caller makes one).
    pub(crate) fn take_worker(&self) -> Option<Worker> {
        self.workers.take()
    }

    /// Keeps `w` for a later [`PixelSampler::take_worker`].
    pub(crate) fn put_worker(&self, w: Worker) {
        self.workers.put([w]);
    }

    /// An empty sample buffer, with the capacity of one given back before if any.
    pub(crate) fn take_out(&self) -> Vec<Rgb> {
        let mut v = self.outs.take().unwrap_or_default();
        v.clear();
        v
    }

    /// Keeps sample buffers for later [`PixelSampler::take_out`]s.
    pub(crate) fn put_outs(&self, outs: impl IntoIterator<Item = Vec<Rgb>>) {
        self.outs.put(outs);
    }

    /// One camera ray per pixel sample.
    pub fn plain(camera: &'a Camera) -> PixelSampler<'a> {
        let stats = SplitStats { emission_split: 1, ..SplitStats::default() };
        PixelSampler {
            camera,
            k: 1,
            cap: MAX_VERTICES,
            split: Vec::new(),
            maps: Vec::new(),
            stats,
            workers: Pool::default(),
            outs: Pool::default(),
            sobol: false,
        }
    }

    /// This sampler with the camera streams of `kind` (default [`SamplerKind::Independent`]).
    pub fn with_sampler(self, kind: SamplerKind) -> Self {
        PixelSampler { sobol: kind == SamplerKind::Sobol, ..self }
    }

    /// `k` rays per sample (clamped to 1..=[`MAX_EMISSION_SPLIT`]) in the pixels where the probe
    /// finds a light-source edge; `cap` bounds the extra rays' Dirac chains and must be the
    /// integrator's `Integrator::prefix_cap`. Runs the probe on the current rayon pool.
    pub fn new(world: &World, camera: &'a Camera, k: u32, cap: u32) -> PixelSampler<'a> {
        PixelSampler::new_until(world, camera, k, cap, &Stop::never())
    }

    /// [`PixelSampler::new`] whose probe ends at `stop` (its share of a time box, or a signal):
    /// the bands not probed by then are not split (`SplitStats::probe_stopped`).
    pub fn new_until(world: &World, camera: &'a Camera, k: u32, cap: u32, stop: &Stop) -> PixelSampler<'a> {
        let k = k.clamp(1, MAX_EMISSION_SPLIT);
        if k == 1 {
            return PixelSampler { cap, ..PixelSampler::plain(camera) };
        }
        let t0 = Instant::now();
        let (split, probe_stopped) = probe_edges(world, camera, cap, stop);
        let maps = cell_maps(world, camera, cap, &split, stop);
        let n = split.iter().filter(|&&s| s).count() as u64;
        let stats = SplitStats {
            emission_split: k,
            split_pixels: n,
            split_fraction: n as f64 / split.len().max(1) as f64,
            probe_s: t0.elapsed().as_secs_f64(),
            probe_stopped,
        };
        PixelSampler {
            camera,
            k,
            cap,
            split,
            maps,
            stats,
            workers: Pool::default(),
            outs: Pool::default(),
            sobol: false,
        }
    }

    /// `k` rays per sample in every pixel, no probe (tests and ablations: the estimator must be
    /// unbiased in any pixel, not only at edges).
    pub fn everywhere(camera: &'a Camera, k: u32, cap: u32) -> PixelSampler<'a> {
        let k = k.clamp(1, MAX_EMISSION_SPLIT);
        let n = camera.width as u64 * camera.height as u64;
        let stats = SplitStats { emission_split: k, split_pixels: n, split_fraction: 1.0, ..SplitStats::default() };
        PixelSampler {
            camera,
            k,
            cap,
            split: vec![true; n as usize],
            maps: Vec::new(),
            stats,
            workers: Pool::default(),
            outs: Pool::default(),
            sobol: false,
        }
    }

    /// The image size, `(width, height)`.
    pub fn resolution(&self) -> (u32, u32) {
        (self.camera.width, self.camera.height)
    }

    /// The camera.
    pub fn camera(&self) -> &Camera {
        self.camera
    }

    /// What the probe found.
    pub fn stats(&self) -> SplitStats {
        self.stats
    }

    /// One sample of each pixel of `tile` (`(x, y, row-major index)`, in order) for each pass of
    /// `passes` into `out`, pixel-major: `out[k·G + j]` is pixel `k`'s sample of `passes[j]`
    /// (`G = passes.len()`). Pixel `p` of pass `q` draws from its camera stream keyed by
    /// (`seed`, `q`, `p`) alone, so a sample does not depend on which passes share the call. The unsplit samples' camera rays go to the integrator as one
    /// batch ([`Integrator::estimate_batch`]), a pixel's samples side by side (coherent camera
    /// rays for the tracer); the split ones go one by one.
    pub(crate) fn sample_tile(
        &self,
        (world, integrator): (&World, &dyn Integrator),
        tile: &[(usize, usize, u64)],
        (seed, passes): (u64, &[u64]),
        (ctx, buf): (&mut Context, &mut TileBuffers),
        out: &mut Vec<Rgb>,
    ) {
        let cam = self.camera;
        let TileBuffers { keys, rays, rngs, slots, est } = buf;
        rays.clear();
        rngs.clear();
        slots.clear();
        out.clear();
        keys.clear();
        keys.extend(passes.iter().map(|&q| Rng::pass_key(seed, stream::CAMERA, q)));
        let sobol = self.sobol.then_some(seed);
        for &(x, y, pixel) in tile {
            if self.k == 1 || !self.split[pixel as usize] {
                for (keys, passes) in keys.chunks(LANES).zip(passes.chunks(LANES)) {
                    camera_lanes(cam, (keys, passes, sobol), (x, y, pixel), rays, rngs);
                }
                slots.extend(out.len()..out.len() + keys.len());
                out.resize(out.len() + keys.len(), Rgb::ZERO);
                continue;
            }
            for (&pass, &key) in passes.iter().zip(keys.iter()) {
                let mut rng = camera_stream(Rng::indexed(key, pixel), sobol, pass, pixel);
                let [jx, jy] = rng.next_2d();
                ctx.rng = rng;
                let key = (seed, pass);
                out.push(self.split_sample(world, integrator, (x, y, pixel), key, [jx, jy], ctx));
            }
        }
        integrator.estimate_batch(world, rays, rngs, ctx, est);
        for (&slot, e) in slots.iter().zip(est.iter()) {
            out[slot] = e.total();
        }
    }

    /// The sample of a split pixel, its jitter `[jx, jy]` already drawn from `ctx.rng`.
    fn split_sample(
        &self,
        world: &World,
        integrator: &dyn Integrator,
        (x, y, pixel): (usize, usize, u64),
        key: (u64, u64),
        [jx, jy]: [f32; 2],
        ctx: &mut Context,
    ) -> Rgb {
        let cam = self.camera;
        let k = self.k as usize;
        let mut rng = Rng::keyed(key.0, stream::PIXEL_SPLIT, key.1, pixel);
        if let Ok(i) = self.maps.binary_search_by_key(&pixel, |m| m.0) {
            let map = &self.maps[i].1;
            let at = |[u, v]: [f32; 2]| cam.direction(x as f32 + u, y as f32 + v);
            let n = (k - 1) as f32;
            let weight = |uv: [f32; 2]| 1.0 / (1.0 + n * map.pdf(uv));
            let est = integrator.estimate(world, cam.position, at([jx, jy]), ctx);
            let t0 = ctx.profile.start(Phase::EmissionSplit);
            let mut e = est.prefix_le * weight([jx, jy]);
            for i in 0..k - 1 {
                let u = (i as f32 + rng.next_f32()) / n;
                let uv = map.sample(u, rng.next_2d());
                e += prefix_emission(world, cam.position, at(uv), self.cap, &mut rng) * weight(uv);
            }
            ctx.profile.record(Phase::EmissionSplit, t0);
            return e + est.rest;
        }
        let mut rows = [0u8; MAX_EMISSION_SPLIT as usize];
        for i in 0..k {
            // inside-out Fisher–Yates: a uniform permutation of 0..k
            let j = rng.below(i as u32 + 1) as usize;
            rows[i] = rows[j];
            rows[j] = i as u8;
        }
        let kf = k as f32;
        let at = |i: usize, [u, v]: [f32; 2]| {
            cam.direction(x as f32 + (i as f32 + u) / kf, y as f32 + (rows[i] as f32 + v) / kf)
        };
        let chosen = rng.below(k as u32) as usize;
        let est = integrator.estimate(world, cam.position, at(chosen, [jx, jy]), ctx);
        let t0 = ctx.profile.start(Phase::EmissionSplit);
        let mut e = est.prefix_le;
        for i in (0..k).filter(|&i| i != chosen) {
            e += prefix_emission(world, cam.position, at(i, rng.next_2d()), self.cap, &mut rng);
        }
        ctx.profile.record(Phase::EmissionSplit, t0);
        e * (1.0 / kf) + est.rest
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec3;

    /// `camera_lanes` gives, for 1 to 16 passes (both of its paths) and both samplers, the rays
    /// and streams of one pass at a time (`Rng::indexed`, the Sobol prefix if any, the jitter,
    /// `Camera::direction`), as bits, and streams that go on alike.
    #[test]
    fn camera_lanes_are_one_pass_at_a_time() {
        let cam = Camera::new(Vec3::new(0.3, 1.0, 4.0), Vec3::ZERO, Vec3::Y, 40.0, 64, 48);
        let bits = |v: Vec3| v.to_array().map(f32::to_bits);
        for n in [1usize, 3, 4, 5, 16] {
            let keys: Vec<u64> = (0..n as u64).map(|q| Rng::pass_key(11, stream::CAMERA, q)).collect();
            let passes: Vec<u64> = (0..n as u64).collect();
            for ((x, y), sobol) in [(0usize, 0usize), (17, 9), (63, 47)].into_iter().zip([None, Some(11), Some(12)]) {
                let pixel = (y * 64 + x) as u64;
                let (mut rays, mut rngs) = (Vec::new(), Vec::new());
                camera_lanes(&cam, (&keys, &passes, sobol), (x, y, pixel), &mut rays, &mut rngs);
                assert_eq!((rays.len(), rngs.len()), (n, n));
                for (j, &key) in keys.iter().enumerate() {
                    let mut rng = Rng::indexed(key, pixel);
                    if let Some(seed) = sobol {
                        rng = rng.with_qmc(Rng::qmc_key(seed, j as u64, pixel), j as u64);
                    }
                    let [jx, jy] = rng.next_2d();
                    let d = cam.direction(x as f32 + jx, y as f32 + jy);
                    assert_eq!(bits(rays[j].d), bits(d), "{n} passes, pixel {pixel}, lane {j}");
                    assert_eq!(bits(rays[j].o), bits(cam.position));
                    assert_eq!(rngs[j].next_u32(), rng.next_u32(), "{n} passes, pixel {pixel}, lane {j}");
                    assert_eq!(rngs[j].next_2d(), rng.next_2d(), "{n} passes, pixel {pixel}, lane {j}");
                }
            }
        }
    }
}
