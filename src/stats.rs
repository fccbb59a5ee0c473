//! Statistical test helpers used by the whole crate's tests (spec §8).
//!
//! - the regularized incomplete gamma functions `gamma_p`/`gamma_q` (Numerical Recipes series and
//!   Lentz continued fraction, f64) and the chi-square survival function built on them;
//! - Pearson's chi-square goodness-of-fit test with Mitsuba-3 `chi2.py` style pooling of cells whose
//!   expected count is small (cells sorted by expected count, pooled until the pool reaches the
//!   threshold), failing outright when a sample lands in a cell whose expected count is zero;
//! - Šidák correction and two-sided normal (z-test) helpers;
//! - `hemisphere_chi2` / `sphere_chi2`: histogram a direction sampler on a (φ, μ = cosθ) grid, integrate
//!   its claimed solid-angle pdf `pdf_w` over each cell (every cell has solid angle Δφ·Δμ by Archimedes),
//!   and run the chi-square test.
//!
//! Invariants: nothing here panics on degenerate input (empty slices, NaN, zero expected counts); a
//! degenerate test reports `p_value = 0` (reject) when it saw impossible samples and `p_value = 1` when
//! it has no degrees of freedom. Every result is deterministic given the seed.

// `!(x > 0.0)`-style tests are deliberate: they are true for NaN (degenerate input is rejected).
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use crate::math::Vec3;
use crate::sampling::rng::{stream, Rng};

