//! Piecewise-constant discrete distributions: [`Distribution1D`] (light selection by power) and
//! [`Distribution2D`] (a marginal over rows, then the conditional within the row: the
//! environment map's cells).
//!
//! Invariants: `pmf` sums to 1 over all entries; entries with zero weight are never sampled. Each
//! entry keeps its cdf and its pmf side by side, so a draw reads one cache line for both.

/// One entry of a table: the cdf at its end and its probability.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Entry {
    cdf: f32,
    pmf: f32,
}

/// The entries of `weights` (normalised in `f64`, the last cdf set to 1) appended to `out`;
/// `None` (nothing appended) if the total is not positive and finite.
fn push_table(weights: &[f32], out: &mut Vec<Entry>) -> Option<()> {
    let total: f64 = weights.iter().map(|&w| w.max(0.0) as f64).sum();
    if !(total > 0.0 && total.is_finite()) {
        return None;
    }
    let start = out.len();
    let mut acc = 0.0f64;
    for &w in weights {
        let p = w.max(0.0) as f64 / total;
        acc += p;
        out.push(Entry { cdf: acc as f32, pmf: p as f32 });
    }
    if out.len() > start {
        out.last_mut().unwrap().cdf = 1.0;
    }
    Some(())
}

/// Samples the table `t` (not empty): (index, pmf, u remapped to [0,1) inside the chosen entry).
#[inline]
fn sample_table(t: &[Entry], u: f32) -> (usize, f32, f32) {
    let i = t.partition_point(|e| e.cdf <= u).min(t.len() - 1);
    finish_draw(i, t.len(), |k| t[k], u)
}

/// The draw of `u` from the table of `n` entries `at(0..n)` whose first entry with a cdf above
/// `u` is `i`: zero-probability entries that share the cdf value skipped, then (index, pmf, u
/// remapped to [0,1) inside the entry).
#[inline(always)]
fn finish_draw(i: usize, n: usize, at: impl Fn(usize) -> Entry, u: f32) -> (usize, f32, f32) {
    let i = (i..n).find(|&j| at(j).pmf > 0.0).unwrap_or(i);
    let lo = if i == 0 { 0.0 } else { at(i - 1).cdf };
    let p = at(i).pmf;
    let ur = if p > 0.0 { ((u - lo) / p).clamp(0.0, 0.999_999_94) } else { 0.0 };
    (i, p, ur)
}

/// Entries per [`Block`]: one cache line.
const BLOCK: usize = 8;

/// `BLOCK` consecutive entries of a row, aligned to a cache line (padding past the row's end:
/// cdf +∞, pmf 0).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
struct Block([Entry; BLOCK]);

/// A discrete distribution over `0..n` proportional to non-negative weights.
#[derive(Clone, Debug, Default)]
pub struct Distribution1D {
    table: Vec<Entry>,
}

impl Distribution1D {
    /// Builds from weights; `None` if the total is not positive and finite.
    pub fn new(weights: &[f32]) -> Option<Self> {
        let mut table = Vec::with_capacity(weights.len());
        push_table(weights, &mut table)?;
        Some(Distribution1D { table })
    }

    /// Number of entries.
    pub fn len(&self) -> usize {
        self.table.len()
    }

    /// True when there are no entries.
    pub fn is_empty(&self) -> bool {
        self.table.is_empty()
    }

    /// Samples an index; returns (index, pmf, u remapped to [0,1) inside the chosen cell).
    #[inline]
    pub fn sample(&self, u: f32) -> (usize, f32, f32) {
        sample_table(&self.table, u)
    }

    /// Probability of index `i`.
    #[inline]
    pub fn pmf(&self, i: usize) -> f32 {
        self.table.get(i).map_or(0.0, |e| e.pmf)
    }
}

/// A discrete distribution over the cells `(i, j)` of a `width × height` grid proportional to
/// non-negative weights (row-major, `j·width + i`): row `j` is drawn from the marginal (the rows'
/// sums), then column `i` from row `j`'s conditional (pbrt's `PiecewiseConstant2D`, discrete).
/// The pmf of a cell is `marginal(j) · conditional(i | j)`, the same product for the sampler
/// and for [`Distribution2D::pmf`].
///
/// Layout (the draw is bound by cache misses, not arithmetic): the marginal is small; each row's
/// conditional is stored in cache-line [`Block`]s of `BLOCK` entries, and searched through its
/// `coarse` cdfs (the cdf at each block's end: `height × width/BLOCK` floats, which stay cached)
/// and then inside one block: one line of the big table per draw, the same index as a binary
/// search of the whole row.
#[derive(Clone, Debug, Default)]
pub struct Distribution2D {
    width: usize,
    /// Blocks per row, `⌈width/BLOCK⌉`.
    row_blocks: usize,
    marginal: Distribution1D,
    /// Each row's cdf at the end of each of its blocks, row after row.
    coarse: Vec<f32>,
    /// Each row's conditional table in blocks, row after row (a row of zero weight: zero pmfs,
    /// never drawn).
    blocks: Vec<Block>,
}

