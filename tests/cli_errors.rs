//! The binary's error paths, run as a user would (`env!("CARGO_BIN_EXE_forecast")`): each case
//! is a clear message and the documented exit status (docs/cli.md, "Exit status"): 1 for an error,
//! 2 for a command line clap cannot parse, never 101 (a panic).
//!
//! * stdout and/or stderr on `/dev/full` (Linux): no panic ("failed printing to stdout"), exit 1;
//! * `diff` of images of different sizes names both files and sizes;
//! * `--out dir/` (no file name) is refused before any work and writes no hidden `dir/.exr`;
//! * `bench --repeats 0`, `--threads 0`, `--threads 100000` (at once, not after 35 s of thread
//!   creation), `stability --only nonexistent` (lists the valid cases);
//! * a flag of another method (`--method pt --clusters 5`, or the scene's method) exits 2 naming
//!   the methods it belongs to; the JSON `options` hold only the chosen method's.

mod common;

use common::cli::{cornell_box, finish, forecast, run};
use common::tmp_dir;
use forecast::image_io::{write_exr, Image};
use std::fs::{File, OpenOptions};
use std::path::Path;
use std::process::Stdio;
use std::time::{Duration, Instant};

fn dev_full() -> Option<File> {
    OpenOptions::new().write(true).open("/dev/full").ok()
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
    let child = forecast().args(["diff", &sa, &sb]).stdout(full).stderr(Stdio::piped()).spawn().unwrap();
    let (code, _, stderr) = finish(&["diff", &sa, &sb], child);
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
    let (code, _, err) = run(&[
        "render",
        &cornell_box(),
        "--method",
        "pt",
        "--spp",
        "1",
        "--resolution",
        "8x8",
        "--out",
        &prefix,
        "--quiet",
    ]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("no file name"), "{err}");
    assert!(t.elapsed() < Duration::from_secs(20), "refused only after {:?}", t.elapsed());
    assert_eq!(std::fs::read_dir(&d).unwrap().count(), 0, "files were written into {}", d.display());
    let _ = std::fs::remove_dir_all(d);
}

#[test]
fn bench_refuses_zero_repeats() {
    let (code, out, err) = run(&["bench", &cornell_box(), "--repeats", "0", "--resolution", "8x8"]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("--repeats"), "{err}");
    assert!(!out.contains("median of 0"), "{out}");
}

