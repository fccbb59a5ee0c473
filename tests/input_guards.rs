//! The guards found by an adversarial pass over the binary (2026-12-01), run as a user would
//! (`env!("CARGO_BIN_EXE_forecast")`):
//!
//! * an input that is a FIFO or a device (`--resume /dev/zero`, `diff A FIFO`, `compare
//!   --reference FIFO`) is refused at once instead of blocking or filling the memory;
//! * an output path that names an input or another output (`--checkpoint-path` onto the scene or
//!   onto `PREFIX.exr`, `export-mitsuba --out` onto its input) is refused and the file stays;
//! * a closed stderr never ends a render (its files are written, exit 0), a closed stdout ends
//!   `diff` quietly with 141 (SIGPIPE's status), not a panic;
//! * images with NaN pixels or a negative variance are refused by `diff`, and an agreement check
//!   without any noise estimate (identical halves) fails instead of passing vacuously;
//! * `--table-cache` takes only finite values ≥ 0; options that do not apply are refused, not
//!   ignored (`-D` on a TOML scene, `compare --spp`, `stability --only ""`, `bench --spp 0`).

mod common;

use common::cli::{cornell_box, forecast, run};
use common::{root, tmp_dir};
use forecast::image_io::{write_exr, write_exr_layers, Image};
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

fn s(p: &Path) -> String {
    p.display().to_string()
}

#[test]
fn fifo_and_device_inputs_are_refused_at_once() {
    let d = tmp_dir("guards-fifo");
    let fifo = d.join("pipe.exr");
    assert!(Command::new("mkfifo").arg(&fifo).status().is_ok_and(|st| st.success()), "mkfifo failed");
    let img = d.join("a.exr");
    write_exr(&img, &Image::new(8, 8)).unwrap();
    let out = s(&d.join("r"));
    let cases: [Vec<String>; 4] = [
        vec!["diff".into(), s(&img), s(&fifo)],
        vec!["diff".into(), s(&img), "/dev/zero".into()],
        [
            "render",
            &cornell_box(),
            "--method",
            "pt",
            "--spp",
            "1",
            "--resolution",
            "8x8",
            "--quiet",
            "--out",
            &out,
            "--resume",
            "/dev/zero",
        ]
        .map(String::from)
        .to_vec(),
        ["compare", &cornell_box(), "--methods", "pt", "--budgets", "1s", "--seeds", "1", "--out", &out, "--reference"]
            .iter()
            .map(|a| a.to_string())
            .chain([s(&fifo)])
            .collect(),
    ];
    for args in cases {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let t = Instant::now();
        let (code, _, err) = run(&args);
        assert_eq!(code, 1, "{args:?}: {err}");
        assert!(err.contains("not a regular file"), "{args:?}: {err}");
        assert!(t.elapsed() < Duration::from_secs(20), "{args:?} took {:?}", t.elapsed());
    }
    let _ = std::fs::remove_dir_all(d);
}

#[test]
fn outputs_never_overwrite_inputs_or_each_other() {
    let d = tmp_dir("guards-clobber");
    let victim = d.join("victim.toml");
    std::fs::copy(root().join("scenes/cornell-box.toml"), &victim).unwrap();
    let before = std::fs::read(&victim).unwrap();
    let prefix = s(&d.join("r"));
    let render = |ckpt: &str| {
        let a =
            ["render", &s(&victim), "--method", "pt", "--spp", "2", "--resolution", "8x8", "--quiet", "--out", &prefix];
        let mut args: Vec<&str> = a.to_vec();
        args.extend(["--checkpoint-every", "1ms", "--checkpoint-path", ckpt]);
        run(&args)
    };
    // the scene itself, also spelled through `..`
    let dotted = s(&d.join("sub").join("..").join("victim.toml"));
    std::fs::create_dir_all(d.join("sub")).unwrap();
    for ckpt in [s(&victim), dotted] {
        let (code, _, err) = render(&ckpt);
        assert_eq!(code, 1, "{err}");
        assert!(err.contains("--checkpoint-path") && err.contains("destroy"), "{err}");
    }
    let (code, _, err) = render(&format!("{prefix}.exr"));
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("overwrite"), "{err}");
    let (code, _, err) = run(&["export-mitsuba", &s(&victim), "--out", &s(&victim)]);
    assert_eq!(code, 1, "{err}");
    assert_eq!(std::fs::read(&victim).unwrap(), before, "the scene was changed");
    // an XML scene is not exported again (it used to be parsed as TOML)
    let xml = s(&root().join("scenes/external/sms-ring/ring.xml"));
    let (code, _, err) = run(&["export-mitsuba", &xml, "--out", &s(&d.join("again.xml"))]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("TOML scenes"), "{err}");
    // a checkpoint beside the outputs is fine
    let (code, _, err) = render(&format!("{prefix}.ckpt"));
    assert_eq!(code, 0, "{err}");
    let _ = std::fs::remove_dir_all(d);
}

