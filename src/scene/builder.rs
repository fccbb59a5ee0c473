//! `SceneBuilder`: the one place a `Scene` is assembled and validated. Every scene format (the
//! TOML file, Mitsuba XML) is a translator that hands the builder its camera, materials, shapes,
//! lights and render options, each with its provenance (`Origin`: the line and key in the
//! file); the builder checks them once, with the same words in every format:
//!
//! - the camera: position and target inside the extent (`limits`), a finite non-zero up that is
//!   not parallel to the view, a vertical fov in (0, 180), a resolution in 1..=65536;
//! - shapes: every finite vertex (after its transform) and every sphere's bounds inside the
//!   extent, else the extent error naming the shape's key; degenerate triangles (zero area, or a
//!   non-finite vertex) skipped with one warning per shape; an empty scene names the last shape
//!   whose triangles were all dropped;
//! - lights: radiance ≤ `MAX_RADIANCE`, intensity ≤ `MAX_INTENSITY`, point lights inside the
//!   extent, each light's power finite; at least one light with positive power;
//! - render options: the `param_limits` shared with the command line; ROIs inside the image,
//!   each with a name of its own (not `full`).
//!
//! Invariants of the result: material 0 is black; triangles in the order given, then spheres;
//! emitters in primitive order (emissive triangles, then emissive spheres); lights = the area
//! emitters then the point lights, picked ∝ power (`light_power`).

use super::limits::{extent_message, light_value_error, within_extent, MAX_INTENSITY, MAX_RADIANCE};
use super::shape_uv::{ShapeUv, ShapeUvs};
use super::spec::{CameraSpec, Corners, Origin, SceneError, ShapeIn, View};
use super::{
    light_power, BoundingSphere, Camera, DirectionalLight, Emitter, Environment, LightRef, Lights, Material,
    PointLight, RenderDefaults, Roi, Scene, Sphere, Surface, Triangle, NO_EMITTER,
};
use crate::math::{Rgb, Vec3, PI};
use crate::sampling::distribution::Distribution1D;
use crate::texture::Texture;

mod options;

struct ShapeRec {
    shape: ShapeIn,
    skipped: usize,
    flat: usize,
    kept: usize,
}

/// The builder (see the module docs).
pub(super) struct SceneBuilder {
    file: String,
    hash: u64,
    mesh_files: Vec<std::path::PathBuf>,
    warnings: Vec<String>,
    camera: Option<Camera>,
    /// Render defaults (set through the checked setters).
    pub render: RenderDefaults,
    materials: Vec<Material>,
    surfaces: Vec<Surface>,
    textures: Vec<Texture>,
    triangles: Vec<Triangle>,
    tri_shape: Vec<u32>,
    spheres: Vec<Sphere>,
    sph_shape: Vec<u32>,
    shapes: Vec<ShapeRec>,
    /// The shapes with an analytic parametrisation (shape id, its record).
    shape_uvs: Vec<(u32, ShapeUv)>,
    point_lights: Vec<(PointLight, Origin)>,
    directional: Vec<(DirectionalLight, Origin)>,
    environment: Option<(Environment, Origin)>,
    /// Each ROI with where its name was given.
    rois: Vec<(Roi, Origin)>,
    forecast_target: Option<(Vec3, Vec3)>,
    forecast_photons: Option<u64>,
}

impl SceneBuilder {
    /// A builder for `file` whose text hashes to `hash`.
    pub fn new(file: &str, hash: u64) -> SceneBuilder {
        SceneBuilder {
            file: file.to_string(),
            hash,
            mesh_files: Vec::new(),
            warnings: Vec::new(),
            camera: None,
            render: RenderDefaults {
                method: super::AUTO_METHOD.into(),
                spp: None,
                time: None,
                seed: 0,
                max_depth: 64,
                options: Vec::new(),
            },
            materials: vec![Material::Black],
            surfaces: vec![Surface::TWO_SIDED],
            textures: Vec::new(),
            triangles: Vec::new(),
            tri_shape: Vec::new(),
            spheres: Vec::new(),
            sph_shape: Vec::new(),
            shapes: Vec::new(),
            shape_uvs: Vec::new(),
            point_lights: Vec::new(),
            directional: Vec::new(),
            environment: None,
            rois: Vec::new(),
            forecast_target: None,
            forecast_photons: None,
        }
    }

    /// An error at `at`.
    pub fn err(&self, at: &Origin, message: impl Into<String>) -> SceneError {
        SceneError { file: self.file.clone(), line: at.line, key: at.key.clone(), message: message.into() }
    }

