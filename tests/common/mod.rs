//! Shared helpers for the integration tests: temporary directories, render jobs, a brute-force
//! ray caster that does not use the BVH (the reference for `tests/bvh.rs`), and the binary run as a
//! user runs it ([`cli`]).
#![allow(dead_code)]

pub mod cli;

use forecast::distributed::local::Local;
use forecast::integrators::{Method, MethodArgs};
use forecast::math::Vec3;
use forecast::pipeline::{render, RenderJob};
use forecast::render::film::Film;
use forecast::scene::Scene;
use forecast::texture::Texture;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// A fresh, empty directory under the system temp dir, unique per process and `name`.
pub fn tmp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("forecast-tests-{}-{}", std::process::id(), name));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The crate root (for `scenes/` and `tests/scenes/`).
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// A render job with everything explicit (no progress, no checkpoints).
pub fn job(
    scene: &Path,
    method: Method,
    spp: u64,
    seed: u64,
    res: (u32, u32),
    threads: usize,
    out: &Path,
) -> RenderJob {
    RenderJob {
        scene: scene.to_path_buf(),
        method: Some(method.into()),
        args: MethodArgs::default(),
        spp: Some(spp),
        time: None,
        seed: Some(seed),
        resolution: Some(res),
        out: out.to_path_buf(),
        progress: false,
        checkpoint_every: None,
        resume: None,
        checkpoint_path: None,
        max_rounds: None,
        threads: Some(threads),
        defines: Vec::new(),
        snapshots: Vec::new(),
        interrupt: Default::default(),
    }
}

/// Renders `job` on the single-process cluster and returns the film.
pub fn render_film(job: &RenderJob) -> Film {
    let r = render(job, &Local::new(), Instant::now()).expect("render failed").expect("rank 0 returns a result");
    r.film
}

