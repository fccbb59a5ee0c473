//! The hemisphere bins of the Jensen-95 direction tables ([BAJ08 §3.2], spec §4 "pdfs"):
//! `N_PHI × N_MU = 32 × 16` bins uniform in φ ∈ [0, 2π) and μ = cosθ ∈ [0, 1] of the local frame
//! (z = shading normal), bin `i = l·N_PHI + j` for μ-row `l` and φ-column `j`. By Archimedes every
//! bin has the solid angle `ΔΩ = 2π/512`.
//!
//! The one geometry below both the tables (`direction_table`) and the forecaster splatting
//! (`splat`). Invariants: `bin_of` is `None` on and below the horizon and for non-finite input,
//! and otherwise in `0..N_BINS`; `bin_center(i)` lies in bin `i`.

// `!(x > 0.0)`-style tests are deliberate: they are true for NaN (degenerate input is rejected).
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use crate::math::{Vec3, PI};

/// Azimuth bins.
pub const N_PHI: usize = 32;
/// Cos-zenith bins.
pub const N_MU: usize = 16;
/// Total bins.
pub const N_BINS: usize = N_PHI * N_MU;
/// Solid angle of every bin, ΔΩ = 2π/(N_φ N_μ).
pub const BIN_SOLID_ANGLE: f32 = 2.0 * PI / N_BINS as f32;

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
pub(super) fn dir_in_bin(i: usize, a: f32, b: f32) -> Vec3 {
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
