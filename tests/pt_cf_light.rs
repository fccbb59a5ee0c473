//! `pt-cf`'s light-traced caustics (issue #34, `integrators::pt_cf::light`): agreement with `pt`
//! (Šidák per-pixel and whole-image z-tests, α = 1e-3, `common::assert_agrees`) with area lights
//! on `cornell-box` and `ring`, with a light inside glass and through smooth-shaded glass; the
//! glass furnace; the analytic point-light caustic of a planar mirror (which `pt` misses); `--light-paths 0` is the old
//! `pt-cf` bit for bit (a stored render of the base commit); the image and the light-path pilot
//! do not depend on the thread count, and a resumed render is the uninterrupted one. The MIS weights' sum is a unit
//! test in `src/integrators/pt_cf/light.rs`.

mod common;
use common::{
    assert_agrees, assert_furnace_is_one, assert_same_image, cf_test_opts as opts, job, render_film, render_passes,
    tmp_dir, world,
};
use forecast::accel::World;
use forecast::integrators::{Integrator, Method, MethodArgs};
use forecast::render::film::Film;
use forecast::stats::z_test_threshold;
use std::path::{Path, PathBuf};
use std::process::Command;

fn build(world: &World, method: Method, o: &MethodArgs) -> Box<dyn Integrator> {
    let bytes = method.preprocess(world, o, 17).unwrap();
    method.build(world, o, &bytes).unwrap()
}

fn pt(world: &World, res: u32, spp: u64) -> Film {
    let mut p = Method::Pt.build(world, &opts(), &[]).unwrap();
    render_passes(world, p.as_mut(), res, res, spp, 11)
}

/// The summed light splats of pass 0 at `res`² (the light side is really on).
fn splat_sum(w: &World, g: &dyn Integrator, res: u32) -> f64 {
    let cam = w.scene.camera.with_resolution(res, res);
    let s = g.light_tracer().expect("pt-cf traces light paths by default").light_splats(w, &cam, 3, 0);
    s.image.iter().map(|c| (c.x + c.y + c.z) as f64).sum()
}

/// `pt-cf` (light paths on, `o`) agrees with `pt` on `w`.
fn agrees_with_pt(w: &World, o: &MethodArgs, res: u32, (spp_pt, spp): (u64, u64), label: &str) {
    let reference = pt(w, res, spp_pt);
    let mut g = build(w, Method::PtCf, o);
    if o.ptcf.light_paths != Some(0) {
        let s = splat_sum(w, g.as_ref(), res);
        eprintln!("{label}: pass 0 splat sum {s}");
        assert!(s > 0.0, "{label}: no light path reached the camera");
    }
    let img = render_passes(w, g.as_mut(), res, res, spp, 3);
    assert_agrees(&img, &reference, label);
}

#[test]
fn light_paths_agree_with_pt_on_cornell_box() {
    // (65,536, 8,192) for the negative control's power, as `tests/pt_cf.rs`' defaults test
    agrees_with_pt(&world("scenes/cornell-box.toml"), &opts(), 16, (65536, 8192), "pt-cf+L cornell-box");
}

/// Many light paths per pixel (8; the light side dominates C) with splitting and guiding at
/// three depths: the weights at guided and split vertices. At 8² with 131,072 `pt` and 8,192
/// `pt-cf` samples per pixel, as `tests/pt_cf.rs`' share-rule test and for the same reason (heavy
/// tails at 16² and (4096, 512)); seeds 3–8 give max|z| 2.4–3.9 against the threshold 4.6.
#[test]
fn many_light_paths_with_strong_guiding_agree_with_pt_on_cornell_box() {
    let mut o = opts();
    (o.ptcf.guide_fraction, o.ptcf.guide_min_share, o.cf.split, o.cf.table_depth) = (0.1, 0.0, 4, 3);
    o.ptcf.light_paths = Some(512);
    // 65,536 passes for the negative control's power (at 8,192 a 3% error moved the global z by
    // 3.74, 94% of the variance in the image; 3.74 / √(0.94/8 + 0.06) ≈ 8.9)
    agrees_with_pt(&world("scenes/cornell-box.toml"), &o, 8, (131_072, 65536), "pt-cf+L 512 c=0.1 S0=4 D=3");
}

