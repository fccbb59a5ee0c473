//! Per-plugin agreement with Mitsuba 3: each scene of `tests/scenes/mitsuba-plugins/` (one
//! plugin or feature in the same closed room, 64 × 64) rendered by `pt` agrees with the
//! committed Mitsuba 3.9.1 reference in `tests/reference/plugins/` (made by
//! `scripts/mitsuba-plugin-references.py`: `path`, box pixel filter, 16,384 spp in 64 passes;
//! provenance in `tests/reference/README.md`).
//!
//! Per scene, at a family-wise significance [`ALPHA`] = 1e-3 over all [`SCENES`] (Šidák: the
//! per-scene level is `α_s = 1 − (1 − α)^(1/S)`):
//! - every pixel and channel: the Welch z of `pt` against the reference, threshold
//!   `z_test_threshold(α_s, 3·64·64)` (Šidák again over the pixel-channels). The reference's
//!   variance of the mean is the spread of its 64 passes (the `var.*` channels of its EXR).
//!   `pt`'s is the larger of its own (s²/n) and Mitsuba's per-sample variance over `pt`'s n
//!   ([`REF_SPP`] · var_ref / n): a pixel whose light comes from a rare path (a sliver of a
//!   bright reflection, a caustic) that `pt`'s n samples missed has no trace of it in its own
//!   variance, and a z against that is not normal (at 512 spp the normal-mapped mirror and glass
//!   scenes gave |z| 10 in such pixels, and `pt` at 8192 spp agreed there within |z| 3.8). Where
//!   `pt` is the less noisy renderer this overstates its variance: conservative;
//! - the image mean: the whole-image z (`common::global_z`, its conservative variance bound)
//!   and each channel's mean, thresholds `z_test_threshold(α_s, 1)` and `z_test_threshold(α_s, 3)`,
//!   with `pt`'s own variances;
//! - the test has power: a 1% error of the whole image would move the global z by more than
//!   twice its threshold (`common::assert_detects`), and a few scenes with their plugin's
//!   feature taken away (no normal map, uv not flipped, the one-sided panel two-sided) fail the
//!   per-pixel test ([`negative_controls_fail`]);
//! - and `scripts/check-mitsuba.sh`'s rule (`metrics::mitsuba_agreement`: means within 0.5%, the
//!   noise ratio from the reference halves within its 5σ), as `forecast diff --half0 --half1`.
//!
//! A scene that disagrees is a renderer bug to report (with the figures), never a threshold to
//! tune. `MITSUBA_PLUGINS_DUMP=DIR` writes each `pt` image (with its variance) to `DIR/NAME.exr`
//! for that (`forecast diff DIR/NAME.exr tests/reference/plugins/NAME.exr --half0 ... --half1 ...`).

mod common;
use common::{assert_detects, global_z, render_passes, root};
use forecast::accel::World;
use forecast::image_io::{read_exr, read_exr_variance, Image};
use forecast::integrators::{Method, MethodArgs};
use forecast::render::film::{Film, STRIDE};
use forecast::stats::{sidak_alpha, z_test_threshold};
use std::path::PathBuf;
use std::time::Instant;

/// Family-wise significance of each kind of test over all scenes.
const ALPHA: f64 = 1e-3;

/// The scenes and `pt`'s samples per pixel for each (the test's cost; the reference's own
/// variance, 1/32 of `pt`'s at 512 spp, is in the z statistics).
const SCENES: &[(&str, u64)] = &[
    ("bitmap-png", 512),
    ("bitmap-exr", 512),
    ("checkerboard", 512),
    ("texture-ref", 512),
    ("normalmap-diffuse", 512),
    ("normalmap-conductor", 512),
    ("normalmap-dielectric", 512),
    ("plastic", 512),
    ("plastic-nonlinear", 512),
    ("thindielectric", 512),
    ("onesided", 512),
    ("obj-uv", 512),
    ("ply-uv", 512),
    ("roughconductor-ggx", 512),
    ("roughconductor-beckmann", 512),
    ("roughdielectric-ggx", 512),
    ("roughdielectric-beckmann", 512),
    ("roughplastic-ggx", 512),
    ("roughplastic-beckmann", 512),
    ("bumpmap-diffuse", 512),
    ("bumpmap-conductor", 512),
    ("roughconductor-aniso", 512),
    ("roughdielectric-aniso", 512),
    ("aniso-maps", 512),
];

