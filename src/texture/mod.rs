//! Mitsuba 3's textures, evaluated at a surface's UV point: a constant colour, `bitmap` (an
//! image file, [`Bitmap`]) and `checkerboard` ([`Checkerboard`]), for materials to take in place
//! of a constant.
//!
//! What it computes, as Mitsuba 3.9.1 does in its `rgb` variants (`src/textures/bitmap.cpp`,
//! `checkerboard.cpp`, Dr.Jit's `texture.h`):
//! * [`Texture::eval`]: linear RGB at `uv`. [`Texture::eval_1`]: one value for a monochrome use
//!   (a roughness): a bitmap's luminance (Mitsuba's coefficients [`LUMINANCE`]) or its one
//!   channel, a constant's channel mean. [`Texture::mean`]: Mitsuba's `mean()`, a bitmap's mean
//!   luminance over its texels, a constant's channel mean, a checkerboard's mean of its two.
//!   [`Texture::eval_1_grad`]: Mitsuba's gradient of `eval_1` in uv (a bump map's slopes),
//!   the derivative of the bilinear blend in its cell, zero for `nearest` and constants.
//! * UV convention: the texture's `to_uv` ([`UvTransform`], an affine 2D map) is applied first;
//!   then `(0, 0)` is the **top-left** corner of the image and `v` grows downward (row 0 of the
//!   file is `v` in `[0, 1/height)`). The texture itself does **not** flip `v`: Mitsuba flips it
//!   where meshes are read (its OBJ loader stores `1 − v` unless `flip_tex_coords` is false; PLY
//!   does not), and so must the shape loaders here. Texel `(x, y)` covers
//!   `[x/w, (x+1)/w) × [y/h, (y+1)/h)`; its centre is `((x + ½)/w, (y + ½)/h)`.
//! * `filter_type`: `nearest` reads texel `floor(u·w), floor(v·h)`; `bilinear` (default) blends
//!   the four texels around `(u·w − ½, v·h − ½)` (texel centres at half-integers), so at a texel
//!   centre it returns that texel. `wrap_mode` is applied to each **integer texel index** (also
//!   to both of a bilinear pair): `repeat` (default) `i mod n`, `mirror` reflects with period
//!   `2n` (`−1 → 0`, `n → n−1`), `clamp` `clamp(i, 0, n−1)`.
//! * Colour: 8- and 16-bit images (PNG, JPEG) are sRGB-decoded to linear per texel, before any
//!   blending, unless `raw`; float images (EXR, Radiance HDR) are linear already and `raw` does
//!   nothing to them. Grey images stay one channel and read as grey RGB. Alpha is ignored.
//!
//! * [`Texture::prefetch`] asks the cache for the lines a later `eval`, `eval_1` or
//!   `eval_1_grad` at the same `uv` reads (the texels of [`Bitmap::texels_read`], the one
//!   formula the lookups use): a hint, with no effect on any value. A wavefront issues it for a
//!   whole batch of hits before it shades them, so that their misses overlap.
//!
//! Invariants: evaluation never panics and never allocates; a [`TexelImage`] is immutable once
//! built and shared through an `Arc` by every bitmap that names the same file with the same
//! `raw` ([`TextureCache`]); texels are finite and `>= 0`.
//!
//! Differences from Mitsuba, all below its own precision: the sRGB curve is the exact one
//! (Mitsuba: a rational fit, within ~1e-6); 16-bit images are kept as `f32` (Mitsuba: half
//! floats, ~5e-4 relative); sums are formed without fused multiply-adds.
//!
//! Agreement with Mitsuba 3.9.1 is checked on committed images (`tests/data/texture/`, written
//! with their reference values by `scripts/mitsuba-texture-values.py`).

mod bitmap;
mod checkerboard;
#[cfg(test)]
mod tests;

pub use bitmap::{Bitmap, BitmapParams, FilterType, TexelImage, TextureCache, WrapMode};
pub use checkerboard::Checkerboard;

use crate::math::{Rgb, Vec2};

/// Mitsuba 3's luminance weights (`mitsuba/core/spectrum.h`), used by a bitmap's `eval_1` and
/// `mean`. They differ from `math::luminance`'s Rec. 709 roundings in the fourth digit.
pub const LUMINANCE: [f32; 3] = [0.212671, 0.715160, 0.072169];

