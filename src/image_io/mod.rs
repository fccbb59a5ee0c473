//! Image container and file I/O: OpenEXR (linear float) and PNG (8-bit sRGB).
//!
//! * [`Image`] is a row-major buffer of linear RGB `f32` pixels; pixel `(0, 0)` is the top-left
//!   corner and `pixels[y * width + x]` is pixel `(x, y)`. Invariant:
//!   `pixels.len() == width * height`.
//! * EXR files are written as one scan-line layer, float32, ZIP compression, channels `R`, `G`,
//!   `B` and optionally the per-pixel variance-of-the-mean channels [`VARIANCE_CHANNELS`]
//!   (`var.R`, `var.G`, `var.B`) in the same layer. Readers take the first layer that has `R`, `G`,
//!   `B` (alpha and other channels are ignored; a lone `Y` channel is read as grey).
//! * Every writer is atomic: bytes go to [`atomic_path`]`(path)` (`PATH.tmp`, same directory)
//!   and are then renamed over `path`, so a reader never sees a half-written file
//!   ([`crate::atomic_io`]). The `encode_*` functions return the file's bytes instead, for a
//!   set of files written as a whole ([`crate::atomic_io::FileSet`]).
//! * Nothing here panics on bad input; errors are [`ImageError`]s that name the file (where
//!   there is one).
//!
//! This is the only module that uses the `exr` and `png` crates.

pub use crate::atomic_io::{atomic_path, atomic_write};
use std::io::Cursor;
use std::path::{Path, PathBuf};

mod decode;
mod error;
pub use decode::{decode_texture, decode_texture_bytes, DecodedImage, TexelData, MAX_TEXELS};
pub use error::ImageError;

/// Names of the per-pixel variance-of-the-mean channels written by [`write_exr_layers`].
pub const VARIANCE_CHANNELS: [&str; 3] = ["var.R", "var.G", "var.B"];

/// [`atomic_write`] with its failure as an [`ImageError::Write`].
fn write_file(path: &Path, bytes: &[u8]) -> Result<(), ImageError> {
    Ok(atomic_write(path, bytes)?)
}

/// A linear-RGB float image, row-major, `(0, 0)` at the top-left.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// `width * height` pixels; pixel `(x, y)` is at index `y * width + x`.
    pub pixels: Vec<[f32; 3]>,
}

impl Image {
    /// A black image of the given size.
    pub fn new(width: usize, height: usize) -> Image {
        Image { width, height, pixels: vec![[0.0; 3]; width * height] }
    }

    /// Wraps a pixel vector, checking that its length is `width * height`.
    pub fn from_pixels(width: usize, height: usize, pixels: Vec<[f32; 3]>) -> Result<Image, ImageError> {
        if width.checked_mul(height) != Some(pixels.len()) {
            return Err(ImageError::PixelCount { width, height, pixels: pixels.len() });
        }
        Ok(Image { width, height, pixels })
    }

    /// Builds an image by evaluating `f(x, y)` for every pixel.
    pub fn from_fn(width: usize, height: usize, mut f: impl FnMut(usize, usize) -> [f32; 3]) -> Image {
        let mut pixels = Vec::with_capacity(width * height);
        for y in 0..height {
            for x in 0..width {
                pixels.push(f(x, y));
            }
        }
        Image { width, height, pixels }
    }

    /// Pixel `(x, y)`. Panics if out of bounds (like slice indexing); see [`Image::try_get`].
    pub fn get(&self, x: usize, y: usize) -> [f32; 3] {
        assert!(x < self.width && y < self.height, "pixel ({x},{y}) outside {}x{}", self.width, self.height);
        self.pixels[y * self.width + x]
    }

    /// Pixel `(x, y)`, or `None` if out of bounds.
    pub fn try_get(&self, x: usize, y: usize) -> Option<[f32; 3]> {
        if x < self.width && y < self.height {
            self.pixels.get(y * self.width + x).copied()
        } else {
            None
        }
    }

