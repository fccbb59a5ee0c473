//! Decoding of texture images (the `texture` module's one way in): PNG, JPEG and Radiance HDR
//! through the `image` crate, OpenEXR through `exr`, each file read once and decoded to its
//! texels as stored, without colour transforms.
//!
//! * The format is told by the file's first bytes (as Mitsuba 3's `Bitmap` does), not by its
//!   name: PNG signature, JPEG `FF D8`, Radiance `#?`, OpenEXR magic `76 2F 31 01`.
//! * [`DecodedImage`] holds `width * height * channels` samples, row-major, the top row first
//!   (texel `(0, 0)` is the top-left corner, as every one of these formats stores it), with
//!   `channels` 1 (grey: a grey PNG or JPEG, an EXR with a lone `Y` channel) or 3 (RGB). Alpha
//!   is dropped; palette and 1/2/4-bit grey PNGs are expanded to 8 bits.
//! * Samples keep their encoding ([`TexelData`]): 8- and 16-bit integer codes (PNG, JPEG; the
//!   caller decides whether they are sRGB-encoded) or linear `f32` (EXR of any sample type;
//!   Radiance RGBE, expanded as `m · 2^(e−136)` like Mitsuba and the `image` crate; its first
//!   line may name any program after `#?`, as Mitsuba's own `#?RGBE`).
//! * Limits, checked from the header before any texel is allocated: at most [`MAX_TEXELS`]
//!   (2^28) texels and no empty image ([`ImageError::TooLarge`], [`ImageError::Unsupported`]);
//!   the `image` decoders also run under `image::Limits` (`max_alloc` = 16 bytes per texel of
//!   that bound). A header may also claim no more texels than a file of its size can hold in
//!   its format ([`ImageError::Overclaimed`]), since the decoders fill what a short file lacks
//!   (a 718-byte JPEG claiming 16384² decoded, filled, in 5.7 s and 0.8 GB). The bounds, each a
//!   format's densest coding with room to spare: JPEG (Huffman-coded, the only kind read) spends
//!   at least one bit on each 8×8 block of its full-resolution component, so at most 512 texels
//!   a byte: refused past [`JPEG_TEXELS_PER_BYTE`] = 4096; PNG's deflate stores at most 1032
//!   bytes in one (a 258-byte match in two 1-bit codes), so the filtered scanlines
//!   (`height · (1 + ⌈width · bits per texel / 8⌉)`) may be at most [`DEFLATE_RATIO`] × the file;
//!   OpenEXR packs no more than deflate does (RLE 64:1, PIZ about 400:1, B44A about 10:1), a
//!   sample taking at least 2 bytes, so its samples (every layer and channel) may be at most
//!   [`DEFLATE_RATIO`] × the file (twice the densest); a Radiance scanline opens with at least a
//!   4-byte pixel or run header, so the height is at most a quarter of the file (its old run
//!   codes can make a scanline arbitrarily long, so the width is bounded by [`MAX_TEXELS`]
//!   only: a claim the file cannot fill fails at its first missing scanline). The JPEG, PNG and
//!   EXR bounds allow [`CLAIM_SLACK`] more, so tiny files are never refused by them.
//!   Float texels must be finite and non-negative ([`ImageError::BadPixels`] with
//!   the first bad texel's `(x, y)`). Truncated or corrupt files are [`ImageError::Decode`].
//!   Every error names the file; nothing here panics on bad input.

use super::{decode_error, find_channels, io_error, unsupported, ImageError};
use std::io::Cursor;
use std::path::Path;

/// The most texels a texture may have (2^28 = 268 435 456, e.g. 16384 × 16384): about 3 GiB as
/// `f32` RGB. Larger headers are refused before anything is allocated.
pub const MAX_TEXELS: u64 = 1 << 28;

/// The most texels a JPEG may claim per byte of its file (8 times the densest Huffman coding).
pub const JPEG_TEXELS_PER_BYTE: u64 = 4096;

/// The most bytes deflate can store in one (PNG scanlines, OpenEXR samples).
pub const DEFLATE_RATIO: u64 = 1032;

/// What each claim bound allows beyond its ratio (texels, bytes or samples).
pub const CLAIM_SLACK: u64 = 4096;

