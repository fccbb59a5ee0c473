//! The TOML scene file (documented in `scenes/README.md` and `docs/scene-formats.md`): a
//! translator into `SceneBuilder`, which checks what every format shares (extents, camera, light
//! limits, degenerate triangles, emitters, the light pick). This file checks what is TOML's own:
//! the schema (`schema`), material values, quads, mesh transforms.
//!
//! Every error names the file, the line and the key (`SceneError`'s Display is
//! `file:line: key `k`: message`). Unknown keys are errors. Degenerate triangles are skipped with a
//! warning; everything else that is wrong (NaN, negative values, zero-area lights, a bad fov, a
//! missing OBJ, an empty scene) is an error, never a panic.

mod ctx;
mod params;

use super::builder::SceneBuilder;
use super::limits::{self, extent_message, within_extent};
use super::plugins;
use super::schema::{Doc, LightDef, MaterialDef, ShapeDef};
use super::spec::{CameraSpec, Corners, Origin, ShapeIn, View};
use super::{locate, Material, Scene, SceneError, Surface};
use crate::math::{fnv1a, Vec2, Vec3};
use crate::texture::{BitmapParams, TextureCache};
use ctx::Ctx;
use params::{TomlParams, PARAM_KEYS};
use std::collections::BTreeMap;
use std::path::Path;

/// The smallest quad area |u × v| (its two triangles' doubled area; `make_triangle` drops less).
const MIN_QUAD_AREA: f32 = 1e-12;

fn finite3(v: [f32; 3]) -> bool {
    v.iter().all(|x| x.is_finite())
}

fn v3(a: [f32; 3]) -> Vec3 {
    Vec3::from_array(a)
}

/// Loads a scene file (and the OBJ files it names).
pub fn load(path: &Path) -> Result<Scene, SceneError> {
    let file = path.display().to_string();
    let fail = |message: String| SceneError { file: file.clone(), line: 0, key: String::new(), message };
    limits::check_regular_file(path, "scene file").map_err(fail)?;
    let src = std::fs::read_to_string(path).map_err(|e| fail(format!("cannot read scene file: {e}")))?;
    let dir = path.parent().unwrap_or(Path::new("."));
    load_str(&src, &file, dir)
}

/// Parses scene text; `dir` resolves relative mesh paths; `file` is used in messages.
pub fn load_str(src: &str, file: &str, dir: &Path) -> Result<Scene, SceneError> {
    let starts = std::iter::once(0).chain(src.match_indices('\n').map(|(i, _)| i + 1)).collect();
    let cx = Ctx { file: file.to_string(), src, starts };
    let doc = parse_doc(&cx)?;
    let mut b = SceneBuilder::new(file, fnv1a(0xcbf2_9ce4_8422_2325, src.as_bytes()));
    camera(&cx, &mut b, &doc)?;
    render(&cx, &mut b, &doc)?;
    let names = materials(&cx, &mut b, &doc, dir)?;
    for idx in 0..doc.shape.len() {
        shape(&cx, &mut b, &doc, &names, dir, idx)?;
    }
    for (idx, l) in doc.light.iter().enumerate() {
        let ls = l.span();
        let key = |k: &str| format!("light[{idx}].{k}");
        let def = l.get_ref().resolve().map_err(|(k, m)| cx.err(ls.clone(), &key(&k), m))?;
        let at = |k: &str| cx.at(ls.clone(), &key(k));
        match def {
            LightDef::Point { position, intensity } => {
                b.point_light((v3(position), &at("position")), (v3(intensity), &at("intensity")), None)?;
            }
            LightDef::Spot { position, intensity, direction, cutoff, beam } => {
                let d = v3(direction).normalize();
                if !d.is_finite() {
                    return Err(cx.err(
                        ls.clone(),
                        &key("direction"),
                        "the direction must be a finite, non-zero vector",
                    ));
                }
                let spot =
                    super::Spot::new(d, Vec3::X, cutoff, beam).map_err(|(k, m)| cx.err(ls.clone(), &key(k), m))?;
                b.point_light((v3(position), &at("position")), (v3(intensity), &at("intensity")), Some(spot))?;
            }
            LightDef::Directional { direction, irradiance } => {
                b.directional_light((v3(direction), &at("direction")), (v3(irradiance), &at("irradiance")))?;
            }
            LightDef::Constant { radiance } => {
                let l = v3(radiance);
                if let Some(m) = limits::light_value_error("radiance", l, super::limits::MAX_RADIANCE) {
                    return Err(cx.err(ls.clone(), &key("radiance"), m));
                }
                b.environment(super::Environment::constant(l), &at("radiance"))?;
            }
        }
    }
    extras(&cx, &mut b, &doc)?;
    b.build(&Origin::new(1, ""), "shape.emission")
}

