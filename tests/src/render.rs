//! Single-threaded pass rendering for tests through the core's render protocol and its
//! serial runner: one image per pass, so per-pass statistics (independent across passes)
//! give honest error bars.

use ember_core::estimators::PhaseBuffers;
use ember_core::estimators::spcbpt::{Model, Spcbpt};
use ember_core::estimators::{EstimatorConfig, EstimatorKind, Renderer, SpcbptConfig};
use ember_core::geometry::RayQuery;
use ember_core::render::{Context, Film, render_pass as serial_pass, run_phases};
use ember_core::scene::Scene;
use ember_core::transport::{Counters, RenderParams};

use crate::stats::{MeanVar, normal_two_sided_p};

/// The estimators without setup or per-pass caches (most tests compare these three).
pub const PT_LT_BDPT: [EstimatorKind; 3] = [EstimatorKind::Pt, EstimatorKind::Lt, EstimatorKind::Bdpt];

/// An estimator bound to a scene and tracer, its setup run, rendering one image per pass.
#[derive(Debug)]
pub struct Passes<'a, Q: RayQuery + ?Sized> {
    pub renderer: Renderer,
    ctx: Context<'a, Q>,
    buffers: PhaseBuffers,
}

impl<'a, Q: RayQuery + ?Sized> Passes<'a, Q> {
    /// `config` for `scene`, its setup phases run serially here.
    pub fn new(scene: &'a Scene, tracer: &'a Q, params: &RenderParams, config: EstimatorConfig) -> Self {
        let mut renderer = Renderer::new(scene, *params, config).expect("valid test configuration");
        let ctx = Context { scene, tracer };
        let mut buffers = PhaseBuffers::new();
        run_phases(&mut renderer, &ctx, &mut Film::new(0, 0), &mut buffers);
        Self { renderer, ctx, buffers }
    }

    /// Pass `pass` alone: its image (the film's after one pass) and the counters, with
    /// the film's discarded samples added to the estimator's. Under a tent or gaussian
    /// filter a pass's camera samples are a ratio estimate (`render::Film`), biased
    /// for one pass: average [`Self::passes_image`]s of many passes each instead.
    pub fn pass_image(&mut self, pass: u32) -> (Vec<[f64; 3]>, Counters) {
        self.passes_image(pass..pass + 1)
    }

    /// Passes `passes` in one film: its image and the summed counters (as
    /// [`Self::pass_image`]).
    pub fn passes_image(&mut self, passes: core::ops::Range<u32>) -> (Vec<[f64; 3]>, Counters) {
        let camera = &self.ctx.scene.camera;
        let mut film = Film::for_camera(camera);
        let mut counters = Counters::default();
        for pass in passes {
            counters += serial_pass(&mut self.renderer, &self.ctx, &mut film, &mut self.buffers, pass).0;
        }
        counters.discarded += film.discarded();
        (film.to_rgb_f64(), counters)
    }

    /// The SPCBPT state (model, pass cache), if this is SPCBPT.
    pub fn spcbpt(&mut self) -> Option<&mut Spcbpt> {
        match &mut self.renderer {
            Renderer::Spcbpt(s) => Some(s),
            _ => None,
        }
    }
}

/// Render one pass of PT, LT or BDPT (W·H light paths for LT; BDPT traces one light path
/// per pixel): the pass image in f64 and the counters.
pub fn render_pass<Q: RayQuery + ?Sized>(est: EstimatorKind, scene: &Scene, tracer: &Q, params: &RenderParams, pass: u32) -> (Vec<[f64; 3]>, Counters) {
    Passes::new(scene, tracer, params, est.default_config()).pass_image(pass)
}

/// A small SPCBPT configuration for tests: `subspaces` light subspaces of which
/// `light_source_bins` are light-source bins (0: next-event estimation), |D| = `dataset`,
/// M' = `q_paths`, M = `light_paths`, Adam α = 0.1 on batches of 200 for 2 epochs (Γ far
/// from uniform), N = 3, no reuse.
pub fn spcbpt_config(subspaces: u32, light_source_bins: u32, dataset: u32, q_paths: u32, light_paths: u32, mixture: f32) -> SpcbptConfig {
    SpcbptConfig {
        light_paths: Some(light_paths),
        connections: 3,
        dataset: Some(dataset),
        subspaces: Some(subspaces),
        learning_rate: 0.1,
        batch: 200,
        steps: 0,
        epochs: 2,
        mixture,
        reuse: 0,
        k_d: 0.05,
        light_source_share: light_source_bins as f32 / subspaces as f32,
        q_paths: Some(q_paths),
    }
}

