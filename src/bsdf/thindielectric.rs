//! `thindielectric` (Mitsuba 3's `ThinDielectric`): a dielectric slab so thin that it neither
//! displaces nor bends the light: a Dirac reflection (wi = mirror of wo) and a Dirac transmission
//! straight through (wi = −wo), on both sides of the surface. The slab's two parallel interfaces
//! reflect light back and forth; summing the incoherent geometric series of internal
//! reflections with R = F(|cos θ_o|, η) at both interfaces (T = 1 − R) gives
//!
//!   R' = R + T²R(1 + R² + R⁴ + …) = R + T²R/(1 − R²) = 2R/(1 + R),   T' = 1 − R',
//!
//! the formula of Mitsuba's plugin (derived the same way for pbrt-v4's `ThinDielectricBxDF`:
//! Pharr, Jakob & Humphreys, "Physically Based Rendering", 4th ed., ch. 9). F is the unpolarised
//! dielectric Fresnel term ([`fresnel_dielectric`]) with η = η_int/η_ext, evaluated at |cos θ_o|
//! from either side (the slab is symmetric).
//!
//! Sampling (Mitsuba's): reflection with probability R', transmission with T'; the weights are
//! `specular_reflectance` and `specular_transmittance` (R' and T' cancel against the choice).
//!
//! Invariants: every sample is Dirac (`is_delta`, pdf_w = R' or T', `eta` = 1: no net refraction,
//! so no 1/η² factor in either transport mode); `eval` and `pdf_w` are 0 everywhere; with unit
//! reflectance and transmittance the expected weight is exactly R' + T' = 1.

use super::{fresnel_dielectric, BsdfSample, LocalBsdf, Mode};
use crate::math::{Rgb, Vec3};

/// Mitsuba's `thindielectric` in its local frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ThinDielectric {
    /// η = `int_ior / ext_ior` (Mitsuba's default: BK7 in air, 1.5046/1.000277).
    pub eta: f32,
    /// Factor on the reflection, Mitsuba's `specular_reflectance` (default 1).
    pub specular_reflectance: Rgb,
    /// Factor on the transmission, Mitsuba's `specular_transmittance` (default 1).
    pub specular_transmittance: Rgb,
}

impl ThinDielectric {
    /// Mitsuba's parameters (nothing to precompute).
    pub fn new(eta: f32, specular_reflectance: Rgb, specular_transmittance: Rgb) -> Self {
        assert!(eta > 0.0, "thindielectric: η must be positive, got {eta}");
        ThinDielectric { eta, specular_reflectance, specular_transmittance }
    }

    /// The slab's reflectance R' = 2R/(1 + R), R = F(|cos θ|, η), at `cos_theta` on either side;
    /// its transmittance is 1 − R' (Mitsuba's `eval_null_transmission` without the tint).
    #[inline]
    pub fn reflectance(&self, cos_theta: f32) -> f32 {
        let r = fresnel_dielectric(cos_theta.abs(), self.eta);
        r * (2.0 / (1.0 + r))
    }
}

impl LocalBsdf for ThinDielectric {
    fn eval(&self, _: Vec3, _: Vec3, _: Mode) -> Rgb {
        Rgb::ZERO
    }

    fn pdf_w(&self, _: Vec3, _: Vec3, _: Mode) -> f32 {
        0.0
    }

    fn sample(&self, wo: Vec3, u: [f32; 3], _: Mode) -> Option<BsdfSample> {
        let r = self.reflectance(wo.z);
        let t = 1.0 - r;
        // Mitsuba picks reflection at u ≤ R'; `<` differs only at u = R' exactly, and never
        // draws a choice of probability 0 (R' = 0 at η = 1)
        let (wi, weight, pdf_w) = if u[0] < r {
            (Vec3::new(-wo.x, -wo.y, wo.z), self.specular_reflectance, r)
        } else {
            (-wo, self.specular_transmittance, t)
        };
        Some(BsdfSample { wi, weight, pdf_w, is_delta: true, eta: 1.0 })
    }
}

#[cfg(test)]
mod tests {
    use super::super::testing::*;
    use super::super::Mode;
    use super::*;
    use crate::stats::z_test_threshold;

    /// Mitsuba's default η: BK7 (1.5046) in air (1.000277), as its `ior.h` tabulates them.
    const BK7: f32 = 1.5046 / 1.000277;

    /// The cases of `tests/data/bsdf/thindielectric.json` and of the sampled values below.
    fn cases() -> Vec<(&'static str, ThinDielectric)> {
        vec![
            ("bk7", ThinDielectric::new(BK7, Rgb::ONE, Rgb::ONE)),
            ("tinted", ThinDielectric::new(1.33, Rgb::new(0.9, 0.5, 0.2), Rgb::new(0.3, 0.6, 0.8))),
            ("diamond", ThinDielectric::new(2.417, Rgb::ONE, Rgb::ONE)),
        ]
    }

