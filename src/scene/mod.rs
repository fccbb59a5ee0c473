//! `Scene`: immutable geometry, materials, lights and camera, as loaded from a scene file (TOML,
//! `file`, or Mitsuba XML, `mitsuba`), each a translator into the one `builder::SceneBuilder`
//! that validates and assembles every scene.
//!
//! Primitives are triangles (quads and OBJ meshes) and analytic spheres. Primitive ids are
//! `[0, ntri)` for triangles and `[ntri, ntri+nsph)` for spheres. Every emissive primitive is one
//! `Emitter`; lights (emitters and point lights) are picked in proportion to their power.
//!
//! Invariants: geometric normals are unit and define the emitting side of area lights; shading
//! normals lie on the geometric normal's side; emitters have the black material.

mod builder;
mod camera;
mod dirac_target;
mod emitters;
pub mod export;
mod file;
mod limits;
mod locate;
mod mesh;
pub mod mitsuba;
mod obj;
mod plugins;
pub mod ply;
mod schema;
mod shape_uv;
mod spec;
mod surface;

pub use camera::Camera;
pub use dirac_target::{MAX_OBJECTS, MAX_TARGETS, SPHERE_PAD};
pub use emitters::{BoundingSphere, DirectionalLight, EnvMap, Environment, LatLong, Spot};
pub use file::load_str;
pub use limits::{within_extent, MAX_EXTENT};
pub use shape_uv::ShapeUvs;
pub use spec::SceneError;

/// How a scene file is loaded: the `-D NAME=VALUE` substitutions for Mitsuba XML `$NAME`
/// parameters (ignored by TOML scenes).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct LoadOptions {
    /// `(NAME, VALUE)` pairs, later ones overriding earlier ones and the XML `<default>`s.
    pub defines: Vec<(String, String)>,
}

/// Loads a scene file by extension with no `-D` values (`load_with`).
pub fn load(path: &std::path::Path) -> Result<Scene, SceneError> {
    load_with(path, &LoadOptions::default())
}

/// Loads a scene file by extension: `.xml` is Mitsuba XML (with `opts.defines`), anything else
/// the TOML format.
pub fn load_with(path: &std::path::Path, opts: &LoadOptions) -> Result<Scene, SceneError> {
    if path.extension().is_some_and(|e| e.eq_ignore_ascii_case("xml")) {
        // refused before opening: reading a FIFO would block forever
        limits::check_regular_file(path, "scene file").map_err(|message| SceneError {
            file: path.display().to_string(),
            line: 0,
            key: String::new(),
            message,
        })?;
        return mitsuba::load(path, &opts.defines);
    }
    if let Some((name, _)) = opts.defines.first() {
        return Err(SceneError {
            file: path.display().to_string(),
            line: 0,
            key: String::new(),
            message: format!("-D {name}=…: -D sets Mitsuba XML `<default>` parameters; this is a TOML scene"),
        });
    }
    file::load(path)
}

/// The `--method` names a scene file may choose as its default (`[render] method`, XML
/// `forecast_method`): `integrators::Method::ALL`'s, which lie above this module
/// (`tests/bad_scenes.rs` checks that the two lists agree).
pub const METHOD_NAMES: [&str; 5] = ["pt", "iws", "iws-pm", "iws-cf", "pt-cf"];

/// `[render] method = "auto"`, also the default of a scene that names no method:
/// `integrators::auto` picks the method from what the scene contains.
pub const AUTO_METHOD: &str = "auto";

/// `s` as a file-name part: ASCII letters, digits, `-` and `_` kept, anything else `_` (the
/// names of `compare`'s per-ROI files; two ROIs equal under it would share them).
pub fn safe_name(s: &str) -> String {
    s.chars().map(|c| if c.is_ascii_alphanumeric() || c == '-' || c == '_' { c } else { '_' }).collect()
}

/// True for a name a scene may give as its method: [`AUTO_METHOD`] or one of [`METHOD_NAMES`].
pub fn is_method_name(s: &str) -> bool {
    s == AUTO_METHOD || METHOD_NAMES.contains(&s)
}

/// Parses one `-D NAME=VALUE` (NAME non-empty, alphanumeric or `_`), as clap's value parser.
pub fn parse_define(s: &str) -> Result<(String, String), String> {
    let (k, v) = s.split_once('=').ok_or_else(|| format!("`{s}`: expected NAME=VALUE"))?;
    let k = k.trim();
    if k.is_empty() || !k.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
        return Err(format!("`{s}`: NAME must be a non-empty identifier (letters, digits, `_`)"));
    }
    Ok((k.to_string(), v.to_string()))
}

