//! The C functions and types (`include/ember.h` is generated from this file).
//!
//! Every function returns an [`EmberStatus`]; on failure, [`ember_last_error`] gives the
//! message (per thread, valid until the thread's next ember call). Nothing panics across
//! the boundary: each call runs under `catch_unwind`, and a caught panic is
//! `EMBER_STATUS_PANIC` with the panic's message, reported there once and not printed:
//! the first call installs a panic hook that stays silent for panics inside ember's
//! calls (on the calling thread while it is in one, or on ember's render threads) and
//! hands every other panic to the hook it replaced, so the host's own panics are
//! reported as before.
//!
//! Every value that crosses from C is checked on entry: counts, indices, sizes, floats,
//! and enums, which cross as integers (a C enum may hold any `int`; a Rust enum read
//! from a value it does not name is undefined behaviour) and are converted here. The hits
//! the ray callbacks return are checked as they come (`ray_queries::CallbackTracer`).
//!
//! The caller's undefined behaviour, which no check can catch: a pointer that is not
//! null but does not point to as many valid elements as its count says, a `user_data`
//! or callback that is not valid for the renderer's whole life, and callbacks that are
//! not safe to call from several threads at once when `threads` is not 1.
#![allow(unsafe_code)]

pub mod desc;
mod film;
mod ray_queries;
mod scene;

pub use desc::{
    EmberBsdf, EmberBsdfKind, EmberFilterKind, EmberFovAxis, EmberLens, EmberLight, EmberLightKind, EmberMicrofacet, EmberPixelFilter, EmberPrincipled,
    EmberSceneDesc2, EmberTexture, EmberTextureFilter, EmberTextureKind, EmberTextureSlot, EmberWrapMode,
};
pub use film::{ember_film_export, ember_film_import};
pub use ray_queries::{Callbacks, EmberHit, EmberRay, EmberRayBatch, EmberRayBatchCallbacks, EmberRayCallbacks};
pub use scene::{ember_bsdf_init, ember_light_init, ember_scene_create2, ember_texture_init};

use std::cell::{Cell, RefCell};
use std::ffi::{CStr, CString, c_char};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::{Arc, LazyLock, Mutex, MutexGuard, Once, RwLock, RwLockReadGuard, RwLockWriteGuard};
use std::time::Instant;

use ember_core::estimators::ChunkOutput;
use ember_core::estimators::{EstimatorKind, Renderer};
use ember_core::render::{Context, Film, Phase, Phased};
use ember_host::driver::{self, Limits};

use ray_queries::{Fault, MAX_BATCH_WIDTH, Tracer, fault_error, tracer};

use crate::{Config, EmberStatus, Error, MaterialDesc, Registry, RenderIdentity, RendererState, Result, SceneData, SceneDesc, Settings};

/// A scene handle (0 is never valid).
pub type EmberScene = u64;
/// A renderer handle (0 is never valid).
pub type EmberRenderer = u64;

/// Material kinds: the values of [`EmberMaterial`]'s `kind`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EmberMaterialKind {
    /// Lambertian; `color` is the albedo.
    Diffuse = 0,
    /// A perfect mirror; `color` is the reflectance.
    Mirror = 1,
    /// Smooth glass; `ior` is the interior index of refraction (outside: 1).
    Glass = 2,
}

impl EmberMaterialKind {
    /// Every kind, in value order.
    const ALL: [Self; 3] = [Self::Diffuse, Self::Mirror, Self::Glass];

    /// The kind whose value is `raw`, or an error naming `field` and the valid range.
    pub fn from_raw(raw: u32, field: &str) -> Result<Self> {
        Self::ALL.into_iter().find(|k| *k as u32 == raw).ok_or_else(|| {
            let last = Self::ALL.len() - 1;
            Error::new(EmberStatus::InvalidArgument, format!("{field} {raw} is not an EmberMaterialKind (0..={last}: diffuse, mirror, glass)"))
        })
    }
}

/// A material.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct EmberMaterial {
    /// An `EmberMaterialKind` value; any other is refused (`EMBER_STATUS_INVALID_ARGUMENT`).
    /// An integer rather than the enum type: a C enum may hold any `int`.
    pub kind: u32,
    pub color: [f32; 3],
    pub ior: f32,
}

