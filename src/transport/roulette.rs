//! The one Russian-roulette rule: survive with probability `q`, then divide by `q`
//! (unbiased: `E[β/q · 1[u < q]] = β`). `q ≤ 0` (or NaN) ends the path without a draw and
//! `q ≥ 1` keeps it without a draw, so no random number is spent when the outcome is certain.
//!
//! The survival probabilities: [`q_max`] for `pt` and Dirac chains (Mitsuba's and pbrt-v4's
//! `min(max β·etaScale, 0.95)`, applied by [`Throughput::scatter`]), [`q_recursion`] for the
//! IWS recursion (spec §4 "Termination", on the largest channel rather than the luminance, see
//! there) and [`q_particle`] for light paths (spec §2).

use crate::bsdf::BsdfSample;
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

/// First path vertex (counting from 1) at which `pt`, `pt-cf` and the Dirac chains may roulette:
/// one constant, so that a camera prefix is sampled the same way by every integrator and by
/// `transport::dirac::prefix_emission` (emission splitting relies on it).
pub const RR_FROM_VERTEX: u32 = 5;

/// The throughput β of a `pt`-style path (`pt`, `pt-cf`, Dirac chains) with pbrt-v4's
/// `etaScale`, the product of η² over its refractions (`BsdfSample::eta`). Radiance-mode
/// transport puts 1/η² into β at each refraction (`bsdf::dielectric`), so inside a glass ball β
/// is 0.44 of the energy the path carries; roulette on `β·etaScale` gives a path inside the ball
/// the survival probability it has outside. Any `q` is unbiased, but roulette on β alone kills
/// 56% of the paths inside glass and lets the survivors leave with ×2.25/q: a heavy tail (on
/// `cornell-box`, camera rays through the glass ball that reach the light after an internal
/// reflection were worth 2.37·Le, and a 1/16 of them carried most of a crop's error).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Throughput {
    /// β, the path's weight so far.
    pub beta: Rgb,
    eta_scale: f32,
}

impl Throughput {
    /// A path of weight `beta` that starts outside every dielectric.
    pub fn new(beta: Rgb) -> Throughput {
        Throughput { beta, eta_scale: 1.0 }
    }

    /// Vertex `vertex` (from 0) scatters into `bs`: β·weight, then from vertex
    /// [`RR_FROM_VERTEX`] on, roulette with `q = q_max(β·etaScale)`. False when the path ends.
    #[inline]
    pub fn scatter(&mut self, bs: &BsdfSample, vertex: u32, rng: &mut Rng) -> bool {
        self.beta *= bs.weight;
        self.eta_scale *= bs.eta * bs.eta;
        if vertex + 1 >= RR_FROM_VERTEX {
            let Some(b) = roulette(self.beta, q_max(self.beta * self.eta_scale), rng) else { return false };
            self.beta = b;
        }
        true
    }
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::rng::{stream, Rng};

    /// No channel of a recursion weight grows through roulette beyond `max(1, max_c w_c / 0.95)`
    /// (the survivor's factor `w_c / q`), for saturated colours too; the luminance rule fails
    /// this (a red-wall weight survives with q = 0.18 and its red grows 3.4×).
    #[test]
    fn recursion_roulette_grows_no_channel() {
        let mut r = Rng::keyed(7, stream::MISC, 0, 0);
        for i in 0..100_000 {
            let s = if i % 2 == 0 { 1.0 } else { 0.1 };
            let w = Rgb::new(r.next_f32(), r.next_f32(), r.next_f32()) * Rgb::new(s, s * r.next_f32(), 1.3);
            let q = q_recursion(w, 2);
            let bound = (w.max_element() / 0.95).max(1.0);
            assert!((w / q).max_element() <= bound * (1.0 + 1e-6), "{w:?}: q = {q}");
        }
        let red = Rgb::new(0.63, 0.065, 0.05);
        assert!((red / luminance(red)).x > 3.0, "the luminance rule would grow red");
        assert_eq!(q_recursion(red, 2), 0.63);
        assert_eq!(q_recursion(red, 1), 1.0);
    }

    /// The survivor's weight β/q has mean β (unbiased) for the three rules.
    #[test]
    fn roulette_is_unbiased() {
        let beta = Rgb::new(0.63, 0.065, 0.05);
        for q in [q_max(beta), q_recursion(beta, 3), q_particle(beta)] {
            let mut rng = Rng::keyed(9, stream::MISC, 0, 0);
            let n = 200_000;
            let sum = (0..n).filter_map(|_| roulette(beta, q, &mut rng)).fold(Rgb::ZERO, |a, b| a + b);
            let mean = sum / n as f32;
            // Bernoulli(q) scaled by β/q: σ of the mean = β·sqrt((1−q)/(q·n)); 5σ
            let tol = beta * (((1.0 - q) / (q * n as f32)).sqrt() * 5.0);
            assert!((mean - beta).abs().cmple(tol + Rgb::splat(1e-7)).all(), "q = {q}: {mean:?} vs {beta:?}");
        }
    }
}
