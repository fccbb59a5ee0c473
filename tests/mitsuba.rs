//! Mitsuba XML and PLY import (issue 13): the TOML → XML → Scene round trip (identical scene,
//! bit-identical image), the external SMS ring scene (loads with its ignored parameters listed,
//! renders with every method, `pt` and `iws-cf` agree by a Šidák-corrected per-pixel Welch z-test
//! at family-wise α = 1e-3), the cylinder tessellation against the analytic cylinder, `fov_axis`,
//! transform order, `-D`, PLY meshes from XML and TOML, and malformed inputs (clear errors with
//! file and line, no panic).

mod common;
use common::{assert_detects, global_z, max_z, render_passes, root, tmp_dir};
use forecast::accel::World;
use forecast::integrators::{Integrator, Method, MethodArgs};
use forecast::math::Vec3;
use forecast::scene::{mitsuba, Material, Scene};
use forecast::stats::z_test_threshold;
use std::path::Path;

// ---- the only lines that depend on the World / integrator API ----
fn world(s: Scene) -> World {
    World::build(s).expect("BVH builds")
}

/// Method options: cap 64, `vpl` IWS paths per pass, `photons` for iws-pm and iws-cf.
fn opts(vpl: u32, photons: u64) -> MethodArgs {
    let mut o = MethodArgs::default();
    (o.settings.max_depth, o.iws.vpl_paths, o.pm.photons, o.cf.forecast_photons) =
        (Some(64), vpl, photons, Some(photons));
    o
}

/// Preprocess (seeded) and build a method's integrator, as a rank would.
fn integrator(m: Method, w: &World, o: &MethodArgs, seed: u64) -> Box<dyn Integrator> {
    let bytes = m.preprocess(w, o, seed).unwrap();
    m.build(w, o, &bytes).unwrap()
}
// ----

fn xml(src: &str, dir: &Path) -> Result<Scene, forecast::scene::SceneError> {
    mitsuba::load_str(src, "t.xml", dir, &[])
}

/// The scene minus `path`, `hash` and `warnings`, as comparable text (f32 printed exactly).
fn fingerprint(s: &Scene) -> String {
    format!(
        "{:?}|{:?}|{:?}|{:?}|{:?}|{:?}|{:?}|{:?}|{:?}|{:?}|{:?}|{:?}|{:?}",
        s.camera,
        s.render,
        s.materials,
        s.triangles,
        s.spheres,
        s.emitters,
        s.point_lights,
        s.lights,
        s.light_pick,
        s.rois,
        s.forecast_target,
        s.forecast_photons,
        s.bounds
    )
}

#[test]
fn exported_toml_scenes_load_back_identical_and_render_bit_identically() {
    let dir = tmp_dir("mitsuba-roundtrip");
    let mut n = 0;
    for e in std::fs::read_dir(root().join("scenes")).unwrap() {
        let p = e.unwrap().path();
        if p.extension().is_none_or(|x| x != "toml") {
            continue;
        }
        let out = dir.join(p.file_stem().unwrap()).with_extension("xml");
        forecast::scene::export::export_mitsuba(&p, &out).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
        let a = forecast::scene::load(&p).unwrap();
        let b = forecast::scene::load(&out).unwrap_or_else(|e| panic!("{e}"));
        assert!(fingerprint(&a) == fingerprint(&b), "{}: the exported scene differs", p.display());
        assert!(b.warnings.is_empty(), "{}: {:?}", p.display(), b.warnings);
        let (wa, wb) = (world(a), world(b));
        let o = opts(32, 1000);
        let mut pa = integrator(Method::Pt, &wa, &o, 1);
        let mut pb = integrator(Method::Pt, &wb, &o, 1);
        let (fa, fb) = (render_passes(&wa, pa.as_mut(), 20, 20, 2, 9), render_passes(&wb, pb.as_mut(), 20, 20, 2, 9));
        assert!(fa.data.iter().zip(&fb.data).all(|(x, y)| x.to_bits() == y.to_bits()), "{}", p.display());
        assert!(fa.data.iter().any(|&x| x > 0.0));
        n += 1;
    }
    assert!(n >= 3, "expected the committed scenes, found {n}");
}

fn ring_src() -> String {
    std::fs::read_to_string(root().join("scenes/external/sms-ring/ring.xml")).unwrap()
}