/// `ring` with a wider light (as `tests/pt_cf.rs`, so that `pt` converges at 8²).
#[test]
fn light_paths_agree_with_pt_on_ring() {
    let w = common::ring_with_wide_light();
    agrees_with_pt(&w, &opts(), 8, (16384, 2048), "pt-cf+L ring (wide light)");
}

/// A light inside a glass ball over a floor (`tests/scenes/glass-bulb.toml`): the receiver and the
/// light lie in media of different index, whose `(η_x1/η_y0)²` factor the MIS ratio leaves out
/// (docs/limitations.md). Both sides evaluate the same ratio for a path, so the weights still sum
/// to one and the image is unbiased: `pt-cf` agrees with `pt`. The emission falls back to the
/// cosine lobe here (the light is inside the Dirac bounds).
#[test]
fn light_inside_glass_agrees_with_pt() {
    // 8× both counts for the negative control's power: at (16,384, 2,048) a 3% error moved the
    // global z by 2.84 (45% of the variance in the image); 2.84 · √8 ≈ 8.0
    agrees_with_pt(&world("tests/scenes/glass-bulb.toml"), &opts(), 8, (131_072, 16384), "pt-cf+L glass bulb");
}

#[test]
fn glass_furnace_with_light_paths_is_exactly_one() {
    let w = world("tests/scenes/glass-furnace-white.toml");
    let mut o = opts();
    // few light paths end on the white ball through the glass: 16 per pixel so that many do
    (o.cf.table_depth, o.ptcf.light_paths) = (4, Some(4096));
    let mut g = build(&w, Method::PtCf, &o);
    assert!(splat_sum(&w, g.as_ref(), 16) > 0.0, "no light path reached the camera");
    let img = render_passes(&w, g.as_mut(), 16, 16, 512, 5);
    assert_furnace_is_one(&img, "pt-cf+L glass furnace");
}

/// The point light under a mirror (`tests/scenes/point-mirror.toml`): on the pixels wholly on the
/// patch, `pt` renders the direct light ρ/π·I cosθ/d² and `pt-cf` adds the mirror's caustic, the
/// direct light of the image source `R·I` at (0, 3, 0). Per-pixel z against the analytic values
/// at the pixel centres (the terms vary by < 1e-4 over a pixel; second-order light < 1e-3), and
/// `pt-cf − pt` against the caustic alone (`pt`'s tiny variance would resolve those 1e-3).
#[test]
fn point_light_mirror_caustic_is_the_image_source() {
    let w = world("tests/scenes/point-mirror.toml");
    let res = 16;
    let cam = w.scene.camera.with_resolution(res, res);
    let (rho, r, i) = (0.5f64, 0.5f64, 10.0f64);
    let term = |x: f64, z: f64, h: f64| rho / std::f64::consts::PI * i * h / (x * x + h * h + z * z).powf(1.5);
    let on_patch = |px: f32, py: f32| {
        let d = cam.direction(px, py);
        let t = -cam.position.y / d.y;
        let p = cam.position + t * d;
        (p.x.abs() < 0.19 && p.z.abs() < 0.19).then_some((p.x as f64, p.z as f64))
    };
    let mut o = opts();
    o.ptcf.light_paths = Some(4096);
    let mut g = build(&w, Method::PtCf, &o);
    let with_light = render_passes(&w, g.as_mut(), res, res, 1500, 5);
    let plain = pt(&w, res, 256);
    let (mut tested, mut zmax_cf, mut zmax_pt) = (0usize, 0.0f64, 0.0f64);
    let (m_cf, v_cf, m_pt, v_pt) =
        (with_light.mean(), with_light.variance_of_mean(), plain.mean(), plain.variance_of_mean());
    let n = (res * res) as usize * 3;
    for y in 0..res {
        for x in 0..res {
            let corners = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)];
            if corners.iter().any(|&(a, b)| on_patch(x as f32 + a, y as f32 + b).is_none()) {
                continue;
            }
            let (px, pz) = on_patch(x as f32 + 0.5, y as f32 + 0.5).unwrap();
            let (direct, caustic) = (term(px, pz, 1.0), r * term(px, pz, 3.0));
            let k = (y * res + x) as usize;
            tested += 1;
            let z = |m: f32, v: f32, want: f64| (m as f64 - want).abs() / (v as f64).sqrt().max(1e-30);
            zmax_cf = zmax_cf.max(z(m_cf[k][0], v_cf[k][0], direct + caustic));
            // the caustic alone: pt-cf − pt (footprint and second-order light cancel to < 1e-3)
            let diff = m_cf[k][0] - m_pt[k][0];
            zmax_pt = zmax_pt.max(z(diff, v_cf[k][0] + v_pt[k][0], caustic));
            // pt gives no caustic: its mean is the direct light alone, far below direct + caustic
            assert!((m_pt[k][0] as f64) < direct + 0.5 * caustic, "pixel {k}: pt {} direct {direct}", m_pt[k][0]);
        }
    }
    let thr = z_test_threshold(1e-3, n);
    eprintln!("point mirror: {tested} pixels, max|z| pt-cf {zmax_cf:.2}, pt-cf − pt {zmax_pt:.2}, threshold {thr:.2}");
    assert!(tested >= 16, "only {tested} pixels on the patch");
    assert!(zmax_cf < thr, "pt-cf misses the analytic point-light caustic: max|z| {zmax_cf}");
    assert!(zmax_pt < thr, "pt-cf − pt differs from the analytic caustic: max|z| {zmax_pt}");
}

