//! Correctness tests of `pt-cf` (issue #12): agreement with `pt` by a Šidák-corrected per-pixel
//! Welch z-test (family-wise α = 1e-3) plus a whole-image z-test on the Cornell box (defaults, and
//! a strongly guided variant with splitting and deeper guiding) and on `ring`; the glass furnace
//! (L = 1 exactly, with caustic light so the tables are used); bit-for-bit `pt` at c = 1 (with
//! `--light-paths 0`; the light-traced caustics are `tests/pt_cf_light.rs`'s) and on a
//! scene without Dirac objects (no forecasters, so every vertex is a `pt` vertex); parameter errors.
//! The split counts per cluster are checked against the energy rule.
//! Each agreement test checks that guiding really happened (lookups inside clusters), and negative
//! controls show the statistics reject a 3% error. The mixture sampler's χ² is in
//! `tests/selection.rs`; `tests/furnace.rs` runs `pt-cf` through `Method::ALL`.

mod common;
use common::{
    assert_agrees, assert_furnace_is_one, cf_test_opts as opts, max_z, render_passes as render, render_profiled, world,
};
use forecast::accel::World;
use forecast::cf::estimator::CausticForecast;
use forecast::integrators::iws_cf::share::{caustic_shares, CausticShare};
use forecast::integrators::{Integrator, Method, MethodArgs, MethodError};
use forecast::profile::Profile;
use forecast::render::film::Film;
use forecast::stats::z_test_threshold;

/// Builds `method` through the broadcast bytes, as a rank would.
fn build(world: &World, method: Method, o: &MethodArgs) -> Box<dyn Integrator> {
    let bytes = method.preprocess(world, o, 17).unwrap();
    method.build(world, o, &bytes).unwrap()
}

fn pt(world: &World, w: u32, h: u32, spp: u64) -> Film {
    let mut p = Method::Pt.build(world, &opts(), &[]).unwrap();
    render(world, p.as_mut(), w, h, spp, 11)
}

/// The guide figures of a `pt-cf` render's stats: (lookups, fraction inside clusters).
fn guide_stats(i: &dyn Integrator, profile: &Profile) -> (u64, f64) {
    let s = i.stats(profile);
    (s["guide"]["lookups"].as_u64().unwrap(), s["guide"]["fraction_inside_clusters"].as_f64().unwrap())
}

/// `pt-cf` with `o` agrees with `pt` on `w` at `res`² (per pixel and whole image), and the
/// same statistics reject the image scaled by 0.97.
fn agrees_with_pt(w: &World, o: &MethodArgs, res: u32, (spp_pt, spp): (u64, u64), label: &str) {
    let reference = pt(w, res, res, spp_pt);
    let mut g = build(w, Method::PtCf, o);
    let (img, profile) = render_profiled(w, g.as_mut(), (res, res), spp, 3);
    let (lookups, inside) = guide_stats(g.as_ref(), &profile);
    eprintln!("{label}: {lookups} lookups, {:.1}% inside kept clusters", 100.0 * inside);
    assert!(lookups > 0 && inside > 0.01, "{label}: the tables were never used");
    assert_agrees(&img, &reference, label);
}

/// (65,536, 8,192) passes, from the negative control's power (`common::assert_detects`): at
/// (4,096, 1,024) a 3% error moved the conservative global z by 2.93 (78% of the variance in the
/// image), short of 6.58; 2.93 / √(0.78/8 + 0.22/16) ≈ 8.8.
#[test]
fn defaults_agree_with_pt_on_cornell_box() {
    agrees_with_pt(&world("scenes/cornell-box.toml"), &opts(), 16, (65536, 8192), "pt-cf cornell-box");
}

