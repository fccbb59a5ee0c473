//! The `forecast` binary run as a user runs it (`env!("CARGO_BIN_EXE_forecast")`), for the tests of
//! its messages and exit statuses (tests/cli_errors.rs, tests/input_guards.rs, tests/bad_scenes.rs).

use super::root;
use std::io::Read;
use std::process::{Child, Command, Stdio};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// A run past this is killed and fails its test: a blocked read must fail, not hang the suite.
const LIMIT: Duration = Duration::from_secs(60);

/// The binary, run from the crate root, without an MPI launcher's environment, stdin closed.
pub fn forecast() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_forecast"));
    c.current_dir(root()).env_remove("MPI_LOCALNRANKS").stdin(Stdio::null());
    c
}

/// Runs `forecast ARGS` with stdout and stderr captured: (exit code, stdout, stderr), checked as
/// [`finish`] checks them.
pub fn run(args: &[&str]) -> (i32, String, String) {
    let child = forecast().args(args).stdout(Stdio::piped()).stderr(Stdio::piped()).spawn().expect("spawn forecast");
    finish(args, child)
}

/// Waits for `child` (spawned with `args`) and returns (exit code, stdout, stderr); a stream that
/// was not piped reads as "". Fails the test on a signal, a panic (status 101 or "panicked" on
/// stderr), or a run past [`LIMIT`] (it is killed). The pipes are drained on threads of their own,
/// so a chatty child never blocks on a full pipe.
pub fn finish(args: &[&str], mut child: Child) -> (i32, String, String) {
    let (out, err) = (drain(child.stdout.take()), drain(child.stderr.take()));
    let t = Instant::now();
    let status = loop {
        if let Some(st) = child.try_wait().expect("wait") {
            break st;
        }
        if t.elapsed() > LIMIT {
            let _ = child.kill();
            let _ = child.wait();
            panic!("{args:?} still running after {LIMIT:?} (blocked?)");
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let (out, err) = (out.join().expect("stdout reader"), err.join().expect("stderr reader"));
    let code = status.code().unwrap_or_else(|| panic!("{args:?} ended by a signal; stderr: {err}"));
    assert!(code != 101 && !err.contains("panicked"), "{args:?} panicked: {err}");
    (code, out, err)
}

/// Reads `pipe` (if any) to its end on a thread of its own, as text (invalid UTF-8 replaced).
fn drain<R: Read + Send + 'static>(pipe: Option<R>) -> JoinHandle<String> {
    std::thread::spawn(move || {
        let mut buf = Vec::new();
        if let Some(mut p) = pipe {
            let _ = p.read_to_end(&mut buf);
        }
        String::from_utf8_lossy(&buf).into_owned()
    })
}

/// `scenes/cornell-box.toml`, the scene these tests render when the scene is not the point.
pub fn cornell_box() -> String {
    root().join("scenes/cornell-box.toml").display().to_string()
}
