//! Jensen-95 directional sampling tables and the CF dual-table / single-table estimators ([BAJ08 §3.2]
//! "Caustic Forecast Importance Sampling"; spec §4, §7.3, §7.7, §10).
//!
//! A table is a piecewise-constant pdf over `N_PHI × N_MU = 32 × 16` bins uniform in φ ∈ [0, 2π) and
//! μ = cosθ ∈ [0, 1] of the local frame (z = shading normal). By Archimedes every bin has solid angle
//! `ΔΩ = 2π/512`, so `p(ω) = (w_{i(ω)}/W)/ΔΩ` (spec §4 "pdfs"). Bin index `i = l·N_PHI + j` for μ-row
//! `l` and φ-column `j`.
//!
//! `ForecastTables` builds, from gathered forecasters `(ω_in local, weight)`:
//! - `Dual`: T1 from the photon weights, T2 on exactly the bins where `w_i = 0` with
//!   `v_i = f·cos(bin centre)` floored at `1e-3·max v`; the estimate is the SUM of the two averages
//!   (`Ω_1`, `Ω_2` partition the hemisphere, so `E = ∫_{Ω1} g + ∫_{Ω2} g = ∫ g`);
//! - `DualSpread { radius, alpha }`: T1 as `Dual`; T2 on the same empty bins, but weighted
//!   `(1−α)·s_i/S + α·v_i/V` where `s` is the forecasters spread by a tent of `radius` bins
//!   (`splat.rs`): a caustic seen through glass that the photons covered with gaps puts T2's
//!   samples into the gaps next to the photons instead of over the whole hemisphere;
//! - `Single { alpha }`: one defensive table `w' = (1−α)w/W + α v/V` with `v > 0` everywhere.
//!
//! Invariants: every bin where the integrand may be non-zero has pdf > 0 in exactly one dual table
//! (or in the single table); sampled directions have μ ∈ (0, 1] (never on the horizon) and a pdf
//! equal to `pdf_w` of the same direction; the number of samples never depends on the samples.
//! Construction never panics: NaN/negative weights count as 0, a table with no weight is `None`.

// `!(x > 0.0)`-style tests are deliberate: they are true for NaN (degenerate input is rejected).
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::splat::blend_spread;
pub use super::splat::{splat_histogram, Splat};
use crate::math::{Vec3, PI};
use crate::sampling::alias::quantised_columns;
use crate::sampling::rng::Rng;
use std::ops::{Add, Mul};

/// Azimuth bins.
pub const N_PHI: usize = 32;
/// Cos-zenith bins.
pub const N_MU: usize = 16;
/// Total bins.
pub const N_BINS: usize = N_PHI * N_MU;
/// Solid angle of every bin, ΔΩ = 2π/(N_φ N_μ).
pub const BIN_SOLID_ANGLE: f32 = 2.0 * PI / N_BINS as f32;
/// Smallest probability of a bin with positive weight (see `DirectionTable::from_weights`).
pub const MIN_BIN_PMF: f64 = 1.0 / 65536.0;
/// Relative floor of the T2 / defensive fill values (spec §4 ⚠ sharp lobes).
pub const FILL_FLOOR_REL: f32 = 1e-3;

/// Bin of a local direction (z = normal), or `None` below/on the horizon or for non-finite input.
#[inline]
pub fn bin_of(local: Vec3) -> Option<usize> {
    let len = local.length();
    if !(len > 0.0) || !len.is_finite() {
        return None;
    }
    let mu = local.z / len;
    if !(mu > 0.0) {
        return None;
    }
    let mut phi = local.y.atan2(local.x);
    if phi < 0.0 {
        phi += 2.0 * PI;
    }
    let j = ((phi * (N_PHI as f32 / (2.0 * PI))) as usize).min(N_PHI - 1);
    let l = ((mu * N_MU as f32) as usize).min(N_MU - 1);
    Some(l * N_PHI + j)
}

