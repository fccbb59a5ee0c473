//! Microfacet normal distributions, Beckmann and GGX (Trowbridge–Reitz), isotropic or
//! anisotropic: Mitsuba 3's `MicrofacetDistribution` (`include/mitsuba/render/microfacet.h`),
//! the building block of `roughconductor`, `roughdielectric` and `roughplastic`.
//!
//! - [`MicrofacetDistribution::eval`]: D(m) (Walter et al. 2007, "Microfacet Models for
//!   Refraction through Rough Surfaces", eqs. 25 and 33, with anisotropic α_u, α_v).
//! - [`MicrofacetDistribution::smith_g1`], [`MicrofacetDistribution::g`]: Smith's masking
//!   G1(v, m) (Beckmann: Walter's rational approximation, < 0.35% error; GGX: exact) and the
//!   separable G = G1(wo, m)·G1(wi, m).
//! - [`MicrofacetDistribution::sample`], [`MicrofacetDistribution::pdf`]: a microfacet normal m
//!   and its solid-angle density (of m, not of the reflected or refracted direction). With
//!   `sample_visible` the distribution of visible normals D_wo(m) = G1(wo, m)·|wo·m|·D(m)/cos θ_o
//!   (Heitz & d'Eon 2014, "Importance Sampling Microfacet-Based BSDFs using the Distribution of
//!   Visible Normals"; Beckmann by Jakob's numerical inversion, GGX by Heitz 2018, "Sampling the
//!   GGX Distribution of Visible Normals"), else D(m)·cos θ_m (Walter 2007).
//!
//! Plus Mitsuba's `fresnel` (F with cos θ_t, η_it, η_ti, the F from [`super::fresnel_dielectric`])
//! and `refract` about a microfacet normal, as the rough dielectric BSDFs need them.
//!
//! Invariants: α_u, α_v ≥ 1e-4 ([`MicrofacetDistribution::new`] clamps, as Mitsuba's
//! `configure`); D(m) = 0 for cos θ_m ≤ 0 and wherever D·cos θ_m ≤ 1e-20; G1(v, m) = 0 unless
//! v·m and cos θ_v have the same sign; `pdf(wo, m)` is the density of `sample(wo, ·)` drawing m,
//! for `wo` in the upper hemisphere (callers flip it there, as Mitsuba's `mulsign`).

use crate::math::{Vec2, Vec3, PI};
use crate::sampling::warp::sample_concentric_disk;

/// The normal distribution function (Mitsuba's `MicrofacetType`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MicrofacetKind {
    /// Beckmann: Gaussian random surfaces (Mitsuba's default).
    Beckmann,
    /// GGX / Trowbridge–Reitz: long tails.
    Ggx,
}

/// A Beckmann or GGX distribution of microfacet normals in the local frame (z = macro normal,
/// α_u along x, α_v along y).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MicrofacetDistribution {
    /// Beckmann or GGX.
    pub kind: MicrofacetKind,
    /// Roughness along the tangent x (≥ 1e-4 when built by [`Self::new`]).
    pub alpha_u: f32,
    /// Roughness along the bitangent y (≥ 1e-4 when built by [`Self::new`]).
    pub alpha_v: f32,
    /// Sample the visible normals (Mitsuba's `sample_visible`, default true) rather than D·cos.
    pub sample_visible: bool,
}

impl MicrofacetDistribution {
    /// A distribution with α clamped to at least 1e-4 (Mitsuba's `configure`).
    pub fn new(kind: MicrofacetKind, alpha_u: f32, alpha_v: f32, sample_visible: bool) -> Self {
        MicrofacetDistribution { kind, alpha_u: alpha_u.max(1e-4), alpha_v: alpha_v.max(1e-4), sample_visible }
    }

    /// An isotropic distribution (α_u = α_v = `alpha`, clamped as [`Self::new`]).
    pub fn isotropic(kind: MicrofacetKind, alpha: f32, sample_visible: bool) -> Self {
        Self::new(kind, alpha, alpha, sample_visible)
    }