    #[test]
    fn fresnel_choice_frequencies() {
        // binomial z-tests of the reflection count against R', Šidák over the 12 tests here
        let angles = [0.0f32, 40.0, 75.0, 89.0, 110.0, 160.0];
        let etas = [BK7, 2.417];
        let zcrit = z_test_threshold(0.01, angles.len() * etas.len());
        let n = 200_000usize;
        let mut seed = 40;
        for eta in etas {
            let b = ThinDielectric::new(eta, Rgb::ONE, Rgb::ONE);
            for theta in angles {
                let wo = dir(theta, 25.0);
                let r = b.reflectance(wo.z) as f64;
                seed += 1;
                let mut g = rng(seed);
                let mut n_refl = 0usize;
                for _ in 0..n {
                    let s = b.sample(wo, u3(&mut g), Mode::Radiance).unwrap();
                    assert!(s.is_delta && s.eta == 1.0 && s.weight == Rgb::ONE);
                    if s.wi == Vec3::new(-wo.x, -wo.y, wo.z) {
                        n_refl += 1;
                        assert_eq!(s.pdf_w as f64, r);
                    } else {
                        assert_eq!(s.wi, -wo);
                        assert_eq!(s.pdf_w, 1.0 - r as f32);
                    }
                }
                let z = (n_refl as f64 - n as f64 * r) / (n as f64 * r * (1.0 - r)).sqrt();
                assert!(
                    z.abs() < zcrit,
                    "η {eta} θ {theta}: reflected {n_refl}/{n}, R' = {r}, z = {z:.2} (limit {zcrit:.2})"
                );
            }
        }
    }

    #[test]
    fn slab_reflectance_sums_the_internal_reflections() {
        // R' = R + T²R/(1 − R²) (the geometric series), symmetric in the side, 1 at grazing
        let b = ThinDielectric::new(1.5, Rgb::ONE, Rgb::ONE);
        for theta in [0.0f32, 30.0, 60.0, 85.0] {
            let c = theta.to_radians().cos();
            let r = fresnel_dielectric(c, 1.5);
            let t = 1.0 - r;
            assert!((b.reflectance(c) - (r + t * t * r / (1.0 - r * r))).abs() < 1e-6);
            assert_eq!(b.reflectance(c), b.reflectance(-c));
        }
        assert_eq!(b.reflectance(0.0), 1.0);
        // index-matched: no reflection, and u = 0 still transmits
        let m = ThinDielectric::new(1.0, Rgb::ONE, Rgb::ONE);
        assert_eq!(m.reflectance(0.7), 0.0);
        assert_eq!(m.sample(dir(30.0, 0.0), [0.0; 3], Mode::Radiance).unwrap().wi, -dir(30.0, 0.0));
    }

    #[test]
    fn weights_and_white_furnace() {
        for (name, b) in cases() {
            for theta in [0.0, 50.0, 89.0, 130.0] {
                assert_weights(
                    &format!("thindielectric {name} θ={theta}"),
                    &b,
                    dir(theta, 10.0),
                    Mode::Radiance,
                    2_000,
                    1e-6,
                );
            }
        }
        // unit reflectance and transmittance: every weight is 1, so the albedo R' + T' is 1 exactly
        let white = ThinDielectric::new(BK7, Rgb::ONE, Rgb::ONE);
        for theta in [0.0, 45.0, 80.0, 135.0] {
            assert_eq!(albedo(&white, dir(theta, 0.0), 100_000), Rgb::ONE);
        }
    }