#[test]
fn thread_counts_are_checked_up_front() {
    for n in ["0", "100000"] {
        let t = Instant::now();
        let (code, _, err) = run(&[
            "render",
            &cornell_box(),
            "--method",
            "pt",
            "--spp",
            "1",
            "--resolution",
            "8x8",
            "--threads",
            n,
            "--quiet",
        ]);
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
    let (code, _, err) = run(&["render", &cornell_box(), "--method", "pt", "--spp", "many"]);
    assert_eq!(code, 2, "malformed value: {err}");
    let (code, _, err) = run(&["no-such-command"]);
    assert_eq!(code, 2, "{err}");
    let (code, _, err) = run(&["render", "missing.toml"]);
    assert_eq!(code, 1, "{err}");
    assert!(err.starts_with("error: ") && err.contains("missing.toml"), "{err}");
}

/// A flag of another method is a usage error (exit 2, before any work) naming the methods it
/// belongs to, whether `--method` names the method or the scene's `render.method` does
/// (`cornell-box.toml`: `pt`); the method's own flags and the render settings are accepted.
#[test]
fn a_flag_of_another_method_exits_2_naming_its_method() {
    let d = tmp_dir("cli-foreign");
    let prefix = d.join("x").display().to_string();
    let sc = cornell_box();
    let cases: &[(&[&str], &str)] = &[
        (&["--method", "pt", "--clusters", "5"], "--clusters belongs to iws-cf/pt-cf, not pt"),
        // no --method: the scene names none, so `auto` resolves it (pt-cf on cornell-box)
        (&["--variant", "baj08"], "--variant belongs to iws-cf, not pt-cf"),
        (&["--method", "iws", "--guide-fraction", "0.5"], "--guide-fraction belongs to pt-cf, not iws"),
        (&["--method", "iws-cf", "--light-paths", "100"], "--light-paths belongs to pt-cf, not iws-cf"),
        (&["--method", "pt-cf", "--variant", "baj08"], "--variant belongs to iws-cf, not pt-cf"),
        (&["--method", "iws-pm", "--split", "4"], "--split belongs to iws-cf/pt-cf, not iws-pm"),
        (&["--method", "iws-cf", "--photons", "10"], "--photons belongs to iws-pm, not iws-cf"),
        (&["--method", "pt", "--vpl-paths", "8"], "--vpl-paths belongs to iws/iws-pm/iws-cf, not pt"),
        (&["--photons", "10"], "--photons belongs to iws-pm, not pt-cf"),
        // the pilot is pt-cf's default now: its former flag is unknown
        (&["--method", "pt-cf", "--light-path-pilot"], "unexpected argument '--light-path-pilot'"),
    ];
    for (opts, want) in cases {
        let t = Instant::now();
        let args = [&["render", sc.as_str(), "--resolution", "8x8", "--quiet", "--out", &prefix][..], opts].concat();
        let (code, _, err) = run(&args);
        assert_eq!(code, 2, "{opts:?}: {err}");
        assert!(err.starts_with("error: ") && err.contains(want), "{opts:?}: expected `{want}` in: {err}");
        assert!(err.contains("Usage: forecast render"), "{opts:?}: clap's usage format: {err}");
        assert!(t.elapsed() < Duration::from_secs(10), "{opts:?} refused only after {:?}", t.elapsed());
        assert_eq!(std::fs::read_dir(&d).unwrap().count(), 0, "{opts:?} wrote files into {}", d.display());
    }
    let _ = std::fs::remove_dir_all(d);
}

/// The report's `options` are the render settings and the chosen method's groups only: `pt`
/// records `--path-filter` and no CF option; `iws-cf` its IWS and CF groups and `--variant`
/// (with `baj08`'s `direct = vpl` applied), and neither `pt-cf`'s nor `iws-pm`'s options.
#[test]
fn the_json_records_only_the_chosen_methods_options() {
    let d = tmp_dir("cli-options");
    let sc = cornell_box();
    let keys = |method: &str, extra: &[&str]| -> serde_json::Map<String, serde_json::Value> {
        let prefix = d.join(method).display().to_string();
        let base = ["render", sc.as_str(), "--method", method, "--resolution", "4x4", "--spp", "1"];
        let args = [&base[..], &["--threads", "1", "--quiet", "--out", &prefix], extra].concat();
        let (code, _, err) = run(&args);
        assert_eq!(code, 0, "{method}: {err}");
        let text = std::fs::read_to_string(format!("{prefix}.json")).expect("report written");
        let j: serde_json::Value = serde_json::from_str(&text).expect("JSON");
        j["options"].as_object().expect("options is an object").clone()
    };
    let pt = keys("pt", &[]);
    let mut names: Vec<&str> = pt.keys().map(String::as_str).collect();
    names.sort_unstable();
    assert_eq!(names, ["accel", "emission_split", "max_depth", "path_filter", "sampler"], "{pt:?}");
    assert_eq!(pt["accel"].as_str(), Some("wide"), "the default back end is recorded");
    assert_eq!(pt["sampler"].as_str(), Some("independent"), "the default sampler is recorded");
    let cf = keys("iws-cf", &["--variant", "baj08", "--forecast-photons", "2000", "--clusters", "4"]);
    for k in ["max_depth", "emission_split", "vpl_paths", "direct", "clusters", "split", "table_depth", "variant"] {
        assert!(cf.contains_key(k), "iws-cf options lack `{k}`: {cf:?}");
    }
    for k in
        ["guide_fraction", "guide_min_share", "light_paths", "light_path_pilot", "photons", "gather", "path_filter"]
    {
        assert!(!cf.contains_key(k), "iws-cf options hold another method's `{k}`: {cf:?}");
    }
    assert_eq!(
        (cf["variant"].as_str(), cf["direct"].as_str(), cf["clusters"].as_u64()),
        (Some("baj08"), Some("vpl"), Some(4))
    );
    // pt-cf's light paths are recorded as the count per pass the render used: when not given,
    // the pilot's ν (⅛ to 2 per pixel) of the 4×4 image, ⌈16ν⌉
    let ptcf = keys("pt-cf", &["--forecast-photons", "2000", "--clusters", "4"]);
    let n = ptcf["light_paths"].as_u64().expect("recorded");
    assert!([2, 4, 8, 16, 32].contains(&n), "{ptcf:?}");
    let _ = std::fs::remove_dir_all(d);
}

/// Every option the scene format would refuse is refused on the command line too, by the one
/// validation (`forecast::param_limits`), before any work: no file is written, in well under the
/// time of a render.
#[test]
fn invalid_render_options_are_refused_before_any_work() {
    let d = tmp_dir("cli-invalid");
    let prefix = d.join("x").display().to_string();
    let cases: &[(&[&str], &str)] = &[
        (&["--spp", "0"], "--spp 0: spp must be at least 1"),
        (&["--method", "iws-pm", "--photons", "0"], "--photons 0: photons must be at least 1"),
        (
            &["--method", "iws-cf", "--forecast-photons", "0"],
            "--forecast-photons 0: forecast photons must be at least 1",
        ),
        (&["--threads", "0"], "--threads 0: threads must be between 1 and 4096"),
        (&["--max-depth", "1"], "--max-depth 1: max_depth must be at least 2"),
        (&["--max-depth", "0"], "--max-depth 0: max_depth must be at least 2"),
        (&["--method", "iws-cf", "--split", "4294967295"], "--split 4294967295: split must be between 1 and 1024"),
        (
            &["--method", "iws", "--vpl-paths", "4294967295"],
            "--vpl-paths 4294967295: vpl paths must be between 1 and 65536",
        ),
        (
            &["--method", "pt-cf", "--light-paths", "18446744073709551615"],
            "--light-paths 18446744073709551615: light paths must be between 0 and 1073741824",
        ),
    ];
    let sc = cornell_box();
    for (opts, want) in cases {
        let t = Instant::now();
        let args = [&["render", sc.as_str(), "--resolution", "8x8", "--quiet", "--out", &prefix][..], opts].concat();
        let (code, _, err) = run(&args);
        assert_eq!(code, 1, "{opts:?}: {err}");
        assert!(err.starts_with("error: ") && err.contains(want), "{opts:?}: expected `{want}` in: {err}");
        assert!(t.elapsed() < Duration::from_secs(10), "{opts:?} refused only after {:?}", t.elapsed());
        assert_eq!(std::fs::read_dir(&d).unwrap().count(), 0, "{opts:?} wrote files into {}", d.display());
    }
    let _ = std::fs::remove_dir_all(d);
}

/// `--spp 0` used to exit 0 and replace an existing `PREFIX.{exr,png,json}` with a black image.
#[test]
fn spp_zero_leaves_an_existing_set_untouched() {
    let d = tmp_dir("cli-spp0");
    let prefix = d.join("keep").display().to_string();
    let (code, _, err) = run(&[
        "render",
        &cornell_box(),
        "--method",
        "pt",
        "--spp",
        "2",
        "--resolution",
        "8x8",
        "--quiet",
        "--out",
        &prefix,
    ]);
    assert_eq!(code, 0, "{err}");
    let read = |ext: &str| std::fs::read(format!("{prefix}.{ext}")).unwrap();
    let before: Vec<Vec<u8>> = ["exr", "png", "json"].iter().map(|e| read(e)).collect();
    let (code, _, err) = run(&[
        "render",
        &cornell_box(),
        "--method",
        "pt",
        "--spp",
        "0",
        "--resolution",
        "8x8",
        "--quiet",
        "--out",
        &prefix,
    ]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("--spp 0"), "{err}");
    let after: Vec<Vec<u8>> = ["exr", "png", "json"].iter().map(|e| read(e)).collect();
    assert!(before == after, "--spp 0 changed the existing set");
    assert_eq!(std::fs::read_dir(&d).unwrap().count(), 3, "temporaries left behind");
    let _ = std::fs::remove_dir_all(d);
}

/// A film that cannot be allocated (65536² pixels × 56 bytes = 224 GiB per copy) is refused with
/// the estimate, at once, instead of a SIGABRT after the preprocess.
#[test]
fn an_impossible_film_is_refused_up_front() {
    let avail = forecast::param_limits::available_memory();
    if avail.is_none_or(|a| a > 900 << 30) {
        eprintln!("skipped: available memory unknown or above the estimate ({avail:?})");
        return;
    }
    let d = tmp_dir("cli-huge");
    let prefix = d.join("huge").display().to_string();
    let t = Instant::now();
    let args =
        ["render", &cornell_box(), "--method", "iws-pm", "--resolution", "65536x65536", "--quiet", "--out", &prefix];
    let (code, _, err) = run(&args);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("65536x65536") && err.contains("GiB") && err.contains("available"), "{err}");
    assert!(t.elapsed() < Duration::from_secs(10), "refused only after {:?}", t.elapsed());
    assert_eq!(std::fs::read_dir(&d).unwrap().count(), 0);
    let _ = std::fs::remove_dir_all(d);
}

