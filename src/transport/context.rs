//! The explicit per-worker context handed down the radiance recursion (pbrt-v4's
//! `ScratchBuffer` idea): the sample's random stream, reusable scratch buffers and the profile
//! counters. One per rayon work split, reused across its tiles; `render::render_passes` rekeys
//! `rng` for every pixel and takes the profile per tile, so randomness stays a pure function of
//! (seed, pass, pixel) whatever the thread, and nothing else carries from one tile to the next
//! but buffers. Also the
//! [`ShadingQuery`] of a non-specular point of the recursion.

use crate::bsdf::ShadingPoint;
use crate::math::Vec3;
use crate::profile::Profile;
use crate::sampling::rng::Rng;
use crate::scene::{Camera, Material};
use std::any::Any;

/// Per-worker state of the hot path.
pub struct Context {
    /// The current sample's random stream.
    pub rng: Rng,
    /// Scratch for k-nearest gathers (photon map, forecast maps): `(distance², id)`.
    pub knn: Vec<(f32, u32)>,
    /// Counters and phase times, summed into the report.
    pub profile: Profile,
    /// The camera of the image being rendered (set by `render::render_passes`; `None` elsewhere,
    /// e.g. preprocess gathers): `pt-cf`'s camera-side MIS weight against its light paths.
    pub camera: Option<Camera>,
    /// Buffers an integrator keeps from one batch to the next (`pt`'s wavefront), typed by that
    /// integrator: capacity only, never read by the math.
    pub scratch: Option<Box<dyn Any + Send>>,
    /// Values of pure functions an integrator keeps per worker (`pt-cf`'s memo of the table
    /// cache, `cf::table_cache::TableMemo`), typed by that integrator: they change how fast a
    /// value is found, never the value.
    pub memo: Option<Box<dyn Any + Send>>,
}

impl Context {
    /// A context drawing from `rng`.
    pub fn new(rng: Rng) -> Context {
        Context { rng, knn: Vec::new(), profile: Profile::default(), camera: None, scratch: None, memo: None }
    }

    /// The memo of type `T` (a fresh one when absent or of another type).
    pub fn memo<T: Default + Send + 'static>(&mut self) -> &mut T {
        let b = self.memo.get_or_insert_with(|| Box::new(T::default()));
        if !b.is::<T>() {
            *b = Box::new(T::default());
        }
        b.downcast_mut::<T>().unwrap_or_else(|| unreachable!("the memo was just made a T"))
    }

    /// The scratch of type `T` (a fresh one when absent or of another type), to be given back
    /// with [`Context::put_scratch`].
    pub fn take_scratch<T: Default + Send + 'static>(&mut self) -> Box<T> {
        self.scratch.take().and_then(|b| b.downcast::<T>().ok()).unwrap_or_default()
    }

    /// Keeps `s` for the next [`Context::take_scratch`].
    pub fn put_scratch<T: Send + 'static>(&mut self, s: Box<T>) {
        self.scratch = Some(s);
    }
}

/// A non-specular shading point of the recursion: where, what, toward where, how deep.
#[derive(Clone, Copy, Debug)]
pub struct ShadingQuery<'a> {
    /// The point and its normals.
    pub x: &'a ShadingPoint,
    /// Its material (non-Dirac).
    pub m: &'a Material,
    /// Direction toward the previous vertex (unit).
    pub wo: Vec3,
    /// Diffuse depth `d`.
    pub depth: u32,
}
