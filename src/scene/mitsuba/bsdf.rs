//! Mitsuba BSDF plugins → `Material` and `Surface`: `diffuse` → Diffuse, smooth `conductor` →
//! Mirror (preset `none`) or Conductor (η, k), `dielectric` → Glass with η = int_ior/ext_ior,
//! 0.6's `phong` → Glossy (the same energy-conserving modified Phong), `twosided` around any of
//! the reflective ones, `normalmap` around any BSDF. As in Mitsuba, a BSDF not wrapped in
//! `twosided` is black from behind (`scene::Surface`); the dielectric scatters from both sides.
//! Reflectances may be textures (`super::texture`). `ref`/`id` resolve through `Cx::ids`.
//!
//! Invariants: anything else (`twosided` with two different sides, a `normalmap` in a
//! `normalmap`) is an error naming the file, line, plugin and parameter; constant reflectances in
//! [0, 1].

use super::params::Plugin;
use super::presets;
use super::texture::Param;
use super::xml::Node;
use super::Cx;
use crate::bsdf::microfacet::{MicrofacetDistribution, MicrofacetKind};
use crate::bsdf::plastic::Plastic;
use crate::bsdf::roughconductor::RoughConductor;
use crate::bsdf::roughdielectric::RoughDielectric;
use crate::bsdf::roughplastic::RoughPlastic;
use crate::bsdf::thindielectric::ThinDielectric;
use crate::bsdf::Slot;
use crate::math::Rgb;
use crate::scene::{Material, SceneError, SlotTexture, Surface};

/// The material index of a `<bsdf>` or `<ref>` element (registering inline BSDFs and ids).
pub(super) fn resolve(cx: &mut Cx, n: &Node) -> Result<u32, SceneError> {
    if n.tag == "ref" {
        let id = n.attr("id").unwrap_or("");
        return cx.ids.get(id).copied().ok_or_else(|| {
            cx.err(n.line, &format!("ref.{id}"), format!("`<ref id=\"{id}\">` names no BSDF defined before it"))
        });
    }
    let Parsed { m, surface } = material(cx, n)?;
    let idx = cx.b.material_with(m, surface);
    if let Some(id) = n.attr("id") {
        cx.ids.insert(id.to_string(), idx);
    }
    Ok(idx)
}

/// A parsed `<bsdf>`: its parameters (a textured one at the texture's mean) and its surface.
pub(super) struct Parsed {
    /// The material.
    pub m: Material,
    /// Its sides, textures and normal map.
    pub surface: Surface,
}

/// The one nested BSDF of a wrapper plugin (`twosided`, `normalmap`).
fn nested(cx: &mut Cx, p: &mut Plugin) -> Result<Parsed, SceneError> {
    let kids = p.objects(&["bsdf", "ref"]);
    if kids.len() != 1 {
        let msg = "exactly one nested BSDF is supported (different front and back sides are not)";
        return Err(p.err(cx, p.node.line, "bsdf", msg));
    }
    material(cx, kids[0])
}

