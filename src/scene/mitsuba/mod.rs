//! Mitsuba XML scenes (Mitsuba 3, and the 0.5/0.6/2.0 spellings Mitsuba 3 upgrades) → `Scene`,
//! for the subset documented in `scenes/README.md`: shapes (`shapes`), BSDFs (`bsdf`), `area`
//! and `point` emitters, the `perspective` sensor (every `fov_axis`), the sampler's
//! `sample_count` (→ default spp) and the integrator's `max_depth` (→ the vertex cap).
//!
//! `<default>` values and `-D name=value` substitute `$name` (`xml`). forecast's own render
//! options, which Mitsuba has no place for, travel as `<default name="forecast_*">` values that
//! Mitsuba ignores (written by `export`): method, seed, time, photons, target box, ROIs.
//!
//! Invariants: the result is assembled exactly as the TOML loader assembles its scene (material
//! 0 black, triangles then spheres, emitters in primitive order), so an exported TOML scene loads
//! back identical. Unsupported plugins and parameters that change the image are errors naming
//! the file, line, plugin and parameter; unknown parameters of supported plugins are warnings
//! (`Scene::warnings`, hence the JSON report).

mod bsdf;
mod params;
mod presets;
mod shapes;
mod xml;

pub use shapes::SEGMENTS;

use crate::math::Vec3;
use crate::scene::{limits, Camera, Material, PointLight, RenderDefaults, Scene, SceneError};
use params::Plugin;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use xml::Node;

/// Loading state.
pub(super) struct Cx {
    file: String,
    dir: PathBuf,
    warnings: Vec<String>,
    hash: u64,
    materials: Vec<Material>,
    ids: BTreeMap<String, u32>,
    default_diffuse: Option<u32>,
}

impl Cx {
    fn err(&self, line: usize, key: &str, message: impl Into<String>) -> SceneError {
        SceneError { file: self.file.clone(), line, key: key.to_string(), message: message.into() }
    }
    fn warn(&mut self, line: usize, msg: String) {
        self.warnings.push(format!("{}:{line}: {msg}", self.file));
    }
    /// Mitsuba's BSDF for shapes without one: `diffuse` with reflectance 0.5.
    fn default_diffuse(&mut self) -> u32 {
        *self.default_diffuse.get_or_insert_with(|| {
            self.materials.push(Material::Diffuse { albedo: Vec3::splat(0.5) });
            self.materials.len() as u32 - 1
        })
    }
}

/// Loads a Mitsuba XML scene with `-D` overrides.
pub fn load(path: &Path, defines: &[(String, String)]) -> Result<Scene, SceneError> {
    let file = path.display().to_string();
    let src = std::fs::read_to_string(path).map_err(|e| SceneError {
        file: file.clone(),
        line: 0,
        key: String::new(),
        message: format!("cannot read scene file: {e}"),
    })?;
    load_str(&src, &file, path.parent().unwrap_or(Path::new(".")), defines)
}

/// Parses Mitsuba XML text; `dir` resolves mesh paths; `file` is used in messages.
pub fn load_str(src: &str, file: &str, dir: &Path, defines: &[(String, String)]) -> Result<Scene, SceneError> {
    let mut cx = Cx {
        file: file.to_string(),
        dir: dir.to_path_buf(),
        warnings: Vec::new(),
        hash: crate::math::fnv1a(0xcbf2_9ce4_8422_2325, src.as_bytes()),
        materials: vec![Material::Black],
        ids: BTreeMap::new(),
        default_diffuse: None,
    };
    let (root, _version, vars) = xml::parse(src, defines).map_err(|(l, m)| cx.err(l, "", m))?;
    let mut camera = None;
    let mut render =
        RenderDefaults { method: crate::scene::AUTO_METHOD.into(), spp: None, time: None, seed: 0, max_depth: 64 };
    let mut shapes = Vec::new();
    let mut point_lights = Vec::new();
    for n in &root.children {
        match n.tag.as_str() {
            "default" => {}
            "integrator" => render.max_depth = integrator(&mut cx, n)?,
            "sensor" => {
                if camera.is_some() {
                    return Err(cx.err(n.line, "sensor", "only one sensor is supported"));
                }
                let (c, spp) = sensor(&mut cx, n)?;
                camera = Some(c);
                render.spp = spp;
            }
            "bsdf" => {
                bsdf::resolve(&mut cx, n)?;
            }
            "shape" => shapes.push(shapes::shape(&mut cx, n)?),
            "emitter" => point_lights.push(point(&mut cx, n)?),
            t => {
                let what = format!("`<{t}>` is not supported (textures, media, includes, shape groups, ...)");
                return Err(cx.err(n.line, t, what));
            }
        }
    }
    let camera = camera.ok_or_else(|| cx.err(root.line, "sensor", "the scene has no `<sensor>`"))?;
    let extras = forecast_defaults(&cx, &root, &vars, &mut render, &camera)?;
    assemble(cx, camera, render, shapes, point_lights, extras)
}

