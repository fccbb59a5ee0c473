//! Smooth dielectric (glass): Fresnel-weighted choice between mirror reflection and Snell
//! refraction. Lossless: R + T = 1, so both choices carry weight 1 apart from the radiance-mode
//! 1/η² factor at refraction (pbrt-v4 `DielectricBxDF`; none in importance mode).

use super::{BsdfSample, Mode, ShadingPoint};
use crate::math::{reflect, Rgb, Vec3};

/// Unpolarised Fresnel reflectance for a dielectric; `cos_i` > 0 on the incident side,
/// `eta` = η_t/η_i. Returns 1 under total internal reflection.
#[inline]
pub fn fresnel_dielectric(cos_i: f32, eta: f32) -> f32 {
    let cos_i = cos_i.clamp(0.0, 1.0);
    let sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let r_par = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_perp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    0.5 * (r_par * r_par + r_perp * r_perp)
}

/// The normals on `wo`'s side: (geometric, shading), `entering` when `wo` is outside.
#[inline]
fn sided(sp: &ShadingPoint, wo: Vec3) -> (Vec3, Vec3, bool) {
    let entering = wo.dot(sp.ng) > 0.0;
    if entering {
        (sp.ng, sp.ns, true)
    } else {
        (-sp.ng, -sp.ns, false)
    }
}

/// True when `wo` lies below the shading normal on its side: the glass then reflects and
/// refracts about the geometric normal (and light paths take no shading-normal factor).
#[inline]
pub fn falls_back(sp: &ShadingPoint, wo: Vec3) -> bool {
    let (_, ns, _) = sided(sp, wo);
    wo.dot(ns) <= 0.0
}

/// Samples reflection (probability F) or refraction (1 − F).
#[inline]
pub fn sample(ior: f32, sp: &ShadingPoint, wo: Vec3, u: f32, mode: Mode) -> Option<BsdfSample> {
    let (ng, ns, entering) = sided(sp, wo);
    let eta = if entering { ior } else { 1.0 / ior };
    // shading normal disagreeing with the geometry: fall back to the geometric normal
    let n = if falls_back(sp, wo) { ng } else { ns };
    let cos_i = wo.dot(n);
    let f = fresnel_dielectric(cos_i, eta);
    if u < f {
        let wi = reflect(wo, n);
        if wi.dot(ng) <= 0.0 {
            return None;
        }
        return Some(BsdfSample { wi, weight: Rgb::ONE, pdf_w: f, is_delta: true, eta: 1.0 });
    }
    let sin2_t = (1.0 - cos_i * cos_i).max(0.0) / (eta * eta);
    let cos_t = (1.0 - sin2_t).max(0.0).sqrt();
    let wi = (-wo / eta + (cos_i / eta - cos_t) * n).normalize();
    if wi.dot(ng) >= 0.0 {
        return None;
    }
    let scale = if mode == Mode::Radiance { 1.0 / (eta * eta) } else { 1.0 };
    Some(BsdfSample { wi, weight: Rgb::splat(scale), pdf_w: 1.0 - f, is_delta: true, eta })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fresnel_known_values() {
        // normal incidence: ((n-1)/(n+1))^2 = 0.04 for n = 1.5
        assert!((fresnel_dielectric(1.0, 1.5) - 0.04).abs() < 1e-6);
        // total internal reflection from inside beyond the critical angle (41.8°)
        assert_eq!(fresnel_dielectric((50f32).to_radians().cos(), 1.0 / 1.5), 1.0);
        // grazing incidence reflects everything
        assert!(fresnel_dielectric(1e-4, 1.5) > 0.99);
    }

    #[test]
    fn refraction_obeys_snell() {
        let sp = ShadingPoint::new(Vec3::ZERO, Vec3::Z, Vec3::Z);
        let wo = Vec3::new(0.5f32.sin(), 0.0, 0.5f32.cos());
        // u = 0.999 chooses refraction (F is small at 0.5 rad)
        let s = sample(1.5, &sp, wo, 0.999, Mode::Importance).unwrap();
        let sin_t = (s.wi.x * s.wi.x + s.wi.y * s.wi.y).sqrt();
        assert!((0.5f32.sin() - 1.5 * sin_t).abs() < 1e-5);
        assert!(s.wi.z < 0.0 && s.wi.x < 0.0);
    }
}
