//! Emission splitting (`--emission-split K`, `render::PixelSampler`): `K` camera rays per pixel
//! sample average the emission seen along their Dirac prefixes, one of them carries the rest of
//! the estimate.
//!
//! - Unbiased: on the Cornell box (light seen directly and in the mirror ball) every method with
//!   `K = 8` in every pixel (not only the probed edges) agrees with the same method at `K = 1`
//!   (Šidák-corrected per-pixel and whole-image z-tests, family-wise α = 1e-3, with a negative
//!   control inside `assert_agrees`). Not with `pt` at `K = 1`: `pt`'s estimate of the mirror
//!   ball's caustic on the ceiling is heavy-tailed, so at 4096 spp its sample variance is not a
//!   reliable z-test reference (seed 11: pixel 45's blue 0.00453 ± 0.00015; seeds 12, 13 at 4096
//!   spp 0.0088 ± 0.0020, 0.0064 ± 0.0013; 16384 spp 0.0066 ± 0.0006), and `pt-cf`'s light paths,
//!   which sample that light well (0.00570 ± 0.00013), failed against it on every seed tried.
//!   Each method's agreement with `pt` is `tests/pt_cf.rs`, `tests/pt_cf_light.rs`, `tests/iws.rs`.
//! - The probe marks the edges, and splitting works in every integrator: in a scene that is only
//!   a tilted emitter in the void, a pixel sample is its prefix emission and nothing else, so the summed per-pixel
//!   variance with `K = 16` must be at most 1/8 of that with `K = 1`. Bound: `K` independent rays
//!   would give exactly 1/16; N-rooks stratification only lowers the variance of a straight edge;
//!   the factor 2 covers the noise of the variance estimates (relative sd ≈ 2% over the ~40 edge
//!   pixels at 512 passes). An integrator that put the prefix emission into `rest` would give
//!   ratio 1; one that counted it twice would fail the agreement of means.
//! - The probe marks the light seen through glass along some Fresnel choices only: a glass ball
//!   before a large emitter behind the camera, seen only by the ball's random reflections. The
//!   summed variance with `K = 16` must again be at most 1/8 of `K = 1`'s (the bound above); a
//!   probe that traced one chain per lattice point marked a pixel only when one of its 9 points
//!   happened to reflect (the pixels inside the highlight, about 1 − 0.96⁹ ≈ 0.3 of them at
//!   normal incidence), which left most of the variance (ratio ≈ 0.7) and fails it.
//! - The probe's lattice is finer below 640 pixels across: an emitter of 0.29 pixels between the
//!   half-pixel lattice lines is split at 16² (one pixel), where half-pixel steps split none.
//! - The split rays go where the probe saw the light (its cell map): a light of 8% of a pixel
//!   keeps at most 1/64 of its variance at `K` = 16 (the uniform rays keep 1/26).
//! - `K = 1` is the pixel sampler from before splitting bit for bit (written out in the test).
//! - The furnaces of `tests/furnace.rs` stay exact with splitting in every pixel (mirror: every
//!   sample 1; glass ball in an emissive enclosure: per-pixel z-tests against 1), every method.

mod common;
use common::{assert_agrees, assert_furnace_is_one, render_sampled};
use forecast::accel::World;
use forecast::integrators::{Integrator, Method, MethodArgs};
use forecast::render::film::Film;
use forecast::render::PixelSampler;
use std::path::Path;

/// An emitter quad (`corner`, `u`, `v`; Le = 1) facing the camera 3 m away (40°, 16²), nothing
/// else: the world of the probe tests.
fn emitter_in_the_void(corner: [f32; 3], u: [f32; 3], v: [f32; 3]) -> World {
    let toml = format!(
        "[camera]\nposition = [0.0, 0.0, 3.0]\nlook_at = [0.0, 0.0, 0.0]\nfov = 40.0\nresolution = [16, 16]\n\n\
         [[shape]]\ntype = \"quad\"\ncorner = {corner:?}\nu = {u:?}\nv = {v:?}\nemission = [1.0, 1.0, 1.0]\n"
    );
    World::build(forecast::scene::load_str(&toml, "emitter.toml", Path::new(".")).unwrap()).unwrap()
}

fn world(path: &str) -> World {
    World::build(forecast::scene::load(Path::new(path)).expect("scene loads")).expect("BVH builds")
}

