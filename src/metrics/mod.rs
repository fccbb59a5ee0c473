//! Image-comparison metrics, difference maps and the Mitsuba noise-consistency check
//! (the last in `agreement`).
//!
//! * Error metrics ([`mse`], [`rmse`], [`rel_mse`], [`mean_abs`]) average over all pixels *and*
//!   channels, in `f64`, optionally restricted to a crop `(x, y, w, h)`. Size mismatches and bad
//!   crops are errors, never panics.
//! * [`false_colour_diff`] maps the signed per-pixel difference (mean over channels of `a − b`)
//!   to a diverging colour map: white = 0, red = `a > b`, blue = `a < b`, saturated at a robust
//!   scale (99th percentile of `|a − b|`); non-finite differences are black.
//! * Noise statistics use variances **of the pixel mean** (not of single samples). The reference
//!   variance per pixel is estimated from two independent half renders as `(h0 − h1)² / 4`.
//!   [`noise_consistency`] compares `mean((I − R)²)` with `mean(σ_I² + σ_R²)`: their ratio is ≈ 1
//!   when the test and the reference differ only by noise.
//! * [`mitsuba_agreement`] is the pass/fail rule of `scripts/check-mitsuba.sh`: per-channel means
//!   within [`MEAN_REL_TOLERANCE`] and the noise ratio within a tolerance derived from its own
//!   standard error (see [`NoiseReport::ratio_tolerance`]).

mod agreement;

pub use agreement::{
    mitsuba_agreement, noise_consistency, AgreementReport, NoiseReport, GAUSSIAN_FRAC_Z3, MEAN_REL_TOLERANCE,
    Z_SMOOTH_RADIUS,
};

use crate::image_io::{write_png_rgb8, Image, ImageError};
use std::fmt;
use std::path::{Path, PathBuf};

/// A crop rectangle `(x, y, width, height)` in pixels, `(0, 0)` at the top-left.
pub type Rect = (usize, usize, usize, usize);

/// The default `ε` of [`rel_mse`].
pub const REL_MSE_EPS: f64 = 0.01;

/// Why a metric could not be computed; `Display` is the message.
#[derive(Debug)]
pub enum MetricsError {
    /// The two images of metric `what` (`mse`, `z_scores (mean_a vs var_a)`) differ in size.
    SizeMismatch {
        /// The metric, and which images where it takes more than two.
        what: &'static str,
        /// The first image's `(width, height)`.
        a: (usize, usize),
        /// The second image's `(width, height)`.
        b: (usize, usize),
    },
    /// An image of metric `what` is empty or its pixel count does not match its size.
    Malformed {
        /// The metric.
        what: &'static str,
    },
    /// A crop outside the image, or the image file that could not be written.
    Image(ImageError),
    /// The difference map to be written to `path` could not be computed.
    InFile {
        /// The PNG.
        path: PathBuf,
        /// Why.
        source: Box<MetricsError>,
    },
}

impl fmt::Display for MetricsError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            MetricsError::SizeMismatch { what, a: (aw, ah), b: (bw, bh) } => {
                write!(f, "{what}: size mismatch {aw}x{ah} vs {bw}x{bh}")
            }
            MetricsError::Malformed { what } => write!(f, "{what}: empty image or pixel count does not match its size"),
            MetricsError::Image(e) => write!(f, "{e}"),
            MetricsError::InFile { path, source } => write!(f, "{}: {source}", path.display()),
        }
    }
}

impl std::error::Error for MetricsError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            MetricsError::Image(e) => Some(e),
            MetricsError::InFile { source, .. } => Some(source.as_ref()),
            _ => None,
        }
    }
}

impl From<ImageError> for MetricsError {
    fn from(e: ImageError) -> MetricsError {
        MetricsError::Image(e)
    }
}

/// For the callers whose own errors are still messages.
impl From<MetricsError> for String {
    fn from(e: MetricsError) -> String {
        e.to_string()
    }
}

fn check_same(a: &Image, b: &Image, what: &'static str) -> Result<(), MetricsError> {
    if !a.same_size(b) {
        return Err(MetricsError::SizeMismatch { what, a: (a.width, a.height), b: (b.width, b.height) });
    }
    if a.pixels.len() != a.width * a.height || b.pixels.len() != b.width * b.height || a.pixels.is_empty() {
        return Err(MetricsError::Malformed { what });
    }
    Ok(())
}

