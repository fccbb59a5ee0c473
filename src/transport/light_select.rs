//! Point-light (VPL) selection by resampled importance sampling (RIS; Talbot, Cline, Egbert 2005,
//! "Importance Resampling for Global Illumination"; the core of ReSTIR DI, Bitterli et al. 2020).
//!
//! Replaces the full gather `Σ_i F_i·V_i` (evidence: `results/rejected/vpl-select.md`): draw `M`
//! candidates `i_1..i_M` from a cheap source `q` (an alias table, e.g. ∝ lum(Φ_i), built once per
//! pass), weight each by `w_j = p̂(i_j)/q(i_j)` with the caller's target
//! `p̂(i) = lum(|f|·min(G,b)·Φ_i)` (no visibility), keep `y = i_j` with probability `w_j/Σw`
//! (prefix sums for M ≤ 32, else streaming weighted reservoirs), and estimate `F(y)·V(y)·W` with
//! the unbiased contribution weight `W = Σ_j w_j / (M·p̂(y))`.
//! `K` survivors (K shadow rays) are averaged, so each returned weight is `W/K` and the caller's
//! estimate is simply `Σ_k weight_k·F(y_k)·V(y_k)`.
//!
//! Unbiasedness: `E[Σ_k weight_k F(y_k) V(y_k)] = Σ_{i: p̂(i)>0} F_i V_i`, for every `M ≥ 1` and
//! `K ≥ 1`, provided `q(i) > 0` wherever `p̂(i) > 0` (source weights positive wherever a light can
//! contribute) and `p̂(i) > 0` wherever `F_i ≠ 0` (a target without visibility keeps the support).
//! `candidates = 0` takes every light once (`q = 1/n`, `M = n`): then `y ~ p̂/Σp̂` exactly and
//! `W = Σp̂/p̂(y)`, the `M → ∞` limit.
//!
//! Invariants: the number of uniforms drawn depends only on the parameters and `n` (never on the
//! samples); non-finite or negative targets count as 0; all candidates with `p̂ = 0` give no
//! survivor (estimate 0). The target is a closure, so this module knows nothing about VPLs.

// `!(x > 0.0)`-style tests are deliberate: they are true for NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use crate::sampling::alias::AliasTable;
use crate::sampling::rng::Rng;

/// Largest number of survivors `K` per selection (reservoirs live on the stack).
pub const MAX_SURVIVORS: u32 = 16;
/// Candidate sets up to this size are evaluated into a buffer and the survivors drawn from its
/// prefix sums (one uniform each); larger ones stream through weighted reservoirs.
pub const BUFFERED: usize = 32;
/// Largest number of candidates `M` per reservoir.
pub const MAX_CANDIDATES: u32 = 1 << 16;

/// RIS parameters (validated by [`RisParams::new`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct RisParams {
    /// Candidates per reservoir `M`; 0 = every light once (the `M → ∞` limit, exact `p̂/Σp̂`).
    pub candidates: u32,
    /// Survivors `K` (shadow rays), 1..=[`MAX_SURVIVORS`].
    pub survivors: u32,
    /// The `K` survivors are resampled from one shared candidate set (`M` target evaluations)
    /// rather than from `K` independent reservoirs (`K·M` evaluations). Both are unbiased.
    pub shared_candidates: bool,
}

impl RisParams {
    /// Checks the ranges; the error names the offending option.
    pub fn new(candidates: u32, survivors: u32, shared_candidates: bool) -> Result<Self, String> {
        if candidates > MAX_CANDIDATES {
            return Err(format!("RIS candidates M = {candidates}: at most {MAX_CANDIDATES} (0 = all lights)"));
        }
        if !(1..=MAX_SURVIVORS).contains(&survivors) {
            return Err(format!("RIS survivors K = {survivors}: must be in 1..={MAX_SURVIVORS}"));
        }
        Ok(RisParams { candidates, survivors, shared_candidates })
    }
}

/// One selected light and its estimator weight.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Selected<T> {
    /// Index of the light.
    pub index: usize,
    /// `W/K`: the contribution is `weight · F(index) · V(index)`.
    pub weight: f32,
    /// The value the target closure returned with `p̂(index)` (e.g. the unshadowed RGB
    /// contribution, so the caller does not evaluate it again).
    pub value: T,
}

/// A candidate kept by a reservoir: (index, p̂, value).
type Pick<T> = Option<(usize, f32, T)>;

/// The per-pass light selector: a source alias table over the lights.
#[derive(Clone, Debug, PartialEq)]
pub struct LightSelector {
    source: AliasTable,
}

impl LightSelector {
    /// Source `q ∝ source_weights` (e.g. lum(Φ_i)); `None` when no weight is positive.
    pub fn new(source_weights: &[f32]) -> Option<Self> {
        AliasTable::new(source_weights).map(|source| LightSelector { source })
    }

    /// Defensive source `q = (1−s)·w/Σw + s/n` (`s` clamped to [0, 1]): every light gets a
    /// positive candidate probability whatever its source weight. `None` as [`Self::new`].
    pub fn with_uniform_share(source_weights: &[f32], share: f32) -> Option<Self> {
        let s = if share.is_finite() { share.clamp(0.0, 1.0) } else { 0.0 };
        let ok = |x: f32| if x.is_finite() && x > 0.0 { x as f64 } else { 0.0 };
        let total: f64 = source_weights.iter().map(|&x| ok(x)).sum();
        if !(total > 0.0) || !total.is_finite() {
            return None;
        }
        let n = source_weights.len() as f64;
        let mixed: Vec<f32> =
            source_weights.iter().map(|&x| ((1.0 - s as f64) * ok(x) / total + s as f64 / n) as f32).collect();
        Self::new(&mixed)
    }

