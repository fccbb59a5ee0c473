//! The `forecast` binary: parses the command line and dispatches; nothing else.

use forecast::cli::{Cli, Command};
use forecast::{accel, bench, compare, distributed, errln, image_io, metrics, outln, output, pipeline, scenegen};
use std::process::ExitCode;
use std::time::Instant;

/// Why the command failed: the message, whether this process prints it (under `mpirun` the
/// ranks agree on every error and only rank 0 prints it, once), and whether it is a usage error
/// (exit 2, in clap's format).
struct Failure {
    message: String,
    print: bool,
    usage: bool,
    /// A render ended by Ctrl-C/SIGTERM after writing what was done (exit 130, nothing printed).
    interrupted: bool,
}

impl From<String> for Failure {
    fn from(message: String) -> Failure {
        Failure { message, print: true, usage: false, interrupted: false }
    }
}

/// Runs `f` on the cluster; an error is printed by rank 0 only (the pipeline agrees errors
/// across ranks, so rank 0's message names every failing rank).
fn on_cluster<T>(f: impl FnOnce(&dyn distributed::Cluster) -> Result<T, String>) -> Result<T, Failure> {
    on_cluster_usage(f, |_| false)
}

/// [`on_cluster`], with `usage` telling which errors are usage errors (exit 2).
fn on_cluster_usage<T, E: std::fmt::Display>(
    f: impl FnOnce(&dyn distributed::Cluster) -> Result<T, E>,
    usage: impl FnOnce(&E) -> bool,
) -> Result<T, Failure> {
    let cluster = distributed::try_init().map_err(String::from)?;
    let print = cluster.rank() == 0;
    f(cluster.as_ref()).map_err(|e| Failure { usage: usage(&e), message: e.to_string(), print, interrupted: false })
}

/// Parses the command line with `try_parse`, so that `--help`/`--version` text that cannot be
/// written (a full stdout) is an error (exit 1), and a usage error exits 2 (`output::EXIT_USAGE`).
fn parse() -> Result<Cli, ExitCode> {
    use std::io::Write;
    let e = match Cli::parse_checked() {
        Ok(cli) => return Ok(cli),
        Err(e) => e,
    };
    let text = e.render().to_string();
    if e.use_stderr() {
        let _ = std::io::stderr().lock().write_all(text.as_bytes());
        return Err(ExitCode::from(e.exit_code().clamp(0, 255) as u8));
    }
    let mut out = std::io::stdout().lock();
    match out.write_all(text.as_bytes()).and_then(|()| out.flush()) {
        Ok(()) => Err(ExitCode::from(output::EXIT_OK)),
        Err(err) => {
            errln!("error: cannot write to stdout: {err}");
            Err(ExitCode::from(output::EXIT_ERROR))
        }
    }
}

