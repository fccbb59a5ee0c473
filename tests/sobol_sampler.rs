//! The camera streams' Sobol prefix in the renderer (`--sampler sobol`, `src/sampling/qmc.rs`,
//! docs/sampling.md): on `cornell-box` it agrees with the independent streams and lowers the
//! error of the image. The sampler's own properties (nets, uniformity over pixels, a shadow
//! edge's variance) are unit tests in `src/sampling/qmc.rs`; the furnaces with it are in
//! `tests/furnace.rs`.
//!
//! Statistics. The prefix makes a pixel's passes stratified, so the film's variance of the mean
//! (from the spread of its passes) over-states its error; the error itself is measured between
//! seeds, which are independent under either sampler.

mod common;

use common::{assert_detects, global_z, render_sampled, world};
use forecast::image_io::Image;
use forecast::integrators::{Method, MethodArgs};
use forecast::render::film::Film;
use forecast::render::PixelSampler;
use forecast::sampling::qmc::SamplerKind;

const RES: u32 = 16;

/// `pt` on `cornell-box` at RES², `passes` passes, seed `seed`, camera streams of `sampler`.
fn render(sampler: SamplerKind, passes: u64, seed: u64) -> Film {
    let w = world("scenes/cornell-box.toml");
    let mut o = MethodArgs::default();
    o.settings.max_depth = Some(64);
    let mut pt = Method::Pt.build(&w, &o, &[]).unwrap();
    let cam = w.scene.camera.with_resolution(RES, RES);
    render_sampled(&w, pt.as_mut(), &PixelSampler::plain(&cam).with_sampler(sampler), passes, seed).0
}

/// Mean over pixels and channels of the squared difference of two films' means
/// (`metrics::mse`, as `forecast diff`).
fn mse(a: &Film, b: &Film) -> f64 {
    let image = |f: &Film| Image { width: f.width, height: f.height, pixels: f.mean() };
    forecast::metrics::mse(&image(a), &image(b), None).expect("equal sizes")
}

/// Half the mean over consecutive seed pairs of the MSE between them: the error variance of one
/// render (per pixel and channel, averaged), from the seeds alone.
fn error_variance(f: &[Film]) -> f64 {
    f.windows(2).map(|p| mse(&p[0], &p[1]) / 2.0).sum::<f64>() / (f.len() - 1) as f64
}

/// Sixteen seeds of 1,024 passes per sampler. (1) The whole-image means agree (Welch z of the
/// image sums, α = 1e-3: per-pixel z-tests are left to the furnaces, since at 16² `cornell-box`
/// has pixels whose rare caustic paths make any one render's variance estimate collapse, under
/// either sampler), and a 3% error moves that z by more than twice the threshold
/// (`common::assert_detects`; with four seeds it moved the conservative z by 4.46, so sixteen
/// double that to ≈ 8.9; the variance layer over-states the Sobol image's error, so this
/// under-states the power). (2) The error variance between seeds falls
/// to at most half of the independent streams': RQMC's O(N^-3/2) for a smooth pixel integrand
/// is about 1/32 of Monte Carlo's 1/N at N = 1,024, and the
/// bound leaves room for the pixels whose light comes through the glass ball, where the prefix
/// does not reach. With the prefix switched off (independent in both) the ratio is ≈ 1.
#[test]
fn sobol_agrees_with_the_independent_streams_and_lowers_the_error() {
    let films = |s: SamplerKind| -> Vec<Film> { (1..=16).map(|seed| render(s, 1024, seed)).collect() };
    let (sobol, indep) = (films(SamplerKind::Sobol), films(SamplerKind::Independent));
    let merged = |f: &[Film]| {
        let mut m = Film::new(RES as usize, RES as usize);
        f.iter().for_each(|x| m.merge(x));
        m
    };
    let (ms, mi) = (merged(&sobol), merged(&indep));
    let thr = forecast::stats::z_test_threshold(1e-3, 1);
    let z = global_z(&ms, &mi);
    eprintln!("global z {z:.2} (threshold {thr:.2})");
    assert!(z.abs() < thr, "the Sobol image's mean differs from the independent one's: z {z}");
    assert_detects(&ms, &mi, 0.03, thr, "sobol against independent");
    let (vs, vi) = (error_variance(&sobol), error_variance(&indep));
    eprintln!("error variance: Sobol {vs:.3e}, independent {vi:.3e}, ratio {:.3}", vs / vi);
    assert!(vs < 0.5 * vi, "the prefix did not lower the error: {vs:.3e} against {vi:.3e}");
}

/// Randomness stays a pure function of (seed, pass, pixel) under the prefix: `pt-cf` with its
/// light paths renders the same bits on 1 and 2 threads, in one pass group or pass by pass.
#[test]
fn sobol_images_do_not_depend_on_the_thread_count() {
    let d = common::tmp_dir("sobol-threads");
    let scene = common::root().join("scenes/cornell-box.toml");
    let film = |threads: usize| {
        let mut job = common::job(&scene, Method::PtCf, 6, 5, (24, 24), threads, &d.join(format!("t{threads}")));
        job.args.settings.sampler = SamplerKind::Sobol;
        (job.args.cf.forecast_photons, job.args.cf.clusters) = (Some(20_000), 16);
        common::render_film(&job)
    };
    assert!(film(1).data == film(2).data, "the Sobol image depends on the thread count");
}
