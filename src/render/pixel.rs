//! How one pixel sample is drawn: one jittered camera ray, or emission splitting
//! (`--emission-split K`) in the pixels where light sources have edges (beyond the paper; the
//! derivation and the tests: `docs/emission-split.md`).
//!
//! Estimator. In a split pixel a sample is `L̂ = (1/K)·Σ_k E(r_k) + (L − E)(r_J)`: `K` camera rays
//! `r_k` at N-rooks positions in the pixel (ray `k` in column stratum `k` and row stratum
//! `rows[k]`, a uniform random permutation), each contributing `E`, the emission seen along its
//! Dirac prefix (`transport::dirac::prefix_emission`: the first hit, or a short mirror/glass
//! chain), and one of them, `J` uniform, continued by the integrator for everything else
//! (`Integrator::estimate` returns `E` and `L − E` apart).
//!
//! Which pixels. A probe traces the prefix emission on a lattice of `m` intervals per pixel side
//! (`(mW+1)×(mH+1)` points, from a fixed stream, band by band; `m` from [`probe_subdivision`])
//! (a point whose prefix meets a mirror or glass [`PROBE_CHAINS`] times: the light seen through
//! glass along some Fresnel choices only) and splits exactly the pixels where the prefix
//! emission's luminance, over the pixel's `(m+1)²` points and their chains, has a standard
//! deviation of at least [`SPLIT_SIGMA`] of the brightest emitter's: the coin toss that splitting
//! averages. Where it is smaller (the sky's reflections in water beside a sun a million times
//! brighter) the `K − 1` extra prefixes cost more than the variance they remove.
//! The probe traces each distinct ray of a lattice point once (its chains repeat the camera ray
//! and mostly the same choices: `transport::dirac::RayMemo`, per thread), the same values bit
//! for bit.
//!
//! Invariants: `L̂` is unbiased for any `K` (the contract on `E` is `transport::dirac`'s); the
//! split set is a pure function of the scene, the camera, the resolution and the cap (and, when
//! the probe runs against a time box's share, of how many bands it finished: the rest are not
//! split), never of the samples, so it cannot bias (a pixel it misses, an edge thinner than `1/m` pixel, is merely
//! not split); `K = 1` draws exactly the random numbers of the plain sampler and traces no probe.
//! Measurements: `results/CONCLUSIONS.md`, "Emission splitting and its probe".

use super::Context;
use crate::accel::{Ray, World};
use crate::integrators::{CameraEstimate, Integrator};
use crate::interrupt::Stop;
use crate::math::{luminance, Rgb};
use crate::profile::Phase;
use crate::sampling::qmc::SamplerKind;
use crate::sampling::rng::{stream, Rng};
use crate::scene::{Camera, EnvMap};
use crate::transport::dirac::{prefix_emission, prefix_emission_with, RayMemo, Tracer};
use crate::transport::particle::MAX_VERTICES;
use rayon::prelude::*;
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
        let n = split.iter().filter(|&&s| s).count() as u64;
        let stats = SplitStats {
            emission_split: k,
            split_pixels: n,
            split_fraction: n as f64 / split.len().max(1) as f64,
            probe_s: t0.elapsed().as_secs_f64(),
            probe_stopped,
        };
        PixelSampler { camera, k, cap, split, stats, workers: Pool::default(), outs: Pool::default(), sobol: false }
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

/// Pixel rows per probe band (bounds the probe's memory to about m²·W·BAND colours).
const PROBE_BAND: usize = 64;

/// Chains traced at a lattice point whose prefix meets a mirror or glass.
pub const PROBE_CHAINS: usize = 16;

/// The luminance of the prefix emission at a lattice point: its mean and mean square over the
/// point's chains. A prefix that meets a Dirac vertex draws numbers (its Fresnel choices) and is
/// traced [`PROBE_CHAINS`] times from the same stream (the light seen through glass along some
/// choices only); a prefix that draws nothing is certain, one chain.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Moments {
    m1: f64,
    m2: f64,
}

/// A lattice point's [`Moments`]. Its chains repeat one camera ray and mostly the same choices:
/// `memo` (cleared here) traces each distinct ray once and shades each hit once: the same values
/// bit for bit.
fn probe_point(
    world: &World,
    camera: &Camera,
    [u, v]: [f32; 2],
    cap: u32,
    rng: &mut Rng,
    memo: &mut RayMemo,
) -> Moments {
    memo.clear();
    probe_point_with(world, camera, [u, v], cap, rng, memo)
}

