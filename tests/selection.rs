//! Light and direction selection for issues #11 and #12: the alias table, RIS point-light
//! selection, the defensive BSDF/table mixture and splatted forecast tables.
//!
//! Every sampler is tested against its own distribution (Pearson χ², `stats::chi2_test` /
//! `hemisphere_chi2`, cells with expected < 5 pooled, any sample in a zero-pdf cell fails), and every
//! estimator against the quantity it estimates (z-test of the mean with the sample variance; two-sample
//! when the reference is itself a Monte Carlo estimate). Family-wise level ALPHA = 0.01 over the
//! N_TESTS statistical tests of this file, Šidák-corrected; seeds are fixed, so outcomes are
//! deterministic. Negative controls show each harness can fail.
//!
//! The timings of these samplers are a bench, not a test: `cargo bench --bench selection`.

use forecast::bsdf::{self, Mode, ShadingPoint};
use forecast::cf::direction_table::{
    bin_of, splat_histogram, DirectionTable, ForecastTables, Splat, TableMode, N_BINS, N_MU, N_PHI,
};
use forecast::cf::mixture::{DefensiveMixture, MixtureWeights};
use forecast::math::{luminance, Frame, Rgb, Vec3, PI};
use forecast::sampling::alias::AliasTable;
use forecast::sampling::rng::{stream, Rng};
use forecast::scene::Material;
use forecast::stats::{chi2_test, hemisphere_chi2, sidak_alpha, z_test_threshold, Chi2Result};
use forecast::transport::light_select::{LightSelector, RisParams};

/// Family-wise significance level of the file.
const ALPHA: f64 = 0.01;
/// Statistical tests that must pass, counted below: alias χ² 3; RIS all-candidates z 2,
/// RIS selection χ² 4, RIS small-M z 6; mixture χ² 4, mixture estimator z 5; splatted tables χ² 4.
const N_TESTS: usize = 28;
/// Samples per χ² test.
const N: usize = 1_000_000;

fn alpha() -> f64 {
    sidak_alpha(ALPHA, N_TESTS)
}

fn zcrit() -> f64 {
    z_test_threshold(ALPHA, N_TESTS)
}

fn check(name: &str, r: &Chi2Result) {
    assert!(r.dof >= 3, "{name}: too few cells: {r:?}");
    assert!(r.impossible_samples == 0.0, "{name}: samples in zero-probability cells: {r:?}");
    assert!(r.passes(alpha()), "{name}: rejected at per-test level {:.3e}: {r:?}", alpha());
    let rel = (r.n_expected - r.n_observed).abs() / r.n_observed.max(1.0);
    assert!(rel < 0.01, "{name}: total expected {} vs observed {}", r.n_expected, r.n_observed);
}

/// (mean, standard error) of `n` independent estimates, each from its own keyed stream.
fn mean_se(n: usize, seed: u64, mut est: impl FnMut(&mut Rng) -> f64) -> (f64, f64) {
    let (mut s, mut s2) = (0.0f64, 0.0f64);
    for i in 0..n {
        let mut r = Rng::keyed(seed, stream::MISC, 7, i as u64);
        let x = est(&mut r);
        s += x;
        s2 += x * x;
    }
    let m = s / n as f64;
    let var = (s2 / n as f64 - m * m).max(0.0) * n as f64 / (n - 1) as f64;
    (m, (var / n as f64).sqrt())
}

fn z_check(name: &str, (m, se): (f64, f64), truth: f64, truth_se: f64) {
    let z = (m - truth) / (se * se + truth_se * truth_se).sqrt();
    assert!(z.abs() < zcrit(), "{name}: mean {m} vs {truth} (se {se}, {truth_se}): z = {z:.2} > {:.2}", zcrit());
}

// ---------------------------------------------------------------------------------------------
// Alias table
// ---------------------------------------------------------------------------------------------