fn ring_dir() -> std::path::PathBuf {
    root().join("scenes/external/sms-ring")
}

#[test]
fn sms_ring_loads_with_its_ignored_parameters_listed() {
    let s = mitsuba::load(&ring_dir().join("ring.xml"), &[]).unwrap_or_else(|e| panic!("{e}"));
    let w = s.warnings.join("\n");
    for (line, what) in [
        (6, "integrator `path_sms_ss` ignored"),
        (39, "`caustic_emitter_single` ignored"),
        (45, "`caustic_caster_single` ignored"),
        (63, "`caustic_receiver` ignored"),
    ] {
        assert!(w.contains(&format!("ring.xml:{line}: ")) && w.contains(what), "missing line {line} `{what}` in\n{w}");
    }
    assert_eq!(s.triangles.len(), 2 + 2 * mitsuba::SEGMENTS as usize + 2);
    assert_eq!((s.camera.width, s.camera.height, s.render.spp), (720, 540, Some(200)));
    // fov 28° along the larger (x) axis
    let want = 2.0 * ((14f64).to_radians().tan() * 540.0 / 720.0).atan().to_degrees();
    assert!((s.camera.fov_deg as f64 - want).abs() < 1e-4, "{}", s.camera.fov_deg);
    assert!(s.materials.iter().any(|m| matches!(m, Material::Conductor { eta, .. } if (eta.x - 0.143).abs() < 1e-3)));
    // the light: 0.2 × 0.2 at y = 10 facing down, radiance 70000 × the sRGB of illuminant E
    assert_eq!(s.emitters.len(), 2);
    let e = &s.emitters[0];
    assert!(
        (e.area - 0.02).abs() < 1e-6
            && (e.radiance - 70000.0 * Vec3::new(1.204_793_9, 0.948_291, 0.908_916_06)).abs().max_element() < 0.05
    );
    // (a uniform emitter <spectrum> is Mitsuba 3's equal-energy spectrum in sRGB: docs/mitsuba.md)
    assert!((s.triangles[0].ng - Vec3::NEG_Y).length() < 1e-6);
    // -D overrides the default
    let s = mitsuba::load(&ring_dir().join("ring.xml"), &[("spp".into(), "8".into())]).unwrap();
    assert_eq!(s.render.spp, Some(8));
    let opts = forecast::scene::LoadOptions { defines: vec![("spp".into(), "8".into())] };
    assert_eq!(forecast::scene::load_with(&ring_dir().join("ring.xml"), &opts).unwrap().render.spp, Some(8));
    assert_eq!(forecast::scene::load(&ring_dir().join("ring.xml")).unwrap().render.spp, Some(200));
}

/// `forecast render ring.xml -D spp=3` renders 3 spp (the XML's `$spp` default is 200), and a
/// malformed `-D` is a clear command-line error.
#[test]
fn cli_define_overrides_the_xml_default() {
    let dir = tmp_dir("mitsuba_cli_define");
    let out = dir.join("ring");
    let run = |d: &str| {
        std::process::Command::new(env!("CARGO_BIN_EXE_forecast"))
            .args(["render", ring_dir().join("ring.xml").to_str().unwrap(), "--method", "pt"])
            .args(["--resolution", "8x6", "--threads", "1", "--quiet", "--out", out.to_str().unwrap(), "-D", d])
            .output()
            .unwrap()
    };
    let o = run("spp=3");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let rep: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.with_extension("json")).unwrap()).unwrap();
    assert_eq!(rep["spp"], 3, "{rep}");
    let o = run("spp");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("NAME=VALUE") && !err.contains("panicked"), "{err}");
}

#[test]
fn sms_ring_renders_with_every_method() {
    let w = world(mitsuba::load(&ring_dir().join("ring.xml"), &[]).unwrap());
    let o = opts(32, 2000);
    for m in [Method::Pt, Method::Iws, Method::IwsPm, Method::IwsCf] {
        let mut integ = integrator(m, &w, &o, 3);
        let f = render_passes(&w, integ.as_mut(), 12, 9, 2, 1);
        let mean = f.mean();
        assert!(mean.iter().flatten().all(|x| x.is_finite() && *x >= 0.0), "{m:?}");
        assert!(mean.iter().flatten().any(|&x| x > 0.0), "{m:?}: black image");
    }
}