/// A pipe whose reading end is already closed: every write to it fails with EPIPE at once.
fn closed_pipe() -> std::io::PipeWriter {
    let (reader, writer) = std::io::pipe().expect("pipe");
    drop(reader);
    writer
}

#[test]
fn a_closed_stderr_never_ends_a_render_and_a_closed_stdout_ends_quietly() {
    let d = tmp_dir("guards-pipe");
    let prefix = d.join("r");
    // point light + glass: the render warns on stderr before its first pass
    let warns = s(&root().join("scenes/stability/point-glass.toml"));
    let args = ["render", &warns, "--spp", "1", "--resolution", "8x8", "--quiet", "--out", &s(&prefix)];
    let st = forecast().args(args).stdout(Stdio::null()).stderr(closed_pipe()).status().unwrap();
    assert_eq!(st.code(), Some(0), "the render was ended by its closed stderr: {st:?}");
    for ext in ["exr", "png", "json"] {
        assert!(prefix.with_extension(ext).is_file(), "no {ext} written");
    }
    let json = std::fs::read_to_string(prefix.with_extension("json")).unwrap();
    assert!(json.contains("L S+ D"), "the warning is in the JSON all the same");
    // a closed stdout: `diff`'s numbers have no reader
    let img = s(&prefix.with_extension("exr"));
    let out = forecast().args(["diff", &img, &img]).stdout(closed_pipe()).output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(141), "{:?}: {err}", out.status);
    assert!(err.is_empty(), "not quiet: {err}");
    let _ = std::fs::remove_dir_all(d);
}

#[test]
fn non_finite_images_and_checks_without_noise_are_refused() {
    let d = tmp_dir("guards-nan");
    let mut img = Image::new(4, 4);
    img.pixels.iter_mut().for_each(|p| *p = [0.5; 3]);
    let ok = d.join("ok.exr");
    write_exr(&ok, &img).unwrap();
    let mut bad = img.clone();
    bad.pixels[6] = [0.5, f32::NAN, 0.5];
    let nan = d.join("nan.exr");
    write_exr(&nan, &bad).unwrap();
    let (code, _, err) = run(&["diff", &s(&nan), &s(&ok)]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("nan.exr") && err.contains("not finite") && err.contains("(2, 1)"), "{err}");
    // a negative variance layer
    let mut var = Image::new(4, 4);
    var.pixels[0] = [-1.0, 0.0, 0.0];
    let negvar = d.join("negvar.exr");
    write_exr_layers(&negvar, &img, Some(&var)).unwrap();
    let o = s(&ok);
    let (code, _, err) = run(&["diff", &s(&negvar), &o, "--half0", &o, "--half1", &o]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("negative"), "{err}");
    // identical halves and zero variance: the same image given three times is refused up front
    // (no noise estimate could come of it), and so is a test image equal to the reference
    let zero = d.join("zerovar.exr");
    write_exr_layers(&zero, &img, Some(&Image::new(4, 4))).unwrap();
    let (code, _, err) = run(&["diff", &s(&zero), &o, "--half0", &o, "--half1", &o]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("are the same image") && err.contains("independently"), "{err}");
    let _ = std::fs::remove_dir_all(d);
}

#[test]
fn table_cache_takes_finite_values_only() {
    for bad in ["nan", "-1", "inf", "-inf", "1e39"] {
        let flag = format!("--table-cache={bad}");
        let (code, _, err) =
            run(&["render", &cornell_box(), "--method", "iws-cf", "--spp", "1", "--resolution", "8x8", &flag]);
        assert_eq!(code, 2, "--table-cache {bad}: {err}");
        assert!(err.contains("--table-cache"), "{err}");
    }
}

