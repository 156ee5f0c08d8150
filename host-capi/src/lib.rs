//! ember for engines written in C, C++ or anything with a C FFI (docs/embedding.md).
//!
//! The model is Embree's: opaque handles with create and destroy, a status code from
//! every call plus a message for the last error, and callbacks with a user-data pointer
//! where the engine brings its own ray tracer. The C declarations are in
//! `include/ember.h`, generated from [`ffi`] by cbindgen and checked to be current by
//! `tests/header.rs`.
//!
//! Layers: this module is the safe part (the handle registry with generation-checked
//! ids, scenes built from plain descriptions, renderers driving the core's render
//! protocol on `ember-host`'s threads and BVH); [`ffi`] is the only module with
//! `unsafe`: it turns pointers and lengths into slices, calls the engine's callbacks, and
//! catches every panic at the boundary.

pub mod ffi;
pub mod film_state;

use std::borrow::Cow;
use std::sync::{Arc, OnceLock, RwLock, RwLockReadGuard, RwLockWriteGuard, TryLockError};

use ember_core::camera::{FovAxis, PerspectiveCamera};
use ember_core::estimators::options::{self, OptionError, Options};
use ember_core::estimators::{EstimatorConfig, EstimatorKind, Renderer};
use ember_core::math::Vec3;
use ember_core::render::Film;
use ember_core::scene::{AreaEmission, Scene, SceneBuilder, SceneGeometry};
use ember_core::spectrum::Rgb;
use ember_core::transport::{Heuristic, MaxDepth, RenderParams};
use ember_host::accel::Accel;

/// What a call returned. Every function returns one; `Ok` is 0.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EmberStatus {
    /// Success.
    Ok = 0,
    /// A required pointer was null.
    NullPointer = 1,
    /// A count, index, size or value is out of its range (the message says which).
    InvalidArgument = 2,
    /// The handle was never created, or was destroyed.
    InvalidHandle = 3,
    /// The estimator name or a configuration value is not valid (the message names it).
    InvalidConfig = 4,
    /// The renderer is in use by another call (calls on one renderer do not overlap).
    Busy = 5,
    /// A panic inside ember was caught at the boundary; the object involved should be
    /// destroyed (its state is unknown).
    Panic = 6,
    /// `ember_phase_begin`: no phase is pending (the pass is complete).
    Done = 7,
    /// `ember_renderer_create`: the render would need more memory than is available (or
    /// than the `memory-limit` option allows). Nothing was allocated; the message says
    /// what to lower.
    OutOfMemory = 8,
    /// A ray callback returned a hit that breaks its contract (the message names the
    /// value). The rest of the call treated every ray as a miss, so the film's passes
    /// are not to be trusted: destroy the renderer.
    CallbackError = 9,
    /// `ember_film_import`: the bytes are not a film this library reads: the magic, the
    /// format version, the size (a truncated buffer) or the checksum (a damaged one) is
    /// wrong (the message names which).
    InvalidFilm = 10,
    /// `ember_film_import`: the film is of another render: another estimator,
    /// configuration, seed, max depth, tracer, size, scene, film kind or ember build (the message
    /// names the field and both values).
    FilmMismatch = 11,
}

/// An error: its status and message.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Error {
    pub status: EmberStatus,
    pub message: String,
}

impl Error {
    pub fn new(status: EmberStatus, message: impl Into<String>) -> Self {
        Self { status, message: message.into() }
    }
    fn arg(message: impl Into<String>) -> Self {
        Self::new(EmberStatus::InvalidArgument, message)
    }
}

/// A result of the safe layer.
pub type Result<T> = std::result::Result<T, Error>;

/// Handles: the slot index in the low 32 bits, the slot's generation in the high 32. A
/// destroyed handle's slot gets a new generation, so the old id is refused even after
/// the slot is reused. 0 is never a valid handle.
#[derive(Debug)]
pub struct Registry<T> {
    slots: Vec<(u32, Option<T>)>,
}

impl<T> Default for Registry<T> {
    fn default() -> Self {
        Self { slots: Vec::new() }
    }
}

