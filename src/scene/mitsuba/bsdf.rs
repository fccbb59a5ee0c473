//! Mitsuba BSDF plugins → `Material` and `Surface`: `diffuse` → Diffuse, smooth `conductor` →
//! Mirror (preset `none`) or Conductor (η, k), `dielectric` → Glass with η = int_ior/ext_ior,
//! 0.6's `phong` → Glossy (the same energy-conserving modified Phong), `twosided` around any of
//! the reflective ones, `normalmap` and `bumpmap` (a nested height texture and `scale`) around
//! any BSDF, inside or around `twosided` (the two orders differ from behind:
//! `scene::surface`). As in Mitsuba, a BSDF not wrapped in
//! `twosided` is black from behind (`scene::Surface`); the dielectric scatters from both sides.
//! Reflectances may be textures (`super::texture`). `ref`/`id` resolve through `Cx::ids`. The
//! plugins themselves (defaults, presets, checks) are built by `scene::plugins`, which the TOML
//! reader shares; this file reads their XML and wraps them.
//!
//! Invariants: anything else (`twosided` with two different sides, a map in a map, a bump map
//! without exactly one texture or with a `checkerboard`, `flip_invalid_normals` or
//! `use_shadowing_function` false) is an error naming the file, line, plugin and parameter;
//! constant reflectances in [0, 1].

use super::params::Plugin;
use super::texture::Param;
use super::xml::Node;
use super::Cx;
use crate::math::Rgb;
use crate::scene::plugins;
use crate::scene::{BumpMap, Material, SceneError, Surface};
use crate::texture::Texture;

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

/// Mitsuba's `bumpmap`: its one nested BSDF and its one nested height texture, each taken by its
/// type whatever its name (a `<ref>` by the kind of object its id names), `scale` (default 1),
/// `flip_invalid_normals` and `use_shadowing_function` at their default, true. The texture must
/// have Mitsuba's `eval_1_grad` (a `bitmap`; a constant's is zero; not a `checkerboard`).
fn bumpmap(cx: &mut Cx, mut p: Plugin) -> Result<Parsed, SceneError> {
    let node = p.node;
    let id = |c: &Node| c.attr("id").unwrap_or("").to_string();
    let is_bsdf = |cx: &Cx, c: &Node| c.tag == "bsdf" || (c.tag == "ref" && !cx.texture_ids.contains_key(&id(c)));
    let is_texture = |cx: &Cx, c: &Node| {
        c.tag == "texture"
            || (c.tag == "ref" && !is_bsdf(cx, c))
            || (matches!(c.tag.as_str(), "spectrum" | "rgb") && c.attr("type").is_some())
    };
    let bsdfs: Vec<&Node> = node.children.iter().filter(|c| is_bsdf(cx, c)).collect();
    let heights: Vec<&Node> = node.children.iter().filter(|c| is_texture(cx, c)).collect();
    if bsdfs.len() != 1 {
        return Err(p.err(cx, node.line, "bsdf", "needs exactly one nested BSDF"));
    }
    if heights.len() != 1 {
        let msg = "needs exactly one nested texture, the height map (Mitsuba 2's `filename` form is not read)";
        return Err(p.err(cx, node.line, "texture", msg));
    }
    p.objects(&["bsdf", "texture", "ref"]);
    let h = heights[0];
    if h.tag != "texture" && h.tag != "ref" {
        p.find(h.name());
    }
    // the texture alone under its name (or `texture`), so that `texture::param` reads it
    let name = if h.name().is_empty() { "texture" } else { h.name() };
    let mut attrs: Vec<(String, String)> = h.attrs.iter().filter(|(k, _)| k != "name").cloned().collect();
    attrs.push(("name".into(), name.into()));
    let holder = Node {
        tag: node.tag.clone(),
        attrs: vec![("type".into(), "bumpmap".into())],
        line: node.line,
        children: vec![Node { attrs, ..h.clone() }],
    };
    let t = match super::texture::param(cx, &mut Plugin::new(&holder), name)? {
        Some(Param::Texture(t)) => t,
        Some(Param::Constant(c)) => cx.b.texture(Texture::Constant(c)),
        None => return Err(p.err(cx, h.line, name, "the height map is not a texture")),
    };
    if !cx.b.texture_at(t).has_eval_1_grad() {
        let msg = "Mitsuba's `checkerboard` has no gradient (`eval_1_grad`): a bump map's height must be a `bitmap`";
        return Err(p.err(cx, h.line, name, msg));
    }
    let scale = p.float(cx, "scale")?.unwrap_or(1.0);
    for k in ["flip_invalid_normals", "use_shadowing_function"] {
        if p.boolean(cx, k)? == Some(false) {
            return Err(p.err(cx, p.line_of(k), k, "only Mitsuba's default, true, is supported"));
        }
    }
    let inner = material(cx, bsdfs[0])?;
    if inner.surface.has_map() {
        let msg = "a `bumpmap` around a `normalmap` or `bumpmap` is not supported";
        return Err(p.err(cx, bsdfs[0].line, "bsdf", msg));
    }
    p.finish(cx);
    let bump = BumpMap { texture: t, scale };
    Ok(Parsed { surface: Surface { bumpmap: Some(bump), map_in_twosided: false, ..inner.surface }, ..inner })
}

