//! The render pipeline, top to bottom, and the only place the stages meet:
//! scene → [`RenderJob::resolve`] (and the output guard, `RenderJob::output_set`) → BVH →
//! the ranks' job check (`distributed::job::agree_job`) → [`preprocess`] (rank 0, broadcast) →
//! [`agree_resume`] → [`run_passes`] (interleaved passes, checkpoints) → [`reduce`] → images +
//! [`RenderReport`].
//!
//! Ranks: rank r renders passes r, r+N, … in rounds of N passes; all ranks agree once per round
//! whether to start another (time boxes), so finished passes are always a contiguous range
//! (`distributed::schedule`). The image is the mean over exactly the samples that were summed.
//! Checkpoints are taken at round boundaries: rank 0 gathers the sums and writes the checkpoint
//! and the current `PREFIX.{exr,png,json}` as one set (`atomic_io::FileSet`); a failed checkpoint
//! is a warning (the previous set stays, the next interval retries). `--resume` continues with the
//! next pass and repeats none.
//! Snapshots (`--snapshots`) are taken at round boundaries the same way: `PREFIX.snap-LABEL.*`.
//! Submodules: `scene_options` (a scene's `[render]` options under the command line's), `memory`
//! (the up-front estimate), `identity` (what `--resume` and the ranks compare), `preprocess`
//! (stage 2, with `light_pilot`, `pt-cf`'s light-path pilot), `passes` (stage 4), `checkpoints`
//! (checkpoint and output sets), `snapshots` (the image at intermediate wall-clock times),
//! `report` (the typed `RenderReport`).
//!
//! Failure: every parameter is validated and the memory estimated in [`RenderJob::resolve`],
//! before any work. An error on any rank — during setup, the preprocess, resuming, inside the
//! pass loop (at the next round's agreement) or writing the outputs — is agreed across ranks
//! (`distributed::agree`), so every rank leaves together with the error and rank 0 reports it;
//! no rank is left waiting in a collective.

use crate::accel::World;
use crate::atomic_io::{FileSet, OutputSet};
use crate::checkpoint::Checkpoint;
use crate::distributed::{self, Cluster};
use crate::image_io::{with_ext, Image};
use crate::integrators::{Integrator, Method, MethodArgs, MethodChoice};
use crate::param_limits as params;
use crate::render::film::Film;
use crate::render::PassCounters;
use crate::scene::Scene;

pub mod budget;
mod checkpoints;
mod identity;
mod light_pilot;
pub mod memory;
mod passes;
mod preprocess;
mod report;
mod scene_options;
mod snapshots;

use passes::{run_passes, Passes};

pub use checkpoints::{image_files, image_from_film, write_images};
pub use identity::{job_fields, job_keys};
pub use light_pilot::LightPathRule;
pub use report::{RankStats, Rays, RenderReport, RenderResult, Timings};
mod error;
pub use error::RenderError;
pub use snapshots::{check_snapshots, snapshot_label, snapshot_prefix, SnapshotReport};

use budget::Budget;
use memory::local_ranks;
use preprocess::preprocess;
use std::path::PathBuf;
use std::time::Instant;

/// Everything a render needs, as requested (the scene's defaults fill the `None`s, see
/// [`RenderJob::resolve`]).
#[derive(Clone, Debug)]
pub struct RenderJob {
    /// Scene file.
    pub scene: PathBuf,
    /// Method or `auto` (`None`: the scene's `[render] method`, else `auto`; see
    /// `integrators::auto`).
    pub method: Option<MethodChoice>,
    /// Every method's parameters.
    pub args: MethodArgs,
    /// Samples per pixel (one per pass).
    pub spp: Option<u64>,
    /// Time budget in seconds, preprocess included.
    pub time: Option<f64>,
    /// Seed (`None`: the scene's default).
    pub seed: Option<u64>,
    /// Resolution override.
    pub resolution: Option<(u32, u32)>,
    /// Output prefix (`PREFIX.exr`, `.png`, `.json`).
    pub out: PathBuf,
    /// Show progress.
    pub progress: bool,
    /// Checkpoint interval in seconds.
    pub checkpoint_every: Option<f64>,
    /// Checkpoint to resume from.
    pub resume: Option<PathBuf>,
    /// Where checkpoints go (default `PREFIX.ckpt`).
    pub checkpoint_path: Option<PathBuf>,
    /// Stop after this many rounds (tests of kill-and-resume); `None` = no limit.
    pub max_rounds: Option<u64>,
    /// Worker threads (`None`: all cores divided among the ranks on this node).
    pub threads: Option<usize>,
    /// Mitsuba XML `-D NAME=VALUE` substitutions used when loading `scene`.
    pub defines: Vec<(String, String)>,
    /// Snapshot times in seconds since the process started (`PREFIX.snap-LABEL.{exr,json}`);
    /// each must be earlier than the time budget.
    pub snapshots: Vec<f64>,
    /// Ctrl-C/SIGTERM: once set, the render stops after the round in flight and writes its
    /// outputs (`interrupt`).
    pub interrupt: crate::interrupt::Interrupt,
}