/// The samples of a [`DecodedImage`], in the file's own encoding.
#[derive(Clone, Debug, PartialEq)]
pub enum TexelData {
    /// 8-bit integer codes (PNG, JPEG): `code / 255` is the stored value.
    U8(Vec<u8>),
    /// 16-bit integer codes (PNG): `code / 65535` is the stored value.
    U16(Vec<u16>),
    /// Linear floats (OpenEXR, Radiance HDR), each finite and `>= 0`.
    F32(Vec<f32>),
}

impl TexelData {
    /// Number of samples.
    pub fn len(&self) -> usize {
        match self {
            TexelData::U8(v) => v.len(),
            TexelData::U16(v) => v.len(),
            TexelData::F32(v) => v.len(),
        }
    }

    /// `true` if there are no samples.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// `true` for integer codes (8- or 16-bit), which a colour texture reads as sRGB-encoded;
    /// `false` for linear floats.
    pub fn is_integer(&self) -> bool {
        !matches!(self, TexelData::F32(_))
    }
}

/// A decoded texture image. Invariant: `data.len() == width * height * channels`, `width` and
/// `height` `>= 1`, `width * height <= MAX_TEXELS`, `channels` 1 or 3.
#[derive(Clone, Debug, PartialEq)]
pub struct DecodedImage {
    /// Width in texels.
    pub width: usize,
    /// Height in texels.
    pub height: usize,
    /// Samples per texel: 1 (grey) or 3 (R, G, B).
    pub channels: usize,
    /// The samples, texel `(x, y)` channel `c` at `(y * width + x) * channels + c`.
    pub data: TexelData,
    /// `"PNG"`, `"JPEG"`, `"HDR"` or `"EXR"`.
    pub format: &'static str,
}

impl DecodedImage {
    /// Texel `(x, y)` as RGB values in the file's scale (integer codes divided by 255 or 65535,
    /// no sRGB decoding; grey replicated), or `None` outside the image.
    pub fn texel(&self, x: usize, y: usize) -> Option<[f32; 3]> {
        if x >= self.width || y >= self.height {
            return None;
        }
        let i = (y * self.width + x) * self.channels;
        let s = |c: usize| {
            let k = i + if self.channels == 1 { 0 } else { c };
            match &self.data {
                TexelData::U8(v) => v[k] as f32 / 255.0,
                TexelData::U16(v) => v[k] as f32 / 65535.0,
                TexelData::F32(v) => v[k],
            }
        };
        Some([s(0), s(1), s(2)])
    }
}

/// Reads and decodes the texture image at `path` (PNG, JPEG, Radiance HDR or OpenEXR, told by
/// its first bytes). See the module documentation for the layout, the limits and the errors.
pub fn decode_texture(path: &Path) -> Result<DecodedImage, ImageError> {
    let bytes = crate::atomic_io::read_regular(path).map_err(|e| io_error(path, "read", e))?;
    decode_texture_bytes(path, &bytes)
}

/// [`decode_texture`] of bytes already read (`path` is named in errors only).
pub fn decode_texture_bytes(path: &Path, bytes: &[u8]) -> Result<DecodedImage, ImageError> {
    let image = if bytes.starts_with(&[0x76, 0x2f, 0x31, 0x01]) {
        decode_exr(path, bytes)?
    } else if bytes.starts_with(b"\x89PNG\r\n\x1a\n") {
        decode_with_image(path, bytes, image::ImageFormat::Png, "PNG")?
    } else if bytes.starts_with(&[0xff, 0xd8]) {
        decode_with_image(path, bytes, image::ImageFormat::Jpeg, "JPEG")?
    } else if bytes.starts_with(b"#?") {
        decode_with_image(path, bytes, image::ImageFormat::Hdr, "HDR")?
    } else {
        return Err(unsupported(
            path,
            "not a texture image this reader knows (PNG, JPEG, Radiance HDR or OpenEXR, told by the first bytes)"
                .into(),
        ));
    };
    if let TexelData::F32(v) = &image.data {
        check_texels(path, image.width, image.channels, v)?;
    }
    Ok(image)
}

