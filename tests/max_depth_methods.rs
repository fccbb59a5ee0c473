//! Small vertex caps (issue #62 item 5's follow-up): `pt-cf` agrees with `pt` at `--max-depth`
//! 1, 2 and 3 on a glass ball over a diffuse floor beside a glossy wall under a small light, where
//! each cap cuts a path class (1: direct light, and the light seen in the wall; 2: through one
//! glass surface; 3: the caustic `L S S D E` and the light seen through the ball). `pt`'s cap N
//! traces N surface vertices and the N-th vertex's BSDF ray for the emitter it reaches; `pt-cf`
//! must do the same on both of its sides (the camera side's last BSDF ray; the light side's
//! connections at its N-th vertex). Šidák per-pixel and whole-image z-tests at α = 1e-3 with the
//! 3% negative control (`common::assert_agrees`). Each cap also checks that it changes `pt`'s
//! image (the test has power against a reading one vertex off). Also: the prefix emission that
//! emission splitting averages reaches the emitter through as many Dirac vertices as the
//! estimate does (`Integrator::prefix_cap`).

mod common;
use common::{assert_agrees, global_z, max_z, render_passes};
use forecast::accel::World;
use forecast::integrators::{Integrator, Method, MethodArgs};
use forecast::render::film::Film;
use std::path::Path;

/// A glass ball over a diffuse floor, a glossy back wall, a 0.6 m light (`tests/scenes/glass-ball`).
fn scene_src() -> String {
    let dir = common::root().join("tests/scenes/glass-ball");
    let read = |f: &str| std::fs::read_to_string(dir.join(f)).unwrap();
    read("geometry.toml") + &read("plain.toml")
}

const RES: u32 = 12;

fn world() -> World {
    World::build(forecast::scene::load_str(&scene_src(), "caps.toml", Path::new(".")).unwrap()).unwrap()
}

/// The scene seen from below the light, which the view then holds (and its image in the ball).
fn world_up() -> World {
    let src = scene_src().replace("look_at = [0.0, 0.5, 0.0]", "look_at = [0.0, 1.3, 0.0]");
    World::build(forecast::scene::load_str(&src, "caps-up.toml", Path::new(".")).unwrap()).unwrap()
}

/// Method options at vertex cap `cap` (a small CF preprocess).
fn opts(cap: u32) -> MethodArgs {
    let mut o = MethodArgs::default();
    (o.settings.max_depth, o.cf.forecast_photons, o.cf.clusters) = (Some(cap), Some(20_000), 16);
    o
}

fn build(w: &World, method: Method, o: &MethodArgs) -> Box<dyn Integrator> {
    let bytes = method.preprocess(w, o, 17).unwrap();
    method.build(w, o, &bytes).unwrap()
}

fn pt(w: &World, cap: u32, spp: u64) -> Film {
    render_passes(w, build(w, Method::Pt, &opts(cap)).as_mut(), RES, RES, spp, 11)
}

#[test]
fn pt_cf_agrees_with_pt_at_small_caps() {
    let w = world();
    let mut previous: Option<Film> = None;
    for cap in 1..=3 {
        let reference = pt(&w, cap, 16384);
        // the cap matters: the image one vertex shorter is rejected
        if let Some(p) = &previous {
            let z = global_z(p, &reference);
            eprintln!("pt cap {} against cap {cap}: global z {z:.1}", cap - 1);
            assert!(z.abs() > 10.0, "cap {cap} adds nothing to cap {}: the test has no power", cap - 1);
        }
        let mut g = build(&w, Method::PtCf, &opts(cap));
        let img = render_passes(&w, g.as_mut(), RES, RES, 4096, 3);
        assert_agrees(&img, &reference, &format!("pt-cf --max-depth {cap}"));
        previous = Some(reference);
    }
}

/// At cap 0 (a Mitsuba `max_depth` of 1) every method renders the emitters seen directly and
/// nothing else, as `pt` (the IWS methods read 0 as 64 before).
#[test]
fn every_method_sees_only_the_emitters_at_cap_zero() {
    let w = world_up();
    let reference = pt(&w, 0, 8192);
    let lit = reference.mean().iter().filter(|p| p[0] > 0.0).count();
    assert!(lit > 0 && lit < (RES * RES) as usize, "{lit} pixels see the light");
    for method in [Method::PtCf, Method::Iws, Method::IwsPm, Method::IwsCf] {
        let mut g = build(&w, method, &opts(0));
        let img = render_passes(&w, g.as_mut(), RES, RES, 8192, 3);
        let dark = img.mean().iter().zip(reference.mean()).filter(|(a, b)| b[0] == 0.0 && a[0] != 0.0).count();
        assert_eq!(dark, 0, "{method:?} at cap 0 lights pixels that see no emitter");
        // (the 3% control of `assert_agrees` has no power here: only the light's edge pixels vary)
        let (z, n) = max_z(&img, &reference, None);
        let (thr, zg) = (forecast::stats::z_test_threshold(1e-3, n), global_z(&img, &reference));
        eprintln!("{method:?} --max-depth 0: max|z| {z:.2} (threshold {thr:.2}), global z {zg:.2}");
        assert!(z < thr && zg.abs() < forecast::stats::z_test_threshold(1e-3, 1), "{method:?} at cap 0");
    }
}
