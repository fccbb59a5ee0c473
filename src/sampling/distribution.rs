//! Piecewise-constant discrete distribution (light selection by power).
//!
//! Invariants: `pmf` sums to 1 over all entries; entries with zero weight are never sampled.
//! `sample` is a pure function of `u`: the guide table (below) only narrows the search for the
//! first cdf entry above `u`, whose answer is unique, so it returns what a binary search over the
//! whole cdf returns, bit for bit.
//!
//! The guide table (the cutpoint method, Chen & Asau 1974): for `m` buckets, `guide[b]` is the
//! number of cdf entries ≤ `b/m`; a `u` in `[b/m, (b+1)/m)` has its answer between `guide[b]`
//! and `guide[b+1]`, a few entries apart, so a draw from a large distribution (an environment
//! map's 512k cells) touches two or three cache lines instead of the ~19 of a binary search.

/// A discrete distribution over `0..n` proportional to non-negative weights.
#[derive(Clone, Debug, Default)]
pub struct Distribution1D {
    cdf: Vec<f32>,
    pmf: Vec<f32>,
    /// `guide[b]`: the number of cdf entries ≤ `bucket_start(b)`, b < m; empty for small
    /// distributions (searched whole).
    guide: Vec<u32>,
}

/// Distributions with fewer entries are searched without a guide table.
const GUIDE_MIN: usize = 64;

/// The lower end `b/m` of guide bucket `b` (one expression for building and for lookups).
#[inline(always)]
fn bucket_start(b: usize, m: usize) -> f32 {
    b as f32 / m as f32
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
        let n = cdf.len();
        let guide = if n < GUIDE_MIN || n >= u32::MAX as usize {
            Vec::new()
        } else {
            // one pass: the counts are non-decreasing in b
            let mut k = 0usize;
            (0..n)
                .map(|b| {
                    let t = bucket_start(b, n);
                    while k < n && cdf[k] <= t {
                        k += 1;
                    }
                    k as u32
                })
                .collect()
        };
        Some(Distribution1D { cdf, pmf, guide })
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
        let i = self.count_at_most(u).min(self.cdf.len() - 1);
        // skip zero-probability cells that share the cdf value
        let i = (i..self.pmf.len()).find(|&j| self.pmf[j] > 0.0).unwrap_or(i);
        let lo = if i == 0 { 0.0 } else { self.cdf[i - 1] };
        let p = self.pmf[i];
        let ur = if p > 0.0 { ((u - lo) / p).clamp(0.0, 0.999_999_94) } else { 0.0 };
        (i, p, ur)
    }

    /// The number of cdf entries ≤ `u` (the cdf is non-decreasing, so the answer is unique):
    /// searched between two guide entries when there is a table.
    #[inline]
    fn count_at_most(&self, u: f32) -> usize {
        let m = self.guide.len();
        if m == 0 || !(u >= 0.0) {
            return self.cdf.partition_point(|&c| c <= u);
        }
        // the bucket b with bucket_start(b) ≤ u < bucket_start(b + 1), whatever the rounding of u·m
        let mut b = ((u * m as f32) as usize).min(m - 1);
        while b > 0 && bucket_start(b, m) > u {
            b -= 1;
        }
        while b + 1 < m && bucket_start(b + 1, m) <= u {
            b += 1;
        }
        // every entry below lo is ≤ bucket_start(b) ≤ u; every entry from hi on is
        // > bucket_start(b + 1) > u (or hi is the end)
        let lo = self.guide[b] as usize;
        let hi = if b + 1 < m { self.guide[b + 1] as usize } else { self.cdf.len() };
        lo + self.cdf[lo..hi].partition_point(|&c| c <= u)
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

    /// With a guide table, `sample` gives what a binary search over the whole cdf gives, for
    /// every u on a fine lattice, at bucket ends and at the cdf values themselves, on weights
    /// with zero runs, huge and tiny entries (ties and flat stretches of the f32 cdf).
    #[test]
    fn guide_table_search_is_the_binary_search() {
        let mut s = 0x2545_f491_4f6c_dd1du64;
        let mut rnd = move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 40) as f32 / (1u64 << 24) as f32
        };
        for n in [64usize, 100, 1000, 4099, 100_000] {
            let w: Vec<f32> = (0..n)
                .map(|i| match i % 7 {
                    0 | 1 => 0.0,
                    2 => 1e6 * rnd(),
                    3 => 1e-9 * rnd(),
                    _ => rnd(),
                })
                .collect();
            let d = Distribution1D::new(&w).unwrap();
            assert_eq!(d.guide.len(), n);
            let mut us: Vec<f32> = (0..200_000).map(|k| k as f32 / 200_000.0).collect();
            us.extend((0..=n).map(|b| bucket_start(b, n)));
            us.extend((0..=n).flat_map(|b| {
                let t = bucket_start(b, n);
                [f32::from_bits(t.to_bits().saturating_sub(1)), f32::from_bits(t.to_bits() + 1)]
            }));
            us.extend(d.cdf.iter().flat_map(|&c| [c, f32::from_bits(c.to_bits() + 1), f32::from_bits(c.to_bits().saturating_sub(1))]));
            us.extend([0.0, 0.999_999_94, 1.0, -0.0]);
            for u in us {
                let whole = d.cdf.partition_point(|&c| c <= u);
                assert_eq!(d.count_at_most(u), whole, "n {n}, u {u:e}");
            }
        }
    }
}
