//! The light tree of `--vpl-select tree` (`transport::light_tree`, issue #11 item 2).
//!
//! The sampler against its own distribution (Pearson χ² of the selected light, the "nothing
//! selected" outcome as one more cell, `LightTree::pmf` as the expected frequencies, cells with
//! expected < 5 pooled) and the estimator against the full sum it replaces (z-test of the mean of
//! `Σ_k weight_k·F(y_k)` against the exact `Σ_i F_i`). Family-wise level ALPHA = 0.01 over the
//! N_TESTS statistical tests of this file, Šidák-corrected; seeds are fixed. Negative controls show
//! that each harness can fail.

use forecast::math::{Rgb, Vec3};
use forecast::sampling::rng::{stream, Rng};
use forecast::stats::{chi2_test, sidak_alpha, z_test_threshold};
use forecast::transport::light_tree::{LightTree, TreeLight, TreeQuery};

/// Family-wise significance level of the file.
const ALPHA: f64 = 0.01;
/// Statistical tests that must pass: selection χ² 4 (cases), estimator z 8 (cases × K ∈ {1, 3}).
const N_TESTS: usize = 12;
/// Traversals per χ² test.
const N: usize = 1_000_000;

/// Point lights on the walls of a unit box (as VPLs on a Cornell box), a few omni and unclamped.
fn box_lights(n: usize, seed: u64, omni_every: usize) -> Vec<TreeLight> {
    let mut r = Rng::keyed(seed, stream::MISC, 11, 0);
    (0..n)
        .map(|i| {
            let axis = i % 3;
            let side = if (i / 3) % 2 == 0 { 0.0 } else { 1.0 };
            let mut p = Vec3::new(r.next_f32(), r.next_f32(), r.next_f32());
            p[axis] = side;
            let mut nrm = Vec3::ZERO;
            nrm[axis] = if side == 0.0 { 1.0 } else { -1.0 };
            let omni = omni_every > 0 && i % omni_every == 0;
            TreeLight {
                p,
                n: nrm,
                power: Rgb::new(0.05 + r.next_f32(), 0.05 + r.next_f32(), 0.05),
                clamped: !omni,
                omni,
            }
        })
        .collect()
}

/// A shading configuration: lights, point, normal, clamp b.
struct Case {
    name: &'static str,
    lights: Vec<TreeLight>,
    x: Vec3,
    nx: Vec3,
    b: f32,
}

impl Case {
    fn q(&self) -> TreeQuery {
        TreeQuery { x: self.x, nx: self.nx, tint: Rgb::ONE, b: self.b }
    }
}

fn cases() -> Vec<Case> {
    vec![
        Case {
            name: "floor corner, b = 4",
            lights: box_lights(75, 1, 0),
            x: Vec3::new(0.95, 0.0, 0.5),
            nx: Vec3::Y,
            b: 4.0,
        },
        Case {
            name: "floor centre, b = inf",
            lights: box_lights(75, 2, 0),
            x: Vec3::new(0.5, 0.0, 0.5),
            nx: Vec3::Y,
            b: f32::INFINITY,
        },
        Case {
            name: "outside, omni lights",
            lights: box_lights(40, 3, 5),
            x: Vec3::new(0.5, 2.0, 0.5),
            nx: -Vec3::Y,
            b: 2.0,
        },
        Case {
            name: "wall, 300 lights, b = 1",
            lights: box_lights(300, 4, 0),
            x: Vec3::new(1.0, 0.3, 0.7),
            nx: -Vec3::X,
            b: 1.0,
        },
    ]
}

/// The caller's target `p̂_i`: Φ·min(G, b)·f with `G = |n_x·ŵ|·|n_i·ŵ|/r²` (`|n_x·ŵ|/r²`, unclamped,
/// for omni lights), `f` = 0.2 except 0 for every 4th light (a BSDF that is 0 there) and for lights
/// behind the point (one-sided).
fn p_hat(c: &Case, i: usize) -> f32 {
    let l = &c.lights[i];
    let d = l.p - c.x;
    let r2 = d.length_squared();
    let w = d / r2.sqrt();
    if i % 4 == 1 || c.nx.dot(w) <= 0.0 {
        return 0.0;
    }
    let g = if l.omni { c.nx.dot(w).abs() / r2 } else { (c.nx.dot(w).abs() * l.n.dot(w).abs() / r2).min(c.b) };
    l.power.dot(Rgb::ONE) * g * 0.2
}