/// A point light.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct EmberPointLight {
    pub position: [f32; 3],
    pub intensity: [f32; 3],
}

/// A pinhole camera (Mitsuba's `lookat`; the field of view is horizontal).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EmberCamera {
    pub origin: [f32; 3],
    pub target: [f32; 3],
    pub up: [f32; 3],
    pub fov_degrees: f32,
    pub width: u32,
    pub height: u32,
}

/// A scene as arrays. The pointers are read during `ember_scene_create` only; the
/// scene keeps its own copy.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct EmberSceneDesc {
    /// `vertex_count` × 3 floats.
    pub positions: *const f32,
    pub vertex_count: u32,
    /// `triangle_count` × 3 vertex indices; the triangle's front is counter-clockwise.
    pub indices: *const u32,
    pub triangle_count: u32,
    /// `triangle_count` material indices.
    pub triangle_materials: *const u32,
    /// Null, or `triangle_count` × 3 floats: radiance emitted from each triangle's front
    /// (all zero: not an emitter).
    pub triangle_emission: *const f32,
    /// `material_count` materials.
    pub materials: *const EmberMaterial,
    pub material_count: u32,
    /// Null, or `point_light_count` lights.
    pub point_lights: *const EmberPointLight,
    pub point_light_count: u32,
    pub camera: EmberCamera,
}

/// How to render. Zero in a count keeps the estimator's default.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct EmberRenderSettings {
    /// An estimator name (`ember_estimator_name` lists them), e.g. "pt" or "bdpt".
    pub estimator: *const c_char,
    pub seed: u64,
    /// Longest path in segments; -1 unbounded (Russian roulette ends paths).
    pub max_depth: i32,
    /// Threads for `ember_render_passes` (0: every core). More than 4 × the cores (or
    /// than 1024) are capped there, as `ember render --threads` caps them: more only add
    /// start-up time.
    pub threads: u32,
    /// Light paths per pass (LVCBPT, SPCBPT, PPM, BPM, VCM).
    pub light_paths: u32,
    /// Connections per camera vertex (LVCBPT, SPCBPT).
    pub connections: u32,
    /// Initial merging or filtering radius in pixel footprints (PPM, BPM, VCM, MVF, PhF, BPF).
    pub radius_footprints: f32,
    /// Null, or further options of the estimator's configuration: space-separated
    /// `name=value` with the names of `ember render`'s options, e.g.
    /// "subspaces=64 reuse=0" (SPCBPT) or "kernel=disk beta=1" (segments, filters); and
    /// "memory-limit=2G" (suffixes K, M, G, T: binary), the bytes the renderer may claim,
    /// checked instead of the memory available (`EMBER_STATUS_OUT_OF_MEMORY`).
    pub options: *const c_char,
}

/// The phase `ember_phase_begin` opened.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct EmberPhaseInfo {
    /// Chunks to map, `0..chunks`, each once, on any threads.
    pub chunks: u32,
    /// The pass it belongs to, or -1 for a setup phase.
    pub pass: i64,
}

/// One chunk of an open phase: its output and whether it has been mapped.
type ChunkSlot = Mutex<(ChunkOutput, bool)>;

/// A renderer with the phase a host's own threads are mapping, if any.
#[derive(Debug)]
struct Shared {
    state: RwLock<RendererState>,
    /// Filled by `ember_phase_begin`, mapped under a read lock, reduced by `ember_phase_end`.
    /// Each chunk's output with whether it has been mapped.
    phase: RwLock<OpenPhase>,
}

/// An open phase: the phase and its chunks.
type OpenPhase = Option<(Phase, Vec<ChunkSlot>)>;

impl Shared {
    fn phase_read(&self) -> Result<RwLockReadGuard<'_, OpenPhase>> {
        self.phase.read().map_err(|_| Error::new(EmberStatus::Panic, "a previous phase call panicked: destroy the renderer"))
    }
    fn phase_write(&self) -> Result<RwLockWriteGuard<'_, OpenPhase>> {
        self.phase.write().map_err(|_| Error::new(EmberStatus::Panic, "a previous phase call panicked: destroy the renderer"))
    }
}

static SCENES: LazyLock<Mutex<Registry<Arc<SceneData>>>> = LazyLock::new(Default::default);
static RENDERERS: LazyLock<Mutex<Registry<Arc<Shared>>>> = LazyLock::new(Default::default);

