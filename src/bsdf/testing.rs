//! The checks every BSDF file's tests run on a [`LocalBsdf`] (spec §8; Mitsuba 3's `chi2.py`):
//! a χ² test of `sample` against `pdf_w`, `sample`'s weight against `eval·|cos|/pdf`, a white
//! furnace (the mean weight, the directional albedo, is at most 1) and agreement with Mitsuba 3's
//! own `eval` and `pdf` on the committed tables of `tests/data/bsdf/<plugin>.csv`
//! (`scripts/mitsuba-bsdf-tables.py` writes them).
//!
//! Significance: each BSDF file runs its χ² tests at `sidak_alpha(0.01, n)` for its own `n`
//! tests, so a correct sampler fails with probability below 1% per file.

use super::{LocalBsdf, Mode};
use crate::math::{Rgb, Vec3};
use crate::sampling::rng::{stream, Rng};
use crate::stats::{chi2_test, sidak_alpha, Chi2Result};

/// Samples per χ² test.
pub const CHI2_SAMPLES: usize = 1_000_000;

/// The unit direction at polar angle `theta` and azimuth `phi` (degrees) in the local frame.
pub fn dir(theta: f32, phi: f32) -> Vec3 {
    let (t, p) = (theta.to_radians(), phi.to_radians());
    Vec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos())
}

/// Three uniforms.
pub fn u3(rng: &mut Rng) -> [f32; 3] {
    [rng.next_f32(), rng.next_f32(), rng.next_f32()]
}

/// A deterministic generator for test `seed`.
pub fn rng(seed: u64) -> Rng {
    Rng::keyed(seed, stream::MISC, 0x0b5d_f7e5, 0)
}

/// χ² of `b`'s non-Dirac samples against its `pdf_w` over the sphere (Dirac samples are left
/// out: their share is `1 − ∫pdf_w`, which the test's total checks). Asserts a pass at the
/// Šidák level of `n_tests` tests and that the observed total matches `∫pdf_w` within 1%.
pub fn assert_chi2(name: &str, b: &impl LocalBsdf, wo: Vec3, mode: Mode, n_tests: usize, seed: u64) -> Chi2Result {
    let r = sphere_chi2_fine(
        |rng| b.sample(wo, u3(rng), mode).filter(|s| !s.is_delta).map(|s| s.wi),
        |wi| b.pdf_w(wo, wi, mode) as f64,
        seed,
    );
    let alpha = sidak_alpha(0.01, n_tests);
    assert!(r.impossible_samples == 0.0, "{name}: samples where pdf_w = 0: {r:?}");
    assert!(r.passes(alpha), "{name}: χ² rejected at {alpha:.2e}: {r:?}");
    let rel = (r.n_expected - r.n_observed).abs() / r.n_observed.max(1.0);
    assert!(rel < 0.01, "{name}: ∫pdf_w = {} samples, drew {}", r.n_expected, r.n_observed);
    r
}

/// Cells of [`assert_chi2`]'s grid in φ and in μ = cos θ.
const CHI2_CELLS: usize = 40;