impl<T> Registry<T> {
    /// Store `value`; its handle.
    pub fn insert(&mut self, value: T) -> u64 {
        let index = match self.slots.iter().position(|(_, v)| v.is_none()) {
            Some(i) => i,
            None => {
                self.slots.push((0, None));
                self.slots.len() - 1
            }
        };
        let slot = &mut self.slots[index];
        slot.0 = slot.0.wrapping_add(1).max(1);
        slot.1 = Some(value);
        ((slot.0 as u64) << 32) | index as u64
    }

    fn slot(&self, handle: u64) -> Option<&(u32, Option<T>)> {
        let (generation, index) = ((handle >> 32) as u32, handle as u32 as usize);
        self.slots.get(index).filter(|(g, v)| *g == generation && generation != 0 && v.is_some())
    }

    /// The value behind `handle`, if it is live.
    pub fn get(&self, handle: u64) -> Option<&T> {
        self.slot(handle).and_then(|(_, v)| v.as_ref())
    }

    /// Remove the value behind `handle`; `None` if it was not live.
    pub fn remove(&mut self, handle: u64) -> Option<T> {
        self.slot(handle)?;
        let slot = &mut self.slots[handle as u32 as usize];
        slot.1.take()
    }
}

/// A material of a scene description.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MaterialDesc {
    /// Lambertian with this albedo.
    Diffuse([f32; 3]),
    /// A perfect mirror with this reflectance.
    Mirror([f32; 3]),
    /// Smooth glass with this interior index of refraction (outside: 1).
    Glass(f32),
}

/// A scene as plain data: triangles indexing positions, a material and optional
/// emitted radiance per triangle, point lights and a camera.
#[derive(Clone, Debug, Default)]
pub struct SceneDesc {
    pub positions: Vec<[f32; 3]>,
    pub triangles: Vec<[u32; 3]>,
    pub triangle_materials: Vec<u32>,
    /// Per triangle, or empty: radiance emitted from the triangle's front.
    pub triangle_emission: Vec<[f32; 3]>,
    pub materials: Vec<MaterialDesc>,
    /// (position, intensity).
    pub point_lights: Vec<([f32; 3], [f32; 3])>,
    /// The camera: the C struct itself (plain values, no pointers).
    pub camera: ffi::EmberCamera,
}

/// A built scene: what the estimators read, the tracer's geometry, the built-in BVH and,
/// per triangle of the description, its index in the geometry (`None`: dropped as
/// degenerate).
#[derive(Debug)]
pub struct SceneData {
    pub scene: Scene,
    pub geometry: SceneGeometry,
    pub accel: Accel,
    pub triangle_index: Vec<Option<u32>>,
    /// [`SceneData::hash`], computed the first time it is asked for.
    hash: OnceLock<u64>,
}

fn finite3(v: [f32; 3], what: &str) -> Result<Vec3> {
    if v.iter().all(|x| x.is_finite()) { Ok(Vec3::from(v)) } else { Err(Error::arg(format!("{what} is not finite"))) }
}

fn colour(v: [f32; 3], what: &str) -> Result<Rgb> {
    if v.iter().all(|x| x.is_finite() && *x >= 0.0) { Ok(Rgb::new(v[0], v[1], v[2])) } else { Err(Error::arg(format!("{what} is negative or not finite"))) }
}

