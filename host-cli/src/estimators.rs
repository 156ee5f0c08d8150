//! Scene loading and ray queries for the core's estimators: a [`PreparedScene`] and a
//! [`CoreRenderer`] (the core's [`Renderer`] bound to it, its setup run on threads).

use std::time::Instant;

use ember_core::integrator::{Heuristic, MaxDepth, RenderParams};
use ember_core::render::{Context, EstimatorConfig, EstimatorKind, Film, MemoryEstimate, Renderer};
use ember_core::scene::{BuildWarnings, Scene, SceneGeometry, builtin};
use std::path::Path;

use crate::accel::Accel;
use crate::app::{Built, builtin_resolution};
use crate::cli::{CacheArgs, EstimatorChoice, RenderArgs};
use crate::driver::{self, DriverConfig, DriverError, Limits, PhaseTimes, RenderSummary};
use crate::mitsuba;

/// A scene ready to render: what the estimators read and the ray queries.
#[derive(Debug)]
pub struct PreparedScene {
    pub name: String,
    pub scene: Scene,
    pub accel: Accel,
    /// The depth the scene file asks for (Mitsuba's `max_depth`), if any.
    pub max_depth: Option<i32>,
    /// The sample count the scene file asks for, if any.
    pub spp: Option<u32>,
    pub warnings: Vec<String>,
    /// The files the scene was read from: the scene file, its meshes, textures and
    /// environment maps (outputs never overwrite them); empty for a built-in scene.
    pub inputs: Vec<std::path::PathBuf>,
}

impl PreparedScene {
    /// FNV-1a of the built scene's full content: the camera, materials and lights (their
    /// `Debug` form: f32s print as their shortest round-trip decimal) and every triangle
    /// and sphere the queries see (raw bits). Equal for equal scenes however they were
    /// written, different when any value that reaches the renderer differs. Computed on
    /// demand (split renders and trained models check it), not for every render.
    pub fn hash(&self) -> u64 {
        scene_hasher(&self.scene, &self.accel).value()
    }
}

/// The hasher behind [`PreparedScene::hash`], fed with `scene` and `accel`'s geometry, for
/// hosts that add what else their renders read (the C API: its triangle numbering).
pub fn scene_hasher(scene: &Scene, accel: &Accel) -> ember_core::fnv::Fnv1a {
    let mut h = ember_core::fnv::Fnv1a::new();
    // Writing to the hasher cannot fail.
    let _ = std::fmt::Write::write_fmt(&mut h, format_args!("{scene:?}"));
    accel.hash_geometry(&mut h);
    h
}

/// Build the built-in scene `--builtin` names (the Cornell box by default) at the requested resolution.
pub fn prepare_builtin(args: &RenderArgs) -> Result<PreparedScene, String> {
    let (w, h) = builtin_resolution(args);
    let (name, builder) = match args.builtin.as_deref() {
        Some(ember_core::scene::builtin_glass::GLASS_SPHERES) => ("built-in glass-spheres", ember_core::scene::builtin_glass::glass_spheres(w, h)),
        _ => ("built-in Cornell box", builtin::cornell_box(w, h)),
    };
    let (scene, geometry, warnings) = builder.build().map_err(|e| format!("built-in scene: {e}"))?;
    Ok(finish(name.into(), scene, &geometry, warnings, None, None, Vec::new()))
}

/// Load a Mitsuba 3 XML scene; `width`/`height` override the file's film.
pub fn prepare_file(path: &Path, width: Option<u32>, height: Option<u32>, defaults: Vec<(String, String)>) -> Result<PreparedScene, String> {
    let loaded = mitsuba::load_scene(path, &mitsuba::LoadOptions { defaults, width, height }).map_err(|e| e.to_string())?;
    let (scene, geometry, warnings) = loaded.builder.build().map_err(|e| format!("{}: {e}", path.display()))?;
    let mut prepared = finish(path.display().to_string(), scene, &geometry, warnings, loaded.max_depth, loaded.spp, loaded.warnings);
    prepared.inputs = std::iter::once(path.to_path_buf()).chain(loaded.inputs).collect();
    Ok(prepared)
}