/// The integrator's `max_depth` (−1: the default cap 64); its type is not used.
fn integrator(cx: &mut Cx, n: &Node) -> Result<u32, SceneError> {
    let mut p = Plugin::new(n);
    let d = p.int(cx, "max_depth")?.unwrap_or(-1);
    let depth = match d {
        -1 => 64,
        d if (2..=1_000_000).contains(&d) => d as u32,
        d => return Err(p.err(cx, n.line, "max_depth", format!("max_depth {d}: use -1 or a value >= 2"))),
    };
    if !matches!(n.ty(), "path" | "volpath") {
        cx.warn(n.line, format!("integrator `{}` ignored (the method is forecast's `--method`)", n.ty()));
        if let Some(c) = n.children.iter().find(|c| c.name() != "max_depth") {
            let msg = format!("integrator `{}`: parameter `{}` is not supported", n.ty(), c.name());
            return Err(cx.err(c.line, &format!("{}.{}", n.ty(), c.name()), msg));
        }
    }
    if p.boolean(cx, "hide_emitters")? == Some(true) {
        return Err(p.err(cx, n.line, "hide_emitters", "hiding emitters is not supported"));
    }
    p.finish(cx);
    Ok(depth)
}

/// Vertical field of view (degrees) from Mitsuba's `fov` along `axis`.
fn fov_y(fov: f32, axis: &str, w: u32, h: u32) -> Option<f32> {
    let a = w as f64 / h as f64;
    let t = (fov as f64).to_radians() * 0.5;
    let from_x = |t: f64| Some((2.0 * (t.tan() / a).atan()).to_degrees() as f32);
    match axis {
        "y" => Some(fov),
        "x" => from_x(t),
        "smaller" | "larger" if (axis == "smaller") == (w >= h) => Some(fov),
        "smaller" | "larger" => from_x(t),
        "diagonal" => Some((2.0 * (t.tan() / (1.0 + a * a).sqrt()).atan()).to_degrees() as f32),
        _ => None,
    }
}

/// The perspective sensor → camera, and the sampler's `sample_count`.
fn sensor(cx: &mut Cx, n: &Node) -> Result<(Camera, Option<u64>), SceneError> {
    let mut p = Plugin::new(n);
    if n.ty() != "perspective" {
        return Err(cx.err(n.line, &format!("sensor.{}", n.ty()), format!("sensor `{}`: only `perspective`", n.ty())));
    }
    p.reject(cx, &["focal_length", "principal_point_offset_x", "principal_point_offset_y"], "use `fov`")?;
    let Some(fov) = p.float(cx, "fov")? else { return Err(p.err(cx, n.line, "fov", "missing `fov`")) };
    let (axis, al) = p.string(cx, "fov_axis")?.unwrap_or(("x".into(), n.line));
    let xf = p.transform(cx, "to_world")?;
    let ((w, h), spp) = (film(cx, &mut p)?, sampler(cx, &mut p)?);
    let fovy = fov_y(fov, &axis, w, h).ok_or_else(|| {
        p.err(cx, al, "fov_axis", format!("unknown fov_axis `{axis}` (x, y, smaller, larger, diagonal)"))
    })?;
    if !(fovy > 0.0 && fovy < 180.0) {
        return Err(p.err(cx, n.line, "fov", format!("fov must give a vertical fov in (0, 180), got {fovy}")));
    }
    let camera = camera_from(cx, &p, xf, fovy, (w, h))?;
    p.finish(cx);
    Ok((camera, spp))
}

