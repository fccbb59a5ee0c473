//! Mitsuba XML scenes (Mitsuba 3, and the 0.5/0.6/2.0 spellings Mitsuba 3 upgrades) → `Scene`,
//! for the subset documented in `scenes/README.md`: shapes (`shapes`), BSDFs (`bsdf`), `area`
//! and top-level emitters: `point`, `spot`, `directional`, `constant` and `envmap` (`emitters`),
//! the `perspective` sensor (every `fov_axis`; its film's crop window; a film and sampler given at
//! the top level with an `id` and named by its `<ref>`s), the sampler's `sample_count` (→ default
//! spp) and the integrator's `max_depth` (path segments: the vertex cap `max_depth` − 1).
//!
//! `<default>` values and `-D name=value` substitute `$name` (`xml`). forecast's own render
//! options, which Mitsuba has no place for, travel as `<default name="forecast_*">` values that
//! Mitsuba ignores (written by `export`): method, seed, time, photons, target box, ROIs.
//!
//! Invariants: a translator into `SceneBuilder`, which checks and assembles the scene exactly as
//! it does the TOML file's (material 0 black, triangles then spheres, emitters in primitive
//! order; the same extent, camera and light checks with the same words), so an exported TOML
//! scene loads back identical. Unsupported plugins and parameters that change the image are
//! errors naming the file, line, plugin and parameter; unknown parameters of supported plugins,
//! and every parameter of another renderer's integrator, are warnings (`Scene::warnings`, hence
//! the JSON report).

mod bsdf;
mod emitters;
mod params;
pub(super) mod presets;
mod shapes;
mod texture;
mod xml;

pub use shapes::SEGMENTS;

use crate::math::Vec3;
use crate::scene::builder::SceneBuilder;
use crate::scene::spec::{CameraSpec, Origin, View};
use crate::scene::{Material, Scene, SceneError};
use crate::texture::TextureCache;
use params::Plugin;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use xml::Node;

/// Loading state: the builder the elements go to, and the XML reader's own (ids, Mitsuba's
/// default BSDF).
pub(super) struct Cx {
    dir: PathBuf,
    b: SceneBuilder,
    ids: BTreeMap<String, u32>,
    /// Top-level textures by `id`.
    texture_ids: BTreeMap<String, u32>,
    /// The images decoded so far.
    textures: TextureCache,
    /// Top-level `<film>`s and `<sampler>`s by `id`, for a sensor's `<ref>`s.
    sensor_parts: BTreeMap<String, Node>,
    default_diffuse: Option<u32>,
}

impl Cx {
    fn err(&self, line: usize, key: &str, message: impl Into<String>) -> SceneError {
        self.b.err(&Origin::new(line, key), message)
    }
    fn warn(&mut self, line: usize, msg: String) {
        self.b.warn(&Origin::new(line, ""), msg);
    }
    /// Mitsuba's BSDF for shapes without one: `diffuse` with reflectance 0.5.
    fn default_diffuse(&mut self) -> u32 {
        if let Some(i) = self.default_diffuse {
            return i;
        }
        let i = self.b.material(Material::Diffuse { albedo: Vec3::splat(0.5) });
        *self.default_diffuse.insert(i)
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
        dir: dir.to_path_buf(),
        b: SceneBuilder::new(file, crate::math::fnv1a(0xcbf2_9ce4_8422_2325, src.as_bytes())),
        ids: BTreeMap::new(),
        texture_ids: BTreeMap::new(),
        textures: TextureCache::default(),
        sensor_parts: BTreeMap::new(),
        default_diffuse: None,
    };
    let (root, _version, vars) = xml::parse(src, defines).map_err(|(l, m)| cx.err(l, "", m))?;
    // the bitmaps' files decoded in parallel up front; each is taken, with its error, where the
    // loop below reaches it
    let mut files = Vec::new();
    texture::bitmap_files(&root, dir, &mut files);
    cx.textures.predecode(&files);
    let mut sensor_line = None;
    for n in &root.children {
        match n.tag.as_str() {
            "default" => {}
            "integrator" => integrator(&mut cx, n)?,
            "sensor" => {
                if let Some(first) = sensor_line {
                    let m = format!("only one sensor is supported (the first is on line {first})");
                    return Err(cx.err(n.line, "sensor", m));
                }
                sensor_line = Some(n.line);
                sensor(&mut cx, n)?;
            }
            "bsdf" => {
                bsdf::resolve(&mut cx, n)?;
            }
            "texture" => texture::declare(&mut cx, n)?,
            "shape" => shapes::shape(&mut cx, n)?,
            "film" | "sampler" => match n.attr("id") {
                Some(id) => {
                    cx.sensor_parts.insert(id.to_string(), n.clone());
                }
                None => {
                    let m = format!("a top-level `<{}>` needs an `id` for a sensor's `<ref>`", n.tag);
                    return Err(cx.err(n.line, &n.tag, m));
                }
            },
            "emitter" => emitters::emitter(&mut cx, n)?,
            t => {
                let what = format!("`<{t}>` is not supported (textures, media, includes, shape groups, ...)");
                return Err(cx.err(n.line, t, what));
            }
        }
    }
    if sensor_line.is_none() {
        return Err(cx.err(root.line, "sensor", "the scene has no `<sensor>`"));
    }
    options::forecast_defaults(&mut cx, &root, &vars)?;
    cx.b.build(&Origin::new(root.line, ""), "emitter")
}