    /// Sets pixel `(x, y)`; returns `false` (and does nothing) if out of bounds.
    pub fn set(&mut self, x: usize, y: usize, value: [f32; 3]) -> bool {
        if x < self.width && y < self.height {
            self.pixels[y * self.width + x] = value;
            true
        } else {
            false
        }
    }

    /// The `w`×`h` sub-image whose top-left corner is `(x, y)`; errors if it leaves the image
    /// or is empty.
    pub fn crop(&self, x: usize, y: usize, w: usize, h: usize) -> Result<Image, ImageError> {
        let fits = w > 0
            && h > 0
            && x.checked_add(w).is_some_and(|r| r <= self.width)
            && y.checked_add(h).is_some_and(|b| b <= self.height);
        if !fits {
            return Err(ImageError::Crop { rect: (x, y, w, h), width: self.width, height: self.height });
        }
        let mut pixels = Vec::with_capacity(w * h);
        for row in y..y + h {
            let start = row * self.width + x;
            pixels.extend_from_slice(&self.pixels[start..start + w]);
        }
        Ok(Image { width: w, height: h, pixels })
    }

    /// Per-channel mean over all pixels (accumulated in `f64`); `[0; 3]` for an empty image.
    pub fn mean(&self) -> [f64; 3] {
        let mut s = [0.0f64; 3];
        for p in &self.pixels {
            for c in 0..3 {
                s[c] += p[c] as f64;
            }
        }
        let n = self.pixels.len().max(1) as f64;
        [s[0] / n, s[1] / n, s[2] / n]
    }

    /// `true` if the other image has the same width and height.
    pub fn same_size(&self, other: &Image) -> bool {
        self.width == other.width && self.height == other.height
    }
}

/// `prefix` + "." + `ext` (keeps dots inside the prefix, unlike `Path::with_extension`).
pub fn with_ext(prefix: &Path, ext: &str) -> PathBuf {
    let mut s = prefix.as_os_str().to_owned();
    s.push(".");
    s.push(ext);
    PathBuf::from(s)
}

/// Checks that every image has the size of the first; the error names both files and sizes.
pub fn check_same_size(named: &[(&Path, &Image)]) -> Result<(), ImageError> {
    let Some(&(p0, i0)) = named.first() else { return Ok(()) };
    match named.iter().find(|(_, i)| !i.same_size(i0)) {
        None => Ok(()),
        Some((p, i)) => Err(ImageError::SizeMismatch {
            first: (p0.to_path_buf(), (i0.width, i0.height)),
            other: (p.to_path_buf(), (i.width, i.height)),
        }),
    }
}

fn check_len(path: &Path, img: &Image) -> Result<(), ImageError> {
    if img.pixels.len() != img.width * img.height || img.width == 0 || img.height == 0 {
        let (width, height, pixels) = (img.width, img.height, img.pixels.len());
        return Err(ImageError::Malformed { path: path.to_path_buf(), width, height, pixels });
    }
    Ok(())
}

/// Writes an RGB float32 EXR (channels `R`, `G`, `B`).
pub fn write_exr(path: &Path, img: &Image) -> Result<(), ImageError> {
    write_exr_layers(path, img, None)
}

/// Writes an RGB float32 EXR; with `variance` also the channels [`VARIANCE_CHANNELS`]
/// (`var.R`, `var.G`, `var.B`, the per-pixel variance of the mean) in the same layer.
pub fn write_exr_layers(path: &Path, img: &Image, variance: Option<&Image>) -> Result<(), ImageError> {
    write_file(path, &encode_exr_layers(path, img, variance)?)
}