/// Applies an optional crop to an image (borrowing it unchanged when `crop` is `None`).
pub fn apply_crop(img: &Image, crop: Option<Rect>) -> Result<std::borrow::Cow<'_, Image>, MetricsError> {
    match crop {
        None => Ok(std::borrow::Cow::Borrowed(img)),
        Some((x, y, w, h)) => Ok(std::borrow::Cow::Owned(img.crop(x, y, w, h)?)),
    }
}

/// Mean over pixels and channels of `f(a, b)`, after checking sizes and cropping.
fn mean_over(
    a: &Image,
    b: &Image,
    crop: Option<Rect>,
    what: &'static str,
    f: impl Fn(f64, f64) -> f64,
) -> Result<f64, MetricsError> {
    check_same(a, b, what)?;
    let (a, b) = (apply_crop(a, crop)?, apply_crop(b, crop)?);
    let mut s = 0.0;
    for (p, q) in a.pixels.iter().zip(&b.pixels) {
        for c in 0..3 {
            s += f(p[c] as f64, q[c] as f64);
        }
    }
    Ok(s / (3 * a.pixels.len()) as f64)
}

/// Mean squared error over pixels and channels.
pub fn mse(a: &Image, b: &Image, crop: Option<Rect>) -> Result<f64, MetricsError> {
    mean_over(a, b, crop, "mse", |x, y| (x - y) * (x - y))
}

/// Root mean squared error, `sqrt(mse)`.
pub fn rmse(a: &Image, b: &Image, crop: Option<Rect>) -> Result<f64, MetricsError> {
    mse(a, b, crop).map(f64::sqrt)
}

/// Relative MSE: mean over pixels and channels of `(I − R)² / (R² + eps)`; use [`REL_MSE_EPS`].
pub fn rel_mse(img: &Image, reference: &Image, eps: f64, crop: Option<Rect>) -> Result<f64, MetricsError> {
    mean_over(img, reference, crop, "rel_mse", |x, r| (x - r) * (x - r) / (r * r + eps))
}

/// Mean absolute difference over pixels and channels.
pub fn mean_abs(a: &Image, b: &Image, crop: Option<Rect>) -> Result<f64, MetricsError> {
    mean_over(a, b, crop, "mean_abs", |x, y| (x - y).abs())
}

/// Per-channel mean of an image (or of a crop of it).
pub fn channel_means(img: &Image, crop: Option<Rect>) -> Result<[f64; 3], MetricsError> {
    Ok(apply_crop(img, crop)?.mean())
}

/// All scalar metrics of one comparison, as printed by `forecast diff`.
#[derive(Clone, Debug, PartialEq)]
pub struct DiffMetrics {
    /// Mean squared error.
    pub mse: f64,
    /// Root mean squared error.
    pub rmse: f64,
    /// Relative MSE with `ε =` [`REL_MSE_EPS`], `b` taken as the reference.
    pub rel_mse: f64,
    /// Mean absolute difference.
    pub mean_abs: f64,
    /// Per-channel means of `a`.
    pub mean_a: [f64; 3],
    /// Per-channel means of `b`.
    pub mean_b: [f64; 3],
    /// Per-channel `(mean_a − mean_b) / mean_b` (0 when both are 0).
    pub mean_rel_diff: [f64; 3],
}

/// Computes [`DiffMetrics`] of `a` against the reference `b`, optionally on a crop.
pub fn compare(a: &Image, b: &Image, crop: Option<Rect>) -> Result<DiffMetrics, MetricsError> {
    let m = mse(a, b, crop)?;
    let (mean_a, mean_b) = (channel_means(a, crop)?, channel_means(b, crop)?);
    Ok(DiffMetrics {
        mse: m,
        rmse: m.sqrt(),
        rel_mse: rel_mse(a, b, REL_MSE_EPS, crop)?,
        mean_abs: mean_abs(a, b, crop)?,
        mean_a,
        mean_b,
        mean_rel_diff: std::array::from_fn(|c| rel_diff(mean_a[c], mean_b[c])),
    })
}

