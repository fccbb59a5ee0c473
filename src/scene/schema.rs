//! The TOML schema of a scene file (serde): one struct per table, unknown keys rejected
//! (`deny_unknown_fields`). Values are checked, and turned into a `Scene`, by `file`.
//! The format is documented in `scenes/README.md`.

use serde::de::{self, MapAccess, SeqAccess, Visitor};
use serde::{Deserialize, Deserializer};
use std::collections::BTreeMap;
use toml::Spanned;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct Doc {
    pub(super) camera: Spanned<CameraDef>,
    pub(super) render: Option<Spanned<RenderDef>>,
    #[serde(default)]
    pub(super) materials: BTreeMap<String, Spanned<MaterialRaw>>,
    #[serde(default)]
    pub(super) shape: Vec<Spanned<ShapeRaw>>,
    #[serde(default)]
    pub(super) light: Vec<Spanned<LightRaw>>,
    #[serde(default)]
    pub(super) roi: Vec<Spanned<RoiDef>>,
    pub(super) forecast: Option<Spanned<ForecastDef>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct CameraDef {
    #[serde(deserialize_with = "exact")]
    pub(super) position: [f32; 3],
    #[serde(deserialize_with = "exact")]
    pub(super) look_at: [f32; 3],
    #[serde(default = "default_up", deserialize_with = "exact")]
    pub(super) up: [f32; 3],
    pub(super) fov: f32,
    #[serde(deserialize_with = "exact")]
    pub(super) resolution: [u32; 2],
}

fn default_up() -> [f32; 3] {
    [0.0, 1.0, 0.0]
}

/// `[T; N]` from an array of exactly `N` values. serde's own array impl reads the first `N` and
/// toml does not report the rest, so `position = [0, 1, 2, 3]` would load as `[0, 1, 2]`.
fn exact<'de, D: Deserializer<'de>, T: Deserialize<'de>, const N: usize>(d: D) -> Result<[T; N], D::Error> {
    sized(Vec::deserialize(d)?)
}

/// `v` as `[T; N]`, or serde's invalid-length error.
fn sized<T, E: serde::de::Error, const N: usize>(v: Vec<T>) -> Result<[T; N], E> {
    let n = v.len();
    v.try_into().map_err(|_| E::invalid_length(n, &format!("an array of length {N}").as_str()))
}

/// [`exact`] of an optional key (with `#[serde(default)]` for a missing one).
fn exact_opt<'de, D: Deserializer<'de>, T: Deserialize<'de>, const N: usize>(d: D) -> Result<Option<[T; N]>, D::Error> {
    exact(d).map(Some)
}

/// `target_box = [[x, y, z], [x, y, z]]`: two corners of exactly three values each.
fn exact_box<'de, D: Deserializer<'de>>(d: D) -> Result<Option<[[f32; 3]; 2]>, D::Error> {
    let [a, b]: [Vec<f32>; 2] = exact(d)?;
    Ok(Some([sized(a)?, sized(b)?]))
}

/// `[render]`: its own keys, and the render settings and method options by their flag names in
/// `options` (checked by the pipeline, which knows the flags: an unknown key is refused there).
#[derive(Deserialize)]
pub(super) struct RenderDef {
    pub(super) method: Option<String>,
    pub(super) spp: Option<u64>,
    pub(super) time: Option<String>,
    pub(super) seed: Option<u64>,
    pub(super) max_depth: Option<u32>,
    #[serde(flatten)]
    pub(super) options: BTreeMap<String, toml::Value>,
}

/// A `[materials.NAME]` table as written: `type` plus the union of every type's keys. Kept flat
/// (not a serde-tagged enum, which buffers the table and loses the spans of its values) so that a
/// value of the wrong type is reported at its own line; `resolve` checks the keys per type.
/// Mitsuba's types take Mitsuba's parameter names, read by name (`param`, `ior`, `string`,
/// `boolean`) by `scene::plugins`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct MaterialRaw {
    #[serde(rename = "type")]
    kind: String,
    albedo: Option<Spanned<ParamRaw>>,
    specular: Option<Spanned<ParamRaw>>,
    exponent: Option<f32>,
    reflectance: Option<Spanned<ParamRaw>>,
    ior: Option<f32>,
    twosided: Option<bool>,
    normalmap: Option<String>,
    diffuse_reflectance: Option<Spanned<ParamRaw>>,
    specular_reflectance: Option<Spanned<ParamRaw>>,
    specular_transmittance: Option<Spanned<ParamRaw>>,
    int_ior: Option<IorRaw>,
    ext_ior: Option<IorRaw>,
    nonlinear: Option<bool>,
    material: Option<String>,
    eta: Option<Spanned<ParamRaw>>,
    k: Option<Spanned<ParamRaw>>,
    distribution: Option<String>,
    alpha: Option<Spanned<ParamRaw>>,
    alpha_u: Option<Spanned<ParamRaw>>,
    alpha_v: Option<Spanned<ParamRaw>>,
    sample_visible: Option<bool>,
}