    /// A warning at `at` (`file:line: key `k`: message`, as errors read).
    pub fn warn(&mut self, at: &Origin, message: impl std::fmt::Display) {
        let w = self.err(at, message.to_string()).to_string();
        self.warnings.push(w);
    }

    /// Records a mesh file read (an input no output may name) and folds its bytes hash into the
    /// scene hash.
    pub fn mesh_file(&mut self, path: &std::path::Path, bytes_hash: u64) {
        self.mesh_files.push(path.to_path_buf());
        self.hash = crate::math::fnv1a(self.hash, &bytes_hash.to_le_bytes());
    }

    /// Adds a two-sided material; returns its index.
    pub fn material(&mut self, m: Material) -> u32 {
        self.material_with(m, Surface::TWO_SIDED)
    }

    /// Adds a material with its surface properties; returns its index.
    pub fn material_with(&mut self, m: Material, s: Surface) -> u32 {
        self.materials.push(m);
        self.surfaces.push(s);
        self.materials.len() as u32 - 1
    }

    /// The surface properties of material `i`.
    pub fn surface_at(&self, i: u32) -> &Surface {
        &self.surfaces[i as usize]
    }

    /// The texture at `i`.
    pub fn texture_at(&self, i: u32) -> &Texture {
        &self.textures[i as usize]
    }

    /// Records an image file the scene reads (an input no output may name).
    pub fn image_file(&mut self, path: &std::path::Path) {
        self.mesh_files.push(path.to_path_buf());
    }

    /// Adds a texture; returns its index. Its images' texels enter the scene hash.
    pub fn texture(&mut self, t: Texture) -> u32 {
        let mut hash = self.hash;
        t.for_each_image(&mut |i| hash = crate::math::fnv1a(hash, &i.content_hash().to_le_bytes()));
        self.hash = hash;
        self.textures.push(t);
        self.textures.len() as u32 - 1
    }

    /// The material at `i`.
    pub fn material_at(&self, i: u32) -> Material {
        self.materials[i as usize]
    }

    /// Checks and sets the camera.
    pub fn camera(&mut self, c: CameraSpec) -> Result<(), SceneError> {
        let (position, pat) = c.position;
        if !within_extent(position) {
            return Err(self.err(&pat, extent_message("camera position", position)));
        }
        let (fov, fat) = c.fov;
        if !(fov.is_finite() && fov > 0.0 && fov < 180.0) {
            return Err(self.err(&fat, format!("fov must give a vertical fov in (0, 180) degrees, got {fov}")));
        }
        let ([w, h], rat) = c.resolution;
        if !(1..=65536).contains(&w) || !(1..=65536).contains(&h) {
            return Err(self.err(&rat, "resolution must be in 1..=65536 per axis"));
        }
        let bad_up = |up: Vec3| !up.is_finite() || up.abs().max_element() == 0.0;
        let camera = match c.view {
            (View::LookAt { target, up }, tat) => {
                if !within_extent(target) {
                    return Err(self.err(&tat, extent_message("camera target", target)));
                }
                if bad_up(up) {
                    return Err(self.err(&c.up_at, "up must be finite and non-zero"));
                }
                // scaled to max |component| 1, so that normalizing cannot overflow
                let up = up / up.abs().max_element();
                let fwd = target - position;
                if fwd.length() < 1e-9 {
                    return Err(self.err(&tat, "the camera target equals its position"));
                }
                if fwd.normalize().cross(up.normalize()).length() < 1e-6 {
                    return Err(self.err(&c.up_at, "up is parallel to the view direction"));
                }
                Camera::new(position, target, up, fov, w, h)
            }
            (View::Frame { forward, up, right }, mat) => {
                let unit = |v: Vec3| v.is_finite() && (v.length() - 1.0).abs() < 1e-3;
                if !unit(forward) || !unit(right) || bad_up(up) || !unit(up) {
                    return Err(self.err(&mat, "the camera's forward, up and right must be finite and non-zero"));
                }
                if forward.dot(up).abs() > 1e-4 || forward.dot(right).abs() > 1e-4 || up.dot(right).abs() > 1e-4 {
                    return Err(self.err(&mat, "the camera transform must be rigid (no shear)"));
                }
                Camera::from_frame(position, (forward, right, up), fov, w, h)
            }
        };
        self.camera = Some(camera);
        Ok(())
    }