/// clap's own `--help` into a full stdout is an error (exit 1), not a silent success.
#[test]
fn help_into_a_full_stdout_is_an_error() {
    let Some(full) = dev_full() else {
        eprintln!("skipped: no /dev/full on this system");
        return;
    };
    let child = forecast().arg("--help").stdout(full).stderr(Stdio::piped()).spawn().unwrap();
    let (code, _, err) = finish(&["--help"], child);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("cannot write to stdout"), "{err}");
    let (code, out, _) = run(&["--help"]);
    assert_eq!(code, 0);
    assert!(out.contains("render"), "{out}");
    let (code, out, _) = run(&["--version"]);
    assert_eq!(code, 0);
    assert!(out.starts_with("forecast "), "{out}");
}

/// `--accel embree` in a build without the `embree` feature is a clear error, before any work
/// (`render` and `bench`).
#[cfg(not(feature = "embree"))]
#[test]
fn accel_embree_without_the_feature_is_refused() {
    let d = tmp_dir("cli-accel");
    let sc = cornell_box();
    let prefix = d.join("r").display().to_string();
    for args in [
        vec!["render", sc.as_str(), "--accel", "embree", "--spp", "1", "--quiet", "--out", &prefix],
        vec!["bench", sc.as_str(), "--accel", "embree", "--repeats", "1"],
    ] {
        let (code, _, err) = run(&args);
        assert_ne!(code, 0, "{args:?} succeeded");
        assert!(err.contains("rebuild with --features embree"), "{args:?}: {err}");
    }
    assert!(!Path::new(&format!("{prefix}.json")).exists(), "nothing is written");
}

