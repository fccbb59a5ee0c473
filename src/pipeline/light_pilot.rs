//! `pt-cf`'s light paths per pass unless `--light-paths` is given (issue #34): a pilot render on
//! rank 0, after the CF preprocess, measures variance × cost region by region at a few counts
//! per pixel and keeps the count whose regions are the most efficient together.
//!
//! Why measured, not modelled. A pass's value of a pixel is its camera estimate plus the
//! pass's light splats there, so one could split its variance into the two sides' and let the
//! light side's fall as `1/ν`. That model picked 0.08–0.3 paths per pixel on the four measured
//! scenes, where the equal-time sweep of 2026-12-03 (before the per-object cones) found 1–2
//! best: more light paths also take a larger MIS share of the paths both sides sample, and the
//! camera side's variance on those paths, large on a caustic, falls with them. The pilot
//! measures the sum instead.
//!
//! Pilot. The render's camera at about [`PILOT_PIXELS`] pixels (same aspect; the full image if
//! smaller), [`PILOT_PASSES`] passes at each count of [`CANDIDATES`] (paths per pixel), on one
//! integrator ([`Integrator::set_light_paths`]). Every count sees the same camera random numbers
//! (keyed by pass and pixel) and a prefix of the same light paths (keyed by path index), so the
//! counts are compared on common random numbers. For each count: `V_b` = the per-pass variance
//! of every pixel's luminance (camera + splats), summed over each of the [`SIDE`]² blocks `b` of
//! the image; `C` = rays per pixel per pass, both sides (rays, not seconds, so that the choice
//! is a pure function of the seed and never of the machine). The score of a count is
//! `C · exp(mean_b log V_b)`, relative to that of 1 path per pixel: the geometric mean over the
//! regions of their variance × cost, so that every region's efficiency counts alike however
//! bright it is. A whole-image sum (`results/2026-12-03-light-path-pilot.md`) let the bright
//! regions the camera side carries outvote a dim floor lit only through a caustic (the SMS
//! ring's: ¼ per pixel where its floor wants 1–2); `results/2026-12-05-block-pilot.md` measures
//! this rule. A firefly of the camera side is the same at every count and adds the same to its
//! block's `V_b`, so it cannot decide. The least score wins (ties: the fewer paths). The passes
//! are [`PILOT_PASS_BASE`]`+i`, which no render reaches: the pilot's random numbers are disjoint
//! from the render's, it is a function of (scene, options, seed, resolution, CF product) only,
//! so every rank count and thread count gets the same count, and its samples are not in the
//! image. The CF product is fixed by the options except under `--time` without
//! `--forecast-photons`, where its photon count follows the measured speed; so the pilot's count
//! is not part of what `--resume` compares (`pipeline::identity::job_keys`): a resumed render
//! may run its new passes at another count, each pass an unbiased sample at any count.
//! The render's count is `⌈ν·W·H⌉` for its `W × H`.
//!
//! Known leanings: the pilot's larger pixels add the image's variation inside a pixel to the
//! camera side's variance (towards fewer paths); rays price the camera side's table lookups and
//! mixtures at nothing (towards fewer paths where those dominate, more where a light path's rays
//! are cheap).

use super::Plan;
use crate::accel::World;
use crate::distributed::Cluster;
use crate::integrators::{Integrator, Method, MethodArgs, MethodError};
use crate::interrupt::Stop;
use crate::math::luminance;
use crate::render::{camera_tiles_until, tile_pixels, with_splat, PassCounters, PixelSampler};

