//! Time-boxed method comparisons: `forecast compare`, `forecast reference`, `forecast stability`.
//!
//! * [`run_compare`] renders every (method, budget, seed) as a time box (`RenderJob::time`,
//!   counted from just before the render starts, so scene loading and the caustic preprocess are
//!   inside the budget) and measures each result against a reference EXR: RMSE and relMSE
//!   (`metrics`, ε = 0.01) of the whole image and of every `[[roi]]` of the scene, spp reached
//!   and the preprocess share `preprocess_s / total_s`.
//! * Before any rendering, the reference must belong to the scene: the `REF.json` beside
//!   `REF.exr` must name the same scene file ([`reference::check_scene`]); without one (a Mitsuba
//!   EXR) a warning says the reference's scene could not be checked.
//! * Under MPI every rank runs the same loop (each render is collective and the whole job shares
//!   the budget); only rank 0 measures and writes. Failed runs are recorded, not fatal.
//! * ROIs are given at the scene camera's resolution; [`scale_roi`] maps them to the render
//!   resolution as the camera maps the scene (vertical field of view, square pixels: another
//!   aspect ratio crops or widens the sides), rounding outward, clamped to the image, never empty.
//!
//! * `--single-run` (`single_run`): each (method, seed) is rendered once at the largest budget
//!   with snapshots (`render --snapshots`) at the smaller ones; each smaller budget's row is
//!   measured from its snapshot image (spp, wall time = the snapshot's elapsed seconds). The
//!   report says so (`CompareOutcome::single_run`): the preprocess was sized for the largest budget.
//!
//! Submodules: [`reference`] (two independent halves + their mean), [`report`] (charts, crops,
//! `report.md`/`report.html`/`results.json`), `single_run`, [`stability`] (the edge-case suite and
//! the scene warnings every render emits).

pub mod reference;
pub mod report;
mod single_run;
pub mod stability;

use crate::atomic_io::OutputSet;
use crate::distributed::Cluster;
use crate::image_io::{self, with_ext, Image};
use crate::integrators::Method;
use crate::metrics::{self, Rect, REL_MSE_EPS};
use crate::pipeline::{self, RenderJob};
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// A named image region; `rect: None` is the whole image.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Region {
    /// `full` for the whole image, else the ROI's name.
    pub name: String,
    /// Crop `(x, y, w, h)` at the render resolution.
    pub rect: Option<Rect>,
}

/// Errors of one image in one region.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RegionError {
    /// Region name.
    pub region: String,
    /// Root mean squared error against the reference.
    pub rmse: f64,
    /// Relative MSE against the reference (ε = [`REL_MSE_EPS`]).
    pub rel_mse: f64,
}

/// One time-boxed run and its measurements.
#[derive(Clone, Debug, Serialize)]
pub struct RunRecord {
    /// Method name.
    pub method: String,
    /// Time budget in seconds.
    pub budget_s: f64,
    /// Seed index (0-based) within the comparison.
    pub seed_index: u64,
    /// The seed used.
    pub seed: u64,
    /// `None` when the run finished; else its error.
    pub error: Option<String>,
    /// Samples per pixel reached.
    pub spp: u64,
    /// Wall time of the run (`timings.total_s`).
    pub wall_s: f64,
    /// Preprocess time.
    pub preprocess_s: f64,
    /// `preprocess_s / wall_s`.
    pub preprocess_share: f64,
    /// Non-finite samples caught by the renderer.
    pub nonfinite_samples: u64,
    /// Errors per region (`full` first).
    pub regions: Vec<RegionError>,
    /// Output prefix of the run's images (`PREFIX.exr`, `.png`, `.json`; with `from_snapshot`,
    /// the snapshot's `PREFIX.exr` and `.json`).
    pub prefix: PathBuf,
    /// Measured from a snapshot of the (method, seed)'s one run at the largest budget
    /// (`--single-run`), not from a run of its own.
    pub from_snapshot: bool,
}

