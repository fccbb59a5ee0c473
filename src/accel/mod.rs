//! `World`: the scene plus its ray-tracing acceleration structure, from one of two back ends.
//!
//! `AccelKind::Wide` (the default, `wide.rs`): an 8-wide float-box BVH of our own (binned SAH,
//! traced near to far). `AccelKind::Obvhs` (`obvhs.rs`): a CWBVH from the obvhs crate (the
//! default before `wide`, kept as the reference its images are z-tested against).
//! `AccelKind::Embree` (`embree.rs`, cargo feature `embree`): Intel Embree 3 through the system
//! library. `World` holds the chosen one in an enum (no trait object in the hot path); a back end
//! answers only "which primitive, at which t"; this module turns that into a `Hit` (normals,
//! shading normal, sphere re-projection), so both back ends give hits of the same meaning.
//! Spheres are analytic in both, tested by the one `sphere_t` here.
//!
//! `World::build` refuses primitives whose box is not finite or leaves the scene extent limit
//! (`scene::MAX_EXTENT`): obvhs panics on such boxes, and the loader should have rejected them
//! already (this is the last line of defence). Closest-hit and occlusion queries; ray counts are
//! kept in thread-local counters (`take_ray_counts`).
//!
//! Invariants: directions passed in are unit length (the sphere test relies on it); hit normals
//! are unit; `Hit::ns` lies on the side of `Hit::ng`; primitive ids follow `Scene` (triangles, then
//! spheres); a back end reports t ∈ [0, tmax] (triangles) or (0, tmax) (spheres).

use crate::bsdf::{Material, ShadingPoint};
use crate::math::Vec3;
use crate::scene::Scene;
mod bvh8;
#[cfg(feature = "embree")]
mod embree;
mod obvhs;
#[cfg(test)]
mod test_rays;
mod wide;

use std::cell::Cell;

thread_local! {
    static RAY_COUNTS: Cell<(u64, u64)> = const { Cell::new((0, 0)) };
}

#[inline]
fn count(closest: u64, shadow: u64) {
    RAY_COUNTS.with(|c| {
        let (a, b) = c.get();
        c.set((a + closest, b + shadow));
    });
}

/// Returns and resets this thread's (closest-hit, shadow) ray counts.
pub fn take_ray_counts() -> (u64, u64) {
    RAY_COUNTS.with(|c| c.replace((0, 0)))
}

/// A ray of a batch (`World::intersect_batch`, `World::occluded_batch`): `o + t·d`, t ∈ (0, tmax),
/// `d` unit length.
#[derive(Clone, Copy, Debug)]
pub struct Ray {
    /// Origin.
    pub o: Vec3,
    /// Unit direction.
    pub d: Vec3,
    /// The far end of the segment.
    pub tmax: f32,
}

/// Reusable buffers of [`World::intersect_batch`] and [`World::occluded_batch`] (the back end's
/// packet records), so that a batch traced bounce after bounce allocates once.
#[derive(Default)]
pub struct BatchScratch {
    #[cfg(feature = "embree")]
    embree: embree::Scratch,
}

/// A surface hit.
#[derive(Clone, Copy, Debug)]
pub struct Hit {
    /// Ray parameter.
    pub t: f32,
    /// Position.
    pub p: Vec3,
    /// Unit geometric normal as the shape defines it.
    pub ng: Vec3,
    /// Unit shading normal (on the `ng` side).
    pub ns: Vec3,
    /// Primitive id.
    pub prim: u32,
}

/// Offset for spawning rays off a surface at `p`, scaled by the coordinates' magnitude.
#[inline]
pub fn ray_epsilon(p: Vec3) -> f32 {
    1e-4 * p.abs().max_element().max(1.0)
}

/// A ray origin moved off the surface toward the side `dir` leaves on.
#[inline]
pub fn offset_origin(p: Vec3, ng: Vec3, dir: Vec3) -> Vec3 {
    let e = ray_epsilon(p);
    if dir.dot(ng) >= 0.0 {
        p + e * ng
    } else {
        p - e * ng
    }
}

/// The shadow segment between surface points `a` (normal `na`) and `b` (normal `nb`), both ends
/// offset off their surfaces, and whether it exists (false when the points coincide). Without
/// early returns, so that `pt`'s lanes run it sixteen wide ([`World::visibility_ray`] is its
/// scalar form).
#[inline(always)]
pub fn shadow_segment(a: Vec3, na: Vec3, b: Vec3, nb: Vec3) -> (Ray, bool) {
    let d = b - a;
    let dist = d.length();
    let dir = d / dist;
    let o = offset_origin(a, na, dir);
    let target = offset_origin(b, nb, -dir);
    let seg = target - o;
    let len = seg.length();
    (Ray { o, d: seg / len.max(1e-30), tmax: len }, dist > 0.0 || dist.is_nan())
}

