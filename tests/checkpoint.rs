//! Checkpoint and resume, single process: a render killed after a checkpoint and resumed gives
//! the same image as an uninterrupted render of the same passes (up to f64 summation order,
//! bounded at relative 1e-6), and a stale checkpoint (other seed, `-D` value, `--max-depth`) is
//! refused with a clear error naming the key.

mod common;
use common::{assert_same_image, tmp_dir};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

fn bin() -> &'static str {
    env!("CARGO_BIN_EXE_forecast")
}

fn scene() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell-box.toml")
}

/// `forecast render SCENE --method pt`, the start of most command lines here.
fn pt_render() -> Command {
    let mut c = Command::new(bin());
    c.args(["render", scene().to_str().unwrap(), "--method", "pt"]);
    c
}

#[test]
fn killed_render_resumes_to_the_uninterrupted_image() {
    let d = tmp_dir("kill");
    let spp = "600";
    let full = d.join("full");
    let st = pt_render()
        .args(["--spp", spp, "--resolution", "48x48", "--seed", "3", "--quiet"])
        .arg("--out")
        .arg(&full)
        .status()
        .unwrap();
    assert!(st.success());

    // Start the same render with frequent checkpoints and kill it once one exists.
    let part = d.join("part");
    let ckpt = PathBuf::from(format!("{}.ckpt", part.display()));
    let mut child = pt_render()
        .args(["--spp", spp, "--resolution", "48x48", "--seed", "3", "--quiet"])
        .args(["--checkpoint-every", "50ms", "--threads", "1"])
        .arg("--out")
        .arg(&part)
        .stdout(Stdio::null())
        .spawn()
        .unwrap();
    let t = Instant::now();
    while !ckpt.exists() && t.elapsed() < Duration::from_secs(60) {
        std::thread::sleep(Duration::from_millis(5));
    }
    let finished_early = child.try_wait().unwrap().is_some();
    child.kill().ok();
    child.wait().unwrap();
    assert!(ckpt.exists(), "no checkpoint was written");
    let c = forecast::checkpoint::Checkpoint::load(&ckpt).unwrap();
    assert!(finished_early || c.passes_done < 600, "the run was not interrupted");
    assert!(c.passes_done > 0);
    // the checkpoint came with its images and JSON (renamed before it): a consistent set
    let part_json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(format!("{}.json", part.display())).unwrap()).unwrap();
    assert!(part_json["passes"].as_u64().unwrap() > 0);
    assert!(finished_early || part_json["complete"] == false, "{part_json}");
    assert!(Path::new(&format!("{}.exr", part.display())).exists());

    let st = pt_render()
        .args(["--spp", spp, "--resolution", "48x48", "--seed", "3", "--quiet"])
        .arg("--resume")
        .arg(&ckpt)
        .arg("--out")
        .arg(d.join("resumed"))
        .status()
        .unwrap();
    assert!(st.success());
    let json: serde_json::Value = serde_json::from_slice(&std::fs::read(d.join("resumed.json")).unwrap()).unwrap();
    assert_eq!(json["spp"], 600);
    assert_eq!(json["first_pass"], c.next_pass);
    assert_same_image(&d.join("resumed.exr"), &PathBuf::from(format!("{}.exr", full.display())));
}

#[test]
fn resume_with_another_seed_is_refused() {
    let d = tmp_dir("seed");
    let out = d.join("a");
    let st = pt_render()
        .args(["--spp", "4", "--resolution", "16x16", "--seed", "1", "--quiet"])
        .args(["--checkpoint-every", "1ms"])
        .arg("--out")
        .arg(&out)
        .status()
        .unwrap();
    assert!(st.success());
    let o = pt_render()
        .args(["--spp", "8", "--resolution", "16x16", "--seed", "2", "--quiet"])
        .arg("--resume")
        .arg(format!("{}.ckpt", out.display()))
        .arg("--out")
        .arg(d.join("b"))
        .output()
        .unwrap();
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("cannot resume") && err.contains("seed"), "{err}");
}

fn render_json(name: &str, args: &[&str]) -> (std::process::Output, serde_json::Value, PathBuf) {
    let d = tmp_dir(name);
    let out = d.join("r");
    // `pt` unless the case names its method (the scene's own default is `auto`)
    let method: &[&str] = if args.contains(&"--method") { &[] } else { &["--method", "pt"] };
    let o = Command::new(bin())
        .args(["render", scene().to_str().unwrap()])
        .args(method)
        .args(["--resolution", "16x16", "--seed", "2", "--quiet"])
        .args(args)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    let json = std::fs::read(format!("{}.json", out.display())).ok();
    let v = json.map_or(serde_json::Value::Null, |j| serde_json::from_slice(&j).unwrap());
    (o, v, d)
}

