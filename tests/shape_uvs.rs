//! Texture coordinates of Mitsuba's shapes (issue #61): for `rectangle`, `sphere`, `disk`,
//! `cylinder` and `cube`, each with a non-trivial `to_world` (translations, rotations, and a
//! non-uniform scale wherever Mitsuba allows one: rectangle, disk, cube, and along the cylinder's
//! axis; a sheared matrix on a flipped disk), forecast loads the same XML as Mitsuba 3.9.1, traces
//! the same rays and finds Mitsuba's `si.p`, `si.n`, `si.uv`, `si.dp_du` and checkerboard
//! reflectance. The table: `tests/data/uv/<case>.{xml,json}` by `scripts/mitsuba-shape-uvs.py`
//! (scalar_rgb; 40 rays per case, incidence ≤ 60°, away from seams, edges and checker edges).
//!
//! Tolerances, derived (not tuned):
//! - rounding: both sides hit at p = o + t·d in float32, a few ulps of |o| + t each, so
//!   `EPS_P` = 8·2⁻²³·(|o| + t) per hit; texture coordinates themselves round at 2⁻²³.
//! - tessellation: forecast's cylinder is a 512-gon prism inscribed in Mitsuba's, within
//!   δ = r(1 − cos(π/512)) = 1.88e-5 r of it (r = |∂p/∂u|/2π, Mitsuba's own); along a ray at
//!   incidence θ the hit moves by at most δ/cos θ, its tangential part by δ·tan θ (the radial part
//!   changes no coordinate: forecast projects radially). Planes (rectangle, cube, disk) and the
//!   analytic sphere have δ = 0.
//! - uv: the tangential offset through the inverse of Mitsuba's Jacobian [∂p/∂u ∂p/∂v]:
//!   |Δuv| ≤ (δ·tan θ + EPS_P)/σ_min + 4·2⁻²³.
//! - ∂p/∂u: it turns and stretches with uv at a relative rate of at most K = 20 per unit of uv
//!   (2π on the cylinder and in the sphere's u; π·cot(πv) ≤ 19.8 in the sphere's v for the kept
//!   v ∈ [0.05, 0.95]; 2π·σ_max/σ_min ≤ 11.8 on the disks' maps): |Δ∂p/∂u| ≤ |∂p/∂u|·(K·|Δuv|
//!   + 8·2⁻²³).
//! - the geometric normal: within π/512 of Mitsuba's on the cylinder (a facet's), equal elsewhere.
//! - the reflectance (the checkerboard at the hit, through `Scene::shade`): equal, the rows lying
//!   0.01 in uv from the checker's edges, far beyond |Δuv|.

use forecast::accel::World;
use forecast::math::{Vec2, Vec3};
use forecast::scene::{mitsuba::SEGMENTS, Material};
use serde_json::Value;
use std::path::{Path, PathBuf};

const EPS: f32 = f32::EPSILON;
/// The relative rate at which ∂p/∂u changes per unit of uv on the kept rows (module docs).
const K: f32 = 20.0;

fn data() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/uv")
}

struct Row {
    o: Vec3,
    d: Vec3,
    t: f32,
    p: Vec3,
    n: Vec3,
    uv: Vec2,
    dp_du: Vec3,
    dp_dv: Vec3,
    reflectance: Vec3,
}

fn floats(v: &Value, key: &str) -> Vec<f32> {
    v[key].as_array().unwrap_or_else(|| panic!("`{key}`")).iter().map(|x| x.as_f64().unwrap() as f32).collect()
}

fn v3(v: &Value, key: &str) -> Vec3 {
    Vec3::from_slice(&floats(v, key))
}

/// The case's plugin and Mitsuba's rows.
fn table(case: &str) -> (String, Vec<Row>) {
    let path = data().join(format!("{case}.json"));
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let j: Value = serde_json::from_str(&text).unwrap();
    assert_eq!(j["mitsuba"], "3.9.1");
    assert_eq!(j["scene"].as_str(), Some(format!("{case}.xml").as_str()));
    let rows = j["rows"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| Row {
            o: v3(r, "o"),
            d: v3(r, "d"),
            t: r["t"].as_f64().unwrap() as f32,
            p: v3(r, "p"),
            n: v3(r, "n"),
            uv: Vec2::from_slice(&floats(r, "uv")),
            dp_du: v3(r, "dp_du"),
            dp_dv: v3(r, "dp_dv"),
            reflectance: v3(r, "reflectance"),
        })
        .collect();
    (j["shape"].as_str().unwrap().to_string(), rows)
}