/// Small preprocesses (as `tests/pt_cf.rs`; the photon map as `tests/furnace.rs`).
fn opts() -> MethodArgs {
    let mut o = MethodArgs::default();
    (o.settings.max_depth, o.cf.forecast_photons, o.cf.clusters, o.pm.photons) = (Some(64), Some(20_000), 16, 20_000);
    o
}

/// Builds `method` through the broadcast bytes, as a rank would.
fn build(world: &World, method: Method, o: &MethodArgs) -> Box<dyn Integrator> {
    let bytes = method.preprocess(world, o, 17).unwrap();
    method.build(world, o, &bytes).unwrap()
}

/// How the pixels are split.
#[derive(Clone, Copy)]
enum Split {
    /// `K` rays in the pixels the probe marks (what the pipeline does).
    Probed(u32),
    /// `K` rays in every pixel.
    Everywhere(u32),
}

fn render(w: &World, m: Method, (res, spp, seed): (u32, u64, u64), split: Split) -> Film {
    let mut i = build(w, m, &opts());
    let cam = w.scene.camera.with_resolution(res, res);
    let pixels = match split {
        Split::Probed(k) => PixelSampler::new(w, &cam, k, i.prefix_cap()),
        Split::Everywhere(k) => PixelSampler::everywhere(&cam, k, i.prefix_cap()),
    };
    render_sampled(w, i.as_mut(), &pixels, spp, seed).0
}

/// Σ over pixels and channels of the variance of the pixel mean.
fn summed_variance(f: &Film) -> f64 {
    f.variance_of_mean().iter().flat_map(|p| p.iter().map(|&v| v as f64)).sum()
}

#[test]
fn every_method_with_split_agrees_with_itself_unsplit_on_cornell_box() {
    let w = world("scenes/cornell-box.toml");
    for &m in Method::ALL.iter().filter(|&&m| m != Method::Iws && m != Method::IwsPm) {
        // the method's own image at K = 1 (the plain sampler, bit for bit: below) is the
        // reference; each method's agreement with `pt` is its own test file's
        // (16,384, 4,096) passes for the negative control's power: at (4,096, 1,024) a 3% error
        // moved `pt`'s conservative global z by 4.99 (37% of the variance in the image), short
        // of 6.58; 4.99 · 2 ≈ 10
        let reference = render(&w, m, (16, 16384, 11), Split::Probed(1));
        // every pixel split: E and L − E are separated right on diffuse, mirror and glass pixels
        let img = render(&w, m, (16, 4096, 3), Split::Everywhere(8));
        assert_agrees(&img, &reference, &format!("{} --emission-split 8 everywhere vs K = 1", m.name()));
    }
}

#[test]
fn probe_marks_the_edges_and_split_removes_their_variance_in_every_integrator() {
    // a 1 m emitter tilted 20° about the view axis
    let w = emitter_in_the_void([-0.3277, -0.6408, 0.0], [0.9397, 0.3420, 0.0], [-0.3420, 0.9397, 0.0]);
    let cam = w.scene.camera.with_resolution(16, 16);
    let found = PixelSampler::new(&w, &cam, 16, 64).stats();
    // the quad covers about 7×7 of the 16×16 pixels: its edges cross ~30 of them
    eprintln!("probe: {} edge pixels", found.split_pixels);
    assert!((20..=60).contains(&found.split_pixels), "probe found {} edge pixels", found.split_pixels);
    for &m in Method::ALL {
        let (one, split) = split_removes_variance(&w, m, "edges");
        assert_agrees(&split, &one, &format!("{} emitter edges, K = 16 vs 1", m.name()));
    }
}

/// A light smaller than half a pixel is found at low resolution: the one pixel that holds it is
/// split, and no other. (With half-pixel steps at every resolution the probe split none: a glint
/// of the light in glass is such a light, and `figurines` at 256×144 lost most of its own.)
#[test]
fn probe_finds_a_light_smaller_than_half_a_pixel_at_low_resolution() {
    // 0.29 pixels wide (0.04 m at 3 m, 16², 40°), centred a quarter pixel off the image's centre
    // in x and y: between the half-pixel lattice lines (u, v ∈ k/2), which see none of it; the
    // lattice of 1/8 pixel that a 16² image gets (`probe_subdivision`) has points inside it
    let w = emitter_in_the_void([0.01412, 0.01412, 0.0], [0.04, 0.0, 0.0], [0.0, 0.04, 0.0]);
    let cam = w.scene.camera.with_resolution(16, 16);
    assert_eq!(PixelSampler::new(&w, &cam, 16, 64).stats().split_pixels, 1);
}