#[test]
fn sms_ring_pt_and_iws_cf_agree() {
    // The scene's 0.2 × 0.2 light makes the caustic a ~1e-5 event for `pt`, whose variance
    // estimate is then empty or heavy-tailed at any test budget; the same light at 30× the size
    // and 1/900 the radiance (the same power) keeps every other parameter of the file.
    let src = ring_src().replace("<scale x=\"0.1\" y=\"0.1\" z=\"0.1\"/>", "<scale x=\"3\" y=\"3\" z=\"3\"/>");
    let src = src.replace("value=\"70000\"", "value=\"77.777778\"");
    let w = world(mitsuba::load_str(&src, "ring-big-light.xml", &ring_dir(), &[]).unwrap());
    assert!((w.scene.emitters[0].area - 18.0).abs() < 1e-4);
    let o = opts(64, 20_000);
    let (rw, rh) = (8, 6);
    let mut pt = integrator(Method::Pt, &w, &o, 17);
    let reference = render_passes(&w, pt.as_mut(), rw, rh, 16384, 11);
    let mut cf = integrator(Method::IwsCf, &w, &o, 17);
    let img = render_passes(&w, cf.as_mut(), rw, rh, 2048, 3);
    let (z, n) = max_z(&img, &reference, None);
    let thr = z_test_threshold(1e-3, n);
    eprintln!("sms ring: max|z| = {z:.2}, threshold {thr:.2} over {n} tests");
    assert!(z < thr, "iws-cf disagrees with pt on the ring: max|z| {z} >= {thr}");
    let (zg, thr1) = (global_z(&img, &reference), z_test_threshold(1e-3, 1));
    assert!(zg.abs() < thr1, "image means differ: z {zg}");
    assert_detects(&img, &reference, 0.05, thr1, "sms ring");
}

#[test]
fn cylinder_tessellation_matches_the_analytic_cylinder() {
    let src = r#"<scene version="3.0.0"><sensor type="perspective"><float name="fov" value="40"/></sensor>
        <shape type="cylinder"><float name="radius" value="2"/><point name="p1" x="0" y="0" z="3"/></shape>
        <emitter type="point"><point name="position" value="0, 0, 10"/></emitter></scene>"#;
    let s = xml(src, Path::new(".")).unwrap();
    let area: f64 = s.triangles.iter().map(|t| t.area as f64).sum();
    let exact = 2.0 * std::f64::consts::PI * 2.0 * 3.0;
    // stated tolerances: area short by 1 − sin(π/N)/(π/N), silhouette inside by r(1 − cos(π/N))
    let h = std::f64::consts::PI / mitsuba::SEGMENTS as f64;
    let (da, ds) = (1.0 - h.sin() / h, 1.0 - h.cos());
    assert!(da < 1e-5 && ds < 2e-5, "tessellation too coarse: {da} {ds}");
    assert!(((exact - area) / exact - da).abs() < 1e-6, "area {area} vs {exact}");
    // silhouette: the distance of every edge midpoint (the farthest-in points) and vertex from the axis
    let mut worst = 0.0f64;
    for t in &s.triangles {
        for (a, b) in [(t.p[0], t.p[1]), (t.p[1], t.p[2]), (t.p[2], t.p[0])] {
            for q in [a, 0.5 * (a + b)] {
                let r = ((q.x as f64).powi(2) + (q.y as f64).powi(2)).sqrt();
                worst = worst.max((2.0 - r).abs() / 2.0);
            }
        }
        let n = t.n.expect("radial vertex normals");
        for (k, v) in n.iter().enumerate() {
            let radial = Vec3::new(t.p[k].x, t.p[k].y, 0.0).normalize();
            assert!((*v - radial).length() < 1e-5 && t.ng.dot(radial) > 0.99);
        }
    }
    assert!(worst <= ds * 1.01 + 1e-6, "silhouette off by {worst} r (stated {ds})");
}

fn camera_xml(axis: &str, fov: f32, w: u32, h: u32, xf: &str) -> String {
    format!(
        r#"<scene version="3.0.0"><sensor type="perspective"><float name="fov" value="{fov}"/>
        <string name="fov_axis" value="{axis}"/><transform name="to_world">{xf}</transform>
        <film type="hdrfilm"><integer name="width" value="{w}"/><integer name="height" value="{h}"/></film></sensor>
        <shape type="sphere"><emitter type="area"><rgb name="radiance" value="1, 1, 1"/></emitter></shape></scene>"#
    )
}

