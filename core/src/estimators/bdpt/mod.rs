//! Bidirectional path tracing (Veach 1997 ch. 10; Lafortune and Willems 1993).
//!
//! For each pixel sample, a camera sub-path z₀…z_{t−1} and a light sub-path y₀…y_{s−1}
//! are traced; every pair of prefixes (s, t) is joined into a full path, giving one
//! estimate per path length from each strategy:
//! - s = 0: the camera path hits an emitter by itself;
//! - s = 1: the camera vertex connects to a freshly sampled light point (next-event
//!   estimation, whose density is taken as the light's position density in the weights);
//! - t = 1: the light vertex connects to the pinhole and splats to the pixel it sees;
//! - s, t ≥ 2: the two end vertices are joined by a shadow ray.
//!
//! (s, t) = (1, 1) is skipped: (0, 2) already sees emitters directly.
//!
//! Strategies are combined by the balance heuristic, w_{s,t} = p_{s,t} / Σ p_{i,j} over
//! the strategies producing the same path, computed in O(s + t) from per-vertex ratios
//! of reverse and forward area densities ([`crate::path::mis`]). Camera paths and light paths are
//! traced one each per pixel sample, so every strategy has sample count one; splats
//! from t = 1 are divided by the number of light paths per pass (W·H) by the host.
//!
//! Connecting (the sample loop, [`Sample::each_strategy`]) and weighting (the closure it
//! calls per connection) are separate: [`probe`] draws the same paths and weights each
//! connection as a term of PT's second moment instead.

use core::ops::Range;

pub mod probe;

use crate::geometry::RayQuery;
use crate::path::{
    Connection, LightPointSample, Vertex, connect, light_subpath_with_kernel, mis::mis_weight, pixel_camera_subpath_with_kernel, vertex_budgets,
};
use crate::rng::{SampleStream, Stream};
use crate::scene::Context;
use crate::scene::Scene;
use crate::segment::{Junctions, Kernel, LIGHT_KERNEL_KEY};
use crate::spectrum::Rgb;
use crate::transport::{Counters, RenderParams, Splat};

/// Render one BDPT sample for each pixel in `pixels` of pass `pass`; camera-side
/// estimates go to `out`, t = 1 splats to `splat`.
pub fn render_pixels<Q: RayQuery + ?Sized>(
    scene: &Scene,
    tracer: &Q,
    params: &RenderParams,
    pass: u32,
    pixels: Range<u32>,
    out: &mut [Rgb],
    splat: &mut dyn FnMut(Splat),
) -> Counters {
    render_pixels_with_kernel(scene, tracer, params, Kernel::Dirac, pass, pixels, out, splat)
}

/// [`render_pixels`] with `kernel` joining consecutive segments on both sub-paths, and
/// every connection a bridge segment: segment BDPT ([`crate::estimators::segment::sbdpt`]). With the
/// Dirac kernel it is BDPT; the kernels draw from streams of their own.
pub(crate) fn render_pixels_with_kernel<Q: RayQuery + ?Sized>(
    scene: &Scene,
    tracer: &Q,
    params: &RenderParams,
    kernel: Kernel,
    pass: u32,
    pixels: Range<u32>,
    out: &mut [Rgb],
    splat: &mut dyn FnMut(Splat),
) -> Counters {
    let sample = Sample { scene, tracer, params, kernel, pass };
    sample.each_strategy(pixels, out, splat, |light, camera, s, t, c, counters| {
        // Weighting, a separate step: the balance heuristic over unit counts.
        let weight = mis_weight(scene, light, camera, c.sampled.as_ref(), s, t);
        counters.sanitize(c.weighted(weight).value)
    })
}

/// What one BDPT sample of a pass needs: its estimator's strategies and the PT-moment
/// probe ([`probe`]) draw the same paths from it.
pub(crate) struct Sample<'a, Q: RayQuery + ?Sized> {
    pub scene: &'a Scene,
    pub tracer: &'a Q,
    pub params: &'a RenderParams,
    pub kernel: Kernel,
    pub pass: u32,
}

impl<Q: RayQuery + ?Sized> Sample<'_, Q> {
    /// For each pixel in `pixels`, trace a camera and a light sub-path, connect every
    /// strategy (s, t) and pass each connection to `value`, whose result goes to the
    /// pixel's slot in `out` or, for t = 1, to `splat`.
    pub(crate) fn each_strategy<V>(&self, pixels: Range<u32>, out: &mut [Rgb], splat: &mut dyn FnMut(Splat), mut value: V) -> Counters
    where
        V: FnMut(&[Vertex], &[Vertex], usize, usize, Connection, &mut Counters) -> Rgb,
    {
        let Self { scene, tracer, params, kernel, pass } = *self;
        let mut counters = Counters::default();
        let ctx = Context { scene, tracer };
        let (max_camera, max_light) = vertex_budgets(params);
        for (slot, pixel) in out.iter_mut().zip(pixels) {
            let camera = pixel_camera_subpath_with_kernel(scene, tracer, params, pixel, pass, max_camera, kernel, &mut counters);
            let mut light_rng = SampleStream::for_sample(params.seed, Stream::Light, pixel, pass, 0);
            let mut light_junctions = Junctions::for_path(kernel, params.seed, pixel, pass, LIGHT_KERNEL_KEY);
            let light = light_subpath_with_kernel(scene, tracer, params, max_light, &mut light_rng, light_junctions.as_mut(), &mut counters);
            let mut connect_rng = SampleStream::for_sample(params.seed, Stream::Aux, pixel, pass, 0);
            let mut l = Rgb::ZERO;
            for t in 1..=camera.len() {
                for s in 0..=light.len() {
                    let segments = s + t;
                    if (s == 1 && t == 1) || segments < 2 || !params.max_depth.allows(segments as u32 - 1) {
                        continue;
                    }
                    let u = LightPointSample { u_light: connect_rng.next_f32(), u_point: connect_rng.next_2d() };
                    let Some(c) = connect(&ctx, &light, &camera, s, t, u, &mut counters) else { continue };
                    let film = c.film;
                    let v = value(&light, &camera, s, t, c, &mut counters);
                    match film {
                        Some(film) => splat(Splat { film, value: v }),
                        None => l += v,
                    }
                }
            }
            *slot = l;
        }
        counters
    }
}