/// The split rays go where the probe saw the light: the light of 0.29 pixels above (8% of its
/// pixel) is seen by a uniformly placed ray 8% of the time, so `K` = 16 uniform rays keep about
/// 1/16 of a sample's variance (N-rooks helps an image this small little: 0.0385 measured with
/// the uniform sampler). The pixel's map (16×16 cells) puts half the rays (`1 − DEFENSIVE`) on
/// the cells whose corners saw the light, about a 6×6 block around its 4.6×4.6 cells, where each
/// sees it with probability ≈ 0.6: the variance kept must be at most 1/64 of one ray's, 2.5×
/// below the uniform sampler's (0.0066 measured). `pt` and `pt-cf`; their light agrees with the
/// unsplit render's (z < 4).
#[test]
fn split_rays_go_where_the_probe_saw_the_light() {
    let w = emitter_in_the_void([0.01412, 0.01412, 0.0], [0.04, 0.0, 0.0], [0.0, 0.04, 0.0]);
    for m in [Method::Pt, Method::PtCf] {
        let one = render(&w, m, (16, 512, 5), Split::Probed(1));
        let split = render(&w, m, (16, 512, 6), Split::Probed(16));
        let (v1, v16) = (summed_variance(&one), summed_variance(&split));
        eprintln!("{} sub-pixel light: summed variance K=1 {v1:.3e}, K=16 {v16:.3e}, ratio {:.4}", m.name(), v16 / v1);
        assert!(v1 > 0.0 && v16 <= v1 / 64.0, "{}: K = 16 kept {:.4} of the variance", m.name(), v16 / v1);
        // the image is one lit pixel: its means must agree (the per-pixel z-tests of the other
        // tests here exercise the same estimator with power; this one has too little light)
        let sums = |f: &Film| {
            let (mean, var) = (f.mean(), f.variance_of_mean());
            (
                mean.iter().flatten().map(|&x| x as f64).sum::<f64>(),
                var.iter().flatten().map(|&x| x as f64).sum::<f64>(),
            )
        };
        let ((a, va), (b, vb)) = (sums(&split), sums(&one));
        let z = (a - b) / (va + vb).sqrt();
        assert!(z.abs() < 4.0, "{}: the split image's light {a:.5} against {b:.5} (z = {z:.2})", m.name());
    }
}

/// Renders `m` at `K = 1` and `K = 16` (16², 512 passes each) and asserts that splitting kept at
/// most 1/8 of the summed variance of `what` (the bound in the module docs); returns both films.
fn split_removes_variance(w: &World, m: Method, what: &str) -> (Film, Film) {
    let one = render(w, m, (16, 512, 5), Split::Probed(1));
    let split = render(w, m, (16, 512, 6), Split::Probed(16));
    let (v1, v16) = (summed_variance(&one), summed_variance(&split));
    eprintln!("{} {what}: summed variance K=1 {v1:.3e}, K=16 {v16:.3e}, ratio {:.4}", m.name(), v16 / v1);
    assert!(v1 > 0.0, "{}: the {what} must be noisy without splitting", m.name());
    assert!(v16 <= v1 / 8.0, "{}: K = 16 kept {:.3} of the {what}' variance", m.name(), v16 / v1);
    (one, split)
}

/// A glass ball whose only light is an 8×8 emitter behind the camera, seen in the ball's
/// reflections (chosen with the Fresnel probability at each glass interface).
const LIGHT_IN_GLASS: &str = r#"
[camera]
position   = [0.0, 0.0, 3.0]
look_at    = [0.0, 0.0, 0.0]
fov        = 40.0
resolution = [16, 16]

[materials.glass]
type = "glass"
ior  = 1.5

[[shape]]
type     = "sphere"
center   = [0.0, 0.0, 0.0]
radius   = 0.8
material = "glass"

[[shape]]
type     = "quad"
corner   = [-4.0, 4.0, 5.0]
u        = [8.0, 0.0, 0.0]
v        = [0.0, -8.0, 0.0]
emission = [1.0, 1.0, 1.0]
"#;