/// A checkpoint that cannot be written (its directory is a regular file, so even root cannot
/// create it) is a warning: the render goes on, retries at every interval and completes with its
/// image and JSON, which records the warnings.
#[test]
fn a_failed_checkpoint_write_warns_and_the_render_completes() {
    let d = tmp_dir("ckpt-fail");
    let blocker = d.join("not-a-dir");
    std::fs::write(&blocker, b"x").unwrap();
    let ckpt = blocker.join("r.ckpt");
    let (o, json, _) = render_json(
        "ckpt-fail-run",
        &["--spp", "40", "--checkpoint-every", "1ms", "--checkpoint-path", ckpt.to_str().unwrap()],
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert_eq!(json["spp"], 40, "{json}");
    assert_eq!(json["complete"], true);
    let warnings: Vec<String> =
        json["warnings"].as_array().unwrap().iter().map(|w| w.as_str().unwrap().to_string()).collect();
    // one warning per checkpoint interval (one per pass group: a group holds at most 16 passes, so
    // 40 passes are at least three groups whatever the machine's speed) plus the final checkpoint
    let failed = warnings.iter().filter(|w| w.contains("checkpoint") && w.contains("not written")).count();
    assert!(failed >= 2, "{warnings:?}");
    assert!(warnings.iter().all(|w| !w.contains("checkpoint") || w.contains("not-a-dir")), "{warnings:?}");
    assert_eq!(err.matches("warning: ").count(), failed, "{err}");
}

/// `--time` stops the preprocess's photon tracing at its share, but not the clustering (4,096
/// clusters of 20,000 photons: about 1.5 s on two cores, the preprocess 2.6 s); when the phases
/// before the passes still use up the budget, the run warns and records it in the JSON. (A budget
/// below loading and the write reserve, `1ms`, is refused: `tests/time_boxes.rs`.)
#[test]
fn a_preprocess_over_the_time_budget_is_recorded() {
    let (o, json, _) = render_json(
        "over-budget",
        &["--method", "iws-cf", "--forecast-photons", "20000", "--clusters", "4096", "--time", "200ms"],
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert_eq!(json["preprocess_over_budget"], true, "{json}");
    let w = json["warnings"].to_string();
    assert!(w.contains("over the --time budget"), "{w}");
    assert!(err.contains("warning: the preprocess took"), "{err}");
    // and not without a time budget
    let (o, json, _) = render_json("in-budget", &["--method", "iws-pm", "--photons", "20000", "--spp", "1"]);
    assert!(o.status.success());
    assert_eq!(json["preprocess_over_budget"], false, "{json}");
}

/// Renders `scene` with `first` and a checkpoint, then resumes it with `second`; returns the
/// resume's (exit status, stderr).
fn resume_with(name: &str, scene: &Path, first: &[&str], second: &[&str]) -> (bool, String) {
    let d = tmp_dir(name);
    let (a, b) = (d.join("a"), d.join("b"));
    let base = ["render", scene.to_str().unwrap(), "--resolution", "16x16", "--seed", "1", "--threads", "1", "--quiet"];
    let mut first_run = Command::new(bin());
    first_run.args(base).args(["--spp", "2", "--checkpoint-every", "1h"]).args(first);
    let st = first_run.arg("--out").arg(&a).status().unwrap();
    assert!(st.success());
    let o = Command::new(bin())
        .args(base)
        .args(["--spp", "4", "--resume", &format!("{}.ckpt", a.display())])
        .args(second)
        .arg("--out")
        .arg(&b)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(o.status.code() != Some(101), "{err}");
    assert!(!o.status.success() || b.with_extension("exr").exists());
    (o.status.success(), err)
}

/// `-D` values change the scene (its hash covers the XML text, not the values): a resume with
/// another value, or without one, is refused naming the key; the same value resumes.
#[test]
fn resume_with_another_define_is_refused() {
    let xml = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/external/sms-ring/ring.xml");
    let (ok, err) = resume_with("resume-d", &xml, &["-D", "spp=4"], &["-D", "spp=8"]);
    assert!(
        !ok && err.contains("cannot resume") && err.contains("-D spp differs (checkpoint 4, requested 8)"),
        "{err}"
    );
    let (ok, err) = resume_with("resume-d-unset", &xml, &["-D", "spp=4"], &[]);
    assert!(!ok && err.contains("-D spp differs (checkpoint 4, requested unset)"), "{err}");
    let (ok, err) = resume_with("resume-d-same", &xml, &["-D", "spp=4"], &["-D", "spp=4"]);
    assert!(ok, "{err}");
}

/// `--max-depth` (and every other method option) changes the image: refused, naming the key.
#[test]
fn resume_with_another_max_depth_is_refused() {
    let (ok, err) = resume_with("resume-depth", &scene(), &["--max-depth", "8"], &["--max-depth", "3"]);
    assert!(!ok && err.contains("option max_depth differs (checkpoint 8, requested 3)"), "{err}");
    // the same options resume
    let (ok, err) = resume_with("resume-depth-same", &scene(), &["--max-depth", "8"], &["--max-depth", "8"]);
    assert!(ok, "{err}");
}

/// A texture image enters the scene hash that a checkpoint and MPI's ranks compare: the same
/// scene beside another image of the same name is another scene; beside the same image, the same.
#[test]
fn a_changed_texture_image_is_another_scene() {
    let src = common::root().join("tests/scenes/mitsuba-plugins");
    let d = tmp_dir("ckpt-texture-hash");
    std::fs::copy(src.join("bitmap-png.xml"), d.join("bitmap-png.xml")).unwrap();
    let hash = |image: &str| {
        std::fs::copy(src.join(image), d.join("tex16.png")).unwrap();
        forecast::scene::load(&d.join("bitmap-png.xml")).expect("loads").hash
    };
    let (a, again, other) = (hash("tex16.png"), hash("tex16.png"), hash("height32.png"));
    assert_eq!(a, again, "the same image");
    assert_ne!(a, other, "another image under the same name");
    let _ = std::fs::remove_dir_all(d);
}
