//! Counter-based random streams: every random number is a pure function of
//! (seed, stream, pass, index), so images never depend on thread count or scheduling
//! (pbrt-v4 / psychopath style).
//!
//! `Rng` is PCG32 (O'Neill 2014, XSH-RR 64/32). `Rng::keyed` hashes the key with SplitMix64
//! into a state and an odd increment (a distinct sequence per key). It implements
//! `rand::TryRng` so rand's adaptors work on it (they draw PCG words: `next_u32`).
//!
//! A camera stream may be led by a Sobol prefix (`Rng::with_qmc`, `sampling::qmc`,
//! `--sampler sobol`): its first `qmc::SLOTS` `next_2d` calls then return the pass's point of
//! the pixel's scrambled sequence, without touching the PCG state; every other draw is PCG's.

use super::qmc;

/// Named stream ids, so that preprocess and render randomness never overlap.
pub mod stream {
    /// Camera/eye paths of pixel samples.
    pub const CAMERA: u64 = 1;
    /// IWS point-light (VPL) particle paths.
    pub const VPL: u64 = 2;
    /// Caustic photon map particle paths.
    pub const PHOTON: u64 = 3;
    /// Caustic-forecast particle paths.
    pub const FORECAST: u64 = 4;
    /// Clustering (seeding, shuffles).
    pub const CLUSTER: u64 = 5;
    /// Tests and benchmarks.
    pub const MISC: u64 = 6;
    /// The extra camera rays of emission splitting (`render::PixelSampler`).
    pub const PIXEL_SPLIT: u64 = 7;
    /// The CF preprocess's caustic-share gather (`integrators::iws_cf::share`).
    pub const GUIDE: u64 = 8;
    /// `pt-cf`'s light paths connected to the camera (`integrators::pt_cf::light`).
    pub const LIGHT_PATHS: u64 = 9;
    /// The scrambling keys of the camera streams' Sobol prefixes (`sampling::qmc`).
    pub const CAMERA_QMC: u64 = 10;
}

/// A 32-bit word's top 24 bits as a uniform in [0, 1) (never 1.0).
#[inline]
fn to_f32(w: u32) -> f32 {
    (w >> 8) as f32 * (1.0 / 16_777_216.0)
}

#[inline]
fn splitmix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// PCG32 generator (equal states draw equal numbers), optionally led by a scrambled Sobol
/// prefix (`Rng::with_qmc`, `sampling::qmc`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Rng {
    state: u64,
    inc: u64,
    /// The Sobol prefix word (`qmc::prefix`: pixel key, sample index, next slot), or
    /// [`qmc::OFF`] when there is none or it is spent.
    q: u64,
}

impl Rng {
    const MUL: u64 = 6364136223846793005;

    /// A stream keyed by (seed, stream, pass, index).
    pub fn keyed(seed: u64, stream: u64, pass: u64, index: u64) -> Self {
        Self::indexed(Self::pass_key(seed, stream, pass), index)
    }

    /// The (seed, stream, pass) part of a key, hashed once for the many streams of a pass:
    /// `Rng::indexed(Rng::pass_key(s, t, p), i)` is `Rng::keyed(s, t, p, i)`.
    #[inline]
    pub fn pass_key(seed: u64, stream: u64, pass: u64) -> u64 {
        let h1 = splitmix64(seed ^ splitmix64(stream.wrapping_mul(0xA24B_AED4_963E_E407)));
        splitmix64(h1 ^ splitmix64(pass.wrapping_add(0x632B_E59B_D9B4_E019)))
    }

    /// Pixel `pixel`'s Sobol scrambling key for pass `pass` under `seed`: the same in every
    /// pass of one block of 2^26 (`qmc::INDEX_BITS`), so those passes share one sequence, and
    /// another in the next block (the light pilot's passes, from 2^62 on, get their own).
    #[inline]
    pub fn qmc_key(seed: u64, pass: u64, pixel: u64) -> u32 {
        let base = Self::pass_key(seed, stream::CAMERA_QMC, pass >> qmc::INDEX_BITS);
        (splitmix64(base ^ pixel.wrapping_mul(0xD6E8_FEB8_6659_FD93)) >> 32) as u32
    }

    /// Stream `index` under a [`Rng::pass_key`].
    #[inline]
    pub fn indexed(pass_key: u64, index: u64) -> Self {
        let h3 = splitmix64(pass_key ^ index.wrapping_mul(0x9FB2_1C65_1E98_DF25));
        let mut r = Rng { state: 0, inc: (splitmix64(h3 ^ 0xD1B5_4A32_D192_ED03) << 1) | 1, q: qmc::OFF };
        r.next_u32();
        r.state = r.state.wrapping_add(h3);
        r.next_u32();
        r
    }

