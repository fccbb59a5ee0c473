//! Every refused scene, in every format (TOML, Mitsuba XML, OBJ and PLY meshes): a malformed scene
//! is rejected with an error that names the file, the line and the key (never a panic, never a
//! hang: parsers are bounded by their input), degenerate mesh input loads with a warning
//! (scenes/README.md, src/scene/file.rs), and the binary prints the error as `FILE:line: key
//! `KEY`: message` with exit status 1.
//!
//! Each TOML case is a valid base scene with one fault; the offending line carries the marker
//! `#<`, and the error's `line` must be that line and its `key` the given key.

mod common;

use common::cli::run;
use common::{ply_scene, root, tmp_dir, xml, PLY_ASCII};
use forecast::scene::{load, load_str, Scene, SceneError};
use std::path::Path;

const BASE: &str = r#"[camera]
position   = [0.0, 1.0, 3.0]
look_at    = [0.0, 1.0, 0.0]
fov        = 40.0
resolution = [32, 32]

[render]
method = "pt"
spp    = 4

[materials.white]
type   = "diffuse"
albedo = [0.5, 0.5, 0.5]

[materials.plastic]
type     = "glossy"
albedo   = [0.3, 0.3, 0.3]
specular = [0.2, 0.2, 0.2]
exponent = 20.0

[[shape]]
type     = "quad"
corner   = [-1.0, 0.0, -1.0]
u        = [2.0, 0.0, 0.0]
v        = [0.0, 0.0, 2.0]
material = "white"

[[shape]]
type     = "sphere"
center   = [0.0, 0.5, 0.0]
radius   = 0.5
material = "plastic"

[[shape]]
type     = "quad"
corner   = [-0.2, 1.9, -0.2]
u        = [0.4, 0.0, 0.0]
v        = [0.0, 0.0, 0.4]
emission = [5.0, 5.0, 5.0]
"#;

/// `BASE` with the first line starting with `from` replaced by `to` (which carries the `#<` marker).
fn with(from: &str, to: &str) -> String {
    let mut done = false;
    let out: Vec<String> = BASE
        .lines()
        .map(|l| {
            if !done && l.starts_with(from) {
                done = true;
                to.to_string()
            } else {
                l.to_string()
            }
        })
        .collect();
    assert!(done, "test bug: no line starts with {from:?}");
    out.join("\n") + "\n"
}

/// `BASE` with `extra` inserted after the first line starting with `after`.
fn insert_after(after: &str, extra: &str) -> String {
    let mut out = String::new();
    let mut done = false;
    for l in BASE.lines() {
        out.push_str(l);
        out.push('\n');
        if !done && l.starts_with(after) {
            out.push_str(extra);
            out.push('\n');
            done = true;
        }
    }
    assert!(done, "test bug: no line starts with {after:?}");
    out
}

fn marked_line(src: &str) -> usize {
    src.lines().position(|l| l.contains("#<")).expect("test bug: no #< marker") + 1
}

/// Loads `src` and checks the error's file, line, key and Display; returns the error, or a
/// description of what was wrong.
fn try_err(name: &str, src: &str, dir: &Path, line: usize, key: &str) -> Result<SceneError, String> {
    let e = match load_str(src, "bad.toml", dir) {
        Ok(_) => return Err(format!("{name}: scene was accepted")),
        Err(e) => e,
    };
    let shown = e.to_string();
    if e.file != "bad.toml" || e.line != line || e.key != key {
        return Err(format!("{name}: want bad.toml:{line} key `{key}`, got: {shown}"));
    }
    if e.message.is_empty() || !shown.starts_with(&format!("bad.toml:{line}: ")) || !shown.contains(key) {
        return Err(format!("{name}: Display must show file:line and key: {shown}"));
    }
    Ok(e)
}

fn expect_err(name: &str, src: &str, dir: &Path, line: usize, key: &str) -> SceneError {
    try_err(name, src, dir, line, key).unwrap_or_else(|m| panic!("{m}"))
}

/// Runs one case; the failures of a group are collected so that one run shows them all.
fn case(fails: &mut Vec<String>, name: &str, src: &str, key: &str) {
    if let Err(m) = try_err(name, src, Path::new("."), marked_line(src), key) {
        fails.push(m);
    }
}

fn finish(fails: Vec<String>) {
    assert!(fails.is_empty(), "{} case(s) failed:\n{}", fails.len(), fails.join("\n"));
}

/// `BASE` plus a mesh shape (shape[3]) reading `file`; the `file =` line is marked.
fn with_mesh(file: &str, extra: &str) -> String {
    format!("{BASE}\n[[shape]]\ntype = \"mesh\"\nfile = \"{file}\" #<\nmaterial = \"white\"\n{extra}")
}

#[test]
fn base_scene_is_valid() {
    let s = load_str(BASE, "base.toml", Path::new(".")).unwrap_or_else(|e| panic!("{e}"));
    assert!(s.warnings.is_empty());
    assert_eq!((s.triangles.len(), s.spheres.len(), s.emitters.len()), (4, 1, 2));
}

/// `[render]`'s keys besides its own are render settings and method options by their flag names
/// (tests/scene_options.rs), which the render checks as it resolves the job (the pipeline knows
/// the flags): an unknown key, another method's option, a value its flag refuses and two options
/// that exclude each other are errors at the key's line, as the loader's are.
#[test]
fn render_options() {
    let resolve = |src: &str| {
        let scene = load_str(src, "bad.toml", Path::new(".")).unwrap_or_else(|e| panic!("loads: {e}"));
        let job = forecast::pipeline::RenderJob {
            method: None,
            spp: None,
            ..common::job(Path::new("bad.toml"), forecast::integrators::Method::Pt, 1, 0, (8, 8), 1, Path::new("out"))
        };
        job.resolve(&scene).err().map(|e| e.to_string())
    };
    let mut fails = Vec::new();
    let mut check = |name: &str, src: &str, key: &str, words: &str| {
        let want = format!("bad.toml:{}: key `{key}`: ", marked_line(src));
        match resolve(src) {
            Some(e) if e.starts_with(&want) && e.contains(words) => {}
            other => fails.push(format!("{name}: want `{want}...{words}...`, got {other:?}")),
        }
    };
    check("unknown", &with("spp", "spp = 4\nsamples = 16 #<"), "render.samples", "unknown key `samples`");
    check(
        "the table's own key spelled as a flag",
        &with("spp", "spp = 4\nmax-depth = 8 #<"),
        "render.max-depth",
        "unknown",
    );
    check(
        "another method's",
        &with("spp", "spp = 4\nclusters = 8 #<"),
        "render.clusters",
        "--clusters belongs to iws-cf/pt-cf, not pt",
    );
    check("out of range", &with("spp", "spp = 4\nemission_split = 0 #<"), "render.emission_split", "invalid value '0'");
    check(
        "not a number",
        &with("spp", "spp = 4\nemission-split = \"many\" #<"),
        "render.emission-split",
        "invalid value 'many'",
    );
    check("bad path classes", &with("spp", "spp = 4\npath_filter = \"X\" #<"), "render.path_filter", "--path-filter");
    let iws_cf = |extra: &str| with("method", &format!("method = \"iws-cf\"\n{extra}"));
    check("over its limit", &iws_cf("split = 2000 #<"), "render.split", "--split");
    check(
        "excluded by another",
        &iws_cf("variant = \"baj08\"\ndirect = \"vpl\" #<"),
        "render.direct",
        "cannot be used with",
    );
    // `auto` picks pt for this scene (no mirror or glass): its options are pt's
    let auto = |extra: &str| with("method", &format!("method = \"auto\"\n{extra}"));
    check("another method's than auto's", &auto("guide_fraction = 0.5 #<"), "render.guide_fraction", "not pt");
    assert!(fails.is_empty(), "{} case(s) failed:\n{}", fails.len(), fails.join("\n"));
    // a value that no flag takes is refused by the loader
    let mut f = Vec::new();
    case(&mut f, "array value", &with("spp", "spp = 4\nclusters = [8] #<"), "render.clusters");
    finish(f);
}

#[test]
fn unknown_keys() {
    let mut f = Vec::new();
    case(
        &mut f,
        "top-level",
        &insert_after("[render]", "").replacen("[camera]", "colour = 3 #<\n[camera]", 1),
        "colour",
    );
    case(&mut f, "camera", &with("fov", "fov = 40.0\nfocus = 2.0 #<"), "camera.focus");
    case(
        &mut f,
        "material",
        &with("albedo   = [0.3", "albedo   = [0.3, 0.3, 0.3]\nroughness = 0.1 #<"),
        "materials.plastic.roughness",
    );
    case(&mut f, "shape", &with("radius", "radius = 0.5\nradious = 0.5 #<"), "shape[1].radious");
    finish(f);
}