/// A TOML `type = "mesh"` file by extension: `.ply` (PLY reader) or OBJ.
fn load_mesh_file(path: &std::path::Path, smooth: bool) -> Result<mesh::Mesh, String> {
    if path.extension().is_some_and(|e| e.eq_ignore_ascii_case("ply")) {
        return ply::load_mesh(path, smooth);
    }
    obj::load_mesh(path, smooth)
}
pub use crate::bsdf::Material;
pub use surface::{BumpMap, SlotTexture, Surface};

use crate::bsdf::ShadingPoint;
use crate::math::{luminance, Rgb, Vec2, Vec3, PI};
use crate::sampling::distribution::Distribution1D;
use crate::sampling::warp;
use crate::texture::Texture;

/// Sentinel for "no emitter".
pub const NO_EMITTER: u32 = u32::MAX;

/// A triangle with optional per-vertex shading normals.
#[derive(Clone, Debug, PartialEq)]
pub struct Triangle {
    /// Vertices.
    pub p: [Vec3; 3],
    /// Per-vertex shading normals (smooth meshes).
    pub n: Option<[Vec3; 3]>,
    /// Per-vertex texture coordinates (meshes with UVs, rectangles, quads).
    pub uv: Option<[Vec2; 3]>,
    /// Unit geometric normal, normalize((p1−p0)×(p2−p0)).
    pub ng: Vec3,
    /// Area.
    pub area: f32,
    /// Material index.
    pub material: u32,
    /// Emitter index or `NO_EMITTER`.
    pub emitter: u32,
}

/// An analytic sphere.
#[derive(Clone, Debug, PartialEq)]
pub struct Sphere {
    /// Centre.
    pub center: Vec3,
    /// Radius (> 0).
    pub radius: f32,
    /// Normals point inwards (closed rooms).
    pub inward: bool,
    /// Its own frame's unit axes in world space (the rotation of Mitsuba's `to_world`), which
    /// orient its texture coordinates; the world axes where none is given.
    pub axes: [Vec3; 3],
    /// Material index.
    pub material: u32,
    /// Emitter index or `NO_EMITTER`.
    pub emitter: u32,
}

/// An emissive primitive: a one-sided Lambertian emitter with constant radiance.
#[derive(Clone, Debug, PartialEq)]
pub struct Emitter {
    /// Primitive id (triangle or sphere).
    pub prim: u32,
    /// Emitted radiance on the normal's side.
    pub radiance: Rgb,
    /// Area.
    pub area: f32,
}

/// A point light: isotropic (`point`), or a `spot` with its angular profile.
#[derive(Clone, Debug, PartialEq)]
pub struct PointLight {
    /// Position.
    pub position: Vec3,
    /// Radiant intensity (W/sr), along the beam for a spot.
    pub intensity: Rgb,
    /// A spot light's cone and falloff (`None`: isotropic).
    pub spot: Option<Spot>,
}

impl PointLight {
    /// The intensity toward the unit direction `w` (away from the light): `I`, or `I·falloff(w)`
    /// for a spot.
    #[inline]
    pub fn intensity_toward(&self, w: Vec3) -> Rgb {
        match &self.spot {
            None => self.intensity,
            Some(s) => self.intensity * s.falloff(w),
        }
    }

    /// The light's own emission directions: uniform over the sphere, or over a spot's cone;
    /// `(ω, pdf_w)`.
    #[inline]
    pub fn sample_dir(&self, u: [f32; 2]) -> (Vec3, f32) {
        match &self.spot {
            None => (warp::sample_uniform_sphere(u), warp::uniform_sphere_pdf()),
            Some(s) => s.sample_dir(u),
        }
    }

    /// The pdf of [`PointLight::sample_dir`] at `w`.
    #[inline]
    pub fn pdf_dir(&self, w: Vec3) -> f32 {
        match &self.spot {
            None => warp::uniform_sphere_pdf(),
            Some(s) => s.pdf_dir(w),
        }
    }

    /// Power (luminance, W): `4π·I`, or `I·∫falloff dω`.
    pub fn power(&self) -> f32 {
        let omega = self.spot.as_ref().map_or(4.0 * PI, |s| s.falloff_solid_angle());
        omega * luminance(self.intensity)
    }
}