/// A colour or number parameter as written: a number (grey, or a roughness), `[r, g, b]`, or a
/// texture table (`{ type = "bitmap", filename = "wood.png" }`).
pub(super) enum ParamRaw {
    /// A number.
    Number(f32),
    /// Three numbers.
    Rgb([f32; 3]),
    /// A texture.
    Texture(Box<TextureRaw>),
}

impl<'de> Deserialize<'de> for ParamRaw {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<ParamRaw, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = ParamRaw;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a colour [r, g, b], a number or a texture table { type = \"bitmap\", ... }")
            }
            fn visit_f64<E: de::Error>(self, x: f64) -> Result<ParamRaw, E> {
                Ok(ParamRaw::Number(x as f32))
            }
            fn visit_i64<E: de::Error>(self, x: i64) -> Result<ParamRaw, E> {
                Ok(ParamRaw::Number(x as f32))
            }
            fn visit_u64<E: de::Error>(self, x: u64) -> Result<ParamRaw, E> {
                Ok(ParamRaw::Number(x as f32))
            }
            fn visit_seq<A: SeqAccess<'de>>(self, s: A) -> Result<ParamRaw, A::Error> {
                let v = Vec::<f32>::deserialize(de::value::SeqAccessDeserializer::new(s))?;
                Ok(ParamRaw::Rgb(sized(v)?))
            }
            fn visit_map<A: MapAccess<'de>>(self, m: A) -> Result<ParamRaw, A::Error> {
                Ok(ParamRaw::Texture(Box::new(TextureRaw::deserialize(de::value::MapAccessDeserializer::new(m))?)))
            }
        }
        d.deserialize_any(V)
    }
}

/// An index of refraction as written: a number or Mitsuba's preset name (`"bk7"`, `"water"`).
pub(super) enum IorRaw {
    /// A number.
    Number(f32),
    /// A preset name.
    Name(String),
}

impl<'de> Deserialize<'de> for IorRaw {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<IorRaw, D::Error> {
        struct V;
        impl Visitor<'_> for V {
            type Value = IorRaw;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("an index of refraction: a number or a preset name such as \"bk7\"")
            }
            fn visit_f64<E: de::Error>(self, x: f64) -> Result<IorRaw, E> {
                Ok(IorRaw::Number(x as f32))
            }
            fn visit_i64<E: de::Error>(self, x: i64) -> Result<IorRaw, E> {
                Ok(IorRaw::Number(x as f32))
            }
            fn visit_u64<E: de::Error>(self, x: u64) -> Result<IorRaw, E> {
                Ok(IorRaw::Number(x as f32))
            }
            fn visit_str<E: de::Error>(self, s: &str) -> Result<IorRaw, E> {
                Ok(IorRaw::Name(s.to_string()))
            }
        }
        d.deserialize_any(V)
    }
}

/// A texture table as written (flat, see `MaterialRaw`): Mitsuba's `bitmap` or `checkerboard`
/// with its parameters.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct TextureRaw {
    #[serde(rename = "type")]
    pub(super) kind: String,
    pub(super) filename: Option<String>,
    pub(super) raw: Option<bool>,
    pub(super) filter_type: Option<String>,
    pub(super) wrap_mode: Option<String>,
    pub(super) to_uv: Option<UvRaw>,
    pub(super) color0: Option<Spanned<ParamRaw>>,
    pub(super) color1: Option<Spanned<ParamRaw>>,
}

