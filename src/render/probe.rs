//! The emission-split probe: which pixels `--emission-split` splits, and where in each of them
//! its extra rays go (`docs/emission-split.md`).
//!
//! Which pixels. The probe traces the prefix emission `E` (`transport::dirac::prefix_emission`)
//! on a lattice of `m` intervals per pixel side (`(mW+1)×(mH+1)` points, from a fixed stream, band
//! by band; `m` from [`probe_subdivision`]); a point whose prefix meets a mirror or glass is
//! traced [`PROBE_CHAINS`] times (the light seen through glass along some Fresnel choices only).
//! A pixel is split where the luminance of `E` over its `(m+1)²` points and their chains has a
//! standard deviation of at least [`SPLIT_SIGMA`] of the brightest emitter's: the coin toss that
//! splitting averages, weighed against the light that rules the scene. The probe traces each
//! distinct ray of a lattice point once (its chains repeat the camera ray and mostly the same
//! choices: `transport::dirac::RayMemo`, per thread), the same values bit for bit.
//!
//! Where in the pixel. In each split pixel a finer lattice of [`SUB`] cells per side (its
//! `(SUB+1)²` corners traced as above) gives each cell the root mean square of `E` at its
//! brightest corner; the pixel's [`CellMap`] is the distribution over cells proportional to
//! it, mixed with the uniform one ([`DEFENSIVE`]). The sampler draws its extra rays from it
//! (`pixel`), weighted by the balance heuristic against the uniformly placed ray that carries
//! the rest of the estimate, so any map is unbiased; a good one puts the rays on a light image
//! far smaller than the pixel.
//!
//! Invariants: the split set and the maps are pure functions of the scene, the camera, the
//! resolution and the cap (and, when the probe runs against a time box's share, of how far it
//! got: the bands not probed are not split, the pixels not mapped are split uniformly), never
//! of the samples, so they cannot bias.

