//! The TOML scene file (documented in `scenes/README.md`): parsing and validation.
//!
//! Every error names the file, the line and the key (`SceneError`'s Display is
//! `file:line: key `k`: message`). Unknown keys are errors. Degenerate triangles are skipped with a
//! warning; everything else that is wrong (NaN, negative values, zero-area lights, a bad fov, a
//! missing OBJ, an empty scene) is an error, never a panic.

use super::limits::{extent_message, light_value_error, within_extent, MAX_INTENSITY, MAX_RADIANCE};
use super::schema::{Doc, LightDef, MaterialDef, ShapeDef};
use super::{
    light_power, limits, locate, Camera, Emitter, LightRef, Material, PointLight, RenderDefaults, Roi, Scene, Sphere,
    Triangle, NO_EMITTER,
};
use crate::math::{fnv1a, Vec3, PI};
use crate::param_limits as params;
use crate::sampling::distribution::Distribution1D;
use std::collections::BTreeMap;
use std::path::Path;

/// A scene loading error with its location.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneError {
    /// File name.
    pub file: String,
    /// 1-based line (0 when unknown).
    pub line: usize,
    /// The offending key (may be empty).
    pub key: String,
    /// What is wrong.
    pub message: String,
}

impl std::fmt::Display for SceneError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}:{}: ", self.file, self.line)?;
        if !self.key.is_empty() {
            write!(f, "key `{}`: ", self.key)?;
        }
        write!(f, "{}", self.message)
    }
}

impl std::error::Error for SceneError {}

/// Parses a duration such as `500ms`, `30s`, `4m`, `1h` or `1m30s` into seconds.
pub fn parse_duration(s: &str) -> Result<f64, String> {
    let s = s.trim();
    let mut total = 0.0;
    let mut num = String::new();
    let mut chars = s.chars().peekable();
    let mut any = false;
    while let Some(c) = chars.next() {
        if c.is_ascii_digit() || c == '.' {
            num.push(c);
            continue;
        }
        let mut unit = c.to_string();
        while let Some(&n) = chars.peek() {
            if n.is_ascii_alphabetic() {
                unit.push(n);
                chars.next();
            } else {
                break;
            }
        }
        let v: f64 = num.parse().map_err(|_| format!("bad duration `{s}` (expected e.g. 30s, 4m, 1h)"))?;
        total += v * match unit.as_str() {
            "ms" => 1e-3,
            "s" => 1.0,
            "m" | "min" => 60.0,
            "h" => 3600.0,
            _ => return Err(format!("bad duration unit `{unit}` in `{s}` (use ms, s, m, h)")),
        };
        num.clear();
        any = true;
    }
    if !num.is_empty() {
        // a bare number means seconds
        total += num.parse::<f64>().map_err(|_| format!("bad duration `{s}`"))?;
        any = true;
    }
    if !any || !total.is_finite() || total <= 0.0 {
        return Err(format!("bad duration `{s}`: must be positive (e.g. 30s, 4m, 1h)"));
    }
    Ok(total)
}

struct Ctx<'a> {
    file: String,
    src: &'a str,
}

