//! Rendering passes: every pixel gets one sample per pass, tiles run in parallel with rayon.
//!
//! Randomness is a pure function of (seed, pass, pixel) (`Rng::keyed` with the camera stream),
//! and each tile's results merge into the film in tile order, so the film is bit-identical for
//! any thread count. Non-finite samples are counted and replaced by zero (never written).
//! Each tile runs with its own explicit `transport::context::Context` (random stream rekeyed
//! per pixel, scratch, profile counters); the tiles' profiles are summed into the pass's.
//! How a pixel sample is drawn (one camera ray, or emission splitting) is `pixel::PixelSampler`.
//!
//! Pass groups (`render_passes`): an integrator whose passes share no state traces several
//! passes at once, each pixel's samples side by side in the batch. A sample's value depends only
//! on (seed, pass, pixel), and each pixel's samples enter the film in pass order, so a group's
//! film is bit for bit that of its passes rendered one by one; the grouping is pure speed.
//!
//! Cut passes (`trace_passes`): a group is traced before it enters the film, each tile (and each
//! chunk of the light side's paths) started only while its `interrupt::Stop` is not due; a group
//! the stop reached is dropped whole, never merged in part, so the film holds whole passes only.

pub mod film;
pub mod pixel;
pub mod probe;

use crate::accel::{take_ray_counts, World};
use crate::integrators::{Integrator, LightSplats};
use crate::interrupt::Stop;
use crate::math::Rgb;
use crate::profile::Profile;
use crate::sampling::rng::{stream, Rng};
use crate::transport::context::Context;
use film::Film;
pub use pixel::{PixelSampler, TileBuffers, Worker, MAX_EMISSION_SPLIT};
use rayon::prelude::*;

/// Tile edge in pixels.
pub const TILE: usize = 16;

/// What one pass cost.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct PassCounters {
    /// Closest-hit rays.
    pub closest_rays: u64,
    /// Shadow rays.
    pub shadow_rays: u64,
    /// Samples whose estimate was NaN or infinite (replaced by 0).
    pub nonfinite: u64,
    /// Samples taken.
    pub samples: u64,
    /// The integrator's counters and phase times (summed over tiles).
    #[serde(skip)]
    pub profile: Profile,
}

impl PassCounters {
    /// Adds another pass's counters.
    pub fn add(&mut self, o: &PassCounters) {
        self.closest_rays += o.closest_rays;
        self.shadow_rays += o.shadow_rays;
        self.nonfinite += o.nonfinite;
        self.samples += o.samples;
        self.profile.add(&o.profile);
    }
}

/// One tile's camera estimates (row-major within the tile) and what they cost.
pub type TileResult = (usize, Vec<Rgb>, PassCounters);

/// The tile grid of a `w` × `h` image: `(tiles_x, tiles_y)`.
pub fn tile_counts(w: usize, h: usize) -> (usize, usize) {
    (w.div_ceil(TILE), h.div_ceil(TILE))
}

/// The pixels of tile `tile` in row-major order, as `(x, y)`.
pub fn tile_pixels(tile: usize, (w, h): (usize, usize)) -> impl Iterator<Item = (usize, usize)> {
    let tiles_x = w.div_ceil(TILE);
    let (tx, ty) = (tile % tiles_x, tile / tiles_x);
    (ty * TILE..((ty + 1) * TILE).min(h)).flat_map(move |y| (tx * TILE..((tx + 1) * TILE).min(w)).map(move |x| (x, y)))
}

/// The most passes traced in one call of [`render_passes`] (issue #33): a batch then holds up
/// to this many samples of each pixel side by side, so that a 16-ray packet of camera rays is
/// one pixel's (Mitsuba 3's wavefront order, `results/2026-12-05-pass-groups.md`).
pub const MAX_PASS_GROUP: usize = 16;

/// Samples held at once by a pass group (its camera values and each pass's splat image, 12
/// bytes each): the group of a `w` × `h` image is at most `MAX_GROUP_SAMPLES / (w·h)` passes.
pub const MAX_GROUP_SAMPLES: usize = 1 << 22;

/// The largest pass group for a `w` × `h` image: [`MAX_PASS_GROUP`], fewer for large images
/// (at least 1).
pub fn pass_group_limit(w: usize, h: usize) -> usize {
    (MAX_GROUP_SAMPLES / (w * h).max(1)).clamp(1, MAX_PASS_GROUP)
}

