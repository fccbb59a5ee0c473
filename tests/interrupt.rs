//! Ctrl-C and SIGTERM during `forecast render` (`forecast::interrupt`): the render stops after
//! the pass group in flight, writes its image, JSON (`interrupted: true`) and checkpoint, and
//! exits 130; the image is the `--spp` render of the same pass count bit for bit (a pass is a pure
//! function of seed, pass and pixel), so nothing finished was lost and nothing half-done was
//! kept. Unix only (the test sends the signals with `kill`).
#![cfg(unix)]

mod common;
use common::tmp_dir;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

fn bin() -> &'static str {
    env!("CARGO_BIN_EXE_forecast")
}

fn render(out: &std::path::Path, budget: &[&str]) -> Command {
    let mut c = Command::new(bin());
    c.args(["render", "scenes/cornell-box.toml", "--method", "pt", "--resolution", "32x32", "--threads", "2"])
        .args(["--seed", "4", "--quiet", "--out"])
        .arg(out)
        .args(budget);
    c
}

/// Sends `signal` to the render once it has run `after`, and waits for it.
fn interrupted(out: &std::path::Path, signal: &str, after: Duration) -> std::process::Output {
    let child = render(out, &["--time", "120s", "--checkpoint-every", "1000s"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(after);
    let t = Instant::now();
    let k = Command::new("kill").args([signal, &child.id().to_string()]).status().unwrap();
    assert!(k.success(), "kill {signal} failed");
    let o = child.wait_with_output().unwrap();
    // the pass group in flight is planned at about a second (schedule::GROUP_SECS)
    assert!(t.elapsed() < Duration::from_secs(20), "stopped only after {:?}", t.elapsed());
    o
}

#[test]
fn a_signal_writes_the_passes_done_and_exits_130() {
    let d = tmp_dir("interrupt");
    for (signal, name) in [("-INT", "int"), ("-TERM", "term")] {
        let out = d.join(name);
        let o = interrupted(&out, signal, Duration::from_secs(3));
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(130), "{signal}: {err}");
        assert!(err.contains("interrupted: the") && err.contains("passes done"), "{err}");
        let json: serde_json::Value =
            serde_json::from_slice(&std::fs::read(out.with_extension("json")).unwrap()).unwrap();
        assert_eq!(json["interrupted"], true, "{json}");
        // a signal's render is not the one asked for (issue #63: it said `complete: true`)
        assert_eq!(json["complete"], false, "{json}");
        let passes = json["passes"].as_u64().unwrap();
        assert!(passes > 0, "{json}");
        assert!(out.with_extension("ckpt").exists(), "{signal}: no checkpoint");
        // the same passes rendered by count: the same image, bit for bit
        let by_count = d.join(format!("{name}-spp"));
        let st = render(&by_count, &["--spp", &passes.to_string()]).status().unwrap();
        assert!(st.success());
        let spp_json: serde_json::Value =
            serde_json::from_slice(&std::fs::read(by_count.with_extension("json")).unwrap()).unwrap();
        assert_eq!((spp_json["complete"].clone(), spp_json["interrupted"].clone()), (true.into(), false.into()));
        let (a, b) =
            (std::fs::read(out.with_extension("exr")).unwrap(), std::fs::read(by_count.with_extension("exr")).unwrap());
        assert!(a == b, "{signal}: the interrupted image is not the --spp {passes} image");
    }
    let _ = std::fs::remove_dir_all(d);
}