/// The visible contribution `F_i = p̂_i·V_i·(colour factor)`.
fn contribution(c: &Case, i: usize) -> f64 {
    let v = if i % 3 == 2 { 0.0 } else { 1.0 };
    p_hat(c, i) as f64 * v * (1.0 + 0.5 * (i as f64).sin())
}

fn estimate(tree: &LightTree, c: &Case, k: u32, rng: &mut Rng) -> f64 {
    let mut acc = 0.0f64;
    tree.select(&c.q(), k, rng, |i| (p_hat(c, i), contribution(c, i)), |s| acc += s.weight as f64 * s.value);
    acc
}

/// Selection counts of `N` single traversals; the last cell is "nothing selected".
fn counts(tree: &LightTree, c: &Case, seed: u64) -> Vec<f64> {
    let n = c.lights.len();
    let mut obs = vec![0.0f64; n + 1];
    let mut rng = Rng::keyed(seed, stream::MISC, 0, 0);
    for _ in 0..N {
        let mut got = n;
        tree.select(&c.q(), 1, &mut rng, |i| (p_hat(c, i), ()), |s| got = s.index);
        obs[got] += 1.0;
    }
    obs
}

fn expected(tree: &LightTree, c: &Case) -> Vec<f64> {
    let mut exp: Vec<f64> = (0..c.lights.len()).map(|i| tree.pmf(&c.q(), i, |j| p_hat(c, j))).collect();
    let total: f64 = exp.iter().sum();
    assert!(total <= 1.0 + 1e-9, "{}: Σ pmf = {total} > 1", c.name);
    exp.push((1.0 - total).max(0.0));
    exp.iter().map(|p| p * N as f64).collect()
}

#[test]
fn tree_selection_matches_its_pmf_and_covers_every_contributing_light() {
    let alpha = sidak_alpha(ALPHA, N_TESTS);
    for (k, c) in cases().iter().enumerate() {
        let tree = LightTree::new(&c.lights).unwrap();
        assert_eq!(tree.len(), c.lights.len());
        let exp = expected(&tree, c);
        for (i, &e) in exp.iter().take(c.lights.len()).enumerate() {
            let contributes = p_hat(c, i) > 0.0;
            assert_eq!(e > 0.0, contributes, "{}: light {i} support (p̂ = {})", c.name, p_hat(c, i));
        }
        let r = chi2_test(&counts(&tree, c, 100 + k as u64), &exp, 5.0);
        assert!(r.dof >= 3 && r.impossible_samples == 0.0, "{}: {r:?}", c.name);
        assert!(r.passes(alpha), "{}: χ² rejected at {alpha:.3e}: {r:?}", c.name);
    }
    // Negative control: a 5% error in the probability of the most likely light is rejected.
    let c = &cases()[0];
    let tree = LightTree::new(&c.lights).unwrap();
    let mut exp = expected(&tree, c);
    let top = (0..c.lights.len()).max_by(|&a, &b| exp[a].total_cmp(&exp[b])).unwrap();
    exp[top] *= 1.05;
    assert!(!chi2_test(&counts(&tree, c, 100), &exp, 5.0).passes(alpha), "a 5% pmf error must be rejected");
}