/// The reference's passes (the `var.*` channels are the variance of the mean of this many).
const REF_PASSES: f64 = 64.0;

/// The reference's samples per pixel (checked against `tests/reference/plugins/renders.jsonl`).
const REF_SPP: f64 = 16384.0;

/// `pt`'s path-vertex cap: 64 surface vertices, NEE at each = the scenes' `max_depth` 65.
const MAX_DEPTH: u32 = 64;

fn scene_path(name: &str) -> PathBuf {
    root().join("tests/scenes/mitsuba-plugins").join(format!("{name}.xml"))
}

fn ref_path(name: &str, suffix: &str) -> PathBuf {
    root().join("tests/reference/plugins").join(format!("{name}{suffix}.exr"))
}

/// The per-scene level: Šidák over the scenes.
fn scene_alpha() -> f64 {
    sidak_alpha(ALPHA, SCENES.len())
}

/// The reference as a film of `REF_PASSES` samples per pixel with its mean and variance of the
/// mean (Σx = n·m, Σx² = n·(m² + (n − 1)·v)), so the suite's z statistics apply unchanged.
fn reference_film(mean: &Image, var: &Image) -> Film {
    let n = REF_PASSES;
    let mut data = Vec::with_capacity(mean.pixels.len() * STRIDE);
    for (m, v) in mean.pixels.iter().zip(&var.pixels) {
        let (m, v) = (m.map(|x| x as f64), v.map(|x| x as f64));
        data.extend((0..3).map(|c| n * m[c]));
        data.extend((0..3).map(|c| n * (m[c] * m[c] + (n - 1.0) * v[c])));
        data.push(n);
    }
    Film::from_data(mean.width, mean.height, data).expect("sizes match")
}

fn image_of(rows: Vec<[f32; 3]>, w: usize, h: usize) -> Image {
    Image::from_pixels(w, h, rows).expect("sizes match")
}

/// Per-channel z of the image means (pixels independent, channels tested separately).
fn channel_mean_z(a: &Film, b: &Film) -> [f64; 3] {
    let (ma, va, mb, vb) = (a.mean(), a.variance_of_mean(), b.mean(), b.variance_of_mean());
    std::array::from_fn(|c| {
        let (mut d, mut v) = (0.0f64, 0.0f64);
        for i in 0..ma.len() {
            d += ma[i][c] as f64 - mb[i][c] as f64;
            v += va[i][c] as f64 + vb[i][c] as f64;
        }
        d / v.sqrt()
    })
}

/// Relative rounding of a pixel's mean in the two renderers' 32-bit films and sums: a pixel that
/// sees only the light is 4.6 exactly in `pt` and 4.59999 in Mitsuba, both with zero variance.
const ROUNDING: f64 = 1e-5;

/// Per-pixel, per-channel Welch z of `pt` against the reference `r`: `pt`'s variance of the mean
/// the larger of its own and `REF_SPP · var_r / n` (the module docs), plus the rounding floor
/// `(ROUNDING · mean)²` so that zero-variance pixels compare to rounding. Returns the largest
/// |z|, its index `3·pixel + channel`, and the number of tests.
fn max_z(pt: &Film, r: &Film) -> (f64, usize, usize) {
    let (ma, va, mb, vb) = (pt.mean(), pt.variance_of_mean(), r.mean(), r.variance_of_mean());
    let mut best = (0.0f64, 0);
    for i in 0..ma.len() {
        let scale = REF_SPP / pt.count(i).max(1.0);
        for c in 0..3 {
            let (x, y, vr) = (ma[i][c] as f64, mb[i][c] as f64, vb[i][c] as f64);
            let vt = (va[i][c] as f64).max(scale * vr);
            let v = vt + vr + (ROUNDING * x.abs().max(y.abs())).powi(2);
            let z = if x == y {
                0.0
            } else if v > 0.0 {
                (x - y).abs() / v.sqrt()
            } else {
                f64::INFINITY
            };
            if z > best.0 {
                best = (z, 3 * i + c);
            }
        }
    }
    (best.0, best.1, ma.len() * 3)
}

