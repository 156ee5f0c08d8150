//! The only `unsafe` in ember-host: our own minimal bindings to Embree 3.13's C API
//! (Debian's `libembree-dev`, `libembree3.so`), written from its headers
//! (`/usr/include/embree3/rtcore_*.h`), and the safe owner of one committed scene.
//!
//! # What is bound
//! A device (with a memory monitor that counts what Embree allocates), a scene holding
//! one triangle geometry over *shared* buffers (our vertex and index arrays, which Embree
//! reads in place and never copies), the commit, and the queries: `rtcIntersect1` /
//! `rtcOccluded1` and the packet forms `rtcIntersect4/8/16` / `rtcOccluded4/8/16` with
//! their valid masks. Nothing else (no instancing, filters, streams, motion blur).
//!
//! # Why each `unsafe` holds
//! - **Lifetimes.** [`EmbreeScene`] owns the device, the scene and the buffers the
//!   scene reads. Its `Drop` releases the scene first; the fields then drop in
//!   declaration order: the device (whose release may still report freed bytes to the
//!   monitor), then the buffers and the monitor's counter, which nothing reads any more.
//!   The buffers live in `Vec`s that are never touched after the commit, so the pointers
//!   Embree keeps stay valid.
//! - **Padding.** Embree reads a `FLOAT3` vertex with a 16-byte load, so the vertex
//!   buffer carries one extra element past the count it is given (rtcSetSharedGeometryBuffer's
//!   documented requirement).
//! - **Layouts.** The ray and hit structs repeat the headers' field order; the header's
//!   `RTC_MAX_INSTANCE_LEVEL_COUNT` is 1 and `RTC_MIN_WIDTH` 0 in this build
//!   (`rtcore_config.h`), which fixes `RTCIntersectContext` to three fields. Packets are
//!   aligned to 64 bytes, at least what each width asks (16, 32, 64). Sizes are
//!   checked at compile time below against the C sizes (80, 320, 640, 1280 bytes).
//! - **Threads.** Embree documents queries on a committed scene as thread-safe; the
//!   scene is never modified after [`EmbreeScene::new`], and the monitor's counter is
//!   atomic. Hence the `Send` and `Sync` implementations.
//! - **Input.** Every query takes its ray by value in a struct built here; Embree writes
//!   only into that struct.

#![allow(unsafe_code)]

use core::ffi::{c_char, c_int, c_uint, c_void};
use std::sync::atomic::{AtomicI64, Ordering};

type RtcDevice = *mut c_void;
type RtcScene = *mut c_void;
type RtcGeometry = *mut c_void;

const RTC_GEOMETRY_TYPE_TRIANGLE: c_uint = 0;
const RTC_BUFFER_TYPE_INDEX: c_uint = 0;
const RTC_BUFFER_TYPE_VERTEX: c_uint = 1;
const RTC_FORMAT_UINT3: c_uint = 0x5003;
const RTC_FORMAT_FLOAT3: c_uint = 0x9003;
const RTC_SCENE_FLAG_ROBUST: c_uint = 1 << 2;
const RTC_BUILD_QUALITY_MEDIUM: c_uint = 1;
const RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT: c_uint = 0;
const RTC_INTERSECT_CONTEXT_FLAG_COHERENT: c_uint = 1;
/// `RTC_INVALID_GEOMETRY_ID`: a hit's geometry id when nothing was hit.
pub const INVALID_ID: u32 = u32::MAX;

/// `RTCIntersectContext` in this build (one instance level, no minimum width).
#[repr(C)]
struct Context {
    flags: c_uint,
    filter: Option<extern "C" fn(*const c_void)>,
    inst_id: [c_uint; 1],
}

impl Context {
    /// What `rtcInitIntersectContext` sets, with the coherence hint.
    fn new(coherent: bool) -> Self {
        let flags = if coherent { RTC_INTERSECT_CONTEXT_FLAG_COHERENT } else { RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT };
        Self { flags, filter: None, inst_id: [INVALID_ID] }
    }
}