/// The TOML document, its errors with the key's line; serde's struct names in words.
fn parse_doc(cx: &Ctx) -> Result<Doc, SceneError> {
    let src = cx.src;
    toml::from_str(src).map_err(|e| {
        let line = e.span().map(|s| cx.line_of(s.start)).unwrap_or(0);
        let msg = in_words(e.message().trim());
        let key = msg
            .split('`')
            .nth(1)
            .filter(|_| msg.contains("unknown field") || msg.contains("missing field"))
            .unwrap_or("")
            .to_string();
        let from = e.span().map_or(0, |s| s.start);
        if msg == "duplicate key" {
            // toml names neither the key nor the table: the span is the repeated key's
            if let Some((l, path, m)) = e.span().and_then(|_| locate::duplicate_at(src, from)) {
                return SceneError { file: cx.file.clone(), line: l, key: path, message: m };
            }
        }
        let missing = msg.contains("missing field");
        if let Some((l, path)) = e.span().and_then(|_| inline_path(cx, from, &key, missing)) {
            return SceneError { file: cx.file.clone(), line: l, key: path, message: msg };
        }
        if !key.is_empty() {
            // the span may cover a whole table (or array of tables): find the key's own line
            // (a missing key: the table's header) and name the key with its table's path
            let missing = missing && key != "camera"; // `camera`: the document's
            if let Some((l, path)) = e.span().and_then(|_| locate::field_at(src, from, &key, missing)) {
                return SceneError { file: cx.file.clone(), line: l, key: path, message: msg };
            }
        } else if let Some((l, path)) = e.span().and_then(|_| locate::key_path_at(src, from)) {
            // a value error (wrong type, bad length): the span is the value's; name its key
            return SceneError { file: cx.file.clone(), line: l, key: path, message: msg };
        }
        SceneError { file: cx.file.clone(), line, key, message: msg }
    })
}

/// The line and dotted key path of a deserialization error at byte `from` inside an inline table
/// (`reflectance = { type = "bitmap", raw = 1 }`): the key at `from` (an unknown one), or the key
/// whose value starts at `from`, and with `missing` the table at `from` and the missing `key`
/// (`materials.wood.reflectance.raw`). `None` outside inline tables (`locate` finds those).
fn inline_path(cx: &Ctx, from: usize, key: &str, missing: bool) -> Option<(usize, String)> {
    let src = cx.src;
    let (key_line, base) = locate::key_path_at(src, from)?;
    let line_start = *cx.starts.get(key_line - 1)?;
    let text = src.get(line_start..from)?;
    let is_word = |c: u8| c.is_ascii_alphanumeric() || c == b'_' || c == b'-';
    // the keys of the inline tables open at `from`, and the last `key =` read
    let (mut open, mut last) = (Vec::<Option<&str>>::new(), None::<&str>);
    let b = text.as_bytes();
    let mut i = text.find('=')? + 1;
    while i < b.len() {
        match b[i] {
            q @ (b'"' | b'\'') => {
                i += 1;
                while i < b.len() && b[i] != q {
                    i += if b[i] == b'\\' && q == b'"' { 2 } else { 1 };
                }
            }
            b'{' => open.push(last.take()),
            b'}' => {
                open.pop();
                last = None;
            }
            c if is_word(c) => {
                let s = i;
                while i < b.len() && is_word(b[i]) {
                    i += 1;
                }
                if text[i..].trim_start().starts_with('=') {
                    last = Some(&text[s..i]);
                }
                continue;
            }
            _ => {}
        }
        i += 1;
    }
    let rest = &src[from..];
    let at_table = rest.starts_with('{');
    if open.is_empty() && !at_table {
        return None;
    }
    // the first `{` opens the value of the line's own key (`base`)
    let mut path: Vec<&str> = std::iter::once(base.as_str()).chain(open.into_iter().flatten()).collect();
    let word = rest.bytes().take_while(|c| is_word(*c)).count();
    if word > 0 && rest[word..].trim_start().starts_with('=') {
        path.push(&rest[..word]);
    } else if let Some(l) = last {
        path.push(l);
    }
    if missing && at_table {
        path.push(key);
    }
    Some((cx.line_of(from), path.join(".")))
}

