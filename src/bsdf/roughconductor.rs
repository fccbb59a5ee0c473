//! `roughconductor` (Mitsuba 3's plugin): reflection off a rough metal, the microfacet model of
//! Walter et al. 2007 ("Microfacet Models for Refraction through Rough Surfaces") with a Beckmann
//! or GGX distribution ([`MicrofacetDistribution`]) and the conductor Fresnel term of the complex
//! index η + ik:
//!
//!   f(wo, wi) = F(wo·h) · D(h) · G(wo, wi, h) / (4 cos θ_o cos θ_i) · specular_reflectance,
//!   h = (wo + wi)/|wo + wi|.
//!
//! Sampling draws a microfacet normal m (the visible normals of Heitz & d'Eon 2014 / Heitz 2018
//! when `sample_visible`, Mitsuba's default, else D·cos θ_m) and mirrors `wo` about it:
//! pdf_w(wi) = pdf_m(m) / (4 wi·m), and the weight is F·G1(wi, m) (visible normals) or
//! F·G·(wo·m)/(cos θ_o cos θ_m).
//!
//! Invariants: one-sided, black unless `wo.z > 0` and `wi.z > 0`; `pdf_w` is 0 wherever a
//! sample cannot land (wo·h ≤ 0 or wi·h ≤ 0, as Mitsuba's `pdf`); `weight = eval·cos θ_i/pdf_w`;
//! `eta` of a sample is 1 (no refraction); the F is [`fresnel_conductor`]'s (η = 0, k = 1 gives
//! F = 1, Mitsuba's `material = "none"`).

use super::microfacet::MicrofacetDistribution;
use super::{fresnel_conductor, BsdfSample, LocalBsdf, Mode};
use crate::math::{reflect, Rgb, Vec3};

/// Mitsuba 3's `roughconductor` in the local shading frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoughConductor {
    /// The microfacet normals (Mitsuba's `distribution`, `alpha`/`alpha_u`/`alpha_v`,
    /// `sample_visible`).
    pub distribution: MicrofacetDistribution,
    /// Real part of the relative index of refraction (Mitsuba's `eta`).
    pub eta: Rgb,
    /// Imaginary part, the absorption coefficient (Mitsuba's `k`).
    pub k: Rgb,
    /// Scale on the reflection (Mitsuba's `specular_reflectance`, 1 when absent).
    pub specular_reflectance: Rgb,
}

impl LocalBsdf for RoughConductor {
    fn eval(&self, wo: Vec3, wi: Vec3, _: Mode) -> Rgb {
        if !(wo.z > 0.0 && wi.z > 0.0) {
            return Rgb::ZERO;
        }
        let d = &self.distribution;
        let h = (wo + wi).normalize();
        let dh = d.eval(h);
        if dh == 0.0 {
            return Rgb::ZERO;
        }
        let value = dh * d.g(wo, wi, h) / (4.0 * wo.z * wi.z);
        fresnel_conductor(wo.dot(h), self.eta, self.k) * self.specular_reflectance * value
    }

    fn pdf_w(&self, wo: Vec3, wi: Vec3, _: Mode) -> f32 {
        let h = (wo + wi).normalize();
        if !(wo.z > 0.0 && wi.z > 0.0 && wo.dot(h) > 0.0 && wi.dot(h) > 0.0) {
            return 0.0;
        }
        let d = &self.distribution;
        if d.sample_visible {
            d.eval(h) * d.smith_g1(wo, h) / (4.0 * wo.z)
        } else {
            d.pdf(wo, h) / (4.0 * wi.dot(h))
        }
    }

    fn sample(&self, wo: Vec3, u: [f32; 3], _: Mode) -> Option<BsdfSample> {
        if wo.z <= 0.0 || wo.z.is_nan() {
            return None;
        }
        let d = &self.distribution;
        let (m, pdf_m) = d.sample(wo, [u[1], u[2]]);
        let wi = reflect(wo, m);
        let cos_m = wo.dot(m);
        // a normal facing away from wo (possible without visible sampling) reflects nothing
        if !(pdf_m > 0.0 && wi.z > 0.0 && cos_m > 0.0) {
            return None;
        }
        let g = if d.sample_visible { d.smith_g1(wi, m) } else { d.g(wo, wi, m) * cos_m / (wo.z * m.z) };
        let pdf_w = pdf_m / (4.0 * wi.dot(m));
        let weight = fresnel_conductor(cos_m, self.eta, self.k) * self.specular_reflectance * g;
        (pdf_w.is_finite() && g > 0.0).then_some(BsdfSample { wi, weight, pdf_w, is_delta: false, eta: 1.0 })
    }
}

#[cfg(test)]
mod tests {
    use super::super::microfacet::MicrofacetKind::{self, Beckmann, Ggx};
    use super::super::testing::*;
    use super::*;

    fn conductor(kind: MicrofacetKind, au: f32, av: f32, vis: bool, eta: Rgb, k: Rgb) -> RoughConductor {
        RoughConductor {
            distribution: MicrofacetDistribution::new(kind, au, av, vis),
            eta,
            k,
            specular_reflectance: Rgb::ONE,
        }
    }

