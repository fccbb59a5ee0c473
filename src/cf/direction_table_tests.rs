//! Tests of `cf::direction_table`: bin geometry, the alias tables' exactness, χ² of every
//! table sampler, estimator-level unbiasedness of the dual, single, defensive and spread tables.

use super::*;
use crate::sampling::rng::stream;
use crate::stats::{hemisphere_chi2, sidak_alpha, Chi2Result};

fn dir(theta_deg: f32, phi_deg: f32) -> Vec3 {
    let (t, p) = (theta_deg.to_radians(), phi_deg.to_radians());
    Vec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos())
}

fn lambert(w: Vec3) -> f32 {
    w.z.max(0.0) / PI
}

/// Photons in a cone of half-angle `spread_deg` around (θ, φ), weight = lum·f·μ with lum = 1.
fn photon_set(n: usize, theta: f32, phi: f32, spread_deg: f32, seed: u64) -> Vec<(Vec3, f32)> {
    let mut r = Rng::keyed(seed, stream::MISC, 0, 0);
    (0..n)
        .map(|_| {
            let d = dir(
                (theta + spread_deg * (2.0 * r.next_f32() - 1.0)).clamp(0.5, 89.0),
                phi + spread_deg * (2.0 * r.next_f32() - 1.0),
            );
            (d, lambert(d) * d.z)
        })
        .collect()
}

fn uniformish(n: usize, seed: u64) -> Vec<(Vec3, f32)> {
    let mut r = Rng::keyed(seed, stream::MISC, 1, 0);
    (0..n).map(|_| (sample_cosine([r.next_f32(), r.next_f32()]), 0.5 + r.next_f32())).collect()
}

fn chi2_table(t: &DirectionTable, seed: u64) -> Chi2Result {
    hemisphere_chi2(
        |r: &mut Rng| Some(t.sample([r.next_f32(), r.next_f32(), r.next_f32()]).0),
        |w| t.pdf_w(w) as f64,
        64,
        32,
        1_000_000,
        seed,
    )
}

#[test]
fn bins_centres_and_normalisation() {
    for i in 0..N_BINS {
        assert_eq!(bin_of(bin_center(i)), Some(i));
    }
    assert_eq!(bin_of(Vec3::new(1.0, 0.0, 0.0)), None);
    assert_eq!(bin_of(Vec3::new(0.0, 0.0, -1.0)), None);
    assert_eq!(bin_of(Vec3::NAN), None);
    assert_eq!(bin_of(Vec3::Z), Some((N_MU - 1) * N_PHI));
    let t = ForecastTables::build(photon_set(50, 30.0, 10.0, 20.0, 1), lambert, TableMode::Dual);
    for tab in [t.t1.as_ref().unwrap(), t.t2.as_ref().unwrap()] {
        let s: f32 = (0..N_BINS).map(|i| tab.pdf_w(bin_center(i)) * BIN_SOLID_ANGLE).sum();
        assert!((s - 1.0).abs() < 1e-4);
        let mut r = Rng::keyed(2, stream::MISC, 0, 0);
        for _ in 0..10_000 {
            let (w, pdf) = tab.sample([r.next_f32(), r.next_f32(), r.next_f32()]);
            assert!(w.z > 0.0 && (w.length() - 1.0).abs() < 1e-5);
            assert_eq!(pdf, tab.pdf_w(w));
            assert!(pdf > 0.0);
        }
        // Bin-edge uniforms stay in the chosen bin (sample pdf == pdf_w) for every bin.
        for i in (0..N_BINS).filter(|&i| tab.bin_pmf(i) > 0.0) {
            let u0 = tab.u0_for(i).expect("a positive bin is reachable");
            for (a, b) in [(0.0, 0.0), (0.999_999_94, 0.999_999_94), (0.0, 0.999_999_94), (0.999_999_94, 0.0)] {
                let (w, pdf) = tab.sample([u0, a, b]);
                assert_eq!(bin_of(w), Some(i));
                assert_eq!(pdf, tab.pdf_w(w));
            }
        }
        // u → 1 never picks a zero bin.
        let (w, pdf) = tab.sample([0.999_999_94, 0.5, 0.5]);
        assert!(pdf > 0.0 && tab.pdf_w(w) > 0.0);
    }
    // Dual tables partition the hemisphere: exactly one of p1, p2 is positive per bin.
    let (t1, t2) = (t.t1.unwrap(), t.t2.unwrap());
    assert!((0..N_BINS).all(|i| (t1.bin_pmf(i) > 0.0) != (t2.bin_pmf(i) > 0.0)));
}

