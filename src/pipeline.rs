//! The render pipeline, top to bottom, and the only place the stages meet:
//! scene → BVH → caustic preprocess (rank 0, broadcast) → interleaved passes → reduce → image.
//!
//! Ranks: rank r renders passes r, r+N, … in rounds of N passes; all ranks agree once per round
//! whether to start another (time boxes), so finished passes are always a contiguous range
//! (`distributed::schedule`). The image is the mean over exactly the samples that were summed.
//! Checkpoints are taken at round boundaries: rank 0 gathers the sums and writes them atomically
//! with the pass bookkeeping; `--resume` continues with the next pass and repeats none.

use crate::accel::World;
use crate::atomic_io::FileSet;
use crate::checkpoint::Checkpoint;
use crate::distributed::schedule::{Deadline, PassTimer};
use crate::distributed::{self, Cluster};
use crate::image_io::{self, Image};
use crate::integrators::{self, Method, MethodOptions};
use crate::progress::Progress;
use crate::render::film::Film;
use crate::render::{render_pass, PassCounters};
use serde_json::json;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Everything a render needs (resolved from the CLI and the scene's defaults).
#[derive(Clone, Debug)]
pub struct RenderJob {
    /// Scene file.
    pub scene: PathBuf,
    /// Method (`None`: the scene's default).
    pub method: Option<Method>,
    /// Method options.
    pub opts: MethodOptions,
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
}

/// The outcome on rank 0.
pub struct RenderResult {
    /// The accumulated film (rank 0).
    pub film: Film,
    /// The JSON report written next to the image.
    pub report: serde_json::Value,
}

fn secs(t: Instant) -> f64 {
    t.elapsed().as_secs_f64()
}

/// Runs a render on every rank of `cluster`; returns `Some` on rank 0.
pub fn render(job: &RenderJob, cluster: &dyn Cluster, started: Instant) -> Result<Option<RenderResult>, String> {
    let (rank, size) = (cluster.rank(), cluster.size());
    crate::atomic_io::check_output_prefix(&job.out)?;
    let pool = thread_pool(job.threads)?;
    let t_load = Instant::now();
    let mut scene = crate::scene::load(&job.scene).map_err(|e| e.to_string())?;
    let limitations = crate::compare::stability::scene_warnings(&scene);
    scene.warnings.extend(limitations);
    let load_s = secs(t_load);
    if rank == 0 {
        for w in &scene.warnings {
            crate::errln!("warning: {w}");
        }
    }
    let method = match job.method {
        Some(m) => m,
        None => Method::from_name(&scene.render.method)
            .ok_or_else(|| format!("{}: method `{}` is not available", scene.path, scene.render.method))?,
    };
    let seed = job.seed.unwrap_or(scene.render.seed);
    let mut opts = job.opts.clone();
    if opts.max_depth == 0 {
        opts.max_depth = scene.render.max_depth;
    }
    let time = job.time.or(if job.spp.is_some() { None } else { scene.render.time });
    let spp = if time.is_some() { None } else { Some(job.spp.or(scene.render.spp).unwrap_or(16)) };
    let (w, h) = job.resolution.unwrap_or((scene.camera.width, scene.camera.height));
    let camera = scene.camera.with_resolution(w, h);
    let world = World::build(scene);
    let bvh_s = world.build_secs;
    let deadline: Deadline = distributed::shared_deadline(cluster, started, time);

    // Caustic preprocess on rank 0, broadcast to the others.
    let t_pre = Instant::now();
    let pre = if rank == 0 { integrators::preprocess(method, &world, &opts, seed) } else { Ok(Vec::new()) };
    let preprocess_s = secs(t_pre);
    // every rank must leave together when rank 0 fails, or the others wait in the broadcast
    let mut product = agree_or_fail(cluster, pre, "the caustic preprocess")?;
    let t_bc = Instant::now();
    cluster.broadcast_bytes(&mut product);
    let broadcast_s = secs(t_bc);
    let bytes_broadcast = product.len();
    let product_hash = crate::checkpoint::checksum(&product);
    let mut integrator = integrators::build(method, &world, &opts, &product)?;
    drop(product);

    // Resume: rank 0 validates the checkpoint; everyone learns the first pass.
    let ckpt_path = job.checkpoint_path.clone().unwrap_or_else(|| with_ext(&job.out, "ckpt"));
    let loaded = match (&job.resume, rank) {
        (Some(p), 0) => Checkpoint::load(p).map_err(|e| e.to_string()).and_then(|c| {
            c.validate(world.scene.hash, seed, method.name(), w, h)
                .map_err(|e| format!("{}: cannot resume: {e}", p.display()))
                .map(|()| Some(c))
        }),
        _ => Ok(None),
    };
    let resumed: Option<Checkpoint> = agree_or_fail(cluster, loaded, "resuming")?;
    let mut first = resumed.as_ref().map_or(0u64, |c| c.next_pass).to_le_bytes().to_vec();
    cluster.broadcast_bytes(&mut first);
    let first_pass = u64::from_le_bytes(first.as_slice().try_into().map_err(|_| "bad resume broadcast")?);
    let total_passes = spp.map(|s| s.max(first_pass));

    let progress = Progress::new(job.progress && rank == 0, total_passes.map(|t| t - first_pass), time);
    let mut film = Film::new(w as usize, h as usize);
    let mut counters = PassCounters::default();
    let mut timer = PassTimer::new();
    let t_render = Instant::now();
    let mut last_ckpt = Instant::now();
    let mut my_passes = 0u64;
    let mut round = 0u64;
    let mut passes_done = first_pass;
    loop {
        let round_start = first_pass + round * size as u64;
        let more = match total_passes {
            Some(t) => round_start < t,
            // the first round always runs, so a time-boxed image is never empty
            None if round == 0 => true,
            None => distributed::all_agree(cluster, deadline.should_start_next(Instant::now(), timer.mean_secs())),
        };
        if !more || job.max_rounds.is_some_and(|m| round >= m) {
            break;
        }
        let pass = round_start + rank as u64;
        if total_passes.is_none_or(|t| pass < t) {
            let t_pass = Instant::now();
            integrator.begin_pass(&world, seed, pass);
            let integ = integrator.as_ref();
            let c = pool.install(|| render_pass(&world, integ, &camera, seed, pass, &mut film));
            counters.add(&c);
            timer.record(secs(t_pass));
            my_passes += 1;
        }
        round += 1;
        passes_done = total_passes.map_or(round_start + size as u64, |t| (round_start + size as u64).min(t));
        let rays = counters.closest_rays + counters.shadow_rays;
        progress.update(passes_done - first_pass, passes_done, secs(t_render), secs(started), rays * size as u64);
        if let Some(every) = job.checkpoint_every {
            let want = if rank == 0 && last_ckpt.elapsed().as_secs_f64() >= every { 1.0 } else { 0.0 };
            if cluster.all_reduce_max(want) > 0.0 {
                if let Some(sums) = cluster.reduce_sum(&film.data) {
                    let total = total_film(w, h, sums, &resumed)?;
                    let ck = checkpoint_of(&world, seed, method, (w, h), passes_done, &total, started, &resumed);
                    ck.save(&ckpt_path).map_err(|e| e.to_string())?;
                    write_images(&job.out, &total)?;
                }
                last_ckpt = Instant::now();
            }
        }
    }
    let render_s = secs(t_render);
    progress.finish();

    // Reduce the sums to rank 0.
    let t_red = Instant::now();
    let sums = cluster.reduce_sum(&film.data);
    let totals = cluster.all_reduce_sum(&[
        counters.closest_rays as f64,
        counters.shadow_rays as f64,
        counters.nonfinite as f64,
        counters.samples as f64,
    ]);
    let reduce_s = secs(t_red);
    let rank_stats = json!({
        "rank": rank, "passes": my_passes, "preprocess_s": preprocess_s, "broadcast_s": broadcast_s,
        "render_s": render_s, "reduce_s": reduce_s, "bytes_broadcast": bytes_broadcast, "product_hash": product_hash,
        "samples": counters.samples, "closest_rays": counters.closest_rays, "shadow_rays": counters.shadow_rays,
    });
    let gathered = cluster.gather_bytes(rank_stats.to_string().as_bytes());
    let Some(sums) = sums else { return Ok(None) };
    let total = total_film(w, h, sums, &resumed)?;
    let per_rank: Vec<serde_json::Value> = gathered
        .unwrap_or_default()
        .iter()
        .map(|b| serde_json::from_slice(b).unwrap_or(serde_json::Value::Null))
        .collect();
    let t_write = Instant::now();
    if job.checkpoint_every.is_some() {
        // the final state too, so a finished run can be extended with --resume
        let ck = checkpoint_of(&world, seed, method, (w, h), passes_done, &total, started, &resumed);
        ck.save(&ckpt_path).map_err(|e| e.to_string())?;
    }
    let mut outputs = FileSet::new(); // EXR, PNG and JSON replace the old set as a whole
    let image = image_files(&job.out, &total, &mut outputs)?;
    let write_s = secs(t_write);
    let pixels = (w as f64) * (h as f64);
    let samples_total = total.total_samples();
    let (closest, shadow) = (totals[0] as u64, totals[1] as u64);
    let report = json!({
        "method": method.name(),
        "scene": world.scene.path,
        "resolution": [w, h],
        "spp": (samples_total / pixels).round() as u64,
        "passes": passes_done,
        "first_pass": first_pass,
        "resumed": resumed.is_some(),
        "seed": seed,
        "ranks": size,
        "time_budget_s": time,
        "timings": {
            "load_s": load_s, "bvh_s": bvh_s, "preprocess_s": preprocess_s, "broadcast_s": broadcast_s,
            "render_s": render_s, "reduce_s": reduce_s, "write_s": write_s, "total_s": secs(started),
        },
        "rays": { "closest": closest, "shadow": shadow },
        "mrays_per_s": (closest + shadow) as f64 / render_s.max(1e-9) / 1e6,
        "samples_per_s": totals[3] / render_s.max(1e-9),
        "nonfinite_samples": totals[2] as u64,
        "bytes_broadcast": bytes_broadcast,
        "method_stats": integrator.stats(),
        "options": opts,
        "per_rank": per_rank,
        "warnings": world.scene.warnings,
        "image_mean": image.mean(),
    });
    let json_path = with_ext(&job.out, "json");
    let text = serde_json::to_string_pretty(&report).map_err(|e| e.to_string())?;
    outputs.add(json_path, text.into_bytes());
    outputs.commit()?;
    let _ = &mut integrator;
    Ok(Some(RenderResult { film: total, report }))
}

/// A rayon pool of `threads` workers (default: cores ÷ ranks on this node, from MPICH's
/// `MPI_LOCALNRANKS` or Open MPI's `OMPI_COMM_WORLD_LOCAL_SIZE`).
pub fn thread_pool(threads: Option<usize>) -> Result<rayon::ThreadPool, String> {
    let local = ["MPI_LOCALNRANKS", "OMPI_COMM_WORLD_LOCAL_SIZE"]
        .iter()
        .find_map(|v| std::env::var(v).ok()?.parse::<usize>().ok())
        .unwrap_or(1);
    let n = threads.unwrap_or_else(|| {
        let cores = std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1);
        (cores / local.max(1)).max(1)
    });
    if n == 0 || n > MAX_THREADS {
        return Err(format!("--threads {n}: must be between 1 and {MAX_THREADS}"));
    }
    rayon::ThreadPoolBuilder::new().num_threads(n).build().map_err(|e| format!("cannot start {n} threads: {e}"))
}

