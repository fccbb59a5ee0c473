//! Mitsuba BSDF plugins → `Material`: `diffuse` → Diffuse, smooth `conductor` → Mirror (preset
//! `none`) or Conductor (η, k), `dielectric` → Glass with η = int_ior/ext_ior, 0.6's `phong` →
//! Glossy (the same energy-conserving modified Phong), `twosided` around any of the reflective
//! ones. As in Mitsuba, a BSDF not wrapped in `twosided` is black from behind
//! (`scene::Surface`); the dielectric scatters from both sides. `ref`/`id` resolve through
//! `Cx::ids`.
//!
//! Invariants: anything else (rough or layered BSDFs, textures, `twosided` with two different
//! sides) is an error naming the file, line, plugin and parameter; reflectances in [0, 1].

use super::params::Plugin;
use super::presets;
use super::xml::Node;
use super::Cx;
use crate::math::Rgb;
use crate::scene::{Material, SceneError, Surface};

/// The material index of a `<bsdf>` or `<ref>` element (registering inline BSDFs and ids).
pub(super) fn resolve(cx: &mut Cx, n: &Node) -> Result<u32, SceneError> {
    if n.tag == "ref" {
        let id = n.attr("id").unwrap_or("");
        return cx.ids.get(id).copied().ok_or_else(|| {
            cx.err(n.line, &format!("ref.{id}"), format!("`<ref id=\"{id}\">` names no BSDF defined before it"))
        });
    }
    let m = material(cx, n)?;
    // Mitsuba's BSDFs scatter from the front only, unless wrapped in `twosided`
    let s = if n.ty() == "twosided" { Surface::TWO_SIDED } else { Surface::one_sided(&m) };
    let idx = cx.b.material_with(m, s);
    if let Some(id) = n.attr("id") {
        cx.ids.insert(id.to_string(), idx);
    }
    Ok(idx)
}

/// Parses one `<bsdf>` into a material (not registered).
pub(super) fn material(cx: &mut Cx, n: &Node) -> Result<Material, SceneError> {
    if n.tag == "ref" {
        let i = resolve(cx, n)?;
        return Ok(cx.b.material_at(i));
    }
    let mut p = Plugin::new(n);
    let m = match n.ty() {
        "twosided" => {
            let kids = p.objects(&["bsdf", "ref"]);
            if kids.len() != 1 {
                let msg = "exactly one nested BSDF is supported (different front and back sides are not)";
                return Err(p.err(cx, n.line, "bsdf", msg));
            }
            let inner = material(cx, kids[0])?;
            if matches!(inner, Material::Glass { .. }) {
                return Err(p.err(cx, kids[0].line, "bsdf", "`twosided` around `dielectric` is not a valid BSDF"));
            }
            inner
        }
        "diffuse" => {
            let c = p.color(cx, "reflectance")?.unwrap_or(Rgb::splat(0.5));
            Material::Diffuse { albedo: refl(cx, &p, c, "reflectance")? }
        }
        "conductor" => conductor(cx, &mut p)?,
        "dielectric" => {
            let int = ior(cx, &mut p, "int_ior", 1.5046)?;
            let ext = ior(cx, &mut p, "ext_ior", 1.000277)?;
            for k in ["specular_reflectance", "specular_transmittance"] {
                if p.color(cx, k)?.is_some_and(|c| c != Rgb::ONE) {
                    return Err(p.err(cx, n.line, k, "only the default 1 is supported (lossless glass)"));
                }
            }
            let eta = int / ext;
            if !(eta.is_finite() && eta > 0.0 && eta <= 10.0) {
                return Err(p.err(cx, n.line, "int_ior", format!("int_ior/ext_ior = {eta} must be in (0, 10]")));
            }
            Material::Glass { ior: eta }
        }
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
            let why = match t {
                "roughconductor" | "roughdielectric" | "roughplastic" | "plastic" => "rough and layered BSDFs",
                _ => "supported: diffuse, conductor, dielectric, twosided, phong",
            };
            return Err(cx.err(n.line, &format!("bsdf.{t}"), format!("bsdf `{t}` is not supported ({why})")));
        }
    };
    p.finish(cx);
    Ok(m)
}

/// Smooth conductor: `material` preset (default `none`) or explicit `eta`/`k`, times
/// `specular_reflectance`; η and k are relative to `ext_eta` (default 1).
fn conductor(cx: &mut Cx, p: &mut Plugin) -> Result<Material, SceneError> {
    let line = p.node.line;
    let spec = p.color(cx, "specular_reflectance")?.unwrap_or(Rgb::ONE);
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
    if eta == Rgb::ZERO && k == Rgb::ONE {
        return Ok(Material::Mirror { reflectance: spec }); // F = 1 exactly
    }
    Ok(Material::Conductor { reflectance: spec, eta: eta / ext, k: k / ext })
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