fn alias_counts(t: &AliasTable, n: usize, seed: u64) -> Vec<f64> {
    let mut obs = vec![0.0f64; t.len()];
    let mut rng = Rng::keyed(seed, stream::MISC, 0, 0);
    for _ in 0..n {
        obs[t.sample(&mut rng).0] += 1.0;
    }
    obs
}

fn weight_sets() -> Vec<(&'static str, Vec<f32>)> {
    let mut r = Rng::keyed(1, stream::MISC, 0, 0);
    let vpls: Vec<f32> = (0..75).map(|i| if i % 7 == 3 { 0.0 } else { r.next_f32() }).collect();
    // 20 decades of dynamic range, with zeros in between.
    let range: Vec<f32> = (0..40).map(|i| if i % 5 == 4 { 0.0 } else { 10f32.powf(-(i as f32) / 2.0) }).collect();
    let many: Vec<f32> = (0..1000).map(|_| (-6.0 * r.next_f32()).exp()).collect();
    vec![("75 vpl-like", vpls), ("1e-20 range", range), ("1000 entries", many)]
}

#[test]
fn alias_table_matches_its_pmf() {
    for (k, (name, w)) in weight_sets().into_iter().enumerate() {
        let t = AliasTable::new(&w).unwrap();
        let total: f64 = w.iter().map(|&x| x as f64).sum();
        for (i, &x) in w.iter().enumerate() {
            let p = x as f64 / total;
            // exact up to the 2^-32 threshold quantisation (which floors tiny entries up)
            assert!((t.pmf(i) as f64 - p).abs() <= 1e-5 * p + 1e-9, "{name} #{i}: pmf {} vs {p}", t.pmf(i));
            assert_eq!(t.pmf(i) > 0.0, x > 0.0, "{name} #{i}: support");
        }
        let obs = alias_counts(&t, N, 10 + k as u64);
        let exp: Vec<f64> = (0..w.len()).map(|i| t.pmf(i) as f64 * N as f64).collect();
        check(&format!("alias {name}"), &chi2_test(&obs, &exp, 5.0));
    }
    // Negative control: a 5% error in one entry of 75 is detected.
    let w = &weight_sets()[0].1;
    let t = AliasTable::new(w).unwrap();
    let obs = alias_counts(&t, N, 19);
    let mut exp: Vec<f64> = (0..w.len()).map(|i| t.pmf(i) as f64 * N as f64).collect();
    exp[0] *= 1.05;
    assert!(!chi2_test(&obs, &exp, 5.0).passes(alpha()), "a 5% pmf error must be rejected");
}

// ---------------------------------------------------------------------------------------------
// RIS light selection
// ---------------------------------------------------------------------------------------------

/// A synthetic gather: source weights Φ_i, target p̂_i (unshadowed, clamped contribution) and the
/// visible contribution F_i = p̂_i·V_i·(colour factor), zero wherever p̂ is.
struct Lights {
    phi: Vec<f32>,
    p_hat: Vec<f32>,
    f: Vec<f64>,
}

fn lights(n: usize, seed: u64) -> Lights {
    let mut r = Rng::keyed(seed, stream::MISC, 3, 0);
    let phi: Vec<f32> = (0..n).map(|_| 0.1 + 2.0 * r.next_f32()).collect();
    let p_hat: Vec<f32> =
        phi.iter().enumerate().map(|(i, &p)| if i % 4 == 1 { 0.0 } else { p * r.next_f32().min(0.7) }).collect();
    let f = p_hat
        .iter()
        .enumerate()
        .map(|(i, &p)| {
            let v = if i % 3 == 2 { 0.0 } else { 1.0 }; // occluded lights
            p as f64 * v * (1.0 + 0.5 * (i as f64).sin())
        })
        .collect();
    Lights { phi, p_hat, f }
}