/// Refuses a `width`×`height` header: empty, or over [`MAX_TEXELS`].
fn check_size(path: &Path, width: u64, height: u64) -> Result<(), ImageError> {
    if width == 0 || height == 0 {
        return Err(unsupported(path, format!("image of {width}x{height} texels is empty")));
    }
    if width.saturating_mul(height) > MAX_TEXELS {
        return Err(ImageError::TooLarge { path: path.to_path_buf(), width, height, limit: MAX_TEXELS });
    }
    Ok(())
}

/// Refuses a `width`×`height` header (already within [`MAX_TEXELS`]) of the `image` crate's
/// formats claiming more texels than `bytes` can hold (see the module documentation).
fn check_claim(path: &Path, format: &'static str, bytes: &[u8], width: u64, height: u64) -> Result<(), ImageError> {
    let n = bytes.len() as u64;
    let (fits, bound) = match format {
        "JPEG" => (
            width * height <= JPEG_TEXELS_PER_BYTE * n + CLAIM_SLACK,
            format!(
                "a JPEG spends at least a bit on each 8x8 block, so at most 512 texels a byte; \
                 refused past {JPEG_TEXELS_PER_BYTE}"
            ),
        ),
        "PNG" => {
            // IHDR follows the signature: length, "IHDR", width, height, bit depth, colour type
            let depth = bytes.get(24).map_or(1, |&d| d.max(1) as u64);
            let samples = match bytes.get(25) {
                Some(2) => 3,
                Some(4) => 2,
                Some(6) => 4,
                _ => 1,
            };
            let raw = height * (1 + (width * depth * samples).div_ceil(8));
            (
                raw <= DEFLATE_RATIO * n + CLAIM_SLACK,
                format!("{raw} bytes of scanlines, and deflate stores at most {DEFLATE_RATIO} bytes in one"),
            )
        }
        _ => (height <= n / 4, "each Radiance scanline opens with at least a 4-byte pixel or run header".to_string()),
    };
    if fits {
        return Ok(());
    }
    Err(ImageError::Overclaimed { path: path.to_path_buf(), format, width, height, bytes: n, bound })
}

/// Refuses float samples that are NaN, infinite or negative, naming the first such texel.
fn check_texels(path: &Path, width: usize, channels: usize, v: &[f32]) -> Result<(), ImageError> {
    let bad = |t: &[f32]| !t.iter().all(|&s| s.is_finite() && s >= 0.0);
    let mut texels = v.chunks_exact(channels);
    let Some(first) = texels.position(bad) else { return Ok(()) };
    let count = 1 + texels.filter(|t| bad(t)).count();
    let t = &v[first * channels..(first + 1) * channels];
    let value = if channels == 1 { [t[0]; 3] } else { [t[0], t[1], t[2]] };
    let (path, what) = (path.to_path_buf(), "not finite or negative");
    Err(ImageError::BadPixels { path, count, what, first: (first % width, first / width), value })
}

/// PNG, JPEG or Radiance HDR through the `image` crate, its limits set before decoding.
fn decode_with_image(
    path: &Path,
    bytes: &[u8],
    format: image::ImageFormat,
    name: &'static str,
) -> Result<DecodedImage, ImageError> {
    use image::{DynamicImage as D, ImageDecoder};
    let fail = |e: image::ImageError| decode_error(path, name, e);
    // Radiance files may open with any `#?` program name (Mitsuba writes `#?RGBE`); the `image`
    // decoder wants `#?RADIANCE`
    let renamed;
    let bytes = if format == image::ImageFormat::Hdr && !bytes.starts_with(b"#?RADIANCE") {
        let end = bytes.iter().position(|&b| b == b'\n').unwrap_or(bytes.len());
        renamed = [&b"#?RADIANCE"[..], &bytes[end..]].concat();
        &renamed[..]
    } else {
        bytes
    };
    let mut reader = image::ImageReader::with_format(Cursor::new(bytes), format);
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(u32::MAX);
    limits.max_image_height = Some(u32::MAX);
    limits.max_alloc = Some(MAX_TEXELS * 16);
    reader.limits(limits);
    let decoder = reader.into_decoder().map_err(fail)?;
    let (w, h) = decoder.dimensions();
    check_size(path, w as u64, h as u64)?;
    check_claim(path, name, bytes, w as u64, h as u64)?;
    let decoded = D::from_decoder(decoder).map_err(fail)?;
    let (width, height) = (w as usize, h as usize);
    let (channels, data) = match decoded {
        D::ImageLuma8(b) => (1, TexelData::U8(b.into_raw())),
        D::ImageRgb8(b) => (3, TexelData::U8(b.into_raw())),
        d @ D::ImageLumaA8(_) => (1, TexelData::U8(d.into_luma8().into_raw())),
        d @ D::ImageRgba8(_) => (3, TexelData::U8(d.into_rgb8().into_raw())),
        D::ImageLuma16(b) => (1, TexelData::U16(b.into_raw())),
        D::ImageRgb16(b) => (3, TexelData::U16(b.into_raw())),
        d @ D::ImageLumaA16(_) => (1, TexelData::U16(d.into_luma16().into_raw())),
        d @ D::ImageRgba16(_) => (3, TexelData::U16(d.into_rgb16().into_raw())),
        D::ImageRgb32F(b) => (3, TexelData::F32(b.into_raw())),
        d @ D::ImageRgba32F(_) => (3, TexelData::F32(d.into_rgb32f().into_raw())),
        d => return Err(unsupported(path, format!("unsupported {name} pixel type {:?}", d.color()))),
    };
    if data.len() != width * height * channels {
        return Err(unsupported(path, format!("{name} decoder returned {} samples for {w}x{h}", data.len())));
    }
    Ok(DecodedImage { width, height, channels, data, format: name })
}

