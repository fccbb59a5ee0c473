//! A scrambled Sobol prefix for the camera streams (randomized quasi-Monte Carlo, Owen 1997):
//! the first [`SLOTS`] two-dimensional draws of a pixel's camera path at sample `i` are the `i`-th
//! point of a 14-dimensional Sobol sequence (Joe and Kuo's direction numbers) scrambled for that
//! pixel, so that across passes a pixel's jitter, its first light samples and its first bounces
//! are stratified rather than independent.
//!
//! A slot is one `Rng::next_2d` call and takes the next two dimensions. One-dimensional draws
//! (`next_f32`, `next_u32`: a light pick, a lobe, roulette) come from the PCG stream throughout,
//! so on diffuse paths the slots line up with the same 2-D decisions in every pass: the jitter,
//! then each vertex's point on a light and its BSDF direction. (A Dirac vertex draws no light
//! sample and a forecast table several, so on such paths a slot serves different decisions in
//! different passes: less stratification, no bias.) Each dimension of each pixel is
//! Owen-scrambled (hash-based, pbrt-v4's `FastOwenScrambler`) and then XORed with its own 32-bit
//! hash (a random digital shift). Scrambling keeps every realization a (t, s)-sequence, so a pixel's own passes
//! converge. (A padded sampler, independent 2-D sequences per slot with a hashed index shuffle,
//! failed the suite's per-pixel z-tests at 4,096 passes: its slots' pairings were too regular;
//! `results/2026-12-06-sobol-prefix.md`.)
//!
//! Invariants: over pixels, the shift makes every coordinate as uniform as the hash of its seed,
//! whatever the point, and the dimensions' seeds are separate hashes of the pixel key, so for
//! any one sample the draws are uniform and independent to the quality of that hashing, as PCG's
//! keyed streams are: an estimator stays unbiased pass by pass. (The keys have 32 bits: two
//! pixels of a large image may share one, correlating their errors, not biasing either.) Only the
//! joint distribution *across* passes changes. Randomness stays a pure function of
//! (seed, pass, pixel).

/// The camera streams' sampler (`--sampler`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
// The values are described in `--sampler`'s help: a value's doc comment would be its help text,
// which turns `render --help` into its long format.
#[allow(missing_docs)]
pub enum SamplerKind {
    // PCG alone: every pass independent, so the film's variance layer is exact (the default).
    #[default]
    Independent,
    // A scrambled Sobol prefix of [`SLOTS`] 2-D slots, then PCG (this module).
    Sobol,
}

/// 2-D slots of a camera stream's Sobol prefix: the jitter, then a light sample and a BSDF
/// direction at each of three vertices.
pub const SLOTS: u64 = 7;
/// The prefix word of a stream without a prefix, or whose prefix is spent (slot field 63).
pub const OFF: u64 = 63;
/// The sample index bits kept: each block of 2^26 passes is its own sequence, under its own
/// pixel keys (`Rng::qmc_key` keys them by `pass >> INDEX_BITS`).
pub const INDEX_BITS: u32 = 26;
const INDEX_MASK: u64 = (1 << INDEX_BITS) - 1;

/// The prefix word (`Rng`'s `q`) of pixel key `key` at sample `index`, at its first slot: the key
/// in the high 32 bits, the index in the next 26, the slot in the low 6.
#[inline]
pub fn prefix(key: u32, index: u64) -> u64 {
    ((key as u64) << 32) | ((index & INDEX_MASK) << 6)
}

/// True while prefix word `q` has a slot left.
#[inline]
pub fn has_slot(q: u64) -> bool {
    q & 63 < SLOTS
}

/// Prefix word `q` after its slot is drawn: the next slot, or [`OFF`] once the last is spent (a
/// spent prefix is no prefix, so equal streams compare equal).
#[inline]
pub fn advance(q: u64) -> u64 {
    if (q & 63) + 1 < SLOTS {
        q + 1
    } else {
        OFF
    }
}

