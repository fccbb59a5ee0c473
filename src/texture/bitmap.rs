//! Mitsuba's `bitmap` texture: [`TexelImage`] (an image file's texels, decoded once, linear),
//! [`Bitmap`] (one use of it: `filter_type`, `wrap_mode`, `to_uv`) and [`TextureCache`] (one
//! decoded image per file and `raw` flag). The conventions are in the module header
//! (`texture/mod.rs`).

use super::{luminance, UvTransform};
use crate::image_io::{decode_texture, DecodedImage, ImageError, TexelData};
use crate::math::{Rgb, Vec2};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Mitsuba's `filter_type`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum FilterType {
    /// `bilinear` (the default): blends the four nearest texel centres.
    #[default]
    Bilinear,
    /// `nearest`: the texel that contains the point.
    Nearest,
}

impl FilterType {
    /// From Mitsuba's name (`bilinear`, `nearest`); the error lists the names.
    pub fn parse(name: &str) -> Result<FilterType, String> {
        match name {
            "bilinear" => Ok(FilterType::Bilinear),
            "nearest" => Ok(FilterType::Nearest),
            _ => Err(format!("invalid filter_type \"{name}\", must be one of: \"nearest\", \"bilinear\"")),
        }
    }

    /// Mitsuba's name.
    pub fn name(self) -> &'static str {
        match self {
            FilterType::Bilinear => "bilinear",
            FilterType::Nearest => "nearest",
        }
    }
}

/// Mitsuba's `wrap_mode`, applied to integer texel indices.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum WrapMode {
    /// `repeat` (the default): `i mod n`.
    #[default]
    Repeat,
    /// `mirror`: reflected with period `2n`, the edge texel repeated (`-1 → 0`, `n → n-1`).
    Mirror,
    /// `clamp`: `clamp(i, 0, n - 1)`.
    Clamp,
}

impl WrapMode {
    /// From Mitsuba's name (`repeat`, `mirror`, `clamp`); the error lists the names.
    pub fn parse(name: &str) -> Result<WrapMode, String> {
        match name {
            "repeat" => Ok(WrapMode::Repeat),
            "mirror" => Ok(WrapMode::Mirror),
            "clamp" => Ok(WrapMode::Clamp),
            _ => Err(format!("invalid wrap_mode \"{name}\", must be one of: \"repeat\", \"mirror\", \"clamp\"")),
        }
    }

    /// Mitsuba's name.
    pub fn name(self) -> &'static str {
        match self {
            WrapMode::Repeat => "repeat",
            WrapMode::Mirror => "mirror",
            WrapMode::Clamp => "clamp",
        }
    }

    /// The index in `0..n` that texel index `i` reads (`n >= 1`).
    #[inline]
    pub fn wrap(self, i: i64, n: usize) -> usize {
        let n = n as i64;
        (match self {
            WrapMode::Repeat => i.rem_euclid(n),
            WrapMode::Clamp => i.clamp(0, n - 1),
            WrapMode::Mirror => {
                let m = i.rem_euclid(2 * n);
                if m < n {
                    m
                } else {
                    2 * n - 1 - m
                }
            }
        }) as usize
    }
}

/// How the texels are held.
#[derive(Clone, Debug)]
enum Store {
    /// 8-bit codes and the linear value of each code (sRGB-decoded unless `raw`), decoded on
    /// lookup like Mitsuba's 8-bit storage.
    Codes { codes: Vec<u8>, table: Box<[f32; 256]> },
    /// Linear floats (16-bit codes are decoded to these when loaded).
    Linear(Vec<f32>),
}

/// The texels of one image file, linear, shared by every [`Bitmap`] that reads it. Invariants:
/// `width, height >= 1`; `channels` 1 or 3; `width * height * channels` samples; every decoded
/// value finite and `>= 0`.
#[derive(Clone, Debug)]
pub struct TexelImage {
    path: PathBuf,
    raw: bool,
    width: usize,
    height: usize,
    channels: usize,
    srgb: bool,
    store: Store,
    mean: f32,
    /// `content_hash`, computed once when decoded (on the decoding's thread).
    hash: u64,
}