/// `RTCRay`.
#[repr(C, align(16))]
#[derive(Clone, Copy, Debug, Default)]
pub struct Ray1 {
    pub org: [f32; 3],
    pub tnear: f32,
    pub dir: [f32; 3],
    pub time: f32,
    pub tfar: f32,
    pub mask: u32,
    pub id: u32,
    pub flags: u32,
}

/// `RTCHit`.
#[repr(C, align(16))]
#[derive(Clone, Copy, Debug, Default)]
pub struct Hit1 {
    pub ng: [f32; 3],
    pub u: f32,
    pub v: f32,
    pub prim_id: u32,
    pub geom_id: u32,
    pub inst_id: [u32; 1],
}

/// `RTCRayHit`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct RayHit1 {
    pub ray: Ray1,
    pub hit: Hit1,
}

/// `RTCRayN` for N = 4, 8, 16 (structure of arrays, the header's field order).
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct RayN<const N: usize> {
    pub org_x: [f32; N],
    pub org_y: [f32; N],
    pub org_z: [f32; N],
    pub tnear: [f32; N],
    pub dir_x: [f32; N],
    pub dir_y: [f32; N],
    pub dir_z: [f32; N],
    pub time: [f32; N],
    pub tfar: [f32; N],
    pub mask: [u32; N],
    pub id: [u32; N],
    pub flags: [u32; N],
}

/// `RTCHitN` for N = 4, 8, 16.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct HitN<const N: usize> {
    pub ng_x: [f32; N],
    pub ng_y: [f32; N],
    pub ng_z: [f32; N],
    pub u: [f32; N],
    pub v: [f32; N],
    pub prim_id: [u32; N],
    pub geom_id: [u32; N],
    pub inst_id: [[u32; N]; 1],
}

/// `RTCRayHitN` for N = 4, 8, 16, aligned for the widest (the ray part's size is a
/// multiple of each width's alignment, so the hit part sits where C puts it).
#[repr(C, align(64))]
#[derive(Clone, Copy, Debug)]
pub struct RayHitN<const N: usize> {
    pub ray: RayN<N>,
    pub hit: HitN<N>,
}

/// `RTCRayN` alone (the occlusion queries' argument), aligned for the widest.
#[repr(C, align(64))]
#[derive(Clone, Copy, Debug)]
pub struct RayOnlyN<const N: usize> {
    pub ray: RayN<N>,
}

impl<const N: usize> Default for RayN<N> {
    fn default() -> Self {
        Self {
            org_x: [0.0; N],
            org_y: [0.0; N],
            org_z: [0.0; N],
            tnear: [0.0; N],
            dir_x: [0.0; N],
            dir_y: [0.0; N],
            dir_z: [0.0; N],
            time: [0.0; N],
            tfar: [0.0; N],
            mask: [u32::MAX; N],
            id: [0; N],
            flags: [0; N],
        }
    }
}

impl<const N: usize> Default for HitN<N> {
    fn default() -> Self {
        Self { ng_x: [0.0; N], ng_y: [0.0; N], ng_z: [0.0; N], u: [0.0; N], v: [0.0; N], prim_id: [0; N], geom_id: [INVALID_ID; N], inst_id: [[INVALID_ID; N]] }
    }
}

const _: () = {
    assert!(size_of::<Context>() == 24);
    assert!(size_of::<RayHit1>() == 80);
    assert!(size_of::<RayN<4>>() == 192 && size_of::<HitN<4>>() == 128 && size_of::<RayHitN<4>>() == 320);
    assert!(size_of::<RayN<8>>() == 384 && size_of::<HitN<8>>() == 256 && size_of::<RayHitN<8>>() == 640);
    assert!(size_of::<RayN<16>>() == 768 && size_of::<HitN<16>>() == 512 && size_of::<RayHitN<16>>() == 1280);
};

type MemoryMonitor = extern "C" fn(user: *mut c_void, bytes: isize, post: bool) -> bool;

