//! The Embree back end (cargo feature `embree`, off by default): Intel Embree 3 (the system's
//! `libembree3`, Debian `libembree-dev` 3.13) over the same primitives as the obvhs back end.
//!
//! Bindings: raw FFI declarations of the few Embree 3 functions used (`ffi`, in `embree/ffi.rs`,
//! written against the installed `embree3/rtcore*.h`), not the `embree` crate (embree-rs 0.3): its
//! safe API has no user geometry, which the analytic spheres need, and the dozen calls here are
//! simpler to audit than a binding's full surface. `rtcInitIntersectContext` is an inline function in the header,
//! so `context()` does what it does.
//!
//! Geometry 0 (`TRI_GEOM`) is one triangle mesh with three unshared vertices per triangle (the
//! scene's coordinates, bit for bit); geometry 1 (`SPHERE_GEOM`) is a user geometry whose callbacks
//! run `super::sphere_t`, the sphere test of the obvhs back end; with at most `LOOP_SPHERES`
//! spheres (the committed scenes) they are tested in a loop before the Embree query instead, which
//! spares Embree's callbacks. The scene is built with `RTC_BUILD_QUALITY_HIGH` and the default
//! flags: `RTC_SCENE_FLAG_ROBUST` (a watertight triangle test) traced 10–25% fewer closest-hit
//! rays per second on `ring` and is not needed for agreement: the default test matches obvhs'
//! inclusive test on every random ray of `tests/accel_embree.rs` (robust mode differed on 6 of
//! 96k rays at shared edges), and a ray through a shared edge hits (`tests/bvh.rs`).
//!
//! Invariants: primitive ids map back to `Scene` ids (triangle `primID`, `ntri + primID` for
//! spheres); the sphere data the callbacks read is owned here in a boxed slice (stable address) and
//! never changes after the build; a committed scene is only read, which Embree allows from any
//! number of threads (hence `Send`/`Sync`); the device and scene are released once, in `Drop`.

use crate::math::Vec3;
use crate::scene::Scene;
use std::ffi::c_void;

/// The Embree 3 declarations used (values from `rtcore_*.h`, 3.13.5).
mod ffi;

/// Geometry id of the triangle mesh.
const TRI_GEOM: u32 = 0;
/// Geometry id of the spheres.
const SPHERE_GEOM: u32 = 1;

/// A sphere as the callbacks read it.
#[derive(Clone, Copy)]
struct SphereData {
    center: Vec3,
    radius: f32,
}

/// At most this many spheres are tested in a loop before the Embree query instead of as a user
/// geometry (a user primitive costs Embree a callback per box hit; see `results/2026-12-03-embree-backend.md`).
const LOOP_SPHERES: usize = 8;

/// A committed Embree scene over the triangles and spheres of a `Scene`.
pub(super) struct EmbreeScene {
    device: ffi::RTCDevice,
    scene: ffi::RTCScene,
    /// Read by the sphere callbacks through the geometry's user pointer; never mutated.
    spheres: Box<[SphereData]>,
    /// The spheres are tested in a loop (≤ `LOOP_SPHERES`), not by Embree.
    loop_spheres: bool,
    ntri: u32,
}

// SAFETY: after `rtcCommitScene` the scene is only traversed, which Embree documents as thread
// safe; the sphere data is immutable; the handles are released once, in `Drop`.
unsafe impl Send for EmbreeScene {}
unsafe impl Sync for EmbreeScene {}

impl Drop for EmbreeScene {
    fn drop(&mut self) {
        // SAFETY: both handles are valid (checked non-null in `build`) and released only here.
        unsafe {
            ffi::rtcReleaseScene(self.scene);
            ffi::rtcReleaseDevice(self.device);
        }
    }
}

/// A fresh intersection context (what the header's inline `rtcInitIntersectContext` sets).
#[inline]
fn context() -> ffi::RTCIntersectContext {
    context_with(ffi::RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT)
}

/// An intersection context with `flags`: `RTC_INTERSECT_CONTEXT_FLAG_COHERENT` lets Embree trace
/// a packet whose rays run side by side (one pixel's camera rays) with its frustum code path.
#[inline]
fn context_with(flags: std::ffi::c_uint) -> ffi::RTCIntersectContext {
    ffi::RTCIntersectContext { flags, filter: std::ptr::null(), instID: [ffi::RTC_INVALID_GEOMETRY_ID] }
}

#[inline]
fn ray(origin: Vec3, dir: Vec3, tmax: f32) -> ffi::RTCRay {
    ffi::RTCRay {
        org: origin.to_array(),
        tnear: 0.0,
        dir: dir.to_array(),
        tfar: tmax,
        mask: u32::MAX,
        ..Default::default()
    }
}