#[test]
fn options_that_do_not_apply_are_refused() {
    let d = tmp_dir("guards-unused");
    let out = s(&d.join("c"));
    let sc = cornell_box();
    let cases: [(&[&str], &str); 4] = [
        (&["-D", "spp=3", "render", &sc, "--spp", "1", "--resolution", "8x8", "--out", &out], "TOML scene"),
        (&["compare", &sc, "--spp", "1", "--reference", &sc, "--out", &out], "--spp is a `render` option"),
        (&["stability", "--only", "", "--out", &out], "no case named"),
        (&["bench", &sc, "--spp", "0"], "--spp"),
    ];
    for (args, want) in cases {
        let t = Instant::now();
        let (code, _, err) = run(args);
        assert_eq!(code, 1, "{args:?}: {err}");
        assert!(err.contains(want), "{args:?}: {err}");
        assert!(t.elapsed() < Duration::from_secs(20), "{args:?} took {:?}", t.elapsed());
    }
    let _ = std::fs::remove_dir_all(d);
}

/// Copies `scenes/ring.{toml,obj}` into `d`: a scene whose mesh is an input no output may name.
fn ring_copy(d: &Path) -> (String, std::path::PathBuf) {
    std::fs::copy(root().join("scenes/ring.toml"), d.join("ring.toml")).unwrap();
    std::fs::copy(root().join("scenes/ring.obj"), d.join("ring.obj")).unwrap();
    (s(&d.join("ring.toml")), d.join("ring.obj"))
}

/// `args` exits 1 with every one of `words` in its message, and `file` is byte for byte as before.
fn refused(args: &[&str], file: &Path, words: &[&str]) {
    let before = std::fs::read(file).unwrap();
    let (code, _, err) = run(args);
    assert_eq!(code, 1, "{args:?}: {err}");
    for w in words {
        assert!(err.contains(w), "{args:?}: `{w}` not in {err}");
    }
    assert_eq!(std::fs::read(file).unwrap(), before, "{args:?} changed {}", file.display());
}

/// Every file under `dir` (relative name → bytes).
fn files_under(dir: &Path) -> std::collections::BTreeMap<String, Vec<u8>> {
    let mut m = std::collections::BTreeMap::new();
    for e in std::fs::read_dir(dir).unwrap().flatten() {
        if e.path().is_file() {
            m.insert(e.file_name().to_string_lossy().into_owned(), std::fs::read(e.path()).unwrap());
        }
    }
    m
}

#[test]
fn export_never_writes_over_the_scene_or_its_meshes() {
    let d = tmp_dir("guards-export");
    let (toml, obj) = ring_copy(&d);
    // `--out ring.obj`: the scene's own mesh
    refused(&["export-mitsuba", &toml, "--out", &s(&obj)], &obj, &["--out", "the scene's mesh", "destroy"]);
    // an input mesh where the export writes its own, OUT_meshes/shape_001.ply
    let (code, _, err) = run(&["export-mitsuba", &toml, "--out", &s(&d.join("r.xml"))]);
    assert_eq!(code, 0, "{err}");
    std::fs::create_dir_all(d.join("q_meshes")).unwrap();
    let ply = d.join("q_meshes/shape_001.ply");
    std::fs::copy(d.join("r_meshes/shape_001.ply"), &ply).unwrap();
    let q = std::fs::read_to_string(&toml).unwrap().replace("\"ring.obj\"", "\"q_meshes/shape_001.ply\"");
    std::fs::write(d.join("q.toml"), q).unwrap();
    let q_xml = d.join("q.xml");
    refused(&["export-mitsuba", &s(&d.join("q.toml")), "--out", &s(&q_xml)], &ply, &["mesh", "destroy"]);
    assert!(!q_xml.exists(), "nothing of a refused export is written");
    let _ = std::fs::remove_dir_all(d);
}