/// The scene a `render` command names (a file, or the built-in one).
pub fn prepare(args: &RenderArgs) -> Result<PreparedScene, String> {
    match &args.scene {
        Some(path) => prepare_file(path, args.width, args.height, args.defines.pairs.clone()),
        None if !args.defines.pairs.is_empty() => Err("-D sets parameters of a scene file; the built-in scenes have none (give a SCENE)".into()),
        None => prepare_builtin(args),
    }
}

/// [`prepare_file`] at the file's resolution, for commands that load the scene once per
/// run (convergence, suite); the scene's warnings (an unused `-D` among them) are printed
/// on the first load only.
pub fn preparer<'a>(path: &'a Path, defaults: &'a [(String, String)]) -> impl Fn() -> Result<PreparedScene, String> + 'a {
    let warned = std::sync::Once::new();
    move || {
        let prepared = prepare_file(path, None, None, defaults.to_vec())?;
        warned.call_once(|| prepared.warnings.iter().for_each(|w| eprintln!("warning: {}: {w}", path.display())));
        Ok(prepared)
    }
}

fn finish(
    name: String,
    scene: Scene,
    geometry: &SceneGeometry,
    warnings: BuildWarnings,
    max_depth: Option<i32>,
    spp: Option<u32>,
    mut notes: Vec<String>,
) -> PreparedScene {
    // Dropped triangles are reported by the scene reader, shape by shape with their
    // cause (the built-in scenes drop none); a count here repeated them.
    // Only what was really dropped (the core counts no light it keeps). A light of any
    // power, even one too bright for f32, is selectable, so there is no selection only
    // when no emitter is left.
    if warnings.dark_lights > 0 {
        notes.push(format!("{} lights emit nothing and were dropped (an emitting mesh counts once per triangle)", warnings.dark_lights));
    }
    if scene.light_selection.is_none() {
        notes.push("the scene has no light: the image will be black".into());
    }
    let accel = Accel::new(geometry);
    PreparedScene { name, scene, accel, max_depth, spp, warnings: notes, inputs: Vec::new() }
}

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
        // PT combines its two techniques with the power heuristic (as Mitsuba does);
        // BDPT's weights are the balance heuristic by construction.
        let params = RenderParams { max_depth: MaxDepth(max_depth), seed, heuristic: Heuristic::Power, ..RenderParams::default() };
        let renderer = Renderer::new(&prepared.scene, params, config).map_err(|e| format!("{} {e}", config.kind()))?;
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
        r.setup_times = driver::run_setup(&mut r.renderer, &ctx, threads).map_err(|e| e.to_string())?;
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
    pub fn camera_filter(&self) -> ember_core::filter::Filter {
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

    /// The kernel radius r₀ this renderer's setup chose, with the rule that chose it: the
    /// merging estimators (where the plan keeps merging), the path filters and segment
    /// kernels of the disk; `None` for the others.
    pub fn initial_radius(&self) -> Option<(f32, ember_core::merge::RadiusRule)> {
        match &self.renderer {
            Renderer::Merging(m) if m.config.merges(m.mode) => Some((m.r0, m.config.radius)),
            Renderer::Segment(s) => match s.kernel {
                ember_core::segment::Kernel::Disk { radius } => Some((radius, s.config.radius)),
                ember_core::segment::Kernel::Dirac => None,
            },
            Renderer::Filter(f) => Some((f.r0, f.config.radius)),
            Renderer::PhotonFilter(f) => Some((f.r0, f.config.radius)),
            Renderer::BidirectionalFilter(f) => Some((f.r0, f.config.radius)),
            _ => None,
        }
    }

    /// Refuse a kernel radius larger than the scene's bounding-box diagonal: every merge
    /// or filter kernel would then span the whole scene, and the image came out nearly
    /// black with exit 0 (`--radius 10` on the 2-unit Cornell box: 2 % of the right mean).
    pub fn check_radius(&self) -> Result<(), String> {
        use ember_core::merge::RadiusRule;
        let Some((r0, rule)) = self.initial_radius() else { return Ok(()) };
        let bounds = &self.prepared.scene.bounds;
        let diagonal = if bounds.is_empty() { 0.0 } else { (bounds.max - bounds.min).length() };
        if !(diagonal > 0.0) || r0 <= diagonal {
            return Ok(());
        }
        let option = match rule {
            RadiusRule::Footprints(k) => format!("--radius-footprints {k}"),
            RadiusRule::SceneFraction(f) => format!("--radius-scene {f}"),
            RadiusRule::Absolute(r) => format!("--radius {r}"),
        };
        Err(format!(
            "{option} gives {} a kernel radius r0 = {r0:.4e}, larger than the scene itself (its bounding box's diagonal is {diagonal:.4e}): every kernel would span the whole scene; lower it",
            self.renderer.kind().name()
        ))
    }

    /// The filtering estimators' report line: memory per pass and per pixel, reuse, depth
    /// and kernel.
    fn filter_report(&self, pass: &ember_core::segment::filter::FilterPass, segments: u32, r0: f32) -> Vec<String> {
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
        driver::render(&mut self.renderer, &ctx, film, limits, config, program_start)
    }
}