fn scenes() -> Result<MutexGuard<'static, Registry<Arc<SceneData>>>> {
    SCENES.lock().map_err(|_| Error::new(EmberStatus::Panic, "the scene registry is poisoned"))
}

fn renderers() -> Result<MutexGuard<'static, Registry<Arc<Shared>>>> {
    RENDERERS.lock().map_err(|_| Error::new(EmberStatus::Panic, "the renderer registry is poisoned"))
}

fn dead_scene(handle: EmberScene) -> Error {
    Error::new(EmberStatus::InvalidHandle, format!("scene handle {handle:#x} is not a live scene"))
}

fn dead_renderer(handle: EmberRenderer) -> Error {
    Error::new(EmberStatus::InvalidHandle, format!("renderer handle {handle:#x} is not a live renderer"))
}

thread_local! {
    static LAST_ERROR: RefCell<CString> = RefCell::new(CString::default());
    /// Ember calls in progress on this thread (a callback may call ember again).
    static IN_CALL: Cell<u32> = const { Cell::new(0) };
}

/// The names of the render threads (`ember_render_passes` names its pool "ember-render";
/// the panic test in `tests/panics.rs` fails if the two part).
const RENDER_THREAD_PREFIX: &str = "ember-render-";

/// Install, once, the panic hook that keeps ember's panics off the host's stderr: silent
/// for a panic inside an ember call (its thread is in one, or is one of ember's render
/// threads: `guard` reports it once, as the status and message), the previous hook (the
/// host's, or the default printer) for every other panic.
fn install_panic_hook() {
    static HOOK: Once = Once::new();
    HOOK.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            let inside = IN_CALL.with(Cell::get) > 0 || std::thread::current().name().is_some_and(|n| n.starts_with(RENDER_THREAD_PREFIX));
            if !inside {
                previous(info);
            }
        }));
    });
}

fn set_error(message: &str) {
    let text = CString::new(message.replace('\0', " ")).unwrap_or_default();
    LAST_ERROR.with(|e| *e.borrow_mut() = text);
}

/// Run `f` at the boundary: its status, the message kept for `ember_last_error`, and any
/// panic caught and turned into `Panic`.
fn guard(f: impl FnOnce() -> Result<EmberStatus>) -> EmberStatus {
    install_panic_hook();
    IN_CALL.with(|n| n.set(n.get() + 1));
    let result = catch_unwind(AssertUnwindSafe(f));
    IN_CALL.with(|n| n.set(n.get() - 1));
    match result {
        Ok(Ok(status)) => {
            set_error("");
            status
        }
        Ok(Err(e)) => {
            set_error(&e.message);
            e.status
        }
        Err(payload) => {
            let what = payload.downcast_ref::<&str>().map(|s| s.to_string()).or_else(|| payload.downcast_ref::<String>().cloned()).unwrap_or_default();
            set_error(&format!("panic inside ember: {what}"));
            EmberStatus::Panic
        }
    }
}

fn null(what: &str) -> Error {
    Error::new(EmberStatus::NullPointer, format!("{what} is null"))
}

/// `count` elements at `ptr` (null allowed only when `count` is 0).
///
/// # Safety
/// A non-null `ptr` must point to `count` valid, initialised `T`s.
unsafe fn slice<'a, T>(ptr: *const T, count: u32, what: &str) -> Result<&'a [T]> {
    if count == 0 {
        return Ok(&[]);
    }
    if ptr.is_null() {
        return Err(null(&format!("{what} (with a count of {count})")));
    }
    // SAFETY: the caller guarantees `count` valid elements at a non-null `ptr`.
    Ok(unsafe { std::slice::from_raw_parts(ptr, count as usize) })
}

/// The output `ptr` points to, or an error naming it when null.
///
/// # Safety
/// A non-null `ptr` must point to a valid, writable `T` for the call's duration.
unsafe fn out<'a, T>(ptr: *mut T, what: &str) -> Result<&'a mut T> {
    // SAFETY: the caller's contract.
    unsafe { ptr.as_mut() }.ok_or_else(|| null(what))
}

fn scene_of(handle: EmberScene) -> Result<Arc<SceneData>> {
    scenes()?.get(handle).cloned().ok_or_else(|| dead_scene(handle))
}

