//! `forecast export-mitsuba SCENE.toml --out SCENE.xml`: a TOML scene as Mitsuba 3 XML, so that
//! Mitsuba can render a reference of the same scene, and forecast loads it back identically.
//!
//! Exactness: triangles are written as binary PLY files (world-space f32 vertices, three per
//! triangle, with the shading normals of smooth ones) in `SCENE_meshes/` beside the XML, grouped
//! into runs of equal material, emission and smoothness, in scene order; spheres stay analytic;
//! the camera is the TOML `lookat` with `fov_axis="y"`; the vertex cap N is `max_depth` N + 1
//! (Mitsuba counts path segments); numbers are printed in Rust's shortest
//! round-trip form. forecast's own options (method, seed, time, photons, target box, ROIs) go
//! into `<default name="forecast_*">` values that Mitsuba ignores. So the scene loaded back is
//! the same `Scene` (apart from `path`, `hash`, `warnings`) and renders bit-identically.
//!
//! Writing: the XML and its meshes are one `atomic_io::FileSet` (all replaced or none), checked
//! first by the output guard (`atomic_io::OutputSet`): no file of the set may be the scene or one
//! of its meshes (`--out ring.obj`, or an input mesh at `OUT_meshes/shape_NNN.ply`).
//!
//! Mapping: diffuse → `twosided` `diffuse`; mirror → `twosided` `conductor` (`material` none,
//! `specular_reflectance`); glass → `dielectric` (`int_ior` = ior, `ext_ior` = 1); glossy →
//! Mitsuba 0.6's `phong` (the same modified Phong; Mitsuba 3 has none: a warning); emitters carry
//! a black `diffuse` (they reflect nothing).

use super::ply::{write_binary, IndexedMesh};
use super::schema::Doc;
use super::shape_uv::{ShapeKind, ShapeUv};
use super::{Material, Scene, Surface, Triangle};
use crate::bsdf::microfacet::{MicrofacetDistribution, MicrofacetKind};
use crate::bsdf::Slot;
use crate::math::Vec2;
use crate::math::{Rgb, Vec3};
use crate::texture::{Texture, UvTransform};
use serde::Serialize;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// What `export` wrote.
#[derive(Clone, Debug, Serialize)]
pub struct ExportReport {
    /// The XML file.
    pub xml: PathBuf,
    /// The PLY files.
    pub meshes: Vec<PathBuf>,
    /// Things Mitsuba 3 cannot render as forecast does.
    pub warnings: Vec<String>,
}

fn v3(v: Vec3) -> String {
    format!("{}, {}, {}", v.x, v.y, v.z)
}

fn esc(s: &str) -> String {
    s.replace('&', "&amp;").replace('"', "&quot;").replace('<', "&lt;").replace('>', "&gt;")
}

