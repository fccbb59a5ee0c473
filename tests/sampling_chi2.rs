//! Chi-square goodness-of-fit tests of every sampler against its claimed pdf (spec §8,
//! Mitsuba 3 `chi2.py` style: 1e6 samples on a (φ, cosθ) grid, cells with expected count < 5
//! pooled, any sample in a zero-pdf cell fails outright), plus binomial z-tests of the glass
//! Fresnel choice and exact `weight == f·|cos|/pdf` checks.
//!
//! Significance: the family-wise level is ALPHA = 0.01 over all N_TESTS statistical tests in this
//! file, Šidák-corrected (`sidak_alpha(0.01, N_TESTS)` per test, about 2.5e-4). All seeds are fixed,
//! so the outcome is deterministic; a correct sampler fails with probability < 1% over the file.
//! The negative controls (`wrong_pdfs_are_rejected`) show the harness has the power to fail.

use forecast::bsdf::{self, fresnel_dielectric, Mode, ShadingPoint};
use forecast::math::{Frame, Rgb, Vec3, PI};
use forecast::sampling::rng::{stream, Rng};
use forecast::sampling::warp;
use forecast::scene::{load_str, Material};
use forecast::stats::{chi2_test, hemisphere_chi2, sidak_alpha, sphere_chi2, z_test_threshold, Chi2Result};
use std::path::Path;

/// Family-wise significance level of the file.
const ALPHA: f64 = 0.01;
/// Number of statistical tests that must pass in this file (chi-square + z-tests), counted below:
/// cosine 1, uniform sphere 1, Phong lobe 4, diffuse BSDF 4, glossy BSDF 7, triangle 1,
/// quad emitter 1, sphere emitter 2, glass Fresnel frequencies 8 (z-tests; the TIR case is exact,
/// counted anyway: conservative), environment map 3, spot cone 1. Total 33.
const N_TESTS: usize = 33;
/// Samples per chi-square test (spec §8).
const N: usize = 1_000_000;

fn alpha() -> f64 {
    sidak_alpha(ALPHA, N_TESTS)
}

fn check(name: &str, r: &Chi2Result) {
    assert!(r.dof >= 10, "{name}: too few cells for a meaningful test: {r:?}");
    assert!(r.impossible_samples == 0.0, "{name}: samples in zero-pdf cells: {r:?}");
    assert!(r.passes(alpha()), "{name}: rejected at per-test level {:.3e}: {r:?}", alpha());
    // The claimed pdf must integrate to (almost) what was observed; catches normalisation errors
    // even if the chi-square happened to pass (relative tolerance: 5σ of a Poisson total
    // 5/sqrt(N) = 0.5%, plus the midpoint-rule error).
    let rel = (r.n_expected - r.n_observed).abs() / r.n_observed.max(1.0);
    assert!(rel < 0.01, "{name}: total expected {} vs observed {}", r.n_expected, r.n_observed);
}

fn sp_z() -> ShadingPoint {
    ShadingPoint::new(Vec3::ZERO, Vec3::Z, Vec3::Z)
}

/// Unit direction at polar angle `theta_deg` from +z, in the xz plane.
fn dir_at(theta_deg: f32) -> Vec3 {
    let t = theta_deg.to_radians();
    Vec3::new(t.sin(), 0.0, t.cos())
}

fn u3(rng: &mut Rng) -> [f32; 3] {
    [rng.next_f32(), rng.next_f32(), rng.next_f32()]
}

// ---------------------------------------------------------------------------------------------
// Warps
// ---------------------------------------------------------------------------------------------

#[test]
fn cosine_hemisphere_matches_its_pdf() {
    let r = hemisphere_chi2(
        |rng| Some(warp::sample_cosine_hemisphere(rng.next_2d())),
        |w| warp::cosine_hemisphere_pdf(w.z) as f64,
        64,
        32,
        N,
        101,
    );
    check("cosine hemisphere", &r);
}

#[test]
fn uniform_sphere_matches_its_pdf() {
    let r = sphere_chi2(
        |rng| Some(warp::sample_uniform_sphere(rng.next_2d())),
        |_| warp::uniform_sphere_pdf() as f64,
        64,
        32,
        N,
        102,
    );
    check("uniform sphere", &r);
}