/// Why `World::build` refused a scene.
#[derive(Clone, Debug, PartialEq)]
pub enum BuildError {
    /// A primitive's bounding box is not finite or leaves `[-MAX_EXTENT, MAX_EXTENT]³`.
    OutOfRange {
        /// Primitive id (triangles, then spheres).
        prim: u32,
        /// Box minimum.
        lo: [f32; 3],
        /// Box maximum.
        hi: [f32; 3],
    },
    /// More primitives than 32-bit ids can name.
    TooManyPrimitives(usize),
    /// The back end is not in this build, or failed (Embree's device or scene).
    Backend(String),
}

impl std::fmt::Display for BuildError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            BuildError::OutOfRange { prim, lo, hi } => write!(
                f,
                "cannot build the BVH: primitive {prim} has bounds {lo:?}..{hi:?}, outside the scene extent limit \
                 |coordinate| <= {:e}",
                crate::scene::MAX_EXTENT
            ),
            BuildError::TooManyPrimitives(n) => write!(f, "cannot build the BVH: {n} primitives (at most 2^32 - 2)"),
            BuildError::Backend(m) => write!(f, "cannot build the BVH: {m}"),
        }
    }
}

impl std::error::Error for BuildError {}

/// The ray-tracing back end (`--accel`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum AccelKind {
    // The own 8-wide BVH (`wide.rs`, always built in); no doc comment, which would be a help text
    // turning `render --help` into the long format.
    #[allow(missing_docs)]
    #[default]
    Wide,
    // The obvhs crate's CWBVH (always built in).
    #[allow(missing_docs)]
    Obvhs,
    /// Intel Embree 3, in builds with --features embree only.
    // Hidden in a build without the feature, so that `--help` offers only what the build has;
    // the value still parses there, and `check` refuses it with the rebuild hint.
    #[cfg_attr(not(feature = "embree"), value(hide = true))]
    Embree,
}

impl AccelKind {
    /// The command-line name.
    pub fn name(self) -> &'static str {
        match self {
            AccelKind::Wide => "wide",
            AccelKind::Obvhs => "obvhs",
            AccelKind::Embree => "embree",
        }
    }

    /// Whether this build has the back end.
    pub fn available(self) -> bool {
        match self {
            AccelKind::Wide | AccelKind::Obvhs => true,
            AccelKind::Embree => cfg!(feature = "embree"),
        }
    }

    /// `Err` with the message for a back end this build lacks.
    pub fn check(self) -> Result<(), String> {
        if self.available() {
            Ok(())
        } else {
            Err("--accel embree: this build has no Embree back end; rebuild with --features embree".into())
        }
    }
}

/// The built back end. A `World` holds exactly one, so the variants' sizes do not matter (and a
/// box would add a load to every query).
#[allow(clippy::large_enum_variant)]
enum Accel {
    Obvhs(obvhs::ObvhsBvh),
    Wide(wide::WideBvh),
    #[cfg(feature = "embree")]
    Embree(embree::EmbreeScene),
}

/// The scene with its acceleration structure.
pub struct World {
    /// The scene.
    pub scene: Scene,
    accel: Accel,
    /// BVH build time in seconds.
    pub build_secs: f64,
}

/// Each primitive's bounds (lo, hi): triangles, then spheres.
fn bounds(scene: &Scene) -> Vec<(Vec3, Vec3)> {
    let tris = scene.triangles.iter().map(|t| (t.p[0].min(t.p[1]).min(t.p[2]), t.p[0].max(t.p[1]).max(t.p[2])));
    let r = |s: &crate::scene::Sphere| Vec3::splat(s.radius);
    tris.chain(scene.spheres.iter().map(|s| (s.center - r(s), s.center + r(s)))).collect()
}

/// The point `p` near sphere `s` re-projected onto its surface (`World::hit`'s hit point on a
/// sphere: it limits error growth along Dirac chains).
#[inline(always)]
fn on_sphere(s: &crate::scene::Sphere, p: Vec3) -> Vec3 {
    s.center + (p - s.center).normalize() * s.radius
}

impl Hit {
    /// Its position and normals as a BSDF sees them.
    #[inline(always)]
    pub fn shading_point(&self) -> ShadingPoint {
        ShadingPoint::new(self.p, self.ng, self.ns)
    }
}