/// One RIS estimate Σ_k weight_k·F(y_k).
fn ris_estimate(sel: &LightSelector, p: &RisParams, l: &Lights, rng: &mut Rng) -> f64 {
    let mut acc = 0.0f64;
    sel.select(p, rng, |i| (l.p_hat[i], l.f[i]), |s| acc += s.weight as f64 * s.value);
    acc
}

#[test]
fn ris_with_all_candidates_equals_the_full_gather() {
    let l = lights(75, 1);
    let truth: f64 = l.f.iter().sum();
    let sel = LightSelector::new(&l.phi).unwrap();
    for (k, surv) in [1u32, 4].into_iter().enumerate() {
        let p = RisParams::new(0, surv, true).unwrap();
        let r = mean_se(200_000, 20 + k as u64, |rng| ris_estimate(&sel, &p, &l, rng));
        z_check(&format!("RIS all, K={surv}"), r, truth, 0.0);
    }
}

/// Exact selection distribution (index n = none) and E[W·F] of RIS with K = 1 and M candidates,
/// by enumerating all n^M candidate tuples with the selector's own source pmf.
fn ris_exact(sel: &LightSelector, l: &Lights, m: u32) -> (Vec<f64>, f64) {
    let n = l.phi.len();
    let mut dist = vec![0.0f64; n + 1];
    let mut mean = 0.0f64;
    for code in 0..n.pow(m) {
        let tuple: Vec<usize> = (0..m).map(|j| code / n.pow(j) % n).collect();
        let prob: f64 = tuple.iter().map(|&i| sel.source_pmf(i) as f64).product();
        let w: Vec<f64> = tuple.iter().map(|&i| l.p_hat[i] as f64 / sel.source_pmf(i) as f64).collect();
        let ws: f64 = w.iter().sum();
        if ws <= 0.0 {
            dist[n] += prob;
            continue;
        }
        for (j, &i) in tuple.iter().enumerate().filter(|&(j, _)| w[j] > 0.0) {
            dist[i] += prob * w[j] / ws;
            mean += prob * w[j] / ws * l.f[i] * ws / (m as f64 * l.p_hat[i] as f64);
        }
    }
    (dist, mean)
}

#[test]
fn ris_selection_frequencies_match_the_exact_distribution() {
    let count = |sel: &LightSelector, p: &RisParams, n: usize, l: &Lights, seed: u64| {
        let mut obs = vec![0.0f64; n + 1];
        let mut rng = Rng::keyed(seed, stream::MISC, 0, 0);
        for _ in 0..N {
            let mut got = n;
            sel.select(p, &mut rng, |i| (l.p_hat[i], ()), |s| got = s.index);
            obs[got] += 1.0;
        }
        obs
    };
    // M → ∞ (all lights once): exactly p̂/Σp̂.
    let l = lights(40, 2);
    let sel = LightSelector::new(&l.phi).unwrap();
    let sum: f64 = l.p_hat.iter().map(|&x| x as f64).sum();
    let mut exp: Vec<f64> = l.p_hat.iter().map(|&x| x as f64 / sum * N as f64).collect();
    exp.push(0.0);
    let obs = count(&sel, &RisParams::new(0, 1, true).unwrap(), 40, &l, 30);
    check("RIS all: p̂/Σp̂", &chi2_test(&obs, &exp, 5.0));
    // Finite M on 5 lights: the enumerated distribution (which is not p̂/Σp̂).
    let l = lights(5, 3);
    let sel = LightSelector::new(&l.phi).unwrap();
    let truth: f64 = l.f.iter().sum();
    for m in [1u32, 2, 3] {
        let (dist, mean) = ris_exact(&sel, &l, m);
        // f32 pmfs: Σq = 1 to ~1e-7, so the enumerated mean is exact to ~M·1e-7
        assert!((mean - truth).abs() <= 1e-6 * truth, "M={m}: exact E[W·F] {mean} vs Σ F {truth}");
        let exp: Vec<f64> = dist.iter().map(|&p| p * N as f64).collect();
        let obs = count(&sel, &RisParams::new(m, 1, false).unwrap(), 5, &l, 31 + m as u64);
        check(&format!("RIS M={m} exact"), &chi2_test(&obs, &exp, 5.0));
    }
}