#[test]
fn every_fov_axis_and_the_transform_order() {
    let look = r#"<lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/>"#;
    let (w, h) = (400u32, 200u32);
    let a = w as f64 / h as f64;
    let ty = (20f64).to_radians().tan(); // vertical half-angle 20°
    let tx = ty * a;
    let deg = |t: f64| (2.0 * t.atan()).to_degrees() as f32;
    for (axis, fov) in [("y", deg(ty)), ("x", deg(tx)), ("smaller", deg(ty)), ("larger", deg(tx))] {
        let s = xml(&camera_xml(axis, fov, w, h, look), Path::new(".")).unwrap();
        assert!((s.camera.fov_deg - 40.0).abs() < 1e-3, "{axis}: {}", s.camera.fov_deg);
    }
    let s = xml(&camera_xml("diagonal", deg((tx * tx + ty * ty).sqrt()), w, h, look), Path::new(".")).unwrap();
    assert!((s.camera.fov_deg - 40.0).abs() < 1e-3);
    // portrait: `smaller` is x
    let s = xml(&camera_xml("smaller", deg(ty / a), h, w, look), Path::new(".")).unwrap();
    assert!((s.camera.fov_deg - 40.0).abs() < 1e-3, "{}", s.camera.fov_deg);
    // Mitsuba's order: first listed first; translate after rotate keeps the position
    let xf = r#"<rotate y="1" angle="90"/><translate x="1" y="2" z="3"/>"#;
    let s = xml(&camera_xml("y", 40.0, w, h, xf), Path::new(".")).unwrap();
    assert!((s.camera.position - Vec3::new(1.0, 2.0, 3.0)).length() < 1e-6);
    // local +z rotated 90° about +y is +x; image right is local −x → +z
    assert!((s.camera.forward - Vec3::X).length() < 1e-6 && (s.camera.right - Vec3::Z).length() < 1e-6);
    // the lookat matrix gives the same frame as the lookat camera
    let m = r#"<lookat origin="1, 2, 3" target="0, 0, 0" up="0, 1, 0"/><scale value="1"/>"#;
    let l = r#"<lookat origin="1, 2, 3" target="0, 0, 0" up="0, 1, 0"/>"#;
    let (cm, cl) = (
        xml(&camera_xml("y", 40.0, w, h, m), Path::new(".")).unwrap().camera,
        xml(&camera_xml("y", 40.0, w, h, l), Path::new(".")).unwrap().camera,
    );
    for (p, q) in [(cm.forward, cl.forward), (cm.right, cl.right), (cm.up, cl.up), (cm.position, cl.position)] {
        assert!((p - q).length() < 1e-6, "{p} vs {q}");
    }
}

const PLY_ASCII: &str =
    "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n\
element face 2\nproperty list uchar int vertex_indices\nend_header\n-1 0 -1\n1 0 -1\n1 0 1\n-1 0 1\n3 0 2 1\n3 0 3 2\n";

fn ply_scene(shape: &str) -> String {
    format!(
        r#"<scene version="2.0.0"><sensor type="perspective"><float name="fov" value="40"/>
    <transform name="toWorld"><lookat origin="0, 3, 0.1" target="0, 0, 0"/></transform></sensor>
    {shape}
    <emitter type="point"><point name="position" value="0, 2, 0"/><rgb name="intensity" value="1"/></emitter></scene>"#
    )
}