/// Mitsuba 2's `normalmap` as the Specular Manifold Sampling repository's fork defines it
/// (`src/bsdfs/normalmap.cpp` there): the image a `filename` child (the texels' 2·rgb − 1, raw),
/// `tiles` (default 1: uv·tiles, repeated), `use_slopes` (default true: the texels' slopes
/// −n_xy/n_z interpolated bilinearly instead of the normals), `lean_fallback` (default false: a
/// LEAN-mapped conductor on paths without ray differentials) and its `lean_fallback_alpha`,
/// `lean_fallback_material`, `eta`, `k`. Read as Mitsuba 3's `normalmap` around a raw `bitmap`
/// with `to_uv` scale `tiles` (what `scenes/external/*/scene.xml` write by hand). Differences,
/// named in one warning: Mitsuba 3 (so forecast) interpolates normals, not slopes (within a
/// texel), applies its shadowing term and flips invalid normals, which Mitsuba 2's plugin does
/// not, and repeats the map across a tile's edge where Mitsuba 2 clamps (half a texel at the
/// edge). `lean_fallback` true (another BSDF) is an error.
fn mitsuba2_normalmap(cx: &mut Cx, mut p: Plugin, inner: Parsed) -> Result<Parsed, SceneError> {
    let node = p.node;
    let Some((file, fl)) = p.string(cx, "filename")? else { unreachable!("called with a `filename`") };
    let tiles = p.float(cx, "tiles")?.unwrap_or(1.0);
    if !(tiles.is_finite() && tiles > 0.0) {
        return Err(p.err(cx, p.line_of("tiles"), "tiles", format!("tiles {tiles} must be positive")));
    }
    let slopes = p.boolean(cx, "use_slopes")?.unwrap_or(true);
    if p.boolean(cx, "lean_fallback")? == Some(true) {
        let msg = "lean_fallback true (Mitsuba 2's LEAN-mapped conductor on secondary paths) is not supported";
        return Err(p.err(cx, p.line_of("lean_fallback"), "lean_fallback", msg));
    }
    for k in ["lean_fallback_alpha", "lean_fallback_material", "eta", "k"] {
        p.find(k); // only read with lean_fallback
    }
    if p.node.children.iter().any(|c| c.name() == "normalmap") {
        let msg = "both a `filename` (Mitsuba 2) and a `normalmap` texture (Mitsuba 3): give one";
        return Err(p.err(cx, p.line_of("normalmap"), "normalmap", msg));
    }
    let at = |tag: &str, attrs: &[(&str, &str)], children: Vec<Node>| Node {
        tag: tag.into(),
        attrs: attrs.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect(),
        line: fl,
        children,
    };
    let t = tiles.to_string();
    let bitmap = at(
        "texture",
        &[("name", "normalmap"), ("type", "bitmap")],
        vec![
            at("string", &[("name", "filename"), ("value", &file)], vec![]),
            at("boolean", &[("name", "raw"), ("value", "true")], vec![]),
            at("transform", &[("name", "to_uv")], vec![at("scale", &[("x", &t), ("y", &t)], vec![])]),
        ],
    );
    let holder = Node { tag: node.tag.clone(), attrs: node.attrs.clone(), line: node.line, children: vec![bitmap] };
    let Some(Param::Texture(tex)) = super::texture::param(cx, &mut Plugin::new(&holder), "normalmap")? else {
        unreachable!("a bitmap is a texture")
    };
    let slope_note = if slopes { "interpolates the normals, not the slopes (use_slopes), " } else { "" };
    let m = format!(
        "bsdf `normalmap`: Mitsuba 2's form (`filename`) read as Mitsuba 3's normalmap around a raw bitmap; \
         forecast {slope_note}applies Mitsuba 3's shadowing term and flip of invalid normals, and repeats the map \
         across a tile's edge (Mitsuba 2's plugin clamps)"
    );
    cx.warn(node.line, m);
    p.finish(cx);
    Ok(Parsed { surface: Surface { normalmap: Some(tex), ..inner.surface }, ..inner })
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
            // a map inside `twosided` sees the back mirrored (scene::surface's docs)
            let map_in_twosided = inner.surface.has_map();
            return Ok(Parsed { surface: Surface { two_sided: true, map_in_twosided, ..inner.surface }, ..inner });
        }
        "bumpmap" => return bumpmap(cx, p),
        "normalmap" => {
            let inner = nested(cx, &mut p)?;
            if inner.surface.has_map() {
                let msg = "a `normalmap` around a `normalmap` or `bumpmap` is not supported";
                return Err(p.err(cx, p.line_of("bsdf"), "bsdf", msg));
            }
            if p.node.children.iter().any(|c| c.name() == "filename") {
                return mitsuba2_normalmap(cx, p, inner);
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
        "phong" => {
            let a = p.color(cx, "diffuse_reflectance")?.unwrap_or(Rgb::splat(0.5));
            let a = plugins::refl(&Xml { cx, p: &mut p }, a, "diffuse_reflectance")?;
            let s = p.color(cx, "specular_reflectance")?.unwrap_or(Rgb::splat(0.2));
            let s = plugins::refl(&Xml { cx, p: &mut p }, s, "specular_reflectance")?;
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
            let Some(built) = plugins::plugin(&mut Xml { cx, p: &mut p }, t)? else {
                let why = "supported: diffuse, conductor, roughconductor, dielectric, roughdielectric, \
                           thindielectric, plastic, roughplastic, twosided, normalmap, bumpmap, phong";
                return Err(cx.err(n.line, &format!("bsdf.{t}"), format!("bsdf `{t}` is not supported ({why})")));
            };
            textures = built.textures;
            built.m
        }
    };
    p.finish(cx);
    // Mitsuba's BSDFs scatter from the front only, unless wrapped in `twosided`
    Ok(Parsed { m, surface: Surface { textures, ..Surface::one_sided(&m) } })
}