fn rel_diff(x: f64, r: f64) -> f64 {
    if x == r {
        0.0
    } else {
        (x - r) / r.abs().max(1e-300)
    }
}

impl fmt::Display for DiffMetrics {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "mse       {:.6e}", self.mse)?;
        writeln!(f, "rmse      {:.6e}", self.rmse)?;
        writeln!(f, "rel_mse   {:.6e}", self.rel_mse)?;
        writeln!(f, "mean_abs  {:.6e}", self.mean_abs)?;
        writeln!(f, "mean_a    {:.6} {:.6} {:.6}", self.mean_a[0], self.mean_a[1], self.mean_a[2])?;
        writeln!(f, "mean_b    {:.6} {:.6} {:.6}", self.mean_b[0], self.mean_b[1], self.mean_b[2])?;
        write!(
            f,
            "mean_diff {:+.4}% {:+.4}% {:+.4}%",
            100.0 * self.mean_rel_diff[0],
            100.0 * self.mean_rel_diff[1],
            100.0 * self.mean_rel_diff[2]
        )
    }
}

/// A false-colour difference image (8-bit RGB, row-major) and the scale it saturates at.
#[derive(Clone, Debug, PartialEq)]
pub struct DiffMap {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// `3 * width * height` bytes.
    pub rgb: Vec<u8>,
    /// `|a − b|` at which the colour saturates (99th percentile of `|a − b|`, or 1 if all zero).
    pub scale: f64,
}

/// The `q`-quantile (`0..=1`) of the finite values, by nearest rank; `None` if there are none.
fn quantile(mut v: Vec<f64>, q: f64) -> Option<f64> {
    v.retain(|x| x.is_finite());
    if v.is_empty() {
        return None;
    }
    let k = ((q.clamp(0.0, 1.0) * v.len() as f64).ceil() as usize).clamp(1, v.len()) - 1;
    let (_, x, _) = v.select_nth_unstable_by(k, f64::total_cmp);
    Some(*x)
}

/// Signed difference map of `a − b` (per pixel, mean over channels): white at 0, red where
/// `a > b`, blue where `a < b`, fully saturated at the 99th percentile of `|a − b|`.
pub fn false_colour_diff(a: &Image, b: &Image) -> Result<DiffMap, MetricsError> {
    check_same(a, b, "false_colour_diff")?;
    let d: Vec<f64> = a
        .pixels
        .iter()
        .zip(&b.pixels)
        .map(|(p, q)| (0..3).map(|c| p[c] as f64 - q[c] as f64).sum::<f64>() / 3.0)
        .collect();
    let abs: Vec<f64> = d.iter().map(|x| x.abs()).collect();
    let mut scale = quantile(abs.clone(), 0.99).unwrap_or(0.0);
    if scale <= 0.0 {
        scale = abs.iter().copied().filter(|x| x.is_finite()).fold(0.0, f64::max);
    }
    if scale <= 0.0 {
        scale = 1.0;
    }
    let rgb = d
        .iter()
        .flat_map(|&x| {
            if !x.is_finite() {
                return [0, 0, 0];
            }
            let t = (x / scale).clamp(-1.0, 1.0);
            let fade = ((1.0 - t.abs()) * 255.0).round() as u8;
            if t >= 0.0 {
                [255, fade, fade]
            } else {
                [fade, fade, 255]
            }
        })
        .collect();
    Ok(DiffMap { width: a.width, height: a.height, rgb, scale })
}

/// Writes [`false_colour_diff`]`(a, b)` as a PNG; returns the saturation scale.
pub fn write_diff_png(path: &Path, a: &Image, b: &Image) -> Result<f64, MetricsError> {
    let m =
        false_colour_diff(a, b).map_err(|e| MetricsError::InFile { path: path.to_path_buf(), source: Box::new(e) })?;
    write_png_rgb8(path, m.width, m.height, &m.rgb)?;
    Ok(m.scale)
}

