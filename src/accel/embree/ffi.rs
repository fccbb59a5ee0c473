//! The Embree 3 declarations the back end uses: raw FFI written against the installed
//! `embree3/rtcore*.h` (values from 3.13.5), and the structure-of-arrays records of the 16-wide
//! packet calls. Nothing here is safe to call on its own: `super` (the back end) holds the
//! invariants (a committed scene, aligned records, live buffers).

#![allow(non_snake_case, non_camel_case_types, dead_code)]

use std::ffi::{c_char, c_int, c_uint, c_void};
pub type RTCDevice = *mut c_void;
pub type RTCScene = *mut c_void;
pub type RTCGeometry = *mut c_void;
pub const RTC_GEOMETRY_TYPE_TRIANGLE: c_uint = 0;
pub const RTC_GEOMETRY_TYPE_USER: c_uint = 120;
pub const RTC_BUFFER_TYPE_INDEX: c_uint = 0;
pub const RTC_BUFFER_TYPE_VERTEX: c_uint = 1;
pub const RTC_FORMAT_UINT3: c_uint = 0x5003;
pub const RTC_FORMAT_FLOAT3: c_uint = 0x9003;
pub const RTC_SCENE_FLAG_NONE: c_uint = 0;
pub const RTC_SCENE_FLAG_ROBUST: c_uint = 1 << 2;
pub const RTC_BUILD_QUALITY_HIGH: c_uint = 2;
pub const RTC_INVALID_GEOMETRY_ID: c_uint = u32::MAX;
pub const RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT: c_uint = 0;
pub const RTC_INTERSECT_CONTEXT_FLAG_COHERENT: c_uint = 1;

/// `RTCIntersectContext` with `RTC_MAX_INSTANCE_LEVEL_COUNT` 1 and `RTC_MIN_WIDTH` 0.
#[repr(C)]
pub struct RTCIntersectContext {
    pub flags: c_uint,
    pub filter: *const c_void,
    pub instID: [c_uint; 1],
}
#[repr(C, align(16))]
#[derive(Clone, Copy, Default)]
pub struct RTCRay {
    pub org: [f32; 3],
    pub tnear: f32,
    pub dir: [f32; 3],
    pub time: f32,
    pub tfar: f32,
    pub mask: c_uint,
    pub id: c_uint,
    pub flags: c_uint,
}
#[repr(C, align(16))]
#[derive(Clone, Copy, Default)]
pub struct RTCHit {
    pub Ng: [f32; 3],
    pub u: f32,
    pub v: f32,
    pub primID: c_uint,
    pub geomID: c_uint,
    pub instID: [c_uint; 1],
}
#[repr(C)]
#[derive(Clone, Copy, Default)]
pub struct RTCRayHit {
    pub ray: RTCRay,
    pub hit: RTCHit,
}
#[repr(C, align(16))]
pub struct RTCBounds {
    pub lower: [f32; 3],
    pub align0: f32,
    pub upper: [f32; 3],
    pub align1: f32,
}
#[repr(C)]
pub struct RTCBoundsFunctionArguments {
    pub geometryUserPtr: *mut c_void,
    pub primID: c_uint,
    pub timeStep: c_uint,
    pub bounds_o: *mut RTCBounds,
}
#[repr(C)]
pub struct RTCIntersectFunctionNArguments {
    pub valid: *mut c_int,
    pub geometryUserPtr: *mut c_void,
    pub primID: c_uint,
    pub context: *mut RTCIntersectContext,
    pub rayhit: *mut f32,
    pub N: c_uint,
    pub geomID: c_uint,
}
#[repr(C)]
pub struct RTCOccludedFunctionNArguments {
    pub valid: *mut c_int,
    pub geometryUserPtr: *mut c_void,
    pub primID: c_uint,
    pub context: *mut RTCIntersectContext,
    pub ray: *mut f32,
    pub N: c_uint,
    pub geomID: c_uint,
}
pub type BoundsFn = unsafe extern "C" fn(*const RTCBoundsFunctionArguments);
pub type IntersectFn = unsafe extern "C" fn(*const RTCIntersectFunctionNArguments);
pub type OccludedFn = unsafe extern "C" fn(*const RTCOccludedFunctionNArguments);

/// `RTCRayHit16`: 12 ray fields then 8 hit fields, each 16 lanes of 4 bytes.
#[repr(C, align(64))]
pub struct RTCRayHit16(pub [[f32; 16]; 20]);
/// `RTCRay16`: the 12 ray fields.
#[repr(C, align(64))]
pub struct RTCRay16(pub [[f32; 16]; 12]);
/// A packet's valid mask (−1 valid, 0 not).
#[repr(C, align(64))]
pub struct Valid16(pub [c_int; 16]);
const _: () = assert!(std::mem::size_of::<RTCRayHit16>() == 1280 && std::mem::size_of::<RTCRay16>() == 768);

#[link(name = "embree3")]
extern "C" {
    pub fn rtcNewDevice(config: *const c_char) -> RTCDevice;
    pub fn rtcReleaseDevice(device: RTCDevice);
    pub fn rtcGetDeviceError(device: RTCDevice) -> c_uint;
    pub fn rtcNewScene(device: RTCDevice) -> RTCScene;
    pub fn rtcSetSceneFlags(scene: RTCScene, flags: c_uint);
    pub fn rtcSetSceneBuildQuality(scene: RTCScene, quality: c_uint);
    pub fn rtcAttachGeometryByID(scene: RTCScene, geometry: RTCGeometry, id: c_uint);
    pub fn rtcCommitScene(scene: RTCScene);
    pub fn rtcReleaseScene(scene: RTCScene);
    pub fn rtcNewGeometry(device: RTCDevice, kind: c_uint) -> RTCGeometry;
    pub fn rtcSetNewGeometryBuffer(
        geometry: RTCGeometry,
        kind: c_uint,
        slot: c_uint,
        format: c_uint,
        stride: usize,
        count: usize,
    ) -> *mut c_void;
    pub fn rtcSetGeometryBuildQuality(geometry: RTCGeometry, quality: c_uint);
    pub fn rtcSetGeometryUserPrimitiveCount(geometry: RTCGeometry, count: c_uint);
    pub fn rtcSetGeometryUserData(geometry: RTCGeometry, ptr: *mut c_void);
    pub fn rtcSetGeometryBoundsFunction(geometry: RTCGeometry, f: BoundsFn, user: *mut c_void);
    pub fn rtcSetGeometryIntersectFunction(geometry: RTCGeometry, f: IntersectFn);
    pub fn rtcSetGeometryOccludedFunction(geometry: RTCGeometry, f: OccludedFn);
    pub fn rtcCommitGeometry(geometry: RTCGeometry);
    pub fn rtcReleaseGeometry(geometry: RTCGeometry);
    pub fn rtcIntersect1(scene: RTCScene, context: *mut RTCIntersectContext, rayhit: *mut RTCRayHit);
    pub fn rtcOccluded1(scene: RTCScene, context: *mut RTCIntersectContext, ray: *mut RTCRay);
    pub fn rtcIntersect16(
        valid: *const Valid16,
        scene: RTCScene,
        context: *mut RTCIntersectContext,
        rayhit: *mut RTCRayHit16,
    );
    pub fn rtcOccluded16(valid: *const Valid16, scene: RTCScene, context: *mut RTCIntersectContext, ray: *mut RTCRay16);
}