/// Maps an ROI rectangle given at resolution `from` to resolution `to`, as the camera does: the
/// field of view is vertical and pixels are square, so the frame scales by `s = to.h/from.h` about
/// its centre in both axes (a change of aspect ratio crops or widens the sides: at 640×640 a
/// 640×360 frame's x = 138 lies at 320 + (138 − 320)·s < 0). With the same aspect ratio this is
/// the plain `to/from` scaling. Edges round outward, clamped to the image; `None` if the ROI lies
/// outside it.
pub fn scale_roi(rect: [u32; 4], from: (u32, u32), to: (u32, u32)) -> Option<Rect> {
    let [x, y, w, h] = rect.map(i128::from);
    let (fw, fh) = (i128::from(from.0.max(1)), i128::from(from.1.max(1)));
    let (tw, th) = (i128::from(to.0), i128::from(to.1));
    // target x of source x, times 2·fh: tw/2 + (x − fw/2)·th/fh
    let xs = |x: i128| (2 * x - fw) * th + tw * fh;
    let (x0, x1) = (xs(x).div_euclid(2 * fh), (xs(x + w) + 2 * fh - 1).div_euclid(2 * fh));
    let (y0, y1) = ((y * th).div_euclid(fh), ((y + h) * th + fh - 1).div_euclid(fh));
    // y0 ≥ 0 always (the height is kept); only x can fall left of the image: a region ending at
    // or before 0 that starts before it (a zero-width one at 0 stays, as with the plain scaling)
    if x1 < 0 || (x1 == 0 && x0 < 0) || x0 >= tw || y0 >= th {
        return None;
    }
    let (x0, y0) = (x0.max(0), y0.max(0));
    let (x1, y1) = (x1.min(tw).max(x0 + 1), y1.min(th).max(y0 + 1));
    Some((x0 as usize, y0 as usize, (x1 - x0) as usize, (y1 - y0) as usize))
}

/// `full` plus every `[[roi]]` of `scene` that falls inside an image of `res` (scaled from the
/// camera resolution).
pub fn regions(scene: &crate::scene::Scene, res: (u32, u32)) -> Vec<Region> {
    let cam = (scene.camera.width, scene.camera.height);
    let mut v = vec![Region { name: "full".into(), rect: None }];
    for r in &scene.rois {
        if let Some(rect) = scale_roi(r.rect, cam, res) {
            v.push(Region { name: r.name.clone(), rect: Some(rect) });
        }
    }
    v
}

/// RMSE and relMSE of `img` against `reference` in every region.
pub fn measure(img: &Image, reference: &Image, regions: &[Region]) -> Result<Vec<RegionError>, String> {
    regions
        .iter()
        .map(|r| {
            Ok(RegionError {
                region: r.name.clone(),
                rmse: metrics::rmse(img, reference, r.rect)?,
                rel_mse: metrics::rel_mse(img, reference, REL_MSE_EPS, r.rect)?,
            })
        })
        .collect()
}

/// A budget as a short label: `500ms`, `30s`, `1.5s`, `4m`, `1h` (the label of a render's
/// snapshot at that time, `pipeline::snapshot_label`).
pub fn budget_label(secs: f64) -> String {
    pipeline::snapshot_label(secs)
}

/// What `forecast compare` does.
#[derive(Clone, Debug)]
pub struct CompareConfig {
    /// Base job: scene, options, resolution, threads (method, time, seed, out are replaced).
    pub base: RenderJob,
    /// Methods.
    pub methods: Vec<Method>,
    /// Budgets in seconds.
    pub budgets: Vec<f64>,
    /// Seeds per (method, budget).
    pub seeds: u64,
    /// Reference EXR.
    pub reference: PathBuf,
    /// Output directory.
    pub out: PathBuf,
    /// One render per (method, seed) at the largest budget; smaller budgets from its snapshots.
    pub single_run: bool,
}

