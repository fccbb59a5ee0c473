//! `forecast compare`, `reference` and `stability`: ROI scaling and metrics against hand-computed
//! values, chart file validity, the comparison end to end on a 16×16 Cornell box, the reference's
//! halves, and the stability suite (every run finishes with finite output; the expected warnings
//! fire and reach the JSON).

mod common;

use clap::Parser;
use common::{root, tmp_dir};
use forecast::cli::{Cli, Command};
use forecast::compare::{self, stability, Region};
use forecast::distributed::local::Local;
use forecast::image_io::{self, Image};
use forecast::integrators::Method;
use std::path::Path;
use std::time::Instant;

fn cli(args: &[&str]) -> Command {
    Cli::try_parse_from(std::iter::once("forecast").chain(args.iter().copied())).expect("CLI parses").command
}

fn png_dims(path: &Path) -> (u32, u32) {
    let b = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    assert_eq!(&b[..8], b"\x89PNG\r\n\x1a\n", "{} is not a PNG", path.display());
    assert_eq!(&b[12..16], b"IHDR");
    (u32::from_be_bytes(b[16..20].try_into().unwrap()), u32::from_be_bytes(b[20..24].try_into().unwrap()))
}

fn assert_svg(path: &Path) {
    let s = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    assert!(s.trim_start().starts_with("<svg"), "{} does not start with <svg", path.display());
    assert!(s.trim_end().ends_with("</svg>"), "{} is not a complete SVG", path.display());
}

#[test]
fn roi_scaling_by_hand() {
    // Cornell's glass-caustic ROI from 640² to 16²: x 8.25→8, right 13.25→14; y 13, bottom 15.5→16.
    assert_eq!(compare::scale_roi([330, 520, 200, 100], (640, 640), (16, 16)), Some((8, 13, 6, 3)));
    // Same resolution: unchanged.
    assert_eq!(compare::scale_roi([330, 520, 200, 100], (640, 640), (640, 640)), Some((330, 520, 200, 100)));
    // Upscaling doubles.
    assert_eq!(compare::scale_roi([3, 4, 5, 6], (10, 10), (20, 20)), Some((6, 8, 10, 12)));
    // A 1-pixel ROI never vanishes; one leaving the image is clamped; one outside is dropped.
    assert_eq!(compare::scale_roi([0, 0, 1, 1], (640, 640), (16, 16)), Some((0, 0, 1, 1)));
    assert_eq!(compare::scale_roi([0, 0, 0, 0], (640, 640), (16, 16)), Some((0, 0, 1, 1)));
    assert_eq!(compare::scale_roi([600, 600, 100, 100], (640, 640), (64, 64)), Some((60, 60, 4, 4)));
    assert_eq!(compare::scale_roi([700, 0, 10, 10], (640, 640), (64, 64)), None);
    // Another aspect ratio: the frame scales by to.h/from.h = 2 about its centre (vertical field
    // of view), so 100×50 → 50×100 keeps only the middle quarter of the width: x = 10..20 lies at
    // 25 + (10 − 50)·2 = −55..−35, outside; x = 45..55 at 15..35; y doubles.
    assert_eq!(compare::scale_roi([10, 10, 10, 10], (100, 50), (50, 100)), None);
    assert_eq!(compare::scale_roi([45, 10, 10, 10], (100, 50), (50, 100)), Some((15, 20, 20, 20)));
    // figurines' knot caustic, 640×360 → 640×640: x 138..269 → 320 + (x − 320)·16/9 = −3.6..229.3
    assert_eq!(compare::scale_roi([138, 181, 131, 90], (640, 360), (640, 640)), Some((0, 321, 230, 161)));
}