/// The camera side of the passes `passes`: every tile's pixel estimates, pixel-major
/// (`out[k·G + j]` is the tile's pixel `k` in pass `passes[j]`; non-finite ones counted and
/// replaced by zero), in tile order, with the tile's rays and profile. The light side is
/// [`Integrator::light_splats`].
pub fn camera_tiles(
    world: &World,
    integrator: &dyn Integrator,
    pixels: &PixelSampler,
    seed: u64,
    passes: &[u64],
) -> Vec<TileResult> {
    camera_tiles_until(world, integrator, pixels, seed, passes, &Stop::never()).expect("a pass without a stop is whole")
}

/// [`camera_tiles`], each tile started only while `stop` is not due: `None` when a tile was
/// left out (the passes are cut; what was traced is dropped and its buffers given back).
pub fn camera_tiles_until(
    world: &World,
    integrator: &dyn Integrator,
    pixels: &PixelSampler,
    seed: u64,
    passes: &[u64],
    stop: &Stop,
) -> Option<Vec<TileResult>> {
    let (w, h) = pixels.resolution();
    let (w, h) = (w as usize, h as usize);
    let (tiles_x, tiles_y) = tile_counts(w, h);
    let fresh = || Rng::keyed(seed, stream::CAMERA, passes[0], 0);
    // one worker (context and buffers) per rayon split, reused by its tiles and kept by the
    // pixel sampler for the next call (what carries over is capacity: the rng is rekeyed and
    // the profile taken per tile)
    let init = || {
        let w = pixels.take_worker().unwrap_or_else(|| {
            let mut ctx = Context::new(fresh());
            ctx.camera = Some(pixels.camera().clone());
            Worker { ctx, buf: TileBuffers::default(), px: Vec::with_capacity(TILE * TILE) }
        });
        Lease { pixels, w: Some(w) }
    };
    let tiles: Vec<Option<TileResult>> = (0..tiles_x * tiles_y)
        .into_par_iter()
        .map_init(init, |lease, tile| {
            // the deadline or a signal: the tiles not yet started are left out (a tile is at
            // most 256 pixels × the group's passes, so the cut comes within a fraction of a second)
            if stop.is_due() {
                return None;
            }
            let Worker { ctx, buf, px } = lease.w.as_mut().expect("a lease holds its worker until dropped");
            let _ = take_ray_counts();
            let mut c = PassCounters::default();
            ctx.rng = fresh();
            px.clear();
            px.extend(tile_pixels(tile, (w, h)).map(|(x, y)| (x, y, (y * w + x) as u64)));
            let mut out = pixels.take_out();
            out.reserve(px.len() * passes.len());
            pixels.sample_tile((world, integrator), px, (seed, passes), (ctx, buf), &mut out);
            for l in out.iter_mut().filter(|l| !l.is_finite()) {
                c.nonfinite += 1;
                *l = Rgb::ZERO;
            }
            c.samples += out.len() as u64;
            let (closest, shadow) = take_ray_counts();
            c.closest_rays = closest;
            c.shadow_rays = shadow;
            c.profile = std::mem::take(&mut ctx.profile);
            Some((tile, out, c))
        })
        .collect();
    if tiles.iter().all(Option::is_some) {
        return Some(tiles.into_iter().flatten().collect());
    }
    pixels.put_outs(tiles.into_iter().flatten().map(|(_, out, _)| out));
    None
}

/// Renders pass `pass` (one sample per pixel) into `film`.
pub fn render_pass(
    world: &World,
    integrator: &dyn Integrator,
    pixels: &PixelSampler,
    seed: u64,
    pass: u64,
    film: &mut Film,
) -> PassCounters {
    render_passes(world, integrator, pixels, seed, &[pass], film)
}

/// Renders the passes `passes` (one sample per pixel each) into `film`, their camera rays traced
/// together. Each pixel gets its samples in the order of `passes`, each the value `render_pass`
/// would give, so the film is bit for bit that of rendering them one by one. Only for
/// integrators whose passes are independent ([`Integrator::independent_passes`]: no state from
/// `begin_pass`), and at most [`pass_group_limit`] passes.
pub fn render_passes(
    world: &World,
    integrator: &dyn Integrator,
    pixels: &PixelSampler,
    seed: u64,
    passes: &[u64],
    film: &mut Film,
) -> PassCounters {
    let traced = trace_passes(world, integrator, pixels, seed, passes, &Stop::never());
    traced.expect("a pass without a stop is whole").merge(pixels, film)
}