    #[test]
    fn agrees_with_mitsuba() {
        // eval and pdf: Mitsuba's are 0 on its whole grid (all Dirac), ours too; exact
        let mut rows = 0;
        for (name, b) in cases() {
            rows += assert_mitsuba("thindielectric", name, &b, Mode::Radiance, 0.0, 0.0);
        }
        assert_eq!(rows, 3 * 350);
        // sampling: Mitsuba 3.9.1 (scalar_rgb) `bsdf.sample(ctx, si, sample1, [0.5, 0.5])` with
        // si.wi = `direction(θ, 30°)` of scripts/mitsuba-bsdf-tables.py, for the cases above (η
        // from the same int_ior/ext_ior), produced by /work/mitsuba-venv/bin/python:
        // (case, θ, sample1) → (Mitsuba's wo = our wi, pdf, weight r, g, b). sample1 = 0 picks the
        // reflection, 0.999 the transmission unless R' > 0.999. 1e-6 relative: our Fresnel term
        // is arranged differently from Mitsuba's (a few f32 ulps).
        let want: [(&str, f32, f32, [f32; 7]); 30] = [
            ("bk7", 0.0, 0.0, [-0.0, -0.0, 1.0, 0.077914335, 1.0, 1.0, 1.0]),
            ("bk7", 0.0, 0.999, [-0.0, -0.0, -1.0, 0.92208564, 1.0, 1.0, 1.0]),
            ("bk7", 40.0, 0.0, [-0.5566704, -0.32139382, 0.76604444, 0.08850156, 1.0, 1.0, 1.0]),
            ("bk7", 40.0, 0.999, [-0.5566704, -0.32139382, -0.76604444, 0.9114984, 1.0, 1.0, 1.0]),
            ("bk7", 80.0, 0.0, [-0.85286856, -0.49240386, 0.17364818, 0.55949634, 1.0, 1.0, 1.0]),
            ("bk7", 80.0, 0.999, [-0.85286856, -0.49240386, -0.17364818, 0.44050366, 1.0, 1.0, 1.0]),
            ("bk7", 140.0, 0.0, [-0.5566704, -0.32139382, -0.76604444, 0.08850156, 1.0, 1.0, 1.0]),
            ("bk7", 140.0, 0.999, [-0.5566704, -0.32139382, 0.76604444, 0.9114984, 1.0, 1.0, 1.0]),
            ("bk7", 100.0, 0.0, [-0.85286856, -0.49240386, -0.17364818, 0.55949634, 1.0, 1.0, 1.0]),
            ("bk7", 100.0, 0.999, [-0.85286856, -0.49240386, 0.17364818, 0.44050366, 1.0, 1.0, 1.0]),
            ("tinted", 0.0, 0.0, [-0.0, -0.0, 1.0, 0.039329708, 0.9, 0.5, 0.2]),
            ("tinted", 0.0, 0.999, [-0.0, -0.0, -1.0, 0.9606703, 0.3, 0.6, 0.8]),
            ("tinted", 40.0, 0.0, [-0.5566704, -0.32139382, 0.76604444, 0.047164816, 0.9, 0.5, 0.2]),
            ("tinted", 40.0, 0.999, [-0.5566704, -0.32139382, -0.76604444, 0.9528352, 0.3, 0.6, 0.8]),
            ("tinted", 80.0, 0.0, [-0.85286856, -0.49240386, 0.17364818, 0.5151265, 0.9, 0.5, 0.2]),
            ("tinted", 80.0, 0.999, [-0.85286856, -0.49240386, -0.17364818, 0.48487347, 0.3, 0.6, 0.8]),
            ("tinted", 140.0, 0.0, [-0.5566704, -0.32139382, -0.76604444, 0.047164816, 0.9, 0.5, 0.2]),
            ("tinted", 140.0, 0.999, [-0.5566704, -0.32139382, 0.76604444, 0.9528352, 0.3, 0.6, 0.8]),
            ("tinted", 100.0, 0.0, [-0.85286856, -0.49240386, -0.17364818, 0.5151265, 0.9, 0.5, 0.2]),
            ("tinted", 100.0, 0.999, [-0.85286856, -0.49240386, 0.17364818, 0.48487347, 0.3, 0.6, 0.8]),
            ("diamond", 0.0, 0.0, [-0.0, -0.0, 1.0, 0.29347003, 1.0, 1.0, 1.0]),
            ("diamond", 0.0, 0.999, [-0.0, -0.0, -1.0, 0.70653, 1.0, 1.0, 1.0]),
            ("diamond", 40.0, 0.0, [-0.5566704, -0.32139382, 0.76604444, 0.30115256, 1.0, 1.0, 1.0]),
            ("diamond", 40.0, 0.999, [-0.5566704, -0.32139382, -0.76604444, 0.6988474, 1.0, 1.0, 1.0]),
            ("diamond", 80.0, 0.0, [-0.85286856, -0.49240386, 0.17364818, 0.604633, 1.0, 1.0, 1.0]),
            ("diamond", 80.0, 0.999, [-0.85286856, -0.49240386, -0.17364818, 0.39536703, 1.0, 1.0, 1.0]),
            ("diamond", 140.0, 0.0, [-0.5566704, -0.32139382, -0.76604444, 0.30115256, 1.0, 1.0, 1.0]),
            ("diamond", 140.0, 0.999, [-0.5566704, -0.32139382, 0.76604444, 0.6988474, 1.0, 1.0, 1.0]),
            ("diamond", 100.0, 0.0, [-0.85286856, -0.49240386, -0.17364818, 0.604633, 1.0, 1.0, 1.0]),
            ("diamond", 100.0, 0.999, [-0.85286856, -0.49240386, 0.17364818, 0.39536703, 1.0, 1.0, 1.0]),
        ];
        for (case, theta, s1, w) in want {
            let b = cases().into_iter().find(|c| c.0 == case).unwrap().1;
            let s = b.sample(dir(theta, 30.0), [s1, 0.5, 0.5], Mode::Radiance).unwrap();
            assert!(s.is_delta && s.eta == 1.0);
            let got = [s.wi.x, s.wi.y, s.wi.z, s.pdf_w, s.weight.x, s.weight.y, s.weight.z];
            for k in 0..7 {
                assert!(
                    (got[k] - w[k]).abs() <= 1e-6 * w[k].abs() + 1e-7,
                    "{case} θ {theta} u {s1}: {got:?} vs Mitsuba {w:?}"
                );
            }
        }
    }
}