/// A scene point and the ROI pixel it falls in stay together when the render changes the
/// aspect ratio: `scale_roi` of the point's pixel at the camera's resolution contains the pixel
/// the camera projects it to at the render's (figurines' frame, its two caustics' centres).
#[test]
fn roi_scaling_follows_the_camera() {
    use forecast::math::Vec3;
    use forecast::scene::Camera;
    let cam = |w, h| Camera::new(Vec3::new(0.05, 2.0, 1.95), Vec3::new(0.05, 0.88, -0.12), Vec3::Y, 30.0, w, h);
    for p in [Vec3::new(-0.3, 0.8, 0.05), Vec3::new(0.2, 0.8, 0.05), Vec3::new(0.0, 0.8, -0.2)] {
        let (sx, sy) = cam(640, 360).project(p).unwrap();
        for to in [(640, 640), (256, 256), (320, 180), (1280, 360)] {
            let (tx, ty) = cam(to.0, to.1).project(p).unwrap();
            let (x, y, w, h) = compare::scale_roi([sx as u32, sy as u32, 1, 1], (640, 360), to).unwrap();
            let inside = (x as f32..(x + w) as f32).contains(&tx) && (y as f32..(y + h) as f32).contains(&ty);
            assert!(inside, "{p:?} → {to:?}: pixel ({tx}, {ty}) outside the scaled ROI {:?}", (x, y, w, h));
        }
    }
}

#[test]
fn metrics_of_regions_by_hand() {
    // 2×2 grey images; only pixel (1,0) differs by 1 in every channel, reference value 1.
    let reference = Image::from_fn(2, 2, |_, _| [1.0; 3]);
    let img = Image::from_fn(2, 2, |x, y| if (x, y) == (1, 0) { [2.0; 3] } else { [1.0; 3] });
    let regions = vec![
        Region { name: "full".into(), rect: None },
        Region { name: "hit".into(), rect: Some((1, 0, 1, 1)) },
        Region { name: "miss".into(), rect: Some((0, 1, 2, 1)) },
    ];
    let m = compare::measure(&img, &reference, &regions).unwrap();
    // full: MSE = 1/4 → RMSE 0.5; relMSE = (1/(1+0.01))/4.
    assert!((m[0].rmse - 0.5).abs() < 1e-12, "{m:?}");
    assert!((m[0].rel_mse - 0.25 / 1.01).abs() < 1e-12, "{m:?}");
    assert!((m[1].rmse - 1.0).abs() < 1e-12 && (m[1].rel_mse - 1.0 / 1.01).abs() < 1e-12, "{m:?}");
    assert_eq!((m[2].rmse, m[2].rel_mse), (0.0, 0.0));
    // A region outside the image is an error, not a panic.
    let bad = [Region { name: "out".into(), rect: Some((1, 1, 2, 2)) }];
    assert!(compare::measure(&img, &reference, &bad).is_err());
}

#[test]
fn budgets_and_methods_parse() {
    let parse = |extra: &[&str]| {
        let args = [&["compare", "s.toml", "--reference", "r.exr"], extra].concat();
        Cli::try_parse_from(std::iter::once("forecast").chain(args.iter().copied()))
    };
    let Ok(Cli { command: Command::Compare(ca), .. }) = parse(&[]) else { panic!("compare parses") };
    let cfg = ca.config();
    assert_eq!(cfg.budgets, vec![30.0, 60.0, 120.0, 240.0]);
    assert_eq!(cfg.methods, vec![Method::Pt, Method::IwsPm, Method::IwsCf, Method::PtCf]);
    let Ok(Cli { command: Command::Compare(ca), .. }) = parse(&["--budgets", "500ms,2m", "--methods", "iws,pt"]) else {
        panic!("compare parses")
    };
    assert_eq!((ca.config().budgets, ca.methods), (vec![0.5, 120.0], vec![Method::Iws, Method::Pt]));
    assert!(parse(&["--budgets", ""]).is_err());
    assert!(parse(&["--budgets", "0s"]).is_err());
    assert!(parse(&["--methods", "pt,nope"]).is_err());
    assert_eq!(
        [0.5, 1.0, 30.0, 60.0, 240.0, 90.0].map(compare::budget_label),
        ["500ms", "1s", "30s", "1m", "4m", "90s"].map(String::from)
    );
}

