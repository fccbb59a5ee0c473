//! `forecast reference`: a long `pt` render made of two independent halves, so that noise can be
//! told apart from bias (`forecast diff TEST.exr REF.exr --half0 REF.half0.exr --half1 REF.half1.exr`).
//!
//! * Half `k` is an ordinary `pt` render with seed [`half_seed`]`(seed, k)` (the two seeds differ,
//!   so their sample streams are independent) written to `PREFIX.half{k}.{exr,png,json}`.
//! * Time: both halves count from the same start; half 0 stops at `T/2`, half 1 at `T`, so each
//!   gets about half the budget. With `--spp N` each half renders `ceil(N/2)` passes.
//! * `PREFIX.exr` is the pooled mean of both halves (their film sums added) with the `var.*`
//!   variance-of-mean channels; `PREFIX.json` holds the totals and both halves' reports.
//! * Resumable: each half always writes `PREFIX.half{k}.ckpt` at the end (and every
//!   `--checkpoint-every`); `--resume PREFIX` (or `PREFIX.ckpt`) continues both halves, adding
//!   passes for the new budget. Under MPI both halves are collective renders; rank 0 writes.

use crate::distributed::Cluster;
use crate::image_io::with_ext;
use crate::integrators::Method;
use crate::pipeline::{self, RenderReport};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Seed of half `k` (0 or 1) of a reference with base seed `seed`. Offset far from the small
/// seeds a comparison uses (`seed + i`), so the reference is independent of the runs it judges.
pub fn half_seed(seed: u64, k: u64) -> u64 {
    seed.wrapping_add(0x5EED_0000_0000).wrapping_add(0x9E37_79B9 * (k + 1))
}

/// The output prefix of half `k`.
pub fn half_prefix(prefix: &Path, k: u64) -> PathBuf {
    with_ext(prefix, &format!("half{k}"))
}

/// `--resume` accepts the reference prefix or `PREFIX.ckpt`; returns the prefix.
fn resume_prefix(p: &Path) -> PathBuf {
    let s = p.to_string_lossy();
    PathBuf::from(s.strip_suffix(".ckpt").unwrap_or(&s).to_string())
}

/// The output guard (`atomic_io::OutputSet`) of a reference: the scene and its meshes against
/// `PREFIX.{exr,png,json}` and each half's `PREFIX.half{k}.{exr,png,json,ckpt}`.
fn reference_guard(base: &pipeline::RenderJob, scene: &crate::scene::Scene) -> crate::atomic_io::OutputSet {
    let mut g = crate::atomic_io::OutputSet::new();
    g.scene_inputs(&base.scene, &scene.mesh_files);
    for e in ["exr", "png", "json"] {
        g.output("--out", &with_ext(&base.out, e));
    }
    for (k, e) in (0..2).flat_map(|k| ["exr", "png", "json", "ckpt"].map(|e| (k, e))) {
        g.output("--out", &with_ext(&half_prefix(&base.out, k), e));
    }
    g
}

/// The files of a reference.
#[derive(Clone, Debug, serde::Serialize)]
pub struct ReferenceFiles {
    /// The mean EXR.
    pub mean: PathBuf,
    /// Half 0's EXR.
    pub half0: PathBuf,
    /// Half 1's EXR.
    pub half1: PathBuf,
    /// The two halves' checkpoints.
    pub checkpoints: [PathBuf; 2],
}

/// The reference's JSON summary (`PREFIX.json`).
#[derive(Clone, Debug, serde::Serialize)]
pub struct ReferenceReport {
    /// Always `reference`.
    pub kind: &'static str,
    /// Always `pt`.
    pub method: Method,
    /// Scene file.
    pub scene: String,
    /// Image size.
    pub resolution: [u32; 2],
    /// Samples per pixel of the mean (both halves).
    pub spp: u64,
    /// Base seed.
    pub seed: u64,
    /// The halves' seeds.
    pub half_seeds: [u64; 2],
    /// Time budget, seconds.
    pub time_budget_s: Option<f64>,
    /// Wall time, seconds.
    pub total_s: f64,
    /// Files written.
    pub files: ReferenceFiles,
    /// NaN/Inf samples replaced by zero (both halves).
    pub nonfinite_samples: u64,
    /// Non-finite pixels in the mean.
    pub nonfinite_pixels: usize,
    /// Mean of the image per channel.
    pub image_mean: [f64; 3],
    /// Scene warnings.
    pub warnings: Vec<String>,
    /// The halves' render reports.
    pub halves: [RenderReport; 2],
}