impl SceneData {
    /// Build `desc`, checking every index and value.
    pub fn from_desc(desc: &SceneDesc) -> Result<Self> {
        let cam = &desc.camera;
        if cam.width == 0 || cam.height == 0 || cam.width > 65536 || cam.height > 65536 {
            return Err(Error::arg(format!("camera size {}x{} is outside 1..=65536", cam.width, cam.height)));
        }
        if !(cam.fov_degrees > 0.0 && cam.fov_degrees < 180.0) {
            return Err(Error::arg(format!("camera fov_degrees {} is outside (0, 180)", cam.fov_degrees)));
        }
        let (origin, target, up) = (finite3(cam.origin, "camera origin")?, finite3(cam.target, "camera target")?, finite3(cam.up, "camera up")?);
        let forward = target - origin;
        if forward.length_squared() == 0.0 || forward.cross(up).length_squared() == 0.0 {
            return Err(Error::arg("camera target equals its origin, or up is parallel to the view direction"));
        }
        let mut b = SceneBuilder::new();
        b.set_camera(PerspectiveCamera::new(ember_core::scene::builtin::look_at(origin, target, up), cam.fov_degrees, FovAxis::X, cam.width, cam.height));
        let mut materials = Vec::with_capacity(desc.materials.len());
        for (i, m) in desc.materials.iter().enumerate() {
            let material = match *m {
                MaterialDesc::Diffuse(c) => ember_core::bsdf::Material::diffuse(colour(c, &format!("material {i}'s albedo"))?),
                MaterialDesc::Mirror(c) => ember_core::bsdf::Material::conductor(Rgb::ZERO, Rgb::ONE, colour(c, &format!("material {i}'s reflectance"))?),
                MaterialDesc::Glass(ior) if ior.is_finite() && ior > 0.0 => ember_core::bsdf::Material::dielectric(ior, 1.0, Rgb::ONE, Rgb::ONE),
                MaterialDesc::Glass(ior) => return Err(Error::arg(format!("material {i}'s index of refraction {ior} is not positive and finite"))),
            };
            materials.push(b.add_material(material));
        }
        let n = desc.triangles.len();
        if desc.triangle_materials.len() != n {
            return Err(Error::arg(format!("{} triangle materials for {n} triangles", desc.triangle_materials.len())));
        }
        if !desc.triangle_emission.is_empty() && desc.triangle_emission.len() != n {
            return Err(Error::arg(format!("{} triangle emissions for {n} triangles (give none or one per triangle)", desc.triangle_emission.len())));
        }
        let positions: Vec<Vec3> = desc.positions.iter().enumerate().map(|(i, p)| finite3(*p, &format!("position {i}"))).collect::<Result<_>>()?;
        let mut triangle_index = Vec::with_capacity(n);
        let mut kept = 0u32;
        for (t, tri) in desc.triangles.iter().enumerate() {
            let p = tri.map(|v| positions.get(v as usize).copied());
            let [Some(p0), Some(p1), Some(p2)] = p else {
                return Err(Error::arg(format!("triangle {t} indexes a vertex past the {} positions", positions.len())));
            };
            let m = desc.triangle_materials[t];
            let material =
                *materials.get(m as usize).ok_or_else(|| Error::arg(format!("triangle {t}'s material {m} is past the {} materials", materials.len())))?;
            let emission = match desc.triangle_emission.get(t) {
                Some(e) if e.iter().any(|&x| x != 0.0) => Some(AreaEmission { radiance: colour(*e, &format!("triangle {t}'s emission"))?, two_sided: false }),
                _ => None,
            };
            if b.add_triangle([p0, p1, p2], None, material, emission) {
                triangle_index.push(Some(kept));
                kept += 1;
            } else {
                triangle_index.push(None);
            }
        }
        for (i, (p, intensity)) in desc.point_lights.iter().enumerate() {
            let light = ember_core::light::Light::point(
                finite3(*p, &format!("point light {i}'s position"))?,
                colour(*intensity, &format!("point light {i}'s intensity"))?,
            );
            b.add_light(light);
        }
        let (scene, geometry, _) = b.build().map_err(|e| Error::arg(format!("the scene cannot be built: {e}")))?;
        Ok(Self::new(scene, geometry, triangle_index))
    }

    /// A built-in scene: `cornell-box` or `glass-spheres`, as `ember render --builtin`.
    pub fn builtin(name: &str, width: u32, height: u32) -> Result<Self> {
        if width == 0 || height == 0 || width > 65536 || height > 65536 {
            return Err(Error::arg(format!("size {width}x{height} is outside 1..=65536")));
        }
        let builder = match name {
            "cornell-box" => ember_core::scene::builtin::cornell_box(width, height),
            "glass-spheres" => ember_core::scene::builtin_glass::glass_spheres(width, height),
            other => return Err(Error::arg(format!("no built-in scene '{other}' (cornell-box, glass-spheres)"))),
        };
        let (scene, geometry, _) = builder.build().map_err(|e| Error::arg(format!("built-in scene: {e}")))?;
        let triangle_index = (0..geometry.triangles.len() as u32).map(Some).collect();
        Ok(Self::new(scene, geometry, triangle_index))
    }

