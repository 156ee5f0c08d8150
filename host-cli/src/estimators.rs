//! The core's estimators on the command line's scenes: a [`CoreRenderer`] (the core's
//! [`Renderer`] bound to a [`PreparedScene`], its setup run on threads, reports for the
//! closing summary) and the [`Render`] interface the `render` command drives.

use std::fmt;
use std::path::Path;
use std::time::Instant;

use ember_core::estimators::{EstimatorConfig, EstimatorKind, Renderer};
use ember_core::render::{Context, Film};
use ember_host::driver::{self, DriverError, Limits, PhaseTimes, RenderSummary};
use ember_host::scene::PreparedScene;

use crate::cli::CacheArgs;
use crate::progress::{DriverConfig, SetupSpinner};

/// One of the core's estimators bound to a prepared scene, its setup (SPCBPT's and
/// LVCBPT's preprocessing) already run.
#[derive(Debug)]
pub struct CoreRenderer {
    pub prepared: PreparedScene,
    pub renderer: Renderer,
    /// The configuration it was built with.
    pub config: EstimatorConfig,
    /// Seconds per setup phase.
    pub setup_times: PhaseTimes,
    /// Seconds the whole setup took.
    pub setup_seconds: f64,
}

impl CoreRenderer {
    /// `estimator` with its default configuration; setup on rayon's current pool size.
    pub fn new(prepared: PreparedScene, estimator: EstimatorKind, max_depth: i32, seed: u64) -> Result<Self, String> {
        Self::with_config(prepared, estimator.default_config(), max_depth, seed, rayon::current_num_threads())
    }

    /// [`Self::new`] with the cache-based estimators' options from the command line.
    pub fn with_options(prepared: PreparedScene, estimator: EstimatorKind, max_depth: i32, seed: u64, cache: &CacheArgs) -> Result<Self, String> {
        Self::with_config(prepared, cache.config_for(estimator), max_depth, seed, rayon::current_num_threads())
    }

    /// The estimator `config` names; its setup phases run here on `threads` threads, so a
    /// clock started before counts them.
    pub fn with_config(prepared: PreparedScene, config: EstimatorConfig, max_depth: i32, seed: u64, threads: usize) -> Result<Self, String> {
        Self::with_model(prepared, config, max_depth, seed, threads, None)
    }

    /// [`Self::with_config`], with the setup's result loaded from `model` (a file of
    /// `ember train`, checked against this render) instead of computed.
    pub fn with_model(
        prepared: PreparedScene,
        config: EstimatorConfig,
        max_depth: i32,
        seed: u64,
        threads: usize,
        model: Option<&Path>,
    ) -> Result<Self, String> {
        let renderer = ember_host::setup::new_renderer(&prepared, config, max_depth, seed)?;
        let mut r = Self { prepared, renderer, config, setup_times: PhaseTimes::new(), setup_seconds: 0.0 };
        if let Some(path) = model {
            let camera = &r.prepared.scene.camera;
            let loaded = crate::trained::load(path, &r.identity(), camera.width(), camera.height(), &r.prepared.scene)?;
            let Renderer::Spcbpt(s) = &mut r.renderer else {
                return Err(format!(
                    "--model: {} has no trained state to load (only spcbpt; where the scene plan renders another estimator, --no-plan keeps spcbpt)",
                    config.kind()
                ));
            };
            s.use_model(loaded).map_err(|e| format!("--model {}: {e}", path.display()))?;
        }
        let start = Instant::now();
        let ctx = Context { scene: &r.prepared.scene, tracer: &r.prepared.accel };
        r.setup_times = driver::run_setup(&mut r.renderer, &ctx, threads, Some(&SetupSpinner::new())).map_err(|e| e.to_string())?;
        r.setup_seconds = start.elapsed().as_secs_f64();
        r.check_radius()?;
        Ok(r)
    }

    pub fn kind(&self) -> EstimatorKind {
        self.renderer.kind()
    }

    pub fn width(&self) -> u32 {
        self.prepared.scene.camera.width()
    }

    pub fn height(&self) -> u32 {
        self.prepared.scene.camera.height()
    }

    /// The camera's pixel filter (the film's).
    pub fn camera_filter(&self) -> ember_core::pixel_filter::Filter {
        self.prepared.scene.camera.filter()
    }