/// Local direction at (φ, μ) fractions `(j + a)/N_PHI`, `(l + b)/N_MU` of bin `i`.
#[inline]
fn dir_in_bin(i: usize, a: f32, b: f32) -> Vec3 {
    let (l, j) = (i / N_PHI, i % N_PHI);
    let phi = 2.0 * PI * (j as f32 + a) / N_PHI as f32;
    let mu = ((l as f32 + b) / N_MU as f32).min(1.0);
    let s = (1.0 - mu * mu).max(0.0).sqrt();
    Vec3::new(s * phi.cos(), s * phi.sin(), mu)
}

/// Centre direction (φ_c, μ_c) of bin `i` (used for the representative f·cosθ, spec §7.7).
#[inline]
pub fn bin_center(i: usize) -> Vec3 {
    dir_in_bin(i.min(N_BINS - 1), 0.5, 0.5)
}

/// Cosine-weighted hemisphere sample (the fallback outside kept clusters, spec §4); pdf = μ/π.
#[inline]
pub fn sample_cosine(u: [f32; 2]) -> Vec3 {
    let r = u[0].sqrt();
    let phi = 2.0 * PI * u[1];
    // 1 − u0 ∈ (0, 1]: μ > 0, never on the horizon.
    Vec3::new(r * phi.cos(), r * phi.sin(), (1.0 - u[0]).sqrt())
}

/// Solid-angle pdf of [`sample_cosine`].
#[inline]
pub fn cosine_pdf_w(local: Vec3) -> f32 {
    if local.z > 0.0 {
        local.z / PI
    } else {
        0.0
    }
}

/// A piecewise-constant pdf over the 512 hemisphere bins, sampled in O(1) by an alias table
/// (Walker 1977, Vose 1991) packed into one word per bin: a sample reads two cache lines (its
/// column, then the pmf of the bin it lands in), where a binary search of the cdf read up to nine
/// (the tables of a render do not fit in cache: that search was 10% of an `iws-cf` sample).
///
/// Exactness: a uniform `u0 = k/2²⁴` (`Rng::next_f32`) picks column `k >> 15` and accepts it iff
/// `k mod 2¹⁵ < T_col`, else returns the column's alias. The thresholds `T` are integers and the
/// pmf is computed from them, so `pmf_i` is exactly the probability of bin `i` under uniform `k`.
#[derive(Clone, Debug, PartialEq)]
pub struct DirectionTable {
    /// Bin probabilities (sum 1), exact multiples of 2⁻²⁴.
    pmf: [f32; N_BINS],
    /// Column word: acceptance threshold `T ∈ [0, 2¹⁵]` in the high 16 bits, alias bin in the low.
    cols: [u32; N_BINS],
}

/// Bits of the 24-bit uniform that decide acceptance (the top 9 choose one of the 2⁹ columns).
const ACC_BITS: u32 = 15;
/// 2¹⁵: a column that always accepts.
const ACC_ONE: u32 = 1 << ACC_BITS;

impl DirectionTable {
    /// Table ∝ `weights` (non-finite or negative entries count as 0; positive bins floored at
    /// [`MIN_BIN_PMF`] before renormalising); `None` if nothing is positive.
    pub fn from_weights(weights: &[f32; N_BINS]) -> Option<Self> {
        let w = |x: f32| if x.is_finite() && x > 0.0 { x as f64 } else { 0.0 };
        let total: f64 = weights.iter().map(|&x| w(x)).sum();
        if !(total > 0.0) || !total.is_finite() {
            return None;
        }
        // Positive bins get probability ≥ MIN_BIN_PMF (then renormalised): a bin with a vanishing
        // weight next to bright ones is still sampled, not left as a firefly lottery.
        let floored: Vec<f64> =
            weights.iter().map(|&x| if w(x) > 0.0 { (w(x) / total).max(MIN_BIN_PMF) } else { 0.0 }).collect();
        let (thresh, alias) = quantised_columns(&floored, ACC_ONE.into());
        // exact probabilities of the quantised table, in units of 2⁻²⁴: column c gives T_c to
        // itself and 2¹⁵ − T_c to its alias
        let mut count = [0u32; N_BINS];
        for c in 0..N_BINS {
            count[c] += thresh[c] as u32;
            count[alias[c] as usize] += ACC_ONE - thresh[c] as u32;
        }
        let pmf = count.map(|k| k as f32 * (1.0 / 16_777_216.0));
        let cols = std::array::from_fn(|c| ((thresh[c] as u32) << 16) | alias[c]);
        Some(DirectionTable { pmf, cols })
    }

