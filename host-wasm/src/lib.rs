//! ember in the browser: the core's estimators (`ember_core::integrator::{pt, lt, bdpt}`;
//! the others need the render protocol on the workers, issue 19)
//! over an obvhs BVH2 ([`accel`]), compiled to `wasm32-unknown-unknown` and driven by a
//! static page (`host-wasm/www/`) through plain C exports. No wasm-bindgen, no imports:
//! the module needs nothing from JavaScript, and JavaScript reads the results straight
//! out of the module's linear memory.
//!
//! # Protocol
//! Workers (one module instance each):
//! 1. `ember_setup(scene, estimator, width, height, max_depth, seed_hi, seed_lo)` builds
//!    the scene and the BVH; 0 on success, a negative [`SetupError`] code otherwise.
//!    Scene and estimator are indices into [`SCENES`] and `EstimatorKind::ALL` (the page
//!    reads both lists from the module: [`page`]).
//! 2. Each pass, `ember_render(pass, pixel_start, pixel_end, path_start, path_end)` renders
//!    the camera samples of pixels `pixel_start..pixel_end` (PT, BDPT) and the light
//!    paths `path_start..path_end` (LT; `ember_light_paths_per_pass` of them per pass):
//!    camera values, 3 × f32 per band pixel, at `ember_camera_ptr()`, and the call's
//!    splats, 5 × f32 each (film x, y, r, g, b), at `ember_splat_ptr()`
//!    (`ember_splat_count()` of them), both raw.
//!
//! The page's own instance holds the core's [`ember_core::render::Film`] ([`page`]): per
//! pass it stages every band's camera values, then every worker's splats in worker
//! order (that is, in pixel or light-path order, as the CLI's driver reduces them), and
//! commits the pass with `ember_splat_scale()`. Invalid values are discarded and counted
//! there, as in the CLI, and the image is the CLI's bit for bit up to ray-query
//! differences between the two BVHs.
//!
//! Random numbers derive from (seed, pixel or path index, pass) only
//! (`SampleStream::for_sample`), so how the page cuts the image into bands, and how
//! many workers it runs, changes nothing.

pub mod accel;
#[cfg(not(target_arch = "wasm32"))]
pub mod compare;
pub mod page;
#[cfg(test)]
mod tests;

use core::cell::RefCell;

use ember_core::Rgb;
use ember_core::integrator::{Counters, Heuristic, MaxDepth, RenderParams, Splat, bdpt, lt, pt};
use ember_core::render::EstimatorKind;
use ember_core::scene::{Scene, SceneBuilder, builtin, builtin_glass};

pub use accel::WasmAccel;

/// The built-in scenes the page offers, by the index it passes to `ember_setup`.
pub const SCENES: [&str; 2] = ["cornell-box", builtin_glass::GLASS_SPHERES];

/// The scene builder for a [`SCENES`] index.
pub fn builtin_scene(index: u32, width: u32, height: u32) -> Option<SceneBuilder> {
    match index {
        0 => Some(builtin::cornell_box(width, height)),
        1 => Some(builtin_glass::glass_spheres(width, height)),
        _ => None,
    }
}

/// The estimators the page can run (their indices in [`EstimatorKind::ALL`]: 0 pt,
/// 1 lt, 2 bdpt); the cache-based ones need the phase protocol on the workers (issue 19).
pub fn supported(kind: EstimatorKind) -> bool {
    matches!(kind, EstimatorKind::Pt | EstimatorKind::Lt | EstimatorKind::Bdpt)
}

/// Why `ember_setup` failed (returned negated).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SetupError {
    UnknownScene = 1,
    UnknownEstimator = 2,
    /// Width or height zero, or more than 4096.
    BadResolution = 3,
    /// The scene builder rejected the scene.
    SceneBuild = 4,
}

/// Why `ember_render` failed (returned negated).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RenderError {
    NotSetUp = 1,
    /// A pixel or path range outside the image / the pass's light paths.
    BadRange = 2,
}