/// A region of interest in pixels at the camera's resolution.
#[derive(Clone, Debug, PartialEq)]
pub struct Roi {
    /// Name.
    pub name: String,
    /// x, y, w, h (top-left origin).
    pub rect: [u32; 4],
}

/// Defaults from the scene's `[render]` table.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderDefaults {
    /// Method name.
    pub method: String,
    /// Samples per pixel (when no time budget).
    pub spp: Option<u64>,
    /// Time budget in seconds.
    pub time: Option<f64>,
    /// Seed.
    pub seed: u64,
    /// Safety cap on path vertices.
    pub max_depth: u32,
    /// The table's other keys, in file order: render settings and method options by their long
    /// flag names (`clusters = 32`), which the pipeline checks and applies (it knows the flags).
    pub options: Vec<RenderOption>,
}

/// A `[render]` key that is not the table's own (`method`, `spp`, `time`, `seed`, `max_depth`):
/// a render setting or a method's option by its long flag name, `-` or `_` (`guide_fraction =
/// 0.5`). The scene reader keeps it as written; `pipeline` parses it as `--KEY=VALUE`.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderOption {
    /// The key as written (`guide_fraction`).
    pub key: String,
    /// The value as command-line text (`0.5`, `inf`, `DSL,DD*`).
    pub value: String,
    /// The key's line in the scene file.
    pub line: usize,
}

/// The scene's lights, as `light_power` reads them.
pub struct Lights<'a> {
    /// Area emitters.
    pub emitters: &'a [Emitter],
    /// Point and spot lights.
    pub point_lights: &'a [PointLight],
    /// Directional lights.
    pub directional: &'a [DirectionalLight],
    /// The environment.
    pub environment: Option<&'a Environment>,
    /// The sphere bounding the shapes.
    pub bsphere: BoundingSphere,
}

/// Power (luminance, W) of a light, the weight of light selection: `π·A·Le` (area), the
/// intensity over the directions it emits into (point, spot), the flux through the disk of the
/// bounding sphere `π r²·E` (directional) or `π r²·∫L dω` (environment).
pub fn light_power(ls: &Lights, l: LightRef) -> f32 {
    match l {
        LightRef::Area(i) => {
            let e = &ls.emitters[i as usize];
            luminance(e.radiance) * e.area * PI
        }
        LightRef::Point(i) => ls.point_lights[i as usize].power(),
        LightRef::Directional(i) => ls.bsphere.disk_area() * luminance(ls.directional[i as usize].irradiance),
        LightRef::Environment => ls.bsphere.disk_area() * ls.environment.map_or(0.0, |e| e.power_per_area()),
    }
}

/// A light that next-event estimation can pick.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightRef {
    /// Index into `Scene::emitters`.
    Area(u32),
    /// Index into `Scene::point_lights` (point and spot lights).
    Point(u32),
    /// Index into `Scene::directional_lights`.
    Directional(u32),
    /// `Scene::environment`.
    Environment,
}

impl LightRef {
    /// True for the lights at infinity (directional, environment), whose light paths start on
    /// the bounding sphere's disk.
    #[inline]
    pub fn is_infinite(self) -> bool {
        matches!(self, LightRef::Directional(_) | LightRef::Environment)
    }
}

