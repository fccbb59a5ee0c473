//! The stability suite (`forecast stability`) and the scene warnings every render emits.
//!
//! * [`scene_warnings`] (re-exported from `scene`): the scene-level limitations every render
//!   prints and stores in its JSON `warnings`; the suite checks that they fire.
//! * [`run_suite`]: every [`CASES`] scene (`scenes/stability/`, 64×64 cameras) with every method,
//!   each a short time box. A run's error or panic is caught and recorded (never aborting the
//!   suite); per run: finished, NaN/Inf samples caught (`nonfinite_samples`), whether the image is
//!   finite, whether the expected warnings fired, relMSE and mean difference against the scene's
//!   `pt` reference (rendered by the suite with an independent seed), the time and spp.
//! * [`write_stability_report`]: `stability.json`, `stability.md`, `stability.html`.
//!
//! Single-process only (catching a panic on one MPI rank would leave the others waiting).

use super::report::{esc, html_page, table_html, table_md};
use crate::distributed::local::Local;
use crate::image_io::{atomic_write, Image};
use crate::integrators::{Method, MethodArgs};
use crate::metrics::{self, REL_MSE_EPS};
use crate::pipeline::{self, RenderJob, RenderResult};
use serde::Serialize;
use std::fmt::Write as _;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::time::Instant;

pub use crate::scene::{scene_warnings, POINT_LIGHT_WARNING};

/// One scene of the suite.
#[derive(Clone, Copy, Debug)]
pub struct Case {
    /// Case name.
    pub name: &'static str,
    /// Scene file name in the suite directory.
    pub file: &'static str,
    /// IWS bound `b` as a multiple of the default `0.25·π·N/A_D` (`None`: the default).
    pub bound_factor: Option<f64>,
    /// Substrings that must each appear in some warning of every run.
    pub expect_warnings: &'static [&'static str],
    /// What it tests.
    pub what: &'static str,
}

/// The suite.
pub const CASES: &[Case] = &[
    Case {
        name: "point-glass",
        file: "point-glass.toml",
        bound_factor: None,
        expect_warnings: &[POINT_LIGHT_WARNING],
        what: "point light casting a caustic through glass (pt and iws-cf cannot sample it)",
    },
    Case {
        name: "no-dirac",
        file: "no-dirac.toml",
        bound_factor: None,
        expect_warnings: &[],
        what: "no Dirac objects: iws-cf reduces to IWS and agrees with pt",
    },
    Case {
        name: "tiny-glass",
        file: "tiny-glass.toml",
        bound_factor: None,
        expect_warnings: &[],
        what: "a 1 cm glass sphere far from the light (few or no caustic points)",
    },
    Case {
        name: "thin-wall",
        file: "thin-wall.toml",
        bound_factor: None,
        expect_warnings: &[],
        what: "2 mm wall with a caustic on one side (photon-map light bleeding)",
    },
    Case {
        name: "light-in-shell",
        file: "light-in-shell.toml",
        bound_factor: None,
        expect_warnings: &[],
        what: "the only light inside a glass shell",
    },
    Case {
        name: "bound-1e-6",
        file: "cornell-small.toml",
        bound_factor: Some(1e-6),
        expect_warnings: &[],
        what: "IWS bound b = 1e-6 x default",
    },
    Case {
        name: "bound-1e6",
        file: "cornell-small.toml",
        bound_factor: Some(1e6),
        expect_warnings: &[],
        what: "IWS bound b = 1e6 x default",
    },
    Case {
        name: "degenerate-obj",
        file: "degenerate-obj.toml",
        bound_factor: None,
        expect_warnings: &["degenerate triangle", "NaN or zero vertex normals"],
        what: "OBJ with zero-area triangles, NaN/zero normals, duplicate vertices",
    },
    Case {
        name: "fireflies",
        file: "fireflies.toml",
        bound_factor: None,
        expect_warnings: &[],
        what: "a tiny, very bright light (fireflies)",
    },
];

/// What `forecast stability` does.
#[derive(Clone, Debug)]
pub struct StabilityConfig {
    /// Directory of the suite's scenes (`scenes/stability`).
    pub scenes: PathBuf,
    /// Resolution override (default: the scenes' 64×64).
    pub resolution: Option<(u32, u32)>,
    /// Time box per run, seconds.
    pub time_per_run: f64,
    /// Time of each scene's `pt` reference, seconds.
    pub reference_time: f64,
    /// Methods.
    pub methods: Vec<Method>,
    /// Only these cases (empty: all).
    pub only: Vec<String>,
    /// Worker threads.
    pub threads: Option<usize>,
    /// Output directory.
    pub out: PathBuf,
}

