//! Conductor Fresnel reflectance for a complex index of refraction η + ik, unpolarised and exact
//! (Moeller, "Optics", 1988; the form Mitsuba 3's `fresnel_conductor` evaluates), per RGB channel.
//! It weights the mirror reflection of `Material::Conductor`; `Material::Mirror` keeps its constant
//! reflectance (its images are unchanged).
//!
//! Invariants: F ∈ [0, 1]; F(1, η, 0) = ((η−1)/(η+1))²; F → 1 at grazing incidence; k = 0 gives
//! the dielectric Fresnel term from outside.

use crate::math::Rgb;

/// F(cos θ_i) per channel; `cos_i` is clamped to [0, 1].
#[inline]
pub fn fresnel_conductor(cos_i: f32, eta: Rgb, k: Rgb) -> Rgb {
    let c = cos_i.clamp(0.0, 1.0);
    let c2 = c * c;
    let s2 = 1.0 - c2;
    let s4 = s2 * s2;
    let f = |eta: f32, k: f32| -> f32 {
        let t1 = eta * eta - k * k - s2;
        let a2pb2 = (t1 * t1 + 4.0 * k * k * eta * eta).max(0.0).sqrt();
        let a = (0.5 * (a2pb2 + t1)).max(0.0).sqrt();
        let term1 = a2pb2 + c2;
        let term2 = 2.0 * c * a;
        let rs = (term1 - term2) / (term1 + term2);
        let term3 = a2pb2 * c2 + s4;
        let term4 = term2 * s2;
        let rp = rs * (term3 - term4) / (term3 + term4);
        (0.5 * (rs + rp)).clamp(0.0, 1.0)
    };
    Rgb::new(f(eta.x, k.x), f(eta.y, k.y), f(eta.z, k.z))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bsdf::fresnel_dielectric;

    #[test]
    fn known_values() {
        // normal incidence: ((η−1)² + k²) / ((η+1)² + k²)
        let (eta, k) = (Rgb::new(0.143, 0.375, 1.442), Rgb::new(3.983, 2.386, 1.603));
        let f = fresnel_conductor(1.0, eta, k);
        let want = |n: f32, k: f32| ((n - 1.0).powi(2) + k * k) / ((n + 1.0).powi(2) + k * k);
        assert!((f.x - want(0.143, 3.983)).abs() < 1e-5 && (f.z - want(1.442, 1.603)).abs() < 1e-5, "{f}");
        // grazing incidence reflects everything
        assert!(fresnel_conductor(1e-4, eta, k).min_element() > 0.99);
        // k = 0 is the dielectric term
        for c in [0.1f32, 0.5, 0.9] {
            let d = fresnel_dielectric(c, 1.5);
            assert!((fresnel_conductor(c, Rgb::splat(1.5), Rgb::ZERO).x - d).abs() < 1e-5);
        }
        // η = 0, k = 1 (Mitsuba's `none`) is a perfect mirror
        assert!((fresnel_conductor(0.3, Rgb::ZERO, Rgb::ONE) - Rgb::ONE).abs().max_element() < 1e-6);
    }
}
