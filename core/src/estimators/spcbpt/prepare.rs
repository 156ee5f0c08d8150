//! SPCBPT preprocessing (section 7): the classification κ, Q per light subspace
//! (eq. 19) and the training set of the MIS-aware loss (section 6.3/7.3, eq. 16). Each
//! phase is a function over an index range writing into caller storage; the host runs
//! the ranges in parallel and merges in index order.
//!
//! The dataset D is traced by path tracing with next-event estimation (the public code's
//! choice): each dataset sample is a camera path through a uniformly chosen pixel, and
//! each of its NEE connections (strategy s = 1) is a full path x with its f(x)/p₁(x).
//! Its record holds only what the loss needs, all relative to p₁(x): the weight
//! (f/p₁)² of the path's relative contribution (divided by its ~10×10 pixel block's mean
//! brightness, clamped), the Γ-independent part Σ n_i p_i/p₁ and, per split s' ≥ 2 with
//! t' ≥ 2, coef = N · (p_{s'}/p₁) · W_{s'} / Q(κ_L) with its (κ_L, κ_E). Then
//! F(x|Γ)/p₁ = fixed + Σ coef·Γ(κ_L | κ_E) and the loss Σ f²/(p₁ F) is what
//! [`crate::subspace::train`] minimises. D is traced twice from the same random numbers
//! (first for the eye features and block brightness, then for the records), so no path
//! is stored.

use alloc::vec::Vec;
use core::ops::Range;

use super::{Classifier, FullPath, cache_weight, join, light_prefix_weights, scalar};
use crate::geometry::RayQuery;
use crate::math::Vec2;
use crate::path::{self, LightPointSample, Vertex, VertexKind, camera_subpath, connect, is_cacheable, mis::for_each_strategy_ratio, trace_light_subpath};
use crate::rng::{SampleStream, Stream};
use crate::scene::{Context, Scene};
use crate::spectrum::Rgb;
use crate::subspace::{DecisionTree, DistanceParams, SubpathFeature, TrainingSet, TrainingSplit, TreeParams, nearest_centroid, sample_centroids};
use crate::transport::{Counters, RenderParams};

/// Index offsets keeping the preprocessing phases' random streams apart.
const Q_BASE: u32 = 0x2000_0000;
const DATASET_BASE: u32 = 0x4000_0000;
/// Side of the pixel blocks of relative contributions.
pub const BLOCK: u32 = 10;
/// Clamp of a path's relative weight (f/p₁)² (the public code's 1e6).
pub const WEIGHT_CLAMP: f64 = 1e6;

/// Light-side features of dataset samples `samples`: every light prefix of each NEE full
/// path x = (y, z_t, …, z_1) whose end vertex could be cached, (y, z_t) ending at z_t,
/// (y, z_t, z_{t−1}) at z_{t−1}, and so on, each weighted by the full path's f(x)/p(x)
/// (section 7.2.2: "we sample the centroid sub-paths from the prefix/suffix of the full
/// paths stored in D ... proportional to the contribution of the corresponding full
/// path", and the tree is trained on the same prefixes). Light paths traced from the
/// lights and weighted by their own f_y/p instead (what this did before) spend the
/// centroids where light is, not where the light that reaches the camera passes: on
/// ajar, 5 of 222 surface subspaces fell in the room the camera sees.
pub fn light_features<Q: RayQuery + ?Sized>(
    scene: &Scene,
    tracer: &Q,
    params: &RenderParams,
    samples: Range<u32>,
    features: &mut Vec<SubpathFeature>,
    weights: &mut Vec<f32>,
) -> Counters {
    let mut counters = Counters::default();
    for i in samples {
        dataset_sample(scene, tracer, params, i, &mut counters, &mut |_pixel, camera, t, y, value| {
            let w = scalar(value);
            if !(w > 0.0 && w.is_finite()) {
                return;
            }
            for j in (1..t).rev() {
                let prev = if j + 1 == t { y.p } else { camera[j + 1].p };
                if is_cacheable(scene, &camera[j]) {
                    features.push(super::feature(&camera[j], prev));
                    weights.push(w);
                }
            }
        });
    }
    counters
}

/// Fit a classifier side: `count` centroids drawn ∝ weight, nearest-centroid labels
/// under eq. 18's distance, a decision tree reproducing them. Returns (tree, subspaces).
pub fn fit_side(features: &[SubpathFeature], weights: &[f32], count: usize, k_d: f32, seed: u64) -> (DecisionTree, u32) {
    let centroids = sample_centroids(features, weights, count, seed);
    let positions: Vec<_> = features.iter().map(|f| f.position).collect();
    let distance = DistanceParams::from_positions(&positions, k_d);
    let labels: Vec<u32> = features.iter().map(|f| nearest_centroid(&centroids, &distance, f)).collect();
    let tree = DecisionTree::fit(features, &labels, weights, &TreeParams { seed, ..TreeParams::default() });
    (tree, centroids.len().max(1) as u32)
}