#[test]
fn chart_files_are_valid_svg_and_png() {
    let d = tmp_dir("compare-chart");
    let s = vec![forecast::chart::Series {
        label: "pt".into(),
        points: vec![(1.0, 1e-2), (2.0, 5e-3), (4.0, 2.5e-3)],
        band: Some(vec![(1.0, 8e-3, 1.2e-2), (2.0, 4e-3, 6e-3), (4.0, 2e-3, 3e-3)]),
    }];
    let (svg, png) = (d.join("c.svg"), d.join("c.png"));
    forecast::chart::line_chart_loglog(&svg, &png, "t", "x", "y", &s, Some(-1.0)).unwrap();
    assert_svg(&svg);
    assert_eq!(png_dims(&png), forecast::chart::DEFAULT_SIZE);
}

#[test]
fn reference_halves_and_compare_end_to_end() {
    let d = tmp_dir("compare-e2e");
    let scene = root().join("scenes/cornell-box.toml");
    let (scene_s, refp) = (scene.to_str().unwrap(), d.join("ref"));
    // Reference: two independent 32-spp halves at 16×16.
    let Command::Reference(ra) = cli(&[
        "reference",
        scene_s,
        "--resolution",
        "16x16",
        "--spp",
        "64",
        "--quiet",
        "--out",
        refp.to_str().unwrap(),
    ]) else {
        panic!("not a reference command")
    };
    let rep = compare::reference::run_reference(&ra.job(), &Local::new(), Instant::now()).unwrap().unwrap();
    assert_eq!(rep.spp, 64);
    let read = |s: &str| image_io::read_exr(&d.join(s)).unwrap();
    let (mean, h0, h1) = (read("ref.exr"), read("ref.half0.exr"), read("ref.half1.exr"));
    assert!(image_io::read_exr_variance(&d.join("ref.exr")).unwrap().is_some(), "reference lacks var.* channels");
    assert_ne!(h0.pixels, h1.pixels, "halves must be independent");
    for ((m, a), b) in mean.pixels.iter().zip(&h0.pixels).zip(&h1.pixels) {
        for c in 0..3 {
            assert!((m[c] - 0.5 * (a[c] + b[c])).abs() <= 1e-5 * (1.0 + m[c].abs()), "mean is not the halves' average");
        }
    }
    assert!(d.join("ref.half0.ckpt").exists() && d.join("ref.half1.ckpt").exists(), "reference is not resumable");

    // Comparison: pt and iws-cf, 1 s and 2 s, one seed.
    let out = d.join("cmp");
    let Command::Compare(ca) = cli(&[
        "compare",
        scene_s,
        "--methods",
        "pt,iws-cf",
        "--budgets",
        "1s,2s",
        "--seeds",
        "1",
        "--forecast-photons",
        "20000",
        "--threads",
        "2",
        "--reference",
        d.join("ref.exr").to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]) else {
        panic!("not a compare command")
    };
    let cfg = ca.config();
    assert_eq!(cfg.out, out);
    let o = compare::run_compare(&cfg, &Local::new()).unwrap().unwrap();
    assert_eq!(o.runs.len(), 4);
    assert_eq!(
        o.regions.iter().map(|r| r.name.as_str()).collect::<Vec<_>>(),
        ["full", "glass-caustic", "wall-caustic"]
    );
    for r in &o.runs {
        assert!(r.error.is_none(), "{} {}: {:?}", r.method, r.budget_s, r.error);
        assert!(r.spp > 0 && r.wall_s > 0.0 && r.wall_s < r.budget_s + 2.0, "{r:?}");
        assert!((0.0..=1.0).contains(&r.preprocess_share), "{r:?}");
        assert_eq!(r.regions.len(), 3);
        assert!(r.regions.iter().all(|e| e.rmse.is_finite() && e.rel_mse.is_finite() && e.rel_mse > 0.0), "{r:?}");
    }
    // results.json holds the same numbers.
    let j: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("results.json")).unwrap()).unwrap();
    let runs = j["runs"].as_array().unwrap();
    assert_eq!(runs.len(), 4);
    assert!(runs.iter().all(|r| r["regions"][1]["rel_mse"].as_f64().is_some_and(|v| v > 0.0)));
    // Every artifact exists and is valid.
    for region in ["full", "glass-caustic"] {
        for kind in ["time", "spp"] {
            assert_svg(&out.join(format!("charts/relmse-{kind}-{region}.svg")));
            assert_eq!(png_dims(&out.join(format!("charts/relmse-{kind}-{region}.png"))), (800, 600));
        }
        let (w, h) = png_dims(&out.join(format!("strip-{region}.png")));
        assert!(w > h && h >= 160, "strip {region} is {w}x{h}");
        for m in ["reference", "pt", "iws-cf"] {
            png_dims(&out.join(format!("crops/{region}-{m}.png")));
        }
    }
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert!(md.contains("relMSE glass-caustic (mean)") && html.contains("charts/relmse-time-full.png"));
    // The summary table's rows carry numbers: method, budget, and a relMSE in scientific notation.
    let row = md.lines().find(|l| l.starts_with("| iws-cf | 2s |")).expect("summary row for iws-cf 2s");
    let cells: Vec<&str> = row.split('|').map(str::trim).collect();
    assert!(cells[7].parse::<f64>().is_ok_and(|v| v > 0.0), "relMSE cell `{}` in `{row}`", cells[7]);

    // A reference at another resolution is refused with the file named.
    let cfg2 = compare::CompareConfig {
        base: forecast::pipeline::RenderJob { resolution: Some((8, 8)), ..cfg.base.clone() },
        out: d.join("cmp2"),
        ..cfg
    };
    let e = compare::run_compare(&cfg2, &Local::new()).expect_err("resolution mismatch must fail");
    assert!(e.contains("ref.exr") && e.contains("16x16"), "{e}");
}