#[test]
fn bad_values() {
    let mut f = Vec::new();
    case(&mut f, "nan albedo", &with("albedo = [0.5", "albedo = [nan, 0.5, 0.5] #<"), "materials.white.albedo");
    case(&mut f, "negative albedo", &with("albedo = [0.5", "albedo = [0.5, -0.1, 0.5] #<"), "materials.white.albedo");
    case(&mut f, "albedo > 1", &with("albedo = [0.5", "albedo = [0.5, 1.2, 0.5] #<"), "materials.white.albedo");
    case(
        &mut f,
        "glossy albedo + specular > 1",
        &with("specular", "specular = [0.8, 0.2, 0.2] #<"),
        "materials.plastic.specular",
    );
    case(&mut f, "negative emission", &with("emission", "emission = [5.0, -1.0, 5.0] #<"), "shape[2].emission");
    case(&mut f, "inf emission", &with("emission", "emission = [5.0, inf, 5.0] #<"), "shape[2].emission");
    // above 1e15 a render's variance layer overflows f32 (src/scene/limits.rs)
    case(&mut f, "emission 1e16", &with("emission", "emission = [5.0, 1e16, 5.0] #<"), "shape[2].emission");
    // arrays of the wrong length, longer ones too (serde alone would drop the surplus)
    case(&mut f, "albedo of 4", &with("albedo = [0.5", "albedo = [0.5, 0.5, 0.5, 0.5] #<"), "materials.white.albedo");
    case(&mut f, "albedo of 2", &with("albedo = [0.5", "albedo = [0.5, 0.5] #<"), "materials.white.albedo");
    case(&mut f, "position of 4", &with("position", "position = [0.0, 1.0, 3.0, 1.0] #<"), "camera.position");
    case(&mut f, "resolution of 3", &with("resolution", "resolution = [32, 32, 3] #<"), "camera.resolution");
    case(
        &mut f,
        "corner of 5",
        &with("corner   = [-1.0", "corner = [-1.0, 0.0, -1.0, 0.0, 0.0] #<"),
        "shape[0].corner",
    );
    case(&mut f, "emission of 4", &with("emission", "emission = [5.0, 5.0, 5.0, 5.0] #<"), "shape[2].emission");
    case(
        &mut f,
        "zero-area emissive quad",
        &with("v        = [0.0, 0.0, 0.4]", "v        = [0.8, 0.0, 0.0] #<"),
        "shape[2].v",
    );
    case(&mut f, "negative radius", &with("radius", "radius = -0.5 #<"), "shape[1].radius");
    case(&mut f, "zero radius", &with("radius", "radius = 0.0 #<"), "shape[1].radius");
    case(&mut f, "unknown material", &with("material = \"plastic\"", "material = \"plastik\" #<"), "shape[1].material");
    case(&mut f, "fov 0", &with("fov", "fov = 0.0 #<"), "camera.fov");
    case(&mut f, "fov 180", &with("fov", "fov = 180.0 #<"), "camera.fov");
    case(&mut f, "fov nan", &with("fov", "fov = nan #<"), "camera.fov");
    case(&mut f, "zero resolution", &with("resolution", "resolution = [0, 32] #<"), "camera.resolution");
    case(&mut f, "bad duration", &with("spp", "time = \"10 parsecs\" #<"), "render.time");
    case(&mut f, "zero duration", &with("spp", "time = \"0s\" #<"), "render.time");
    case(&mut f, "unknown method", &with("method", "method = \"bdpt\" #<"), "render.method");
    case(&mut f, "zero spp", &with("spp", "spp = 0 #<"), "render.spp");
    case(&mut f, "spp and time", &with("spp", "spp = 4\ntime = \"1s\" #<"), "render.time");
    case(
        &mut f,
        "glass ior < 1",
        &insert_after("exponent", "\n[materials.glass]\ntype = \"glass\"\nior = 0.5 #<"),
        "materials.glass.ior",
    );
    finish(f);
}

#[test]
fn missing_obj_file() {
    let dir = tmp_dir("bad-obj");
    let src = with_mesh("nothere.obj", "");
    let e = expect_err("missing obj", &src, &dir, marked_line(&src), "shape[3].file");
    assert!(e.message.contains("nothere.obj"), "message should name the OBJ: {e}");
}

#[test]
fn empty_scene_and_no_lights() {
    // No shapes at all: nothing to point at but the document (line 1), key `shape`.
    let src = "[camera]\nposition = [0.0, 0.0, 3.0]\nlook_at = [0.0, 0.0, 0.0]\nfov = 40.0\nresolution = [8, 8]\n";
    expect_err("empty scene", src, Path::new("."), 1, "shape");
    // Shapes but no light with positive power.
    let src = BASE.replace("emission = [5.0, 5.0, 5.0]", "material = \"white\"");
    let e = expect_err("no light", &src, Path::new("."), 1, "shape.emission");
    assert!(e.message.contains("light"));
}

#[test]
fn toml_syntax_error_has_a_line() {
    let src = with("fov", "fov = [40.0 #<");
    let e = load_str(&src, "bad.toml", Path::new(".")).expect_err("rejected");
    // the parser reports the position where it gave up: the marked line or the next one
    assert!(e.line == marked_line(&src) || e.line == marked_line(&src) + 1, "{e}");
    assert!(e.to_string().starts_with("bad.toml:"), "{e}");
}

#[test]
fn load_reports_the_path_and_unreadable_files() {
    let dir = tmp_dir("bad-load");
    let p = dir.join("scene.toml");
    std::fs::write(&p, with("fov", "fov = 0.0 #<")).unwrap();
    let e = load(&p).expect_err("rejected");
    assert_eq!((e.line, e.key.as_str()), (4, "camera.fov"));
    assert!(e.to_string().contains(&p.display().to_string()), "{e}");
    let e = load(&dir.join("missing.toml")).expect_err("a missing file is an error");
    assert!(e.to_string().contains("missing.toml"), "{e}");
}

#[test]
fn degenerate_obj_triangles_are_skipped_with_a_warning() {
    let dir = tmp_dir("bad-degenerate");
    // 4 faces: two good, one zero-area (collinear), one good whose vertex normal is NaN.
    let obj = "\
v 0 0 0
v 1 0 0
v 0 1 0
v 1 1 0
v 2 2 0
v 0 0 1
v 1 0 1
v 0 1 1
vn 0 0 1
vn nan 0 1
f 1//1 2//1 3//1
f 2//1 4//1 3//1
f 1//1 4//1 5//1
f 6//1 7//2 8//1
";
    std::fs::write(dir.join("m.obj"), obj).unwrap();
    let src = with_mesh("m.obj", "normals = \"smooth\"\n");
    let line = marked_line(&src);
    let s = load_str(&src, "deg.toml", &dir).unwrap_or_else(|e| panic!("{e}"));
    // two quads: 4 triangles; mesh: 3 of 4
    assert_eq!(s.triangles.len(), 4 + 3, "the zero-area face must be skipped, the others kept");
    let w =
        s.warnings.iter().find(|w| w.contains("degenerate")).unwrap_or_else(|| panic!("no warning: {:?}", s.warnings));
    assert!(w.contains("skipped 1 degenerate"), "{w}");
    assert!(
        w.starts_with("deg.toml:") && w.contains("shape[3].file") && w.contains("m.obj"),
        "warning must name file, key and OBJ: {w}"
    );
    let w = w.clone();
    // no NaN may survive into the scene: every kept shading normal is finite and unit
    for t in &s.triangles {
        assert!(t.ng.is_finite() && t.area > 0.0);
        if let Some(n) = t.n {
            assert!(
                n.iter().all(|v| v.is_finite() && (v.length() - 1.0).abs() < 1e-4),
                "NaN shading normal kept: {n:?}"
            );
        }
    }
    // and the world built from it returns finite shading normals on the NaN-normal face
    let (o, d) = (forecast::math::Vec3::new(0.2, 0.2, 5.0), forecast::math::Vec3::new(1e-3, 1e-3, -1.0).normalize());
    let brute = common::brute_hits(&s, o, d, f64::INFINITY);
    assert!(brute.first().is_some_and(|b| (b.0 - 4.0).abs() < 1e-4), "brute force: {brute:?}");
    let world = forecast::accel::World::build(s).expect("BVH builds");
    let h = world.intersect(o, d, f32::INFINITY).unwrap_or_else(|| {
        panic!(
            "BVH: no hit; brute force: {brute:?}; triangles: {:?}",
            world.scene.triangles.iter().map(|t| t.p).collect::<Vec<_>>()
        )
    });
    assert!((h.t - 4.0).abs() < 1e-4 && h.ns.is_finite() && h.ng.is_finite(), "{h:?}");
    // last, the line: the warning must point at the `file =` line
    assert!(w.starts_with(&format!("deg.toml:{line}:")), "warning must point at line {line}: {w}");
}

