//! Mitsuba 3's BSDF plugins built from their parameters, for every scene format: the Mitsuba XML
//! reader (`mitsuba::bsdf`) and the TOML reader (`file`) hand their parameters over through
//! [`Params`], by Mitsuba's names, and get the same `Material`, the same textures and the same
//! errors back. Each plugin's defaults, presets and checks are written here once:
//!
//! - `diffuse`: `reflectance` 0.5; `conductor` and `roughconductor`: `material` preset `none`
//!   (the plain mirror: a smooth one is `Material::Mirror`), or `eta`/`k`, relative to `ext_eta`
//!   (1), times `specular_reflectance` (1); `dielectric`, `roughdielectric`, `thindielectric`:
//!   `int_ior` 1.5046 (bk7), `ext_ior` 1.000277 (air), numbers or Mitsuba's preset names, with
//!   `specular_reflectance`/`specular_transmittance` 1 (a smooth `dielectric` takes only 1);
//!   `plastic`, `roughplastic`: `diffuse_reflectance` 0.5, `specular_reflectance` 1, `int_ior`
//!   1.49, `ext_ior` 1.000277, `nonlinear` false; the rough ones: `distribution` `beckmann`,
//!   `alpha` 0.1 (or `alpha_u`/`alpha_v`), `sample_visible` true.
//! - A colour may be a texture ([`Param::Texture`], registered with the builder by the reader):
//!   the material then holds the texture's mean (what is known of it at load) and the
//!   `SlotTexture` records the slot; `alpha` reads a texture's `eval_1`.
//! - [`bitmap`]: an image texture, decoded once per file and `raw` flag (`TextureCache`), the file
//!   recorded as an input of the scene (no output may overwrite it).
//!
//! Invariants: reflectances (constant, or a texture's mean) finite and in [0, 1]; η = int/ext in
//! (0, 10]; conductor η, k ≥ 0; α ≥ 0 and finite; every error names the parameter
//! ([`Params::err`] adds the format's file, line and key).

use super::builder::SceneBuilder;
use super::mitsuba::presets;
use super::{Material, SceneError, SlotTexture};
use crate::bsdf::microfacet::{MicrofacetDistribution, MicrofacetKind};
use crate::bsdf::plastic::Plastic;
use crate::bsdf::roughconductor::RoughConductor;
use crate::bsdf::roughdielectric::RoughDielectric;
use crate::bsdf::roughplastic::RoughPlastic;
use crate::bsdf::thindielectric::ThinDielectric;
use crate::bsdf::Slot;
use crate::math::Rgb;
use crate::texture::{BitmapParams, Texture, TextureCache};

/// Mitsuba's default `int_ior` of the dielectrics (`bk7`).
pub(super) const DIELECTRIC_INT_IOR: f32 = 1.5046;
/// Mitsuba's default `int_ior` of the plastics (`polypropylene`).
pub(super) const PLASTIC_INT_IOR: f32 = 1.49;
/// Mitsuba's default `ext_ior` (`air`).
pub(super) const EXT_IOR: f32 = 1.000277;

/// A parameter that may be a texture, as a reader has it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Param {
    /// A constant (a number is grey).
    Constant(Rgb),
    /// A texture: its index in the builder's textures.
    Texture(u32),
}

/// An index of refraction as written: a number, or Mitsuba's preset name (`bk7`, `water`).
pub(super) struct IorValue {
    /// The number, when it is one.
    pub number: Option<f32>,
    /// The value as written (for the message).
    pub text: String,
}

/// A plugin's parameters as a reader has them, by Mitsuba's names. Getters return `None` for a
/// parameter that is not given and an error (the reader's) for one of the wrong kind.
pub(super) trait Params {
    /// True when parameter `name` is given.
    fn has(&self, name: &str) -> bool;
    /// A colour or, for a monochrome parameter, a number; either may be a texture.
    fn param(&mut self, name: &str) -> Result<Option<Param>, SceneError>;
    /// A constant colour (a number is grey).
    fn color(&mut self, name: &str) -> Result<Option<Rgb>, SceneError>;
    /// A number.
    fn float(&mut self, name: &str) -> Result<Option<f32>, SceneError>;
    /// A boolean.
    fn boolean(&mut self, name: &str) -> Result<Option<bool>, SceneError>;
    /// A string.
    fn string(&mut self, name: &str) -> Result<Option<String>, SceneError>;
    /// An index of refraction: a number or a preset name.
    fn ior_value(&mut self, name: &str) -> Result<Option<IorValue>, SceneError>;
    /// An error about parameter `name` (at its line; the plugin's when it is not given).
    fn err(&self, name: &str, message: &str) -> SceneError;
    /// The texture registered at `t`.
    fn texture(&self, t: u32) -> &Texture;
}