#[test]
fn a_failed_export_leaves_the_previous_export_whole() {
    let d = tmp_dir("guards-export-set");
    let (toml, _) = ring_copy(&d);
    let xml = d.join("r.xml");
    let (code, _, err) = run(&["export-mitsuba", &toml, "--out", &s(&xml)]);
    assert_eq!(code, 0, "{err}");
    let (meshes_before, xml_before) = (files_under(&d.join("r_meshes")), std::fs::read(&xml).unwrap());
    // another scene (the ring moved: other mesh bytes) whose export fails at its last file, the
    // XML, after the meshes' temporaries were written (as a full disk would)
    let moved = std::fs::read_to_string(&toml)
        .unwrap()
        .replace("file     = \"ring.obj\"", "file     = \"ring.obj\"\ntranslate = [0.0, 0.5, 0.0]");
    std::fs::write(d.join("moved.toml"), moved).unwrap();
    std::fs::create_dir_all(d.join("r.xml.tmp")).unwrap();
    let (code, _, err) = run(&["export-mitsuba", &s(&d.join("moved.toml")), "--out", &s(&xml)]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("r.xml.tmp"), "{err}");
    assert_eq!(files_under(&d.join("r_meshes")), meshes_before, "the previous meshes changed (or .tmp left)");
    assert_eq!(std::fs::read(&xml).unwrap(), xml_before);
    // and the same export without the obstacle replaces the set
    std::fs::remove_dir(d.join("r.xml.tmp")).unwrap();
    let (code, _, err) = run(&["export-mitsuba", &s(&d.join("moved.toml")), "--out", &s(&xml)]);
    assert_eq!(code, 0, "{err}");
    assert_ne!(files_under(&d.join("r_meshes")), meshes_before);
    let _ = std::fs::remove_dir_all(d);
}

#[test]
fn a_checkpoint_never_replaces_a_mesh_or_a_snapshot() {
    let d = tmp_dir("guards-ckpt-mesh");
    let (toml, obj) = ring_copy(&d);
    let prefix = s(&d.join("r"));
    let base = ["render", &toml, "--resolution", "8x8", "--threads", "1", "--quiet", "--out", &prefix];
    let mut args = base.to_vec();
    args.extend(["--spp", "2", "--checkpoint-every", "1h", "--checkpoint-path", obj.to_str().unwrap()]);
    refused(&args, &obj, &["--checkpoint-path", "the scene's mesh", "destroy"]);
    // a --snapshots image: the guard sees it before it exists
    let snap = format!("{prefix}.snap-1ms.exr");
    let mut args = base.to_vec();
    args.extend(["--time", "1s", "--snapshots", "1ms", "--checkpoint-every", "1h", "--checkpoint-path", &snap]);
    let (code, _, err) = run(&args);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("--checkpoint-path") && err.contains("--snapshots") && err.contains("overwrite"), "{err}");
    assert!(!Path::new(&snap).exists() && !d.join("r.exr").exists(), "a refused render wrote files");
    let _ = std::fs::remove_dir_all(d);
}

#[test]
fn diff_png_never_replaces_an_input_image() {
    let d = tmp_dir("guards-diff");
    let (a, b) = (d.join("a.exr"), d.join("b.exr"));
    write_exr(&a, &Image::new(8, 8)).unwrap();
    write_exr(&b, &Image::new(8, 8)).unwrap();
    refused(&["diff", &s(&a), &s(&b), "--png", &s(&a)], &a, &["--png", "the image A", "destroy"]);
    // also through `..` and onto B
    let dotted = s(&d.join("x").join("..").join("b.exr"));
    std::fs::create_dir_all(d.join("x")).unwrap();
    refused(&["diff", &s(&a), &s(&b), "--png", &dotted], &b, &["the image B"]);
    let (code, _, err) = run(&["diff", &s(&a), &s(&b), "--png", &s(&d.join("d.png"))]);
    assert_eq!(code, 0, "{err}");
    let _ = std::fs::remove_dir_all(d);
}

#[test]
fn compare_never_overwrites_its_reference() {
    let d = tmp_dir("guards-compare");
    let runs = d.join("c/runs");
    std::fs::create_dir_all(&runs).unwrap();
    let reference = runs.join("pt_300ms_s0.exr");
    write_exr(&reference, &Image::new(16, 16)).unwrap();
    let out = s(&d.join("c"));
    let args = ["compare", &cornell_box(), "--methods", "pt", "--budgets", "300ms", "--seeds", "1", "--threads", "1"];
    let mut args = args.to_vec();
    args.extend(["--quiet", "--out", &out, "--reference", reference.to_str().unwrap()]);
    refused(&args, &reference, &["--reference", "destroy"]);
    // a reference inside the report's own directories
    let crops = d.join("c/crops");
    std::fs::create_dir_all(&crops).unwrap();
    let in_crops = crops.join("ref.exr");
    std::fs::copy(&reference, &in_crops).unwrap();
    args.pop();
    args.push(in_crops.to_str().unwrap());
    refused(&args, &in_crops, &["--reference", "crops"]);
    let _ = std::fs::remove_dir_all(d);
}