/// The film's `width`, `height` (Mitsuba's defaults 768 × 576).
fn film(cx: &mut Cx, p: &mut Plugin) -> Result<(u32, u32), SceneError> {
    let (mut w, mut h) = (768u32, 576u32);
    for f in p.objects(&["film"]) {
        let mut fp = Plugin::new(f);
        fp.reject(cx, &["crop_offset_x", "crop_offset_y", "crop_width", "crop_height"], "crop the output instead")?;
        let dim = |v: Option<i64>, d: u32| v.map_or(Ok(d), |v| u32::try_from(v).map_err(|_| ()));
        let (fw, fh) = (dim(fp.int(cx, "width")?, w), dim(fp.int(cx, "height")?, h));
        match (fw, fh) {
            (Ok(a), Ok(b)) if (1..=65536).contains(&a) && (1..=65536).contains(&b) => (w, h) = (a, b),
            _ => return Err(fp.err(cx, f.line, "width", "width and height must be in 1..=65536")),
        }
        for r in fp.objects(&["rfilter"]) {
            if r.ty() != "box" {
                cx.warn(r.line, format!("film: rfilter `{}` ignored (pixels are box-filtered)", r.ty()));
            }
        }
        fp.finish(cx);
    }
    Ok((w, h))
}

/// The sampler's `sample_count` (Mitsuba's default 4), if there is a sampler.
fn sampler(cx: &mut Cx, p: &mut Plugin) -> Result<Option<u64>, SceneError> {
    let mut spp = None;
    for s in p.objects(&["sampler"]) {
        let mut sp = Plugin::new(s);
        let c = sp.int(cx, "sample_count")?.unwrap_or(4);
        spp =
            Some(u64::try_from(c).ok().filter(|&c| c > 0).ok_or_else(|| {
                sp.err(cx, s.line, "sample_count", format!("sample_count must be positive, got {c}"))
            })?);
        sp.finish(cx);
    }
    Ok(spp)
}

/// The camera of `to_world`: a lone `lookat` exactly as the TOML camera, else the matrix's
/// frame (position, forward = +z, up = +y, right = −x, Mitsuba's camera space).
fn camera_from(
    cx: &Cx,
    p: &Plugin,
    xf: Option<params::Xform>,
    fovy: f32,
    (w, h): (u32, u32),
) -> Result<Camera, SceneError> {
    if let Some([o, t, u]) = xf.as_ref().and_then(|x| x.lookat) {
        return Ok(Camera::new(Vec3::from_array(o), Vec3::from_array(t), Vec3::from_array(u), fovy, w, h));
    }
    let m = xf.map_or(glam::DMat4::IDENTITY, |x| x.m);
    let (f, u, l) = (m.z_axis.truncate(), m.y_axis.truncate(), m.x_axis.truncate());
    let (f, u, r) = (f.normalize(), u.normalize(), -l.normalize());
    if f.dot(u).abs() > 1e-4 || f.dot(r).abs() > 1e-4 || u.dot(r).abs() > 1e-4 || !f.is_finite() {
        return Err(p.err(cx, p.node.line, "to_world", "the camera transform must be rigid (no shear)"));
    }
    let position = m.w_axis.truncate().as_vec3();
    let (forward, right, up) = (f.as_vec3(), r.as_vec3(), u.as_vec3());
    Ok(Camera { position, forward, right, up, fov_deg: fovy, width: w, height: h })
}

/// A top-level `point` emitter.
fn point(cx: &mut Cx, n: &Node) -> Result<PointLight, SceneError> {
    if n.ty() != "point" {
        let msg = format!("emitter `{}` is not supported (`point` at the top level, `area` inside shapes)", n.ty());
        return Err(cx.err(n.line, &format!("emitter.{}", n.ty()), msg));
    }
    let mut p = Plugin::new(n);
    let pos = p.point(cx, "position")?.map(Vec3::from_array);
    let xf = p.transform(cx, "to_world")?;
    let position = pos.or(xf.map(|x| x.m.w_axis.truncate().as_vec3())).unwrap_or(Vec3::ZERO);
    let intensity = p.color(cx, "intensity")?.unwrap_or(Vec3::ONE);
    if let Some(m) = limits::light_value_error("intensity", intensity, limits::MAX_INTENSITY) {
        return Err(p.err(cx, n.line, "intensity", m));
    }
    p.finish(cx);
    Ok(PointLight { position, intensity })
}

mod assemble;
use assemble::{assemble, forecast_defaults};
