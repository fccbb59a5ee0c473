//! Snapshots (`render --snapshots 15s,30s,1m`): the image as it stood at intermediate wall-clock
//! times of one render, so that one run at the largest budget measures every smaller budget
//! (`compare --single-run`).
//!
//! At the first round boundary (stage 4) at or after each snapshot time, counted from the process
//! start like the `--time` budget (scene loading and the preprocess count), rank 0 gathers the
//! sums exactly as a checkpoint does (`Run::maybe_checkpoint`: one `all_reduce_max` to agree,
//! then the collective reduce) and writes `PREFIX.snap-LABEL.{exr,json}` as one
//! `atomic_io::FileSet` (`LABEL` is [`snapshot_label`]: `15s`, `1m`, as `compare`'s budget labels).
//!
//! Invariants: a snapshot only reads the film, so the final image is bit-identical with and
//! without snapshots for the same passes; `elapsed_s ≥ nominal_s`, and the passes of successive
//! snapshots never decrease. Snapshots due at the same boundary share its image. A write that
//! fails is a warning (it is not retried: its moment has passed); a snapshot the render ends
//! before is a warning too.

use super::{counter_sums, secs, Passes, Run};
use crate::atomic_io::FileSet;
use crate::image_io::{self, with_ext, Image};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// `PREFIX.snap-LABEL.json`: what a snapshot image holds and when it was taken.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SnapshotReport {
    /// Label of the nominal time (`15s`, `1m`), as in the file name.
    pub label: String,
    /// The requested time, seconds since the process started.
    pub nominal_s: f64,
    /// Seconds since the process started at the round boundary the image is from (≥ `nominal_s`).
    pub elapsed_s: f64,
    /// Passes in the image (contiguous from pass 0).
    pub passes: u64,
    /// Samples per pixel in the image.
    pub spp: u64,
    /// Preprocess seconds (rank 0), inside `elapsed_s`.
    pub preprocess_s: f64,
    /// Seconds of passes so far, inside `elapsed_s`.
    pub render_s: f64,
    /// NaN/Inf samples replaced by zero so far (all ranks).
    pub nonfinite_samples: u64,
    /// Method name.
    pub method: String,
    /// Scene file.
    pub scene: String,
    /// Seed.
    pub seed: u64,
    /// Image size.
    pub resolution: [u32; 2],
    /// The render's time budget (`None`: a fixed spp).
    pub time_budget_s: Option<f64>,
    /// MPI ranks.
    pub ranks: usize,
    /// Mean of the image, per channel.
    pub image_mean: [f64; 3],
}

/// `PREFIX.snap-LABEL` (add `.exr` / `.json` with `image_io::with_ext`).
pub fn snapshot_prefix(out: &Path, label: &str) -> PathBuf {
    with_ext(out, &format!("snap-{label}"))
}

/// A snapshot time (or a compare budget, `compare::budget_label`) as a short label: `500ms`,
/// `30s`, `1.5s`, `4m`, `1h`.
pub fn snapshot_label(secs: f64) -> String {
    if secs < 1.0 {
        format!("{}ms", (secs * 1000.0).round())
    } else if secs >= 3600.0 && secs % 3600.0 == 0.0 {
        format!("{}h", secs / 3600.0)
    } else if secs >= 60.0 && secs % 60.0 == 0.0 {
        format!("{}m", secs / 60.0)
    } else {
        format!("{}s", (secs * 100.0).round() / 100.0)
    }
}

/// Checks `--snapshots` against the time budget: every time positive and finite, earlier than
/// the budget (a snapshot at or after it would never be taken), labels distinct.
pub fn check_snapshots(times: &[f64], budget: Option<f64>) -> Result<(), String> {
    let mut labels: Vec<String> = Vec::new();
    for &t in times {
        let label = snapshot_label(t);
        if !(t.is_finite() && t > 0.0) {
            return Err(format!("--snapshots: {t} s is not a positive duration"));
        }
        if let Some(b) = budget.filter(|&b| t >= b) {
            return Err(format!(
                "--snapshots: {label} is not before the time budget of {} (--time or the scene's render.time); \
                 every snapshot must be earlier than the budget",
                snapshot_label(b)
            ));
        }
        if labels.contains(&label) {
            return Err(format!("--snapshots: two snapshots have the label `{label}`"));
        }
        labels.push(label);
    }
    Ok(())
}

