//! `pt-cf` and `iws-cf` agree with `pt` on the swimming pool (`scenes/external/sms-pool`) pixel
//! by pixel (issue #62): Šidák per-pixel and whole-image z-tests at α = 1e-3 with the 3% negative
//! control (`common::assert_agrees`), at 24×14 on the pool with its sun widened at equal power;
//! about 70–85 s on 2 cores, most of it `pt`'s 16,384 passes.
//!
//! Why the sun is widened: the pool floor is seen through the normal-mapped water (a Dirac
//! surface), so `pt` reaches the sun's caustic on the floor only when a floor point's
//! BSDF-sampled ray leaves through the water and hits the sun. The published map's sun (68% of
//! its power in ~60 texels, 0.35° each) is found so rarely that `pt` at 16,384 samples per pixel
//! holds 0–6 effective hits of it per floor pixel, and its variance estimate misses it too: a
//! per-pixel z-test against it fails where `pt-cf`'s guide and light side find the sun (here at
//! 24×14 max|z| 8.74, 34 pixels over the threshold; `results/2026-12-07-pool-cf.md` at 48×27).
//! With the disc below `pt` holds 40–170 (`results/2026-12-07-pool-perpixel.md`). A reference must resolve every class of transport the
//! other image carries (as `wide_light` in `tests/normal_mapped_casters.rs` does for
//! `sms-sphere`), so the test renders a variant: [`wide_sun`] moves the sun's power (the excess of
//! every texel over luminance [`SUN_LUMINANCE`]) into a uniform disc of radius [`SUN_RADIUS_DEG`]
//! around the brightest texel, the rest of the sky and the total power kept. The variant map is
//! generated here from the committed `quarry_03_1k.exr` (one source; no second binary to keep in
//! step with it) and loaded through the Mitsuba loader with the envmap's filename replaced in the
//! XML text.
//!
//! `POOL_VARIANT_DIR=DIR cargo test --release --test pool_agrees -- --ignored write_variant`
//! writes the variant as a scene the CLI renders (`DIR/scene.xml`, its meshes and textures linked).

mod common;
use common::{assert_agrees, cf_test_opts, render_passes};
use forecast::accel::World;
use forecast::integrators::{Method, MethodArgs};
use forecast::math::luminance;
use forecast::math::Rgb;
use forecast::render::film::Film;
use std::f64::consts::PI;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

const POOL: &str = "scenes/external/sms-pool";
const ENVMAP: &str = "textures/quarry_03_1k.exr";
/// Texels brighter than this (luminance, before the scene's `scale`) give their excess to the
/// disc; the sky's median is 0.24, the sun's peak 6.5e4, and the texels above 10 hold 68% of
/// the map's power.
const SUN_LUMINANCE: f64 = 10.0;
/// The widened sun's angular radius (the published sun's bright core is ~1.5°).
const SUN_RADIUS_DEG: f64 = 8.0;

/// The direction of texel `(x, y)` of a `w × h` lat-long map (columns texel-centred, rows on the
/// poles, as `scene::emitters::LatLong::lookup` reads them), in any fixed frame of the map.
fn texel_dir(x: usize, y: usize, w: usize, h: usize) -> [f64; 3] {
    let (phi, theta) = (2.0 * PI * (x as f64 + 0.5) / w as f64, PI * y as f64 / (h - 1) as f64);
    [theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin()]
}

/// The map at `src` with its sun widened at equal power (module docs), written to `dst`. Returns
/// (the moved share of the map's power, the disc's texel count).
fn wide_sun(src: &Path, dst: &Path) -> (f64, usize) {
    let img = forecast::image_io::decode_texture(src).unwrap();
    let (w, h) = (img.width, img.height);
    let mut px: Vec<[f64; 3]> = (0..w * h).map(|i| img.texel(i % w, i / w).unwrap().map(f64::from)).collect();
    // a texel's weight in the map's power: its row's sin θ (equal in every column)
    let weight = |i: usize| (PI * (i / w) as f64 / (h - 1) as f64).sin();
    let lum = |p: &[f64; 3]| luminance(Rgb::new(p[0] as f32, p[1] as f32, p[2] as f32)) as f64;
    let total: f64 = px.iter().enumerate().map(|(i, p)| lum(p) * weight(i)).sum();
    let (mut excess, mut peak) = ([0.0f64; 3], (0.0f64, 0usize));
    for (i, p) in px.iter_mut().enumerate() {
        let l = lum(p);
        if l > peak.0 {
            peak = (l, i);
        }
        if l > SUN_LUMINANCE {
            let keep = SUN_LUMINANCE / l;
            for c in 0..3 {
                excess[c] += p[c] * (1.0 - keep) * weight(i);
                p[c] *= keep;
            }
        }
    }
    let sun = texel_dir(peak.1 % w, peak.1 / w, w, h);
    let cos_r = SUN_RADIUS_DEG.to_radians().cos();
    let disc: Vec<usize> = (0..w * h)
        .filter(|&i| {
            let d = texel_dir(i % w, i / w, w, h);
            d[0] * sun[0] + d[1] * sun[1] + d[2] * sun[2] >= cos_r
        })
        .collect();
    let omega: f64 = disc.iter().map(|&i| weight(i)).sum();
    for &i in &disc {
        for c in 0..3 {
            px[i][c] += excess[c] / omega;
        }
    }
    let after: f64 = px.iter().enumerate().map(|(i, p)| lum(p) * weight(i)).sum();
    assert!((after / total - 1.0).abs() < 1e-6, "power {total} became {after}");
    let out = px.iter().map(|p| p.map(|v| v as f32)).collect();
    forecast::image_io::write_exr(dst, &forecast::image_io::Image::from_pixels(w, h, out).unwrap()).unwrap();
    (lum(&excess) / total, disc.len())
}