/// sRGB-encoded value in `[0, 1]` to linear, the exact curve (IEC 61966-2-1), in `f64`.
pub fn srgb_to_linear(c: f64) -> f64 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

impl TexelImage {
    /// Decodes the image at `path` ([`decode_texture`]); `raw` keeps 8-/16-bit codes linear
    /// (`code / max`) instead of sRGB-decoding them (float images are linear either way).
    pub fn load(path: &Path, raw: bool) -> Result<TexelImage, ImageError> {
        TexelImage::from_decoded(path, decode_texture(path)?, raw)
    }

    /// From an image already decoded (`path` is kept for messages and [`TexelImage::path`]).
    /// Errors if the image breaks [`DecodedImage`]'s invariants or holds a float that is not
    /// finite or is negative.
    pub fn from_decoded(path: &Path, image: DecodedImage, raw: bool) -> Result<TexelImage, ImageError> {
        let DecodedImage { width, height, channels, data, .. } = image;
        let bad = |reason: String| ImageError::Unsupported { path: path.to_path_buf(), reason };
        if width == 0 || height == 0 || !(channels == 1 || channels == 3) {
            return Err(bad(format!("texture of {width}x{height} texels with {channels} channels")));
        }
        if width.checked_mul(height).and_then(|n| n.checked_mul(channels)) != Some(data.len()) {
            return Err(bad(format!("{} samples for {width}x{height}x{channels}", data.len())));
        }
        let srgb = !raw && data.is_integer();
        let curve = |c: f64| if srgb { srgb_to_linear(c) } else { c };
        let store = match data {
            TexelData::U8(codes) => {
                let table: Box<[f32; 256]> = Box::new(std::array::from_fn(|i| curve(i as f64 / 255.0) as f32));
                Store::Codes { codes, table }
            }
            TexelData::U16(codes) => Store::Linear(codes.iter().map(|&c| curve(c as f64 / 65535.0) as f32).collect()),
            TexelData::F32(v) => {
                if let Some(i) = v.iter().position(|s| !(s.is_finite() && *s >= 0.0)) {
                    let (x, y) = ((i / channels) % width, (i / channels) / width);
                    return Err(bad(format!("texel ({x}, {y}) is {} (not finite or negative)", v[i])));
                }
                Store::Linear(v)
            }
        };
        let mut image =
            TexelImage { path: path.to_path_buf(), raw, width, height, channels, srgb, store, mean: 0.0, hash: 0 };
        image.mean = image.compute_mean();
        image.hash = image.compute_hash();
        Ok(image)
    }

    /// Mitsuba's mean: of the luminance ([`super::LUMINANCE`]) of each texel, or of the one
    /// channel; summed in `f64`.
    fn compute_mean(&self) -> f32 {
        // the texels in row-major order, as `texel` reads them, without its per-texel check
        let value = |t: Rgb| if self.channels == 1 { t.x as f64 } else { luminance(t) as f64 };
        let n = self.width * self.height;
        let sum = (0..n).fold(0.0, |s, k| s + value(self.decode(k * self.channels)));
        (sum / n as f64) as f32
    }

    /// Linear texel `(x, y)` (grey replicated to RGB). `x < width`, `y < height`, else it
    /// panics like slice indexing (the evaluators only pass wrapped indices).
    #[inline]
    pub fn texel(&self, x: usize, y: usize) -> Rgb {
        assert!(x < self.width && y < self.height, "texel ({x}, {y}) outside {}x{}", self.width, self.height);
        self.decode(self.sample_index(x, y))
    }

    /// The store's index of texel `(x, y)`'s first sample: where `texel` reads and
    /// `prefetch_texel` fetches.
    #[inline(always)]
    fn sample_index(&self, x: usize, y: usize) -> usize {
        (y * self.width + x) * self.channels
    }