/// The SPCBPT model `config` trains (setup phases run serially) and its per-epoch losses.
pub fn spcbpt_model<Q: RayQuery + ?Sized>(scene: &Scene, tracer: &Q, params: &RenderParams, config: SpcbptConfig) -> (Model, Vec<f64>) {
    let mut passes = Passes::new(scene, tracer, params, EstimatorConfig::Spcbpt(config));
    let s = passes.spcbpt().expect("SPCBPT");
    (s.model.clone().expect("setup ran"), s.report.losses.clone())
}

/// Per-channel means over square `block`×`block` pixel blocks of a `width`-wide image,
/// blocks in row-major order (the comparisons between estimators and references).
pub fn block_means(img: &[[f64; 3]], width: usize, block: usize) -> Vec<[f64; 3]> {
    let height = img.len() / width.max(1);
    let (bx, by) = (width / block, height / block);
    let mut sums = vec![[0.0f64; 3]; bx * by];
    for (i, px) in img.iter().enumerate() {
        let (x, y) = (i % width, i / width);
        if x / block < bx && y / block < by {
            let s = &mut sums[(y / block) * bx + x / block];
            for c in 0..3 {
                s[c] += px[c] / (block * block) as f64;
            }
        }
    }
    sums
}

/// Add one pass image's [`block_means`] to per-block, per-channel statistics.
pub fn push_block_means(stats: &mut [[MeanVar; 3]], img: &[[f64; 3]], width: usize, block: usize) {
    for (s, mean) in stats.iter_mut().zip(&block_means(img, width, block)) {
        for c in 0..3 {
            s[c].push(mean[c]);
        }
    }
}

/// Two-sided z-test of every block and channel of `other` against `reference` (means of
/// independent passes); panics naming `name`, the block and channel when p ≤ `alpha`.
/// Returns the smallest p.
pub fn assert_blocks_agree(name: &str, reference: &[[MeanVar; 3]], other: &[[MeanVar; 3]], alpha: f64) -> f64 {
    let mut min_p = 1.0f64;
    for (b, (x, y)) in reference.iter().zip(other).enumerate() {
        for c in 0..3 {
            let z = (x[c].mean() - y[c].mean()) / (x[c].std_error().powi(2) + y[c].std_error().powi(2)).sqrt();
            let p = normal_two_sided_p(z);
            min_p = min_p.min(p);
            assert!(p > alpha, "{name}: block {b}, channel {c}: reference {} vs {} (z = {z:.2})", x[c].mean(), y[c].mean());
        }
    }
    min_p
}

/// relMSE of `config` against Mitsuba's reference of the Cornell box at 32×32 (the
/// 256×256 reference averaged over 8×8 pixel blocks: the box filter's pixel measurement
/// at 32×32) after each of `checkpoints` passes (increasing), one continuous render with
/// seed 31 and max_depth 30.
pub fn cornell_relmse(config: EstimatorConfig, checkpoints: &[u32]) -> Vec<f64> {
    use crate::reference::{read_exr, scenes_dir};
    const RES: usize = 32;
    let reference = read_exr(&scenes_dir().join("cornell-box").join("reference.exr")).expect("the suite's reference (../shared/scenes)");
    let scale = reference.width / RES;
    let target: Vec<[f64; 3]> = (0..RES * RES).map(|i| reference.block_mean(i % RES, i / RES, scale, scale)).collect();
    let (scene, geometry, _) = crate::scenes::cornell(RES as u32, RES as u32).build().expect("scene");
    let tracer = crate::tracer::BruteForce::new(geometry);
    let params = RenderParams { max_depth: ember_core::transport::MaxDepth(30), seed: 31, ..RenderParams::default() };
    let mut passes = Passes::new(&scene, &tracer, &params, config);
    let mut sum = vec![[0.0f64; 3]; RES * RES];
    let mut errors = Vec::new();
    let mut done = 0u32;
    for &checkpoint in checkpoints {
        while done < checkpoint {
            let (img, counters) = passes.pass_image(done);
            assert_eq!(counters.discarded, 0, "non-finite samples");
            for (s, p) in sum.iter_mut().zip(&img) {
                for c in 0..3 {
                    s[c] += p[c];
                }
            }
            done += 1;
        }
        let rel: f64 =
            sum.iter().zip(&target).map(|(s, t)| (0..3).map(|c| (s[c] / done as f64 - t[c]).powi(2) / (t[c] * t[c] + 1e-2)).sum::<f64>() / 3.0).sum::<f64>()
                / (RES * RES) as f64;
        errors.push(rel);
    }
    errors
}

/// Give every fourth node a kernel half the pass's, or a quarter for every eighth (as
/// `estimators::filter::scale_kernels` does to glossy nodes), so that the filters'
/// propagation-against-recursion tests check that every kernel is its centre's own.
pub fn vary_kernels(nodes: &mut [ember_core::estimators::filter::Node]) {
    for (i, n) in nodes.iter_mut().enumerate() {
        n.kernel_scale = if i % 8 == 0 {
            0.25
        } else if i % 4 == 0 {
            0.5
        } else {
            1.0
        };
    }
}