/// The measured comparison (rank 0).
#[derive(Clone, Debug, Serialize)]
pub struct CompareOutcome {
    /// Scene file.
    pub scene: String,
    /// Reference EXR.
    pub reference: PathBuf,
    /// Render resolution.
    pub resolution: (u32, u32),
    /// Regions measured.
    pub regions: Vec<Region>,
    /// Every run, in order (method, budget, seed).
    pub runs: Vec<RunRecord>,
    /// `--single-run`: every (method, seed) was rendered once at the largest budget and the
    /// smaller budgets' rows were measured from snapshots of that run, so their preprocess (e.g.
    /// the CF photon count) was sized for the largest budget.
    pub single_run: bool,
    /// Warnings of the scene (also in every run's JSON).
    pub warnings: Vec<String>,
}

/// Rank 0: reads the reference, after checking that its JSON names this scene
/// ([`reference::check_scene`], whose warning is printed here), and decides the resolution: the
/// reference's, which `--resolution` must match.
fn load_reference(cfg: &CompareConfig) -> Result<(Image, (u32, u32)), String> {
    let img = image_io::read_exr(&cfg.reference)?;
    if let Some(line) = reference::check_scene(&cfg.reference, &cfg.base.scene)? {
        crate::errln!("{line}");
    }
    let rr = (img.width as u32, img.height as u32);
    match cfg.base.resolution {
        Some(r) if r != rr => Err(format!(
            "{}: reference is {}x{} but --resolution is {}x{}; render the reference at the same resolution",
            cfg.reference.display(),
            rr.0,
            rr.1,
            r.0,
            r.1
        )),
        _ => Ok((img, rr)),
    }
}

/// Rank 0 reads the reference and decides the resolution ([`load_reference`]); every rank learns
/// it (or the error).
fn agree_resolution(cfg: &CompareConfig, cluster: &dyn Cluster) -> Result<(Option<Image>, (u32, u32)), String> {
    let mut payload = Vec::new();
    let mut reference = None;
    if cluster.rank() == 0 {
        let decided = load_reference(cfg);
        payload = match decided {
            Ok((img, (w, h))) => {
                reference = Some(img);
                let mut p = vec![0u8];
                p.extend(w.to_le_bytes());
                p.extend(h.to_le_bytes());
                p
            }
            Err(e) => {
                let mut p = vec![1u8];
                p.extend(e.as_bytes());
                p
            }
        };
    }
    cluster.broadcast_bytes(&mut payload);
    match payload.first() {
        Some(0) if payload.len() == 9 => {
            let w = u32::from_le_bytes(payload[1..5].try_into().map_err(|_| "bad broadcast")?);
            let h = u32::from_le_bytes(payload[5..9].try_into().map_err(|_| "bad broadcast")?);
            Ok((reference, (w, h)))
        }
        _ => Err(String::from_utf8_lossy(payload.get(1..).unwrap_or_default()).into_owned()),
    }
}

/// What every run of one comparison shares.
struct Ctx<'a> {
    cfg: &'a CompareConfig,
    cluster: &'a dyn Cluster,
    /// The reference (rank 0 only: only rank 0 measures).
    reference: Option<&'a Image>,
    regions: &'a [Region],
    res: (u32, u32),
    base_seed: u64,
    runs_dir: PathBuf,
}