    /// The address of texel `(x, y)`'s first sample, the byte `texel(x, y)` reads first (not
    /// dereferenced here: any `x`, `y` give some address).
    #[inline(always)]
    pub fn texel_address(&self, x: usize, y: usize) -> *const u8 {
        let i = self.sample_index(x, y);
        match &self.store {
            Store::Codes { codes, .. } => codes.as_ptr().wrapping_add(i),
            Store::Linear(v) => v.as_ptr().wrapping_add(i) as *const u8,
        }
    }

    /// Asks the cache for texel `(x, y)`'s line ([`super::prefetch`]): no effect on any value.
    #[inline(always)]
    pub fn prefetch_texel(&self, x: usize, y: usize) {
        super::prefetch(self.texel_address(x, y));
    }

    /// The linear texel whose first sample is sample `i` of the store: the one decoding.
    #[inline(always)]
    fn decode(&self, i: usize) -> Rgb {
        match &self.store {
            Store::Codes { codes, table } => {
                if self.channels == 1 {
                    Rgb::splat(table[codes[i] as usize])
                } else {
                    Rgb::new(table[codes[i] as usize], table[codes[i + 1] as usize], table[codes[i + 2] as usize])
                }
            }
            Store::Linear(v) => {
                if self.channels == 1 {
                    Rgb::splat(v[i])
                } else {
                    Rgb::new(v[i], v[i + 1], v[i + 2])
                }
            }
        }
    }

    /// Width in texels.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Height in texels.
    pub fn height(&self) -> usize {
        self.height
    }

    /// 1 (grey) or 3 (RGB).
    pub fn channels(&self) -> usize {
        self.channels
    }

    /// The file it was read from, as given to [`TexelImage::load`] (the cache gives the
    /// canonical path).
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// A hash of what it holds (size, channels, decoding and every texel): a changed image is
    /// another scene for `--resume` and MPI's job identity (`Scene::hash`).
    pub fn content_hash(&self) -> u64 {
        self.hash
    }

    /// `content_hash`'s value: FNV-1a over the sizes, then the codes and their table or the
    /// linear samples.
    fn compute_hash(&self) -> u64 {
        let dims = [self.width as u64, self.height as u64, self.channels as u64, self.srgb as u64];
        let mut h = crate::math::fnv1a(0xcbf2_9ce4_8422_2325, &dims.map(u64::to_le_bytes).concat());
        match &self.store {
            Store::Codes { codes, table } => {
                h = crate::math::fnv1a(h, codes);
                table.iter().fold(h, |h, v| crate::math::fnv1a(h, &v.to_le_bytes()))
            }
            Store::Linear(v) => v.iter().fold(h, |h, x| crate::math::fnv1a(h, &x.to_le_bytes())),
        }
    }

    /// The `raw` flag it was decoded with.
    pub fn raw(&self) -> bool {
        self.raw
    }

    /// `true` if its integer codes were sRGB-decoded (an 8-/16-bit image without `raw`).
    pub fn is_srgb(&self) -> bool {
        self.srgb
    }

    /// Mitsuba's `mean()` of a bitmap of this image: the mean luminance of its texels (one
    /// channel: their mean).
    pub fn mean(&self) -> f32 {
        self.mean
    }

    /// Bytes this image holds in memory: its texels (1 byte a sample for 8-bit images, plus the
    /// 1 KiB code table; 4 bytes a sample otherwise, 16-bit images included) and the struct.
    pub fn memory_bytes(&self) -> usize {
        let texels = match &self.store {
            Store::Codes { codes, table } => codes.len() + std::mem::size_of_val(&**table),
            Store::Linear(v) => v.len() * std::mem::size_of::<f32>(),
        };
        texels + std::mem::size_of::<TexelImage>() + self.path.as_os_str().len()
    }
}