    fn new(scene: Scene, geometry: SceneGeometry, triangle_index: Vec<Option<u32>>) -> Self {
        let accel = Accel::new(&geometry);
        Self { scene, geometry, accel, triangle_index, hash: OnceLock::new() }
    }

    /// FNV-1a of everything a render reads, as the CLI hashes its scenes
    /// (`ember_host::scene::PreparedScene::hash`): the scene's `Debug` form (camera,
    /// materials, lights), the BVH's geometry as raw bits, and each description
    /// triangle's index in the geometry (the callbacks name triangles by it; `u32::MAX`
    /// for a dropped one). Computed once, when an
    /// exported film first needs it.
    pub fn hash(&self) -> u64 {
        *self.hash.get_or_init(|| {
            let mut h = ember_host::scene::scene_hasher(&self.scene, &self.accel);
            for index in &self.triangle_index {
                std::hash::Hasher::write_u32(&mut h, index.unwrap_or(u32::MAX));
            }
            h.value()
        })
    }
}

/// Rendering settings: the estimator by name, the shared settings, and the estimator's
/// configuration as options.
#[derive(Clone, Debug, PartialEq)]
pub struct Settings {
    pub estimator: String,
    pub seed: u64,
    pub max_depth: i32,
    pub threads: u32,
    pub light_paths: u32,
    pub connections: u32,
    pub radius_footprints: f32,
    /// Further options of the estimator's configuration, space-separated `name=value`
    /// with the names of `ember render`'s options (`subspaces=64 reuse=0 kernel=disk`).
    pub options: String,
}

/// [`Settings`] validated: the core's configuration and what the C API itself uses.
#[derive(Clone, Debug, PartialEq)]
pub struct Config {
    pub estimator: EstimatorConfig,
    pub params: RenderParams,
    /// The `memory-limit` option: the bytes a renderer may claim (else the memory available).
    pub memory_limit: Option<u64>,
    /// Threads for `ember_render_passes`, capped ([`thread_count`]).
    pub threads: usize,
}

/// The option that is the C API's own, not an estimator's: `ember render --memory-limit`.
const MEMORY_LIMIT: &str = "memory-limit";

impl Settings {
    /// The settings validated. The options go through the core's options table
    /// ([`ember_core::estimators::options`], which the command line's flags are checked against), so
    /// every configuration field the CLI sets is settable here with the same names and
    /// defaults, and the core validates each value; besides them only `memory-limit`
    /// (`ember render`'s, with its parser) is accepted.
    pub fn config(&self) -> Result<Config> {
        let invalid = |m: String| Error::new(EmberStatus::InvalidConfig, m);
        let kind = EstimatorKind::from_name(&self.estimator).ok_or_else(|| {
            let names: Vec<&str> = EstimatorKind::ALL.iter().map(|k| k.name()).collect();
            invalid(format!("no estimator '{}' ({})", self.estimator, names.join(", ")))
        })?;
        if self.max_depth < -1 {
            return Err(invalid(format!("max_depth {} is below -1 (-1: unbounded)", self.max_depth)));
        }
        // The settings' own fields first, as options given (an option repeating one is
        // refused as given twice).
        let mut options = Options::new(kind);
        let mut set = |name: &str, value: &str| options.set(name, value).map_err(|e| invalid(message(e)));
        if self.light_paths > 0 {
            set("light-paths", &self.light_paths.to_string())?;
        }
        if self.connections > 0 {
            set("connections", &self.connections.to_string())?;
        }
        if self.radius_footprints != 0.0 {
            set("radius-footprints", &self.radius_footprints.to_string())?;
        }
        let mut memory_limit = None;
        for pair in options::pairs(&self.options) {
            let (name, value) = pair.map_err(|e| invalid(message(e)))?;
            if name == MEMORY_LIMIT {
                if memory_limit.is_some() {
                    return Err(invalid(format!("option '{MEMORY_LIMIT}' is given twice")));
                }
                memory_limit = Some(ember_host::memory::parse_size(value).map_err(|e| invalid(format!("{MEMORY_LIMIT}: {e}")))?);
                continue;
            }
            set(name, value)?;
        }
        let estimator = options.finish().map_err(|e| invalid(message(e)))?;
        // As `ember render`: PT's two techniques under the power heuristic.
        let params = RenderParams { max_depth: MaxDepth(self.max_depth), seed: self.seed, heuristic: Heuristic::Power, ..RenderParams::default() };
        Ok(Config { estimator, params, memory_limit, threads: thread_count(self.threads) })
    }
}