/// Mitsuba's luminance of a linear RGB value ([`LUMINANCE`]).
#[inline]
pub fn luminance(c: Rgb) -> f32 {
    c.x * LUMINANCE[0] + c.y * LUMINANCE[1] + c.z * LUMINANCE[2]
}

/// A texture: a constant, a bitmap or a checkerboard.
#[derive(Clone, Debug)]
pub enum Texture {
    /// The same linear RGB everywhere (Mitsuba's `rgb` value or a float, as grey).
    Constant(Rgb),
    /// An image file ([`Bitmap`]).
    Bitmap(Bitmap),
    /// Two textures in a checkerboard pattern ([`Checkerboard`]).
    Checkerboard(Checkerboard),
}

impl Texture {
    /// Linear RGB at `uv` (a finite UV; a non-finite one gives an unspecified value, never a
    /// panic).
    #[inline]
    pub fn eval(&self, uv: Vec2) -> Rgb {
        match self {
            Texture::Constant(c) => *c,
            Texture::Bitmap(b) => b.eval(uv),
            Texture::Checkerboard(c) => c.eval(uv),
        }
    }

    /// One value at `uv` for a monochrome use (Mitsuba's `eval_1`): a constant's channel mean
    /// (Mitsuba's `rgb` texture: `mean(value)`), a bitmap's luminance (or its one channel); a
    /// checkerboard's per Mitsuba's rule ([`Checkerboard::eval_1`]).
    #[inline]
    pub fn eval_1(&self, uv: Vec2) -> f32 {
        match self {
            Texture::Constant(c) => channel_mean(*c),
            Texture::Bitmap(b) => b.eval_1(uv),
            Texture::Checkerboard(c) => c.eval_1(uv),
        }
    }

    /// Mitsuba's `eval_1_grad`: the gradient (∂/∂u, ∂/∂v) of [`Texture::eval_1`] at `uv`, what
    /// `bumpmap` tilts the normal by: a bitmap's ([`Bitmap::eval_1_grad`]), zero for a constant
    /// (Mitsuba's `uniform`). Mitsuba has none for a checkerboard ([`Texture::has_eval_1_grad`]):
    /// zero here.
    #[inline]
    pub fn eval_1_grad(&self, uv: Vec2) -> Vec2 {
        match self {
            Texture::Bitmap(b) => b.eval_1_grad(uv),
            Texture::Constant(_) | Texture::Checkerboard(_) => Vec2::ZERO,
        }
    }

    /// Prefetches the texels a lookup at `uv` reads ([`Bitmap::prefetch`]; a checkerboard's
    /// colours are constants or bitmaps of their own, and a checkerboard reads one of them at a
    /// time: nothing is fetched for it). Changes no value.
    #[inline]
    pub fn prefetch(&self, uv: Vec2) {
        if let Texture::Bitmap(b) = self {
            b.prefetch(uv);
        }
    }

    /// `false` for a texture Mitsuba's `eval_1_grad` refuses (a checkerboard): a scene reader
    /// rejects it as a bump map's height.
    pub fn has_eval_1_grad(&self) -> bool {
        !matches!(self, Texture::Checkerboard(_))
    }

    /// Mitsuba's `mean()`: a constant's channel mean, a bitmap's mean luminance over its texels
    /// (one channel: its mean), a checkerboard's `(mean(color0) + mean(color1)) / 2`.
    pub fn mean(&self) -> f32 {
        match self {
            Texture::Constant(c) => channel_mean(*c),
            Texture::Bitmap(b) => b.mean(),
            Texture::Checkerboard(c) => c.mean(),
        }
    }

    /// `true` unless the texture is a [`Texture::Constant`] (Mitsuba's `is_spatially_varying`).
    pub fn is_spatially_varying(&self) -> bool {
        !matches!(self, Texture::Constant(_))
    }

    /// Calls `f` with every image this texture reads (a checkerboard's colours included); an
    /// image shared by several bitmaps comes once per bitmap (compare with `Arc::ptr_eq`, or
    /// count memory with [`TextureCache::memory_bytes`]).
    pub fn for_each_image(&self, f: &mut impl FnMut(&std::sync::Arc<TexelImage>)) {
        match self {
            Texture::Constant(_) => {}
            Texture::Bitmap(b) => f(&b.image),
            Texture::Checkerboard(c) => {
                c.color0.for_each_image(f);
                c.color1.for_each_image(f);
            }
        }
    }
}