/// A job with every default resolved against its scene.
#[derive(Clone, Debug)]
pub struct Plan {
    /// Method.
    pub method: Method,
    /// Why this method, one line: named by `--method` or the scene, or `auto`'s rule.
    pub method_reason: String,
    /// What `auto`'s pick rests on (its figures and notes); `None` for a named method.
    pub method_evidence: Option<String>,
    /// Seed.
    pub seed: u64,
    /// Method parameters (`max_depth` resolved).
    pub args: MethodArgs,
    /// Time budget (exclusive with `spp`).
    pub time: Option<f64>,
    /// Samples per pixel (exclusive with `time`).
    pub spp: Option<u64>,
    /// Image size.
    pub resolution: (u32, u32),
}

impl RenderJob {
    /// The render's output guard: its inputs (the scene file, `scene`'s meshes, `--resume`) and
    /// every file it may write (`PREFIX.{exr,png,json}`, the checkpoint, each snapshot's
    /// `PREFIX.snap-LABEL.{exr,json}`). The checkpoint may replace the one it resumed from.
    pub fn output_set(&self, scene: &Scene) -> OutputSet {
        let mut g = OutputSet::new();
        g.scene_inputs(&self.scene, &scene.mesh_files);
        if let Some(r) = &self.resume {
            g.input("--resume", r);
        }
        for ext in ["exr", "png", "json"] {
            g.output("--out", &with_ext(&self.out, ext));
        }
        for label in self.snapshots.iter().map(|&t| snapshot_label(t)) {
            let p = snapshot_prefix(&self.out, &label);
            g.output("--snapshots", &with_ext(&p, "exr")).output("--snapshots", &with_ext(&p, "json"));
        }
        let ckpt = self.checkpoint_path.clone().unwrap_or_else(|| with_ext(&self.out, "ckpt"));
        let flag = if self.checkpoint_path.is_some() { "--checkpoint-path" } else { "the checkpoint" };
        match (&self.resume, self.checkpoint_every.is_some() || self.checkpoint_path.is_some()) {
            (Some(r), true) => {
                g.output_replacing(flag, &ckpt, r);
            }
            (None, true) => {
                g.output(flag, &ckpt);
            }
            (_, false) => {}
        }
        g.best_effort(&ckpt); // a checkpoint that cannot be written is a warning
        g
    }

    /// How `scene` is loaded (the job's `-D` values).
    pub fn load_options(&self) -> crate::scene::LoadOptions {
        crate::scene::LoadOptions { defines: self.defines.clone() }
    }

    /// Fills the job's `None`s from the scene's `[render]` defaults, and the method options the
    /// command line did not give from the scene's `[render]` options (`scene_options`).
    pub fn resolve(&self, scene: &Scene) -> Result<Plan, RenderError> {
        let r = &scene.render;
        let (method, method_reason) = crate::integrators::auto::resolve(self.method, scene)?;
        // the command line's own values first, with the limits the scene format applies too
        self.args.validate()?;
        if let Some(n) = self.threads {
            params::THREADS.check_flag("--threads", n as u64)?;
        }
        // the scene's [render] options, which the command line's override, must fit its own method
        let own = if self.method.is_some() { crate::integrators::auto::resolve(None, scene)?.0 } else { method };
        let mut args = scene_options::apply(&self.args, scene, method, own)?;
        // the scene's cap was checked by its reader (a Mitsuba `max_depth` may give 0 or 1, below
        // `--max-depth`'s least): the plan checks the command line's own
        let scene_cap = args.settings.max_depth.is_none().then_some(r.max_depth);
        let time = self.time.or(if self.spp.is_some() { None } else { r.time });
        args.cf.time_budget_s = time; // the CF preprocess scales its photon count to the budget
        let spp = if time.is_some() { None } else { Some(self.spp.or(r.spp).unwrap_or(16)) };
        let resolution = self.resolution.unwrap_or((scene.camera.width, scene.camera.height));
        let seed = self.seed.unwrap_or(r.seed);
        let method_evidence = crate::integrators::auto::resolve_evidence(self.method, scene);
        let mut plan = Plan { method, method_reason, method_evidence, seed, args, time, spp, resolution };
        plan.validate()?;
        plan.args.settings.max_depth = plan.args.settings.max_depth.or(scene_cap);
        check_snapshots(&self.snapshots, time)?;
        let gathers = self.checkpoint_every.is_some() || self.resume.is_some() || !self.snapshots.is_empty();
        let (need, what) = plan.memory_estimate(scene, gathers);
        memory::check(need, &what)?;
        Ok(plan)
    }
}

