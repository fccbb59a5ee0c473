//! The noise-consistency check and the Mitsuba agreement rule of `scripts/check-mitsuba.sh`.
//!
//! Variances are variances **of the pixel mean**. The reference variance per pixel is estimated
//! from two independent half renders as `(h0 − h1)² / 4`. [`noise_consistency`] compares
//! `mean((I − R)²)` with `mean(σ_I² + σ_R²)`: their ratio is ≈ 1 when the test and the reference
//! differ only by noise, within a tolerance derived from its own standard error
//! ([`NoiseReport::ratio_tolerance`]). [`mitsuba_agreement`] also bounds the per-channel means.

use super::{box_filter, check_same, half_variance, rel_diff, z_scores, MetricsError};
use crate::image_io::Image;
use std::fmt;

/// Fraction of `|z| > 3` expected for pure Gaussian noise (two-sided).
pub const GAUSSIAN_FRAC_Z3: f64 = 0.0027;

/// Radius of the box filter used to smooth per-pixel variances for z-scores (2 → 5×5).
pub const Z_SMOOTH_RADIUS: usize = 2;

/// Maximum relative difference of per-channel image means accepted by [`mitsuba_agreement`].
pub const MEAN_REL_TOLERANCE: f64 = 0.005;

/// Result of [`noise_consistency`].
#[derive(Clone, Debug, PartialEq)]
pub struct NoiseReport {
    /// Number of pixels compared.
    pub pixels: usize,
    /// Whether a test variance was supplied (without one `ratio` uses `σ_I² = 0` and is not
    /// meaningful as a noise check).
    pub test_var_available: bool,
    /// Mean over pixels and channels of `(I − R)²`.
    pub mean_sq_diff: f64,
    /// Mean over pixels and channels of the test's variance of the mean, `σ_I²`.
    pub mean_var_test: f64,
    /// Mean over pixels and channels of the reference's variance of the mean, `(h0 − h1)²/4`.
    pub mean_var_ref: f64,
    /// `mean_sq_diff / (mean_var_test + mean_var_ref)`; ≈ 1 when the difference is pure noise.
    pub ratio: f64,
    /// Effective number of independent terms, `(Σ s_p)² / Σ s_p²` with `s_p` the per-pixel
    /// (channel-summed) raw variance estimate; channels are treated as fully correlated.
    pub n_eff: f64,
    /// Standard error of `ratio` under pure noise: `sqrt(2 Σ s_p² + 2 Σ r_p²) / Σ s_p`, where the
    /// first term is the χ² spread of the numerator and the second that of the half-based
    /// reference variance estimate `r_p` (itself χ² with one degree of freedom).
    pub ratio_sigma: f64,
    /// Accepted `|ratio − 1|`: `max(5 · ratio_sigma, 0.03)`.
    pub ratio_tolerance: f64,
    /// Fraction of pixel-channels with `|z| > 3`, z using 5×5 box-smoothed variances.
    pub frac_z_above_3: f64,
    /// Largest finite `|z|` (smoothed variances).
    pub max_abs_z: f64,
}

impl NoiseReport {
    /// `true` if there is a noise estimate ([`Self::has_estimate`]) and `|ratio − 1| <= ratio_tolerance`.
    pub fn ratio_ok(&self) -> bool {
        self.has_estimate() && (self.ratio - 1.0).abs() <= self.ratio_tolerance
    }

    /// False when there is nothing to compare the ratio with: no variance channels, or halves
    /// and variances that give no noise at all (identical halves, zero variance: n_eff = 0).
    pub fn has_estimate(&self) -> bool {
        self.test_var_available && self.ratio.is_finite() && self.ratio_tolerance.is_finite()
    }
}

