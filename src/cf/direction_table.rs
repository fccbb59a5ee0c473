//! Jensen-95 directional sampling tables and the CF dual-table estimators ([BAJ08 §3.2]
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
//!   samples into the gaps next to the photons instead of over the whole hemisphere.
//!
//! (The single defensive table and the defensive T1, `--table single|dual-defensive`, measured
//! no better and were retired: `results/rejected/table.md`.)
//!
//! Invariants: every bin where the integrand may be non-zero has pdf > 0 in exactly one dual
//! table; sampled directions have μ ∈ (0, 1] (never on the horizon) and a pdf equal to `pdf_w`
//! of the same direction; the number of samples never depends on the samples.
//! Construction never panics: NaN/negative weights count as 0, a table with no weight is `None`.

// `!(x > 0.0)`-style tests are deliberate: they are true for NaN (degenerate input is rejected).
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::bins::dir_in_bin;
pub use super::bins::{bin_center, bin_of, BIN_SOLID_ANGLE, N_BINS, N_MU, N_PHI};
use super::splat::blend_spread;
pub use super::splat::{splat_histogram, Splat};
use crate::math::{Vec3, PI};
use crate::sampling::alias::quantised_columns;
use crate::sampling::rng::Rng;
use std::ops::{Add, Mul};

/// Smallest probability of a bin with positive weight (see `DirectionTable::from_weights`).
pub const MIN_BIN_PMF: f64 = 1.0 / 65536.0;
/// Relative floor of the T2 / defensive fill values (spec §4 ⚠ sharp lobes).
pub const FILL_FLOOR_REL: f32 = 1e-3;

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
    /// Dual table whose T2 (still exactly the empty bins) follows the forecasters spread over
    /// their neighbouring bins: `(1−α) s/S + α v/V` on Ω₂ (`s` = tent splat of half-width
    /// `radius` bins). T1 is `Dual`'s, so the partition and the unbiasedness are unchanged.
    DualSpread {
        /// Tent half-width in bins (`splat::Splat::Tent`).
        radius: f32,
        /// Share of the f·cos fill in T2 (clamped to [1e-3, 1]).
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
    /// 0 for T1, 1 for T2.
    pub table: u8,
}

/// The tables of one shading point.
#[derive(Clone, Debug, PartialEq)]
pub struct ForecastTables {
    /// T1 (photon table).
    pub t1: Option<DirectionTable>,
    /// T2 (dual fill on empty bins).
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
        // T1 skipped if k = 0 / zero total (from_weights → None).
        let t1 = DirectionTable::from_weights(&w);
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
                let u = rng.next_3d();
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
#[path = "direction_table_tests.rs"]
mod tests;