/// Strong guiding (c = 0.1) in every cluster with any caustic light (`--guide-min-share 0`),
/// splitting by the energy rule (S0 = 4) and three guided depths.
#[test]
fn strong_guiding_with_splitting_agrees_with_pt_on_cornell_box() {
    let w = world("scenes/cornell-box.toml");
    let mut o = opts();
    (o.ptcf.guide_fraction, o.ptcf.guide_min_share, o.cf.split, o.cf.table_depth) = (0.1, 0.0, 4, 3);
    let bytes = Method::PtCf.preprocess(&w, &o, 17).unwrap();
    let cf = CausticForecast::from_bytes(&bytes).unwrap();
    let (want, _) = energy_counts(&cf, &o);
    assert_eq!(split_per_cluster(Method::PtCf.build(&w, &o, &bytes).unwrap().as_ref()), want);
    assert!(want.contains(&4) && want.contains(&1), "{want:?}");
    // 8² as the share-rule test below, for its reason; seeds 3–8 give max|z| 2.4–3.9 against
    // the threshold 4.6 (at 16² and (4096, 512): 4.95 ≥ 4.84). 65,536 passes, from the negative
    // control's power: at 8,192 a 3% error moved the global z by 3.74 (94% of the variance in
    // the image); 3.74 / √(0.94/8 + 0.06) ≈ 8.9
    agrees_with_pt(&w, &o, 8, (131_072, 65536), "pt-cf c=0.1 min share 0 S0=4 D=3");
}

/// The continuations at diffuse depth 0 per kept cluster, from the stats.
fn split_per_cluster(i: &dyn Integrator) -> Vec<u64> {
    let s = i.stats(&Profile::default());
    s["guide"]["split_per_cluster"].as_array().unwrap().iter().map(|v| v.as_u64().unwrap()).collect()
}

/// The energy rule's counts for `o`, from the product alone: ⌈S0·ρ_k/ρ_max⌉ clamped to [1, S0]
/// in the guided clusters (share ≥ `--guide-min-share`, > 0), ρ_max the densest guided one's; 1
/// elsewhere. Also returns the guided clusters.
fn energy_counts(cf: &CausticForecast, o: &MethodArgs) -> (Vec<u64>, Vec<usize>) {
    let k = &cf.clustering.clusters;
    let min = o.ptcf.guide_min_share;
    let guided: Vec<usize> =
        (0..cf.shares.len()).filter(|&c| cf.shares[c].share() >= min && cf.shares[c].share() > 0.0).collect();
    let max = guided.iter().map(|&c| k[c].density).fold(0.0f32, f32::max);
    let s0 = o.cf.split as f32;
    let n = (0..cf.shares.len()).map(|c| {
        if guided.contains(&c) {
            (s0 * k[c].density / max).ceil().clamp(1.0, s0) as u64
        } else {
            1
        }
    });
    (n.collect(), guided)
}

/// The default split (the energy rule, `--split 16`) per kept cluster, against
/// [`energy_counts`]: the densest guided cluster gets 16, some others fewer, the unguided 1. (On
/// this scene the densest kept cluster is also the most caustic one, so it is guided; the unit
/// test `split_counts_follow_the_guided_clusters` covers an unguided densest cluster.) The
/// defaults' agreement with `pt` is `defaults_agree_with_pt_on_cornell_box`.
#[test]
fn energy_guide_split_follows_the_density() {
    let w = world("scenes/cornell-box.toml");
    let o = opts();
    assert_eq!(o.cf.split, 16, "the default");
    let bytes = Method::PtCf.preprocess(&w, &o, 17).unwrap();
    let cf = CausticForecast::from_bytes(&bytes).unwrap();
    let (want, guided) = energy_counts(&cf, &o);
    assert!(!guided.is_empty() && guided.len() < cf.shares.len(), "{:?}", cf.shares);
    let got = split_per_cluster(Method::PtCf.build(&w, &o, &bytes).unwrap().as_ref());
    assert_eq!(got, want, "densities {:?}", cf.clustering.clusters.iter().map(|c| c.density).collect::<Vec<_>>());
    assert!(want.contains(&16) && want.iter().any(|&n| n > 1 && n < 16), "{want:?}");
}

