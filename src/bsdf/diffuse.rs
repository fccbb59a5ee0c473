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