/// serde's messages name the schema's Rust types (`expected struct MaterialRaw`): the words a
/// scene author knows instead.
fn in_words(msg: &str) -> String {
    const WORDS: [(&str, &str); 10] = [
        ("struct Doc", "a scene file ([camera], [render], [materials.NAME], [[shape]], [[light]], ...)"),
        ("struct CameraDef", "the [camera] table"),
        ("struct RenderDef", "the [render] table"),
        (
            "struct MaterialRaw",
            "a material table `[materials.NAME]` with a `type` (a key directly under [materials] must be such a table)",
        ),
        ("struct ShapeRaw", "a `[[shape]]` table"),
        ("struct LightRaw", "a `[[light]]` table"),
        ("struct RoiDef", "a `[[roi]]` table"),
        ("struct ForecastDef", "the [forecast] table"),
        ("struct TextureRaw", "a texture table (`{ type = \"bitmap\", filename = ... }`)"),
        ("struct UvRaw", "a `to_uv` table (`{ scale = [su, sv], rotate = degrees, translate = [tu, tv] }`)"),
    ];
    let mut m = msg.to_string();
    for (rust, words) in WORDS {
        m = m.replace(rust, words);
    }
    m
}

fn camera(cx: &Ctx, b: &mut SceneBuilder, doc: &Doc) -> Result<(), SceneError> {
    let cs = doc.camera.span();
    let c = doc.camera.get_ref();
    let at = |k: &str| cx.at(cs.clone(), &format!("camera.{k}"));
    b.camera(CameraSpec {
        position: (v3(c.position), at("position")),
        view: (View::LookAt { target: v3(c.look_at), up: v3(c.up) }, at("look_at")),
        up_at: at("up"),
        fov: (c.fov, at("fov")),
        resolution: (c.resolution, at("resolution")),
    })
}

fn render(cx: &Ctx, b: &mut SceneBuilder, doc: &Doc) -> Result<(), SceneError> {
    let Some(r) = &doc.render else { return Ok(()) };
    let rs = r.span();
    let r = r.get_ref();
    let at = |k: &str| cx.at(rs.clone(), &format!("render.{k}"));
    if let Some(m) = &r.method {
        b.method(m, &at("method"))?;
    }
    // the limits shared with the command line (crate::param_limits)
    if let Some(s) = r.spp {
        b.spp(s, &at("spp"))?;
    }
    if let (Some(_), Some(_)) = (r.spp, &r.time) {
        let m = "`spp` and `time` exclude each other (as --spp and --time): give one";
        return Err(b.err(&at("time"), m));
    }
    if let Some(t) = &r.time {
        b.time(t, &at("time"))?;
    }
    b.render.seed = r.seed.unwrap_or(0);
    if let Some(d) = r.max_depth {
        b.max_depth(d.into(), &at("max_depth"))?;
    }
    for (key, value) in &r.options {
        let line = at(key).line;
        let value = match value {
            toml::Value::String(s) => s.clone(),
            toml::Value::Integer(i) => i.to_string(),
            toml::Value::Float(f) => f.to_string(),
            toml::Value::Boolean(v) => v.to_string(),
            other => {
                let m =
                    format!("a method option takes a number or a string, as its flag does; got a {}", other.type_str());
                return Err(b.err(&at(key), m));
            }
        };
        b.render.options.push(crate::scene::RenderOption { key: key.clone(), value, line });
    }
    b.render.options.sort_by_key(|o| o.line);
    Ok(())
}