/// The reference of `name`: its mean, its variance of the mean, and both as a film.
fn reference(name: &str) -> (Image, Image, Film) {
    let rm = read_exr(&ref_path(name, "")).unwrap();
    let rv = read_exr_variance(&ref_path(name, "")).unwrap();
    let rv = rv.unwrap_or_else(|| panic!("{name}: the reference has no var.R/G/B channels"));
    let f = reference_film(&rm, &rv);
    (rm, rv, f)
}

/// `pt` at `spp` (seed 1, the vertex cap [`MAX_DEPTH`]) on a loaded scene.
fn render_pt(scene: forecast::scene::Scene, spp: u64) -> Film {
    let (w, h) = (scene.camera.width, scene.camera.height);
    let world = World::build(scene).expect("BVH builds");
    let mut o = MethodArgs::default();
    o.settings.max_depth = Some(MAX_DEPTH);
    let bytes = Method::Pt.preprocess(&world, &o, 1).unwrap();
    let mut pt = Method::Pt.build(&world, &o, &bytes).unwrap();
    render_passes(&world, pt.as_mut(), w, h, spp, 1)
}

/// Renders `name` with `pt` (seed 1) and asserts agreement with its Mitsuba reference.
fn check(name: &str) {
    let t0 = Instant::now();
    let spp = SCENES.iter().find(|s| s.0 == name).expect("a listed scene").1;
    let scene = forecast::scene::load(&scene_path(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
    assert!(scene.warnings.is_empty(), "{name}: every parameter is read: {:?}", scene.warnings);
    let (w, h) = (scene.camera.width, scene.camera.height);
    let img = render_pt(scene, spp);
    let t_render = t0.elapsed().as_secs_f64();
    let (rm, rv, reference) = reference(name);
    assert_eq!((rm.width, rm.height), (w as usize, h as usize), "{name}: reference size");

    let a_s = scene_alpha();
    let (z, worst, n) = max_z(&img, &reference);
    let thr = z_test_threshold(a_s, n);
    let (zg, thr1) = (global_z(&img, &reference), z_test_threshold(a_s, 1));
    let zc = channel_mean_z(&img, &reference);
    let thr3 = z_test_threshold(a_s, 3);
    let (mt, mr) = (image_of(img.mean(), w as usize, h as usize).mean(), rm.mean());
    eprintln!(
        "{name}: pt {spp} spp in {t_render:.1} s; max|z| {z:.2} (threshold {thr:.2} over {n}); global z {zg:+.2}, \
         channel z {:+.2} {:+.2} {:+.2} (thresholds {thr1:.2}, {thr3:.2}); means pt {:.5} {:.5} {:.5} ref {:.5} {:.5} {:.5}",
        zc[0], zc[1], zc[2], mt[0], mt[1], mt[2], mr[0], mr[1], mr[2]
    );
    if let Ok(dir) = std::env::var("MITSUBA_PLUGINS_DUMP") {
        let (m, v) =
            (image_of(img.mean(), w as usize, h as usize), image_of(img.variance_of_mean(), w as usize, h as usize));
        forecast::image_io::write_exr_layers(&PathBuf::from(dir).join(format!("{name}.exr")), &m, Some(&v)).unwrap();
    }
    let (x, y, c) = (worst / 3 % w as usize, worst / 3 / w as usize, worst % 3);
    let (pm, pv) = (img.mean()[worst / 3][c], img.variance_of_mean()[worst / 3][c]);
    let (qm, qv) = (rm.pixels[worst / 3][c], rv.pixels[worst / 3][c]);
    let why =
        format!("pixel ({x}, {y}) channel {c}: pt {pm:.5} ± {:.5}, Mitsuba {qm:.5} ± {:.5}", pv.sqrt(), qv.sqrt());
    eprintln!("{name}: the largest |z| at {why}");
    assert!(z < thr, "{name}: a pixel disagrees with Mitsuba: max|z| {z:.2} >= {thr:.2} at {why}");
    assert!(zg.abs() < thr1, "{name}: the image mean disagrees with Mitsuba: global z {zg:.2}");
    for (c, zc) in zc.iter().enumerate() {
        assert!(zc.abs() < thr3, "{name}: channel {c}'s mean disagrees with Mitsuba: z {zc:.2} (threshold {thr3:.2})");
    }
    assert_detects(&img, &reference, 0.01, thr1, name);

    // scripts/check-mitsuba.sh's rule, with the reference's independent halves
    let (h0, h1) = (read_exr(&ref_path(name, ".half0")).unwrap(), read_exr(&ref_path(name, ".half1")).unwrap());
    let test = image_of(img.mean(), w as usize, h as usize);
    let test_var = image_of(img.variance_of_mean(), w as usize, h as usize);
    let rep = forecast::metrics::mitsuba_agreement(&test, Some(&test_var), &rm, &h0, &h1).unwrap();
    assert!(rep.passed, "{name}: forecast diff's rule fails:\n{rep}");
}

#[test]
fn every_reference_is_listed_and_every_scene_has_one() {
    let dir = root().join("tests/scenes/mitsuba-plugins");
    let mut found: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "xml"))
        .map(|p| p.file_stem().unwrap().to_string_lossy().into_owned())
        .collect();
    found.sort();
    let mut listed: Vec<String> = SCENES.iter().map(|s| s.0.to_string()).collect();
    listed.sort();
    assert_eq!(found, listed, "tests/scenes/mitsuba-plugins and SCENES differ");
    for (name, _) in SCENES {
        for s in ["", ".half0", ".half1"] {
            assert!(ref_path(name, s).exists(), "missing {}", ref_path(name, s).display());
        }
    }
}