#[test]
fn tree_estimate_equals_the_full_sum() {
    let zcrit = z_test_threshold(ALPHA, N_TESTS);
    let mean_se = |tree: &LightTree, c: &Case, k: u32, seed: u64, drop: Option<usize>| {
        let (mut s, mut s2, n) = (0.0f64, 0.0f64, 200_000usize);
        for j in 0..n {
            let mut rng = Rng::keyed(seed, stream::MISC, 7, j as u64);
            let x = match drop {
                None => estimate(tree, c, k, &mut rng),
                Some(i0) => {
                    let mut acc = 0.0;
                    let t = |i: usize| (if i == i0 { 0.0 } else { p_hat(c, i) }, contribution(c, i));
                    tree.select(&c.q(), k, &mut rng, t, |s| acc += s.weight as f64 * s.value);
                    acc
                }
            };
            (s, s2) = (s + x, s2 + x * x);
        }
        let m = s / n as f64;
        (m, ((s2 / n as f64 - m * m).max(0.0) / (n - 1) as f64).sqrt())
    };
    for (j, c) in cases().iter().enumerate() {
        let tree = LightTree::new(&c.lights).unwrap();
        let truth: f64 = (0..c.lights.len()).map(|i| contribution(c, i)).sum();
        assert!(truth > 0.0);
        for k in [1u32, 3] {
            let (m, se) = mean_se(&tree, c, k, 200 + 10 * j as u64 + k as u64, None);
            let z = (m - truth) / se;
            assert!(z.abs() < zcrit, "{} K={k}: mean {m} vs Σ F {truth} (se {se}): z = {z:.2}", c.name);
        }
    }
    // Negative control: a target that is 0 on the largest contributor loses its F (bias detected).
    let c = &cases()[0];
    let tree = LightTree::new(&c.lights).unwrap();
    let truth: f64 = (0..c.lights.len()).map(|i| contribution(c, i)).sum();
    let i0 = (0..c.lights.len()).max_by(|&a, &b| contribution(c, a).total_cmp(&contribution(c, b))).unwrap();
    let (m, se) = mean_se(&tree, c, 1, 299, Some(i0));
    assert!(((m - truth) / se).abs() > zcrit, "a target missing light {i0} must be biased: {m} vs {truth}");
}

#[test]
fn tree_draws_two_words_per_traversal_and_handles_degenerate_input() {
    let c = &cases()[0];
    let tree = LightTree::new(&c.lights).unwrap();
    for k in [1u32, 2, 5] {
        let mut a = Rng::keyed(9, stream::MISC, 0, 0);
        let mut b = a.clone();
        let mut n_sel = 0;
        tree.select(&c.q(), k, &mut a, |i| (p_hat(c, i), ()), |_| n_sel += 1);
        assert!(n_sel <= k);
        for _ in 0..2 * k {
            b.next_u32();
        }
        assert_eq!(a.next_u32(), b.next_u32(), "K={k}: {} words expected", 2 * k);
    }
    // b = 0 (pure compensation) or an all-zero target: nothing is selected.
    let mut rng = Rng::keyed(9, stream::MISC, 1, 0);
    tree.select(
        &TreeQuery { b: 0.0, ..c.q() },
        4,
        &mut rng,
        |i| (p_hat(c, i), ()),
        |_| panic!("b = 0: no light may be selected"),
    );
    tree.select(&c.q(), 4, &mut rng, |_| (f32::NAN, ()), |_| panic!("zero target: no light may be selected"));
    // No positive power: no tree. One light: selected with weight 1/K wherever it contributes.
    let dark: Vec<TreeLight> = c.lights.iter().map(|l| TreeLight { power: Rgb::ZERO, ..*l }).collect();
    assert!(LightTree::new(&dark).is_none() && LightTree::new(&[]).is_none());
    let one = LightTree::new(&c.lights[..1]).unwrap();
    let mut got = Vec::new();
    one.select(&c.q(), 2, &mut rng, |_| (1.0, ()), |s| got.push((s.index, s.weight)));
    assert_eq!(got, vec![(0, 0.5), (0, 0.5)]);
    // Coincident lights (zero-size boxes) and non-finite powers are handled.
    let mut same = vec![c.lights[0]; 8];
    same[3].power = Rgb::splat(f32::NAN);
    let t = LightTree::new(&same).unwrap();
    let total: f64 = (0..8).map(|i| t.pmf(&c.q(), i, |_| 1.0)).sum();
    assert!((total - 1.0).abs() < 1e-9 && t.pmf(&c.q(), 3, |_| 1.0) == 0.0, "Σ pmf {total}");
}
