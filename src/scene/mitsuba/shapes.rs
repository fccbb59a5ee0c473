//! Mitsuba shapes → triangles and analytic spheres: `obj`, `ply` (file normals, else Mitsuba 3's
//! angle-weighted vertex normals unless `face_normals`), `rectangle` ([-1,1]² at z = 0, +z),
//! `cube` ([-1,1]³, outward), `disk` (unit, +z) and the open `cylinder` (`p0`, `p1`, `radius`),
//! the last two tessellated into `SEGMENTS` = 512 slices: the lateral area is short by
//! 1 − sin(π/N)/(π/N) = 6.3e-6 and the silhouette inside the circle by at most r(1 − cos(π/N)) =
//! 1.9e-5 r, both far below the noise of any render; the cylinder carries exact radial vertex
//! normals. `sphere` stays analytic (uniform `to_world` scale only). `to_world` maps positions,
//! and normals by the inverse transpose; `flip_normals` reverses the winding (and the emitting side).
//! Texture coordinates are Mitsuba's: per-vertex on `rectangle` and `cube` (its 24 vertices and
//! per-face UVs), the analytic (r, φ/2π) and (φ/2π, z) of the hit point on `disk` and `cylinder`
//! (`scene::shape_uv`, whose frame needs an invertible `to_world` when the BSDF is textured).
//!
//! Invariants: degenerate triangles are skipped with a warning; a missing or malformed mesh file
//! is an error naming the scene file and line.

use super::params::{Plugin, Xform};
use super::xml::Node;
use super::Cx;
use crate::math::{Rgb, Vec2, Vec3};
use crate::scene::limits;
use crate::scene::ply::IndexedMesh;
use crate::scene::shape_uv::{ShapeKind, ShapeUv};
use crate::scene::spec::{Corners, Origin, ShapeIn};
use crate::scene::SceneError;
use glam::{DMat3, DMat4, DVec3};

/// Slices of the tessellated `disk` and `cylinder`.
pub const SEGMENTS: u32 = 512;

/// Loads one `<shape>` into the builder.
pub(super) fn shape(cx: &mut Cx, n: &Node) -> Result<(), SceneError> {
    let mut p = Plugin::new(n);
    let xl = p.line_of("to_world");
    let xf = p.transform(cx, "to_world")?;
    let flip = p.boolean(cx, "flip_normals")?.unwrap_or(false);
    if let Some(m) = p.objects(&["medium"]).first() {
        return Err(p.err(cx, m.line, "medium", "participating media are not supported"));
    }
    let emission = emitter(cx, &mut p)?;
    let material = shape_material(cx, &mut p, emission.is_some())?;
    let ty = n.ty();
    // the key blamed when a vertex leaves the extent before the transform (the file, the
    // cylinder's points) and after it; the analytic parametrisation and its local frame
    let mut local = None;
    let (mesh, raw_at) = match ty {
        "obj" | "ply" => {
            let (m, fl) = file_mesh(cx, &mut p)?;
            (Some(m), Origin::new(fl, format!("{ty}.filename")))
        }
        "rectangle" => (Some(rectangle()), Origin::new(n.line, ty)),
        "cube" => (Some(cube()), Origin::new(n.line, ty)),
        "disk" => {
            local = Some((ShapeKind::Disk, DMat4::IDENTITY));
            (Some(disk()), Origin::new(n.line, ty))
        }
        "cylinder" => {
            let (m, frame) = cylinder(cx, &mut p)?;
            local = Some((ShapeKind::Cylinder, frame));
            (Some(m), Origin::new(p.line_of("p1"), "cylinder.p1"))
        }
        "sphere" => (None, Origin::new(n.line, ty)),
        t => {
            let msg = format!("shape `{t}` is not supported (obj, ply, rectangle, cube, sphere, disk, cylinder)");
            return Err(cx.err(n.line, &format!("shape.{t}"), msg));
        }
    };
    let xf_at = Origin::new(xl, format!("{ty}.to_world"));
    let what = match &raw_at.key {
        k if k.ends_with(".filename") => format!("shape `{ty}` ({})", mesh_name(&p)),
        _ => format!("shape `{ty}`"),
    };
    let at = Origin::new(n.line, format!("shape.{ty}"));
    let id = cx.b.shape(ShapeIn { at, material, emission, what, exact_normals: true });
    if let Some((kind, frame)) = local {
        let to_world = xf.as_ref().map_or(frame, |x| x.m * frame);
        match ShapeUv::new(kind, to_world) {
            Some(uv) => cx.b.shape_uv(id, uv),
            None if !cx.b.surface_at(material).is_constant() => {
                let msg = format!("`to_world` must be invertible for the texture coordinates of shape `{ty}`");
                return Err(p.err(cx, xl, "to_world", msg));
            }
            None => {}
        }
    }
    // Mitsuba's analytic disk and cylinder face along their normal transformed as a normal
    // (outward, +z), which a mirroring `to_world` does not turn; their tessellation's winding
    // turns with it, so it is reversed there (meshes, `rectangle` and `cube` face by their winding,
    // as Mitsuba's)
    let mirrored = local.is_some() && xf.as_ref().is_some_and(|x| DMat3::from_mat4(x.m).determinant() < 0.0);
    match mesh {
        Some(m) => triangles(cx, id, &m, xf.as_ref(), (flip, mirrored), (&raw_at, &xf_at))?,
        None => sphere(cx, &mut p, id, xf, flip, &xf_at)?,
    }
    p.finish(cx);
    Ok(())
}