    /// What the estimator holds per pass, for the closing report.
    pub fn memory_report(&self) -> Vec<String> {
        let mib = |b: usize| b as f64 / 1_048_576.0;
        match &self.renderer {
            Renderer::Lvcbpt(l) => vec![format!(
                "lvcbpt     memory per pass: light paths {:.1} MiB, cache {:.1} MiB ({} vertices)",
                mib(l.paths.size_bytes()),
                mib(l.size_bytes() - l.paths.size_bytes()),
                l.cache.len()
            )],
            Renderer::Spcbpt(s) => {
                let cache = &s.cache;
                let (total, paths, retained) = (cache.size_bytes(), cache.paths.size_bytes(), cache.retained.size_bytes());
                let kept: usize = cache.retained.fifos.iter().map(|f| f.len()).sum();
                let n_light = s.model.as_ref().map_or(0, |m| m.classifier.n_light);
                vec![format!(
                    "spcbpt     memory per pass: light paths {:.1} MiB, buckets + stage tables {:.1} MiB, reuse FIFOs {:.1} MiB ({kept} vertices, at most M0 = {} × {n_light} subspaces)",
                    mib(paths),
                    mib(total - paths - retained),
                    mib(retained),
                    cache.retained.capacity
                )]
            }
            Renderer::Merging(m) if !m.config.merges(m.mode) => {
                vec![format!(
                    "{:<10} memory per pass: light paths {:.1} MiB; merging left out (no photons or grid)",
                    self.renderer.kind().name(),
                    mib(m.size_bytes())
                )]
            }
            Renderer::Merging(m) => {
                let paths = m.paths.size_bytes() + m.prefix.capacity() * 8;
                vec![format!(
                    "{:<10} memory per pass: light paths {:.1} MiB, photons + grid {:.1} MiB ({} photons); radius r0 = {:.4e}, last pass {:.4e}",
                    self.renderer.kind().name(),
                    mib(paths),
                    mib(m.size_bytes() - paths),
                    m.photons.len(),
                    m.r0,
                    m.grid.radius()
                )]
            }
            Renderer::Segment(s) => match s.kernel {
                ember_core::segment::Kernel::Disk { radius } => vec![format!("{:<10} kernel: disk of radius {radius:.4e}", self.renderer.kind().name())],
                ember_core::segment::Kernel::Dirac => vec![format!("{:<10} kernel: dirac", self.renderer.kind().name())],
            },
            Renderer::Filter(f) => self.filter_report(&f.pass, f.segments, f.r0),
            Renderer::PhotonFilter(f) => self.filter_report(&f.pass, f.segments, f.r0),
            Renderer::BidirectionalFilter(f) => self.filter_report(&f.pass, f.segments, f.r0),
            Renderer::OnePhase(_) => Vec::new(),
        }
    }

    /// The kernel radius r₀ this renderer's setup chose ([`ember_host::setup::initial_radius`]).
    pub fn initial_radius(&self) -> Option<(f32, ember_core::merge::RadiusRule)> {
        ember_host::setup::initial_radius(&self.renderer)
    }

    /// Refuse a kernel radius larger than the scene ([`ember_host::setup::check_radius`]).
    pub fn check_radius(&self) -> Result<(), String> {
        ember_host::setup::check_radius(&self.renderer, &self.prepared.scene)
    }

    /// The filtering estimators' report line: memory per pass and per pixel, reuse, depth
    /// and kernel.
    fn filter_report(&self, pass: &ember_core::estimators::filter::FilterPass, segments: u32, r0: f32) -> Vec<String> {
        let camera = &self.prepared.scene.camera;
        let pixels = (camera.width() as f64 * camera.height() as f64).max(1.0);
        vec![format!(
            "{:<10} memory per pass: {:.1} MiB ({} nodes, {} reused segments, {:.0} B per pixel); {segments} segments per path; radius r0 = {r0:.4e}, last pass {:.4e}",
            self.renderer.kind().name(),
            pass.size_bytes() as f64 / 1_048_576.0,
            pass.nodes.len(),
            pass.graph.targets.len(),
            pass.size_bytes() as f64 / pixels,
            pass.r
        )]
    }

    /// What a partial image of this render records about it.
    pub fn identity(&self) -> crate::distributed::RenderIdentity {
        let params = self.renderer.params();
        crate::distributed::RenderIdentity {
            scene: self.prepared.name.clone(),
            scene_hash: self.prepared.hash(),
            estimator: self.kind().name().to_string(),
            config: format!("{:?}; max depth {}, heuristic {:?}, rr depth {}", self.config, params.max_depth.0, params.heuristic, params.rr_depth),
            seed: params.seed,
        }
    }

    /// Render passes into `film` (see [`driver::render`]).
    pub fn render(&mut self, film: &mut Film, limits: Limits, config: DriverConfig, program_start: Instant) -> Result<RenderSummary, DriverError> {
        let ctx = Context { scene: &self.prepared.scene, tracer: &self.prepared.accel };
        config.render(&mut self.renderer, &ctx, film, limits, program_start)
    }
}