/// The outcome of one (case, method) run.
#[derive(Clone, Debug, Serialize)]
pub struct StabilityRecord {
    /// Case name.
    pub case: String,
    /// Method name.
    pub method: String,
    /// Finished without error or panic.
    pub finished: bool,
    /// It panicked (caught).
    pub panicked: bool,
    /// Error or panic message.
    pub error: Option<String>,
    /// Wall time of the run in seconds.
    pub wall_s: f64,
    /// spp reached.
    pub spp: u64,
    /// NaN/Inf samples caught by the renderer.
    pub nonfinite_samples: u64,
    /// Every pixel of the output is finite.
    pub image_finite: bool,
    /// The warnings of the run's JSON.
    pub warnings: Vec<String>,
    /// Every expected warning fired.
    pub expected_warnings_ok: bool,
    /// IWS bound `b` in use (`method_stats.b`), if the method has one.
    pub b: Option<f64>,
    /// relMSE against the scene's reference, if it has one.
    pub rel_mse: Option<f64>,
    /// Relative difference of mean luminance against the reference.
    pub mean_rel_diff: Option<f64>,
}

impl StabilityRecord {
    /// Finished, finite, and the expected warnings fired.
    pub fn ok(&self) -> bool {
        self.finished && self.image_finite && self.expected_warnings_ok
    }
}

fn panic_text(p: &(dyn std::any::Any + Send)) -> String {
    p.downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| p.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "panic".into())
}

/// Renders `job` single-process, turning a panic into `Err((message, true))`.
pub fn guarded_render(job: &RenderJob) -> Result<RenderResult, (String, bool)> {
    match catch_unwind(AssertUnwindSafe(|| pipeline::render(job, &Local::new(), Instant::now()))) {
        Ok(Ok(Some(r))) => Ok(r),
        Ok(Ok(None)) => Err(("no result".into(), false)),
        Ok(Err(e)) => Err((e.to_string(), false)),
        Err(p) => Err((format!("panic: {}", panic_text(p.as_ref())), true)),
    }
}

fn lum(m: [f64; 3]) -> f64 {
    0.2126 * m[0] + 0.7152 * m[1] + 0.0722 * m[2]
}

/// One run of the suite: a method with its parameters, a time box and a seed.
struct RunSpec<'a> {
    method: Method,
    args: &'a MethodArgs,
    time: f64,
    seed: u64,
}

fn job(scene: &Path, run: RunSpec, cfg: &StabilityConfig, out: PathBuf) -> RenderJob {
    RenderJob {
        scene: scene.to_path_buf(),
        method: Some(run.method.into()),
        args: run.args.clone(),
        spp: None,
        time: Some(run.time),
        seed: Some(run.seed),
        resolution: cfg.resolution,
        out,
        progress: false,
        checkpoint_every: None,
        resume: None,
        checkpoint_path: None,
        max_rounds: None,
        threads: cfg.threads,
        defines: Vec::new(),
        snapshots: Vec::new(),
        interrupt: Default::default(),
    }
}