fn bin() -> &'static str {
    env!("CARGO_BIN_EXE_forecast")
}

/// `pt-cf --light-paths 0` renders exactly what `pt-cf` rendered before the light paths: the
/// stored EXR was written by the base commit 3a693d7 with the same command line, and rewritten
/// with the same command line by each intended change of `pt-cf`'s camera side since: the
/// roulette after guided vertices (`results/2026-12-04-guided-roulette.md`) and the targeted
/// emission's cone per Dirac object (`results/2026-12-05-targeted-cones.md`), both z-tested against
/// `pt` by `tests/pt_cf.rs`, and the concentric map's polynomial sine and cosine, which moved the
/// last bits of every cosine-sampled direction (`results/2026-12-05-diffuse-lanes.md`, z-tested
/// against the images before); and the emission-split probe's chains at mirror and glass points,
/// which split one more of its pixels (`results/2026-12-06-glass-probe.md`; with
/// `--emission-split 1` the image was the same bit for bit); and the probe's finer lattice below
/// 640 pixels across, which splits 12 of its pixels instead of 9
/// (`results/2026-12-06-probe-resolution.md`; again the same bit for bit with `--emission-split
/// 1`); and emission splitting's `K` = 64 by default with the probe's cell maps
/// (`results/2026-12-08-split-k.md`, `results/2026-12-08-cell-maps.md`, z-tested by
/// `tests/emission_split.rs`; with `--emission-split 1` the same bit for bit). It renders with `--sampler
/// independent`, the camera streams as they were before the Sobol prefix (docs/sampling.md),
/// which are the same bit for bit, and with `--accel obvhs`, the tree it was written with (the
/// default tree, `wide`, differs at exact ties in t: results/2026-12-07-own-tree.md). Regenerate it
/// only for such a change, and say so there.
#[test]
fn light_paths_zero_is_the_old_pt_cf_bit_for_bit() {
    let d = tmp_dir("light-paths-0");
    let out = d.join("lp0");
    let st = Command::new(bin())
        .args(["render", "scenes/cornell-box.toml", "--method", "pt-cf", "--light-paths", "0", "--spp", "4"])
        .args(["--resolution", "24x24", "--seed", "5", "--threads", "2", "--forecast-photons", "20000"])
        .args(["--clusters", "16", "--sampler", "independent", "--accel", "obvhs", "--quiet", "--out"])
        .arg(&out)
        .status()
        .unwrap();
    assert!(st.success());
    let stored = Path::new("tests/reference/pt-cf-light-paths-0-cornell-24-seed5.exr");
    let (a, b) = (
        forecast::image_io::read_exr(&out.with_extension("exr")).unwrap(),
        forecast::image_io::read_exr(stored).unwrap(),
    );
    assert!(a.pixels == b.pixels, "--light-paths 0 differs from the old pt-cf");
}