/// The threads `ember_render_passes` starts for `requested` (0: every core): capped, not
/// refused, at 4 × the cores and at 1024, as `ember render --threads` caps them
/// (`ember_host::driver::capped_threads`: the CLI's rule without its warning, which a
/// library must not print). Without the cap `UINT32_MAX` spent 30 s and 240 MB starting threads
/// before failing.
pub fn thread_count(requested: u32) -> usize {
    ember_host::driver::capped_threads((requested != 0).then_some(requested))
}

/// Refuse, before the film and the estimator's stores are allocated, a renderer whose
/// estimated memory ([`EstimatorConfig::memory_estimate`], at least the film's) exceeds
/// `limit` or, without one, the memory available (`ember_host::memory`): as `ember
/// render` refuses it. An allocation that fails aborts the process, which no
/// `catch_unwind` can turn into a status (a 65536×65536 camera did).
pub fn check_memory(scene: &SceneData, config: &EstimatorConfig, limit: Option<u64>) -> Result<()> {
    let camera = &scene.scene.camera;
    let (bytes, estimate) = ember_host::memory::need(camera, config);
    let (available, source) = match limit {
        Some(l) => (Some(l), "the memory-limit option"),
        None => (ember_host::memory::available_bytes(), "available memory"),
    };
    match available {
        Some(a) if bytes > a => Err(Error::new(
            EmberStatus::OutOfMemory,
            format!(
                "{} would need about {} ({} at {}×{} is the largest part), more than the {} of {source}; lower {}",
                config.kind(),
                ember_host::memory::human(bytes),
                estimate.largest,
                camera.width(),
                camera.height(),
                ember_host::memory::human(a),
                c_spelling(estimate.lower)
            ),
        )),
        _ => Ok(()),
    }
}

/// What to lower, as the core spells it for the command line (`--width/--height`,
/// `--light-paths`, `--dataset`, …), in this API's words: the camera's size, a field of
/// `EmberRenderSettings`, or an option of the options string.
fn c_spelling(lower: &str) -> String {
    const FIELDS: [&str; 3] = ["light-paths", "connections", "radius-footprints"];
    lower
        .replace("--width/--height", "the camera's width and height")
        .split(' ')
        .map(|word| match word.strip_prefix("--") {
            Some(name) if FIELDS.contains(&name) => format!("settings.{}", name.replace('-', "_")),
            Some(name) => format!("the option {name}"),
            None => word.to_string(),
        })
        .collect::<Vec<_>>()
        .join(" ")
}

/// An options error in this API's words: an unknown name lists `memory-limit` too.
fn message(e: OptionError) -> String {
    match e {
        OptionError::Unknown(name) => {
            let names: Vec<&str> = options::all().iter().map(|o| o.name).collect();
            format!("no estimator option '{name}' (options: {}, {MEMORY_LIMIT})", names.join(", "))
        }
        other => other.to_string(),
    }
}

