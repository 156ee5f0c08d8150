//! Path space: the building blocks every bidirectional estimator shares.
//!
//! - [`vertex`]: path vertices with their forward and reverse densities and the
//!   conversions between measures;
//! - [`walk`]: camera and light sub-paths (random walks with Russian roulette);
//! - [`connect`]: joining a light prefix and a camera prefix into a full path (the
//!   (s, t) strategies), returning the contribution and the resampled endpoint;
//! - [`mis`]: balance-heuristic weights of the strategies that produce one path, with
//!   per-strategy sample counts, in O(s + t) from density ratios;
//! - [`store`]: light sub-paths stored contiguously and the cache entries pointing into
//!   them (LVCBPT's and SPCBPT's per-pass light-vertex caches).
//!
//! An estimator module (BDPT, LVCBPT, SPCBPT, and the merging and filtering estimators
//! to come) holds only its own strategies and weights on top of these.

pub mod connect;
pub mod mis;
pub mod store;
pub mod vertex;
pub mod walk;

use crate::geometry::RayQuery;
use crate::rng::{SampleStream, Stream};
use crate::scene::Scene;
use crate::segment::{CAMERA_KERNEL_KEY, Junctions, Kernel};
use crate::transport::{Counters, RenderParams};

pub use connect::{Connection, LightPointSample, Weighted, connect, connect_light_source};
pub use store::{CacheEntry, LightPaths, cacheable_entries, is_cacheable, trace_light_subpath};
pub use vertex::{Vertex, VertexKind};
pub use walk::{SubPath, camera_subpath, camera_subpath_from, camera_subpath_with_kernel, light_subpath, light_subpath_with_kernel};

/// Capacity of a sub-path (vertices); unbounded depth truncates here (counted).
pub const MAX_VERTICES: usize = 34;

/// Sub-path vertex budgets implied by `max_depth`: a path of s + t vertices has
/// s + t − 1 segments.
pub fn vertex_budgets(params: &RenderParams) -> (usize, usize) {
    let segments = params.max_depth.capped(MAX_VERTICES as u32 - 1) as usize;
    // Camera: up to segments + 1 vertices (s = 0); light: up to `segments` (t = 1).
    (segments + 1, segments)
}

/// The camera sub-path of pixel `pixel`'s sample in pass `pass`: a jittered film position
/// and the walk, both from the pixel's camera stream (the draws every estimator of the
/// BDPT family makes, so their camera paths coincide).
pub fn pixel_camera_subpath<Q: RayQuery + ?Sized>(
    scene: &Scene,
    tracer: &Q,
    params: &RenderParams,
    pixel: u32,
    pass: u32,
    max_camera: usize,
    counters: &mut Counters,
) -> SubPath {
    pixel_camera_subpath_with_kernel(scene, tracer, params, pixel, pass, max_camera, Kernel::Dirac, counters)
}

/// [`pixel_camera_subpath`] with `kernel` at its junctions (segment BDPT), drawn from the
/// pixel's camera-kernel stream.
pub fn pixel_camera_subpath_with_kernel<Q: RayQuery + ?Sized>(
    scene: &Scene,
    tracer: &Q,
    params: &RenderParams,
    pixel: u32,
    pass: u32,
    max_camera: usize,
    kernel: Kernel,
    counters: &mut Counters,
) -> SubPath {
    let width = scene.camera.width().max(1);
    let mut rng = SampleStream::for_sample(params.seed, Stream::Camera, pixel, pass, 0);
    let primary = scene.camera.sample_ray(pixel % width, pixel / width, &mut rng);
    let mut junctions = Junctions::for_path(kernel, params.seed, pixel, pass, CAMERA_KERNEL_KEY);
    camera_subpath_from(scene, tracer, params, primary, max_camera, &mut rng, junctions.as_mut(), counters)
}