/// Natural log of Γ(x) for x > 0 (Lanczos, g = 7, n = 9; relative error ~1e-15).
pub fn ln_gamma(x: f64) -> f64 {
    const G: f64 = 7.0;
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if !(x > 0.0) {
        return f64::NAN;
    }
    if x < 0.5 {
        // Reflection: Γ(x)Γ(1−x) = π / sin(πx).
        let pi = std::f64::consts::PI;
        return (pi / (pi * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut a = C[0];
    let t = x + G + 0.5;
    for (i, c) in C.iter().enumerate().skip(1) {
        a += c / (x + i as f64);
    }
    0.5 * (2.0 * std::f64::consts::PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

const GAMMA_EPS: f64 = 1e-15;
const GAMMA_ITMAX: usize = 100_000;

/// Series for P(a, x), valid for x < a + 1.
fn gamma_p_series(a: f64, x: f64) -> f64 {
    let mut ap = a;
    let mut del = 1.0 / a;
    let mut sum = del;
    for _ in 0..GAMMA_ITMAX {
        ap += 1.0;
        del *= x / ap;
        sum += del;
        if del.abs() < sum.abs() * GAMMA_EPS {
            break;
        }
    }
    (sum.ln() - x + a * x.ln() - ln_gamma(a)).exp()
}

/// Continued fraction (modified Lentz) for Q(a, x), valid for x ≥ a + 1.
fn gamma_q_cf(a: f64, x: f64) -> f64 {
    const FPMIN: f64 = 1e-300;
    let mut b = x + 1.0 - a;
    let mut c = 1.0 / FPMIN;
    let mut d = 1.0 / b;
    let mut h = d;
    for i in 1..GAMMA_ITMAX {
        let an = -(i as f64) * (i as f64 - a);
        b += 2.0;
        d = an * d + b;
        if d.abs() < FPMIN {
            d = FPMIN;
        }
        c = b + an / c;
        if c.abs() < FPMIN {
            c = FPMIN;
        }
        d = 1.0 / d;
        let del = d * c;
        h *= del;
        if (del - 1.0).abs() < GAMMA_EPS {
            break;
        }
    }
    (-x + a * x.ln() - ln_gamma(a)).exp() * h
}

/// Regularized incomplete gammas (P(a, x), Q(a, x) = 1 − P): the series below a + 1, the
/// continued fraction above, so each side keeps its precision. NaN for a ≤ 0 or NaN input.
fn gamma_pq(a: f64, x: f64) -> (f64, f64) {
    if !(a > 0.0) || x.is_nan() {
        return (f64::NAN, f64::NAN);
    }
    if x <= 0.0 {
        return (0.0, 1.0);
    }
    if x.is_infinite() {
        return (1.0, 0.0);
    }
    let (p, q) = if x < a + 1.0 {
        let p = gamma_p_series(a, x);
        (p, 1.0 - p)
    } else {
        let q = gamma_q_cf(a, x);
        (1.0 - q, q)
    };
    (p.clamp(0.0, 1.0), q.clamp(0.0, 1.0))
}

/// Regularized lower incomplete gamma P(a, x) = γ(a, x)/Γ(a). NaN for a ≤ 0 or NaN input.
pub fn gamma_p(a: f64, x: f64) -> f64 {
    gamma_pq(a, x).0
}

/// Regularized upper incomplete gamma Q(a, x) = 1 − P(a, x). NaN for a ≤ 0 or NaN input.
pub fn gamma_q(a: f64, x: f64) -> f64 {
    gamma_pq(a, x).1
}

/// Chi-square survival function P(X ≥ chi2) for `dof` degrees of freedom: Q(dof/2, chi2/2).
/// Returns 1 for `dof == 0` and 0 for a NaN statistic.
pub fn chi2_sf(chi2: f64, dof: usize) -> f64 {
    if dof == 0 {
        return 1.0;
    }
    if chi2.is_nan() {
        return 0.0;
    }
    gamma_q(0.5 * dof as f64, 0.5 * chi2.max(0.0))
}

/// Complementary error function erfc(x) = 1 − erf(x) (via Q(1/2, x²) for x ≥ 0; ~1e-14 relative).
pub fn erfc(x: f64) -> f64 {
    if x.is_nan() {
        return f64::NAN;
    }
    if x >= 0.0 {
        gamma_q(0.5, x * x)
    } else {
        2.0 - gamma_q(0.5, x * x)
    }
}

/// Two-sided normal tail probability P(|Z| ≥ |z|) = erfc(|z|/√2) for a standard normal Z.
/// (Use [`normal_upper_tail`] for the one-sided P(Z ≥ z).)
pub fn normal_sf(z: f64) -> f64 {
    erfc(z.abs() / std::f64::consts::SQRT_2)
}

/// One-sided upper normal tail P(Z ≥ z) = erfc(z/√2)/2.
pub fn normal_upper_tail(z: f64) -> f64 {
    0.5 * erfc(z / std::f64::consts::SQRT_2)
}

/// Šidák-corrected per-test significance level so that `n_tests` independent tests have a family-wise
/// error rate `alpha`: 1 − (1 − alpha)^(1/n). Returns `alpha` for `n_tests ≤ 1`.
pub fn sidak_alpha(alpha: f64, n_tests: usize) -> f64 {
    if n_tests <= 1 {
        return alpha;
    }
    // -expm1(log1p(-alpha)/n) is accurate for tiny per-test levels.
    -((-alpha).ln_1p() / n_tests as f64).exp_m1()
}

/// |z| threshold of a two-sided z-test at family-wise level `alpha`, Šidák-corrected over `n`
/// independent tests: the z with `normal_sf(z) = sidak_alpha(alpha, n)`, found by bisection.
/// Example: alpha = 0.01, n = 1 gives 2.5758.
pub fn z_test_threshold(alpha: f64, n: usize) -> f64 {
    let target = sidak_alpha(alpha, n);
    if !(target > 0.0) {
        return f64::INFINITY;
    }
    if target >= 1.0 {
        return 0.0;
    }
    let (mut lo, mut hi) = (0.0f64, 40.0f64);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if normal_sf(mid) > target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// Outcome of a Pearson chi-square goodness-of-fit test.
#[derive(Clone, Debug, PartialEq)]
pub struct Chi2Result {
    /// Pearson statistic Σ (O − E)²/E over the (pooled) cells.
    pub chi2: f64,
    /// Degrees of freedom: number of cells used − 1.
    pub dof: usize,
    /// P(X ≥ chi2); forced to 0 when `impossible_samples > 0`.
    pub p_value: f64,
    /// Number of input cells whose expected count was below the threshold and got pooled.
    pub pooled_cells: usize,
    /// Observed samples that landed in cells with expected count 0 (an outright failure).
    pub impossible_samples: f64,
    /// Total observed count.
    pub n_observed: f64,
    /// Total expected count.
    pub n_expected: f64,
}

impl Chi2Result {
    /// True when the test does not reject at significance level `alpha` (already corrected).
    pub fn passes(&self, alpha: f64) -> bool {
        self.impossible_samples == 0.0 && self.p_value >= alpha
    }
}

/// Pearson chi-square test of `observed` against `expected` counts (Mitsuba 3 `chi2.py` style).
///
/// Cells are sorted by expected count; cells with expected < `min_expected` are pooled until the pool
/// reaches `min_expected` (a leftover pool joins the next larger cell, or stands alone if there is
/// none). Cells with both counts zero are ignored. Any observation in a cell with expected 0 (or a
/// non-finite/negative expectation) makes the test fail with `p_value = 0`.
pub fn chi2_test(observed: &[f64], expected: &[f64], min_expected: f64) -> Chi2Result {
    let n = observed.len().min(expected.len());
    let mut impossible = 0.0;
    let mut cells: Vec<(f64, f64)> = Vec::with_capacity(n); // (expected, observed)
    let (mut n_obs, mut n_exp) = (0.0, 0.0);
    for i in 0..n {
        let (o, e) = (observed[i], expected[i]);
        let o = if o.is_finite() && o > 0.0 { o } else { 0.0 };
        n_obs += o;
        if !(e.is_finite() && e > 0.0) {
            impossible += o;
            continue;
        }
        n_exp += e;
        cells.push((e, o));
    }
    cells.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (mut chi2, mut used, mut pooled_cells) = (0.0f64, 0usize, 0usize);
    let (mut pool_e, mut pool_o) = (0.0f64, 0.0f64);
    for &(e, o) in &cells {
        if e < min_expected {
            pool_e += e;
            pool_o += o;
            pooled_cells += 1;
            if pool_e >= min_expected {
                chi2 += (pool_o - pool_e).powi(2) / pool_e;
                used += 1;
                pool_e = 0.0;
                pool_o = 0.0;
            }
        } else {
            let (e, o) = (e + pool_e, o + pool_o);
            pool_e = 0.0;
            pool_o = 0.0;
            chi2 += (o - e).powi(2) / e;
            used += 1;
        }
    }
    if pool_e > 0.0 {
        chi2 += (pool_o - pool_e).powi(2) / pool_e;
        used += 1;
    }
    let dof = used.saturating_sub(1);
    let p_value = if impossible > 0.0 { 0.0 } else { chi2_sf(chi2, dof) };
    Chi2Result {
        chi2,
        dof,
        p_value,
        pooled_cells,
        impossible_samples: impossible,
        n_observed: n_obs,
        n_expected: n_exp,
    }
}

/// Sub-cell resolution (per dimension) of the midpoint rule integrating `pdf_w` over a grid cell.
pub const PDF_INTEGRATION_RES: usize = 6;

/// Local direction from (φ, μ = cosθ).
#[inline]
fn dir_from_phi_mu(phi: f64, mu: f64) -> Vec3 {
    let s = (1.0 - mu * mu).max(0.0).sqrt();
    Vec3::new((s * phi.cos()) as f32, (s * phi.sin()) as f32, mu as f32)
}

/// Shared implementation of the (φ, μ) grid test over μ ∈ [mu_lo, 1].
fn grid_chi2(
    mut sample: impl FnMut(&mut Rng) -> Option<Vec3>,
    pdf_w: impl Fn(Vec3) -> f64,
    n_phi: usize,
    n_mu: usize,
    n_samples: usize,
    seed: u64,
    mu_lo: f64,
) -> Chi2Result {
    let (n_phi, n_mu) = (n_phi.max(1), n_mu.max(1));
    let n_cells = n_phi * n_mu;
    // One extra cell (expected 0) collects samples outside the domain or non-finite.
    let mut observed = vec![0.0f64; n_cells + 1];
    let two_pi = 2.0 * std::f64::consts::PI;
    let mu_span = 1.0 - mu_lo;
    let mut rng = Rng::keyed(seed, stream::MISC, 0x0c41_2000, 0);
    for _ in 0..n_samples {
        let Some(w) = sample(&mut rng) else { continue };
        let len = w.length() as f64;
        if !len.is_finite() || (len - 1.0).abs() > 1e-3 {
            observed[n_cells] += 1.0;
            continue;
        }
        let mu = (w.z as f64 / len).clamp(-1.0, 1.0);
        if mu < mu_lo {
            observed[n_cells] += 1.0;
            continue;
        }
        // Cells in f32 with the same formula as the samplers' own binning (e.g. the CF tables'
        // `bin_of`): for power-of-two refinements the cell edges then coincide bit for bit, so a
        // sample on a shared edge is never attributed to a neighbouring zero-pdf cell.
        let mut phi32 = w.y.atan2(w.x);
        if phi32 < 0.0 {
            phi32 += 2.0 * std::f32::consts::PI;
        }
        let j = ((phi32 * (n_phi as f32 / (2.0 * std::f32::consts::PI))) as usize).min(n_phi - 1);
        let mu32 = w.z / w.length();
        let l = if mu_lo == 0.0 {
            ((mu32 * n_mu as f32) as usize).min(n_mu - 1)
        } else {
            (((mu - mu_lo) / mu_span * n_mu as f64) as usize).min(n_mu - 1)
        };
        observed[l * n_phi + j] += 1.0;
    }
    // Expected counts: N · ∫_cell pdf_w dω, with dω = dφ dμ; midpoint rule on RES×RES sub-cells.
    let mut expected = vec![0.0f64; n_cells + 1];
    let (dphi, dmu) = (two_pi / n_phi as f64, mu_span / n_mu as f64);
    let res = PDF_INTEGRATION_RES;
    let sub_area = dphi * dmu / (res * res) as f64;
    for l in 0..n_mu {
        for j in 0..n_phi {
            let mut acc = 0.0;
            for a in 0..res {
                let mu = mu_lo + dmu * (l as f64 + (a as f64 + 0.5) / res as f64);
                for b in 0..res {
                    let phi = dphi * (j as f64 + (b as f64 + 0.5) / res as f64);
                    let p = pdf_w(dir_from_phi_mu(phi, mu));
                    if p.is_finite() && p > 0.0 {
                        acc += p;
                    }
                }
            }
            expected[l * n_phi + j] = acc * sub_area * n_samples as f64;
        }
    }
    chi2_test(&observed, &expected, 5.0)
}

/// Chi-square test of a direction sampler over the upper hemisphere (local z = cosθ ≥ 0).
///
/// `sample` draws one local unit direction (or `None` for a failed/absorbed sample, which is not
/// counted); `pdf_w` is its claimed solid-angle density. Samples below the horizon (or non-unit) count
/// as impossible. Grid: `n_phi × n_mu` cells uniform in φ ∈ [0, 2π) and μ ∈ [0, 1].
pub fn hemisphere_chi2(
    sample: impl FnMut(&mut Rng) -> Option<Vec3>,
    pdf_w: impl Fn(Vec3) -> f64,
    n_phi: usize,
    n_mu: usize,
    n_samples: usize,
    seed: u64,
) -> Chi2Result {
    grid_chi2(sample, pdf_w, n_phi, n_mu, n_samples, seed, 0.0)
}

/// Chi-square test of a direction sampler over the full sphere (μ ∈ [−1, 1]); for samplers that can
/// go below the horizon (dielectric BSDFs, Phong). Same contract as [`hemisphere_chi2`].
pub fn sphere_chi2(
    sample: impl FnMut(&mut Rng) -> Option<Vec3>,
    pdf_w: impl Fn(Vec3) -> f64,
    n_phi: usize,
    n_mu: usize,
    n_samples: usize,
    seed: u64,
) -> Chi2Result {
    grid_chi2(sample, pdf_w, n_phi, n_mu, n_samples, seed, -1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Number of chi-square tests in this module that must pass (for Šidák correction).
    const N_PASSING_TESTS: usize = 3;
    const ALPHA: f64 = 0.01;

    fn cosine_sample(rng: &mut Rng) -> Option<Vec3> {
        let (u1, u2) = (rng.next_f32(), rng.next_f32());
        let r = u1.sqrt();
        let phi = 2.0 * std::f32::consts::PI * u2;
        Some(Vec3::new(r * phi.cos(), r * phi.sin(), (1.0 - u1).max(0.0).sqrt()))
    }

    #[test]
    fn gamma_and_chi2_reference_values() {
        // Q(1, x) = e^{-x}; chi2 with 2 dof: sf = e^{-x/2}.
        for &x in &[0.01f64, 0.5, 1.0, 3.0, 10.0, 40.0] {
            assert!((gamma_q(1.0, x) - (-x).exp()).abs() < 1e-12);
            assert!((chi2_sf(x, 2) - (-x / 2.0f64).exp()).abs() < 1e-12);
        }
        // erfc(1) = 0.157299207050285..., two-sided p at 1.96 ≈ 0.0499958.
        assert!((erfc(1.0) - 0.157_299_207_050_285_1).abs() < 1e-12);
        assert!((normal_sf(1.959_963_984_540_054) - 0.05).abs() < 1e-10);
        // chi2 critical value for dof = 10 at 0.05 is 18.307038.
        assert!((chi2_sf(18.307_038_053_275_146, 10) - 0.05).abs() < 1e-9);
        // Large dof: mean ≈ dof gives p ≈ 0.5 - O(1/sqrt(dof)).
        let p = chi2_sf(2000.0, 2000);
        assert!(p > 0.45 && p < 0.5, "{p}");
        assert!((gamma_p(3.0, 2.5) + gamma_q(3.0, 2.5) - 1.0).abs() < 1e-14);
        // Degenerate inputs do not panic.
        assert!(gamma_q(-1.0, 1.0).is_nan());
        assert_eq!(chi2_sf(f64::NAN, 3), 0.0);
        assert_eq!(chi2_sf(5.0, 0), 1.0);
    }

    #[test]
    fn sidak_and_z_threshold() {
        assert!((sidak_alpha(0.01, 1) - 0.01).abs() < 1e-15);
        let a = sidak_alpha(0.01, 100);
        assert!(((1.0 - a).powi(100) - 0.99).abs() < 1e-12);
        assert!((z_test_threshold(0.01, 1) - 2.575_829_303_548_901).abs() < 1e-9);
        assert!((z_test_threshold(0.05, 1) - 1.959_963_984_540_054).abs() < 1e-9);
        // Two-sided p = 1.005e-8 at 1e6 tests: z ≈ 5.73; check by the defining identity.
        let z = z_test_threshold(0.01, 1_000_000);
        assert!(z > 5.6 && z < 5.9, "{z}");
        assert!((normal_sf(z) / sidak_alpha(0.01, 1_000_000) - 1.0).abs() < 1e-9);
    }

    #[test]
    fn chi2_test_pools_and_detects_impossible() {
        let r = chi2_test(&[10.0, 12.0, 1.0, 0.0], &[11.0, 11.0, 0.5, 0.5], 5.0);
        assert_eq!(r.pooled_cells, 2);
        assert_eq!(r.impossible_samples, 0.0);
        let r = chi2_test(&[10.0, 12.0, 1.0], &[11.0, 11.0, 0.0], 5.0);
        assert_eq!(r.impossible_samples, 1.0);
        assert_eq!(r.p_value, 0.0);
        assert!(!r.passes(0.01));
        let r = chi2_test(&[], &[], 5.0);
        assert_eq!(r.dof, 0);
        assert_eq!(r.p_value, 1.0);
    }

    #[test]
    fn cosine_sampler_passes_hemisphere_and_sphere_tests() {
        let alpha = sidak_alpha(ALPHA, N_PASSING_TESTS);
        let pdf = |w: Vec3| if w.z > 0.0 { w.z as f64 / std::f64::consts::PI } else { 0.0 };
        let r = hemisphere_chi2(cosine_sample, pdf, 64, 32, 1_000_000, 1);
        assert!(r.passes(alpha), "{r:?}");
        let r = sphere_chi2(cosine_sample, pdf, 64, 32, 1_000_000, 2);
        assert!(r.passes(alpha), "{r:?}");
        // Uniform sphere sampler against 1/(4π).
        let uni = |rng: &mut Rng| {
            let z = 1.0 - 2.0 * rng.next_f32();
            let s = (1.0 - z * z).max(0.0).sqrt();
            let phi = 2.0 * std::f32::consts::PI * rng.next_f32();
            Some(Vec3::new(s * phi.cos(), s * phi.sin(), z))
        };
        let r = sphere_chi2(uni, |_| 0.25 / std::f64::consts::PI, 32, 32, 500_000, 3);
        assert!(r.passes(alpha), "{r:?}");
    }

    #[test]
    fn wrong_pdfs_fail() {
        // Uniform-hemisphere pdf claimed for cosine samples: must be rejected.
        let r = hemisphere_chi2(cosine_sample, |_| 0.5 / std::f64::consts::PI, 64, 32, 1_000_000, 4);
        assert!(!r.passes(1e-6), "{r:?}");
        // A subtly wrong pdf (μ^1.1 normalised) is rejected too.
        let r = hemisphere_chi2(
            cosine_sample,
            |w| 2.1 / (2.0 * std::f64::consts::PI) * (w.z.max(0.0) as f64).powf(1.1),
            64,
            32,
            1_000_000,
            5,
        );
        assert!(!r.passes(1e-6), "{r:?}");
        // Samples below the horizon in a hemisphere test are impossible.
        let down = |rng: &mut Rng| cosine_sample(rng).map(|w| Vec3::new(w.x, w.y, -w.z));
        let r = hemisphere_chi2(down, |w| w.z.max(0.0) as f64 / std::f64::consts::PI, 16, 8, 1000, 6);
        assert!(r.impossible_samples > 0.0 && !r.passes(0.01));
    }
}