/// A mesh shape (shape[3]) with a one-triangle OBJ in `dir` and the given extra keys.
fn with_small_mesh(dir: &Path, extra: &str) -> String {
    std::fs::write(dir.join("tri.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    format!("{BASE}\n[[shape]]\ntype = \"mesh\"\nfile = \"tri.obj\"\nmaterial = \"white\"\n{extra}")
}

// Issue #9 §2: bounds that overflow f32 made obvhs panic (bvh2_to_cwbvh.rs:369 and :465); they
// are now extent errors (|coordinate| <= MAX_EXTENT) at the offending key.

#[test]
fn reproducer_sphere_radius_1e19() {
    let src = with("radius", "radius = 1e19 #<");
    let e = expect_err("radius 1e19", &src, Path::new("."), marked_line(&src), "shape[1].radius");
    assert!(e.message.contains("extent"), "{e}");
}

#[test]
fn reproducer_sheared_quad_v_3_4e38() {
    let src = with("v        = [0.0, 0.0, 2.0]", "v        = [3.4e38, 0.0, 2.0] #<");
    let e = expect_err("sheared quad", &src, Path::new("."), marked_line(&src), "shape[0].v");
    assert!(e.message.contains("extent"), "{e}");
}

#[test]
fn reproducer_mesh_translate_3_4e38() {
    let dir = tmp_dir("bad-translate");
    let src = with_small_mesh(&dir, "translate = [3.4e38, 0.8, -0.15] #<\n");
    let e = expect_err("mesh translate", &src, &dir, marked_line(&src), "shape[3].translate");
    assert!(e.message.contains("extent"), "{e}");
    // a scale that carries the vertices out names `scale`, and the vertex
    let src = with_small_mesh(&dir, "scale = 1e13 #<\n");
    let e = expect_err("mesh scale", &src, &dir, marked_line(&src), "shape[3].scale");
    assert!(e.message.contains("tri.obj") && e.message.contains("extent"), "{e}");
}

#[test]
fn world_build_refuses_out_of_range_primitives() {
    use forecast::accel::{BuildError, World};
    let s = load_str(BASE, "base.toml", Path::new(".")).unwrap();
    let mut big = s.clone();
    big.spheres[0].radius = 1e19;
    assert!(matches!(World::build(big), Err(BuildError::OutOfRange { prim: 4, .. })));
    let mut inf = s.clone();
    inf.triangles[1].p[2].x = f32::INFINITY;
    let e = World::build(inf).err().expect("an infinite vertex is refused");
    assert!(e.to_string().contains("extent"), "{e}");
    assert!(World::build(s).is_ok());
}

/// Runs `f` on a thread and fails the test if it does not return within 10 s (a blocked read).
fn within_10s<T: Send + 'static>(what: &str, f: impl FnOnce() -> T + Send + 'static) -> T {
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(f());
    });
    rx.recv_timeout(std::time::Duration::from_secs(10)).unwrap_or_else(|_| panic!("{what}: blocked for 10 s"))
}

#[test]
fn fifo_scene_and_mesh_are_refused() {
    let dir = tmp_dir("bad-fifo");
    let fifo = dir.join("pipe");
    let ok = std::process::Command::new("mkfifo").arg(&fifo).status().map(|s| s.success()).unwrap_or(false);
    assert!(ok, "mkfifo failed");
    let p = fifo.clone();
    let e = within_10s("scene FIFO", move || load(&p)).expect_err("a FIFO scene is refused");
    assert!(e.message.contains("not a regular file") && e.to_string().contains("pipe"), "{e}");
    let src = with_mesh("pipe", "");
    let d = dir.clone();
    let line = marked_line(&src);
    let e = within_10s("mesh FIFO", move || load_str(&src, "bad.toml", &d)).expect_err("a FIFO mesh is refused");
    assert_eq!((e.line, e.key.as_str()), (line, "shape[3].file"), "{e}");
    assert!(e.message.contains("not a regular file"), "{e}");
    let e = load(&dir).expect_err("a directory is refused");
    assert!(e.message.contains("directory"), "{e}");
    // the Mitsuba XML loader and the PLY reader refuse them too
    for name in ["pipe.xml", "pipe.ply"] {
        let ok = std::process::Command::new("mkfifo").arg(dir.join(name)).status().is_ok_and(|s| s.success());
        assert!(ok, "mkfifo failed");
    }
    let p = dir.join("pipe.xml");
    let e = within_10s("XML FIFO", move || load(&p)).expect_err("a FIFO XML scene is refused");
    assert!(e.message.contains("not a regular file"), "{e}");
    let (src, d) = (with_mesh("pipe.ply", ""), dir.clone());
    let e = within_10s("PLY FIFO", move || load_str(&src, "bad.toml", &d)).expect_err("a FIFO PLY is refused");
    assert!(e.message.contains("not a regular file"), "{e}");
}

// Issue #9 §5: messages that misled.

#[test]
fn type_errors_name_the_key_on_its_own_line() {
    let mut f = Vec::new();
    // inside the second [[shape]], not at the first [[shape]] header
    case(&mut f, "radius string", &with("radius", "radius = \"big\" #<"), "shape[1].radius");
    case(&mut f, "fov string", &with("fov", "fov = \"wide\" #<"), "camera.fov");
    case(&mut f, "emission element", &with("emission", "emission = [5.0, \"x\", 5.0] #<"), "shape[2].emission");
    case(&mut f, "albedo length", &with("albedo = [0.5", "albedo = [0.5, 0.5] #<"), "materials.white.albedo");
    case(&mut f, "unknown shape type", &with("type     = \"sphere\"", "type = \"cone\" #<"), "shape[1].type");
    case(&mut f, "key of another type", &with("radius", "radius = 0.5\nu = [1.0, 0.0, 0.0] #<"), "shape[1].u");
    case(
        &mut f,
        "unknown material type",
        &with("type   = \"diffuse\"", "type = \"velvet\" #<"),
        "materials.white.type",
    );
    finish(f);
}

#[test]
fn overflowing_light_power_names_the_light() {
    let light = "\n[[light]]\ntype = \"point\"\nposition = [0.0, 1.5, 0.0]\nintensity = [3e38, 3e38, 3e38] #<\n";
    let src = format!("{BASE}{light}");
    let e = expect_err("point 3e38", &src, Path::new("."), marked_line(&src), "light[0].intensity");
    assert!(e.message.contains("at most 1e9") && !e.message.contains("no light"), "{e}");
    // an emissive sphere of radius 1e30 leaves the extent; one of radius 1e12 (the extent's edge)
    // overflows by its power even at the largest radiance, 1e15
    let sphere = |r: &str, e: &str| {
        format!("{BASE}\n[[shape]]\ntype = \"sphere\"\ncenter = [0.0, 0.0, 0.0]\nradius = {r}\nemission = {e}\n")
    };
    let src = sphere("1e30 #<", "[1.0, 1.0, 1.0]");
    expect_err("emissive radius 1e30", &src, Path::new("."), marked_line(&src), "shape[3].radius");
    let src = sphere("1e12", "[1e15, 1e15, 1e15] #<");
    let e = expect_err("emissive power", &src, Path::new("."), marked_line(&src), "shape[3].emission");
    assert!(e.message.contains("overflows"), "{e}");
}

#[test]
fn huge_camera_position_is_an_extent_error() {
    let src = with("position", "position = [3e38, 1.0, 3.0] #<");
    let e = expect_err("camera 3e38", &src, Path::new("."), marked_line(&src), "camera.position");
    assert!(e.message.contains("extent") && !e.message.contains("parallel"), "{e}");
    // a huge but finite `up` is only a direction: it loads
    let src = with("fov", "fov = 40.0\nup = [0.0, 3e38, 0.0]");
    load_str(&src, "up.toml", Path::new(".")).unwrap_or_else(|e| panic!("{e}"));
}

