//! The pipeline's checkpoint and output sets: at round boundaries (stage 4) rank 0 gathers the
//! sums and writes the checkpoint and the current `PREFIX.{exr,png,json}` as one
//! `atomic_io::FileSet`; `image_files` adds `PREFIX.{exr,png}` to such a set.
//!
//! A checkpoint records `identity::job_keys` (the `-D` values and the method's options) beside the
//! scene hash, seed, method and resolution; `--resume` refuses a render whose keys differ.
//!
//! Invariants: the checkpoint is added to the set last, so once it is visible its images and
//! JSON are too; a failed write is a warning (the previous set stays, the next interval retries).

use super::identity::job_keys;
use super::{counter_sums, secs, Passes, Run, Timings, Totals};
use crate::atomic_io::FileSet;
use crate::checkpoint::Checkpoint;
use crate::image_io::{self, with_ext, Image, ImageError};
use crate::integrators::Integrator;
use crate::render::film::Film;
use std::path::{Path, PathBuf};
use std::time::Instant;

impl Run<'_> {
    pub(super) fn ckpt_path(&self) -> PathBuf {
        self.job.checkpoint_path.clone().unwrap_or_else(|| with_ext(&self.job.out, "ckpt"))
    }

    /// A checkpoint at this round boundary if rank 0's interval has passed (collective): the
    /// checkpoint and `PREFIX.{exr,png,json}` replace the previous ones as one set. A write that
    /// fails is a warning (printed by rank 0, kept for the report): the previous set stays and
    /// the next interval tries again. Other errors end the render at the next round's agreement.
    /// None after rank 0's `last_round` (the final checkpoint follows).
    pub(super) fn maybe_checkpoint(
        &self,
        p: &mut Passes,
        integrator: &dyn Integrator,
        last: &mut Instant,
        last_round: bool,
    ) -> Result<(), String> {
        let Some(every) = self.job.checkpoint_every else { return Ok(()) };
        // rank 0 decides (the others' 0 never outweighs it), so every rank takes the same branch
        let due = self.cluster.rank() == 0 && !last_round && last.elapsed().as_secs_f64() >= every;
        let want = if due { 1.0 } else { 0.0 };
        if self.cluster.all_reduce_max(want) == 0.0 {
            return Ok(());
        }
        *last = Instant::now();
        let t = counter_sums(self.cluster, &p.counters);
        let Some(sums) = self.cluster.reduce_sum(&p.film.data) else { return Ok(()) };
        let total = self.total_film(sums)?;
        let mut set = FileSet::new();
        let written = image_files(&self.job.out, &total, &mut set).map_err(String::from).and_then(|image| {
            let timings = Timings { render_s: p.render_s, total_s: secs(self.started), ..Timings::default() };
            let parts = Totals::new(&t, &total, 0, Vec::new());
            let report = self.report(p, parts, timings, integrator.stats(&p.counters.profile), &image, false);
            set.add(with_ext(&self.job.out, "json"), serde_json::to_vec_pretty(&report).map_err(|e| e.to_string())?);
            // last, so that once the new checkpoint is visible its images and JSON are too
            set.add(self.ckpt_path(), self.checkpoint(p.passes_done, &total).to_bytes());
            Ok(set.write()?)
        });
        if let Err(e) = written {
            let what = format!("checkpoint after {} passes not written ({e}); the previous one is kept", p.passes_done);
            p.warn(what, Some(every));
        }
        Ok(())
    }

    /// The checkpoint of `total` after `passes_done` contiguous passes.
    pub(super) fn checkpoint(&self, passes_done: u64, total: &Film) -> Checkpoint {
        let (width, height) = self.plan.resolution;
        Checkpoint {
            scene_hash: self.world.scene.hash,
            seed: self.plan.seed,
            method: self.plan.checkpoint_label(),
            width,
            height,
            passes_done,
            next_pass: passes_done,
            spp: passes_done,
            elapsed_secs: secs(self.started) + self.resumed.checkpoint.as_ref().map_or(0.0, |r| r.elapsed_secs),
            film: total.data.clone(),
            job: job_keys(self.job, self.plan),
        }
    }

    /// The reduced sums of this run plus the resumed checkpoint's (rank 0).
    pub(super) fn total_film(&self, sums: Vec<f64>) -> Result<Film, String> {
        let (w, h) = self.plan.resolution;
        let mut total = Film::from_data(w as usize, h as usize, sums).ok_or("film size mismatch")?;
        if let Some(r) = &self.resumed.checkpoint {
            let prev =
                Film::from_data(total.width, total.height, r.film.clone()).ok_or("checkpoint film size mismatch")?;
            total.merge(&prev);
        }
        Ok(total)
    }
}

/// The film's mean as an image.
pub fn image_from_film(f: &Film) -> Image {
    Image { width: f.width, height: f.height, pixels: f.mean() }
}

/// Writes PREFIX.exr (mean + variance-of-mean layer) and PREFIX.png as one set; returns the mean.
pub fn write_images(prefix: &Path, film: &Film) -> Result<Image, ImageError> {
    let mut set = FileSet::new();
    let img = image_files(prefix, film, &mut set)?;
    set.write()?;
    Ok(img)
}

/// Adds PREFIX.exr (mean + variance-of-mean layer) and PREFIX.png to `set` (creating PREFIX's
/// directory); returns the mean.
pub fn image_files(prefix: &Path, film: &Film, set: &mut FileSet) -> Result<Image, ImageError> {
    if let Some(dir) = prefix.parent().filter(|d| !d.as_os_str().is_empty()) {
        let dir_error = |source| ImageError::Io { path: dir.to_path_buf(), action: "create", source };
        std::fs::create_dir_all(dir).map_err(dir_error)?;
    }
    let img = image_from_film(film);
    let var = Image { width: film.width, height: film.height, pixels: film.variance_of_mean() };
    let (exr, png) = (with_ext(prefix, "exr"), with_ext(prefix, "png"));
    set.add(exr.clone(), image_io::encode_exr_layers(&exr, &img, Some(&var))?);
    set.add(png.clone(), image_io::encode_png_srgb(&png, &img, 0.0)?); // exposure in stops: 0 = as rendered
    Ok(img)
}