/// The loaded scene.
#[derive(Clone, Debug)]
pub struct Scene {
    /// Source file (for messages and hashing).
    pub path: String,
    /// FNV-1a hash of the scene file text, its meshes and its images' texels (checkpoint and MPI job identity).
    pub hash: u64,
    /// The mesh files read (OBJ, PLY), in scene order: inputs no output may name
    /// (`atomic_io::OutputSet`).
    pub mesh_files: Vec<std::path::PathBuf>,
    /// Camera.
    pub camera: Camera,
    /// Render defaults.
    pub render: RenderDefaults,
    /// Materials (index = material id).
    pub materials: Vec<Material>,
    /// Each material's sides, textures and normal map (index = material id).
    pub surfaces: Vec<Surface>,
    /// The textures `surfaces` name (decoded images shared between them).
    pub textures: Vec<Texture>,
    /// Triangles.
    pub triangles: Vec<Triangle>,
    /// Spheres.
    pub spheres: Vec<Sphere>,
    /// The triangles of tessellated analytic shapes (`disk`, `cylinder`) whose uv and ∂p/∂u come
    /// from the hit point in the shape's frame (`uv_at`), not from per-vertex UVs.
    pub shape_uvs: ShapeUvs,
    /// Area emitters.
    pub emitters: Vec<Emitter>,
    /// Point and spot lights.
    pub point_lights: Vec<PointLight>,
    /// Directional lights.
    pub directional_lights: Vec<DirectionalLight>,
    /// The environment (`constant` or `envmap`; at most one, as in Mitsuba).
    pub environment: Option<Environment>,
    /// The sphere bounding the shapes, where light paths from infinitely distant lights start.
    pub bsphere: BoundingSphere,
    /// All lights, in `light_pick` order: the area emitters first (emitter `e` is light `e`),
    /// then the point and spot lights, the directional lights, the environment.
    pub lights: Vec<LightRef>,
    /// Light selection ∝ power (`light_power`).
    pub light_pick: Distribution1D,
    /// Regions of interest.
    pub rois: Vec<Roi>,
    /// Optional Caustic Forecasting target box override (min, max).
    pub forecast_target: Option<(Vec3, Vec3)>,
    /// Forecast photons to store (`[forecast] photons`).
    pub forecast_photons: Option<u64>,
    /// Scene bounds (min, max).
    pub bounds: (Vec3, Vec3),
    /// Warnings collected while loading (degenerate triangles, ...).
    pub warnings: Vec<String>,
}

impl Scene {
    /// Number of triangles (the first sphere's primitive id).
    #[inline]
    pub fn ntri(&self) -> u32 {
        self.triangles.len() as u32
    }

    /// The material id of a primitive.
    #[inline]
    fn material_id(&self, prim: u32) -> usize {
        let m = if prim < self.ntri() {
            self.triangles[prim as usize].material
        } else {
            self.spheres[(prim - self.ntri()) as usize].material
        };
        m as usize
    }

    /// The material of a primitive as the scene gives it, whichever side it is seen from (for
    /// what does not depend on a direction: is it Dirac, is it black). A path's vertex takes
    /// [`Scene::shade`]'s.
    #[inline]
    pub fn material_of(&self, prim: u32) -> &Material {
        &self.materials[self.material_id(prim)]
    }

    /// The BSDF and shading point at `sp` on `prim`, seen from `wo` (toward the previous vertex):
    /// black behind a one-sided material (`Surface`).
    #[inline]
    pub fn shade(&self, prim: u32, sp: ShadingPoint, wo: Vec3) -> (Material, ShadingPoint) {
        let id = self.material_id(prim);
        let s = &self.surfaces[id];
        if !s.two_sided && wo.dot(sp.ng) <= 0.0 {
            return (Material::Black, sp);
        }
        if s.is_constant() {
            return (self.materials[id], sp);
        }
        // the shading point is rewritten in place, so that the constant paths above return `sp`
        // without a copy through the stack (`results/2026-12-07-mesh-speed-2.md`)
        let mut sp = sp;
        let m = self.shade_varying(prim, id, &mut sp, wo);
        (m, sp)
    }

    /// Prefetches the texels [`Scene::shade`] at the point `p` of `prim` reads (its textures and
    /// map at the point's uv, [`Surface::prefetch`]); nothing for a surface without textures or
    /// map. A hint for a batch of hits about to be shaded: no effect on any value.
    #[inline]
    pub fn prefetch_shading(&self, prim: u32, p: Vec3) {
        let s = &self.surfaces[self.material_id(prim)];
        if s.textures.is_empty() && !s.has_map() {
            return;
        }
        s.prefetch(&self.textures, self.uv_at(prim, p).0);
    }

    /// `shade` where the material has textures, a normal or bump map or an anisotropic BSDF: its
    /// parameters, and `sp`'s shading normal and tangent at the hit's texture coordinates
    /// (`Surface::shading_point`).
    #[inline(never)]
    fn shade_varying(&self, prim: u32, id: usize, sp: &mut ShadingPoint, wo: Vec3) -> Material {
        let at = *sp;
        let (uv, dpdu) = self.uv_at(prim, at.p);
        let s = &self.surfaces[id];
        let m = s.material_at(&self.materials[id], &self.textures, uv);
        let dpdv = || self.dpdv_at(prim, at, dpdu);
        *sp = s.shading_point(at, (uv, dpdu), dpdv, &self.textures, wo);
        m
    }

    /// Emitter of a primitive, or `NO_EMITTER`.
    #[inline]
    pub fn emitter_of(&self, prim: u32) -> u32 {
        if prim < self.ntri() {
            self.triangles[prim as usize].emitter
        } else {
            self.spheres[(prim - self.ntri()) as usize].emitter
        }
    }

