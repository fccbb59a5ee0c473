//! The batched queries and the wavefront `pt` (issue #33) against their scalar forms, bit for bit.
//!
//! - `World::intersect_batch` (its answers' records built by `World::hit_at`) and
//!   `World::occluded_batch` must return exactly what `intersect` / `occluded` return ray by ray
//!   (primitive, t, position and normals compared as bits), for random rays of
//!   `common::random_ray`, batches of several sizes (1, 7, 256: the packets' remainders), with
//!   and without the coherent hint, and the degenerate segments a path can produce (tmax 0,
//!   negative, NaN).
//! - `pt`'s `estimate_batch` (the wavefront, `integrators::pt::wavefront`) must return exactly the
//!   estimates of `estimate` ray by ray (`integrators::estimate_each`) on every camera ray of a
//!   small image with its per-pixel streams, for one pass and for a pass group (each pixel's 16
//!   camera rays side by side, traced with the coherent hint): the wavefront changes when a ray
//!   is traced, never what a path draws or adds. Scenes: `cornell-box` (glass and mirror spheres, Dirac chains),
//!   `ring` (a conductor mesh), the glass furnace, `figurines` (smooth normals, a glossy lobe) and a
//!   point light over a mirror (where the diffuse vertices' 16-wide lanes, `pt::lanes`, do not
//!   apply); elsewhere every diffuse vertex goes through those lanes.
//!
//! Each test runs on every back end of the build: obvhs always, Embree with `--features embree`
//! (`scripts/test.sh` runs this file in both builds), where the batch goes through Embree's
//! 16-wide packets, the 40-sphere scene through its user geometry.

mod common;

use forecast::accel::{AccelKind, BatchScratch, Ray, World};
use forecast::integrators::{estimate_each, CameraEstimate, Context, Method, MethodArgs};
use forecast::math::Vec3;
use forecast::sampling::rng::{stream, Rng};

fn backends() -> Vec<AccelKind> {
    [AccelKind::Wide, AccelKind::Obvhs, AccelKind::Embree].into_iter().filter(|k| k.available()).collect()
}

fn world(path: &str, kind: AccelKind) -> World {
    let s = forecast::scene::load(&common::root().join(path)).expect("scene loads");
    World::build_with(s, kind).expect("world builds")
}

/// The cornell box with 40 more spheres (Embree's user geometry, beyond its sphere loop).
fn many_spheres(kind: AccelKind) -> World {
    World::build_with(common::cornell_with_many_spheres(), kind).expect("world builds")
}

fn bits(v: Vec3) -> [u32; 3] {
    v.to_array().map(f32::to_bits)
}

/// `n` random rays, one in 16 with a degenerate tmax (0, negative or NaN).
fn rays(w: &World, n: usize, seed: u64) -> Vec<Ray> {
    let mut rng = Rng::keyed(seed, stream::MISC, 0, 0);
    (0..n)
        .map(|k| {
            let (o, d, tmax) = common::random_ray(&w.scene, &mut rng, k);
            let tmax = match k % 48 {
                5 => 0.0,
                21 => -1.0,
                37 => f32::NAN,
                _ => tmax,
            };
            Ray { o, d, tmax }
        })
        .collect()
}

fn batch_equals_single(w: &World, label: &str, seed: u64) {
    let rays = rays(w, 6000, seed);
    let mut scratch = BatchScratch::default();
    let (mut hits, mut occ) = (Vec::new(), Vec::new());
    for (size, coherent) in [(1, false), (7, false), (256, false), (7, true), (256, true)] {
        for chunk in rays.chunks(size) {
            w.intersect_batch(chunk, &mut scratch, &mut hits, coherent);
            w.occluded_batch(chunk, &mut scratch, &mut occ);
            assert_eq!((hits.len(), occ.len()), (chunk.len(), chunk.len()), "{label}: one answer per ray");
            for ((r, h), &o) in chunk.iter().zip(&hits).zip(&occ) {
                let single = w.intersect(r.o, r.d, r.tmax);
                let key = |h: Option<forecast::accel::Hit>| {
                    h.map(|h| (h.prim, h.t.to_bits(), bits(h.p), bits(h.ng), bits(h.ns)))
                };
                assert_eq!(
                    key(h.map(|h| w.hit_at(r, h))),
                    key(single),
                    "{label} ({:?}), batch {size}, coherent {coherent}: closest hit of {r:?}",
                    w.accel()
                );
                assert_eq!(
                    o,
                    w.occluded(r.o, r.d, r.tmax),
                    "{label} ({:?}), batch {size}: occlusion of {r:?}",
                    w.accel()
                );
            }
        }
    }
}

#[test]
fn batch_queries_equal_single_queries() {
    for kind in backends() {
        batch_equals_single(&world("scenes/cornell-box.toml", kind), "cornell-box", 1);
        batch_equals_single(&world("scenes/ring.toml", kind), "ring", 2);
        batch_equals_single(&many_spheres(kind), "cornell-box + 40 spheres", 3);
    }
}

/// `pt`'s wavefront against its scalar loop on every camera ray of a `res`² image: one pass,
/// then a group of 16 passes (the camera rays traced as coherent runs).
/// `min_lit`: the fraction of camera rays whose estimate is not 0 (the test is not vacuous).
fn wavefront_equals_scalar(w: &World, label: &str, res: u32, min_lit: f64) {
    method_wavefront_equals_scalar(w, Method::Pt, label, res, min_lit);
}

