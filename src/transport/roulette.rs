//! The one Russian-roulette rule: survive with probability `q`, then divide by `q`
//! (unbiased: `E[β/q · 1[u < q]] = β`). `q ≤ 0` (or NaN) ends the path without a draw and
//! `q ≥ 1` keeps it without a draw, so no random number is spent when the outcome is certain.
//!
//! The survival probabilities: [`q_max`] for `pt` and Dirac chains (Mitsuba's and pbrt-v4's
//! `min(max β·etaScale, 0.95)`, applied by [`Throughput::scatter`]), [`q_recursion`] for the
//! IWS recursion (spec §4 "Termination", on the largest channel rather than the luminance, see
//! there) and [`q_particle`] for light paths (spec §2). Why each: `results/2026-11-30-roulette.md`.

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
///
/// `guide_scale` does for guided vertices (`pt-cf`) what `etaScale` does for refractions: the
/// product over them of `pdf_w / pdf_w_BSDF`, so that roulette sees the β the BSDF sampler would
/// have given the same path. A guided direction drawn where the tables are dense has a small
/// weight `f·|cos|/(n·q)`; on β alone the path then survives a later roulette with that small
/// probability and leaves with β ≈ 1. On the SMS ring that made one `E S D S+ L` sample worth
/// 84,336 (the light's radiance) in a 640×480 render
/// (`results/2026-12-04-guided-roulette.md`). Any survival probability that is a function of the
/// path so far is unbiased; this one gives a guided path the one `pt` gives it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Throughput {
    /// β, the path's weight so far.
    pub beta: Rgb,
    eta_scale: f32,
    guide_scale: f32,
}

impl Throughput {
    /// A path of weight `beta` that starts outside every dielectric.
    pub fn new(beta: Rgb) -> Throughput {
        Throughput { beta, eta_scale: 1.0, guide_scale: 1.0 }
    }

    /// The next direction is drawn with solid-angle pdf `pdf_w` where the BSDF's is `bsdf_pdf_w`
    /// (a guided vertex): roulette from here on sees the throughput of BSDF sampling. Ignored
    /// unless both are positive and finite (equal pdfs leave the path as `pt` has it, bit for bit).
    #[inline]
    pub fn guided(&mut self, pdf_w: f32, bsdf_pdf_w: f32) {
        let r = pdf_w / bsdf_pdf_w;
        if pdf_w > 0.0 && bsdf_pdf_w > 0.0 && r.is_finite() {
            self.guide_scale *= r;
        }
    }

    /// The survival probability of a roulette now: `q_max(β·etaScale·guideScale)`.
    #[inline]
    pub fn q(&self) -> f32 {
        q_max(self.beta * (self.eta_scale * self.guide_scale))
    }

    /// Vertex `vertex` (from 0) scatters into `bs`: β·weight, then from vertex
    /// [`RR_FROM_VERTEX`] on, roulette with [`Throughput::q`]. False when the path ends.
    #[inline]
    pub fn scatter(&mut self, bs: &BsdfSample, vertex: u32, rng: &mut Rng) -> bool {
        self.beta *= bs.weight;
        self.eta_scale *= bs.eta * bs.eta;
        if vertex + 1 >= RR_FROM_VERTEX {
            let Some(b) = roulette(self.beta, self.q(), rng) else { return false };
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

    /// A guided vertex's roulette is the one BSDF sampling of the same path would have had.
    #[test]
    fn guided_roulette_sees_the_bsdf_throughput() {
        // A Lambert vertex (albedo 0.1) guided with split n = 4 into a bin of density q = 8.33
        // where p_BSDF = 0.154: the SMS-ring firefly's numbers.
        let (albedo, n, q, p_b) = (Rgb::new(0.1, 0.07, 0.02), 4.0f32, 8.33f32, 0.154f32);
        let before = Rgb::new(0.9, 0.6, 0.3);
        let f_cos = albedo * (p_b); // f·cos = ρ/π·cos = ρ·p_BSDF for the cosine warp
        let guided =
            BsdfSample { wi: crate::math::Vec3::Z, weight: f_cos / (n * q), pdf_w: n * q, is_delta: false, eta: 1.0 };
        let mut t = Throughput::new(before);
        t.guided(guided.pdf_w, p_b);
        let mut rng = Rng::keyed(1, stream::MISC, 0, 0);
        assert!(t.scatter(&guided, 0, &mut rng), "no roulette before RR_FROM_VERTEX");
        let bsdf_beta = before * albedo;
        assert!((t.q() - q_max(bsdf_beta)).abs() <= 1e-6 * q_max(bsdf_beta), "{} vs {}", t.q(), q_max(bsdf_beta));
        assert!(t.q() > 200.0 * q_max(t.beta) * 0.99, "β alone would survive {}× less often", n * q / p_b);
        // Equal pdfs, zeros and non-finite ratios leave the roulette as pt has it, bit for bit.
        let plain = Throughput::new(before);
        for (a, b) in [(0.3, 0.3), (0.0, 0.2), (0.2, 0.0), (f32::INFINITY, 1.0), (f32::NAN, 1.0), (1e30, 1e-30)] {
            let mut g = Throughput::new(before);
            g.guided(a, b);
            assert_eq!(g.q().to_bits(), plain.q().to_bits(), "guided({a}, {b})");
        }
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
