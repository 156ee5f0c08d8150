//! Light-vertex-cache bidirectional path tracing (LVCBPT; Davidovič, Křivánek, Hašan,
//! Slusallek 2014), the baseline of the SPCBPT paper (Su, Li, Wang 2022, section 3.3).
//!
//! Each iteration (pass) traces M light sub-paths and keeps their vertices in a cache;
//! each pixel then traces one camera sub-path z₀…z_{t−1}. A full path is produced by
//! - s = 0: the camera path hits an emitter by itself (count 1 per camera sample);
//! - s = 1: fresh next-event estimation as in BDPT (count 1) — the light-source vertices
//!   are NOT cached: BDPT's light-point sampler already is the ideal s = 1 technique;
//! - t = 1: every light vertex of the M paths is connected to the pinhole and splatted
//!   (light tracing); the film uses camera densities uniform over the whole film, i.e.
//!   W·H camera samples per pass, so relative to one camera sample this strategy takes
//!   M/(W·H) samples;
//! - s ≥ 2, t ≥ 2: each camera vertex is joined to N cache vertices chosen uniformly
//!   with replacement. Given the cache C, (|C|/(N·M)) Σ_k g(y_k) is an unbiased estimate
//!   of (1/M) Σ_{y∈C} g(y), which estimates the connection integral like one light path
//!   per camera sample would. The effective count of this strategy is N·M/|C|.
//!
//! MIS is the balance heuristic with those counts (Veach's n_i p_i / Σ n_j p_j),
//! computed in O(s + t) by BDPT's ratio walk ([`path::mis::mis_weight_counted`]).
//! The connection count uses the EXPECTED cache size, N/c̄ with c̄ the mean number of
//! cacheable vertices per light path, measured once before rendering
//! ([`count_cacheable`], on the preprocessing stream). Using the pass's own |C| would
//! make the weights depend on the random light paths of the pass, and the weights of one
//! path would then only sum to one conditionally on |C| (a small bias); with a fixed
//! c̄ the weights are a deterministic function of the path, the connection estimate
//! still divides by its true selection probability, and the sum is unbiased.
//!
//! Each phase is a function over an index range writing into caller storage:
//! [`trace_light_paths`] (vertices + t = 1 splats), the cache
//! ([`path::cacheable_entries`]), [`render_pixels`].

mod phases;

pub use phases::Lvcbpt;

use core::ops::Range;

use crate::geometry::RayQuery;
use crate::path::{
    self, CacheEntry, LightPaths, LightPointSample, Vertex, VertexKind, Weighted, connect, is_cacheable, mis::mis_weight_counted, trace_light_subpath,
};
use crate::rng::{SampleStream, Stream};
use crate::scene::Context;
use crate::scene::Scene;
use crate::spectrum::Rgb;
use crate::transport::{Counters, RenderParams, Splat};

/// Sample counts of the strategies per camera sample (see the module notes).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StrategyCounts {
    /// t = 1: M/(W·H).
    pub light_tracing: f64,
    /// s ≥ 2, t ≥ 2: N/c̄ (= N·M / E|C|).
    pub connection: f64,
}

impl StrategyCounts {
    /// Counts for M light paths per pass, N connections per camera vertex, a `pixels`
    /// film and `mean_cache_per_path` cacheable vertices per light path on average.
    pub fn new(light_paths: u32, connections: u32, pixels: u32, mean_cache_per_path: f64) -> Self {
        let c = if mean_cache_per_path > 0.0 && mean_cache_per_path.is_finite() { mean_cache_per_path } else { 1.0 };
        Self { light_tracing: light_paths as f64 / pixels.max(1) as f64, connection: connections as f64 / c }
    }
    /// n_{s,t}.
    #[inline]
    pub fn count(&self, s: usize, t: usize) -> f64 {
        if t == 1 {
            self.light_tracing
        } else if s <= 1 {
            1.0
        } else {
            self.connection
        }
    }
}

/// Trace light paths `paths` of pass `pass` into `out` (appended) and splat their
/// pinhole connections (t = 1, weighted with `counts`) to `splat`; the host scales the
/// pass's splats by 1/M.
pub fn trace_light_paths<Q: RayQuery + ?Sized>(
    scene: &Scene,
    tracer: &Q,
    params: &RenderParams,
    counts: &StrategyCounts,
    pass: u32,
    paths: Range<u32>,
    out: &mut LightPaths,
    splat: &mut dyn FnMut(Splat),
) -> Counters {
    let mut counters = Counters::default();
    let ctx = Context { scene, tracer };
    for index in paths {
        let light = trace_light_subpath(scene, tracer, params, Stream::Light, index, pass, &mut counters);
        out.push(&light);
        // (1, 1) is covered by (0, 2), as in BDPT.
        let mut lens = crate::camera::lens_stream(params.seed, index, pass);
        for s in 2..=light.len() {
            if !params.max_depth.allows(s as u32) {
                break;
            }
            let u = LightPointSample::lens(&scene.camera, &mut lens);
            if let Some(c) = strategy(&ctx, &light[..s], &[], s, 1, u, counts, &mut counters)
                && let Some(film) = c.film
            {
                splat(Splat { film, value: counters.sanitize(c.value) });
            }
        }
    }
    counters
}