impl Ctx<'_> {
    fn line_of(&self, offset: usize) -> usize {
        self.src[..offset.min(self.src.len())].bytes().filter(|&b| b == b'\n').count() + 1
    }
    /// Error at `key` inside the entry spanning `span` (finds the key's own line when present).
    fn err(&self, span: std::ops::Range<usize>, key: &str, message: impl Into<String>) -> SceneError {
        // toml spans of a table cover only its header: search from the header to the next one
        let start = span.start.min(self.src.len());
        let body_start = self.src[start..].find('\n').map_or(self.src.len(), |i| start + i + 1);
        let mut end = self.src.len();
        let mut off = body_start;
        for line in self.src[body_start..].split_inclusive('\n') {
            if line.trim_start().starts_with('[') {
                end = off;
                break;
            }
            off += line.len();
        }
        let end = end.max(span.end.min(self.src.len()));
        let text = &self.src[start..end];
        let mut at = start;
        if !key.is_empty() {
            let leaf = key.rsplit('.').next().unwrap_or(key);
            let mut search = 0;
            while let Some(i) = text[search..].find(leaf) {
                let pos = search + i;
                let b = text.as_bytes();
                let before_ok = pos == 0 || !(b[pos - 1].is_ascii_alphanumeric() || b[pos - 1] == b'_');
                let rest = text[pos + leaf.len()..].trim_start();
                if before_ok && rest.starts_with('=') {
                    at = start + pos;
                    break;
                }
                search = pos + leaf.len();
            }
        }
        SceneError { file: self.file.clone(), line: self.line_of(at), key: key.to_string(), message: message.into() }
    }
}

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
    let cx = Ctx { file: file.to_string(), src };
    let doc: Doc = toml::from_str(src).map_err(|e| {
        let mut line = e.span().map(|s| cx.line_of(s.start)).unwrap_or(0);
        let msg = e.message().trim().to_string();
        let key = msg
            .split('`')
            .nth(1)
            .filter(|_| msg.contains("unknown field") || msg.contains("missing field"))
            .unwrap_or("")
            .to_string();
        let from = e.span().map_or(0, |s| s.start);
        if msg.contains("unknown field") && !key.is_empty() {
            // the span may cover a whole table (or array of tables): find the key's own line
            if let Some(l) = locate::key_line_after(src, from, &key) {
                line = l;
            }
        } else if let Some((l, path)) = e.span().and_then(|_| locate::key_path_at(src, from)) {
            // a value error (wrong type, bad length): the span is the value's; name its key
            return SceneError { file: cx.file.clone(), line: l, key: path, message: msg };
        }
        SceneError { file: cx.file.clone(), line, key, message: msg }
    })?;
    let mut hash = fnv1a(0xcbf2_9ce4_8422_2325, src.as_bytes());
    let mut warnings = Vec::new();

    // camera
    let cs = doc.camera.span();
    let c = doc.camera.get_ref();
    for (k, p) in [("position", c.position), ("look_at", c.look_at)] {
        if !within_extent(v3(p)) {
            return Err(cx.err(cs, &format!("camera.{k}"), extent_message(&format!("camera {k}"), v3(p))));
        }
    }
    if !finite3(c.up) || v3(c.up).abs().max_element() == 0.0 {
        return Err(cx.err(cs, "camera.up", "up must be finite and non-zero"));
    }
    // scaled to max |component| 1, so that normalizing cannot overflow
    let up = v3(c.up) / v3(c.up).abs().max_element();
    if !(c.fov.is_finite() && c.fov > 0.0 && c.fov < 180.0) {
        return Err(cx.err(cs, "camera.fov", format!("fov must be in (0, 180) degrees, got {}", c.fov)));
    }
    if c.resolution[0] == 0 || c.resolution[1] == 0 || c.resolution[0] > 65536 || c.resolution[1] > 65536 {
        return Err(cx.err(cs, "camera.resolution", "resolution must be in 1..=65536 per axis"));
    }
    let fwd = v3(c.look_at) - v3(c.position);
    if fwd.length() < 1e-9 {
        return Err(cx.err(cs, "camera.look_at", "look_at equals position"));
    }
    if fwd.normalize().cross(up.normalize()).length() < 1e-6 {
        return Err(cx.err(cs, "camera.up", "up is parallel to the view direction"));
    }
    let camera = Camera::new(v3(c.position), v3(c.look_at), up, c.fov, c.resolution[0], c.resolution[1]);

    // render defaults
    let mut render =
        RenderDefaults { method: super::AUTO_METHOD.into(), spp: None, time: None, seed: 0, max_depth: 64 };
    if let Some(r) = &doc.render {
        let rs = r.span();
        let r = r.get_ref();
        if let Some(m) = &r.method {
            if !super::is_method_name(m) {
                let all = super::METHOD_NAMES.join(", ");
                let all = format!("{}, {all}", super::AUTO_METHOD);
                return Err(cx.err(rs, "render.method", format!("unknown method `{m}` ({all})")));
            }
            render.method = m.clone();
        }
        // the limits shared with the command line (crate::param_limits)
        if let Some(s) = r.spp {
            params::SPP.check(s).map_err(|m| cx.err(rs.clone(), "render.spp", m))?;
            render.spp = Some(s);
        }
        if let (Some(_), Some(_)) = (r.spp, &r.time) {
            let m = "`spp` and `time` exclude each other (as --spp and --time): give one";
            return Err(cx.err(rs.clone(), "render.time", m));
        }
        if let Some(t) = &r.time {
            let secs = parse_duration(t).and_then(|v| params::check_time(v).map(|()| v));
            render.time = Some(secs.map_err(|m| cx.err(rs.clone(), "render.time", m))?);
        }
        render.seed = r.seed.unwrap_or(0);
        if let Some(d) = r.max_depth {
            params::MAX_DEPTH.check(d.into()).map_err(|m| cx.err(rs, "render.max_depth", m))?;
            render.max_depth = d;
        }
    }

    // materials
    let mut materials = vec![Material::Black];
    let mut names: BTreeMap<&str, u32> = BTreeMap::new();
    for (name, m) in &doc.materials {
        let ms = m.span();
        let bad = |k: &str, msg: &str| cx.err(ms.clone(), &format!("materials.{name}.{k}"), msg);
        let refl = |k: &str, a: [f32; 3]| -> Result<Vec3, SceneError> {
            if !finite3(a) || a.iter().any(|&x| !(0.0..=1.0).contains(&x)) {
                return Err(bad(k, "must be three finite values in [0, 1]"));
            }
            Ok(v3(a))
        };
        let def = m.get_ref().resolve().map_err(|(k, msg)| bad(&k, &msg))?;
        let mat = match &def {
            MaterialDef::Diffuse { albedo } => Material::Diffuse { albedo: refl("albedo", *albedo)? },
            MaterialDef::Glossy { albedo, specular, exponent } => {
                let (a, s) = (refl("albedo", *albedo)?, refl("specular", *specular)?);
                if (a + s).max_element() > 1.0 + 1e-6 {
                    return Err(bad("specular", "albedo + specular must be <= 1 per channel (energy conservation)"));
                }
                if !(exponent.is_finite() && *exponent >= 0.0 && *exponent <= 1e6) {
                    return Err(bad("exponent", "exponent must be finite and in [0, 1e6]"));
                }
                Material::Glossy { albedo: a, specular: s, exponent: *exponent }
            }
            MaterialDef::Mirror { reflectance } => Material::Mirror { reflectance: refl("reflectance", *reflectance)? },
            MaterialDef::Glass { ior } => {
                if !(ior.is_finite() && *ior >= 1.0 && *ior <= 10.0) {
                    return Err(bad("ior", "ior must be finite and in [1, 10]"));
                }
                Material::Glass { ior: *ior }
            }
        };
        names.insert(name.as_str(), materials.len() as u32);
        materials.push(mat);
    }

    // shapes
    let mut triangles: Vec<Triangle> = Vec::new();
    let mut spheres: Vec<Sphere> = Vec::new();
    // (emission, shape index) per primitive
    let mut tri_emission: Vec<Option<(Vec3, usize)>> = Vec::new();
    let mut sph_emission: Vec<Option<(Vec3, usize)>> = Vec::new();
    for (idx, s) in doc.shape.iter().enumerate() {
        let ss = s.span();
        let key = |k: &str| format!("shape[{idx}].{k}");
        let resolve = |mat: &Option<String>, emission: &Option<[f32; 3]>| -> Result<(u32, Option<Vec3>), SceneError> {
            let e = match emission {
                Some(e) => {
                    if let Some(m) = light_value_error("emission", v3(*e), MAX_RADIANCE) {
                        return Err(cx.err(ss.clone(), &key("emission"), m));
                    }
                    Some(v3(*e)).filter(|e| e.max_element() > 0.0)
                }
                None => None,
            };
            if e.is_some() || (emission.is_some() && mat.is_none()) {
                // emitters reflect nothing; a zero emission without a material is a black absorber
                return Ok((0, e));
            }
            match mat {
                Some(m) => names
                    .get(m.as_str())
                    .map(|&i| (i, None))
                    .ok_or_else(|| cx.err(ss.clone(), &key("material"), format!("unknown material `{m}`"))),
                None => Err(cx.err(ss.clone(), &key("material"), "a shape needs `material` (or `emission`)")),
            }
        };
        let def = s.get_ref().resolve().map_err(|(k, m)| cx.err(ss.clone(), &key(&k), m))?;
        match &def {
            ShapeDef::Quad { corner, u, v, material, emission } => {
                for (k, a) in [("corner", corner), ("u", u), ("v", v)] {
                    if !finite3(*a) {
                        return Err(cx.err(ss, &key(k), format!("quad `{k}` must be finite, got {a:?}")));
                    }
                }
                let (mat, e) = resolve(material, emission)?;
                let (c, u, v) = (v3(*corner), v3(*u), v3(*v));
                // the vertex that leaves the extent names the vector that took it there
                let blame = if u.abs().max_element() >= v.abs().max_element() { "u" } else { "v" };
                for (k, p) in [("corner", c), ("u", c + u), ("v", c + v), (blame, c + u + v)] {
                    if !within_extent(p) {
                        return Err(cx.err(ss, &key(k), extent_message("quad vertex", p)));
                    }
                }
                if u.cross(v).length() < 1e-12 {
                    return Err(cx.err(ss, &key("v"), "zero-area quad (u × v = 0)"));
                }
                for p in [[c, c + u, c + u + v], [c, c + u + v, c + v]] {
                    let t = make_triangle(p, None, mat).ok_or_else(|| {
                        cx.err(ss.clone(), &key("v"), "degenerate quad: |u × v| is zero or not finite")
                    })?;
                    triangles.push(t);
                    tri_emission.push(e.map(|e| (e, idx)));
                }
            }
            ShapeDef::Sphere { center, radius, material, emission, inward } => {
                if !finite3(*center) {
                    return Err(cx.err(ss, &key("center"), "center must be finite"));
                }
                if !(radius.is_finite() && *radius > 0.0) {
                    return Err(cx.err(
                        ss,
                        &key("radius"),
                        format!("radius must be positive and finite, got {radius}"),
                    ));
                }
                let (c, r) = (v3(*center), Vec3::splat(*radius));
                if !within_extent(c) {
                    return Err(cx.err(ss, &key("center"), extent_message("sphere center", c)));
                }
                if !within_extent(c - r) || !within_extent(c + r) {
                    return Err(cx.err(ss, &key("radius"), extent_message("sphere bounds corner", c + r.copysign(c))));
                }
                let (mat, e) = resolve(material, emission)?;
                spheres.push(Sphere {
                    center: v3(*center),
                    radius: *radius,
                    inward: *inward,
                    material: mat,
                    emitter: NO_EMITTER,
                });
                sph_emission.push(e.map(|e| (e, idx)));
            }
            ShapeDef::Mesh { file: f, normals, material, emission, translate, scale, rotate_y } => {
                let smooth = match normals.as_str() {
                    "flat" => false,
                    "smooth" => true,
                    other => {
                        return Err(cx.err(
                            ss,
                            &key("normals"),
                            format!("normals must be `flat` or `smooth`, got `{other}`"),
                        ))
                    }
                };
                let (mat, e) = resolve(material, emission)?;
                let t = translate.unwrap_or([0.0; 3]);
                let sc = scale.unwrap_or(1.0);
                let ry = rotate_y.unwrap_or(0.0);
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
                hash = fnv1a(hash, &mesh.bytes_hash.to_le_bytes());
                let (sin, cos) = ry.to_radians().sin_cos();
                let xf = |p: Vec3| {
                    let p = p * sc;
                    Vec3::new(cos * p.x + sin * p.z, p.y, -sin * p.x + cos * p.z) + v3(t)
                };
                let xn = |n: Vec3| Vec3::new(cos * n.x + sin * n.z, n.y, -sin * n.x + cos * n.z);
                let mut skipped = 0usize;
                let mut flat_fallback = 0usize;
                for (k, tri) in mesh.triangles.iter().enumerate() {
                    let p = [xf(tri[0]), xf(tri[1]), xf(tri[2])];
                    let n = mesh.normals.as_ref().map(|ns| [xn(ns[k][0]), xn(ns[k][1]), xn(ns[k][2])]);
                    // non-finite OBJ vertices make a degenerate face (skipped below); finite ones
                    // must stay inside the extent after the transform
                    let far = p.iter().find(|&&q| !within_extent(q));
                    if let (Some(&q), true) = (far, tri.iter().all(|r| r.is_finite())) {
                        let blame = if tri.iter().any(|&r| !within_extent(r)) {
                            "file"
                        } else if scale.is_some() {
                            "scale"
                        } else {
                            "translate"
                        };
                        let at = format!("(face {} of {}, after the transform)", k + 1, path.display());
                        let msg = format!("{} {at}", extent_message("mesh vertex", q));
                        return Err(cx.err(ss, &key(blame), msg));
                    }
                    match make_triangle(p, n, mat) {
                        Some(t) => {
                            flat_fallback += (n.is_some() && t.n.is_none()) as usize;
                            triangles.push(t);
                            tri_emission.push(e.map(|e| (e, idx)));
                        }
                        None => skipped += 1,
                    }
                }
                if skipped > 0 {
                    warnings.push(format!(
                        "{}:{}: key `{}`: skipped {skipped} degenerate triangle(s) in {}",
                        cx.file,
                        cx.err(ss.clone(), &key("file"), "").line,
                        key("file"),
                        path.display()
                    ));
                }
                if flat_fallback > 0 {
                    warnings.push(format!(
                        "{}:{}: key `{}`: {flat_fallback} triangle(s) in {} have NaN or zero vertex normals; shaded flat",
                        cx.file,
                        cx.err(ss.clone(), &key("normals"), "").line,
                        key("normals"),
                        path.display()
                    ));
                }
            }
        }
    }
    if triangles.is_empty() && spheres.is_empty() {
        return Err(SceneError {
            file: cx.file.clone(),
            line: 1,
            key: "shape".into(),
            message: "empty scene: no shapes".into(),
        });
    }

    // emitters
    let mut emitters = Vec::new();
    let mut emitter_shape = Vec::new(); // shape index of each emitter (messages)
    for (i, e) in tri_emission.iter().enumerate() {
        if let Some((le, shape)) = e {
            triangles[i].emitter = emitters.len() as u32;
            emitters.push(Emitter { prim: i as u32, radiance: *le, area: triangles[i].area });
            emitter_shape.push(*shape);
        }
    }
    let ntri = triangles.len() as u32;
    for (i, e) in sph_emission.iter().enumerate() {
        if let Some((le, shape)) = e {
            spheres[i].emitter = emitters.len() as u32;
            let r = spheres[i].radius;
            emitters.push(Emitter { prim: ntri + i as u32, radiance: *le, area: 4.0 * PI * r * r });
            emitter_shape.push(*shape);
        }
    }
    let mut point_lights = Vec::new();
    for (idx, l) in doc.light.iter().enumerate() {
        let ls = l.span();
        let def = l.get_ref().resolve().map_err(|(k, m)| cx.err(ls.clone(), &format!("light[{idx}].{k}"), m))?;
        let LightDef::Point { position, intensity } = &def;
        if !within_extent(v3(*position)) {
            return Err(cx.err(ls, &format!("light[{idx}].position"), extent_message("position", v3(*position))));
        }
        if let Some(m) = light_value_error("intensity", v3(*intensity), MAX_INTENSITY) {
            return Err(cx.err(ls, &format!("light[{idx}].intensity"), m));
        }
        point_lights.push(PointLight { position: v3(*position), intensity: v3(*intensity) });
    }
    let mut lights: Vec<LightRef> = (0..emitters.len() as u32).map(LightRef::Area).collect();
    lights.extend((0..point_lights.len() as u32).map(LightRef::Point));
    let powers: Vec<f32> = lights.iter().map(|&l| light_power(&emitters, &point_lights, l)).collect();
    if let Some(i) = powers.iter().position(|p| !p.is_finite()) {
        let (span, k) = match lights[i] {
            LightRef::Area(e) => {
                let s = emitter_shape[e as usize];
                (doc.shape[s].span(), format!("shape[{s}].emission"))
            }
            LightRef::Point(p) => (doc.light[p as usize].span(), format!("light[{p}].intensity")),
        };
        return Err(cx.err(span, &k, "the light's power (radiance × area × π, or 4π × intensity) overflows f32"));
    }
    let light_pick = Distribution1D::new(&powers).ok_or_else(|| SceneError {
        file: cx.file.clone(),
        line: 1,
        key: "shape.emission".into(),
        message: "the scene has no light with positive power (add `emission` to a shape or a [[light]])".into(),
    })?;

    // regions of interest and forecast options
    let mut rois = Vec::new();
    for (i, r) in doc.roi.iter().enumerate() {
        let rd = r.get_ref();
        let [x, y, w, h] = rd.rect;
        let inside = |o: u32, len: u32, size: u32| o.checked_add(len).is_some_and(|e| e <= size);
        if w == 0 || h == 0 || !inside(x, w, camera.width) || !inside(y, h, camera.height) {
            return Err(cx.err(
                r.span(),
                &format!("roi[{i}].rect"),
                format!("rect {:?} must be non-empty and inside the {}x{} image", rd.rect, camera.width, camera.height),
            ));
        }
        rois.push(Roi { name: rd.name.clone(), rect: rd.rect });
    }
    let mut forecast_target = None;
    let mut forecast_photons = None;
    if let Some(f) = &doc.forecast {
        if let Some(n) = f.get_ref().photons {
            params::FORECAST_PHOTONS.check(n).map_err(|m| cx.err(f.span(), "forecast.photons", m))?;
            forecast_photons = Some(n);
        }
        if let Some([lo, hi]) = f.get_ref().target_box {
            if !finite3(lo) || !finite3(hi) || (0..3).any(|k| lo[k] > hi[k]) {
                return Err(cx.err(
                    f.span(),
                    "forecast.target_box",
                    "target_box must be [[min], [max]] with min <= max",
                ));
            }
            forecast_target = Some((v3(lo), v3(hi)));
        }
    }

    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for t in &triangles {
        for p in t.p {
            lo = lo.min(p);
            hi = hi.max(p);
        }
    }
    for s in &spheres {
        lo = lo.min(s.center - Vec3::splat(s.radius));
        hi = hi.max(s.center + Vec3::splat(s.radius));
    }
    Ok(Scene {
        path: cx.file.clone(),
        hash,
        camera,
        render,
        materials,
        triangles,
        spheres,
        emitters,
        point_lights,
        lights,
        light_pick,
        rois,
        forecast_target,
        forecast_photons,
        bounds: (lo, hi),
        warnings,
    })
}

/// Builds a triangle, or `None` when degenerate (zero area or non-finite).
pub(super) fn make_triangle(p: [Vec3; 3], n: Option<[Vec3; 3]>, material: u32) -> Option<Triangle> {
    let c = (p[1] - p[0]).cross(p[2] - p[0]);
    // scaled by the largest component first, so that |c|² cannot overflow (|c| up to 1e25)
    let m = c.abs().max_element();
    let len = if m > 0.0 { m * (c / m).length() } else { 0.0 };
    if !(len.is_finite() && len > 1e-12) {
        return None;
    }
    let ng = c / len;
    // shading normals must be finite and on the geometric side; else fall back to flat
    let n = n.and_then(|ns| {
        let ok = ns.iter().all(|v| v.is_finite() && v.length() > 1e-6);
        ok.then(|| {
            ns.map(|v| {
                let v = v.normalize();
                if v.dot(ng) < 0.0 {
                    -v
                } else {
                    v
                }
            })
        })
    });
    Some(Triangle { p, n, ng, area: 0.5 * len, material, emitter: NO_EMITTER })
}