/// The most worker threads a process may ask for (more fail late, after minutes of thread
/// creation, with "Resource temporarily unavailable").
pub const MAX_THREADS: usize = 4096;

/// The checkpoint of `total` after `passes_done` contiguous passes.
#[allow(clippy::too_many_arguments)]
fn checkpoint_of(
    world: &World,
    seed: u64,
    method: Method,
    (w, h): (u32, u32),
    passes_done: u64,
    total: &Film,
    started: Instant,
    resumed: &Option<Checkpoint>,
) -> Checkpoint {
    Checkpoint {
        scene_hash: world.scene.hash,
        seed,
        method: method.name().to_string(),
        width: w,
        height: h,
        passes_done,
        next_pass: passes_done,
        spp: passes_done,
        elapsed_secs: secs(started) + resumed.as_ref().map_or(0.0, |r| r.elapsed_secs),
        film: total.data.clone(),
    }
}

/// The reduced sums of this run plus the resumed checkpoint's (rank 0).
fn total_film(w: u32, h: u32, sums: Vec<f64>, resumed: &Option<Checkpoint>) -> Result<Film, String> {
    let mut total = Film::from_data(w as usize, h as usize, sums).ok_or("film size mismatch")?;
    if let Some(r) = resumed {
        let prev = Film::from_data(total.width, total.height, r.film.clone()).ok_or("checkpoint film size mismatch")?;
        total.merge(&prev);
    }
    Ok(total)
}

