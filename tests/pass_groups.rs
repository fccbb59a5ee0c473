//! Pass groups (`render::render_passes`, issue #33) are pure speed.
//!
//! - A group's film is bit for bit its passes rendered one by one (`render::render_pass`), for
//!   `pt` (the wavefront, its camera rays traced as coherent runs on Embree) and `pt-cf` (the
//!   scalar camera side and the light splats), with emission splitting's split pixels in the
//!   image, on every back end of the build, and for the interleaved passes of one MPI rank.
//! - The pipeline, which groups the passes of independent integrators, renders exactly the passes
//!   `0..spp`: its film is the one-by-one film of those passes, bit for bit.

mod common;

use common::{cf_test_opts, job, render_film, root, tmp_dir};
use forecast::accel::{AccelKind, World};
use forecast::integrators::{Integrator, Method, MethodArgs};
use forecast::render::{film::Film, render_pass, render_passes, PixelSampler, MAX_EMISSION_SPLIT};

fn bits(f: &Film) -> Vec<u64> {
    f.data.iter().map(|x| x.to_bits()).collect()
}

fn build(world: &World, method: Method) -> Box<dyn Integrator> {
    let o = cf_test_opts();
    let bytes = method.preprocess(world, &o, 17).unwrap();
    method.build(world, &o, &bytes).unwrap()
}

/// The passes `passes` rendered one by one, in order.
fn one_by_one(world: &World, integ: &dyn Integrator, pixels: &PixelSampler, passes: &[u64]) -> Film {
    let (w, h) = pixels.resolution();
    let mut film = Film::new(w as usize, h as usize);
    for &q in passes {
        render_pass(world, integ, pixels, 5, q, &mut film);
    }
    film
}

/// The same passes rendered as the groups `groups`, in order.
fn grouped(world: &World, integ: &dyn Integrator, pixels: &PixelSampler, groups: &[&[u64]]) -> Film {
    let (w, h) = pixels.resolution();
    let mut film = Film::new(w as usize, h as usize);
    for g in groups {
        render_passes(world, integ, pixels, 5, g, &mut film);
    }
    film
}

#[test]
fn a_pass_group_is_its_passes_one_by_one_bit_for_bit() {
    let kinds = [AccelKind::Wide, AccelKind::Obvhs, AccelKind::Embree].into_iter().filter(|k| k.available());
    for kind in kinds {
        let scene = forecast::scene::load(&root().join("scenes/cornell-box.toml")).unwrap();
        let world = World::build_with(scene, kind).unwrap();
        let cam = world.scene.camera.with_resolution(40, 40);
        for method in [Method::Pt, Method::PtCf] {
            let integ = build(&world, method);
            assert!(integ.independent_passes(), "{method:?} has no per-pass state");
            let pixels = PixelSampler::new(&world, &cam, MAX_EMISSION_SPLIT, integ.prefix_cap());
            assert!(pixels.stats().split_pixels > 0, "the image holds split pixels");
            let label = format!("{method:?} on {kind:?}");
            let all: Vec<u64> = (0..12).collect();
            let a = one_by_one(&world, integ.as_ref(), &pixels, &all);
            assert!(a.mean().iter().filter(|p| p[0] > 0.0).count() > 800, "{label}: the image is lit");
            let b = grouped(&world, integ.as_ref(), &pixels, &[&all[..1], &all[1..5], &all[5..]]);
            assert!(bits(&a) == bits(&b), "{label}: groups of 1, 4 and 7 passes");
            // one rank of two: the passes 0, 2, 4, … of the interleave
            let even: Vec<u64> = (0..12).step_by(2).collect();
            let c = one_by_one(&world, integ.as_ref(), &pixels, &even);
            let d = grouped(&world, integ.as_ref(), &pixels, &[&even[..2], &even[2..]]);
            assert!(bits(&c) == bits(&d), "{label}: interleaved passes");
        }
    }
}

#[test]
fn the_pipeline_renders_exactly_the_passes_0_to_spp() {
    let path = root().join("scenes/cornell-box.toml");
    let world = World::build(forecast::scene::load(&path).unwrap()).unwrap();
    let cam = world.scene.camera.with_resolution(32, 32);
    // what the pipeline builds for `common::job`: default options, the scene's max_depth (64)
    let mut args = MethodArgs::default();
    args.settings.max_depth = Some(64);
    let pt = Method::Pt.build(&world, &args, &[]).unwrap();
    let pixels = PixelSampler::new(&world, &cam, args.emission_split(), pt.prefix_cap());
    let spp = 40;
    let passes: Vec<u64> = (0..spp).collect();
    let expect = one_by_one(&world, pt.as_ref(), &pixels, &passes);
    let dir = tmp_dir("pass-groups");
    let film = render_film(&job(&path, Method::Pt, spp, 5, (32, 32), 2, &dir.join("out")));
    let _ = std::fs::remove_dir_all(dir);
    assert_eq!(film.total_samples(), (32 * 32 * spp) as f64);
    assert!(bits(&film) == bits(&expect), "the pipeline's film is passes 0..{spp} one by one");
}
