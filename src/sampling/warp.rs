//! Warps from [0,1)² to hemispheres, spheres, triangles and lobes, each beside its pdf
//! (pbrt's sampling triplets). Local directions have z = cos θ.
//!
//! Invariants: every `sample_*` returns unit vectors whose density is exactly the matching
//! `*_pdf` (checked by χ² tests in `tests/sampling_chi2.rs`).

use crate::math::{Vec2, Vec3, INV_PI, PI};

/// Shirley–Chiu concentric map of the square onto the unit disk. The angle is (π/4)·t in one
/// octant pair and π/2 − (π/4)·t in the other, so its sine and cosine are those of (π/4)·t,
/// from [`sin_cos_quarter_pi`], swapped in the second case. Written without early returns (both
/// octant pairs select their operands, one sine and cosine is computed) so that `pt`'s lanes run
/// it sixteen wide (`integrators::pt::lanes`).
#[inline(always)]
pub fn sample_concentric_disk(u: [f32; 2]) -> Vec2 {
    let ox = 2.0 * u[0] - 1.0;
    let oy = 2.0 * u[1] - 1.0;
    let wide = ox.abs() > oy.abs();
    let (r, t) = if wide { (ox, oy / ox) } else { (oy, ox / oy) };
    let (s, c) = sin_cos_quarter_pi(t);
    let disk = if wide { Vec2::new(r * c, r * s) } else { Vec2::new(r * s, r * c) };
    if ox == 0.0 && oy == 0.0 {
        Vec2::ZERO
    } else {
        disk
    }
}

/// (sin x, cos x) of x = (π/4)·t for t ∈ [−1, 1]: Cephes' single-precision minimax
/// polynomials on [−π/4, π/4] (`sinf.c`, `cosf.c`), within 2 ulp of the exact values (tested).
/// Plain arithmetic, so that LLVM can run it 16 lanes wide (`integrators::pt::lanes`) with the
/// scalar code's bits; libm's `sincosf` was 3.8% of `pt` on `ring`, called lane by lane
/// (`results/2026-12-05-diffuse-lanes.md`).
#[inline(always)]
pub fn sin_cos_quarter_pi(t: f32) -> (f32, f32) {
    let x = (PI / 4.0) * t;
    let z = x * x;
    let s = x + x * z * ((-1.951_529_6e-4 * z + 8.332_161e-3) * z - 1.666_665_5e-1);
    let c = 1.0 - 0.5 * z + z * z * ((2.443_315_7e-5 * z - 1.388_731_6e-3) * z + 4.166_664_6e-2);
    (s, c)
}

/// Cosine-weighted hemisphere direction (Malley's method).
#[inline(always)]
pub fn sample_cosine_hemisphere(u: [f32; 2]) -> Vec3 {
    let d = sample_concentric_disk(u);
    let z = (1.0 - d.length_squared()).max(0.0).sqrt();
    Vec3::new(d.x, d.y, z)
}

/// Solid-angle pdf of `sample_cosine_hemisphere`.
#[inline(always)]
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

/// The point of barycentrics (b0, b1, 1 − b0 − b1) in the triangle `p`.
#[inline(always)]
pub fn triangle_point(p: [Vec3; 3], (b0, b1): (f32, f32)) -> Vec3 {
    b0 * p[0] + b1 * p[1] + (1.0 - b0 - b1) * p[2]
}

/// Uniform barycentrics (b0, b1) on a triangle; b2 = 1 − b0 − b1 (area pdf 1/area).
#[inline(always)]
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The polynomial sine and cosine stay within 2 ulp of the exact values of the same f32
    /// angle over the whole range the concentric map uses, and are exact at 0.
    #[test]
    fn sin_cos_quarter_pi_is_within_two_ulp() {
        let ulp = |y: f64| {
            let f = (y as f32).abs();
            (f32::from_bits(f.to_bits() + 1) - f) as f64
        };
        let mut worst = 0.0f64;
        for k in -200_000..=200_000 {
            let t = k as f32 / 200_000.0;
            let x = ((PI / 4.0) * t) as f64;
            let (s, c) = sin_cos_quarter_pi(t);
            for (got, exact) in [(s, x.sin()), (c, x.cos())] {
                let e = (got as f64 - exact).abs() / ulp(exact).max(f64::MIN_POSITIVE);
                worst = worst.max(e);
            }
        }
        assert!(worst <= 2.0, "worst error {worst} ulp");
        assert_eq!(sin_cos_quarter_pi(0.0), (0.0, 1.0));
    }
}