#[test]
fn mesh_transform_errors_name_their_own_key() {
    let dir = tmp_dir("bad-transform");
    let mut f = Vec::new();
    for (extra, key) in [
        ("rotate_y = inf #<", "shape[3].rotate_y"),
        ("scale = -1.0 #<", "shape[3].scale"),
        ("translate = [nan, 0.0, 0.0] #<", "shape[3].translate"),
    ] {
        let src = with_small_mesh(&dir, &format!("{extra}\n"));
        if let Err(m) = try_err(extra, &src, &dir, marked_line(&src), key) {
            f.push(m);
        }
    }
    finish(f);
}

#[test]
fn zero_emission_without_material_is_a_black_shape() {
    let src = format!(
        "{BASE}\n[[shape]]\ntype = \"quad\"\ncorner = [2.0, 0.0, 0.0]\nu = [1.0, 0.0, 0.0]\nv = [0.0, 1.0, 0.0]\nemission = [0.0, 0.0, 0.0]\n"
    );
    let s = load_str(&src, "zero.toml", Path::new(".")).unwrap_or_else(|e| panic!("{e}"));
    let t = s.triangles.last().unwrap();
    assert!(s.materials[t.material as usize].is_black() && t.emitter == forecast::scene::NO_EMITTER);
    assert_eq!(s.emitters.len(), 2, "the zero-emission quad is no emitter");
}

#[test]
fn overflowing_quad_is_an_error_not_dropped() {
    let src = with("u        = [2.0", "u        = [3e38, 0.0, 0.0] #<").replacen(
        "v        = [0.0, 0.0, 2.0]",
        "v        = [0.0, 0.0, 3e38]",
        1,
    );
    expect_err("quad u×v overflow", &src, Path::new("."), marked_line(&src), "shape[0].u");
}

#[test]
fn roi_rect_overflow_is_refused() {
    let mut f = Vec::new();
    for rect in ["[4294967295, 0, 1, 1]", "[0, 4294967295, 1, 1]", "[1, 0, 4294967295, 1]", "[0, 0, 4, 4, 4]"] {
        let src = format!("{BASE}\n[[roi]]\nname = \"r\"\nrect = {rect} #<\n");
        case(&mut f, rect, &src, "roi[0].rect");
    }
    finish(f);
}

/// A `target_box` corner of four values, and a point light above the intensity limit (1e9, so
/// that I/d² at 1 mm stays within the radiance limit): each names its key on its own line.
#[test]
fn target_box_corners_and_point_intensity_have_their_limits() {
    let mut f = Vec::new();
    let src = format!("{BASE}\n[forecast]\ntarget_box = [[0.0, 0.0, 0.0], [1.0, 1.0, 1.0, 1.0]] #<\n");
    case(&mut f, "target_box corner of 4", &src, "forecast.target_box");
    let light = "\n[[light]]\ntype = \"point\"\nposition = [0.0, 1.5, 0.0]\nintensity = [2e9, 1.0, 1.0] #<\n";
    case(&mut f, "intensity 2e9", &format!("{BASE}{light}"), "light[0].intensity");
    finish(f);
    let ok = "\n[[light]]\ntype = \"point\"\nposition = [0.0, 1.5, 0.0]\nintensity = [1e9, 1.0, 1.0]\n";
    load_str(&format!("{BASE}{ok}"), "ok.toml", Path::new(".")).expect("the limit itself loads");
}

/// `[render] method` takes every method: `scene::METHOD_NAMES` is `Method::ALL`'s names, written
/// twice because the scene module lies below the integrators (`pt-cf` was missing from it).
#[test]
fn every_method_is_a_valid_scene_default() {
    let names: Vec<&str> = forecast::integrators::Method::ALL.iter().map(|m| m.name()).collect();
    assert_eq!(names, forecast::scene::METHOD_NAMES);
    for n in names {
        let s = load_str(&with("method", &format!("method = \"{n}\"")), "m.toml", Path::new(".")).expect(n);
        assert_eq!(s.render.method, n);
    }
}

// ---- OBJ and PLY errors name the mesh file and its line; XML names the parameter at fault ----

/// The error of `BASE` plus a mesh shape reading `name` (written with `body`) in a fresh folder:
/// it must point at the `file =` line and name the mesh file.
fn mesh_err(name: &str, body: &str) -> String {
    let dir = tmp_dir(&format!("bad-mesh-{}", name.replace('.', "-")));
    std::fs::write(dir.join(name), body).unwrap();
    let src = with_mesh(name, "");
    let e = expect_err(name, &src, &dir, marked_line(&src), "shape[3].file");
    assert!(e.message.contains(&format!("{name}`")), "must name the mesh file: {e}");
    e.message
}

#[test]
fn obj_errors_name_the_line_and_the_statement() {
    let m = mesh_err("oob.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n# a comment\nf 1 2 9\n");
    assert!(m.contains("line 5") && m.contains("`f`") && m.contains("index 9 out of range"), "{m}");
    let m = mesh_err("zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n");
    assert!(m.contains("line 4") && m.contains("`f`") && m.contains("index 0"), "{m}");
    let m = mesh_err("pos.obj", "v 0 0 0\nv 1 zero 0\nv 0 1 0\nf 1 2 3\n");
    assert!(m.contains("line 2") && m.contains("`v`") && m.contains("position"), "{m}");
}

const PLY_HEAD: &str = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";

#[test]
fn ascii_ply_is_read_line_by_line() {
    // one value too many on vertex line 11 (it was read as the face's count, line 12)
    let m = mesh_err("extra.ply", &format!("{PLY_HEAD}0 0 0\n1 0 0 5\n0 1 0\n3 0 1 2\n"));
    assert!(m.contains("line 11") && m.contains("element `vertex`") && m.contains("`z`"), "{m}");
    // one too few: the line ends before `z`
    let m = mesh_err("short.ply", &format!("{PLY_HEAD}0 0 0\n1 0\n0 1 0\n3 0 1 2\n"));
    assert!(m.contains("line 11") && m.contains("element `vertex`") && m.contains("property `z`"), "{m}");
    // a list longer than its count
    let m = mesh_err("list.ply", &format!("{PLY_HEAD}0 0 0\n1 0 0\n0 1 0\n3 0 1 2 2\n"));
    assert!(m.contains("line 13") && m.contains("element `face`") && m.contains("vertex_indices"), "{m}");
    // trailing content after the last element
    let m = mesh_err("tail.ply", &format!("{PLY_HEAD}0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n\n7 7\n"));
    assert!(m.contains("line 15") && m.contains("7 7"), "{m}");
    // blank lines between rows and a final blank line are fine
    let dir = tmp_dir("ply-blank-lines");
    std::fs::write(dir.join("ok.ply"), format!("{PLY_HEAD}0 0 0\n\n1 0 0\n0 1 0\r\n3 0 1 2\n\n")).unwrap();
    load_str(&with_mesh("ok.ply", ""), "ok.toml", &dir).unwrap_or_else(|e| panic!("{e}"));
}

#[test]
fn array_table_keys_are_named_with_their_table() {
    let mut f = Vec::new();
    let missing_type = with("type     = \"quad\"", "[[shape]] #<").replacen("[[shape]]\n[[shape]]", "[[shape]]", 1);
    case(&mut f, "missing shape type", &missing_type, "shape[0].type");
    case(&mut f, "unknown field in shape[1]", &with("radius", "radius = 0.5\nradious = 1 #<"), "shape[1].radious");
    let light = "[[light]]\ntype = \"point\"\nposition = [0.0, 1.0, 0.0]\nintensity = [1.0, 1.0, 1.0]\nradius = 1.0 #<";
    case(&mut f, "unknown field in light[0]", &format!("{BASE}\n{light}\n"), "light[0].radius");
    case(&mut f, "missing roi name", &format!("{BASE}\n[[roi]] #<\nrect = [0, 0, 4, 4]\n"), "roi[0].name");
    case(
        &mut f,
        "missing camera key",
        &BASE.replacen("[camera]", "[camera] #<", 1).replace("fov        = 40.0\n", ""),
        "camera.fov",
    );
    finish(f);
}

/// A Mitsuba scene whose sensor holds `sensor` and whose top level holds `body`.
fn xml_scene(sensor: &str, body: &str) -> String {
    format!(
        "<scene version=\"3.0.0\">\n<sensor type=\"perspective\">\n<float name=\"fov\" value=\"40\"/>\n\
<transform name=\"to_world\"><lookat origin=\"0, 1, 3\" target=\"0, 1, 0\" up=\"0, 1, 0\"/></transform>\n\
{sensor}\n</sensor>\n<emitter type=\"point\"><point name=\"position\" x=\"0\" y=\"1\" z=\"2\"/></emitter>\n\
<shape type=\"rectangle\">\n{body}\n</shape>\n</scene>\n"
    )
}