    /// α_u = α_v.
    #[inline]
    pub fn is_isotropic(&self) -> bool {
        self.alpha_u == self.alpha_v
    }

    /// The same distribution with both roughnesses times `s` (Mitsuba's `scale_alpha`, no clamp).
    #[inline]
    pub fn scaled(&self, s: f32) -> Self {
        MicrofacetDistribution { alpha_u: self.alpha_u * s, alpha_v: self.alpha_v * s, ..*self }
    }

    /// D(m): microfacet normals per unit projected area and solid angle of m.
    #[inline]
    pub fn eval(&self, m: Vec3) -> f32 {
        let (au, av) = (self.alpha_u, self.alpha_v);
        let cos2 = m.z * m.z;
        let r = match self.kind {
            MicrofacetKind::Beckmann => {
                let e = (m.x / au).powi(2) + (m.y / av).powi(2);
                (-e / cos2).exp() / (PI * au * av * cos2 * cos2)
            }
            MicrofacetKind::Ggx => {
                let t = (m.x / au).powi(2) + (m.y / av).powi(2) + cos2;
                1.0 / (PI * au * av * t * t)
            }
        };
        // Mitsuba's guard against numerical trouble downstream (and the lower hemisphere)
        if r * m.z > 1e-20 {
            r
        } else {
            0.0
        }
    }

    /// Solid-angle density of [`Self::sample`] drawing `m` given `wo` (upper hemisphere).
    #[inline]
    pub fn pdf(&self, wo: Vec3, m: Vec3) -> f32 {
        let d = self.eval(m);
        if self.sample_visible {
            d * self.smith_g1(wo, m) * wo.dot(m).abs() / wo.z
        } else {
            d * m.z
        }
    }

    /// Smith's masking G1(v, m) for one direction.
    #[inline]
    pub fn smith_g1(&self, v: Vec3, m: Vec3) -> f32 {
        let xy_alpha_2 = (self.alpha_u * v.x).powi(2) + (self.alpha_v * v.y).powi(2);
        let tan_theta_alpha_2 = xy_alpha_2 / (v.z * v.z);
        let mut r = match self.kind {
            MicrofacetKind::Beckmann => {
                let a = 1.0 / tan_theta_alpha_2.sqrt();
                if a >= 1.6 {
                    1.0
                } else {
                    // Walter's rational approximation (< 0.35% relative error)
                    let a2 = a * a;
                    (3.535 * a + 2.181 * a2) / (1.0 + 2.276 * a + 2.577 * a2)
                }
            }
            MicrofacetKind::Ggx => 2.0 / (1.0 + (1.0 + tan_theta_alpha_2).sqrt()),
        };
        if xy_alpha_2 == 0.0 {
            r = 1.0;
        }
        // the back of a microfacet is never seen from the front and vice versa
        if v.dot(m) * v.z <= 0.0 {
            r = 0.0;
        }
        r
    }

    /// Smith's separable shadowing-masking G1(wo, m)·G1(wi, m).
    #[inline]
    pub fn g(&self, wo: Vec3, wi: Vec3, m: Vec3) -> f32 {
        self.smith_g1(wo, m) * self.smith_g1(wi, m)
    }

