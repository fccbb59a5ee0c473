//! Warps from [0,1)² to hemispheres, spheres, triangles and lobes, each beside its pdf
//! (pbrt's sampling triplets). Local directions have z = cos θ.
//!
//! Invariants: every `sample_*` returns unit vectors whose density is exactly the matching
//! `*_pdf` (checked by χ² tests in `tests/sampling_chi2.rs`).

use crate::math::{Vec2, Vec3, INV_PI, PI};

/// Shirley–Chiu concentric map of the square onto the unit disk.
#[inline]
pub fn sample_concentric_disk(u: [f32; 2]) -> Vec2 {
    let ox = 2.0 * u[0] - 1.0;
    let oy = 2.0 * u[1] - 1.0;
    if ox == 0.0 && oy == 0.0 {
        return Vec2::ZERO;
    }
    let (r, theta) =
        if ox.abs() > oy.abs() { (ox, (PI / 4.0) * (oy / ox)) } else { (oy, PI / 2.0 - (PI / 4.0) * (ox / oy)) };
    Vec2::new(r * theta.cos(), r * theta.sin())
}

/// Cosine-weighted hemisphere direction (Malley's method).
#[inline]
pub fn sample_cosine_hemisphere(u: [f32; 2]) -> Vec3 {
    let d = sample_concentric_disk(u);
    let z = (1.0 - d.length_squared()).max(0.0).sqrt();
    Vec3::new(d.x, d.y, z)
}

/// Solid-angle pdf of `sample_cosine_hemisphere`.
#[inline]
pub fn cosine_hemisphere_pdf(cos_theta: f32) -> f32 {
    cos_theta.max(0.0) * INV_PI
}

/// Uniform direction on the unit sphere.
#[inline]
pub fn sample_uniform_sphere(u: [f32; 2]) -> Vec3 {
    let z = 1.0 - 2.0 * u[0];
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u[1];
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// Solid-angle pdf of `sample_uniform_sphere`.
#[inline]
pub fn uniform_sphere_pdf() -> f32 {
    1.0 / (4.0 * PI)
}

/// Phong lobe `cosᵉα` around local +z: pdf_w = (e+1)/(2π)·cosᵉα.
#[inline]
pub fn sample_phong_lobe(u: [f32; 2], exponent: f32) -> Vec3 {
    let cos_a = u[0].powf(1.0 / (exponent + 1.0));
    let sin_a = (1.0 - cos_a * cos_a).max(0.0).sqrt();
    let phi = 2.0 * PI * u[1];
    Vec3::new(sin_a * phi.cos(), sin_a * phi.sin(), cos_a)
}

/// Solid-angle pdf of `sample_phong_lobe` given cos α to the lobe axis.
#[inline]
pub fn phong_lobe_pdf(cos_alpha: f32, exponent: f32) -> f32 {
    if cos_alpha <= 0.0 {
        0.0
    } else {
        (exponent + 1.0) * (0.5 * INV_PI) * cos_alpha.powf(exponent)
    }
}

/// Uniform barycentrics (b0, b1) on a triangle; b2 = 1 − b0 − b1 (area pdf 1/area).
#[inline]
pub fn sample_triangle(u: [f32; 2]) -> (f32, f32) {
    // Heitz 2019 low-distortion map.
    let (b0, b1) = if u[0] < u[1] {
        let b0 = u[0] / 2.0;
        (b0, u[1] - b0)
    } else {
        let b1 = u[1] / 2.0;
        (u[0] - b1, b1)
    };
    (b0, b1)
}