    /// The camera's image as the window `size` at `offset` of its film (checked by the reader:
    /// inside the film, non-empty).
    pub fn crop(&mut self, offset: [u32; 2], size: [u32; 2]) {
        self.camera = self.camera.take().map(|c| c.with_crop(offset, size));
    }

    /// A checked area-light radiance: `None` when black (the shape then emits nothing).
    pub fn emission(&self, radiance: Rgb, at: &Origin) -> Result<Option<Rgb>, SceneError> {
        if let Some(m) = light_value_error(&leaf(&at.key), radiance, MAX_RADIANCE) {
            return Err(self.err(at, m));
        }
        Ok(Some(radiance).filter(|l| l.max_element() > 0.0))
    }

    /// Starts a shape; its triangles and sphere follow (`triangle`, `sphere`).
    pub fn shape(&mut self, s: ShapeIn) -> usize {
        self.shapes.push(ShapeRec { shape: s, skipped: 0, flat: 0, kept: 0 });
        self.shapes.len() - 1
    }

    /// Adds a triangle of shape `s`: `p` after its transform, `raw` before. When the raw
    /// vertices are finite, a vertex outside the extent (after the transform: finite or not) is
    /// the extent error at `blame`; a degenerate triangle (zero area, a non-finite raw vertex) is
    /// skipped, with one warning per shape at `build`. `face` numbers the face in messages.
    pub fn triangle(
        &mut self,
        s: usize,
        (p, raw): ([Vec3; 3], [Vec3; 3]),
        corners: Corners,
        blame: &Origin,
        face: Option<usize>,
    ) -> Result<(), SceneError> {
        let far = p.iter().find(|q| !within_extent(**q)).filter(|_| raw.iter().all(|r| r.is_finite()));
        if let Some(q) = far {
            let at = face.map_or(String::new(), |k| {
                format!(" (face {} of {}, after the transform)", k + 1, self.shapes[s].shape.what)
            });
            return Err(self.err(blame, format!("{}{at}", extent_message("mesh vertex", *q))));
        }
        let rec = &mut self.shapes[s];
        let Some(t) = make_triangle(p, corners, rec.shape.material, rec.shape.exact_normals) else {
            rec.skipped += 1;
            return Ok(());
        };
        rec.flat += (corners.n.is_some() && t.n.is_none()) as usize;
        rec.kept += 1;
        self.triangles.push(t);
        self.tri_shape.push(s as u32);
        Ok(())
    }

    /// Gives the triangles of shape `s` the analytic parametrisation `uv` (a tessellated `disk`
    /// or `cylinder`) in place of per-vertex UVs.
    pub fn shape_uv(&mut self, s: usize, uv: ShapeUv) {
        self.shape_uvs.push((s as u32, uv));
    }

    /// Adds the analytic sphere of shape `s`: a positive finite radius, its bounds in the extent.
    pub fn sphere(
        &mut self,
        s: usize,
        (center, cat): (Vec3, &Origin),
        (radius, rat): (f32, &Origin),
        inward: bool,
        axes: [Vec3; 3],
    ) -> Result<(), SceneError> {
        if !within_extent(center) {
            return Err(self.err(cat, extent_message("sphere center", center)));
        }
        if !(radius.is_finite() && radius > 0.0) {
            return Err(self.err(rat, format!("radius must be positive and finite, got {radius}")));
        }
        let r = Vec3::splat(radius);
        if !within_extent(center - r) || !within_extent(center + r) {
            return Err(self.err(rat, extent_message("sphere bounds corner", center + r.copysign(center))));
        }
        let rec = &mut self.shapes[s];
        rec.kept += 1;
        let material = rec.shape.material;
        self.spheres.push(Sphere { center, radius, inward, axes, material, emitter: NO_EMITTER });
        self.sph_shape.push(s as u32);
        Ok(())
    }

    /// Adds a point light, or a spot light with `spot`: its position in the extent, its
    /// intensity checked.
    pub fn point_light(
        &mut self,
        (position, pat): (Vec3, &Origin),
        (intensity, iat): (Rgb, &Origin),
        spot: Option<super::Spot>,
    ) -> Result<(), SceneError> {
        if !within_extent(position) {
            return Err(self.err(pat, extent_message("point light position", position)));
        }
        if let Some(m) = light_value_error(&leaf(&iat.key), intensity, MAX_INTENSITY) {
            return Err(self.err(iat, m));
        }
        self.point_lights.push((PointLight { position, intensity, spot }, iat.clone()));
        Ok(())
    }