fn run(cli: Cli) -> Result<(), Failure> {
    let started = Instant::now();
    let opts = forecast::scene::LoadOptions { defines: cli.define };
    match cli.command {
        Command::Render(a) => {
            let interrupted = on_cluster_usage(|c| render(&a, &opts, c, started), |e| foreign_flag_usage(&a, e))?;
            match interrupted {
                false => Ok(()),
                true => Err(Failure { message: String::new(), print: false, usage: false, interrupted: true }),
            }
        }
        Command::Diff(a) => Ok(diff(&a)?),
        Command::Bench(a) => Ok(bench_cmd(&a, &opts)?),
        Command::ExportMitsuba { scene, out } => {
            forecast::atomic_io::check_input("scene file", &scene).map_err(String::from)?;
            let rep = forecast::scene::export::export_mitsuba(&scene, &out)?;
            rep.warnings.iter().for_each(|w| errln!("warning: {w}"));
            outln!("wrote {} and {} PLY mesh(es)", rep.xml.display(), rep.meshes.len())?;
            Ok(())
        }
        Command::GenerateScenes { dir } => {
            for p in scenegen::write_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))? {
                outln!("wrote {}", p.display())?;
            }
            Ok(())
        }
        Command::ForecastMap(a) => Ok(forecast_map(&a, &opts)?),
        Command::Reference(a) => on_cluster(|c| {
            let job = pipeline::RenderJob { defines: opts.defines.clone(), ..a.job() };
            if let Some(r) = compare::reference::run_reference(&job, c, started)? {
                if r.halves.iter().all(|h| nothing_resumed_added(h, &a)) {
                    let held = r.halves[0].first_pass + r.halves[1].first_pass;
                    warn_nothing_added("the checkpoints already hold", held, a.spp);
                }
                errln!("reference: {} spp -> {}.{{exr,json}} + .half0/.half1", r.spp, a.out.display());
            }
            Ok(())
        }),
        Command::Compare(a) => on_cluster(|c| {
            let mut cfg = a.config();
            cfg.base.defines = opts.defines.clone();
            if compare::run_compare(&cfg, c)?.is_some() {
                errln!("compare: report in {}", cfg.out.join("report.html").display());
            }
            Ok(())
        }),
        Command::Stability(a) => Ok(stability(&a)?),
        Command::MpiSelftest => on_cluster(|c| {
            let r = distributed::self_test(c);
            if c.rank() == 0 {
                match &r {
                    Ok(()) => outln!("mpi self-test passed on {} rank(s)", c.size())?,
                    Err(e) => errln!("mpi self-test FAILED: {e}"),
                }
            }
            Ok(r?)
        }),
    }
}

/// A render's failure because a flag of the command line belongs to another method than the
/// one the scene (or `auto`) chose is a usage error (exit 2), as it is at parse time for
/// `--method M`: the error refuses the flag that `MethodArgs::foreign_flag` finds first among
/// the command line's for that method (the scene's `[render]` table may name it too).
fn foreign_flag_usage(a: &forecast::cli::RenderArgs, e: &pipeline::RenderError) -> bool {
    use forecast::integrators::{MethodArgs, MethodError};
    match e.foreign_flag() {
        Some(f @ MethodError::ForeignFlag { method, .. }) => {
            MethodArgs::foreign_flag(*method, &a.method_args.explicit).as_ref() == Some(f)
        }
        _ => false,
    }
}

/// `forecast render`; `Ok(true)` when a signal ended it early (its outputs are written).
fn render(
    a: &forecast::cli::RenderArgs,
    opts: &forecast::scene::LoadOptions,
    cluster: &dyn distributed::Cluster,
    started: Instant,
) -> Result<bool, pipeline::RenderError> {
    let interrupt = forecast::interrupt::Interrupt::install()?;
    let job = pipeline::RenderJob { defines: opts.defines.clone(), interrupt, ..a.job() };
    let res = pipeline::render(&job, cluster, started)?;
    let mut interrupted = false;
    if let Some(r) = res {
        if r.report.interrupted {
            interrupted = true;
            errln!(
                "interrupted: the {} passes done are in {}.{{exr,png,json}}{}",
                r.report.passes,
                a.out.display(),
                if job.checkpoint_every.is_some() { " and the checkpoint (--resume adds passes)" } else { "" }
            );
        }
        if nothing_resumed_added(&r.report, a) {
            warn_nothing_added("the checkpoint already holds", r.report.first_pass, a.spp);
        }
        if !a.quiet {
            let rep = &r.report;
            errln!(
                "{}: {} spp in {:.2} s ({:.2} Msamples/s, {:.1} Mrays/s) -> {}.{{exr,png,json}}",
                rep.method.name(),
                rep.spp,
                rep.timings.total_s,
                rep.samples_per_s / 1e6,
                rep.mrays_per_s,
                a.out.display()
            );
        }
    }
    Ok(interrupted)
}

/// Whether a `--resume` render added no pass: its checkpoint already held the requested total
/// (`--spp N`, or the scene's `render.spp`), so the run stops at once (docs/cli.md, "Checkpoints").
fn nothing_resumed_added(rep: &pipeline::RenderReport, a: &forecast::cli::RenderArgs) -> bool {
    rep.resumed && rep.passes == rep.first_pass && rep.time_budget_s.is_none() && a.max_rounds.is_none()
}