/// The reversed-bit mixing of pbrt-v4's `FastOwenScrambler`: in the reversed domain each step
/// lets only lower bits change higher ones, so in the value domain a bit depends on those above.
#[inline]
fn mix(mut v: u32, seed: u32) -> u32 {
    v ^= v.wrapping_mul(0x3d20_adea);
    v = v.wrapping_add(seed);
    v = v.wrapping_mul((seed >> 16) | 1);
    v ^= v.wrapping_mul(0x0552_6c56);
    v ^= v.wrapping_mul(0x53a2_2864);
    v
}

/// Owen scrambling of a 32-bit fixed-point value (hash-based nested uniform scrambling: a bit
/// flips with a hash of the bits above it and the seed).
#[inline]
fn owen(v: u32, seed: u32) -> u32 {
    mix(v.reverse_bits(), seed).reverse_bits()
}

/// Sobol's dimensions 2–14 (Joe and Kuo's `new-joe-kuo-6.21201`, d = 2..14): the degree `s` of
/// the primitive polynomial, its inner coefficients `a`, and the initial `m_1..m_s`. Dimension 1
/// is the van der Corput sequence.
const JOE_KUO: [(u32, u32, [u32; 6]); DIMS - 1] = [
    (1, 0, [1, 0, 0, 0, 0, 0]),
    (2, 1, [1, 3, 0, 0, 0, 0]),
    (3, 1, [1, 3, 1, 0, 0, 0]),
    (3, 2, [1, 1, 1, 0, 0, 0]),
    (4, 1, [1, 1, 3, 3, 0, 0]),
    (4, 4, [1, 3, 5, 13, 0, 0]),
    (5, 2, [1, 1, 5, 5, 17, 0]),
    (5, 4, [1, 1, 5, 5, 5, 0]),
    (5, 7, [1, 1, 7, 11, 19, 0]),
    (5, 11, [1, 1, 5, 1, 1, 0]),
    (5, 13, [1, 1, 1, 3, 11, 0]),
    (5, 14, [1, 3, 5, 5, 31, 0]),
    (6, 1, [1, 3, 3, 9, 7, 49]),
];

/// Dimensions of the prefix: two per slot.
const DIMS: usize = 2 * SLOTS as usize;

/// The direction numbers `V[d][k]` (bit `k` of the index flips `V[d][k]`), by Joe and Kuo's
/// recurrence `V_k = V_{k-s} ^ (V_{k-s} >> s) ^ (a_j-weighted V_{k-j}, j < s)`.
static DIRECTIONS: [[u32; 32]; DIMS] = directions();

const fn directions() -> [[u32; 32]; DIMS] {
    let mut v = [[0u32; 32]; DIMS];
    let mut k = 0;
    while k < 32 {
        v[0][k] = 1 << (31 - k);
        k += 1;
    }
    let mut d = 1;
    while d < DIMS {
        let (s, a, m) = JOE_KUO[d - 1];
        let s = s as usize;
        let mut k = 0;
        while k < 32 {
            v[d][k] = if k < s {
                m[k] << (31 - k)
            } else {
                let mut x = v[d][k - s] ^ (v[d][k - s] >> s);
                let mut j = 1;
                while j < s {
                    if (a >> (s - 1 - j)) & 1 == 1 {
                        x ^= v[d][k - j];
                    }
                    j += 1;
                }
                x
            };
            k += 1;
        }
        d += 1;
    }
    v
}

/// Sobol dimension `d` (0-based) at index `i`: the XOR of the direction numbers of `i`'s set bits.
#[inline]
fn sobol(d: usize, mut i: u32) -> u32 {
    let mut x = 0;
    while i != 0 {
        x ^= DIRECTIONS[d][i.trailing_zeros() as usize];
        i &= i - 1;
    }
    x
}

/// A 32-bit integer hash (lowbias32, Wellons).
#[inline]
fn hash32(mut x: u32) -> u32 {
    x ^= x >> 16;
    x = x.wrapping_mul(0x7feb_352d);
    x ^= x >> 15;
    x = x.wrapping_mul(0x846c_a68b);
    x ^ (x >> 16)
}