/// The `filename` value (for messages; "" when absent).
fn mesh_name(p: &Plugin) -> String {
    p.node.children.iter().find(|c| c.name() == "filename").and_then(|c| c.attr("value")).unwrap_or("").to_string()
}

/// The area emitter's radiance (`None` when black) and its origin, if the shape has one.
fn emitter(cx: &mut Cx, p: &mut Plugin) -> Result<Option<(Rgb, Origin)>, SceneError> {
    let es = p.objects(&["emitter"]);
    let Some(e) = es.first() else { return Ok(None) };
    if e.ty() != "area" || es.len() > 1 {
        return Err(cx.err(e.line, &format!("emitter.{}", e.ty()), "a shape takes one `area` emitter"));
    }
    let mut ep = Plugin::new(e);
    let rl = ep.line_of("radiance");
    let Some(l) = ep.emission(cx, "radiance")? else {
        return Err(ep.err(cx, e.line, "radiance", "the area emitter needs `radiance`"));
    };
    let at = Origin::new(rl, "area.radiance");
    let l = cx.b.emission(l, &at)?;
    ep.finish(cx);
    Ok(l.map(|l| (l, at)))
}

/// Material index: the shape's BSDF, Mitsuba's default `diffuse` (0.5), or black for emitters.
fn shape_material(cx: &mut Cx, p: &mut Plugin, emits: bool) -> Result<u32, SceneError> {
    let bs = p.objects(&["bsdf", "ref"]);
    if bs.len() > 1 {
        return Err(p.err(cx, bs[1].line, "bsdf", "a shape takes one BSDF"));
    }
    if emits {
        let black = match bs.first() {
            Some(b) => super::bsdf::material(cx, b)?.m.is_black_diffuse(),
            None => false,
        };
        if !black {
            let line = bs.first().map_or(p.node.line, |b| b.line);
            cx.warn(
                line,
                format!(
                    "{}: emitters reflect nothing here; its BSDF (or Mitsuba's default diffuse) is dropped",
                    p.what()
                ),
            );
        }
        return Ok(0);
    }
    match bs.first() {
        Some(b) => super::bsdf::resolve(cx, b),
        None => Ok(cx.default_diffuse()),
    }
}

