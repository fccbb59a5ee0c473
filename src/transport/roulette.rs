//! The one Russian-roulette rule: survive with probability `q`, then divide by `q`
//! (unbiased: `E[β/q · 1[u < q]] = β`). `q ≤ 0` (or NaN) ends the path without a draw and
//! `q ≥ 1` keeps it without a draw, so no random number is spent when the outcome is certain.
//!
//! The survival probabilities are the ones the methods are specified with (kept bit-exact):
//! [`q_max`] for `pt` and Dirac chains (Mitsuba's `min(max β, 0.95)`), [`q_recursion`] for the
//! IWS recursion (spec §4 "Termination", on the largest channel rather than the luminance, see
//! there) and [`q_particle`] for light paths (spec §2).

use crate::math::{luminance, Rgb};
use crate::sampling::rng::Rng;

/// `Some(β/q)` with probability `q` (clamped to [0, 1]), else `None`.
#[inline]
pub fn roulette(beta: Rgb, q: f32, rng: &mut Rng) -> Option<Rgb> {
    if q.is_nan() || q <= 0.0 {
        return None;
    }
    if q >= 1.0 {
        return Some(beta);
    }
    if rng.next_f32() >= q {
        return None;
    }
    Some(beta / q)
}

/// `pt` and Dirac chains: `q = min(max_c β_c, 0.95)`.
#[inline]
pub fn q_max(beta: Rgb) -> f32 {
    beta.max_element().min(0.95)
}

/// The IWS recursion `L̂(·, d)` at `d ≥ 2`: `q = clamp(max_c weight_c, 0.05, 0.95)`; 1 below.
///
/// The spec's `lum(weight)` is unbiased too, but on a saturated surface it multiplies the
/// dominant channel at every bounce: a red-wall bounce (albedo 0.63/0.065/0.05, luminance 0.18)
/// survives with q = 0.18 and scales red by 3.4, so chains of compensation bounces in the red
/// corner of `cornell-box` made red fireflies (one `iws-cf` sample worth ≈ 4,900 at 4 min). On
/// the largest channel no channel grows (`weight_c / q ≤ 1` whenever q < 0.95).
#[inline]
pub fn q_recursion(weight: Rgb, depth: u32) -> f32 {
    if depth < 2 {
        1.0
    } else {
        weight.max_element().clamp(0.05, 0.95)
    }
}

/// Light paths: `q = min(1, lum(f·|cos|/p))` on the sampled BSDF weight.
#[inline]
pub fn q_particle(weight: Rgb) -> f32 {
    luminance(weight).min(1.0)
}