/// A `pt-cf` job with the light paths on (small preprocess).
fn light_job(out: &Path, threads: usize, spp: u64) -> forecast::pipeline::RenderJob {
    let mut j = job(Path::new("scenes/cornell-box.toml"), Method::PtCf, spp, 7, (32, 32), threads, out);
    (j.args.cf.forecast_photons, j.args.cf.clusters) = (Some(20_000), 16);
    j
}

#[test]
fn light_paths_do_not_depend_on_the_thread_count() {
    let d = tmp_dir("light-threads");
    let one = render_film(&light_job(&d.join("one"), 1, 3));
    let two = render_film(&light_job(&d.join("two"), 2, 3));
    assert!(one.data == two.data, "1 and 2 threads differ");
    let mut off = light_job(&d.join("off"), 2, 3);
    off.args.ptcf.light_paths = Some(0);
    assert!(render_film(&off).data != two.data, "the light paths changed nothing");
}

/// Without `--light-paths`, the pilot (`pipeline::light_pilot`) picks the count: the report holds
/// its figures and the count the render used, neither depends on the thread count, nor does the
/// image; a given count runs no pilot.
#[test]
fn the_light_path_pilot_is_recorded_and_does_not_depend_on_the_thread_count() {
    use forecast::distributed::local::Local;
    let d = tmp_dir("light-pilot");
    let report = |j: &forecast::pipeline::RenderJob| {
        let r = forecast::pipeline::render(j, &Local::new(), std::time::Instant::now()).unwrap().unwrap();
        serde_json::to_value(&r.report).unwrap()
    };
    let pilot = |out: &Path, threads| light_job(out, threads, 1);
    let (one, two) = (report(&pilot(&d.join("one"), 1)), report(&pilot(&d.join("two"), 2)));
    assert_same_image(&d.join("one.exr"), &d.join("two.exr"));
    let rule = &one["light_path_rule"];
    assert_eq!(rule, &two["light_path_rule"], "the pilot differs between 1 and 2 threads");
    assert_eq!(rule["pilot_resolution"], serde_json::json!([32, 32]), "a 32² image is its own pilot");
    let nu = rule["paths_per_pixel"].as_f64().unwrap();
    assert_eq!(rule["light_paths"].as_u64(), Some((nu * 1024.0).ceil() as u64), "{rule}");
    assert_eq!(one["options"]["light_paths"], rule["light_paths"], "the render used another count");
    // the chosen count is the candidate of least variance × rays, and more paths cost more rays
    let cands = rule["candidates"].as_array().unwrap();
    let f = |c: &serde_json::Value, k: &str| c[k].as_f64().unwrap();
    let least = cands.iter().map(|c| f(c, "relative_variance_x_rays")).fold(f64::INFINITY, f64::min);
    let chosen = cands.iter().find(|c| f(c, "paths_per_pixel") == nu).expect("the choice is a candidate");
    assert_eq!(f(chosen, "relative_variance_x_rays"), least, "{rule}");
    assert!(cands.windows(2).all(|w| f(&w[1], "rays_per_pixel") > f(&w[0], "rays_per_pixel")), "{rule}");
    assert!(cands.iter().all(|c| f(c, "variance") > 0.0), "{rule}");
    let mut given = light_job(&d.join("given"), 2, 1);
    given.args.ptcf.light_paths = Some(100);
    let g = report(&given);
    assert!(g["light_path_rule"].is_null() && g["options"]["light_paths"] == 100, "{}", g["options"]);
}

#[test]
fn a_resumed_render_with_light_paths_is_the_uninterrupted_one() {
    let d = tmp_dir("light-resume");
    let run = |spp: &str, out: &PathBuf, extra: &[&str]| {
        let st = Command::new(bin())
            .args(["render", "scenes/cornell-box.toml", "--method", "pt-cf", "--resolution", "16x16", "--seed", "1"])
            .args(["--threads", "1", "--quiet", "--forecast-photons", "20000", "--clusters", "16", "--spp", spp])
            .args(extra)
            .arg("--out")
            .arg(out)
            .status()
            .unwrap();
        assert!(st.success());
    };
    let (full, a, b) = (d.join("full"), d.join("a"), d.join("b"));
    run("4", &full, &[]);
    run("2", &a, &["--checkpoint-every", "1h"]);
    run("4", &b, &["--resume", &format!("{}.ckpt", a.display())]);
    assert_same_image(&b.with_extension("exr"), &full.with_extension("exr"));
}

