//! A render in progress: the renderer `ember render` would build for the same arguments
//! (the options parsed and checked by the core's options table, the scene plan, the
//! memory check, the setup phases, the radius check: [`ember_host::setup`]), its film, and
//! a thread pool kept for its passes. Python drives it one pass per [`Render::step`], the
//! GIL released during the pass; between passes Python runs its signal handlers, so
//! Ctrl-C raises `KeyboardInterrupt` at the next pass boundary and the film keeps the
//! passes done.
//!
//! A render of n passes one step at a time is the driver's render of n passes: the
//! driver continues a film that holds passes (the pass index, and with it every random
//! stream, is the film's pass count), as `ember render --checkpoint` relies on too.

use std::sync::Arc;
use std::time::{Duration, Instant};

use pyo3::prelude::*;
use pyo3::types::PyByteArray;

use ember_core::estimators::options::{self, OptionError, Options};
use ember_core::estimators::{EstimatorKind, Renderer};
use ember_core::render::{Context, Film};
use ember_host::driver::{self, Limits};
use ember_host::scene::PreparedScene;
use ember_host::setup;

use crate::Error;
use crate::scene::Scene;

/// What a render is asked for, as the Python half hands it over (types and integer
/// ranges already checked there).
#[derive(Debug)]
struct Request {
    estimator: String,
    options: Vec<(String, String)>,
    seed: u64,
    threads: Option<u32>,
    width: Option<u32>,
    height: Option<u32>,
    max_depth: Option<i32>,
    no_plan: bool,
    spp: Option<u32>,
    time: Option<f64>,
}

/// A render: the renderer after its setup, the film so far and when to stop.
#[pyclass(module = "ember._ember")]
#[derive(Debug)]
pub struct Render {
    prepared: Arc<PreparedScene>,
    renderer: Renderer,
    film: Film,
    pool: rayon::ThreadPool,
    /// The passes asked for (`u32::MAX`: until the time budget).
    limit: u32,
    deadline: Option<Instant>,
    start: Instant,
    /// The scene plan's lines (`ember render` prints them as `plan ...`).
    plan: Vec<String>,
    setup_seconds: f64,
}

/// The estimator `name` names; `auto` is the command line's race, not offered here.
fn estimator(name: &str) -> Result<EstimatorKind, Error> {
    let names = || EstimatorKind::ALL.iter().map(|k| k.name()).collect::<Vec<_>>().join(", ");
    match EstimatorKind::from_name(name) {
        Some(k) if k.is_compiled() => Ok(k),
        Some(k) => Err(Error::Value(format!("estimator '{k}' is not compiled into this build"))),
        None if name == "auto" => Err(Error::Value(format!("estimator 'auto' (the pilot race) is the command line's; name one of {}", names()))),
        None => Err(Error::Value(format!("no estimator '{name}' (estimators: {})", names()))),
    }
}

/// An option refused by the core's table, named as Python spells it (`radius_footprints`)
/// before the core's message, which names it as the command line does.
fn option_error(name: &str, value: &str, e: OptionError) -> Error {
    let python = |n: &str| n.replace('-', "_");
    match e {
        OptionError::Unknown(_) => {
            let known: Vec<String> = options::all().iter().map(|o| python(o.name)).collect();
            Error::Value(format!("no estimator option '{}' (options: {})", python(name), known.join(", ")))
        }
        e => Error::Value(format!("{}={value}: {e}", python(name))),
    }
}