/// An `envmap`'s direction sampler (`scene::Environment::sample`: the cells of its lat-long image
/// weighted by luminance × solid angle, drawn as a row and then a cell in the row through
/// `Distribution2D`'s blocked search) against its `pdf_w`: a smooth map turned by a rotation; a
/// map 21 cells wide (rows of 2⅝ search blocks) with a bright band in one row; and a small map with
/// one bright texel (a sun) beside black ones.
#[test]
fn environment_map_sampler_matches_its_pdf() {
    use forecast::math::{Mat3, Rgb};
    use forecast::scene::{Environment, LatLong};
    let smooth: Vec<Rgb> = (0..16 * 8)
        .map(|k| {
            let (x, y) = ((k % 16) as f32, (k / 16) as f32);
            Rgb::new(0.2 + x * 0.1, 1.0 + (x * 0.7 + y).sin(), 0.1 + y * y * 0.05)
        })
        .collect();
    let rot = Mat3::from_rotation_y(0.9) * Mat3::from_rotation_x(0.5);
    let env = Environment::lat_long(LatLong::new(16, 8, smooth).unwrap(), rot);
    let r = sphere_chi2(|rng| env.sample(rng.next_2d()).map(|s| s.0), |w| env.pdf_w(w) as f64, 64, 32, N, 140);
    check("envmap, smooth and turned", &r);
    // The (φ, cos θ) grid of `sphere_chi2` would cut the cells of a map whose pdf jumps (a band,
    // a sun), so these bin in the map's own cells (`map_cell_chi2`).
    let banded: Vec<Rgb> = (0..21 * 7)
        .map(|k| {
            let (x, y) = ((k % 21) as f32, (k / 21) as f32);
            Rgb::splat(0.3 + 0.2 * (x * 0.9 - y).cos() + if y == 2.0 && (x - 13.0).abs() < 3.0 { 4.0 } else { 0.0 })
        })
        .collect();
    let env = Environment::lat_long(LatLong::new(21, 7, banded).unwrap(), Mat3::IDENTITY);
    check("envmap, 21 wide, a bright band", &map_cell_chi2(&env, 21, 7, 3, 143));
    // A sun 170× its neighbours beside black texels, each cell split 4 × 4.
    let (w, h) = (6usize, 4usize);
    let sun: Vec<Rgb> = (0..w * h)
        .map(|i| {
            if i == 8 {
                Rgb::splat(50.0)
            } else if i % 5 == 0 {
                Rgb::ZERO
            } else {
                Rgb::splat(0.3)
            }
        })
        .collect();
    let env = Environment::lat_long(LatLong::new(w, h, sun).unwrap(), Mat3::IDENTITY);
    check("envmap, a sun and black texels", &map_cell_chi2(&env, w, h, 4, 141));
}

/// The chi-square of `env`'s sampler (an unturned `w × h` map) binned in the map's own cells,
/// each split `k × k` in φ and cos θ, expected counts from `pdf_w` at the sub-cell centres (exact:
/// the pdf is constant in a cell).
fn map_cell_chi2(env: &forecast::scene::Environment, w: usize, h: usize, k: usize, seed: u64) -> Chi2Result {
    let cos_row = |j: usize| (PI * j as f32 / h as f32).cos();
    let n_bins = w * h * k * k;
    let bin = |d: Vec3| {
        let u = d.x.atan2(-d.z) / (2.0 * PI);
        let u = u - u.floor();
        let j = ((d.y.clamp(-1.0, 1.0).acos() / PI * h as f32) as usize).min(h - 1);
        let (c0, c1) = (cos_row(j), cos_row(j + 1));
        let a = (((c0 - d.y) / (c0 - c1) * k as f32) as usize).min(k - 1);
        let b = ((u * (w * k) as f32) as usize).min(w * k - 1);
        (j * k + a) * w * k + b
    };
    let mut obs = vec![0.0f64; n_bins];
    let mut rng = Rng::keyed(seed, stream::MISC, 0, 0);
    for _ in 0..N {
        if let Some((d, _)) = env.sample(rng.next_2d()) {
            obs[bin(d)] += 1.0;
        }
    }
    let mut exp = vec![0.0f64; n_bins];
    for j in 0..h {
        let (c0, c1) = (cos_row(j) as f64, cos_row(j + 1) as f64);
        for a in 0..k {
            let (ca, cb) = (c0 - (c0 - c1) * a as f64 / k as f64, c0 - (c0 - c1) * (a + 1) as f64 / k as f64);
            let y = (ca + cb) / 2.0;
            for b in 0..w * k {
                let phi = 2.0 * std::f64::consts::PI * (b as f64 + 0.5) / (w * k) as f64;
                let st = (1.0 - y * y).sqrt();
                let d = Vec3::new((phi.sin() * st) as f32, y as f32, (-phi.cos() * st) as f32);
                let omega = 2.0 * std::f64::consts::PI / (w * k) as f64 * (ca - cb);
                exp[(j * k + a) * w * k + b] = N as f64 * env.pdf_w(d) as f64 * omega;
            }
        }
    }
    chi2_test(&obs, &exp, 5.0)
}

