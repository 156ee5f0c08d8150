//! The core's estimators as [`PassRenderer`]s: scene loading, ray queries and the
//! per-pass calls into `ember_core::integrator`.

use std::ops::Range;

use ember_core::integrator::{Counters, Heuristic, MaxDepth, RenderParams, bdpt, lt, pt};
use ember_core::scene::{BuildWarnings, Scene, SceneGeometry, builtin};
use std::path::Path;
use ember_core::Rgb;

use crate::accel::Accel;
use crate::app::{Built, builtin_resolution};
use crate::cached::{LvcbptHost, SpcbptHost};
use crate::cli::{CacheArgs, EstimatorArg, RenderArgs};
use crate::driver::{PassRenderer, PassStats, Splat};
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
}

/// Build the built-in scene `--builtin` names (the Cornell box by default) at the requested resolution.
pub fn prepare_builtin(args: &RenderArgs) -> Result<PreparedScene, String> {
    let (w, h) = builtin_resolution(args);
    let (name, builder) = match args.builtin.as_deref() {
        Some(ember_core::scene::builtin_glass::GLASS_SPHERES) => {
            ("built-in glass-spheres", ember_core::scene::builtin_glass::glass_spheres(w, h))
        }
        _ => ("built-in Cornell box", builtin::cornell_box(w, h)),
    };
    let (scene, geometry, warnings) = builder.build().map_err(|e| format!("built-in scene: {e}"))?;
    Ok(finish(name.into(), scene, &geometry, warnings, None, None, Vec::new()))
}

/// Load a Mitsuba 3 XML scene; `width`/`height` override the file's film.
pub fn prepare_file(path: &Path, width: Option<u32>, height: Option<u32>, defaults: Vec<(String, String)>) -> Result<PreparedScene, String> {
    let loaded = mitsuba::load_scene(path, &mitsuba::LoadOptions { defaults, width, height }).map_err(|e| e.to_string())?;
    let (scene, geometry, warnings) = loaded.builder.build().map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(finish(path.display().to_string(), scene, &geometry, warnings, loaded.max_depth, loaded.spp, loaded.warnings))
}

/// The scene a `render` command names (a file, or the built-in one).
pub fn prepare(args: &RenderArgs) -> Result<PreparedScene, String> {
    match &args.scene {
        Some(path) => prepare_file(path, args.width, args.height, Vec::new()),
        None => prepare_builtin(args),
    }
}

fn finish(name: String, scene: Scene, geometry: &SceneGeometry, warnings: BuildWarnings, max_depth: Option<i32>, spp: Option<u32>, mut notes: Vec<String>) -> PreparedScene {
    if warnings.degenerate_triangles > 0 {
        notes.push(format!("{} degenerate (zero-area) triangles dropped", warnings.degenerate_triangles));
    }
    if warnings.dark_lights > 0 {
        notes.push(format!("{} lights emit nothing and were dropped", warnings.dark_lights));
    }
    if scene.light_selection.is_none() {
        notes.push("the scene has no light: the image will be black".into());
    }
    let accel = Accel::new(geometry);
    PreparedScene { name, scene, accel, max_depth, spp, warnings: notes }
}

/// One of the core's estimators bound to a prepared scene.
#[derive(Debug)]
pub struct CoreRenderer {
    pub prepared: PreparedScene,
    pub estimator: EstimatorArg,
    pub params: RenderParams,
    /// LVCBPT's per-pass state (built in `new`).
    pub lvcbpt: Option<LvcbptHost>,
    /// SPCBPT's model and per-pass state (preprocessing runs in `new`).
    pub spcbpt: Option<SpcbptHost>,
}

impl CoreRenderer {
    pub fn new(prepared: PreparedScene, estimator: EstimatorArg, max_depth: i32, seed: u64) -> Self {
        Self::with_options(prepared, estimator, max_depth, seed, &CacheArgs::default())
    }

    /// [`Self::new`] with the cache-based estimators' options; their preprocessing runs
    /// here (on the global rayon pool), so a clock started before counts it.
    pub fn with_options(prepared: PreparedScene, estimator: EstimatorArg, max_depth: i32, seed: u64, cache: &CacheArgs) -> Self {
        // PT combines its two techniques with the power heuristic (as Mitsuba does);
        // BDPT's weights are the balance heuristic by construction.
        let params = RenderParams { max_depth: MaxDepth(max_depth), seed, heuristic: Heuristic::Power, ..RenderParams::default() };
        let lvcbpt = match estimator {
            EstimatorArg::Lvcbpt => Some(LvcbptHost::new(&prepared.scene, &prepared.accel, &params, cache)),
            _ => None,
        };
        let spcbpt = match estimator {
            EstimatorArg::Spcbpt => Some(SpcbptHost::new(&prepared.scene, &prepared.accel, &params, cache)),
            _ => None,
        };
        Self { prepared, estimator, params, lvcbpt, spcbpt }
    }
    fn pixels(&self) -> u32 {
        self.width() * self.height()
    }
}

fn stats(c: Counters, samples: usize) -> PassStats {
    PassStats { rays: c.rays, samples: samples as u64 }
}