/// The smallest singular value of the 3×2 Jacobian [a b].
fn sigma_min(a: Vec3, b: Vec3) -> f32 {
    let (aa, ab, bb) = (a.dot(a) as f64, a.dot(b) as f64, b.dot(b) as f64);
    let (tr, det) = (aa + bb, aa * bb - ab * ab);
    let disc = (0.25 * tr * tr - det).max(0.0).sqrt();
    (0.5 * tr - disc).max(0.0).sqrt() as f32
}

/// The worst of each comparison over a case, each as a share of its tolerance and as a value.
#[derive(Default, Debug)]
struct Worst {
    p: f32,
    uv: f32,
    uv_abs: f32,
    dp_du: f32,
    angle: f32,
    stretch: f32,
}

fn check(case: &str) -> Worst {
    let (plugin, rows) = table(case);
    assert_eq!(rows.len(), 40, "{case}");
    let scene = forecast::scene::load(&data().join(format!("{case}.xml"))).unwrap_or_else(|e| panic!("{e}"));
    assert!(scene.warnings.is_empty(), "{case}: {:?}", scene.warnings);
    let w = World::build(scene).expect("BVH builds");
    let facet = (std::f64::consts::PI / SEGMENTS as f64).cos() as f32;
    let mut worst = Worst::default();
    for (i, r) in rows.iter().enumerate() {
        let at = format!("{case} row {i}");
        let hit = w.intersect(r.o, r.d, f32::INFINITY).unwrap_or_else(|| panic!("{at}: no hit"));
        let cos = r.d.normalize().dot(r.n).abs();
        let tan = (1.0 - cos * cos).sqrt() / cos;
        let delta = if plugin == "cylinder" {
            (1.0 - (std::f64::consts::PI / SEGMENTS as f64).cos()) as f32 * r.dp_du.length() / std::f32::consts::TAU
        } else {
            0.0
        };
        let eps_p = 8.0 * EPS * (r.o.length() + r.t);
        // the hit point
        let tol_p = delta / cos + 2.0 * eps_p;
        let dp = (hit.p - r.p).length();
        assert!(dp <= tol_p, "{at}: p {} vs Mitsuba's {} (|Δ| {dp:e} > {tol_p:e})", hit.p, r.p);
        // the geometric normal, on Mitsuba's side
        let min_dot = if plugin == "cylinder" { facet - 4.0 * EPS } else { 1.0 - 4.0 * EPS };
        assert!(hit.ng.dot(r.n) >= min_dot, "{at}: n {} vs Mitsuba's {}", hit.ng, r.n);
        // uv
        let (uv, dp_du) = w.scene.uv_at(hit.prim, hit.p);
        let tol_uv = (delta * tan + 2.0 * eps_p) / sigma_min(r.dp_du, r.dp_dv) + 4.0 * EPS;
        let duv = (uv - r.uv).length();
        assert!(duv <= tol_uv, "{at}: uv {uv} vs Mitsuba's {} (|Δ| {duv:e} > {tol_uv:e})", r.uv);
        // ∂p/∂u: direction and length
        let tol_du = r.dp_du.length() * (K * tol_uv + 8.0 * EPS);
        let ddu = (dp_du - r.dp_du).length();
        assert!(ddu <= tol_du, "{at}: dp_du {dp_du} vs Mitsuba's {} (|Δ| {ddu:e} > {tol_du:e})", r.dp_du);
        // the checkerboard at the hit, as a render shades it
        let (m, _) = w.shade(&hit, -r.d);
        let Material::Diffuse { albedo } = m else { panic!("{at}: {m:?}") };
        assert!((albedo - r.reflectance).abs().max_element() <= 1e-6, "{at}: {albedo} vs {}", r.reflectance);
        worst.p = worst.p.max(dp / tol_p);
        worst.uv = worst.uv.max(duv / tol_uv);
        worst.uv_abs = worst.uv_abs.max(duv);
        worst.dp_du = worst.dp_du.max(ddu / tol_du);
        worst.angle = worst.angle.max(dp_du.cross(r.dp_du).length().atan2(dp_du.dot(r.dp_du)));
        worst.stretch = worst.stretch.max((dp_du.length() / r.dp_du.length() - 1.0).abs());
    }
    eprintln!(
        "{case:<18} worst share of tolerance: p {:.3}, uv {:.3}, dp_du {:.3}; |Δuv| {:.2e}, ∠dp_du {:.2e} rad, \
         |dp_du| ratio − 1 {:.2e}",
        worst.p, worst.uv, worst.dp_du, worst.uv_abs, worst.angle, worst.stretch
    );
    worst
}

