//! Walker/Vose alias table: O(n) construction, O(1) sampling of a discrete distribution
//! (Walker 1977; Vose 1991, "A linear algorithm for generating random numbers with a given
//! distribution"; pbrt-v4 `AliasTable`).
//!
//! Sampling takes two 32-bit words: the first picks a column uniformly (Lemire's multiply-shift),
//! the second is compared with the column's integer acceptance threshold `t ∈ [0, 2³²]`; on
//! rejection the column's alias is returned. The thresholds are quantised **before** the pmf is
//! computed, so `pmf(i)` is exactly the probability that `sample` returns `i` given uniform words
//! (up to the ≤ n/2³² non-uniformity of multiply-shift column choice and f32 rounding of the
//! stored value): the pmf an estimator divides by is the one it sampled from.
//!
//! Invariants: every entry with positive finite weight has `pmf > 0` (its own column keeps a
//! threshold ≥ 1, so weights down to any dynamic range stay reachable and unbiased); entries with
//! zero, negative or non-finite weight have `pmf = 0` and are never returned; Σ pmf = 1; no input
//! panics (all-zero/NaN/empty → `None`).

// `!(x > 0.0)`-style tests are deliberate: they are true for NaN (degenerate input is rejected).
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::rng::Rng;

/// 2³² as f64: the acceptance-threshold scale.
const SCALE: f64 = 4_294_967_296.0;

/// An alias table over `0..n`.
#[derive(Clone, Debug, PartialEq)]
pub struct AliasTable {
    /// Acceptance threshold of each column: return the column if `word < thresh` (`u64` so that
    /// 2³², "always accept", is representable).
    thresh: Vec<u64>,
    /// Entry returned when the column rejects.
    alias: Vec<u32>,
    /// Exact sampling probability of each entry (computed from the quantised thresholds).
    pmf: Vec<f32>,
}

/// Vose's alias construction on weights `p` (normalised here; zero, negative and non-finite
/// entries count as 0; at least one must be positive), its acceptance thresholds quantised to integers in
/// `[0, one]`: column `c` returns `c` for `one·t_c` of its words and `alias_c` for the rest.
/// A positive entry keeps a threshold ≥ 1 in its own column (reachable whatever its size); a
/// zero entry has threshold 0 and aliases a positive entry (never returned). Shared by
/// [`AliasTable`] (`one` = 2³²) and the 512-bin `cf::direction_table` (2¹⁵).
pub fn quantised_columns(p: &[f64], one: u64) -> (Vec<u64>, Vec<u32>) {
    let n = p.len();
    let pos = |x: f64| if x.is_finite() && x > 0.0 { x } else { 0.0 };
    let total: f64 = p.iter().map(|&x| pos(x)).sum();
    // scaled probabilities n·p_i; columns below 1 are filled from columns above 1
    let mut scaled: Vec<f64> = p.iter().map(|&x| pos(x) * n as f64 / total).collect();
    let mut alias: Vec<u32> = (0..n as u32).collect();
    let (mut small, mut large): (Vec<u32>, Vec<u32>) = (0..n as u32).partition(|&i| scaled[i as usize] < 1.0);
    let mut prob = vec![1.0f64; n];
    while let (Some(&s), Some(&l)) = (small.last(), large.last()) {
        small.pop();
        prob[s as usize] = scaled[s as usize];
        alias[s as usize] = l;
        scaled[l as usize] -= 1.0 - scaled[s as usize];
        if scaled[l as usize] < 1.0 {
            large.pop();
            small.push(l);
        }
    }
    // leftovers (rounding) are full columns: prob 1, alias self (already initialised)
    for i in small.into_iter().chain(large) {
        prob[i as usize] = 1.0;
        alias[i as usize] = i;
    }
    let heaviest = (0..n).max_by(|&a, &b| pos(p[a]).total_cmp(&pos(p[b]))).unwrap_or(0) as u32;
    let mut thresh = Vec::with_capacity(n);
    for i in 0..n {
        let t = if !(pos(p[i]) > 0.0) {
            // a zero-weight column always rejects (to a positive entry, even after rounding)
            if alias[i] as usize == i {
                alias[i] = heaviest;
            }
            0
        } else if alias[i] as usize == i {
            one
        } else {
            // reachability floor: a positive entry keeps at least one accepting word
            ((prob[i] * one as f64).round().clamp(0.0, one as f64) as u64).max(1)
        };
        thresh.push(t);
    }
    (thresh, alias)
}