/// Dimension `d` of the point in `q` (`Rng`'s prefix word: pixel key, sample index), scrambled:
/// Owen-scrambled, then XORed with a shift, both seeded by a hash of the pixel key and `d`.
#[inline]
fn coordinate(q: u64, d: usize) -> u32 {
    let (index, key) = (((q >> 6) & INDEX_MASK) as u32, (q >> 32) as u32);
    let k = key ^ (d as u32 + 1).wrapping_mul(0x9e37_79b9);
    owen(sobol(d, index), hash32(k ^ 0xa511_e9b3)) ^ hash32(k ^ 0x63d8_3595)
}

/// The 2-D slot in `q`: dimensions `2·slot` and `2·slot + 1` of the pixel's scrambled point.
#[inline]
pub fn sample_2d(q: u64) -> [u32; 2] {
    let d = 2 * (q & 63) as usize;
    [coordinate(q, d), coordinate(q, d + 1)]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::rng::Rng;
    use crate::stats::chi2_test;

    /// The first `n` samples' slot-`slot` points of pixel key `key` from sample `first` on.
    fn points(key: u32, slot: usize, first: u64, n: u64) -> Vec<[f32; 2]> {
        (first..first + n)
            .map(|i| {
                let mut r = Rng::keyed(1, 2, i, key as u64).with_qmc(key, i);
                (0..slot).for_each(|_| {
                    let _ = r.next_2d();
                });
                r.next_2d()
            })
            .collect()
    }

    /// Every dimension's direction numbers are valid (`V_k = m_k · 2^(31-k)` with `m_k` odd and
    /// below `2^(k+1)`: its lowest set bit is bit `31 - k`, so each generator matrix is
    /// invertible and every dimension a (0, 1)-sequence), and dimension 1 is the Pascal matrix (`V_k = V_{k-1} ^
    /// (V_{k-1} >> 1)`).
    #[test]
    fn direction_numbers_are_valid() {
        for (d, v) in DIRECTIONS.iter().enumerate() {
            assert!(v.iter().enumerate().all(|(k, &x)| x.trailing_zeros() == 31 - k as u32), "dimension {d}: {v:x?}");
        }
        assert!((1..32).all(|k| DIRECTIONS[1][k] == DIRECTIONS[1][k - 1] ^ (DIRECTIONS[1][k - 1] >> 1)));
    }

    /// Each aligned block of 2^m samples is stratified: every dimension puts one point in each
    /// of 2^m intervals, and dimensions 0 and 1 (the jitter) form a (0, m, 2)-net, one point in
    /// each 2^a × 2^b cell (a + b = m). Scrambling keeps both for every pixel key, which is
    /// what makes each pixel's own sequence converge.
    #[test]
    fn every_aligned_block_of_2_to_the_m_samples_is_stratified() {
        let m = 8u32;
        for (key, block) in [(0u32, 0u64), (0xdead_beef, 0), (7, 5)] {
            for slot in 0..SLOTS as usize {
                let pts = points(key, slot, block << m, 1 << m);
                for c in 0..2 {
                    let mut seen = vec![0u32; 1 << m];
                    pts.iter().for_each(|p| seen[(p[c] * (1u32 << m) as f32) as usize] += 1);
                    assert!(seen.iter().all(|&n| n == 1), "key {key:#x} block {block} dimension {}", 2 * slot + c);
                }
            }
            let pts = points(key, 0, block << m, 1 << m);
            for a in 0..=m {
                let b = m - a;
                let mut seen = vec![0u32; 1 << m];
                for &[x, y] in &pts {
                    let (i, j) = ((x * (1u32 << a) as f32) as usize, (y * (1u32 << b) as f32) as usize);
                    seen[(i << b) | j] += 1;
                }
                assert!(seen.iter().all(|&c| c == 1), "key {key:#x} block {block}: 2^{a} × 2^{b}");
            }
        }
    }

    /// Over pixels (keys), one sample's point is uniform in the square and independent of the
    /// next slot's (χ² on 8 × 8 cells at α = 1e-4): the prefix is unbiased pass by pass.
    #[test]
    fn one_sample_is_uniform_and_its_slots_independent_over_pixels() {
        let n = 1u32 << 16;
        for index in [0u64, 37, 1 << 20] {
            let (mut own, mut pair) = (vec![0.0; 64], vec![0.0; 64]);
            for key in 0..n {
                let mut r = Rng::keyed(9, 1, index, key as u64).with_qmc(Rng::qmc_key(11, 0, key as u64), index);
                let ([x0, y0], [x1, _]) = (r.next_2d(), r.next_2d());
                let cell = |u: f32, v: f32| (u * 8.0) as usize * 8 + (v * 8.0) as usize;
                own[cell(x0, y0)] += 1.0;
                pair[cell(x0, x1)] += 1.0;
            }
            let expected = vec![n as f64 / 64.0; 64];
            for (what, obs) in [("a slot", &own), ("two slots", &pair)] {
                let r = chi2_test(obs, &expected, 5.0);
                assert!(r.passes(1e-4), "sample {index}, {what}: {r:?}");
            }
        }
    }

    /// The estimate of a disk's area fraction (a discontinuous integrand, like a shadow edge)
    /// from 256 samples: Owen-scrambled nets have variance O(N^-3/2) against Monte Carlo's
    /// σ²/N, i.e. about 1/√N = 1/16 of it here up to a constant. Asserting ≤ 1/4 leaves that
    /// constant 4× room; an independent stream (no prefix) gives ≈ 1 and fails.
    #[test]
    fn the_prefix_cuts_the_variance_of_a_shadow_edge() {
        let (n, pixels) = (256u64, 400u32);
        let f = |[x, y]: [f32; 2]| f64::from(u8::from((x - 0.4).powi(2) + (y - 0.55).powi(2) < 0.09));
        let p = std::f64::consts::PI * 0.09;
        let mc = p * (1.0 - p) / n as f64;
        let var = (0..pixels)
            .map(|key| {
                let mean = points(Rng::qmc_key(3, 0, key as u64), 1, 0, n).into_iter().map(f).sum::<f64>() / n as f64;
                (mean - p).powi(2)
            })
            .sum::<f64>()
            / pixels as f64;
        eprintln!("variance {var:.3e}, Monte Carlo's {mc:.3e}: ratio {:.3}", var / mc);
        assert!(var < mc / 4.0, "ratio {}", var / mc);
    }

    /// The light pilot's passes (from 2^62 on) and the render's share their low index bits but
    /// not their pixel keys, so they never draw the same points.
    #[test]
    fn each_block_of_2_to_the_26_passes_has_its_own_keys() {
        for (pixel, pass) in [(0u64, 0u64), (9, 3), (4095, 77)] {
            let (a, b) = (Rng::qmc_key(5, pass, pixel), Rng::qmc_key(5, (1 << 62) + pass, pixel));
            assert_ne!(a, b);
            assert_ne!(points(a, 0, pass, 1), points(b, 0, pass, 1), "pixel {pixel} pass {pass}");
        }
        assert_eq!(Rng::qmc_key(5, 3, 9), Rng::qmc_key(5, (1 << 26) - 1, 9), "one block, one key");
    }

    /// A stream with a prefix draws its 1-D numbers from PCG and, once its slots are spent, its
    /// 2-D ones too, as a stream without a prefix would; without a prefix nothing changes.
    #[test]
    fn the_prefix_takes_the_2d_draws_then_pcg_follows() {
        let plain = Rng::keyed(4, 1, 9, 2);
        let (mut a, mut b) = (plain.clone(), plain.clone().with_qmc(77, 9));
        assert_eq!(a.next_f32(), b.next_f32());
        let slots: Vec<[f32; 2]> = (0..SLOTS).map(|_| b.next_2d()).collect();
        assert_eq!(slots[0], points(77, 0, 9, 1)[0]);
        assert_eq!(a, b, "a spent prefix is no prefix");
        assert_eq!(a.next_2d(), b.next_2d());
        assert_eq!(a.next_3d(), b.next_3d());
    }
}