fn renderer_of(handle: EmberRenderer) -> Result<Arc<Shared>> {
    renderers()?.get(handle).cloned().ok_or_else(|| dead_renderer(handle))
}

/// The message of the calling thread's last failed call ("" after a success). Valid
/// until the thread's next ember call.
#[unsafe(no_mangle)]
pub extern "C" fn ember_last_error() -> *const c_char {
    LAST_ERROR.with(|e| e.borrow().as_ptr())
}

/// This library's version and build, e.g. "ember 0.1.0 (commit 0123456789ab)" (static):
/// the same string split renders record, so an engine can log which build rendered.
#[unsafe(no_mangle)]
pub extern "C" fn ember_version() -> *const c_char {
    static VERSION: LazyLock<CString> = LazyLock::new(|| CString::new(ember_host::program_version()).unwrap_or_default());
    VERSION.as_ptr()
}

/// Number of estimators.
#[unsafe(no_mangle)]
pub extern "C" fn ember_estimator_count() -> u32 {
    EstimatorKind::ALL.len() as u32
}

/// The name of estimator `index` (static), or null past the end.
#[unsafe(no_mangle)]
pub extern "C" fn ember_estimator_name(index: u32) -> *const c_char {
    static NAMES: LazyLock<Vec<CString>> = LazyLock::new(|| EstimatorKind::ALL.iter().map(|k| CString::new(k.name()).unwrap_or_default()).collect());
    NAMES.get(index as usize).map_or(std::ptr::null(), |n| n.as_ptr())
}

/// Build a scene from arrays; `*scene` receives its handle.
///
/// # Safety
/// `desc` must be null or point to a valid description whose non-null pointers hold
/// as many elements as its counts say.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ember_scene_create(desc: *const EmberSceneDesc, scene: *mut EmberScene) -> EmberStatus {
    guard(|| {
        // SAFETY: null or valid, by the caller's contract.
        let d = unsafe { desc.as_ref() }.ok_or_else(|| null("desc"))?;
        let out = unsafe { out(scene, "scene") }?;
        let (n, v) = (d.triangle_count, d.vertex_count);
        let too_many =
            |count: u32, what: &str| (count > u32::MAX / 3).then(|| Error::new(EmberStatus::InvalidArgument, format!("{what} {count} is too large")));
        if let Some(e) = too_many(n, "triangle_count").or_else(|| too_many(v, "vertex_count")) {
            return Err(e);
        }
        // SAFETY (each `slice`): the caller's contract on the description's pointers.
        let positions = unsafe { slice(d.positions, v * 3, "positions") }?;
        let indices = unsafe { slice(d.indices, n * 3, "indices") }?;
        let materials = unsafe { slice(d.triangle_materials, n, "triangle_materials") }?;
        let emission = if d.triangle_emission.is_null() { &[][..] } else { unsafe { slice(d.triangle_emission, n * 3, "triangle_emission") }? };
        let mats = unsafe { slice(d.materials, d.material_count, "materials") }?;
        let lights = unsafe { slice(d.point_lights, d.point_light_count, "point_lights") }?;
        let desc = SceneDesc {
            positions: positions.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect(),
            triangles: indices.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect(),
            triangle_materials: materials.to_vec(),
            triangle_emission: emission.chunks_exact(3).map(|e| [e[0], e[1], e[2]]).collect(),
            materials: mats
                .iter()
                .enumerate()
                .map(|(i, m)| {
                    Ok(match EmberMaterialKind::from_raw(m.kind, &format!("materials[{i}].kind"))? {
                        EmberMaterialKind::Diffuse => MaterialDesc::Diffuse(m.color),
                        EmberMaterialKind::Mirror => MaterialDesc::Mirror(m.color),
                        EmberMaterialKind::Glass => MaterialDesc::Glass(m.ior),
                    })
                })
                .collect::<Result<_>>()?,
            point_lights: lights.iter().map(|l| (l.position, l.intensity)).collect(),
            camera: d.camera,
            ..SceneDesc::default()
        };
        let data = SceneData::from_desc(&desc)?;
        *out = scenes()?.insert(Arc::new(data));
        Ok(EmberStatus::Ok)
    })
}