/// Rank 0's `result` if every rank got `Ok`; an error on every rank otherwise (collective).
fn agree_or_fail<T>(cluster: &dyn Cluster, result: Result<T, String>, what: &str) -> Result<T, String> {
    let ok = distributed::all_agree(cluster, result.is_ok());
    match result {
        Ok(v) if ok => Ok(v),
        Err(e) => Err(e),
        Ok(_) => Err(format!("{what} failed on rank 0")),
    }
}

/// The film's mean as an image.
pub fn image_from_film(f: &Film) -> Image {
    Image { width: f.width, height: f.height, pixels: f.mean() }
}

/// Writes PREFIX.exr (mean + variance-of-mean layer) and PREFIX.png as one set; returns the mean.
pub fn write_images(prefix: &Path, film: &Film) -> Result<Image, String> {
    let mut set = FileSet::new();
    let img = image_files(prefix, film, &mut set)?;
    set.commit()?;
    Ok(img)
}

/// Adds PREFIX.exr (mean + variance-of-mean layer) and PREFIX.png to `set` (creating PREFIX's
/// directory); returns the mean.
pub fn image_files(prefix: &Path, film: &Film, set: &mut FileSet) -> Result<Image, String> {
    if let Some(dir) = prefix.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    }
    let img = image_from_film(film);
    let var = Image { width: film.width, height: film.height, pixels: film.variance_of_mean() };
    let (exr, png) = (with_ext(prefix, "exr"), with_ext(prefix, "png"));
    set.add(exr.clone(), image_io::encode_exr_layers(&exr, &img, Some(&var))?);
    set.add(png.clone(), image_io::encode_png_srgb(&png, &img, 0.0)?); // exposure in stops: 0 = as rendered
    Ok(img)
}

/// `prefix` + "." + `ext` (keeps dots inside the prefix).
pub fn with_ext(prefix: &Path, ext: &str) -> PathBuf {
    let mut s = prefix.as_os_str().to_owned();
    s.push(".");
    s.push(ext);
    PathBuf::from(s)
}