/// Renders the reference of `base` (the `reference` command's settings, as a render job: its
/// method must be `pt` or unset) on every rank of `cluster`; returns rank 0's summary (also
/// written to `PREFIX.json`).
pub fn run_reference(
    base: &pipeline::RenderJob,
    cluster: &dyn Cluster,
    started: Instant,
) -> Result<Option<ReferenceReport>, String> {
    if base.method.is_some_and(|m| m != Method::Pt.into()) {
        return Err("reference: only `--method pt` (the unbiased reference) is supported".into());
    }
    if base.args.pt.path_filter.is_some() {
        return Err("reference: --path-filter is a `render` diagnostic (a reference is unbiased)".into());
    }
    if !base.snapshots.is_empty() {
        return Err("reference: --snapshots is a `render` option (the reference is two half renders)".into());
    }
    crate::atomic_io::check_output_prefix(&base.out)?;
    crate::atomic_io::check_input("scene file", &base.scene)?;
    let scene = crate::scene::load_with(&base.scene, &base.load_options()).map_err(|e| e.to_string())?;
    reference_guard(base, &scene).not_writer(cluster.rank() != 0).check()?; // each half's render checks its own resume too
    let plan = pipeline::RenderJob { method: Some(Method::Pt.into()), ..base.clone() }.resolve(&scene)?;
    let prefix = base.out.clone();
    let resume = base.resume.as_deref().map(resume_prefix);
    if let Some(dir) = prefix.parent().filter(|d| !d.as_os_str().is_empty() && cluster.rank() == 0) {
        std::fs::create_dir_all(dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    }
    let mut results = Vec::new();
    for k in 0..2u64 {
        let job = half_job(base, &plan, k, resume.as_deref(), cluster.rank())?;
        results.push(pipeline::render(&job, cluster, started)?);
    }
    let (Some(h1), Some(h0)) = (results.pop().flatten(), results.pop().flatten()) else { return Ok(None) };
    write_mean(&prefix, h0, h1, &plan, started).map(Some)
}

/// The render job of half `k`: `pt` with the half's seed, half the passes (or the first or
/// whole time budget), always checkpointed; resuming from `resume`'s half checkpoint, which
/// must exist (checked on rank 0).
fn half_job(
    base: &pipeline::RenderJob,
    plan: &pipeline::Plan,
    k: u64,
    resume: Option<&Path>,
    rank: usize,
) -> Result<pipeline::RenderJob, String> {
    let resume_k = resume.map(|r| with_ext(&half_prefix(r, k), "ckpt"));
    if let Some(r) = &resume_k {
        if rank == 0 && !r.exists() {
            return Err(format!("{}: cannot resume the reference: half checkpoint missing", r.display()));
        }
    }
    Ok(pipeline::RenderJob {
        method: Some(Method::Pt.into()),
        spp: plan.spp.map(|s| s.div_ceil(2)),
        time: plan.time.map(|t| t * (k + 1) as f64 / 2.0),
        seed: Some(half_seed(plan.seed, k)),
        out: half_prefix(&base.out, k),
        checkpoint_every: Some(base.checkpoint_every.unwrap_or(f64::INFINITY)),
        resume: resume_k,
        checkpoint_path: None,
        ..base.clone()
    })
}

/// Rank 0: the pooled mean of the two halves (`PREFIX.exr`, `.png`) and the summary
/// (`PREFIX.json`), written as one set.
fn write_mean(
    prefix: &Path,
    h0: pipeline::RenderResult,
    h1: pipeline::RenderResult,
    plan: &pipeline::Plan,
    started: Instant,
) -> Result<ReferenceReport, String> {
    let (seed, time) = (plan.seed, plan.time);
    let mut film = h0.film.clone();
    if film.data.len() != h1.film.data.len() {
        return Err(format!("{}: the two halves have different sizes", prefix.display()));
    }
    film.merge(&h1.film);
    let mut outputs = crate::atomic_io::FileSet::new(); // mean EXR, PNG and JSON as one set
    let mean = pipeline::image_files(prefix, &film, &mut outputs)?;
    let nonfinite_pixels = mean.pixels.iter().filter(|p| p.iter().any(|v| !v.is_finite())).count();
    let half = |k: u64, ext: &str| with_ext(&half_prefix(prefix, k), ext);
    let report = ReferenceReport {
        kind: "reference",
        method: Method::Pt,
        scene: h0.report.scene.clone(),
        resolution: h0.report.resolution,
        spp: h0.report.spp + h1.report.spp,
        seed,
        half_seeds: [half_seed(seed, 0), half_seed(seed, 1)],
        time_budget_s: time,
        total_s: started.elapsed().as_secs_f64(),
        files: ReferenceFiles {
            mean: with_ext(prefix, "exr"),
            half0: half(0, "exr"),
            half1: half(1, "exr"),
            checkpoints: [half(0, "ckpt"), half(1, "ckpt")],
        },
        nonfinite_samples: h0.report.nonfinite_samples + h1.report.nonfinite_samples,
        nonfinite_pixels,
        image_mean: mean.mean(),
        warnings: h0.report.warnings.clone(),
        halves: [h0.report, h1.report],
    };
    let text = serde_json::to_string_pretty(&report).map_err(|e| e.to_string())?;
    outputs.add(with_ext(prefix, "json"), text.into_bytes());
    outputs.write()?;
    Ok(report)
}

/// Checks, before any rendering, that the reference EXR `reference` was rendered from `scene`:
/// its `REF.json` (the `render` report or the `reference` summary beside `REF.exr`) records the
/// scene path, which must name the same file as `scene` (`atomic_io::same_file`: resolved paths,
/// links, inodes; a relative recorded path is taken from the current directory). A recorded path
/// that no longer exists is compared by file name. A mismatch is an error naming both scenes and
/// the JSON. `Ok(Some(line))` is a line to print: no readable JSON beside the reference (e.g. a
/// Mitsuba EXR), so the scene could not be checked, or the check was by file name only.
pub fn check_scene(reference: &Path, scene: &Path) -> Result<Option<String>, String> {
    let json = reference.with_extension("json");
    let unchecked = |why: String| {
        let r = reference.display();
        Ok(Some(format!("warning: compare: {why}; the scene of the reference {r} could not be checked")))
    };
    if !json.exists() {
        return unchecked(format!("no {} beside the reference", json.display()));
    }
    let recorded = match recorded_scene(&json) {
        Ok(s) => s,
        Err(e) => return unchecked(e),
    };
    let rec = Path::new(&recorded);
    let mismatch = |how: &str| {
        Err(format!(
            "compare: the reference {} was rendered from the scene {recorded} (as {} records{how}), not from {}; \
             compare against a reference of this scene (`forecast reference {} --out PREFIX`)",
            reference.display(),
            json.display(),
            scene.display(),
            scene.display()
        ))
    };
    if rec.exists() {
        return if crate::atomic_io::same_file(rec, scene) { Ok(None) } else { mismatch("") };
    }
    if rec.file_name().is_some() && rec.file_name() == scene.file_name() {
        return Ok(Some(format!(
            "warning: compare: the scene {recorded} recorded in {} no longer exists; the reference was matched \
             to {} by file name only",
            json.display(),
            scene.display()
        )));
    }
    mismatch("; that path no longer exists, so the file names were compared")
}

/// The `scene` a render report or reference summary (`PREFIX.json`) records.
fn recorded_scene(json: &Path) -> Result<String, String> {
    let bytes = crate::atomic_io::read_regular(json).map_err(|e| format!("{}: {e}", json.display()))?;
    let v: serde_json::Value =
        serde_json::from_slice(&bytes).map_err(|e| format!("{}: not a JSON report ({e})", json.display()))?;
    match v.get("scene").and_then(|s| s.as_str()) {
        Some(s) => Ok(s.to_string()),
        None => Err(format!("{} records no `scene`", json.display())),
    }
}