#[test]
fn probe_marks_light_seen_through_glass_and_split_removes_its_variance() {
    let w = World::build(forecast::scene::load_str(LIGHT_IN_GLASS, "glass.toml", Path::new(".")).unwrap()).unwrap();
    let cam = w.scene.camera.with_resolution(16, 16);
    eprintln!("probe: {} pixels", PixelSampler::new(&w, &cam, 16, 64).stats().split_pixels);
    for m in [Method::Pt, Method::PtCf] {
        split_removes_variance(&w, m, "reflections");
        // the reference at 16× the passes: the rare chains (two internal reflections, p ≈ 0.002)
        // must be sampled often enough for its variance estimate. Both at 4× the passes of
        // the variance check for the negative control's power: at (8,192, 512) a 3% error moved
        // `pt`'s global z by 5.16, short of 6.58; 5.16 · 2 ≈ 10
        let split = render(&w, m, (16, 2048, 6), Split::Probed(16));
        let reference = render(&w, m, (16, 32768, 7), Split::Probed(1));
        assert_agrees(&split, &reference, &format!("{} light in glass, K = 16 vs 1", m.name()));
    }
}

/// The probe weighs a pixel's coin tosses against the brightest emitter: the reflections of the
/// 8×8 light in the glass ball (`LIGHT_IN_GLASS`, Le = 1; a reflection is chosen with the Fresnel
/// probability F ≈ 0.04, so a point's prefix emission has standard deviation √(F(1−F)) ≈ 0.2)
/// are split while that light is the brightest; beside an emitter 100 times brighter the pixels
/// inside the highlight, where every lattice point reflects it (0.2/100 = 2·10⁻³ of the brightest,
/// above `SPLIT_SIGMA` = 10⁻³), stay split and only some at its rim, where fewer points see it,
/// drop; beside one 10⁶ times brighter none is split (a coin toss on a light of 1 has standard
/// deviation at most 0.5: 5·10⁻⁷ of it; the pool's sky in its water beside its sun: 1.4·10⁻⁶ at
/// most). The bright emitter is a tiny quad below the ball, facing away from the camera: never
/// seen.
#[test]
fn probe_weighs_coin_tosses_against_the_brightest_emitter() {
    let split_with = |le: f32| {
        let toml = format!(
            "{LIGHT_IN_GLASS}\n[[shape]]\ntype = \"quad\"\ncorner = [0.0, -3.0, 0.0]\nu = [0.0, 0.0, 0.01]\n\
             v = [0.01, 0.0, 0.0]\nemission = [{le}, {le}, {le}]\n"
        );
        let w = World::build(forecast::scene::load_str(&toml, "glass.toml", Path::new(".")).unwrap()).unwrap();
        let cam = w.scene.camera.with_resolution(16, 16);
        PixelSampler::new(&w, &cam, 16, 64).stats().split_pixels
    };
    let (dim, bright_100, bright_1e6) = (split_with(0.5), split_with(100.0), split_with(1e6));
    eprintln!("split pixels beside an emitter of 0.5, 100, 1e6: {dim}, {bright_100}, {bright_1e6}");
    assert!(dim >= 20, "the light's reflections must be split while it is the brightest ({dim} pixels)");
    assert!(
        bright_100 <= dim && 2 * bright_100 >= dim,
        "the highlight's inside is still split ({bright_100} of {dim})"
    );
    assert_eq!(bright_1e6, 0, "2·10⁻⁷ of the brightest emitter is not");
}

/// The pixel sample from before emission splitting, written out: the pixel's camera stream,
/// its jitter, one `radiance` call.
fn pre_split_film(w: &World, integ: &mut dyn Integrator, res: u32, passes: u64, seed: u64) -> Film {
    use forecast::sampling::rng::{stream, Rng};
    let cam = w.scene.camera.with_resolution(res, res);
    let mut film = Film::new(res as usize, res as usize);
    for pass in 0..passes {
        integ.begin_pass(w, seed, pass);
        let mut ctx = forecast::transport::context::Context::new(Rng::keyed(seed, stream::CAMERA, pass, 0));
        for pixel in 0..(res * res) as usize {
            ctx.rng = Rng::keyed(seed, stream::CAMERA, pass, pixel as u64);
            let [jx, jy] = ctx.rng.next_2d();
            let (x, y) = ((pixel % res as usize) as f32, (pixel / res as usize) as f32);
            let l = integ.radiance(w, cam.position, cam.direction(x + jx, y + jy), &mut ctx);
            film.add(pixel, if l.is_finite() { l } else { forecast::math::Rgb::ZERO });
        }
    }
    film
}