/// Add Σ f/p of light paths `paths`' cacheable vertices into `q[κ_L]` (the host divides
/// by M'), and of their light-source vertices into their bins when the classifier has
/// them. Every path of the range is traced: the loop never stops early.
pub fn accumulate_q<Q: RayQuery + ?Sized>(
    scene: &Scene,
    tracer: &Q,
    params: &RenderParams,
    classifier: &Classifier,
    paths: Range<u32>,
    q: &mut [f64],
) -> Counters {
    let mut counters = Counters::default();
    for i in paths {
        let light = trace_light_subpath(scene, tracer, params, Stream::Preprocess, Q_BASE.wrapping_add(i), 0, &mut counters);
        if let Some(l) = light.first().and_then(|y0| classifier.light_source_of(scene, y0))
            && let Some(slot) = q.get_mut(l as usize)
        {
            *slot += cache_weight(&light[..1]) as f64;
        }
        for k in 1..light.len() {
            if is_cacheable(scene, &light[k]) {
                let l = classifier.light_of(&light[k], light[k - 1].p) as usize;
                if let Some(slot) = q.get_mut(l) {
                    *slot += scalar(light[k].beta) as f64;
                }
            }
        }
    }
    counters
}

/// Receives (pixel, camera sub-path, t, sampled light vertex, unweighted f/p₁) per NEE
/// full path of a dataset sample.
type DatasetVisit<'a> = dyn FnMut(u32, &[Vertex], usize, Vertex, Rgb) + 'a;

/// Trace dataset sample `i`: its pixel, camera path and each NEE full path (t, sampled
/// light vertex, unweighted f/p₁) handed to `visit`.
fn dataset_sample<Q: RayQuery + ?Sized>(scene: &Scene, tracer: &Q, params: &RenderParams, i: u32, counters: &mut Counters, visit: &mut DatasetVisit<'_>) {
    let width = scene.camera.width().max(1);
    let pixels = width * scene.camera.height().max(1);
    let pixel = i % pixels;
    let (max_camera, _) = path::vertex_budgets(params);
    let mut rng = SampleStream::for_sample(params.seed, Stream::Preprocess, DATASET_BASE.wrapping_add(i), 0, 0);
    let film = Vec2::new((pixel % width) as f32, (pixel / width) as f32) + rng.next_2d();
    let camera = camera_subpath(scene, tracer, params, film, max_camera, &mut rng, counters);
    let mut aux = SampleStream::for_sample(params.seed, Stream::Preprocess, DATASET_BASE.wrapping_add(i), 1, 0);
    let ctx = Context { scene, tracer };
    for t in 2..=camera.len() {
        let (u_light, u_point) = (aux.next_f32(), aux.next_2d());
        if !params.max_depth.allows(t as u32) {
            break;
        }
        // The unweighted f/p₁ of the NEE full path.
        if let Some(c) = connect(&ctx, &[], &camera[..t], 1, t, LightPointSample { u_light, u_point }, counters)
            && let Some(y) = c.sampled
        {
            visit(pixel, &camera, t, y, c.value);
        }
    }
}

/// First pass over dataset samples `samples`: eye features of camera vertices (weighted
/// by the camera path's total contribution) and per-block brightness sums (`blocks`,
/// (⌈W/10⌉·⌈H/10⌉) entries) and sample counts.
pub fn dataset_features<Q: RayQuery + ?Sized>(
    scene: &Scene,
    tracer: &Q,
    params: &RenderParams,
    samples: Range<u32>,
    features: &mut Vec<SubpathFeature>,
    weights: &mut Vec<f32>,
    blocks: &mut [f64],
    block_samples: &mut [u32],
) -> Counters {
    let mut counters = Counters::default();
    let width = scene.camera.width().max(1);
    let bw = width.div_ceil(BLOCK);
    for i in samples {
        let mut total = 0.0f32;
        let mut last: Option<(u32, heapless::Vec<SubpathFeature, { path::MAX_VERTICES }>)> = None;
        dataset_sample(scene, tracer, params, i, &mut counters, &mut |pixel, camera, _t, _y, value| {
            total += scalar(value);
            if last.is_none() {
                let mut f = heapless::Vec::new();
                for j in 1..camera.len() {
                    if camera[j].kind == VertexKind::Surface && camera[j].is_connectible(scene) {
                        let _ = f.push(super::feature(&camera[j], camera[j - 1].p));
                    }
                }
                last = Some((pixel, f));
            }
        });
        let pixel = i % (width * scene.camera.height().max(1));
        let b = ((pixel / width) / BLOCK * bw + (pixel % width) / BLOCK) as usize;
        if let Some(slot) = blocks.get_mut(b) {
            *slot += if total.is_finite() { total as f64 } else { 0.0 };
            block_samples[b] += 1;
        }
        if let Some((_, f)) = last
            && total > 0.0
            && total.is_finite()
        {
            for feat in f {
                features.push(feat);
                weights.push(total);
            }
        }
    }
    counters
}

