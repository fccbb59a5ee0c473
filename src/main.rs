//! The `forecast` binary: parses the command line and dispatches; nothing else.

use clap::Parser;
use forecast::cli::{Cli, Command};
use forecast::{accel, bench, compare, distributed, image_io, metrics, pipeline, scenegen};
use std::process::ExitCode;
use std::time::Instant;

fn run() -> Result<(), String> {
    let started = Instant::now();
    let cli = Cli::parse();
    forecast::scene::mitsuba::set_cli_defines(&cli.define)?;
    match cli.command {
        Command::ExportMitsuba { scene, out } => {
            let rep = forecast::scene::export::export_mitsuba(&scene, &out)?;
            rep.warnings.iter().for_each(|w| eprintln!("warning: {w}"));
            println!("wrote {} and {} PLY mesh(es)", rep.xml.display(), rep.meshes.len());
            Ok(())
        }
        Command::Render(a) => {
            let cluster = distributed::try_init()?;
            let job = a.job();
            let res = pipeline::render(&job, cluster.as_ref(), started)?;
            if let Some(r) = res {
                if !a.quiet {
                    let rep = &r.report;
                    eprintln!(
                        "{}: {} spp in {:.2} s ({:.2} Msamples/s, {:.1} Mrays/s) -> {}.{{exr,png,json}}",
                        rep["method"].as_str().unwrap_or("?"),
                        rep["spp"],
                        rep["timings"]["total_s"].as_f64().unwrap_or(0.0),
                        rep["samples_per_s"].as_f64().unwrap_or(0.0) / 1e6,
                        rep["mrays_per_s"].as_f64().unwrap_or(0.0),
                        a.out.display()
                    );
                }
            }
            Ok(())
        }
        Command::Diff(a) => {
            let ia = image_io::read_exr(&a.a)?;
            let ib = image_io::read_exr(&a.b)?;
            let m = metrics::compare(&ia, &ib, a.crop)?;
            println!("RMSE      {:.6e}", m.rmse);
            println!("relMSE    {:.6e}  (eps = 0.01)", m.rel_mse);
            println!("mean A    {:.6} {:.6} {:.6}", m.mean_a[0], m.mean_a[1], m.mean_a[2]);
            println!("mean B    {:.6} {:.6} {:.6}", m.mean_b[0], m.mean_b[1], m.mean_b[2]);
            println!(
                "mean diff {:+.4}% {:+.4}% {:+.4}%",
                100.0 * m.mean_rel_diff[0],
                100.0 * m.mean_rel_diff[1],
                100.0 * m.mean_rel_diff[2]
            );
            if let Some(p) = &a.png {
                let crop_a = metrics::apply_crop(&ia, a.crop)?;
                let crop_b = metrics::apply_crop(&ib, a.crop)?;
                let scale = metrics::write_diff_png(p, &crop_a, &crop_b)?;
                println!("diff PNG  {} (saturates at |diff| = {scale:.4e})", p.display());
            }
            if let (Some(h0), Some(h1)) = (&a.half0, &a.half1) {
                let (h0, h1) = (image_io::read_exr(h0)?, image_io::read_exr(h1)?);
                let var = image_io::read_exr_variance(&a.a)?;
                let rep = metrics::mitsuba_agreement(&ia, var.as_ref(), &ib, &h0, &h1)?;
                println!("{rep}");
                if !rep.passed {
                    return Err(format!("agreement check FAILED: {}", rep.failures.join("; ")));
                }
                println!("agreement check PASSED");
            }
            Ok(())
        }
        Command::Bench(a) => {
            let scene = forecast::scene::load(&a.scene).map_err(|e| e.to_string())?;
            let t = Instant::now();
            let ntri = scene.triangles.len();
            let world = accel::World::build(scene);
            println!(
                "scene {}: {} triangles, {} spheres, BVH {:.3} s",
                a.scene.display(),
                ntri,
                world.scene.spheres.len(),
                t.elapsed().as_secs_f64()
            );
            let pool = pipeline::thread_pool(a.threads)?;
            let r = pool.install(|| bench::run(&world, a.resolution, a.repeats))?;
            println!("threads               {}", r.threads);
            println!("closest-hit Mrays/s   {:.2}  (median of {})", r.closest_mrays, a.repeats);
            println!("shadow Mrays/s        {:.2}", r.shadow_mrays);
            println!(
                "pt samples/s          {:.0}  ({}x{}, {:.2} closest + {:.2} shadow rays/sample)",
                r.pt_samples_per_s, a.resolution.0, a.resolution.1, r.rays_per_sample.0, r.rays_per_sample.1
            );
            Ok(())
        }
        Command::GenerateScenes { dir } => {
            for p in scenegen::write_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))? {
                println!("wrote {}", p.display());
            }
            Ok(())
        }
        Command::ForecastMap(a) => forecast_map(&a),
        Command::Reference(a) => {
            let cluster = distributed::try_init()?;
            if let Some(r) = compare::reference::run_reference(&a, cluster.as_ref(), started)? {
                eprintln!("reference: {} spp -> {}.{{exr,json}} + .half0/.half1", r["spp"], a.out.display());
            }
            Ok(())
        }
        Command::Compare(a) => {
            let cluster = distributed::try_init()?;
            let cfg = compare::CompareConfig {
                base: a.render.job(),
                methods: compare::parse_methods(&a.methods)?,
                budgets: compare::parse_budgets(&a.budgets)?,
                seeds: a.seeds,
                reference: a.reference.clone(),
                out: a.render.out.clone(),
            };
            if compare::run_compare(&cfg, cluster.as_ref())?.is_some() {
                eprintln!("compare: report in {}", cfg.out.join("report.html").display());
            }
            Ok(())
        }
        Command::Stability(a) => {
            let cluster = distributed::try_init()?;
            if cluster.size() > 1 {
                return Err("stability runs single-process; start it without mpirun".into());
            }
            let cfg = compare::stability::StabilityConfig {
                scenes: a.scenes.clone(),
                resolution: a.resolution,
                time_per_run: a.time_per_run,
                reference_time: a.reference_time.unwrap_or(4.0 * a.time_per_run),
                methods: compare::parse_methods(&a.methods)?,
                only: a.only.as_deref().map_or(Vec::new(), |s| s.split(',').map(|t| t.trim().to_string()).collect()),
                threads: a.threads,
                out: a.out.clone(),
            };
            let recs = compare::stability::run_suite(&cfg)?;
            compare::stability::write_stability_report(&cfg.out, &cfg, &recs)?;
            let bad = recs.iter().filter(|r| !r.ok()).count();
            eprintln!(
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
        Command::MpiSelftest => {
            let c = distributed::try_init()?;
            let r = distributed::self_test(c.as_ref());
            if c.rank() == 0 {
                match &r {
                    Ok(()) => println!("mpi self-test passed on {} rank(s)", c.size()),
                    Err(e) => eprintln!("mpi self-test FAILED: {e}"),
                }
            }
            r
        }
    }
}

