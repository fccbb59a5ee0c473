//! The TOML schema of a scene file (serde): one struct per table, unknown keys rejected
//! (`deny_unknown_fields`). Values are checked, and turned into a `Scene`, by `file`. The
//! material tables and their parameters are in `material`. The format is documented in
//! `scenes/README.md`.

use serde::{Deserialize, Deserializer};
use std::collections::BTreeMap;
use toml::Spanned;

mod material;
pub(super) use material::{IorRaw, MaterialDef, MaterialRaw, ParamRaw, TextureRaw, UvRaw};

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

/// A key problem found by `resolve`: (the key's leaf name, message).
pub(super) type Bad = (String, String);

fn missing(key: &str, kind: &str) -> Bad {
    (key.to_string(), format!("missing key `{key}` (required for type `{kind}`)"))
}

fn need<T: Clone>(v: &Option<T>, key: &str, kind: &str) -> Result<T, Bad> {
    v.clone().ok_or_else(|| missing(key, kind))
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