/// A built-in scene ("cornell-box" or "glass-spheres") at `width` × `height`.
///
/// # Safety
/// `name` must be null or a NUL-terminated string.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ember_scene_builtin(name: *const c_char, width: u32, height: u32, scene: *mut EmberScene) -> EmberStatus {
    guard(|| {
        if name.is_null() {
            return Err(null("name"));
        }
        // SAFETY: non-null and NUL-terminated by the caller's contract.
        let name = unsafe { CStr::from_ptr(name) }.to_string_lossy().into_owned();
        let out = unsafe { out(scene, "scene") }?;
        let data = SceneData::builtin(&name, width, height)?;
        *out = scenes()?.insert(Arc::new(data));
        Ok(EmberStatus::Ok)
    })
}

/// Destroy a scene handle. Renderers made from it keep the scene alive until they are
/// destroyed.
#[unsafe(no_mangle)]
pub extern "C" fn ember_scene_destroy(scene: EmberScene) -> EmberStatus {
    guard(|| scenes()?.remove(scene).map(|_| EmberStatus::Ok).ok_or_else(|| dead_scene(scene)))
}

/// A renderer for `scene` with `settings`; `callbacks` null uses the built-in BVH.
///
/// # Safety
/// `settings` must be null or valid, its `estimator` and `options` null or
/// NUL-terminated; a non-null
/// `callbacks` must stay valid (with its `user_data`) until the renderer is destroyed.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ember_renderer_create(
    scene: EmberScene,
    settings: *const EmberRenderSettings,
    callbacks: *const EmberRayCallbacks,
    renderer: *mut EmberRenderer,
) -> EmberStatus {
    guard(|| {
        // SAFETY: null or valid, by the caller's contract.
        let callbacks = match unsafe { callbacks.as_ref() } {
            None => None,
            Some(cb) => match (cb.intersect, cb.occluded) {
                (Some(intersect), Some(occluded)) => Some(Callbacks::Single { user_data: cb.user_data, intersect, occluded }),
                _ => return Err(null("callbacks.intersect or callbacks.occluded")),
            },
        };
        // SAFETY: the caller's contract, passed on.
        unsafe { create(scene, settings, callbacks, renderer) }
    })
}

/// A renderer for `scene` with `settings` whose rays go to the engine's batch callbacks
/// (`EmberRayBatchCallbacks`; not null).
///
/// # Safety
/// As `ember_renderer_create`; `callbacks` must stay valid (with its `user_data`) until
/// the renderer is destroyed.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ember_renderer_create_batched(
    scene: EmberScene,
    settings: *const EmberRenderSettings,
    callbacks: *const EmberRayBatchCallbacks,
    renderer: *mut EmberRenderer,
) -> EmberStatus {
    guard(|| {
        // SAFETY: null or valid, by the caller's contract.
        let cb = unsafe { callbacks.as_ref() }.ok_or_else(|| null("callbacks"))?;
        let (Some(intersect), Some(occluded)) = (cb.intersect, cb.occluded) else {
            return Err(null("callbacks.intersect or callbacks.occluded"));
        };
        if !(1..=MAX_BATCH_WIDTH).contains(&cb.width) {
            return Err(Error::arg(format!("callbacks.width = {} outside 1..={MAX_BATCH_WIDTH}", cb.width)));
        }
        let callbacks = Callbacks::Batch { user_data: cb.user_data, width: cb.width as usize, intersect, occluded };
        // SAFETY: the caller's contract, passed on.
        unsafe { create(scene, settings, Some(callbacks), renderer) }
    })
}