    /// Mitsuba's `material = "none"`: F = 1.
    fn mirror(kind: MicrofacetKind, au: f32, av: f32, vis: bool) -> RoughConductor {
        conductor(kind, au, av, vis, Rgb::ZERO, Rgb::ONE)
    }

    const ROUGHNESS: [(f32, f32); 4] = [(0.05, 0.05), (0.2, 0.2), (0.5, 0.5), (0.1, 0.4)];
    const THETA: [f32; 3] = [10.0, 50.0, 80.0];

    /// χ² of `sample` against `pdf_w`: both distributions, four roughnesses (one anisotropic),
    /// three incident angles, both `sample_visible`: 48 tests at the Šidák level of 48.
    #[test]
    fn chi2_sample_matches_pdf() {
        let n_tests = 2 * ROUGHNESS.len() * THETA.len() * 2;
        let mut seed = 100;
        for kind in [Beckmann, Ggx] {
            for vis in [true, false] {
                for (au, av) in ROUGHNESS {
                    for theta in THETA {
                        let b = mirror(kind, au, av, vis);
                        let name = format!("{kind:?} α {au}/{av} vis {vis} θ {theta}");
                        assert_chi2(&name, &b, dir(theta, 30.0), Mode::Radiance, n_tests, seed);
                        seed += 1;
                    }
                }
            }
        }
    }

    #[test]
    fn weights_are_f_cos_over_pdf() {
        let (eta, k) = (Rgb::new(0.2, 0.9, 1.1), Rgb::new(3.9, 2.4, 1.6));
        for kind in [Beckmann, Ggx] {
            for vis in [true, false] {
                for (au, av) in [(0.05, 0.05), (0.3, 0.3), (0.1, 0.4)] {
                    for theta in [10.0, 50.0, 85.0] {
                        let b = conductor(kind, au, av, vis, eta, k);
                        let name = format!("{kind:?} α {au}/{av} vis {vis} θ {theta}");
                        assert_weights(&name, &b, dir(theta, 30.0), Mode::Radiance, 2000, 1e-3);
                    }
                }
            }
        }
    }

    /// White furnace with F = 1: the albedo is at most 1 within 5 standard errors of its
    /// estimate (a passive BSDF; single scattering loses energy at high roughness), and within
    /// 1% of 1 at α = 0.05, where masking hardly loses any. `albedo` agrees with the mean.
    #[test]
    fn furnace() {
        assert_microfacet_furnace(mirror, &[0.0, 45.0, 80.0], |theta| theta < 60.0);
    }

    /// Every case of `tests/data/bsdf/roughconductor.json` against Mitsuba 3.9.1's `eval` and
    /// `pdf` (350 directions each, both hemispheres of `wo`).
    ///
    /// Tolerance: relative 1e-5, absolute 1e-8. Both sides evaluate the same f32 expressions,
    /// differing only in operation order and fused multiply-adds: a few ulp each, 1.6e-6
    /// relative at most on these tables (the Beckmann exponent −tan²θ_h/α², up to ~100 here,
    /// turns an ulp of its argument into ~1e-5 of the value at worst). The absolute floor is
    /// for values near 0 (largest difference 1.6e-10), e.g. where Mitsuba cuts D at
    /// D·cos θ_h ≤ 1e-20 on one side of the threshold and not on the other.
    #[test]
    fn agrees_with_mitsuba() {
        let (rel, abs) = (1e-5, 1e-8);
        // Mitsuba 3.9.1's `Au` in `scalar_rgb` (read with `mi.traverse`): the same as the
        // checked digits of `scene::mitsuba::presets`' test
        let (au_eta, au_k) =
            (Rgb::new(0.143_035_98, 0.375_307_08, 1.442_045_3), Rgb::new(3.982_997, 2.385_556_5, 1.603_359_2));
        let (eta, k) = (Rgb::new(0.2, 0.9, 1.1), Rgb::new(3.9, 2.4, 1.6));
        let tinted = |kind, au, av, vis| RoughConductor {
            specular_reflectance: Rgb::new(0.9, 0.6, 0.3),
            ..conductor(kind, au, av, vis, eta, k)
        };
        let cases: [(&str, RoughConductor); 8] = [
            ("beckmann_0.2", conductor(Beckmann, 0.2, 0.2, true, eta, k)),
            ("ggx_0.3_au", conductor(Ggx, 0.3, 0.3, true, au_eta, au_k)),
            ("beckmann_0.5_au_novis", conductor(Beckmann, 0.5, 0.5, false, au_eta, au_k)),
            ("ggx_0.05", conductor(Ggx, 0.05, 0.05, true, eta, k)),
            ("ggx_aniso_0.1_0.4_novis", conductor(Ggx, 0.1, 0.4, false, eta, k)),
            ("beckmann_aniso_0.3_0.08", tinted(Beckmann, 0.3, 0.08, true)),
            ("ggx_0.7_none", mirror(Ggx, 0.7, 0.7, true)),
            ("beckmann_0_clamped", mirror(Beckmann, 0.0, 0.0, true)),
        ];
        let mut rows = 0;
        for (name, b) in &cases {
            rows += assert_mitsuba("roughconductor", name, b, Mode::Radiance, rel, abs);
        }
        assert_eq!(rows, 350 * cases.len());
    }
}