impl Plan {
    /// The method as a checkpoint records it: its name, and its `--path-filter` if any (a
    /// filtered image must never be resumed as an unfiltered one, nor the other way round).
    pub fn checkpoint_label(&self) -> String {
        match &self.args.pt.path_filter {
            Some(f) => format!("{} --path-filter {f}", self.method.name()),
            None => self.method.name().to_string(),
        }
    }

    /// The plan's values against `crate::param_limits` (the same limits as the scene format's).
    pub fn validate(&self) -> Result<(), RenderError> {
        if let Some(s) = self.spp {
            params::SPP.check_flag("--spp", s)?;
        }
        if let Some(t) = self.time {
            params::check_time(t).map_err(|m| format!("--time: {m}"))?;
        }
        self.args.check_for(self.method)?;
        let (w, h) = self.resolution;
        let most = crate::integrators::pt_cf::light::max_paths(w, h);
        match self.args.ptcf.light_paths {
            Some(n) if self.method == Method::PtCf && n > most => {
                return Err(format!(
                    "--light-paths {n}: at most {most} per pass at {w}x{h} ({} per pixel, at least {}); {} per \
                     pixel would make one pass outlast time boxes and signals",
                    crate::integrators::pt_cf::light::MAX_PATHS_PER_PIXEL,
                    crate::integrators::pt_cf::light::MAX_PATHS_FLOOR,
                    n / (w as u64 * h as u64).max(1)
                )
                .into())
            }
            _ => {}
        }
        Ok(self.args.validate()?)
    }
}

fn secs(t: Instant) -> f64 {
    t.elapsed().as_secs_f64()
}

/// Disarms the cluster's watchdog when the render is over, however it ends.
struct Disarm<'a>(&'a dyn Cluster);

impl Drop for Disarm<'_> {
    fn drop(&mut self) {
        self.0.watch(None);
    }
}

