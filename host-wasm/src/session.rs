//! One module instance's side of the render protocol ([`ember_core::render`]).
//!
//! Every instance, the page's and each worker's, builds the same scene and the same
//! estimator and walks the same phases: the protocol's phase order is the core's, so
//! the browser has none of its own. Per phase:
//! 1. each instance takes the phase ([`Session::next_phase`]) and checks it is the one the
//!    page announced (an instance out of step is an error, never a wrong image);
//! 2. workers map chunks as the page hands them out ([`Session::map`]), each output as two
//!    byte parts ([`ember_core::render::wire`]): the film part goes to the page only, the
//!    state part to every instance;
//! 3. every instance receives the parts it needs for every chunk ([`Session::receive`])
//!    and reduces ([`Session::reduce`]), which refuses to run while a chunk is missing.
//!
//! The page's instance holds the image's film; a worker's film has no pixels (it never
//! receives film parts). Every instance keeps its own copy of the estimator's state
//! (light-vertex caches, SPCBPT's classifier, Γ and Q): reductions are deterministic
//! functions of the outputs, so the copies stay equal bit for bit.

use core::fmt::Write as _;

use ember_core::estimators::{ChunkOutput, PhaseBuffers};
use ember_core::estimators::{EstimatorKind, Renderer};
use ember_core::render::wire::Part;
use ember_core::render::{Context, Film, Phase, Phased};
use ember_core::scene::Scene;
use ember_core::transport::{Heuristic, MaxDepth, RenderParams};

use ember_host::accel::Accel;

/// Which instance: the page's holds the film.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Role {
    Worker,
    Page,
}

/// Why a call failed: a code for JavaScript and a message ([`Session::error`] keeps the
/// last one).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Failure {
    UnknownScene = 1,
    UnknownEstimator = 2,
    /// Width or height zero or above 4096.
    BadResolution = 3,
    /// The scene builder or the estimator's configuration refused.
    Setup = 4,
    /// No setup yet, or no phase taken.
    NotReady = 5,
    /// A chunk index outside the phase, or the phase is not the one announced.
    OutOfStep = 6,
    /// Bytes that do not decode as this chunk's part.
    BadBytes = 7,
    /// Reduce called before every chunk's parts arrived.
    Missing = 8,
}

/// A scene, its ray queries, the estimator, its film and the protocol's buffers.
#[derive(Debug)]
pub struct Session {
    pub scene: Scene,
    pub accel: Accel,
    pub renderer: Renderer,
    pub role: Role,
    pub film: Film,
    buffers: PhaseBuffers,
    phase: Option<Phase>,
    /// Per chunk of the current phase: film part received, state part received.
    received: Vec<(bool, bool)>,
    scratch: ChunkOutput,
    /// The last map's parts, encoded.
    pub film_bytes: Vec<u8>,
    pub state_bytes: Vec<u8>,
    /// Rays traced by the last map.
    pub last_rays: u64,
    /// Where JavaScript writes a part before [`Session::receive`].
    pub input: Vec<u8>,
    image: Vec<f32>,
}

impl Session {
    /// Build built-in scene `scene` for estimator `estimator` (an index into
    /// [`EstimatorKind::ALL`]) with its default configuration, as the CLI does.
    pub fn new(scene: u32, estimator: u32, width: u32, height: u32, max_depth: i32, seed: u64, role: Role) -> Result<Self, (Failure, String)> {
        let kind = EstimatorKind::from_index(estimator).ok_or((Failure::UnknownEstimator, format!("no estimator {estimator}")))?;
        if width == 0 || height == 0 || width > 4096 || height > 4096 {
            return Err((Failure::BadResolution, format!("{width}×{height}: each side must be 1 to 4096")));
        }
        let builder = crate::builtin_scene(scene, width, height).ok_or((Failure::UnknownScene, format!("no scene {scene}")))?;
        let (scene, geometry, _warnings) = builder.build().map_err(|e| (Failure::Setup, format!("the scene: {e}")))?;
        let accel = Accel::new(&geometry);
        // As the CLI: the power heuristic where an estimator has a choice.
        let params = RenderParams { max_depth: MaxDepth(max_depth), seed, heuristic: Heuristic::Power, ..RenderParams::default() };
        let renderer = Renderer::new(&scene, params, kind.default_config()).map_err(|e| (Failure::Setup, format!("{kind}: {e}")))?;
        let film = if role == Role::Page { Film::for_camera(&scene.camera) } else { Film::new(0, 0) };
        Ok(Self {
            scene,
            accel,
            renderer,
            role,
            film,
            buffers: PhaseBuffers::new(),
            phase: None,
            received: Vec::new(),
            scratch: ChunkOutput::default(),
            film_bytes: Vec::new(),
            state_bytes: Vec::new(),
            last_rays: 0,
            input: Vec::new(),
            image: Vec::new(),
        })
    }