/// Runs each of `cases` (extra flags after `base`) and checks a usage error of `forecast SUB`
/// (exit 2, clap's format) holding the expected words, before any work and writing nothing.
fn refused_as_usage(sub: &str, base: &[&str], cases: &[(&[&str], &str)], dir: &Path) {
    for (opts, want) in cases {
        let t = Instant::now();
        let args = [&[sub][..], base, opts].concat();
        let (code, _, err) = run(&args);
        assert_eq!(code, 2, "{opts:?}: {err}");
        assert!(err.starts_with("error: ") && err.contains(want), "{opts:?}: expected `{want}` in: {err}");
        assert!(err.contains(&format!("Usage: forecast {sub}")), "{opts:?}: clap's usage format: {err}");
        assert!(t.elapsed() < Duration::from_secs(10), "{opts:?} refused only after {:?}", t.elapsed());
        assert_eq!(std::fs::read_dir(dir).unwrap().count(), 0, "{opts:?} wrote files into {}", dir.display());
    }
}

/// `reference` renders `pt` only: a flag of another method is the usage error it is under
/// `render --method pt`, and so is `--method` naming another method.
#[test]
fn reference_refuses_a_flag_that_pt_does_not_take() {
    let d = tmp_dir("cli-reference-foreign");
    let (sc, prefix) = (cornell_box(), d.join("r").display().to_string());
    let base = [sc.as_str(), "--resolution", "8x8", "--threads", "2", "--quiet", "--out", &prefix];
    let cases: &[(&[&str], &str)] = &[
        (&["--time", "1s", "--light-paths", "1"], "--light-paths belongs to pt-cf, not pt"),
        (&["--spp", "1", "--vpl-paths", "4"], "--vpl-paths belongs to iws/iws-pm/iws-cf, not pt"),
        (&["--spp", "1", "--clusters", "5"], "--clusters belongs to iws-cf/pt-cf, not pt"),
        (&["--spp", "1", "--method", "iws"], "reference renders pt only"),
    ];
    refused_as_usage("reference", &base, cases, &d);
    let _ = std::fs::remove_dir_all(d);
}