    /// Draws a microfacet normal from `u`: `(m, pdf)`, the pdf that of [`Self::pdf`]. `wo` must
    /// lie in the upper hemisphere (it is used only with `sample_visible`).
    pub fn sample(&self, wo: Vec3, u: [f32; 2]) -> (Vec3, f32) {
        let (au, av) = (self.alpha_u, self.alpha_v);
        if !self.sample_visible {
            // azimuth (the same for both distributions), then elevation
            let (sin_phi, cos_phi, alpha_2) = if self.is_isotropic() {
                let (s, c) = (2.0 * PI * u[1]).sin_cos();
                (s, c, au * au)
            } else {
                let tmp = (av / au) * (2.0 * PI * u[1]).tan();
                let cos_phi = (1.0 / (tmp * tmp + 1.0).sqrt()).copysign((u[1] - 0.5).abs() - 0.25);
                let sin_phi = cos_phi * tmp;
                (sin_phi, cos_phi, 1.0 / ((cos_phi / au).powi(2) + (sin_phi / av).powi(2)))
            };
            let (cos_theta, pdf) = match self.kind {
                MicrofacetKind::Beckmann => {
                    let cos_theta = 1.0 / (1.0 - alpha_2 * (1.0 - u[0]).ln()).sqrt();
                    let cos3 = (cos_theta * cos_theta * cos_theta).max(1e-20);
                    (cos_theta, (1.0 - u[0]) / (PI * au * av * cos3))
                }
                MicrofacetKind::Ggx => {
                    let tan_2 = alpha_2 * u[0] / (1.0 - u[0]);
                    let cos_theta = 1.0 / (1.0 + tan_2).sqrt();
                    let temp = 1.0 + tan_2 / alpha_2;
                    let cos3 = (cos_theta * cos_theta * cos_theta).max(1e-20);
                    (cos_theta, 1.0 / (PI * au * av * cos3 * temp * temp))
                }
            };
            let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
            return (Vec3::new(cos_phi * sin_theta, sin_phi * sin_theta, cos_theta), pdf);
        }
        // visible normals: stretch wo to the α = 1 configuration, sample its slopes there,
        // rotate back and unstretch
        let wo_p = Vec3::new(au * wo.x, av * wo.y, wo.z).normalize();
        let (sin_phi, cos_phi) = sincos_phi(wo_p);
        let slope = self.sample_visible_11(wo_p.z, u);
        let slope =
            Vec2::new((cos_phi * slope.x - sin_phi * slope.y) * au, (sin_phi * slope.x + cos_phi * slope.y) * av);
        let m = Vec3::new(-slope.x, -slope.y, 1.0).normalize();
        let pdf = self.eval(m) * self.smith_g1(wo, m) * wo.dot(m).abs() / wo.z;
        (m, pdf)
    }

    /// The slopes of a visible normal of the α = 1 distribution seen at `cos_theta_i`, in the
    /// frame where the incident direction has azimuth 0 (Mitsuba's `sample_visible_11`).
    fn sample_visible_11(&self, cos_theta_i: f32, u: [f32; 2]) -> Vec2 {
        match self.kind {
            MicrofacetKind::Beckmann => {
                // Jakob's numerical inversion in the erf domain (continuous in u, unlike the
                // paper's): a guess exact at θ_i = π/2, then three Newton steps
                let tan_theta_i = (1.0 - cos_theta_i * cos_theta_i).max(0.0).sqrt() / cos_theta_i;
                let cot_theta_i = 1.0 / tan_theta_i;
                let maxval = erf(cot_theta_i);
                let u = [u[0].clamp(1e-6, 1.0 - 1e-6), u[1].clamp(1e-6, 1.0 - 1e-6)];
                let inv_sqrt_pi = std::f32::consts::FRAC_2_SQRT_PI * 0.5;
                let mut x = maxval - (maxval + 1.0) * erf((-u[0].ln()).sqrt());
                let sx = u[0] * (1.0 + maxval + inv_sqrt_pi * tan_theta_i * (-cot_theta_i * cot_theta_i).exp());
                for _ in 0..3 {
                    let slope = erfinv(x);
                    let value = 1.0 + x + inv_sqrt_pi * tan_theta_i * (-slope * slope).exp() - sx;
                    let derivative = 1.0 - slope * tan_theta_i;
                    x -= value / derivative;
                }
                Vec2::new(erfinv(x), erfinv(2.0 * u[1] - 1.0))
            }
            MicrofacetKind::Ggx => {
                // Heitz 2018: a disk point, squeezed onto the visible half, projected to the
                // hemisphere
                let mut p = sample_concentric_disk(u);
                let s = 0.5 * (1.0 + cos_theta_i);
                let h = (1.0 - p.x * p.x).max(0.0).sqrt();
                p.y = h * (1.0 - s) + p.y * s;
                let (x, y) = (p.x, p.y);
                let z = (1.0 - x * x - y * y).max(0.0).sqrt();
                let sin_theta_i = (1.0 - cos_theta_i * cos_theta_i).max(0.0).sqrt();
                let norm = 1.0 / (sin_theta_i * y + cos_theta_i * z);
                Vec2::new((cos_theta_i * y - sin_theta_i * z) * norm, x * norm)
            }
        }
    }
}