fn xml_load(src: &str) -> Result<Scene, SceneError> {
    xml(src, Path::new("."))
}

/// The line (1-based) of the first line of `src` holding `pat`.
fn line_with(src: &str, pat: &str) -> usize {
    src.lines().position(|l| l.contains(pat)).expect("test bug: pattern not found") + 1
}

#[test]
fn phong_energy_error_names_the_reflectances() {
    let bsdf = "<bsdf type=\"phong\">\n<rgb name=\"diffuseReflectance\" value=\"0.7\"/>\n\
<rgb name=\"specularReflectance\" value=\"0.5\"/>\n<float name=\"exponent\" value=\"20\"/>\n</bsdf>";
    let src = xml_scene("", bsdf);
    let Err(e) = xml_load(&src) else { panic!("refused") };
    assert_eq!(
        (e.file.as_str(), e.line, e.key.as_str()),
        ("t.xml", line_with(&src, "specularRefl"), "phong.specular_reflectance"),
        "{e}"
    );
    assert!(e.message.contains("diffuse_reflectance") && !e.key.contains("exponent"), "{e}");
    let src =
        xml_scene("", &bsdf.replace("\n<rgb name=\"specularReflectance\" value=\"0.5\"/>", "").replace("0.7", "0.9"));
    let Err(e) = xml_load(&src) else { panic!("refused: 0.9 + the default 0.2") };
    assert_eq!((e.line, e.key.as_str()), (line_with(&src, "diffuseRefl"), "phong.diffuse_reflectance"), "{e}");
}

#[test]
fn xml_second_film_duplicate_parameters_and_film_sampler_types() {
    let film = |w: u32| format!("<film type=\"hdrfilm\"><integer name=\"width\" value=\"{w}\"/></film>");
    let src = xml_scene(&format!("{}\n{}", film(8), film(16)), "");
    let Err(e) = xml_load(&src) else { panic!("a second film is refused") };
    assert_eq!((e.file.as_str(), e.line, e.key.as_str()), ("t.xml", 5 + 1, "perspective.film"), "{e}");
    assert!(e.message.contains("line 5"), "must name the first film's line: {e}");
    // a repeated parameter: which value is used, which line is ignored
    let src = xml_scene("<float name=\"fov\" value=\"60\"/>", "");
    let s = xml_load(&src).unwrap_or_else(|e| panic!("{e}"));
    let w = s.warnings.iter().find(|w| w.contains("`fov`")).unwrap_or_else(|| panic!("{:?}", s.warnings));
    assert!(w.starts_with("t.xml:5:") && w.contains("line 3 is used") && w.contains("twice"), "{w}");
    // specfilm changes the output: refused; stratified only changes the noise: a warning
    let src = xml_scene("<film type=\"specfilm\"/>", "");
    let Err(e) = xml_load(&src) else { panic!("specfilm is refused") };
    assert_eq!((e.line, e.key.as_str()), (5, "film.specfilm"), "{e}");
    let src = xml_scene("<sampler type=\"stratified\"><integer name=\"sample_count\" value=\"4\"/></sampler>", "");
    let s = xml_load(&src).unwrap_or_else(|e| panic!("{e}"));
    assert!(s.warnings.iter().any(|w| w.starts_with("t.xml:5:") && w.contains("stratified")), "{:?}", s.warnings);
}

// ---- refusals found by running the binary (they lived in tests/input_guards.rs and
// tests/cli_errors.rs) ----

/// `src` is refused at its `#<` line with `key`, and its message holds every one of `words`.
fn case_says(fails: &mut Vec<String>, name: &str, src: &str, key: &str, words: &[&str]) {
    match try_err(name, src, Path::new("."), marked_line(src), key) {
        Err(m) => fails.push(m),
        Ok(e) => {
            fails.extend(words.iter().filter(|w| !e.message.contains(*w)).map(|w| format!("{name}: `{w}` not in {e}")))
        }
    }
}

/// The binary prints a scene's error as `FILE:line: key `KEY`: message` and exits 1, and the scene
/// format applies the command line's limits in the same words (`render.spp = 0` as `--spp 0`).
#[test]
fn the_binary_names_the_file_line_and_key_in_the_command_lines_words() {
    let d = tmp_dir("bad-scene-spp");
    let (file, out) = (d.join("zero.toml"), d.join("r").display().to_string());
    let src = with("spp", "spp    = 0 #<");
    std::fs::write(&file, &src).unwrap();
    let f = file.display().to_string();
    let (code, _, err) = run(&["render", &f, "--resolution", "8x8", "--threads", "2", "--quiet", "--out", &out]);
    assert_eq!(code, 1, "{err}");
    let at = format!("{f}:{}: key `render.spp`: ", marked_line(&src));
    assert!(err.contains(&at) && err.contains("spp must be at least 1 (got 0)"), "{err}");
    let _ = std::fs::remove_dir_all(d);
}

/// An emitter's `material` must exist too (it was ignored when `emission` was given).
#[test]
fn an_emitters_unknown_material_is_refused() {
    let mut f = Vec::new();
    let src = format!("{BASE}material = \"x\" #<\n");
    case_says(&mut f, "emitter material", &src, "shape[2].material", &["unknown material `x`"]);
    finish(f);
}

/// Two ROIs with one name, or a ROI named `full`, would write over each other's `compare` files.
#[test]
fn duplicate_and_reserved_roi_names_are_refused() {
    let roi = |n: &str, mark: &str| format!("\n[[roi]]\nname = \"{n}\"{mark}\nrect = [0, 0, 4, 4]\n");
    let first = format!("`roi[0].name` (line {})", BASE.lines().count() + 3);
    let mut f = Vec::new();
    let two = format!("{BASE}{}{}", roi("a", ""), roi("a", " #<"));
    case_says(&mut f, "roi twice", &two, "roi[1].name", &["duplicate roi name `a`", &first]);
    let alike = format!("{BASE}{}{}", roi("a b", ""), roi("a_b", " #<"));
    case_says(&mut f, "roi alike", &alike, "roi[1].name", &["duplicate roi name `a_b`", "`a b`"]);
    let full = format!("{BASE}{}", roi("full", " #<"));
    case_says(&mut f, "roi full", &full, "roi[0].name", &["`full` is reserved"]);
    finish(f);
}

/// toml's bare "duplicate key" names the table or key and its first definition.
#[test]
fn a_table_or_key_defined_twice_is_named() {
    let mut f = Vec::new();
    let camera = format!("{BASE}\n[camera] #<\nposition = [0.0, 1.0, 3.0]\nfov = 40.0\n");
    case_says(&mut f, "camera twice", &camera, "camera", &["the table `camera` is defined twice (first at line 1)"]);
    let white = format!("{BASE}\n[materials.white] #<\ntype = \"diffuse\"\nalbedo = [0.5, 0.5, 0.5]\n");
    let words = [format!(
        "the table `materials.white` is defined twice (first at line {})",
        line_with(BASE, "[materials.white]")
    )];
    case_says(&mut f, "material twice", &white, "materials.white", &[&words[0]]);
    let key = format!("{BASE}emission = [2.0, 2.0, 2.0] #<\n");
    let words = [format!("`shape[2].emission` is given twice (first at line {})", line_with(BASE, "emission"))];
    case_says(&mut f, "key twice", &key, "shape[2].emission", &[&words[0]]);
    finish(f);
}

/// A tiny light quad is too small (area and limit given), not "zero-area".
#[test]
fn a_tiny_quad_is_too_small_not_zero_area() {
    let mut f = Vec::new();
    let tiny = format!(
        "{BASE}\n[[shape]]\ntype = \"quad\"\ncorner = [0.0, 1.0, 0.0]\nu = [1e-7, 0.0, 0.0]\nv = [0.0, 0.0, 1e-7] #<\nemission = [1.0, 1.0, 1.0]\n"
    );
    case_says(&mut f, "tiny quad", &tiny, "shape[3].v", &["quad too small: area |u × v| = 1e-14", "limit 1e-12"]);
    finish(f);
}

// ---- Mitsuba XML and PLY: clear errors with file and line, never a panic (they lived in
// tests/mitsuba.rs) ----