/// `forecast-map` runs the CF preprocess only: every flag it does not use (render budgets,
/// checkpoints, snapshots, `--method`, other methods' options) is a usage error naming it; the
/// CF options, `--variant` and the general settings are accepted.
#[test]
fn forecast_map_refuses_the_flags_it_does_not_use() {
    let d = tmp_dir("cli-forecast-map");
    let (sc, prefix) = (cornell_box(), d.join("m").display().to_string());
    let base = [sc.as_str(), "--resolution", "8x8", "--threads", "2", "--quiet", "--out", &prefix];
    let cases: &[(&[&str], &str)] = &[
        (&["--method", "pt"], "forecast-map does not use --method"),
        (&["--method", "iws-pm"], "forecast-map does not use --method"),
        (&["--vpl-paths", "3"], "forecast-map does not use --vpl-paths (it belongs to iws/iws-pm/iws-cf)"),
        (&["--light-paths", "3"], "forecast-map does not use --light-paths (it belongs to pt-cf)"),
        (&["--photons", "5"], "forecast-map does not use --photons (it belongs to iws-pm)"),
        (&["--spp", "3"], "forecast-map does not use --spp"),
        (&["--time", "3s"], "forecast-map does not use --time"),
        (&["--snapshots", "1s"], "forecast-map does not use --snapshots"),
        (&["--checkpoint-every", "1s"], "forecast-map does not use --checkpoint-every"),
        (&["--max-depth", "5"], "forecast-map does not use --max-depth"),
    ];
    refused_as_usage("forecast-map", &base, cases, &d);
    let cf = ["--forecast-photons", "2000", "--clusters", "8", "--variant", "baj08", "--compare-paths", "1000"];
    let (code, _, err) = run(&[&["forecast-map"][..], &base, &cf, &["--seed", "3", "--accel", "obvhs"]].concat());
    assert_eq!(code, 0, "the CF options are forecast-map's: {err}");
    assert!(Path::new(&format!("{prefix}.json")).exists(), "forecast-map wrote its JSON");
    let _ = std::fs::remove_dir_all(d);
}

/// `compare` takes `--methods`, not `--method`, and refuses a method flag that none of the
/// compared methods takes; a flag of at least one compared method is accepted (the run then
/// fails only on the missing reference: exit 1, not a usage error).
#[test]
fn compare_refuses_a_flag_of_none_of_the_compared_methods() {
    let d = tmp_dir("cli-compare-foreign");
    let (sc, out) = (cornell_box(), d.join("c").display().to_string());
    let missing = d.join("missing.exr").display().to_string();
    let base =
        [sc.as_str(), "--resolution", "8x8", "--threads", "2", "--quiet", "--reference", &missing, "--out", &out];
    let cases: &[(&[&str], &str)] = &[
        (&["--methods", "pt", "--light-paths", "2"], "--light-paths belongs to pt-cf, none of the compared methods pt"),
        (
            &["--methods", "pt-cf,pt", "--vpl-paths", "4"],
            "--vpl-paths belongs to iws/iws-pm/iws-cf, none of the compared methods pt-cf,pt",
        ),
        (&["--methods", "pt", "--method", "iws"], "compare takes --methods"),
    ];
    refused_as_usage("compare", &base, cases, &d);
    for opts in [&["--methods", "pt-cf,pt", "--light-paths", "2"][..], &["--methods", "iws,pt", "--vpl-paths", "4"]] {
        let (code, _, err) = run(&[&["compare"][..], &base, opts].concat());
        assert_eq!(code, 1, "{opts:?}: a compared method takes the flag: {err}");
        assert!(err.contains("missing.exr"), "{opts:?}: {err}");
    }
    let _ = std::fs::remove_dir_all(d);
}

