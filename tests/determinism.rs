//! Renders are a pure function of (scene, seed, pass, pixel): the film is bit-identical for any
//! thread count, and different seeds give different films (spec: counter-based RNG streams, tiles
//! merged in tile order).

mod common;

use common::{job, render_film, root, tmp_dir};
use forecast::integrators::Method;
use forecast::render::film::Film;

fn cornell(seed: u64, threads: usize, tag: &str) -> Film {
    let dir = tmp_dir(&format!("det-{tag}-{seed}-{threads}"));
    let f = render_film(&job(
        &root().join("scenes/cornell-box.toml"),
        Method::Pt,
        4,
        seed,
        (32, 32),
        threads,
        &dir.join("out"),
    ));
    let _ = std::fs::remove_dir_all(dir);
    f
}

fn bits(f: &Film) -> Vec<u64> {
    f.data.iter().map(|x| x.to_bits()).collect()
}

#[test]
fn same_seed_is_bit_identical_for_any_thread_count() {
    let a = cornell(7, 1, "a");
    assert_eq!(a.total_samples(), 32.0 * 32.0 * 4.0);
    assert!(a.data.iter().all(|x| x.is_finite()));
    // the image is not trivially black (otherwise identity would prove nothing)
    assert!(a.mean().iter().filter(|p| p[0] > 0.0).count() > 500);
    for threads in [2, 3] {
        let b = cornell(7, threads, "b");
        assert!(bits(&a) == bits(&b), "threads=1 and threads={threads} differ");
    }
    // and it is reproducible run to run with the same thread count
    assert!(bits(&a) == bits(&cornell(7, 1, "c")));
}

#[test]
fn different_seeds_differ() {
    let a = cornell(1, 2, "s");
    let b = cornell(2, 2, "s");
    let differing = a.mean().iter().zip(b.mean().iter()).filter(|(x, y)| x != y).count();
    // With 4 spp of a noisy path tracer nearly every lit pixel differs; require most of them.
    assert!(differing > 32 * 32 / 2, "only {differing} pixels differ between seeds 1 and 2");
}

/// Every method, preprocess included (the CF photons and tables, the shared table cache, the IWS
/// point lights, `pt-cf`'s light paths and pilot): the film is bit-identical for 1 and 3 threads.
#[test]
fn every_method_is_bit_identical_for_any_thread_count() {
    for method in [Method::Iws, Method::IwsPm, Method::IwsCf, Method::PtCf] {
        let film = |threads: usize| {
            let dir = tmp_dir(&format!("det-{}-{threads}", method.name()));
            let mut j = job(&root().join("scenes/cornell-box.toml"), method, 2, 5, (32, 32), threads, &dir.join("out"));
            (j.args.cf.forecast_photons, j.args.cf.clusters, j.args.pm.photons) = (Some(20_000), 16, 20_000);
            let f = render_film(&j);
            let _ = std::fs::remove_dir_all(dir);
            f
        };
        let a = film(1);
        assert!(a.mean().iter().filter(|p| p[0] > 0.0).count() > 500, "{}: a black image", method.name());
        assert!(bits(&a) == bits(&film(3)), "{}: threads=1 and threads=3 differ", method.name());
    }
}