/// The passes of a group traced in full, not yet in the film: the camera side's tiles and the
/// light side's splats of each pass, which enter the film together ([`Traced::merge`]) or not
/// at all ([`Traced::discard`]).
pub struct Traced {
    tiles: Vec<TileResult>,
    splats: Vec<Option<LightSplats>>,
}

/// Traces the passes `passes` as [`render_passes`] does, the camera side's tiles and then the
/// light side's paths, while `stop` is not due; `None` when it came due first (the passes are
/// cut: nothing of them may enter the film, as a pass's light paths and camera samples are one
/// estimator, and the film holds whole passes only).
pub fn trace_passes(
    world: &World,
    integrator: &dyn Integrator,
    pixels: &PixelSampler,
    seed: u64,
    passes: &[u64],
    stop: &Stop,
) -> Option<Traced> {
    assert!(!passes.is_empty() && (passes.len() == 1 || integrator.independent_passes()));
    let tiles = camera_tiles_until(world, integrator, pixels, seed, passes, stop)?;
    let mut splats = Vec::with_capacity(passes.len());
    for &q in passes {
        match integrator.light_tracer().map(|l| l.light_splats_until(world, pixels.camera(), seed, q, stop)) {
            Some(None) => {
                pixels.put_outs(tiles.into_iter().map(|(_, out, _)| out));
                return None;
            }
            s => splats.push(s.flatten()),
        }
    }
    Some(Traced { tiles, splats })
}

impl Traced {
    /// Adds the passes to `film` (each pixel its samples in pass order) and gives the buffers
    /// back to `pixels`; what they cost.
    pub fn merge(self, pixels: &PixelSampler, film: &mut Film) -> PassCounters {
        let (w, h) = (film.width, film.height);
        assert_eq!(pixels.resolution(), (w as u32, h as u32), "pixel sampler and film sizes differ");
        let Traced { tiles: results, splats } = self;
        let g = splats.len();
        // The merge runs in parallel over rows of tiles (each a contiguous band of the film); every
        // pixel still gets its samples in pass order, so the film is the serial merge's.
        let tiles_x = w.div_ceil(TILE);
        let band = w * TILE * film::STRIDE;
        let mut total = film
            .data
            .par_chunks_mut(band)
            .zip(results.par_chunks(tiles_x))
            .map(|(rows, tiles)| {
                let mut c = PassCounters::default();
                for (tile, out, tc) in tiles {
                    for ((x, y), ls) in tile_pixels(*tile, (w, h)).zip(out.chunks_exact(g)) {
                        let i = (y % TILE) * w + x;
                        for (&l, s) in ls.iter().zip(&splats) {
                            let v = with_splat(l, s.as_ref(), y * w + x, &mut c);
                            film::add_at(&mut rows[i * film::STRIDE..(i + 1) * film::STRIDE], v);
                        }
                    }
                    c.add(tc);
                }
                c
            })
            .reduce(PassCounters::default, |mut a, b| {
                a.add(&b);
                a
            });
        for s in splats.iter().flatten() {
            total.nonfinite += s.nonfinite;
            total.closest_rays += s.closest_rays;
            total.shadow_rays += s.shadow_rays;
        }
        pixels.put_outs(results.into_iter().map(|(_, out, _)| out));
        total
    }

    /// Drops the passes (another rank's were cut: the round is discarded on every rank), giving
    /// the buffers back to `pixels`.
    pub fn discard(self, pixels: &PixelSampler) {
        pixels.put_outs(self.tiles.into_iter().map(|(_, out, _)| out));
    }
}

/// A worker borrowed from a pixel sampler for one rayon split; given back when the split ends.
struct Lease<'a, 'b> {
    pixels: &'a PixelSampler<'b>,
    w: Option<Worker>,
}

impl Drop for Lease<'_, '_> {
    fn drop(&mut self) {
        if let Some(w) = self.w.take() {
            self.pixels.put_worker(w);
        }
    }
}

/// A pixel's sample of the pass: its camera estimate plus the pass's light splats there, if the
/// integrator traces light paths (so each pass still adds one i.i.d. sample per pixel and the
/// film's variance stays the variance of the pass values). A non-finite sum is counted and
/// replaced by zero, as a non-finite camera estimate.
#[inline]
pub fn with_splat(camera: Rgb, splats: Option<&LightSplats>, pixel: usize, c: &mut PassCounters) -> Rgb {
    let Some(s) = splats else { return camera };
    let l = camera + s.image[pixel];
    if l.is_finite() {
        l
    } else {
        c.nonfinite += 1;
        Rgb::ZERO
    }
}