/// `--resume` with `--spp N` stops at N passes in total: a checkpoint that already holds N or
/// more adds none, and says so on stderr (even under `--quiet`); a larger N adds passes silently.
#[test]
fn resume_of_a_checkpoint_past_the_requested_spp_warns() {
    let d = tmp_dir("cli-resume-spp");
    let (sc, prefix) = (cornell_box(), d.join("a").display().to_string());
    let ckpt = format!("{prefix}.ckpt");
    let base = ["render", sc.as_str(), "--method", "pt", "--resolution", "8x8", "--threads", "2", "--quiet"];
    let first = [&base[..], &["--spp", "8", "--checkpoint-every", "1h", "--out", &prefix]].concat();
    let (code, _, err) = run(&first);
    assert_eq!(code, 0, "{err}");
    let spp = |p: &str| -> u64 {
        let j: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(format!("{p}.json")).unwrap()).unwrap();
        j["spp"].as_u64().expect("spp")
    };
    let again = d.join("b").display().to_string();
    let (code, _, err) = run(&[&base[..], &["--spp", "2", "--resume", &ckpt, "--out", &again]].concat());
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("warning: --resume: the checkpoint already holds 8 passes"), "{err}");
    assert!(err.contains("--spp 2") && err.contains("no pass was added"), "{err}");
    assert_eq!(spp(&again), 8, "the checkpoint's passes, nothing added");
    let more = d.join("c").display().to_string();
    let (code, _, err) = run(&[&base[..], &["--spp", "10", "--resume", &ckpt, "--out", &more]].concat());
    assert_eq!(code, 0, "{err}");
    assert!(!err.contains("warning"), "passes were added: {err}");
    assert_eq!(spp(&more), 10);
    let _ = std::fs::remove_dir_all(d);
}

/// A render whose every sample is 0 while the scene has a light (here a quad light facing away
/// from the only other surface, issue #63: exit 0 and no word) warns on stderr and in the JSON's
/// `warnings`; the same scene with the light turned to face the floor does not.
#[test]
fn a_black_image_with_lights_warns() {
    let d = tmp_dir("cli-black");
    let scene = |u: &str, v: &str| {
        format!(
            "[camera]\nposition = [0.0, 1.0, 3.88]\nlook_at = [0.0, 0.5, 0.0]\nup = [0.0, 1.0, 0.0]\nfov = 39.3\n\
             resolution = [16, 16]\n\n[materials.white]\ntype = \"diffuse\"\nalbedo = [0.7, 0.7, 0.7]\n\n\
             [[shape]]\ntype = \"quad\"\ncorner = [-1.0, 0.0, -1.0]\nu = [0.0, 0.0, 2.0]\nv = [2.0, 0.0, 0.0]\n\
             material = \"white\"\n\n[[shape]]\ntype = \"quad\"\ncorner = [-0.24, 1.98, -0.19]\nu = {u}\nv = {v}\n\
             emission = [17.0, 12.0, 4.0]\n"
        )
    };
    for (name, u, v, black) in [
        ("away", "[0.0, 0.0, 0.38]", "[0.48, 0.0, 0.0]", true),
        ("down", "[0.48, 0.0, 0.0]", "[0.0, 0.0, 0.38]", false),
    ] {
        let path = d.join(format!("{name}.toml"));
        std::fs::write(&path, scene(u, v)).unwrap();
        let out = d.join(name);
        let (code, _, err) = run(&[
            "render",
            &path.display().to_string(),
            "--spp",
            "4",
            "--threads",
            "2",
            "--quiet",
            "--out",
            &out.display().to_string(),
        ]);
        assert_eq!(code, 0, "{name}: {err}");
        let json: serde_json::Value =
            serde_json::from_slice(&std::fs::read(out.with_extension("json")).unwrap()).unwrap();
        let warned =
            json["warnings"].as_array().unwrap().iter().any(|w| w.as_str().unwrap().contains("image is black"));
        assert_eq!(warned, black, "{name}: {json}");
        assert_eq!(err.contains("warning: the image is black"), black, "{name}: {err}");
        if black {
            assert!(err.contains("the scene has lights") && err.contains("face the scene"), "{err}");
            assert_eq!(json["image_mean"], serde_json::json!([0.0, 0.0, 0.0]));
        }
    }
    let _ = std::fs::remove_dir_all(d);
}