    /// Samples a point uniformly on an emitter: (position, unit geometric normal, pdf_a = 1/area).
    pub fn sample_emitter_point(&self, emitter: u32, u: [f32; 2]) -> (Vec3, Vec3, f32) {
        let e = &self.emitters[emitter as usize];
        if e.prim < self.ntri() {
            let t = &self.triangles[e.prim as usize];
            let p = warp::triangle_point(t.p, warp::sample_triangle(u));
            (p, t.ng, 1.0 / t.area)
        } else {
            let s = &self.spheres[(e.prim - self.ntri()) as usize];
            let d = warp::sample_uniform_sphere(u);
            let n = if s.inward { -d } else { d };
            (s.center + s.radius * d, n, 1.0 / e.area)
        }
    }

    /// The bytes the scene's decoded images hold (each shared image once).
    pub fn texture_bytes(&self) -> u64 {
        let mut seen = std::collections::HashSet::new();
        let mut bytes = 0u64;
        for t in &self.textures {
            t.for_each_image(&mut |img| {
                if seen.insert(std::sync::Arc::as_ptr(img)) {
                    bytes += img.memory_bytes() as u64;
                }
            });
        }
        bytes
    }

    /// Total area of non-Dirac, non-emitting surfaces (IWS's A_D).
    pub fn non_specular_area(&self) -> f32 {
        let tri: f32 = self
            .triangles
            .iter()
            .filter(|t| !self.materials[t.material as usize].is_dirac() && t.emitter == NO_EMITTER)
            .map(|t| t.area)
            .sum();
        let sph: f32 = self
            .spheres
            .iter()
            .filter(|s| !self.materials[s.material as usize].is_dirac() && s.emitter == NO_EMITTER)
            .map(|s| 4.0 * PI * s.radius * s.radius)
            .sum();
        tri + sph
    }

    /// The light-pick index of the environment (`None` without one).
    #[inline]
    pub fn environment_light(&self) -> Option<usize> {
        self.environment.as_ref()?;
        Some(self.lights.len() - 1)
    }

    /// True when the scene has a light at infinity (directional or environment).
    pub fn has_infinite_lights(&self) -> bool {
        self.environment.is_some() || !self.directional_lights.is_empty()
    }

    /// True when the scene has a spot light.
    pub fn has_spot_lights(&self) -> bool {
        self.point_lights.iter().any(|p| p.spot.is_some())
    }

    /// Bounding box of all Dirac primitives, if any.
    pub fn dirac_bounds(&self) -> Option<(Vec3, Vec3)> {
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        let mut any = false;
        for t in &self.triangles {
            if self.materials[t.material as usize].is_dirac() {
                any = true;
                for p in t.p {
                    lo = lo.min(p);
                    hi = hi.max(p);
                }
            }
        }
        for s in &self.spheres {
            if self.materials[s.material as usize].is_dirac() {
                any = true;
                lo = lo.min(s.center - Vec3::splat(s.radius));
                hi = hi.max(s.center + Vec3::splat(s.radius));
            }
        }
        any.then_some((lo, hi))
    }
}

/// The distinctive part of the point-light caustic warning (tests look for it).
pub const POINT_LIGHT_WARNING: &str = "cannot be sampled by `pt` and `iws-cf`";

/// Warnings about scene-level limitations of the methods; empty when there are none. Every
/// render prints them (rank 0) and stores them in the JSON `warnings`. Today: point, spot or
/// directional lights (Dirac in position or direction) together with Dirac objects, whose
/// caustics `pt` and `iws-cf` cannot sample (BAJ08).
pub fn scene_warnings(scene: &Scene) -> Vec<String> {
    let mut w = Vec::new();
    let n = scene.point_lights.len() + scene.directional_lights.len();
    if n > 0 && scene.dirac_bounds().is_some() {
        w.push(format!(
            "{}: {n} point, spot or directional light(s) and Dirac (mirror/glass) objects: caustics lit by them (paths L S+ D) \
             {POINT_LIGHT_WARNING} (BAJ08 limitation: such a light is never hit, and a Dirac chain cannot be \
             connected to it); those methods leave them out, `iws-pm` includes them (biased) and `pt-cf` renders them \
             with its light paths (`--light-paths`)",
            scene.path
        ));
    }
    w
}