/// Refuses an OpenEXR from its headers alone, before any sample is decoded: an empty layer, or
/// samples (all layers and channels) more than the file can hold (see the module
/// documentation); with `texture` also a layer over [`MAX_TEXELS`] or samples over four
/// channels' worth of that limit. Every EXR this crate reads passes here first (textures, and
/// `read_exr` of rendered images, which may be larger than a texture): a header claiming
/// billions of samples otherwise keeps the decoder busy for minutes.
pub(crate) fn check_exr_header(path: &Path, bytes: &[u8], texture: bool) -> Result<(), ImageError> {
    let meta =
        exr::meta::MetaData::read_from_buffered(Cursor::new(bytes), false).map_err(|e| decode_error(path, "EXR", e))?;
    let mut total: u64 = 0;
    for header in meta.headers.iter() {
        let (w, h) = (header.layer_size.width() as u64, header.layer_size.height() as u64);
        if texture {
            check_size(path, w, h)?;
        } else if w == 0 || h == 0 {
            return Err(unsupported(path, format!("image of {w}x{h} pixels is empty")));
        }
        total = total.saturating_add(w.saturating_mul(h).saturating_mul(header.channels.list.len() as u64));
    }
    // every layer is read whole: bound the sum as four channels' worth of the texel limit
    if texture && total > 4 * MAX_TEXELS {
        let (w, h) = meta.headers.first().map_or((0, 0), |h| (h.layer_size.width(), h.layer_size.height()));
        return Err(ImageError::TooLarge {
            path: path.to_path_buf(),
            width: w as u64,
            height: h as u64,
            limit: MAX_TEXELS,
        });
    }
    // no EXR compression packs more than deflate, a sample taking at least 2 bytes
    let n = bytes.len() as u64;
    if total > DEFLATE_RATIO * n + CLAIM_SLACK {
        let (w, h) = meta.headers.first().map_or((0, 0), |h| (h.layer_size.width(), h.layer_size.height()));
        return Err(ImageError::Overclaimed {
            path: path.to_path_buf(),
            format: "EXR",
            width: w as u64,
            height: h as u64,
            bytes: n,
            bound: format!(
                "{total} samples, and no EXR compression stores more than {DEFLATE_RATIO} bytes in one, \
                 a sample taking at least 2"
            ),
        });
    }
    Ok(())
}