/// Checks whether `test` differs from `reference` only by noise. `ref_half0`/`ref_half1` are
/// the two independent halves of the reference (their average is `reference`);
/// `test_var_of_mean` is the test's per-pixel variance of the mean, if known.
pub fn noise_consistency(
    test: &Image,
    reference: &Image,
    ref_half0: &Image,
    ref_half1: &Image,
    test_var_of_mean: Option<&Image>,
) -> Result<NoiseReport, MetricsError> {
    check_same(test, reference, "noise_consistency (test vs reference)")?;
    let var_ref = half_variance(ref_half0, ref_half1)?;
    check_same(test, &var_ref, "noise_consistency (test vs reference halves)")?;
    let var_test = match test_var_of_mean {
        Some(v) => {
            check_same(test, v, "noise_consistency (test vs test variance)")?;
            v.clone()
        }
        None => Image::new(test.width, test.height),
    };
    let n = test.pixels.len();
    let (mut sd, mut svt, mut svr) = (0.0f64, 0.0f64, 0.0f64);
    let (mut s_sq, mut r_sq) = (0.0f64, 0.0f64);
    for i in 0..n {
        let (mut sp, mut rp) = (0.0, 0.0);
        for c in 0..3 {
            let d = test.pixels[i][c] as f64 - reference.pixels[i][c] as f64;
            let (vt, vr) = (var_test.pixels[i][c] as f64, var_ref.pixels[i][c] as f64);
            sd += d * d;
            svt += vt;
            svr += vr;
            sp += vt + vr;
            rp += vr;
        }
        s_sq += sp * sp;
        r_sq += rp * rp;
    }
    let s_tot = svt + svr;
    let ratio = if s_tot > 0.0 {
        sd / s_tot
    } else if sd == 0.0 {
        1.0
    } else {
        f64::INFINITY
    };
    let n_eff = if s_sq > 0.0 { s_tot * s_tot / s_sq } else { 0.0 };
    let ratio_sigma = if s_tot > 0.0 { (2.0 * s_sq + 2.0 * r_sq).sqrt() / s_tot } else { f64::INFINITY };

    let z = z_scores(test, &box_filter(&var_test, Z_SMOOTH_RADIUS), reference, &box_filter(&var_ref, Z_SMOOTH_RADIUS))?;
    let (mut above, mut max_abs_z) = (0usize, 0.0f64);
    for p in &z.pixels {
        for &v in p {
            let a = (v as f64).abs();
            if a > 3.0 {
                above += 1;
            }
            if a.is_finite() {
                max_abs_z = max_abs_z.max(a);
            }
        }
    }
    let m = (3 * n) as f64;
    Ok(NoiseReport {
        pixels: n,
        test_var_available: test_var_of_mean.is_some(),
        mean_sq_diff: sd / m,
        mean_var_test: svt / m,
        mean_var_ref: svr / m,
        ratio,
        n_eff,
        ratio_sigma,
        ratio_tolerance: (5.0 * ratio_sigma).max(0.03),
        frac_z_above_3: above as f64 / m,
        max_abs_z,
    })
}

impl fmt::Display for NoiseReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "noise: pixels {}  test variance {}",
            self.pixels,
            if self.test_var_available { "yes" } else { "MISSING" }
        )?;
        writeln!(
            f,
            "noise: mean (I-R)^2 {:.4e} = ratio {:.4} x (var_I {:.4e} + var_R {:.4e})",
            self.mean_sq_diff, self.ratio, self.mean_var_test, self.mean_var_ref
        )?;
        writeln!(
            f,
            "noise: ratio {:.4} (expect 1 +- {:.4}, tolerance {:.4}, n_eff {:.0})",
            self.ratio, self.ratio_sigma, self.ratio_tolerance, self.n_eff
        )?;
        write!(
            f,
            "noise: |z|>3 in {:.3}% of pixel-channels (Gaussian {:.2}%), max |z| {:.2}",
            100.0 * self.frac_z_above_3,
            100.0 * GAUSSIAN_FRAC_Z3,
            self.max_abs_z
        )
    }
}

/// Result of [`mitsuba_agreement`].
#[derive(Clone, Debug, PartialEq)]
pub struct AgreementReport {
    /// Per-channel means of the test image.
    pub mean_test: [f64; 3],
    /// Per-channel means of the reference.
    pub mean_ref: [f64; 3],
    /// Per-channel `(mean_test − mean_ref) / mean_ref`.
    pub mean_rel_diff: [f64; 3],
    /// The noise-consistency statistics.
    pub noise: NoiseReport,
    /// Copy of `noise.ratio`.
    pub ratio: f64,
    /// `true` if every check passed.
    pub passed: bool,
    /// One line per failed check (empty when `passed`).
    pub failures: Vec<String>,
}

/// The Mitsuba agreement rule: passes iff every `|mean_rel_diff| <` [`MEAN_REL_TOLERANCE`]
/// (0.5 %) and the test variance is present and `|ratio − 1| <= noise.ratio_tolerance`.
/// The `|z| > 3` fraction is reported but not judged (edges and fireflies make it non-Gaussian).
pub fn mitsuba_agreement(
    test: &Image,
    test_var: Option<&Image>,
    reference: &Image,
    half0: &Image,
    half1: &Image,
) -> Result<AgreementReport, MetricsError> {
    let noise = noise_consistency(test, reference, half0, half1, test_var)?;
    let (mean_test, mean_ref) = (test.mean(), reference.mean());
    let mean_rel_diff: [f64; 3] = std::array::from_fn(|c| rel_diff(mean_test[c], mean_ref[c]));
    let mut failures = Vec::new();
    for (c, name) in ["R", "G", "B"].iter().enumerate() {
        let d = mean_rel_diff[c];
        if d.is_nan() || d.abs() >= MEAN_REL_TOLERANCE {
            failures.push(format!(
                "mean {name}: test {:.6} vs reference {:.6} ({:+.3}%, limit {:.1}%)",
                mean_test[c],
                mean_ref[c],
                100.0 * d,
                100.0 * MEAN_REL_TOLERANCE
            ));
        }
    }
    if !noise.test_var_available {
        failures.push("noise: test image has no variance channels (var.R, var.G, var.B); cannot check noise".into());
    } else if !noise.has_estimate() {
        failures.push(format!(
            "noise: no noise estimate (ratio {}, n_eff {:.0}): the reference's halves are identical or the variances zero",
            noise.ratio, noise.n_eff
        ));
    } else if !noise.ratio_ok() {
        failures.push(format!(
            "noise: ratio {:.4} differs from 1 by more than {:.4} (5 sigma, sigma {:.4})",
            noise.ratio, noise.ratio_tolerance, noise.ratio_sigma
        ));
    }
    Ok(AgreementReport {
        mean_test,
        mean_ref,
        mean_rel_diff,
        ratio: noise.ratio,
        noise,
        passed: failures.is_empty(),
        failures,
    })
}