impl DirectionTable {
    /// A uniform `u0` that selects bin `i`, if any does.
    fn u0_for(&self, i: usize) -> Option<f32> {
        let k = (0..N_BINS).find_map(|c| {
            let (t, a) = (self.cols[c] >> 16, (self.cols[c] & 0xffff) as usize);
            if c == i && t > 0 {
                Some((c as u32) << ACC_BITS)
            } else {
                (a == i && t < ACC_ONE).then_some(((c as u32) << ACC_BITS) + ACC_ONE - 1)
            }
        })?;
        Some(k as f32 / 16_777_216.0)
    }
}

/// Every one of the 2²⁴ values of `Rng::next_f32` is mapped to a bin; the counts are exactly
/// the pmf the estimator divides by (so the alias quantisation adds no bias), zero bins get
/// none, and a bin floored from a weight of 1e-30 is among the reachable ones.
#[test]
fn alias_sampling_is_exactly_the_pmf() {
    let mut w = [0.0f32; N_BINS];
    let mut r = Rng::keyed(7, stream::MISC, 0, 0);
    for (i, x) in w.iter_mut().enumerate() {
        *x = match i % 5 {
            0 => 0.0,
            1 => 1e-30,
            _ => r.next_f32().powi(4) * 100.0,
        };
    }
    let t = DirectionTable::from_weights(&w).unwrap();
    let mut count = vec![0u32; N_BINS];
    for k in 0..(1u32 << 24) {
        count[t.bin_for(k as f32 / 16_777_216.0)] += 1;
    }
    for (i, &c) in count.iter().enumerate() {
        assert_eq!(c as f32 / 16_777_216.0, t.bin_pmf(i), "bin {i}");
        assert_eq!(c > 0, i % 5 != 0, "bin {i}");
    }
    let total: f64 = (0..N_BINS).map(|i| t.bin_pmf(i) as f64).sum();
    assert_eq!(total, 1.0);
}

#[test]
fn degenerate_tables() {
    assert!(DirectionTable::from_weights(&[0.0; N_BINS]).is_none());
    assert!(DirectionTable::from_weights(&[f32::NAN; N_BINS]).is_none());
    // No photons: T2 covers everything; all-zero BRDF: uniform fill.
    let t = ForecastTables::build(std::iter::empty(), lambert, TableMode::Dual);
    assert!(t.t1.is_none() && t.t2.is_some());
    let t = ForecastTables::build(std::iter::empty(), |_| 0.0, TableMode::Dual);
    let t2 = t.t2.unwrap();
    assert!((0..N_BINS).all(|i| (t2.bin_pmf(i) - 1.0 / N_BINS as f32).abs() < 1e-7));
    // A vanishingly small but positive bin is still reachable (pmf floor).
    let mut w = [0.0f32; N_BINS];
    w[5] = 1e-30;
    w[6] = 1.0;
    let t = DirectionTable::from_weights(&w).unwrap();
    assert!(t.bin_pmf(5) as f64 >= 0.99 * MIN_BIN_PMF);
    let (d, pdf) = t.sample([t.u0_for(5).expect("floored bin reachable"), 0.5, 0.5]);
    assert_eq!((bin_of(d), pdf), (Some(5), t.pdf_w(d)));
    // Photons in every bin: no T2.
    let all: Vec<(Vec3, f32)> = (0..N_BINS).map(|i| (bin_center(i), 1.0)).collect();
    let t = ForecastTables::build(all, lambert, TableMode::Dual);
    assert!(t.t1.is_some() && t.t2.is_none());
    assert_eq!(t.n_samples(3), 3);
    // Below-horizon / NaN / negative photons are ignored.
    let bad = vec![(Vec3::new(0.0, 0.0, -1.0), 1.0), (Vec3::Z, f32::NAN), (Vec3::Z, -1.0)];
    let t = ForecastTables::build(bad, |_| f32::NAN, TableMode::Dual);
    assert!(t.t1.is_none() && t.t2.is_some());
}