    /// Number of lights.
    pub fn len(&self) -> usize {
        self.source.len()
    }

    /// Always false (a selector has at least one light).
    pub fn is_empty(&self) -> bool {
        self.source.is_empty()
    }

    /// Candidate probability `q(i)`.
    pub fn source_pmf(&self, i: usize) -> f32 {
        self.source.pmf(i)
    }

    /// Selects up to `K` lights. `target(i)` returns `(p̂(i), value_i)`; `emit` receives each
    /// survivor (none when every candidate had `p̂ = 0`). `target` is called once per candidate
    /// (`M` times when shared, `K·M` for independent reservoirs, `n` with `candidates = 0`).
    /// 32-bit words drawn per candidate set of `M` with `S` survivors: `2M + S` when `M ≤`
    /// [`BUFFERED`], `2M + M·S` beyond (the `2M` are absent with `candidates = 0`); one set with
    /// `S = K` when shared, `K` sets with `S = 1` otherwise.
    pub fn select<T: Copy>(
        &self,
        params: &RisParams,
        rng: &mut Rng,
        mut target: impl FnMut(usize) -> (f32, T),
        mut emit: impl FnMut(Selected<T>),
    ) {
        let k = params.survivors.clamp(1, MAX_SURVIVORS) as usize;
        let shared = params.shared_candidates || params.candidates == 0;
        let (rounds, per_round) = if shared { (1, k) } else { (k, 1) };
        let m = if params.candidates == 0 { self.source.len() } else { params.candidates as usize };
        for _ in 0..rounds {
            if m <= BUFFERED {
                self.buffered(params.candidates, per_round, k, rng, &mut target, &mut emit);
                continue;
            }
            let mut res: [Pick<T>; MAX_SURVIVORS as usize] = [None; MAX_SURVIVORS as usize];
            let slots = &mut res[..per_round];
            let w_sum = self.stream(params.candidates, slots, rng, &mut target);
            for &(index, p_hat, value) in slots.iter().flatten() {
                let weight = (w_sum / (m as f64 * p_hat as f64) / k as f64) as f32;
                emit(Selected { index, weight, value });
            }
        }
    }

    /// Candidate `j` of a set: the light, and `q` (1/n when every light is a candidate).
    #[inline]
    fn candidate(&self, candidates: u32, j: usize, rng: &mut Rng) -> (usize, f64) {
        if candidates == 0 {
            (j, 1.0 / self.source.len() as f64)
        } else {
            let (i, q) = self.source.sample(rng);
            (i, q as f64)
        }
    }

    /// Small candidate sets (M ≤ [`BUFFERED`]): evaluate all, then draw each of the `slots`
    /// survivors from the prefix sums with one uniform (`2M + slots` words, `slots` if all lights).
    fn buffered<T: Copy>(
        &self,
        candidates: u32,
        slots: usize,
        k: usize,
        rng: &mut Rng,
        target: &mut impl FnMut(usize) -> (f32, T),
        emit: &mut impl FnMut(Selected<T>),
    ) {
        let m = if candidates == 0 { self.source.len() } else { candidates as usize };
        let mut set: [Option<(usize, f32, T)>; BUFFERED] = [None; BUFFERED];
        let mut prefix = [0.0f64; BUFFERED];
        let mut w_sum = 0.0f64;
        for j in 0..m {
            let (i, q) = self.candidate(candidates, j, rng);
            let (p_hat, value) = target(i);
            let p_hat = if p_hat.is_finite() && p_hat > 0.0 { p_hat } else { 0.0 };
            if p_hat > 0.0 && q > 0.0 {
                w_sum += p_hat as f64 / q;
                set[j] = Some((i, p_hat, value));
            }
            prefix[j] = w_sum;
        }
        for _ in 0..slots {
            let u = rng.next_f32() as f64 * w_sum;
            // first candidate whose prefix sum exceeds u (zero-weight candidates have no width)
            let j = prefix[..m].partition_point(|&c| c <= u).min(m - 1);
            let Some((index, p_hat, value)) = (0..=j).rev().find_map(|t| set[t]).filter(|_| w_sum > 0.0) else {
                continue;
            };
            let weight = (w_sum / (m as f64 * p_hat as f64) / k as f64) as f32;
            emit(Selected { index, weight, value });
        }
    }

    /// Streams the candidates through the reservoirs `slots`; returns Σw.
    fn stream<T: Copy>(
        &self,
        candidates: u32,
        slots: &mut [Pick<T>],
        rng: &mut Rng,
        target: &mut impl FnMut(usize) -> (f32, T),
    ) -> f64 {
        let m = if candidates == 0 { self.source.len() } else { candidates as usize };
        let mut w_sum = 0.0f64;
        for j in 0..m {
            let (i, q) = self.candidate(candidates, j, rng);
            let (p_hat, value) = target(i);
            let p_hat = if p_hat.is_finite() && p_hat > 0.0 { p_hat } else { 0.0 };
            let w = if p_hat > 0.0 && q > 0.0 { p_hat as f64 / q } else { 0.0 };
            w_sum += w;
            for s in slots.iter_mut() {
                // keep candidate j with probability w_j / Σ_{≤j} w (weighted reservoir sampling)
                let u = rng.next_f32() as f64;
                if w > 0.0 && u * w_sum < w {
                    *s = Some((i, p_hat, value));
                }
            }
        }
        w_sum
    }
}