#[test]
fn split_one_is_the_plain_sampler_bit_for_bit() {
    let w = world("scenes/cornell-box.toml");
    for m in [Method::Pt, Method::IwsCf] {
        let mut a = build(&w, m, &opts());
        let before = pre_split_film(&w, a.as_mut(), 16, 8, 2);
        let one = render(&w, m, (16, 8, 2), Split::Probed(1));
        assert_eq!(before.data, one.data, "{}", m.name());
        // and splitting does change the random numbers of the split pixels
        let split = render(&w, m, (16, 8, 2), Split::Everywhere(2));
        assert_ne!(before.data, split.data, "{}", m.name());
    }
}

#[test]
fn furnaces_stay_exact_with_split() {
    let mirror = world("tests/scenes/furnace_mirror.toml");
    let glass = world("tests/scenes/furnace_glass.toml");
    for &m in Method::ALL {
        // every sample of the mirror furnace is exactly 1, split or not
        for p in render(&mirror, m, (16, 4, 2), Split::Everywhere(5)).mean() {
            assert!(p.iter().all(|c| (c - 1.0).abs() < 1e-5), "{}: mirror furnace pixel {p:?}", m.name());
        }
        // no diffuse surface behind the glass (L_c = 0), so every method must give 1
        let img = render(&glass, m, (16, 256, 3), Split::Everywhere(4));
        assert_furnace_is_one(&img, &format!("{} glass furnace, K = 4 everywhere", m.name()));
    }
}

/// Two facing lossless mirrors 1 m apart and an emitter (Le = 1) 10 m down the corridor: a ray
/// at 1:8 to the mirrors' normal reaches it after ~80 reflections.
const MIRROR_CORRIDOR: &str = r#"
[camera]
position   = [0.0, 0.0, 0.5]
look_at    = [1.0, 0.0, 8.5]
fov        = 40.0
resolution = [4, 4]

[materials.mirror]
type        = "mirror"
reflectance = [1.0, 1.0, 1.0]

[[shape]]
type     = "quad"
corner   = [-1.0, -5.0, 0.0]
u        = [21.0, 0.0, 0.0]
v        = [0.0, 10.0, 0.0]
material = "mirror"

[[shape]]
type     = "quad"
corner   = [-1.0, -5.0, 1.0]
u        = [0.0, 10.0, 0.0]
v        = [21.0, 0.0, 0.0]
material = "mirror"

[[shape]]
type     = "quad"
corner   = [10.0, -5.0, 0.0]
u        = [0.0, 0.0, 1.0]
v        = [0.0, 10.0, 0.0]
emission = [1.0, 1.0, 1.0]
"#;

/// The extra rays' Dirac chains stop where the integrator's camera prefix stops: `pt` with
/// `--max-depth 100` reaches the emitter at the end of an ~80-reflection corridor, so `E` must
/// too (mean 1: lossless mirrors, unbiased roulette), while a 64-vertex cap (the IWS core's)
/// gives exactly 0. Tolerance: 5 standard errors of the sample mean (the roulette weights make
/// single values ≈ 47 with probability ≈ 2%).
#[test]
fn extra_rays_follow_the_integrators_prefix_cap() {
    use forecast::sampling::rng::{stream, Rng};
    use forecast::transport::dirac::prefix_emission;
    let w = World::build(forecast::scene::load_str(MIRROR_CORRIDOR, "corridor.toml", Path::new(".")).unwrap()).unwrap();
    let mut o = opts();
    o.settings.max_depth = Some(100);
    let pt = Method::Pt.build(&w, &o, &[]).unwrap();
    let iws = Method::Iws.build(&w, &o, &[]).unwrap();
    assert_eq!((pt.prefix_cap(), iws.prefix_cap()), (101, 64));
    let (origin, dir) =
        (forecast::math::Vec3::new(0.0, 0.0, 0.5), forecast::math::Vec3::new(1.0, 0.0, 8.0).normalize());
    let sample = |cap: u32, n: u64| -> (f64, f64) {
        let v: Vec<f64> = (0..n)
            .map(|i| prefix_emission(&w, origin, dir, cap, &mut Rng::keyed(1, stream::MISC, 0, i)).x as f64)
            .collect();
        let m = v.iter().sum::<f64>() / n as f64;
        let var = v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (n - 1) as f64;
        (m, (var / n as f64).sqrt())
    };
    let (m, se) = sample(pt.prefix_cap(), 40_000);
    eprintln!("corridor E with cap 100: {m:.4} ± {se:.4}");
    assert!(se > 0.0 && (m - 1.0).abs() < 5.0 * se, "cap 100: E = {m} ± {se}, expected 1");
    assert_eq!(sample(iws.prefix_cap(), 1000).0, 0.0, "a 64-vertex chain cannot reach the emitter");
}