/// What both constructors share.
///
/// # Safety
/// `settings` null or valid, its strings null or NUL-terminated; `renderer` null or
/// writable.
unsafe fn create(scene: EmberScene, settings: *const EmberRenderSettings, callbacks: Option<Callbacks>, renderer: *mut EmberRenderer) -> Result<EmberStatus> {
    let data = scene_of(scene)?;
    // SAFETY: null or valid, by the caller's contract.
    let s = unsafe { settings.as_ref() }.ok_or_else(|| null("settings"))?;
    if s.estimator.is_null() {
        return Err(null("settings.estimator"));
    }
    // SAFETY: non-null and NUL-terminated by the caller's contract.
    let estimator = unsafe { CStr::from_ptr(s.estimator) }.to_string_lossy().into_owned();
    // SAFETY: null or NUL-terminated by the caller's contract.
    let options = if s.options.is_null() { String::new() } else { unsafe { CStr::from_ptr(s.options) }.to_string_lossy().into_owned() };
    let settings = Settings {
        estimator,
        seed: s.seed,
        max_depth: s.max_depth,
        threads: s.threads,
        light_paths: s.light_paths,
        connections: s.connections,
        radius_footprints: s.radius_footprints,
        options,
    };
    let out = unsafe { out(renderer, "renderer") }?;
    let config = settings.config()?;
    let identity = RenderIdentity::of(&config);
    let Config { estimator, mut params, memory_limit, threads } = config;
    // The lane kernels at the level the scene's accelerator chose for this machine, with
    // its BVH; an engine's callbacks get batches of the width they ask for (one ray per
    // call for single-ray callbacks), so the lanes stay at the baseline's one path.
    if callbacks.is_none() {
        params.simd = data.accel.shading_level();
    }
    crate::check_memory(&data, &estimator, memory_limit)?;
    let r = Renderer::new(&data.scene, params, estimator).map_err(|e| Error::new(EmberStatus::InvalidConfig, e.to_string()))?;
    let film = Film::for_camera(&data.scene.camera);
    let state = RendererState {
        scene: data,
        renderer: r,
        film,
        imported: None,
        identity,
        threads,
        pool: None,
        callbacks,
        ready: false,
        pass_started: false,
        out_of_order: None,
    };
    let shared = Arc::new(Shared { state: RwLock::new(state), phase: RwLock::new(None) });
    *out = renderers()?.insert(shared);
    Ok(EmberStatus::Ok)
}

/// Destroy a renderer handle (its film with it).
#[unsafe(no_mangle)]
pub extern "C" fn ember_renderer_destroy(renderer: EmberRenderer) -> EmberStatus {
    guard(|| renderers()?.remove(renderer).map(|_| EmberStatus::Ok).ok_or_else(|| dead_renderer(renderer)))
}

/// Render `passes` more passes on the renderer's threads (its setup first, the first
/// time). The image is then the mean of every pass rendered so far. After
/// `ember_film_import` of N passes, they are passes N, N + 1, …: the bits of one render.
#[unsafe(no_mangle)]
pub extern "C" fn ember_render_passes(renderer: EmberRenderer, passes: u32) -> EmberStatus {
    guard(|| {
        let shared = renderer_of(renderer)?;
        if shared.phase_read()?.is_some() {
            return Err(Error::arg("a phase is open (ember_phase_begin): end it before rendering passes"));
        }
        let mut guard = crate::write(&shared.state)?;
        let st = &mut *guard;
        let end = st.passes().checked_add(passes).ok_or_else(|| Error::arg(format!("{passes} more passes would pass 2^32 - 1")))?;
        // After an import, the film holds passes `first_pass..`. The driver replays passes
        // `0..first_pass` (SPCBPT's reuse) while the film is empty: a call of no passes
        // would replay them, and the next call again, so it renders nothing at all.
        let first_pass = st.imported.as_ref().map_or(0, Film::passes);
        if passes == 0 && first_pass > 0 && st.film.passes() == 0 {
            return Ok(EmberStatus::Ok);
        }
        let fault = Fault::new();
        let q = tracer(&st.scene, &st.callbacks, &fault);
        let ctx = Context { scene: &st.scene.scene, tracer: &q };
        let limits = Limits { spp: end, deadline: None, interrupt: None, first_pass };
        // The renderer's own pool, started on its first render (not one per call).
        let pool = match &mut st.pool {
            Some(pool) => pool,
            empty => empty.insert(driver::render_pool(st.threads).map_err(|e| Error::new(EmberStatus::InvalidArgument, e.to_string()))?),
        };
        driver::render_on(pool, &mut st.renderer, &ctx, &mut st.film, limits, None, Instant::now())
            .map_err(|e| Error::new(EmberStatus::InvalidArgument, e.to_string()))?;
        st.ready = true;
        fault_error(fault, "the rest of the call's rays were misses, and the film holds its passes: destroy the renderer")?;
        Ok(EmberStatus::Ok)
    })
}