impl EmbreeScene {
    /// Builds and commits the scene (bounds already checked by `World::build_with`).
    pub(super) fn build(scene: &Scene) -> Result<EmbreeScene, String> {
        // SAFETY: a null config is allowed; the result is checked before use.
        let device = unsafe { ffi::rtcNewDevice(std::ptr::null()) };
        if device.is_null() {
            return Err("Embree: rtcNewDevice failed (unsupported CPU?)".into());
        }
        let spheres: Box<[SphereData]> =
            scene.spheres.iter().map(|s| SphereData { center: s.center, radius: s.radius }).collect();
        // SAFETY: `device` is valid; a null scene is released nowhere (checked here).
        let handle = unsafe { ffi::rtcNewScene(device) };
        if handle.is_null() {
            // SAFETY: `device` is valid and released once, here.
            let err = unsafe {
                let err = ffi::rtcGetDeviceError(device);
                ffi::rtcReleaseDevice(device);
                err
            };
            return Err(format!("Embree: rtcNewScene failed (RTCError {err})"));
        }
        let loop_spheres = spheres.len() <= LOOP_SPHERES;
        let e = EmbreeScene { device, scene: handle, spheres, loop_spheres, ntri: scene.ntri() };
        // SAFETY: valid handles; buffers are filled within their allocated sizes.
        unsafe {
            ffi::rtcSetSceneFlags(e.scene, ffi::RTC_SCENE_FLAG_NONE);
            ffi::rtcSetSceneBuildQuality(e.scene, ffi::RTC_BUILD_QUALITY_HIGH);
            if !scene.triangles.is_empty() {
                e.attach_triangles(scene);
            }
            if !e.spheres.is_empty() && !e.loop_spheres {
                e.attach_spheres();
            }
            ffi::rtcCommitScene(e.scene);
            if let err @ 1.. = ffi::rtcGetDeviceError(device) {
                return Err(format!("Embree: building the scene failed (RTCError {err})"));
            }
            // a libembree3 built without ray packets reports an error here instead of tracing
            let mut probe = Scratch::default();
            put_lane(&mut probe.hit16.0, 0, Vec3::new(0.0, 0.0, 0.0), Vec3::new(0.0, 0.0, 1.0), 0.0);
            probe.hit16.0[18][0] = f32::from_bits(ffi::RTC_INVALID_GEOMETRY_ID);
            e.closest16(&mut probe.hit16.0, &[0], &mut context(), &mut [None]);
            match ffi::rtcGetDeviceError(device) {
                0 => Ok(e),
                err => Err(format!("Embree: this libembree3 cannot trace 16-wide packets (RTCError {err})")),
            }
        }
    }

    /// Geometry `TRI_GEOM`: three unshared vertices per triangle.
    unsafe fn attach_triangles(&self, scene: &Scene) {
        let n = scene.triangles.len();
        let g = ffi::rtcNewGeometry(self.device, ffi::RTC_GEOMETRY_TYPE_TRIANGLE);
        if g.is_null() {
            return; // the device error is reported after the commit
        }
        let vb = ffi::rtcSetNewGeometryBuffer(g, ffi::RTC_BUFFER_TYPE_VERTEX, 0, ffi::RTC_FORMAT_FLOAT3, 12, 3 * n);
        let ib = ffi::rtcSetNewGeometryBuffer(g, ffi::RTC_BUFFER_TYPE_INDEX, 0, ffi::RTC_FORMAT_UINT3, 12, n);
        if vb.is_null() || ib.is_null() {
            ffi::rtcReleaseGeometry(g);
            return; // the device error is reported after the commit
        }
        let verts = std::slice::from_raw_parts_mut(vb as *mut [f32; 3], 3 * n);
        let idx = std::slice::from_raw_parts_mut(ib as *mut [u32; 3], n);
        for (i, t) in scene.triangles.iter().enumerate() {
            for k in 0..3 {
                verts[3 * i + k] = t.p[k].to_array();
            }
            let b = 3 * i as u32;
            idx[i] = [b, b + 1, b + 2];
        }
        ffi::rtcSetGeometryBuildQuality(g, ffi::RTC_BUILD_QUALITY_HIGH);
        ffi::rtcCommitGeometry(g);
        ffi::rtcAttachGeometryByID(self.scene, g, TRI_GEOM);
        ffi::rtcReleaseGeometry(g);
    }