/// A `spot`'s emission directions (uniform in its cone, `PointLight::sample_dir`) against its pdf.
#[test]
fn spot_cone_matches_its_pdf() {
    use forecast::scene::{PointLight, Spot};
    // about the grid's pole, cos(cutoff) = 0.75 on a cell edge of its 32 cos θ bands (a cell cut
    // by the cone's edge would be integrated by the midpoint rule, not exactly); the turn of the
    // frame is the Mitsuba reference's (tests/emitters.rs)
    let spot = Spot::new(Vec3::Z, Vec3::X, 0.75f32.acos().to_degrees(), 30.0).unwrap();
    let pl = PointLight { position: Vec3::ZERO, intensity: forecast::math::Rgb::ONE, spot: Some(spot) };
    let r = sphere_chi2(|rng| Some(pl.sample_dir(rng.next_2d()).0), |w| pl.pdf_dir(w) as f64, 64, 32, N, 142);
    check("spot cone", &r);
}

#[test]
fn phong_lobe_matches_its_pdf() {
    // Exponents from uniform to a narrow lobe. The hemisphere grid counts samples below the horizon
    // as impossible. 256 μ-cells: stats' midpoint rule (6 sub-cells) has relative error
    // h²/24·f''/f with f = μ^e, f''/f ≈ e², h = 1/(256·6): 7e-4 at e = 100, far below the Poisson
    // noise of a cell (with 64 μ-cells it is 1.1% and falsely rejects e = 100).
    for (k, &e) in [0.0f32, 1.0, 10.0, 100.0].iter().enumerate() {
        let r = hemisphere_chi2(
            |rng| Some(warp::sample_phong_lobe(rng.next_2d(), e)),
            |w| warp::phong_lobe_pdf(w.z, e) as f64,
            64,
            256,
            N,
            110 + k as u64,
        );
        check(&format!("phong lobe e={e}"), &r);
    }
}

#[test]
fn triangle_barycentrics_are_uniform() {
    // Histogram (b0, b1) on an n×n grid of [0,1]². The sampled point b0·A + b1·B + b2·C is uniform
    // on any triangle iff (b0, b1) is uniform on {b0, b1 ≥ 0, b0 + b1 ≤ 1} (an affine map), with
    // density 2. Cells strictly below the diagonal have probability 2/n², cells the diagonal
    // cuts in half (i + j = n − 1) have 1/n², the rest 0 (exact, no quadrature).
    let n = 32usize;
    let mut obs = vec![0.0f64; n * n + 1];
    let mut rng = Rng::keyed(120, stream::MISC, 0, 0);
    for _ in 0..N {
        let (b0, b1) = warp::sample_triangle(rng.next_2d());
        let b2 = 1.0 - b0 - b1;
        if !(b0 >= 0.0 && b1 >= 0.0 && b2 >= -1e-6) {
            obs[n * n] += 1.0; // outside the triangle: impossible
            continue;
        }
        let i = ((b0 * n as f32) as usize).min(n - 1);
        let j = ((b1 * n as f32) as usize).min(n - 1);
        obs[j * n + i] += 1.0;
    }
    let mut exp = vec![0.0f64; n * n + 1];
    for j in 0..n {
        for i in 0..n {
            exp[j * n + i] = N as f64
                * match (i + j).cmp(&(n - 1)) {
                    std::cmp::Ordering::Less => 2.0 / (n * n) as f64,
                    std::cmp::Ordering::Equal => 1.0 / (n * n) as f64,
                    std::cmp::Ordering::Greater => 0.0,
                };
        }
    }
    check("triangle barycentrics", &chi2_test(&obs, &exp, 5.0));
}