/// Strategy (s, t) with LVCBPT's sample counts: connect, then weight (balance heuristic
/// over the counts).
fn strategy<Q: RayQuery + ?Sized>(
    ctx: &Context<'_, Q>,
    light: &[Vertex],
    camera: &[Vertex],
    s: usize,
    t: usize,
    u: LightPointSample,
    counts: &StrategyCounts,
    counters: &mut Counters,
) -> Option<Weighted> {
    let c = connect(ctx, light, camera, s, t, u, counters)?;
    let weight = mis_weight_counted(ctx.scene, light, camera, c.sampled.as_ref(), s, t, &|s2, t2| counts.count(s2, t2));
    Some(c.weighted(weight))
}

/// Number of cacheable vertices on light paths `paths` of the preprocessing stream
/// (the host divides the sum over a few thousand paths by their number to get c̄).
pub fn count_cacheable<Q: RayQuery + ?Sized>(scene: &Scene, tracer: &Q, params: &RenderParams, paths: Range<u32>) -> (u64, Counters) {
    let mut counters = Counters::default();
    let mut n = 0u64;
    for index in paths {
        let light = trace_light_subpath(scene, tracer, params, Stream::Preprocess, index, 0, &mut counters);
        n += light.iter().skip(1).filter(|v| is_cacheable(scene, v)).count() as u64;
    }
    (n, counters)
}

/// What the camera pass of one iteration reads.
#[derive(Clone, Copy, Debug)]
pub struct PassInputs<'a> {
    pub paths: &'a LightPaths,
    pub cache: &'a [CacheEntry],
    /// M: light paths traced this pass.
    pub light_paths: u32,
    /// N: connections per camera vertex.
    pub connections: u32,
    pub counts: StrategyCounts,
}

/// One LVCBPT sample for each pixel in `pixels` of pass `pass` into `out` (strategies
/// with t ≥ 2; t = 1 is splatted by [`trace_light_paths`]).
pub fn render_pixels<Q: RayQuery + ?Sized>(
    scene: &Scene,
    tracer: &Q,
    params: &RenderParams,
    inputs: &PassInputs,
    pass: u32,
    pixels: Range<u32>,
    out: &mut [Rgb],
) -> Counters {
    let mut counters = Counters::default();
    let (max_camera, _) = path::vertex_budgets(params);
    let counts = inputs.counts;
    let ctx = Context { scene, tracer };
    let cache_len = inputs.cache.len();
    // Each connection's estimate is divided by its selection probability N/|C| and by M.
    let connection_scale =
        if inputs.connections > 0 && inputs.light_paths > 0 { cache_len as f32 / (inputs.connections as f32 * inputs.light_paths as f32) } else { 0.0 };
    for (slot, pixel) in out.iter_mut().zip(pixels) {
        let camera = path::pixel_camera_subpath(scene, tracer, params, pixel, pass, max_camera, &mut counters);
        let mut aux = SampleStream::for_sample(params.seed, Stream::Aux, pixel, pass, 0);
        let mut l = Rgb::ZERO;
        for t in 2..=camera.len() {
            if !params.max_depth.allows(t as u32 - 1) {
                break;
            }
            // s = 0 and s = 1 (fresh light sample), as in BDPT.
            for s in 0..=1usize {
                let (u_light, u_point) = (aux.next_f32(), aux.next_2d());
                if s == 1 && !params.max_depth.allows(t as u32) {
                    continue;
                }
                if let Some(c) = strategy(&ctx, &[], &camera, s, t, LightPointSample { u_light, u_point }, &counts, &mut counters) {
                    l += counters.sanitize(c.value);
                }
            }
            // N connections to uniformly chosen cache vertices.
            let pt = &camera[t - 1];
            if cache_len == 0 || pt.kind != VertexKind::Surface || !pt.is_connectible(scene) {
                continue;
            }
            for _ in 0..inputs.connections {
                let pick = ((aux.next_f32() * cache_len as f32) as usize).min(cache_len - 1);
                let entry = inputs.cache[pick];
                let s = entry.s as usize;
                if !params.max_depth.allows((s + t - 1) as u32) {
                    continue;
                }
                let light = entry.subpath(inputs.paths);
                if let Some(c) = strategy(&ctx, light, &camera, s, t, LightPointSample::default(), &counts, &mut counters) {
                    l += counters.sanitize(c.value * connection_scale);
                }
            }
        }
        *slot = l;
    }
    counters
}