/// Pixels of the pilot image (about; the aspect is kept).
pub const PILOT_PIXELS: f64 = 4096.0;
/// Passes of the pilot per candidate count (each pixel's variance from this many samples).
pub const PILOT_PASSES: u64 = 8;
/// The pilot's first pass index: far beyond any render's passes (`Rng::keyed` streams differ).
pub const PILOT_PASS_BASE: u64 = 1 << 62;
/// The light paths per pixel the pilot tries: the range over which the equal-time sweeps found
/// each scene's best (`results/2026-12-05-targeted-cones.md`: ⅛ on `cornell-box` and
/// `figurines`, ½–1 on `ring`, 1 on the SMS ring), by factors of 2. Never 0, which would drop
/// the point-light caustics that only the light side renders.
pub const CANDIDATES: [f64; 5] = [0.125, 0.25, 0.5, 1.0, 2.0];

/// The least share of a time box (seconds) worth a pilot: below it the pilot is skipped and the
/// render takes the default count (the pilot's own integrator build alone takes a few tenths of
/// a second on `cornell-box`).
pub const PILOT_MIN_S: f64 = 1.0;

/// The pilot image is cut into `SIDE × SIDE` blocks (regions) whose efficiencies the score
/// weighs alike.
pub const SIDE: usize = 4;
/// The number of blocks.
pub const BLOCKS: usize = SIDE * SIDE;
/// The candidate the scores are relative to (1 path per pixel).
const REFERENCE: usize = 3;

/// One candidate count as the pilot measured it.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Candidate {
    /// Light paths per pixel `ν`.
    pub paths_per_pixel: f64,
    /// `V`: the per-pass variance of luminance, summed over the pilot's pixels.
    pub variance: f64,
    /// `C`: rays per pixel per pass, camera and light side.
    pub rays_per_pixel: f64,
    /// The score: `C` times the geometric mean over the blocks of `V_b`, relative to 1 path per
    /// pixel (lower is better; 1 for that count).
    pub relative_variance_x_rays: f64,
}

/// What one candidate's passes measured: the variance sum of each block, and the rays.
struct Measured {
    /// Light paths per pixel `ν`.
    nu: f64,
    blocks: [f64; BLOCKS],
    rays_per_pixel: f64,
}

/// `C/C_ref · exp(mean_b log(V_b / V_b,ref))`: the cost ratio times the geometric mean over the
/// blocks of the variance ratios, over the blocks with variance at the reference count (the
/// same set for every count; the costs alone when there is none). Each block's efficiency
/// counts alike, however bright the block. A block with none at `m`'s count but some at the
/// reference's is one that only light paths reach and that none reached in the pilot's passes:
/// its variance is taken as the reference's scaled by `ν_ref/ν`, as a light-side variance
/// scales, not as 0, which would reward the count that sampled it least.
fn relative(m: &Measured, reference: &Measured) -> f64 {
    let c = m.rays_per_pixel / reference.rays_per_pixel;
    let logs: Vec<f64> = (0..BLOCKS)
        .filter(|&b| reference.blocks[b] > 0.0)
        .map(|b| {
            let v = if m.blocks[b] > 0.0 { m.blocks[b] } else { reference.blocks[b] * reference.nu / m.nu };
            (v / reference.blocks[b]).ln()
        })
        .collect();
    if logs.is_empty() {
        return c;
    }
    c * (logs.iter().sum::<f64>() / logs.len() as f64).exp()
}

/// What the pilot measured and chose (the report's `light_path_rule`).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct LightPathRule {
    /// The pilot image, `[w, h]`.
    pub pilot_resolution: [u32; 2],
    /// Its passes per candidate.
    pub pilot_passes: u64,
    /// Every candidate, in [`CANDIDATES`]' order.
    pub candidates: Vec<Candidate>,
    /// The chosen light paths per pixel.
    pub paths_per_pixel: f64,
    /// Light paths per pass of the render, `⌈ν·W·H⌉`.
    pub light_paths: u64,
}

/// The pilot's image size for a `w × h` render.
pub fn pilot_resolution(w: u32, h: u32) -> (u32, u32) {
    let n = w as f64 * h as f64;
    if n <= PILOT_PIXELS {
        return (w, h);
    }
    let s = (PILOT_PIXELS / n).sqrt();
    (((w as f64 * s).round() as u32).max(1), ((h as f64 * s).round() as u32).max(1))
}