#[test]
fn ris_with_few_candidates_is_unbiased() {
    let l = lights(75, 4);
    let truth: f64 = l.f.iter().sum();
    let power = LightSelector::new(&l.phi).unwrap();
    let defensive = LightSelector::with_uniform_share(&l.phi, 0.3).unwrap();
    let cases = [
        (&power, RisParams::new(1, 1, false).unwrap()),
        (&power, RisParams::new(2, 1, false).unwrap()),
        (&power, RisParams::new(4, 1, false).unwrap()),
        (&power, RisParams::new(4, 3, false).unwrap()),
        (&defensive, RisParams::new(8, 4, true).unwrap()),
        (&power, RisParams::new(40, 2, false).unwrap()), // M > BUFFERED: streaming reservoirs
    ];
    for (k, (sel, p)) in cases.iter().enumerate() {
        let r = mean_se(400_000, 40 + k as u64, |rng| ris_estimate(sel, p, &l, rng));
        z_check(&format!("RIS {p:?}"), r, truth, 0.0);
    }
    // Negative control: a target that is 0 on a contributing light loses its F (bias detected).
    let i0 = (0..75).find(|&i| l.f[i] > 0.5).unwrap();
    let p = RisParams::new(4, 1, false).unwrap();
    let r = mean_se(400_000, 49, |rng| {
        let mut acc = 0.0;
        power.select(
            &p,
            rng,
            |i| (if i == i0 { 0.0 } else { l.p_hat[i] }, l.f[i]),
            |s| acc += s.weight as f64 * s.value,
        );
        acc
    });
    assert!(((r.0 - truth) / r.1).abs() > zcrit(), "a target missing light {i0} must be biased: {r:?} vs {truth}");
}

#[test]
fn ris_draws_a_fixed_number_of_uniforms_and_rejects_bad_parameters() {
    let l = lights(75, 5);
    let sel = LightSelector::new(&l.phi).unwrap();
    for (m, k, shared, words) in [
        (4u32, 1u32, false, 9usize),
        (8, 3, true, 19),
        (4, 2, false, 18),
        (0, 2, true, 150),
        (40, 2, true, 160),
        (40, 2, false, 240),
    ] {
        let p = RisParams::new(m, k, shared).unwrap();
        let mut a = Rng::keyed(9, stream::MISC, 0, 0);
        let mut b = a.clone();
        let mut n_sel = 0;
        sel.select(&p, &mut a, |i| (l.p_hat[i], ()), |_| n_sel += 1);
        assert!(n_sel <= k);
        for _ in 0..words {
            b.next_u32();
        }
        assert_eq!(a.next_u32(), b.next_u32(), "M={m} K={k} shared={shared}: {words} words expected");
    }
    // All-zero target: no survivor, estimate 0.
    let p = RisParams::new(4, 2, true).unwrap();
    let mut rng = Rng::keyed(9, stream::MISC, 1, 0);
    sel.select(&p, &mut rng, |_| (f32::NAN, ()), |_| panic!("no light may be selected"));
    assert!(RisParams::new(4, 0, false).is_err() && RisParams::new(4, 17, true).is_err());
    assert!(RisParams::new(1 << 20, 1, true).unwrap_err().contains("candidates"));
    assert!(LightSelector::new(&[0.0; 4]).is_none() && LightSelector::new(&[]).is_none());
}

// ---------------------------------------------------------------------------------------------
// Defensive mixture
// ---------------------------------------------------------------------------------------------

fn dir(theta_deg: f32, phi_deg: f32) -> Vec3 {
    let (t, p) = (theta_deg.to_radians(), phi_deg.to_radians());
    Vec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos())
}