/// Asserts that `label`'s run reached guided vertices, split ones among them (more
/// continuations than guided vertices).
fn assert_guided(label: &str, (inside, samples): (u64, u64)) {
    eprintln!("{label}: {inside} guided vertices, {samples} continuations");
    assert!(inside > 0, "{label}: no guided vertex: the test does not reach the guided code");
    assert!(samples > inside, "{label}: no split vertex ({samples} continuations at {inside})");
}

/// [`wavefront_equals_scalar`] for `method` (`pt`, or `pt-cf` with its light side on: the
/// camera's MIS ratio is tracked through the wavefront too). Returns the guide's counters of
/// both runs (`pt-cf`): (vertices inside a guided cluster, continuations drawn there).
fn method_wavefront_equals_scalar(w: &World, method: Method, label: &str, res: u32, min_lit: f64) -> (u64, u64) {
    let mut args = MethodArgs::default();
    args.settings.max_depth = Some(64);
    let pt = method.build(w, &args, &method.preprocess(w, &args, 1).expect("preprocess")).expect("build");
    let cam = w.scene.camera.with_resolution(res, res);
    let mut guided = (0, 0);
    // one pass, then a pass group of 16 (each pixel's 16 camera rays side by side)
    for passes in [vec![0u64], (1..17).collect::<Vec<u64>>()] {
        let (mut rays, mut rngs) = (Vec::new(), Vec::new());
        for p in 0..(res * res) as u64 {
            for &pass in &passes {
                let mut rng = Rng::keyed(9, stream::CAMERA, pass, p);
                let [jx, jy] = rng.next_2d();
                let (x, y) = ((p % res as u64) as f32, (p / res as u64) as f32);
                rays.push(Ray { o: cam.position, d: cam.direction(x + jx, y + jy), tmax: f32::INFINITY });
                rngs.push(rng);
            }
        }
        let pass = passes[0];
        let mut scalar_rngs = rngs.clone();
        let mut ctx = Context::new(Rng::keyed(0, stream::MISC, 0, 0));
        ctx.camera = Some(cam.clone());
        let (mut batch, mut scalar) = (Vec::new(), Vec::new());
        pt.estimate_batch(w, &rays, &mut rngs, &mut ctx, &mut batch);
        estimate_each(pt.as_ref(), w, &rays, &mut scalar_rngs, &mut ctx, &mut scalar);
        guided = (guided.0 + ctx.profile.cf.inside, guided.1 + ctx.profile.cf.samples);
        let key = |e: &CameraEstimate| (bits(e.prefix_le), bits(e.rest));
        let lit = scalar.iter().filter(|e| e.total() != Vec3::ZERO).count();
        assert!(lit as f64 > min_lit * rays.len() as f64, "{label}: the test image is lit ({lit} of {})", rays.len());
        for (i, (b, s)) in batch.iter().zip(&scalar).enumerate() {
            assert_eq!(key(b), key(s), "{label} ({:?}), pass {pass}, pixel {i}", w.accel());
        }
    }
    guided
}

#[test]
fn pt_wavefront_is_bit_identical_to_the_scalar_loop() {
    for kind in backends() {
        wavefront_equals_scalar(&world("scenes/cornell-box.toml", kind), "cornell-box", 48, 0.25);
        wavefront_equals_scalar(&world("scenes/ring.toml", kind), "ring", 48, 0.25);
        wavefront_equals_scalar(&world("tests/scenes/furnace_glass.toml", kind), "glass furnace", 32, 0.25);
        // smooth shading normals and a glossy lobe beside the diffuse lanes
        wavefront_equals_scalar(&world("scenes/figurines.toml", kind), "figurines", 32, 0.25);
        // a point light: the diffuse lanes do not apply (`pt::lanes`), every vertex is scalar;
        // the light reaches a fifth of this view (the floor it lights)
        wavefront_equals_scalar(&world("tests/scenes/point-mirror.toml", kind), "point mirror", 32, 0.1);
    }
}

/// `pt-cf`'s wavefront (`integrators::pt_cf::wavefront`) against `trace`, bit for bit: guided and
/// split vertices (`cornell-box`'s glass caustic, `ring`'s cardioid, `figurines`, the mirror's
/// caustic; each reached, `assert_guided`), the MIS ratio against the light paths at lane and
/// scalar vertices, and a point light (no lanes).
#[test]
fn pt_cf_wavefront_is_bit_identical_to_the_scalar_loop() {
    let cases = [
        ("scenes/cornell-box.toml", 48, 0.25),
        ("scenes/ring.toml", 48, 0.25),
        ("scenes/figurines.toml", 32, 0.25),
        ("tests/scenes/point-mirror.toml", 32, 0.1),
    ];
    for kind in backends() {
        for (path, res, min_lit) in cases {
            let label = format!("pt-cf {path}");
            let counts = method_wavefront_equals_scalar(&world(path, kind), Method::PtCf, &label, res, min_lit);
            assert_guided(&label, counts);
        }
    }
}

/// The wavefront `pt` and `pt-cf` under Mitsuba's `spot`, `directional`, `constant` and
/// `envmap` (issue #62): rays that escape to an environment, infinite shadow rays, no lanes.
#[test]
fn wavefronts_are_bit_identical_under_the_new_emitters() {
    for kind in backends() {
        for name in ["spot", "directional", "constant", "envmap"] {
            let w = world(&format!("tests/scenes/emitters/{name}.xml"), kind);
            wavefront_equals_scalar(&w, name, 32, 0.1);
            method_wavefront_equals_scalar(&w, Method::PtCf, name, 32, 0.1);
        }
    }
}