/// Exports a TOML scene file to Mitsuba XML at `out` (meshes in `OUT_STEM_meshes/`).
pub fn export_mitsuba(scene_path: &Path, out: &Path) -> Result<ExportReport, String> {
    if scene_path.extension().is_some_and(|e| e.eq_ignore_ascii_case("xml")) {
        return Err(format!(
            "{}: export-mitsuba converts TOML scenes; this one is Mitsuba XML already",
            scene_path.display()
        ));
    }
    let scene = super::file::load(scene_path).map_err(|e| e.to_string())?;
    let src = std::fs::read_to_string(scene_path).map_err(|e| format!("{}: {e}", scene_path.display()))?;
    let doc: Doc = toml::from_str(&src).map_err(|e| format!("{}: {e}", scene_path.display()))?;
    let names: Vec<String> = doc.materials.keys().cloned().collect();
    let stem = out.file_stem().and_then(|s| s.to_str()).unwrap_or("scene").to_string();
    let mesh_dir_name = format!("{stem}_meshes");
    let mesh_dir = out.parent().unwrap_or(Path::new(".")).join(&mesh_dir_name);
    let mut rep = ExportReport { xml: out.to_path_buf(), meshes: Vec::new(), warnings: Vec::new() };
    let mut x = String::new();
    let _ = writeln!(x, "<?xml version=\"1.0\" encoding=\"utf-8\"?>");
    let _ = writeln!(x, "<!-- exported by `forecast export-mitsuba {}` -->", esc(&scene_path.display().to_string()));
    let _ = writeln!(x, "<scene version=\"3.0.0\">");
    header(&mut x, &scene, &doc);
    let out_dir = out.parent().unwrap_or(Path::new("."));
    let mut images = Images {
        dir: out_dir.join(format!("{stem}_textures")),
        dir_name: format!("{stem}_textures"),
        names: Vec::new(),
    };
    for (i, m) in scene.materials.iter().enumerate().skip(1) {
        let (s, t) = (&scene.surfaces[i], &scene.textures);
        let _ = writeln!(x, "{}", bsdf(m, s, t, Some(&names[i - 1]), (&mut rep.warnings, &mut images)));
    }
    let meshes = triangle_runs(&mut x, &scene, &names, &mesh_dir, &mesh_dir_name);
    rep.meshes = meshes.iter().map(|(p, _)| p.clone()).collect();
    for s in &scene.spheres {
        let le = (s.emitter != super::NO_EMITTER).then(|| scene.emitters[s.emitter as usize].radiance);
        let _ = writeln!(x, "    <shape type=\"sphere\">");
        let c = s.center;
        let _ = writeln!(x, "        <point name=\"center\" x=\"{}\" y=\"{}\" z=\"{}\"/>", c.x, c.y, c.z);
        let _ = writeln!(x, "        <float name=\"radius\" value=\"{}\"/>", s.radius);
        if s.inward {
            let _ = writeln!(x, "        <boolean name=\"flip_normals\" value=\"true\"/>");
        }
        surface(&mut x, s.material, le, &names);
        let _ = writeln!(x, "    </shape>");
    }
    for l in &scene.point_lights {
        let Some(spot) = &l.spot else {
            let _ = writeln!(
                x,
                "    <emitter type=\"point\">\n        <point name=\"position\" value=\"{}\"/>\n        \
                 <rgb name=\"intensity\" value=\"{}\"/>\n    </emitter>",
                v3(l.position),
                v3(l.intensity)
            );
            continue;
        };
        // the beam along the lookat's z; the falloff has no azimuth, so any up will do
        let f = spot.frame;
        let _ = writeln!(
            x,
            "    <emitter type=\"spot\">\n        <transform name=\"to_world\"><lookat origin=\"{}\" target=\"{}\" \
             up=\"{}\"/></transform>\n        <rgb name=\"intensity\" value=\"{}\"/>\n        \
             <float name=\"cutoff_angle\" value=\"{}\"/>\n        <float name=\"beam_width\" value=\"{}\"/>\n    </emitter>",
            v3(l.position),
            v3(l.position + f.n),
            v3(f.t),
            v3(l.intensity),
            spot.cutoff.to_degrees(),
            (spot.cutoff - spot.inv_transition.recip()).to_degrees()
        );
    }
    for l in &scene.directional_lights {
        let _ = writeln!(
            x,
            "    <emitter type=\"directional\">\n        <vector name=\"direction\" value=\"{}\"/>\n        \
             <rgb name=\"irradiance\" value=\"{}\"/>\n    </emitter>",
            v3(l.d),
            v3(l.irradiance)
        );
    }
    if let Some(super::Environment { map: super::EnvMap::Constant(l), .. }) = &scene.environment {
        let _ = writeln!(
            x,
            "    <emitter type=\"constant\">\n        <rgb name=\"radiance\" value=\"{}\"/>\n    </emitter>",
            v3(*l)
        );
    }
    let _ = writeln!(x, "</scene>");
    let images = images.files()?;
    write_export(scene_path, &scene, out, x, [(meshes, mesh_dir), (images, out_dir.join(format!("{stem}_textures")))])?;
    Ok(rep)
}

/// The files of one output folder (path and bytes each), and the folder.
type FileGroup = (Vec<(PathBuf, Vec<u8>)>, PathBuf);