/// Runs the suite; never stops at a failing run. Errors only for an unwritable output directory.
pub fn run_suite(cfg: &StabilityConfig) -> Result<Vec<StabilityRecord>, String> {
    if let Some(bad) = cfg.only.iter().find(|o| !CASES.iter().any(|c| c.name == o.as_str())) {
        let names: Vec<&str> = CASES.iter().map(|c| c.name).collect();
        return Err(format!("--only: no stability case `{bad}`; the cases are {}", names.join(", ")));
    }
    let runs_dir = cfg.out.join("runs");
    std::fs::create_dir_all(&runs_dir).map_err(|e| format!("cannot create {}: {e}", runs_dir.display()))?;
    let mut base = MethodArgs::default();
    base.pm.photons = 20_000;
    base.cf.forecast_photons = Some(20_000);
    let mut refs: Vec<(String, Option<Image>)> = Vec::new();
    let mut out = Vec::new();
    for case in CASES.iter().filter(|c| cfg.only.is_empty() || cfg.only.iter().any(|o| o == c.name)) {
        let scene_path = cfg.scenes.join(case.file);
        if !refs.iter().any(|(f, _)| f == case.file) {
            refs.push((case.file.to_string(), case_reference(case, &scene_path, &base, cfg)));
        }
        let reference = refs.iter().find(|(f, _)| f == case.file).and_then(|(_, i)| i.as_ref());
        let opts = case_args(case, &scene_path, &base);
        for &m in &cfg.methods {
            let prefix = runs_dir.join(format!("{}_{}", case.name, m.name()));
            let t = Instant::now();
            let spec = RunSpec { method: m, args: &opts, time: cfg.time_per_run, seed: 1 };
            let rec = match guarded_render(&job(&scene_path, spec, cfg, prefix)) {
                Ok(r) => finished_record(case, m, &r, reference),
                Err((e, panicked)) => failed_record(case, m, e, panicked, t.elapsed().as_secs_f64()),
            };
            crate::errln!(
                "stability: {:<15} {:<7} {} ({} spp, {:.2} s)",
                rec.case,
                rec.method,
                if rec.ok() { "ok" } else { "FAILED" },
                rec.spp,
                rec.wall_s
            );
            out.push(rec);
        }
    }
    Ok(out)
}

/// The `pt` reference of a case's scene (`None`, reported, when it fails).
fn case_reference(case: &Case, scene_path: &Path, base: &MethodArgs, cfg: &StabilityConfig) -> Option<Image> {
    let prefix = cfg.out.join("refs").join(case.file.trim_end_matches(".toml"));
    let spec = RunSpec { method: Method::Pt, args: base, time: cfg.reference_time, seed: 0x05EE_D4EF };
    match guarded_render(&job(scene_path, spec, cfg, prefix)) {
        Ok(r) => Some(pipeline::image_from_film(&r.film)),
        Err((e, _)) => {
            crate::errln!("stability: reference of {} failed: {e}", case.file);
            None
        }
    }
}

/// The suite's parameters with the case's IWS bound, if it sets one (`bound_factor` × the
/// scene's default bound; a scene that does not load keeps the default, reported).
fn case_args(case: &Case, scene_path: &Path, base: &MethodArgs) -> MethodArgs {
    let mut opts = base.clone();
    if let Some(f) = case.bound_factor {
        match crate::scene::load(scene_path) {
            Ok(s) => match crate::accel::World::build(s) {
                Ok(world) => {
                    let b = crate::integrators::iws::default_bound(&world, opts.iws.vpl_paths) as f64 * f;
                    opts.iws.bound = Some(b as f32);
                }
                Err(e) => crate::errln!("stability: {}: {e}", case.name),
            },
            Err(e) => crate::errln!("stability: {}: {e}", case.name),
        }
    }
    opts
}

/// The record of a run that finished, measured against the case's reference when it has one
/// of the same size.
fn finished_record(case: &Case, m: Method, r: &RenderResult, reference: Option<&Image>) -> StabilityRecord {
    let img = pipeline::image_from_film(&r.film);
    let warnings = r.report.warnings.clone();
    let cmp = reference.filter(|rf| rf.same_size(&img));
    StabilityRecord {
        case: case.name.into(),
        method: m.name().into(),
        finished: true,
        panicked: false,
        error: None,
        wall_s: r.report.timings.total_s,
        spp: r.report.spp,
        nonfinite_samples: r.report.nonfinite_samples,
        image_finite: img.pixels.iter().all(|p| p.iter().all(|v| v.is_finite())),
        expected_warnings_ok: case.expect_warnings.iter().all(|e| warnings.iter().any(|w| w.contains(e))),
        warnings,
        b: r.report.method_stats.get("b").and_then(|b| b.as_f64()),
        rel_mse: cmp.and_then(|rf| metrics::rel_mse(&img, rf, REL_MSE_EPS, None).ok()),
        mean_rel_diff: cmp.map(|rf| mean_rel_diff(&img, rf)),
    }
}

/// Relative difference of the mean luminance of `img` against `rf` (0 when both are black).
fn mean_rel_diff(img: &Image, rf: &Image) -> f64 {
    let (a, b) = (lum(img.mean()), lum(rf.mean()));
    if b > 0.0 {
        a / b - 1.0
    } else if a == 0.0 {
        0.0
    } else {
        f64::INFINITY
    }
}