    /// Adds a directional light along `d` (any non-zero length), its irradiance checked as a
    /// radiance.
    pub fn directional_light(
        &mut self,
        (d, dat): (Vec3, &Origin),
        (irradiance, iat): (Rgb, &Origin),
    ) -> Result<(), SceneError> {
        let d = d.normalize();
        if !d.is_finite() {
            return Err(self.err(dat, "the direction must be a finite, non-zero vector"));
        }
        if let Some(m) = light_value_error(&leaf(&iat.key), irradiance, MAX_RADIANCE) {
            return Err(self.err(iat, m));
        }
        self.directional.push((DirectionalLight { d, irradiance }, iat.clone()));
        Ok(())
    }

    /// Sets the environment (`constant` or `envmap`, whose values the reader checked against
    /// `MAX_RADIANCE`); a second one is an error, as in Mitsuba.
    pub fn environment(&mut self, env: Environment, at: &Origin) -> Result<(), SceneError> {
        if let Some((_, first)) = &self.environment {
            let m = format!(
                "only one environment emitter (`constant`, `envmap`) per scene; the first is on line {}",
                first.line
            );
            return Err(self.err(at, m));
        }
        self.environment = Some((env, at.clone()));
        Ok(())
    }

    /// The shape warnings (degenerate triangles, flat-shaded ones), in shape order.
    fn shape_warnings(&mut self) {
        for i in 0..self.shapes.len() {
            let r = &self.shapes[i];
            let (at, what, skipped, flat) = (r.shape.at.clone(), r.shape.what.clone(), r.skipped, r.flat);
            if skipped > 0 {
                self.warn(&at, format!("skipped {skipped} degenerate triangle(s) in {what}"));
            }
            if flat > 0 {
                self.warn(&at, format!("{flat} triangle(s) in {what} have NaN or zero vertex normals; shaded flat"));
            }
        }
    }

    /// Refuses a scene without primitives, at the last shape whose triangles were all dropped.
    fn check_not_empty(&self, root: &Origin) -> Result<(), SceneError> {
        if !self.triangles.is_empty() || !self.spheres.is_empty() {
            return Ok(());
        }
        match self.shapes.iter().rev().find(|r| r.skipped > 0) {
            Some(r) => {
                let (n, what) = (r.skipped, &r.shape.what);
                Err(self
                    .err(&r.shape.at, format!("empty scene: no shapes (skipped {n} degenerate triangle(s) in {what})")))
            }
            None => Err(self.err(&Origin::new(root.line, "shape"), "empty scene: no shapes")),
        }
    }

    /// One emitter per primitive of an emitting shape, in primitive order (triangles, then
    /// spheres), with the origin of its radiance; sets each primitive's `emitter`.
    fn emitters(&mut self) -> (Vec<Emitter>, Vec<Origin>) {
        let (mut emitters, mut emitter_at) = (Vec::new(), Vec::new());
        let ntri = self.triangles.len();
        let prims: Vec<(usize, u32)> = (self.tri_shape.iter().copied().enumerate())
            .chain(self.sph_shape.iter().enumerate().map(|(i, &s)| (i + ntri, s)))
            .collect();
        for (prim, s) in prims {
            let Some((le, at)) = self.shapes[s as usize].shape.emission.clone() else { continue };
            let e = emitters.len() as u32;
            let area = if prim < ntri {
                self.triangles[prim].emitter = e;
                self.triangles[prim].area
            } else {
                let sp = &mut self.spheres[prim - ntri];
                sp.emitter = e;
                4.0 * PI * sp.radius * sp.radius
            };
            emitters.push(Emitter { prim: prim as u32, radiance: le, area });
            emitter_at.push(at);
        }
        (emitters, emitter_at)
    }