fn materials<'d>(
    cx: &Ctx,
    b: &mut SceneBuilder,
    doc: &'d Doc,
    dir: &Path,
) -> Result<BTreeMap<&'d str, u32>, SceneError> {
    let mut names = BTreeMap::new();
    let mut cache = TextureCache::default();
    for (name, m) in &doc.materials {
        let (ms, raw) = (m.span(), m.get_ref());
        let key = format!("materials.{name}");
        let bad = |k: &str, msg: &str| cx.err(ms.clone(), &format!("{key}.{k}"), msg);
        let def = raw.resolve().map_err(|(k, msg)| bad(&k, &msg))?;
        let mut p =
            TomlParams { cx, b, cache: &mut cache, dir, raw, span: ms.clone(), key: key.clone(), read: Vec::new() };
        let mut textures = Vec::new();
        let mat = match def {
            MaterialDef::Diffuse => plugins::diffuse(&mut p, "albedo", &mut textures)?,
            MaterialDef::Glossy { albedo, specular, exponent } => {
                let a = plugins::refl(&p, v3(albedo), "albedo")?;
                let s = plugins::refl(&p, v3(specular), "specular")?;
                if (a + s).max_element() > 1.0 + 1e-6 {
                    return Err(bad("specular", "albedo + specular must be <= 1 per channel (energy conservation)"));
                }
                if !(exponent.is_finite() && (0.0..=1e6).contains(&exponent)) {
                    return Err(bad("exponent", "exponent must be finite and in [0, 1e6]"));
                }
                Material::Glossy { albedo: a, specular: s, exponent }
            }
            MaterialDef::Mirror { reflectance } => {
                Material::Mirror { reflectance: plugins::refl(&p, v3(reflectance), "reflectance")? }
            }
            MaterialDef::Glass { ior } => {
                if !(ior.is_finite() && (1.0..=10.0).contains(&ior)) {
                    return Err(bad("ior", "ior must be finite and in [1, 10]"));
                }
                Material::Glass { ior }
            }
            MaterialDef::Plugin(kind) => {
                if raw.has("alpha") && (raw.has("alpha_u") || raw.has("alpha_v")) {
                    return Err(bad("alpha", "give `alpha`, or `alpha_u` and `alpha_v`, not both"));
                }
                let built = plugins::plugin(&mut p, kind)?.expect("every plugin type of the schema is built");
                if let Some(k) = PARAM_KEYS.iter().find(|k| raw.has(k) && !p.read.contains(k)) {
                    return Err(bad(k, &format!("key `{k}` has no effect with the other keys of this `{kind}`")));
                }
                textures = built.textures;
                built.m
            }
        };
        // a normal map's texture after the material's own, as the XML reader registers them
        let normalmap = match raw.normalmap() {
            Some(f) => {
                let params = BitmapParams { raw: true, ..BitmapParams::new(dir.join(f)) };
                let t = plugins::bitmap(b, &mut cache, &params).map_err(|e| bad("normalmap", &e))?;
                Some(b.texture(t))
            }
            None => None,
        };
        let two_sided = raw.twosided() || mat.is_two_sided_by_nature();
        let surface = Surface { two_sided, textures, normalmap, ..Surface::one_sided(&mat) };
        names.insert(name.as_str(), b.material_with(mat, surface));
    }
    Ok(names)
}