// ---------------------------------------------------------------------------------------------
// BSDFs
// ---------------------------------------------------------------------------------------------

/// Chi-square of `bsdf::sample` against `bsdf::pdf_w` on the full sphere, in the frame of the
/// geometric normal (ng = +z); samples returned as `None` are absorbed and not counted (pdf_w is
/// zero wherever `sample` refuses, so the expectations stay consistent).
fn bsdf_chi2(m: Material, sp: ShadingPoint, wo: Vec3, seed: u64) -> Chi2Result {
    sphere_chi2(
        |rng| bsdf::sample(&m, &sp, wo, u3(rng), Mode::Radiance).map(|s| s.wi),
        |wi| bsdf::pdf_w(&m, &sp, wo, wi) as f64,
        64,
        64,
        N,
        seed,
    )
}

#[test]
fn diffuse_sample_matches_pdf() {
    let m = Material::Diffuse { albedo: Rgb::splat(0.7) };
    for (k, &th) in [0.0f32, 45.0, 89.0].iter().enumerate() {
        let r = bsdf_chi2(m, sp_z(), dir_at(th), 200 + k as u64);
        check(&format!("diffuse wo θ={th}"), &r);
    }
    // A tilted shading normal (20° from ng): the cosine lobe is around ns and clipped at ng's horizon.
    let ns = Vec3::new(20f32.to_radians().sin(), 0.0, 20f32.to_radians().cos());
    let sp = ShadingPoint::new(Vec3::ZERO, Vec3::Z, ns);
    let r = bsdf_chi2(m, sp, dir_at(-30.0), 203);
    check("diffuse, tilted shading normal", &r);
}

#[test]
fn glossy_sample_matches_pdf() {
    let mixed = |e: f32| Material::Glossy { albedo: Rgb::splat(0.3), specular: Rgb::splat(0.5), exponent: e };
    let cases: [(Material, f32); 7] = [
        (mixed(10.0), 0.0),
        (mixed(10.0), 45.0),
        (mixed(10.0), 85.0), // grazing: most of the lobe falls below the horizon
        (mixed(1.0), 60.0),
        (mixed(50.0), 30.0),
        // specular only (the diffuse branch has probability 0)
        (Material::Glossy { albedo: Rgb::ZERO, specular: Rgb::splat(0.8), exponent: 20.0 }, 60.0),
        // coloured: the lobe choice uses luminance
        (Material::Glossy { albedo: Rgb::new(0.6, 0.1, 0.1), specular: Rgb::new(0.1, 0.3, 0.8), exponent: 5.0 }, 70.0),
    ];
    for (k, (m, th)) in cases.iter().enumerate() {
        let r = bsdf_chi2(*m, sp_z(), dir_at(*th), 300 + k as u64);
        check(&format!("glossy {m:?} wo θ={th}"), &r);
    }
}