/// The bytes [`write_exr_layers`] would write to `path` (named in errors only).
pub fn encode_exr_layers(path: &Path, img: &Image, variance: Option<&Image>) -> Result<Vec<u8>, ImageError> {
    use exr::image::write::WritableImage;
    use exr::image::{AnyChannel, AnyChannels, Encoding, FlatSamples, Layer};
    use exr::meta::header::LayerAttributes;
    check_len(path, img)?;
    let plane = |im: &Image, c: usize| FlatSamples::F32(im.pixels.iter().map(|p| p[c]).collect());
    let mut list: Vec<AnyChannel<FlatSamples>> =
        ["R", "G", "B"].iter().enumerate().map(|(c, n)| AnyChannel::new(*n, plane(img, c))).collect();
    if let Some(v) = variance {
        if !v.same_size(img) {
            let (variance, colour) = ((v.width, v.height), (img.width, img.height));
            return Err(ImageError::VarianceSize { path: path.to_path_buf(), variance, colour });
        }
        check_len(path, v)?;
        for (c, n) in VARIANCE_CHANNELS.iter().enumerate() {
            list.push(AnyChannel::new(*n, plane(v, c)));
        }
    }
    let channels = AnyChannels::sort(list.into_iter().collect());
    let layer = Layer::new((img.width, img.height), LayerAttributes::default(), Encoding::SMALL_LOSSLESS, channels);
    let image = exr::image::Image::from_layer(layer);
    let mut buf = Cursor::new(Vec::new());
    image.write().to_buffered(&mut buf).map_err(|e| ImageError::Encode {
        path: Some(path.to_path_buf()),
        format: "EXR",
        reason: e.to_string(),
    })?;
    Ok(buf.into_inner())
}

type FlatLayer = exr::image::Layer<exr::image::AnyChannels<exr::image::FlatSamples>>;

/// Every layer of the EXR `bytes` (of `path`, for messages), all channels as flat samples.
fn read_exr_layers(path: &Path, bytes: &[u8]) -> Result<Vec<FlatLayer>, ImageError> {
    use exr::image::read::{image::ReadLayers, layers::ReadChannels, read};
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .from_buffered(Cursor::new(bytes))
        .map_err(|e| decode_error(path, "EXR", e))?;
    Ok(image.layer_data.into_vec())
}

fn read_first_layer(path: &Path) -> Result<FlatLayer, ImageError> {
    let bytes = crate::atomic_io::read_regular(path).map_err(|e| io_error(path, "read", e))?;
    decode::check_exr_header(path, &bytes, false)?;
    let mut layers = read_exr_layers(path, &bytes)?.into_iter();
    let first = layers.next().ok_or_else(|| unsupported(path, "EXR has no layers".into()))?;
    if find_channels(&first, &["R", "G", "B"]).is_some() || find_channels(&first, &["Y"]).is_some() {
        return Ok(first);
    }
    layers.find(|l| find_channels(l, &["R", "G", "B"]).is_some()).ok_or_else(|| {
        unsupported(path, format!("no layer with R, G, B channels (first layer has {:?})", channel_names(&first)))
    })
}

fn channel_names(layer: &FlatLayer) -> Vec<String> {
    layer.channel_data.list.iter().map(|c| c.name.to_string()).collect()
}

fn find_channels(layer: &FlatLayer, names: &[&str]) -> Option<Vec<usize>> {
    names.iter().map(|n| layer.channel_data.list.iter().position(|c| c.name.eq(n))).collect()
}

fn layer_to_image(path: &Path, layer: &FlatLayer, idx: &[usize]) -> Result<Image, ImageError> {
    let (w, h) = (layer.size.width(), layer.size.height());
    let planes: Vec<Vec<f32>> =
        idx.iter().map(|&i| layer.channel_data.list[i].sample_data.values_as_f32().collect()).collect();
    if planes.iter().any(|p| p.len() != w * h) {
        return Err(unsupported(path, format!("channel sample count does not match {w}x{h} (subsampled channels?)")));
    }
    let pixels = (0..w * h)
        .map(|i| {
            let g = |c: usize| planes[c.min(planes.len() - 1)][i];
            [g(0), g(1), g(2)]
        })
        .collect();
    Ok(Image { width: w, height: h, pixels })
}