/// The renderer a `render` command asks for, with what its report needs.
pub fn make_built(args: &RenderArgs) -> Result<Built, String> {
    make_built_at(args, Instant::now())
}

/// [`make_built`] for a program that started at `start` (`--estimator auto` counts its
/// pilot race in the `--time` budget that runs from there).
pub fn make_built_at(args: &RenderArgs, start: Instant) -> Result<Built, String> {
    let (r, film) = renderer_and_head(args, start)?;
    Ok(Built { scene: r.prepared.name.clone(), max_depth: r.renderer.params().max_depth.0, file_spp: r.prepared.spp, renderer: Box::new(r), film })
}

/// What `config` would hold for `prepared`'s film: its estimate, with the bytes at least
/// the film's own.
pub fn memory_need(prepared: &PreparedScene, config: &EstimatorConfig) -> (u64, MemoryEstimate) {
    memory_need_for(&prepared.scene.camera, config)
}

/// [`memory_need`] for a film of `camera`'s size (hosts with scenes of their own: the C API).
pub fn memory_need_for(camera: &ember_core::camera::PerspectiveCamera, config: &EstimatorConfig) -> (u64, MemoryEstimate) {
    let pixels = camera.width() as u64 * camera.height() as u64;
    let estimate = config.memory_estimate(pixels.min(u32::MAX as u64) as u32);
    (estimate.bytes.max(pixels * ember_core::render::FILM_BYTES_PER_PIXEL), estimate)
}

/// The memory a run may claim, `limit` or else what the machine has available
/// ([`crate::memory`]), with how messages name it.
pub fn memory_budget(limit: Option<u64>) -> (Option<u64>, &'static str) {
    match limit {
        Some(l) => (Some(l), "--memory-limit"),
        None => (crate::memory::available_bytes(), "available memory"),
    }
}

/// Bytes the loaded geometry holds per triangle: the scene's triangle records, the
/// accelerator's leaf-ordered copies and attributes and its BVH (measured on a
/// 2 M-triangle mesh: about 435 bytes each).
pub const GEOMETRY_BYTES_PER_TRIANGLE: u64 = 435;

/// What the loaded scene's geometry holds, by [`GEOMETRY_BYTES_PER_TRIANGLE`].
pub fn geometry_bytes(prepared: &PreparedScene) -> u64 {
    (prepared.accel.triangle_count() as u64 + prepared.accel.sphere_count() as u64) * GEOMETRY_BYTES_PER_TRIANGLE
}

/// Refuse, before anything large is allocated, a render whose estimated memory exceeds
/// `limit` or, without one, the memory available. Under `--memory-limit` (a budget for the
/// whole process) the loaded geometry counts too; measured against the memory available
/// it does not, since it is already allocated and so already missing from that figure.
pub fn check_memory(prepared: &PreparedScene, config: &EstimatorConfig, limit: Option<u64>) -> Result<(), String> {
    let camera = &prepared.scene.camera;
    let (bytes, estimate) = memory_need(prepared, config);
    let geometry = if limit.is_some() { geometry_bytes(prepared) } else { 0 };
    match memory_budget(limit) {
        (Some(a), source) if bytes.saturating_add(geometry) > a => {
            let (largest, lower) = if geometry > bytes {
                (format!("the scene's geometry, {} triangles,", prepared.accel.triangle_count()), "the scene's triangle count")
            } else {
                (format!("{} at {}×{}", estimate.largest, camera.width(), camera.height()), estimate.lower)
            };
            Err(format!(
                "{} would need about {} ({largest} is the largest part{}), more than the {} of {source}; lower {lower} or raise --memory-limit",
                config.kind(),
                crate::memory::human(bytes.saturating_add(geometry)),
                if geometry > 0 { format!("; the geometry holds {}", crate::memory::human(geometry)) } else { String::new() },
                crate::memory::human(a),
            ))
        }
        _ => Ok(()),
    }
}