    /// The bin that a uniform `u0 ∈ [0, 1)` selects (never a bin of pmf 0).
    #[inline]
    fn bin_for(&self, u0: f32) -> usize {
        let k = if u0.is_finite() { (u0.clamp(0.0, 1.0) * 16_777_216.0) as u32 } else { 0 }.min((1 << 24) - 1);
        let col = (k >> ACC_BITS) as usize;
        let word = self.cols[col];
        if k & (ACC_ONE - 1) < word >> 16 {
            col
        } else {
            (word & 0xffff) as usize
        }
    }

    /// Probability of bin `i` (0 outside).
    #[inline]
    pub fn bin_pmf(&self, i: usize) -> f32 {
        self.pmf.get(i).copied().unwrap_or(0.0)
    }

    /// Solid-angle pdf `p(ω) = pmf_{i(ω)} / ΔΩ` of a local direction (0 below the horizon).
    #[inline]
    pub fn pdf_w(&self, local: Vec3) -> f32 {
        bin_of(local).map_or(0.0, |i| self.pmf[i] / BIN_SOLID_ANGLE)
    }

    /// Samples a local direction from three uniforms in [0, 1): `u[0]` picks the bin through the
    /// alias table, `u[1]`, `u[2]` place it uniformly in (φ, μ) within the bin. Returns `(ω, pdf_w)`.
    #[inline]
    pub fn sample(&self, u: [f32; 3]) -> (Vec3, f32) {
        let i = self.bin_for(u[0]);
        // μ = (l + 1 − u2)/N_MU ∈ (l/N_MU, (l+1)/N_MU]: never exactly on the horizon.
        let (a, b) = (u[1].clamp(0.0, 1.0), 1.0 - u[2].clamp(0.0, 1.0));
        let mut w = dir_in_bin(i, a, b);
        if bin_of(w) != Some(i) {
            // f32 rounding put a bin-edge sample into a neighbour (measure ~1e-7): nudge it inside so
            // that the returned pdf always equals `pdf_w(w)`.
            w = dir_in_bin(i, a.clamp(1e-3, 1.0 - 1e-3), b.clamp(1e-3, 1.0 - 1e-3));
        }
        (w, self.pmf[i] / BIN_SOLID_ANGLE)
    }
}

/// How the forecaster tables are combined (spec §4).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TableMode {
    /// CF dual table: T1 (photons) + T2 (f·cos on the empty bins), estimates summed.
    Dual,
    /// Dual table whose T1 is itself defensive on its own bins: `(1−α) w/W + α v/V₁` over
    /// Ω₁ = {w > 0}, so a bin holding only weak photons keeps an f·cos share (fewer fireflies);
    /// T2 as in `Dual`. Still a partition of the hemisphere, so still unbiased.
    DualDefensive {
        /// Share of the f·cos fill inside T1 (clamped to [0, 1]).
        alpha: f32,
    },
    /// Dual table whose T2 (still exactly the empty bins) follows the forecasters spread over
    /// their neighbouring bins: `(1−α) s/S + α v/V` on Ω₂ (`s` = tent splat of half-width
    /// `radius` bins). T1 is `Dual`'s, so the partition and the unbiasedness are unchanged.
    DualSpread {
        /// Tent half-width in bins (`splat::Splat::Tent`).
        radius: f32,
        /// Share of the f·cos fill in T2 (clamped to [1e-3, 1]).
        alpha: f32,
    },
    /// One defensive mixture `(1−α) w/W + α v/V`.
    Single {
        /// Mixture weight of the f·cos fill (clamped to [1e-4, 1]).
        alpha: f32,
    },
}

