//! Single-threaded passes of the cache-based estimators (LVCBPT, SPCBPT) for tests: the
//! same phases the CLI host runs in parallel, here in order on one thread.

use ember_core::geometry::RayQuery;
use ember_core::integrator::lvcbpt::{self, CacheEntry, LightPaths, PassInputs, StrategyCounts};
use ember_core::integrator::{Counters, RenderParams, Splat};
use ember_core::scene::Scene;
use ember_core::spectrum::Rgb;

/// Add `splats` scaled by `scale` to the pixels they land in.
pub fn add_splats(img: &mut [[f64; 3]], width: u32, height: u32, splats: &[Splat], scale: f64) {
    for s in splats {
        let (x, y) = (s.film.x.floor() as i64, s.film.y.floor() as i64);
        if x >= 0 && y >= 0 && (x as u32) < width && (y as u32) < height {
            let px = &mut img[(y as u32 * width + x as u32) as usize];
            for c in 0..3 {
                px[c] += s.value[c] as f64 * scale;
            }
        }
    }
}

/// LVCBPT settings for a test.
#[derive(Clone, Copy, Debug)]
pub struct LvcbptSetup {
    /// M.
    pub light_paths: u32,
    /// N.
    pub connections: u32,
    pub counts: StrategyCounts,
}

impl LvcbptSetup {
    /// Measure c̄ over `probe` preprocessing light paths and fix the counts.
    pub fn new<Q: RayQuery>(scene: &Scene, tracer: &Q, params: &RenderParams, light_paths: u32, connections: u32, probe: u32) -> Self {
        let (n, _) = lvcbpt::count_cacheable(scene, tracer, params, 0..probe);
        let pixels = scene.camera.width() * scene.camera.height();
        let counts = StrategyCounts::new(light_paths, connections, pixels, n as f64 / probe as f64);
        Self { light_paths, connections, counts }
    }
}

/// One LVCBPT pass: the image (f64) and the counters.
pub fn lvcbpt_pass<Q: RayQuery>(setup: &LvcbptSetup, scene: &Scene, tracer: &Q, params: &RenderParams, pass: u32) -> (Vec<[f64; 3]>, Counters) {
    let (w, h) = (scene.camera.width(), scene.camera.height());
    let n = (w * h) as usize;
    let mut paths = LightPaths::new();
    let mut splats = Vec::new();
    let mut counters = lvcbpt::trace_light_paths(scene, tracer, params, &setup.counts, pass, 0..setup.light_paths, &mut paths, &mut |s| splats.push(s));
    let mut cache: Vec<CacheEntry> = Vec::new();
    lvcbpt::build_cache(scene, &paths, &mut cache);
    let inputs = PassInputs { paths: &paths, cache: &cache, light_paths: setup.light_paths, connections: setup.connections, counts: setup.counts };
    let mut camera = vec![Rgb::ZERO; n];
    counters += lvcbpt::render_pixels(scene, tracer, params, &inputs, pass, 0..n as u32, &mut camera);
    let mut img: Vec<[f64; 3]> = camera.iter().map(|c| c.to_f64()).collect();
    add_splats(&mut img, w, h, &splats, 1.0 / setup.light_paths as f64);
    (img, counters)
}

use ember_core::integrator::spcbpt::{self, Classifier, Model, PassCache, prepare};
use ember_core::spcbpt::{AdamParams, SubspaceMatrix, TrainParams, TrainingSet};