impl World {
    /// The BSDF and shading point at `hit` seen from `wo` (`Scene::shade`).
    #[inline(always)]
    pub fn shade(&self, hit: &Hit, wo: Vec3) -> (Material, ShadingPoint) {
        self.scene.shade(hit.prim, hit.shading_point(), wo)
    }

    /// Builds the default (`wide`) BVH over the scene's primitives; refuses boxes that are not
    /// finite or exceed `scene::MAX_EXTENT` (obvhs would panic on them).
    pub fn build(scene: Scene) -> Result<World, BuildError> {
        World::build_with(scene, AccelKind::Wide)
    }

    /// Builds the acceleration structure of back end `kind` (same checks as `build`).
    pub fn build_with(scene: Scene, kind: AccelKind) -> Result<World, BuildError> {
        let t0 = std::time::Instant::now();
        kind.check().map_err(BuildError::Backend)?;
        let nprim = scene.triangles.len() + scene.spheres.len();
        if nprim >= u32::MAX as usize - 1 {
            return Err(BuildError::TooManyPrimitives(nprim));
        }
        let b = bounds(&scene);
        let within = crate::scene::within_extent;
        if let Some(i) = b.iter().position(|&(lo, hi)| !within(lo) || !within(hi)) {
            let (lo, hi) = b[i];
            return Err(BuildError::OutOfRange { prim: i as u32, lo: lo.to_array(), hi: hi.to_array() });
        }
        let accel = match kind {
            AccelKind::Wide => Accel::Wide(wide::WideBvh::build(&scene, &b)),
            AccelKind::Obvhs => Accel::Obvhs(obvhs::ObvhsBvh::build(&scene, &b)),
            #[cfg(feature = "embree")]
            AccelKind::Embree => Accel::Embree(embree::EmbreeScene::build(&scene).map_err(BuildError::Backend)?),
            #[cfg(not(feature = "embree"))]
            AccelKind::Embree => unreachable!("checked by AccelKind::check"),
        };
        Ok(World { scene, accel, build_secs: t0.elapsed().as_secs_f64() })
    }

    /// The back end in use.
    pub fn accel(&self) -> AccelKind {
        match self.accel {
            Accel::Wide(_) => AccelKind::Wide,
            Accel::Obvhs(_) => AccelKind::Obvhs,
            #[cfg(feature = "embree")]
            Accel::Embree(_) => AccelKind::Embree,
        }
    }

    /// Closest hit along `origin + t·dir`, t ∈ (0, tmax); `dir` must be unit length. `inline`:
    /// the release profile's 4 codegen units otherwise may leave it out of line in `pt-cf`'s
    /// loop, which cost that loop 3% (`results/2026-12-05-diffuse-lanes.md`).
    #[inline]
    pub fn intersect(&self, origin: Vec3, dir: Vec3, tmax: f32) -> Option<Hit> {
        let (prim, t) = self.closest(origin, dir, tmax)?;
        Some(self.hit(origin, dir, prim, t))
    }

    /// The closest hit's (primitive, t), before its record is built (one ray counted).
    #[inline]
    fn closest(&self, origin: Vec3, dir: Vec3, tmax: f32) -> Option<(u32, f32)> {
        count(1, 0);
        match &self.accel {
            Accel::Obvhs(b) => b.closest(&self.scene, origin, dir, tmax),
            Accel::Wide(b) => b.closest(&self.scene, origin, dir, tmax),
            #[cfg(feature = "embree")]
            Accel::Embree(e) => e.closest(origin, dir, tmax),
        }
    }

    /// The hit record of a batch answer (`intersect_batch`) for its ray: with `found[i]` and
    /// `rays[i]`, `hit_at(&rays[i], found[i]?)` is `intersect(rays[i])`, bit for bit.
    #[inline]
    pub fn hit_at(&self, ray: &Ray, (prim, t): (u32, f32)) -> Hit {
        self.hit(ray.o, ray.d, prim, t)
    }