/// The pool's `scene.xml` with its envmap replaced by `map`.
fn pool_xml(map: &Path) -> String {
    let src = std::fs::read_to_string(common::root().join(POOL).join("scene.xml")).unwrap();
    assert!(src.contains(ENVMAP), "the pool's envmap changed");
    src.replace(ENVMAP, map.to_str().unwrap())
}

/// The pool with its sun widened (module docs), its map written under `dir`.
fn wide_sun_pool(dir: &Path) -> World {
    let map = dir.join("quarry_03_wide_sun.exr");
    let (share, texels) = wide_sun(&common::root().join(POOL).join(ENVMAP), &map);
    eprintln!("wide sun: {:.1}% of the power moved into {texels} texels", 100.0 * share);
    let scene = forecast::scene::mitsuba::load_str(&pool_xml(&map), "scene.xml", &common::root().join(POOL), &[]);
    World::build(scene.unwrap()).unwrap()
}

/// The options of every render here: the tests' CF sizes and their vertex cap of 64 (the IWS
/// methods honour a scene's smaller cap only at 0, `docs/limitations.md`; the pool's
/// `max_depth` 7 takes 4% off `pt`'s image).
fn opts() -> MethodArgs {
    cf_test_opts()
}

const RES: (u32, u32) = (24, 14);

/// The variant and `pt`'s image of it (16,384 passes, seed 11), rendered once for every test.
fn reference() -> &'static (World, Film) {
    static REF: OnceLock<(World, Film)> = OnceLock::new();
    REF.get_or_init(|| {
        let w = wide_sun_pool(&common::tmp_dir("pool-wide-sun"));
        let mut p = Method::Pt.build(&w, &opts(), &[]).unwrap();
        let img = render_passes(&w, p.as_mut(), RES.0, RES.1, 16384, 11);
        (w, img)
    })
}

/// `method` (`passes` passes, seed 3) against [`reference`].
fn agrees(method: Method, passes: u64) {
    let (w, reference) = reference();
    let o = opts();
    let bytes = method.preprocess(w, &o, 17).unwrap();
    let mut g = method.build(w, &o, &bytes).unwrap();
    let img = render_passes(w, g.as_mut(), RES.0, RES.1, passes, 3);
    assert_agrees(&img, reference, &format!("{} pool, wide sun", method.name()));
}

#[test]
fn pt_cf_agrees_with_pt_on_the_pool_with_a_wide_sun() {
    agrees(Method::PtCf, 4096);
}

#[test]
fn iws_cf_agrees_with_pt_on_the_pool_with_a_wide_sun() {
    agrees(Method::IwsCf, 2048); // at 1,024 a 3% error moves the global z by 6.46 (needs 6.58)
}

/// Writes the variant as a CLI scene under `$POOL_VARIANT_DIR` (module docs).
#[test]
#[ignore]
fn write_variant() {
    let dir = PathBuf::from(std::env::var("POOL_VARIANT_DIR").expect("set POOL_VARIANT_DIR"));
    std::fs::create_dir_all(&dir).unwrap();
    let map = dir.join("quarry_03_wide_sun.exr");
    let (share, texels) = wide_sun(&common::root().join(POOL).join(ENVMAP), &map);
    eprintln!("wide sun: {:.1}% of the power moved into {texels} texels", 100.0 * share);
    for sub in ["meshes", "textures"] {
        let link = dir.join(sub);
        if !link.exists() {
            std::os::unix::fs::symlink(common::root().join(POOL).join(sub), link).unwrap();
        }
    }
    std::fs::write(dir.join("scene.xml"), pool_xml(&map)).unwrap();
}