/// SPCBPT preprocessing on one thread (the CLI host's phases, in order): κ_L from
/// `dataset` light paths, dataset pass 1 (eye features, block brightness), κ_E, Q over
/// `q_paths` light paths, dataset pass 2 (training set), Adam. Returns the model and
/// the per-epoch losses. `light_source_bins` > 0 adds that many light-source subspaces
/// (s = 1 through the cache); 0 keeps next-event estimation.
#[allow(clippy::too_many_arguments)]
pub fn spcbpt_model<Q: RayQuery>(scene: &Scene, tracer: &Q, params: &RenderParams, subspaces: usize, light_source_bins: u32, dataset: u32, q_paths: u32, light_paths: u32, mixture: f32) -> (Model, Vec<f64>) {
    let (w, h) = (scene.camera.width(), scene.camera.height());
    let (mut f, mut wt) = (Vec::new(), Vec::new());
    prepare::light_features(scene, tracer, params, 0..dataset, &mut f, &mut wt);
    let (light, n_light_surface) = prepare::fit_side(&f, &wt, subspaces, 0.05, 1);
    let blocks_n = (w.div_ceil(prepare::BLOCK) * h.div_ceil(prepare::BLOCK)) as usize;
    let (mut b, mut bs) = (vec![0.0; blocks_n], vec![0u32; blocks_n]);
    let (mut ef, mut ew) = (Vec::new(), Vec::new());
    prepare::dataset_features(scene, tracer, params, 0..dataset, &mut ef, &mut ew, &mut b, &mut bs);
    let (eye, n_eye) = prepare::fit_side(&ef, &ew, subspaces, 0.05, 2);
    let sources = (light_source_bins > 0).then(|| spcbpt::light_source_bins(scene, light_source_bins, n_light_surface).expect("light-source bins"));
    let classifier = Classifier::new(eye, n_eye, light, n_light_surface, sources);
    let n_light = classifier.n_light;
    let mut q = vec![0.0f64; n_light as usize];
    prepare::accumulate_q(scene, tracer, params, &classifier, 0..q_paths, &mut q);
    let q: Vec<f32> = q.iter().map(|v| (v / q_paths as f64) as f32).collect();
    let mean: Vec<f64> = b.iter().zip(&bs).map(|(s, &n)| if n > 0 { s / n as f64 } else { 0.0 }).collect();
    let mut set = TrainingSet::new();
    let lt = light_paths as f64 / (w * h) as f64;
    prepare::dataset_records(scene, tracer, params, &classifier, &q, 3, lt, &mean, 0..dataset, &mut set);
    let (nl, ne) = (n_light as usize, n_eye as usize);
    let mut theta = vec![0.0f32; nl * ne];
    let tp = TrainParams { adam: AdamParams { learning_rate: 0.1, ..AdamParams::default() }, batch: 200, epochs: 2, mixture, seed: 3 };
    let losses = ember_core::spcbpt::train(&set, &mut theta, nl, ne, &tp);
    let gamma = SubspaceMatrix::from_theta(&theta, nl, ne, mixture);
    (Model { classifier, q, gamma, connections: 3 }, losses)
}

/// One SPCBPT pass with `model` and M = `light_paths`.
pub fn spcbpt_pass<Q: RayQuery>(model: &Model, light_paths: u32, scene: &Scene, tracer: &Q, params: &RenderParams, pass: u32) -> (Vec<[f64; 3]>, Counters) {
    let (w, h) = (scene.camera.width(), scene.camera.height());
    let n = (w * h) as usize;
    let mut cache = PassCache::default();
    let mut counters = spcbpt::trace_light_paths(scene, tracer, params, model, pass, 0..light_paths, &mut cache.paths, &mut cache.memo);
    spcbpt::build_buckets(scene, model, &mut cache);
    let ne = model.classifier.n_eye as usize;
    let (mut tables, mut norms) = (vec![None; ne], vec![0.0f32; ne]);
    spcbpt::build_gamma_tables(model, &cache, 0..ne as u32, &mut tables, &mut norms);
    cache.gamma_tables = tables;
    cache.gamma_norm = norms;
    let mut splats = Vec::new();
    counters += spcbpt::splat_light_paths(scene, tracer, params, model, &cache, light_paths as f64 / n as f64, 0..light_paths, &mut |s| splats.push(s));
    let mut camera = vec![Rgb::ZERO; n];
    counters += spcbpt::render_pixels(scene, tracer, params, model, &cache, light_paths, pass, 0..n as u32, &mut camera);
    let mut img: Vec<[f64; 3]> = camera.iter().map(|c| c.to_f64()).collect();
    add_splats(&mut img, w, h, &splats, 1.0 / light_paths as f64);
    (img, counters)
}