fn file_mesh(cx: &mut Cx, p: &mut Plugin) -> Result<(IndexedMesh, usize), SceneError> {
    let line = p.node.line;
    let Some((f, fl)) = p.string(cx, "filename")? else {
        return Err(p.err(cx, line, "filename", "missing `filename`"));
    };
    let path = cx.dir.join(&f);
    let m = if p.node.ty() == "ply" {
        crate::scene::ply::load_indexed(&path)
    } else {
        crate::scene::obj::load_indexed(&path)
    };
    let mut m = m.map_err(|e| p.err(cx, fl, "filename", e))?;
    cx.b.mesh_file(&path, m.bytes_hash);
    p.reject(cx, &["max_smooth_angle"], "normals are per-vertex or per-face")?;
    let face_normals = p.boolean(cx, "face_normals")?.unwrap_or(false);
    if face_normals {
        m.normals = None;
    } else if m.normals.is_none() {
        m.normals = Some(angle_weighted_normals(&m));
    }
    // OBJ's `vt` has its origin at the bottom left: the reader flips v, as Mitsuba's
    // `flip_tex_coords` (default true for OBJ, false for PLY)
    let flip_default = p.node.ty() == "obj";
    if p.boolean(cx, "flip_tex_coords")?.unwrap_or(flip_default) != flip_default {
        m.uvs.iter_mut().flatten().for_each(|t| t.y = 1.0 - t.y);
    }
    Ok((m, fl))
}

/// Mitsuba 3's vertex normals: face normals weighted by the corner angle, normalised.
fn angle_weighted_normals(m: &IndexedMesh) -> Vec<Vec3> {
    let mut vn = vec![Vec3::ZERO; m.positions.len()];
    for f in &m.faces {
        let v = f.map(|i| m.positions[i as usize]);
        let n = (v[1] - v[0]).cross(v[2] - v[0]);
        if n.length().is_nan() || n.length() <= 1e-12 {
            continue;
        }
        let n = n.normalize();
        for k in 0..3 {
            let (a, b) = ((v[(k + 1) % 3] - v[k]).normalize(), (v[(k + 2) % 3] - v[k]).normalize());
            let ang = a.dot(b).clamp(-1.0, 1.0).acos();
            if ang.is_finite() {
                vn[f[k] as usize] += n * ang;
            }
        }
    }
    vn.into_iter().map(|v| v.normalize_or_zero()).collect()
}

fn mesh(positions: Vec<Vec3>, normals: Option<Vec<Vec3>>, faces: Vec<[u32; 3]>) -> IndexedMesh {
    IndexedMesh { positions, normals, uvs: None, faces, bytes_hash: 0 }
}

fn rectangle() -> IndexedMesh {
    let p = [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]].map(|[x, y]| Vec3::new(x, y, 0.0));
    // Mitsuba's uv = (x + 1, y + 1)/2
    let uvs = p.iter().map(|p| Vec2::new(p.x + 1.0, p.y + 1.0) * 0.5).collect();
    IndexedMesh { uvs: Some(uvs), ..mesh(p.to_vec(), None, vec![[0, 1, 2], [2, 3, 0]]) }
}

