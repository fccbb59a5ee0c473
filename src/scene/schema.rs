//! The TOML schema of a scene file (serde): one struct per table, unknown keys rejected
//! (`deny_unknown_fields`). Values are checked, and turned into a `Scene`, by `file`.
//! The format is documented in `scenes/README.md`.

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
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct MaterialRaw {
    #[serde(rename = "type")]
    kind: String,
    #[serde(default, deserialize_with = "exact_opt")]
    albedo: Option<[f32; 3]>,
    #[serde(default, deserialize_with = "exact_opt")]
    specular: Option<[f32; 3]>,
    exponent: Option<f32>,
    #[serde(default, deserialize_with = "exact_opt")]
    reflectance: Option<[f32; 3]>,
    ior: Option<f32>,
}

/// A material by type (after `MaterialRaw::resolve`).
pub(super) enum MaterialDef {
    Diffuse { albedo: [f32; 3] },
    Glossy { albedo: [f32; 3], specular: [f32; 3], exponent: f32 },
    Mirror { reflectance: [f32; 3] },
    Glass { ior: f32 },
}

/// A key problem found by `resolve`: (the key's leaf name, message).
pub(super) type Bad = (String, String);

fn need<T: Clone>(v: &Option<T>, key: &str, kind: &str) -> Result<T, Bad> {
    v.clone().ok_or_else(|| (key.to_string(), format!("missing key `{key}` (required for type `{kind}`)")))
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

impl MaterialRaw {
    pub(super) fn resolve(&self) -> Result<MaterialDef, Bad> {
        let k = self.kind.as_str();
        let present = [
            ("albedo", self.albedo.is_some()),
            ("specular", self.specular.is_some()),
            ("exponent", self.exponent.is_some()),
            ("reflectance", self.reflectance.is_some()),
            ("ior", self.ior.is_some()),
        ];
        Ok(match k {
            "diffuse" => {
                only(k, &["albedo"], &present)?;
                MaterialDef::Diffuse { albedo: need(&self.albedo, "albedo", k)? }
            }
            "glossy" => {
                only(k, &["albedo", "specular", "exponent"], &present)?;
                MaterialDef::Glossy {
                    albedo: need(&self.albedo, "albedo", k)?,
                    specular: need(&self.specular, "specular", k)?,
                    exponent: need(&self.exponent, "exponent", k)?,
                }
            }
            "mirror" => {
                only(k, &["reflectance"], &present)?;
                MaterialDef::Mirror { reflectance: need(&self.reflectance, "reflectance", k)? }
            }
            "glass" => {
                only(k, &["ior"], &present)?;
                MaterialDef::Glass { ior: need(&self.ior, "ior", k)? }
            }
            _ => return Err(unknown_type("material", k, "diffuse, glossy, mirror, glass")),
        })
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
}

/// A light by type (after `LightRaw::resolve`).
pub(super) enum LightDef {
    Point { position: [f32; 3], intensity: [f32; 3] },
}

impl LightRaw {
    pub(super) fn resolve(&self) -> Result<LightDef, Bad> {
        let k = self.kind.as_str();
        match k {
            "point" => Ok(LightDef::Point {
                position: need(&self.position, "position", k)?,
                intensity: need(&self.intensity, "intensity", k)?,
            }),
            _ => Err(unknown_type("light", k, "point")),
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