impl Ctx<'_> {
    /// The job of one render: `method` with `seed` under a `budget`, snapshots at `snapshots`.
    fn job(&self, method: Method, budget: f64, seed: u64, prefix: PathBuf, snapshots: Vec<f64>) -> RenderJob {
        RenderJob {
            method: Some(method.into()),
            time: Some(budget),
            spp: None,
            seed: Some(seed),
            resolution: Some(self.res),
            out: prefix,
            progress: false,
            checkpoint_every: None,
            resume: None,
            checkpoint_path: None,
            max_rounds: None,
            snapshots,
            ..self.cfg.base.clone()
        }
    }

    /// The output prefix of (method, budget, seed index).
    fn prefix(&self, method: Method, budget: f64, k: u64) -> PathBuf {
        run_prefix(&self.runs_dir, method, budget, k)
    }

    /// A record of (method, budget, seed index) before measuring.
    fn record(&self, method: Method, budget: f64, k: u64, prefix: PathBuf) -> RunRecord {
        RunRecord {
            method: method.name().into(),
            budget_s: budget,
            seed_index: k,
            seed: self.base_seed.wrapping_add(k),
            error: None,
            spp: 0,
            wall_s: 0.0,
            preprocess_s: 0.0,
            preprocess_share: 0.0,
            nonfinite_samples: 0,
            regions: Vec::new(),
            prefix,
            from_snapshot: false,
        }
    }

    /// Measures `img` (the image at `rec.prefix`) into `rec`.
    fn measure_into(&self, rec: &mut RunRecord, img: &Image) {
        let Some(reference) = self.reference else { return };
        match measure(img, reference, self.regions) {
            Ok(m) => rec.regions = m,
            Err(e) => rec.error = Some(format!("{}: {e}", with_ext(&rec.prefix, "exr").display())),
        }
    }

    /// Fills `rec` from a finished render (rank 0) and measures its film.
    fn fill_from_render(
        &self,
        rec: &mut RunRecord,
        result: &Result<Option<pipeline::RenderResult>, pipeline::RenderError>,
    ) {
        match result {
            Ok(Some(r)) => {
                let rep = &r.report;
                rec.spp = rep.spp;
                rec.wall_s = rep.timings.total_s;
                rec.preprocess_s = rep.timings.preprocess_s;
                rec.preprocess_share = rec.preprocess_s / rec.wall_s.max(1e-12);
                rec.nonfinite_samples = rep.nonfinite_samples;
                self.measure_into(rec, &pipeline::image_from_film(&r.film));
            }
            Ok(None) => rec.error = Some("no result on rank 0".into()),
            Err(e) => rec.error = Some(e.to_string()),
        }
    }

    /// One render per (budget, seed), as a separate time box.
    fn separate_runs(&self, method: Method) -> Vec<RunRecord> {
        let mut runs = Vec::new();
        for &budget in &self.cfg.budgets {
            for k in 0..self.cfg.seeds {
                let prefix = self.prefix(method, budget, k);
                let seed = self.base_seed.wrapping_add(k);
                let result = pipeline::render(
                    &self.job(method, budget, seed, prefix.clone(), Vec::new()),
                    self.cluster,
                    Instant::now(),
                );
                if self.reference.is_none() {
                    continue;
                }
                let mut rec = self.record(method, budget, k, prefix);
                self.fill_from_render(&mut rec, &result);
                log_record(&rec);
                runs.push(rec);
            }
        }
        runs
    }
}

/// `DIR/runs/METHOD_BUDGET_sK`: the output prefix of (method, budget, seed index).
fn run_prefix(runs_dir: &Path, method: Method, budget: f64, k: u64) -> PathBuf {
    runs_dir.join(format!("{}_{}_s{k}", method.name(), budget_label(budget)))
}

/// The comparison's output guard (`atomic_io::OutputSet`): its inputs (the scene, its meshes,
/// `--reference`) against every file it writes: each run's `PREFIX.{exr,png,json}` (with
/// `--single-run`, the largest budget's run and its snapshots), `results.json`, `report.md`,
/// `report.html`, and the `charts/` and `crops/` directories.
fn output_guard(cfg: &CompareConfig, scene: &crate::scene::Scene, runs_dir: &Path) -> OutputSet {
    let mut g = OutputSet::new();
    g.scene_inputs(&cfg.base.scene, &scene.mesh_files).input("--reference", &cfg.reference);
    let top = cfg.budgets.iter().copied().max_by(f64::total_cmp).unwrap_or(0.0);
    let mut labels = Vec::new();
    for &budget in &cfg.budgets {
        let label = budget_label(budget);
        if cfg.single_run && (labels.contains(&label) || (budget < top && label == budget_label(top))) {
            continue; // one snapshot per label (`single_runs` dedups them the same way)
        }
        labels.push(label.clone());
        for (method, k) in cfg.methods.iter().flat_map(|&m| (0..cfg.seeds).map(move |k| (m, k))) {
            if cfg.single_run && budget < top {
                let p = pipeline::snapshot_prefix(&run_prefix(runs_dir, method, top, k), &label);
                g.output("compare --single-run", &with_ext(&p, "exr"))
                    .output("compare --single-run", &with_ext(&p, "json"));
            } else {
                let p = run_prefix(runs_dir, method, budget, k);
                ["exr", "png", "json"].iter().for_each(|e| {
                    g.output("compare --out", &with_ext(&p, e));
                });
            }
        }
    }
    for f in ["results.json", "report.md", "report.html"] {
        g.output("compare --out", &cfg.out.join(f));
    }
    for d in ["charts", "crops"] {
        g.output_dir("compare --out", &cfg.out.join(d));
    }
    g
}

