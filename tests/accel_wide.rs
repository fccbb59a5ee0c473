//! The default back end's own tree (`--accel wide`, `accel/wide.rs`) against obvhs' CWBVH
//! (`--accel obvhs`, the default before it) in images: `pt` and `pt-cf` rendered with each, at
//! different seeds, must agree by `common::assert_agrees` (Šidák per-pixel and whole-image Welch
//! z-tests, family-wise α = 1e-3, with its negative control: a 3% scaling must be detected).
//!
//! The two trees' hits are not bit for bit the same: at exact ties in t another primitive may
//! win, and `wide` finds hits at t < 1e-4 that obvhs' node-entry floor misses (the hit-level
//! comparison, against brute force wherever the two differ, is `accel::wide`'s unit tests), so
//! the images are compared to noise, not hashed.
//!
//! Scenes: `ring` under the wide light (`common::ring_with_wide_light`: tails light enough for the
//! CLT at 8×8, the passes those of `tests/accel_embree.rs`) and the pool
//! (`scenes/external/sms-pool`, 45k triangles of a scene written by others). On the pool the
//! z-tests run without the negative control: its caustic tails are so heavy that at 16×9 and
//! 4,096 passes a 3% error moves the global z by only 0.21 (`pt`) and 0.71 (`pt-cf`), far below
//! the control's 6.58 (measured when this test was written): there the test catches gross
//! differences (a lost surface, a wrong primitive's shading), not percent-level ones; `ring`
//! carries the power.

mod common;

use forecast::accel::{AccelKind, World};
use forecast::integrators::{Method, MethodArgs};
use forecast::render::film::Film;
use std::path::Path;

/// `method` on `w` (its preprocess with seed 17), `passes` passes of a `w`×`h` image.
fn img(w: &World, method: Method, o: &MethodArgs, (x, y): (u32, u32), passes: u64, seed: u64) -> Film {
    let bytes = method.preprocess(w, o, 17).expect("preprocess");
    let mut g = method.build(w, o, &bytes).expect("builds");
    common::render_passes(w, g.as_mut(), x, y, passes, seed)
}

/// `w` (the default tree) and the same scene on obvhs' tree.
fn both(w: World) -> (World, World) {
    assert_eq!(w.accel(), AccelKind::Wide, "the default back end");
    let o = World::build_with(w.scene.clone(), AccelKind::Obvhs).expect("obvhs builds");
    (w, o)
}

fn agree(scene: World, method: Method, o: &MethodArgs, res: (u32, u32), passes: u64, label: &str) {
    let (w, ob) = both(scene);
    common::assert_agrees(&img(&w, method, o, res, passes, 2), &img(&ob, method, o, res, passes, 1), label);
}

/// The z-tests of `assert_agrees` without its negative control (see the module doc: on the pool
/// the control has no power at a test's size).
fn agree_no_control(scene: World, method: Method, o: &MethodArgs, res: (u32, u32), passes: u64, label: &str) {
    let (w, ob) = both(scene);
    let (a, b) = (img(&w, method, o, res, passes, 2), img(&ob, method, o, res, passes, 1));
    let (z, n) = common::max_z(&a, &b, None);
    let thr = forecast::stats::z_test_threshold(1e-3, n);
    eprintln!("{label}: max|z| = {z:.2}, threshold {thr:.2} over {n} tests");
    assert!(z < thr, "{label}: max|z| {z} ≥ {thr}");
    let (zg, thr1) = (common::global_z(&a, &b), forecast::stats::z_test_threshold(1e-3, 1));
    eprintln!("{label}: global z = {zg:.2}, threshold {thr1:.2}");
    assert!(zg.abs() < thr1, "{label}: image means differ, z {zg}");
}

fn pool() -> World {
    World::build(forecast::scene::load(Path::new("scenes/external/sms-pool/scene.xml")).expect("loads"))
        .expect("builds")
}

#[test]
fn pt_ring() {
    agree(common::ring_with_wide_light(), Method::Pt, &MethodArgs::default(), (8, 8), 32768, "pt wide vs obvhs (ring)");
}

#[test]
fn pt_cf_ring() {
    agree(
        common::ring_with_wide_light(),
        Method::PtCf,
        &common::cf_test_opts(),
        (8, 8),
        32768,
        "pt-cf wide vs obvhs (ring)",
    );
}

#[test]
fn pt_pool() {
    agree_no_control(pool(), Method::Pt, &MethodArgs::default(), (16, 9), 4096, "pt wide vs obvhs (pool)");
}

#[test]
fn pt_cf_pool() {
    agree_no_control(pool(), Method::PtCf, &common::cf_test_opts(), (16, 9), 4096, "pt-cf wide vs obvhs (pool)");
}
