//! Checkpoint and resume, single process: a render killed after a checkpoint and resumed gives
//! the same image as an uninterrupted render of the same passes (up to f64 summation order,
//! bounded at relative 1e-6), and a stale checkpoint (other seed) is refused with a clear error.

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

#[test]
fn killed_render_resumes_to_the_uninterrupted_image() {
    let d = tmp_dir("kill");
    let spp = "600";
    let full = d.join("full");
    let st = Command::new(bin())
        .args(["render", scene().to_str().unwrap(), "--spp", spp, "--resolution", "48x48", "--seed", "3", "--quiet"])
        .arg("--out")
        .arg(&full)
        .status()
        .unwrap();
    assert!(st.success());

    // Start the same render with frequent checkpoints and kill it once one exists.
    let part = d.join("part");
    let ckpt = PathBuf::from(format!("{}.ckpt", part.display()));
    let mut child = Command::new(bin())
        .args(["render", scene().to_str().unwrap(), "--spp", spp, "--resolution", "48x48", "--seed", "3", "--quiet"])
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

    let st = Command::new(bin())
        .args(["render", scene().to_str().unwrap(), "--spp", spp, "--resolution", "48x48", "--seed", "3", "--quiet"])
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
    let st = Command::new(bin())
        .args(["render", scene().to_str().unwrap(), "--spp", "4", "--resolution", "16x16", "--seed", "1", "--quiet"])
        .args(["--checkpoint-every", "1ms"])
        .arg("--out")
        .arg(&out)
        .status()
        .unwrap();
    assert!(st.success());
    let o = Command::new(bin())
        .args(["render", scene().to_str().unwrap(), "--spp", "8", "--resolution", "16x16", "--seed", "2", "--quiet"])
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