    /// Geometry `SPHERE_GEOM`: a user geometry over `self.spheres`.
    unsafe fn attach_spheres(&self) {
        let g = ffi::rtcNewGeometry(self.device, ffi::RTC_GEOMETRY_TYPE_USER);
        if g.is_null() {
            return; // the device error is reported after the commit
        }
        let user = self.spheres.as_ptr() as *mut c_void;
        ffi::rtcSetGeometryUserPrimitiveCount(g, self.spheres.len() as u32);
        ffi::rtcSetGeometryUserData(g, user);
        ffi::rtcSetGeometryBoundsFunction(g, sphere_bounds, user);
        ffi::rtcSetGeometryIntersectFunction(g, sphere_intersect);
        ffi::rtcSetGeometryOccludedFunction(g, sphere_occluded);
        ffi::rtcCommitGeometry(g);
        ffi::rtcAttachGeometryByID(self.scene, g, SPHERE_GEOM);
        ffi::rtcReleaseGeometry(g);
    }

    /// Closest hit along `origin + t·dir`, t ∈ (0, tmax): (primitive id, t).
    #[inline]
    pub(super) fn closest(&self, origin: Vec3, dir: Vec3, tmax: f32) -> Option<(u32, f32)> {
        if tmax.is_nan() || tmax <= 0.0 {
            return None;
        }
        let (mut tfar, mut best) = (tmax, None);
        if self.loop_spheres {
            for (i, s) in self.spheres.iter().enumerate() {
                let t = super::sphere_t(s.center, s.radius, origin, dir, 0.0, tfar);
                if t < tfar {
                    (tfar, best) = (t, Some((self.ntri + i as u32, t)));
                }
            }
        }
        let mut rh = ffi::RTCRayHit { ray: ray(origin, dir, tfar), hit: ffi::RTCHit::default() };
        rh.hit.geomID = ffi::RTC_INVALID_GEOMETRY_ID;
        let mut ctx = context();
        // SAFETY: the scene is committed; `rh` and `ctx` are valid, aligned and live for the call.
        unsafe { ffi::rtcIntersect1(self.scene, &mut ctx, &mut rh) };
        match rh.hit.geomID {
            TRI_GEOM => Some((rh.hit.primID, rh.ray.tfar)),
            SPHERE_GEOM => Some((self.ntri + rh.hit.primID, rh.ray.tfar)),
            _ => best,
        }
    }

    /// True if anything blocks the segment (0, tmax) along unit `dir`.
    #[inline]
    pub(super) fn occluded(&self, origin: Vec3, dir: Vec3, tmax: f32) -> bool {
        if tmax.is_nan() || tmax <= 0.0 {
            return false;
        }
        if self.loop_spheres
            && self.spheres.iter().any(|s| super::sphere_t(s.center, s.radius, origin, dir, 0.0, tmax) < tmax)
        {
            return true;
        }
        let mut r = ray(origin, dir, tmax);
        let mut ctx = context();
        // SAFETY: as in `closest`.
        unsafe { ffi::rtcOccluded1(self.scene, &mut ctx, &mut r) };
        r.tfar == f32::NEG_INFINITY
    }
}

/// The packet records of the batch calls, reused from call to call: the rays are written into
/// them lane by lane straight from the batch (no intermediate one-ray records).
pub(super) struct Scratch {
    hit16: Box<ffi::RTCRayHit16>,
    ray16: Box<ffi::RTCRay16>,
}

impl Default for Scratch {
    fn default() -> Self {
        Scratch { hit16: Box::new(ffi::RTCRayHit16([[0.0; 16]; 20])), ray16: Box::new(ffi::RTCRay16([[0.0; 16]; 12])) }
    }
}

impl EmbreeScene {
    /// Closest hits of a batch of rays in 16-wide packets (`rtcIntersect16`, as Mitsuba 3's llvm
    /// variants call Embree: 1.01–1.04× the stream call `rtcIntersect1M`, bit for bit,
    /// `results/2026-12-05-embree-packets.md`): `found[i]` is what `closest(rays[i])` returns.
    /// The rays that need a query fill the packets in batch order, 16 to a packet.
    pub(super) fn closest_batch(
        &self,
        rays: &[super::Ray],
        s: &mut Scratch,
        found: &mut Vec<Option<(u32, f32)>>,
        coherent: bool,
    ) {
        found.clear();
        let flags = if coherent {
            ffi::RTC_INTERSECT_CONTEXT_FLAG_COHERENT
        } else {
            ffi::RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT
        };
        let mut ctx = context_with(flags);
        let (p, mut lanes) = (&mut s.hit16.0, Lanes::default());
        for (i, r) in rays.iter().enumerate() {
            found.push(None);
            if r.tmax.is_nan() || r.tmax <= 0.0 {
                continue;
            }
            put_lane(p, lanes.n, r.o, r.d, r.tmax);
            p[18][lanes.n] = f32::from_bits(ffi::RTC_INVALID_GEOMETRY_ID);
            if let Some(full) = lanes.push(i) {
                self.closest16(p, full, &mut ctx, found);
            }
        }
        self.closest16(p, lanes.rest(), &mut ctx, found);
    }