impl TextureRaw {
    /// Rejects the keys the texture's type does not take; the type must be known.
    pub(super) fn check_keys(&self) -> Result<(), Bad> {
        let present = [
            ("filename", self.filename.is_some()),
            ("raw", self.raw.is_some()),
            ("filter_type", self.filter_type.is_some()),
            ("wrap_mode", self.wrap_mode.is_some()),
            ("to_uv", self.to_uv.is_some()),
            ("color0", self.color0.is_some()),
            ("color1", self.color1.is_some()),
        ];
        let k = self.kind.as_str();
        match k {
            "bitmap" => only(k, &["filename", "raw", "filter_type", "wrap_mode", "to_uv"], &present),
            "checkerboard" => only(k, &["color0", "color1", "to_uv"], &present),
            _ => Err(unknown_type("texture", k, "bitmap, checkerboard")),
        }
    }
}

/// A texture's `to_uv` as written: `scale`, then `rotate` (degrees, counter-clockwise), then
/// `translate`, in that order.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct UvRaw {
    #[serde(default, deserialize_with = "exact_opt")]
    pub(super) scale: Option<[f32; 2]>,
    pub(super) rotate: Option<f32>,
    #[serde(default, deserialize_with = "exact_opt")]
    pub(super) translate: Option<[f32; 2]>,
}

/// A material by type (after `MaterialRaw::resolve`): the four of forecast's own format with
/// their values, or one of Mitsuba's plugins, built from the table by `scene::plugins`.
pub(super) enum MaterialDef {
    /// `albedo` may be a texture (`MaterialRaw::param("albedo")`).
    Diffuse,
    Glossy {
        albedo: [f32; 3],
        specular: [f32; 3],
        exponent: f32,
    },
    Mirror {
        reflectance: [f32; 3],
    },
    Glass {
        ior: f32,
    },
    /// A Mitsuba plugin by name (`plugins::PLUGINS`).
    Plugin(&'static str),
}

/// A key problem found by `resolve`: (the key's leaf name, message).
pub(super) type Bad = (String, String);

fn missing(key: &str, kind: &str) -> Bad {
    (key.to_string(), format!("missing key `{key}` (required for type `{kind}`)"))
}

fn need<T: Clone>(v: &Option<T>, key: &str, kind: &str) -> Result<T, Bad> {
    v.clone().ok_or_else(|| missing(key, kind))
}

/// A required constant colour (a number is grey): a texture is refused.
fn constant(v: &Option<Spanned<ParamRaw>>, key: &str, kind: &str) -> Result<[f32; 3], Bad> {
    match v.as_ref().map(|s| s.get_ref()) {
        None => Err(missing(key, kind)),
        Some(ParamRaw::Number(x)) => Ok([*x; 3]),
        Some(ParamRaw::Rgb(c)) => Ok(*c),
        Some(ParamRaw::Texture(_)) => {
            Err((key.to_string(), format!("type `{kind}` takes a constant `{key}`, not a texture")))
        }
    }
}

/// Rejects keys present in the table that the type does not take.
fn only(kind: &str, allowed: &[&str], present: &[(&str, bool)]) -> Result<(), Bad> {
    match present.iter().find(|(k, p)| *p && !allowed.contains(k)) {
        Some((k, _)) => {
            Err((k.to_string(), format!("key `{k}` does not apply to type `{kind}` (it takes {})", allowed.join(", "))))
        }
        None => Ok(()),
    }
}

fn unknown_type(what: &str, kind: &str, types: &str) -> Bad {
    ("type".into(), format!("unknown {what} type `{kind}` (one of {types})"))
}

/// The material types and the keys each takes (besides `type`).
const MATERIAL_KEYS: [(&str, &[&str]); 11] = [
    ("diffuse", &["albedo", "twosided", "normalmap"]),
    ("glossy", &["albedo", "specular", "exponent", "twosided", "normalmap"]),
    ("mirror", &["reflectance", "twosided", "normalmap"]),
    ("glass", &["ior", "normalmap"]),
    ("conductor", &["material", "eta", "k", "specular_reflectance", "twosided", "normalmap"]),
    (
        "roughconductor",
        &[
            "material",
            "eta",
            "k",
            "specular_reflectance",
            "distribution",
            "alpha",
            "alpha_u",
            "alpha_v",
            "sample_visible",
            "twosided",
            "normalmap",
        ],
    ),
    ("dielectric", &["int_ior", "ext_ior", "normalmap"]),
    ("thindielectric", &["int_ior", "ext_ior", "specular_reflectance", "specular_transmittance", "normalmap"]),
    (
        "roughdielectric",
        &[
            "int_ior",
            "ext_ior",
            "specular_reflectance",
            "specular_transmittance",
            "distribution",
            "alpha",
            "alpha_u",
            "alpha_v",
            "sample_visible",
            "normalmap",
        ],
    ),
    (
        "plastic",
        &["diffuse_reflectance", "specular_reflectance", "int_ior", "ext_ior", "nonlinear", "twosided", "normalmap"],
    ),
    (
        "roughplastic",
        &[
            "diffuse_reflectance",
            "specular_reflectance",
            "int_ior",
            "ext_ior",
            "nonlinear",
            "distribution",
            "alpha",
            "sample_visible",
            "twosided",
            "normalmap",
        ],
    ),
];

impl MaterialRaw {
    pub(super) fn resolve(&self) -> Result<MaterialDef, Bad> {
        let k = self.kind.as_str();
        let present = [
            ("albedo", self.albedo.is_some()),
            ("specular", self.specular.is_some()),
            ("exponent", self.exponent.is_some()),
            ("reflectance", self.reflectance.is_some()),
            ("ior", self.ior.is_some()),
            ("twosided", self.twosided.is_some()),
            ("normalmap", self.normalmap.is_some()),
            ("diffuse_reflectance", self.diffuse_reflectance.is_some()),
            ("specular_reflectance", self.specular_reflectance.is_some()),
            ("specular_transmittance", self.specular_transmittance.is_some()),
            ("int_ior", self.int_ior.is_some()),
            ("ext_ior", self.ext_ior.is_some()),
            ("nonlinear", self.nonlinear.is_some()),
            ("material", self.material.is_some()),
            ("eta", self.eta.is_some()),
            ("k", self.k.is_some()),
            ("distribution", self.distribution.is_some()),
            ("alpha", self.alpha.is_some()),
            ("alpha_u", self.alpha_u.is_some()),
            ("alpha_v", self.alpha_v.is_some()),
            ("sample_visible", self.sample_visible.is_some()),
        ];
        let Some((kind, allowed)) = MATERIAL_KEYS.iter().find(|(t, _)| *t == k) else {
            let types: Vec<&str> = MATERIAL_KEYS.iter().map(|(t, _)| *t).collect();
            return Err(unknown_type("material", k, &types.join(", ")));
        };
        only(k, allowed, &present)?;
        Ok(match *kind {
            "diffuse" if self.albedo.is_none() => return Err(missing("albedo", k)),
            "diffuse" => MaterialDef::Diffuse,
            "glossy" => MaterialDef::Glossy {
                albedo: constant(&self.albedo, "albedo", k)?,
                specular: constant(&self.specular, "specular", k)?,
                exponent: need(&self.exponent, "exponent", k)?,
            },
            "mirror" => MaterialDef::Mirror { reflectance: constant(&self.reflectance, "reflectance", k)? },
            "glass" => MaterialDef::Glass { ior: need(&self.ior, "ior", k)? },
            plugin => MaterialDef::Plugin(plugin),
        })
    }