/// Per-pixel, per-channel Welch z-scores `(μa − μb) / sqrt(σa² + σb²)`, where the `var_*`
/// images hold variances of the means. Where the denominator is 0 the score is 0 if the means
/// are equal, else ±∞.
pub fn z_scores(mean_a: &Image, var_a: &Image, mean_b: &Image, var_b: &Image) -> Result<Image, MetricsError> {
    check_same(mean_a, var_a, "z_scores (mean_a vs var_a)")?;
    check_same(mean_a, mean_b, "z_scores (mean_a vs mean_b)")?;
    check_same(mean_a, var_b, "z_scores (mean_a vs var_b)")?;
    let pixels = (0..mean_a.pixels.len())
        .map(|i| {
            std::array::from_fn(|c| {
                let d = mean_a.pixels[i][c] as f64 - mean_b.pixels[i][c] as f64;
                let v = var_a.pixels[i][c] as f64 + var_b.pixels[i][c] as f64;
                if v > 0.0 {
                    (d / v.sqrt()) as f32
                } else if d == 0.0 {
                    0.0
                } else {
                    d.signum() as f32 * f32::INFINITY
                }
            })
        })
        .collect();
    Ok(Image::from_pixels(mean_a.width, mean_a.height, pixels)?)
}

/// Variance of the mean of the full render estimated from two independent halves:
/// `(h0 − h1)² / 4` per pixel and channel.
pub fn half_variance(half0: &Image, half1: &Image) -> Result<Image, MetricsError> {
    check_same(half0, half1, "half_variance")?;
    let pixels = half0
        .pixels
        .iter()
        .zip(&half1.pixels)
        .map(|(p, q)| std::array::from_fn(|c| ((p[c] as f64 - q[c] as f64).powi(2) / 4.0) as f32))
        .collect();
    Ok(Image::from_pixels(half0.width, half0.height, pixels)?)
}

