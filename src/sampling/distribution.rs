//! Piecewise-constant discrete distribution (light selection by power).
//!
//! Invariants: `pmf` sums to 1 over all entries; entries with zero weight are never sampled.

/// A discrete distribution over `0..n` proportional to non-negative weights.
#[derive(Clone, Debug, Default)]
pub struct Distribution1D {
    cdf: Vec<f32>,
    pmf: Vec<f32>,
}

impl Distribution1D {
    /// Builds from weights; `None` if the total is not positive and finite.
    pub fn new(weights: &[f32]) -> Option<Self> {
        let total: f64 = weights.iter().map(|&w| w.max(0.0) as f64).sum();
        if !(total > 0.0 && total.is_finite()) {
            return None;
        }
        let mut acc = 0.0f64;
        let mut cdf = Vec::with_capacity(weights.len());
        let mut pmf = Vec::with_capacity(weights.len());
        for &w in weights {
            let p = w.max(0.0) as f64 / total;
            acc += p;
            pmf.push(p as f32);
            cdf.push(acc as f32);
        }
        if let Some(last) = cdf.last_mut() {
            *last = 1.0;
        }
        Some(Distribution1D { cdf, pmf })
    }

    /// Number of entries.
    pub fn len(&self) -> usize {
        self.pmf.len()
    }

    /// True when there are no entries.
    pub fn is_empty(&self) -> bool {
        self.pmf.is_empty()
    }

    /// Samples an index; returns (index, pmf, u remapped to [0,1) inside the chosen cell).
    #[inline]
    pub fn sample(&self, u: f32) -> (usize, f32, f32) {
        let i = self.cdf.partition_point(|&c| c <= u).min(self.cdf.len() - 1);
        // skip zero-probability cells that share the cdf value
        let i = (i..self.pmf.len()).find(|&j| self.pmf[j] > 0.0).unwrap_or(i);
        let lo = if i == 0 { 0.0 } else { self.cdf[i - 1] };
        let p = self.pmf[i];
        let ur = if p > 0.0 { ((u - lo) / p).clamp(0.0, 0.999_999_94) } else { 0.0 };
        (i, p, ur)
    }

    /// Probability of index `i`.
    #[inline]
    pub fn pmf(&self, i: usize) -> f32 {
        self.pmf.get(i).copied().unwrap_or(0.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sampling_frequencies_match_the_pmf() {
        let d = Distribution1D::new(&[1.0, 0.0, 3.0, 4.0]).unwrap();
        let mut counts = [0usize; 4];
        let n = 80_000;
        for k in 0..n {
            let u = (k as f32 + 0.5) / n as f32;
            counts[d.sample(u).0] += 1;
        }
        assert_eq!(counts[1], 0, "zero-weight entry sampled");
        for (i, &c) in counts.iter().enumerate() {
            assert!((c as f32 / n as f32 - d.pmf(i)).abs() < 1e-3);
        }
        assert!(Distribution1D::new(&[0.0, 0.0]).is_none());
        assert!(Distribution1D::new(&[f32::NAN]).is_none());
    }
}