/// The reference film reproduces the reference's mean and variance of the mean.
#[test]
fn the_reference_film_holds_the_reference() {
    let m = Image::from_pixels(2, 1, vec![[0.3, 0.0, 2.5], [1e-3, 0.7, 0.2]]).unwrap();
    let v = Image::from_pixels(2, 1, vec![[1e-6, 0.0, 4e-4], [1e-9, 2e-7, 0.0]]).unwrap();
    let f = reference_film(&m, &v);
    for (i, (fm, fv)) in f.mean().iter().zip(f.variance_of_mean()).enumerate() {
        for c in 0..3 {
            assert!((fm[c] - m.pixels[i][c]).abs() <= 1e-6 * m.pixels[i][c].abs());
            assert!((fv[c] - v.pixels[i][c]).abs() <= 1e-4 * v.pixels[i][c] + 1e-12, "{i} {c}: {fv:?}");
        }
    }
}

/// The back wall of `normalmap-diffuse`, and the same wall without its normal map.
const NORMAL_MAPPED_WALL: &str = r#"<bsdf type="normalmap"><texture name="normalmap" type="bitmap"><string name="filename" value="normals32.png"/><boolean name="raw" value="true"/></texture><bsdf type="diffuse"><rgb name="reflectance" value="0.75, 0.72, 0.7"/></bsdf></bsdf>"#;
const WALL: &str = r#"<bsdf type="diffuse"><rgb name="reflectance" value="0.75, 0.72, 0.7"/></bsdf>"#;