/// Box filter of radius `r` ((2r+1)² window), averaging only the in-bounds pixels (so borders
/// are not darkened). Separable, accumulated in `f64`.
pub fn box_filter(img: &Image, r: usize) -> Image {
    let (w, h) = (img.width, img.height);
    if img.pixels.len() != w * h || w == 0 || h == 0 {
        return img.clone();
    }
    let pass = |src: &[[f64; 3]], horizontal: bool| -> Vec<[f64; 3]> {
        let mut out = vec![[0.0; 3]; w * h];
        for y in 0..h {
            for x in 0..w {
                let (pos, len) = if horizontal { (x, w) } else { (y, h) };
                let (lo, hi) = (pos.saturating_sub(r), (pos + r).min(len - 1));
                let mut s = [0.0; 3];
                for k in lo..=hi {
                    let p = if horizontal { src[y * w + k] } else { src[k * w + x] };
                    for c in 0..3 {
                        s[c] += p[c];
                    }
                }
                let n = (hi - lo + 1) as f64;
                out[y * w + x] = s.map(|v| v / n);
            }
        }
        out
    };
    let src: Vec<[f64; 3]> = img.pixels.iter().map(|p| p.map(|v| v as f64)).collect();
    let out = pass(&pass(&src, true), false);
    Image { width: w, height: h, pixels: out.into_iter().map(|p| p.map(|v| v as f32)).collect() }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn img(w: usize, h: usize, v: &[[f32; 3]]) -> Image {
        Image::from_pixels(w, h, v.to_vec()).unwrap()
    }

    #[test]
    fn scalar_metrics_by_hand() {
        let a = img(2, 1, &[[1.0, 2.0, 3.0], [0.0, 0.0, 0.0]]);
        let b = img(2, 1, &[[1.0, 0.0, 3.0], [0.0, 0.0, 1.0]]);
        // differences 0, 2, 0 | 0, 0, -1
        assert!((mse(&a, &b, None).unwrap() - 5.0 / 6.0).abs() < 1e-12);
        assert!((rmse(&a, &b, None).unwrap() - (5.0f64 / 6.0).sqrt()).abs() < 1e-12);
        assert!((mean_abs(&a, &b, None).unwrap() - 0.5).abs() < 1e-12);
        // 4/(0+0.01) + 1/(1+0.01)
        let want = (400.0 + 1.0 / 1.01) / 6.0;
        assert!((rel_mse(&a, &b, REL_MSE_EPS, None).unwrap() - want).abs() < 1e-9);
        assert!((mse(&a, &b, Some((0, 0, 1, 1))).unwrap() - 4.0 / 3.0).abs() < 1e-12);
        assert_eq!(mse(&a, &b, Some((1, 0, 1, 1))).unwrap(), 1.0 / 3.0);
        assert!(mse(&a, &b, Some((1, 0, 2, 1))).is_err());
        assert_eq!(mse(&a, &Image::new(1, 2), None).unwrap_err().to_string(), "mse: size mismatch 2x1 vs 1x2");
        assert_eq!(channel_means(&a, None).unwrap(), [0.5, 1.0, 1.5]);
        let m = compare(&a, &b, None).unwrap();
        assert_eq!(m.mean_b, [0.5, 0.0, 2.0]);
        assert_eq!(m.mean_rel_diff[0], 0.0);
        assert!((m.mean_rel_diff[2] + 0.25).abs() < 1e-12);
        assert!(m.to_string().contains("rel_mse"));
    }

    #[test]
    fn false_colour_by_hand() {
        let a = img(3, 1, &[[1.0; 3], [0.0; 3], [2.0; 3]]);
        let b = img(3, 1, &[[0.0; 3], [0.5; 3], [2.0; 3]]);
        let m = false_colour_diff(&a, &b).unwrap();
        assert_eq!(m.scale, 1.0); // nearest-rank 99th percentile of {1, 0.5, 0}
        assert_eq!(m.rgb, vec![255, 0, 0, 128, 128, 255, 255, 255, 255]);
        let same = false_colour_diff(&a, &a).unwrap();
        assert_eq!(same.scale, 1.0);
        assert!(same.rgb.iter().all(|&v| v == 255));
        let nan = img(1, 1, &[[f32::NAN; 3]]);
        assert_eq!(false_colour_diff(&nan, &img(1, 1, &[[0.0; 3]])).unwrap().rgb, vec![0, 0, 0]);
        let p = std::env::temp_dir().join(format!("forecast-metrics-diff-{}.png", std::process::id()));
        assert_eq!(write_diff_png(&p, &a, &b).unwrap(), 1.0);
        assert_eq!(crate::image_io::read_png_rgb8(&p).unwrap(), (3, 1, m.rgb));
        let _ = std::fs::remove_file(p);
        assert!(false_colour_diff(&a, &Image::new(2, 1)).is_err());
    }

    #[test]
    fn z_half_variance_box_by_hand() {
        let ma = img(2, 1, &[[1.0, 2.0, 0.0], [5.0, 0.0, 1.0]]);
        let va = img(2, 1, &[[0.09, 0.0, 0.0], [1.0, 0.0, 0.0]]);
        let mb = img(2, 1, &[[0.0, 2.0, 0.0], [1.0, 0.0, 0.0]]);
        let vb = img(2, 1, &[[0.16, 0.0, 0.0], [3.0, 0.0, 0.0]]);
        let z = z_scores(&ma, &va, &mb, &vb).unwrap();
        assert!((z.get(0, 0)[0] - 2.0).abs() < 1e-6); // 1/sqrt(0.25)
        assert_eq!(z.get(0, 0)[1], 0.0);
        assert!((z.get(1, 0)[0] - 2.0).abs() < 1e-6); // 4/sqrt(4)
        assert_eq!(z.get(1, 0)[2], f32::INFINITY);
        let hv = half_variance(&img(1, 1, &[[1.0, 0.0, 2.0]]), &img(1, 1, &[[0.6, 0.0, 1.0]])).unwrap();
        let want = [0.04f32, 0.0, 0.25];
        for (got, want) in hv.pixels[0].iter().zip(want) {
            assert!((got - want).abs() < 1e-7);
        }
        let row = img(3, 1, &[[0.0; 3], [3.0; 3], [6.0; 3]]);
        assert_eq!(box_filter(&row, 1).pixels, vec![[1.5; 3], [3.0; 3], [4.5; 3]]);
        let col = img(1, 3, &[[0.0; 3], [3.0; 3], [6.0; 3]]);
        assert_eq!(box_filter(&col, 5).pixels, vec![[3.0; 3]; 3]);
    }
}
