//! Forecaster splatting, for the `dual-spread` tables (beyond BAJ08; `docs/methods/iws-cf.md`,
//! "Sampling L_c"): how a forecaster's weight is spread over the 32×16 direction bins of
//! [`super::bins`] when a table is built. Evidence: `results/rejected/table.md`.
//!
//! Invariant: every spread adds exactly the forecaster's weight, so the tables stay valid pdfs
//! and the estimator unbiased.

use super::bins::{bin_of, N_BINS, N_MU, N_PHI};
use crate::math::{Vec3, PI};

/// How a forecaster's weight is spread over the bins when a table is built (issue #11 item 6).
/// Any spread keeps the tables valid pdfs (and the dual partition), so every choice is unbiased.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Splat {
    /// All of it into its own bin (the paper; bit-identical to `direction_table::ForecastTables::build`).
    #[default]
    None,
    /// A separable tent of half-width `radius` bins (clamped to [1, 8]; 1 = bilinear between the
    /// nearest bin centres) in (φ, μ) bin coordinates, φ wrapping round, rows beyond the pole or the
    /// horizon dropped; the weights are renormalised so they sum to the forecaster's weight.
    Tent {
        /// Half-width in bins.
        radius: f32,
    },
}

/// Bin-coordinate (x, y) of a local direction: bin centres at integers, `None` as [`bin_of`].
#[inline]
fn bin_coords(local: Vec3) -> Option<(f32, f32)> {
    bin_of(local)?;
    let mu = local.z / local.length();
    let mut phi = local.y.atan2(local.x);
    if phi < 0.0 {
        phi += 2.0 * PI;
    }
    Some((phi * (N_PHI as f32 / (2.0 * PI)) - 0.5, mu * N_MU as f32 - 0.5))
}

/// Tent weights `max(0, 1 − |x − c|/h)` of the integer centres `c` within `h` of `x`.
#[inline]
fn tent(x: f32, h: f32) -> impl Iterator<Item = (i32, f32)> {
    ((x - h).ceil() as i32..=(x + h).floor() as i32).map(move |c| (c, (1.0 - (x - c as f32).abs() / h).max(0.0)))
}

/// The bin weights of a set of forecasters `(ω local, weight)`: photons with μ ≤ 0 or a weight that is
/// not positive and finite are skipped; each photon adds exactly its weight (spread by `splat`).
pub fn splat_histogram(photons: impl IntoIterator<Item = (Vec3, f32)>, splat: Splat) -> [f32; N_BINS] {
    let mut w = [0.0f32; N_BINS];
    let ok = |weight: f32| weight.is_finite() && weight > 0.0;
    match splat {
        Splat::None => {
            for (dir, weight) in photons {
                if let Some(i) = bin_of(dir) {
                    if ok(weight) {
                        w[i] += weight;
                    }
                }
            }
        }
        Splat::Tent { radius } => {
            let h = if radius.is_finite() { radius.clamp(1.0, 8.0) } else { 1.0 };
            for (dir, weight) in photons {
                let Some((x, y)) = bin_coords(dir).filter(|_| ok(weight)) else { continue };
                let rows = || tent(y, h).filter(|&(l, _)| (0..N_MU as i32).contains(&l));
                let (sx, sy): (f32, f32) = (tent(x, h).map(|t| t.1).sum(), rows().map(|t| t.1).sum());
                if !(sx > 0.0 && sy > 0.0) {
                    continue; // unreachable: the nearest centre always has weight > 0
                }
                for (l, wy) in rows() {
                    for (j, wx) in tent(x, h) {
                        let j = j.rem_euclid(N_PHI as i32) as usize;
                        w[l as usize * N_PHI + j] += weight * (wx / sx) * (wy / sy);
                    }
                }
            }
        }
    }
    w
}

/// Blends the spread forecaster weights `spread` into the fill `v` on `bins` (T2's empty bins):
/// `v_i ← (1−α)·s_i/S + α·v_i/V` with `S`, `V` the sums over `bins` (`α` clamped to [1e-3, 1]).
/// Every bin with `v_i > 0` keeps a positive weight (α > 0), so the fill still covers its bins;
/// without spread mass on `bins` (`S = 0`), `v` is left as it is.
pub fn blend_spread(
    v: &mut [f32; N_BINS],
    spread: &[f32; N_BINS],
    bins: impl Iterator<Item = usize> + Clone,
    alpha: f32,
) {
    let alpha = if alpha.is_finite() { alpha.clamp(1e-3, 1.0) } else { 1.0 };
    let ok = |x: f32| if x.is_finite() && x > 0.0 { x } else { 0.0 };
    let big_s: f32 = bins.clone().map(|i| ok(spread[i])).sum();
    let big_v: f32 = bins.clone().map(|i| ok(v[i])).sum();
    if !(big_s > 0.0 && big_v > 0.0) {
        return;
    }
    for i in bins {
        v[i] = (1.0 - alpha) * ok(spread[i]) / big_s + alpha * ok(v[i]) / big_v;
    }
}