/// `stats::sphere_chi2` on its 40 × 40 grid (the same binning, stream and pooling) with each
/// cell's expected count integrated adaptively: its fixed 6 × 6 midpoint rule is off by percents
/// on lobes a few degrees wide (a microfacet lobe of α = 0.05: a correct sampler rejected at
/// p < 1e-20, and at p = 0.1 with 48 × 48 points), so each cell's midpoint rule doubles its
/// resolution from 6 × 6 up to 96 × 96 until two successive estimates differ by less than
/// 0.05·√(expected count) + 1e-3 samples (a bias whose χ² share is below 0.0025 per cell).
fn sphere_chi2_fine(
    mut sample: impl FnMut(&mut Rng) -> Option<Vec3>,
    pdf_w: impl Fn(Vec3) -> f64,
    seed: u64,
) -> Chi2Result {
    let n = CHI2_CELLS;
    let tau = 2.0 * std::f64::consts::PI;
    // one extra cell (expected 0) collects samples outside the sphere or non-finite
    let mut observed = vec![0.0f64; n * n + 1];
    let mut rng = Rng::keyed(seed, stream::MISC, 0x0c41_2000, 0);
    for _ in 0..CHI2_SAMPLES {
        let Some(w) = sample(&mut rng) else { continue };
        let len = w.length() as f64;
        if !len.is_finite() || (len - 1.0).abs() > 1e-3 {
            observed[n * n] += 1.0;
            continue;
        }
        let mu = (w.z as f64 / len).clamp(-1.0, 1.0);
        let mut phi = w.y.atan2(w.x);
        if phi < 0.0 {
            phi += 2.0 * std::f32::consts::PI;
        }
        let j = ((phi * (n as f32 / (2.0 * std::f32::consts::PI))) as usize).min(n - 1);
        let l = (((mu + 1.0) / 2.0 * n as f64) as usize).min(n - 1);
        observed[l * n + j] += 1.0;
    }
    let (dphi, dmu) = (tau / n as f64, 2.0 / n as f64);
    let count = |l: usize, j: usize, res: usize| {
        let mut acc = 0.0;
        for a in 0..res {
            let mu = -1.0 + dmu * (l as f64 + (a as f64 + 0.5) / res as f64);
            let s = (1.0 - mu * mu).max(0.0).sqrt();
            for c in 0..res {
                let phi = dphi * (j as f64 + (c as f64 + 0.5) / res as f64);
                let p = pdf_w(Vec3::new((s * phi.cos()) as f32, (s * phi.sin()) as f32, mu as f32));
                if p.is_finite() && p > 0.0 {
                    acc += p;
                }
            }
        }
        acc * dphi * dmu / (res * res) as f64 * CHI2_SAMPLES as f64
    };
    let mut expected = vec![0.0f64; n * n + 1];
    for l in 0..n {
        for j in 0..n {
            let (mut res, mut e) = (6, count(l, j, 6));
            loop {
                let finer = count(l, j, 2 * res);
                let settled = (finer - e).abs() < 0.05 * finer.sqrt() + 1e-3;
                (res, e) = (2 * res, finer);
                if settled || res >= 96 {
                    break;
                }
            }
            expected[l * n + j] = e;
        }
    }
    chi2_test(&observed, &expected, 5.0)
}

/// `sample`'s weight equals `eval·|cos θ_i|/pdf_w` and its pdf equals `pdf_w` (relative `tol`)
/// for every non-Dirac sample of `n`.
pub fn assert_weights(name: &str, b: &impl LocalBsdf, wo: Vec3, mode: Mode, n: usize, tol: f32) {
    let mut rng = rng(7);
    for _ in 0..n {
        let Some(s) = b.sample(wo, u3(&mut rng), mode) else { continue };
        assert!(s.weight.is_finite() && s.weight.min_element() >= 0.0, "{name}: weight {} at {:?}", s.weight, s.wi);
        if s.is_delta {
            continue;
        }
        let pdf = b.pdf_w(wo, s.wi, mode);
        assert!((pdf - s.pdf_w).abs() <= tol * pdf.max(1e-3), "{name}: sample pdf {} vs pdf_w {pdf}", s.pdf_w);
        let want = b.eval(wo, s.wi, mode) * s.wi.z.abs() / s.pdf_w;
        let err = (s.weight - want).abs().max_element();
        assert!(
            err <= tol * want.max_element().max(1e-3),
            "{name}: weight {} vs f·cos/pdf {want} at {:?}",
            s.weight,
            s.wi
        );
    }
}

/// The directional albedo ∫f·|cos| dω_i from `wo`: the mean importance-mode weight of `n`
/// samples, Dirac lobes included (the white furnace: at most 1 for a passive BSDF). Summed in
/// f64: an f32 sum of 2·10⁵ weights near 1 drifts by ~6e-4.
pub fn albedo(b: &impl LocalBsdf, wo: Vec3, n: usize) -> Rgb {
    let mut rng = rng(11);
    let mut sum = glam::DVec3::ZERO;
    for _ in 0..n {
        if let Some(s) = b.sample(wo, u3(&mut rng), Mode::Importance) {
            sum += s.weight.as_dvec3();
        }
    }
    (sum / n as f64).as_vec3()
}

