//! `compare --single-run`: every budget of a (method, seed) measured from one render.
//!
//! The render runs at the largest budget with `--snapshots` at every smaller one
//! (`pipeline::snapshots`); the largest budget's row is the render itself, each smaller budget's
//! row is its snapshot `PREFIX.snap-LABEL.exr` (spp, elapsed seconds, preprocess seconds and
//! non-finite samples from `PREFIX.snap-LABEL.json`). The rows are the ones separate runs give,
//! with two differences the report states: the preprocess was sized for the largest budget
//! (the CF photon count scales with `--time`), and a snapshot's wall time is the round boundary
//! it was taken at (≥ its budget). A snapshot the render did not write is a failed row.
//!
//! Rows come out in the order of separate runs: budget (as given), then seed.

use super::{budget_label, log_record, Ctx, RunRecord};
use crate::image_io::{self, with_ext};
use crate::integrators::Method;
use crate::pipeline::{self, snapshot_prefix, RenderError, RenderResult};
use std::time::Instant;

impl Ctx<'_> {
    /// One render per seed at the largest budget; a row per (budget, seed).
    pub(super) fn single_runs(&self, method: Method) -> Vec<RunRecord> {
        let Some(top) = self.cfg.budgets.iter().copied().max_by(f64::total_cmp) else { return Vec::new() };
        let mut snaps: Vec<f64> = self.cfg.budgets.iter().copied().filter(|&b| b < top).collect();
        snaps.sort_by(f64::total_cmp);
        snaps.dedup_by(|a, b| budget_label(*a) == budget_label(*b));
        let mut rows: Vec<(usize, RunRecord)> = Vec::new();
        for k in 0..self.cfg.seeds {
            let prefix = self.prefix(method, top, k);
            let seed = self.base_seed.wrapping_add(k);
            let job = self.job(method, top, seed, prefix.clone(), snaps.clone());
            let result = pipeline::render(&job, self.cluster, Instant::now());
            if self.reference.is_none() {
                continue;
            }
            for (i, &budget) in self.cfg.budgets.iter().enumerate() {
                let mut rec = self.record(method, budget, k, prefix.clone());
                if budget < top {
                    self.fill_from_snapshot(&mut rec, &result);
                } else {
                    self.fill_from_render(&mut rec, &result);
                }
                log_record(&rec);
                rows.push((i, rec));
            }
        }
        rows.sort_by_key(|(i, r)| (*i, r.seed_index));
        rows.into_iter().map(|(_, r)| r).collect()
    }

    /// Fills `rec` from the snapshot at `rec.budget_s` of the render `result` (rank 0).
    fn fill_from_snapshot(&self, rec: &mut RunRecord, result: &Result<Option<RenderResult>, RenderError>) {
        let label = budget_label(rec.budget_s);
        let run_prefix = rec.prefix.clone();
        rec.from_snapshot = true;
        rec.prefix = snapshot_prefix(&run_prefix, &label);
        let r = match result {
            Ok(Some(r)) => r,
            Ok(None) => {
                rec.error = Some("no result on rank 0".into());
                return;
            }
            Err(e) => {
                rec.error = Some(e.to_string());
                return;
            }
        };
        let Some(snap) = r.report.snapshots.iter().find(|s| s.label == label) else {
            let why = r.report.warnings.iter().find(|w| w.contains(&format!("snapshot {label} ")));
            rec.error = Some(format!(
                "{}: no snapshot at {label}{}",
                with_ext(&run_prefix, "json").display(),
                why.map_or(String::new(), |w| format!(" ({w})"))
            ));
            return;
        };
        rec.spp = snap.spp;
        rec.wall_s = snap.elapsed_s;
        rec.preprocess_s = snap.preprocess_s;
        rec.preprocess_share = rec.preprocess_s / rec.wall_s.max(1e-12);
        rec.nonfinite_samples = snap.nonfinite_samples;
        match image_io::read_exr(&with_ext(&rec.prefix, "exr")) {
            Ok(img) => self.measure_into(rec, &img),
            Err(e) => rec.error = Some(e.to_string()),
        }
    }
}
