//! A TOML `[materials.NAME]` table read as Mitsuba's plugin parameters (`plugins::Params`):
//! constants, texture tables (`bitmap`, `checkerboard`, their `to_uv`), registered with the
//! scene builder and its texture cache. Every error names the key's line (`materials.NAME.KEY`).
//!
//! Invariants: `TomlParams::read` lists each of [`PARAM_KEYS`] the plugin asked for (the caller
//! refuses the others); constants are finite; a texture's file is relative to the scene's folder.

use super::ctx::Ctx;
use crate::math::{Rgb, Vec2, Vec3};
use crate::scene::builder::SceneBuilder;
use crate::scene::plugins::{self, IorValue, Param};
use crate::scene::schema::{IorRaw, MaterialRaw, ParamRaw, TextureRaw, UvRaw};
use crate::scene::SceneError;
use crate::texture::{BitmapParams, Checkerboard, FilterType, Texture, TextureCache, UvTransform, WrapMode};
use std::path::Path;
use toml::Spanned;

/// The parameters of Mitsuba's plugin types that `TomlParams` hands to `scene::plugins`.
pub(super) const PARAM_KEYS: [&str; 15] = [
    "diffuse_reflectance",
    "specular_reflectance",
    "specular_transmittance",
    "int_ior",
    "ext_ior",
    "nonlinear",
    "material",
    "eta",
    "k",
    "distribution",
    "alpha",
    "alpha_u",
    "alpha_v",
    "sample_visible",
    "albedo",
];

/// A `[materials.NAME]` table as `plugins::Params`: its keys by Mitsuba's names, a texture table
/// registered with the builder, errors at the key's line (`materials.NAME.KEY`).
pub(super) struct TomlParams<'a, 'c> {
    pub(super) cx: &'a Ctx<'c>,
    pub(super) b: &'a mut SceneBuilder,
    pub(super) cache: &'a mut TextureCache,
    pub(super) dir: &'a Path,
    pub(super) raw: &'a MaterialRaw,
    pub(super) span: std::ops::Range<usize>,
    /// `materials.NAME`.
    pub(super) key: String,
    /// The keys read so far.
    pub(super) read: Vec<&'static str>,
}

impl TomlParams<'_, '_> {
    fn mark(&mut self, name: &str) {
        if let Some(k) = PARAM_KEYS.iter().find(|k| **k == name) {
            self.read.push(k);
        }
    }
}

impl plugins::Params for TomlParams<'_, '_> {
    fn has(&self, name: &str) -> bool {
        self.raw.has(name)
    }
    fn param(&mut self, name: &str) -> Result<Option<Param>, SceneError> {
        self.mark(name);
        let Some(v) = self.raw.param(name) else { return Ok(None) };
        let key = format!("{}.{name}", self.key);
        let monochrome = name.starts_with("alpha");
        match v.get_ref() {
            ParamRaw::Texture(t) => {
                let t = texture(self.cx, (self.b, self.cache, self.dir), t, v.span(), &key)?;
                Ok(Some(Param::Texture(self.b.texture(t))))
            }
            ParamRaw::Rgb(_) if monochrome => Err(self.err(name, "takes a number or a texture, not a colour")),
            c => constant(self.cx, c, v.span(), &key).map(|c| Some(Param::Constant(c))),
        }
    }
    fn color(&mut self, name: &str) -> Result<Option<Rgb>, SceneError> {
        self.mark(name);
        let Some(v) = self.raw.param(name) else { return Ok(None) };
        constant(self.cx, v.get_ref(), v.span(), &format!("{}.{name}", self.key)).map(Some)
    }
    fn float(&mut self, name: &str) -> Result<Option<f32>, SceneError> {
        self.mark(name);
        Ok(None) // no TOML type takes a plain number outside `param` and `ior_value`
    }
    fn boolean(&mut self, name: &str) -> Result<Option<bool>, SceneError> {
        self.mark(name);
        Ok(self.raw.boolean(name))
    }
    fn string(&mut self, name: &str) -> Result<Option<String>, SceneError> {
        self.mark(name);
        Ok(self.raw.string(name).map(str::to_string))
    }
    fn ior_value(&mut self, name: &str) -> Result<Option<IorValue>, SceneError> {
        self.mark(name);
        Ok(self.raw.ior(name).map(|v| match v {
            IorRaw::Number(x) => IorValue { number: Some(*x), text: x.to_string() },
            IorRaw::Name(s) => IorValue { number: None, text: s.clone() },
        }))
    }
    fn err(&self, name: &str, message: &str) -> SceneError {
        self.cx.err(self.span.clone(), &format!("{}.{name}", self.key), message)
    }
    fn texture(&self, t: u32) -> &Texture {
        self.b.texture_at(t)
    }
}