impl fmt::Display for AgreementReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (c, name) in ["R", "G", "B"].iter().enumerate() {
            writeln!(
                f,
                "mean {name}: test {:.6} ref {:.6} diff {:+.4}%",
                self.mean_test[c],
                self.mean_ref[c],
                100.0 * self.mean_rel_diff[c]
            )?;
        }
        writeln!(f, "{}", self.noise)?;
        for line in &self.failures {
            writeln!(f, "FAIL {line}")?;
        }
        write!(f, "agreement: {}", if self.passed { "PASS" } else { "FAIL" })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// xorshift64* + Box–Muller: deterministic standard normals without a rand dependency.
    struct Gauss(u64);
    impl Gauss {
        fn uniform(&mut self) -> f64 {
            self.0 ^= self.0 >> 12;
            self.0 ^= self.0 << 25;
            self.0 ^= self.0 >> 27;
            ((self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 + 0.5) / (1u64 << 53) as f64
        }
        fn normal(&mut self) -> f64 {
            let (u, v) = (self.uniform(), self.uniform());
            (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
        }
    }

    /// A synthetic "render": truth with spatially varying noise; returns
    /// (test, test_var, reference, half0, half1).
    fn synthetic(bias: f64, noise_scale: f64) -> (Image, Image, Image, Image, Image) {
        let (w, h) = (96, 80);
        let mut g = Gauss(0x9E37_79B9_7F4A_7C15);
        let truth = Image::from_fn(w, h, |x, y| [0.1 + 0.01 * x as f32, 0.5, 0.2 + 0.005 * y as f32]);
        let vt = Image::from_fn(w, h, |x, y| [1e-4 * (1 + x % 7) as f32, 4e-4, 2e-4 * (1 + y % 3) as f32]);
        let vr = Image::from_fn(w, h, |x, _| [2e-5 * (1 + x % 5) as f32, 1e-5, 3e-5]);
        let mut add = |base: &Image, var: &Image, k: f64, off: f64| {
            Image::from_fn(w, h, |x, y| {
                let (b, v) = (base.get(x, y), var.get(x, y));
                std::array::from_fn(|c| (b[c] as f64 * (1.0 + off) + g.normal() * (k * v[c] as f64).sqrt()) as f32)
            })
        };
        let test = add(&truth, &vt, noise_scale * noise_scale, bias);
        let h0 = add(&truth, &vr, 2.0, 0.0);
        let h1 = add(&truth, &vr, 2.0, 0.0);
        let reference = Image::from_fn(w, h, |x, y| {
            let (a, b) = (h0.get(x, y), h1.get(x, y));
            std::array::from_fn(|c| 0.5 * (a[c] + b[c]))
        });
        (test, vt, reference, h0, h1)
    }

    #[test]
    fn pure_noise_passes() {
        let (t, vt, r, h0, h1) = synthetic(0.0, 1.0);
        let rep = mitsuba_agreement(&t, Some(&vt), &r, &h0, &h1).unwrap();
        assert!(rep.passed, "{rep}");
        assert!((rep.ratio - 1.0).abs() < 3.0 * rep.noise.ratio_sigma, "{rep}");
        // sigma ~ sqrt(2/N_eff) with N_eff of order the pixel count
        assert!(rep.noise.ratio_sigma > 0.005 && rep.noise.ratio_sigma < 0.05, "{rep}");
        assert!(rep.noise.frac_z_above_3 < 0.01, "{rep}");
        assert!(rep.to_string().ends_with("PASS"));
    }

    #[test]
    fn bias_or_wrong_noise_fails() {
        let (t, vt, r, h0, h1) = synthetic(0.01, 1.0); // 1 % brighter
        let rep = mitsuba_agreement(&t, Some(&vt), &r, &h0, &h1).unwrap();
        assert!(!rep.passed);
        assert!(rep.failures.iter().any(|f| f.starts_with("mean")), "{rep}");
        let (t, vt, r, h0, h1) = synthetic(0.0, 1.5); // noise 1.5x larger than its variance claims
        let rep = mitsuba_agreement(&t, Some(&vt), &r, &h0, &h1).unwrap();
        assert!(!rep.passed && rep.ratio > 1.5, "{rep}");
        assert!(rep.failures.iter().all(|f| f.starts_with("noise")), "{rep}");
        let (t, _, r, h0, h1) = synthetic(0.0, 1.0);
        let rep = mitsuba_agreement(&t, None, &r, &h0, &h1).unwrap();
        assert!(!rep.passed && !rep.noise.test_var_available);
        assert!(mitsuba_agreement(&t, None, &r, &h0, &Image::new(3, 3)).is_err());
    }
}