/// [`probe_point`] through any [`Tracer`] (`Direct`: the reference its memo is tested against).
fn probe_point_with<T: Tracer>(
    world: &World,
    camera: &Camera,
    [u, v]: [f32; 2],
    cap: u32,
    rng: &mut Rng,
    tracer: &mut T,
) -> Moments {
    let d = camera.direction(u, v);
    let before = rng.clone();
    let mut y = luminance(prefix_emission_with(world, tracer, camera.position, d, cap, rng)) as f64;
    if *rng == before {
        return Moments { m1: y, m2: y * y };
    }
    let mut sum = Moments::default();
    for chain in 0..PROBE_CHAINS {
        if chain > 0 {
            y = luminance(prefix_emission_with(world, tracer, camera.position, d, cap, rng)) as f64;
        }
        sum.m1 += y;
        sum.m2 += y * y;
    }
    let n = PROBE_CHAINS as f64;
    Moments { m1: sum.m1 / n, m2: sum.m2 / n }
}

/// A pixel is split where the standard deviation of its prefix emission's luminance (over the
/// pixel's area and the chains' choices) is at least this fraction of the brightest emitter's
/// luminance ([`brightest_emission`]).
pub const SPLIT_SIGMA: f64 = 1e-3;

/// The luminance of the brightest radiance a camera prefix can see: the area emitters' and the
/// environment's largest texel (0 without either: nothing is split).
fn brightest_emission(world: &World) -> f64 {
    let s = &world.scene;
    let area = s.emitters.iter().map(|e| luminance(e.radiance)).fold(0.0f32, f32::max);
    let env = s.environment.as_ref().map_or(0.0, |e| match &e.map {
        EnvMap::Constant(c) => luminance(*c),
        EnvMap::LatLong(m) => m.texels.iter().map(|t| luminance(t.rgb)).fold(0.0, f32::max),
    });
    area.max(env) as f64
}

/// Lattice intervals across the image's wider side at least (the probe's angular resolution):
/// a glint is found at any resolution where it was found at 640 pixels across.
const PROBE_ACROSS: usize = 1280;

/// The most lattice intervals per pixel side (bounds the probe's cost at tiny resolutions).
const PROBE_MAX_SUBDIVISION: usize = 8;

/// Lattice intervals per pixel side for a `w`×`h` image: 2 (corners, edge midpoints and centre)
/// from 640 pixels across up, more below, so that the lattice keeps [`PROBE_ACROSS`] intervals.
pub fn probe_subdivision(w: u32, h: u32) -> usize {
    PROBE_ACROSS.div_ceil(w.max(h).max(1) as usize).clamp(2, PROBE_MAX_SUBDIVISION)
}