/// weight must be eval·|cos(wi, ns)|/pdf_w for non-Dirac lobes (radiance mode) and pdf_w must
/// agree with `bsdf::pdf_w`; in importance mode the adjoint shading-normal factor
/// |wo·ns||wi·ng| / (|wo·ng||wi·ns|) (Veach eq. 5.19) multiplies it.
fn weight_check(sps: &[ShadingPoint], seed: u64) {
    let mats = [
        Material::Diffuse { albedo: Rgb::new(0.2, 0.5, 0.9) },
        Material::Glossy { albedo: Rgb::splat(0.3), specular: Rgb::splat(0.5), exponent: 10.0 },
        Material::Glossy { albedo: Rgb::ZERO, specular: Rgb::splat(0.9), exponent: 200.0 },
        Material::Glossy { albedo: Rgb::new(0.6, 0.1, 0.1), specular: Rgb::new(0.1, 0.3, 0.8), exponent: 3.0 },
    ];
    let mut rng = Rng::keyed(seed, stream::MISC, 0, 0);
    let mut checked = 0;
    for m in &mats {
        for sp in sps {
            for th in [0.0f32, 30.0, 60.0, 80.0, -45.0] {
                // also from below: wo under the geometric surface flips the normals
                for flip in [1.0f32, -1.0] {
                    let wo = dir_at(th) * Vec3::new(1.0, 1.0, flip);
                    for _ in 0..2000 {
                        let u = u3(&mut rng);
                        let Some(s) = bsdf::sample(m, sp, wo, u, Mode::Radiance) else { continue };
                        assert!(!s.is_delta && s.pdf_w > 0.0 && s.pdf_w.is_finite());
                        assert!((s.wi.length() - 1.0).abs() < 1e-4);
                        assert!(s.wi.dot(sp.ng) * wo.dot(sp.ng) > 0.0, "reflection must stay on wo's side of ng");
                        let pdf = bsdf::pdf_w(m, sp, wo, s.wi);
                        assert!((pdf - s.pdf_w).abs() <= 1e-4 * pdf.max(1.0), "{m:?}: pdf {pdf} vs sample {}", s.pdf_w);
                        let f = bsdf::eval(m, sp, wo, s.wi, Mode::Radiance);
                        let expect = f * s.wi.dot(sp.ns).abs() / s.pdf_w;
                        let tol = 1e-4 * expect.max_element().max(1e-3);
                        assert!(
                            (s.weight - expect).abs().max_element() <= tol,
                            "{m:?} wo={wo} wi={}: weight {} vs f·cos/pdf {}",
                            s.wi,
                            s.weight,
                            expect
                        );
                        // importance mode: same direction and pdf, weight × adjoint correction
                        let si = bsdf::sample(m, sp, wo, u, Mode::Importance).expect("same u gives a sample");
                        assert_eq!(si.wi, s.wi);
                        let corr = (wo.dot(sp.ns).abs() * s.wi.dot(sp.ng).abs())
                            / (wo.dot(sp.ng).abs() * s.wi.dot(sp.ns).abs());
                        let ei = expect * corr;
                        assert!(
                            (si.weight - ei).abs().max_element() <= 1e-3 * ei.max_element().max(1e-3),
                            "importance weight {} vs {}",
                            si.weight,
                            ei
                        );
                        checked += 1;
                    }
                }
            }
        }
    }
    assert!(checked > 25_000, "too few samples checked: {checked}");
}

#[test]
fn weight_is_eval_cos_over_pdf() {
    weight_check(&[sp_z()], 400);
}

/// Same with a shading normal tilted ~13° from the geometric one (smooth meshes). A sampled wi can
/// then lie above ng's horizon but below ns's: eval is 0 there, so the weight must be 0 (or the
/// sample refused), never negative.
#[test]
fn weight_is_eval_cos_over_pdf_with_shading_normal() {
    let ns = Vec3::new(0.2, -0.1, 1.0).normalize();
    weight_check(&[ShadingPoint::new(Vec3::ONE, Vec3::Z, ns)], 401);
}

#[test]
fn mirror_reflects_exactly() {
    let m = Material::Mirror { reflectance: Rgb::new(0.9, 0.5, 0.1) };
    for th in [0.0f32, 30.0, 89.0] {
        let wo = dir_at(th);
        let s = bsdf::sample(&m, &sp_z(), wo, [0.3, 0.6, 0.9], Mode::Radiance).unwrap();
        assert!(s.is_delta && s.pdf_w == 1.0);
        assert!((s.wi - Vec3::new(-wo.x, -wo.y, wo.z)).length() < 1e-6);
        assert_eq!(s.weight, Rgb::new(0.9, 0.5, 0.1));
        assert_eq!(bsdf::eval(&m, &sp_z(), wo, s.wi, Mode::Radiance), Rgb::ZERO);
        assert_eq!(bsdf::pdf_w(&m, &sp_z(), wo, s.wi), 0.0);
    }
}