/// Parses one `<bsdf>` into a material and its surface (not registered).
pub(super) fn material(cx: &mut Cx, n: &Node) -> Result<Parsed, SceneError> {
    if n.tag == "ref" {
        let i = resolve(cx, n)?;
        return Ok(Parsed { m: cx.b.material_at(i), surface: cx.b.surface_at(i).clone() });
    }
    let mut p = Plugin::new(n);
    let mut textures = Vec::new();
    let m = match n.ty() {
        "twosided" => {
            let inner = nested(cx, &mut p)?;
            if inner.m.is_two_sided_by_nature() {
                let msg = "`twosided` around `dielectric` is not a valid BSDF";
                return Err(p.err(cx, p.line_of("bsdf"), "bsdf", msg));
            }
            p.finish(cx);
            return Ok(Parsed { surface: Surface { two_sided: true, ..inner.surface }, ..inner });
        }
        "normalmap" => {
            let inner = nested(cx, &mut p)?;
            if inner.surface.normalmap.is_some() {
                return Err(p.err(cx, p.line_of("bsdf"), "bsdf", "a `normalmap` inside a `normalmap`"));
            }
            let line = p.line_of("normalmap");
            let Some(Param::Texture(t)) = super::texture::param(cx, &mut p, "normalmap")? else {
                return Err(p.err(cx, line, "normalmap", "needs a `normalmap` texture (a `bitmap` with `raw` true)"));
            };
            for k in ["flip_invalid_normals", "use_shadowing_function"] {
                if p.boolean(cx, k)? == Some(false) {
                    return Err(p.err(cx, p.line_of(k), k, "only Mitsuba's default, true, is supported"));
                }
            }
            p.finish(cx);
            return Ok(Parsed { surface: Surface { normalmap: Some(t), ..inner.surface }, ..inner });
        }
        "diffuse" => {
            let c = colour(cx, &mut p, "reflectance", 0.5, Slot::Reflectance, &mut textures)?;
            Material::Diffuse { albedo: refl(cx, &p, c, "reflectance")? }
        }
        "conductor" => conductor(cx, &mut p, &mut textures)?,
        "roughconductor" => roughconductor(cx, &mut p, &mut textures)?,
        "roughdielectric" => roughdielectric(cx, &mut p, &mut textures)?,
        "dielectric" => {
            let int = ior(cx, &mut p, "int_ior", 1.5046)?;
            let ext = ior(cx, &mut p, "ext_ior", 1.000277)?;
            for k in ["specular_reflectance", "specular_transmittance"] {
                if p.color(cx, k)?.is_some_and(|c| c != Rgb::ONE) {
                    return Err(p.err(cx, n.line, k, "only the default 1 is supported (lossless glass)"));
                }
            }
            Material::Glass { ior: eta(cx, &p, int, ext)? }
        }
        "thindielectric" => {
            let int = ior(cx, &mut p, "int_ior", 1.5046)?;
            let ext = ior(cx, &mut p, "ext_ior", 1.000277)?;
            let eta = eta(cx, &p, int, ext)?;
            let r = colour(cx, &mut p, "specular_reflectance", 1.0, Slot::SpecularReflectance, &mut textures)?;
            let t = colour(cx, &mut p, "specular_transmittance", 1.0, Slot::SpecularTransmittance, &mut textures)?;
            Material::ThinDielectric(ThinDielectric::new(
                eta,
                refl(cx, &p, r, "specular_reflectance")?,
                refl(cx, &p, t, "specular_transmittance")?,
            ))
        }
        "plastic" => {
            let c = coat(cx, &mut p, &mut textures)?;
            Material::Plastic(Plastic::new(c.diffuse, c.specular, c.eta, c.nonlinear))
        }
        "roughplastic" => roughplastic(cx, &mut p, &mut textures)?,
        "phong" => {
            let a = p.color(cx, "diffuse_reflectance")?.unwrap_or(Rgb::splat(0.5));
            let a = refl(cx, &p, a, "diffuse_reflectance")?;
            let s = p.color(cx, "specular_reflectance")?.unwrap_or(Rgb::splat(0.2));
            let s = refl(cx, &p, s, "specular_reflectance")?;
            let e = p.float(cx, "exponent")?.unwrap_or(30.0);
            if (a + s).max_element() > 1.0 + 1e-6 {
                return Err(phong_sum(cx, &p, a, s));
            }
            if !(0.0..=1e6).contains(&e) {
                return Err(p.err(cx, p.line_of("exponent"), "exponent", format!("exponent {e} must be in [0, 1e6]")));
            }
            Material::Glossy { albedo: a, specular: s, exponent: e }
        }
        t => {
            let why = "supported: diffuse, conductor, roughconductor, dielectric, roughdielectric, thindielectric, \
                       plastic, roughplastic, twosided, normalmap, phong";
            return Err(cx.err(n.line, &format!("bsdf.{t}"), format!("bsdf `{t}` is not supported ({why})")));
        }
    };
    p.finish(cx);
    // Mitsuba's BSDFs scatter from the front only, unless wrapped in `twosided`
    Ok(Parsed { m, surface: Surface { textures, ..Surface::one_sided(&m) } })
}

/// A colour parameter (default `default`) that may be a texture: a texture is recorded for
/// `slot` in `textures`, and the value returned is its mean (what is known of it at load).
fn colour(
    cx: &mut Cx,
    p: &mut Plugin,
    name: &str,
    default: f32,
    slot: Slot,
    textures: &mut Vec<SlotTexture>,
) -> Result<Rgb, SceneError> {
    match super::texture::param(cx, p, name)? {
        None => Ok(Rgb::splat(default)),
        Some(Param::Constant(c)) => Ok(c),
        Some(Param::Texture(t)) => {
            textures.push(SlotTexture { slot, texture: t });
            Ok(Rgb::splat(cx.b.texture_at(t).mean()))
        }
    }
}

/// Smooth conductor: `material` preset (default `none`) or explicit `eta`/`k`, times
/// `specular_reflectance`; η and k are relative to `ext_eta` (default 1).
fn conductor(cx: &mut Cx, p: &mut Plugin, textures: &mut Vec<SlotTexture>) -> Result<Material, SceneError> {
    let (spec, eta, k) = conductor_params(cx, p, textures)?;
    if eta == Rgb::ZERO && k == Rgb::ONE && textures.is_empty() {
        return Ok(Material::Mirror { reflectance: spec }); // F = 1 exactly
    }
    Ok(Material::Conductor { reflectance: spec, eta, k })
}