/// What the training records read besides the scene: the classifier, the normalised Q,
/// N, the light-tracing count M/(W·H) and each pixel block's mean brightness.
#[derive(Clone, Copy, Debug)]
pub struct RecordInputs<'a> {
    pub classifier: &'a Classifier,
    pub q: &'a [f32],
    pub connections: u32,
    pub light_tracing: f64,
    pub block_mean: &'a [f64],
}

/// Second pass over dataset samples `samples`: training records into `set`.
/// `inputs.block_mean[b]` is block b's mean brightness per sample; `inputs.q` the
/// normalised Q.
pub fn dataset_records<Q: RayQuery + ?Sized>(
    ctx: &Context<'_, Q>,
    params: &RenderParams,
    inputs: &RecordInputs<'_>,
    samples: Range<u32>,
    set: &mut TrainingSet,
) -> Counters {
    let (scene, tracer) = (ctx.scene, ctx.tracer);
    let RecordInputs { classifier, q, connections, light_tracing, block_mean } = *inputs;
    let mut counters = Counters::default();
    let width = scene.camera.width().max(1);
    let bw = width.div_ceil(BLOCK);
    let mut splits: Vec<TrainingSplit> = Vec::new();
    for i in samples {
        dataset_sample(scene, tracer, params, i, &mut counters, &mut |pixel, camera, t, y, value| {
            let b = ((pixel / width) / BLOCK * bw + (pixel % width) / BLOCK) as usize;
            let mean = block_mean.get(b).copied().unwrap_or(0.0);
            let rel = scalar(value) as f64 / (mean + 1e-4);
            let weight = (rel * rel).min(WEIGHT_CLAMP);
            if !(weight > 0.0) {
                return;
            }
            let light = [y];
            let x: FullPath = join(&light, camera, Some(y), 1, t);
            let mut w = [0.0f32; 2 * path::MAX_VERTICES + 1];
            light_prefix_weights(scene, &x, &mut w);
            splits.clear();
            // The sampling technique's own strategy (1, t): next-event estimation counts
            // 1; with light-source bins s = 1 is a Γ-connection to the light's bin.
            let mut fixed = match classifier.light_source_of(scene, &y) {
                Some(l) => {
                    let ql = q.get(l as usize).copied().unwrap_or(0.0);
                    let coef = if ql > 0.0 { connections as f64 * w[1] as f64 / ql as f64 } else { 0.0 };
                    if coef.is_finite() && coef > 0.0 {
                        splits.push(TrainingSplit { eye: classifier.eye_of(&camera[t - 1], camera[t - 2].p), light: l, coef });
                    }
                    0.0
                }
                None => 1.0f64,
            };
            for_each_strategy_ratio(scene, &light, &camera[..t], Some(&y), 1, t, &mut |s2, t2, ratio| {
                if t2 == 1 {
                    fixed += light_tracing * ratio;
                } else if s2 <= 1 {
                    fixed += ratio;
                } else {
                    let (ys, zs) = (&x[s2 - 1], &x[s2]);
                    if ys.kind != VertexKind::Surface || zs.kind != VertexKind::Surface {
                        return;
                    }
                    let l = classifier.light_of(ys, x[s2 - 2].p);
                    let e = classifier.eye_of(zs, x[s2 + 1].p);
                    let ql = q.get(l as usize).copied().unwrap_or(0.0);
                    if ql > 0.0 {
                        let coef = connections as f64 * ratio * w[s2] as f64 / ql as f64;
                        if coef.is_finite() && coef > 0.0 {
                            splits.push(TrainingSplit { eye: e, light: l, coef });
                        }
                    }
                }
            });
            if fixed.is_finite() {
                set.push_path(weight, fixed, &splits);
            }
        });
    }
    counters
}