/// One direction to trace and its Monte Carlo weight.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TableSample {
    /// Local direction (z = shading normal), μ > 0.
    pub dir: Vec3,
    /// `1 / (S · pdf_w(dir))` of the table it came from: the contribution is `weight · g(dir)`.
    pub weight: f32,
    /// 0 for T1 (or the single table), 1 for T2.
    pub table: u8,
}

/// The tables of one shading point.
#[derive(Clone, Debug, PartialEq)]
pub struct ForecastTables {
    /// T1 (photon table) or the single defensive table.
    pub t1: Option<DirectionTable>,
    /// T2 (dual fill on empty bins); always `None` in single mode.
    pub t2: Option<DirectionTable>,
}

/// Representative values `v_i = max(f·cos(bin centre), 0)` on `bins`, floored at `1e-3·max v`, or a
/// uniform fill when every value is 0 (so the fill always covers its bins).
fn fill_values(bins: impl Iterator<Item = usize> + Clone, brdf_cos: &impl Fn(Vec3) -> f32) -> [f32; N_BINS] {
    let mut v = [0.0f32; N_BINS];
    let mut vmax = 0.0f32;
    for i in bins.clone() {
        let x = brdf_cos(bin_center(i));
        v[i] = if x.is_finite() && x > 0.0 { x } else { 0.0 };
        vmax = vmax.max(v[i]);
    }
    for i in bins {
        // spec §4 ⚠: floor so that a lobe missing the bin centre still gets pdf > 0.
        v[i] = if vmax > 0.0 { v[i].max(FILL_FLOOR_REL * vmax) } else { 1.0 };
    }
    v
}

impl ForecastTables {
    /// Builds the tables from gathered forecasters `(ω_in local, weight)` (weight = lum(Φ)·f·μ or the
    /// cosine-free variant; photons with μ ≤ 0 or weight ≤ 0 are skipped) and `brdf_cos(ω)` = f·cosθ.
    pub fn build(
        photons: impl IntoIterator<Item = (Vec3, f32)>,
        brdf_cos: impl Fn(Vec3) -> f32,
        mode: TableMode,
    ) -> Self {
        Self::build_with(photons, brdf_cos, mode, Splat::None)
    }

    /// [`Self::build`] with the forecasters spread over neighbouring bins by `splat`.
    pub fn build_with(
        photons: impl IntoIterator<Item = (Vec3, f32)>,
        brdf_cos: impl Fn(Vec3) -> f32,
        mode: TableMode,
        splat: Splat,
    ) -> Self {
        let photons: Vec<(Vec3, f32)> = photons.into_iter().collect();
        let w = splat_histogram(photons.iter().copied(), splat);
        match mode {
            TableMode::Dual | TableMode::DualDefensive { .. } | TableMode::DualSpread { .. } => {
                // T1 skipped if k = 0 / zero total (from_weights → None).
                let t1 = match mode {
                    TableMode::DualDefensive { alpha } if alpha > 0.0 => {
                        let alpha = alpha.min(1.0);
                        let v1 = fill_values((0..N_BINS).filter(|&i| w[i] > 0.0), &brdf_cos);
                        let (big_w, big_v): (f32, f32) = (w.iter().sum(), v1.iter().sum());
                        let mut m = [0.0f32; N_BINS];
                        if big_w > 0.0 && big_v > 0.0 {
                            for i in 0..N_BINS {
                                if w[i] > 0.0 {
                                    m[i] = (1.0 - alpha) * w[i] / big_w + alpha * v1[i] / big_v;
                                }
                            }
                        }
                        DirectionTable::from_weights(&m)
                    }
                    _ => DirectionTable::from_weights(&w),
                };
                let empty = (0..N_BINS).filter(|&i| !(w[i] > 0.0));
                // T2 on exactly Ω_2 = {w_i = 0}; skipped if Ω_2 = ∅.
                let t2 = if empty.clone().next().is_some() {
                    let mut v = fill_values(empty.clone(), &brdf_cos);
                    if let TableMode::DualSpread { radius, alpha } = mode {
                        let spread = splat_histogram(photons.iter().copied(), Splat::Tent { radius });
                        blend_spread(&mut v, &spread, empty, alpha);
                    }
                    DirectionTable::from_weights(&v)
                } else {
                    None
                };
                ForecastTables { t1, t2 }
            }
            TableMode::Single { alpha } => {
                let alpha = if alpha.is_finite() { alpha.clamp(1e-4, 1.0) } else { 0.1 };
                let v = fill_values(0..N_BINS, &brdf_cos);
                let big_v: f32 = v.iter().sum();
                let big_w: f32 = w.iter().sum();
                let mut m = [0.0f32; N_BINS];
                for i in 0..N_BINS {
                    // spec §4: w' = (1−α) w/W + α v/V (just v/V when no photon landed).
                    m[i] = if big_w > 0.0 { (1.0 - alpha) * w[i] / big_w + alpha * v[i] / big_v } else { v[i] / big_v };
                }
                ForecastTables { t1: DirectionTable::from_weights(&m), t2: None }
            }
        }
    }