/// Forecasters in a cone of half-angle `spread` around (θ, φ), weight μ (Lambertian lum·f·μ).
fn photon_set(n: usize, theta: f32, phi: f32, spread: f32, seed: u64) -> Vec<(Vec3, f32)> {
    let mut r = Rng::keyed(seed, stream::MISC, 5, 0);
    (0..n)
        .map(|_| {
            let d = dir(
                (theta + spread * (2.0 * r.next_f32() - 1.0)).clamp(0.5, 89.0),
                phi + spread * (2.0 * r.next_f32() - 1.0),
            );
            (d, d.z)
        })
        .collect()
}

fn sp_with(ns: Vec3) -> ShadingPoint {
    ShadingPoint::new(Vec3::ZERO, Vec3::Z, ns)
}

fn lambert() -> Material {
    Material::Diffuse { albedo: Rgb::new(0.7, 0.5, 0.3) }
}

fn phong() -> Material {
    Material::Glossy { albedo: Rgb::splat(0.3), specular: Rgb::splat(0.5), exponent: 10.0 }
}

/// Tables in the frame of `sp.ns` with the material's own f·cos fill.
fn tables(
    m: &Material,
    sp: &ShadingPoint,
    wo: Vec3,
    photons: &[(Vec3, f32)],
    mode: TableMode,
    s: Splat,
) -> (ForecastTables, Frame) {
    let frame = Frame::from_normal(sp.ns);
    let fc = |l: Vec3| luminance(bsdf::eval(m, sp, wo, frame.to_world(l), Mode::Radiance)) * l.z;
    (ForecastTables::build_with(photons.iter().copied(), fc, mode, s), frame)
}

struct Case {
    name: &'static str,
    m: Material,
    sp: ShadingPoint,
    wo: Vec3,
    t: ForecastTables,
    frame: Frame,
    c: MixtureWeights,
}

fn cases() -> Vec<Case> {
    let w = MixtureWeights::new(0.3, 0.5, 0.2).unwrap();
    let flat = sp_with(Vec3::Z);
    let miss = photon_set(200, 60.0, 200.0, 10.0, 5); // far from the L cone below
    let hit = photon_set(100, 40.0, 30.0, 4.0, 6);
    let mk = |name, m: Material, sp: ShadingPoint, wo: Vec3, ph: &[(Vec3, f32)], mode, s, c| {
        let (t, frame) = tables(&m, &sp, wo, ph, mode, s);
        Case { name, m, sp, wo, t, frame, c }
    };
    let tilted = sp_with(dir(15.0, 90.0));
    vec![
        mk("lambert dual", lambert(), flat, dir(30.0, 0.0), &miss, TableMode::Dual, Splat::None, w),
        mk("phong dual", phong(), flat, dir(45.0, 20.0), &miss, TableMode::Dual, Splat::None, w),
        mk("phong T1 only", phong(), flat, dir(60.0, 0.0), &hit, TableMode::Dual, Splat::None, w).t1_only(),
        mk("lambert splat", lambert(), flat, dir(10.0, 0.0), &hit, TableMode::Dual, Splat::Tent { radius: 1.5 }, w),
        mk("lambert hit", lambert(), flat, dir(30.0, 0.0), &hit, TableMode::Dual, Splat::None, w),
        mk("lambert tilted", lambert(), tilted, dir(50.0, 270.0), &miss, TableMode::Dual, Splat::None, w),
    ]
}

impl Case {
    /// The case with one table (T2 dropped): the mixture's single-table path.
    fn t1_only(mut self) -> Case {
        self.t.t2 = None;
        self
    }

    fn mix(&self) -> DefensiveMixture<'_> {
        DefensiveMixture::new(&self.m, &self.sp, self.wo, &self.t, self.frame, self.c)
    }
}