/// Runs a render on every rank of `cluster`; returns `Some` on rank 0. Every error is agreed
/// across ranks (see the module docs): all ranks return it, rank 0's names the failing ranks.
pub fn render(job: &RenderJob, cluster: &dyn Cluster, started: Instant) -> Result<Option<RenderResult>, RenderError> {
    // the watchdog holds the setup to `--time` (the shared deadline re-arms it with the plan's)
    let _disarm = Disarm(cluster);
    // one process with nothing finished yet: a signal exits at once (`interrupt`); under MPI the
    // ranks leave together at the next agreement instead
    job.interrupt.nothing_to_save(cluster.size() == 1);
    if let Some(at) =
        job.time.and_then(|t| std::time::Duration::try_from_secs_f64(t).ok()).and_then(|d| started.checked_add(d))
    {
        cluster.watch(distributed::job::watchdog_limit(at, job.time));
    }
    let setup = crate::atomic_io::check_output_prefix(&job.out).map_err(RenderError::from).and_then(|()| {
        let pool = thread_pool(job.threads)?;
        let loaded = load(job, cluster.rank(), &pool)?;
        Ok((pool, loaded))
    });
    let (pool, (world, mut plan, mut timings)) = distributed::agree(cluster, setup)?;
    // every phase runs inside the time box (`budget`): loading and the BVH are measured, the
    // write is reserved, and a budget they alone use up is refused before any other work
    let reserve = budget::write_reserve_s(plan.resolution, job.checkpoint_every.is_some());
    let mut budget = Budget::new(started, plan.time, reserve, &job.interrupt);
    budget.record("load", timings.load_s, None, false);
    budget.record("bvh", timings.bvh_s, None, false);
    distributed::agree(cluster, budget.check_minimal().map_err(RenderError::from))?;
    distributed::job::agree_job(cluster, &job_fields(job, &world.scene, &plan))?;
    let deadline = distributed::shared_deadline(cluster, started, budget.passes_budget());
    let mut pre = preprocess(&world, &mut plan, cluster, job.progress && cluster.rank() == 0, &mut budget)?;
    timings.preprocess_s = pre.stats.preprocess_s;
    timings.broadcast_s = pre.stats.broadcast_s;
    let over_budget = preprocess_over_budget(&plan, &timings, started, cluster.rank());
    let resumed = agree_resume(job, &world, &plan, cluster)?;
    let preprocess_s = timings.preprocess_s;
    let light_path_rule = pre.light_path_rule.take();
    let run = Run {
        job,
        world: &world,
        plan: &plan,
        cluster,
        pool: &pool,
        started,
        resumed: &resumed,
        preprocess_s,
        light_path_rule,
    };
    let (probe_stop, probe_allowed) = budget.stop_for(budget::PROBE_SHARE);
    let mut passes = run_passes(&run, pre.integrator.as_mut(), deadline, &probe_stop)?;
    let split = passes.pixel_sampler;
    if split.emission_split > 1 {
        budget.record("probe", split.probe_s, probe_allowed, split.probe_stopped);
    }
    let passes_allowed = budget.passes_budget().map(|t| (t - secs(started) + passes.render_s).max(0.0));
    budget.record("passes", passes.render_s, passes_allowed, passes.passes_cut > 0);
    passes.preprocess_over_budget = over_budget.is_some();
    passes.warnings.splice(0..0, over_budget);
    timings.render_s = passes.render_s;
    let outcome =
        reduce(&run, &passes, &pre.stats, &mut timings).map_err(RenderError::from).and_then(|reduced| match reduced {
            Some(r) => finish(&run, &mut passes, r, (timings, budget), pre.integrator.as_ref()).map(Some),
            None => Ok(None),
        });
    // rank 0's write failing must end every rank with the error too
    distributed::agree(cluster, outcome)
}

/// Stage 6 (rank 0): the final checkpoint (with `--checkpoint-every`, so that a finished run can
/// be extended with `--resume`; a failure is a warning), then images and report, replacing the
/// previous set as a whole.
fn finish(
    run: &Run,
    passes: &mut Passes,
    reduced: Reduced,
    (mut timings, mut budget): (Timings, Budget),
    integrator: &dyn Integrator,
) -> Result<RenderResult, RenderError> {
    let t_write = Instant::now();
    if run.job.checkpoint_every.is_some() {
        let saved = run.checkpoint(passes.passes_done, &reduced.film).save(&run.ckpt_path());
        if let Err(e) = saved {
            passes.warn(format!("final checkpoint not written ({e}); the previous one is kept"), None);
        }
    }
    let scene = &run.world.scene;
    if let Some(w) = report::black_image_warning(&reduced.film, scene.emitters.len() + scene.point_lights.len()) {
        passes.warn(w, None);
    }
    let mut outputs = FileSet::new();
    let image = image_files(&run.job.out, &reduced.film, &mut outputs)?;
    timings.write_s = secs(t_write);
    timings.total_s = secs(run.started);
    // the JSON's own write follows: the phase is the checkpoint and the images' encoding
    let write_allowed =
        budget.passes_budget().and(run.plan.time).map(|t| (t - timings.total_s + timings.write_s).max(0.0));
    budget.record("write", timings.reduce_s + timings.write_s, write_allowed, false);
    let stats = integrator.stats(&passes.counters.profile);
    // a signal's render is not complete; a time box reached is
    let mut report = run.report(passes, reduced.parts, timings, stats, &image, !passes.interrupted);
    report.phases = budget.phases;
    let text = serde_json::to_string_pretty(&report).map_err(|e| e.to_string())?;
    outputs.add(with_ext(&run.job.out, "json"), text.into_bytes());
    outputs.write()?;
    Ok(RenderResult { film: reduced.film, report })
}

/// The warning (printed by rank 0, recorded in the report) when loading and the preprocess alone
/// used up the `--time` budget: the render then gets only its first round of passes.
fn preprocess_over_budget(plan: &Plan, timings: &Timings, started: Instant, rank: usize) -> Option<String> {
    let budget = plan.time?;
    let spent = secs(started);
    if spent <= budget {
        return None;
    }
    let w = format!(
        "the preprocess took {:.2} s ({spent:.2} s since start, loading included), over the --time budget \
         of {budget} s: only one round of passes is rendered (lower the photon counts or raise --time)",
        timings.preprocess_s
    );
    if rank == 0 {
        crate::errln!("warning: {w}");
    }
    Some(w)
}