#[test]
fn chi2_of_all_table_samplers() {
    let sparse = photon_set(3, 40.0, 100.0, 30.0, 3);
    let peaked: Vec<(Vec3, f32)> = vec![(dir(35.0, 250.0), 1.0); 1000];
    let uni = uniformish(300, 4);
    let mut tables: Vec<(&str, DirectionTable)> = Vec::new();
    for (name, set) in [("sparse", &sparse), ("peaked", &peaked), ("uniform", &uni)] {
        let d = ForecastTables::build(set.iter().copied(), lambert, TableMode::Dual);
        tables.push((name, d.t1.unwrap()));
        tables.push((name, d.t2.unwrap()));
        let ds = ForecastTables::build(set.iter().copied(), lambert, TableMode::DualSpread { radius: 2.0, alpha: 0.5 });
        tables.push((name, ds.t2.unwrap()));
    }
    // Cosine-fallback table (k = 0) and a sharp glossy lobe whose fill relies on the floor.
    let cos = ForecastTables::build(std::iter::empty(), lambert, TableMode::Dual);
    tables.push(("k=0", cos.t2.unwrap()));
    let lobe = |w: Vec3| w.dot(dir(20.0, 0.0)).max(0.0).powi(2000) * w.z;
    tables.push(("glossy", ForecastTables::build(sparse.iter().copied(), lobe, TableMode::Dual).t2.unwrap()));
    let n_tests = tables.len() + 1;
    let alpha = sidak_alpha(0.01, n_tests);
    for (k, (name, t)) in tables.iter().enumerate() {
        let r = chi2_table(t, 100 + k as u64);
        assert!(r.passes(alpha), "{name} #{k}: {r:?}");
    }
    let r = hemisphere_chi2(
        |r: &mut Rng| Some(sample_cosine([r.next_f32(), r.next_f32()])),
        |w| cosine_pdf_w(w) as f64,
        64,
        32,
        1_000_000,
        99,
    );
    assert!(r.passes(alpha), "cosine: {r:?}");
}

/// Integrand of the unbiasedness test: a smooth lobe 0.3·μ plus a 5° cone of value 50.
fn cone_axis() -> Vec3 {
    dir(40.0, 30.0)
}
fn g(w: Vec3) -> f32 {
    let cone = if w.dot(cone_axis()) >= 5f32.to_radians().cos() { 50.0 } else { 0.0 };
    0.3 * w.z.max(0.0) + cone
}
fn truth() -> f64 {
    // ∫ 0.3 μ dω = 0.3π; cone: 50 · 2π(1 − cos 5°).
    0.3 * std::f64::consts::PI + 50.0 * 2.0 * std::f64::consts::PI * (1.0 - 5f64.to_radians().cos())
}

/// (mean, standard error) of `n` independent estimates.
fn mean_se(n: usize, seed: u64, mut est: impl FnMut(&mut Rng) -> f32) -> (f64, f64) {
    let (mut s, mut s2) = (0.0f64, 0.0f64);
    for i in 0..n {
        let mut r = Rng::keyed(seed, stream::MISC, 7, i as u64);
        let x = est(&mut r) as f64;
        s += x;
        s2 += x * x;
    }
    let m = s / n as f64;
    let var = (s2 / n as f64 - m * m).max(0.0) * n as f64 / (n - 1) as f64;
    (m, (var / n as f64).sqrt())
}

