//! `diffuse` (Mitsuba 3's plugin): Lambertian reflection, f = ρ/π, cosine-weighted sampling.
//!
//! Each formula here is the one source of both the scalar path (`bsdf::eval`, `pdf_w`,
//! `sample`) and `pt`'s sixteen-wide lanes (`integrators::pt::lanes`), which call these functions
//! lane by lane: they are `#[inline(always)]`, without early returns, so that LLVM vectorises the
//! lane loops, and a rejected sample is a mask, not a `None`.
//!
//! Invariants: `wo` and `wi` must lie on the same side of the **geometric** normal (no light
//! through walls) and above the shading normal, both flipped to `wo`'s side (`super::oriented`).

use super::{oriented, reflects, BsdfSample};
use crate::math::{Frame, Rgb, Vec3, INV_PI};
use crate::sampling::warp::{cosine_hemisphere_pdf, sample_cosine_hemisphere};

/// f(wo, wi) = ρ/π where the pair can reflect, 0 elsewhere.
#[inline(always)]
pub fn eval(albedo: Rgb, ng: Vec3, ns: Vec3, wo: Vec3, wi: Vec3) -> Rgb {
    let (ng, ns) = oriented(ng, ns, wo);
    if reflects(ng, ns, wo, wi) {
        albedo * INV_PI
    } else {
        Rgb::ZERO
    }
}

/// The solid-angle pdf of [`sample`] drawing `wi`.
#[inline(always)]
pub fn pdf_w(ng: Vec3, ns: Vec3, wo: Vec3, wi: Vec3) -> f32 {
    let (ng, ns) = oriented(ng, ns, wo);
    if wi.dot(ng) <= 0.0 {
        0.0
    } else {
        cosine_hemisphere_pdf(wi.dot(ns))
    }
}

/// The sample of direction `wi` drawn by [`sample`] with pdf `pdf_w`: its weight f·cos/pdf is ρ.
#[inline(always)]
pub fn sampled(albedo: Rgb, wi: Vec3, pdf_w: f32) -> BsdfSample {
    BsdfSample { wi, weight: albedo, pdf_w, is_delta: false, eta: 1.0 }
}

/// A cosine-weighted direction from `u`: `(wi, pdf_w, valid)`. Its weight f·cos/pdf is ρ.
#[inline(always)]
pub fn sample(ng: Vec3, ns: Vec3, wo: Vec3, u: [f32; 2]) -> (Vec3, f32, bool) {
    let (ng, ns) = oriented(ng, ns, wo);
    let wi = Frame::from_normal(ns).to_world(sample_cosine_hemisphere(u));
    let cos = wi.dot(ns);
    let valid = !(wi.dot(ng) <= 0.0 || cos <= 0.0 || wo.dot(ns) <= 0.0);
    (wi, cos * INV_PI, valid)
}

/// Mitsuba 3's `diffuse` in its local frame (one-sided: black unless `wo.z > 0`), running the
/// formulas above with ng = ns = z.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Diffuse {
    /// ρ, Mitsuba's `reflectance`.
    pub reflectance: Rgb,
}

impl super::LocalBsdf for Diffuse {
    fn eval(&self, wo: Vec3, wi: Vec3, _: super::Mode) -> Rgb {
        if wo.z > 0.0 {
            eval(self.reflectance, Vec3::Z, Vec3::Z, wo, wi)
        } else {
            Rgb::ZERO
        }
    }
    fn pdf_w(&self, wo: Vec3, wi: Vec3, _: super::Mode) -> f32 {
        if wo.z > 0.0 {
            pdf_w(Vec3::Z, Vec3::Z, wo, wi)
        } else {
            0.0
        }
    }
    fn sample(&self, wo: Vec3, u: [f32; 3], _: super::Mode) -> Option<BsdfSample> {
        let (wi, pdf_w, valid) = sample(Vec3::Z, Vec3::Z, wo, [u[1], u[2]]);
        (valid && wo.z > 0.0).then(|| sampled(self.reflectance, wi, pdf_w))
    }
}

#[cfg(test)]
mod tests {
    use super::super::testing::*;
    use super::super::Mode;
    use super::*;

    #[test]
    fn sampler_weights_furnace_and_mitsuba() {
        let b = Diffuse { reflectance: Rgb::new(0.2, 0.5, 0.8) };
        assert_chi2("diffuse 30°", &b, dir(30.0, 10.0), Mode::Radiance, 1, 1);
        assert_weights("diffuse", &b, dir(60.0, 0.0), Mode::Radiance, 10_000, 1e-4);
        let white = Diffuse { reflectance: Rgb::ONE };
        assert!((albedo(&white, dir(45.0, 0.0), 100_000) - Rgb::ONE).abs().max_element() < 1e-6);
        // f32 against Mitsuba's f32: the same expression, so 1e-6 relative
        assert_eq!(assert_mitsuba("diffuse", "grey", &b, Mode::Radiance, 1e-6, 1e-7), 350);
    }
}