/// A shape's material index and emission: emitters reflect nothing (material 0) but a material
/// they name must exist; a zero emission without a material is a black absorber.
fn material_and_emission(
    cx: &Ctx,
    b: &SceneBuilder,
    names: &BTreeMap<&str, u32>,
    (ss, idx): (std::ops::Range<usize>, usize),
    mat: &Option<String>,
    emission: &Option<[f32; 3]>,
) -> Result<(u32, Option<(Vec3, Origin)>), SceneError> {
    let key = |k: &str| format!("shape[{idx}].{k}");
    let unknown = |m: &str| cx.err(ss.clone(), &key("material"), format!("unknown material `{m}`"));
    let known = mat.as_ref().map(|m| names.get(m.as_str()).copied().ok_or_else(|| unknown(m))).transpose()?;
    let e = match emission {
        Some(e) => {
            let at = cx.at(ss.clone(), &key("emission"));
            b.emission(v3(*e), &at)?.map(|e| (e, at))
        }
        None => None,
    };
    if e.is_some() || (emission.is_some() && mat.is_none()) {
        return Ok((0, e));
    }
    known.map(|i| (i, None)).ok_or_else(|| cx.err(ss, &key("material"), "a shape needs `material` (or `emission`)"))
}

fn shape(
    cx: &Ctx,
    b: &mut SceneBuilder,
    doc: &Doc,
    names: &BTreeMap<&str, u32>,
    dir: &Path,
    idx: usize,
) -> Result<(), SceneError> {
    let s = &doc.shape[idx];
    let ss = s.span();
    let key = |k: &str| format!("shape[{idx}].{k}");
    let at = |k: &str| cx.at(ss.clone(), &key(k));
    let def = s.get_ref().resolve().map_err(|(k, m)| cx.err(ss.clone(), &key(&k), m))?;
    let begin = |b: &mut SceneBuilder, material, emission, k: &str, what: String| {
        let (material, emission) = material_and_emission(cx, b, names, (ss.clone(), idx), material, emission)?;
        Ok::<_, SceneError>(b.shape(ShapeIn { at: at(k), material, emission, what, exact_normals: false }))
    };
    match &def {
        ShapeDef::Quad { corner, u, v, material, emission } => {
            for (k, a) in [("corner", corner), ("u", u), ("v", v)] {
                if !finite3(*a) {
                    return Err(cx.err(ss, &key(k), format!("quad `{k}` must be finite, got {a:?}")));
                }
            }
            let id = begin(b, material, emission, "v", format!("quad shape[{idx}]"))?;
            let (c, u, v) = (v3(*corner), v3(*u), v3(*v));
            // the vertex that leaves the extent names the vector that took it there
            let blame = if u.abs().max_element() >= v.abs().max_element() { "u" } else { "v" };
            for (k, p) in [("corner", c), ("u", c + u), ("v", c + v), (blame, c + u + v)] {
                if !within_extent(p) {
                    return Err(cx.err(ss, &key(k), extent_message("quad vertex", p)));
                }
            }
            let area = u.cross(v).length();
            if area < MIN_QUAD_AREA {
                let m = if area == 0.0 {
                    "zero-area quad (u × v = 0)".to_string()
                } else {
                    format!("quad too small: area |u × v| = {area:e} is below the limit {MIN_QUAD_AREA:e}")
                };
                return Err(cx.err(ss, &key("v"), m));
            }
            let (o, x, xy, y) = (Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y);
            for (p, uv) in [([c, c + u, c + u + v], [o, x, xy]), ([c, c + u + v, c + v], [o, xy, y])] {
                b.triangle(id, (p, p), Corners { n: None, uv: Some(uv) }, &at("v"), None)?;
            }
        }
        ShapeDef::Sphere { center, radius, material, emission, inward } => {
            if !finite3(*center) {
                return Err(cx.err(ss, &key("center"), "center must be finite"));
            }
            let id = begin(b, material, emission, "radius", format!("sphere shape[{idx}]"))?;
            b.sphere(id, (v3(*center), &at("center")), (*radius, &at("radius")), *inward, Vec3::AXES)?;
        }
        ShapeDef::Mesh { material, emission, file, .. } => {
            let id = begin(b, material, emission, "file", dir.join(file).display().to_string())?;
            mesh(cx, b, &def, dir, (ss, idx), id)?;
        }
    }
    Ok(())
}

