//! Mitsuba's `checkerboard` texture: two textures alternating on the unit squares' quarters.

use super::{Texture, UvTransform};
use crate::math::{Rgb, Vec2};

/// Mitsuba's `checkerboard`: with `p = to_uv(uv)` and `a = frac(p.x) > ½`, `b = frac(p.y) > ½`
/// (`frac(t) = t − floor(t)`), [`Checkerboard::eval`] is `color0` where `a == b` and `color1`
/// elsewhere; so the quarter `[0, ½]²` of each unit square is `color0`. The colours are
/// textures themselves, evaluated at the surface's `uv` (before this `to_uv`), as in Mitsuba.
#[derive(Clone, Debug)]
pub struct Checkerboard {
    /// `color0` (Mitsuba's default 0.4).
    pub color0: Box<Texture>,
    /// `color1` (Mitsuba's default 0.2).
    pub color1: Box<Texture>,
    /// `to_uv`.
    pub to_uv: UvTransform,
}

impl Default for Checkerboard {
    /// Mitsuba's defaults: `color0` 0.4, `color1` 0.2, identity `to_uv`.
    fn default() -> Checkerboard {
        Checkerboard::new(Texture::Constant(Rgb::splat(0.4)), Texture::Constant(Rgb::splat(0.2)), UvTransform::IDENTITY)
    }
}

impl Checkerboard {
    /// The two colours and `to_uv`.
    pub fn new(color0: Texture, color1: Texture, to_uv: UvTransform) -> Checkerboard {
        Checkerboard { color0: Box::new(color0), color1: Box::new(color1), to_uv }
    }

    /// `true` where [`Checkerboard::eval`] reads `color0`.
    #[inline]
    pub fn is_color0(&self, uv: Vec2) -> bool {
        let p = self.to_uv.apply(uv);
        (p.x - p.x.floor() > 0.5) == (p.y - p.y.floor() > 0.5)
    }

    /// Linear RGB at `uv`.
    #[inline]
    pub fn eval(&self, uv: Vec2) -> Rgb {
        if self.is_color0(uv) {
            self.color0.eval(uv)
        } else {
            self.color1.eval(uv)
        }
    }

    /// Mitsuba 3.9.1's `eval_1`, which reads the colours the other way round from its `eval`:
    /// `color0`'s `eval_1` where `eval` gives `color1`, and the reverse (its test is
    /// `a != b`). Kept so that a checkerboard roughness renders as in Mitsuba.
    #[inline]
    pub fn eval_1(&self, uv: Vec2) -> f32 {
        if self.is_color0(uv) {
            self.color1.eval_1(uv)
        } else {
            self.color0.eval_1(uv)
        }
    }

    /// Mitsuba's `mean()`: `(mean(color0) + mean(color1)) / 2`.
    pub fn mean(&self) -> f32 {
        0.5 * (self.color0.mean() + self.color1.mean())
    }
}