    /// Traces the first `slot.len()` lanes of packet `p`; lane `k`'s hit goes to `found[slot[k]]`.
    /// The looped spheres go first, 16 lanes at once, and shorten each lane's tfar as `closest`
    /// does one ray at a time.
    fn closest16(
        &self,
        p: &mut [[f32; 16]; 20],
        slot: &[u32],
        ctx: &mut ffi::RTCIntersectContext,
        found: &mut [Option<(u32, f32)>],
    ) {
        if slot.is_empty() {
            return;
        }
        let mut sphere = [u32::MAX; 16];
        if self.loop_spheres {
            for (k, sp) in self.spheres.iter().enumerate() {
                let t = super::sphere_t16(sp.center, sp.radius, [&p[0], &p[1], &p[2]], [&p[4], &p[5], &p[6]], &p[8]);
                for j in 0..16 {
                    if t[j] < p[8][j] {
                        (p[8][j], sphere[j]) = (t[j], k as u32);
                    }
                }
            }
        }
        let valid = valid_lanes(slot.len());
        let packet = p as *mut [[f32; 16]; 20] as *mut ffi::RTCRayHit16;
        // SAFETY: the scene is committed; `p` is a 64-byte aligned `RTCRayHit16` (a field of the
        // boxed record, `repr(C, align(64))`), `valid` is aligned, and both live for the call.
        unsafe { ffi::rtcIntersect16(&valid, self.scene, ctx, packet) };
        for (k, &i) in slot.iter().enumerate() {
            let (tfar, prim) = (p[8][k], p[17][k].to_bits());
            found[i as usize] = match p[18][k].to_bits() {
                TRI_GEOM => Some((prim, tfar)),
                SPHERE_GEOM => Some((self.ntri + prim, tfar)),
                // a looped sphere's hit: Embree leaves tfar as that sphere's t on a miss
                _ => (sphere[k] != u32::MAX).then_some((self.ntri + sphere[k], tfar)),
            };
        }
    }

    /// Occlusion of a batch of segments in 16-wide packets (`rtcOccluded16`):
    /// `out[i]` is what `occluded(rays[i])` returns.
    pub(super) fn occluded_batch(&self, rays: &[super::Ray], s: &mut Scratch, out: &mut Vec<bool>) {
        out.clear();
        let mut ctx = context();
        let (p, mut lanes) = (&mut s.ray16.0, Lanes::default());
        for (i, r) in rays.iter().enumerate() {
            out.push(false);
            if r.tmax.is_nan() || r.tmax <= 0.0 {
                continue;
            }
            put_lane(p, lanes.n, r.o, r.d, r.tmax);
            if let Some(full) = lanes.push(i) {
                self.occluded16(p, full, &mut ctx, out);
            }
        }
        self.occluded16(p, lanes.rest(), &mut ctx, out);
    }

    /// Traces the first `slot.len()` lanes of packet `p`; lane `k`'s answer goes to `out[slot[k]]`.
    /// A lane that a looped sphere blocks (tested 16 lanes at once) is answered without Embree.
    fn occluded16(&self, p: &mut [[f32; 16]; 12], slot: &[u32], ctx: &mut ffi::RTCIntersectContext, out: &mut [bool]) {
        if slot.is_empty() {
            return;
        }
        let mut valid = valid_lanes(slot.len());
        if self.loop_spheres {
            for sp in self.spheres.iter() {
                let t = super::sphere_t16(sp.center, sp.radius, [&p[0], &p[1], &p[2]], [&p[4], &p[5], &p[6]], &p[8]);
                for j in 0..16 {
                    if t[j] < p[8][j] {
                        valid.0[j] = 0;
                    }
                }
            }
        }
        let packet = p as *mut [[f32; 16]; 12] as *mut ffi::RTCRay16;
        // SAFETY: as in `closest16` (`p` is the boxed `RTCRay16`'s field).
        unsafe { ffi::rtcOccluded16(&valid, self.scene, ctx, packet) };
        for (k, &i) in slot.iter().enumerate() {
            out[i as usize] = valid.0[k] == 0 || p[8][k] == f32::NEG_INFINITY;
        }
    }
}

/// The batch index of each filled lane of the packet being built.
#[derive(Default)]
struct Lanes {
    slot: [u32; 16],
    /// Lanes filled (the next one to fill).
    n: usize,
}