/// `figurines` (glass figurines and a mirror tin on a glossy table) at 8²: more light paths per
/// pixel than the default so that the light side matters at this size.
#[test]
fn light_paths_agree_with_pt_on_figurines() {
    let w = world("scenes/figurines.toml");
    let mut o = opts();
    o.ptcf.light_paths = Some(1024);
    agrees_with_pt(&w, &o, 8, (16384, 2048), "pt-cf+L figurines");
}

/// The SMS gold ring (`scenes/external/sms-ring`, Mitsuba XML) with its light 40× wider and 1600×
/// dimmer (the same power), so that `pt` converges at 8²: the conductor's Fresnel chain. (With
/// the light only 10× wider, `pt` at 16384 spp is still short of its heavy tail: `pt-cf` with
/// and without light paths agree with each other there and both lie above `pt`, global z 4.4.)
#[test]
fn light_paths_agree_with_pt_on_sms_ring() {
    let src = std::fs::read_to_string("scenes/external/sms-ring/ring.xml").unwrap();
    let wide = src
        .replace(r#"<scale x="0.1" y="0.1" z="0.1"/>"#, r#"<scale x="4" y="4" z="4"/>"#)
        .replace(r#"<spectrum name="radiance" value="70000"/>"#, r#"<spectrum name="radiance" value="43.75"/>"#);
    assert!(wide.contains(r#"value="43.75""#) && wide.contains(r#"<scale x="4" y="4" z="4"/>"#), "ring.xml changed");
    let d = tmp_dir("sms-ring-wide");
    let path = d.join("ring-wide.xml");
    std::fs::write(&path, wide).unwrap();
    let w = World::build(forecast::scene::load(&path).unwrap()).unwrap();
    let mut o = opts();
    o.ptcf.light_paths = Some(1024);
    agrees_with_pt(&w, &o, 8, (16384, 2048), "pt-cf+L sms-ring (wide light)");
}

/// What `--resume` compares (`pipeline::job_keys`) holds the light paths when given and not when
/// the pilot chose them: the pilot reads the CF product, whose photon count under `--time`
/// follows the machine's speed, so a resume may pick another count (each pass unbiased at any).
#[test]
fn the_pilots_count_is_not_what_a_resume_compares() {
    let scene = forecast::scene::load(Path::new("scenes/cornell-box.toml")).unwrap();
    let d = tmp_dir("light-keys");
    let keys = |light_paths: Option<u64>| {
        let mut j = light_job(&d.join("k"), 1, 1);
        j.args.ptcf.light_paths = light_paths;
        let mut plan = j.resolve(&scene).unwrap();
        plan.args.ptcf.light_paths = Some(light_paths.unwrap_or(128)); // as the preprocess sets it
        forecast::pipeline::job_keys(&j, &plan)
    };
    let has = |k: &[(String, String)]| k.iter().any(|(name, _)| name == "option light_paths");
    assert!(!has(&keys(None)), "the pilot's count is compared on resume");
    assert!(has(&keys(Some(100))), "a given count is not compared on resume");
    assert!(keys(None).iter().any(|(name, _)| name == "option guide_fraction"), "the other options are");
}

/// A smooth-shaded glass icosphere (`tests/scenes/smooth-glass.toml`, shading normals up to 21°
/// from the faces): light paths refract about the shading normals, so their throughput needs
/// Veach's adjoint shading-normal factor at every glass vertex, as at every other vertex. (Not
/// against the camera side alone: its `L S+ D E` tails through the small light are too heavy.)
/// Without the factor at glass (before this test) it failed: max|z| 11.6 against the threshold 4.84.
#[test]
fn light_paths_through_smooth_glass_agree_with_pt() {
    let w = world("tests/scenes/smooth-glass.toml");
    let mut o = opts();
    o.ptcf.light_paths = Some(1024);
    agrees_with_pt(&w, &o, 16, (262_144, 8192), "pt-cf+L smooth glass");
}