/// `roughconductor`: the smooth conductor's parameters and a microfacet distribution.
fn roughconductor(cx: &mut Cx, p: &mut Plugin, textures: &mut Vec<SlotTexture>) -> Result<Material, SceneError> {
    let (specular_reflectance, eta, k) = conductor_params(cx, p, textures)?;
    let distribution = distribution(cx, p, textures)?;
    Ok(Material::RoughConductor(RoughConductor { distribution, eta, k, specular_reflectance }))
}

/// `roughdielectric`: η = int_ior/ext_ior, its tints and a microfacet distribution.
fn roughdielectric(cx: &mut Cx, p: &mut Plugin, textures: &mut Vec<SlotTexture>) -> Result<Material, SceneError> {
    let int = ior(cx, p, "int_ior", 1.5046)?;
    let ext = ior(cx, p, "ext_ior", 1.000277)?;
    eta(cx, p, int, ext)?;
    let r = colour(cx, p, "specular_reflectance", 1.0, Slot::SpecularReflectance, textures)?;
    let t = colour(cx, p, "specular_transmittance", 1.0, Slot::SpecularTransmittance, textures)?;
    let distribution = distribution(cx, p, textures)?;
    let mut d = RoughDielectric::new(distribution, int, ext);
    d.specular_reflectance = refl(cx, p, r, "specular_reflectance")?;
    d.specular_transmittance = refl(cx, p, t, "specular_transmittance")?;
    Ok(Material::RoughDielectric(d))
}

/// The parameters `plastic` and `roughplastic` share: a coat of η = int_ior/ext_ior (defaults
/// 1.49, 1.000277) over a base of `diffuse_reflectance` (default 0.5) with
/// `specular_reflectance` (default 1) and `nonlinear` (default false).
struct Coat {
    diffuse: Rgb,
    specular: Rgb,
    eta: f32,
    nonlinear: bool,
}

fn coat(cx: &mut Cx, p: &mut Plugin, textures: &mut Vec<SlotTexture>) -> Result<Coat, SceneError> {
    let d = colour(cx, p, "diffuse_reflectance", 0.5, Slot::DiffuseReflectance, textures)?;
    let s = colour(cx, p, "specular_reflectance", 1.0, Slot::SpecularReflectance, textures)?;
    let int = ior(cx, p, "int_ior", 1.49)?;
    let ext = ior(cx, p, "ext_ior", 1.000277)?;
    let eta = eta(cx, p, int, ext)?;
    let nonlinear = p.boolean(cx, "nonlinear")?.unwrap_or(false);
    let (diffuse, specular) = (refl(cx, p, d, "diffuse_reflectance")?, refl(cx, p, s, "specular_reflectance")?);
    Ok(Coat { diffuse, specular, eta, nonlinear })
}

/// `roughplastic`: the plastic's parameters under an isotropic microfacet coat (`alpha` a
/// number, as Mitsuba reads it; η ≠ 1, which Mitsuba requires).
fn roughplastic(cx: &mut Cx, p: &mut Plugin, textures: &mut Vec<SlotTexture>) -> Result<Material, SceneError> {
    let c = coat(cx, p, textures)?;
    if c.eta == 1.0 {
        return Err(p.err(cx, p.line_of("int_ior"), "int_ior", "int_ior and ext_ior must differ"));
    }
    let n = textures.len();
    let d = distribution(cx, p, textures)?;
    if textures.len() > n {
        return Err(p.err(cx, p.line_of("alpha"), "alpha", "roughplastic's alpha is a number, not a texture"));
    }
    if d.alpha_u != d.alpha_v {
        return Err(p.err(cx, p.line_of("alpha_u"), "alpha_u", "roughplastic does not support anisotropic roughness"));
    }
    let rp = RoughPlastic::new(c.diffuse, c.specular, c.eta, c.nonlinear, d.kind, d.alpha_u, d.sample_visible);
    Ok(Material::RoughPlastic(rp))
}

