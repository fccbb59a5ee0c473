//! Mitsuba 3's `spot`, `directional`, `constant` and `envmap` emitters (issue #62 item 1):
//! - furnaces: a white diffuse sphere inside a constant environment, and inside an `envmap` whose
//!   texels are all 1, has the environment's radiance (exactly 1 per pixel, z-test per pixel);
//! - a spot's irradiance on a plane inside its beam, in its transition and outside its cone
//!   against the analytic `I·falloff(θ)·cos θ/d²` (one NEE sample of a point light is exact);
//! - each scene of `tests/scenes/emitters/` against its Mitsuba 3 reference
//!   (`tests/reference/emitters/`, `scripts/mitsuba-emitter-references.py`): a Šidák-corrected
//!   per-pixel z-test and a whole-image z-test at family-wise α = 1e-3 per scene, the variance
//!   of both sides from their passes;
//! - `iws`, `iws-cf` and `pt-cf` agree with `pt` on a scene with each light
//!   (`common::assert_agrees`; under the environments with a mirror sphere, whose caustic on the
//!   floor `pt-cf`'s light paths and camera paths share by MIS), and `--direct vpl`, which
//!   renders none of them, refuses them with a clear error;
//! - bad input: an envmap whose file is missing, truncated, 1×1, or holds NaN, negative or 1e30
//!   texels, a spot with cutoff 0 or above 90°: errors naming the file, the line and the key.

mod common;
use common::{assert_agrees, assert_furnace_is_one, cf_test_opts, global_z, render_passes, tmp_dir};
use forecast::accel::World;
use forecast::image_io::{read_exr, read_exr_variance, write_exr, Image};
use forecast::integrators::{Integrator, Method, MethodArgs};
use forecast::math::Vec3;
use forecast::render::film::Film;
use forecast::sampling::rng::{stream, Rng};
use forecast::scene::{mitsuba, Scene};
use forecast::stats::z_test_threshold;
use std::path::{Path, PathBuf};

const DIR: &str = "tests/scenes/emitters";

fn load(src: &str, dir: &Path) -> Result<Scene, forecast::scene::SceneError> {
    mitsuba::load_str(src, "test.xml", dir, &[])
}

fn build(w: &World, method: Method, o: &MethodArgs) -> Result<Box<dyn Integrator>, String> {
    let bytes = method.preprocess(w, o, 17).map_err(|e| e.to_string())?;
    method.build(w, o, &bytes).map_err(|e| e.to_string())
}

/// A camera 4 units from a unit sphere of white `diffuse`, 16×16, and `emitter`.
fn furnace_scene(emitter: &str) -> String {
    format!(
        r#"<scene version="3.0.0">
  <sensor type="perspective"><float name="fov" value="30"/>
    <transform name="to_world"><lookat origin="0, 0, 4" target="0, 0, 0" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="16"/></film>
  </sensor>
  <shape type="sphere"><float name="radius" value="1"/>
    <bsdf type="diffuse"><rgb name="reflectance" value="1"/></bsdf></shape>
  {emitter}
</scene>"#
    )
}

fn furnace(emitter: &str, dir: &Path, label: &str) {
    let w = World::build(load(&furnace_scene(emitter), dir).unwrap()).unwrap();
    let o = MethodArgs::default();
    for m in [Method::Pt, Method::Iws] {
        let mut integ = build(&w, m, &o).unwrap();
        // 1024 passes: the mean's σ is then below ¼ of `assert_furnace_is_one`'s 1% bound even
        // for `iws`'s light sampling alone (uniform directions: variance 16·⅙ − 1 ≈ 1.7 a sample)
        let img = render_passes(&w, integ.as_mut(), 16, 16, 1024, 3);
        assert_furnace_is_one(&img, &format!("{label}, {}", m.name()));
    }
}