#[test]
fn mixture_sampler_matches_its_pdf() {
    // The flat cases (n_g = n_s = z, identity frame): the 64×32 grid refines the 32×16 bins.
    for (k, c) in cases().iter().take(4).enumerate() {
        let mix = c.mix();
        assert!(c.frame.to_world(Vec3::new(0.3, 0.2, 0.9)) == Vec3::new(0.3, 0.2, 0.9));
        let r = hemisphere_chi2(|rng| mix.sample(rng).map(|s| s.wi), |w| mix.pdf_w(w) as f64, 64, 32, N, 60 + k as u64);
        check(&format!("mixture {}", c.name), &r);
    }
    // Negative control: the same samples judged against other weights are rejected.
    let c = &cases()[0];
    let (mix, wrong) = (c.mix(), MixtureWeights::new(0.3, 0.6, 0.1).unwrap());
    let other = DefensiveMixture::new(&c.m, &c.sp, c.wo, &c.t, c.frame, wrong);
    let r = hemisphere_chi2(|rng| mix.sample(rng).map(|s| s.wi), |w| other.pdf_w(w) as f64, 64, 32, N, 69);
    assert!(!r.passes(alpha()), "wrong mixture weights accepted: {r:?}");
}

#[test]
fn mixture_weights_are_bounded_by_the_bsdf_weight_over_c_b() {
    for c in cases() {
        let mix = c.mix();
        let cb = mix.weights()[0];
        let mut rng = Rng::keyed(70, stream::MISC, 0, 0);
        let mut n_ok = 0;
        for _ in 0..200_000 {
            let Some(s) = mix.sample(&mut rng) else { continue };
            let p_b = bsdf::pdf_w(&c.m, &c.sp, c.wo, s.wi);
            let q = mix.pdf_w(s.wi);
            assert!((s.pdf_w - q).abs() <= 1e-4 * q, "{}: sample pdf {} vs pdf_w {q}", c.name, s.pdf_w);
            // the BSDF's own pdf, which the roulette after a guided vertex divides by
            assert!((s.bsdf_pdf_w - p_b).abs() <= 1e-4 * p_b, "{}: bsdf_pdf_w {} vs {p_b}", c.name, s.bsdf_pdf_w);
            let f_cos = bsdf::eval(&c.m, &c.sp, c.wo, s.wi, Mode::Radiance) * s.wi.dot(c.sp.ns).abs();
            let bound = f_cos / (cb * p_b);
            assert!(s.weight.cmple(bound * (1.0 + 1e-4) + 1e-7).all(), "{}: weight {} > {bound}", c.name, s.weight);
            if let Material::Diffuse { albedo } = c.m {
                assert!(s.weight.cmple(albedo / cb * (1.0 + 1e-4)).all(), "{}: {} > albedo/c_B", c.name, s.weight);
            }
            n_ok += 1;
        }
        assert!(n_ok > 150_000, "{}: only {n_ok} samples", c.name);
    }
}

/// Incident radiance of the estimator test: 0.3 everywhere plus 50 in a 5° cone (world).
fn cone_axis() -> Vec3 {
    dir(40.0, 30.0)
}
fn radiance(w: Vec3) -> f32 {
    let cone = if w.dot(cone_axis()) >= 5f32.to_radians().cos() { 50.0 } else { 0.0 };
    0.3 + cone
}