#[test]
fn rectangle_uvs_equal_mitsubas() {
    check("rectangle");
}

#[test]
fn sphere_uvs_equal_mitsubas() {
    check("sphere");
}

#[test]
fn disk_uvs_equal_mitsubas() {
    check("disk");
    check("disk-flipped");
}

#[test]
fn cylinder_uvs_equal_mitsubas() {
    check("cylinder");
    check("cylinder-stretched");
}

#[test]
fn cube_uvs_equal_mitsubas() {
    check("cube");
}

/// A textured disk whose `to_world` flattens its own frame has no texture coordinates: a typed
/// error at the transform (untextured, it loads as before).
#[test]
fn singular_frame_of_a_textured_disk_is_an_error() {
    let scene = |bsdf: &str| {
        format!(
            r#"<scene version="3.0.0"><sensor type="perspective"><float name="fov" value="40"/></sensor>
<emitter type="point"><point name="position" value="0, 0, 5"/></emitter>
<shape type="disk">
    <transform name="to_world"><scale x="1" y="1" z="0"/></transform>
    {bsdf}
</shape></scene>"#
        )
    };
    let load = |src: &str| forecast::scene::mitsuba::load_str(src, "t.xml", Path::new("."), &[]);
    if let Err(e) = load(&scene("")) {
        panic!("{e}");
    }
    let textured = r#"<bsdf type="diffuse"><texture name="reflectance" type="checkerboard"/></bsdf>"#;
    let e = load(&scene(textured)).expect_err("refused");
    assert_eq!((e.line, e.key.as_str()), (4, "disk.to_world"), "{e}");
    assert!(e.to_string().contains("invertible"), "{e}");
}

/// A mirroring `to_world` does not turn Mitsuba's analytic `disk` and `cylinder`: they face along
/// their normal transformed as a normal. Mitsuba 3.9.1 (scalar_rgb, rays from both sides):
/// `disk` under scale (1, 1, −1) has `si.n` = (0, 0, −1); `cylinder` under scale (−1, 1, 1) has
/// `si.n` = (0.994987, 0.1, 0) at (0.994987, 0.1, 0.5), outward. The tessellations face the same
/// way (their winding reversed where `to_world` mirrors), and a `flip_normals` turns them.
#[test]
fn mirrored_disks_and_cylinders_face_as_mitsubas() {
    let scene = |shape: &str, xf: &str, flip: bool| {
        let xml = format!(
            "<scene version=\"3.0.0\"><sensor type=\"perspective\"><float name=\"fov\" value=\"40\"/></sensor><shape type=\"sphere\"><point name=\"center\" x=\"0\" y=\"0\" z=\"9\"/><emitter type=\"area\"><rgb name=\"radiance\" value=\"1\"/></emitter></shape><shape type=\"{shape}\"><transform name=\"to_world\"><scale {xf}/></transform>\
             <boolean name=\"flip_normals\" value=\"{flip}\"/></shape></scene>"
        );
        forecast::scene::mitsuba::load_str(&xml, "mirrored.xml", Path::new("."), &[]).expect("loads")
    };
    for flip in [false, true] {
        let sign = if flip { -1.0 } else { 1.0 };
        let disk = scene("disk", "x=\"1\" y=\"1\" z=\"-1\"", flip);
        assert!(
            disk.triangles.iter().all(|t| (t.ng - Vec3::new(0.0, 0.0, -sign)).length() < 1e-5),
            "disk, flip {flip}"
        );
        let cyl = scene("cylinder", "x=\"-1\" y=\"1\" z=\"1\"", flip);
        assert!(
            cyl.triangles.iter().all(|t| {
                let c = (t.p[0] + t.p[1] + t.p[2]) / 3.0;
                t.ng.dot(Vec3::new(c.x, c.y, 0.0)) * sign > 0.0
            }),
            "cylinder, flip {flip}"
        );
    }
}