#[test]
fn a_white_sphere_in_a_constant_environment_is_the_environment() {
    furnace(r#"<emitter type="constant"><rgb name="radiance" value="1"/></emitter>"#, Path::new("."), "constant");
}

#[test]
fn a_white_sphere_in_a_uniform_envmap_is_the_environment() {
    let d = tmp_dir("emitters-furnace");
    write_exr(&d.join("one.exr"), &Image::from_fn(8, 4, |_, _| [1.0; 3])).unwrap();
    let e = r#"<emitter type="envmap"><string name="filename" value="one.exr"/>
        <transform name="to_world"><rotate y="1" angle="30"/></transform></emitter>"#;
    furnace(e, &d, "envmap of ones");
}

/// `I·falloff(θ)·(ρ/π)·cos θ/d²` at points of a diffuse plane 2 below a spot aimed straight
/// down (cutoff 30°, beam 20°), from one NEE sample (exact for a point light).
#[test]
fn a_spots_irradiance_on_a_plane_is_analytic() {
    let src = r#"<scene version="3.0.0">
  <sensor type="perspective"><float name="fov" value="40"/><transform name="to_world"><lookat origin="0, 5, 5" target="0, 0, 0" up="0, 1, 0"/></transform></sensor>
  <shape type="rectangle"><transform name="to_world"><scale value="10"/><rotate x="1" angle="-90"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.5"/></bsdf></shape>
  <emitter type="spot"><transform name="to_world"><lookat origin="0, 2, 0" target="0, 0, 0" up="0, 0, 1"/></transform>
    <rgb name="intensity" value="3, 2, 1"/><float name="cutoff_angle" value="30"/><float name="beam_width" value="20"/></emitter>
</scene>"#;
    let w = World::build(load(src, Path::new(".")).unwrap()).unwrap();
    let mut rng = Rng::keyed(1, stream::MISC, 0, 0);
    // θ, the linear falloff of Mitsuba's spot.cpp
    for (theta, falloff) in
        [(0.0f32, 1.0f32), (10.0, 1.0), (19.0, 1.0), (25.0, 0.5), (28.0, 0.2), (31.0, 0.0), (60.0, 0.0)]
    {
        let r = 2.0 * theta.to_radians().tan();
        let (x, z) = (r * 0.6, r * 0.8); // off every axis
        let hit = w.intersect(Vec3::new(x, 1.0, z), -Vec3::Y, f32::INFINITY).unwrap();
        let (m, sp) = w.shade(&hit, Vec3::Y);
        let v = forecast::transport::direct::sample_light(&w, &sp, &m, Vec3::Y, &mut rng);
        let d2 = 4.0 + r * r;
        let cos = 2.0 / d2.sqrt();
        for (c, i) in [3.0f32, 2.0, 1.0].into_iter().enumerate() {
            let want = i * falloff * 0.5 / std::f32::consts::PI * cos / d2;
            let got = v[c];
            assert!((got - want).abs() <= 2e-3 * want.max(1e-3), "θ {theta}°, channel {c}: {got} against {want}");
        }
    }
}

/// The Mitsuba reference of `name` as a film (its mean and variance of the mean from 64 passes).
fn reference(name: &str) -> (Film, Image) {
    let p = PathBuf::from("tests/reference/emitters").join(format!("{name}.exr"));
    let (m, v) = (read_exr(&p).unwrap(), read_exr_variance(&p).unwrap().expect("var.R/G/B channels"));
    let n = 64.0f64;
    let mut data = Vec::new();
    for (a, b) in m.pixels.iter().zip(&v.pixels) {
        data.extend((0..3).map(|c| n * a[c] as f64));
        data.extend((0..3).map(|c| n * ((a[c] as f64).powi(2) + (n - 1.0) * b[c] as f64)));
        data.push(n);
    }
    (Film::from_data(m.width, m.height, data).unwrap(), m)
}

/// Largest per-pixel Welch |z| (the references' variance rounded to 8 bits: 0.4%, 0.2% of z;
/// a `ROUNDING` term for zero-variance pixels), and the number of tests.
fn max_z(a: &Film, b: &Film) -> (f64, usize) {
    let (ma, va, mb, vb) = (a.mean(), a.variance_of_mean(), b.mean(), b.variance_of_mean());
    let mut z = 0.0f64;
    for i in 0..ma.len() {
        for c in 0..3 {
            let (x, y) = (ma[i][c] as f64, mb[i][c] as f64);
            let v = va[i][c] as f64 + vb[i][c] as f64 + (1e-4 * x.abs().max(y.abs())).powi(2);
            if x != y {
                z = z.max((x - y).abs() / v.sqrt());
            }
        }
    }
    (z, ma.len() * 3)
}

fn against_mitsuba(name: &str, spp: u64) {
    let scene = forecast::scene::load(&Path::new(DIR).join(format!("{name}.xml"))).unwrap();
    assert!(scene.warnings.is_empty(), "{name}: {:?}", scene.warnings);
    let (rw, rh) = (scene.camera.width, scene.camera.height);
    let w = World::build(scene).unwrap();
    let mut o = MethodArgs::default();
    o.settings.max_depth = Some(64);
    let mut pt = build(&w, Method::Pt, &o).unwrap();
    let img = render_passes(&w, pt.as_mut(), rw, rh, spp, 1);
    let (r, rm) = reference(name);
    let (z, n) = max_z(&img, &r);
    let thr = z_test_threshold(1e-3, n);
    let (zg, thr1) = (global_z(&img, &r), z_test_threshold(1e-3, 1));
    let mean = |f: &Film| f.mean().iter().map(|p| p[0] as f64 + p[1] as f64 + p[2] as f64).sum::<f64>();
    eprintln!(
        "{name}: pt {spp} spp: max|z| {z:.2} (threshold {thr:.2} over {n}), global z {zg:+.2} (threshold {thr1:.2}); \
         mean pt {:.5}, Mitsuba {:.5}",
        mean(&img) / (3 * rm.pixels.len()) as f64,
        mean(&r) / (3 * rm.pixels.len()) as f64
    );
    assert!(z < thr, "{name}: a pixel disagrees with Mitsuba 3: max|z| {z:.2} >= {thr:.2}");
    assert!(zg.abs() < thr1, "{name}: the image mean disagrees with Mitsuba 3: z {zg:.2}");
    common::assert_detects(&img, &r, 0.01, thr1, name);
}

#[test]
fn spot_agrees_with_mitsuba() {
    against_mitsuba("spot", 4096);
}

#[test]
fn directional_agrees_with_mitsuba() {
    against_mitsuba("directional", 4096);
}

#[test]
fn constant_agrees_with_mitsuba() {
    against_mitsuba("constant", 4096);
}

#[test]
fn envmap_agrees_with_mitsuba() {
    against_mitsuba("envmap", 4096);
}

/// The scene `name` at 16×16, its mirror sphere made diffuse where `no_mirror` (caustics of a
/// light that is a Dirac in position or direction, `L S D`, are `pt`'s blind spot).
fn small_world(name: &str, no_mirror: bool) -> World {
    let mut src = std::fs::read_to_string(Path::new(DIR).join(format!("{name}.xml"))).unwrap();
    src = src.replace(r#"value="32"/>"#, r#"value="16"/>"#);
    if no_mirror {
        let mirror = r#"<bsdf type="conductor"><string name="material" value="Al"/></bsdf>"#;
        assert!(src.contains(mirror));
        src = src.replace(mirror, r#"<bsdf type="diffuse"><rgb name="reflectance" value="0.8"/></bsdf>"#);
    }
    World::build(mitsuba::load_str(&src, &format!("{name}.xml"), Path::new(DIR), &[]).unwrap()).unwrap()
}

fn every_method_agrees(name: &str, no_mirror: bool, methods: &[Method]) {
    let w = small_world(name, no_mirror);
    let o = cf_test_opts();
    let reference = render_passes(&w, build(&w, Method::Pt, &o).unwrap().as_mut(), 16, 16, 16384, 11);
    for &m in methods {
        let mut integ = build(&w, m, &o).unwrap();
        if m == Method::PtCf && !no_mirror {
            // the light side is on and reaches the camera (the mirror's caustic)
            let cam = w.scene.camera.with_resolution(16, 16);
            let tracer = integ.light_tracer().expect("pt-cf traces light paths");
            let sum: f64 = (0..32)
                .map(|pass| {
                    tracer.light_splats(&w, &cam, 3, pass).image.iter().map(|c| (c.x + c.y + c.z) as f64).sum::<f64>()
                })
                .sum();
            eprintln!("{name}: pt-cf's light splats of passes 0..32 sum to {sum:.4}");
            assert!(sum > 0.0, "{name}: pt-cf's light paths splat nothing");
        }
        let img = render_passes(&w, integ.as_mut(), 16, 16, 4096, 3);
        assert_agrees(&img, &reference, &format!("{name}: {}", m.name()));
    }
}

#[test]
fn every_method_agrees_with_pt_under_a_spot() {
    every_method_agrees("spot", true, &[Method::Iws, Method::IwsCf, Method::PtCf]);
}

#[test]
fn every_method_agrees_with_pt_under_a_directional_light() {
    every_method_agrees("directional", true, &[Method::Iws, Method::IwsCf, Method::PtCf]);
}

#[test]
fn every_method_agrees_with_pt_under_a_constant_environment() {
    every_method_agrees("constant", false, &[Method::IwsCf, Method::PtCf]);
}

#[test]
fn every_method_agrees_with_pt_under_an_envmap() {
    every_method_agrees("envmap", false, &[Method::IwsCf, Method::PtCf]);
}

/// `--direct vpl` (the emitter point lights of the IWS methods) refuses every new light.
#[test]
fn methods_that_cannot_render_a_light_refuse_it() {
    for name in ["spot", "directional", "constant", "envmap"] {
        let w = small_world(name, false);
        let mut o = cf_test_opts();
        o.iws.direct = forecast::integrators::iws::DirectLight::Vpl;
        for m in [Method::Iws, Method::IwsPm] {
            let e = build(&w, m, &o).err().expect("--direct vpl refuses");
            assert!(e.contains("--direct"), "{e}");
        }
    }
}

// ------------------------------------------------------------------------------------ bad input

fn envmap_error(setup: impl FnOnce(&Path), label: &str) -> String {
    let d = tmp_dir(&format!("emitters-bad-{label}"));
    setup(&d);
    let src = furnace_scene("<emitter type=\"envmap\">\n    <string name=\"filename\" value=\"env.exr\"/></emitter>");
    let e = load(&src, &d).err().unwrap_or_else(|| panic!("{label}: loads")).to_string();
    eprintln!("{label}: {e}");
    assert!(e.starts_with("test.xml:9: key `envmap.filename`"), "{label}: {e}");
    assert!(e.contains("env.exr"), "{label}: names the image: {e}");
    e
}

#[test]
fn bad_envmaps_are_clear_errors() {
    envmap_error(|_| {}, "missing");
    let good = |d: &Path| write_exr(&d.join("env.exr"), &Image::from_fn(8, 4, |_, _| [1.0; 3])).unwrap();
    envmap_error(
        |d| {
            good(d);
            let b = std::fs::read(d.join("env.exr")).unwrap();
            std::fs::write(d.join("env.exr"), &b[..b.len() / 2]).unwrap();
        },
        "truncated",
    );
    let e = envmap_error(|d| write_exr(&d.join("env.exr"), &Image::from_fn(1, 1, |_, _| [1.0; 3])).unwrap(), "1x1");
    assert!(e.contains("1x1"), "{e}");
    for (label, v) in [("nan", f32::NAN), ("negative", -1.0), ("huge", 1e30)] {
        let e = envmap_error(
            |d| {
                let img = Image::from_fn(8, 4, |x, y| if (x, y) == (3, 2) { [0.5, v, 0.5] } else { [1.0; 3] });
                write_exr(&d.join("env.exr"), &img).unwrap()
            },
            label,
        );
        assert!(e.contains("(3, 2)"), "{label}: names the texel: {e}");
    }
}

#[test]
fn bad_spots_are_clear_errors() {
    for (cutoff, beam) in [("0", ""), ("95", ""), ("-5", ""), ("30", r#"<float name="beam_width" value="40"/>"#)] {
        let src = furnace_scene(&format!(
            "<emitter type=\"spot\">\n    <float name=\"cutoff_angle\" value=\"{cutoff}\"/>\n    {beam}</emitter>"
        ));
        let e = load(&src, Path::new(".")).expect_err("refused").to_string();
        eprintln!("{e}");
        let key =
            if beam.is_empty() { "test.xml:9: key `spot.cutoff_angle`" } else { "test.xml:10: key `spot.beam_width`" };
        assert!(e.starts_with(key), "{e}");
    }
    let two = furnace_scene(
        r#"<emitter type="constant"/>
  <emitter type="constant"/>"#,
    );
    let e = load(&two, Path::new(".")).expect_err("refused").to_string();
    assert!(e.contains("only one environment"), "{e}");
}

/// The TOML `[[light]]` types `spot`, `directional` and `constant` load as the Mitsuba plugins,
/// and `export-mitsuba` writes them so that the XML renders bit for bit the same `pt` image.
#[test]
fn toml_lights_export_to_mitsuba_and_back() {
    let d = tmp_dir("emitters-toml");
    let toml = d.join("t.toml");
    std::fs::copy(Path::new(DIR).join("toml-lights.toml"), &toml).unwrap();
    let xml = d.join("t.xml");
    forecast::scene::export::export_mitsuba(&toml, &xml).unwrap();
    let render = |p: &Path| {
        let w = World::build(forecast::scene::load(p).unwrap()).unwrap();
        assert!(w.scene.has_spot_lights() && w.scene.has_infinite_lights(), "{}", p.display());
        let mut pt = build(&w, Method::Pt, &MethodArgs::default()).unwrap();
        render_passes(&w, pt.as_mut(), 16, 16, 16, 5).mean()
    };
    assert_eq!(render(&toml), render(&xml));
    // a TOML spot's bad cutoff names its key
    let src = std::fs::read_to_string(&toml).unwrap().replace("cutoff_angle = 30.0", "cutoff_angle = 95.0");
    let e = forecast::scene::load_str(&src, "t.toml", &d).expect_err("refused").to_string();
    assert!(e.contains("light[0].cutoff_angle") && e.contains("95"), "{e}");
}

/// The emission split (`--emission-split`, `render::pixel`) sees the environment along its extra
/// camera rays as the methods' own `prefix_le` does (directly and through the mirror): `pt` and
/// `pt-cf` with 4 rays per pixel everywhere agree with `pt` unsplit under the envmap.
#[test]
fn the_emission_split_sees_the_environment() {
    let w = small_world("envmap", false);
    let o = cf_test_opts();
    let reference = render_passes(&w, build(&w, Method::Pt, &o).unwrap().as_mut(), 16, 16, 16384, 11);
    let cam = w.scene.camera.with_resolution(16, 16);
    for m in [Method::Pt, Method::PtCf] {
        let mut integ = build(&w, m, &o).unwrap();
        let pixels = forecast::render::PixelSampler::everywhere(&cam, 4, integ.prefix_cap());
        let (img, _) = common::render_sampled(&w, integ.as_mut(), &pixels, 4096, 3);
        assert_agrees(&img, &reference, &format!("envmap, {} with the emission split", m.name()));
    }
}