/// A scene file that cannot be read is named with no line (it has none; issue #63 showed
/// `missing.toml:0:`), by every command that loads one, TOML or Mitsuba XML.
#[test]
fn a_missing_scene_is_named_without_a_line() {
    let d = tmp_dir("cli-missing-scene");
    let out = d.join("x").display().to_string();
    for args in [
        vec!["render", "missing.toml", "--out", &out],
        vec!["render", "missing.xml", "--out", &out],
        vec!["bench", "missing.toml"],
        vec!["forecast-map", "missing.toml", "--out", &out],
        vec!["export-mitsuba", "missing.toml", "--out", &out],
    ] {
        let (code, _, err) = run(&args);
        assert_eq!(code, 1, "{args:?}: {err}");
        let file = args[1];
        assert!(err.contains(&format!("cannot read scene file `{file}`")), "{args:?}: {err}");
        assert!(!err.contains(&format!("{file}:")), "{args:?}: a line number: {err}");
    }
    let _ = std::fs::remove_dir_all(d);
}

/// `diff` gives a verdict: without the reference's halves it says that a verdict needs them; with
/// them, `agree` for an independent `pt` render of the same scene (exit 0) and `differ` for a
/// biased one (`--max-depth 2` drops the indirect light; exit 1), each with its statistic. Images
/// that are not independent are refused: the same file as both halves, A, and B
/// (`diff_identical_halves_pass.sh` passed), or a test image equal to the reference.
#[test]
fn diff_gives_a_verdict_or_says_it_needs_the_halves() {
    let d = tmp_dir("cli-diff-verdict");
    let p = |n: &str| d.join(n).display().to_string();
    let scene = "scenes/stability/no-dirac.toml";
    let small = ["--resolution", "16x16", "--threads", "2", "--quiet"];
    // the counts hold the image mean's relative standard deviation to about 0.1%, a fifth of the
    // 0.5% limit on the means (the var.* layer at 1024 spp: 2.6e-5 per pixel, mean 0.14 in G)
    let (code, _, err) =
        run(&[&["reference", scene, "--spp", "16384", "--seed", "1", "--out", &p("ref")], &small[..]].concat());
    assert_eq!(code, 0, "{err}");
    for (name, spp, extra) in [("a", "8192", vec![]), ("biased", "64", vec!["--max-depth", "2"])] {
        let args = [
            &["render", scene, "--method", "pt", "--spp", spp, "--seed", "7", "--out", &p(name)],
            &small[..],
            &extra[..],
        ];
        let (code, _, err) = run(&args.concat());
        assert_eq!(code, 0, "{err}");
    }
    let (a, r, h0, h1) = (p("a.exr"), p("ref.exr"), p("ref.half0.exr"), p("ref.half1.exr"));
    let (code, out, err) = run(&["diff", &a, &r]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("verdict   none") && out.contains("--half0") && out.contains("--half1"), "{out}");
    let (code, out, err) = run(&["diff", &a, &r, "--half0", &h0, "--half1", &h1]);
    assert_eq!(code, 0, "{out}{err}");
    assert!(out.contains("verdict   agree: largest mean difference") && out.contains("noise ratio"), "{out}");
    let (code, out, err) = run(&["diff", &p("biased.exr"), &r, "--half0", &h0, "--half1", &h1]);
    assert_eq!(code, 1, "{out}{err}");
    assert!(out.contains("verdict   differ: largest mean difference"), "{out}");
    assert!(err.contains("agreement check FAILED"), "{err}");
    // not independent: refused, whatever the statistics would say
    for args in [["diff", &a, &a, "--half0", &a, "--half1", &a], ["diff", &r, &r, "--half0", &h0, "--half1", &h1]] {
        let (code, out, err) = run(&args);
        assert_eq!(code, 1, "{args:?}: {out}{err}");
        assert!(err.contains("are the same image") && !out.contains("PASSED"), "{args:?}: {out}{err}");
    }
    let (code, _, err) = run(&["diff", &a, &r, "--half0", &h0, "--half1", &h0]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("--half0") && err.contains("--half1") && err.contains("same image"), "{err}");
    let _ = std::fs::remove_dir_all(d);
}