/// The renderer a `render` command asks for, its setup run and reported on stderr.
pub fn make_core_renderer(args: &RenderArgs) -> Result<CoreRenderer, String> {
    make_core_renderer_at(args, Instant::now())
}

/// [`make_core_renderer`] for a program that started at `start`.
pub fn make_core_renderer_at(args: &RenderArgs, start: Instant) -> Result<CoreRenderer, String> {
    renderer_and_head(args, start).map(|(r, _)| r)
}

/// [`make_core_renderer_at`], with the passes `--estimator auto`'s race already rendered
/// at full size with the renderer's own configuration and seed, for the render to
/// continue ([`crate::auto::Head`]).
fn renderer_and_head(args: &RenderArgs, start: Instant) -> Result<(CoreRenderer, Option<Film>), String> {
    let mut prepared = prepare(args)?;
    let mut head = None;
    for w in &prepared.warnings {
        eprintln!("warning: {w}");
    }
    let max_depth = args.max_depth.or(prepared.max_depth).unwrap_or(-1);
    let kind = match args.estimator {
        EstimatorChoice::Fixed(kind) => kind,
        EstimatorChoice::Auto => {
            let load = |w: u32, h: u32| {
                let mut low = args.clone();
                (low.width, low.height) = (Some(w), Some(h));
                prepare(&low)
            };
            let (choice, back) = crate::auto::choose(args, prepared, max_depth, start, &load)?;
            prepared = back;
            for line in choice.describe() {
                eprintln!("{line}");
            }
            head = choice.head;
            choice.kind
        }
    };
    let asked = args.cache.config_for(kind);
    // Options are checked before anything is estimated from them (an out-of-range
    // --subspaces was reported as too much memory rather than as out of range).
    asked.validate().map_err(|e| format!("{} {e}", asked.kind()))?;
    // The plan is a pure function of the scene, the options and the seed, so `ember
    // train` and the renders that load its model plan alike.
    let config = if args.no_plan {
        asked
    } else {
        let plan = crate::plan::plan_for(&prepared, asked, max_depth, args.seed, args.thread_count(), ember_core::plan::pilot::DEFAULT_SAMPLES)?;
        for line in plan.describe() {
            eprintln!("plan       {line}");
        }
        plan.planned
    };
    check_memory(&prepared, &config, args.memory_limit)?;
    let r = CoreRenderer::with_model(prepared, config, max_depth, args.seed, args.thread_count(), args.model.as_deref())?;
    if let Renderer::Lvcbpt(l) = &r.renderer {
        eprintln!(
            "lvcbpt     M = {} light paths/pass, N = {}, counts: light tracing {:.4}, connection {:.4}",
            l.light_paths, l.config.connections, l.counts.light_tracing, l.counts.connection
        );
    }
    if let Some(model) = &args.model {
        eprintln!("{:<10} model loaded from {} (its preprocessing skipped)", r.kind().name(), model.display());
    }
    if let Renderer::Spcbpt(s) = &r.renderer {
        let rep = &s.report;
        if let Some(why) = rep.unbinned_because {
            eprintln!("spcbpt     light sources not binned ({why}): s = 1 is next-event estimation");
        }
        let phases = r.setup_times.iter().map(|(n, t)| format!("{n} {t:.2} s")).collect::<Vec<_>>().join(", ");
        eprintln!(
            "spcbpt     preprocessing {:.2} s ({phases}); {} eye × {} light subspaces ({} of them light-source bins{})",
            r.setup_seconds,
            rep.n_eye,
            rep.n_light,
            rep.light_source_bins,
            if rep.light_source_bins > 0 { ", s = 1 through the cache" } else { ", s = 1 by NEE" }
        );
        eprintln!("spcbpt     training: {} Adam steps in batches of {}; losses per epoch {:?}", rep.steps, rep.batch, rep.losses);
        eprintln!(
            "spcbpt     memory: D {:.1} MiB ({} paths, freed after training), trees {:.1} KiB, Γ {:.1} KiB",
            rep.dataset_bytes as f64 / 1048576.0,
            rep.dataset_paths,
            rep.tree_bytes as f64 / 1024.0,
            rep.gamma_bytes as f64 / 1024.0
        );
    }
    // The race's passes continue only where they are this render's own: the same
    // configuration after the plan (and the same seed, scene and depth by construction).
    let head = head.filter(|h| h.config == r.config).map(|h| h.film);
    Ok((r, head))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The notes `prepare_file` prints for a scene holding `emitters` (and one rectangle).
    fn notes(emitters: &str) -> Vec<String> {
        let xml = format!(
            r#"<scene version="3.0.0">
                <sensor type="perspective"><float name="fov" value="40"/>
                    <transform name="to_world"><lookat origin="0,0,5" target="0,0,0" up="0,1,0"/></transform>
                    <film type="hdrfilm"><integer name="width" value="4"/><integer name="height" value="4"/><rfilter type="box"/></film>
                </sensor>
                <shape type="rectangle"/>
                {emitters}
            </scene>"#
        );
        let loaded = mitsuba::load_scene_from_str(&xml, Path::new("notes.xml"), &mitsuba::LoadOptions::default()).unwrap();
        let (scene, geometry, warnings) = loaded.builder.build().unwrap();
        finish("notes.xml".into(), scene, &geometry, warnings, None, None, loaded.warnings).warnings
    }

    /// Dropped triangles are reported once, by the reader, with their cause (issue 51: a
    /// rectangle scaled by 1e38 was "zero area", and a second count followed the reader's
    /// line). Injected bug checked: the old count in `finish` makes each case two notes.
    #[test]
    fn dropped_triangles_are_reported_once_with_their_cause() {
        let lit = |shape: &str| notes(&format!(r#"<emitter type="constant"/>{shape}"#));
        let huge = lit(r#"<shape type="rectangle"><transform name="to_world"><scale value="1e38"/></transform></shape>"#);
        assert!(huge.len() == 1 && huge[0].contains("too large for single precision"), "{huge:?}");
        let flat = lit(r#"<shape type="rectangle"><transform name="to_world"><scale x="0" y="1" z="1"/></transform></shape>"#);
        assert!(flat.len() == 1 && flat[0].contains("2 of 2 triangles have zero area"), "{flat:?}");
    }

    /// Regression: every `constant` and `directional` emitter was reported as "emits
    /// nothing and was dropped" though it was kept and lit the scene. Injected bug checked:
    /// counting `light.power() <= 0` in `SceneBuilder::add_light` again fails here.
    #[test]
    fn lights_at_infinity_give_no_note() {
        for emitter in [r#"<emitter type="constant"/>"#, r#"<emitter type="directional"><vector name="direction" value="0,0,-1"/></emitter>"#] {
            assert_eq!(notes(emitter), Vec::<String>::new(), "{emitter}");
        }
    }

    /// Regression: a light whose power overflows f32 was left out of the light selection
    /// and the scene reported as having no light. Injected bug checked: removing the
    /// saturation in `Light::power` fails here.
    #[test]
    fn a_very_bright_light_is_a_light() {
        assert_eq!(
            notes(r#"<emitter type="point"><point name="position" value="0,0,1"/><rgb name="intensity" value="1e38"/></emitter>"#),
            Vec::<String>::new()
        );
    }

    /// Dark lights are counted as dropped, and a scene left with none is said to be unlit.
    #[test]
    fn dark_lights_are_reported_dropped_and_the_scene_unlit() {
        let n = notes(r#"<emitter type="point"><point name="position" value="0,0,1"/><rgb name="intensity" value="0"/></emitter>"#);
        assert!(n[0].starts_with("1 lights emit nothing and were dropped"), "{n:?}");
        assert!(n[1].contains("has no light"), "{n:?}");
        assert_eq!(n.len(), 2, "{n:?}");
        let none = notes("");
        assert_eq!(none.len(), 1, "{none:?}");
        assert!(none[0].contains("has no light"), "{none:?}");
    }
}