/// `pt-cf` builds the same forecast as `iws-cf`, so the up-front memory estimate holds it too:
/// 4e9 forecast photons are refused at once (they used to be traced past `--time`, 33 MB/s).
#[test]
fn pt_cf_forecast_photons_are_held_to_the_memory_estimate() {
    let d = tmp_dir("guards-ptcf-memory");
    for method in ["iws-cf", "pt-cf"] {
        let out = s(&d.join(method));
        let args =
            ["render", &cornell_box(), "--method", method, "--resolution", "16x16", "--time", "3s", "--threads", "1"];
        let mut args = args.to_vec();
        args.extend(["--quiet", "--forecast-photons", "4000000000", "--out", &out]);
        let t = Instant::now();
        let (code, _, err) = run(&args);
        assert_eq!(code, 1, "{method}: {err}");
        assert!(err.contains("GiB") && err.contains("preprocess product"), "{method}: {err}");
        assert!(t.elapsed() < Duration::from_secs(10), "{method} took {:?}", t.elapsed());
    }
    let _ = std::fs::remove_dir_all(d);
}

/// `forecast ARGS` under `ulimit -v KIB` (a child shell sets the limit, then becomes the binary).
fn run_under_ulimit_v(kib: u64, args: &[&str]) -> (i32, String, String, f64) {
    let t = Instant::now();
    let child = Command::new("bash")
        .args(["-c", &format!("ulimit -v {kib} && exec \"$0\" \"$@\""), env!("CARGO_BIN_EXE_forecast")])
        .args(args)
        .current_dir(root())
        .env_remove("MPI_LOCALNRANKS")
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn bash");
    let (code, out, err) = common::cli::finish(args, child);
    (code, out, err, t.elapsed().as_secs_f64())
}

/// The memory estimate takes the address-space limit (`ulimit -v`, RLIMIT_AS) into account: a
/// `pt-cf` render of 2560² (about 1.6 GiB by the estimate) under a 0.95 GiB limit is refused at
/// once, naming the limit (it used to run the preprocess, the pilot and a pass for 92 s and then
/// abort on a failed allocation), while a small render under the same limit runs.
#[test]
fn the_memory_estimate_honours_ulimit_v() {
    let d = tmp_dir("guards-rlimit");
    let cb = cornell_box();
    let out = s(&d.join("big"));
    let args = [
        "render",
        &cb,
        "--method",
        "pt-cf",
        "--forecast-photons",
        "2000",
        "--resolution",
        "2560x2560",
        "--spp",
        "1",
        "--threads",
        "1",
        "--quiet",
        "--out",
        &out,
    ];
    let (code, _, err, secs) = run_under_ulimit_v(1_000_000, &args);
    assert!(code != 0 && err.contains("needs about") && err.contains("available"), "{code}: {err}");
    assert!(secs < 20.0, "refused after {secs:.1} s: {err}");
    // where the machine has the memory, it is the limit that refuses it, and the message says so
    if forecast::param_limits::available_memory().is_some_and(|m| m > 3 << 30) {
        assert!(err.contains("RLIMIT_AS"), "{err}");
    }
    assert!(!d.join("big.exr").exists());
    let small = s(&d.join("small"));
    let args = ["render", &cb, "--resolution", "16x16", "--spp", "1", "--threads", "1", "--quiet", "--out", &small];
    let (code, _, err, _) = run_under_ulimit_v(1_000_000, &args);
    assert_eq!(code, 0, "{err}");
    assert!(d.join("small.exr").exists());
}

/// `forecast-map` checks its forecast photons against the memory estimate and bounds
/// `--compare-paths`, before any work (both used to run until killed).
#[test]
fn forecast_map_is_bounded_by_the_memory_estimate() {
    let d = tmp_dir("guards-fmap");
    let cb = cornell_box();
    let out = s(&d.join("fm"));
    let t = Instant::now();
    let (code, _, err) =
        run(&["forecast-map", &cb, "--out", &out, "--forecast-photons", "4000000000", "--quiet", "--threads", "1"]);
    assert!(code != 0 && err.contains("needs about") && err.contains("4000000000 forecast photons"), "{err}");
    let (code, _, err) = run(&[
        "forecast-map",
        &cb,
        "--out",
        &out,
        "--forecast-photons",
        "100",
        "--compare-paths",
        "18446744073709551615",
        "--quiet",
    ]);
    assert!(code != 0 && err.contains("--compare-paths") && err.contains("1073741824"), "{err}");
    assert!(t.elapsed() < Duration::from_secs(20), "{:?}", t.elapsed());
    assert!(!d.join("fm.png").exists() && !d.join("fm.json").exists());
}