/// The pixels whose prefix emission's luminance varies over the pixel: its variance over the
/// pixel's `(m+1)²` lattice points (`m` = [`probe_subdivision`]) and their chains
/// ([`probe_point`]) at least ([`SPLIT_SIGMA`] × [`brightest_emission`])², from a fixed stream
/// keyed by the lattice index: a pure function of scene, camera, resolution and cap, unless
/// `stop` comes first (checked at every lattice point): then the band in flight and those after
/// it are not split, and the flag returned is `true`. Band by band, so the lattice never needs to
/// be held whole.
fn probe_edges(world: &World, camera: &Camera, cap: u32, stop: &Stop) -> (Vec<bool>, bool) {
    use std::sync::atomic::{AtomicBool, Ordering};
    let (w, h) = (camera.width as usize, camera.height as usize);
    let m = probe_subdivision(camera.width, camera.height);
    let (lw, step) = (m * w + 1, 1.0 / m as f32);
    let floor = (SPLIT_SIGMA * brightest_emission(world)).powi(2);
    let mut split = Vec::with_capacity(w * h);
    let cut = AtomicBool::new(false);
    let mut lattice: Vec<Moments> = Vec::new();
    for y0 in (0..h).step_by(PROBE_BAND) {
        let y1 = (y0 + PROBE_BAND).min(h);
        // lattice rows m·y0 ..= m·y1; row m·y0 is the band before's last (kept, not traced again)
        let base = m * y0 * lw;
        let kept = if y0 == 0 { 0 } else { lw };
        let mut rows: Vec<Moments> = Vec::with_capacity((m * (y1 - y0) + 1) * lw);
        rows.extend_from_slice(&lattice[lattice.len() - kept..]);
        rows.par_extend((base + kept..(m * y1 + 1) * lw).into_par_iter().map_init(RayMemo::default, |memo, i| {
            if cut.load(Ordering::Relaxed) || stop.is_due() {
                cut.store(true, Ordering::Relaxed);
                return Moments::default();
            }
            let (u, v) = ((i % lw) as f32 * step, (i / lw) as f32 * step);
            let mut rng = Rng::keyed(0, stream::PIXEL_SPLIT, u64::MAX, i as u64);
            probe_point(world, camera, [u, v], cap, &mut rng, memo)
        }));
        lattice = rows;
        if cut.load(Ordering::Relaxed) {
            split.resize(w * h, false);
            return (split, true);
        }
        let band = (y0 * w..y1 * w).into_par_iter().map(|p| {
            let (x, y) = (m * (p % w), m * (p / w - y0));
            let n = ((m + 1) * (m + 1)) as f64;
            let sum = (0..(m + 1) * (m + 1)).fold(Moments::default(), |a, j| {
                let q = lattice[(y + j / (m + 1)) * lw + x + j % (m + 1)];
                Moments { m1: a.m1 + q.m1, m2: a.m2 + q.m2 }
            });
            let (m1, m2) = (sum.m1 / n, sum.m2 / n);
            m2 - m1 * m1 >= floor && m2 > m1 * m1
        });
        split.par_extend(band);
    }
    (split, false)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec3;

    /// Half-pixel steps from 640 pixels across up (the probe of before, unchanged there); below,
    /// at least `PROBE_ACROSS` intervals across the wider side, up to 8 per pixel.
    #[test]
    fn probe_subdivision_keeps_the_lattice_s_angular_resolution() {
        let cases = [((640, 360), 2), ((640, 640), 2), ((1920, 1080), 2), ((360, 640), 2), ((639, 10), 3)];
        let low = [((256, 256), 5), ((256, 144), 5), ((256, 192), 5), ((85, 48), 8), ((16, 16), 8), ((1, 1), 8)];
        for ((w, h), m) in cases.into_iter().chain(low) {
            assert_eq!(probe_subdivision(w, h), m, "{w}x{h}");
            assert!(m == PROBE_MAX_SUBDIVISION || m * w.max(h) as usize >= PROBE_ACROSS, "{w}x{h}");
        }
    }

    /// A glass sphere with a light behind it (`tests/emission_split.rs`'s), and a mirror.
    const LIGHT_IN_GLASS: &str = r#"
[camera]
position   = [0.0, 0.0, 3.0]
look_at    = [0.0, 0.0, 0.0]
fov        = 40.0
resolution = [16, 16]

[materials.glass]
type = "glass"
ior  = 1.5

[materials.mirror]
type = "mirror"
reflectance = [0.9, 0.9, 0.9]

[[shape]]
type     = "sphere"
center   = [0.0, 0.0, 0.0]
radius   = 0.8
material = "glass"

[[shape]]
type     = "sphere"
center   = [0.9, 0.7, -0.5]
radius   = 0.3
material = "mirror"

[[shape]]
type     = "quad"
corner   = [-4.0, 4.0, 5.0]
u        = [8.0, 0.0, 0.0]
v        = [0.0, -8.0, 0.0]
emission = [1.0, 1.0, 1.0]
"#;

    /// The memoized probe gives every lattice point's value bit for bit as the plain chain
    /// follower (`Direct`, the same random numbers), tracing fewer rays; and `probe_edges` (bands
    /// of 64 rows, the shared row kept) splits exactly the pixels the plain lattice, held whole,
    /// says. 8×130 pixels: three bands, `m` = 8.
    #[test]
    fn memoized_probe_is_the_plain_probe_bit_for_bit() {
        use crate::accel::take_ray_counts;
        use crate::transport::dirac::Direct;
        let world =
            World::build(crate::scene::load_str(LIGHT_IN_GLASS, "glass.toml", std::path::Path::new(".")).unwrap())
                .unwrap();
        let (w, h) = (8usize, 130usize);
        let camera = world.scene.camera.with_resolution(w as u32, h as u32);
        let cap = 64;
        let m = probe_subdivision(w as u32, h as u32);
        let (lw, step) = (m * w + 1, 1.0 / m as f32);
        let bits = |q: Moments| [q.m1.to_bits(), q.m2.to_bits()];
        let mut memo = RayMemo::default();
        let (mut plain_rays, mut memo_rays, mut random, mut chained) = (0, 0, 0, 0);
        let mut lattice = Vec::new();
        for i in 0..lw * (m * h + 1) {
            let uv = [(i % lw) as f32 * step, (i / lw) as f32 * step];
            let key = |i: usize| Rng::keyed(0, stream::PIXEL_SPLIT, u64::MAX, i as u64);
            let _ = take_ray_counts();
            let (mut a, mut b) = (key(i), key(i));
            let plain = probe_point_with(&world, &camera, uv, cap, &mut a, &mut Direct);
            let n = take_ray_counts().0;
            let memoized = probe_point(&world, &camera, uv, cap, &mut b, &mut memo);
            let k = take_ray_counts().0;
            assert_eq!(bits(plain), bits(memoized), "lattice point {i}");
            assert!(a == b, "lattice point {i}: the streams went on alike");
            (plain_rays, memo_rays) = (plain_rays + n, memo_rays + k);
            random += (plain.m2 > plain.m1 * plain.m1) as usize;
            chained += (n > 1) as usize;
            lattice.push(plain);
        }
        eprintln!("{chained} chained points, {random} random: {plain_rays} rays plain, {memo_rays} memoized");
        assert!(random > 0 && chained > random, "the scene must have random and chained points");
        assert!(memo_rays * 4 < plain_rays, "{memo_rays} rays memoized vs {plain_rays}");
        let floor = (SPLIT_SIGMA * brightest_emission(&world)).powi(2);
        let expected: Vec<bool> = (0..w * h)
            .map(|p| {
                let (x, y) = (m * (p % w), m * (p / w));
                let n = ((m + 1) * (m + 1)) as f64;
                let sum = (0..(m + 1) * (m + 1)).fold(Moments::default(), |a, j| {
                    let q: Moments = lattice[(y + j / (m + 1)) * lw + x + j % (m + 1)];
                    Moments { m1: a.m1 + q.m1, m2: a.m2 + q.m2 }
                });
                let (m1, m2) = (sum.m1 / n, sum.m2 / n);
                m2 - m1 * m1 >= floor && m2 > m1 * m1
            })
            .collect();
        let (split, stopped) = probe_edges(&world, &camera, cap, &Stop::never());
        assert!(!stopped);
        assert!(expected.iter().any(|&s| s) && expected.iter().any(|&s| !s));
        assert_eq!(split, expected);
    }

    /// The rays the probe traces on the benchmark scenes, plain (every chain traced whole, the
    /// shared band rows twice) and memoized, with `pt`'s cap (the scene's `max_depth` + 1), all
    /// on one thread (`results/2026-12-08-probe-chains.md`; slow with the plain count: ignored).
    #[test]
    #[ignore]
    fn probe_ray_counts_on_the_benchmark_scenes() {
        use crate::accel::take_ray_counts;
        use crate::transport::dirac::Direct;
        let scenes = [
            ("scenes/ring.toml", 256, 256),
            ("scenes/external/sms-pool/scene.xml", 384, 216),
            ("scenes/figurines.toml", 640, 360),
            ("scenes/cornell-box.toml", 640, 640),
        ];
        for (path, w, h) in scenes {
            let world = World::build(crate::scene::load(std::path::Path::new(path)).unwrap()).unwrap();
            let camera = world.scene.camera.with_resolution(w, h);
            let cap = world.scene.render.max_depth.saturating_add(1);
            let m = probe_subdivision(w, h);
            let (lw, lh, step) = (m * w as usize + 1, m * h as usize + 1, 1.0 / m as f32);
            let shared_rows = (h as usize).div_ceil(PROBE_BAND) - 1;
            let (mut plain, mut memoized, mut chained) = (0u64, 0u64, 0u64);
            let mut memo = RayMemo::default();
            for i in 0..lw * lh {
                let uv = [(i % lw) as f32 * step, (i / lw) as f32 * step];
                let key = || Rng::keyed(0, stream::PIXEL_SPLIT, u64::MAX, i as u64);
                let _ = take_ray_counts();
                probe_point_with(&world, &camera, uv, cap, &mut key(), &mut Direct);
                let n = take_ray_counts().0;
                probe_point(&world, &camera, uv, cap, &mut key(), &mut memo);
                let k = take_ray_counts().0;
                let twice = (i / lw) % (m * PROBE_BAND) == 0 && i / lw > 0 && i / lw < lh - 1;
                plain += n * (1 + twice as u64);
                memoized += k;
                chained += (n > 1) as u64;
            }
            eprintln!(
                "{path} {w}x{h} m={m}: {} lattice points ({} rows twice before), {chained} chained; \
                 rays: {plain} plain, {memoized} memoized ({:.2}x fewer)",
                lw * lh,
                shared_rows,
                plain as f64 / memoized as f64
            );
        }
    }

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