impl PassRenderer for CoreRenderer {
    fn width(&self) -> u32 {
        self.prepared.scene.camera.width()
    }
    fn height(&self) -> u32 {
        self.prepared.scene.camera.height()
    }
    fn camera_pass(&self, pass: u32, pixels: Range<u32>, out: &mut [Rgb], splat: &mut dyn FnMut(Splat)) -> PassStats {
        let (scene, accel) = (&self.prepared.scene, &self.prepared.accel);
        let n = pixels.len();
        match self.estimator {
            EstimatorArg::Pt => stats(pt::render_pixels(scene, accel, &self.params, pass, pixels, out), n),
            EstimatorArg::Bdpt => stats(bdpt::render_pixels(scene, accel, &self.params, pass, pixels, out, splat), n),
            EstimatorArg::Lvcbpt | EstimatorArg::Spcbpt => match (&self.lvcbpt, &self.spcbpt) {
                (Some(l), _) => l.camera_pass(scene, accel, &self.params, pass, pixels, out),
                (_, Some(s)) => s.camera_pass(scene, accel, &self.params, pass, pixels, out),
                _ => {
                    out.fill(Rgb::ZERO);
                    PassStats::default()
                }
            },
            // Light tracing has no camera-side work: its image is all splats.
            EstimatorArg::Lt => {
                out.fill(Rgb::ZERO);
                PassStats::default()
            }
        }
    }
    fn light_paths_per_pass(&self) -> u32 {
        match self.estimator {
            EstimatorArg::Lt => self.pixels(),
            _ => 0,
        }
    }
    fn light_pass(&self, pass: u32, paths: Range<u32>, splat: &mut dyn FnMut(Splat)) -> PassStats {
        match self.estimator {
            EstimatorArg::Lt => {
                let n = paths.len();
                stats(lt::trace_paths(&self.prepared.scene, &self.prepared.accel, &self.params, pass, paths, splat), n)
            }
            _ => PassStats::default(),
        }
    }
    fn prepare_pass(&self, pass: u32, splat: &mut dyn FnMut(Splat)) -> PassStats {
        let (scene, accel) = (&self.prepared.scene, &self.prepared.accel);
        match (&self.lvcbpt, &self.spcbpt) {
            (Some(l), _) => l.prepare_pass(scene, accel, &self.params, pass, splat),
            (_, Some(s)) => s.prepare_pass(scene, accel, &self.params, pass, splat),
            _ => PassStats::default(),
        }
    }
    fn splat_scale(&self) -> f64 {
        if let Some(l) = &self.lvcbpt {
            // LVCBPT's splats come from its M light paths.
            return 1.0 / l.light_paths.max(1) as f64;
        }
        if let Some(s) = &self.spcbpt {
            return 1.0 / s.light_paths.max(1) as f64;
        }
        // LT traces W·H light paths per pass; BDPT traces one per pixel sample.
        1.0 / self.pixels() as f64
    }
}

/// The renderer a `render` command asks for, with what its report needs.
pub fn make_built(args: &RenderArgs) -> Result<Built, String> {
    let r = make_core_renderer(args)?;
    Ok(Built { scene: r.prepared.name.clone(), max_depth: r.params.max_depth.0, file_spp: r.prepared.spp, renderer: Box::new(r) })
}

/// Run `f` (a renderer's construction: SPCBPT's and LVCBPT's preprocessing is
/// parallel) on `threads` rayon threads, so `--threads` bounds preprocessing as it
/// bounds rendering; on rayon's global pool if that pool cannot be built.
pub fn on_threads<T: Send>(threads: usize, f: impl FnOnce() -> T + Send) -> T {
    match rayon::ThreadPoolBuilder::new().num_threads(threads.max(1)).thread_name(|i| format!("ember-prepare-{i}")).build() {
        Ok(pool) => pool.install(f),
        Err(_) => f(),
    }
}

/// The renderer alone (benchmarks and tools that print nothing about the scene).
pub fn make_renderer(args: &RenderArgs) -> Result<Box<dyn PassRenderer>, String> {
    Ok(Box::new(make_core_renderer(args)?))
}

/// [`make_renderer`] with the concrete type (the scene's name and settings stay readable).
pub fn make_core_renderer(args: &RenderArgs) -> Result<CoreRenderer, String> {
    let prepared = prepare(args)?;
    for w in &prepared.warnings {
        eprintln!("warning: {w}");
    }
    let max_depth = args.max_depth.or(prepared.max_depth).unwrap_or(-1);
    let r = on_threads(args.thread_count(), || CoreRenderer::with_options(prepared, args.estimator, max_depth, args.seed, &args.cache));
    if let Some(l) = &r.lvcbpt {
        eprintln!("lvcbpt     M = {} light paths/pass, N = {}, counts: light tracing {:.4}, connection {:.4}", l.light_paths, l.connections, l.counts.light_tracing, l.counts.connection);
    }
    if let Some(s) = &r.spcbpt {
        let rep = &s.report;
        eprintln!("spcbpt     preprocessing {:.2} s ({}); {} eye × {} light subspaces ({} of them light-source bins{})", rep.seconds, rep.phases.iter().map(|(n, t)| format!("{n} {t:.2} s")).collect::<Vec<_>>().join(", "), rep.n_eye, rep.n_light, rep.light_source_bins, if rep.light_source_bins > 0 { ", s = 1 through the cache" } else { ", s = 1 by NEE" });
        eprintln!("spcbpt     losses per epoch {:?}", rep.losses);
        eprintln!("spcbpt     memory: D {:.1} MiB ({} paths, freed after training), trees {:.1} KiB, Γ {:.1} KiB", rep.dataset_bytes as f64 / 1048576.0, rep.dataset_paths, rep.tree_bytes as f64 / 1024.0, rep.gamma_bytes as f64 / 1024.0);
    }
    Ok(r)
}