/// The film's size in pixels.
///
/// # Safety
/// Non-null `width` and `height` must point to writable `uint32_t`s.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ember_renderer_size(renderer: EmberRenderer, width: *mut u32, height: *mut u32) -> EmberStatus {
    guard(|| {
        let shared = renderer_of(renderer)?;
        let st = crate::read(&shared.state)?;
        let (w, h) = (unsafe { out(width, "width") }?, unsafe { out(height, "height") }?);
        (*w, *h) = (st.film.width(), st.film.height());
        Ok(EmberStatus::Ok)
    })
}

/// The passes the film holds.
///
/// # Safety
/// A non-null `passes` must point to a writable `uint32_t`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ember_renderer_passes(renderer: EmberRenderer, passes: *mut u32) -> EmberStatus {
    guard(|| {
        let shared = renderer_of(renderer)?;
        let st = crate::read(&shared.state)?;
        *unsafe { out(passes, "passes") }? = st.passes();
        Ok(EmberStatus::Ok)
    })
}

/// Copy the image (the mean over passes, linear RGB, rows top to bottom) into `rgb`,
/// which holds `floats` floats: exactly 3 × width × height.
///
/// # Safety
/// A non-null `rgb` must point to `floats` writable floats.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ember_renderer_image(renderer: EmberRenderer, rgb: *mut f32, floats: usize) -> EmberStatus {
    guard(|| {
        let shared = renderer_of(renderer)?;
        let st = crate::read(&shared.state)?;
        if rgb.is_null() {
            return Err(null("rgb"));
        }
        let need = st.film.pixels() * 3;
        if floats != need {
            return Err(Error::arg(format!("the image holds {need} floats (3 × {} × {}), not {floats}", st.film.width(), st.film.height())));
        }
        // SAFETY: `floats` writable floats at a non-null `rgb`, by the caller's contract.
        let dst = unsafe { std::slice::from_raw_parts_mut(rgb, floats) };
        for (d, p) in dst.chunks_exact_mut(3).zip(st.whole()?.to_rgb_f32()) {
            d.copy_from_slice(&p);
        }
        Ok(EmberStatus::Ok)
    })
}

/// For a host that brings its own threads: queue pass `pass` (after any pending setup),
/// then open its phases one by one with `ember_phase_begin`. Refused on a renderer that
/// imported a film (its passes continue with `ember_render_passes`, which replays what
/// the passes before them left behind). A pass other than the next of one render (pass
/// `ember_renderer_passes` reports) is rendered, but the film can then not be exported.
#[unsafe(no_mangle)]
pub extern "C" fn ember_pass_start(renderer: EmberRenderer, pass: u32) -> EmberStatus {
    guard(|| {
        let shared = renderer_of(renderer)?;
        if shared.phase_read()?.is_some() {
            return Err(Error::arg("a phase is open: map its chunks and end it first"));
        }
        let mut st = crate::write(&shared.state)?;
        if st.imported.is_some() {
            return Err(Error::arg(
                "the renderer continues an imported film: render its passes with ember_render_passes (the phase calls do not replay the passes before them)",
            ));
        }
        let next = st.film.passes();
        if pass != next && st.out_of_order.is_none() {
            st.out_of_order = Some((pass, next));
        }
        st.pass_started = true;
        Phased::<Tracer<'_>>::start_pass(&mut st.renderer, pass);
        Ok(EmberStatus::Ok)
    })
}

/// Open the next pending phase (setup or pass): `*info` gets its chunk count. Returns
/// `EMBER_STATUS_DONE` when nothing is pending. Then call `ember_phase_map` once for
/// every chunk (on any threads, concurrently), then `ember_phase_end`.
///
/// # Safety
/// A non-null `info` must point to a writable `EmberPhaseInfo`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ember_phase_begin(renderer: EmberRenderer, info: *mut EmberPhaseInfo) -> EmberStatus {
    guard(|| {
        let shared = renderer_of(renderer)?;
        let info = unsafe { out(info, "info") }?;
        let mut open = shared.phase_write()?;
        if open.is_some() {
            return Err(Error::arg("a phase is already open: end it first"));
        }
        let st = crate::read(&shared.state)?;
        let Some(phase) = Phased::<Tracer<'_>>::next_phase(&st.renderer) else { return Ok(EmberStatus::Done) };
        let chunks = phase.chunk_count();
        let outputs = (0..chunks)
            .map(|c| {
                let mut o = ChunkOutput::default();
                o.reset(phase.chunk_range(c));
                Mutex::new((o, false))
            })
            .collect();
        *info = EmberPhaseInfo { chunks: chunks as u32, pass: phase.pass.map_or(-1, i64::from) };
        *open = Some((phase, outputs));
        Ok(EmberStatus::Ok)
    })
}