/// Mitsuba's `bitmap` texture: an image and how it is read. Any combination of fields is valid.
#[derive(Clone, Debug)]
pub struct Bitmap {
    /// The texels (shared).
    pub image: Arc<TexelImage>,
    /// `filter_type`.
    pub filter_type: FilterType,
    /// `wrap_mode`.
    pub wrap_mode: WrapMode,
    /// `to_uv`.
    pub to_uv: UvTransform,
}

/// The cell of a bilinear lookup: its texels' wrapped indices and the fractional position in it.
struct BilinearCell {
    x0: usize,
    x1: usize,
    y0: usize,
    y1: usize,
    fx: f32,
    fy: f32,
}

/// `floor(v)` as an index; saturates for huge values, 0 for NaN.
#[inline]
fn floor_index(v: f32) -> i64 {
    v.floor() as i64
}

impl Bitmap {
    /// `image` read with Mitsuba's defaults: bilinear, repeat, identity `to_uv`.
    pub fn new(image: Arc<TexelImage>) -> Bitmap {
        Bitmap {
            image,
            filter_type: FilterType::default(),
            wrap_mode: WrapMode::default(),
            to_uv: UvTransform::IDENTITY,
        }
    }

    /// Linear RGB at `uv` (after `to_uv`; see the module header for the conventions).
    #[inline]
    pub fn eval(&self, uv: Vec2) -> Rgb {
        let p = self.to_uv.apply(uv);
        let img = &*self.image;
        match self.filter_type {
            FilterType::Nearest => {
                let (x, y) = self.nearest_texel(p);
                img.texel(x, y)
            }
            FilterType::Bilinear => {
                let c = self.bilinear_cell(p);
                let (gx, gy) = (1.0 - c.fx, 1.0 - c.fy);
                img.texel(c.x0, c.y0) * (gx * gy)
                    + img.texel(c.x1, c.y0) * (c.fx * gy)
                    + img.texel(c.x0, c.y1) * (gx * c.fy)
                    + img.texel(c.x1, c.y1) * (c.fx * c.fy)
            }
        }
    }

    /// The texel a `nearest` lookup at `p` (after `to_uv`) reads, wrapped.
    #[inline]
    fn nearest_texel(&self, p: Vec2) -> (usize, usize) {
        let (w, h) = (self.image.width, self.image.height);
        let wrap = self.wrap_mode;
        (wrap.wrap(floor_index(p.x * w as f32), w), wrap.wrap(floor_index(p.y * h as f32), h))
    }

    /// The texels `eval`, `eval_1` and `eval_1_grad` at `uv` may read, as `(x, y)`: the bilinear
    /// cell's four (`(x0, y0), (x1, y0), (x0, y1), (x1, y1)`), or the nearest texel four times
    /// (`eval_1_grad` reads none then). From the lookups' own formulas (`nearest_texel`,
    /// `bilinear_cell`).
    #[inline]
    pub fn texels_read(&self, uv: Vec2) -> [(usize, usize); 4] {
        let p = self.to_uv.apply(uv);
        match self.filter_type {
            FilterType::Nearest => [self.nearest_texel(p); 4],
            FilterType::Bilinear => {
                let c = self.bilinear_cell(p);
                [(c.x0, c.y0), (c.x1, c.y0), (c.x0, c.y1), (c.x1, c.y1)]
            }
        }
    }

    /// Asks the cache for the lines of [`Bitmap::texels_read`] (the two rows' pairs; a pair
    /// split across lines gets both): a hint, no effect on any value.
    #[inline]
    pub fn prefetch(&self, uv: Vec2) {
        for (x, y) in self.texels_read(uv) {
            self.image.prefetch_texel(x, y);
        }
    }

    /// The four texels a bilinear lookup at `p` (after `to_uv`) blends, wrapped, and the
    /// weights toward the second of each pair (Mitsuba's `bilinear_weights`: `w1`).
    #[inline]
    fn bilinear_cell(&self, p: Vec2) -> BilinearCell {
        let (w, h) = (self.image.width, self.image.height);
        let wrap = self.wrap_mode;
        let (px, py) = (p.x * w as f32 - 0.5, p.y * h as f32 - 0.5);
        let (ix, iy) = (floor_index(px), floor_index(py));
        BilinearCell {
            x0: wrap.wrap(ix, w),
            x1: wrap.wrap(ix.saturating_add(1), w),
            y0: wrap.wrap(iy, h),
            y1: wrap.wrap(iy.saturating_add(1), h),
            fx: px - ix as f32,
            fy: py - iy as f32,
        }
    }