impl Distribution2D {
    /// Builds from `weights` (`width × height`, row-major); `None` if the total is not positive
    /// and finite or the length is not a multiple of `width` (> 0).
    pub fn new(weights: &[f32], width: usize) -> Option<Self> {
        if width == 0 || !weights.len().is_multiple_of(width) {
            return None;
        }
        let rows: Vec<f32> =
            weights.chunks(width).map(|r| r.iter().map(|&w| w.max(0.0) as f64).sum::<f64>() as f32).collect();
        let marginal = Distribution1D::new(&rows)?;
        let row_blocks = width.div_ceil(BLOCK);
        let pad = Entry { cdf: f32::INFINITY, pmf: 0.0 };
        let (mut coarse, mut blocks) = (Vec::new(), Vec::new());
        let mut row = Vec::with_capacity(width);
        for r in weights.chunks(width) {
            row.clear();
            if push_table(r, &mut row).is_none() {
                row.extend((1..=width).map(|i| Entry { cdf: i as f32 / width as f32, pmf: 0.0 }));
            }
            for c in row.chunks(BLOCK) {
                let mut b = Block([pad; BLOCK]);
                b.0[..c.len()].copy_from_slice(c);
                coarse.push(c[c.len() - 1].cdf);
                blocks.push(b);
            }
        }
        Some(Distribution2D { width, row_blocks, marginal, coarse, blocks })
    }

    /// True when there are no cells.
    pub fn is_empty(&self) -> bool {
        self.blocks.is_empty()
    }

    /// Entry `i` of row `j`'s conditional table (`i < width`).
    #[inline(always)]
    fn entry(&self, i: usize, j: usize) -> Entry {
        self.blocks[j * self.row_blocks + i / BLOCK].0[i % BLOCK]
    }

    /// Samples a cell: `u[1]` picks the row, `u[0]` the column; returns `((i, j), pmf, u
    /// remapped to [0,1)² inside the cell)` (`[column, row]`).
    #[inline]
    pub fn sample(&self, u: [f32; 2]) -> ((usize, usize), f32, [f32; 2]) {
        let (j, pj, vr) = self.marginal.sample(u[1]);
        let (u, nb) = (u[0], self.row_blocks);
        let b = self.coarse[j * nb..(j + 1) * nb].partition_point(|&c| c <= u).min(nb - 1);
        let in_block = self.blocks[j * nb + b].0.iter().filter(|e| e.cdf <= u).count();
        let i = (b * BLOCK + in_block).min(self.width - 1);
        let (i, pi, ur) = finish_draw(i, self.width, |k| self.entry(k, j), u);
        ((i, j), pj * pi, [ur, vr])
    }

    /// Probability of the cell `(i, j)`.
    #[inline]
    pub fn pmf(&self, i: usize, j: usize) -> f32 {
        if i >= self.width {
            return 0.0;
        }
        if j >= self.marginal.len() {
            return 0.0;
        }
        self.marginal.pmf(j) * self.entry(i, j).pmf
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

    /// The 2D draw's frequencies on a stratified grid of `u` match `pmf`, which sums to 1 and is
    /// the pmf the draw reports; zero cells and a zero row are never drawn.
    #[test]
    fn two_d_frequencies_match_the_pmf() {
        #[rustfmt::skip]
        let w = [1.0, 0.0, 3.0,
                 0.0, 0.0, 0.0,
                 2.0, 5.0, 0.5,
                 0.0, 0.25, 0.0];
        let d = Distribution2D::new(&w, 3).unwrap();
        let total: f32 = w.iter().sum();
        let mut sum = 0.0;
        for (k, &wk) in w.iter().enumerate() {
            let p = d.pmf(k % 3, k / 3);
            assert!((p - wk / total).abs() < 1e-6, "cell {k}: pmf {p}");
            sum += p;
        }
        assert!((sum - 1.0).abs() < 1e-6);
        let n = 400;
        let mut counts = [0usize; 12];
        for a in 0..n {
            for b in 0..n {
                let u = [(a as f32 + 0.5) / n as f32, (b as f32 + 0.5) / n as f32];
                let ((i, j), p, r) = d.sample(u);
                assert_eq!(p, d.pmf(i, j));
                assert!(r.iter().all(|&x| (0.0..1.0).contains(&x)));
                counts[j * 3 + i] += 1;
            }
        }
        for (k, &c) in counts.iter().enumerate() {
            let f = c as f32 / (n * n) as f32;
            assert!((f - d.pmf(k % 3, k / 3)).abs() < 5e-3, "cell {k}: {f} against {}", d.pmf(k % 3, k / 3));
        }
        assert_eq!(counts[1] + counts[3] + counts[4] + counts[5] + counts[9] + counts[11], 0);
        assert!(Distribution2D::new(&[0.0; 6], 3).is_none());
        assert!(Distribution2D::new(&[1.0; 5], 3).is_none());
    }

    /// The blocked search draws the same cell as a binary search of the row's whole table, on
    /// rows that are not a whole number of blocks, with runs of zero weights.
    #[test]
    fn two_d_blocked_search_is_the_binary_search() {
        let (w, h) = (37, 5);
        let weights: Vec<f32> = (0..w * h)
            .map(|k| if k % 7 < 3 || (k / w == 2 && k % w > 20) { 0.0 } else { ((k * 2654435761usize) % 1000) as f32 })
            .collect();
        let d = Distribution2D::new(&weights, w).unwrap();
        let n = 20_000;
        for k in 0..n {
            let u = [(k as f32 + 0.5) / n as f32, ((k * 7919) % n) as f32 / n as f32];
            let ((i, j), p, r) = d.sample(u);
            let mut row = Vec::new();
            push_table(&weights[j * w..(j + 1) * w], &mut row).unwrap();
            let (i2, p2, r2) = sample_table(&row, u[0]);
            assert_eq!((i, p, r[0]), (i2, d.marginal.pmf(j) * p2, r2), "u = {u:?}");
        }
    }
}