/// A BSDF plugin's material and the textures that set its parameters.
pub(super) struct Built {
    /// The material (a textured parameter at its texture's mean).
    pub m: Material,
    /// The textured parameters.
    pub textures: Vec<SlotTexture>,
}

/// Mitsuba's BSDF plugin `kind` from its parameters; `None` for a plugin not built here
/// (`twosided`, `normalmap`, `phong` and the unknown ones are the XML reader's).
pub(super) fn plugin(p: &mut impl Params, kind: &str) -> Result<Option<Built>, SceneError> {
    let mut textures = Vec::new();
    let t = &mut textures;
    let m = match kind {
        "diffuse" => diffuse(p, "reflectance", t)?,
        "conductor" => conductor(p, t)?,
        "roughconductor" => roughconductor(p, t)?,
        "dielectric" => dielectric(p)?,
        "roughdielectric" => roughdielectric(p, t)?,
        "thindielectric" => thindielectric(p, t)?,
        "plastic" => {
            let c = coat(p, t)?;
            Material::Plastic(Plastic::new(c.diffuse, c.specular, c.eta, c.nonlinear))
        }
        "roughplastic" => roughplastic(p, t)?,
        _ => return Ok(None),
    };
    Ok(Some(Built { m, textures }))
}

/// `diffuse` with its reflectance parameter `name` (Mitsuba's `reflectance`, the TOML `albedo`).
pub(super) fn diffuse(p: &mut impl Params, name: &str, t: &mut Vec<SlotTexture>) -> Result<Material, SceneError> {
    let c = colour(p, name, 0.5, Slot::Reflectance, t)?;
    Ok(Material::Diffuse { albedo: refl(p, c, name)? })
}

/// A colour parameter (default `default`) that may be a texture: a texture is recorded for
/// `slot` in `textures`, and the value returned is its mean (what is known of it at load).
pub(super) fn colour(
    p: &mut impl Params,
    name: &str,
    default: f32,
    slot: Slot,
    textures: &mut Vec<SlotTexture>,
) -> Result<Rgb, SceneError> {
    match p.param(name)? {
        None => Ok(Rgb::splat(default)),
        Some(Param::Constant(c)) => Ok(c),
        Some(Param::Texture(t)) => {
            textures.push(SlotTexture { slot, texture: t });
            let (texture, mean) = (p.texture(t), p.texture(t).mean());
            // the range the caller checks (`refl`, `alpha`), said here with the image it comes from
            let (fits, range) = match slot.is_monochrome() {
                true => (mean.is_finite() && mean >= 0.0, "a non-negative number"),
                false => (mean.is_finite() && (0.0..=1.0).contains(&mean), "in [0, 1]"),
            };
            if !fits {
                let from = texture.image_files().map_or(String::new(), |f| format!(" (image {f})"));
                return Err(p.err(name, &format!("{name} must be {range}, got its texture's mean {mean}{from}")));
            }
            Ok(Rgb::splat(mean))
        }
    }
}

/// A reflectance: finite and in [0, 1] per channel.
pub(super) fn refl(p: &impl Params, c: Rgb, name: &str) -> Result<Rgb, SceneError> {
    if !c.is_finite() || c.min_element() < 0.0 || c.max_element() > 1.0 {
        return Err(p.err(name, &format!("reflectance must be in [0, 1], got {:?}", c.to_array())));
    }
    Ok(c)
}

/// Smooth conductor: the plain mirror for the preset `none` without textures (F = 1 exactly),
/// else the conductor Fresnel term.
fn conductor(p: &mut impl Params, textures: &mut Vec<SlotTexture>) -> Result<Material, SceneError> {
    let (spec, eta, k) = conductor_params(p, textures)?;
    if eta == Rgb::ZERO && k == Rgb::ONE && textures.is_empty() {
        return Ok(Material::Mirror { reflectance: spec });
    }
    Ok(Material::Conductor { reflectance: spec, eta, k })
}

/// `roughconductor`: the smooth conductor's parameters and a microfacet distribution.
fn roughconductor(p: &mut impl Params, textures: &mut Vec<SlotTexture>) -> Result<Material, SceneError> {
    let (specular_reflectance, eta, k) = conductor_params(p, textures)?;
    let distribution = distribution(p, textures)?;
    Ok(Material::RoughConductor(RoughConductor { distribution, eta, k, specular_reflectance }))
}