/// Reads the colour of an EXR: channels `R`, `G`, `B` of the first layer that has them (or a
/// lone `Y` channel of the first layer, replicated to grey). Other channels are ignored.
pub fn read_exr(path: &Path) -> Result<Image, ImageError> {
    let layer = read_first_layer(path)?;
    let idx = find_channels(&layer, &["R", "G", "B"])
        .or_else(|| find_channels(&layer, &["Y"]))
        .ok_or_else(|| unsupported(path, "no R, G, B or Y channels".into()))?;
    layer_to_image(path, &layer, &idx).and_then(|img| checked(path, img, "not finite", |v| v.is_finite()))
}

/// `img` if every channel of every pixel passes `ok`; else an error naming the first pixel that
/// does not (a NaN would make every metric NaN, and a check that compares with NaN pass).
fn checked(path: &Path, img: Image, what: &'static str, ok: impl Fn(f32) -> bool) -> Result<Image, ImageError> {
    let bad = |p: &[f32; 3]| !p.iter().all(|&v| ok(v));
    let Some(first) = img.pixels.iter().position(bad) else { return Ok(img) };
    let count = img.pixels.iter().filter(|p| bad(p)).count();
    let (path, value) = (path.to_path_buf(), img.pixels[first]);
    Err(ImageError::BadPixels { path, count, what, first: (first % img.width, first / img.width), value })
}

fn io_error(path: &Path, action: &'static str, source: std::io::Error) -> ImageError {
    ImageError::Io { path: path.to_path_buf(), action, source }
}

fn decode_error(path: &Path, format: &'static str, e: impl std::fmt::Display) -> ImageError {
    ImageError::Decode { path: path.to_path_buf(), format, reason: e.to_string() }
}

fn unsupported(path: &Path, reason: String) -> ImageError {
    ImageError::Unsupported { path: path.to_path_buf(), reason }
}

/// Reads the [`VARIANCE_CHANNELS`] of the colour layer of an EXR, or `Ok(None)` if it has none.
pub fn read_exr_variance(path: &Path) -> Result<Option<Image>, ImageError> {
    let layer = read_first_layer(path)?;
    match find_channels(&layer, &VARIANCE_CHANNELS) {
        Some(idx) => layer_to_image(path, &layer, &idx)
            .and_then(|v| {
                checked(path, v, "with a variance that is negative or not finite", |v| v.is_finite() && v >= 0.0)
            })
            .map(Some),
        None => Ok(None),
    }
}

/// sRGB opto-electronic transfer function for a linear value in `[0, 1]`.
pub fn srgb_oetf(v: f32) -> f32 {
    if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

/// Tone-maps one linear value to an 8-bit sRGB code: multiply by `scale`, clamp to `[0, 1]`
/// (NaN becomes 0), apply the sRGB OETF, round.
pub fn to_srgb8(v: f32, scale: f32) -> u8 {
    let x = v * scale;
    let x = if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) };
    (srgb_oetf(x) * 255.0 + 0.5).floor().clamp(0.0, 255.0) as u8
}

/// Writes an 8-bit sRGB PNG of a linear image. `exposure` is in stops: values are multiplied
/// by `2^exposure` (0 = unchanged), clamped to `[0, 1]`, then encoded with the sRGB OETF.
pub fn write_png_srgb(path: &Path, img: &Image, exposure: f32) -> Result<(), ImageError> {
    write_file(path, &encode_png_srgb(path, img, exposure)?)
}

/// The bytes [`write_png_srgb`] would write to `path` (named in errors only).
pub fn encode_png_srgb(path: &Path, img: &Image, exposure: f32) -> Result<Vec<u8>, ImageError> {
    check_len(path, img)?;
    let scale = exposure.exp2();
    let bytes: Vec<u8> = img.pixels.iter().flat_map(|p| p.map(|v| to_srgb8(v, scale))).collect();
    encode_png_rgb8(img.width, img.height, &bytes).map_err(|e| e.in_file(path))
}