/// Each malformed input: (xml, files to write, expected line, words the message must contain).
#[test]
fn malformed_inputs_are_clear_errors_with_file_and_line() {
    let dir = tmp_dir("mitsuba-bad");
    std::fs::write(dir.join("quad.ply"), PLY_ASCII).unwrap();
    std::fs::write(dir.join("bad_index.ply"), PLY_ASCII.replace("3 0 3 2", "3 0 3 9")).unwrap();
    let mut bin = forecast::scene::ply::write_binary(&forecast::scene::ply::parse(PLY_ASCII.as_bytes()).unwrap());
    bin.truncate(bin.len() - 5);
    std::fs::write(dir.join("short.ply"), bin).unwrap();
    // a texture of mean 2: out of a reflectance's range, named with its image (issue #63)
    let bright = forecast::image_io::Image::from_fn(2, 2, |_, _| [2.0; 3]);
    forecast::image_io::write_exr(&dir.join("bright.exr"), &bright).unwrap();
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
        (ply_scene("<shape type=\"ply\"><string name=\"filename\" value=\"quad.ply\"/>\n<bsdf type=\"principled\"/></shape>"), 4, vec!["principled", "not supported"]),
        (ply_scene("<shape type=\"ply\"><string name=\"filename\" value=\"quad.ply\"/>\n<bsdf type=\"roughplastic\">\n<float name=\"alpha_u\" value=\"0.1\"/><float name=\"alpha_v\" value=\"0.2\"/></bsdf></shape>"), 5, vec!["alpha_u", "anisotropic"]),
        (ply_scene("<shape type=\"ply\"><string name=\"filename\" value=\"quad.ply\"/>\n<bsdf type=\"roughplastic\">\n<float name=\"int_ior\" value=\"1.2\"/><float name=\"ext_ior\" value=\"1.2\"/></bsdf></shape>"), 5, vec!["int_ior", "differ"]),
        (ply_scene("<shape type=\"ply\"><string name=\"filename\" value=\"quad.ply\"/>\n<bsdf type=\"diffuse\">\n<texture name=\"reflectance\" type=\"bitmap\"/></bsdf></shape>"), 5, vec!["bitmap.filename", "missing `filename`"]),
        (ply_scene("<shape type=\"ply\"><string name=\"filename\" value=\"quad.ply\"/>\n<bsdf type=\"diffuse\">\n<texture name=\"reflectance\" type=\"bitmap\"><string name=\"filename\" value=\"missing.png\"/></texture></bsdf></shape>"), 5, vec!["missing.png", "filename"]),
        (ply_scene("<shape type=\"ply\"><string name=\"filename\" value=\"quad.ply\"/>\n<bsdf type=\"diffuse\">\n<texture name=\"reflectance\" type=\"bitmap\"><string name=\"filename\" value=\"bright.exr\"/></texture></bsdf></shape>"), 5, vec!["reflectance must be in [0, 1]", "mean 2", "bright.exr"]),
        (ply_scene("<shape type=\"ply\"><string name=\"filename\" value=\"quad.ply\"/>\n<bsdf type=\"roughconductor\">\n<texture name=\"specular_reflectance\" type=\"checkerboard\"><texture name=\"color0\" type=\"bitmap\"><string name=\"filename\" value=\"bright.exr\"/></texture></texture></bsdf></shape>"), 5, vec!["specular_reflectance", "mean 1.1", "bright.exr"]),
        (ply_scene("\n<emitter type=\"projector\"/>"), 4, vec!["projector", "not supported"]),
        (ply_scene("\n<emitter type=\"envmap\"/>"), 4, vec!["envmap", "missing `filename`"]),
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

// ---- issue 61: texture coordinates of OBJ and PLY meshes (UV indices, partial UVs, meshes without) ----

/// The texture coordinates of the triangles of the XML scene around the mesh `file` (written
/// with `body` in a fresh folder), in the file's face order; Err(the loader's message).
fn mesh_uvs(file: &str, body: &str) -> Result<Vec<Option<[forecast::math::Vec2; 3]>>, String> {
    let dir = tmp_dir(&format!("uv-{}", file.replace('.', "-")));
    std::fs::write(dir.join(file), body).unwrap();
    let ty = if file.ends_with(".ply") { "ply" } else { "obj" };
    let src = ply_scene(&format!("<shape type=\"{ty}\"><string name=\"filename\" value=\"{file}\"/></shape>"));
    let scene = xml(&src, &dir).map_err(|e| {
        assert!(e.message.contains(&format!("{file}`")) && e.key == format!("{ty}.filename"), "{e}");
        e.to_string()
    })?;
    Ok(scene.triangles.iter().map(|t| t.uv).collect())
}

const TRI3: &str = "v 0 0 0\nv 1 0 0\nv 0 0 1\n";

#[test]
fn obj_uv_indices_out_of_range_are_errors_naming_the_line() {
    use forecast::math::Vec2;
    let err = |name: &str, body: &str| mesh_uvs(name, body).err().unwrap_or_else(|| panic!("{name}: accepted"));
    // `vt` 7 of 2 (tobj and Mitsuba refuse it; the line was not named)
    let m = err("vt7.obj", &format!("{TRI3}vt 0 0\nvt 1 0\nf 1/1 2/2 3/7\n"));
    assert!(m.contains("line 6") && m.contains("`f`") && m.contains("vt index 7 out of range (2 `vt`"), "{m}");
    // the same where the file has no `vt` at all: tobj ignored the index (the mesh loaded without UVs)
    let m = err("novt.obj", &format!("{TRI3}f 1/7 2/7 3/7\n"));
    assert!(m.contains("line 4") && m.contains("vt index 7 out of range (0 `vt`"), "{m}");
    // a `vt` the face names before it is defined
    let m = err("later.obj", &format!("{TRI3}f 1/1 2/1 3/1\nvt 0 0\n"));
    assert!(m.contains("line 4") && m.contains("vt index 1 out of range"), "{m}");
    // relative (negative) indices are refused as Mitsuba 3 refuses them (issue #63), in range
    // or not, in any of the three places
    let m = err("rel.obj", &format!("{TRI3}vt 0 0\nvt 1 0\nf 1/-1 2/-2 3/-3\n"));
    assert!(m.contains("line 6") && m.contains("vt index -1 is relative (negative)"), "{m}");
    let m = err("relv.obj", &format!("{TRI3}vn 0 1 0\nf -3 -2 -1\n"));
    assert!(m.contains("line 5") && m.contains("`f`") && m.contains("v index -3 is relative"), "{m}");
    let m = err("relvn.obj", &format!("{TRI3}vn 0 1 0\nf 1//1 2//1 3//-1\n"));
    assert!(m.contains("line 5") && m.contains("vn index -1 is relative"), "{m}");
    // zero, not a number, four parts, no position
    let m = err("zero.obj", &format!("{TRI3}vt 0 0\nf 1/0 2/1 3/1\n"));
    assert!(m.contains("line 5") && m.contains("vt index 0 (OBJ indices start at 1)"), "{m}");
    let m = err("nan-index.obj", &format!("{TRI3}vt 0 0\nf 1/x 2/1 3/1\n"));
    assert!(m.contains("line 5") && m.contains("`x` is not an index"), "{m}");
    let m = err("parts.obj", &format!("{TRI3}vt 0 0\nf 1/1/1/1 2/1 3/1\n"));
    assert!(m.contains("line 5") && m.contains("more than three"), "{m}");
    let m = err("nopos.obj", &format!("{TRI3}vt 0 0\nf /1 2/1 3/1\n"));
    assert!(m.contains("line 5") && m.contains("no position index"), "{m}");
    // a `vt` needs two numbers, both finite (tobj refused `vt 0.5` without naming the line)
    let m = err("vt1.obj", &format!("{TRI3}vt 0.5\nf 1/1 2/1 3/1\n"));
    assert!(m.contains("line 4") && m.contains("`vt`") && m.contains("needs 2 numbers"), "{m}");
    let m = err("vtnan.obj", &format!("{TRI3}vt 0 0\nvt nan 1\nf 1/1 2/2 3/1\n"));
    assert!(m.contains("line 5") && m.contains("not finite"), "{m}");
    let m = err("vtinf.obj", &format!("{TRI3}vt 1e39 0\nf 1/1 2/1 3/1\n"));
    assert!(m.contains("line 4") && m.contains("not finite"), "{m}");
    // absolute indices read their `vt` (v flipped as Mitsuba's OBJ)
    let uvs = mesh_uvs("absok.obj", &format!("{TRI3}vt 0.1 0.2\nvt 0.3 0.4\nvt 0.5 0.6\nf 1/1 2/2 3/3\n")).unwrap();
    let want = [Vec2::new(0.1, 0.8), Vec2::new(0.3, 0.6), Vec2::new(0.5, 0.4)];
    assert_eq!(uvs.len(), 1);
    let got = uvs[0].expect("UVs");
    assert!(got.iter().zip(want).all(|(a, b)| (*a - b).abs().max_element() < 1e-6), "{got:?}");
    // and through the TOML loader: the mesh's `file =` line and key
    let m = mesh_err("vt9.obj", &format!("{TRI3}vt 0 0\nf 1/1 2/9 3/1\n"));
    assert!(m.contains("line 5") && m.contains("vt index 9 out of range"), "{m}");
}

#[test]
fn obj_corners_without_vt_read_zero_uvs_as_mitsuba() {
    use forecast::math::Vec2;
    let near = |a: [Vec2; 3], b: [Vec2; 3]| a.iter().zip(b).all(|(a, b)| (*a - b).abs().max_element() < 1e-6);
    // one face with UVs on two corners (they were dropped for the whole mesh): the bare corner
    // reads (0, 0) after the flip, as Mitsuba 3 gives it (3.9.1 left it uninitialised)
    let uvs = mesh_uvs("partial.obj", &format!("{TRI3}vt 0.25 0.5\nvt 0.75 0.25\nf 1/1 2/2 3\n")).unwrap();
    let got = uvs[0].expect("UVs");
    assert!(near(got, [Vec2::new(0.25, 0.5), Vec2::new(0.75, 0.75), Vec2::ZERO]), "{got:?}");
    // objects with and without `vt` in one file (and `v//vn` corners): the bare ones read (0, 0),
    // the others keep theirs
    let body = "o a\nv 0 0 0\nv 1 0 0\nv 0 0 1\nvn 0 1 0\nvt 0.5 0.5\nvt 1 0.5\nvt 0.5 1\nf 1/1/1 2/2/1 3/3/1\n\
o b\nv 1 0 1\nf 2//1 4//1 3//1\n";
    let uvs = mesh_uvs("objects.obj", body).unwrap();
    assert_eq!(uvs.len(), 2, "{uvs:?}");
    let (a, b) = (uvs[0].expect("UVs"), uvs[1].expect("UVs"));
    assert!(near(a, [Vec2::new(0.5, 0.5), Vec2::new(1.0, 0.5), Vec2::new(0.5, 0.0)]), "{a:?}");
    assert!(near(b, [Vec2::ZERO; 3]), "{b:?}");
    // `vt` that no face names: no UVs (Mitsuba 3.9.1 read uninitialised ones; later versions none)
    assert_eq!(mesh_uvs("unused.obj", &format!("{TRI3}vt 0.5 0.5\nf 1 2 3\n")).unwrap(), vec![None]);
    // a comment after a statement is a comment, as in Mitsuba (tobj read it as an index)
    let uvs = mesh_uvs("comment.obj", &format!("{TRI3}vt 0 0 # origin\nf 1/1 2/1 3/1 # one face\n")).unwrap();
    assert!(near(uvs[0].expect("UVs"), [Vec2::new(0.0, 1.0); 3]), "{uvs:?}");
}

#[test]
fn ply_uv_errors_name_the_line() {
    const HEAD: &str =
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n";
    // per-corner UVs as a face list (MeshLab's `texcoord`): Mitsuba refuses it ("i0 already
    // exists"); it was read and dropped without a word
    let body = format!(
        "{HEAD}element face 1\nproperty list uchar int vertex_indices\nproperty list uchar float texcoord\nend_header\n\
0 0 0\n1 0 0\n0 0 1\n3 0 1 2 6 0 0 1 0 0 1\n"
    );
    let m = mesh_uvs("wedge.ply", &body).expect_err("accepted");
    assert!(m.contains("line 9") && m.contains("`texcoord`") && m.contains("per vertex"), "{m}");
    // a texture coordinate that is not finite: its line and vertex
    let body = format!(
        "{HEAD}property float u\nproperty float v\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\
0 0 0 0 0\n1 0 0 inf 0\n0 0 1 0 1\n3 0 1 2\n"
    );
    let m = mesh_uvs("inf.ply", &body).expect_err("accepted");
    assert!(m.contains("line 13: vertex 2: texture coordinates") && m.contains("not finite"), "{m}");
    // `u` without `v`: no UVs, as Mitsuba reads it
    let body = format!(
        "{HEAD}property float u\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\
0 0 0 0.5\n1 0 0 0.5\n0 0 1 0.5\n3 0 1 2\n"
    );
    assert_eq!(mesh_uvs("u-only.ply", &body).unwrap(), vec![None]);
}

/// One of the tables of `scripts/mitsuba-no-uv-values.py`.
#[derive(serde::Deserialize)]
struct NoUvTable {
    rows: Vec<NoUvRow>,
}

#[derive(serde::Deserialize)]
struct NoUvRow {
    o: [f32; 3],
    d: [f32; 3],
    t: f32,
    reflectance: [f32; 3],
    wi: Vec<[f32; 3]>,
    eval: Vec<[f32; 3]>,
}

#[test]
fn a_textured_or_normal_mapped_mesh_without_uvs_shades_as_mitsuba() {
    // Mitsuba 3 renders a bitmap-textured BSDF, alone or under a `normalmap`, on an OBJ without
    // `vt` and a PLY without u/v: uv = the hit's barycentrics (b1, b2), dp/du = p1 - p0. At 32
    // rays per scene forecast's textured reflectance and its BSDF value (cosine, tilt and
    // shadowing term included) must be Mitsuba's: within 2e-4 relative + 2e-5 (float32 hit
    // points that differ in the last bits move a bilinear lookup by about 1e-5)
    use forecast::bsdf::{eval, Material, Mode};
    use forecast::math::Vec3;
    let dir = root().join("tests/data/no-uv");
    let worst = std::cell::Cell::new(0.0f32);
    let close = |a: Vec3, b: Vec3| {
        let e = (a - b).abs().max_element();
        worst.set(worst.get().max(e / (b.abs().max_element() + 0.1)));
        e <= 2e-4 * b.abs().max_element() + 2e-5
    };
    for case in ["obj-textured", "obj-normalmap", "ply-normalmap"] {
        let table: NoUvTable =
            serde_json::from_str(&std::fs::read_to_string(dir.join(format!("{case}.json"))).unwrap()).unwrap();
        let scene = load(&dir.join(format!("{case}.xml"))).unwrap_or_else(|e| panic!("{case}: {e}"));
        assert!(scene.triangles.iter().all(|t| t.uv.is_none()), "{case}: the mesh has no UVs");
        let world = forecast::accel::World::build(scene).unwrap();
        let textured = case == "obj-textured";
        // the rows see many texels (a wrong uv would show): the reflectance spans more than 0.2
        let red = table.rows.iter().map(|r| r.reflectance[0]);
        assert!(red.clone().fold(0.0, f32::max) - red.fold(1.0, f32::min) > 0.2, "{case}: one texel");
        worst.set(0.0);
        for (k, r) in table.rows.iter().enumerate() {
            let (o, d) = (Vec3::from_array(r.o), Vec3::from_array(r.d));
            let hit = world.intersect(o, d, f32::INFINITY).unwrap_or_else(|| panic!("{case} row {k}: no hit"));
            assert!((hit.t - r.t).abs() <= 1e-4 * r.t, "{case} row {k}: t {} vs Mitsuba's {}", hit.t, r.t);
            let (m, sp) = world.shade(&hit, -d);
            let Material::Diffuse { albedo } = m else { panic!("{case} row {k}: {m:?}") };
            let want = Vec3::from_array(r.reflectance);
            assert!(close(albedo, want), "{case} row {k}: reflectance {albedo} vs Mitsuba's {want}");
            assert_eq!(sp.ns == sp.n0, textured, "{case} row {k}: the normal map tilts the normal");
            for (wi, want) in r.wi.iter().zip(&r.eval) {
                let (wi, want) = (Vec3::from_array(*wi), Vec3::from_array(*want));
                let got = eval(&m, &sp, -d, wi, Mode::Radiance) * wi.dot(sp.ns).abs();
                assert!(close(got, want), "{case} row {k} wi {wi}: f cos = {got} vs Mitsuba's {want}");
            }
        }
        eprintln!(
            "{case}: {} rows, worst |forecast - Mitsuba| / (|Mitsuba| + 0.1) = {:.2e}",
            table.rows.len(),
            worst.get()
        );
    }
}

// ---- issue 61: the TOML format's Mitsuba materials and textures (tests/toml_materials.rs) ----

/// `BASE` with the material table `wood` (its lines `body`, one marked `#<`) before `white`.
fn with_wood(body: &str) -> String {
    with("[materials.white]", &format!("[materials.wood]\n{body}\n\n[materials.white]"))
}

#[test]
fn toml_material_and_texture_errors_name_the_file_line_and_key() {
    let mut f = Vec::new();
    let png = "filename = \"../mitsuba-plugins/tex16.png\"";
    // unknown types: of a material, of a texture (inline and under its own header)
    case(&mut f, "unknown material type", &with_wood("type = \"roughplastik\" #<"), "materials.wood.type");
    let inline = |v: &str| with_wood(&format!("type = \"diffuse\"\nalbedo = {v} #<"));
    case(&mut f, "unknown texture type", &inline("{ type = \"marble\" }"), "materials.wood.albedo.type");
    let table = |lines: &str| with_wood(&format!("type = \"diffuse\"\n\n[materials.wood.albedo]\n{lines}"));
    case(&mut f, "texture table type", &table("type = \"marble\" #<"), "materials.wood.albedo.type");
    // unknown keys: in an inline texture, in its to_uv, in a texture table, a key of another type
    case(
        &mut f,
        "inline texture key",
        &inline("{ type = \"bitmap\", filenme = \"a.png\" }"),
        "materials.wood.albedo.filenme",
    );
    let uv = "{ type = \"checkerboard\", to_uv = { scael = [2, 2] } }";
    case(&mut f, "to_uv key", &inline(uv), "materials.wood.albedo.to_uv.scael");
    case(
        &mut f,
        "table key",
        &table(&format!("type = \"bitmap\"\n{png}\nfilenme = \"a\" #<")),
        "materials.wood.albedo.filenme",
    );
    case(&mut f, "key of another type", &with_wood("type = \"plastic\"\nalpha = 0.1 #<"), "materials.wood.alpha");
    case(
        &mut f,
        "bitmap key on a checkerboard",
        &inline("{ type = \"checkerboard\", raw = true }"),
        "materials.wood.albedo.raw",
    );
    case(
        &mut f,
        "twosided on a dielectric",
        &with_wood("type = \"roughdielectric\"\ntwosided = true #<"),
        "materials.wood.twosided",
    );
    case(&mut f, "missing texture type", &inline("{ filename = \"a.png\" }"), "materials.wood.albedo.type");
    case(
        &mut f,
        "both alphas",
        &with_wood("type = \"roughconductor\"\nalpha_u = 0.1\nalpha = 0.2 #<"),
        "materials.wood.alpha",
    );
    // values of the wrong type
    case(
        &mut f,
        "raw not a boolean",
        &inline(&format!("{{ type = \"bitmap\", {png}, raw = 1 }}")),
        "materials.wood.albedo.raw",
    );
    case(
        &mut f,
        "twosided a string",
        &with_wood("type = \"plastic\"\ntwosided = \"no\" #<"),
        "materials.wood.twosided",
    );
    case(
        &mut f,
        "colour a string",
        &with_wood("type = \"plastic\"\ndiffuse_reflectance = \"red\" #<"),
        "materials.wood.diffuse_reflectance",
    );
    case(
        &mut f,
        "colour of 2",
        &with_wood("type = \"plastic\"\nspecular_reflectance = [1, 1] #<"),
        "materials.wood.specular_reflectance",
    );
    case(&mut f, "ior an array", &with_wood("type = \"plastic\"\nint_ior = [1.5] #<"), "materials.wood.int_ior");
    case(
        &mut f,
        "alpha a colour",
        &with_wood("type = \"roughconductor\"\nalpha = [0.1, 0.1, 0.1] #<"),
        "materials.wood.alpha",
    );
    case(
        &mut f,
        "textured glossy",
        &with("albedo   = [0.3", "albedo = { type = \"checkerboard\" } #<"),
        "materials.plastic.albedo",
    );
    case(
        &mut f,
        "scale of 3",
        &inline("{ type = \"checkerboard\", to_uv = { scale = [1, 2, 3] } }"),
        "materials.wood.albedo.to_uv.scale",
    );
    // values out of range, unknown names
    case(
        &mut f,
        "filter_type",
        &table(&format!("type = \"bitmap\"\n{png}\nfilter_type = \"cubic\" #<")),
        "materials.wood.albedo.filter_type",
    );
    case(
        &mut f,
        "reflectance > 1",
        &with_wood("type = \"plastic\"\ndiffuse_reflectance = [0.5, 1.5, 0.5] #<"),
        "materials.wood.diffuse_reflectance",
    );
    case(
        &mut f,
        "conductor preset",
        &with_wood("type = \"conductor\"\nmaterial = \"Gold\" #<"),
        "materials.wood.material",
    );
    case(
        &mut f,
        "ior preset",
        &with_wood("type = \"thindielectric\"\nint_ior = \"glass\" #<"),
        "materials.wood.int_ior",
    );
    case(
        &mut f,
        "distribution",
        &with_wood("type = \"roughplastic\"\ndistribution = \"phong\" #<"),
        "materials.wood.distribution",
    );
    case(
        &mut f,
        "nan colour",
        &inline("{ type = \"checkerboard\", color1 = [nan, 0, 0] }"),
        "materials.wood.albedo.color1",
    );
    finish(f);
}

#[test]
fn a_missing_image_is_named_with_its_key() {
    let dir = root().join("tests/scenes/toml-materials");
    for (body, key) in [
        ("type = \"diffuse\"\nalbedo = { type = \"bitmap\", filename = \"no-such.png\" } #<", "materials.wood.albedo.filename"),
        (
            "type = \"plastic\"\n\n[materials.wood.diffuse_reflectance]\ntype = \"checkerboard\"\ncolor0 = { type = \"bitmap\", filename = \"no-such.png\" } #<",
            "materials.wood.diffuse_reflectance.color0.filename",
        ),
        ("type = \"plastic\"\nnormalmap = \"no-such.png\" #<", "materials.wood.normalmap"),
    ] {
        let src = with_wood(body);
        let e = expect_err(key, &src, &dir, marked_line(&src), key);
        assert!(e.message.contains("no-such.png"), "{e}");
    }
    // a file that is not an image
    let src = with_wood("type = \"diffuse\"\nalbedo = { type = \"bitmap\", filename = \"every-material.toml\" } #<");
    let e = expect_err("not an image", &src, &dir, marked_line(&src), "materials.wood.albedo.filename");
    assert!(e.message.contains("every-material.toml"), "{e}");
}

/// An error whose line is unknown (0) names its file without a line, never `file:0:`.
#[test]
fn an_unknown_line_is_left_out() {
    let e = |line| SceneError { file: "s.xml".into(), line, key: "k".into(), message: "m".into() }.to_string();
    assert_eq!(e(0), "s.xml: key `k`: m");
    assert_eq!(e(7), "s.xml:7: key `k`: m");
}

/// The bitmaps of an XML scene are decoded in parallel before it is read (`TextureCache::
/// predecode`); the error is still the first bad texture's in file order, with its line and key,
/// whichever decoding ends first, on one thread or four; the good ones load as before.
#[test]
fn parallel_texture_decoding_keeps_the_first_error_in_file_order() {
    let dir = tmp_dir("mitsuba-bad-textures");
    let good = forecast::image_io::Image::from_fn(4, 4, |x, y| [0.1 * x as f32, 0.2, 0.1 * y as f32]);
    forecast::image_io::write_exr(&dir.join("good.exr"), &good).unwrap();
    std::fs::write(dir.join("torn-a.png"), b"\x89PNG\r\n\x1a\nnot a png").unwrap();
    std::fs::write(dir.join("torn-b.exr"), b"v/1\x01 not an exr").unwrap();
    let shape = |f: &str| {
        format!(
            "<shape type=\"rectangle\"><bsdf type=\"diffuse\">\n<texture name=\"reflectance\" type=\"bitmap\">\
             <string name=\"filename\" value=\"{f}\"/></texture></bsdf></shape>"
        )
    };
    let scene = |files: &[&str]| {
        let body: Vec<String> = files.iter().map(|f| shape(f)).collect();
        ply_scene(&body.join("\n"))
    };
    for threads in [1, 4] {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        for (files, bad) in [
            (vec!["good.exr", "torn-a.png", "torn-b.exr"], "torn-a.png"),
            (vec!["good.exr", "torn-b.exr", "good.exr", "torn-a.png"], "torn-b.exr"),
        ] {
            let src = scene(&files);
            let Err(e) = pool.install(|| xml(&src, &dir)) else { panic!("accepted {files:?}") };
            let line = line_with(&src, bad);
            assert!(e.line == line && e.key.ends_with("filename"), "{threads} threads, want line {line}: {e}");
            assert!(e.to_string().contains(bad), "{threads} threads: {e}");
        }
        pool.install(|| xml(&scene(&["good.exr", "good.exr"]), &dir)).unwrap_or_else(|e| panic!("{e}"));
    }
}