    /// Closest hits of a batch of rays as (primitive, t), with the same ray counts as `intersect`
    /// ray by ray: `hit_at` builds the record of the ones a caller shades (building them all here
    /// cost about 4% of `pt`, `results/2026-12-04-lazy-hits.md`). The Embree back end
    /// traces the batch in 16-wide packets (its per-call cost is what a batch saves,
    /// `results/2026-12-04-core-wavefront.md`, `results/2026-12-05-embree-packets.md`); obvhs
    /// ray by ray. `coherent` is a hint that runs of 16 rays leave one point in nearly one
    /// direction (a pixel's camera rays, `render::render_passes`): Embree then traces them with
    /// its coherent code path (`results/2026-12-05-pass-groups.md`); the hits are the same.
    pub fn intersect_batch(
        &self,
        rays: &[Ray],
        scratch: &mut BatchScratch,
        out: &mut Vec<Option<(u32, f32)>>,
        coherent: bool,
    ) {
        out.clear();
        match &self.accel {
            #[cfg(feature = "embree")]
            Accel::Embree(e) => {
                count(rays.len() as u64, 0);
                e.closest_batch(rays, &mut scratch.embree, out, coherent);
            }
            _ => {
                let _ = (scratch, coherent);
                out.extend(rays.iter().map(|r| self.closest(r.o, r.d, r.tmax)));
            }
        }
    }

    /// Occlusion of a batch of segments: `out[i]` is `occluded(rays[i])` (as `intersect_batch`).
    pub fn occluded_batch(&self, rays: &[Ray], scratch: &mut BatchScratch, out: &mut Vec<bool>) {
        match &self.accel {
            #[cfg(feature = "embree")]
            Accel::Embree(e) => {
                count(0, rays.len() as u64);
                e.occluded_batch(rays, &mut scratch.embree, out);
            }
            _ => {
                let _ = scratch;
                out.clear();
                out.extend(rays.iter().map(|r| self.occluded(r.o, r.d, r.tmax)));
            }
        }
    }

    /// The hit record of primitive `prim` at `t` along the ray.
    #[inline(always)]
    fn hit(&self, origin: Vec3, dir: Vec3, prim: u32, t: f32) -> Hit {
        let p = origin + t * dir;
        let ntri = self.scene.ntri();
        if prim < ntri {
            let tri = &self.scene.triangles[prim as usize];
            let ns = match &tri.n {
                Some(n) => {
                    let (b1, b2) = barycentrics(tri.p, p);
                    let v = (1.0 - b1 - b2) * n[0] + b1 * n[1] + b2 * n[2];
                    let v = v.normalize_or_zero();
                    if v.dot(tri.ng) > 1e-4 {
                        v
                    } else {
                        tri.ng
                    }
                }
                None => tri.ng,
            };
            Hit { t, p, ng: tri.ng, ns, prim }
        } else {
            let s = &self.scene.spheres[(prim - ntri) as usize];
            let mut n = ((p - s.center) / s.radius).normalize();
            if s.inward {
                n = -n;
            }
            Hit { t, p: on_sphere(s, p), ng: n, ns: n, prim }
        }
    }

    /// `hit`'s point `p` of the hit `(prim, t)` along `ray`, without the rest of the record.
    #[inline(always)]
    fn hit_point(&self, ray: &Ray, (prim, t): (u32, f32)) -> Vec3 {
        let p = ray.o + t * ray.d;
        let ntri = self.scene.ntri();
        if prim < ntri {
            p
        } else {
            on_sphere(&self.scene.spheres[(prim - ntri) as usize], p)
        }
    }

    /// Prefetches what shading the batch answer `found` (`intersect_batch`) of `rays` will read
    /// from memory: for a hit, the texels of its surface's textures and map at its point
    /// (`Scene::prefetch_shading`), where `surfaces` (false where no hit of the batch will be
    /// shaded, only checked for an emitter); for a ray that escaped, the environment texels of its
    /// direction (`Environment::prefetch`). Issued for the whole batch before its first hit is
    /// shaded, so that the misses overlap; a hint, with no effect on any value
    /// (`results/2026-12-08-prefetch.md`).
    pub fn prefetch_shading(&self, rays: &[Ray], found: &[Option<(u32, f32)>], surfaces: bool) {
        let s = &self.scene;
        if s.textures.is_empty() && s.environment.is_none() {
            return;
        }
        for (ray, f) in rays.iter().zip(found) {
            match *f {
                Some(h) if surfaces => s.prefetch_shading(h.0, self.hit_point(ray, h)),
                Some(_) => {}
                None => {
                    if let Some(env) = &s.environment {
                        env.prefetch(ray.d);
                    }
                }
            }
        }
    }

    /// True if anything blocks the open segment (0, tmax) along unit `dir`.
    pub fn occluded(&self, origin: Vec3, dir: Vec3, tmax: f32) -> bool {
        count(0, 1);
        match &self.accel {
            Accel::Obvhs(b) => b.occluded(&self.scene, origin, dir, tmax),
            Accel::Wide(b) => b.occluded(&self.scene, origin, dir, tmax),
            #[cfg(feature = "embree")]
            Accel::Embree(e) => e.occluded(origin, dir, tmax),
        }
    }