impl Render {
    /// Build the renderer `request` asks for on `scene` and run its setup.
    fn build(scene: &Scene, request: Request) -> Result<Self, Error> {
        let start = Instant::now();
        let kind = estimator(&request.estimator)?;
        let mut options = Options::new(kind);
        for (name, value) in &request.options {
            options.set(name, value).map_err(|e| option_error(name, value, e))?;
        }
        let asked = options.finish().map_err(|e| Error::Value(e.to_string()))?;
        let time = request.time.map(|t| setup::check_seconds(t, t)).transpose().map_err(|e| Error::Value(format!("time: {e}")))?;
        let prepared = match (request.width, request.height) {
            (None, None) => scene.prepared.clone(),
            (w, h) => Arc::new(scene.resized(w, h)?),
        };
        let max_depth = request.max_depth.or(prepared.max_depth).unwrap_or(-1);
        let threads = driver::capped_threads(request.threads);
        setup::check_config(&asked).map_err(Error::Value)?;
        let (config, plan) = if request.no_plan {
            (asked, Vec::new())
        } else {
            let plan = setup::plan_for(&prepared, asked, max_depth, request.seed, threads, ember_core::plan::pilot::DEFAULT_SAMPLES).map_err(Error::Runtime)?;
            (plan.planned, plan.describe())
        };
        setup::check_memory(&prepared, &config, None).map_err(Error::Memory)?;
        let mut renderer = setup::new_renderer(&prepared, config, max_depth, request.seed).map_err(Error::Value)?;
        let setup_start = Instant::now();
        let ctx = Context { scene: &prepared.scene, tracer: &prepared.accel };
        driver::run_setup(&mut renderer, &ctx, threads, None).map_err(|e| Error::Runtime(e.to_string()))?;
        setup::check_radius(&renderer, &prepared.scene).map_err(Error::Value)?;
        let camera = &prepared.scene.camera;
        let film = Film::with_filter(camera.width(), camera.height(), camera.filter());
        let pool = driver::thread_pool(threads, "ember-render").map_err(|e| Error::Runtime(e.to_string()))?;
        let deadline = time.and_then(|t| Duration::try_from_secs_f64(t).ok()).and_then(|d| start.checked_add(d));
        Ok(Self {
            limit: setup::pass_limit(request.spp, time, prepared.spp),
            prepared,
            renderer,
            film,
            pool,
            deadline,
            start,
            plan,
            setup_seconds: setup_start.elapsed().as_secs_f64(),
        })
    }

    /// Has the render all it asked for? (The first pass always runs, as the driver's.)
    fn finished(&self) -> bool {
        let passes = self.film.passes();
        passes >= self.limit || (passes > 0 && self.deadline.is_some_and(|d| Instant::now() >= d))
    }

    /// Render the next pass.
    fn pass(&mut self) -> Result<(), Error> {
        let ctx = Context { scene: &self.prepared.scene, tracer: &self.prepared.accel };
        let limits = Limits { spp: self.film.passes() + 1, first_pass: 0, deadline: None, interrupt: None };
        driver::render_on(&self.pool, &mut self.renderer, &ctx, &mut self.film, limits, None, self.start).map_err(|e| Error::Runtime(e.to_string()))?;
        Ok(())
    }
}

#[pymethods]
impl Render {
    /// Build the renderer (options checked, the plan, the setup phases), the GIL released.
    #[new]
    #[pyo3(signature = (scene, estimator, options, seed, threads, width, height, max_depth, no_plan, spp, time))]
    fn new(
        py: Python<'_>,
        scene: &Scene,
        estimator: String,
        options: Vec<(String, String)>,
        seed: u64,
        threads: Option<u32>,
        width: Option<u32>,
        height: Option<u32>,
        max_depth: Option<i32>,
        no_plan: bool,
        spp: Option<u32>,
        time: Option<f64>,
    ) -> PyResult<Self> {
        let request = Request { estimator, options, seed, threads, width, height, max_depth, no_plan, spp, time };
        Ok(py.detach(|| Self::build(scene, request))?)
    }

    /// Render one more pass, the GIL released; `False` (and nothing rendered) once the
    /// render has its passes or its time is up.
    fn step(&mut self, py: Python<'_>) -> PyResult<bool> {
        if self.finished() {
            return Ok(false);
        }
        py.detach(|| self.pass())?;
        Ok(true)
    }

    /// Has the render all it asked for?
    #[getter]
    fn done(&self) -> bool {
        self.finished()
    }
    /// Passes rendered (samples per pixel).
    #[getter]
    fn passes(&self) -> u32 {
        self.film.passes()
    }
    /// Seconds since the render was asked for (scene reading, plan and setup included).
    #[getter]
    fn elapsed(&self) -> f64 {
        self.start.elapsed().as_secs_f64()
    }
    /// Seconds the setup phases took (SPCBPT's training, LVCBPT's probe, radii).
    #[getter]
    fn setup_seconds(&self) -> f64 {
        self.setup_seconds
    }
    /// The estimator that renders (the plan may hand SPCBPT's work to another).
    #[getter]
    fn estimator(&self) -> &'static str {
        self.renderer.kind().name()
    }
    /// The scene plan's lines: what it kept and left out, and why.
    #[getter]
    fn plan(&self) -> Vec<String> {
        self.plan.clone()
    }
    #[getter]
    fn width(&self) -> u32 {
        self.film.width()
    }
    #[getter]
    fn height(&self) -> u32 {
        self.film.height()
    }
    /// Samples discarded as NaN, infinite or negative.
    #[getter]
    fn discarded(&self) -> u64 {
        self.film.discarded()
    }
    /// The mean image so far as float32 RGB bytes, rows top to bottom.
    fn image_bytes<'py>(&self, py: Python<'py>) -> Bound<'py, PyByteArray> {
        crate::pixel_bytes(py, &self.film.to_rgb_f32())
    }
}