#[link(name = "embree3")]
unsafe extern "C" {
    fn rtcNewDevice(config: *const c_char) -> RtcDevice;
    fn rtcReleaseDevice(device: RtcDevice);
    fn rtcGetDeviceError(device: RtcDevice) -> c_uint;
    fn rtcGetDeviceProperty(device: RtcDevice, prop: c_uint) -> isize;
    fn rtcSetDeviceMemoryMonitorFunction(device: RtcDevice, monitor: Option<MemoryMonitor>, user: *mut c_void);
    fn rtcNewScene(device: RtcDevice) -> RtcScene;
    fn rtcReleaseScene(scene: RtcScene);
    fn rtcSetSceneFlags(scene: RtcScene, flags: c_uint);
    fn rtcSetSceneBuildQuality(scene: RtcScene, quality: c_uint);
    fn rtcAttachGeometry(scene: RtcScene, geometry: RtcGeometry) -> c_uint;
    fn rtcCommitScene(scene: RtcScene);
    fn rtcNewGeometry(device: RtcDevice, kind: c_uint) -> RtcGeometry;
    fn rtcReleaseGeometry(geometry: RtcGeometry);
    fn rtcCommitGeometry(geometry: RtcGeometry);
    fn rtcSetSharedGeometryBuffer(
        geometry: RtcGeometry,
        kind: c_uint,
        slot: c_uint,
        format: c_uint,
        ptr: *const c_void,
        byte_offset: usize,
        byte_stride: usize,
        count: usize,
    );
    fn rtcIntersect1(scene: RtcScene, context: *mut Context, rayhit: *mut RayHit1);
    fn rtcOccluded1(scene: RtcScene, context: *mut Context, ray: *mut Ray1);
    fn rtcIntersect4(valid: *const c_int, scene: RtcScene, context: *mut Context, rayhit: *mut c_void);
    fn rtcIntersect8(valid: *const c_int, scene: RtcScene, context: *mut Context, rayhit: *mut c_void);
    fn rtcIntersect16(valid: *const c_int, scene: RtcScene, context: *mut Context, rayhit: *mut c_void);
    fn rtcOccluded4(valid: *const c_int, scene: RtcScene, context: *mut Context, ray: *mut c_void);
    fn rtcOccluded8(valid: *const c_int, scene: RtcScene, context: *mut Context, ray: *mut c_void);
    fn rtcOccluded16(valid: *const c_int, scene: RtcScene, context: *mut Context, ray: *mut c_void);
}

/// Bytes Embree holds now and at most, as its memory monitor reports them.
#[derive(Debug, Default)]
struct Counter {
    now: AtomicI64,
    peak: AtomicI64,
}

extern "C" fn monitor(user: *mut c_void, bytes: isize, _post: bool) -> bool {
    // SAFETY: `user` is the `Counter` boxed in the `EmbreeScene` that owns the device,
    // which outlives every callback (see the module documentation).
    let counter = unsafe { &*(user as *const Counter) };
    let now = counter.now.fetch_add(bytes as i64, Ordering::Relaxed) + bytes as i64;
    counter.peak.fetch_max(now, Ordering::Relaxed);
    true
}

/// How to build the scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BuildOptions {
    /// `RTC_SCENE_FLAG_ROBUST`: conservative node tests and no accuracy-reducing
    /// shortcuts in the triangle test (what keeps rays from slipping between triangles).
    pub robust: bool,
    /// Build threads (`threads=N` in the device configuration); 0 for Embree's default
    /// (every hardware thread).
    pub threads: u32,
}

impl Default for BuildOptions {
    fn default() -> Self {
        Self { robust: true, threads: 0 }
    }
}

/// Why no scene could be built.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct EmbreeError(pub String);

impl core::fmt::Display for EmbreeError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for EmbreeError {}

/// The device's capabilities as `rtcGetDeviceProperty` reports them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DeviceInfo {
    /// `RTC_DEVICE_PROPERTY_VERSION` (e.g. 31305 for 3.13.5).
    pub version: isize,
    /// Whether 4-, 8- and 16-wide packets run natively (else Embree emulates them).
    pub native: [bool; 3],
    /// `RTC_DEVICE_PROPERTY_TASKING_SYSTEM`: 0 internal, 1 TBB, 2 PPL.
    pub tasking: isize,
}