    /// Visibility between surface points `a` (normal `na`) and `b` (normal `nb`).
    pub fn visible(&self, a: Vec3, na: Vec3, b: Vec3, nb: Vec3) -> bool {
        self.visibility_ray(a, na, b, nb).is_some_and(|r| !self.occluded(r.o, r.d, r.tmax))
    }

    /// The shadow segment that [`World::visible`] tests between `a` (normal `na`) and `b`
    /// (normal `nb`), both ends offset off their surfaces; `None` when the points coincide
    /// (never visible).
    pub fn visibility_ray(&self, a: Vec3, na: Vec3, b: Vec3, nb: Vec3) -> Option<Ray> {
        let (ray, valid) = shadow_segment(a, na, b, nb);
        valid.then_some(ray)
    }
}

/// Barycentric (b1, b2) of `p` in triangle `t` (b0 = 1 − b1 − b2).
#[inline]
fn barycentrics(t: [Vec3; 3], p: Vec3) -> (f32, f32) {
    let (e1, e2, d) = (t[1] - t[0], t[2] - t[0], p - t[0]);
    let (d00, d01, d11) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
    let (d20, d21) = (d.dot(e1), d.dot(e2));
    let den = d00 * d11 - d01 * d01;
    if den.abs() < 1e-30 {
        return (1.0 / 3.0, 1.0 / 3.0);
    }
    ((d11 * d20 - d01 * d21) / den, (d00 * d21 - d01 * d20) / den)
}

/// `sphere_t` with tmin 0 for the 16 lanes of a packet in structure-of-arrays form (Embree's
/// layout: `o`, `d` are the x, y, z fields): lane `j` is `sphere_t(c, r, o_j, d_j, 0, tmax[j])`
/// bit for bit, the same operations in the same order, its branches as selects, so that LLVM runs
/// the lanes as one vector (the Embree back end's loop over a few spheres,
/// `results/2026-12-05-lane-spheres.md`).
#[cfg(feature = "embree")]
#[inline]
fn sphere_t16(c: Vec3, r: f32, o: [&[f32; 16]; 3], d: [&[f32; 16]; 3], tmax: &[f32; 16]) -> [f32; 16] {
    let mut out = [0.0f32; 16];
    for j in 0..16 {
        let (fx, fy, fz) = (o[0][j] - c.x, o[1][j] - c.y, o[2][j] - c.z);
        let (dx, dy, dz) = (d[0][j], d[1][j], d[2][j]);
        let b = -((fx * dx + fy * dy) + fz * dz);
        let (lx, ly, lz) = (fx + dx * b, fy + dy * b, fz + dz * b);
        let disc = r * r - ((lx * lx + ly * ly) + lz * lz);
        let cc = ((fx * fx + fy * fy) + fz * fz) - r * r;
        let q = b + b.signum() * disc.sqrt();
        let (t0, t1) = if q == 0.0 { (0.0, 0.0) } else { (cc / q, q) };
        let (t0, t1) = if t0 > t1 { (t1, t0) } else { (t0, t1) };
        let tm = tmax[j];
        let t = if t0 > 0.0 && t0 < tm {
            t0
        } else if t1 > 0.0 && t1 < tm {
            t1
        } else {
            f32::INFINITY
        };
        out[j] = if disc < 0.0 { f32::INFINITY } else { t };
    }
    out
}

/// Ray–sphere distance in (tmin, tmax), or ∞ (unit direction `d`; Ray Tracing Gems ch. 7 form).
/// The one sphere test of both back ends.
#[inline]
fn sphere_t(c: Vec3, r: f32, o: Vec3, d: Vec3, tmin: f32, tmax: f32) -> f32 {
    let f = o - c;
    let b = -f.dot(d);
    let l = f + b * d;
    let disc = r * r - l.dot(l);
    if disc < 0.0 {
        return f32::INFINITY;
    }
    let cc = f.dot(f) - r * r;
    let q = b + b.signum() * disc.sqrt();
    let (mut t0, mut t1) = if q == 0.0 { (0.0, 0.0) } else { (cc / q, q) };
    if t0 > t1 {
        std::mem::swap(&mut t0, &mut t1);
    }
    if t0 > tmin && t0 < tmax {
        t0
    } else if t1 > tmin && t1 < tmax {
        t1
    } else {
        f32::INFINITY
    }
}