use crate::accel::World;
use crate::interrupt::Stop;
use crate::math::luminance;
use crate::sampling::rng::{stream, Rng};
use crate::scene::{Camera, EnvMap};
use crate::transport::dirac::{prefix_emission_with, RayMemo, Tracer};
use rayon::prelude::*;

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
pub fn probe_edges(world: &World, camera: &Camera, cap: u32, stop: &Stop) -> (Vec<bool>, bool) {
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

/// Cells per side of a split pixel's [`CellMap`].
pub const SUB: usize = 16;

/// The uniform distribution's share of a [`CellMap`]: light the map's corners did not see still
/// gets rays, and a map that points the rays away from the light costs at most `1/DEFENSIVE` of
/// the uniform rays' variance (a quarter of the rays, measured, cost 2× on `sms-sphere` once).
pub const DEFENSIVE: f32 = 0.5;

/// Where a split pixel's extra rays go: a distribution over its `SUB`×`SUB` cells (row-major
/// from the pixel's top-left), as a cumulative table, `cdf[SUB²−1] = 1`.
#[derive(Clone, Debug, PartialEq)]
pub struct CellMap {
    cdf: [f32; SUB * SUB],
}

impl CellMap {
    /// The map of cell weights `w` (≥ 0), mixed with the uniform one by [`DEFENSIVE`].
    fn from_weights(w: &[f32; SUB * SUB]) -> CellMap {
        let total: f32 = w.iter().sum();
        let n = (SUB * SUB) as f32;
        let (a, b) = if total > 0.0 { (DEFENSIVE / n, (1.0 - DEFENSIVE) / total) } else { (1.0 / n, 0.0) };
        let mut cdf = [0.0; SUB * SUB];
        let mut acc = 0.0;
        for (c, &wc) in cdf.iter_mut().zip(w) {
            acc += a + b * wc;
            *c = acc;
        }
        cdf[SUB * SUB - 1] = 1.0;
        CellMap { cdf }
    }

    /// The probability of cell `c`.
    fn pmf(&self, c: usize) -> f32 {
        self.cdf[c] - if c == 0 { 0.0 } else { self.cdf[c - 1] }
    }

    /// The density at pixel-relative point `[u, v]` ∈ [0, 1)², per unit pixel area (1 for the
    /// uniform map).
    pub fn pdf(&self, [u, v]: [f32; 2]) -> f32 {
        let cell = |t: f32| ((t * SUB as f32) as usize).min(SUB - 1);
        self.pmf(cell(v) * SUB + cell(u)) * (SUB * SUB) as f32
    }

    /// The point of `u` ∈ [0, 1) in the cells' order, uniform within its cell by `[a, b]`:
    /// pixel-relative `[u, v]` ∈ [0, 1)².
    pub fn sample(&self, u: f32, [a, b]: [f32; 2]) -> [f32; 2] {
        let c = self.cdf.partition_point(|&f| f <= u).min(SUB * SUB - 1);
        let s = SUB as f32;
        let at = |i: usize, t: f32| ((i as f32 + t) / s).min(1.0 - f32::EPSILON / 2.0);
        [at(c % SUB, a), at(c / SUB, b)]
    }
}

/// `(pixel, map)` for each split pixel (`split[p]`), ascending: its [`CellMap`] from a finer
/// lattice of its `(SUB+1)²` corners traced as the probe's points ([`probe_point`], streams keyed
/// by pixel and corner). The pixels left when `stop` came due get none (split uniformly).
pub fn cell_maps(world: &World, camera: &Camera, cap: u32, split: &[bool], stop: &Stop) -> Vec<(u64, CellMap)> {
    let w = camera.width as usize;
    let n = SUB + 1;
    let pixels: Vec<usize> = split.iter().enumerate().filter_map(|(p, &s)| s.then_some(p)).collect();
    pixels
        .into_par_iter()
        .map_init(RayMemo::default, |memo, p| {
            if stop.is_due() {
                return None;
            }
            let (x, y) = ((p % w) as f32, (p / w) as f32);
            let rms: Vec<f32> = (0..n * n)
                .map(|j| {
                    let mut rng = Rng::keyed(0, stream::PIXEL_SPLIT, u64::MAX - 1, (p * n * n + j) as u64);
                    let (u, v) = (x + (j % n) as f32 / SUB as f32, y + (j / n) as f32 / SUB as f32);
                    probe_point(world, camera, [u, v], cap, &mut rng, memo).m2.sqrt() as f32
                })
                .collect();
            let mut wts = [0.0; SUB * SUB];
            for (c, wc) in wts.iter_mut().enumerate() {
                let (i, j) = (c % SUB, c / SUB);
                *wc = [rms[j * n + i], rms[j * n + i + 1], rms[(j + 1) * n + i], rms[(j + 1) * n + i + 1]]
                    .into_iter()
                    .fold(0.0, f32::max);
            }
            Some((p as u64, CellMap::from_weights(&wts)))
        })
        .flatten()
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

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

    /// A map's cells' probabilities sum to one, its density integrates to one over the pixel,
    /// and its draws land in the cell their `u` names: the sampler's weights rely on `pdf` being
    /// the density of `sample`.
    #[test]
    fn cell_map_sample_has_density_pdf() {
        let mut w = [0.0f32; SUB * SUB];
        (w[9], w[10], w[63]) = (4.0, 1.0, 0.5);
        for map in [CellMap::from_weights(&[0.0; SUB * SUB]), CellMap::from_weights(&w)] {
            assert!((1..SUB * SUB).all(|c| map.cdf[c] >= map.cdf[c - 1]));
            let total: f32 = (0..SUB * SUB).map(|c| map.pmf(c)).sum();
            assert!((total - 1.0).abs() < 1e-5);
            // χ²-free check: the histogram of 64k stratified draws over the cells equals the pmf
            let n = 1 << 16;
            let mut hist = [0u32; SUB * SUB];
            for i in 0..n {
                let u = (i as f32 + 0.5) / n as f32;
                let [x, y] = map.sample(u, [0.37, 0.81]);
                assert!((0.0..1.0).contains(&x) && (0.0..1.0).contains(&y));
                let c = ((y * SUB as f32) as usize) * SUB + (x * SUB as f32) as usize;
                hist[c] += 1;
                assert!((map.pdf([x, y]) - map.pmf(c) * (SUB * SUB) as f32).abs() < 1e-6);
            }
            for (c, &count) in hist.iter().enumerate() {
                assert!((count as f32 / n as f32 - map.pmf(c)).abs() <= 2.0 / n as f32, "cell {c}");
            }
        }
    }
}