/// A scene, its ray queries, the estimator and the output buffers of the last call.
#[derive(Debug)]
pub struct Renderer {
    pub scene: Scene,
    pub accel: WasmAccel,
    pub estimator: EstimatorKind,
    pub params: RenderParams,
    camera: Vec<Rgb>,
    camera_out: Vec<f32>,
    /// The call's splats as plain floats, 5 per splat (film x, y, r, g, b).
    splats: Vec<f32>,
    pub last: Counters,
}

impl Renderer {
    /// Build a built-in scene; `max_depth` −1 is unbounded (the CLI's default).
    pub fn new(scene: u32, estimator: u32, width: u32, height: u32, max_depth: i32, seed: u64) -> Result<Self, SetupError> {
        let estimator = EstimatorKind::from_index(estimator).filter(|&e| supported(e)).ok_or(SetupError::UnknownEstimator)?;
        if width == 0 || height == 0 || width > 4096 || height > 4096 {
            return Err(SetupError::BadResolution);
        }
        let builder = builtin_scene(scene, width, height).ok_or(SetupError::UnknownScene)?;
        let (scene, geometry, _warnings) = builder.build().map_err(|_| SetupError::SceneBuild)?;
        let accel = WasmAccel::new(&geometry);
        // As the CLI: PT with the power heuristic; BDPT's weights are balance by construction.
        let params = RenderParams { max_depth: MaxDepth(max_depth), seed, heuristic: Heuristic::Power, ..RenderParams::default() };
        Ok(Self { scene, accel, estimator, params, camera: Vec::new(), camera_out: Vec::new(), splats: Vec::new(), last: Counters::default() })
    }

    pub fn width(&self) -> u32 {
        self.scene.camera.width()
    }

    pub fn height(&self) -> u32 {
        self.scene.camera.height()
    }

    fn pixels(&self) -> u32 {
        self.width() * self.height()
    }

    /// Light paths per pass: W·H for LT (as the CLI), none otherwise.
    pub fn light_paths_per_pass(&self) -> u32 {
        if self.estimator == EstimatorKind::Lt { self.pixels() } else { 0 }
    }

    /// Render one pass's share; see the crate documentation.
    pub fn render(&mut self, pass: u32, pixels: core::ops::Range<u32>, paths: core::ops::Range<u32>) -> Result<(), RenderError> {
        if pixels.start > pixels.end || pixels.end > self.pixels() || paths.start > paths.end || paths.end > self.light_paths_per_pass() {
            return Err(RenderError::BadRange);
        }
        self.splats.clear();
        self.camera.clear();
        self.camera.resize(pixels.len(), Rgb::ZERO);
        let splats = &mut self.splats;
        let mut splat = |s: Splat| splats.extend_from_slice(&[s.film.x, s.film.y, s.value.r, s.value.g, s.value.b]);
        let (scene, accel, params) = (&self.scene, &self.accel, &self.params);
        self.last = match self.estimator {
            EstimatorKind::Pt => pt::render_pixels(scene, accel, params, pass, pixels, &mut self.camera),
            EstimatorKind::Bdpt => bdpt::render_pixels(scene, accel, params, pass, pixels, &mut self.camera, &mut splat),
            EstimatorKind::Lt => lt::trace_paths(scene, accel, params, pass, paths, &mut splat),
            _ => Counters::default(),
        };
        // Raw values: the page's film (the core's) discards and counts invalid ones.
        self.camera_out.clear();
        self.camera_out.extend(self.camera.iter().flat_map(|v| [v.r, v.g, v.b]));
        Ok(())
    }

    /// The factor the page's film multiplies this estimator's splats by: 1/(W·H) (LT traces
    /// W·H light paths per pass; BDPT one per pixel).
    pub fn splat_scale(&self) -> f64 {
        1.0 / self.pixels().max(1) as f64
    }

    /// Camera values of the last call, 3 × f32 per pixel of its band (not sanitised).
    pub fn camera_values(&self) -> &[f32] {
        &self.camera_out
    }