    /// `twosided` (default true: a TOML material scatters from both sides unless it says so).
    pub(super) fn twosided(&self) -> bool {
        self.twosided.unwrap_or(true)
    }

    /// `normalmap`: the image file of a tangent-space normal map.
    pub(super) fn normalmap(&self) -> Option<&str> {
        self.normalmap.as_deref()
    }

    /// A colour or number parameter by its key.
    pub(super) fn param(&self, key: &str) -> Option<&Spanned<ParamRaw>> {
        match key {
            "albedo" => self.albedo.as_ref(),
            "specular" => self.specular.as_ref(),
            "reflectance" => self.reflectance.as_ref(),
            "diffuse_reflectance" => self.diffuse_reflectance.as_ref(),
            "specular_reflectance" => self.specular_reflectance.as_ref(),
            "specular_transmittance" => self.specular_transmittance.as_ref(),
            "eta" => self.eta.as_ref(),
            "k" => self.k.as_ref(),
            "alpha" => self.alpha.as_ref(),
            "alpha_u" => self.alpha_u.as_ref(),
            "alpha_v" => self.alpha_v.as_ref(),
            _ => None,
        }
    }

    /// An index of refraction by its key.
    pub(super) fn ior(&self, key: &str) -> Option<&IorRaw> {
        match key {
            "int_ior" => self.int_ior.as_ref(),
            "ext_ior" => self.ext_ior.as_ref(),
            _ => None,
        }
    }

