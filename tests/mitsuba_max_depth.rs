//! Mitsuba's `max_depth` counts path segments (issue #62): a scene's `max_depth` d is forecast's
//! vertex cap d − 1 (`--max-depth` N: N surface vertices, next-event estimation at each and the
//! emitter the N-th one's BSDF sample reaches, the two halves of its MIS), so that
//! `tests/scenes/max-depth/room.xml` (a closed room, a large ceiling light, a diffuse and a glass
//! sphere, 32²) rendered by `pt` through the pipeline at `max_depth` 1, 2, 3 and 5 agrees with
//! Mitsuba 3 `path`'s image mean at the same `max_depth` (`tests/reference/max-depth.json`, made
//! by `scripts/mitsuba-max-depth-references.py`: 32 independent renders of 1024 spp each, the SE
//! their spread).
//!
//! Per depth and channel a z of the two image means (forecast's variance of the mean from its
//! per-pixel sample variances, pixels independent; the reference's from its renders), threshold
//! `z_test_threshold(α, tests)` at family-wise α = 1e-3 over all depths and channels. Power: the
//! old reading (cap d for `max_depth` d, one segment more) must miss Mitsuba's `max_depth` 2 by
//! more than twice the threshold.

mod common;
use common::{job, render_film, root, tmp_dir};
use forecast::integrators::Method;
use forecast::render::film::Film;
use forecast::stats::z_test_threshold;

const ALPHA: f64 = 1e-3;
const DEPTHS: [u32; 4] = [1, 2, 3, 5];
const SPP: u64 = 1024;

/// Mitsuba's image mean and its standard error per channel at `max_depth` d.
fn reference(d: u32) -> ([f64; 3], [f64; 3]) {
    let text = std::fs::read_to_string(root().join("tests/reference/max-depth.json")).unwrap();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    let e = &v["depths"][d.to_string()];
    let three = |k: &str| -> [f64; 3] { std::array::from_fn(|c| e[k][c].as_f64().expect("a number")) };
    (three("mean"), three("se"))
}

/// The image mean per channel and its variance.
fn image_mean(f: &Film) -> ([f64; 3], [f64; 3]) {
    let (m, v) = (f.mean(), f.variance_of_mean());
    let n = m.len() as f64;
    let mut out = ([0.0; 3], [0.0; 3]);
    for (mp, vp) in m.iter().zip(&v) {
        for c in 0..3 {
            out.0[c] += mp[c] as f64 / n;
            out.1[c] += vp[c] as f64 / (n * n);
        }
    }
    out
}

/// `pt` on the room at `max_depth` d (seed 10 + d), with `--max-depth` `cap` if given.
fn render(d: u32, cap: Option<u32>) -> Film {
    let scene = root().join("tests/scenes/max-depth/room.xml");
    let out = tmp_dir(&format!("max-depth-{d}-{cap:?}")).join("img");
    let mut j = job(&scene, Method::Pt, SPP, 10 + d as u64, (32, 32), 1, &out);
    j.defines = vec![("max_depth".into(), d.to_string())];
    j.args.settings.max_depth = cap;
    render_film(&j)
}

fn z_of(d: u32, f: &Film) -> [f64; 3] {
    let ((m, v), (rm, rse)) = (image_mean(f), reference(d));
    std::array::from_fn(|c| (m[c] - rm[c]) / (v[c] + rse[c] * rse[c]).sqrt())
}

#[test]
fn scene_max_depth_is_segments() {
    let path = root().join("tests/scenes/max-depth/room.xml");
    for d in DEPTHS {
        let opts = forecast::scene::LoadOptions { defines: vec![("max_depth".into(), d.to_string())] };
        let s = forecast::scene::load_with(&path, &opts).unwrap();
        assert_eq!(s.render.max_depth, d - 1, "max_depth {d}");
    }
    let thr = z_test_threshold(ALPHA, 3 * DEPTHS.len());
    let mut worst = 0.0f64;
    for d in DEPTHS {
        let f = render(d, None);
        let ((m, _), (rm, _)) = (image_mean(&f), reference(d));
        let z = z_of(d, &f);
        eprintln!("max_depth {d}: forecast {m:.5?} Mitsuba {rm:.5?} z {z:+.2?} (threshold {thr:.2})");
        worst = z.iter().fold(worst, |a, z| a.max(z.abs()));
    }
    assert!(worst < thr, "a max_depth disagrees with Mitsuba: max |z| {worst:.2} >= {thr:.2}");
}

/// The test's power: reading `max_depth` 2 as 2 vertices (one segment more) is far outside it.
#[test]
fn one_segment_more_is_detected() {
    let thr = z_test_threshold(ALPHA, 3 * DEPTHS.len());
    let z = z_of(2, &render(2, Some(2)));
    eprintln!("max_depth 2 rendered with --max-depth 2: z {z:+.2?}");
    assert!(z.iter().all(|z| *z > 2.0 * thr), "{z:?} against {thr:.2}");
}

/// Mitsuba's `max_depth` 0 renders nothing and other negatives are not Mitsuba's: refused at the
/// key; −1 is the default cap.
#[test]
fn max_depth_zero_and_below_minus_one_are_refused() {
    let src = |d: &str| {
        format!(
            "<scene version=\"3.0.0\">\n<integrator type=\"path\">\n<integer name=\"max_depth\" value=\"{d}\"/>\n</integrator>\n\
             <sensor type=\"perspective\"><float name=\"fov\" value=\"40\"/></sensor>\n</scene>"
        )
    };
    for d in ["0", "-2"] {
        let e = common::xml(&src(d), &root()).unwrap_err();
        assert_eq!((e.line, e.key.as_str()), (3, "path.max_depth"), "{e}");
        assert!(e.message.contains("path segments >= 1"), "{e}");
    }
}