/// A conductor's (`specular_reflectance`, η, k): `material` preset (default `none`) or explicit
/// `eta`/`k`, both relative to `ext_eta` (default 1).
fn conductor_params(p: &mut impl Params, textures: &mut Vec<SlotTexture>) -> Result<(Rgb, Rgb, Rgb), SceneError> {
    let spec = colour(p, "specular_reflectance", 1.0, Slot::SpecularReflectance, textures)?;
    let spec = refl(p, spec, "specular_reflectance")?;
    let name = p.string("material")?.unwrap_or_else(|| "none".into());
    let Some((e, k)) = presets::conductor(&name) else {
        return Err(p.err("material", &format!("unknown conductor preset `{name}`")));
    };
    let eta = p.color("eta")?.unwrap_or(Rgb::from_array(e));
    let k = p.color("k")?.unwrap_or(Rgb::from_array(k));
    let ext = p.float("ext_eta")?.unwrap_or(1.0);
    for (key, v) in [("eta", eta), ("k", k)] {
        if !(v.is_finite() && v.min_element() >= 0.0) {
            return Err(p.err(key, &format!("{key} must be finite and non-negative, got {:?}", v.to_array())));
        }
    }
    if !(ext.is_finite() && ext > 0.0) {
        return Err(p.err("ext_eta", &format!("ext_eta must be positive, got {ext}")));
    }
    Ok((spec, eta / ext, k / ext))
}

/// Smooth `dielectric`: η = int_ior/ext_ior; its tints must be the default 1 (lossless glass).
fn dielectric(p: &mut impl Params) -> Result<Material, SceneError> {
    let int = ior(p, "int_ior", DIELECTRIC_INT_IOR)?;
    let ext = ior(p, "ext_ior", EXT_IOR)?;
    for k in ["specular_reflectance", "specular_transmittance"] {
        if p.color(k)?.is_some_and(|c| c != Rgb::ONE) {
            return Err(p.err(k, "only the default 1 is supported (lossless glass)"));
        }
    }
    Ok(Material::Glass { ior: eta(p, int, ext)? })
}

/// `thindielectric`: η = int_ior/ext_ior and its tints.
fn thindielectric(p: &mut impl Params, textures: &mut Vec<SlotTexture>) -> Result<Material, SceneError> {
    let int = ior(p, "int_ior", DIELECTRIC_INT_IOR)?;
    let ext = ior(p, "ext_ior", EXT_IOR)?;
    let eta = eta(p, int, ext)?;
    let r = colour(p, "specular_reflectance", 1.0, Slot::SpecularReflectance, textures)?;
    let t = colour(p, "specular_transmittance", 1.0, Slot::SpecularTransmittance, textures)?;
    let (r, t) = (refl(p, r, "specular_reflectance")?, refl(p, t, "specular_transmittance")?);
    Ok(Material::ThinDielectric(ThinDielectric::new(eta, r, t)))
}

/// `roughdielectric`: η = int_ior/ext_ior, its tints and a microfacet distribution.
fn roughdielectric(p: &mut impl Params, textures: &mut Vec<SlotTexture>) -> Result<Material, SceneError> {
    let int = ior(p, "int_ior", DIELECTRIC_INT_IOR)?;
    let ext = ior(p, "ext_ior", EXT_IOR)?;
    eta(p, int, ext)?;
    let r = colour(p, "specular_reflectance", 1.0, Slot::SpecularReflectance, textures)?;
    let t = colour(p, "specular_transmittance", 1.0, Slot::SpecularTransmittance, textures)?;
    let distribution = distribution(p, textures)?;
    let mut d = RoughDielectric::new(distribution, int, ext);
    d.specular_reflectance = refl(p, r, "specular_reflectance")?;
    d.specular_transmittance = refl(p, t, "specular_transmittance")?;
    Ok(Material::RoughDielectric(d))
}

/// The parameters `plastic` and `roughplastic` share: a coat of η = int_ior/ext_ior over a base
/// of `diffuse_reflectance` with `specular_reflectance` and `nonlinear`.
struct Coat {
    diffuse: Rgb,
    specular: Rgb,
    eta: f32,
    nonlinear: bool,
}

fn coat(p: &mut impl Params, textures: &mut Vec<SlotTexture>) -> Result<Coat, SceneError> {
    let d = colour(p, "diffuse_reflectance", 0.5, Slot::DiffuseReflectance, textures)?;
    let s = colour(p, "specular_reflectance", 1.0, Slot::SpecularReflectance, textures)?;
    let int = ior(p, "int_ior", PLASTIC_INT_IOR)?;
    let ext = ior(p, "ext_ior", EXT_IOR)?;
    let eta = eta(p, int, ext)?;
    let nonlinear = p.boolean("nonlinear")?.unwrap_or(false);
    let (diffuse, specular) = (refl(p, d, "diffuse_reflectance")?, refl(p, s, "specular_reflectance")?);
    Ok(Coat { diffuse, specular, eta, nonlinear })
}

