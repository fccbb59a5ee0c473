//! The binary's error paths, run as a user would (`env!("CARGO_BIN_EXE_forecast")`): each case
//! is a clear message and the documented exit status (README "Exit status"): 1 for an error,
//! 2 for a command line clap cannot parse, never 101 (a panic).
//!
//! * stdout and/or stderr on `/dev/full` (Linux): no panic ("failed printing to stdout"), exit 1;
//! * `diff` of images of different sizes names both files and sizes;
//! * `--out dir/` (no file name) is refused before any work and writes no hidden `dir/.exr`;
//! * `bench --repeats 0`, `--threads 0`, `--threads 100000` (at once, not after 35 s of thread
//!   creation), `stability --only nonexistent` (lists the valid cases).

mod common;

use common::{root, tmp_dir};
use forecast::image_io::{write_exr, Image};
use std::fs::{File, OpenOptions};
use std::path::Path;
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

fn forecast() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_forecast"));
    c.current_dir(root()).env_remove("MPI_LOCALNRANKS").stdin(Stdio::null());
    c
}

/// Runs `args`, returns (exit code, stdout, stderr); fails the test on a signal or a panic.
fn run(args: &[&str]) -> (i32, String, String) {
    let out = forecast().args(args).output().expect("spawn forecast");
    check(args, out)
}

fn check(args: &[&str], out: Output) -> (i32, String, String) {
    let stderr = String::from_utf8_lossy(&out.stderr).to_string();
    let code = out.status.code().unwrap_or_else(|| panic!("{args:?} ended by a signal; stderr: {stderr}"));
    assert_ne!(code, 101, "{args:?} panicked: {stderr}");
    assert!(!stderr.contains("panicked"), "{args:?} panicked: {stderr}");
    (code, String::from_utf8_lossy(&out.stdout).to_string(), stderr)
}

fn dev_full() -> Option<File> {
    OpenOptions::new().write(true).open("/dev/full").ok()
}

fn scene() -> String {
    root().join("scenes/cornell-box.toml").display().to_string()
}

#[test]
fn full_stdout_and_stderr_are_an_error_not_a_panic() {
    let Some(full) = dev_full() else {
        eprintln!("skipped: no /dev/full on this system");
        return;
    };
    // The real error cannot be printed anywhere, so the status must carry it.
    let out = forecast()
        .args(["render", "missing.toml"])
        .stdout(full.try_clone().unwrap())
        .stderr(full.try_clone().unwrap())
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1), "{:?}", out.status);
    // stderr full, stdout fine: still the error status, nothing on stdout.
    let out = forecast().args(["render", "missing.toml"]).stderr(full.try_clone().unwrap()).output().unwrap();
    assert_eq!(out.status.code(), Some(1));
    assert!(out.stdout.is_empty());
    // stdout full: `diff`'s result is lost, so it is an error, reported on stderr.
    let d = tmp_dir("cli-full");
    let (a, b) = (d.join("a.exr"), d.join("b.exr"));
    write_exr(&a, &Image::new(4, 4)).unwrap();
    write_exr(&b, &Image::new(4, 4)).unwrap();
    let (sa, sb) = (a.display().to_string(), b.display().to_string());
    let out = forecast().args(["diff", &sa, &sb]).stdout(full).output().unwrap();
    let (code, _, stderr) = check(&["diff", &sa, &sb], out);
    assert_eq!(code, 1, "{stderr}");
    assert!(stderr.contains("cannot write to stdout"), "{stderr}");
    let _ = std::fs::remove_dir_all(d);
}

#[test]
fn diff_of_different_sizes_names_both_files() {
    let d = tmp_dir("cli-diff-size");
    let (a, b) = (d.join("small.exr"), d.join("large.exr"));
    write_exr(&a, &Image::new(4, 3)).unwrap();
    write_exr(&b, &Image::new(8, 6)).unwrap();
    let (code, _, err) = run(&["diff", &a.display().to_string(), &b.display().to_string()]);
    assert_eq!(code, 1, "{err}");
    for needle in ["small.exr", "4x3", "large.exr", "8x6"] {
        assert!(err.contains(needle), "missing {needle}: {err}");
    }
    let _ = std::fs::remove_dir_all(d);
}

#[test]
fn an_output_prefix_without_a_file_name_is_refused() {
    let d = tmp_dir("cli-out-dir");
    let prefix = format!("{}/", d.display());
    let t = Instant::now();
    let (code, _, err) = run(&["render", &scene(), "--spp", "1", "--resolution", "8x8", "--out", &prefix, "--quiet"]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("no file name"), "{err}");
    assert!(t.elapsed() < Duration::from_secs(20), "refused only after {:?}", t.elapsed());
    assert_eq!(std::fs::read_dir(&d).unwrap().count(), 0, "files were written into {}", d.display());
    let _ = std::fs::remove_dir_all(d);
}

#[test]
fn bench_refuses_zero_repeats() {
    let (code, out, err) = run(&["bench", &scene(), "--repeats", "0", "--resolution", "8x8"]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("--repeats"), "{err}");
    assert!(!out.contains("median of 0"), "{out}");
}

#[test]
fn thread_counts_are_checked_up_front() {
    for n in ["0", "100000"] {
        let t = Instant::now();
        let (code, _, err) = run(&["render", &scene(), "--spp", "1", "--resolution", "8x8", "--threads", n, "--quiet"]);
        assert_eq!(code, 1, "--threads {n}: {err}");
        assert!(err.contains("--threads") && err.contains("4096"), "{err}");
        assert!(t.elapsed() < Duration::from_secs(10), "--threads {n} refused only after {:?}", t.elapsed());
    }
}

#[test]
fn stability_only_with_an_unknown_case_lists_the_cases() {
    let d = tmp_dir("cli-stability");
    let (code, _, err) = run(&["stability", "--only", "nonexistent", "--out", &d.display().to_string()]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("nonexistent") && err.contains("no-dirac") && err.contains("point-glass"), "{err}");
    assert!(!Path::new(&d).join("stability.json").exists());
    let _ = std::fs::remove_dir_all(d);
}

#[test]
fn usage_errors_exit_2_and_other_errors_exit_1() {
    let (code, _, err) = run(&["render"]);
    assert_eq!(code, 2, "missing SCENE: {err}");
    let (code, _, err) = run(&["render", &scene(), "--spp", "many"]);
    assert_eq!(code, 2, "malformed value: {err}");
    let (code, _, err) = run(&["no-such-command"]);
    assert_eq!(code, 2, "{err}");
    let (code, _, err) = run(&["render", "missing.toml"]);
    assert_eq!(code, 1, "{err}");
    assert!(err.starts_with("error: ") && err.contains("missing.toml"), "{err}");
}