/// Every cluster that has any caustic light guided (c_k = max(c, 1 − s_k) from 0.2 up): the
/// per-cluster mixtures are unbiased. At 8² with 131,072 `pt` and 8,192 `pt-cf` samples per
/// pixel: at 16² with (4096, 1024) both estimators' heavy tails (the ceiling's and the floor's
/// caustics) broke the z-test's normal approximation, failing 5 of 8 `pt-cf` seeds already at
/// fea9f43 (before the per-object cones), while 32,768 `pt-cf` samples showed no bias (global
/// z −0.82); here seeds 3–8 give max|z| 2.5–3.6 against the threshold 4.6
/// (`results/2026-12-05-targeted-cones.md`).
#[test]
fn share_rule_guiding_every_cluster_agrees_with_pt_on_cornell_box() {
    let mut o = opts();
    (o.ptcf.guide_fraction, o.ptcf.guide_min_share) = (0.2, 0.0);
    // 65,536 passes for the negative control's power, as the strong-guiding test above
    agrees_with_pt(&world("scenes/cornell-box.toml"), &o, 8, (131_072, 65536), "pt-cf share rule, min share 0");
}

/// Clusters below `--guide-min-share` are `pt` vertices: with 1 (no cornell-box cluster is free
/// of diffuse interreflection, so none qualifies) `pt-cf` is `pt` bit for bit, and it queries
/// no tree (`ClusterMap::may_accept` rejects every vertex).
#[test]
fn unguided_clusters_are_pt_vertices_bit_for_bit() {
    let w = world("scenes/cornell-box.toml");
    let mut o = opts();
    // the camera side alone (the light paths add the light-traced caustics, tests/pt_cf_light.rs)
    (o.ptcf.guide_min_share, o.ptcf.light_paths) = (1.0, Some(0));
    let mut g = build(&w, Method::PtCf, &o);
    let (a, profile) = render_profiled(&w, g.as_mut(), (16, 16), 64, 9);
    let stats = g.stats(&profile);
    assert_eq!(stats["shares"]["guided_clusters"].as_u64(), Some(0), "{}", stats["shares"]);
    assert!(stats["shares"]["per_cluster"].as_array().is_some_and(|v| !v.is_empty()), "clusters were kept");
    assert_eq!(guide_stats(g.as_ref(), &profile).1, 0.0, "a vertex was guided");
    let mut p = Method::Pt.build(&w, &o, &[]).unwrap();
    assert!(render(&w, p.as_mut(), 16, 16, 64, 9).data == a.data, "unguided pt-cf differs from pt");
}

/// The share gather is a pure function of (scene, product, seed): the same on 1 and 3 threads,
/// and it is part of the broadcast product.
#[test]
fn caustic_shares_do_not_depend_on_threads() {
    let w = world("scenes/cornell-box.toml");
    let o = opts();
    let cf = CausticForecast::from_bytes(&Method::IwsCf.preprocess(&w, &o, 17).unwrap()).unwrap();
    let on = |n, seed| -> Vec<CausticShare> {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(n).build().unwrap();
        pool.install(|| caustic_shares(&w, &cf, 64, seed))
    };
    let a = on(1, 17);
    assert_eq!(a.len(), cf.clustering.n_kept(cf.opts.max_rank));
    assert!(a == on(3, 17), "the shares depend on the thread count");
    assert!(a == cf.shares, "the product holds the shares of its own seed");
    assert!(a.iter().all(|s| s.other > 0.0 && (0.0..=1.0).contains(&s.share())), "{a:?}");
    assert!(a != on(2, 18), "the seed is not used");
}

/// `ring` with its light 4× wider and 16× dimmer (same power, same centre and orientation). With
/// the paper's 0.5 m light the floor → gold band → light paths are so rare that `pt` at a test
/// budget misses them: at 16×16, 4096 spp, pixel (3,11) reads 0.61 ± 0.0004 in `pt` where the
/// 32768-spp 256² reference and `pt-cf` read 1.10, so the reference's variance estimate, and
/// with it the z-test, is invalid there. The wider light keeps the cardioid and makes both
/// estimators' tails light enough for the CLT at 8×8 pixels.
#[test]
fn agrees_with_pt_on_ring() {
    let w = common::ring_with_wide_light();
    agrees_with_pt(&w, &opts(), 8, (16384, 2048), "pt-cf ring (wide light)");
}

