//! `forecast bench`: closest-hit and shadow-ray throughput (Mrays/s) on the scene's own
//! geometry, and `pt` samples/s at a given resolution, each the median over repeats.
//!
//! Rays: for the ray benchmarks we trace camera rays to first hits, then random
//! cosine-distributed rays from those hits (closest hit) and segments between pairs of
//! hit points (shadow rays) — the incoherent mix a path tracer produces.

use crate::accel::{offset_origin, World};
use crate::integrators::{Method, MethodArgs};
use crate::math::{Frame, Vec3};
use crate::render::{film::Film, render_pass, PixelSampler};
use crate::sampling::rng::{stream, Rng};
use crate::sampling::warp::sample_cosine_hemisphere;
use rayon::prelude::*;
use std::time::Instant;

/// Median of a slice (0 for an empty one).
pub fn median(v: &mut [f64]) -> f64 {
    v.sort_by(|a, b| a.total_cmp(b));
    let n = v.len();
    if n == 0 {
        0.0
    } else if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// Bench results.
#[derive(Debug, serde::Serialize)]
pub struct BenchReport {
    /// Closest-hit Mrays/s (median).
    pub closest_mrays: f64,
    /// Shadow Mrays/s (median).
    pub shadow_mrays: f64,
    /// pt samples/s (median).
    pub pt_samples_per_s: f64,
    /// Rays per pt sample (closest, shadow).
    pub rays_per_sample: (f64, f64),
    /// Threads used.
    pub threads: usize,
}

/// A ray's origin and direction.
type Ray = (Vec3, Vec3);
/// A shadow segment: origin, unit direction, length.
type Segment = (Vec3, Vec3, f32);

/// The benchmark's `n` closest-hit rays (cosine-distributed from the first hits of a 256²
/// jittered view) and `n` shadow segments between pairs of those hits; an error if the camera
/// sees fewer than two hits.
fn ray_set(world: &World, n_rays: usize) -> Result<(Vec<Ray>, Vec<Segment>), String> {
    let cam = world.scene.camera.with_resolution(256, 256);
    // Build the ray set: origins and normals of first hits.
    let mut pts: Vec<(Vec3, Vec3)> = Vec::new();
    let mut rng = Rng::keyed(1, stream::MISC, 0, 0);
    for y in 0..256 {
        for x in 0..256 {
            let d = cam.direction(x as f32 + rng.next_f32(), y as f32 + rng.next_f32());
            if let Some(h) = world.intersect(cam.position, d, f32::INFINITY) {
                let n = if h.ng.dot(d) < 0.0 { h.ng } else { -h.ng };
                pts.push((h.p, n));
            }
        }
    }
    if pts.len() < 2 {
        return Err("bench: the camera sees no geometry".into());
    }
    let rays: Vec<Ray> = (0..n_rays)
        .map(|i| {
            let (p, n) = pts[i % pts.len()];
            let d = Frame::from_normal(n).to_world(sample_cosine_hemisphere(rng.next_2d()));
            (offset_origin(p, n, d), d)
        })
        .collect();
    let segs: Vec<Segment> = (0..n_rays)
        .map(|i| {
            let (a, na) = pts[i % pts.len()];
            let (b, _) = pts[rng.below(pts.len() as u32) as usize];
            let d = b - a;
            let len = d.length().max(1e-6);
            let dir = d / len;
            let o = offset_origin(a, na, dir);
            (o, dir, (len - 2e-4).max(0.0))
        })
        .collect();
    Ok((rays, segs))
}

/// Runs the benchmark on the current rayon pool; `repeats` must be at least 1.
pub fn run(world: &World, resolution: (u32, u32), repeats: usize) -> Result<BenchReport, String> {
    if repeats == 0 {
        return Err("--repeats 0: the medians need at least one repeat".into());
    }
    let n_rays = 400_000usize;
    let (rays, segs) = ray_set(world, n_rays)?;
    let mut closest = Vec::new();
    let mut shadow = Vec::new();
    let mut pt = Vec::new();
    let (w, h) = resolution;
    let camera = world.scene.camera.with_resolution(w, h);
    let mut args = MethodArgs::default();
    args.settings.max_depth = Some(world.scene.render.max_depth);
    let integ = Method::Pt.build(world, &args, &Method::Pt.preprocess(world, &args, 7)?)?;
    let mut rays_per_sample = (0.0, 0.0);
    for r in 0..repeats {
        let t = Instant::now();
        let hits: usize = rays
            .par_chunks(1024)
            .map(|c| c.iter().filter(|(o, d)| world.intersect(*o, *d, f32::INFINITY).is_some()).count())
            .sum();
        closest.push(n_rays as f64 / t.elapsed().as_secs_f64() / 1e6);
        let t = Instant::now();
        let occl: usize =
            segs.par_chunks(1024).map(|c| c.iter().filter(|(o, d, l)| world.occluded(*o, *d, *l)).count()).sum();
        shadow.push(n_rays as f64 / t.elapsed().as_secs_f64() / 1e6);
        std::hint::black_box((hits, occl));
        let mut film = Film::new(w as usize, h as usize);
        let t = Instant::now();
        let c = render_pass(world, integ.as_ref(), &PixelSampler::plain(&camera), 7, r as u64, &mut film);
        pt.push(c.samples as f64 / t.elapsed().as_secs_f64());
        rays_per_sample = (c.closest_rays as f64 / c.samples as f64, c.shadow_rays as f64 / c.samples as f64);
    }
    Ok(BenchReport {
        closest_mrays: median(&mut closest),
        shadow_mrays: median(&mut shadow),
        pt_samples_per_s: median(&mut pt),
        rays_per_sample,
        threads: rayon::current_num_threads(),
    })
}

/// The per-phase profile of `method` (default flags, the scene's caps) over `spp` passes at
/// `resolution` on the current rayon pool, preprocess excluded (`forecast bench --method M`);
/// `pt-cf` traces ½ light path per pixel here (`pt_cf::light::PATHS_PER_PIXEL`), not a pilot's count.
pub fn profile_method(
    world: &World,
    method: Method,
    (w, h): (u32, u32),
    spp: u64,
) -> Result<crate::profile::PhaseProfile, String> {
    let mut args = MethodArgs::default();
    args.settings.max_depth = Some(world.scene.render.max_depth);
    let product = method.preprocess(world, &args, 7)?;
    let mut integ = method.build(world, &args, &product)?;
    let camera = world.scene.camera.with_resolution(w, h);
    let pixels = PixelSampler::new(world, &camera, args.emission_split(), integ.prefix_cap())
        .with_sampler(args.settings.sampler);
    let mut profile = crate::profile::Profile::default();
    for pass in 0..spp.max(1) {
        integ.begin_pass(world, 7, pass);
        let mut film = Film::new(w as usize, h as usize);
        profile.add(&render_pass(world, integ.as_ref(), &pixels, 7, pass, &mut film).profile);
    }
    Ok(profile.per_sample())
}