#[test]
fn estimators_are_unbiased_where_photons_miss_the_cone() {
    // Photons far from the cone (θ = 60°, φ = 200°).
    let photons = photon_set(200, 60.0, 200.0, 10.0, 5);
    assert!(photons.iter().all(|p| p.0.dot(cone_axis()) < 0.9));
    let n = 200_000;
    let t = truth();
    let dual = ForecastTables::build(photons.iter().copied(), lambert, TableMode::Dual);
    assert!(dual.t1.as_ref().unwrap().pdf_w(cone_axis()) == 0.0, "T1 must miss the cone");
    for s in [1usize, 3] {
        let (m, se) = mean_se(n / s, 11 + s as u64, |r| dual.estimate(s, r, g));
        assert!((m - t).abs() < 4.0 * se, "dual S={s}: {m} vs {t} ± {se}");
    }
    let ds = ForecastTables::build(photons.iter().copied(), lambert, TableMode::DualSpread { radius: 2.0, alpha: 0.5 });
    let (m, se) = mean_se(n, 19, |r| ds.estimate(1, r, g));
    assert!((m - t).abs() < 4.0 * se, "dual-spread: {m} vs {t} ± {se}");
    // Generic value type: the Rgb estimate equals the scalar one channel-wise.
    let mut r1 = Rng::keyed(1, stream::MISC, 0, 0);
    let mut r2 = r1.clone();
    let a = dual.estimate(2, &mut r1, g);
    let b = dual.estimate(2, &mut r2, |w| Vec3::splat(g(w)));
    assert_eq!(b, Vec3::splat(a));
}

/// `DualSpread` keeps `Dual`'s T1 and partition, and moves T2's mass into the empty bins next
/// to the photons. Photons at the centres of every other φ column of one μ row (a caustic
/// sampled with gaps): the tent of half-width 2 gives each photon's neighbours (±1 column,
/// ±1 row) weights ½·½ of the centre's 1·1 in each axis, so a photon keeps ¼ in its own bin and
/// spreads ¾ over empty ones (S = 16·¾), and a gap bin between two photons gets 2·(¼·½) = ¼.
/// Its T2 pmf is therefore (1−α)·¼/12 + α·p_dual, with p_dual the plain fill's pmf.
#[test]
fn dual_spread_fills_the_gaps_between_photons() {
    let row = 10;
    let photons: Vec<(Vec3, f32)> = (0..N_PHI).step_by(2).map(|j| (bin_center(row * N_PHI + j), 1.0)).collect();
    let dual = ForecastTables::build(photons.iter().copied(), lambert, TableMode::Dual);
    let alpha = 0.5;
    let ds = ForecastTables::build(photons.iter().copied(), lambert, TableMode::DualSpread { radius: 2.0, alpha });
    assert_eq!(dual.t1, ds.t1);
    let (t1, t2, t2d) = (ds.t1.as_ref().unwrap(), ds.t2.as_ref().unwrap(), dual.t2.as_ref().unwrap());
    assert!((0..N_BINS).all(|i| (t1.bin_pmf(i) > 0.0) != (t2.bin_pmf(i) > 0.0)));
    let gap = row * N_PHI + 1;
    let want = (1.0 - alpha) * 0.25 / 12.0 + alpha * t2d.bin_pmf(gap);
    assert!((t2.bin_pmf(gap) / want - 1.0).abs() < 1e-3, "gap pmf {} vs {want}", t2.bin_pmf(gap));
    // two rows away the tent gives nothing: only the halved fill remains
    let far = (row - 2) * N_PHI + 1;
    assert!((t2.bin_pmf(far) / (alpha * t2d.bin_pmf(far)) - 1.0).abs() < 1e-3);
}

#[test]
fn naive_t1_only_estimator_is_biased() {
    let photons = photon_set(200, 60.0, 200.0, 10.0, 5);
    let t1 = ForecastTables::build(photons, lambert, TableMode::Dual).t1.unwrap();
    let (m, se) = mean_se(200_000, 17, |r| {
        let (w, pdf) = t1.sample([r.next_f32(), r.next_f32(), r.next_f32()]);
        g(w) / pdf
    });
    assert!((m - truth()).abs() > 4.0 * se, "T1-only should be biased: {m} vs {} ± {se}", truth());
}