    /// A string parameter by its key.
    pub(super) fn string(&self, key: &str) -> Option<&str> {
        match key {
            "material" => self.material.as_deref(),
            "distribution" => self.distribution.as_deref(),
            _ => None,
        }
    }

    /// A boolean parameter by its key.
    pub(super) fn boolean(&self, key: &str) -> Option<bool> {
        match key {
            "nonlinear" => self.nonlinear,
            "sample_visible" => self.sample_visible,
            _ => None,
        }
    }

    /// True when the table gives `key` (any type).
    pub(super) fn has(&self, key: &str) -> bool {
        self.param(key).is_some()
            || self.ior(key).is_some()
            || self.string(key).is_some()
            || self.boolean(key).is_some()
    }
}

/// A `[[shape]]` table as written (flat, see `MaterialRaw`).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct ShapeRaw {
    #[serde(rename = "type")]
    kind: String,
    #[serde(default, deserialize_with = "exact_opt")]
    corner: Option<[f32; 3]>,
    #[serde(default, deserialize_with = "exact_opt")]
    u: Option<[f32; 3]>,
    #[serde(default, deserialize_with = "exact_opt")]
    v: Option<[f32; 3]>,
    #[serde(default, deserialize_with = "exact_opt")]
    center: Option<[f32; 3]>,
    radius: Option<f32>,
    inward: Option<bool>,
    file: Option<String>,
    normals: Option<String>,
    #[serde(default, deserialize_with = "exact_opt")]
    translate: Option<[f32; 3]>,
    scale: Option<f32>,
    rotate_y: Option<f32>,
    material: Option<String>,
    #[serde(default, deserialize_with = "exact_opt")]
    emission: Option<[f32; 3]>,
}

/// A shape by type (after `ShapeRaw::resolve`).
pub(super) enum ShapeDef {
    Quad {
        corner: [f32; 3],
        u: [f32; 3],
        v: [f32; 3],
        material: Option<String>,
        emission: Option<[f32; 3]>,
    },
    Sphere {
        center: [f32; 3],
        radius: f32,
        material: Option<String>,
        emission: Option<[f32; 3]>,
        inward: bool,
    },
    Mesh {
        file: String,
        normals: String,
        material: Option<String>,
        emission: Option<[f32; 3]>,
        translate: Option<[f32; 3]>,
        scale: Option<f32>,
        rotate_y: Option<f32>,
    },
}

impl ShapeRaw {
    pub(super) fn resolve(&self) -> Result<ShapeDef, Bad> {
        let k = self.kind.as_str();
        let present = [
            ("corner", self.corner.is_some()),
            ("u", self.u.is_some()),
            ("v", self.v.is_some()),
            ("center", self.center.is_some()),
            ("radius", self.radius.is_some()),
            ("inward", self.inward.is_some()),
            ("file", self.file.is_some()),
            ("normals", self.normals.is_some()),
            ("translate", self.translate.is_some()),
            ("scale", self.scale.is_some()),
            ("rotate_y", self.rotate_y.is_some()),
        ];
        let (material, emission) = (self.material.clone(), self.emission);
        Ok(match k {
            "quad" => {
                only(k, &["corner", "u", "v", "material", "emission"], &present)?;
                ShapeDef::Quad {
                    corner: need(&self.corner, "corner", k)?,
                    u: need(&self.u, "u", k)?,
                    v: need(&self.v, "v", k)?,
                    material,
                    emission,
                }
            }
            "sphere" => {
                only(k, &["center", "radius", "inward", "material", "emission"], &present)?;
                ShapeDef::Sphere {
                    center: need(&self.center, "center", k)?,
                    radius: need(&self.radius, "radius", k)?,
                    inward: self.inward.unwrap_or(false),
                    material,
                    emission,
                }
            }
            "mesh" => {
                let keys = ["file", "normals", "translate", "scale", "rotate_y", "material", "emission"];
                only(k, &keys, &present)?;
                ShapeDef::Mesh {
                    file: need(&self.file, "file", k)?,
                    normals: self.normals.clone().unwrap_or_else(|| "flat".into()),
                    material,
                    emission,
                    translate: self.translate,
                    scale: self.scale,
                    rotate_y: self.rotate_y,
                }
            }
            _ => return Err(unknown_type("shape", k, "quad, sphere, mesh")),
        })
    }
}

