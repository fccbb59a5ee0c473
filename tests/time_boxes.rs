//! Time boxes hold for every phase (`pipeline::budget`, issue #63): every method ends within
//! `--time` + 2% + one pass on `cornell-box` and the `water-caustic` stress scene (a large mesh,
//! a tiny light, glass) at small sizes; a budget that loading, the BVH and writing alone exceed
//! is refused at once with the time needed and nothing written; SIGTERM during the
//! emission-split probe or the caustic preprocess ends the render within about a second; the
//! JSON lists each phase's wall seconds and share of the budget. A pass the deadline or a signal
//! cuts is discarded whole (`render::trace_passes`): a cut leaves the film as it was, and a render
//! SIGTERM cut in mid-pass holds whole passes only, bit for bit the `--spp` render of that many
//! (`pt`, `iws` with its per-pass point lights, `pt-cf` with its light paths); a first pass
//! longer than the budget is finished and warned about with the `--time` it needs. Unix only
//! (signals by `kill`).
//!
//! Times are the render's own (`timings.total_s`, wall seconds since the process started), with
//! a tolerance of [`SLACK_S`] for the JSON's own write and a loaded machine's scheduling.
#![cfg(unix)]

mod common;
use common::{cf_test_opts, root, tmp_dir};
use forecast::accel::World;
use forecast::integrators::Method;
use forecast::interrupt::{Interrupt, Stop};
use forecast::render::{film::Film, render_passes, trace_passes, PixelSampler};
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Seconds allowed beyond `--time` + 2% + one pass: the JSON's write after `total_s` and the
/// scheduling of a shared machine (a stop is polled, not preemptive).
const SLACK_S: f64 = 0.25;

const METHODS: [&str; 5] = ["pt", "iws", "iws-pm", "iws-cf", "pt-cf"];

fn bin() -> &'static str {
    env!("CARGO_BIN_EXE_forecast")
}

fn render(scene: &str, method: &str, res: &str, out: &Path, extra: &[&str]) -> Command {
    let mut c = Command::new(bin());
    c.args(["render", scene, "--method", method, "--resolution", res, "--threads", "2", "--quiet", "--out"])
        .arg(out)
        .args(extra);
    c
}

fn json(out: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(out.with_extension("json")).unwrap()).unwrap()
}

/// Every method on `scene` at `res` ends within each budget + 2% + one pass (its mean pass), and
/// reports every phase with its share.
fn every_method_within(scene: &str, res: &str, budgets: &[f64], tag: &str) {
    let d = tmp_dir(tag);
    for &t in budgets {
        for m in METHODS {
            let out = d.join(format!("{m}-{t}"));
            let o = render(scene, m, res, &out, &["--time", &format!("{t}s")]).output().unwrap();
            let err = String::from_utf8_lossy(&o.stderr);
            assert!(o.status.success(), "{m} --time {t}: {err}");
            let j = json(&out);
            let total = j["timings"]["total_s"].as_f64().unwrap();
            let passes = (j["passes"].as_u64().unwrap() - j["first_pass"].as_u64().unwrap()).max(1) as f64;
            let one_pass = j["timings"]["render_s"].as_f64().unwrap() / passes;
            let limit = t * 1.02 + one_pass + SLACK_S;
            assert!(total <= limit, "{m} {scene} {res} --time {t}: {total:.3} s > {limit:.3} s\n{j}");
            let phases: Vec<&str> =
                j["phases"].as_array().unwrap().iter().map(|p| p["phase"].as_str().unwrap()).collect();
            for want in ["load", "bvh", "preprocess", "build", "passes", "write"] {
                assert!(phases.contains(&want), "{m}: no phase {want} in {phases:?}");
            }
            for p in j["phases"].as_array().unwrap() {
                let (w, s) = (p["wall_s"].as_f64().unwrap(), p["share"].as_f64().unwrap());
                assert!((s - w / t).abs() < 1e-9, "{m}: share {s} of {w} s in {t} s");
            }
        }
    }
    let _ = std::fs::remove_dir_all(d);
}

#[test]
fn every_method_ends_within_the_budget_on_cornell_box() {
    every_method_within("scenes/cornell-box.toml", "32x32", &[2.0, 3.0], "tb-cornell");
}

#[test]
fn every_method_ends_within_the_budget_on_the_water_caustic() {
    // the probe alone takes seconds here without a budget (every lattice point behind glass is
    // traced 16 times), the preprocess's caustic shares too
    every_method_within("scenes/water-caustic.toml", "48x48", &[3.0, 5.0], "tb-water");
}