    /// Validates what is left (a camera, a shape, a light) and assembles the scene; `root` is the
    /// document's origin, `light_key` the format's key for "add a light".
    pub fn build(mut self, root: &Origin, light_key: &str) -> Result<Scene, SceneError> {
        let camera = self.camera.take().ok_or_else(|| self.err(root, "the scene has no camera"))?;
        self.shape_warnings();
        self.check_not_empty(root)?;
        let (emitters, emitter_at) = self.emitters();
        let (point_lights, light_at): (Vec<PointLight>, Vec<Origin>) = self.point_lights.drain(..).unzip();
        let (directional_lights, dir_at): (Vec<DirectionalLight>, Vec<Origin>) = self.directional.drain(..).unzip();
        let (environment, env_at) = self.environment.take().unzip();
        let mut lights: Vec<LightRef> = (0..emitters.len() as u32).map(LightRef::Area).collect();
        lights.extend((0..point_lights.len() as u32).map(LightRef::Point));
        lights.extend((0..directional_lights.len() as u32).map(LightRef::Directional));
        lights.extend(environment.iter().map(|_| LightRef::Environment));
        let (lo, hi) = bounds(&self.triangles, &self.spheres);
        let bsphere = BoundingSphere::of_box(lo, hi);
        let ls = Lights {
            emitters: &emitters,
            point_lights: &point_lights,
            directional: &directional_lights,
            environment: environment.as_ref(),
            bsphere,
        };
        let powers: Vec<f32> = lights.iter().map(|&l| light_power(&ls, l)).collect();
        if let Some(i) = powers.iter().position(|p| !p.is_finite()) {
            let at = match lights[i] {
                LightRef::Area(e) => &emitter_at[e as usize],
                LightRef::Point(p) => &light_at[p as usize],
                LightRef::Directional(d) => &dir_at[d as usize],
                LightRef::Environment => env_at.as_ref().expect("an environment light has its origin"),
            };
            return Err(self.err(
                at,
                "the light's power (radiance × area × π, 4π × intensity, or irradiance × the scene's cross-section) overflows f32",
            ));
        }
        let light_pick = Distribution1D::new(&powers).ok_or_else(|| {
            self.err(
                &Origin::new(root.line, light_key),
                "the scene has no light with positive power (an emitting shape, a point, spot or directional light, or an environment)",
            )
        })?;
        let bounds = bounds(&self.triangles, &self.spheres);
        Ok(Scene {
            path: self.file,
            hash: self.hash,
            mesh_files: self.mesh_files,
            camera,
            render: self.render,
            materials: self.materials,
            surfaces: self.surfaces,
            textures: self.textures,
            triangles: self.triangles,
            spheres: self.spheres,
            shape_uvs: ShapeUvs::new(&self.tri_shape, &self.shape_uvs),
            emitters,
            point_lights,
            directional_lights,
            environment,
            bsphere,
            lights,
            light_pick,
            rois: self.rois.into_iter().map(|(r, _)| r).collect(),
            forecast_target: self.forecast_target,
            forecast_photons: self.forecast_photons,
            bounds,
            warnings: self.warnings,
        })
    }
}

/// The last part of a dotted key (`shape[2].emission` → `emission`).
fn leaf(key: &str) -> String {
    key.rsplit('.').next().unwrap_or(key).to_string()
}

/// Scene bounds (min, max) over triangles and spheres.
fn bounds(triangles: &[Triangle], spheres: &[Sphere]) -> (Vec3, Vec3) {
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for t in triangles {
        for p in t.p {
            lo = lo.min(p);
            hi = hi.max(p);
        }
    }
    for s in spheres {
        lo = lo.min(s.center - Vec3::splat(s.radius));
        hi = hi.max(s.center + Vec3::splat(s.radius));
    }
    (lo, hi)
}

/// Builds a triangle, or `None` when degenerate (zero area or non-finite). Shading normals must
/// be finite and non-zero (else the triangle is shaded flat); they are normalised (kept as they
/// are when `exact` and of unit length to 1e-5) and flipped onto the geometric normal's side.
pub(super) fn make_triangle(p: [Vec3; 3], corners: Corners, material: u32, exact: bool) -> Option<Triangle> {
    let Corners { n, uv } = corners;
    let c = (p[1] - p[0]).cross(p[2] - p[0]);
    // scaled by the largest component first, so that |c|² cannot overflow (|c| up to 1e25)
    let m = c.abs().max_element();
    let len = if m > 0.0 { m * (c / m).length() } else { 0.0 };
    if !(len.is_finite() && len > 1e-12) {
        return None;
    }
    let ng = c / len;
    let n = n.and_then(|ns| {
        let ok = ns.iter().all(|v| v.is_finite() && v.length() > 1e-6);
        ok.then(|| {
            ns.map(|v| {
                let v = if exact && (v.length_squared() - 1.0).abs() <= 1e-5 { v } else { v.normalize() };
                if v.dot(ng) < 0.0 {
                    -v
                } else {
                    v
                }
            })
        })
    });
    Some(Triangle { p, n, uv, ng, area: 0.5 * len, material, emitter: NO_EMITTER })
}