/// One committed Embree scene over one triangle mesh, with the device and the buffers
/// it reads.
#[derive(Debug)]
pub struct EmbreeScene {
    scene: RtcScene,
    device: Device,
    /// `count + 1` elements: the last is the padding Embree's 16-byte loads read.
    vertices: Vec<[f32; 3]>,
    indices: Vec<[u32; 3]>,
    info: DeviceInfo,
}

#[derive(Debug)]
struct Device {
    raw: RtcDevice,
    counter: Box<Counter>,
}

impl Drop for Device {
    fn drop(&mut self) {
        // SAFETY: `raw` came from rtcNewDevice and is released once; the counter the
        // monitor writes is dropped only after this.
        unsafe { rtcReleaseDevice(self.raw) }
    }
}

impl Drop for EmbreeScene {
    fn drop(&mut self) {
        // SAFETY: `scene` came from rtcNewScene and is released once, before the
        // device and buffers (fields drop after this).
        unsafe { rtcReleaseScene(self.scene) }
    }
}

// SAFETY: see "Threads" in the module documentation.
unsafe impl Send for EmbreeScene {}
// SAFETY: as above.
unsafe impl Sync for EmbreeScene {}

impl EmbreeScene {
    /// Build and commit a scene over triangles `indices` into `vertices` (both
    /// non-empty, every index below `vertices.len()`).
    pub fn new(mut vertices: Vec<[f32; 3]>, indices: Vec<[u32; 3]>, options: BuildOptions) -> Result<Self, EmbreeError> {
        let count = vertices.len();
        if count == 0 || indices.is_empty() || indices.iter().flatten().any(|&i| i as usize >= count) || count >= u32::MAX as usize {
            return Err(EmbreeError("an Embree scene needs triangles with indices within its vertices".into()));
        }
        vertices.push([0.0; 3]);
        let config = if options.threads > 0 { format!("threads={}\0", options.threads) } else { "\0".into() };
        // SAFETY: a NUL-terminated configuration string.
        let raw = unsafe { rtcNewDevice(config.as_ptr() as *const c_char) };
        if raw.is_null() {
            // SAFETY: a null device asks for the thread's last creation error.
            let code = unsafe { rtcGetDeviceError(core::ptr::null_mut()) };
            return Err(EmbreeError(format!("Embree could not create a device (error {code}: 5 means this CPU lacks SSE2)")));
        }
        let device = Device { raw, counter: Box::default() };
        // SAFETY: the counter is boxed (a stable address) and outlives the device.
        unsafe { rtcSetDeviceMemoryMonitorFunction(raw, Some(monitor), &*device.counter as *const Counter as *mut c_void) };
        let property = |p: c_uint| {
            // SAFETY: a valid device and one of the header's property numbers.
            unsafe { rtcGetDeviceProperty(raw, p) }
        };
        let info = DeviceInfo { version: property(0), native: [property(32) != 0, property(33) != 0, property(34) != 0], tasking: property(128) };
        // SAFETY: the device is valid; the buffers are owned by the returned value and
        // never modified (see the module documentation); counts exclude the padding.
        let scene = unsafe {
            let scene = rtcNewScene(raw);
            if scene.is_null() {
                return Err(EmbreeError(format!("Embree could not create a scene (error {})", rtcGetDeviceError(raw))));
            }
            rtcSetSceneFlags(scene, if options.robust { RTC_SCENE_FLAG_ROBUST } else { 0 });
            rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_MEDIUM);
            let geometry = rtcNewGeometry(raw, RTC_GEOMETRY_TYPE_TRIANGLE);
            rtcSetSharedGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, vertices.as_ptr() as *const c_void, 0, 12, count);
            rtcSetSharedGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, indices.as_ptr() as *const c_void, 0, 12, indices.len());
            rtcCommitGeometry(geometry);
            rtcAttachGeometry(scene, geometry);
            rtcReleaseGeometry(geometry);
            rtcCommitScene(scene);
            scene
        };
        let built = Self { scene, device, vertices, indices, info };
        // SAFETY: a valid device.
        let error = unsafe { rtcGetDeviceError(raw) };
        if error != 0 {
            return Err(EmbreeError(format!("Embree failed to build the scene (error {error}: 4 means out of memory)")));
        }
        Ok(built)
    }

    /// The vertices Embree reads (without the padding).
    pub fn vertices(&self) -> &[[f32; 3]] {
        &self.vertices[..self.vertices.len() - 1]
    }

    /// The vertex indices of each triangle (a primitive id indexes this).
    pub fn indices(&self) -> &[[u32; 3]] {
        &self.indices
    }

    /// Heap bytes of the two shared buffers.
    pub fn buffer_bytes(&self) -> u64 {
        (self.vertices.capacity() * size_of::<[f32; 3]>() + self.indices.capacity() * size_of::<[u32; 3]>()) as u64
    }

    /// What the device reports of itself.
    pub fn info(&self) -> DeviceInfo {
        self.info
    }

    /// Bytes Embree allocated and still holds, and the most it held at once (its build
    /// scratch included), by its memory monitor. Our shared buffers are not in these.
    pub fn embree_bytes(&self) -> (u64, u64) {
        let c = &self.device.counter;
        (c.now.load(Ordering::Relaxed).max(0) as u64, c.peak.load(Ordering::Relaxed).max(0) as u64)
    }

    /// `rtcIntersect1`: fills `rh.hit` and shortens `rh.ray.tfar` on a hit.
    #[inline]
    pub fn intersect1(&self, rh: &mut RayHit1, coherent: bool) {
        let mut context = Context::new(coherent);
        // SAFETY: a committed scene, a live context and a ray/hit struct of C layout.
        unsafe { rtcIntersect1(self.scene, &mut context, rh) }
    }

    /// `rtcOccluded1`: sets `ray.tfar` to −∞ when something blocks the ray.
    #[inline]
    pub fn occluded1(&self, ray: &mut Ray1, coherent: bool) {
        let mut context = Context::new(coherent);
        // SAFETY: as `intersect1`.
        unsafe { rtcOccluded1(self.scene, &mut context, ray) }
    }

    /// `rtcIntersect4/8/16` over the lanes whose `valid` is −1 (0: lane ignored).
    /// Other widths are refused at compile time.
    #[inline]
    pub fn intersect_n<const N: usize>(&self, valid: &[i32; N], rh: &mut RayHitN<N>, coherent: bool) {
        let mut context = Context::new(coherent);
        let (v, s, c, p) = (valid.as_ptr(), self.scene, &mut context as *mut Context, rh as *mut RayHitN<N> as *mut c_void);
        const { assert!(N == 4 || N == 8 || N == 16, "Embree packets are 4, 8 or 16 wide") };
        // SAFETY: `RayHitN<N>` is `RTCRayHitN` for this N (module documentation), the
        // mask has N lanes and the packet is 64-byte aligned.
        unsafe {
            match N {
                4 => rtcIntersect4(v, s, c, p),
                8 => rtcIntersect8(v, s, c, p),
                _ => rtcIntersect16(v, s, c, p),
            }
        }
    }

    /// `rtcOccluded4/8/16`: each blocked valid lane's `tfar` becomes −∞.
    #[inline]
    pub fn occluded_n<const N: usize>(&self, valid: &[i32; N], ray: &mut RayOnlyN<N>, coherent: bool) {
        let mut context = Context::new(coherent);
        let (v, s, c, p) = (valid.as_ptr(), self.scene, &mut context as *mut Context, ray as *mut RayOnlyN<N> as *mut c_void);
        const { assert!(N == 4 || N == 8 || N == 16, "Embree packets are 4, 8 or 16 wide") };
        // SAFETY: as `intersect_n`.
        unsafe {
            match N {
                4 => rtcOccluded4(v, s, c, p),
                8 => rtcOccluded8(v, s, c, p),
                _ => rtcOccluded16(v, s, c, p),
            }
        }
    }
}