/// The white furnace of a microfacet BSDF over both distributions, visible-normal sampling on and
/// off, and four roughnesses (one anisotropic), from each of `thetas` (degrees): the albedo is at
/// most 1 within 5 standard errors of its estimate (a passive BSDF), and above 0.99 at α = 0.05
/// where `near_one(θ)` (masking hardly loses any there); [`albedo`] agrees with the estimate.
/// `make(kind, α_u, α_v, sample_visible)` builds the BSDF.
pub fn assert_microfacet_furnace<B: LocalBsdf>(
    make: impl Fn(super::microfacet::MicrofacetKind, f32, f32, bool) -> B,
    thetas: &[f32],
    near_one: impl Fn(f32) -> bool,
) {
    use super::microfacet::MicrofacetKind::{Beckmann, Ggx};
    let n = 200_000;
    for kind in [Beckmann, Ggx] {
        for vis in [true, false] {
            for (au, av) in [(0.05, 0.05), (0.3, 0.3), (0.8, 0.8), (0.1, 0.4)] {
                for &theta in thetas {
                    let b = make(kind, au, av, vis);
                    let (a, se) = albedo_and_error(&b, dir(theta, 30.0), n);
                    let name = format!("{kind:?} α {au}/{av} vis {vis} θ {theta}");
                    assert!(a <= 1.0 + 5.0 * se, "{name}: albedo {a} ± {se}");
                    if au == 0.05 && near_one(theta) {
                        assert!(a > 0.99, "{name}: albedo {a} ± {se}");
                    }
                    // the shared estimator, on the same samples
                    let mean = albedo(&b, dir(theta, 30.0), n);
                    assert!((mean.x as f64 - a).abs() < 1e-6, "{name}: {mean} vs {a}");
                }
            }
        }
    }
}

/// The mean of the largest channel of `n` importance-mode weights (Dirac lobes included) and
/// its standard error: a furnace's estimate with the error its bound is derived from.
pub fn albedo_and_error(b: &impl LocalBsdf, wo: Vec3, n: usize) -> (f64, f64) {
    let mut r = rng(11);
    let (mut s, mut s2) = (0.0f64, 0.0f64);
    for _ in 0..n {
        if let Some(x) = b.sample(wo, u3(&mut r), Mode::Importance) {
            let w = x.weight.max_element() as f64;
            s += w;
            s2 += w * w;
        }
    }
    let mean = s / n as f64;
    (mean, ((s2 / n as f64 - mean * mean).max(0.0) / n as f64).sqrt())
}

/// One row of a Mitsuba table: a case name, `wo`, `wi`, Mitsuba's f (its eval / |cos θ_i|) and
/// pdf.
#[derive(Clone, Debug)]
pub struct MitsubaRow {
    /// The case's `name` in `<plugin>.json`.
    pub case: String,
    /// Given direction.
    pub wo: Vec3,
    /// Evaluated direction.
    pub wi: Vec3,
    /// Mitsuba's f without the cosine.
    pub f: Rgb,
    /// Mitsuba's pdf.
    pub pdf: f32,
}

/// The rows of `tests/data/bsdf/<plugin>.csv`.
pub fn mitsuba_table(plugin: &str) -> Vec<MitsubaRow> {
    let path = format!("{}/tests/data/bsdf/{plugin}.csv", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
    text.lines()
        .skip(1)
        .map(|l| {
            let c: Vec<&str> = l.split(',').collect();
            let x: Vec<f32> = c[1..].iter().map(|v| v.parse().unwrap()).collect();
            MitsubaRow {
                case: c[0].to_string(),
                wo: Vec3::new(x[0], x[1], x[2]),
                wi: Vec3::new(x[3], x[4], x[5]),
                f: Rgb::new(x[6], x[7], x[8]),
                pdf: x[9],
            }
        })
        .collect()
}

/// Asserts that `b` (the case `case` of `plugin`'s table) agrees with Mitsuba's f and pdf at
/// every row: |ours − Mitsuba's| ≤ `rel`·|Mitsuba's| + `abs`. Returns the rows checked.
pub fn assert_mitsuba(plugin: &str, case: &str, b: &impl LocalBsdf, mode: Mode, rel: f32, abs: f32) -> usize {
    let rows: Vec<MitsubaRow> = mitsuba_table(plugin).into_iter().filter(|r| r.case == case).collect();
    assert!(!rows.is_empty(), "{plugin}.csv has no case {case}");
    for r in &rows {
        let f = b.eval(r.wo, r.wi, mode);
        let pdf = b.pdf_w(r.wo, r.wi, mode);
        let ok_f = (f - r.f).abs().cmple(r.f.abs() * rel + Vec3::splat(abs)).all();
        let ok_pdf = (pdf - r.pdf).abs() <= r.pdf.abs() * rel + abs;
        assert!(
            ok_f && ok_pdf,
            "{plugin}/{case} wo {:?} wi {:?}: f {f} pdf {pdf}, Mitsuba f {} pdf {}",
            r.wo,
            r.wi,
            r.f,
            r.pdf
        );
    }
    rows.len()
}