fn forecast_map(a: &forecast::cli::ForecastMapArgs) -> Result<(), String> {
    use forecast::integrators::{build_forecast, iws_forecast, DEFAULT_FORECAST_PHOTONS};
    use forecast::transport::particle::Emission;
    let r = &a.render;
    let scene = forecast::scene::load(&r.scene).map_err(|e| e.to_string())?;
    let world = accel::World::build(scene);
    let opts = r.method_options();
    let seed = r.seed.unwrap_or(world.scene.render.seed);
    let target = opts.forecast_photons.or(world.scene.forecast_photons).unwrap_or(DEFAULT_FORECAST_PHOTONS);
    let pool = pipeline::thread_pool(r.threads)?;
    let (cf, untargeted) = pool.install(|| {
        let cf = build_forecast(&world, target, opts.forecast.clone(), seed);
        let n = a.compare_paths;
        let untargeted = (n > 0).then(|| {
            let (pts, paths) = forecast::transport::particle::collect_caustic_vertices(
                &world,
                Emission::Cosine,
                u64::MAX,
                n,
                seed,
                forecast::sampling::rng::stream::FORECAST,
            );
            (pts.len() as u64, paths)
        });
        (cf, untargeted)
    });
    let (w, h) = r.resolution.unwrap_or((world.scene.camera.width, world.scene.camera.height));
    let camera = world.scene.camera.with_resolution(w, h);
    let img = forecast::forecast::view::render_view(&world, &camera, &cf);
    forecast::forecast::view::write_view(&r.out, &img)?;
    let targeted_yield = cf.stats.yield_per_path;
    let untargeted_yield = untargeted.map(|(n, p)| n as f64 / p.max(1) as f64);
    let report = serde_json::json!({
        "scene": world.scene.path,
        "preprocess": cf.stats,
        "options": cf.opts,
        "targeted_emission": format!("{:?}", iws_forecast::targeted_emission(&world)),
        "yield_targeted_per_path": targeted_yield,
        "yield_untargeted_per_path": untargeted_yield,
        "targeted_gain": untargeted_yield.map(|u| if u > 0.0 { targeted_yield / u } else { f64::INFINITY }),
        "clusters": cf.clustering.clusters.iter().map(|c| serde_json::json!({
            "rank": c.rank, "points": c.members.len(), "power": c.power, "area": c.area, "density": c.density,
        })).collect::<Vec<_>>(),
    });
    let text = serde_json::to_string_pretty(&report).map_err(|e| e.to_string())?;
    image_io::atomic_write(&pipeline::with_ext(&r.out, "json"), text.as_bytes())?;
    println!("{text}");
    Ok(())
}

/// Restores the default SIGPIPE action so that `forecast diff … | head` ends quietly like other
/// Unix tools instead of panicking on a closed stdout (Rust ignores SIGPIPE by default).
fn default_sigpipe() {
    #[cfg(unix)]
    {
        extern "C" {
            fn signal(signum: i32, handler: usize) -> usize;
        }
        const SIGPIPE: i32 = 13;
        const SIG_DFL: usize = 0;
        // SAFETY: resetting a signal disposition to its default before any thread is started.
        unsafe {
            signal(SIGPIPE, SIG_DFL);
        }
    }
}

fn main() -> ExitCode {
    default_sigpipe();
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