impl Texture {
    /// The image files this texture reads, in words for an error message (`` `a.png` ``, or
    /// `` `a.png` and `b.exr` ``); `None` for a texture without images.
    pub fn image_files(&self) -> Option<String> {
        let mut names: Vec<String> = Vec::new();
        self.for_each_image(&mut |i| {
            let n = format!("`{}`", i.path().display());
            if !names.contains(&n) {
                names.push(n);
            }
        });
        match names.len() {
            0 => None,
            1 => names.pop(),
            n => Some(format!("{} and {}", names[..n - 1].join(", "), names[n - 1])),
        }
    }
}

impl From<Rgb> for Texture {
    fn from(c: Rgb) -> Texture {
        Texture::Constant(c)
    }
}

/// Asks the cache for the line holding `*p` (on x86-64 `prefetcht0`; nothing elsewhere). A
/// hint: it never faults, reads nothing the program sees and changes no value, so `p` need not
/// be dereferenceable.
#[inline(always)]
pub fn prefetch<T>(p: *const T) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: `prefetcht0` (SSE, baseline on x86-64) does not access memory architecturally: it
    // cannot fault, whatever the address.
    unsafe {
        core::arch::x86_64::_mm_prefetch::<{ core::arch::x86_64::_MM_HINT_T0 }>(p as *const i8)
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = p;
}

/// `(r + g + b) / 3`, in Mitsuba's order of operations.
#[inline]
fn channel_mean(c: Rgb) -> f32 {
    (c.x + c.y + c.z) / 3.0
}

/// Mitsuba's `to_uv`: an affine map of the plane, `uv' = A·uv + t`, applied to a surface's UV
/// before a texture is read. Rows `[a00, a01, t0]`, `[a10, a11, t1]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UvTransform {
    /// The two rows of the 3×3 matrix whose last row is `(0, 0, 1)`.
    pub rows: [[f32; 3]; 2],
}

impl Default for UvTransform {
    fn default() -> UvTransform {
        UvTransform::IDENTITY
    }
}

impl UvTransform {
    /// The identity (Mitsuba's default `to_uv`).
    pub const IDENTITY: UvTransform = UvTransform { rows: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] };

    /// From a 3×3 matrix, row-major (Mitsuba's `<matrix value="9 numbers"/>`): the last row is
    /// ignored, as Mitsuba's affine transform ignores it. A 4×4 `to_uv` gives its upper-left
    /// 2×2 block and the first two entries of its last column; pass those here.
    pub fn from_matrix(m: [[f32; 3]; 3]) -> UvTransform {
        UvTransform { rows: [m[0], m[1]] }
    }

    /// Scaling by `s` (Mitsuba's `scale`).
    pub fn scale(s: Vec2) -> UvTransform {
        UvTransform { rows: [[s.x, 0.0, 0.0], [0.0, s.y, 0.0]] }
    }

    /// Translation by `t` (Mitsuba's `translate`).
    pub fn translate(t: Vec2) -> UvTransform {
        UvTransform { rows: [[1.0, 0.0, t.x], [0.0, 1.0, t.y]] }
    }

    /// Counter-clockwise rotation by `degrees` about the origin (Mitsuba's 2D `rotate`:
    /// `[[cos, −sin], [sin, cos]]`).
    pub fn rotate(degrees: f32) -> UvTransform {
        let (s, c) = degrees.to_radians().sin_cos();
        UvTransform { rows: [[c, -s, 0.0], [s, c, 0.0]] }
    }

    /// `self` followed by `next` (the matrix `next · self`): Mitsuba's XML composes a
    /// `<transform>`'s elements this way, each later one applied after the earlier ones.
    pub fn then(self, next: UvTransform) -> UvTransform {
        let (a, b) = (next.rows, self.rows);
        let row = |i: usize| {
            [
                a[i][0] * b[0][0] + a[i][1] * b[1][0],
                a[i][0] * b[0][1] + a[i][1] * b[1][1],
                a[i][0] * b[0][2] + a[i][1] * b[1][2] + a[i][2],
            ]
        };
        UvTransform { rows: [row(0), row(1)] }
    }

    /// `true` for the identity.
    pub fn is_identity(&self) -> bool {
        *self == UvTransform::IDENTITY
    }

    /// The transformed point.
    #[inline]
    pub fn apply(&self, uv: Vec2) -> Vec2 {
        let [r0, r1] = self.rows;
        Vec2::new(r0[2] + r0[0] * uv.x + r0[1] * uv.y, r1[2] + r1[0] * uv.x + r1[1] * uv.y)
    }
}