/// A constant: a finite number (grey) or three finite numbers.
fn constant(cx: &Ctx, v: &ParamRaw, span: std::ops::Range<usize>, key: &str) -> Result<Rgb, SceneError> {
    let c = match v {
        ParamRaw::Number(x) => Rgb::splat(*x),
        ParamRaw::Rgb(c) => Vec3::from_array(*c),
        ParamRaw::Texture(_) => return Err(cx.err_in(span, key, "takes a constant here, not a texture")),
    };
    if !c.is_finite() {
        return Err(cx.err_in(span, key, format!("must be finite, got {:?}", c.to_array())));
    }
    Ok(c)
}

/// A texture table (`key` its dotted path, `span` its value's): Mitsuba's `bitmap` (the image
/// file relative to the scene's folder) or `checkerboard` (whose colours may be textures).
fn texture(
    cx: &Ctx,
    (b, cache, dir): (&mut SceneBuilder, &mut TextureCache, &Path),
    t: &TextureRaw,
    span: std::ops::Range<usize>,
    key: &str,
) -> Result<Texture, SceneError> {
    let bad = |k: &str, m: String| cx.err_in(span.clone(), &format!("{key}.{k}"), m);
    t.check_keys().map_err(|(k, m)| bad(&k, m))?;
    let to_uv = uv_transform(t.to_uv.as_ref()).map_err(|m| bad("to_uv", m))?;
    if t.kind == "checkerboard" {
        let default = Checkerboard::default();
        let mut colour = |k: &str, c: &Option<Spanned<ParamRaw>>, d: Texture| -> Result<Texture, SceneError> {
            let Some(c) = c else { return Ok(d) };
            let k = format!("{key}.{k}");
            match c.get_ref() {
                ParamRaw::Texture(t) => texture(cx, (&mut *b, &mut *cache, dir), t, c.span(), &k),
                v => constant(cx, v, c.span(), &k).map(Texture::Constant),
            }
        };
        let c0 = colour("color0", &t.color0, *default.color0)?;
        let c1 = colour("color1", &t.color1, *default.color1)?;
        return Ok(Texture::Checkerboard(Checkerboard::new(c0, c1, to_uv)));
    }
    let Some(f) = &t.filename else { return Err(bad("filename", "a `bitmap` needs `filename`".into())) };
    let mut params = BitmapParams::new(dir.join(f));
    if let Some(v) = &t.filter_type {
        params.filter_type = FilterType::parse(v).map_err(|m| bad("filter_type", m))?;
    }
    if let Some(v) = &t.wrap_mode {
        params.wrap_mode = WrapMode::parse(v).map_err(|m| bad("wrap_mode", m))?;
    }
    params.raw = t.raw.unwrap_or(false);
    params.to_uv = to_uv;
    plugins::bitmap(b, cache, &params).map_err(|m| bad("filename", m))
}

/// `to_uv = { scale = [su, sv], rotate = degrees, translate = [tu, tv] }`, applied in that order.
fn uv_transform(uv: Option<&UvRaw>) -> Result<UvTransform, String> {
    let Some(uv) = uv else { return Ok(UvTransform::IDENTITY) };
    let s = uv.scale.unwrap_or([1.0; 2]);
    let (r, t) = (uv.rotate.unwrap_or(0.0), uv.translate.unwrap_or([0.0; 2]));
    if !(s.iter().chain(&t).all(|x| x.is_finite()) && r.is_finite()) {
        return Err(format!("scale {s:?}, rotate {r} and translate {t:?} must be finite"));
    }
    let mut x = UvTransform::IDENTITY;
    if uv.scale.is_some() {
        x = x.then(UvTransform::scale(Vec2::from_array(s)));
    }
    if uv.rotate.is_some() {
        x = x.then(UvTransform::rotate(r));
    }
    if uv.translate.is_some() {
        x = x.then(UvTransform::translate(Vec2::from_array(t)));
    }
    Ok(x)
}