#[test]
fn mixture_estimator_is_unbiased() {
    let n = 300_000;
    for (k, c) in cases().iter().enumerate() {
        let mix = c.mix();
        let lum = |s: Option<forecast::cf::mixture::MixtureSample>| {
            s.map_or(0.0, |s| luminance(s.weight) as f64 * radiance(s.wi) as f64)
        };
        let est = mean_se(n, 80 + k as u64, |rng| lum(mix.sample(rng)));
        if c.sp.ns == Vec3::Z && matches!(c.m, Material::Diffuse { .. }) {
            if k == 0 {
                assert!(c.t.t1.as_ref().unwrap().pdf_w(cone_axis()) == 0.0, "T1 must miss the cone");
            }
            // ∫ ρ/π·cos·L = ρ·(0.3 + 50·(a·z)·sin²5°) exactly (the cone lies above the horizon).
            let rho = luminance(Rgb::new(0.7, 0.5, 0.3)) as f64;
            let truth = rho * (0.3 + 50.0 * cone_axis().z as f64 * 5f64.to_radians().sin().powi(2));
            z_check(&format!("mixture estimate {}", c.name), est, truth, 0.0);
        } else if k < 6 {
            // Reference: the plain BSDF estimator (independent streams), two-sample z-test.
            let reference = mean_se(4 * n, 90 + k as u64, |rng| {
                let u = [rng.next_f32(), rng.next_f32(), rng.next_f32()];
                bsdf::sample(&c.m, &c.sp, c.wo, u, Mode::Radiance)
                    .map_or(0.0, |s| luminance(s.weight) as f64 * radiance(s.wi) as f64)
            });
            z_check(&format!("mixture estimate {}", c.name), est, reference.0, reference.1);
        }
    }
}