/// Mitsuba 3's `cube` (cube.cpp): 24 vertices, four per face (−y, +y, +x, +z, −x, −z), each face
/// with the UVs (0, 1), (1, 1), (1, 0), (0, 0) at its vertices and the triangles {0, 1, 2},
/// {3, 0, 2}, counter-clockwise seen from outside.
fn cube() -> IndexedMesh {
    #[rustfmt::skip]
    const P: [[i8; 3]; 24] = [
        [1, -1, -1], [1, -1, 1], [-1, -1, 1], [-1, -1, -1],
        [1, 1, -1], [-1, 1, -1], [-1, 1, 1], [1, 1, 1],
        [1, -1, -1], [1, 1, -1], [1, 1, 1], [1, -1, 1],
        [1, -1, 1], [1, 1, 1], [-1, 1, 1], [-1, -1, 1],
        [-1, -1, 1], [-1, 1, 1], [-1, 1, -1], [-1, -1, -1],
        [1, 1, -1], [1, -1, -1], [-1, -1, -1], [-1, 1, -1],
    ];
    const UV: [[f32; 2]; 4] = [[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]];
    let pos = P.iter().map(|p| Vec3::from_array(p.map(f32::from))).collect();
    let uvs = (0..24).map(|i| Vec2::from_array(UV[i % 4])).collect();
    let faces = (0..6u32).flat_map(|f| [[4 * f, 4 * f + 1, 4 * f + 2], [4 * f + 3, 4 * f, 4 * f + 2]]).collect();
    IndexedMesh { uvs: Some(uvs), ..mesh(pos, None, faces) }
}

fn disk() -> IndexedMesh {
    let mut pos = vec![Vec3::ZERO];
    let mut faces = Vec::new();
    for i in 0..SEGMENTS {
        let a = std::f64::consts::TAU * i as f64 / SEGMENTS as f64;
        pos.push(Vec3::new(a.cos() as f32, a.sin() as f32, 0.0));
        faces.push([0, 1 + i, 1 + (i + 1) % SEGMENTS]);
    }
    mesh(pos, None, faces)
}

/// Unit open cylinder around +z from z = 0 to 1, mapped to `p0`, `p1`, `radius`, with that map
/// (Mitsuba's translate(p0) · frame(p1 − p0) · scale(r, r, |p1 − p0|): glam's
/// `any_orthonormal_pair` is Mitsuba's `coordinate_system`, Duff et al. 2017).
fn cylinder(cx: &Cx, p: &mut Plugin) -> Result<(IndexedMesh, DMat4), SceneError> {
    let p0 = p.point(cx, "p0")?.map_or(DVec3::ZERO, |a| DVec3::from_array(a.map(f64::from)));
    let p1 = p.point(cx, "p1")?.map_or(DVec3::Z, |a| DVec3::from_array(a.map(f64::from)));
    let r = p.float(cx, "radius")?.unwrap_or(1.0) as f64;
    let d = p1 - p0;
    if r.is_nan() || r <= 0.0 || d.length() <= 0.0 {
        return Err(p.err(cx, p.node.line, "radius", "radius must be positive and p0 != p1"));
    }
    let (s, t) = d.normalize().any_orthonormal_pair();
    let local = DMat3::from_cols(s * r, t * r, d);
    let (mut pos, mut nrm, mut faces) = (Vec::new(), Vec::new(), Vec::new());
    let inv_t = local.inverse().transpose();
    for i in 0..SEGMENTS {
        let a = std::f64::consts::TAU * i as f64 / SEGMENTS as f64;
        let c = DVec3::new(a.cos(), a.sin(), 0.0);
        let n = (inv_t * c).normalize().as_vec3();
        for z in [0.0, 1.0] {
            pos.push((p0 + local * (c + DVec3::Z * z)).as_vec3());
            nrm.push(n);
        }
        let (a0, a1, b0, b1) = (2 * i, 2 * i + 1, 2 * ((i + 1) % SEGMENTS), 2 * ((i + 1) % SEGMENTS) + 1);
        faces.extend([[a0, b0, b1], [a0, b1, a1]]);
    }
    let frame = DMat4::from_cols(local.x_axis.extend(0.0), local.y_axis.extend(0.0), d.extend(0.0), p0.extend(1.0));
    Ok((mesh(pos, Some(nrm), faces), frame))
}