/// One line per run on stderr.
fn log_record(rec: &RunRecord) {
    let what = format!("compare: {} {} seed {}", rec.method, budget_label(rec.budget_s), rec.seed_index);
    let from = if rec.from_snapshot { " (snapshot)" } else { "" };
    match &rec.error {
        Some(e) => crate::errln!("{what}: FAILED: {e}"),
        None => crate::errln!(
            "{what}: {} spp in {:.2} s{from}, relMSE {:.4e}",
            rec.spp,
            rec.wall_s,
            rec.regions.first().map_or(f64::NAN, |r| r.rel_mse)
        ),
    }
}

/// Runs the comparison on every rank; returns `Some` on rank 0 (after writing the report).
pub fn run_compare(cfg: &CompareConfig, cluster: &dyn Cluster) -> Result<Option<CompareOutcome>, String> {
    if cfg.seeds == 0 {
        return Err("--seeds must be at least 1".into());
    }
    if !cfg.base.snapshots.is_empty() {
        return Err("compare: --snapshots is a `render` option; use --single-run".into());
    }
    if cfg.base.args.pt.path_filter.is_some() {
        return Err("compare: --path-filter is a `render` diagnostic (a filtered image has no reference)".into());
    }
    let b = &cfg.base;
    let unused = [
        ("--spp", b.spp.is_some()),
        ("--time", b.time.is_some()),
        ("--resume", b.resume.is_some()),
        ("--checkpoint-every", b.checkpoint_every.is_some()),
        ("--checkpoint-path", b.checkpoint_path.is_some()),
    ];
    if let Some((flag, _)) = unused.iter().find(|(_, set)| *set) {
        return Err(format!("compare: {flag} is a `render` option; compare's runs are time-boxed by --budgets"));
    }
    crate::atomic_io::check_input("scene file", &cfg.base.scene)?;
    let scene = crate::scene::load_with(&cfg.base.scene, &cfg.base.load_options()).map_err(|e| e.to_string())?;
    let runs_dir = cfg.out.join("runs");
    output_guard(cfg, &scene, &runs_dir).not_writer(cluster.rank() != 0).check()?;
    let (reference, res) = agree_resolution(cfg, cluster)?;
    let regions = regions(&scene, res);
    if cluster.rank() == 0 {
        std::fs::create_dir_all(&runs_dir).map_err(|e| format!("cannot create {}: {e}", runs_dir.display()))?;
    }
    let base_seed = cfg.base.seed.unwrap_or(scene.render.seed);
    let ctx = Ctx { cfg, cluster, reference: reference.as_ref(), regions: &regions, res, base_seed, runs_dir };
    let mut runs = Vec::new();
    for &method in &cfg.methods {
        runs.extend(if cfg.single_run { ctx.single_runs(method) } else { ctx.separate_runs(method) });
    }
    let Some(reference) = reference else { return Ok(None) };
    let outcome = CompareOutcome {
        scene: scene.path.clone(),
        reference: cfg.reference.clone(),
        resolution: res,
        regions,
        runs,
        single_run: cfg.single_run,
        warnings: {
            let mut w = scene.warnings.clone();
            w.extend(crate::scene::scene_warnings(&scene));
            w
        },
    };
    report::write_compare_report(&cfg.out, &outcome, &reference)?;
    Ok(Some(outcome))
}