    /// Mitsuba's `eval_1_grad`: the gradient (∂f/∂u, ∂f/∂v) of [`Bitmap::eval_1`] with respect to
    /// the surface's uv (before `to_uv`), as Mitsuba 3.9.1's bitmap computes it (what `bumpmap`
    /// perturbs the normal by). `nearest`: zero (the lookup is piecewise constant). `bilinear`:
    /// the derivative of the bilinear blend inside the cell that contains the point, the four
    /// texels read through `wrap_mode` as `eval` reads them, their luminance (or the one
    /// channel): per texel coordinate `∂f/∂x = (1 − f_y)(f10 − f00) + f_y(f11 − f01)` and
    /// `∂f/∂y = (1 − f_x)(f01 − f00) + f_x(f11 − f10)`; then through `to_uv`'s linear part
    /// transposed, `A^T (∂f/∂x, ∂f/∂y)`, and **then** times the resolution per component
    /// (Mitsuba's order: for a `to_uv` that mixes u and v on an image that is not square this is
    /// not the exact derivative, which would scale by the resolution before `A^T`; Mitsuba is
    /// the spec). On a cell edge the derivative is the one-sided one of the cell `floor` picks.
    #[inline]
    pub fn eval_1_grad(&self, uv: Vec2) -> Vec2 {
        if self.filter_type == FilterType::Nearest {
            return Vec2::ZERO;
        }
        let img = &*self.image;
        let c = self.bilinear_cell(self.to_uv.apply(uv));
        let value = |x: usize, y: usize| {
            let t = img.texel(x, y);
            if img.channels == 1 {
                t.x
            } else {
                luminance(t)
            }
        };
        let (f00, f10) = (value(c.x0, c.y0), value(c.x1, c.y0));
        let (f01, f11) = (value(c.x0, c.y1), value(c.x1, c.y1));
        let dfdx = (1.0 - c.fy) * (f10 - f00) + c.fy * (f11 - f01);
        let dfdy = (1.0 - c.fx) * (f01 - f00) + c.fx * (f11 - f10);
        let [r0, r1] = self.to_uv.rows;
        Vec2::new((r0[0] * dfdx + r1[0] * dfdy) * img.width as f32, (r0[1] * dfdx + r1[1] * dfdy) * img.height as f32)
    }

    /// Mitsuba's `eval_1`: the luminance ([`super::LUMINANCE`]) of [`Bitmap::eval`], or the
    /// value of a one-channel image.
    #[inline]
    pub fn eval_1(&self, uv: Vec2) -> f32 {
        let c = self.eval(uv);
        if self.image.channels == 1 {
            c.x
        } else {
            luminance(c)
        }
    }

    /// Mitsuba's `mean()`: [`TexelImage::mean`].
    pub fn mean(&self) -> f32 {
        self.image.mean
    }
}

/// A `bitmap` as a scene declares it, with Mitsuba's names and defaults.
#[derive(Clone, Debug, PartialEq)]
pub struct BitmapParams {
    /// `filename` (resolved by the caller).
    pub filename: PathBuf,
    /// `filter_type` (default `bilinear`).
    pub filter_type: FilterType,
    /// `wrap_mode` (default `repeat`).
    pub wrap_mode: WrapMode,
    /// `raw` (default false: 8-/16-bit images are sRGB-decoded).
    pub raw: bool,
    /// `to_uv` (default identity).
    pub to_uv: UvTransform,
}