/// Stage 1: load the scene (on the render's `pool`: its textures are decoded on its threads;
/// warnings printed on rank 0), resolve the job (validation and the memory estimate), build the
/// BVH.
fn load(job: &RenderJob, rank: usize, pool: &rayon::ThreadPool) -> Result<(World, Plan, Timings), RenderError> {
    let t_load = Instant::now();
    crate::atomic_io::check_input("scene file", &job.scene)?; // named without a line: it has none
    let mut scene = pool.install(|| crate::scene::load_with(&job.scene, &job.load_options()))?;
    job.output_set(&scene).not_writer(rank != 0).check()?; // before anything is written
    let load_s = secs(t_load);
    if rank == 0 {
        for w in &scene.warnings {
            crate::errln!("warning: {w}");
        }
    }
    let plan = job.resolve(&scene)?;
    // the point-light caustic warning does not concern `pt-cf` with its light paths
    let lights_caustics = plan.method == Method::PtCf && plan.args.ptcf.light_paths != Some(0);
    for w in crate::scene::scene_warnings(&scene) {
        if lights_caustics && w.contains(crate::scene::POINT_LIGHT_WARNING) {
            continue;
        }
        if rank == 0 {
            crate::errln!("warning: {w}");
        }
        scene.warnings.push(w);
    }
    if rank == 0 && job.progress {
        crate::errln!("method: {} ({})", plan.method.name(), plan.method_reason);
    }
    if let Some(f) = &plan.args.pt.path_filter {
        let w =
            format!("--path-filter {f}: only these path classes are rendered (a biased diagnostic, no emission split)");
        if rank == 0 {
            crate::errln!("warning: {w}");
        }
        scene.warnings.push(w);
    }
    let world =
        World::build_with(scene, plan.args.settings.accel).map_err(|e| format!("{}: {e}", job.scene.display()))?;
    let bvh_s = world.build_secs;
    Ok((world, plan, Timings { load_s, bvh_s, ..Timings::default() }))
}

/// A checkpoint to continue and the first pass of this run.
struct Resume {
    checkpoint: Option<Checkpoint>,
    first_pass: u64,
}

/// Stage 3: rank 0 validates the checkpoint; every rank learns the first pass.
fn agree_resume(job: &RenderJob, world: &World, plan: &Plan, cluster: &dyn Cluster) -> Result<Resume, RenderError> {
    let (w, h) = plan.resolution;
    let loaded = match (&job.resume, cluster.rank()) {
        (Some(p), 0) => Checkpoint::load(p).map_err(RenderError::from).and_then(|c| {
            c.validate(world.scene.hash, plan.seed, &plan.checkpoint_label(), (w, h), &job_keys(job, plan))
                .map_err(|mismatch| RenderError::Resume { path: p.clone(), mismatch })
                .map(|()| Some(c))
        }),
        _ => Ok(None),
    };
    let checkpoint: Option<Checkpoint> = distributed::agree(cluster, loaded)?;
    let first_pass = distributed::broadcast_u64(cluster, checkpoint.as_ref().map_or(0, |c| c.next_pass), "resume")?;
    Ok(Resume { checkpoint, first_pass })
}

/// What the stages after the preprocess share.
struct Run<'a> {
    job: &'a RenderJob,
    world: &'a World,
    plan: &'a Plan,
    cluster: &'a dyn Cluster,
    pool: &'a rayon::ThreadPool,
    started: Instant,
    resumed: &'a Resume,
    /// Rank 0's preprocess seconds (for the snapshots' reports).
    preprocess_s: f64,
    /// `pt-cf`'s light-path pilot (rank 0).
    light_path_rule: Option<LightPathRule>,
}

/// The summed film (rank 0) and the run-wide figures.
struct Reduced {
    film: Film,
    parts: Totals,
}

/// Figures summed over ranks.
struct Totals {
    rays: Rays,
    nonfinite: u64,
    samples: f64,
    film_samples: f64,
    bytes_broadcast: usize,
    per_rank: Vec<Option<RankStats>>,
}