/// (sin φ, cos φ) of a unit direction; (0, 1) at the pole (Mitsuba's `Frame3f::sincos_phi`).
#[inline]
fn sincos_phi(v: Vec3) -> (f32, f32) {
    let sin_theta_2 = v.x * v.x + v.y * v.y;
    if sin_theta_2 <= 4.0 * f32::EPSILON {
        return (0.0, 1.0);
    }
    let inv = 1.0 / sin_theta_2.sqrt();
    ((v.y * inv).clamp(-1.0, 1.0), (v.x * inv).clamp(-1.0, 1.0))
}

/// The error function, |error| < 1.2e-7 (Numerical Recipes' Chebyshev fit of erfc, in f64).
fn erf(x: f32) -> f32 {
    let z = (x as f64).abs();
    if z.is_infinite() {
        return 1f32.copysign(x);
    }
    let t = 1.0 / (1.0 + 0.5 * z);
    let p = -1.265_512_23
        + t * (1.000_023_68
            + t * (0.374_091_96
                + t * (0.096_784_18
                    + t * (-0.186_288_06
                        + t * (0.278_868_07
                            + t * (-1.135_203_98 + t * (1.488_515_87 + t * (-0.822_152_23 + t * 0.170_872_77))))))));
    let erfc = t * (-z * z + p).exp();
    ((1.0 - erfc) as f32).copysign(x)
}

/// The inverse error function on (−1, 1) (Giles 2010, "Approximating the erfinv function",
/// single precision: relative error below 4e-7), ±∞ at ±1.
fn erfinv(x: f32) -> f32 {
    // Giles' f32 coefficients, evaluated in f64
    let x = x as f64;
    let w = -((1.0 - x) * (1.0 + x)).ln();
    let p = if w < 5.0 {
        let w = w - 2.5;
        let mut p: f64 = 2.810_226_36e-08;
        p = 3.432_739_39e-07 + p * w;
        p = -3.523_387_7e-06 + p * w;
        p = -4.391_506_54e-06 + p * w;
        p = 0.000_218_580_87 + p * w;
        p = -0.001_253_725_03 + p * w;
        p = -0.004_177_681_64 + p * w;
        p = 0.246_640_727 + p * w;
        1.501_409_41 + p * w
    } else {
        let w = w.sqrt() - 3.0;
        let mut p: f64 = -0.000_200_214_257;
        p = 0.000_100_950_558 + p * w;
        p = 0.001_349_343_22 + p * w;
        p = -0.003_673_428_44 + p * w;
        p = 0.005_739_507_73 + p * w;
        p = -0.007_622_461_3 + p * w;
        p = 0.009_438_870_47 + p * w;
        p = 1.001_674_06 + p * w;
        2.832_976_82 + p * w
    };
    (p * x) as f32
}

/// Mitsuba's `fresnel(cos_theta_i, eta)` for a dielectric interface of relative index `eta`
/// (interior over exterior) and the signed cosine `cos_theta_i` of the incident direction with
/// the normal (negative: from inside): `(F, cos_theta_t, eta_it, eta_ti)`, with `cos_theta_t`
/// of the opposite sign (0 under total internal reflection), η_it = η_t/η_i and η_ti = 1/η_it.
/// F is [`super::fresnel_dielectric`]'s.
#[inline]
pub fn fresnel(cos_theta_i: f32, eta: f32) -> (f32, f32, f32, f32) {
    let outside = cos_theta_i >= 0.0;
    let (eta_it, eta_ti) = if outside { (eta, 1.0 / eta) } else { (1.0 / eta, eta) };
    let cos_t_sqr = 1.0 - (1.0 - cos_theta_i * cos_theta_i) * eta_ti * eta_ti;
    let cos_t = cos_t_sqr.max(0.0).sqrt();
    let f = super::fresnel_dielectric(cos_theta_i.abs(), eta_it);
    let cos_theta_t = if outside { -cos_t } else { cos_t };
    (f, cos_theta_t, eta_it, eta_ti)
}