impl Lanes {
    /// Records that lane `n` holds the batch's ray `i`; the full packet's slots when that was
    /// the 16th lane (the packet then starts again empty).
    #[inline]
    fn push(&mut self, i: usize) -> Option<&[u32]> {
        (self.slot[self.n], self.n) = (i as u32, self.n + 1);
        (self.n == 16).then(|| {
            self.n = 0;
            &self.slot[..]
        })
    }

    /// The slots of the last, partial packet (possibly none).
    fn rest(&self) -> &[u32] {
        &self.slot[..self.n]
    }
}

/// Writes the ray (origin, unit direction, (0, tfar)) into lane `i` of a packet's first 12
/// fields, as `ray` builds a one-ray record: time 0, every mask bit, id and flags 0.
#[inline]
fn put_lane(p: &mut [[f32; 16]], i: usize, o: Vec3, d: Vec3, tfar: f32) {
    let f = [o.x, o.y, o.z, 0.0, d.x, d.y, d.z, 0.0, tfar];
    for (k, v) in f.into_iter().enumerate() {
        p[k][i] = v;
    }
    p[9][i] = f32::from_bits(u32::MAX);
    p[10][i] = 0.0;
    p[11][i] = 0.0;
}

/// A packet's valid mask with its first `n` lanes on.
#[inline]
fn valid_lanes(n: usize) -> ffi::Valid16 {
    ffi::Valid16(std::array::from_fn(|i| if i < n { -1 } else { 0 }))
}

/// The box of sphere `primID` (Embree's bounds callback).
unsafe extern "C" fn sphere_bounds(args: *const ffi::RTCBoundsFunctionArguments) {
    let a = &*args;
    let s = *(a.geometryUserPtr as *const SphereData).add(a.primID as usize);
    let r = Vec3::splat(s.radius);
    let b = &mut *a.bounds_o;
    b.lower = (s.center - r).to_array();
    b.upper = (s.center + r).to_array();
}

/// Field `f` of ray `i` of a packet of `n` rays in Embree's structure-of-arrays layout
/// (`RTCRayHitN`: 12 ray fields, then the hit's; every field is 4 bytes).
#[inline]
unsafe fn field(base: *mut f32, n: usize, f: usize, i: usize) -> *mut f32 {
    base.add(f * n + i)
}

/// Ray `i` of a packet: (origin, direction, tnear, tfar).
#[inline]
unsafe fn packet_ray(base: *mut f32, n: usize, i: usize) -> (Vec3, Vec3, f32, f32) {
    let g = |f| *field(base, n, f, i);
    (Vec3::new(g(0), g(1), g(2)), Vec3::new(g(4), g(5), g(6)), g(3), g(8))
}

/// Embree's intersect callback: `super::sphere_t`, shortening tfar and writing the hit.
unsafe extern "C" fn sphere_intersect(args: *const ffi::RTCIntersectFunctionNArguments) {
    let a = &*args;
    let s = *(a.geometryUserPtr as *const SphereData).add(a.primID as usize);
    let n = a.N as usize;
    for i in (0..n).filter(|&i| *a.valid.add(i) != 0) {
        let (o, d, tnear, tfar) = packet_ray(a.rayhit, n, i);
        let t = super::sphere_t(s.center, s.radius, o, d, tnear, tfar);
        if t < f32::INFINITY {
            let ng = o + t * d - s.center;
            *field(a.rayhit, n, 8, i) = t;
            for (k, v) in [ng.x, ng.y, ng.z, 0.0, 0.0].into_iter().enumerate() {
                *field(a.rayhit, n, 12 + k, i) = v;
            }
            let ids = [a.primID, a.geomID, (*a.context).instID[0]];
            for (k, v) in ids.into_iter().enumerate() {
                *(field(a.rayhit, n, 17 + k, i) as *mut u32) = v;
            }
        }
    }
}

/// Embree's occluded callback: tfar = −∞ on a hit.
unsafe extern "C" fn sphere_occluded(args: *const ffi::RTCOccludedFunctionNArguments) {
    let a = &*args;
    let s = *(a.geometryUserPtr as *const SphereData).add(a.primID as usize);
    let n = a.N as usize;
    for i in (0..n).filter(|&i| *a.valid.add(i) != 0) {
        let (o, d, tnear, tfar) = packet_ray(a.ray, n, i);
        if super::sphere_t(s.center, s.radius, o, d, tnear, tfar) < f32::INFINITY {
            *field(a.ray, n, 8, i) = f32::NEG_INFINITY;
        }
    }
}