/// The warning (stderr, even under `--quiet`) of a resume that added nothing.
fn warn_nothing_added(what: &str, held: u64, spp: Option<u64>) {
    let asked = spp.map_or_else(|| "the scene's render.spp".to_string(), |n| format!("--spp {n}"));
    errln!(
        "warning: --resume: {what} {held} passes, at least the requested total ({asked}), so no pass was \
         added; give a larger --spp (or --time) to add passes"
    );
}

fn diff(a: &forecast::cli::DiffArgs) -> Result<(), String> {
    if let Some(p) = &a.png {
        let mut guard = forecast::atomic_io::OutputSet::new();
        guard.input("the image A", &a.a).input("the image B", &a.b).output("--png", p);
        a.half0.iter().chain(&a.half1).for_each(|h| {
            guard.input("a --half0/--half1 image", h);
        });
        guard.check()?;
    }
    let ia = image_io::read_exr(&a.a)?;
    let ib = image_io::read_exr(&a.b)?;
    image_io::check_same_size(&[(&a.a, &ia), (&a.b, &ib)])?;
    let m = metrics::compare(&ia, &ib, a.crop)?;
    outln!("RMSE      {:.6e}", m.rmse)?;
    outln!("relMSE    {:.6e}  (eps = 0.01)", m.rel_mse)?;
    outln!("mean A    {:.6} {:.6} {:.6}", m.mean_a[0], m.mean_a[1], m.mean_a[2])?;
    outln!("mean B    {:.6} {:.6} {:.6}", m.mean_b[0], m.mean_b[1], m.mean_b[2])?;
    outln!(
        "mean diff {:+.4}% {:+.4}% {:+.4}%",
        100.0 * m.mean_rel_diff[0],
        100.0 * m.mean_rel_diff[1],
        100.0 * m.mean_rel_diff[2]
    )?;
    if let Some(p) = &a.png {
        let crop_a = metrics::apply_crop(&ia, a.crop)?;
        let crop_b = metrics::apply_crop(&ib, a.crop)?;
        let scale = metrics::write_diff_png(p, &crop_a, &crop_b)?;
        outln!("diff PNG  {} (saturates at |diff| = {scale:.4e})", p.display())?;
    }
    let (Some(p0), Some(p1)) = (&a.half0, &a.half1) else {
        outln!(
            "verdict   none: whether A and B agree within their noise needs B's two independent halves \
             (--half0 B0.exr --half1 B1.exr, as `forecast reference` writes them)"
        )?;
        return Ok(());
    };
    let (h0, h1) = (image_io::read_exr(p0)?, image_io::read_exr(p1)?);
    image_io::check_same_size(&[(&a.b, &ib), (p0, &h0), (p1, &h1)])?;
    let var = image_io::read_exr_variance(&a.a)?;
    independent_images(&[("A", &a.a, &ia), ("B", &a.b, &ib), ("--half0", p0, &h0), ("--half1", p1, &h1)])?;
    let rep = metrics::mitsuba_agreement(&ia, var.as_ref(), &ib, &h0, &h1)?;
    outln!("{rep}")?;
    let worst = rep.mean_rel_diff.iter().fold(0.0f64, |m, d| m.max(d.abs()));
    let stats = format!(
        "largest mean difference {:.3}% (limit {:.1}%), noise ratio {:.3} (1 ± {:.3})",
        100.0 * worst,
        100.0 * metrics::MEAN_REL_TOLERANCE,
        rep.ratio,
        rep.noise.ratio_tolerance
    );
    if !rep.passed {
        outln!("verdict   differ: {stats}")?;
        return Err(format!("agreement check FAILED: {}", rep.failures.join("; ")));
    }
    outln!("verdict   agree: {stats}")?;
    outln!("agreement check PASSED")?;
    Ok(())
}