    /// Number of directions [`Self::for_each_sample`] produces for `s` samples per table.
    pub fn n_samples(&self, s: usize) -> usize {
        s * (self.t1.is_some() as usize + self.t2.is_some() as usize)
    }

    /// Draws `s` samples from each existing table (3 uniforms each from `rng`) and hands them to `f`
    /// with weight `1/(s·pdf)`. Σ weight·g(dir) is the unbiased estimate of ∫ g over the hemisphere
    /// (spec §4: each table averaged over its own S samples, the averages SUMMED). `s = 0` gives none.
    pub fn for_each_sample(&self, s: usize, rng: &mut Rng, mut f: impl FnMut(TableSample)) {
        if s == 0 {
            return;
        }
        for (ti, t) in [&self.t1, &self.t2].into_iter().enumerate() {
            let Some(t) = t else { continue };
            for _ in 0..s {
                let u = [rng.next_f32(), rng.next_f32(), rng.next_f32()];
                let (dir, pdf) = t.sample(u);
                f(TableSample { dir, weight: 1.0 / (s as f32 * pdf), table: ti as u8 });
            }
        }
    }

    /// Convenience estimator `Σ_tables (1/s) Σ g(X)/p(X)` for any value type (f32, Rgb, …).
    pub fn estimate<T>(&self, s: usize, rng: &mut Rng, mut g: impl FnMut(Vec3) -> T) -> T
    where
        T: Default + Add<Output = T> + Mul<f32, Output = T>,
    {
        let mut acc = T::default();
        self.for_each_sample(s, rng, |smp| {
            let v = g(smp.dir) * smp.weight;
            acc = std::mem::take(&mut acc) + v;
        });
        acc
    }
}

#[cfg(test)]
mod tests {
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
        let t = ForecastTables::build(bad, |_| f32::NAN, TableMode::Single { alpha: f32::NAN });
        assert!(t.t1.is_some());
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
            let s = ForecastTables::build(set.iter().copied(), lambert, TableMode::Single { alpha: 0.1 });
            tables.push((name, s.t1.unwrap()));
            let dd = ForecastTables::build(set.iter().copied(), lambert, TableMode::DualDefensive { alpha: 0.25 });
            tables.push((name, dd.t1.unwrap()));
            let ds =
                ForecastTables::build(set.iter().copied(), lambert, TableMode::DualSpread { radius: 2.0, alpha: 0.5 });
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
        let single = ForecastTables::build(photons.iter().copied(), lambert, TableMode::Single { alpha: 0.1 });
        let (m, se) = mean_se(n, 13, |r| single.estimate(1, r, g));
        assert!((m - t).abs() < 4.0 * se, "single: {m} vs {t} ± {se}");
        let dd = ForecastTables::build(photons.iter().copied(), lambert, TableMode::DualDefensive { alpha: 0.25 });
        let (m, se) = mean_se(n, 17, |r| dd.estimate(1, r, g));
        assert!((m - t).abs() < 4.0 * se, "dual-defensive: {m} vs {t} ± {se}");
        let ds =
            ForecastTables::build(photons.iter().copied(), lambert, TableMode::DualSpread { radius: 2.0, alpha: 0.5 });
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
}