// ---------------------------------------------------------------------------------------------
// Glass
// ---------------------------------------------------------------------------------------------

/// Reference unpolarised Fresnel reflectance in f64 (Hecht): `eta` = η_t/η_i.
fn fresnel_ref(cos_i: f64, eta: f64) -> f64 {
    let sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    let rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    0.5 * (rs * rs + rp * rp)
}

#[test]
fn glass_fresnel_choice_frequency_and_directions() {
    let ior = 1.5f32;
    let m = Material::Glass { ior };
    let zcrit = z_test_threshold(ALPHA, N_TESTS);
    let n = 200_000usize;
    // (θ in degrees, from outside?) — entering and leaving; 50° from inside is beyond the critical
    // angle (41.8°) and must always reflect.
    let cases = [
        (0.0f32, true),
        (30.0, true),
        (60.0, true),
        (85.0, true),
        (0.0, false),
        (30.0, false),
        (41.0, false),
        (50.0, false),
    ];
    for (k, &(th, outside)) in cases.iter().enumerate() {
        // from inside: wo is below the geometric (outward) normal
        let wo = if outside { dir_at(th) } else { dir_at(th) * Vec3::new(1.0, 1.0, -1.0) };
        let eta = if outside { ior } else { 1.0 / ior };
        let cos_i = wo.z.abs();
        let f = fresnel_dielectric(cos_i, eta) as f64;
        let fr = fresnel_ref(cos_i as f64, eta as f64);
        assert!((f - fr).abs() < 1e-5, "fresnel({cos_i}, {eta}) = {f}, reference {fr}");
        let mut rng = Rng::keyed(500 + k as u64, stream::MISC, 0, 0);
        let mut n_refl = 0usize;
        for _ in 0..n {
            let s = bsdf::sample(&m, &sp_z(), wo, u3(&mut rng), Mode::Radiance).expect("glass always scatters");
            assert!(s.is_delta);
            assert!((s.wi.length() - 1.0).abs() < 1e-5);
            if s.wi.z * wo.z > 0.0 {
                // reflection: mirror direction, pdf F, weight 1
                n_refl += 1;
                assert!((s.wi - Vec3::new(-wo.x, -wo.y, wo.z)).length() < 1e-5);
                assert!((s.pdf_w as f64 - f).abs() < 1e-6);
                assert_eq!(s.weight, Rgb::ONE);
            } else {
                // refraction: Snell's law, in the plane of incidence, opposite side; pdf 1 − F;
                // radiance weight 1/η² (η = η_t/η_i)
                let sin_i = (1.0 - cos_i * cos_i).max(0.0).sqrt();
                let sin_t = (s.wi.x * s.wi.x + s.wi.y * s.wi.y).sqrt();
                assert!((sin_i - eta * sin_t).abs() < 1e-5, "Snell: sin_i {sin_i} vs η·sin_t {}", eta * sin_t);
                assert!(
                    s.wi.y.abs() < 1e-6 && (th == 0.0 || s.wi.x * wo.x < 0.0),
                    "refracted ray leaves the plane or side: {}",
                    s.wi
                );
                assert!((s.pdf_w as f64 - (1.0 - f)).abs() < 1e-6);
                assert!((s.weight - Rgb::splat(1.0 / (eta * eta))).abs().max_element() < 1e-6);
            }
        }
        // Binomial z-test of the reflection frequency against F. With F = 0 or 1 the count must be exact.
        if f <= 0.0 || f >= 1.0 {
            assert_eq!(n_refl as f64, f * n as f64, "θ={th} outside={outside}: F={f}");
        } else {
            let z = (n_refl as f64 - n as f64 * f) / (n as f64 * f * (1.0 - f)).sqrt();
            assert!(
                z.abs() < zcrit,
                "θ={th} outside={outside}: reflected {n_refl}/{n}, F={f}, z={z:.2} (limit {zcrit:.2})"
            );
        }
    }
    // importance mode: refraction carries no η² factor
    let s = bsdf::sample(&m, &sp_z(), dir_at(20.0), [0.99, 0.0, 0.0], Mode::Importance).unwrap();
    assert!(s.wi.z < 0.0 && (s.weight - Rgb::ONE).abs().max_element() < 1e-6);
}