/// The record of a run that failed or panicked after `wall` seconds.
fn failed_record(case: &Case, m: Method, error: String, panicked: bool, wall: f64) -> StabilityRecord {
    StabilityRecord {
        case: case.name.into(),
        method: m.name().into(),
        finished: false,
        panicked,
        error: Some(error),
        wall_s: wall,
        spp: 0,
        nonfinite_samples: 0,
        image_finite: false,
        warnings: Vec::new(),
        expected_warnings_ok: false,
        b: None,
        rel_mse: None,
        mean_rel_diff: None,
    }
}

fn opt_e(v: Option<f64>) -> String {
    v.map_or("–".into(), |v| format!("{v:.3e}"))
}

/// One row of the runs table.
fn run_row(r: &StabilityRecord) -> Vec<String> {
    vec![
        r.case.clone(),
        r.method.clone(),
        if r.ok() {
            "ok".into()
        } else if r.panicked {
            "PANIC".into()
        } else {
            "FAILED".into()
        },
        if r.image_finite { "yes".into() } else { "NO".into() },
        r.nonfinite_samples.to_string(),
        if r.expected_warnings_ok { "yes".into() } else { "MISSING".into() },
        r.spp.to_string(),
        format!("{:.2}", r.wall_s),
        opt_e(r.b),
        opt_e(r.rel_mse),
        r.mean_rel_diff.map_or("–".into(), |d| format!("{:+.1}%", 100.0 * d)),
        r.error.clone().unwrap_or_default(),
    ]
}

/// One row of the cases table: the case and every distinct warning its runs emitted.
fn case_row(c: &Case, recs: &[StabilityRecord]) -> Vec<String> {
    let mut ws: Vec<String> = Vec::new();
    for r in recs.iter().filter(|r| r.case == c.name) {
        for w in &r.warnings {
            if !ws.contains(w) {
                ws.push(w.clone());
            }
        }
    }
    vec![c.name.into(), c.file.into(), c.what.into(), ws.join(" / ")]
}

/// Writes `stability.json`, `stability.md` and `stability.html` into `dir`.
pub fn write_stability_report(dir: &Path, cfg: &StabilityConfig, recs: &[StabilityRecord]) -> Result<(), String> {
    std::fs::create_dir_all(dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    let json = serde_json::to_string_pretty(recs).map_err(|e| e.to_string())?;
    atomic_write(&dir.join("stability.json"), json.as_bytes())?;
    let headers: Vec<String> = [
        "case",
        "method",
        "result",
        "finite image",
        "NaN/Inf samples caught",
        "expected warnings",
        "spp",
        "time s",
        "b",
        "relMSE vs ref",
        "mean diff",
        "error",
    ]
    .map(String::from)
    .to_vec();
    let rows: Vec<Vec<String>> = recs.iter().map(run_row).collect();
    let n_ok = recs.iter().filter(|r| r.ok()).count();
    let summary = format!(
        "{n_ok} of {} runs ok. Time box {:.2} s per run; each scene's reference is a {:.2} s `pt` render with an \
         independent seed (for point-light caustics it is itself missing them, see the warnings). Resolution: {}.",
        recs.len(),
        cfg.time_per_run,
        cfg.reference_time,
        cfg.resolution.map_or("the scenes' own (64x64)".into(), |(w, h)| format!("{w}x{h}"))
    );
    let case_rows: Vec<Vec<String>> =
        CASES.iter().filter(|c| recs.iter().any(|r| r.case == c.name)).map(|c| case_row(c, recs)).collect();
    let case_h: Vec<String> = ["case", "scene", "what", "warnings emitted"].map(String::from).to_vec();
    let mut md = format!("# Stability suite\n\n{summary}\n\n## Runs\n\n{}\n## Cases\n\n", table_md(&headers, &rows));
    md.push_str(&table_md(&case_h, &case_rows));
    atomic_write(&dir.join("stability.md"), md.as_bytes())?;
    let mut body = format!("<p>{}</p>\n<h2>Runs</h2>\n{}", esc(&summary), table_html(&headers, &rows));
    let _ = write!(body, "<h2>Cases</h2>\n{}", table_html(&case_h, &case_rows));
    atomic_write(&dir.join("stability.html"), html_page("Stability suite", &body).as_bytes())?;
    Ok(())
}