    /// Splats of the last call, 5 × f32 each (film x, y, r, g, b), in emission order.
    pub fn splat_values(&self) -> &[f32] {
        &self.splats
    }
}

thread_local! {
    /// The module's one renderer (wasm32 is single-threaded; one instance per worker).
    static RENDERER: RefCell<Option<Renderer>> = const { RefCell::new(None) };
}

fn with_renderer<T>(default: T, f: impl FnOnce(&mut Renderer) -> T) -> T {
    RENDERER.with_borrow_mut(|r| r.as_mut().map_or(default, f))
}

// The exports below need `#[unsafe(no_mangle)]` so the page can call them by name; the
// attribute is the only unsafe thing in this crate (it trusts no other symbol has the
// same name, and every name carries the `ember_` prefix).

/// Build scene `scene` ([`SCENES`]) for estimator `estimator` (0 pt, 1 lt, 2 bdpt);
/// 0 on success, −[`SetupError`] otherwise.
#[allow(unsafe_code)]
#[unsafe(no_mangle)]
pub extern "C" fn ember_setup(scene: u32, estimator: u32, width: u32, height: u32, max_depth: i32, seed_hi: u32, seed_lo: u32) -> i32 {
    let seed = (u64::from(seed_hi) << 32) | u64::from(seed_lo);
    match Renderer::new(scene, estimator, width, height, max_depth, seed) {
        Ok(r) => {
            RENDERER.with_borrow_mut(|slot| *slot = Some(r));
            0
        }
        Err(e) => -(e as i32),
    }
}

/// Light paths per pass (W·H for LT, 0 otherwise); 0 before setup.
#[allow(unsafe_code)]
#[unsafe(no_mangle)]
pub extern "C" fn ember_light_paths_per_pass() -> u32 {
    with_renderer(0, |r| r.light_paths_per_pass())
}

/// Number of triangles in the ray-query structure (for the page's status line).
#[allow(unsafe_code)]
#[unsafe(no_mangle)]
pub extern "C" fn ember_triangle_count() -> u32 {
    with_renderer(0, |r| r.accel.triangle_count() as u32)
}

/// Render pass `pass` for pixels `pixel_start..pixel_end` and light paths
/// `path_start..path_end`; 0 on success, −[`RenderError`] otherwise.
#[allow(unsafe_code)]
#[unsafe(no_mangle)]
pub extern "C" fn ember_render(pass: u32, pixel_start: u32, pixel_end: u32, path_start: u32, path_end: u32) -> i32 {
    with_renderer(-(RenderError::NotSetUp as i32), |r| match r.render(pass, pixel_start..pixel_end, path_start..path_end) {
        Ok(()) => 0,
        Err(e) => -(e as i32),
    })
}

/// Address of the last call's camera values (3 × f32 per band pixel).
#[allow(unsafe_code)]
#[unsafe(no_mangle)]
pub extern "C" fn ember_camera_ptr() -> usize {
    with_renderer(0, |r| r.camera_values().as_ptr() as usize)
}

/// Address of the last call's splats (5 × f32 each: film x, y, r, g, b).
#[allow(unsafe_code)]
#[unsafe(no_mangle)]
pub extern "C" fn ember_splat_ptr() -> usize {
    with_renderer(0, |r| r.splat_values().as_ptr() as usize)
}

/// Splats made in the last call.
#[allow(unsafe_code)]
#[unsafe(no_mangle)]
pub extern "C" fn ember_splat_count() -> u32 {
    with_renderer(0, |r| (r.splat_values().len() / 5) as u32)
}

/// The factor the page's film multiplies this estimator's splats by; 0 before setup.
#[allow(unsafe_code)]
#[unsafe(no_mangle)]
pub extern "C" fn ember_splat_scale() -> f64 {
    with_renderer(0.0, |r| r.splat_scale())
}

/// Rays traced in the last call (f64: exact up to 2⁵³).
#[allow(unsafe_code)]
#[unsafe(no_mangle)]
pub extern "C" fn ember_last_rays() -> f64 {
    with_renderer(0.0, |r| r.last.rays as f64)
}