/// Refuses a `diff --half0/--half1` check whose images are not independent: two of A, B and the
/// halves with the same pixels (the same file given twice, or a copy) make the noise check pass
/// or fail vacuously (identical halves estimate no noise; A equal to the reference has none).
fn independent_images(images: &[(&str, &std::path::Path, &image_io::Image)]) -> Result<(), String> {
    for (i, (n0, p0, im0)) in images.iter().enumerate() {
        for (n1, p1, im1) in &images[i + 1..] {
            if im0.pixels == im1.pixels {
                return Err(format!(
                    "diff: {n0} `{}` and {n1} `{}` are the same image: the agreement check needs a test image and \
                     two reference halves rendered independently (different seeds) of each other",
                    p0.display(),
                    p1.display()
                ));
            }
        }
    }
    Ok(())
}

fn bench_cmd(a: &forecast::cli::BenchArgs, opts: &forecast::scene::LoadOptions) -> Result<(), String> {
    forecast::param_limits::SPP.check_flag("--spp", a.spp)?;
    a.accel.check()?;
    forecast::atomic_io::check_input("scene file", &a.scene)?;
    let scene = forecast::scene::load_with(&a.scene, opts).map_err(|e| e.to_string())?;
    let t = Instant::now();
    let ntri = scene.triangles.len();
    let world = accel::World::build_with(scene, a.accel).map_err(|e| format!("{}: {e}", a.scene.display()))?;
    outln!(
        "scene {}: {} triangles, {} spheres, BVH ({}) {:.3} s",
        a.scene.display(),
        ntri,
        world.scene.spheres.len(),
        a.accel.name(),
        t.elapsed().as_secs_f64()
    )?;
    let pool = pipeline::thread_pool(a.threads)?;
    let r = pool.install(|| bench::run(&world, a.resolution, a.repeats))?;
    outln!("threads               {}", r.threads)?;
    outln!("closest-hit Mrays/s   {:.2}  (median of {})", r.closest_mrays, a.repeats)?;
    outln!("shadow Mrays/s        {:.2}", r.shadow_mrays)?;
    outln!(
        "pt samples/s          {:.0}  ({}x{}, {:.2} closest + {:.2} shadow rays/sample)",
        r.pt_samples_per_s,
        a.resolution.0,
        a.resolution.1,
        r.rays_per_sample.0,
        r.rays_per_sample.1
    )?;
    if let Some(m) = a.method {
        let p = pool.install(|| bench::profile_method(&world, m, a.resolution, a.spp))?;
        outln!("{} per-phase profile (CPU µs per sample, {} samples):", m.name(), p.samples)?;
        outln!("{}", serde_json::to_string_pretty(&p).map_err(|e| e.to_string())?)?;
    }
    Ok(())
}

fn stability(a: &forecast::cli::StabilityArgs) -> Result<(), String> {
    let cluster = distributed::try_init()?;
    if cluster.size() > 1 {
        return Err("stability runs single-process; start it without mpirun".into());
    }
    let cfg = a.config();
    if !a.only.is_empty() && cfg.only.is_empty() {
        return Err("--only: no case named (give case names, comma-separated)".into());
    }
    let recs = compare::stability::run_suite(&cfg)?;
    compare::stability::write_stability_report(&cfg.out, &cfg, &recs)?;
    let bad = recs.iter().filter(|r| !r.ok()).count();
    errln!(
        "stability: {} of {} runs ok; report in {}",
        recs.len() - bad,
        recs.len(),
        cfg.out.join("stability.html").display()
    );
    if bad > 0 {
        return Err(format!("stability: {bad} run(s) failed"));
    }
    Ok(())
}