/// OpenEXR: the header's sizes are checked first, then the `R`, `G`, `B` channels of the first
/// layer that has them (or a lone `Y` of the first layer) are read as `f32`.
fn decode_exr(path: &Path, bytes: &[u8]) -> Result<DecodedImage, ImageError> {
    check_exr_header(path, bytes, true)?;
    let layers = &super::read_exr_layers(path, bytes)?;
    let rgb = layers.iter().find_map(|l| find_channels(l, &["R", "G", "B"]).map(|i| (l, i)));
    let (layer, idx) = rgb
        .or_else(|| layers.first().and_then(|l| find_channels(l, &["Y"]).map(|i| (l, i))))
        .ok_or_else(|| unsupported(path, "EXR has no layer with R, G, B or Y channels".into()))?;
    let (width, height) = (layer.size.width(), layer.size.height());
    check_size(path, width as u64, height as u64)?;
    let planes: Vec<Vec<f32>> =
        idx.iter().map(|&i| layer.channel_data.list[i].sample_data.values_as_f32().collect()).collect();
    if planes.iter().any(|p| p.len() != width * height) {
        return Err(unsupported(
            path,
            format!("channel sample count does not match {width}x{height} (subsampled channels?)"),
        ));
    }
    let channels = planes.len();
    let mut data = Vec::with_capacity(width * height * channels);
    for i in 0..width * height {
        data.extend(planes.iter().map(|p| p[i]));
    }
    Ok(DecodedImage { width, height, channels, data: TexelData::F32(data), format: "EXR" })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::image_io::{write_exr, Image};
    use std::path::PathBuf;

    fn data(name: &str) -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/texture").join(name)
    }

    /// A fresh directory under the system's temporary directory, unique to this test run.
    fn tmpdir(name: &str) -> PathBuf {
        let nanos = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_nanos());
        let d = std::env::temp_dir().join(format!("forecast-decode-{name}-{}-{nanos}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    /// Writes `bytes` to `dir/name` and decodes it; the error must name the file.
    fn decode_err(dir: &Path, name: &str, bytes: &[u8]) -> ImageError {
        let p = dir.join(name);
        std::fs::write(&p, bytes).unwrap();
        let e = decode_texture(&p).expect_err(name);
        assert!(e.to_string().contains(&p.display().to_string()), "{name}: {e}");
        e
    }

    fn png_chunk(kind: &[u8; 4], body: &[u8]) -> Vec<u8> {
        let mut out = (body.len() as u32).to_be_bytes().to_vec();
        let mut typed = kind.to_vec();
        typed.extend_from_slice(body);
        out.extend_from_slice(&typed);
        out.extend_from_slice(&crc32fast::hash(&typed).to_be_bytes());
        out
    }

    #[test]
    fn decodes_the_committed_images() {
        let rgb8 = decode_texture(&data("rgb8.png")).unwrap();
        assert_eq!((rgb8.width, rgb8.height, rgb8.channels, rgb8.format), (5, 4, 3, "PNG"));
        assert!(matches!(rgb8.data, TexelData::U8(_)) && rgb8.data.is_integer());
        assert_eq!(rgb8.texel(0, 0), Some([1.0, 0.0, 128.0 / 255.0]));
        assert_eq!(rgb8.texel(5, 0), None);
        let grey = decode_texture(&data("grey8.png")).unwrap();
        assert_eq!((grey.width, grey.height, grey.channels), (3, 2, 1));
        // texel (x, y) = (97x + 41y + 5) mod 256
        assert_eq!(grey.texel(2, 1), Some([(199.0 + 41.0) / 255.0; 3]));
        let x16 = decode_texture(&data("rgb16.png")).unwrap();
        assert_eq!((x16.width, x16.height, x16.channels), (4, 3, 3));
        assert!(matches!(x16.data, TexelData::U16(_)));
        // texel (x, y) channel c = (9973x + 21011y + 7919c + 3) mod 65536
        let v = |x: u32, y: u32, c: u32| ((x * 9973 + y * 21011 + c * 7919 + 3) % 65536) as f32 / 65535.0;
        assert_eq!(x16.texel(3, 2), Some([v(3, 2, 0), v(3, 2, 1), v(3, 2, 2)]));
        let exr = decode_texture(&data("rgb.exr")).unwrap();
        assert_eq!((exr.width, exr.height, exr.channels, exr.format), (4, 3, 3, "EXR"));
        assert_eq!(exr.texel(2, 1), Some([0.0, 0.015625, 5.5]));
        assert!(!exr.data.is_integer());
        let grey_exr = decode_texture(&data("grey.exr")).unwrap();
        assert_eq!((grey_exr.width, grey_exr.height, grey_exr.channels), (3, 2, 1));
        assert_eq!(grey_exr.texel(2, 1), Some([(10.0 + 3.0 + 1.0) / 4.0; 3]));
        let hdr = decode_texture(&data("rgb.hdr")).unwrap();
        assert_eq!((hdr.width, hdr.height, hdr.channels, hdr.format), (3, 3, 3, "HDR"));
        let want = |x: usize, y: usize, c: usize| (x + 2 * y + c + 1) as f32 * 0.37;
        let got = hdr.texel(1, 2).unwrap();
        for c in 0..3 {
            // RGBE keeps 8 bits of mantissa
            assert!((got[c] - want(1, 2, c)).abs() <= want(1, 2, c) / 128.0, "{got:?}");
        }
        let jpg = decode_texture(&data("rgb8.jpg")).unwrap();
        assert_eq!((jpg.width, jpg.height, jpg.channels, jpg.format), (32, 24, 3, "JPEG"));
        let bytes = |x, y| jpg.texel(x, y).unwrap().map(|v| (v * 255.0).round() as u8);
        assert_eq!((bytes(3, 3), bytes(12, 20)), ([40, 200, 90], [100, 100, 30]));
    }

    #[test]
    fn bad_files_are_errors_that_name_the_file() {
        let d = tmpdir("bad");
        let png = std::fs::read(data("rgb8.png")).unwrap();
        let e = decode_err(&d, "truncated.png", &png[..png.len() / 2]);
        assert!(matches!(e, ImageError::Decode { format: "PNG", .. }), "{e:?}");
        let e = decode_err(&d, "only-signature.png", &png[..8]);
        assert!(matches!(e, ImageError::Decode { format: "PNG", .. }), "{e:?}");

        let jpg = std::fs::read(data("rgb8.jpg")).unwrap();
        let mut corrupt = jpg[..jpg.len() * 2 / 3].to_vec();
        corrupt[2..40].fill(0xa5); // the first segment's marker and body
        let e = decode_err(&d, "corrupt.jpg", &corrupt);
        assert!(matches!(e, ImageError::Decode { format: "JPEG", .. }), "{e:?}");
        decode_err(&d, "truncated.jpg", &jpg[..jpg.len() / 3]);

        let exr = std::fs::read(data("rgb.exr")).unwrap();
        for cut in [exr.len() * 3 / 5, exr.len() - 10, 20] {
            let e = decode_err(&d, "truncated.exr", &exr[..cut]);
            assert!(matches!(e, ImageError::Decode { format: "EXR", .. }), "{cut}: {e:?}");
        }

        let e = decode_err(&d, "garbage.hdr", b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 4 +X oops\n\x01\x02\x03");
        assert!(matches!(e, ImageError::Decode { format: "HDR", .. }), "{e:?}");
        let e = decode_err(&d, "short.hdr", b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 4 +X 4\n\x80\x80\x80\x81");
        assert!(matches!(e, ImageError::Decode { format: "HDR", .. }), "{e:?}");

        let e = decode_err(&d, "unknown.png", b"GIF89a not a texture");
        assert!(matches!(e, ImageError::Unsupported { .. }), "{e:?}");
        let e = decode_err(&d, "empty.png", b"");
        assert!(matches!(e, ImageError::Unsupported { .. }), "{e:?}");
        let e = decode_texture(&d.join("missing.exr")).unwrap_err();
        assert!(matches!(e, ImageError::Io { action: "read", .. }) && e.to_string().contains("missing.exr"), "{e}");
        let _ = std::fs::remove_dir_all(d);
    }

    #[test]
    fn huge_headers_are_refused_before_allocating() {
        let d = tmpdir("huge");
        // a valid PNG signature and IHDR claiming 100000 x 100000 RGB, then an empty IDAT
        let mut ihdr = Vec::new();
        ihdr.extend_from_slice(&100_000u32.to_be_bytes());
        ihdr.extend_from_slice(&100_000u32.to_be_bytes());
        ihdr.extend_from_slice(&[8, 2, 0, 0, 0]);
        let mut png = b"\x89PNG\r\n\x1a\n".to_vec();
        png.extend(png_chunk(b"IHDR", &ihdr));
        png.extend(png_chunk(b"IDAT", &[0x78, 0x9c, 0x03, 0x00, 0x00, 0x00, 0x00, 0x01]));
        png.extend(png_chunk(b"IEND", &[]));
        let e = decode_err(&d, "huge.png", &png);
        assert!(matches!(e, ImageError::TooLarge { width: 100_000, height: 100_000, .. }), "{e:?}");
        assert!(e.to_string().contains("100000x100000") && e.to_string().contains(&MAX_TEXELS.to_string()), "{e}");

        let e = decode_err(&d, "huge.hdr", b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 100000 +X 100000\n\x02\x02");
        assert!(matches!(e, ImageError::TooLarge { .. }), "{e:?}");

        // the committed JPEG with its frame header (SOF0) patched to 65535 x 65535
        let mut jpg = std::fs::read(data("rgb8.jpg")).unwrap();
        let sof = jpg.windows(2).position(|w| w == [0xff, 0xc0]).expect("baseline JPEG");
        jpg[sof + 5..sof + 9].copy_from_slice(&[0xff, 0xff, 0xff, 0xff]);
        let e = decode_err(&d, "huge.jpg", &jpg);
        assert!(matches!(e, ImageError::TooLarge { width: 65535, height: 65535, .. }), "{e:?}");

        // an EXR whose data window claims 100000 x 100000 (the display window left as it was)
        let mut exr = std::fs::read(data("rgb.exr")).unwrap();
        let at = exr.windows(10).position(|w| w == b"dataWindow").unwrap();
        let body = at + b"dataWindow\0box2i\0".len() + 4; // name, type, size
        exr[body + 8..body + 16]
            .copy_from_slice(&[&99_999i32.to_le_bytes()[..], &99_999i32.to_le_bytes()[..]].concat());
        let e = decode_err(&d, "huge.exr", &exr);
        assert!(matches!(e, ImageError::TooLarge { width: 100_000, height: 100_000, .. }), "{e:?}");
        let _ = std::fs::remove_dir_all(d);
    }

    /// Headers within [`MAX_TEXELS`] but claiming more texels than their files can hold are
    /// refused at once (the 718-byte JPEG claiming 16384² took 5.7 s and 0.8 GB filled); dense
    /// but real files of the same formats still decode.
    #[test]
    fn headers_claiming_more_than_the_file_holds_are_refused_at_once() {
        let d = tmpdir("claim");
        let started = std::time::Instant::now();
        let mut jpg = std::fs::read(data("rgb8.jpg")).unwrap();
        assert_eq!(jpg.len(), 718);
        let sof = jpg.windows(2).position(|w| w == [0xff, 0xc0]).expect("baseline JPEG");
        for side in [16384u16, 4096, 2048] {
            jpg[sof + 5..sof + 9].copy_from_slice(&[&side.to_be_bytes()[..], &side.to_be_bytes()[..]].concat());
            let e = decode_err(&d, "claims.jpg", &jpg);
            let s = side as u64;
            assert!(
                matches!(e, ImageError::Overclaimed { format: "JPEG", width, height, bytes: 718, .. } if (width, height) == (s, s)),
                "{e:?}"
            );
            assert!(
                e.to_string().contains(&format!("claims {side}x{side} texels")) && e.to_string().contains("718 bytes"),
                "{e}"
            );
        }
        // 718 bytes hold 718 * 4096 + 4096 texels at most: 1700 x 1700 is read (and filled)
        jpg[sof + 5..sof + 9].copy_from_slice(&[&1700u16.to_be_bytes()[..], &1700u16.to_be_bytes()[..]].concat());
        let p = d.join("filled.jpg");
        std::fs::write(&p, &jpg).unwrap();
        assert!(!matches!(decode_texture(&p), Err(ImageError::Overclaimed { .. })));

        // a PNG claiming 16384 x 16384 RGB with an empty IDAT
        let mut ihdr = Vec::new();
        ihdr.extend_from_slice(&16384u32.to_be_bytes());
        ihdr.extend_from_slice(&16384u32.to_be_bytes());
        ihdr.extend_from_slice(&[8, 2, 0, 0, 0]);
        let mut png = b"\x89PNG\r\n\x1a\n".to_vec();
        png.extend(png_chunk(b"IHDR", &ihdr));
        png.extend(png_chunk(b"IDAT", &[0x78, 0x9c, 0x03, 0x00, 0x00, 0x00, 0x00, 0x01]));
        png.extend(png_chunk(b"IEND", &[]));
        let e = decode_err(&d, "claims.png", &png);
        assert!(matches!(e, ImageError::Overclaimed { format: "PNG", width: 16384, height: 16384, .. }), "{e:?}");

        let e = decode_err(&d, "claims.hdr", b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 16384 +X 16384\n\x02\x02");
        assert!(matches!(e, ImageError::Overclaimed { format: "HDR", height: 16384, .. }), "{e:?}");

        let mut exr = std::fs::read(data("rgb.exr")).unwrap();
        let at = exr.windows(10).position(|w| w == b"dataWindow").unwrap();
        let body = at + b"dataWindow\0box2i\0".len() + 4;
        exr[body + 8..body + 16].copy_from_slice(&[&4095i32.to_le_bytes()[..], &4095i32.to_le_bytes()[..]].concat());
        let e = decode_err(&d, "claims.exr", &exr);
        assert!(matches!(e, ImageError::Overclaimed { format: "EXR", width: 4096, height: 4096, .. }), "{e:?}");
        let secs = started.elapsed().as_secs_f64();
        assert!(secs < 2.0, "the refusals took {secs:.2} s");

        // real files near the densest codings still decode: a uniform 2048 x 2048 PNG and EXR
        let (w, h) = (2048, 2048);
        let png = crate::image_io::encode_png_rgb8(w, h, &vec![7u8; w * h * 3]).unwrap();
        let p = d.join("uniform.png");
        std::fs::write(&p, &png).unwrap();
        let img = decode_texture(&p).unwrap_or_else(|e| panic!("{} bytes: {e}", png.len()));
        assert_eq!((img.width, img.height, img.texel(5, 9)), (w, h, Some([7.0 / 255.0; 3])));
        let p = d.join("uniform.exr");
        write_exr(&p, &Image::from_fn(w, h, |_, _| [0.25; 3])).unwrap();
        let img = decode_texture(&p).unwrap();
        assert_eq!((img.width, img.texel(3, 4)), (w, Some([0.25; 3])));
        let _ = std::fs::remove_dir_all(d);
    }

    #[test]
    fn nan_infinite_and_negative_texels_are_refused_with_their_position() {
        let d = tmpdir("texels");
        for (name, value, what) in
            [("nan.exr", f32::NAN, "NaN"), ("inf.exr", f32::INFINITY, "inf"), ("neg.exr", -0.5, "-0.5")]
        {
            let img = Image::from_fn(4, 3, |x, y| if (x, y) == (2, 1) { [0.1, value, 0.2] } else { [0.5; 3] });
            let p = d.join(name);
            write_exr(&p, &img).unwrap();
            let e = decode_texture(&p).unwrap_err();
            let msg = e.to_string();
            assert!(matches!(e, ImageError::BadPixels { count: 1, first: (2, 1), .. }), "{e:?}");
            assert!(msg.contains(&p.display().to_string()) && msg.contains("(2, 1)") && msg.contains(what), "{msg}");
        }
        let _ = std::fs::remove_dir_all(d);
    }

    /// Every prefix of every committed image, and each with bytes overwritten at many places,
    /// decodes or fails: never a panic.
    #[test]
    fn truncated_and_damaged_files_never_panic() {
        let p = Path::new("damaged");
        for name in ["rgb8.png", "grey8.png", "rgb16.png", "rgb.exr", "grey.exr", "rgb.hdr", "rgb8.jpg"] {
            let bytes = std::fs::read(data(name)).unwrap();
            for cut in 0..bytes.len() {
                let _ = decode_texture_bytes(p, &bytes[..cut]);
            }
            let mut state = 0x2545_f491_4f6c_dd1du64;
            for _ in 0..300 {
                let mut b = bytes.clone();
                for _ in 0..3 {
                    state ^= state << 13;
                    state ^= state >> 7;
                    state ^= state << 17;
                    let i = (state % b.len() as u64) as usize;
                    b[i] = (state >> 32) as u8;
                }
                if let Ok(img) = decode_texture_bytes(p, &b) {
                    let c = img.channels;
                    assert!(img.width * img.height * c == img.data.len() && (c == 1 || c == 3), "{name}");
                }
            }
        }
    }
}