fn sphere(
    cx: &mut Cx,
    p: &mut Plugin,
    id: usize,
    xf: Option<Xform>,
    flip: bool,
    xf_at: &Origin,
) -> Result<(), SceneError> {
    let (cl, rl) = (p.line_of("center"), p.line_of("radius"));
    let c = p.point(cx, "center")?.unwrap_or([0.0; 3]);
    let r = p.float(cx, "radius")?.unwrap_or(1.0);
    let (cat, rat) = (Origin::new(cl, "sphere.center"), Origin::new(rl, "sphere.radius"));
    if r.is_nan() || r <= 0.0 {
        return Err(cx.b.err(&rat, "radius must be positive"));
    }
    let (center, radius, axes) = match &xf {
        None => (Vec3::from_array(c), r, Vec3::AXES),
        Some(x) => {
            let m3 = DMat3::from_mat4(x.m);
            let s = [m3.x_axis.length(), m3.y_axis.length(), m3.z_axis.length()];
            let ortho =
                m3.x_axis.dot(m3.y_axis).abs() + m3.y_axis.dot(m3.z_axis).abs() + m3.x_axis.dot(m3.z_axis).abs();
            if (s[0] - s[1]).abs() > 1e-6 * s[0] || (s[0] - s[2]).abs() > 1e-6 * s[0] || ortho > 1e-6 * s[0] * s[0] {
                let msg =
                    "`to_world` must be a similarity (rotation, uniform scale, translation): spheres are analytic";
                return Err(p.err(cx, p.node.line, "to_world", msg));
            }
            let cc = x.m.transform_point3(DVec3::from_array(c.map(f64::from)));
            let axes = [m3.x_axis, m3.y_axis, m3.z_axis].map(|a| a.normalize().as_vec3());
            (cc.as_vec3(), (r as f64 * s[0]) as f32, axes)
        }
    };
    // after a transform, what leaves the extent (or shrinks the radius to 0) is the transform's
    let (cat, rat) = if xf.is_some() { (xf_at, xf_at) } else { (&cat, &rat) };
    cx.b.sphere(id, (center, cat), (radius, rat), flip, axes)
}

/// A mesh's world-space triangles → the builder (which skips degenerate ones with a warning and
/// refuses vertices outside the extent: at `raw_at` when the mesh itself is outside, else at
/// `xf_at`, the transform). `flip` (`flip_normals`) reverses the winding and the normals,
/// `reverse` the winding alone.
fn triangles(
    cx: &mut Cx,
    id: usize,
    m: &IndexedMesh,
    xf: Option<&Xform>,
    (flip, reverse): (bool, bool),
    (raw_at, xf_at): (&Origin, &Origin),
) -> Result<(), SceneError> {
    let nm = xf.map(|x| DMat3::from_mat4(x.m).inverse().transpose());
    let xp = |v: Vec3| xf.map_or(v, |x| x.m.transform_point3(v.as_dvec3()).as_vec3());
    let xn = |v: Vec3| nm.map_or(v, |n: DMat3| (n * v.as_dvec3()).as_vec3());
    let normals = m.normals.as_ref().filter(|ns| ns.len() == m.positions.len());
    let uvs = m.uvs.as_ref().filter(|t| t.len() == m.positions.len());
    for (k, f) in m.faces.iter().enumerate() {
        let f = if flip != reverse { [f[0], f[2], f[1]] } else { *f };
        let raw = f.map(|i| m.positions[i as usize]);
        let n = normals.map(|ns| f.map(|i| if flip { -xn(ns[i as usize]) } else { xn(ns[i as usize]) }));
        let uv = uvs.map(|t| f.map(|i| t[i as usize]));
        let blame = if raw.iter().any(|r| r.is_finite() && !limits::within_extent(*r)) { raw_at } else { xf_at };
        cx.b.triangle(id, (raw.map(xp), raw), Corners { n, uv }, blame, Some(k))?;
    }
    Ok(())
}

trait BlackDiffuse {
    fn is_black_diffuse(&self) -> bool;
}

impl BlackDiffuse for crate::scene::Material {
    fn is_black_diffuse(&self) -> bool {
        matches!(self, crate::scene::Material::Diffuse { albedo } if *albedo == Rgb::ZERO)
    }
}
