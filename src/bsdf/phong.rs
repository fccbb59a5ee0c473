//! Energy-conserving modified Phong (Lafortune & Willems 1994):
//! f = ρ_d/π + ρ_s·(e+2)/(2π)·cosᵉα, α = ∠(wi, reflect(wo, n)).
//! Sampling mixes a cosine lobe and a `cosᵉ` lobe around the mirror direction with probability
//! ∝ luminance of ρ_d and ρ_s; the pdf is the exact mixture.

use crate::math::{luminance, reflect, Frame, Rgb, Vec3, INV_PI};
use crate::sampling::warp::{cosine_hemisphere_pdf, phong_lobe_pdf, sample_cosine_hemisphere, sample_phong_lobe};

#[inline]
fn diffuse_prob(albedo: Rgb, specular: Rgb) -> f32 {
    let (d, s) = (luminance(albedo), luminance(specular));
    if d + s <= 0.0 {
        0.5
    } else {
        d / (d + s)
    }
}

/// f(wo, wi) (both on the `n` side; checked by the caller).
#[inline]
pub fn eval(albedo: Rgb, specular: Rgb, e: f32, n: Vec3, wo: Vec3, wi: Vec3) -> Rgb {
    let cos_a = reflect(wo, n).dot(wi).max(0.0);
    albedo * INV_PI + specular * ((e + 2.0) * 0.5 * INV_PI * cos_a.powf(e))
}

/// Mixture pdf_w of `sample`.
#[inline]
pub fn pdf_w(albedo: Rgb, specular: Rgb, e: f32, n: Vec3, wo: Vec3, wi: Vec3) -> f32 {
    let pd = diffuse_prob(albedo, specular);
    let cos_a = reflect(wo, n).dot(wi);
    pd * cosine_hemisphere_pdf(wi.dot(n)) + (1.0 - pd) * phong_lobe_pdf(cos_a, e)
}

/// Samples wi; returns (wi, pdf_w). wi may fall below the surface (the caller rejects it).
#[inline]
pub fn sample(albedo: Rgb, specular: Rgb, e: f32, n: Vec3, wo: Vec3, u: [f32; 3]) -> Option<(Vec3, f32)> {
    if albedo.max_element() <= 0.0 && specular.max_element() <= 0.0 {
        return None;
    }
    let pd = diffuse_prob(albedo, specular);
    let wi = if u[0] < pd {
        Frame::from_normal(n).to_world(sample_cosine_hemisphere([u[1], u[2]]))
    } else {
        Frame::from_normal(reflect(wo, n)).to_world(sample_phong_lobe([u[1], u[2]], e))
    };
    Some((wi, pdf_w(albedo, specular, e, n, wo, wi)))
}
