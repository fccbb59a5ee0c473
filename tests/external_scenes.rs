//! The scenes of the caustics literature in `scenes/external/` (issue #62): the SMS repository's
//! `sms-sphere-smooth`, `sms-sphere`, `sms-plane` load from `scene.xml` (Mitsuba 3) and from
//! `original.xml` (Mitsuba 2, as published: its absent `Tiles71` texture supplied by a copy of
//! `Tiles27` in a temporary folder), and both forms are the same scene; `sms-ring`'s `ring.xml`
//! (verbatim) loads; `sms-pool` (lit by an `envmap`) loads from both files once the textures this
//! repository leaves out are stood in for, and its committed folder names the first one missing.
//! Each scene that loads renders with `pt` at 32 pixels across, 4 spp: finite and not black.

mod common;
use common::{render_passes, root, scene_fingerprint as fingerprint, tmp_dir};
use forecast::accel::World;
use forecast::integrators::{Method, MethodArgs};
use forecast::scene::Scene;
use std::path::{Path, PathBuf};

const LOADING: [&str; 3] = ["sms-sphere-smooth", "sms-sphere", "sms-plane"];

fn dir(name: &str) -> PathBuf {
    root().join("scenes/external").join(name)
}

/// The folder copied to a temporary one with `Tiles27` at `original.xml`'s absent `Tiles71` path.
fn with_tiles71(name: &str) -> PathBuf {
    let to = tmp_dir(&format!("external-{name}"));
    copy_dir(&dir(name), &to);
    let t71 = to.join("textures/[2K]Tiles71");
    std::fs::create_dir_all(&t71).unwrap();
    std::fs::copy(to.join("textures/[2K]Tiles27/Tiles27_col.jpg"), t71.join("Tiles71_col.jpg")).unwrap();
    to
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        let t = to.join(e.file_name());
        if e.file_type().unwrap().is_dir() {
            copy_dir(&e.path(), &t);
        } else {
            std::fs::copy(e.path(), &t).unwrap();
        }
    }
}

/// `pt` at 32 pixels across (the film's aspect), 4 spp: every pixel finite, the image not black.
fn renders(label: &str, scene: Scene) {
    let (w, h) = (32, (32 * scene.camera.height).div_ceil(scene.camera.width).max(1));
    let world = World::build(scene).unwrap();
    let o = MethodArgs::default();
    let bytes = Method::Pt.preprocess(&world, &o, 1).unwrap();
    let mut pt = Method::Pt.build(&world, &o, &bytes).unwrap();
    let film = render_passes(&world, pt.as_mut(), w, h, 4, 1);
    let m = film.mean();
    assert!(m.iter().flatten().all(|x| x.is_finite()), "{label}: a pixel is not finite");
    let mean: f64 = m.iter().flatten().map(|&x| x as f64).sum::<f64>() / (3 * m.len()) as f64;
    eprintln!("{label}: {w}x{h}, 4 spp, mean {mean:.4}");
    assert!(mean > 0.0, "{label}: black");
}

#[test]
fn sms_scenes_load_from_scene_and_original_xml_and_agree() {
    for name in LOADING {
        let a = forecast::scene::load(&dir(name).join("scene.xml")).unwrap_or_else(|e| panic!("{name}: {e}"));
        let t = with_tiles71(name);
        let b = forecast::scene::load(&t.join("original.xml")).unwrap_or_else(|e| panic!("{name} original: {e}"));
        // absent from the snapshot, so the published file is refused at the texture's line
        let e = forecast::scene::load(&dir(name).join("original.xml")).unwrap_err();
        assert!(e.key.ends_with("filename") && e.message.contains("Tiles71"), "{name}: {e}");
        assert_eq!(fingerprint(&a), fingerprint(&b), "{name}: scene.xml and original.xml differ");
        assert_eq!(b.render.max_depth, 5, "{name}: max_depth 6 is 6 segments");
        let w = b.warnings.join("\n");
        eprintln!("{name} original.xml:\n{w}");
        assert!(w.contains("ignored (the method is forecast's `--method`)"), "{name}: {w}");
        assert!(w.contains("caustic_"), "{name}: the caustic_* flags are named: {w}");
        if name != "sms-sphere-smooth" {
            assert!(w.contains("Mitsuba 2's form (`filename`)"), "{name}: {w}");
        }
        renders(name, a);
        renders(&format!("{name} original"), b);
    }
}

#[test]
fn sms_ring_loads_as_published() {
    let s = forecast::scene::load(&dir("sms-ring/ring.xml")).unwrap();
    let w = s.warnings.join("\n");
    assert!(w.contains("integrator `path_sms_ss` ignored"), "{w}");
    renders("sms-ring", s);
}

/// `sms-pool`'s `scene.xml` loads as committed (its envmap, 14 meshes and every texture) and
/// renders; `original.xml` names its absent `Fabric33` normal map (absent from the SMS
/// repository too) with its file and line.
#[test]
fn sms_pool_loads_as_committed() {
    let s = forecast::scene::load(&dir("sms-pool/scene.xml")).unwrap_or_else(|e| panic!("sms-pool: {e}"));
    assert!(s.environment.is_some(), "the envmap");
    assert!(s.ntri() > 40_000, "{} triangles", s.ntri());
    renders("sms-pool scene.xml", s);
    let e = forecast::scene::load(&dir("sms-pool/original.xml")).unwrap_err();
    assert!(e.file.ends_with("original.xml") && e.line > 0, "{e}");
    assert!(e.message.contains("Fabric33"), "{e}");
}

/// `sms-pool`'s `original.xml` (Mitsuba 2) with its absent texture stood in for as `scene.xml`
/// does (`Fabric33`'s normal map by the cotton one), in a temporary copy: it loads and renders.
#[test]
fn sms_pool_original_loads_with_stand_ins() {
    let t = tmp_dir("external-sms-pool");
    copy_dir(&dir("sms-pool"), &t);
    let tex = t.join("textures");
    let (missing, stand_in) = ("[2K]Fabric33/Fabric33_nrm.png", "Striped_cotton_01_2K_Normal.jpg");
    std::fs::create_dir_all(tex.join(missing).parent().unwrap()).unwrap();
    std::fs::copy(tex.join(stand_in), tex.join(missing)).unwrap();
    let s = forecast::scene::load(&t.join("original.xml")).unwrap_or_else(|e| panic!("sms-pool original.xml: {e}"));
    assert!(s.environment.is_some(), "the envmap");
    assert!(s.ntri() > 40_000, "{} triangles", s.ntri());
    renders("sms-pool original.xml", s);
}