// ---------------------------------------------------------------------------------------------
// Emitters
// ---------------------------------------------------------------------------------------------

const EMITTERS: &str = r#"
[camera]
position = [0.0, 0.0, 5.0]
look_at = [0.0, 0.0, 0.0]
fov = 40.0
resolution = [8, 8]

[[shape]]
type = "quad"
corner = [-1.0, 0.5, 0.2]
u = [2.0, 0.3, 0.0]
v = [0.4, 0.0, -1.2]
emission = [1.0, 2.0, 3.0]

[[shape]]
type = "sphere"
center = [3.0, 1.0, -2.0]
radius = 0.7
emission = [5.0, 5.0, 5.0]

[[shape]]
type = "sphere"
center = [-3.0, 1.0, -2.0]
radius = 1.3
inward = true
emission = [1.0, 1.0, 1.0]
"#;

#[test]
fn quad_emitter_points_are_uniform_by_area() {
    let s = load_str(EMITTERS, "emitters.toml", Path::new(".")).unwrap();
    // The quad is two triangle emitters (0 and 1), both on the quad's two triangles.
    let (c, u, v) = (Vec3::new(-1.0, 0.5, 0.2), Vec3::new(2.0, 0.3, 0.0), Vec3::new(0.4, 0.0, -1.2));
    let quad_area = u.cross(v).length();
    let normal = u.cross(v).normalize();
    let tris: Vec<u32> = (0..s.emitters.len() as u32).filter(|&e| s.emitters[e as usize].prim < s.ntri()).collect();
    assert_eq!(tris.len(), 2, "a quad is two emissive triangles");
    let a0 = s.emitters[tris[0] as usize].area;
    let a1 = s.emitters[tris[1] as usize].area;
    assert!(((a0 + a1) / quad_area - 1.0).abs() < 1e-5);
    // Pick a triangle ∝ area (what light_pick does for equal radiance), then a point on it. Map back
    // to the parallelogram's (s, t) ∈ [0,1]² by the Gram system; uniform by area ⇔ uniform in (s, t).
    let (uu, uv, vv) = (u.dot(u) as f64, u.dot(v) as f64, v.dot(v) as f64);
    let det = uu * vv - uv * uv;
    let n = 32usize;
    let mut obs = vec![0.0f64; n * n + 1];
    let mut rng = Rng::keyed(600, stream::MISC, 0, 0);
    for _ in 0..N {
        let e = if rng.next_f32() * (a0 + a1) < a0 { tris[0] } else { tris[1] };
        let (p, ng, pdf_a) = s.sample_emitter_point(e, rng.next_2d());
        assert!((pdf_a * s.emitters[e as usize].area - 1.0).abs() < 1e-5, "pdf_a must be 1/area");
        assert!((ng - normal).length() < 1e-5, "emitter normal {ng} vs u×v {normal}");
        let d = p - c;
        let (du, dv) = (d.dot(u) as f64, d.dot(v) as f64);
        let ss = (vv * du - uv * dv) / det;
        let tt = (uu * dv - uv * du) / det;
        let off_plane = (d.dot(normal)).abs();
        if !(-1e-5..=1.0 + 1e-5).contains(&ss) || !(-1e-5..=1.0 + 1e-5).contains(&tt) || off_plane > 1e-5 {
            obs[n * n] += 1.0;
            continue;
        }
        let i = ((ss * n as f64) as usize).min(n - 1);
        let j = ((tt * n as f64) as usize).min(n - 1);
        obs[j * n + i] += 1.0;
    }
    let mut exp = vec![N as f64 / (n * n) as f64; n * n + 1];
    exp[n * n] = 0.0;
    check("quad emitter", &chi2_test(&obs, &exp, 5.0));
}

