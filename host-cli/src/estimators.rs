//! The core's estimators as [`PassRenderer`]s: scene loading, ray queries and the
//! per-pass calls into `ember_core::integrator`.

use std::ops::Range;

use ember_core::integrator::{Counters, Heuristic, MaxDepth, RenderParams, bdpt, lt, pt};
use ember_core::scene::{Scene, builtin};
use ember_core::Rgb;

use crate::accel::Accel;
use crate::app::builtin_resolution;
use crate::cli::{EstimatorArg, RenderArgs};
use crate::driver::{PassRenderer, PassStats, Splat};

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

/// Build the built-in Cornell box at the requested resolution.
pub fn prepare_builtin(args: &RenderArgs) -> Result<PreparedScene, String> {
    let (w, h) = builtin_resolution(args);
    let (scene, geometry, warnings) = builtin::cornell_box(w, h).build().map_err(|e| format!("built-in scene: {e}"))?;
    let accel = Accel::new(&geometry);
    let mut notes = Vec::new();
    if warnings.degenerate_triangles > 0 {
        notes.push(format!("{} degenerate triangles dropped", warnings.degenerate_triangles));
    }
    Ok(PreparedScene { name: "built-in Cornell box".into(), scene, accel, max_depth: None, spp: None, warnings: notes })
}

/// One of the core's estimators bound to a prepared scene.
#[derive(Debug)]
pub struct CoreRenderer {
    pub prepared: PreparedScene,
    pub estimator: EstimatorArg,
    pub params: RenderParams,
}

impl CoreRenderer {
    pub fn new(prepared: PreparedScene, estimator: EstimatorArg, max_depth: i32, seed: u64) -> Self {
        // PT combines its two techniques with the power heuristic (as Mitsuba does);
        // BDPT's weights are the balance heuristic by construction.
        let params = RenderParams { max_depth: MaxDepth(max_depth), seed, heuristic: Heuristic::Power, ..RenderParams::default() };
        Self { prepared, estimator, params }
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
    fn splat_scale(&self) -> f64 {
        // LT traces W·H light paths per pass; BDPT traces one per pixel sample.
        1.0 / self.pixels() as f64
    }
}

/// The renderer a `render` command asks for.
pub fn make_renderer(args: &RenderArgs) -> Result<Box<dyn PassRenderer>, String> {
    let prepared = prepare_builtin(args)?;
    for w in &prepared.warnings {
        eprintln!("warning: {w}");
    }
    let max_depth = args.max_depth.or(prepared.max_depth).unwrap_or(-1);
    Ok(Box::new(CoreRenderer::new(prepared, args.estimator, max_depth, args.seed)))
}