    /// Queue pass `pass` (behind any pending setup phases).
    pub fn start_pass(&mut self, pass: u32) {
        Phased::<Accel>::start_pass(&mut self.renderer, pass);
    }

    /// Take the next phase as the current one, or `None` when nothing is pending.
    pub fn next_phase(&mut self) -> Option<Phase> {
        let phase = Phased::<Accel>::next_phase(&self.renderer)?;
        self.buffers.for_phase(&phase);
        self.received.clear();
        self.received.resize(phase.chunk_count(), (false, false));
        self.phase = Some(phase);
        Some(phase)
    }

    /// The current phase.
    pub fn phase(&self) -> Option<&Phase> {
        self.phase.as_ref()
    }

    /// Map chunk `chunk` of the current phase into [`Self::film_bytes`] and
    /// [`Self::state_bytes`].
    pub fn map(&mut self, chunk: u32) -> Result<(), (Failure, String)> {
        let phase = self.phase.ok_or((Failure::NotReady, "map before a phase was taken".into()))?;
        if chunk as usize >= phase.chunk_count() {
            return Err((Failure::OutOfStep, format!("chunk {chunk} of a phase of {} chunks", phase.chunk_count())));
        }
        self.scratch.reset(phase.chunk_range(chunk as usize));
        let ctx = Context { scene: &self.scene, tracer: &self.accel };
        self.renderer.map(&ctx, &phase, &mut self.scratch);
        self.last_rays = self.scratch.counters.rays;
        self.film_bytes.clear();
        self.scratch.encode(&phase, Part::Film, &mut self.film_bytes);
        self.state_bytes.clear();
        self.scratch.encode(&phase, Part::State, &mut self.state_bytes);
        Ok(())
    }

    /// Take the bytes in [`Self::input`] as part `part` of chunk `chunk`'s output.
    pub fn receive(&mut self, chunk: u32, part: Part) -> Result<(), (Failure, String)> {
        let phase = self.phase.ok_or((Failure::NotReady, "receive before a phase was taken".into()))?;
        let c = chunk as usize;
        if c >= phase.chunk_count() {
            return Err((Failure::OutOfStep, format!("chunk {chunk} of a phase of {} chunks", phase.chunk_count())));
        }
        let outputs = self.buffers.outputs(&phase);
        outputs[c]
            .decode(&phase, c, part, &self.input, &self.scene)
            .map_err(|e| (Failure::BadBytes, format!("chunk {chunk} of phase '{}': {e}", phase.name)))?;
        match part {
            Part::Film => self.received[c].0 = true,
            Part::State => self.received[c].1 = true,
        }
        Ok(())
    }

    /// Reduce the current phase once every chunk's parts arrived (film parts on the
    /// page only); returns true when that ended a pass.
    pub fn reduce(&mut self) -> Result<bool, (Failure, String)> {
        let phase = self.phase.ok_or((Failure::NotReady, "reduce before a phase was taken".into()))?;
        let page = self.role == Role::Page;
        if let Some(c) = self.received.iter().position(|&(film, state)| !state || (page && !film)) {
            let mut m = String::new();
            let _ = write!(m, "phase '{}' reduced without chunk {c} of {} (", phase.name, self.received.len());
            let (film, state) = self.received[c];
            let _ = write!(m, "film part {}, state part {})", if film { "in" } else { "missing" }, if state { "in" } else { "missing" });
            return Err((Failure::Missing, m));
        }
        let passes = self.film.passes();
        let ctx = Context { scene: &self.scene, tracer: &self.accel };
        let outputs = self.buffers.outputs(&phase);
        self.renderer.reduce(&ctx, &phase, outputs, &mut self.film);
        self.phase = None;
        Ok(self.film.passes() > passes)
    }

    /// The film's mean image, 3 × f32 per pixel, row 0 at the top.
    pub fn image(&mut self) -> &[f32] {
        self.image.clear();
        self.image.extend(self.film.to_rgb_f32().into_iter().flatten());
        &self.image
    }
}