/// The per-pixel test has power against each feature: the scene with its plugin's feature taken
/// away (the same file with one edit), rendered at 128 spp, fails it.
#[test]
fn negative_controls_fail() {
    let cases = [
        ("normalmap-diffuse", NORMAL_MAPPED_WALL, WALL, "no normal map on the back wall"),
        (
            "obj-uv",
            "<boolean name=\"face_normals\" value=\"true\"/>",
            "<boolean name=\"face_normals\" value=\"true\"/><boolean name=\"flip_tex_coords\" value=\"false\"/>",
            "OBJ v not flipped",
        ),
        (
            "onesided",
            "rotate x=\"0\" y=\"1\" z=\"0\" angle=\"160\"",
            "rotate x=\"0\" y=\"1\" z=\"0\" angle=\"-20\"",
            "the turned-away panel turned around",
        ),
        (
            "roughconductor-aniso",
            r#"value="beckmann"/><float name="alpha_u" value="0.4"/><float name="alpha_v" value="0.05"/>"#,
            r#"value="beckmann"/><float name="alpha_u" value="0.05"/><float name="alpha_v" value="0.4"/>"#,
            "the sphere's anisotropy turned by 90 degrees",
        ),
        (
            "bumpmap-diffuse",
            r#"<bsdf type="twosided"><bsdf type="bumpmap"><texture name="height" type="bitmap"><string name="filename" value="height32.png"/><boolean name="raw" value="true"/></texture><float name="scale" value="0.3"/><bsdf type="diffuse"><rgb name="reflectance" value="0.8, 0.7, 0.3"/></bsdf></bsdf></bsdf>"#,
            r#"<bsdf type="bumpmap"><texture name="height" type="bitmap"><string name="filename" value="height32.png"/><boolean name="raw" value="true"/></texture><float name="scale" value="0.3"/><bsdf type="twosided"><bsdf type="diffuse"><rgb name="reflectance" value="0.8, 0.7, 0.3"/></bsdf></bsdf></bsdf>"#,
            "twosided(bumpmap) seen from behind read as bumpmap(twosided)",
        ),
    ];
    let dir = root().join("tests/scenes/mitsuba-plugins");
    for (name, from, to, what) in cases {
        let src = std::fs::read_to_string(scene_path(name)).unwrap();
        assert_eq!(src.matches(from).count(), 1, "{name}: `{from}` once");
        let src = src.replace(from, to);
        let scene = forecast::scene::mitsuba::load_str(&src, &format!("{name}-control.xml"), &dir, &[])
            .unwrap_or_else(|e| panic!("{e}"));
        let img = render_pt(scene, 128);
        let (_, _, reference) = reference(name);
        let (z, _, n) = max_z(&img, &reference);
        let thr = z_test_threshold(scene_alpha(), n);
        eprintln!("{name} with {what}: max|z| {z:.2} (threshold {thr:.2})");
        assert!(z > thr, "{name} with {what} passes the per-pixel test: max|z| {z:.2} < {thr:.2}");
    }
}

/// Every scene's reference was made at [`REF_SPP`] in [`REF_PASSES`] passes by the script
/// (its log, one JSON line per render; the last line of a scene is its committed reference).
#[test]
fn the_references_are_what_the_log_says() {
    let log = std::fs::read_to_string(root().join("tests/reference/plugins/renders.jsonl")).unwrap();
    for (name, _) in SCENES {
        let last = log
            .lines()
            .map(|l| serde_json::from_str::<serde_json::Value>(l).unwrap())
            .rfind(|v| v["scene"] == *name)
            .unwrap_or_else(|| panic!("{name}: not in renders.jsonl"));
        assert_eq!(last["spp"].as_f64(), Some(REF_SPP), "{name}: {last}");
        assert_eq!(last["passes"].as_f64(), Some(REF_PASSES), "{name}: {last}");
        let (rm, _, _) = reference(name);
        let m = rm.mean();
        for c in 0..3 {
            let logged = last["mean"][c].as_f64().unwrap();
            assert!((m[c] - logged).abs() <= 1e-6 * logged, "{name}: mean {m:?} vs the log's {logged}");
        }
    }
}

macro_rules! scene_tests {
    ($($(#[$m:meta])* $f:ident => $name:literal),* $(,)?) => {$(
        #[test]
        $(#[$m])*
        fn $f() {
            check($name);
        }
    )*};
}

scene_tests! {
    bitmap_png => "bitmap-png",
    bitmap_exr => "bitmap-exr",
    checkerboard => "checkerboard",
    texture_ref => "texture-ref",
    normalmap_diffuse => "normalmap-diffuse",
    normalmap_conductor => "normalmap-conductor",
    normalmap_dielectric => "normalmap-dielectric",
    plastic => "plastic",
    plastic_nonlinear => "plastic-nonlinear",
    thindielectric => "thindielectric",
    onesided => "onesided",
    obj_uv => "obj-uv",
    ply_uv => "ply-uv",
    roughconductor_ggx => "roughconductor-ggx",
    roughconductor_beckmann => "roughconductor-beckmann",
    roughdielectric_ggx => "roughdielectric-ggx",
    roughdielectric_beckmann => "roughdielectric-beckmann",
    roughplastic_ggx => "roughplastic-ggx",
    roughplastic_beckmann => "roughplastic-beckmann",
    bumpmap_diffuse => "bumpmap-diffuse",
    bumpmap_conductor => "bumpmap-conductor",
    roughconductor_aniso => "roughconductor-aniso",
    roughdielectric_aniso => "roughdielectric-aniso",
    aniso_maps => "aniso-maps",
}