/// A `type = "mesh"` shape's triangles (shape `id` begun): the file, its transform.
fn mesh(
    cx: &Ctx,
    b: &mut SceneBuilder,
    def: &ShapeDef,
    dir: &Path,
    (ss, idx): (std::ops::Range<usize>, usize),
    id: usize,
) -> Result<(), SceneError> {
    let ShapeDef::Mesh { file: f, normals, translate, scale, rotate_y, .. } = def else { return Ok(()) };
    let key = |k: &str| format!("shape[{idx}].{k}");
    let at = |k: &str| cx.at(ss.clone(), &key(k));
    let smooth = match normals.as_str() {
        "flat" => false,
        "smooth" => true,
        other => {
            let m = format!("normals must be `flat` or `smooth`, got `{other}`");
            return Err(cx.err(ss, &key("normals"), m));
        }
    };
    let (t, sc, ry) = (translate.unwrap_or([0.0; 3]), scale.unwrap_or(1.0), rotate_y.unwrap_or(0.0));
    if !within_extent(v3(t)) {
        return Err(cx.err(ss, &key("translate"), extent_message("translate", v3(t))));
    }
    if !(sc.is_finite() && sc > 0.0) {
        return Err(cx.err(ss, &key("scale"), format!("scale must be positive and finite, got {sc}")));
    }
    if !ry.is_finite() {
        return Err(cx.err(ss, &key("rotate_y"), format!("rotate_y must be finite, got {ry}")));
    }
    let path = dir.join(f);
    let mesh = super::load_mesh_file(&path, smooth).map_err(|m| cx.err(ss.clone(), &key("file"), m))?;
    b.mesh_file(&path, mesh.bytes_hash);
    let (sin, cos) = ry.to_radians().sin_cos();
    let rot = |p: Vec3| Vec3::new(cos * p.x + sin * p.z, p.y, -sin * p.x + cos * p.z);
    let xf = |p: Vec3| rot(p * sc) + v3(t);
    for (k, tri) in mesh.triangles.iter().enumerate() {
        // a vertex outside the extent names the key that took it there
        let blame = if tri.iter().any(|&r| r.is_finite() && !within_extent(r)) {
            "file"
        } else if scale.is_some() {
            "scale"
        } else {
            "translate"
        };
        let n = mesh.normals.as_ref().map(|ns| ns[k].map(rot));
        let uv = mesh.uvs.as_ref().map(|t| t[k]);
        b.triangle(id, (tri.map(xf), *tri), Corners { n, uv }, &at(blame), Some(k))?;
    }
    Ok(())
}

/// Regions of interest and the `[forecast]` options.
fn extras(cx: &Ctx, b: &mut SceneBuilder, doc: &Doc) -> Result<(), SceneError> {
    for (i, r) in doc.roi.iter().enumerate() {
        let (rd, at) = (r.get_ref(), |k: &str| cx.at(r.span(), &format!("roi[{i}].{k}")));
        b.roi((rd.name.clone(), &at("name")), (rd.rect, &at("rect")))?;
    }
    if let Some(f) = &doc.forecast {
        if let Some(n) = f.get_ref().photons {
            b.forecast_photons(n, &cx.at(f.span(), "forecast.photons"))?;
        }
        if let Some([lo, hi]) = f.get_ref().target_box {
            b.forecast_target(v3(lo), v3(hi), &cx.at(f.span(), "forecast.target_box"))?;
        }
    }
    Ok(())
}
