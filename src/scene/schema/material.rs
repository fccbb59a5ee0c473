//! The material tables of a scene file: `[materials.NAME]` as written ([`MaterialRaw`]), its
//! parameters (a number, a colour or a texture table: [`ParamRaw`], [`TextureRaw`], [`UvRaw`];
//! an index of refraction: [`IorRaw`]), and the check of its keys per type into a [`MaterialDef`].
//! Unknown keys are rejected; a value of the wrong type is reported at its own line.

use super::{exact_opt, missing, need, only, sized, unknown_type, Bad};
use serde::de::{self, MapAccess, SeqAccess, Visitor};
use serde::{Deserialize, Deserializer};
use toml::Spanned;

/// A `[materials.NAME]` table as written: `type` plus the union of every type's keys. Kept flat
/// (not a serde-tagged enum, which buffers the table and loses the spans of its values) so that a
/// value of the wrong type is reported at its own line; `resolve` checks the keys per type.
/// Mitsuba's types take Mitsuba's parameter names, read by name (`param`, `ior`, `string`,
/// `boolean`) by `scene::plugins`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(in crate::scene) struct MaterialRaw {
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
pub(in crate::scene) enum ParamRaw {
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
pub(in crate::scene) enum IorRaw {
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
pub(in crate::scene) struct TextureRaw {
    #[serde(rename = "type")]
    pub(in crate::scene) kind: String,
    pub(in crate::scene) filename: Option<String>,
    pub(in crate::scene) raw: Option<bool>,
    pub(in crate::scene) filter_type: Option<String>,
    pub(in crate::scene) wrap_mode: Option<String>,
    pub(in crate::scene) to_uv: Option<UvRaw>,
    pub(in crate::scene) color0: Option<Spanned<ParamRaw>>,
    pub(in crate::scene) color1: Option<Spanned<ParamRaw>>,
}

impl TextureRaw {
    /// Rejects the keys the texture's type does not take; the type must be known.
    pub(in crate::scene) fn check_keys(&self) -> Result<(), Bad> {
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
pub(in crate::scene) struct UvRaw {
    #[serde(default, deserialize_with = "exact_opt")]
    pub(in crate::scene) scale: Option<[f32; 2]>,
    pub(in crate::scene) rotate: Option<f32>,
    #[serde(default, deserialize_with = "exact_opt")]
    pub(in crate::scene) translate: Option<[f32; 2]>,
}

/// A material by type (after `MaterialRaw::resolve`): the four of forecast's own format with
/// their values, or one of Mitsuba's plugins, built from the table by `scene::plugins`.
pub(in crate::scene) enum MaterialDef {
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
    pub(in crate::scene) fn resolve(&self) -> Result<MaterialDef, Bad> {
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
    pub(in crate::scene) fn twosided(&self) -> bool {
        self.twosided.unwrap_or(true)
    }

    /// `normalmap`: the image file of a tangent-space normal map.
    pub(in crate::scene) fn normalmap(&self) -> Option<&str> {
        self.normalmap.as_deref()
    }

    /// A colour or number parameter by its key.
    pub(in crate::scene) fn param(&self, key: &str) -> Option<&Spanned<ParamRaw>> {
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
    pub(in crate::scene) fn ior(&self, key: &str) -> Option<&IorRaw> {
        match key {
            "int_ior" => self.int_ior.as_ref(),
            "ext_ior" => self.ext_ior.as_ref(),
            _ => None,
        }
    }

    /// A string parameter by its key.
    pub(in crate::scene) fn string(&self, key: &str) -> Option<&str> {
        match key {
            "material" => self.material.as_deref(),
            "distribution" => self.distribution.as_deref(),
            _ => None,
        }
    }

    /// A boolean parameter by its key.
    pub(in crate::scene) fn boolean(&self, key: &str) -> Option<bool> {
        match key {
            "nonlinear" => self.nonlinear,
            "sample_visible" => self.sample_visible,
            _ => None,
        }
    }

    /// True when the table gives `key` (any type).
    pub(in crate::scene) fn has(&self, key: &str) -> bool {
        self.param(key).is_some()
            || self.ior(key).is_some()
            || self.string(key).is_some()
            || self.boolean(key).is_some()
    }
}
