//! A BSDF's parameters at one point: what `Scene::shade` resolves a scene material to (no
//! sampling code; see `bsdf`). The D/S partition of the spec §1 is
//! `Material::is_dirac`: mirrors, glass and thin glass are Dirac (S), everything else, a plastic's
//! coat over its diffuse base included, non-specular (D).

use super::microfacet::MicrofacetDistribution;
use super::plastic::Plastic;
use super::roughconductor::RoughConductor;
use super::roughdielectric::RoughDielectric;
use super::roughplastic::RoughPlastic;
use super::thindielectric::ThinDielectric;
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
    /// Mitsuba's `plastic`: a smooth dielectric coat (Dirac) over a diffuse base.
    Plastic(Plastic),
    /// Mitsuba's `roughplastic`: a rough dielectric coat over a diffuse base (both lobes
    /// non-Dirac).
    RoughPlastic(RoughPlastic),
    /// Mitsuba's `thindielectric`: a thin slab, Dirac reflection and straight transmission.
    ThinDielectric(ThinDielectric),
    /// Mitsuba's `roughconductor`: microfacet reflection with the conductor Fresnel term.
    RoughConductor(RoughConductor),
    /// Mitsuba's `roughdielectric`: microfacet reflection and refraction.
    RoughDielectric(RoughDielectric),
    /// The black BSDF of an area light: it reflects nothing.
    Black,
}

/// A parameter of a material that a texture may set at each point (Mitsuba's parameter names).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Slot {
    /// `diffuse`'s `reflectance`.
    Reflectance,
    /// `diffuse_reflectance` (`phong`, the plastics).
    DiffuseReflectance,
    /// `specular_reflectance` (conductors, `phong`, the plastics, the dielectrics).
    SpecularReflectance,
    /// `specular_transmittance` (the dielectrics).
    SpecularTransmittance,
    /// `alpha` (the rough BSDFs; a monochrome texture).
    Alpha,
}

impl Slot {
    /// Mitsuba's name of the parameter.
    pub fn name(self) -> &'static str {
        match self {
            Slot::Reflectance => "reflectance",
            Slot::DiffuseReflectance => "diffuse_reflectance",
            Slot::SpecularReflectance => "specular_reflectance",
            Slot::SpecularTransmittance => "specular_transmittance",
            Slot::Alpha => "alpha",
        }
    }

    /// True for a parameter that takes one value (a texture's `eval_1`), not a colour.
    pub fn is_monochrome(self) -> bool {
        matches!(self, Slot::Alpha)
    }
}

impl MicrofacetDistribution {
    /// The distribution with isotropic roughness `alpha` (a textured `alpha`), its kind and
    /// sampling kept.
    fn textured_alpha(&self, alpha: f32) -> MicrofacetDistribution {
        MicrofacetDistribution::isotropic(self.kind, alpha, self.sample_visible)
    }
}

impl Material {
    /// Sets parameter `slot` to `v` (a colour, or for a monochrome slot `v.x`); false when this
    /// material has no such parameter.
    pub fn set(&mut self, slot: Slot, v: Rgb) -> bool {
        match (self, slot) {
            (Material::Diffuse { albedo }, Slot::Reflectance) => *albedo = v,
            (Material::Glossy { albedo, .. }, Slot::DiffuseReflectance) => *albedo = v,
            (Material::Glossy { specular, .. }, Slot::SpecularReflectance) => *specular = v,
            (Material::Mirror { reflectance } | Material::Conductor { reflectance, .. }, Slot::SpecularReflectance) => {
                *reflectance = v
            }
            (Material::Plastic(p), Slot::DiffuseReflectance) => *p = p.with_reflectances(v, p.specular_reflectance()),
            (Material::Plastic(p), Slot::SpecularReflectance) => *p = p.with_reflectances(p.diffuse_reflectance(), v),
            (Material::RoughPlastic(p), Slot::DiffuseReflectance) => {
                *p = p.with_reflectances(v, p.specular_reflectance())
            }
            (Material::RoughPlastic(p), Slot::SpecularReflectance) => {
                *p = p.with_reflectances(p.diffuse_reflectance(), v)
            }
            (Material::ThinDielectric(t), Slot::SpecularReflectance) => t.specular_reflectance = v,
            (Material::ThinDielectric(t), Slot::SpecularTransmittance) => t.specular_transmittance = v,
            (Material::RoughConductor(c), Slot::SpecularReflectance) => c.specular_reflectance = v,
            (Material::RoughConductor(c), Slot::Alpha) => c.distribution = c.distribution.textured_alpha(v.x),
            (Material::RoughDielectric(d), Slot::SpecularReflectance) => d.specular_reflectance = v,
            (Material::RoughDielectric(d), Slot::SpecularTransmittance) => d.specular_transmittance = v,
            (Material::RoughDielectric(d), Slot::Alpha) => d.distribution = d.distribution.textured_alpha(v.x),
            _ => return false,
        }
        true
    }

    /// True for Dirac (delta) BSDFs: the S side of the L_d / L_c split. A property of the variant
    /// alone ([`Material::set`] never changes it: `transport::dirac` relies on it).
    #[inline]
    pub fn is_dirac(&self) -> bool {
        matches!(
            self,
            Material::Mirror { .. } | Material::Conductor { .. } | Material::Glass { .. } | Material::ThinDielectric(_)
        )
    }
    /// True for BSDFs that scatter from both sides of a surface by nature (the dielectrics:
    /// Mitsuba refuses `twosided` around them).
    #[inline]
    pub fn is_two_sided_by_nature(&self) -> bool {
        matches!(self, Material::Glass { .. } | Material::ThinDielectric(_) | Material::RoughDielectric(_))
    }
    /// True for BSDFs with both a Dirac and a non-Dirac lobe (`plastic`: a smooth coat over a
    /// diffuse base).
    #[inline]
    pub fn has_mixed_lobes(&self) -> bool {
        matches!(self, Material::Plastic(_))
    }
    /// The larger roughness α of a BSDF that is one microfacet lobe alone (`roughconductor`,
    /// `roughdielectric`); `None` for every other BSDF (diffuse, Phong, the plastics' diffuse base,
    /// Dirac). `pt-cf`'s rule of which glossy vertices its tables guide (`--guide-min-alpha`).
    #[inline]
    pub fn lobe_alpha(&self) -> Option<f32> {
        let d = match self {
            Material::RoughConductor(b) => &b.distribution,
            Material::RoughDielectric(b) => &b.distribution,
            _ => return None,
        };
        Some(d.alpha_u.max(d.alpha_v))
    }
    /// True when the BSDF is identically zero.
    #[inline]
    pub fn is_black(&self) -> bool {
        matches!(self, Material::Black)
    }
}