/// The snapshot schedule of one render (the same on every rank) and rank 0's written reports.
#[derive(Debug, Default)]
pub(super) struct Snapshots {
    /// `(seconds, label)`, ascending.
    times: Vec<(f64, String)>,
    /// Index of the first snapshot not yet taken.
    next: usize,
    /// Rank 0: the snapshots written.
    pub(super) written: Vec<SnapshotReport>,
    /// Rank 0: seconds since the start at the last round boundary that looked for due snapshots.
    last_boundary_s: f64,
}

impl Snapshots {
    pub(super) fn new(times: &[f64]) -> Snapshots {
        let mut times: Vec<(f64, String)> = times.iter().map(|&t| (t, snapshot_label(t))).collect();
        times.sort_by(|a, b| a.0.total_cmp(&b.0));
        times.dedup_by(|a, b| a.1 == b.1);
        Snapshots { times, next: 0, written: Vec::new(), last_boundary_s: 0.0 }
    }
}

impl Run<'_> {
    /// The snapshots due at this round boundary (collective, like `maybe_checkpoint`): rank 0's
    /// clock decides, every rank joins the reduce, rank 0 writes each due snapshot's set. A write
    /// that fails is a warning; other errors end the render at the next round's agreement.
    pub(super) fn maybe_snapshot(&self, p: &mut Passes) -> Result<(), String> {
        let pending = &p.snaps.times[p.snaps.next..];
        if pending.is_empty() {
            return Ok(());
        }
        let now = secs(self.started);
        p.snaps.last_boundary_s = now;
        let mine = if self.cluster.rank() == 0 { pending.iter().take_while(|(t, _)| *t <= now).count() } else { 0 };
        let due = self.cluster.all_reduce_max(mine as f64) as usize;
        if due == 0 {
            return Ok(());
        }
        let taken = pending[..due.min(pending.len())].to_vec();
        p.snaps.next += taken.len();
        let t = counter_sums(self.cluster, &p.counters);
        let Some(sums) = self.cluster.reduce_sum(&p.film.data) else { return Ok(()) };
        let total = self.total_film(sums)?;
        let (w, h) = self.plan.resolution;
        let img = super::image_from_film(&total);
        let var = Image { width: total.width, height: total.height, pixels: total.variance_of_mean() };
        for (nominal_s, label) in taken {
            let report = SnapshotReport {
                label,
                nominal_s,
                elapsed_s: now,
                passes: p.passes_done,
                spp: (total.total_samples() / (w as f64 * h as f64)).round() as u64,
                preprocess_s: self.preprocess_s,
                render_s: p.render_s,
                nonfinite_samples: t[2] as u64,
                method: self.plan.method.name().to_string(),
                scene: self.world.scene.path.clone(),
                seed: self.plan.seed,
                resolution: [w, h],
                time_budget_s: self.plan.time,
                ranks: self.cluster.size(),
                image_mean: img.mean(),
            };
            match write_snapshot(&self.job.out, &img, &var, &report) {
                Ok(()) => p.snaps.written.push(report),
                Err(e) => p.warn(format!("snapshot {} not written ({e})", report.label), None),
            }
        }
        Ok(())
    }

    /// After the last round (rank 0): a warning for every snapshot the render ended before.
    pub(super) fn unreached_snapshots(&self, p: &mut Passes) {
        if self.cluster.rank() != 0 {
            return;
        }
        // the last boundary, not the end: writing earlier snapshots there may outlast later ones' times
        let end = p.snaps.last_boundary_s;
        let missed: Vec<String> = p.snaps.times[p.snaps.next..].iter().map(|(_, l)| l.clone()).collect();
        for label in missed {
            p.warn(
                format!("snapshot {label} not written: the render's last round ended at {end:.2} s, before it"),
                None,
            );
        }
    }
}

/// Writes `PREFIX.snap-LABEL.{exr,json}` as one set (the EXR with its variance-of-mean layer).
fn write_snapshot(out: &Path, img: &Image, var: &Image, report: &SnapshotReport) -> Result<(), String> {
    let prefix = snapshot_prefix(out, &report.label);
    if let Some(dir) = prefix.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    }
    let exr = with_ext(&prefix, "exr");
    let mut set = FileSet::new();
    set.add(exr.clone(), image_io::encode_exr_layers(&exr, img, Some(var))?);
    set.add(with_ext(&prefix, "json"), serde_json::to_vec_pretty(report).map_err(|e| e.to_string())?);
    Ok(set.write()?)
}