#[test]
fn a_budget_too_small_for_the_minimal_phases_is_refused_at_once_with_the_time_needed() {
    let d = tmp_dir("tb-small");
    for m in ["pt", "pt-cf"] {
        let out = d.join(m);
        let t = Instant::now();
        let o = render("scenes/water-caustic.toml", m, "64x64", &out, &["--time", "0.01s"]).output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{m}: {err}");
        assert!(err.contains("too short") && err.contains("give --time"), "{m}: {err}");
        // refused after loading and the BVH (measured, about a second here), before anything else
        assert!(t.elapsed() < Duration::from_secs(15), "{m}: refused only after {:?}", t.elapsed());
        for ext in ["exr", "png", "json"] {
            assert!(!out.with_extension(ext).exists(), "{m}: {ext} written");
        }
    }
    let _ = std::fs::remove_dir_all(d);
}

/// SIGTERM `after` into a render that is then in a long phase before its first pass: it ends
/// within about a second, exit 130, nothing written.
fn sigterm_in_a_phase(method: &str, res: &str, extra: &[&str], tag: &str) {
    let d = tmp_dir(tag);
    let out = d.join("x");
    let child = render("scenes/water-caustic.toml", method, res, &out, extra)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // loading and the BVH take about 0.3 s here; both long phases run for 20 s or more
    std::thread::sleep(Duration::from_millis(1500));
    let t = Instant::now();
    assert!(Command::new("kill").args(["-TERM", &child.id().to_string()]).status().unwrap().success());
    let o = child.wait_with_output().unwrap();
    let took = t.elapsed();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(took < Duration::from_millis(1500), "{method}: SIGTERM honoured after {took:?}: {err}");
    assert_eq!(o.status.code(), Some(130), "{method}: {err}");
    assert!(err.contains("nothing was written"), "{method}: {err}");
    assert!(!out.with_extension("exr").exists() && !out.with_extension("json").exists());
    let _ = std::fs::remove_dir_all(d);
}

#[test]
fn sigterm_during_the_probe_ends_within_a_second() {
    // the probe's lattice is 1280 intervals across up to 640 pixels, 4096 at 2048²: about 20 s
    // on the water here (2 s at 256², which a fast machine finished before the signal)
    sigterm_in_a_phase("pt", "2048x2048", &["--spp", "1", "--emission-split", "16"], "tb-sig-probe");
}

#[test]
fn sigterm_during_the_preprocess_ends_within_a_second() {
    sigterm_in_a_phase("iws-cf", "64x64", &["--spp", "1", "--forecast-photons", "5000000"], "tb-sig-pre");
}