/// `roughplastic`: the plastic's parameters under an isotropic microfacet coat (`alpha` a
/// number, as Mitsuba reads it; η ≠ 1, which Mitsuba requires).
fn roughplastic(p: &mut impl Params, textures: &mut Vec<SlotTexture>) -> Result<Material, SceneError> {
    let c = coat(p, textures)?;
    if c.eta == 1.0 {
        return Err(p.err("int_ior", "int_ior and ext_ior must differ"));
    }
    let n = textures.len();
    let d = distribution(p, textures)?;
    if textures.len() > n {
        return Err(p.err("alpha", "roughplastic's alpha is a number, not a texture"));
    }
    if d.alpha_u != d.alpha_v {
        return Err(p.err("alpha_u", "roughplastic does not support anisotropic roughness"));
    }
    let rp = RoughPlastic::new(c.diffuse, c.specular, c.eta, c.nonlinear, d.kind, d.alpha_u, d.sample_visible);
    Ok(Material::RoughPlastic(rp))
}

/// Mitsuba's microfacet parameters: `distribution` (`beckmann`, default, or `ggx`), `alpha`
/// (default 0.1; a texture sets it per point) or `alpha_u` and `alpha_v`, `sample_visible`
/// (default true).
fn distribution(p: &mut impl Params, textures: &mut Vec<SlotTexture>) -> Result<MicrofacetDistribution, SceneError> {
    let kind = match p.string("distribution")?.as_deref() {
        None | Some("beckmann") => MicrofacetKind::Beckmann,
        Some("ggx") => MicrofacetKind::Ggx,
        Some(s) => return Err(p.err("distribution", &format!("`{s}`: use beckmann or ggx"))),
    };
    let visible = p.boolean("sample_visible")?.unwrap_or(true);
    if p.has("alpha_u") || p.has("alpha_v") {
        let (au, av) = (alpha(p, "alpha_u", textures)?, alpha(p, "alpha_v", textures)?);
        if textures.iter().any(|t| t.slot == Slot::Alpha) {
            return Err(p.err("alpha_u", "textured anisotropic roughness is not supported"));
        }
        return Ok(MicrofacetDistribution::new(kind, au, av, visible));
    }
    let a = alpha(p, "alpha", textures)?;
    Ok(MicrofacetDistribution::isotropic(kind, a, visible))
}

/// A roughness parameter (default 0.1): a non-negative number, or a texture's mean.
fn alpha(p: &mut impl Params, name: &str, textures: &mut Vec<SlotTexture>) -> Result<f32, SceneError> {
    let a = colour(p, name, 0.1, Slot::Alpha, textures)?.x;
    if !(a.is_finite() && a >= 0.0) {
        return Err(p.err(name, &format!("{a} must be a non-negative number")));
    }
    Ok(a)
}

/// The relative index η = int_ior/ext_ior, in (0, 10].
fn eta(p: &impl Params, int: f32, ext: f32) -> Result<f32, SceneError> {
    let eta = int / ext;
    if !(eta.is_finite() && eta > 0.0 && eta <= 10.0) {
        return Err(p.err("int_ior", &format!("int_ior/ext_ior = {eta} must be in (0, 10]")));
    }
    Ok(eta)
}

/// An IOR given as a positive number or a preset name (default `default`).
fn ior(p: &mut impl Params, name: &str, default: f32) -> Result<f32, SceneError> {
    let Some(v) = p.ior_value(name)? else { return Ok(default) };
    let x = match v.number {
        Some(x) => Some(x).filter(|x| x.is_finite() && *x > 0.0),
        None => presets::dielectric_ior(&v.text),
    };
    let text = v.text;
    x.ok_or_else(|| p.err(name, &format!("`{text}` is neither a positive number nor a known IOR preset")))
}

/// A `bitmap` texture: the image decoded once per file and `raw` flag (`cache`), the file recorded
/// as an input of the scene. The error names the image file and what is wrong with it.
pub(super) fn bitmap(b: &mut SceneBuilder, cache: &mut TextureCache, params: &BitmapParams) -> Result<Texture, String> {
    let t = cache.bitmap(params).map_err(|e| e.to_string())?;
    b.image_file(&params.filename);
    Ok(Texture::Bitmap(t))
}