/// Mitsuba's microfacet parameters: `distribution` (`beckmann`, default, or `ggx`), `alpha`
/// (default 0.1; a texture sets it per point) or `alpha_u` and `alpha_v`, `sample_visible`
/// (default true).
fn distribution(
    cx: &mut Cx,
    p: &mut Plugin,
    textures: &mut Vec<SlotTexture>,
) -> Result<MicrofacetDistribution, SceneError> {
    let kind = match p.string(cx, "distribution")? {
        None => MicrofacetKind::Beckmann,
        Some((s, _)) if s == "beckmann" => MicrofacetKind::Beckmann,
        Some((s, _)) if s == "ggx" => MicrofacetKind::Ggx,
        Some((s, l)) => return Err(p.err(cx, l, "distribution", format!("`{s}`: use beckmann or ggx"))),
    };
    let visible = p.boolean(cx, "sample_visible")?.unwrap_or(true);
    let alpha_at = |cx: &mut Cx, p: &mut Plugin, name: &str, textures: &mut Vec<SlotTexture>| {
        let a = colour(cx, p, name, 0.1, Slot::Alpha, textures)?.x;
        if !(a.is_finite() && a >= 0.0) {
            return Err(p.err(cx, p.line_of(name), name, format!("{a} must be a non-negative number")));
        }
        Ok(a)
    };
    if p.node.children.iter().any(|c| c.name() == "alpha_u" || c.name() == "alpha_v") {
        let (au, av) = (alpha_at(cx, p, "alpha_u", textures)?, alpha_at(cx, p, "alpha_v", textures)?);
        if !textures.iter().all(|t| t.slot != Slot::Alpha) {
            return Err(p.err(cx, p.line_of("alpha_u"), "alpha_u", "textured anisotropic roughness is not supported"));
        }
        return Ok(MicrofacetDistribution::new(kind, au, av, visible));
    }
    let a = alpha_at(cx, p, "alpha", textures)?;
    Ok(MicrofacetDistribution::isotropic(kind, a, visible))
}

/// A conductor's (specular_reflectance, η, k).
fn conductor_params(
    cx: &mut Cx,
    p: &mut Plugin,
    textures: &mut Vec<SlotTexture>,
) -> Result<(Rgb, Rgb, Rgb), SceneError> {
    let line = p.node.line;
    let spec = colour(cx, p, "specular_reflectance", 1.0, Slot::SpecularReflectance, textures)?;
    if spec.min_element() < 0.0 || spec.max_element() > 1.0 {
        return Err(p.err(cx, line, "specular_reflectance", "must be in [0, 1]"));
    }
    let (name, nline) = p.string(cx, "material")?.unwrap_or(("none".into(), line));
    let Some((e, k)) = presets::conductor(&name) else {
        return Err(p.err(cx, nline, "material", format!("unknown conductor preset `{name}`")));
    };
    let eta = p.color(cx, "eta")?.unwrap_or(Rgb::from_array(e));
    let k = p.color(cx, "k")?.unwrap_or(Rgb::from_array(k));
    let ext = p.float(cx, "ext_eta")?.unwrap_or(1.0);
    if eta.min_element() < 0.0 || k.min_element() < 0.0 || ext.is_nan() || ext <= 0.0 {
        return Err(p.err(cx, line, "eta", "eta, k must be non-negative and ext_eta positive"));
    }
    Ok((spec, eta / ext, k / ext))
}

/// The relative index η = int_ior/ext_ior, in (0, 10].
fn eta(cx: &Cx, p: &Plugin, int: f32, ext: f32) -> Result<f32, SceneError> {
    let eta = int / ext;
    if !(eta.is_finite() && eta > 0.0 && eta <= 10.0) {
        return Err(p.err(cx, p.line_of("int_ior"), "int_ior", format!("int_ior/ext_ior = {eta} must be in (0, 10]")));
    }
    Ok(eta)
}

/// An IOR given as a number or a preset name.
fn ior(cx: &Cx, p: &mut Plugin, name: &str, default: f32) -> Result<f32, SceneError> {
    let Some(n) = p.find(name) else { return Ok(default) };
    let v = n.attr("value").unwrap_or("");
    let x = match n.tag.as_str() {
        "float" => v.trim().parse::<f32>().ok().filter(|x| x.is_finite() && *x > 0.0),
        "string" => presets::dielectric_ior(v),
        _ => None,
    };
    x.ok_or_else(|| p.err(cx, n.line, name, format!("`{v}` is neither a positive number nor a known IOR preset")))
}

/// phong's diffuse + specular > 1: the error names the specular reflectance (as the TOML glossy's
/// `specular`) at its line, or the diffuse one when only that is written, and both values.
fn phong_sum(cx: &Cx, p: &Plugin, a: Rgb, s: Rgb) -> SceneError {
    let given = |k: &str| p.node.children.iter().any(|c| c.name() == k);
    let k = if given("specular_reflectance") || !given("diffuse_reflectance") {
        "specular_reflectance"
    } else {
        "diffuse_reflectance"
    };
    let (da, sa) = (a.to_array(), s.to_array());
    let msg = format!(
        "diffuse_reflectance {da:?} (line {}) + specular_reflectance {sa:?} (line {}) must be <= 1 per channel (energy conservation)",
        p.line_of("diffuse_reflectance"),
        p.line_of("specular_reflectance")
    );
    p.err(cx, p.line_of(k), k, msg)
}

fn refl(cx: &Cx, p: &Plugin, c: Rgb, name: &str) -> Result<Rgb, SceneError> {
    if c.min_element() < 0.0 || c.max_element() > 1.0 {
        return Err(p.err(cx, p.line_of(name), name, "reflectance must be in [0, 1]"));
    }
    Ok(c)
}