#[test]
fn ply_meshes_load_from_xml_and_toml() {
    let dir = tmp_dir("mitsuba-ply");
    std::fs::write(dir.join("quad.ply"), PLY_ASCII).unwrap();
    let flat = r#"<shape type="ply"><string name="filename" value="quad.ply"/><boolean name="faceNormals" value="true"/></shape>"#;
    let f = xml(&ply_scene(flat), &dir).unwrap();
    assert_eq!(f.triangles.len(), 2);
    assert!(f.triangles.iter().all(|t| t.n.is_none() && (t.ng - Vec3::Y).length() < 1e-6), "{:?}", f.triangles);
    assert!(f.warnings.is_empty(), "{:?}", f.warnings);
    // without face_normals: Mitsuba's vertex normals (flat quad: +y everywhere); flip_normals flips
    let s = xml(&ply_scene(r#"<shape type="ply"><string name="filename" value="quad.ply"/><boolean name="flip_normals" value="true"/></shape>"#), &dir).unwrap();
    assert!(s.triangles.iter().all(|t| (t.ng + Vec3::Y).length() < 1e-6 && t.n.unwrap()[0] == -Vec3::Y));
    // the same quad from a TOML scene (the reader picked by extension)
    let toml = r#"[camera]
position = [0.0, 3.0, 0.1]
look_at = [0.0, 0.0, 0.0]
fov = 40.0
resolution = [8, 8]
[materials.m]
type = "diffuse"
albedo = [0.5, 0.5, 0.5]
[[shape]]
type = "mesh"
file = "quad.ply"
material = "m"
[[light]]
type = "point"
position = [0.0, 2.0, 0.0]
intensity = [1.0, 1.0, 1.0]
"#;
    let t = forecast::scene::load_str(toml, "ply.toml", &dir).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(t.triangles.len(), 2);
    for (a, b) in t.triangles.iter().zip(&f.triangles) {
        assert_eq!((a.p, a.ng, a.area), (b.p, b.ng, b.area));
    }
    // binary little endian with normals, through TOML too
    let m = forecast::scene::ply::parse(PLY_ASCII.as_bytes()).unwrap();
    let m = forecast::scene::ply::IndexedMesh { normals: Some(vec![Vec3::Y; 4]), ..m };
    std::fs::write(dir.join("quad.ply"), forecast::scene::ply::write_binary(&m)).unwrap();
    let toml = toml.replace("material = \"m\"", "material = \"m\"\nnormals = \"smooth\"");
    let t = forecast::scene::load_str(&toml, "ply.toml", &dir).unwrap_or_else(|e| panic!("{e}"));
    assert!(t.triangles.iter().all(|x| x.n == Some([Vec3::Y; 3])));
}

/// Each malformed input: (xml, files to write, expected line, words the message must contain).
#[test]
fn malformed_inputs_are_clear_errors_with_file_and_line() {
    let dir = tmp_dir("mitsuba-bad");
    std::fs::write(dir.join("quad.ply"), PLY_ASCII).unwrap();
    std::fs::write(dir.join("bad_index.ply"), PLY_ASCII.replace("3 0 3 2", "3 0 3 9")).unwrap();
    let mut bin = forecast::scene::ply::write_binary(&forecast::scene::ply::parse(PLY_ASCII.as_bytes()).unwrap());
    bin.truncate(bin.len() - 5);
    std::fs::write(dir.join("short.ply"), bin).unwrap();
    let ply = |f: &str| {
        format!(
            r#"<shape type="ply">
<string name="filename" value="{f}"/></shape>"#
        )
    };
    let cases: Vec<(String, usize, Vec<&str>)> = vec![
        (ply_scene("<shape type=\"ply\">\n<string name=\"filename\" value=\"quad.ply\"/>"), 5, vec!["malformed XML"]),
        (ply_scene("<shape type=\"ply\">\n<string name=\"filename\" value=\"quad.ply\"/>\n<ref id=\"gold\"/></shape>"), 5, vec!["gold", "no BSDF"]),
        (ply_scene(&ply("missing.ply")), 4, vec!["missing.ply", "filename"]),
        (ply_scene(&ply("bad_index.ply")), 4, vec!["line 15", "index 9 out of range"]),
        (ply_scene(&ply("short.ply")), 4, vec!["cut short at byte"]),
        (
            ply_scene("<shape type=\"ply\"><string name=\"filename\" value=\"quad.ply\"/>\n<transform name=\"to_world\">\n<matrix value=\"1 0 0 0 0 1 0 0 0 0 1 0 0 0 0\"/></transform></shape>"),
            5,
            vec!["matrix", "16", "got 15"],
        ),
        (ply_scene("<shape type=\"ply\"><string name=\"filename\" value=\"quad.ply\"/>\n<bsdf type=\"roughconductor\"/></shape>"), 4, vec!["roughconductor", "not supported"]),
        (ply_scene("<shape type=\"ply\"><string name=\"filename\" value=\"quad.ply\"/>\n<bsdf type=\"diffuse\">\n<texture name=\"reflectance\" type=\"bitmap\"/></bsdf></shape>"), 5, vec!["diffuse.reflectance", "textures"]),
        (ply_scene("\n<emitter type=\"envmap\"/>"), 4, vec!["envmap", "not supported"]),
        (ply_scene("\n<medium type=\"homogeneous\"/>"), 4, vec!["medium"]),
        (ply_scene("\n<shape type=\"ply\"><integer name=\"x\" value=\"$nope\"/></shape>"), 4, vec!["$nope", "not defined"]),
        // 0 photons is an error, as `[forecast] photons = 0` (it used to fall back to the default)
        (ply_scene("\n<default name=\"forecast_photons\" value=\"0\"/>"), 4, vec!["forecast_photons", "at least 1"]),
        // the light limits of src/scene/limits.rs
        (ply_scene("\n<emitter type=\"point\"><point name=\"position\" value=\"0, 2, 0\"/><rgb name=\"intensity\" value=\"2e9\"/></emitter>"), 4, vec!["intensity", "at most 1e9"]),
        (ply_scene("<shape type=\"ply\"><string name=\"filename\" value=\"quad.ply\"/>\n<emitter type=\"area\"><rgb name=\"radiance\" value=\"1e16\"/></emitter></shape>"), 4, vec!["radiance", "at most 1e15"]),
    ];
    for (src, line, words) in cases {
        let e = match std::panic::catch_unwind(|| xml(&src, &dir)) {
            Ok(Err(e)) => e,
            Ok(Ok(_)) => panic!("accepted:\n{src}"),
            Err(_) => panic!("panicked on:\n{src}"),
        };
        let msg = e.to_string();
        assert!(msg.starts_with(&format!("t.xml:{line}: ")), "wrong line in `{msg}` (want {line})");
        for w in words {
            assert!(msg.contains(w), "`{msg}` lacks `{w}`");
        }
    }
}

#[test]
fn truncated_inputs_never_panic() {
    let src = ring_src();
    for cut in (0..src.len()).step_by(7) {
        if !src.is_char_boundary(cut) {
            continue;
        }
        let r = std::panic::catch_unwind(|| mitsuba::load_str(&src[..cut], "cut.xml", &ring_dir(), &[]));
        assert!(r.is_ok(), "panic on ring.xml cut at byte {cut}");
    }
    let m = forecast::scene::ply::parse(PLY_ASCII.as_bytes()).unwrap();
    let m = forecast::scene::ply::IndexedMesh { normals: Some(vec![Vec3::Y; 4]), ..m };
    let bin = forecast::scene::ply::write_binary(&m);
    for cut in 0..bin.len() {
        let r = std::panic::catch_unwind(|| forecast::scene::ply::parse(&bin[..cut]));
        assert!(matches!(r, Ok(Err(_))), "PLY cut at byte {cut}: not a clean error");
    }
    for cut in 0..PLY_ASCII.len() - 1 {
        let r = std::panic::catch_unwind(|| forecast::scene::ply::parse(&PLY_ASCII.as_bytes()[..cut]));
        assert!(r.is_ok(), "ASCII PLY cut at byte {cut}: panic");
    }
}

// ---- issue 31: parsers bounded by their input, one builder's checks in every format ----

/// The reproducers of issue 31 (tests/scenes/robustness/).
fn robust() -> std::path::PathBuf {
    root().join("tests/scenes/robustness")
}

/// Loads `name` (TOML or XML) from the reproducers; panics on a panic.
fn load_robust(name: &str) -> Result<Scene, forecast::scene::SceneError> {
    let p = robust().join(name);
    std::panic::catch_unwind(|| forecast::scene::load(&p)).unwrap_or_else(|_| panic!("{name}: panicked"))
}

/// `name` fails at `line` with `key`, and its message holds every word of `words`.
fn refused(name: &str, line: usize, key: &str, words: &[&str]) {
    let e = match load_robust(name) {
        Ok(_) => panic!("{name}: accepted"),
        Err(e) => e,
    };
    let msg = e.to_string();
    assert_eq!((e.line, e.key.as_str()), (line, key), "{name}: {msg}");
    for w in words {
        assert!(msg.contains(w), "{name}: `{msg}` lacks `{w}`");
    }
}

#[test]
fn ply_second_vertex_element_is_refused_not_a_panic() {
    // the normals of a second `element vertex` were shorter than the positions: index panics
    // at scene/ply.rs (TOML, smooth normals) and mitsuba/shapes.rs (XML)
    refused("ply_two_vertex_elements_panic.toml", 11, "shape[0].file", &["second `element vertex`", "line 7"]);
    refused("ply_two_vertex_elements_panic.xml", 5, "ply.filename", &["second `element vertex`"]);
}

#[test]
fn ply_element_counts_are_checked_against_the_bytes_left() {
    // 0 properties × 1.8e19 rows: nothing to read, skipped at once (it was read row by row, forever)
    let t = std::time::Instant::now();
    let s = load_robust("ply_zero_prop_element_hang.toml").unwrap_or_else(|e| panic!("{e}"));
    assert!(!s.triangles.is_empty());
    load_robust("ply_zero_prop_element_hang.xml").unwrap_or_else(|e| panic!("{e}"));
    assert!(t.elapsed().as_secs_f64() < 2.0, "{:?}", t.elapsed());
    // a count the bytes cannot hold is refused before any row is read
    let head = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
property float z\nelement face 4000000000\nproperty list uchar int vertex_indices\nend_header\n";
    let mut b = head.as_bytes().to_vec();
    b.extend(std::iter::repeat_n(0u8, 36));
    let e = forecast::scene::ply::parse(&b).err().unwrap();
    assert!(e.contains("declares 4000000000 rows") && e.contains("at most"), "{e}");
}

#[test]
fn ply_of_20mb_of_empty_faces_fails_at_the_first_face() {
    // 20 M faces of 0 vertices: 1.6 GB before the error (an abort under a 1 GB limit); now the
    // first face is the error and nothing is stored
    let dir = tmp_dir("ply-zero-faces");
    let n = 20_000_000;
    let mut b = format!("ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face {n}\nproperty list uchar int vertex_indices\nend_header\n").into_bytes();
    let head = b.len();
    for v in [[-0.5f32, 0.5, 0.0], [0.5, 0.5, 0.0], [0.0, 1.2, 0.0]] {
        v.iter().for_each(|x| b.extend_from_slice(&x.to_le_bytes()));
    }
    b.resize(b.len() + n, 0);
    std::fs::write(dir.join("ply_zero_len_faces_20M.ply"), &b).unwrap();
    for f in ["ply_zero_len_faces_20M.toml", "ply_zero_len_faces_20M.xml"] {
        std::fs::copy(robust().join(f), dir.join(f)).unwrap();
        let t = std::time::Instant::now();
        let e = forecast::scene::load(&dir.join(f)).err().unwrap().to_string();
        assert!(e.contains(&format!("byte {}: face with 0 vertices", head + 36)), "{f}: {e}");
        assert!(t.elapsed().as_secs_f64() < 5.0, "{f}: {:?}", t.elapsed());
    }
}

#[test]
fn ply_list_length_must_be_a_whole_number() {
    let b = std::fs::read(robust().join("ply_list_len_3.9_accepted.ply")).unwrap();
    let e = forecast::scene::ply::parse(&b).err().unwrap();
    assert!(e.contains("line 8") && e.contains("count type must be an integer"), "{e}");
    let b = String::from_utf8(b).unwrap().replace("list float int", "list uchar int");
    let e = forecast::scene::ply::parse(b.as_bytes()).err().unwrap();
    assert!(e.contains("line 13") && e.contains("bad list length 3.9"), "{e}");
}

/// A minimal XML scene around `body` (a camera, a rectangle, a point light).
fn xml_with(body: &str) -> String {
    format!(
        r#"<scene version="3.0.0"><sensor type="perspective"><float name="fov" value="40"/>
<transform name="to_world"><lookat origin="0, 1, 3.88" target="0, 1, 0" up="0, 1, 0"/></transform>
<film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film></sensor>
<shape type="rectangle"/>
<emitter type="point"><point name="position" x="0" y="1" z="2"/><rgb name="intensity" value="1"/></emitter>
{body}</scene>"#
    )
}

#[test]
fn xml_nesting_is_limited_with_a_clear_error() {
    // 10,000 nested elements overflowed the stack (SIGABRT)
    let n = 10_000;
    let deep =
        format!("<bsdf type=\"twosided\">{}{}</bsdf>", "<bsdf type=\"twosided\">\n".repeat(n), "</bsdf>".repeat(n));
    let e = xml(&xml_with(&deep), Path::new(".")).err().unwrap();
    assert!(e.message.contains("nested more than 64 deep"), "{e}");
    assert_eq!(e.line, 6 + 62, "{e}"); // the 65th element: scene, then 63 bsdfs from line 6
                                       // real scenes nest a handful
    let ok = "<bsdf type=\"twosided\"><bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.5\"/></bsdf></bsdf>";
    xml(&xml_with(ok), Path::new(".")).unwrap_or_else(|e| panic!("{e}"));
}

#[test]
fn xml_load_time_is_linear_in_the_elements() {
    // 10k elements took 0.31 s, 40k 4.9 s, 100k over 20 s (a line lookup from the document start
    // per node): quadratic. Linear: 100k costs about 5× 20k (quadratic: 25×); the best of two runs
    // each, against the noise of a loaded machine.
    let scene =
        |n: usize| xml_with(&(0..n).map(|i| format!("<default name=\"v{i}\" value=\"1\"/>\n")).collect::<String>());
    let best = |src: &str| {
        (0..2)
            .map(|_| {
                let t = std::time::Instant::now();
                xml(src, Path::new(".")).unwrap_or_else(|e| panic!("{e}"));
                t.elapsed().as_secs_f64()
            })
            .fold(f64::INFINITY, f64::min)
    };
    let (small, big) = (scene(20_000), scene(100_000));
    let (t20, t100) = (best(&small), best(&big));
    eprintln!("XML load: 20k elements {t20:.3} s, 100k {t100:.3} s");
    assert!(t100 < 12.0 * t20.max(1e-3) && t100 < 3.0, "20k: {t20:.3} s, 100k: {t100:.3} s");
    // and the line numbers are still right at the end
    let e = xml(&(big.replace("</scene>", "<oops/></scene>")), Path::new(".")).err().unwrap();
    assert_eq!(e.line, 6 + 100_000, "{e}");
}

#[test]
fn xml_refuses_what_toml_refuses() {
    // each rendered a black or wrong image without a word (TOML refused the same values)
    refused("cam_origin_huge.xml", 3, "perspective.to_world", &["camera position", "extent"]);
    refused("cam_translate_huge.xml", 3, "perspective.to_world", &["camera position", "extent"]);
    refused("point_light_huge_pos.xml", 6, "point.position", &["point light position", "extent"]);
    refused("cam_scale_zero_y.xml", 3, "perspective.to_world", &["finite and non-zero"]);
    refused("cam_matrix_proj.xml", 3, "perspective.to_world", &["projective"]);
    refused("ref_dup_id.xml", 5, "", &["id `a` is defined twice (first on line 5)"]);
    refused("sphere_scale_zero.xml", 5, "sphere.to_world", &["radius must be positive"]);
    // a 3e38 vertex is the extent error (it was dropped as "degenerate")
    refused("far_vertex_dropped.xml", 5, "ply.filename", &["mesh vertex", "extent", "face 1 of"]);
    refused("cyl_p1_huge.xml", 5, "cylinder.p1", &["mesh vertex", "extent"]);
    refused("rect_scale_1e19.xml", 5, "rectangle.to_world", &["mesh vertex", "extent"]);
}

#[test]
fn xml_messages_say_what_is_wrong() {
    // the shape's own line, and the degenerate triangles named (the warning was lost)
    refused("nan_vertex_empty_scene.xml", 5, "shape.ply", &["empty scene", "skipped 1 degenerate triangle(s)"]);
    refused("width_huge_int.xml", 4, "hdrfilm.width", &["99999999999999999999999", "out of range"]);
    // the light's power overflows: its own line and key, not "light 0" at line 0
    refused("sphere_emit_r_1e12.xml", 5, "area.radiance", &["overflows"]);
    // serde's Rust type names in words
    let e = load_robust("materialraw_leak.toml").err().unwrap().to_string();
    assert!(!e.contains("MaterialRaw") && e.contains("[materials.NAME]"), "{e}");
}

#[test]
fn a_foreign_integrator_and_its_parameters_are_warnings() {
    // a Mitsuba 0.5 sppm integrator: the method is --method, so its parameters are not errors
    let s = xml(
        &xml_with(
            "<integrator type=\"sppm\"><integer name=\"photonCount\" value=\"250000\"/>\
<integer name=\"maxPasses\" value=\"100\"/><float name=\"initialRadius\" value=\"0\"/></integrator>",
        ),
        Path::new("."),
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let w = s.warnings.join("\n");
    for p in ["integrator `sppm` ignored", "photon_count", "max_passes", "initial_radius"] {
        assert!(w.contains(p), "no warning about {p}: {w}");
    }
}