impl AliasTable {
    /// Builds the table ∝ `weights` (zero, negative and non-finite entries get probability 0).
    /// `None` when no weight is positive, the total overflows, or there are more than `u32::MAX`
    /// entries.
    pub fn new(weights: &[f32]) -> Option<Self> {
        let n = weights.len();
        if n == 0 || n > u32::MAX as usize {
            return None;
        }
        let w = |x: f32| if x.is_finite() && x > 0.0 { x as f64 } else { 0.0 };
        let total: f64 = weights.iter().map(|&x| w(x)).sum();
        if !(total > 0.0) || !total.is_finite() {
            return None;
        }
        let p: Vec<f64> = weights.iter().map(|&x| w(x)).collect();
        let (thresh, alias) = quantised_columns(&p, SCALE as u64);
        let mut pmf64 = vec![0.0f64; n];
        for i in 0..n {
            let acc = thresh[i] as f64 / SCALE;
            pmf64[i] += acc / n as f64;
            pmf64[alias[i] as usize] += (1.0 - acc) / n as f64;
        }
        let pmf = pmf64.iter().map(|&p| p as f32).collect();
        Some(AliasTable { thresh, alias, pmf })
    }

    /// Number of entries.
    #[inline]
    pub fn len(&self) -> usize {
        self.pmf.len()
    }

    /// Always false (a table has at least one entry).
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.pmf.is_empty()
    }

    /// Probability that [`Self::sample`] returns `i` (0 outside `0..n`).
    #[inline]
    pub fn pmf(&self, i: usize) -> f32 {
        self.pmf.get(i).copied().unwrap_or(0.0)
    }

    /// The entry selected by two uniform 32-bit words: `col_word` picks the column
    /// (`⌊col_word·n / 2³²⌋`), `acc_word` accepts it when `acc_word < threshold`.
    #[inline]
    pub fn sample_words(&self, col_word: u32, acc_word: u32) -> usize {
        let c = ((col_word as u64 * self.thresh.len() as u64) >> 32) as usize;
        if (acc_word as u64) < self.thresh[c] {
            c
        } else {
            self.alias[c] as usize
        }
    }

    /// Draws one entry with two words from `rng`; returns `(index, pmf(index))`.
    #[inline]
    pub fn sample(&self, rng: &mut Rng) -> (usize, f32) {
        let (a, b) = (rng.next_u32(), rng.next_u32());
        let i = self.sample_words(a, b);
        (i, self.pmf[i])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn degenerate_inputs() {
        assert!(AliasTable::new(&[]).is_none());
        assert!(AliasTable::new(&[0.0, 0.0]).is_none());
        assert!(AliasTable::new(&[f32::NAN, -1.0, f32::INFINITY]).is_none());
        let one = AliasTable::new(&[3.0]).unwrap();
        assert_eq!(one.pmf(0), 1.0);
        for w in [0, 1, u32::MAX] {
            assert_eq!(one.sample_words(w, u32::MAX), 0);
        }
        // Huge dynamic range: the tiny entry stays reachable, with its exact (floored) pmf.
        let t = AliasTable::new(&[1e30, 1e-30, 1.0, 0.0]).unwrap();
        assert!(t.pmf(1) > 0.0 && t.pmf(3) == 0.0);
        let total: f64 = (0..4).map(|i| t.pmf(i) as f64).sum();
        assert!((total - 1.0).abs() < 1e-6);
        let col1 = 1u32 << 30; // column 1 of 4
        assert_eq!(t.sample_words(col1, 0), 1);
        assert_ne!(t.sample_words(col1, 1), 1);
        // The zero entry is never returned, whatever the words.
        for c in 0..64u32 {
            for a in [0, 1, u32::MAX / 2, u32::MAX] {
                assert_ne!(t.sample_words(c << 26, a), 3);
            }
        }
    }

    #[test]
    fn pmf_is_proportional_to_weights() {
        let w = [0.5f32, 2.0, 0.0, 7.5, 1.0, 1e-3];
        let t = AliasTable::new(&w).unwrap();
        let s: f32 = w.iter().sum();
        for (i, &x) in w.iter().enumerate() {
            assert!((t.pmf(i) - x / s).abs() < 1e-6, "{i}: {} vs {}", t.pmf(i), x / s);
        }
    }
}