/// The candidate with the least score, the first of equals (the fewer paths); a score that is
/// not a number never wins unless all are.
pub fn best(candidates: &[Candidate]) -> Option<&Candidate> {
    let better = |c: &Candidate, b: &Candidate| {
        b.relative_variance_x_rays.is_nan() || c.relative_variance_x_rays < b.relative_variance_x_rays
    };
    candidates.iter().fold(None, |b: Option<&Candidate>, c| match b {
        Some(b) if !better(c, b) => Some(b),
        _ => Some(c),
    })
}

/// Per-pixel sums of luminance over the passes: `(Σx, Σx²)`.
struct Moments(Vec<(f64, f64)>);

impl Moments {
    fn add(&mut self, i: usize, x: f64) {
        let m = &mut self.0[i];
        m.0 += x;
        m.1 += x * x;
    }

    /// The per-pass variance of every pixel (unbiased, `n − 1`) of a `w`-wide image, summed
    /// over each block. A pixel with a non-finite pass value counts no variance (`max` keeps
    /// the 0 over a NaN): the film counts such samples, the pilot only compares counts.
    fn variance_sums(&self, n: u64, w: usize) -> [f64; BLOCKS] {
        let (n, h) = (n as f64, self.0.len() / w);
        let mut v = [0.0; BLOCKS];
        for (i, &(s, s2)) in self.0.iter().enumerate() {
            let b = (i / w) * SIDE / h * SIDE + (i % w) * SIDE / w;
            v[b] += ((s2 - s * s / n) / (n - 1.0)).max(0.0);
        }
        v
    }
}

/// Whether `plan`'s light paths per pass are the pilot's choice (`pt-cf` without `--light-paths`).
pub fn wanted(plan: &Plan) -> bool {
    plan.method == Method::PtCf && plan.args.ptcf.light_paths.is_none()
}

/// Rank 0's count (the rule's; without a light side, where the count does not matter, the
/// default per pixel), broadcast to every rank (collective).
pub fn broadcast_count(
    cluster: &dyn Cluster,
    plan: &Plan,
    rule: Option<&LightPathRule>,
) -> Result<u64, crate::distributed::ClusterError> {
    let (w, h) = plan.resolution;
    let n = rule.map_or(crate::integrators::pt_cf::light::default_paths(w, h), |r| r.light_paths);
    crate::distributed::broadcast_u64(cluster, n, "light-path")
}

/// Runs the pilot for a `pt-cf` render of `resolution` from the broadcast `product` and returns
/// the rule's choice; `None` when the render has no light side (no light or Dirac object, or a
/// `--path-filter`), whose count then does not matter, or when `stop` came first (its share of
/// the time box, a signal): the render then takes the default count
/// (`pt_cf::light::default_paths`). Runs on the current rayon pool. Also returns the pilot's
/// integrator, built from `product` and `args` at another light-path count: at the render's count
/// (`LightTracer::set_light_paths`) it is the render's integrator (its lookup grid and its table
/// cache are pure functions of the product and their keys), which rank 0 then need not build.
pub fn choose(
    world: &World,
    args: &MethodArgs,
    (seed, resolution): (u64, (u32, u32)),
    product: &[u8],
    stop: &Stop,
) -> Result<(Option<LightPathRule>, Box<dyn Integrator>), MethodError> {
    let (pw, ph) = pilot_resolution(resolution.0, resolution.1);
    let px = pw as f64 * ph as f64;
    let paths = |nu: f64| (nu * px).ceil() as u64;
    let mut pilot_args = args.clone();
    pilot_args.ptcf.light_paths = Some(paths(CANDIDATES[0]));
    let mut integrator = Method::PtCf.build(world, &pilot_args, product)?;
    let camera = world.scene.camera.with_resolution(pw, ph);
    let pixels = PixelSampler::new_until(world, &camera, args.emission_split(), integrator.prefix_cap(), stop)
        .with_sampler(args.settings.sampler);
    let measured: Option<Vec<Measured>> = CANDIDATES
        .iter()
        .map(|&nu| {
            if let Some(light) = integrator.light_tracer_mut() {
                light.set_light_paths(paths(nu));
            }
            measure(world, integrator.as_mut(), &pixels, seed, nu, stop)
        })
        .collect();
    let Some(measured) = measured else { return Ok((None, integrator)) };
    let candidates: Vec<Candidate> = CANDIDATES
        .iter()
        .zip(&measured)
        .map(|(&nu, m)| Candidate {
            paths_per_pixel: nu,
            variance: m.blocks.iter().sum(),
            rays_per_pixel: m.rays_per_pixel,
            relative_variance_x_rays: relative(m, &measured[REFERENCE]),
        })
        .collect();
    let nu = best(&candidates).map_or(1.0, |c| c.paths_per_pixel);
    let rule = LightPathRule {
        pilot_resolution: [pw, ph],
        pilot_passes: PILOT_PASSES,
        candidates,
        paths_per_pixel: nu,
        light_paths: (nu * resolution.0 as f64 * resolution.1 as f64).ceil().max(1.0) as u64,
    };
    Ok((Some(rule), integrator))
}

