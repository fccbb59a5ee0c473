//! Mitsuba texture plugins → `texture::Texture`: `bitmap` (`filename`, `filter_type`,
//! `wrap_mode`, `raw`, `to_uv`) and `checkerboard` (`color0`, `color1`, `to_uv`), given where a
//! BSDF takes a colour (`<texture name="reflectance" type="bitmap">`, or Mitsuba 2's
//! `<spectrum name="reflectance" type="bitmap">`), or at the top level with an `id` that a
//! `<ref name="reflectance" id="..."/>` names. Each image file is decoded once per `raw` flag
//! (`texture::TextureCache`).
//!
//! Invariants: an image that cannot be read or decoded, or has a NaN, infinite or negative texel,
//! is an error naming the scene file, the line, the parameter and the image file.

use super::params::Plugin;
use super::xml::Node;
use super::Cx;
use crate::math::Rgb;
use crate::scene::SceneError;
use crate::texture::{BitmapParams, Checkerboard, FilterType, Texture, UvTransform, WrapMode};
use std::path::{Path, PathBuf};

/// A BSDF parameter that may be a colour or a texture.
pub(super) use crate::scene::plugins::Param;

/// True for a child element that is a texture plugin rather than a constant.
fn is_texture(n: &Node) -> bool {
    n.tag == "texture" || n.tag == "ref" || (matches!(n.tag.as_str(), "spectrum" | "rgb") && n.attr("type").is_some())
}

/// Parameter `name` of `p`: a constant colour (`Plugin::color`), or a texture.
pub(super) fn param(cx: &mut Cx, p: &mut Plugin, name: &str) -> Result<Option<Param>, SceneError> {
    let Some(n) = p.node.children.iter().find(|c| c.name() == name) else { return Ok(None) };
    if !is_texture(n) {
        return Ok(p.color(cx, name)?.map(Param::Constant));
    }
    let n = p.find(name).expect("the child was found above");
    if n.tag == "ref" {
        let id = n.attr("id").unwrap_or("");
        return cx
            .texture_ids
            .get(id)
            .map(|&t| Some(Param::Texture(t)))
            .ok_or_else(|| p.err(cx, n.line, name, format!("`<ref id=\"{id}\">` names no texture defined before it")));
    }
    let t = texture(cx, n)?;
    Ok(Some(Param::Texture(cx.b.texture(t))))
}

/// A top-level `<texture id="...">`: registered for `<ref>`s.
pub(super) fn declare(cx: &mut Cx, n: &Node) -> Result<(), SceneError> {
    let t = texture(cx, n)?;
    let i = cx.b.texture(t);
    match n.attr("id") {
        Some(id) => {
            cx.texture_ids.insert(id.to_string(), i);
        }
        None => cx.warn(n.line, "a top-level `<texture>` without `id` is never used".into()),
    }
    Ok(())
}

/// One texture element.
fn texture(cx: &mut Cx, n: &Node) -> Result<Texture, SceneError> {
    let mut p = Plugin::new(n);
    let t = match n.ty() {
        "bitmap" => bitmap(cx, &mut p)?,
        "checkerboard" => {
            let c0 = constant_or_texture(cx, &mut p, "color0", 0.4)?;
            let c1 = constant_or_texture(cx, &mut p, "color1", 0.2)?;
            let to_uv = to_uv(cx, &mut p)?;
            Texture::Checkerboard(Checkerboard::new(c0, c1, to_uv))
        }
        t => {
            let msg = format!("texture `{t}` is not supported (bitmap, checkerboard)");
            return Err(cx.err(n.line, &format!("texture.{t}"), msg));
        }
    };
    p.finish(cx);
    Ok(t)
}

/// A checkerboard's colour: a constant or a nested texture.
fn constant_or_texture(cx: &mut Cx, p: &mut Plugin, name: &str, default: f32) -> Result<Texture, SceneError> {
    if let Some(n) = p.node.children.iter().find(|c| c.name() == name && is_texture(c) && c.tag != "ref") {
        p.find(name);
        return texture(cx, n);
    }
    match param(cx, p, name)? {
        None => Ok(Texture::Constant(Rgb::splat(default))),
        Some(Param::Constant(c)) => Ok(Texture::Constant(c)),
        Some(Param::Texture(i)) => Ok(cx.b.texture_at(i).clone()),
    }
}

/// The files (resolved against `dir`) and `raw` flags of the `bitmap` textures anywhere under
/// `node`, in file order, as `bitmap` reads them when they are well formed (a `<string>`
/// `filename`, a `<boolean>` `raw`): what `TextureCache::predecode` decodes ahead. A guess only:
/// `bitmap` reads each one itself and reports its errors.
pub(super) fn bitmap_files(node: &Node, dir: &Path, out: &mut Vec<(PathBuf, bool)>) {
    if node.tag == "texture" && node.ty() == "bitmap" {
        let child = |tag: &str, name: &str| {
            node.children.iter().find(|c| c.tag == tag && c.name() == name).and_then(|c| c.attr("value"))
        };
        if let Some(f) = child("string", "filename") {
            out.push((dir.join(f), child("boolean", "raw").map(str::trim) == Some("true")));
        }
    }
    for c in &node.children {
        bitmap_files(c, dir, out);
    }
}

fn bitmap(cx: &mut Cx, p: &mut Plugin) -> Result<Texture, SceneError> {
    let line = p.node.line;
    let Some((f, fl)) = p.string(cx, "filename")? else {
        return Err(p.err(cx, line, "filename", "missing `filename`"));
    };
    let mut b = BitmapParams::new(cx.dir.join(&f));
    if let Some((v, l)) = p.string(cx, "filter_type")? {
        b.filter_type = FilterType::parse(&v).map_err(|m| p.err(cx, l, "filter_type", m))?;
    }
    if let Some((v, l)) = p.string(cx, "wrap_mode")? {
        b.wrap_mode = WrapMode::parse(&v).map_err(|m| p.err(cx, l, "wrap_mode", m))?;
    }
    b.raw = p.boolean(cx, "raw")?.unwrap_or(false);
    b.to_uv = to_uv(cx, p)?;
    p.reject(cx, &["format", "accel"], "the texture is read as linear RGB with bilinear or nearest filtering")?;
    crate::scene::plugins::bitmap(&mut cx.b, &mut cx.textures, &b).map_err(|e| p.err(cx, fl, "filename", e))
}

/// `to_uv`: the 4×4 `<transform>`'s action on the plane (its upper-left 2×2 block and the first
/// two entries of its last column).
fn to_uv(cx: &mut Cx, p: &mut Plugin) -> Result<UvTransform, SceneError> {
    let Some(x) = p.transform(cx, "to_uv")? else { return Ok(UvTransform::IDENTITY) };
    let m = x.m.as_mat4();
    let (c0, c1, c3) = (m.x_axis, m.y_axis, m.w_axis);
    Ok(UvTransform::from_matrix([[c0.x, c1.x, c3.x], [c0.y, c1.y, c3.y], [0.0, 0.0, 1.0]]))
}