/// Writes raw 8-bit RGB bytes (`3 * w * h`, row-major, top row first) as a PNG.
pub fn write_png_rgb8(path: &Path, w: usize, h: usize, rgb: &[u8]) -> Result<(), ImageError> {
    let bytes = encode_png_rgb8(w, h, rgb).map_err(|e| e.in_file(path))?;
    write_file(path, &bytes)
}

/// Encodes raw 8-bit RGB bytes (`3 * w * h`) as PNG file bytes in memory.
/// The file is named by the caller ([`ImageError::in_file`]).
pub fn encode_png_rgb8(w: usize, h: usize, rgb: &[u8]) -> Result<Vec<u8>, ImageError> {
    let fail = |reason: String| ImageError::Encode { path: None, format: "PNG", reason };
    if w == 0 || h == 0 || w.checked_mul(h).and_then(|n| n.checked_mul(3)) != Some(rgb.len()) {
        let needs = w.saturating_mul(h).saturating_mul(3);
        return Err(fail(format!("PNG of {w}x{h} needs {needs} RGB bytes, got {}", rgb.len())));
    }
    let w32 = u32::try_from(w).map_err(|_| fail("PNG too wide".into()))?;
    let h32 = u32::try_from(h).map_err(|_| fail("PNG too tall".into()))?;
    let mut out = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut out, w32, h32);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let mut writer = enc.write_header().map_err(|e| fail(format!("PNG header: {e}")))?;
        writer.write_image_data(rgb).map_err(|e| fail(format!("PNG data: {e}")))?;
        writer.finish().map_err(|e| fail(format!("PNG finish: {e}")))?;
    }
    Ok(out)
}