/// The pilot's passes at `nu` paths per pixel (the integrator's current count): the summed
/// per-pixel variance of the pass values in each block (camera + splats, as
/// `render::render_passes` adds them) and the rays of both sides per pixel and pass; `None` when
/// the integrator traces no light paths.
fn measure(
    world: &World,
    integrator: &mut dyn Integrator,
    pixels: &PixelSampler,
    seed: u64,
    nu: f64,
    stop: &Stop,
) -> Option<Measured> {
    let (w, h) = pixels.resolution();
    let (w, h) = (w as usize, h as usize);
    let mut m = Moments(vec![(0.0, 0.0); w * h]);
    let (mut rays, mut scratch) = (0u64, PassCounters::default());
    for i in 0..PILOT_PASSES {
        if stop.is_due() {
            return None;
        }
        let pass = PILOT_PASS_BASE + i;
        integrator.begin_pass(world, seed, pass);
        // each side stops within a tile or a chunk of paths at the pilot's deadline
        let splats = integrator.light_tracer()?.light_splats_until(world, pixels.camera(), seed, pass, stop)?;
        rays += splats.closest_rays + splats.shadow_rays;
        for (tile, out, c) in camera_tiles_until(world, &*integrator, pixels, seed, &[pass], stop)? {
            rays += c.closest_rays + c.shadow_rays;
            for ((x, y), l) in tile_pixels(tile, (w, h)).zip(out) {
                let v = with_splat(l, Some(&splats), y * w + x, &mut scratch);
                m.add(y * w + x, luminance(v) as f64);
            }
        }
    }
    Some(Measured {
        nu,
        blocks: m.variance_sums(PILOT_PASSES, w),
        rays_per_pixel: rays as f64 / (w * h * PILOT_PASSES as usize) as f64,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cand(nu: f64, e: f64) -> Candidate {
        Candidate { paths_per_pixel: nu, variance: e, rays_per_pixel: 1.0, relative_variance_x_rays: e }
    }

    #[test]
    fn the_least_score_wins_and_ties_go_to_fewer_paths() {
        let c = [cand(0.25, 3.0), cand(0.5, 2.0), cand(1.0, 2.0), cand(2.0, 5.0)];
        assert_eq!(best(&c).unwrap().paths_per_pixel, 0.5);
        let n = [cand(0.25, f64::NAN), cand(0.5, 4.0), cand(1.0, f64::NAN)];
        assert_eq!(best(&n).unwrap().paths_per_pixel, 0.5, "a NaN never wins");
        assert!(best(&[]).is_none());
    }

    fn meas(nu: f64, blocks: [f64; BLOCKS], rays_per_pixel: f64) -> Measured {
        Measured { nu, blocks, rays_per_pixel }
    }

    /// A firefly common to both counts (the camera side's random numbers are shared) adds the
    /// same variance to one block at both and barely moves the geometric mean; a block's
    /// brightness does not weigh.
    #[test]
    fn every_block_weighs_alike_and_a_common_firefly_does_not_decide() {
        let reference = meas(1.0, [1.0; BLOCKS], 4.0);
        assert!((relative(&meas(2.0, [0.5; BLOCKS], 6.0), &reference) - 0.75).abs() < 1e-12);
        let (mut r0, mut r1) = ([1.0; BLOCKS], [0.5; BLOCKS]);
        r0[3] += 1e6;
        r1[3] += 1e6;
        let got = relative(&meas(2.0, r1, 6.0), &meas(1.0, r0, 4.0));
        let expect = 1.5 * 0.5f64.powf(15.0 / 16.0);
        assert!((got - expect).abs() < 1e-6, "{got} vs {expect}");
        // One bright block 10⁶ times the others, halved: the same as any block halved.
        let (mut bright, mut halved) = ([1.0; BLOCKS], [1.0; BLOCKS]);
        bright[0] = 1e6;
        halved[0] = 5e5;
        let got = relative(&meas(1.0, halved, 4.0), &meas(1.0, bright, 4.0));
        assert!((got - 0.5f64.powf(1.0 / 16.0)).abs() < 1e-12);
        let none = meas(1.0, [0.0; BLOCKS], 4.0);
        assert!((relative(&meas(2.0, [0.0; BLOCKS], 6.0), &none) - 1.5).abs() < 1e-12, "no variance: the costs decide");
    }

    /// A block that no light path reached at a low count (no variance there) is not free: it
    /// stands in at the reference's variance × ν_ref/ν; a block with no variance at the
    /// reference is left out at every count.
    #[test]
    fn a_block_unreached_at_a_low_count_is_not_free() {
        let mut few = [1.0; BLOCKS];
        few[5] = 0.0; // ⅛ per pixel: no splat landed in block 5
        let got = relative(&meas(0.125, few, 2.0), &meas(1.0, [1.0; BLOCKS], 4.0));
        let expect = 0.5 * 8.0f64.powf(1.0 / 16.0);
        assert!((got - expect).abs() < 1e-12, "{got} vs {expect}");
        let mut dark = [1.0; BLOCKS];
        dark[7] = 0.0; // nothing at the reference either way
        let mut more = [0.5; BLOCKS];
        more[7] = 9.0;
        let got = relative(&meas(2.0, more, 4.0), &meas(1.0, dark, 4.0));
        assert!((got - 0.5).abs() < 1e-12, "{got}: the set is the reference's blocks with variance");
    }

    #[test]
    fn the_pilot_keeps_the_aspect_and_small_images() {
        assert_eq!(pilot_resolution(32, 16), (32, 16));
        assert_eq!(pilot_resolution(256, 256), (64, 64));
        assert_eq!(pilot_resolution(640, 360), (85, 48));
        let (w, h) = pilot_resolution(100_000, 1); // a thin strip keeps one row
        assert_eq!((w, h), (20239, 1));
    }

    #[test]
    fn the_variance_is_the_unbiased_per_pixel_one_summed_per_block() {
        // An 8 × 4 image: blocks of 2 × 1 pixels; pixel (1, 0) is in block 0, (2, 3) in 13.
        let mut m = Moments(vec![(0.0, 0.0); 32]);
        for x in [1.0, 2.0, 3.0] {
            m.add(0, x);
            m.add(1, 2.0 * x);
            m.add(8, 5.0);
            m.add(3 * 8 + 2, x);
        }
        let v = m.variance_sums(3, 8);
        assert!((v[0] - 5.0).abs() < 1e-12 && v[4] == 0.0 && (v[13] - 1.0).abs() < 1e-12, "{v:?}");
        assert_eq!(v.iter().filter(|&&x| x > 0.0).count(), 2);
    }
}