impl BitmapParams {
    /// `filename` with Mitsuba's defaults for the rest.
    pub fn new(filename: impl Into<PathBuf>) -> BitmapParams {
        BitmapParams {
            filename: filename.into(),
            filter_type: FilterType::default(),
            wrap_mode: WrapMode::default(),
            raw: false,
            to_uv: UvTransform::IDENTITY,
        }
    }
}

/// The decoded images of a scene: one [`TexelImage`] per canonical file path and `raw` flag,
/// decoded on first use and shared (`Arc`) by every bitmap that reads it. A reader that knows
/// the files ahead can have them decoded in parallel first ([`TextureCache::predecode`]): each
/// `load` then returns the image, or the error, that decoding it then would have given.
#[derive(Debug, Default)]
pub struct TextureCache {
    images: HashMap<(PathBuf, bool), Arc<TexelImage>>,
    /// Decoded by `predecode`, not yet asked for by `load`: the image or the decoding's error.
    decoded: HashMap<(PathBuf, bool), Result<Arc<TexelImage>, ImageError>>,
}

impl TextureCache {
    /// An empty cache.
    pub fn new() -> TextureCache {
        TextureCache::default()
    }

    /// The image at `path` decoded with `raw`: the cached one if this canonical path was loaded
    /// with this flag before, else decoded now (errors name the file).
    pub fn load(&mut self, path: &Path, raw: bool) -> Result<Arc<TexelImage>, ImageError> {
        let canonical = std::fs::canonicalize(path).map_err(|source| ImageError::Io {
            path: path.to_path_buf(),
            action: "open",
            source,
        })?;
        let key = (canonical, raw);
        if let Some(image) = self.images.get(&key) {
            return Ok(Arc::clone(image));
        }
        let image = match self.decoded.remove(&key) {
            Some(decoded) => decoded?,
            None => Arc::new(TexelImage::load(&key.0, raw)?),
        };
        self.images.insert(key, Arc::clone(&image));
        Ok(image)
    }

    /// Decodes the images `files` names (path and `raw` flag), each distinct canonical file and
    /// flag once, in parallel on the current rayon pool, and keeps each result for the
    /// [`TextureCache::load`] that asks for it: the same image, or the same error, as decoding
    /// it there, so a reader that loads its bitmaps in file order still meets the first error in
    /// file order. A file no `load` asks for costs its decoding only (its error is never
    /// reported); one that cannot be opened, or is held already, is left to `load`.
    pub fn predecode(&mut self, files: &[(PathBuf, bool)]) {
        use rayon::prelude::*;
        let mut todo: Vec<(PathBuf, bool)> = Vec::new();
        for (path, raw) in files {
            let Ok(canonical) = std::fs::canonicalize(path) else { continue };
            let key = (canonical, *raw);
            if !self.images.contains_key(&key) && !self.decoded.contains_key(&key) && !todo.contains(&key) {
                todo.push(key);
            }
        }
        let results: Vec<_> = todo
            .into_par_iter()
            .map(|k| {
                let r = TexelImage::load(&k.0, k.1).map(Arc::new);
                (k, r)
            })
            .collect();
        self.decoded.extend(results);
    }

    /// The bitmap `params` declares, its image through [`TextureCache::load`].
    pub fn bitmap(&mut self, params: &BitmapParams) -> Result<Bitmap, ImageError> {
        Ok(Bitmap {
            image: self.load(&params.filename, params.raw)?,
            filter_type: params.filter_type,
            wrap_mode: params.wrap_mode,
            to_uv: params.to_uv,
        })
    }

    /// Number of distinct images held.
    pub fn len(&self) -> usize {
        self.images.len()
    }

    /// `true` if no image is held.
    pub fn is_empty(&self) -> bool {
        self.images.is_empty()
    }

    /// The images held, in no particular order.
    pub fn images(&self) -> impl Iterator<Item = &Arc<TexelImage>> {
        self.images.values()
    }

    /// Bytes of every image held, each counted once ([`TexelImage::memory_bytes`]).
    pub fn memory_bytes(&self) -> usize {
        self.images.values().map(|i| i.memory_bytes()).sum()
    }
}