/// Something that renders passes into a film: the core's estimators
/// ([`CoreRenderer`]) or a test's stand-in.
pub trait Render {
    /// The image size.
    fn size(&self) -> (u32, u32);
    /// The camera's pixel filter, which the film spreads splats with (box by default).
    fn filter(&self) -> ember_core::pixel_filter::Filter {
        ember_core::pixel_filter::Filter::Box
    }
    /// Render passes into `film` until `limits` say stop.
    fn render(&mut self, film: &mut Film, limits: Limits, config: DriverConfig, program_start: Instant) -> Result<RenderSummary, DriverError>;
    /// Lines about the renderer's memory, printed after rendering.
    fn memory_report(&self) -> Vec<String> {
        Vec::new()
    }
    /// The estimator that renders, where it is one of the core's (`auto` names its choice).
    fn estimator_name(&self) -> Option<&'static str> {
        None
    }
    /// The files the scene was read from (outputs must not overwrite them).
    fn inputs(&self) -> Vec<std::path::PathBuf> {
        Vec::new()
    }
    /// What a partial image records about the render (`None`: cannot be split).
    fn identity(&self) -> Option<crate::distributed::RenderIdentity> {
        None
    }
    /// The denoiser guides (albedo, normal) per pixel, `samples` rays each
    /// (`ember_core::render::aov`); `None` where the renderer has no scene to trace.
    fn guides(&self, _samples: u32, _seed: u64, _threads: usize) -> Option<Guides> {
        None
    }
}

impl Render for CoreRenderer {
    fn estimator_name(&self) -> Option<&'static str> {
        Some(self.kind().name())
    }
    fn size(&self) -> (u32, u32) {
        (self.width(), self.height())
    }
    fn filter(&self) -> ember_core::pixel_filter::Filter {
        self.camera_filter()
    }
    fn render(&mut self, film: &mut Film, limits: Limits, config: DriverConfig, program_start: Instant) -> Result<RenderSummary, DriverError> {
        CoreRenderer::render(self, film, limits, config, program_start)
    }
    fn memory_report(&self) -> Vec<String> {
        CoreRenderer::memory_report(self)
    }
    fn inputs(&self) -> Vec<std::path::PathBuf> {
        self.prepared.inputs.clone()
    }
    fn identity(&self) -> Option<crate::distributed::RenderIdentity> {
        Some(CoreRenderer::identity(self))
    }
    fn guides(&self, samples: u32, seed: u64, threads: usize) -> Option<Guides> {
        Some(guides(&self.prepared, samples, seed, threads))
    }
}

/// The denoiser guides of an image: per pixel the albedo and the normal.
pub type Guides = (Vec<[f32; 3]>, Vec<[f32; 3]>);

/// Rays per pixel of the denoiser guides.
pub const GUIDE_SAMPLES: u32 = 16;

/// The denoiser guides of `prepared`'s image, rows in parallel on `threads` threads (the
/// values do not depend on the thread count: each pixel has its own random stream).
pub fn guides(prepared: &PreparedScene, samples: u32, seed: u64, threads: usize) -> Guides {
    use rayon::prelude::*;
    let camera = &prepared.scene.camera;
    let (w, h) = (camera.width() as usize, camera.height() as usize);
    let mut albedo = vec![ember_core::spectrum::Rgb::ZERO; w * h];
    let mut normal = vec![ember_core::math::Vec3::ZERO; w * h];
    let mut work = || {
        albedo.par_chunks_mut(w.max(1)).zip(normal.par_chunks_mut(w.max(1))).enumerate().for_each(|(y, (a, n))| {
            let start = (y * w) as u32;
            ember_core::render::aov::render_guides(&prepared.scene, &prepared.accel, seed, samples, start..start + w as u32, a, n);
        })
    };
    match rayon::ThreadPoolBuilder::new().num_threads(threads.max(1)).build() {
        Ok(pool) => pool.install(work),
        Err(_) => work(),
    }
    (albedo.iter().map(|c| [c.r, c.g, c.b]).collect(), normal.iter().map(|v| v.to_array()).collect())
}

/// What `render` needs from the estimator wiring: the renderer and what to report.
pub struct Built {
    pub renderer: Box<dyn Render>,
    /// The scene's name (its file, or "built-in Cornell box").
    pub scene: String,
    pub max_depth: i32,
    /// The instruction set the ray queries run with (`--simd`, `EMBER_SIMD`).
    pub simd: ember_host::accel::Isa,
    /// The level the lane kernels run with (the same option, else the widest set).
    pub shading: ember_core::math::simd::Level,
    /// The scene file's sample count, used when neither --spp nor --time is given.
    pub file_spp: Option<u32>,
    /// Passes already rendered with this renderer's configuration and seed, which the
    /// render continues (`--estimator auto`'s race, when PT wins).
    pub film: Option<Film>,
}

impl fmt::Debug for Built {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Built").field("scene", &self.scene).field("max_depth", &self.max_depth).field("file_spp", &self.file_spp).finish_non_exhaustive()
    }
}