#[test]
fn mixture_degenerate_cases() {
    let c = &cases()[0];
    // c_B = 1, Dirac materials and vertices without tables use bsdf::sample bit for bit.
    let glass = Material::Glass { ior: 1.5 };
    let only = MixtureWeights::new(1.0, 0.0, 0.0).unwrap();
    let none = ForecastTables { t1: None, t2: None };
    for (m, t, w) in [(c.m, &c.t, only), (glass, &c.t, c.c), (phong(), &none, c.c)] {
        let mix = DefensiveMixture::new(&m, &c.sp, c.wo, t, c.frame, w);
        assert!(mix.is_bsdf_only());
        let (mut a, mut b) = (Rng::keyed(3, stream::MISC, 0, 0), Rng::keyed(3, stream::MISC, 0, 0));
        for _ in 0..1000 {
            let s = mix.sample(&mut a);
            let u = [b.next_f32(), b.next_f32(), b.next_f32()];
            let r = bsdf::sample(&m, &c.sp, c.wo, u, Mode::Radiance);
            assert_eq!(
                s.map(|s| (s.wi, s.weight, s.pdf_w, s.is_delta)),
                r.map(|r| (r.wi, r.weight, r.pdf_w, r.is_delta))
            );
        }
        assert_eq!(a.next_u32(), b.next_u32(), "same number of uniforms as bsdf::sample");
    }
    // Bad weights are errors naming the weight.
    assert!(MixtureWeights::new(0.0, 1.0, 0.0).unwrap_err().contains("BSDF"));
    assert!(MixtureWeights::new(0.5, f32::NAN, 0.0).unwrap_err().contains("T1"));
    assert!(MixtureWeights::new(0.5, 0.0, -1.0).unwrap_err().contains("T2"));
    assert!(MixtureWeights::guide_fraction(0.0).is_err() && MixtureWeights::guide_fraction(1.5).is_err());
    let g = MixtureWeights::guide_fraction(0.25).unwrap();
    assert!((g.bsdf - 0.25).abs() < 1e-6 && (g.t1 - 0.375).abs() < 1e-6);
    // A single table: T2's share moves to the others; weights sum to 1.
    let single = &cases()[2];
    let w = single.mix().weights();
    assert!(w[2] == 0.0 && (w.iter().sum::<f32>() - 1.0).abs() < 1e-6 && (w[0] - 0.3 / 0.8).abs() < 1e-6);
    // Below the surface: no density, no sample.
    let mix = c.mix();
    assert_eq!(mix.pdf_w(-Vec3::Z), 0.0);
    let from_below = DefensiveMixture::new(&c.m, &c.sp, c.wo * Vec3::new(1.0, 1.0, -1.0), &c.t, c.frame, c.c);
    let mut rng = Rng::keyed(4, stream::MISC, 0, 0);
    for _ in 0..1000 {
        if let Some(s) = from_below.sample(&mut rng) {
            assert!(s.wi.z < 0.0, "wo below n_g: the surface is seen from its other side");
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Splatted tables
// ---------------------------------------------------------------------------------------------

#[test]
fn splatting_conserves_weight_and_the_default_is_unchanged() {
    let ph = photon_set(300, 35.0, 120.0, 25.0, 7);
    let total: f32 = ph.iter().map(|p| p.1).sum();
    for radius in [1.0f32, 1.5, 3.0, 100.0] {
        let h = splat_histogram(ph.iter().copied(), Splat::Tent { radius });
        assert!((h.iter().sum::<f32>() / total - 1.0).abs() < 1e-5, "radius {radius}");
    }
    let lam = |l: Vec3| l.z;
    let plain = ForecastTables::build(ph.iter().copied(), lam, TableMode::Dual);
    assert_eq!(plain, ForecastTables::build_with(ph.iter().copied(), lam, TableMode::Dual, Splat::None));
    let splat = ForecastTables::build_with(ph.iter().copied(), lam, TableMode::Dual, Splat::Tent { radius: 1.0 });
    let covered = |t: &DirectionTable| (0..N_BINS).filter(|&i| t.bin_pmf(i) > 0.0).count();
    assert!(covered(splat.t1.as_ref().unwrap()) > covered(plain.t1.as_ref().unwrap()));
    // Bilinear: a photon at a bin centre stays there; one at a corner splits evenly over 4 bins.
    let centre = |j: f32, l: f32| {
        let (phi, mu) = (2.0 * PI * j / N_PHI as f32, l / N_MU as f32);
        let s = (1.0 - mu * mu).sqrt();
        Vec3::new(s * phi.cos(), s * phi.sin(), mu)
    };
    let bil = Splat::Tent { radius: 1.0 };
    let h = splat_histogram([(centre(5.5, 7.5), 2.0)], bil);
    let i = bin_of(centre(5.5, 7.5)).unwrap();
    assert!((h[i] - 2.0).abs() < 1e-4 && h.iter().sum::<f32>() - h[i] < 1e-4);
    let h = splat_histogram([(centre(6.0, 8.0), 1.0)], bil);
    for b in [7 * N_PHI + 5, 7 * N_PHI + 6, 8 * N_PHI + 5, 8 * N_PHI + 6] {
        assert!((h[b] - 0.25).abs() < 1e-3, "bin {b}: {}", h[b]);
    }
    // φ wraps round; rows past the pole are dropped and the rest renormalised.
    let h = splat_histogram([(centre(0.1, 15.9), 1.0)], bil);
    assert!(h[15 * N_PHI + N_PHI - 1] > 0.0 && h[15 * N_PHI] > 0.0 && (h.iter().sum::<f32>() - 1.0).abs() < 1e-5);
    // Bad photons are ignored.
    let bad = [(-Vec3::Z, 1.0), (Vec3::Z, f32::NAN), (Vec3::Z, -2.0), (Vec3::NAN, 1.0)];
    assert!(splat_histogram(bad, bil).iter().all(|&x| x == 0.0));
}

#[test]
fn splatted_tables_match_their_pdf() {
    let sparse = photon_set(3, 40.0, 100.0, 30.0, 8);
    let peaked: Vec<(Vec3, f32)> = vec![(dir(35.0, 250.0), 1.0); 500];
    let mut k = 0;
    for (set, radius) in [(&sparse, 1.0f32), (&peaked, 2.0)] {
        let t = ForecastTables::build_with(set.iter().copied(), |l| l.z, TableMode::Dual, Splat::Tent { radius });
        for tab in [t.t1.unwrap(), t.t2.unwrap()] {
            let r = hemisphere_chi2(
                |r: &mut Rng| Some(tab.sample([r.next_f32(), r.next_f32(), r.next_f32()]).0),
                |w| tab.pdf_w(w) as f64,
                64,
                32,
                N,
                100 + k,
            );
            check(&format!("splatted table #{k}"), &r);
            k += 1;
        }
    }
}
