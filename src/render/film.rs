//! `Film`: per-pixel f64 sums of radiance, of its square and sample counts, so the mean and
//! the variance of the mean are available (z-tests, EXR variance layer) and films from
//! several ranks or checkpoints add up exactly.
//!
//! Layout (the MPI reduce and checkpoints rely on it): 7 f64 per pixel,
//! `[Σr, Σg, Σb, Σr², Σg², Σb², n]`, row-major from the top-left pixel.

use crate::math::Rgb;

/// f64 values per pixel.
pub const STRIDE: usize = 7;

/// Accumulated samples.
#[derive(Clone, Debug, PartialEq)]
pub struct Film {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// Raw sums (see the module docs for the layout).
    pub data: Vec<f64>,
}

/// Adds one sample to a pixel's `STRIDE` sums `d`.
#[inline]
pub fn add_at(d: &mut [f64], c: Rgb) {
    let (r, g, b) = (c.x as f64, c.y as f64, c.z as f64);
    d[0] += r;
    d[1] += g;
    d[2] += b;
    d[3] += r * r;
    d[4] += g * g;
    d[5] += b * b;
    d[6] += 1.0;
}

impl Film {
    /// An empty film.
    pub fn new(width: usize, height: usize) -> Film {
        Film { width, height, data: vec![0.0; width * height * STRIDE] }
    }

    /// Wraps raw sums; `None` if the length does not match.
    pub fn from_data(width: usize, height: usize, data: Vec<f64>) -> Option<Film> {
        (data.len() == width * height * STRIDE).then_some(Film { width, height, data })
    }

    /// Adds one sample to pixel `i`.
    #[inline]
    pub fn add(&mut self, i: usize, c: Rgb) {
        add_at(&mut self.data[i * STRIDE..(i + 1) * STRIDE], c);
    }

    /// Adds another film's sums.
    pub fn merge(&mut self, other: &Film) {
        for (a, b) in self.data.iter_mut().zip(&other.data) {
            *a += *b;
        }
    }

    /// Sample count of pixel `i`.
    #[inline]
    pub fn count(&self, i: usize) -> f64 {
        self.data[i * STRIDE + 6]
    }

    /// Mean radiance per pixel (0 where no samples).
    pub fn mean(&self) -> Vec<[f32; 3]> {
        self.data
            .chunks_exact(STRIDE)
            .map(|d| {
                let n = d[6].max(1.0);
                [(d[0] / n) as f32, (d[1] / n) as f32, (d[2] / n) as f32]
            })
            .collect()
    }

    /// Variance of the per-pixel mean, s²/n (unbiased sample variance; 0 with < 2 samples).
    pub fn variance_of_mean(&self) -> Vec<[f32; 3]> {
        self.data
            .chunks_exact(STRIDE)
            .map(|d| {
                let n = d[6];
                if n < 2.0 {
                    return [0.0; 3];
                }
                let v = |k: usize| {
                    let m = d[k] / n;
                    (((d[k + 3] / n - m * m) * n / (n - 1.0)).max(0.0) / n) as f32
                };
                [v(0), v(1), v(2)]
            })
            .collect()
    }

    /// Total samples over all pixels.
    pub fn total_samples(&self) -> f64 {
        self.data.chunks_exact(STRIDE).map(|d| d[6]).sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mean_and_variance_of_known_samples() {
        let mut f = Film::new(2, 1);
        for v in [1.0f32, 2.0, 3.0, 4.0] {
            f.add(1, Rgb::new(v, 2.0 * v, 0.0));
        }
        let m = f.mean();
        assert_eq!(m[0], [0.0; 3]);
        assert_eq!(m[1], [2.5, 5.0, 0.0]);
        // sample variance of 1..4 is 5/3; of the mean: 5/12
        let v = f.variance_of_mean();
        assert!((v[1][0] - 5.0 / 12.0).abs() < 1e-6 && (v[1][1] - 4.0 * 5.0 / 12.0).abs() < 1e-5);
        let mut g = f.clone();
        g.merge(&f);
        assert_eq!(g.count(1), 8.0);
    }
}