/// A `[[light]]` table as written (flat, see `MaterialRaw`).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct LightRaw {
    #[serde(rename = "type")]
    kind: String,
    #[serde(default, deserialize_with = "exact_opt")]
    position: Option<[f32; 3]>,
    #[serde(default, deserialize_with = "exact_opt")]
    intensity: Option<[f32; 3]>,
    #[serde(default, deserialize_with = "exact_opt")]
    direction: Option<[f32; 3]>,
    cutoff_angle: Option<f32>,
    beam_width: Option<f32>,
    #[serde(default, deserialize_with = "exact_opt")]
    irradiance: Option<[f32; 3]>,
    #[serde(default, deserialize_with = "exact_opt")]
    radiance: Option<[f32; 3]>,
}

/// A light by type (after `LightRaw::resolve`): Mitsuba's `point`, `spot` (its beam along
/// `direction`, angles in degrees, `beam_width` default ¾ of `cutoff_angle`, default 20),
/// `directional` (light travelling along `direction`) and `constant`.
pub(super) enum LightDef {
    Point { position: [f32; 3], intensity: [f32; 3] },
    Spot { position: [f32; 3], intensity: [f32; 3], direction: [f32; 3], cutoff: f32, beam: f32 },
    Directional { direction: [f32; 3], irradiance: [f32; 3] },
    Constant { radiance: [f32; 3] },
}

impl LightRaw {
    pub(super) fn resolve(&self) -> Result<LightDef, Bad> {
        let k = self.kind.as_str();
        let only = |keys: &[(&str, bool)]| -> Result<(), Bad> {
            match keys.iter().find(|(_, present)| *present) {
                Some((key, _)) => Err(((*key).to_string(), format!("`{key}` is not a parameter of a {k} light"))),
                None => Ok(()),
            }
        };
        let spot_keys = [("cutoff_angle", self.cutoff_angle.is_some()), ("beam_width", self.beam_width.is_some())];
        match k {
            "point" => {
                only(&spot_keys)?;
                only(&[("direction", self.direction.is_some())])?;
                only(&[("irradiance", self.irradiance.is_some()), ("radiance", self.radiance.is_some())])?;
                Ok(LightDef::Point {
                    position: need(&self.position, "position", k)?,
                    intensity: need(&self.intensity, "intensity", k)?,
                })
            }
            "spot" => {
                only(&[("irradiance", self.irradiance.is_some()), ("radiance", self.radiance.is_some())])?;
                let cutoff = self.cutoff_angle.unwrap_or(20.0);
                Ok(LightDef::Spot {
                    position: need(&self.position, "position", k)?,
                    intensity: need(&self.intensity, "intensity", k)?,
                    direction: need(&self.direction, "direction", k)?,
                    cutoff,
                    beam: self.beam_width.unwrap_or(cutoff * 0.75),
                })
            }
            "directional" => {
                only(&spot_keys)?;
                only(&[("position", self.position.is_some()), ("intensity", self.intensity.is_some())])?;
                only(&[("radiance", self.radiance.is_some())])?;
                Ok(LightDef::Directional {
                    direction: need(&self.direction, "direction", k)?,
                    irradiance: need(&self.irradiance, "irradiance", k)?,
                })
            }
            "constant" => {
                only(&spot_keys)?;
                only(&[("position", self.position.is_some()), ("intensity", self.intensity.is_some())])?;
                only(&[("direction", self.direction.is_some()), ("irradiance", self.irradiance.is_some())])?;
                Ok(LightDef::Constant { radiance: need(&self.radiance, "radiance", k)? })
            }
            _ => Err(unknown_type("light", k, "point, spot, directional, constant")),
        }
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RoiDef {
    pub(super) name: String,
    #[serde(deserialize_with = "exact")]
    pub(super) rect: [u32; 4],
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct ForecastDef {
    #[serde(default, deserialize_with = "exact_box")]
    pub(super) target_box: Option<[[f32; 3]; 2]>,
    pub(super) photons: Option<u64>,
}