/// Stage 5: reduce the sums and counters to rank 0 and gather every rank's figures.
fn reduce(run: &Run, p: &Passes, pre: &RankStats, timings: &mut Timings) -> Result<Option<Reduced>, String> {
    let t_red = Instant::now();
    let sums = run.cluster.reduce_sum(&p.film.data);
    let c = &p.counters;
    let t = counter_sums(run.cluster, c);
    timings.reduce_s = secs(t_red);
    let mine = RankStats {
        passes: p.my_passes,
        render_s: p.render_s,
        reduce_s: timings.reduce_s,
        samples: c.samples,
        closest_rays: c.closest_rays,
        shadow_rays: c.shadow_rays,
        ..pre.clone()
    };
    let json = serde_json::to_vec(&mine).unwrap_or_default();
    let gathered = run.cluster.gather_bytes(&json);
    let Some(sums) = sums else { return Ok(None) };
    let film = run.total_film(sums)?;
    let per_rank = gathered.unwrap_or_default().iter().map(|b| serde_json::from_slice(b).ok()).collect();
    let parts = Totals::new(&t, &film, pre.bytes_broadcast, per_rank);
    Ok(Some(Reduced { film, parts }))
}

/// Rays, non-finite samples and samples summed over ranks (collective).
fn counter_sums(cluster: &dyn Cluster, c: &PassCounters) -> Vec<f64> {
    cluster.all_reduce_sum(&[c.closest_rays as f64, c.shadow_rays as f64, c.nonfinite as f64, c.samples as f64])
}

impl Totals {
    fn new(t: &[f64], film: &Film, bytes_broadcast: usize, per_rank: Vec<Option<RankStats>>) -> Totals {
        let rays = Rays { closest: t[0] as u64, shadow: t[1] as u64 };
        let film_samples = film.total_samples();
        Totals { rays, nonfinite: t[2] as u64, samples: t[3], film_samples, bytes_broadcast, per_rank }
    }
}

impl Run<'_> {
    /// Stage 6: the typed report.
    fn report(
        &self,
        p: &Passes,
        t: Totals,
        timings: Timings,
        method_stats: serde_json::Value,
        image: &Image,
        complete: bool,
    ) -> RenderReport {
        let (w, h) = self.plan.resolution;
        let render_s = timings.render_s.max(1e-9);
        RenderReport {
            method: self.plan.method,
            method_reason: self.plan.method_reason.clone(),
            method_evidence: self.plan.method_evidence.clone(),
            scene: self.world.scene.path.clone(),
            resolution: [w, h],
            spp: (t.film_samples / ((w as f64) * (h as f64))).round() as u64,
            passes: p.passes_done,
            first_pass: self.resumed.first_pass,
            resumed: self.resumed.checkpoint.is_some(),
            seed: self.plan.seed,
            ranks: self.cluster.size(),
            time_budget_s: self.plan.time,
            mrays_per_s: (t.rays.closest + t.rays.shadow) as f64 / render_s / 1e6,
            samples_per_s: t.samples / render_s,
            nonfinite_samples: t.nonfinite,
            bytes_broadcast: t.bytes_broadcast,
            rays: t.rays,
            timings,
            method_stats,
            options: self.plan.args.options_for(self.plan.method),
            per_rank: t.per_rank,
            warnings: self.world.scene.warnings.iter().chain(&p.warnings).cloned().collect(),
            preprocess_over_budget: p.preprocess_over_budget,
            snapshots: p.snaps.written.clone(),
            pixel_sampler: p.pixel_sampler,
            light_path_rule: self.light_path_rule.clone(),
            complete,
            interrupted: p.interrupted,
            passes_cut: p.passes_cut,
            cut_s: p.cut_s,
            image_mean: image.mean(),
            phases: Vec::new(),
        }
    }
}

/// A rayon pool of `threads` workers (default: cores ÷ ranks on this node, from MPICH's
/// `MPI_LOCALNRANKS` or Open MPI's `OMPI_COMM_WORLD_LOCAL_SIZE`).
pub fn thread_pool(threads: Option<usize>) -> Result<rayon::ThreadPool, String> {
    let local = local_ranks();
    let n = threads.unwrap_or_else(|| {
        let cores = std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1);
        (cores / local.max(1)).max(1)
    });
    params::THREADS.check_flag("--threads", n as u64)?;
    rayon::ThreadPoolBuilder::new().num_threads(n).build().map_err(|e| format!("cannot start {n} threads: {e}"))
}

/// The most worker threads a process may ask for (more fail late, after minutes of thread
/// creation, with "Resource temporarily unavailable").
pub const MAX_THREADS: usize = params::MAX_THREADS;
