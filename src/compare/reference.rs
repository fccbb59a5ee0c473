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

use crate::cli::RenderArgs;
use crate::distributed::Cluster;
use crate::integrators::Method;
use crate::pipeline::{self, with_ext};
use serde_json::json;
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

/// Renders the reference on every rank of `cluster`; returns rank 0's JSON summary
/// (also written to `PREFIX.json`).
pub fn run_reference(
    args: &RenderArgs,
    cluster: &dyn Cluster,
    started: Instant,
) -> Result<Option<serde_json::Value>, String> {
    if args.method.is_some_and(|m| m != Method::Pt) {
        return Err("reference: only `--method pt` (the unbiased reference) is supported".into());
    }
    let base = args.job();
    crate::atomic_io::check_output_prefix(&base.out)?;
    let scene = crate::scene::load(&base.scene).map_err(|e| e.to_string())?;
    let seed = base.seed.unwrap_or(scene.render.seed);
    let time = base.time.or(if base.spp.is_some() { None } else { scene.render.time });
    let spp = if time.is_some() { None } else { Some(base.spp.or(scene.render.spp).unwrap_or(16)) };
    let prefix = base.out.clone();
    let resume = base.resume.as_deref().map(resume_prefix);
    if let Some(dir) = prefix.parent().filter(|d| !d.as_os_str().is_empty() && cluster.rank() == 0) {
        std::fs::create_dir_all(dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    }
    let mut results = Vec::new();
    for k in 0..2u64 {
        let resume_k = resume.as_ref().map(|r| with_ext(&half_prefix(r, k), "ckpt"));
        if let Some(r) = &resume_k {
            if cluster.rank() == 0 && !r.exists() {
                return Err(format!("{}: cannot resume the reference: half checkpoint missing", r.display()));
            }
        }
        let job = pipeline::RenderJob {
            method: Some(Method::Pt),
            spp: spp.map(|s| s.div_ceil(2)),
            time: time.map(|t| t * (k + 1) as f64 / 2.0),
            seed: Some(half_seed(seed, k)),
            out: half_prefix(&prefix, k),
            checkpoint_every: Some(base.checkpoint_every.unwrap_or(f64::INFINITY)),
            resume: resume_k,
            checkpoint_path: None,
            ..base.clone()
        };
        results.push(pipeline::render(&job, cluster, started)?);
    }
    let (Some(h1), Some(h0)) = (results.pop().flatten(), results.pop().flatten()) else { return Ok(None) };
    let mut film = h0.film.clone();
    if film.data.len() != h1.film.data.len() {
        return Err(format!("{}: the two halves have different sizes", prefix.display()));
    }
    film.merge(&h1.film);
    let mut outputs = crate::atomic_io::FileSet::new(); // mean EXR, PNG and JSON as one set
    let mean = pipeline::image_files(&prefix, &film, &mut outputs)?;
    let spp_total = h0.report["spp"].as_u64().unwrap_or(0) + h1.report["spp"].as_u64().unwrap_or(0);
    let nonfinite_pixels = mean.pixels.iter().filter(|p| p.iter().any(|v| !v.is_finite())).count();
    let report = json!({
        "kind": "reference",
        "method": "pt",
        "scene": h0.report["scene"],
        "resolution": h0.report["resolution"],
        "spp": spp_total,
        "seed": seed,
        "half_seeds": [half_seed(seed, 0), half_seed(seed, 1)],
        "time_budget_s": time,
        "total_s": started.elapsed().as_secs_f64(),
        "files": {
            "mean": with_ext(&prefix, "exr"),
            "half0": with_ext(&half_prefix(&prefix, 0), "exr"),
            "half1": with_ext(&half_prefix(&prefix, 1), "exr"),
            "checkpoints": [with_ext(&half_prefix(&prefix, 0), "ckpt"), with_ext(&half_prefix(&prefix, 1), "ckpt")],
        },
        "nonfinite_samples": h0.report["nonfinite_samples"].as_u64().unwrap_or(0)
            + h1.report["nonfinite_samples"].as_u64().unwrap_or(0),
        "nonfinite_pixels": nonfinite_pixels,
        "image_mean": mean.mean(),
        "warnings": h0.report["warnings"],
        "halves": [h0.report, h1.report],
    });
    let text = serde_json::to_string_pretty(&report).map_err(|e| e.to_string())?;
    outputs.add(with_ext(&prefix, "json"), text.into_bytes());
    outputs.commit()?;
    Ok(Some(report))
}
