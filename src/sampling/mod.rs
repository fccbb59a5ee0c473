//! Random numbers, warps from the unit square, discrete distributions and MIS heuristics.

pub mod alias;
pub mod distribution;
pub mod qmc;
pub mod rng;
pub mod warp;

/// Power heuristic (β = 2) weight of strategy `a` against `b` (Veach 1997, eq. 9.13).
#[inline]
pub fn power_heuristic(pdf_a: f32, pdf_b: f32) -> f32 {
    let (a, b) = (pdf_a * pdf_a, pdf_b * pdf_b);
    if a + b > 0.0 && a.is_finite() {
        a / (a + b)
    } else if a.is_infinite() {
        1.0
    } else {
        0.0
    }
}
