//! The typed reports of a render: per-stage timings, ray counts, per-rank figures and the
//! `RenderReport` written as `PREFIX.json` (every key a field; nothing is read back from text).

use super::snapshots::SnapshotReport;
use crate::integrators::{Method, MethodOptions};
use crate::render::film::Film;
use serde::{Deserialize, Serialize};

/// Wall-clock seconds of each stage (rank 0's).
#[derive(Clone, Debug, Default, Serialize)]
pub struct Timings {
    /// Scene loading.
    pub load_s: f64,
    /// BVH build.
    pub bvh_s: f64,
    /// Caustic preprocess (rank 0).
    pub preprocess_s: f64,
    /// Its broadcast.
    pub broadcast_s: f64,
    /// The passes.
    pub render_s: f64,
    /// The reduce.
    pub reduce_s: f64,
    /// Writing images, checkpoint and JSON.
    pub write_s: f64,
    /// Since the process started.
    pub total_s: f64,
}

/// Rays traced by all ranks.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct Rays {
    /// Closest-hit rays.
    pub closest: u64,
    /// Shadow rays.
    pub shadow: u64,
}

/// One rank's figures (gathered on rank 0).
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct RankStats {
    /// Rank.
    pub rank: usize,
    /// Passes it rendered.
    pub passes: u64,
    /// Its preprocess seconds (0 except on rank 0).
    pub preprocess_s: f64,
    /// Its broadcast seconds.
    pub broadcast_s: f64,
    /// Its render seconds.
    pub render_s: f64,
    /// Its reduce seconds.
    pub reduce_s: f64,
    /// Bytes of the broadcast product.
    pub bytes_broadcast: usize,
    /// Checksum of the product it built its integrator from.
    pub product_hash: u64,
    /// Samples it took.
    pub samples: u64,
    /// Its closest-hit rays.
    pub closest_rays: u64,
    /// Its shadow rays.
    pub shadow_rays: u64,
}

/// The JSON report written next to the image (`PREFIX.json`).
#[derive(Clone, Debug, Serialize)]
pub struct RenderReport {
    /// Method.
    pub method: Method,
    /// Why this method, in one line: named by `--method` or the scene, or `auto`'s rule.
    pub method_reason: String,
    /// `auto`'s evidence for its pick (the equal-time figures of `docs/auto.md` and the notes on
    /// the scene's point lights and glossy receivers); `null` for a named method.
    pub method_evidence: Option<String>,
    /// Scene file.
    pub scene: String,
    /// Image size.
    pub resolution: [u32; 2],
    /// Samples per pixel in the image.
    pub spp: u64,
    /// Passes done (resumed ones included).
    pub passes: u64,
    /// First pass of this run.
    pub first_pass: u64,
    /// Whether it continued a checkpoint.
    pub resumed: bool,
    /// Seed.
    pub seed: u64,
    /// MPI ranks.
    pub ranks: usize,
    /// Time budget, seconds.
    pub time_budget_s: Option<f64>,
    /// Stage timings.
    pub timings: Timings,
    /// Rays traced.
    pub rays: Rays,
    /// Million rays per second of render time.
    pub mrays_per_s: f64,
    /// Samples per second of render time.
    pub samples_per_s: f64,
    /// NaN/Inf samples replaced by zero.
    pub nonfinite_samples: u64,
    /// Bytes of the broadcast product.
    pub bytes_broadcast: usize,
    /// The integrator's own figures.
    pub method_stats: serde_json::Value,
    /// The render settings and the method's own options in use.
    pub options: MethodOptions,
    /// Every rank's figures (`None` if one could not be read).
    pub per_rank: Vec<Option<RankStats>>,
    /// Scene warnings, then the run's (the preprocess over the time budget, failed checkpoints).
    pub warnings: Vec<String>,
    /// Whether loading and the preprocess alone took longer than the `--time` budget.
    pub preprocess_over_budget: bool,
    /// The snapshots written so far (`--snapshots`), in time order.
    pub snapshots: Vec<SnapshotReport>,
    /// The pixel sampler: emission split and the pixels it applies to (`render::pixel`).
    pub pixel_sampler: crate::render::pixel::SplitStats,
    /// `pt-cf` without `--light-paths`: the pilot's figures and the light paths it chose
    /// (`pipeline::light_pilot`); `null` otherwise.
    pub light_path_rule: Option<super::LightPathRule>,
    /// `false` in the JSON written with a checkpoint (a render still running) and in that of a
    /// render Ctrl-C or SIGTERM ended (`interrupted`); `true` when the spp or the time box was
    /// reached (a time box is a complete render).
    pub complete: bool,
    /// Whether Ctrl-C or SIGTERM ended the render before its spp or time box (`interrupt`): the
    /// image holds the passes done.
    pub interrupted: bool,
    /// Passes (every rank's) of the last round, cut at the time box's end or a signal before
    /// they were whole and discarded: the image holds `passes` whole passes only (0: none cut).
    #[serde(default)]
    pub passes_cut: u64,
    /// The wall seconds that cut round ran before it was discarded.
    #[serde(default)]
    pub cut_s: f64,
    /// Mean of the image, per channel.
    pub image_mean: [f64; 3],
    /// Every phase's wall seconds and share of the `--time` budget, in order (`pipeline::budget`).
    pub phases: Vec<super::budget::PhaseTime>,
}

/// The warning of a render whose every sample is exactly 0 (the film's radiance sums are all
/// zero; radiance is never negative, so none cancels): no light reached anything the camera saw,
/// e.g. a light facing away from the scene, or one enclosed by geometry. `lights` counts the
/// scene's emitting primitives and point lights. A render that found light in a single sample anywhere gets
/// none: the check is exact, not a threshold, so it never fires on a dark but lit image.
pub fn black_image_warning(film: &Film, lights: usize) -> Option<String> {
    let black = film.data.chunks_exact(crate::render::film::STRIDE).all(|d| d[0] == 0.0 && d[1] == 0.0 && d[2] == 0.0);
    let samples = film.total_samples();
    if !black || samples == 0.0 {
        return None;
    }
    let spp = samples / (film.width * film.height).max(1) as f64;
    Some(if lights == 0 {
        format!("the image is black ({spp:.0} spp, every sample 0): the scene has no light")
    } else {
        format!(
            "the image is black ({spp:.0} spp, every sample 0): the scene has lights, but no light reached \
             anything the camera sees; check that the lights face the scene and are not enclosed or hidden from \
             it (a light facing away renders black)"
        )
    })
}

/// The outcome on rank 0.
pub struct RenderResult {
    /// The accumulated film (rank 0).
    pub film: Film,
    /// The report written next to the image.
    pub report: RenderReport,
}