/// The integrator's `max_depth`: Mitsuba counts path segments, so d bounds every path at d
/// segments (emitters reached at the d-th, next-event estimation at the first d − 1 surface
/// vertices), which is forecast's vertex cap d − 1 (`--max-depth` N: N surface vertices, NEE at
/// each, and the emitter the N-th one's BSDF sample reaches). 1 renders the emitters seen
/// directly; −1 (Mitsuba's "unlimited") leaves the default cap 64. Its type is not used: the
/// method is `--method`, so another renderer's integrator (`sppm`, `bdpt`, ...) and its
/// parameters are warnings (the unread parameters, by `Plugin::finish`), never errors.
fn integrator(cx: &mut Cx, n: &Node) -> Result<(), SceneError> {
    let mut p = Plugin::new(n);
    let dl = p.line_of("max_depth");
    match p.int(cx, "max_depth")?.unwrap_or(-1) {
        -1 => {}
        d if d >= 1 => cx.b.max_segments(d as u64, &Origin::new(dl, format!("{}.max_depth", n.ty())))?,
        d => {
            let m = format!("max_depth {d}: use -1 (unlimited) or a number of path segments >= 1");
            return Err(p.err(cx, dl, "max_depth", m));
        }
    }
    if !matches!(n.ty(), "path" | "volpath") {
        cx.warn(n.line, format!("integrator `{}` ignored (the method is forecast's `--method`)", n.ty()));
    }
    if p.boolean(cx, "hide_emitters")? == Some(true) {
        return Err(p.err(cx, n.line, "hide_emitters", "hiding emitters is not supported"));
    }
    p.finish(cx);
    Ok(())
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

/// The perspective sensor → the builder's camera, and the sampler's `sample_count` → spp.
fn sensor(cx: &mut Cx, n: &Node) -> Result<(), SceneError> {
    // a `<ref>` to a top-level film or sampler stands for it (Mitsuba 2's SMS scenes)
    let mut n = n.clone();
    for c in &mut n.children {
        if let Some(part) = c.attr("id").filter(|_| c.tag == "ref").and_then(|id| cx.sensor_parts.get(id)) {
            *c = part.clone();
        }
    }
    let n = &n;
    let mut p = Plugin::new(n);
    if n.ty() != "perspective" {
        return Err(cx.err(n.line, &format!("sensor.{}", n.ty()), format!("sensor `{}`: only `perspective`", n.ty())));
    }
    p.reject(cx, &["focal_length", "principal_point_offset_x", "principal_point_offset_y"], "use `fov`")?;
    let fl = p.line_of("fov");
    let Some(fov) = p.float(cx, "fov")? else { return Err(p.err(cx, n.line, "fov", "missing `fov`")) };
    let (axis, al) = p.string(cx, "fov_axis")?.unwrap_or(("x".into(), n.line));
    let xl = p.line_of("to_world");
    let xf = p.transform(cx, "to_world")?;
    let Film { size: [w, h], crop } = film(cx, &mut p)?;
    sampler(cx, &mut p)?;
    let fovy = fov_y(fov, &axis, w, h).ok_or_else(|| {
        p.err(cx, al, "fov_axis", format!("unknown fov_axis `{axis}` (x, y, smaller, larger, diagonal)"))
    })?;
    let at = |line: usize, k: &str| Origin::new(line, format!("perspective.{k}"));
    let (position, view) = camera_view(xf);
    cx.b.camera(CameraSpec {
        position: (position, at(xl, "to_world")),
        view: (view, at(xl, "to_world")),
        up_at: at(xl, "to_world"),
        fov: (fovy, at(fl, "fov")),
        resolution: ([w, h], at(n.line, "film")),
    })?;
    if let Some((offset, size)) = crop {
        cx.b.crop(offset, size);
    }
    p.finish(cx);
    Ok(())
}

/// A crop window: its offset and size in the film's pixels.
type Window = ([u32; 2], [u32; 2]);

/// What the sensor's film says: the full film's size and the crop window, if any.
struct Film {
    size: [u32; 2],
    /// The window, when it is not the whole film.
    crop: Option<Window>,
}

/// The film: `width`, `height` (Mitsuba's defaults 768 × 576); the crop window
/// (`crop_offset_x/y`, default 0; `crop_width/height`, default the film's), which must lie inside
/// the film, as Mitsuba requires; `rfilter` (a box is forecast's pixel; another filter warns);
/// the output's format (`file_format`, `pixel_format`, `component_format`: the output is an RGB
/// float EXR whatever they say, so they warn unless they already say that); `sample_border`
/// (with a box filter no sample crosses a pixel: read, warned when true); Mitsuba 0.6's `banner`,
/// `high_quality_edges` and 2's `compensate` (no effect on the image: read, ignored).
fn film(cx: &mut Cx, p: &mut Plugin) -> Result<Film, SceneError> {
    let (mut w, mut h) = (768u32, 576u32);
    let mut crop = None;
    let films = p.objects(&["film"]);
    only_one(cx, p, &films, "film")?;
    for f in films {
        film_type(cx, f)?;
        let mut fp = Plugin::new(f);
        let dim = |v: Option<i64>, d: u32| v.map_or(Ok(d), |v| u32::try_from(v).map_err(|_| ()));
        let (fw, fh) = (dim(fp.int(cx, "width")?, w), dim(fp.int(cx, "height")?, h));
        match (fw, fh) {
            (Ok(a), Ok(b)) if (1..=65536).contains(&a) && (1..=65536).contains(&b) => (w, h) = (a, b),
            _ => return Err(fp.err(cx, f.line, "width", "width and height must be in 1..=65536")),
        }
        crop = crop_window(cx, &mut fp, [w, h])?;
        for r in fp.objects(&["rfilter"]) {
            if r.ty() != "box" {
                cx.warn(r.line, format!("film: rfilter `{}` ignored (pixels are box-filtered)", r.ty()));
            }
        }
        for (k, fine) in [("file_format", &["openexr", "exr"][..]), ("pixel_format", &["rgb", "rgba"][..])] {
            if let Some((v, l)) = fp.string(cx, k)? {
                if !fine.contains(&v.to_ascii_lowercase().as_str()) {
                    cx.warn(l, format!("film: {k} `{v}` ignored (the output is an RGB OpenEXR image)"));
                }
            }
        }
        if let Some((v, l)) = fp.string(cx, "component_format")? {
            if v != "float32" {
                cx.warn(l, format!("film: component_format `{v}` ignored (the output is 32-bit float)"));
            }
        }
        if fp.boolean(cx, "sample_border")? == Some(true) {
            let m = "film: sample_border ignored (pixels are box-filtered: no sample reaches another pixel)";
            cx.warn(fp.line_of("sample_border"), m.into());
        }
        for k in ["banner", "high_quality_edges", "compensate"] {
            fp.find(k);
        }
        fp.finish(cx);
    }
    Ok(Film { size: [w, h], crop })
}

/// The film's crop window, `None` when it is the whole film. Mitsuba's rule: offset + size
/// inside the film; a window of no pixels is refused too.
fn crop_window(cx: &Cx, fp: &mut Plugin, [w, h]: [u32; 2]) -> Result<Option<Window>, SceneError> {
    let keys = ["crop_offset_x", "crop_offset_y", "crop_width", "crop_height"];
    let lines = keys.map(|k| fp.line_of(k));
    let mut v = [0u32, 0, w, h];
    for (i, k) in keys.iter().enumerate() {
        if let Some(x) = fp.int(cx, k)? {
            v[i] = u32::try_from(x).map_err(|_| fp.err(cx, lines[i], k, format!("{k} {x} must be >= 0")))?;
        }
    }
    let [ox, oy, cw, ch] = v;
    for (i, (o, s, full, axis)) in [(ox, cw, w, "width"), (oy, ch, h, "height")].into_iter().enumerate() {
        let (ko, ks) = (keys[i], keys[2 + i]);
        if s == 0 {
            return Err(fp.err(cx, lines[2 + i], ks, format!("{ks} 0: the crop window has no pixels")));
        }
        if u64::from(o) + u64::from(s) > u64::from(full) {
            // the key given last of the two is the one to blame, the size when both are given
            let given = |k: &str| fp.node.children.iter().any(|c| c.name() == k);
            let (k, l) = if given(ks) || !given(ko) { (ks, lines[2 + i]) } else { (ko, lines[i]) };
            let m = format!("the crop window lies outside the film: {ko} {o} + {ks} {s} > {axis} {full}");
            return Err(fp.err(cx, l, k, m));
        }
    }
    Ok((v != [0, 0, w, h]).then_some(([ox, oy], [cw, ch])))
}

/// A second `<film>` or `<sampler>` in the sensor is an error naming both lines (as a second
/// `<sensor>` is): Mitsuba would take one of them, silently.
fn only_one(cx: &Cx, p: &Plugin, nodes: &[&Node], tag: &str) -> Result<(), SceneError> {
    let [first, second, ..] = nodes else { return Ok(()) };
    let msg = format!("a second `<{tag}>` (the first is on line {}): a sensor has one {tag}", first.line);
    Err(p.err(cx, second.line, tag, msg))
}

/// The film's type: `hdrfilm` (the output is HDR whatever it is); `ldrfilm` (0.5/0.6) is read for
/// its size with a warning; `specfilm` (spectral sensitivities: other channels) and any other
/// film would change the image: an error.
fn film_type(cx: &mut Cx, f: &Node) -> Result<(), SceneError> {
    match f.ty() {
        "hdrfilm" => Ok(()),
        "ldrfilm" => {
            cx.warn(f.line, "film `ldrfilm`: read for its size only (the output is HDR, not tonemapped)".into());
            Ok(())
        }
        t => {
            let why =
                if t == "specfilm" { "its channels are spectral sensitivities, not RGB" } else { "only `hdrfilm`" };
            Err(cx.err(f.line, &format!("film.{t}"), format!("film `{t}` is not supported ({why})")))
        }
    }
}

/// The sampler's `sample_count` (Mitsuba's default 4) → the default spp, if there is a sampler.
fn sampler(cx: &mut Cx, p: &mut Plugin) -> Result<(), SceneError> {
    let samplers = p.objects(&["sampler"]);
    only_one(cx, p, &samplers, "sampler")?;
    for s in samplers {
        if s.ty() != "independent" {
            let m = format!("sampler `{}`: only its `sample_count` is read (forecast draws its own samples; the converged image is the same)", s.ty());
            cx.warn(s.line, m);
        }
        let mut sp = Plugin::new(s);
        let line = sp.line_of("sample_count");
        let c = sp.int(cx, "sample_count")?.unwrap_or(4);
        let c = u64::try_from(c)
            .map_err(|_| sp.err(cx, line, "sample_count", format!("sample_count must be positive, got {c}")))?;
        cx.b.spp(c, &Origin::new(line, format!("{}.sample_count", s.ty())))?;
        sp.finish(cx);
    }
    Ok(())
}

/// The camera of `to_world`: a lone `lookat` exactly as the TOML camera, else the matrix's
/// frame (position, forward = +z, up = +y, right = −x, Mitsuba's camera space). The builder
/// checks both (extent, a finite non-zero rigid frame).
fn camera_view(xf: Option<params::Xform>) -> (Vec3, View) {
    if let Some([o, t, u]) = xf.as_ref().and_then(|x| x.lookat) {
        let (target, up) = (Vec3::from_array(t), Vec3::from_array(u));
        return (Vec3::from_array(o), View::LookAt { target, up });
    }
    let m = xf.map_or(glam::DMat4::IDENTITY, |x| x.m);
    let (f, u, l) = (m.z_axis.truncate(), m.y_axis.truncate(), m.x_axis.truncate());
    let (forward, up, right) = (f.normalize().as_vec3(), u.normalize().as_vec3(), (-l.normalize()).as_vec3());
    (m.w_axis.truncate().as_vec3(), View::Frame { forward, up, right })
}

mod options;