/// Map chunk `chunk` of the open phase. Any thread; chunks may run concurrently.
#[unsafe(no_mangle)]
pub extern "C" fn ember_phase_map(renderer: EmberRenderer, chunk: u32) -> EmberStatus {
    guard(|| {
        let shared = renderer_of(renderer)?;
        let open = shared.phase_read()?;
        let Some((phase, outputs)) = open.as_ref() else { return Err(Error::arg("no phase is open: call ember_phase_begin")) };
        let slot = outputs.get(chunk as usize).ok_or_else(|| Error::arg(format!("chunk {chunk} of a phase of {} chunks", outputs.len())))?;
        let mut slot = match slot.try_lock() {
            Ok(g) => g,
            Err(std::sync::TryLockError::WouldBlock) => return Err(Error::new(EmberStatus::Busy, format!("chunk {chunk} is being mapped by another call"))),
            Err(std::sync::TryLockError::Poisoned(_)) => return Err(Error::new(EmberStatus::Panic, format!("mapping chunk {chunk} panicked before"))),
        };
        if slot.1 {
            return Err(Error::arg(format!("chunk {chunk} was already mapped in this phase")));
        }
        // The estimator is only read while chunks map: a read lock, shared by the threads.
        let st = crate::read(&shared.state)?;
        let fault = Fault::new();
        let q = tracer(&st.scene, &st.callbacks, &fault);
        let ctx = Context { scene: &st.scene.scene, tracer: &q };
        Phased::<Tracer<'_>>::map(&st.renderer, &ctx, phase, &mut slot.0);
        if fault.get().is_some() {
            // The chunk stays unmapped, its output cleared: map it again or destroy the renderer.
            slot.0.reset(phase.chunk_range(chunk as usize));
            fault_error(fault, &format!("chunk {chunk} was not mapped: map it again or destroy the renderer"))?;
        }
        slot.1 = true;
        Ok(EmberStatus::Ok)
    })
}

/// Reduce the open phase (every chunk mapped) into the estimator and the film.
#[unsafe(no_mangle)]
pub extern "C" fn ember_phase_end(renderer: EmberRenderer) -> EmberStatus {
    guard(|| {
        let shared = renderer_of(renderer)?;
        let mut open = shared.phase_write()?;
        let Some((_, slots)) = open.as_ref() else { return Err(Error::arg("no phase is open: call ember_phase_begin")) };
        // Every chunk mapped once, and none of them panicked; a missing chunk leaves the
        // phase open for the host to map it, a panicked one closes it.
        let problem = slots.iter().enumerate().find_map(|(c, slot)| match slot.lock() {
            Ok(s) if s.1 => None,
            Ok(_) => Some((false, format!("chunk {c} of {} was not mapped: map it, then end the phase", slots.len()))),
            Err(_) => Some((true, format!("mapping chunk {c} panicked: destroy the renderer"))),
        });
        match problem {
            None => {}
            Some((false, message)) => return Err(Error::arg(message)),
            Some((true, message)) => {
                *open = None;
                return Err(Error::new(EmberStatus::Panic, message));
            }
        }
        let Some((phase, slots)) = open.take() else { return Err(Error::arg("no phase is open: call ember_phase_begin")) };
        let mut outputs: Vec<ChunkOutput> = slots.into_iter().filter_map(|m| m.into_inner().ok().map(|(o, _)| o)).collect();
        let mut guard = crate::write(&shared.state)?;
        let st = &mut *guard;
        let fault = Fault::new();
        let q = tracer(&st.scene, &st.callbacks, &fault);
        let ctx = Context { scene: &st.scene.scene, tracer: &q };
        Phased::<Tracer<'_>>::reduce(&mut st.renderer, &ctx, &phase, &mut outputs, &mut st.film);
        st.ready = true;
        fault_error(fault, "the rest of the reduction's rays were misses: destroy the renderer")?;
        Ok(EmberStatus::Ok)
    })
}