/// A renderer: an estimator bound to a scene (kept alive by the renderer), its film,
/// and the engine's ray callbacks when it brought some.
///
/// After `ember_film_import` the passes are split in two: `imported` holds passes
/// `0..N`, `film` the passes rendered since, `N..` (the driver's `first_pass` N, as a
/// resumed `ember render`); the image and an export are their exact merge ([`Self::whole`]).
#[derive(Debug)]
pub struct RendererState {
    pub scene: Arc<SceneData>,
    pub renderer: Renderer,
    pub film: Film,
    /// The passes `0..N` an import brought (`None`: none, `film` holds passes `0..`).
    pub imported: Option<Film>,
    /// What the film's passes depend on, less the scene's hash (computed on export).
    pub identity: RenderIdentity,
    pub threads: usize,
    /// The render threads, started by the first `ember_render_passes` and kept until the
    /// renderer is destroyed (a pool per call started `threads` threads for every call).
    pub pool: Option<rayon::ThreadPool>,
    pub callbacks: Option<ffi::Callbacks>,
    /// Set up (setup phases run).
    pub ready: bool,
    /// `ember_pass_start` has queued a pass (an import then comes too late).
    pub pass_started: bool,
    /// The first `ember_pass_start` (pass, and the pass one render would start there)
    /// whose index was not the next: the film then holds no passes `0..N` to export.
    pub out_of_order: Option<(u32, u32)>,
}

/// The renderer's side of [`film_state::FilmIdentity`], fixed at creation.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RenderIdentity {
    pub estimator: String,
    pub config: String,
    pub seed: u64,
    pub max_depth: i32,
}

impl RenderIdentity {
    /// The identity of a render with `config` (the CLI's configuration text for a
    /// partial image, less the max depth, which is a field of its own).
    pub fn of(config: &Config) -> Self {
        let p = &config.params;
        Self {
            estimator: config.estimator.kind().name().to_string(),
            config: format!("{:?}; heuristic {:?}, rr depth {}", config.estimator, p.heuristic, p.rr_depth),
            seed: p.seed,
            max_depth: p.max_depth.0,
        }
    }
}

impl RendererState {
    /// Every pass the renderer holds, imported ones included.
    pub fn passes(&self) -> u32 {
        self.imported.as_ref().map_or(0, Film::passes).saturating_add(self.film.passes())
    }

    /// The film of every pass: the imported passes merged (exactly) with those rendered
    /// since, or the film itself when nothing was imported.
    pub fn whole(&self) -> Result<Cow<'_, Film>> {
        let Some(imported) = &self.imported else { return Ok(Cow::Borrowed(&self.film)) };
        let mut whole = imported.clone();
        // Same size (checked on import), and `ember_render_passes` keeps the count in u32.
        whole.merge(&self.film).map_err(|e| Error::arg(format!("the imported film and the passes since cannot be merged: {e}")))?;
        Ok(Cow::Owned(whole))
    }

    /// The identity an export records and an import must match.
    pub fn film_identity(&self) -> film_state::FilmIdentity {
        let id = &self.identity;
        film_state::FilmIdentity {
            build: ember_host::program_version(),
            estimator: id.estimator.clone(),
            config: id.config.clone(),
            seed: id.seed,
            max_depth: id.max_depth,
            callbacks: self.callbacks.is_some(),
            scene_hash: self.scene.hash(),
            width: self.film.width(),
            height: self.film.height(),
            weighted: !self.film.weighted_sums().is_empty(),
        }
    }
}

/// Lock a renderer for a call that changes it, or say it is busy (or was left broken by
/// a panic).
pub fn write(r: &RwLock<RendererState>) -> Result<RwLockWriteGuard<'_, RendererState>> {
    r.try_write().map_err(busy_or_poisoned)
}

/// Lock a renderer for a call that reads it (several may read at once: the chunks of a
/// phase mapped on the host's threads).
pub fn read(r: &RwLock<RendererState>) -> Result<RwLockReadGuard<'_, RendererState>> {
    r.try_read().map_err(busy_or_poisoned)
}

fn busy_or_poisoned<G>(e: TryLockError<G>) -> Error {
    match e {
        TryLockError::WouldBlock => Error::new(EmberStatus::Busy, "the renderer is in use by another call"),
        TryLockError::Poisoned(_) => Error::new(EmberStatus::Panic, "a previous call on this renderer panicked: destroy it"),
    }
}