#[test]
fn glass_furnace_is_exactly_one() {
    let w = world("tests/scenes/glass-furnace-white.toml");
    let mut o = opts();
    o.cf.table_depth = 4;
    let mut g = build(&w, Method::PtCf, &o);
    let (img, profile) = render_profiled(&w, g.as_mut(), (16, 16), 512, 5);
    let (lookups, inside) = guide_stats(g.as_ref(), &profile);
    assert!(lookups > 0 && inside > 0.01, "the tables were never used ({inside})");
    assert_furnace_is_one(&img, "pt-cf glass furnace");
}

#[test]
fn guide_fraction_one_is_pt_bit_for_bit() {
    let w = world("scenes/cornell-box.toml");
    let mut o = opts();
    (o.ptcf.guide_fraction, o.cf.split, o.cf.table_depth) = (1.0, 4, 8);
    o.ptcf.light_paths = Some(0); // the camera side alone (tests/pt_cf_light.rs has the light side)
    let mut g = build(&w, Method::PtCf, &o);
    let (a, profile) = render_profiled(&w, g.as_mut(), (16, 16), 64, 9);
    let mut p = Method::Pt.build(&w, &o, &[]).unwrap();
    let b = render(&w, p.as_mut(), 16, 16, 64, 9);
    assert_eq!(guide_stats(g.as_ref(), &profile).0, 0, "c = 1 must never look a table up");
    assert!(a.data == b.data, "c = 1 differs from pt");
    // and c < 1 does differ (the comparison has power)
    o.ptcf.guide_fraction = 0.5;
    let mut g = build(&w, Method::PtCf, &o);
    assert!(render(&w, g.as_mut(), 16, 16, 64, 9).data != b.data);
}

#[test]
fn no_dirac_objects_means_pt_exactly() {
    let w = world("tests/scenes/cornell-nodirac.toml");
    let mut o = opts();
    (o.ptcf.guide_fraction, o.cf.table_depth) = (0.2, 8);
    let mut g = build(&w, Method::PtCf, &o);
    let (img, profile) = render_profiled(&w, g.as_mut(), (12, 12), 256, 3);
    let (lookups, inside) = guide_stats(g.as_ref(), &profile);
    assert!(lookups > 0, "the guide was queried");
    assert_eq!(inside, 0.0, "no caustic point, so no kept cluster");
    // in distribution against an independent pt render …
    let reference = pt(&w, 12, 12, 2048);
    let (z, n) = max_z(&img, &reference, None);
    assert!(z < z_test_threshold(1e-3, n), "max|z| {z}");
    // … and bit for bit against pt with the same seed (every vertex is a pt vertex)
    let mut p = Method::Pt.build(&w, &o, &[]).unwrap();
    assert!(render(&w, p.as_mut(), 12, 12, 256, 3).data == img.data);
}

#[test]
fn bad_guide_fraction_is_a_clear_error() {
    let w = world("tests/scenes/cornell-nodirac.toml");
    for c in [0.0f32, -0.5, 1.5, f32::NAN] {
        let mut o = opts();
        o.ptcf.guide_fraction = c;
        let bytes = Method::PtCf.preprocess(&w, &o, 1).unwrap();
        let e = Method::PtCf.build(&w, &o, &bytes).err().expect("must be refused");
        let refused = matches!(&e, MethodError::Option { flag: "--guide-fraction", value: None, .. });
        assert!(refused && e.to_string().starts_with("--guide-fraction: "), "{e:?}");
    }
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_forecast"))
        .args(["render", "scenes/cornell-box.toml", "--method", "pt-cf", "--guide-fraction", "0"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("--guide-fraction") && err.contains("(0, 1]"), "{err}");
    for bad in ["1.5", "-0.1", "x"] {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_forecast"))
            .args(["render", "scenes/cornell-box.toml", "--method", "pt-cf", &format!("--guide-min-share={bad}")])
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success() && err.contains("--guide-min-share"), "{bad}: {err}");
    }
}