#[test]
fn scene_warnings_point_light_with_dirac_only() {
    let load = |p: &str| forecast::scene::load(&root().join(p)).unwrap();
    let w = stability::scene_warnings(&load("scenes/stability/point-glass.toml"));
    assert_eq!(w.len(), 1);
    assert!(w[0].contains(stability::POINT_LIGHT_WARNING) && w[0].contains("point-glass.toml"), "{w:?}");
    assert!(stability::scene_warnings(&load("scenes/cornell-box.toml")).is_empty());
    assert!(stability::scene_warnings(&load("scenes/stability/no-dirac.toml")).is_empty());
}

#[test]
fn iws_cf_equals_iws_without_dirac_objects() {
    let d = tmp_dir("compare-nodirac");
    let scene = root().join("scenes/stability/no-dirac.toml");
    let film = |m| common::render_film(&common::job(&scene, m, 2, 3, (16, 16), 2, &d.join(format!("{m:?}"))));
    let (a, b) = (film(Method::Iws), film(Method::IwsCf));
    assert_eq!(a.data, b.data, "iws-cf must reduce to iws when the scene has no Dirac objects");
}

#[test]
fn stability_suite_finishes_finite_with_warnings() {
    let d = tmp_dir("compare-stability");
    let cfg = stability::StabilityConfig {
        scenes: root().join("scenes/stability"),
        resolution: Some((16, 16)),
        time_per_run: 0.5,
        reference_time: 1.0,
        methods: vec![Method::Pt, Method::Iws, Method::IwsPm, Method::IwsCf],
        only: Vec::new(),
        threads: Some(2),
        out: d.clone(),
    };
    let recs = stability::run_suite(&cfg).unwrap();
    stability::write_stability_report(&d, &cfg, &recs).unwrap();
    assert_eq!(recs.len(), stability::CASES.len() * 4);
    for r in &recs {
        assert!(r.finished && !r.panicked, "{} {}: {:?}", r.case, r.method, r.error);
        assert!(r.image_finite, "{} {}: non-finite pixels", r.case, r.method);
        assert!(r.expected_warnings_ok, "{} {}: expected warnings missing: {:?}", r.case, r.method, r.warnings);
        assert!(r.rel_mse.is_some_and(f64::is_finite), "{} {}: no finite error vs the reference", r.case, r.method);
    }
    // The point-light warning reaches each run's JSON (pipeline), for every method.
    for m in ["pt", "iws", "iws-pm", "iws-cf"] {
        let p = d.join(format!("runs/point-glass_{m}.json"));
        let j: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&p).unwrap()).unwrap();
        let ws = j["warnings"].as_array().unwrap();
        assert!(ws.iter().any(|w| w.as_str().unwrap().contains(stability::POINT_LIGHT_WARNING)), "{}", p.display());
    }
    // Extreme bounds were applied: b differs by 1e12 between the two cases.
    let b = |case: &str| recs.iter().find(|r| r.case == case && r.method == "iws").and_then(|r| r.b).unwrap();
    assert!((b("bound-1e6") / b("bound-1e-6") / 1e12 - 1.0).abs() < 1e-3);
    let md = std::fs::read_to_string(d.join("stability.md")).unwrap();
    assert!(md.contains(&format!("{} of {} runs ok", recs.len(), recs.len())), "{md}");
    assert!(d.join("stability.html").exists() && d.join("stability.json").exists());
}

