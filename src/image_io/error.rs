//! `ImageError`: what went wrong reading, writing or shaping an image, with the file and the
//! figures its message names (`Display` is the message).

use crate::atomic_io::AtomicIoError;
use std::path::{Path, PathBuf};

/// What went wrong reading, writing or shaping an image; each variant keeps the file (where
/// there is one) and the figures its message names. `Display` is the message.
#[derive(Debug)]
pub enum ImageError {
    /// A pixel vector whose length is not `width * height` ([`Image::from_pixels`]).
    PixelCount {
        /// Width asked for.
        width: usize,
        /// Height asked for.
        height: usize,
        /// Pixels given.
        pixels: usize,
    },
    /// A crop rectangle `(x, y, w, h)` that is empty or leaves the `width`×`height` image.
    Crop {
        /// The rectangle asked for: left, top, width, height.
        rect: (usize, usize, usize, usize),
        /// The image's width.
        width: usize,
        /// The image's height.
        height: usize,
    },
    /// Two images that must have the same size do not ([`check_same_size`]).
    SizeMismatch {
        /// The first image's file and `(width, height)`.
        first: (PathBuf, (usize, usize)),
        /// The first image of another size: its file and `(width, height)`.
        other: (PathBuf, (usize, usize)),
    },
    /// An image to write that is empty or whose pixel count does not match its size.
    Malformed {
        /// File it was to be written to.
        path: PathBuf,
        /// Width.
        width: usize,
        /// Height.
        height: usize,
        /// Pixels it holds.
        pixels: usize,
    },
    /// A variance image whose size is not the colour image's.
    VarianceSize {
        /// File they were to be written to.
        path: PathBuf,
        /// The variance image's `(width, height)`.
        variance: (usize, usize),
        /// The colour image's `(width, height)`.
        colour: (usize, usize),
    },
    /// The file cannot be opened or read, or its directory created (`cannot open`, `cannot
    /// read`, `cannot create`).
    Io {
        /// File (or directory) concerned.
        path: PathBuf,
        /// `"open"`, `"read"` or `"create"`, as the message words it.
        action: &'static str,
        /// The I/O error.
        source: std::io::Error,
    },
    /// The bytes are not a valid file of `format` (`"EXR"`, `"PNG"`).
    Decode {
        /// File concerned.
        path: PathBuf,
        /// `"EXR"` or `"PNG"`.
        format: &'static str,
        /// The decoder's message.
        reason: String,
    },
    /// The file decodes but holds no image this reader takes (no colour channels, subsampled
    /// channels, not 8-bit, ...).
    Unsupported {
        /// File concerned.
        path: PathBuf,
        /// What it holds instead.
        reason: String,
    },
    /// Pixels with a value that is refused (not finite; a negative variance).
    BadPixels {
        /// File concerned.
        path: PathBuf,
        /// How many pixels.
        count: usize,
        /// What is wrong with them, in words (`not finite`).
        what: &'static str,
        /// The first one, `(x, y)`.
        first: (usize, usize),
        /// Its value.
        value: [f32; 3],
    },
    /// A texture header whose `width * height` exceeds `limit` texels
    /// ([`super::MAX_TEXELS`]); refused before anything is allocated.
    TooLarge {
        /// File concerned.
        path: PathBuf,
        /// Width the header claims.
        width: u64,
        /// Height the header claims.
        height: u64,
        /// The most texels allowed.
        limit: u64,
    },
    /// A texture header claiming more texels than a file of its size can hold in its format
    /// (decoders would fill the rest); refused before anything is allocated.
    Overclaimed {
        /// File concerned.
        path: PathBuf,
        /// `"PNG"`, `"JPEG"`, `"HDR"` or `"EXR"`.
        format: &'static str,
        /// Width the header claims.
        width: u64,
        /// Height the header claims.
        height: u64,
        /// The file's size in bytes.
        bytes: u64,
        /// The format's bound, in words.
        bound: String,
    },
    /// Encoding failed: the EXR encoder's message (`path` always given), or a PNG's (raw RGB
    /// bytes that do not fit the size, a size PNG cannot hold, the encoder's message), with the
    /// file when the caller named one ([`ImageError::in_file`]).
    Encode {
        /// File the bytes were for, if named.
        path: Option<PathBuf>,
        /// `"EXR"` or `"PNG"`.
        format: &'static str,
        /// What went wrong.
        reason: String,
    },
    /// The file (or the set of files) could not be written: `atomic_io`'s error, which names the
    /// file.
    Write(AtomicIoError),
}

impl ImageError {
    /// This error, for bytes meant for `path` (a PNG's encoding error gains the file name).
    pub fn in_file(self, path: &Path) -> ImageError {
        match self {
            ImageError::Encode { path: None, format, reason } => {
                ImageError::Encode { path: Some(path.to_path_buf()), format, reason }
            }
            e => e,
        }
    }
}

impl std::fmt::Display for ImageError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        use ImageError::*;
        match self {
            PixelCount { width, height, pixels } => {
                write!(f, "image of {width}x{height} needs {} pixels, got {pixels}", width.saturating_mul(*height))
            }
            Crop { rect: (x, y, w, h), width, height } => {
                write!(f, "crop {x},{y},{w},{h} is empty or outside the {width}x{height} image")
            }
            SizeMismatch { first: (p0, (w0, h0)), other: (p, (w, h)) } => write!(
                f,
                "{} is {w0}x{h0} but {} is {w}x{h}: the images must have the same size",
                p0.display(),
                p.display()
            ),
            Malformed { path, width, height, pixels } => write!(
                f,
                "{}: image {width}x{height} has {pixels} pixels (must be non-empty and match)",
                path.display()
            ),
            VarianceSize { path, variance: (vw, vh), colour: (w, h) } => {
                write!(f, "{}: variance image is {vw}x{vh}, colour image is {w}x{h}", path.display())
            }
            Io { path, action, source } => write!(f, "cannot {action} {}: {source}", path.display()),
            Decode { path, format, reason } => write!(f, "cannot decode {format} {}: {reason}", path.display()),
            Unsupported { path, reason } => write!(f, "{}: {reason}", path.display()),
            BadPixels { path, count, what, first: (x, y), value } => {
                write!(f, "{}: {count} pixel(s) {what}, the first at ({x}, {y}): {value:?}", path.display())
            }
            TooLarge { path, width, height, limit } => write!(
                f,
                "{}: image of {width}x{height} texels is larger than the {limit} texels a texture may have",
                path.display()
            ),
            Overclaimed { path, format, width, height, bytes, bound } => write!(
                f,
                "{}: the {format} header claims {width}x{height} texels, more than its {bytes} bytes can hold ({bound})",
                path.display()
            ),
            Encode { path: Some(path), format: "EXR", reason } => {
                write!(f, "cannot encode EXR {}: {reason}", path.display())
            }
            Encode { path: Some(path), reason, .. } => write!(f, "{}: {reason}", path.display()),
            Encode { path: None, reason, .. } => write!(f, "{reason}"),
            Write(e) => write!(f, "{e}"),
        }
    }
}

impl std::error::Error for ImageError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            ImageError::Io { source, .. } => Some(source),
            ImageError::Write(e) => Some(e),
            _ => None,
        }
    }
}

impl From<AtomicIoError> for ImageError {
    fn from(e: AtomicIoError) -> ImageError {
        ImageError::Write(e)
    }
}

/// For the callers whose own errors are still messages.
impl From<ImageError> for String {
    fn from(e: ImageError) -> String {
        e.to_string()
    }
}