/// The refraction of `wi` through the microfacet `m` (Mitsuba's `refract`), `cos_theta_t` and
/// `eta_ti` from [`fresnel`]`(wi·m, η)`.
#[inline]
pub fn refract(wi: Vec3, m: Vec3, cos_theta_t: f32, eta_ti: f32) -> Vec3 {
    m * (wi.dot(m) * eta_ti + cos_theta_t) - wi * eta_ti
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bsdf::testing::{dir, rng};

    #[test]
    fn special_functions() {
        for (x, want) in
            [(0.0f32, 0.0f32), (0.5, 0.520_499_9), (1.0, 0.842_700_8), (2.0, 0.995_322_3), (-1.5, -0.966_105_2)]
        {
            assert!((erf(x) - want).abs() < 2e-7, "erf({x}) = {}", erf(x));
        }
        assert_eq!(erf(f32::INFINITY), 1.0);
        for x in [-0.999_99f32, -0.9, -0.3, 0.0, 0.1, 0.6, 0.99, 0.999_9] {
            let y = erfinv(x);
            assert!((erf(y) - x).abs() < 1e-6 * (1.0 + 10.0 * y.abs()), "erfinv({x}) = {y}");
        }
    }

    /// ∫D(m) cos θ_m dω_m = 1 (projected area) and ∫D_wo(m) dω_m = 1 for the visible normals:
    /// a midpoint sum over the hemisphere of m.
    #[test]
    fn normalised() {
        let n = 800;
        for kind in [MicrofacetKind::Beckmann, MicrofacetKind::Ggx] {
            for (au, av) in [(0.3f32, 0.3f32), (0.15, 0.5)] {
                let d = MicrofacetDistribution::new(kind, au, av, true);
                let wo = dir(50.0, 20.0);
                let (mut proj, mut vis) = (0.0f64, 0.0f64);
                for i in 0..n {
                    let mu = (i as f32 + 0.5) / n as f32;
                    for j in 0..n {
                        let phi = 2.0 * PI * (j as f32 + 0.5) / n as f32;
                        let s = (1.0 - mu * mu).sqrt();
                        let m = Vec3::new(s * phi.cos(), s * phi.sin(), mu);
                        proj += (d.eval(m) * mu) as f64;
                        vis += d.pdf(wo, m) as f64;
                    }
                }
                let dw = 2.0 * std::f64::consts::PI / (n * n) as f64;
                // the visible-normal integral is 1 only up to the Beckmann G1 approximation
                assert!((proj * dw - 1.0).abs() < 2e-3, "{kind:?} {au}/{av}: ∫D cos = {}", proj * dw);
                assert!((vis * dw - 1.0).abs() < 6e-3, "{kind:?} {au}/{av}: ∫D_wo = {}", vis * dw);
            }
        }
    }

    #[test]
    fn alpha_clamped_and_sample_pdf_consistent() {
        let d = MicrofacetDistribution::isotropic(MicrofacetKind::Ggx, 0.0, true);
        assert_eq!((d.alpha_u, d.alpha_v), (1e-4, 1e-4));
        let mut r = rng(3);
        for kind in [MicrofacetKind::Beckmann, MicrofacetKind::Ggx] {
            for vis in [true, false] {
                let d = MicrofacetDistribution::new(kind, 0.2, 0.45, vis);
                let wo = dir(60.0, 40.0);
                for _ in 0..1000 {
                    let (m, pdf) = d.sample(wo, [r.next_f32(), r.next_f32()]);
                    let want = d.pdf(wo, m);
                    assert!((m.length() - 1.0).abs() < 1e-5 && m.z > 0.0, "{m:?}");
                    assert!((pdf - want).abs() <= 1e-3 * want.max(1e-3), "{kind:?} {vis}: {pdf} vs {want}");
                }
            }
        }
    }
}