/// `compare` checks before any rendering that the reference was rendered from the scene being
/// compared (the scene its `REF.json` records): a Cornell reference against `ring.toml` is
/// refused with both scenes and the JSON named; the same scene (under another spelling) passes;
/// a recorded path that no longer exists is matched by file name; without a JSON it warns.
#[test]
fn reference_of_another_scene_is_refused() {
    let d = tmp_dir("compare-ref-scene");
    let (cornell, ring) = (root().join("scenes/cornell-box.toml"), root().join("scenes/ring.toml"));
    common::render_film(&common::job(&cornell, Method::Pt, 2, 1, (8, 8), 2, &d.join("ref")));
    let refp = d.join("ref.exr");
    let out = d.join("cmp");
    let args = ["compare", ring.to_str().unwrap(), "--methods", "pt", "--budgets", "1s", "--seeds", "1"];
    let rest = ["--threads", "2", "--reference", refp.to_str().unwrap(), "--out", out.to_str().unwrap()];
    let Command::Compare(ca) = cli(&[&args[..], &rest[..]].concat()) else { panic!("not a compare command") };
    let e = compare::run_compare(&ca.config(), &Local::new()).expect_err("another scene's reference must fail");
    assert!(e.contains("cornell-box.toml") && e.contains("ring.toml") && e.contains("ref.json"), "{e}");
    assert!(!out.join("runs").exists(), "refused before any rendering");

    let check = |scene: &Path, reference: &Path| compare::reference::check_scene(reference, scene);
    let respelled = root().join("scenes/../scenes/./cornell-box.toml");
    assert_eq!(check(&cornell, &refp), Ok(None));
    assert_eq!(check(&respelled, &refp), Ok(None), "paths are resolved");
    // A recorded scene that no longer exists: compared by file name, and said so.
    std::fs::copy(&refp, d.join("moved.exr")).unwrap();
    std::fs::write(d.join("moved.json"), r#"{"scene": "/gone/scenes/cornell-box.toml"}"#).unwrap();
    let w = check(&cornell, &d.join("moved.exr")).unwrap().expect("a note that only the name was compared");
    assert!(w.contains("no longer exists") && w.contains("file name"), "{w}");
    let e = check(&ring, &d.join("moved.exr")).expect_err("another file name must fail");
    assert!(e.contains("/gone/scenes/cornell-box.toml") && e.contains("ring.toml") && e.contains("moved.json"), "{e}");
    // No JSON beside the reference (a Mitsuba EXR): one warning line, no error.
    let mitsuba = root().join("tests/reference/cornell-box-mitsuba-256.exr");
    let w = check(&cornell, &mitsuba).unwrap().expect("a warning");
    assert!(w.contains("could not be checked") && !w.contains('\n'), "{w}");
}