/// Reads an 8-bit RGB or RGBA PNG into `(width, height, RGB bytes)` (alpha dropped). Used by
/// tests and tools that inspect written PNGs.
pub fn read_png_rgb8(path: &Path) -> Result<(usize, usize, Vec<u8>), ImageError> {
    crate::atomic_io::require_regular(path).map_err(|e| io_error(path, "open", e))?;
    let file = std::fs::File::open(path).map_err(|e| io_error(path, "open", e))?;
    let decoder = png::Decoder::new(std::io::BufReader::new(file));
    let mut reader = decoder.read_info().map_err(|e| decode_error(path, "PNG", e))?;
    let size = reader.output_buffer_size().ok_or_else(|| unsupported(path, "PNG too large".into()))?;
    let mut buf = vec![0; size];
    let info = reader.next_frame(&mut buf).map_err(|e| decode_error(path, "PNG", e))?;
    if info.bit_depth != png::BitDepth::Eight {
        return Err(unsupported(path, "only 8-bit PNGs are supported".into()));
    }
    let (w, h) = (info.width as usize, info.height as usize);
    let rgb = match info.color_type {
        png::ColorType::Rgb => buf[..w * h * 3].to_vec(),
        png::ColorType::Rgba => buf[..w * h * 4].chunks_exact(4).flat_map(|p| [p[0], p[1], p[2]]).collect(),
        other => return Err(unsupported(path, format!("unsupported PNG colour type {other:?}"))),
    };
    Ok((w, h, rgb))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    fn tmpdir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("forecast-image-io-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    fn sample() -> Image {
        Image::from_fn(5, 3, |x, y| [x as f32 * 0.5, y as f32 - 1.0, (x * 10 + y) as f32 * 1e-3 + 1e6])
    }

    #[test]
    fn get_crop_mean() {
        let img = sample();
        assert_eq!(img.get(4, 2), [2.0, 1.0, 42.0 * 1e-3 + 1e6]);
        let c = img.crop(1, 1, 3, 2).unwrap();
        assert_eq!((c.width, c.height), (3, 2));
        assert_eq!(c.get(0, 0), img.get(1, 1));
        assert_eq!(c.get(2, 1), img.get(3, 2));
        assert!(img.crop(3, 0, 3, 1).is_err());
        assert!(img.crop(0, 0, 0, 1).is_err());
        assert!(img.crop(usize::MAX, 0, 2, 1).is_err());
        // mean of x*0.5 over x=0..4 is 1.0; mean of y-1 over y=0..2 is 0.
        let m = img.mean();
        assert!((m[0] - 1.0).abs() < 1e-12 && m[1].abs() < 1e-12);
        assert_eq!(img.try_get(5, 0), None);
        assert!(Image::from_pixels(2, 2, vec![[0.0; 3]; 3]).is_err());
    }

    #[test]
    fn atomic_path_convention() {
        assert_eq!(atomic_path(Path::new("/a/b/c.exr")), PathBuf::from("/a/b/c.exr.tmp"));
        assert_eq!(atomic_path(Path::new("c.png")), PathBuf::from("c.png.tmp"));
    }

    #[test]
    fn exr_round_trip_bit_exact_with_variance() {
        let d = tmpdir("exr");
        let img = sample();
        let var = Image::from_fn(5, 3, |x, y| [x as f32 * 1e-4, y as f32 * 2e-4, 3e-4]);
        let p = d.join("a.exr");
        write_exr(&p, &img).unwrap();
        assert!(!atomic_path(&p).exists());
        assert_eq!(read_exr(&p).unwrap(), img);
        assert_eq!(read_exr_variance(&p).unwrap(), None);
        let q = d.join("b.exr");
        write_exr_layers(&q, &img, Some(&var)).unwrap();
        assert_eq!(read_exr(&q).unwrap(), img);
        assert_eq!(read_exr_variance(&q).unwrap(), Some(var));
        let bad = Image::new(2, 2);
        assert!(write_exr_layers(&q, &img, Some(&bad)).is_err());
        let err = read_exr(&d.join("missing.exr")).unwrap_err();
        assert!(matches!(err, ImageError::Io { action: "read", .. }), "{err:?}");
        assert!(err.to_string().starts_with("cannot read ") && err.to_string().contains("missing.exr"), "{err}");
        std::fs::write(d.join("junk.exr"), b"not an exr").unwrap();
        let err = read_exr(&d.join("junk.exr")).unwrap_err();
        assert!(matches!(err, ImageError::Decode { format: "EXR", .. }), "{err:?}");
        assert!(err.to_string().starts_with("cannot decode EXR ") && err.to_string().contains("junk.exr"), "{err}");
        let _ = std::fs::remove_dir_all(d);
    }

    /// Each error's message, word for word as the callers and the tests read it.
    #[test]
    fn error_messages() {
        let p = Path::new("d/a.exr");
        let msg = |e: ImageError| e.to_string();
        assert_eq!(msg(Image::from_pixels(2, 2, vec![[0.0; 3]; 3]).unwrap_err()), "image of 2x2 needs 4 pixels, got 3");
        assert_eq!(
            msg(Image::new(4, 3).crop(3, 0, 2, 1).unwrap_err()),
            "crop 3,0,2,1 is empty or outside the 4x3 image"
        );
        let (a, b) = (Image::new(4, 3), Image::new(8, 6));
        assert_eq!(
            msg(check_same_size(&[(p, &a), (Path::new("b.exr"), &b)]).unwrap_err()),
            "d/a.exr is 4x3 but b.exr is 8x6: the images must have the same size"
        );
        let empty = Image { width: 2, height: 2, pixels: vec![] };
        assert_eq!(
            msg(encode_exr_layers(p, &empty, None).unwrap_err()),
            "d/a.exr: image 2x2 has 0 pixels (must be non-empty and match)"
        );
        assert_eq!(
            msg(encode_exr_layers(p, &a, Some(&b)).unwrap_err()),
            "d/a.exr: variance image is 8x6, colour image is 4x3"
        );
        assert_eq!(msg(encode_png_rgb8(2, 2, &[0; 5]).unwrap_err()), "PNG of 2x2 needs 12 RGB bytes, got 5");
        assert_eq!(
            msg(write_png_rgb8(Path::new("d/x.png"), 2, 2, &[0; 5]).unwrap_err()),
            "d/x.png: PNG of 2x2 needs 12 RGB bytes, got 5"
        );
        let nan = Image::from_fn(3, 2, |x, y| if (x, y) == (1, 1) { [f32::NAN, 0.0, 0.0] } else { [0.0; 3] });
        assert_eq!(
            msg(checked(p, nan, "not finite", |v| v.is_finite()).unwrap_err()),
            "d/a.exr: 1 pixel(s) not finite, the first at (1, 1): [NaN, 0.0, 0.0]"
        );
        assert_eq!(msg(unsupported(p, "no R, G, B or Y channels".into())), "d/a.exr: no R, G, B or Y channels");
        assert_eq!(msg(decode_error(p, "PNG", "bad")), "cannot decode PNG d/a.exr: bad");
        let io = std::io::Error::new(std::io::ErrorKind::NotFound, "gone");
        assert_eq!(msg(io_error(p, "open", io)), "cannot open d/a.exr: gone");
        let enc = ImageError::Encode { path: Some(p.to_path_buf()), format: "EXR", reason: "full".into() };
        assert_eq!(msg(enc), "cannot encode EXR d/a.exr: full");
    }

    #[test]
    fn srgb_tone_map_values() {
        assert_eq!(to_srgb8(0.0, 1.0), 0);
        assert_eq!(to_srgb8(1.0, 1.0), 255);
        assert_eq!(to_srgb8(7.0, 1.0), 255);
        assert_eq!(to_srgb8(-1.0, 1.0), 0);
        assert_eq!(to_srgb8(f32::NAN, 1.0), 0);
        // 0.5 linear -> 1.055*0.5^(1/2.4)-0.055 = 0.73536 -> 187.5 -> 188
        assert_eq!(to_srgb8(0.5, 1.0), 188);
        assert_eq!(to_srgb8(0.25, 2.0), 188);
        // linear segment: 0.001*12.92*255 = 3.29 -> 3
        assert_eq!(to_srgb8(0.001, 1.0), 3);
    }

    #[test]
    fn png_round_trip() {
        let d = tmpdir("png");
        let img = Image::from_pixels(2, 1, vec![[0.5, 0.0, 1.0], [0.125, 2.0, 0.0]]).unwrap();
        let p = d.join("t.png");
        write_png_srgb(&p, &img, 1.0).unwrap(); // x2
        let (w, h, rgb) = read_png_rgb8(&p).unwrap();
        assert_eq!((w, h), (2, 1));
        // 0.125*2 = 0.25 linear -> 1.055*0.25^(1/2.4)-0.055 = 0.53709 -> 136.96 -> 137
        assert_eq!(rgb, vec![255, 0, 255, 137, 255, 0]);
        assert!(write_png_rgb8(&p, 2, 2, &[0; 5]).is_err());
        let raw: Vec<u8> = (0..4 * 3 * 3).map(|i| i as u8).collect();
        write_png_rgb8(&p, 4, 3, &raw).unwrap();
        assert_eq!(read_png_rgb8(&p).unwrap(), (4, 3, raw));
        let _ = std::fs::remove_dir_all(d);
    }

    #[test]
    fn reads_committed_mitsuba_reference() {
        let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/reference/cornell-box-mitsuba-256.exr");
        let img = read_exr(&p).unwrap();
        assert_eq!((img.width, img.height), (256, 256));
        let m = img.mean();
        let avg = (m[0] + m[1] + m[2]) / 3.0;
        assert!((avg - 0.13958).abs() < 2e-4, "mean {avg}");
    }
}