fn forecast_map(a: &forecast::cli::ForecastMapArgs, opts: &forecast::scene::LoadOptions) -> Result<(), String> {
    use forecast::integrators::iws_cf::{self, build_forecast};
    use forecast::transport::particle::Emission;
    let r = &a.render;
    forecast::atomic_io::check_output_prefix(&r.out)?;
    let accel = r.method_args.settings.accel;
    accel.check()?; // before any work, as `bench` and `render`
    forecast::atomic_io::check_input("scene file", &r.scene)?;
    let scene = forecast::scene::load_with(&r.scene, opts).map_err(|e| e.to_string())?;
    let mut guard = forecast::atomic_io::OutputSet::new();
    guard.scene_inputs(&r.scene, &scene.mesh_files).output("--out", &image_io::with_ext(&r.out, "png"));
    guard.output("--out", &image_io::with_ext(&r.out, "json")).check()?;
    let world = accel::World::build_with(scene, accel).map_err(|e| format!("{}: {e}", r.scene.display()))?;
    let cf_args = &r.method_args.cf;
    let cf_opts = r.method_args.forecast_options();
    let seed = r.seed.unwrap_or(world.scene.render.seed);
    let target = cf_args.target_photons(&world);
    // bounded before any work, as `render`: the photons by the memory estimate, the comparison's
    // paths by their limit and the vertices it keeps by the memory left
    forecast::param_limits::COMPARE_PATHS.check_flag("--compare-paths", a.compare_paths)?;
    let (w, h) = r.resolution.unwrap_or((world.scene.camera.width, world.scene.camera.height));
    let (need, what) = pipeline::memory::forecast_map_estimate(&world.scene, target, (w, h));
    pipeline::memory::check(need, &what)?;
    let vertex_cap = pipeline::memory::forecast_map_vertex_cap(
        need,
        std::mem::size_of::<forecast::transport::particle::CausticVertex>(),
    );
    let pool = pipeline::thread_pool(r.threads)?;
    let phases = forecast::progress::PhaseBar::new(!r.quiet);
    let (cf, untargeted) = pool.install(|| {
        let cf = build_forecast(&world, target, cf_opts, seed, &phases);
        let n = a.compare_paths;
        let untargeted = (n > 0).then(|| {
            let (pts, paths) = forecast::transport::particle::collect_caustic_vertices(
                &world,
                Emission::Cosine,
                vertex_cap,
                n,
                seed,
                forecast::sampling::rng::stream::FORECAST,
                &|_| true,
            );
            (pts.len() as u64, paths)
        });
        (cf, untargeted)
    });
    let camera = world.scene.camera.with_resolution(w, h);
    let img = forecast::cf::view::render_view(&world, &camera, &cf);
    forecast::cf::view::write_view(&r.out, &img)?;
    let targeted_yield = cf.stats.yield_per_path;
    let untargeted_yield = untargeted.map(|(n, p)| n as f64 / p.max(1) as f64);
    let report = serde_json::json!({
        "scene": world.scene.path,
        "preprocess": cf.stats,
        "options": cf.opts,
        "targeted_emission": format!("{:?}", iws_cf::targeted_emission(&world)),
        "yield_targeted_per_path": targeted_yield,
        "yield_untargeted_per_path": untargeted_yield,
        "targeted_gain": untargeted_yield.map(|u| if u > 0.0 { targeted_yield / u } else { f64::INFINITY }),
        "clusters": cf.clustering.clusters.iter().map(|c| serde_json::json!({
            "rank": c.rank, "points": c.members.len(), "power": c.power, "area": c.area, "density": c.density,
        })).collect::<Vec<_>>(),
    });
    let text = serde_json::to_string_pretty(&report).map_err(|e| e.to_string())?;
    image_io::atomic_write(&image_io::with_ext(&r.out, "json"), text.as_bytes())?;
    outln!("{text}")?;
    Ok(())
}

fn main() -> ExitCode {
    // SIGPIPE stays ignored (Rust's default): a closed stdout is handled in `output`, a closed
    // stderr must never end a render
    let cli = match parse() {
        Ok(cli) => cli,
        Err(code) => return code,
    };
    match run(cli) {
        Ok(()) => ExitCode::from(output::EXIT_OK),
        Err(f) if f.interrupted => ExitCode::from(forecast::interrupt::EXIT_INTERRUPTED),
        Err(f) if f.usage => {
            if f.print {
                let text = forecast::cli::render_usage_error(f.message).render().to_string();
                let _ = std::io::Write::write_all(&mut std::io::stderr().lock(), text.as_bytes());
            }
            ExitCode::from(output::EXIT_USAGE)
        }
        Err(f) => {
            if f.print {
                errln!("error: {}", f.message);
            }
            ExitCode::from(output::EXIT_ERROR)
        }
    }
}