/// Writes the XML, its meshes and its images as one set (`atomic_io::FileSet`: a failure leaves
/// the previous export whole), after the output guard: no file of the set may name the scene or
/// one of its inputs (meshes, images). `groups`: the files of each folder, and the folder.
fn write_export(
    scene_path: &Path,
    scene: &Scene,
    out: &Path,
    xml: String,
    groups: [FileGroup; 2],
) -> Result<(), String> {
    let mut guard = crate::atomic_io::OutputSet::new();
    guard.scene_inputs(scene_path, &scene.mesh_files);
    guard.output("--out", out);
    for (files, _) in &groups {
        files.iter().for_each(|(p, _)| {
            guard.output("an exported mesh or image", p);
        });
    }
    guard.check()?;
    let mut set = crate::atomic_io::FileSet::new();
    for (files, dir) in groups {
        if !files.is_empty() {
            std::fs::create_dir_all(&dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
        }
        files.into_iter().for_each(|(p, b)| set.add(p, b));
    }
    set.add(out.to_path_buf(), xml.into_bytes()); // last: once the XML is new, its meshes are too
    set.commit()
}

/// Runs of triangles with equal material, emission and smoothness as PLY shapes: their XML goes
/// to `x`, their files (path, bytes) are returned.
fn triangle_runs(
    x: &mut String,
    scene: &Scene,
    names: &[String],
    dir: &Path,
    dir_name: &str,
) -> Vec<(PathBuf, Vec<u8>)> {
    let tris = &scene.triangles;
    let key = |t: &Triangle| (t.material, radiance(scene, t), t.n.is_some());
    let mut meshes = Vec::new();
    let mut start = 0;
    while start < tris.len() {
        // a tessellated `disk` or `cylinder` goes back as the analytic shape, keeping its UVs
        if let Some((_, end, uv)) = scene.shape_uvs.run(start as u32) {
            let end = (end as usize).min(tris.len());
            analytic_shape(x, scene, &tris[start..end], uv, names);
            start = end;
            continue;
        }
        let split = |j: usize| key(&tris[j]) != key(&tris[start]) || scene.shape_uvs.get(j as u32).is_some();
        let end = (start..tris.len()).find(|&j| split(j)).unwrap_or(tris.len());
        let run = &tris[start..end];
        let k = meshes.len();
        meshes.push((dir.join(format!("shape_{k:03}.ply")), write_binary(&run_mesh(run))));
        let file = format!("{dir_name}/shape_{k:03}.ply");
        let _ = writeln!(x, "    <shape type=\"ply\">\n        <string name=\"filename\" value=\"{}\"/>", esc(&file));
        let _ = writeln!(x, "        <boolean name=\"face_normals\" value=\"{}\"/>", run[0].n.is_none());
        surface(x, run[0].material, radiance(scene, &run[0]), names);
        let _ = writeln!(x, "    </shape>");
        start = end;
    }
    meshes
}

/// The triangles `run` of a tessellated `disk` or `cylinder` as Mitsuba's analytic shape: its
/// `to_world` (the cylinder's frame, radius and length included, its `p0`, `p1` and `radius` left
/// at their defaults), `flip_normals` where the shape had it. Loaded back, it is tessellated the
/// same, facing the same way, and has the same UVs (`scene/shape_uv.rs`).
fn analytic_shape(x: &mut String, scene: &Scene, run: &[Triangle], uv: &ShapeUv, names: &[String]) {
    let ty = match uv.kind {
        ShapeKind::Disk => "disk",
        ShapeKind::Cylinder => "cylinder",
    };
    let t = &run[0];
    // the tessellation's unflipped triangles face along Mitsuba's normal, mirrored or not
    let flip = t.ng.dot(uv.normal_at((t.p[0] + t.p[1] + t.p[2]) / 3.0)) < 0.0;
    let m = uv.to_world().transpose().to_cols_array().map(|v| v.to_string()).join(" ");
    let _ = writeln!(x, "    <shape type=\"{ty}\">");
    let _ = writeln!(x, "        <transform name=\"to_world\"><matrix value=\"{m}\"/></transform>");
    if flip {
        let _ = writeln!(x, "        <boolean name=\"flip_normals\" value=\"true\"/>");
    }
    surface(x, t.material, radiance(scene, t), names);
    let _ = writeln!(x, "    </shape>");
}

fn radiance(scene: &Scene, t: &Triangle) -> Option<Rgb> {
    (t.emitter != super::NO_EMITTER).then(|| scene.emitters[t.emitter as usize].radiance)
}

/// Defaults, integrator and sensor.
fn header(x: &mut String, scene: &Scene, doc: &Doc) {
    let r = &scene.render;
    let d = |x: &mut String, k: &str, v: String| {
        let _ = writeln!(x, "    <default name=\"{k}\" value=\"{}\"/>", esc(&v));
    };
    if let Some(spp) = r.spp {
        d(x, "spp", spp.to_string());
    }
    d(x, "forecast_method", r.method.clone());
    d(x, "forecast_seed", r.seed.to_string());
    if let Some(t) = r.time {
        d(x, "forecast_time", format!("{t}s"));
    }
    if let Some(p) = scene.forecast_photons {
        d(x, "forecast_photons", p.to_string());
    }
    if let Some((lo, hi)) = scene.forecast_target {
        d(x, "forecast_target_box", format!("{} {} {} {} {} {}", lo.x, lo.y, lo.z, hi.x, hi.y, hi.z));
    }
    for (i, roi) in scene.rois.iter().enumerate() {
        let [a, b, c, e] = roi.rect;
        d(x, &format!("forecast_roi_{i}"), format!("{a} {b} {c} {e} {}", roi.name));
    }
    let _ = writeln!(
        x,
        "    <integrator type=\"path\">\n        <integer name=\"max_depth\" value=\"{}\"/>\n    </integrator>",
        // Mitsuba counts segments: N surface vertices with NEE at each are paths of N + 1
        u64::from(r.max_depth) + 1
    );
    let c = doc.camera.get_ref();
    let f = |a: [f32; 3]| format!("{}, {}, {}", a[0], a[1], a[2]);
    let _ = writeln!(x, "    <sensor type=\"perspective\">");
    let _ = writeln!(x, "        <float name=\"fov\" value=\"{}\"/>", c.fov);
    let _ = writeln!(x, "        <string name=\"fov_axis\" value=\"y\"/>");
    let _ = writeln!(
        x,
        "        <transform name=\"to_world\">\n            <lookat origin=\"{}\" target=\"{}\" up=\"{}\"/>\n        </transform>",
        f(c.position),
        f(c.look_at),
        f(c.up)
    );
    if r.spp.is_some() {
        let _ = writeln!(
            x,
            "        <sampler type=\"independent\">\n            <integer name=\"sample_count\" value=\"$spp\"/>\n        </sampler>"
        );
    }
    let _ = writeln!(
        x,
        "        <film type=\"hdrfilm\">\n            <integer name=\"width\" value=\"{}\"/>\n            \
         <integer name=\"height\" value=\"{}\"/>\n            <rfilter type=\"box\"/>\n        </film>\n    </sensor>",
        c.resolution[0], c.resolution[1]
    );
}

/// The image files a scene's bitmaps read, copied beside the XML into `DIR/` (`SCENE_textures`):
/// one copy per source file, under its own name (`k_NAME` where two sources share a name).
struct Images {
    dir: PathBuf,
    dir_name: String,
    /// (source, name in `dir`).
    names: Vec<(PathBuf, String)>,
}

impl Images {
    /// The XML's path of the copy of `source`.
    fn name(&mut self, source: &Path) -> String {
        if let Some((_, n)) = self.names.iter().find(|(s, _)| s == source) {
            return format!("{}/{n}", self.dir_name);
        }
        let base = source.file_name().map_or("image".into(), |f| f.to_string_lossy().into_owned());
        let taken = |n: &str| self.names.iter().any(|(_, m)| m == n);
        let mut name = base.clone();
        let mut k = 1;
        while taken(&name) {
            name = format!("{k}_{base}");
            k += 1;
        }
        self.names.push((source.to_path_buf(), name.clone()));
        format!("{}/{name}", self.dir_name)
    }

    /// The copies: (destination, bytes of the source).
    fn files(&self) -> Result<Vec<(PathBuf, Vec<u8>)>, String> {
        let read = |s: &Path| std::fs::read(s).map_err(|e| format!("cannot read the image {}: {e}", s.display()));
        self.names.iter().map(|(s, n)| Ok((self.dir.join(n), read(s)?))).collect()
    }
}

/// Mitsuba's `to_uv` as a 4×4 matrix (row-major): the affine map's 2×2 block and translation.
fn to_uv(t: &UvTransform) -> String {
    if t.is_identity() {
        return String::new();
    }
    let [[a, b, c], [d, e, f]] = t.rows;
    format!("<transform name=\"to_uv\"><matrix value=\"{a} {b} 0 {c} {d} {e} 0 {f} 0 0 1 0 0 0 0 1\"/></transform>")
}

/// A texture as the parameter `name`: a constant (inside a checkerboard) as `<rgb>`, a bitmap
/// reading the copy of its image, a checkerboard with its colours.
fn texture(name: &str, t: &Texture, images: &mut Images) -> String {
    match t {
        Texture::Constant(c) => format!("<rgb name=\"{name}\" value=\"{}\"/>", v3(*c)),
        Texture::Bitmap(b) => format!(
            "<texture name=\"{name}\" type=\"bitmap\"><string name=\"filename\" value=\"{}\"/><string \
             name=\"filter_type\" value=\"{}\"/><string name=\"wrap_mode\" value=\"{}\"/><boolean name=\"raw\" \
             value=\"{}\"/>{}</texture>",
            esc(&images.name(b.image.path())),
            b.filter_type.name(),
            b.wrap_mode.name(),
            b.image.raw(),
            to_uv(&b.to_uv)
        ),
        Texture::Checkerboard(c) => format!(
            "<texture name=\"{name}\" type=\"checkerboard\">{}{}{}</texture>",
            texture("color0", &c.color0, images),
            texture("color1", &c.color1, images),
            to_uv(&c.to_uv)
        ),
    }
}

/// Mitsuba's parameters of a microfacet distribution (`alpha` as written by `textured` when a
/// texture sets it).
fn microfacet(d: &MicrofacetDistribution, alpha: Option<String>) -> String {
    let kind = match d.kind {
        MicrofacetKind::Beckmann => "beckmann",
        MicrofacetKind::Ggx => "ggx",
    };
    let alpha = alpha.unwrap_or_else(|| {
        format!("<float name=\"alpha_u\" value=\"{}\"/><float name=\"alpha_v\" value=\"{}\"/>", d.alpha_u, d.alpha_v)
    });
    format!(
        "<string name=\"distribution\" value=\"{kind}\"/>{alpha}<boolean name=\"sample_visible\" value=\"{}\"/>",
        d.sample_visible
    )
}

/// A `<bsdf>` for material `m` with its surface (with `id` when named): the plugin, its textured
/// parameters as textures, in `twosided` where it scatters from both sides and is not a
/// dielectric, in `normalmap` (outermost, around `twosided`, as the TOML reader builds it) where
/// it has one.
fn bsdf(
    m: &Material,
    s: &Surface,
    textures: &[Texture],
    id: Option<&str>,
    out: (&mut Vec<String>, &mut Images),
) -> String {
    let (warnings, images) = out;
    let id = id.map_or(String::new(), |i| format!(" id=\"{}\"", esc(i)));
    let mut p = |n: &str, slot: Slot, c: Rgb| match s.textures.iter().find(|t| t.slot == slot) {
        Some(t) => texture(n, &textures[t.texture as usize], images),
        None => format!("<rgb name=\"{n}\" value=\"{}\"/>", v3(c)),
    };
    let alpha = |p: &mut dyn FnMut(&str, Slot, Rgb) -> String| {
        s.textures.iter().any(|t| t.slot == Slot::Alpha).then(|| p("alpha", Slot::Alpha, Rgb::ZERO))
    };
    let rgb = |n: &str, c: Rgb| format!("<rgb name=\"{n}\" value=\"{}\"/>", v3(c));
    let ior = |eta: f32| format!("<float name=\"int_ior\" value=\"{eta}\"/><float name=\"ext_ior\" value=\"1\"/>");
    let inner = match *m {
        Material::Diffuse { albedo } => {
            format!("<bsdf type=\"diffuse\">{}</bsdf>", p("reflectance", Slot::Reflectance, albedo))
        }
        Material::Glossy { albedo, specular, exponent } => {
            warnings.push(format!("a glossy material{id} is written as Mitsuba 0.6's `phong` (Mitsuba 3 has none)"));
            format!(
                "<bsdf type=\"phong\">{}{}<float name=\"exponent\" value=\"{exponent}\"/></bsdf>",
                rgb("diffuse_reflectance", albedo),
                rgb("specular_reflectance", specular)
            )
        }
        Material::Mirror { reflectance } => format!(
            "<bsdf type=\"conductor\"><string name=\"material\" value=\"none\"/>{}</bsdf>",
            p("specular_reflectance", Slot::SpecularReflectance, reflectance)
        ),
        Material::Conductor { reflectance, eta, k } => format!(
            "<bsdf type=\"conductor\">{}{}{}</bsdf>",
            p("specular_reflectance", Slot::SpecularReflectance, reflectance),
            rgb("eta", eta),
            rgb("k", k)
        ),
        Material::Glass { ior: eta } => format!("<bsdf type=\"dielectric\">{}</bsdf>", ior(eta)),
        Material::Plastic(pl) => format!(
            "<bsdf type=\"plastic\">{}{}{}<boolean name=\"nonlinear\" value=\"{}\"/></bsdf>",
            p("diffuse_reflectance", Slot::DiffuseReflectance, pl.diffuse_reflectance()),
            p("specular_reflectance", Slot::SpecularReflectance, pl.specular_reflectance()),
            ior(pl.eta()),
            pl.nonlinear()
        ),
        Material::RoughPlastic(pl) => format!(
            "<bsdf type=\"roughplastic\">{}{}{}{}<boolean name=\"nonlinear\" value=\"{}\"/></bsdf>",
            microfacet(
                pl.distribution(),
                Some(format!("<float name=\"alpha\" value=\"{}\"/>", pl.distribution().alpha_u))
            ),
            p("diffuse_reflectance", Slot::DiffuseReflectance, pl.diffuse_reflectance()),
            p("specular_reflectance", Slot::SpecularReflectance, pl.specular_reflectance()),
            ior(pl.eta()),
            pl.nonlinear()
        ),
        Material::ThinDielectric(t) => format!(
            "<bsdf type=\"thindielectric\">{}{}{}</bsdf>",
            ior(t.eta),
            p("specular_reflectance", Slot::SpecularReflectance, t.specular_reflectance),
            p("specular_transmittance", Slot::SpecularTransmittance, t.specular_transmittance)
        ),
        Material::RoughConductor(c) => format!(
            "<bsdf type=\"roughconductor\">{}{}{}{}</bsdf>",
            microfacet(&c.distribution, alpha(&mut p)),
            p("specular_reflectance", Slot::SpecularReflectance, c.specular_reflectance),
            rgb("eta", c.eta),
            rgb("k", c.k)
        ),
        Material::RoughDielectric(d) => format!(
            "<bsdf type=\"roughdielectric\">{}{}{}{}</bsdf>",
            microfacet(&d.distribution, alpha(&mut p)),
            ior(d.eta),
            p("specular_reflectance", Slot::SpecularReflectance, d.specular_reflectance),
            p("specular_transmittance", Slot::SpecularTransmittance, d.specular_transmittance)
        ),
        Material::Black => format!("<bsdf type=\"diffuse\">{}</bsdf>", rgb("reflectance", Rgb::ZERO)),
    };
    let inner = if s.two_sided && !m.is_two_sided_by_nature() {
        format!("<bsdf type=\"twosided\">{inner}</bsdf>")
    } else {
        inner
    };
    let outer = match s.normalmap {
        Some(t) => {
            format!("<bsdf type=\"normalmap\">{}{inner}</bsdf>", texture("normalmap", &textures[t as usize], images))
        }
        None => inner,
    };
    // the id on the outermost element
    format!("    {}", outer.replacen("<bsdf type=\"", &format!("<bsdf{id} type=\""), 1))
}

/// The BSDF reference or the emitter (with its black BSDF) of a shape.
fn surface(x: &mut String, material: u32, le: Option<Rgb>, names: &[String]) {
    match le {
        Some(l) => {
            let _ = writeln!(
                x,
                "        <bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0\"/></bsdf>\n        \
                 <emitter type=\"area\"><rgb name=\"radiance\" value=\"{}\"/></emitter>",
                v3(l)
            );
        }
        None => {
            let _ = writeln!(x, "        <ref id=\"{}\"/>", esc(&names[material as usize - 1]));
        }
    }
}

/// Unshared vertices of a run of triangles (with shading normals when smooth).
fn run_mesh(run: &[Triangle]) -> IndexedMesh {
    let positions = run.iter().flat_map(|t| t.p).collect();
    let normals = run[0].n.map(|_| run.iter().flat_map(|t| t.n.unwrap_or([t.ng; 3])).collect());
    let faces = (0..run.len() as u32).map(|i| [3 * i, 3 * i + 1, 3 * i + 2]).collect();
    let uvs = run[0].uv.map(|_| run.iter().flat_map(|t| t.uv.unwrap_or([Vec2::ZERO; 3])).collect());
    IndexedMesh { positions, normals, uvs, faces, bytes_hash: 0 }
}

#[cfg(test)]
mod analytic_uv_tests {
    use super::*;

    /// A scene's `disk`s and `cylinder`s written by the exporter's shape writer and loaded back:
    /// the same triangles, facing the same way, with the same parametrisation (uv and ∂p/∂u at
    /// every triangle's centroid), between and beside meshes with UVs.
    #[test]
    fn disks_and_cylinders_keep_their_uvs_through_the_export() {
        let dir = std::env::temp_dir().join(format!("forecast-export-uv-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let shapes = r#"
<shape type="disk"><transform name="to_world"><scale x="2" y="1" z="1"/><rotate x="1" angle="30"/>
<translate y="1"/></transform><bsdf type="diffuse"/></shape>
<shape type="rectangle"><transform name="to_world"><translate z="-2"/></transform><bsdf type="diffuse"/></shape>
<shape type="cylinder"><point name="p0" value="0, 0, 0"/><point name="p1" value="0, 2, 0.5"/>
<float name="radius" value="0.5"/><boolean name="flip_normals" value="true"/>
<transform name="to_world"><translate x="1"/></transform><bsdf type="diffuse"/></shape>
<shape type="disk"><transform name="to_world"><scale value="0.3"/><rotate x="1" angle="90"/>
<translate y="3"/></transform><emitter type="area"><rgb name="radiance" value="5"/></emitter></shape>
<shape type="cylinder"><transform name="to_world"><scale x="1" y="1" z="-1"/></transform><bsdf type="diffuse"/></shape>
"#;
        let wrap = |body: &str| {
            format!(
                "<scene version=\"3.0.0\"><sensor type=\"perspective\"><float name=\"fov\" value=\"40\"/><transform name=\"to_world\">\
<lookat origin=\"0, 1, 6\" target=\"0, 1, 0\"/></transform></sensor>\n\
<emitter type=\"point\"><point name=\"position\" value=\"0, 4, 4\"/></emitter>\n{body}</scene>"
            )
        };
        let load = |src: &str| crate::scene::mitsuba::load_str(src, "t.xml", &dir, &[]).unwrap();
        let scene = load(&wrap(shapes));
        let names: Vec<String> = (1..scene.materials.len()).map(|i| format!("m{i}")).collect();
        let mut x: String = names.iter().map(|n| format!("<bsdf type=\"diffuse\" id=\"{n}\"/>\n")).collect();
        let meshes = triangle_runs(&mut x, &scene, &names, &dir.join("meshes"), "meshes");
        std::fs::create_dir_all(dir.join("meshes")).unwrap();
        for (p, b) in &meshes {
            std::fs::write(p, b).unwrap();
        }
        assert_eq!(x.matches("<shape type=\"disk\">").count(), 2, "{x}");
        assert_eq!(x.matches("<shape type=\"cylinder\">").count(), 2, "{x}");
        assert_eq!(x.matches("flip_normals").count(), 1, "{x}");
        let back = load(&wrap(&x));
        assert_eq!(back.triangles.len(), scene.triangles.len());
        let mut analytic = 0;
        for (i, (a, b)) in scene.triangles.iter().zip(&back.triangles).enumerate() {
            let tol = |u: Vec3| 2e-6 * u.abs().max_element().max(1.0);
            // the same corners (`flip_normals` may list them in another order)
            for p in a.p {
                let near = b.p.iter().any(|q| (p - *q).abs().max_element() <= tol(p));
                assert!(near, "triangle {i}: {p} not in {:?}", b.p);
            }
            assert!(a.ng.dot(b.ng) > 0.999, "triangle {i} turned: {} vs {}", a.ng, b.ng);
            assert_eq!(a.uv, b.uv, "triangle {i}");
            let (sa, sb) = (scene.shape_uvs.get(i as u32), back.shape_uvs.get(i as u32));
            assert_eq!(sa.map(|s| s.kind), sb.map(|s| s.kind), "triangle {i}");
            analytic += sa.is_some() as usize;
            let c = (a.p[0] + a.p[1] + a.p[2]) / 3.0;
            let ((ua, da), (ub, db)) = (scene.uv_at(i as u32, c), back.uv_at(i as u32, c));
            assert!((ua - ub).abs().max_element() < 1e-5, "triangle {i}: uv {ua} vs {ub}");
            assert!((da - db).abs().max_element() <= 1e-5 * da.abs().max_element().max(1.0), "{i}: {da} vs {db}");
        }
        assert!(analytic > 4 * 500, "{analytic} triangles of disks and cylinders");
        let _ = std::fs::remove_dir_all(dir);
    }
}