#[test]
fn sphere_emitter_points_are_uniform_by_area() {
    let s = load_str(EMITTERS, "emitters.toml", Path::new(".")).unwrap();
    let ntri = s.ntri();
    for (k, e) in (0..s.emitters.len() as u32).filter(|&e| s.emitters[e as usize].prim >= ntri).enumerate() {
        let sph = s.spheres[(s.emitters[e as usize].prim - ntri) as usize].clone();
        let area = 4.0 * PI * sph.radius * sph.radius;
        assert!((s.emitters[e as usize].area / area - 1.0).abs() < 1e-5);
        // Uniform by area on a sphere ⇔ the direction from the centre is uniform: chi-square on the
        // (φ, cosθ) grid against 1/(4π). A fixed, arbitrary frame checks all three axes equally.
        let frame = Frame::from_normal(Vec3::new(0.3, 0.8, -0.5).normalize());
        let r = sphere_chi2(
            |rng| {
                let (p, ng, pdf_a) = s.sample_emitter_point(e, rng.next_2d());
                let d = (p - sph.center) / sph.radius;
                assert!((d.length() - 1.0).abs() < 1e-4, "point off the sphere");
                let outward = if sph.inward { -ng } else { ng };
                assert!((outward - d.normalize()).length() < 1e-4, "normal must be ±radial (inward={})", sph.inward);
                assert!((pdf_a * area - 1.0).abs() < 1e-4);
                Some(frame.to_local(d.normalize()))
            },
            |_| 1.0 / (4.0 * std::f64::consts::PI),
            64,
            32,
            N,
            610 + k as u64,
        );
        check(&format!("sphere emitter {e} (inward={})", sph.inward), &r);
    }
}

// ---------------------------------------------------------------------------------------------
// Negative controls: the harness must be able to fail.
// ---------------------------------------------------------------------------------------------

#[test]
fn wrong_pdfs_are_rejected() {
    let a = alpha();
    // 1. Cosine samples against the uniform-hemisphere pdf.
    let r = hemisphere_chi2(
        |rng| Some(warp::sample_cosine_hemisphere(rng.next_2d())),
        |w| if w.z > 0.0 { 0.5 / std::f64::consts::PI } else { 0.0 },
        64,
        32,
        N,
        900,
    );
    assert!(!r.passes(a), "uniform pdf accepted for cosine samples: {r:?}");
    // 2. A subtle one: the glossy sampler with exponent 10 judged against exponent 11's pdf.
    let m = Material::Glossy { albedo: Rgb::splat(0.3), specular: Rgb::splat(0.5), exponent: 10.0 };
    let wrong = Material::Glossy { albedo: Rgb::splat(0.3), specular: Rgb::splat(0.5), exponent: 11.0 };
    let wo = dir_at(30.0);
    let r = sphere_chi2(
        |rng| bsdf::sample(&m, &sp_z(), wo, u3(rng), Mode::Radiance).map(|s| s.wi),
        |wi| bsdf::pdf_w(&wrong, &sp_z(), wo, wi) as f64,
        64,
        64,
        N,
        901,
    );
    assert!(!r.passes(a), "exponent-11 pdf accepted for exponent-10 samples: {r:?}");
    // 3. A sampler that puts mass where the pdf is zero fails outright: mirrored cosine samples.
    let r = sphere_chi2(
        |rng| Some(-warp::sample_cosine_hemisphere(rng.next_2d())),
        |w| warp::cosine_hemisphere_pdf(w.z) as f64,
        16,
        16,
        10_000,
        902,
    );
    assert!(r.impossible_samples > 0.0 && !r.passes(a));
    // 4. A biased triangle warp (square root missing in the classic map) is caught.
    let n = 16usize;
    let mut obs = vec![0.0f64; n * n];
    let mut rng = Rng::keyed(903, stream::MISC, 0, 0);
    for _ in 0..100_000 {
        let [u0, u1] = rng.next_2d();
        let (b0, b1) = (1.0 - u0, u1 * u0); // should be 1 − √u0, u1·√u0
        obs[((b1 * n as f32) as usize).min(n - 1) * n + ((b0 * n as f32) as usize).min(n - 1)] += 1.0;
    }
    let exp: Vec<f64> = (0..n * n)
        .map(|c| {
            let (i, j) = (c % n, c / n);
            1e5 * if i + j < n - 1 {
                2.0
            } else if i + j == n - 1 {
                1.0
            } else {
                0.0
            } / (n * n) as f64
        })
        .collect();
    assert!(!chi2_test(&obs, &exp, 5.0).passes(a));
}
