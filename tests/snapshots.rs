//! `render --snapshots` and `compare --single-run` on a 32×32 Cornell box (fixed seeds):
//! snapshot sets appear in time order (passes and spp non-decreasing, elapsed ≥ nominal), a
//! snapshot image is exactly the image of a render with its pass count, the final image is
//! bit-identical with and without snapshots, bad snapshot times are refused naming the flag,
//! and `compare --single-run` gives a row per budget, the smaller ones from snapshots.

mod common;

use clap::Parser;
use common::{job, render_film, root, tmp_dir};
use forecast::cli::{Cli, Command};
use forecast::distributed::local::Local;
use forecast::image_io::{self, with_ext};
use forecast::integrators::Method;
use forecast::pipeline::{render, snapshot_prefix, RenderJob, SnapshotReport};
use std::path::Path;
use std::time::{Duration, Instant};

const RES: (u32, u32) = (32, 32);

fn cornell() -> std::path::PathBuf {
    root().join("scenes/cornell-box.toml")
}

fn read_snapshot(out: &Path, label: &str) -> SnapshotReport {
    let p = with_ext(&snapshot_prefix(out, label), "json");
    let text = std::fs::read_to_string(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

#[test]
fn snapshots_are_taken_in_order_and_hold_the_image_of_their_passes() {
    let d = tmp_dir("snapshots-order");
    let out = d.join("r");
    let mut time_job = RenderJob {
        spp: None,
        time: Some(1.5),
        snapshots: vec![0.8, 0.2, 0.5], // any order: taken in time order
        ..job(&cornell(), Method::Pt, 1, 7, RES, 1, &out)
    };
    // no probe: under a time box it stops at its share, and the split pixels would then depend
    // on how far it got (`pipeline::budget`), not only on the passes
    time_job.args.settings.emission_split = 1;
    let r = render(&time_job, &Local::new(), Instant::now()).unwrap().unwrap();
    let snaps: Vec<SnapshotReport> = ["200ms", "500ms", "800ms"].iter().map(|l| read_snapshot(&out, l)).collect();
    // The final report lists the snapshots written (serde_json's float parsing may differ in the
    // last bit, so the floats are compared to 1e-12).
    assert_eq!(r.report.snapshots.len(), 3);
    for (a, b) in r.report.snapshots.iter().zip(&snaps) {
        assert_eq!((&a.label, a.passes, a.spp), (&b.label, b.passes, b.spp));
        let close = |x: f64, y: f64| (x - y).abs() <= 1e-12 * x.abs().max(1.0);
        assert!(
            close(a.elapsed_s, b.elapsed_s) && (0..3).all(|c| close(a.image_mean[c], b.image_mean[c])),
            "{a:?} {b:?}"
        );
    }
    for (s, nominal) in snaps.iter().zip([0.2, 0.5, 0.8]) {
        assert_eq!(s.nominal_s, nominal);
        assert!(s.elapsed_s >= s.nominal_s, "{s:?}");
        assert!(s.passes > 0 && s.spp == s.passes, "{s:?}");
        assert_eq!((s.method.as_str(), s.seed, s.resolution), ("pt", 7, [RES.0, RES.1]));
        assert!(s.preprocess_s >= 0.0 && s.preprocess_s <= s.elapsed_s, "{s:?}");
        assert!(with_ext(&snapshot_prefix(&out, &s.label), "exr").exists());
    }
    for w in snaps.windows(2) {
        assert!(w[0].passes <= w[1].passes && w[0].elapsed_s <= w[1].elapsed_s, "{w:?}");
    }
    assert!(snaps[2].passes <= r.report.passes, "final {} passes < snapshot {:?}", r.report.passes, snaps[2]);
    // The first snapshot is exactly the image of a render of its pass count (same seed).
    let spp_out = d.join("spp");
    let mut by_count = job(&cornell(), Method::Pt, snaps[0].passes, 7, RES, 1, &spp_out);
    by_count.args.settings.emission_split = 1;
    render_film(&by_count);
    let a = image_io::read_exr(&with_ext(&snapshot_prefix(&out, "200ms"), "exr")).unwrap();
    let b = image_io::read_exr(&with_ext(&spp_out, "exr")).unwrap();
    assert_eq!(
        a.pixels, b.pixels,
        "snapshot at {} passes differs from a {}-spp render",
        snaps[0].passes, snaps[0].passes
    );
}

#[test]
fn the_final_image_is_bit_identical_with_and_without_snapshots() {
    let d = tmp_dir("snapshots-identical");
    let (plain, snapped) = (d.join("plain"), d.join("snapped"));
    let r0 = render(&job(&cornell(), Method::Pt, 24, 3, RES, 2, &plain), &Local::new(), Instant::now()).unwrap();
    // The clock says the process started 10 s ago: 1s and 2s are due at the first round
    // boundary (after pass 0 of 24), 1h never comes.
    let with = RenderJob { snapshots: vec![1.0, 2.0, 3600.0], ..job(&cornell(), Method::Pt, 24, 3, RES, 2, &snapped) };
    let started = Instant::now().checked_sub(Duration::from_secs(10)).expect("a clock 10 s back");
    let r1 = render(&with, &Local::new(), started).unwrap();
    let (r0, r1) = (r0.unwrap(), r1.unwrap());
    assert_eq!(
        r1.report.snapshots.iter().map(|s| (s.label.as_str(), s.passes)).collect::<Vec<_>>(),
        [("1s", 1), ("2s", 1)]
    );
    assert!(r1.report.warnings.iter().any(|w| w.contains("snapshot 1h not written")), "{:?}", r1.report.warnings);
    assert!(!with_ext(&snapshot_prefix(&snapped, "1h"), "json").exists());
    assert_eq!((r0.report.passes, r1.report.passes), (24, 24));
    assert!(r0.film.data == r1.film.data, "the film changed with snapshots");
    let bytes = |p: &Path| std::fs::read(with_ext(p, "exr")).unwrap();
    assert!(bytes(&plain) == bytes(&snapped), "the final EXR changed with snapshots");
}

#[test]
fn snapshot_times_are_checked_against_the_budget() {
    let Ok(Cli { command: Command::Render(a), .. }) = Cli::try_parse_from([
        "forecast",
        "render",
        cornell().to_str().unwrap(),
        "--time",
        "1m",
        "--snapshots",
        "15s,30s",
    ]) else {
        panic!("render --snapshots parses")
    };
    assert_eq!(a.job().snapshots, vec![15.0, 30.0]);
    let d = tmp_dir("snapshots-bad");
    let err = |time: Option<f64>, snapshots: Vec<f64>| {
        let j = RenderJob { spp: None, time, snapshots, ..job(&cornell(), Method::Pt, 1, 0, RES, 1, &d.join("r")) };
        render(&j, &Local::new(), Instant::now()).err().expect("refused").to_string()
    };
    let e = err(Some(1.0), vec![0.5, 1.0]);
    assert!(e.contains("--snapshots") && e.contains("1s") && e.contains("budget"), "{e}");
    let e = err(Some(60.0), vec![10.0, 10.001]);
    assert!(e.contains("--snapshots") && e.contains("10s"), "{e}");
    assert!(!d.join("r.exr").exists(), "refused before any work");
}

#[test]
fn compare_single_run_gives_a_row_per_budget() {
    let d = tmp_dir("snapshots-compare");
    let refp = d.join("ref");
    render_film(&job(&cornell(), Method::Pt, 16, 99, RES, 2, &refp));
    let (out, scene, reference) = (d.join("cmp"), cornell(), with_ext(&refp, "exr"));
    let args = [
        "forecast",
        "compare",
        scene.to_str().unwrap(),
        "--methods",
        "pt",
        "--budgets",
        "2s,1s",
        "--seeds",
        "1",
        "--single-run",
        "--threads",
        "2",
        "--reference",
        reference.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ];
    let Ok(Cli { command: Command::Compare(ca), .. }) = Cli::try_parse_from(args) else { panic!("compare parses") };
    let t = Instant::now();
    let o = forecast::compare::run_compare(&ca.config(), &Local::new()).unwrap().unwrap();
    assert!(t.elapsed().as_secs_f64() < 4.0, "one 2-s render, not one per budget");
    assert!(o.single_run);
    let rows: Vec<(f64, bool)> = o.runs.iter().map(|r| (r.budget_s, r.from_snapshot)).collect();
    assert_eq!(rows, [(2.0, false), (1.0, true)], "the budgets' order, the smaller from a snapshot");
    for r in &o.runs {
        assert!(r.error.is_none(), "{r:?}");
        assert!(r.spp > 0 && r.regions.iter().all(|e| e.rel_mse.is_finite() && e.rel_mse > 0.0), "{r:?}");
    }
    let (big, small) = (&o.runs[0], &o.runs[1]);
    assert!(small.wall_s >= 1.0 && small.wall_s <= big.wall_s && small.spp <= big.spp, "{small:?} {big:?}");
    assert_eq!(small.prefix, snapshot_prefix(&big.prefix, "1s"));
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(md.contains("Single run (--single-run)") && md.contains("ok (snapshot)"), "{md}");
    let j: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("results.json")).unwrap()).unwrap();
    assert_eq!(j["single_run"], true);
    let svg = std::fs::read_to_string(out.join("charts/relmse-time-full.svg")).unwrap();
    assert!(svg.lines().any(|l| l.trim() == "pt"), "the chart has a line labelled pt");
}