    /// `Rng::indexed(keys[j], index)` for sixteen keys, each followed by its first two
    /// `next_f32` (a camera ray's jitter): operation for operation what one key at a time gives,
    /// in loops over the lanes that LLVM runs as vectors (`render::pixel`'s pass groups).
    #[inline]
    pub fn indexed_2d_lanes(keys: &[u64; 16], index: u64) -> ([Rng; 16], [[f32; 2]; 16]) {
        let (mut state, mut inc, mut u) = ([0u64; 16], [0u64; 16], [[0.0f32; 2]; 16]);
        for j in 0..16 {
            let mut r = Rng::indexed(keys[j], index);
            u[j] = [r.next_f32(), r.next_f32()];
            (state[j], inc[j]) = (r.state, r.inc);
        }
        (std::array::from_fn(|j| Rng { state: state[j], inc: inc[j], q: qmc::OFF }), u)
    }

    /// This stream led by `qmc::SLOTS` slots of the scrambled Sobol sequence of pixel key `key`
    /// at sample `index` (`sampling::qmc`): each of the first `qmc::SLOTS` `next_2d` calls
    /// takes a slot; every other draw comes from the PCG stream as without the prefix.
    #[inline]
    pub fn with_qmc(mut self, key: u32, index: u64) -> Self {
        self.q = qmc::prefix(key, index);
        self
    }

    /// The next slot of the Sobol prefix (out of line: the hot loops inline only the test).
    #[inline(never)]
    fn qmc_2d(&mut self) -> [f32; 2] {
        let [a, b] = qmc::sample_2d(self.q);
        self.q = qmc::advance(self.q);
        [to_f32(a), to_f32(b)]
    }

    /// Next uniform 32-bit word (PCG, also under a Sobol prefix).
    #[inline]
    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old.wrapping_mul(Self::MUL).wrapping_add(self.inc);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }

    /// Uniform in [0, 1), with 24 bits of precision (never returns 1.0).
    #[inline]
    pub fn next_f32(&mut self) -> f32 {
        to_f32(self.next_u32())
    }

    /// Two uniforms in [0, 1) (a slot of the Sobol prefix while one is left).
    #[inline]
    pub fn next_2d(&mut self) -> [f32; 2] {
        if qmc::has_slot(self.q) {
            return self.qmc_2d();
        }
        [self.next_f32(), self.next_f32()]
    }

    /// Three uniforms in [0, 1): a 2-D pair then one (a BSDF's direction, then its lobe), as
    /// `next_2d` then `next_f32`.
    #[inline]
    pub fn next_3d(&mut self) -> [f32; 3] {
        let [a, b] = self.next_2d();
        [a, b, self.next_f32()]
    }

    /// Uniform integer in [0, n) (n > 0), Lemire's multiply-shift.
    #[inline]
    pub fn below(&mut self, n: u32) -> u32 {
        ((self.next_u32() as u64 * n as u64) >> 32) as u32
    }
}

impl rand::TryRng for Rng {
    type Error = core::convert::Infallible;
    fn try_next_u32(&mut self) -> Result<u32, Self::Error> {
        Ok(self.next_u32())
    }
    fn try_next_u64(&mut self) -> Result<u64, Self::Error> {
        Ok(((self.next_u32() as u64) << 32) | self.next_u32() as u64)
    }
    fn try_fill_bytes(&mut self, dst: &mut [u8]) -> Result<(), Self::Error> {
        for chunk in dst.chunks_mut(4) {
            let w = self.next_u32().to_le_bytes();
            chunk.copy_from_slice(&w[..chunk.len()]);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_pass_key_then_an_index_is_the_keyed_stream() {
        for (seed, stream, pass, index) in [(1, 2, 3, 4), (0, 1, u64::MAX, 7), (u64::MAX, 9, 0, u64::MAX)] {
            let (mut a, mut b) =
                (Rng::keyed(seed, stream, pass, index), Rng::indexed(Rng::pass_key(seed, stream, pass), index));
            assert!((0..8).all(|_| a.next_u32() == b.next_u32()));
        }
    }

    #[test]
    fn keyed_streams_are_reproducible_and_distinct() {
        let a: Vec<u32> = (0..8)
            .map({
                let mut r = Rng::keyed(1, 2, 3, 4);
                move |_| r.next_u32()
            })
            .collect();
        let b: Vec<u32> = (0..8)
            .map({
                let mut r = Rng::keyed(1, 2, 3, 4);
                move |_| r.next_u32()
            })
            .collect();
        let c: Vec<u32> = (0..8)
            .map({
                let mut r = Rng::keyed(1, 2, 3, 5);
                move |_| r.next_u32()
            })
            .collect();
        assert_eq!(a, b);
        assert_ne!(a, c);
    }

    #[test]
    fn uniforms_have_the_right_mean_and_range() {
        let mut r = Rng::keyed(7, 0, 0, 0);
        let n = 200_000;
        let mut sum = 0.0f64;
        for _ in 0..n {
            let u = r.next_f32();
            assert!((0.0..1.0).contains(&u));
            sum += u as f64;
        }
        // mean of U(0,1): 0.5 ± 1/sqrt(12 n); 5 sigma bound
        let sigma = (1.0 / 12.0f64 / n as f64).sqrt();
        assert!((sum / n as f64 - 0.5).abs() < 5.0 * sigma);
    }
}