#[test]
fn light_paths_beyond_the_bound_are_refused() {
    let d = tmp_dir("tb-lp");
    let out = d.join("x");
    let o = render("scenes/cornell-box.toml", "pt-cf", "16x16", &out, &["--spp", "1", "--light-paths", "1073741824"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("--light-paths 1073741824: at most 65536 per pass at 16x16"), "{err}");
    let _ = std::fs::remove_dir_all(d);
}

#[test]
fn a_cut_pass_leaves_the_film_as_it_was_and_a_whole_one_is_the_render_of_its_passes() {
    let world = World::build(forecast::scene::load(&root().join("scenes/cornell-box.toml")).unwrap()).unwrap();
    let cam = world.scene.camera.with_resolution(24, 24);
    let due = Stop::new(&Interrupt::default(), Some(Instant::now()));
    for method in [Method::Pt, Method::PtCf] {
        let o = cf_test_opts();
        let integ = method.build(&world, &o, &method.preprocess(&world, &o, 17).unwrap()).unwrap();
        let pixels = PixelSampler::plain(&cam);
        assert!(trace_passes(&world, integ.as_ref(), &pixels, 5, &[0, 1], &due).is_none(), "{method:?}: not cut");
        if let Some(l) = integ.light_tracer() {
            assert!(l.light_splats_until(&world, &cam, 5, 0, &due).is_none(), "{method:?}: light side not cut");
        }
        let mut a = Film::new(24, 24);
        render_passes(&world, integ.as_ref(), &pixels, 5, &[0, 1], &mut a);
        let mut b = Film::new(24, 24);
        let whole = trace_passes(&world, integ.as_ref(), &pixels, 5, &[0, 1], &Stop::never()).unwrap();
        whole.merge(&pixels, &mut b);
        assert!(a.data.iter().zip(&b.data).all(|(x, y)| x.to_bits() == y.to_bits()), "{method:?}");
        assert!(a.total_samples() == 2.0 * 24.0 * 24.0);
    }
}

/// SIGTERM in the middle of a later round of a long `--spp` render: the render ends within about a
/// second (the pass is cut, not finished), its JSON counts the cut passes, and its image is bit
/// for bit the `--spp P` render of the P passes it kept.
fn sigterm_cuts_a_pass(method: &str, extra: &[&str]) {
    // a round lasts about a second (pass groups are sized so): the signal, half a second after a
    // round boundary, lands inside a round unless the machine stalls the render past it; a run
    // whose signal fell between two rounds (nothing cut) is tried again, twice at most
    for attempt in 0..3 {
        if sigterm_in_a_round(method, extra, attempt) {
            return;
        }
    }
    panic!("{method}: three signals, each between two rounds: no round was cut");
}

/// One run of [`sigterm_cuts_a_pass`]: the interrupted image is the `--spp` render of its whole
/// passes; true when the signal cut a round.
fn sigterm_in_a_round(method: &str, extra: &[&str], attempt: u32) -> bool {
    let d = tmp_dir(&format!("tb-cut-{method}-{attempt}"));
    let (out, re) = (d.join("cut"), d.join("whole"));
    let common = [&["--emission-split", "1"][..], extra].concat();
    // a snapshot after 1 s is written at the first round boundary after it: once it is there,
    // a round is done, and the signal then lands in a later one
    let spp = [&["--spp", "100000", "--snapshots", "1s"][..], &common].concat();
    let child = render("scenes/cornell-box.toml", method, "256x256", &out, &spp)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let snapped =
        || std::fs::read_dir(&d).unwrap().flatten().any(|e| e.file_name().to_string_lossy().contains(".snap-"));
    let t = Instant::now();
    while !snapped() && t.elapsed() < Duration::from_secs(120) {
        std::thread::sleep(Duration::from_millis(50));
    }
    std::thread::sleep(Duration::from_millis(500));
    let t = Instant::now();
    assert!(Command::new("kill").args(["-TERM", &child.id().to_string()]).status().unwrap().success());
    let o = child.wait_with_output().unwrap();
    let took = t.elapsed();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(130), "{method}: {err}");
    assert!(took < Duration::from_millis(1500), "{method}: SIGTERM honoured after {took:?}: {err}");
    let j = json(&out);
    assert_eq!(j["interrupted"], true, "{method}: {j}");
    let p = j["passes"].as_u64().unwrap();
    assert!(p >= 1, "{method}: {j}");
    // a signal inside a round cuts it, and the round is discarded
    let cut = j["passes_cut"].as_u64().unwrap() >= 1;
    assert_eq!(j["spp"].as_u64().unwrap(), p, "{method}: the image holds whole passes only");
    let o =
        render("scenes/cornell-box.toml", method, "256x256", &re, &[&["--spp", &p.to_string()][..], &common].concat())
            .output()
            .unwrap();
    assert!(o.status.success(), "{method}: {}", String::from_utf8_lossy(&o.stderr));
    let (a, b) = (
        forecast::image_io::read_exr(&out.with_extension("exr")).unwrap(),
        forecast::image_io::read_exr(&re.with_extension("exr")).unwrap(),
    );
    assert!(a == b, "{method}: the cut render's {p} passes differ from the --spp {p} render");
    let _ = std::fs::remove_dir_all(d);
    cut
}

#[test]
fn sigterm_cuts_a_pass_of_pt_and_the_image_is_the_spp_render_of_its_whole_passes() {
    sigterm_cuts_a_pass("pt", &[]);
}

#[test]
fn sigterm_cuts_a_pass_of_iws_and_the_image_is_the_spp_render_of_its_whole_passes() {
    sigterm_cuts_a_pass("iws", &[]);
}

#[test]
fn sigterm_cuts_a_pass_of_pt_cf_with_its_light_paths() {
    sigterm_cuts_a_pass("pt-cf", &["--forecast-photons", "2000", "--light-paths", "65536"]);
}

#[test]
fn a_first_pass_longer_than_the_budget_is_finished_and_warned_about() {
    // 512² at 1 s: the write reserve (1 µs per pixel + 0.02 s) leaves the passes until 0.718 s,
    // about one `pt` pass on two cores; a loaded machine's first pass ends after it
    let d = tmp_dir("tb-first");
    let out = d.join("x");
    let o = render("scenes/cornell-box.toml", "pt", "512x512", &out, &["--time", "1s", "--emission-split", "1"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    let j = json(&out);
    let passes = j["passes"].as_u64().unwrap();
    let (total, render_s) = (j["timings"]["total_s"].as_f64().unwrap(), j["timings"]["render_s"].as_f64().unwrap());
    let deadline = 1.0 - (1e-6 * 512.0 * 512.0 + 0.02);
    // the passes end within a pass of their deadline (the first round is never cut, a later one
    // is cut within a tile); writing is its own phase
    let write = j["phases"].as_array().unwrap().iter().find(|p| p["phase"] == "write").unwrap()["wall_s"].as_f64();
    let passes_end = total - write.unwrap();
    assert!(passes >= 1 && passes_end <= deadline + render_s / passes as f64 + SLACK_S, "{passes_end} s\n{j}");
    let warned = err.contains("the first pass ran") && err.contains("give --time");
    if passes_end > deadline + SLACK_S && j["passes_cut"] == 0 {
        assert!(warned && passes == 1, "{passes_end} s: {err}");
    }
    if warned {
        assert_eq!(passes, 1, "{err}");
    }
    let _ = std::fs::remove_dir_all(d);
}