/// Möller–Trumbore in f64 against the plane of triangle `p`: the barycentrics (u, v) of the
/// point where the ray meets the plane, and its t; None if the ray is parallel (det = 0).
pub fn plane_hit(p: [Vec3; 3], o: Vec3, d: Vec3) -> Option<(f64, f64, f64, f64)> {
    let f = |v: Vec3| [v.x as f64, v.y as f64, v.z as f64];
    let (p0, p1, p2, o, d) = (f(p[0]), f(p[1]), f(p[2]), f(o), f(d));
    let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let cross =
        |a: [f64; 3], b: [f64; 3]| [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let (e1, e2) = (sub(p1, p0), sub(p2, p0));
    let pv = cross(d, e2);
    let det = dot(e1, pv);
    if det == 0.0 {
        return None;
    }
    let inv = 1.0 / det;
    let tv = sub(o, p0);
    let qv = cross(tv, e1);
    Some((dot(tv, pv) * inv, dot(d, qv) * inv, dot(e2, qv) * inv, det))
}

/// Möller–Trumbore in f64; returns t in (tmin, tmax) or None. No back-face culling.
pub fn tri_t(p: [Vec3; 3], o: Vec3, d: Vec3, tmin: f64, tmax: f64) -> Option<f64> {
    let (u, v, t, det) = plane_hit(p, o, d)?;
    if !det.is_finite() || !(0.0..=1.0).contains(&u) || v < 0.0 || u + v > 1.0 {
        return None;
    }
    (t > tmin && t < tmax).then_some(t)
}

/// Ray–sphere in f64: the nearest root in (tmin, tmax).
pub fn sphere_t(c: Vec3, r: f32, o: Vec3, d: Vec3, tmin: f64, tmax: f64) -> Option<f64> {
    let f = [o.x as f64 - c.x as f64, o.y as f64 - c.y as f64, o.z as f64 - c.z as f64];
    let d = [d.x as f64, d.y as f64, d.z as f64];
    let a = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    let b = f[0] * d[0] + f[1] * d[1] + f[2] * d[2];
    let c2 = f[0] * f[0] + f[1] * f[1] + f[2] * f[2] - (r as f64) * (r as f64);
    let disc = b * b - a * c2;
    if disc < 0.0 {
        return None;
    }
    let s = disc.sqrt();
    let q = -b - b.signum() * s;
    let (mut t0, mut t1) = if q == 0.0 { (-b / a, -b / a) } else { (q / a, c2 / q) };
    if t0 > t1 {
        std::mem::swap(&mut t0, &mut t1);
    }
    [t0, t1].into_iter().find(|&t| t > tmin && t < tmax)
}

/// All primitive hits along the ray, sorted by t: (t, prim id as in `Scene`).
pub fn brute_hits(s: &Scene, o: Vec3, d: Vec3, tmax: f64) -> Vec<(f64, u32)> {
    let mut v = Vec::new();
    for (i, t) in s.triangles.iter().enumerate() {
        if let Some(t) = tri_t(t.p, o, d, 0.0, tmax) {
            v.push((t, i as u32));
        }
    }
    let ntri = s.triangles.len() as u32;
    for (i, sp) in s.spheres.iter().enumerate() {
        if let Some(t) = sphere_t(sp.center, sp.radius, o, d, 0.0, tmax) {
            v.push((t, ntri + i as u32));
        }
    }
    v.sort_by(|a, b| a.0.total_cmp(&b.0));
    v
}

/// Renders `passes` passes of `integ` at `w×h` (one sample per pixel per pass).
pub fn render_passes(
    world: &forecast::accel::World,
    integ: &mut dyn forecast::integrators::Integrator,
    w: u32,
    h: u32,
    passes: u64,
    seed: u64,
) -> Film {
    render_profiled(world, integ, (w, h), passes, seed).0
}

/// As [`render_passes`], also returning the integrator's per-thread counters summed over the
/// passes (what the pipeline hands to `Integrator::stats`).
pub fn render_profiled(
    world: &forecast::accel::World,
    integ: &mut dyn forecast::integrators::Integrator,
    (w, h): (u32, u32),
    passes: u64,
    seed: u64,
) -> (Film, forecast::profile::Profile) {
    let cam = world.scene.camera.with_resolution(w, h);
    render_sampled(world, integ, &forecast::render::PixelSampler::plain(&cam), passes, seed)
}

/// [`render_profiled`] drawing pixel samples with `pixels` (its camera sets the resolution).
pub fn render_sampled(
    world: &forecast::accel::World,
    integ: &mut dyn forecast::integrators::Integrator,
    pixels: &forecast::render::PixelSampler,
    passes: u64,
    seed: u64,
) -> (Film, forecast::profile::Profile) {
    let (w, h) = pixels.resolution();
    let mut film = Film::new(w as usize, h as usize);
    let mut profile = forecast::profile::Profile::default();
    for pass in 0..passes {
        integ.begin_pass(world, seed, pass);
        profile.add(&forecast::render::render_pass(world, &*integ, pixels, seed, pass, &mut film).profile);
    }
    (film, profile)
}

/// Per-pixel, per-channel Welch z statistics of `a (+ add)` against `b`: (max |z|, tests).
pub fn max_z(a: &Film, b: &Film, add: Option<&Film>) -> (f64, usize) {
    let (ma, va) = (a.mean(), a.variance_of_mean());
    let (mb, vb) = (b.mean(), b.variance_of_mean());
    let (mc, vc) = match add {
        Some(c) => (c.mean(), c.variance_of_mean()),
        None => (vec![[0.0; 3]; ma.len()], vec![[0.0; 3]; ma.len()]),
    };
    let mut zmax = 0.0f64;
    for i in 0..ma.len() {
        for c in 0..3 {
            let d = (ma[i][c] + mc[i][c]) as f64 - mb[i][c] as f64;
            let v = (va[i][c] + vc[i][c] + vb[i][c]) as f64;
            if d != 0.0 {
                zmax = zmax.max(if v > 0.0 { d.abs() / v.sqrt() } else { f64::INFINITY });
            }
        }
    }
    (zmax, ma.len() * 3)
}

/// The whole-image sums' difference `Σ (a − b)` over pixels and channels, and a bound on its
/// variance. Pixels are independent, but a pixel's three channels come from the same paths and
/// are strongly correlated, so each pixel contributes `(Σ_c σ_c)²` (Cauchy–Schwarz bounds
/// `Var(Σ_c X_c)` by it) for both images, not `Σ_c σ_c²`. The per-channel sum under-stated the
/// noise 1.3–1.6× on `cornell-box` (`results/2026-12-06-global-z.md`).
fn global_sums(a: &Film, b: &Film) -> (f64, [f64; 2]) {
    let (ma, va, mb, vb) = (a.mean(), a.variance_of_mean(), b.mean(), b.variance_of_mean());
    let sd = |v: &[f32; 3]| v.iter().map(|&x| (x.max(0.0) as f64).sqrt()).sum::<f64>();
    let (mut d, mut v) = (0.0f64, [0.0f64; 2]);
    for i in 0..ma.len() {
        d += (0..3).map(|c| ma[i][c] as f64 - mb[i][c] as f64).sum::<f64>();
        v[0] += sd(&va[i]).powi(2);
        v[1] += sd(&vb[i]).powi(2);
    }
    (d, v)
}

/// Welch z of the whole-image sum (all pixels and channels): far more power against a global
/// bias. Conservative: its variance is the bound of [`global_sums`] (RMS 0.7–1.05 over 15 pairs
/// of equal-method renders, against 1.07–1.63 with per-channel variances).
pub fn global_z(a: &Film, b: &Film) -> f64 {
    let (d, [va, vb]) = global_sums(a, b);
    d / (va + vb).sqrt()
}

/// A negative control with power: scaling `img` by `1 − frac` moves [`global_z`] by more than
/// twice the threshold `thr`, so every image that passes fails once scaled. Asserted from the
/// variances (the expected shift `frac · |Σ img| / √v`), not from one scaled realization, so it
/// does not pass by luck.
pub fn assert_detects(img: &Film, reference: &Film, frac: f64, thr: f64, label: &str) {
    let total: f64 = img.mean().iter().map(|p| p.iter().map(|&x| x as f64).sum::<f64>()).sum();
    let [va, vb] = global_sums(img, reference).1;
    let shift = frac * total.abs() / (va + vb).sqrt();
    eprintln!(
        "{label}: a {:.0}% error moves the global z by {shift:.2} (needs > {:.2}; the image holds {:.0}% of the variance)",
        100.0 * frac,
        2.0 * thr,
        100.0 * va / (va + vb)
    );
    assert!(shift > 2.0 * thr, "{label}: too few samples to detect a {:.0}% error (z shift {shift:.2})", 100.0 * frac);
    let zs = global_z(&scaled(img, 1.0 - frac), reference);
    assert!(zs.abs() > thr, "{label}: the {:.0}% negative control passed (global z {zs})", 100.0 * frac);
}

/// The film of `s·X` for the film of `X` (sums ×s, sums of squares ×s²): a negative control.
pub fn scaled(f: &Film, s: f64) -> Film {
    let mut data = f.data.clone();
    for px in data.chunks_exact_mut(forecast::render::film::STRIDE) {
        for c in 0..3 {
            px[c] *= s;
            px[c + 3] *= s * s;
        }
    }
    Film::from_data(f.width, f.height, data).unwrap()
}

/// Two EXR images agree to float summation order (relative 1e-6).
pub fn assert_same_image(a: &Path, b: &Path) {
    let (a, b) = (forecast::image_io::read_exr(a).unwrap(), forecast::image_io::read_exr(b).unwrap());
    assert_eq!((a.width, a.height), (b.width, b.height));
    for (i, (p, q)) in a.pixels.iter().zip(&b.pixels).enumerate() {
        for c in 0..3 {
            let tol = 1e-6 * p[c].abs().max(q[c].abs()) + 1e-12;
            assert!((p[c] - q[c]).abs() <= tol, "pixel {i} channel {c}: {} vs {}", p[c], q[c]);
        }
    }
}

/// Asserts that `img` agrees with `reference`: every pixel (Šidák-corrected per-pixel z-test at
/// family-wise α = 1e-3) and the whole-image mean (α = 1e-3), and that the same statistics
/// reject `img` scaled by 0.97, so the test can fail.
#[allow(dead_code)]
pub fn assert_agrees(img: &Film, reference: &Film, label: &str) {
    let (z, n) = max_z(img, reference, None);
    let thr = forecast::stats::z_test_threshold(1e-3, n);
    eprintln!("{label}: max|z| = {z:.2}, threshold {thr:.2} over {n} tests");
    assert!(z < thr, "{label} disagrees with pt: max|z| {z} ≥ {thr}");
    let (zg, thr1) = (global_z(img, reference), forecast::stats::z_test_threshold(1e-3, 1));
    eprintln!("{label}: global z = {zg:.2}, threshold {thr1:.2}");
    assert!(zg.abs() < thr1, "{label}: image mean differs from pt, z {zg}");
    assert_detects(img, reference, 0.03, thr1, label);
}

/// Largest per-pixel |z| of `img` against the exact furnace value 1 and its Šidák threshold at
/// family-wise α = 1e-3; a zero-variance pixel must be 1 itself. Also asserts the mean is 1 ± 1%.
#[allow(dead_code)]
pub fn assert_furnace_is_one(img: &Film, label: &str) {
    let (m, v) = (img.mean(), img.variance_of_mean());
    let thr = forecast::stats::z_test_threshold(1e-3, m.len() * 3);
    let mut zmax = 0.0f64;
    for i in 0..m.len() {
        for c in 0..3 {
            let d = (m[i][c] - 1.0) as f64;
            if v[i][c] > 0.0 {
                zmax = zmax.max(d.abs() / (v[i][c] as f64).sqrt());
            } else {
                assert!(d.abs() < 1e-4, "pixel {i}: {} with zero variance", m[i][c]);
            }
        }
    }
    eprintln!("{label}: max|z| = {zmax:.2}, threshold {thr:.2}");
    assert!(zmax < thr, "{label}: max|z| {zmax} ≥ {thr}");
    let mean: f64 = m.iter().map(|p| p[0] as f64).sum::<f64>() / m.len() as f64;
    assert!((mean - 1.0).abs() < 0.01, "{label}: furnace mean {mean}");
}

/// `scenes/ring.toml` under a 2 × 2 m light of the same power in the same direction (its
/// cardioid stays; `pt`'s tails become light enough for a z-test at a few pixels).
pub fn ring_with_wide_light() -> forecast::accel::World {
    let src = std::fs::read_to_string("scenes/ring.toml").unwrap();
    let wide = src
        .replace("corner   = [-6.803, 4.21650635, -0.25]", "corner   = [-6.428, 4.866, -1.0]")
        .replace(
            "u        = [0.0, 0.0, 0.5]\nv        = [-0.25, -0.4330127, 0.0]",
            "u        = [0.0, 0.0, 2.0]\nv        = [-1.0, -1.7320508, 0.0]",
        )
        .replace("emission = [1000.0, 1000.0, 1000.0]", "emission = [62.5, 62.5, 62.5]");
    assert!(wide.contains("[62.5, 62.5, 62.5]") && wide.contains("-1.7320508"), "ring.toml changed: update the test");
    let scene = forecast::scene::load_str(&wide, "ring-wide-light.toml", Path::new("scenes")).unwrap();
    forecast::accel::World::build(scene).unwrap()
}

/// The scene at `path` (relative to the package root) with its BVH.
pub fn world(path: &str) -> forecast::accel::World {
    forecast::accel::World::build(forecast::scene::load(Path::new(path)).expect("scene loads")).expect("BVH builds")
}

/// A small CF preprocess for the `pt-cf` tests: 20k forecasters, 16 clusters, `--max-depth 64`.
pub fn cf_test_opts() -> MethodArgs {
    let mut o = MethodArgs::default();
    (o.settings.max_depth, o.cf.forecast_photons, o.cf.clusters) = (Some(64), Some(20_000), 16);
    o
}

/// A random test ray of `s` (the `k`-th): even `k` from a random point in the (expanded) bounds in
/// a uniform direction, odd `k` aimed from outside at a random point of a random primitive (so
/// most of them hit). tmax is ∞ for half of them and a random distance otherwise.
pub fn random_ray(s: &Scene, rng: &mut forecast::sampling::rng::Rng, k: usize) -> (Vec3, Vec3, f32) {
    use forecast::sampling::warp::{sample_triangle, sample_uniform_sphere};
    let (lo, hi) = s.bounds;
    let (c, ext) = ((lo + hi) * 0.5, (hi - lo).max_element().max(1e-6));
    let (o, d) = if k.is_multiple_of(2) {
        let u = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
        (c + (u * 1.5 - Vec3::splat(0.75)) * ext, sample_uniform_sphere(rng.next_2d()))
    } else {
        let nprim = s.triangles.len() + s.spheres.len();
        let p = (rng.next_f32() * nprim as f32) as usize % nprim;
        let target = if p < s.triangles.len() {
            let t = &s.triangles[p];
            let (b0, b1) = sample_triangle(rng.next_2d());
            b0 * t.p[0] + b1 * t.p[1] + (1.0 - b0 - b1) * t.p[2]
        } else {
            let sp = &s.spheres[p - s.triangles.len()];
            sp.center + sp.radius * 0.999 * sample_uniform_sphere(rng.next_2d())
        };
        let o = c + sample_uniform_sphere(rng.next_2d()) * ext * 1.5;
        (o, (target - o).normalize())
    };
    let tmax = if rng.next_f32() < 0.5 { f32::INFINITY } else { rng.next_f32() * 2.0 * ext };
    (o, d, tmax)
}

/// `cornell-box` with 40 more random spheres (seeded): more than the Embree back end tests in a
/// loop, so they go through its user geometry.
pub fn cornell_with_many_spheres() -> Scene {
    use forecast::sampling::rng::{stream, Rng};
    let mut s = forecast::scene::load(&root().join("scenes/cornell-box.toml")).expect("scene loads");
    let mut rng = Rng::keyed(5, stream::MISC, 0, 0);
    let proto = s.spheres[0].clone();
    for _ in 0..40 {
        let c = Vec3::new(rng.next_f32() * 1.6 - 0.8, rng.next_f32() * 1.6 + 0.2, rng.next_f32() * 1.6 - 0.8);
        s.spheres.push(forecast::scene::Sphere { center: c, radius: 0.02 + 0.15 * rng.next_f32(), ..proto.clone() });
    }
    s
}

// ---- Mitsuba XML and PLY fixtures (tests/mitsuba.rs, tests/bad_scenes.rs) ----

/// Loads Mitsuba XML text as the file `t.xml`, its files relative to `dir`, without `-D` values.
pub fn xml(src: &str, dir: &Path) -> Result<Scene, forecast::scene::SceneError> {
    forecast::scene::mitsuba::load_str(src, "t.xml", dir, &[])
}

/// A flat quad at y = 0 (4 vertices, 2 faces) as ASCII PLY.
pub const PLY_ASCII: &str =
    "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n\
element face 2\nproperty list uchar int vertex_indices\nend_header\n-1 0 -1\n1 0 -1\n1 0 1\n-1 0 1\n3 0 2 1\n3 0 3 2\n";

/// A Mitsuba 2.0 scene around `shape`: a camera looking down at the origin, a point light above it.
pub fn ply_scene(shape: &str) -> String {
    format!(
        r#"<scene version="2.0.0"><sensor type="perspective"><float name="fov" value="40"/>
    <transform name="toWorld"><lookat origin="0, 3, 0.1" target="0, 0, 0"/></transform></sensor>
    {shape}
    <emitter type="point"><point name="position" value="0, 2, 0"/><rgb name="intensity" value="1"/></emitter></scene>"#
    )
}

/// A scene as comparable text, what its image depends on: every field but `path`, `hash`,
/// `mesh_files` and `warnings` (f32 printed exactly), a texture by its kind, parameters and
/// contents ([`texture_print`]), not its file's path.
pub fn scene_fingerprint(s: &Scene) -> String {
    let textures: Vec<String> = s.textures.iter().map(texture_print).collect();
    format!(
        "{:?}|{:?}|{:?}|{:?}|{textures:?}|{:?}|{:?}|{:?}|{:?}|{:?}|{:?}|{:?}|{:?}|{:?}|{:?}|{:?}|{:?}|{:?}|{:?}",
        s.camera,
        s.render,
        s.materials,
        s.surfaces,
        s.triangles,
        s.spheres,
        s.shape_uvs,
        s.emitters,
        s.point_lights,
        s.directional_lights,
        s.environment,
        s.bsphere,
        s.lights,
        s.light_pick,
        s.rois,
        s.forecast_target,
        s.forecast_photons,
        s.bounds
    )
}

/// A texture as comparable text: its kind, parameters and contents (a bitmap by its size,
/// decoding, content hash and mean), not its file's path.
pub fn texture_print(t: &Texture) -> String {
    match t {
        Texture::Constant(c) => format!("constant {c:?}"),
        Texture::Checkerboard(c) => {
            format!("checkerboard({}, {}, {:?})", texture_print(&c.color0), texture_print(&c.color1), c.to_uv.rows)
        }
        Texture::Bitmap(b) => {
            let i = &b.image;
            format!(
                "bitmap {}x{}x{} raw {} srgb {} {:?} {:?} {:?} mean {} content {:016x}",
                i.width(),
                i.height(),
                i.channels(),
                i.raw(),
                i.is_srgb(),
                b.filter_type,
                b.wrap_mode,
                b.to_uv.rows,
                i.mean().to_bits(),
                i.content_hash()
            )
        }
    }
}
