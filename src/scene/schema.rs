//! The TOML schema of a scene file (serde): one struct per table, unknown keys rejected
//! (`deny_unknown_fields`). Values are checked, and turned into a `Scene`, by `file`.
//! The format is documented in `scenes/README.md`.

use serde::Deserialize;
use std::collections::BTreeMap;
use toml::Spanned;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct Doc {
    pub(super) camera: Spanned<CameraDef>,
    pub(super) render: Option<Spanned<RenderDef>>,
    #[serde(default)]
    pub(super) materials: BTreeMap<String, Spanned<MaterialDef>>,
    #[serde(default)]
    pub(super) shape: Vec<Spanned<ShapeDef>>,
    #[serde(default)]
    pub(super) light: Vec<Spanned<LightDef>>,
    #[serde(default)]
    pub(super) roi: Vec<Spanned<RoiDef>>,
    pub(super) forecast: Option<Spanned<ForecastDef>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct CameraDef {
    pub(super) position: [f32; 3],
    pub(super) look_at: [f32; 3],
    #[serde(default = "default_up")]
    pub(super) up: [f32; 3],
    pub(super) fov: f32,
    pub(super) resolution: [u32; 2],
}

fn default_up() -> [f32; 3] {
    [0.0, 1.0, 0.0]
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RenderDef {
    pub(super) method: Option<String>,
    pub(super) spp: Option<u64>,
    pub(super) time: Option<String>,
    pub(super) seed: Option<u64>,
    pub(super) max_depth: Option<u32>,
}

#[derive(Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub(super) enum MaterialDef {
    Diffuse { albedo: [f32; 3] },
    Glossy { albedo: [f32; 3], specular: [f32; 3], exponent: f32 },
    Mirror { reflectance: [f32; 3] },
    Glass { ior: f32 },
}

#[derive(Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
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
        #[serde(default)]
        inward: bool,
    },
    Mesh {
        file: String,
        #[serde(default = "default_normals")]
        normals: String,
        material: Option<String>,
        emission: Option<[f32; 3]>,
        translate: Option<[f32; 3]>,
        scale: Option<f32>,
        rotate_y: Option<f32>,
    },
}

fn default_normals() -> String {
    "flat".into()
}

#[derive(Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub(super) enum LightDef {
    Point { position: [f32; 3], intensity: [f32; 3] },
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RoiDef {
    pub(super) name: String,
    pub(super) rect: [u32; 4],
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct ForecastDef {
    pub(super) target_box: Option<[[f32; 3]; 2]>,
    pub(super) photons: Option<u64>,
}