/// A plugin element as `plugins::Params`: its parameters by name (marked read), an error at the
/// parameter's line (key `PLUGIN.NAME`, "bsdf `PLUGIN`: ...").
struct Xml<'a, 'n> {
    cx: &'a mut Cx,
    p: &'a mut Plugin<'n>,
}

impl plugins::Params for Xml<'_, '_> {
    fn has(&self, name: &str) -> bool {
        self.p.node.children.iter().any(|c| c.name() == name)
    }
    fn param(&mut self, name: &str) -> Result<Option<Param>, SceneError> {
        super::texture::param(self.cx, self.p, name)
    }
    fn color(&mut self, name: &str) -> Result<Option<Rgb>, SceneError> {
        self.p.color(self.cx, name)
    }
    fn float(&mut self, name: &str) -> Result<Option<f32>, SceneError> {
        self.p.float(self.cx, name)
    }
    fn boolean(&mut self, name: &str) -> Result<Option<bool>, SceneError> {
        self.p.boolean(self.cx, name)
    }
    fn string(&mut self, name: &str) -> Result<Option<String>, SceneError> {
        Ok(self.p.string(self.cx, name)?.map(|(s, _)| s))
    }
    fn ior_value(&mut self, name: &str) -> Result<Option<plugins::IorValue>, SceneError> {
        let Some(n) = self.p.find(name) else { return Ok(None) };
        let text = n.attr("value").unwrap_or("").to_string();
        let number = if n.tag == "float" { Some(text.trim().parse::<f32>().unwrap_or(f32::NAN)) } else { None };
        // a `<string>` names a preset; any other element is refused with its value
        let text = if n.tag == "float" || n.tag == "string" { text } else { format!("<{}> {text}", n.tag) };
        Ok(Some(plugins::IorValue { number, text }))
    }
    fn err(&self, name: &str, message: &str) -> SceneError {
        self.p.err(self.cx, self.p.line_of(name), name, message)
    }
    fn texture(&self, t: u32) -> &Texture {
        self.cx.b.texture_at(t)
    }
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
