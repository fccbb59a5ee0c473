//! A BSDF's parameters at one point: what `Scene::shade` resolves a scene material to (no
//! sampling code; see `bsdf`). The D/S partition of the spec §1 is
//! `Material::is_dirac`: mirrors and glass are Dirac (S), everything else non-specular (D).

use crate::math::Rgb;

/// A surface material, by the scene file's `type`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Material {
    /// Lambertian reflector: f = albedo/π.
    Diffuse {
        /// Diffuse reflectance.
        albedo: Rgb,
    },
    /// Energy-conserving modified Phong: albedo/π + specular·(e+2)/(2π)·cosᵉα.
    Glossy {
        /// Diffuse reflectance.
        albedo: Rgb,
        /// Specular reflectance.
        specular: Rgb,
        /// Phong exponent e.
        exponent: f32,
    },
    /// Perfect specular reflector with constant reflectance (Dirac).
    Mirror {
        /// Reflectance.
        reflectance: Rgb,
    },
    /// Perfect specular reflector weighted by the conductor Fresnel term of the complex index
    /// η + ik (per RGB channel): reflectance·F(cos θ, η, k) (Dirac; Mitsuba's smooth `conductor`).
    Conductor {
        /// Specular reflectance (a multiplier on the Fresnel term).
        reflectance: Rgb,
        /// Real part of the relative index of refraction.
        eta: Rgb,
        /// Imaginary part (absorption).
        k: Rgb,
    },
    /// Smooth dielectric with Fresnel reflection and refraction (Dirac).
    Glass {
        /// Index of refraction inside (outside is 1).
        ior: f32,
    },
    /// The black BSDF of an area light: it reflects nothing.
    Black,
}

impl Material {
    /// True for Dirac (delta) BSDFs: the S side of the L_d / L_c split.
    #[inline]
    pub fn is_dirac(&self) -> bool {
        matches!(self, Material::Mirror { .. } | Material::Conductor { .. } | Material::Glass { .. })
    }
    /// True for BSDFs that scatter from both sides of a surface by nature (the dielectrics:
    /// Mitsuba refuses `twosided` around them).
    #[inline]
    pub fn is_two_sided_by_nature(&self) -> bool {
        matches!(self, Material::Glass { .. })
    }
    /// True when the BSDF is identically zero.
    #[inline]
    pub fn is_black(&self) -> bool {
        matches!(self, Material::Black)
    }
}
