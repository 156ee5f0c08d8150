//! Vertex merging: progressive photon mapping (PPM), bidirectional photon mapping (BPM)
//! and vertex connection and merging (VCM; Georgiev, Křivánek, Davidovič, Slusallek
//! 2012, the same estimator as Hachisuka, Pantaleoni and Jensen 2012's UPS).
//!
//! Each pass traces N_L light sub-paths (default one per pixel) and stores their
//! non-Dirac surface vertices after the light source ("photons") in a hash grid
//! ([`crate::merge::HashGrid`]) of the pass's radius r_i ([`crate::merge::radius`]).
//! Each pixel then traces one camera sub-path z₀ … z_{t−1}. **Merging** a photon x_j
//! (light path x₀ … x_j, throughput β_L) found within r of a camera vertex y = z_{t−1}
//! estimates the path x₀ … x_j, z_{t−2} … z₀ as
//!
//! β_C(y) · f_y(ω_o, ω_photon) · β_L · (|n_s · ω_photon| / |n_g · ω_photon|) / (π r² N_L),
//!
//! the uniform disk kernel (the last factor before it converts the photon's flux, which
//! arrives through the geometric normal, to the shading normal the BSDF is used with).
//! Its bias is O(r²) where radiance is smooth, and vanishes as r_i shrinks.
//!
//! - **PPM** (`ppm`): merge at the first non-Dirac camera vertex only, no MIS. Emission
//!   is counted only where every camera vertex before it is Dirac (a light seen directly
//!   or through mirrors and glass); everything else is the photons' job.
//! - **BPM** (`bpm`): merge at every non-Dirac camera vertex, plus camera paths that
//!   reach emitters; the balance heuristic over the merges (and emission) of a path.
//! - **VCM** (`vcm`): BDPT's connections (s = 0, next-event estimation, the pixel's own
//!   light path joined at every pair of vertices, light tracing splatted from the light
//!   phase) plus every merge, all under one balance heuristic with η = N_L π r² as the
//!   merge's relative sample count ([`mis`]).
//!
//! The counts n_s of the connection techniques are those of BDPT (one light path per
//! camera sample; light tracing N_L / (W·H)). With merging off VCM's weights are BDPT's,
//! with connections off BPM's (tests/tests/vcm_mis.rs).

pub mod mis;
mod phases;

pub use phases::Vcm;

use alloc::vec::Vec;
use core::ops::Range;

use self::mis::{CameraSums, MergeDensities, PhotonSums, Side, Techniques, connection_weight, merge_weight_from_sums, mergeable, prefix};
use crate::bsdf::TransportMode;
use crate::geometry::RayQuery;
use crate::merge::HashGrid;
use crate::path::{self, CacheEntry, LightPaths, LightPointSample, MAX_VERTICES, Vertex, VertexKind, connect, trace_light_subpath};
use crate::rng::{SampleStream, Stream};
use crate::scene::{Context, Scene};
use crate::spectrum::Rgb;
use crate::transport::{Counters, RenderParams, Splat};

/// Which vertex-merging estimator: part of the configuration, so defined with it (the
/// configurations compile without the `merging` feature).
pub use crate::estimators::MergeMode;

/// Photons on surfaces turned more than about 37° from the camera vertex's are not
/// merged: within a ball of radius r they lie on another surface (the other wall of a
/// corner, a small sphere and the wall behind it), whose photons the disk kernel would
/// count as if they were on this one. Measured on the Cornell box, PPM at 10 s: relMSE
/// 2.82e-3 → 1.78e-3, image mean 1.0036 → 0.9955 of the reference (the corners' excess
/// becomes a small deficit: the disk is normalised as if whole). As r → 0 on a smooth
/// surface every photon passes, so the estimator stays consistent.
pub const MIN_NORMAL_COSINE: f32 = 0.8;

/// What the camera phase of one pass reads.
#[derive(Clone, Copy, Debug)]
pub struct PassInputs<'a> {
    /// The pass's light paths.
    pub paths: &'a LightPaths,
    /// Prefix sums B per light vertex ([`mis::prefix`]), parallel to `paths.vertices`.
    pub prefix: &'a [f64],
    /// What merges read of each photon, in the grid's slot order.
    pub photons: &'a [Photon],
    /// The grid over the photons' end points, built for this pass's radius.
    pub grid: &'a HashGrid,
    /// Technique counts (η included).
    pub tech: Techniques,
    /// N_L.
    pub light_paths: u32,
}

/// Trace light paths `paths` of pass `pass` into `out` (with their prefix sums) and,
/// where light tracing is on, splat their pinhole connections (scaled by 1/N_L by the
/// host).
#[allow(clippy::too_many_arguments)]
pub fn trace_light_paths<Q: RayQuery + ?Sized>(
    scene: &Scene,
    tracer: &Q,
    params: &RenderParams,
    tech: &Techniques,
    pass: u32,
    paths: Range<u32>,
    out: &mut LightPaths,
    prefix_out: &mut Vec<f64>,
    splat: &mut dyn FnMut(Splat),
) -> Counters {
    let mut counters = Counters::default();
    let ctx = Context { scene, tracer };
    let mut b = [0.0f64; MAX_VERTICES];
    for index in paths {
        let light = trace_light_subpath(scene, tracer, params, Stream::Light, index, pass, &mut counters);
        let b = &mut b[..light.len()];
        prefix(scene, &light, Side::Light, tech, b);
        out.push(&light);
        prefix_out.extend_from_slice(b);
        if !(tech.light_tracing > 0.0) {
            continue;
        }
        let mut lens = crate::camera::lens_stream(params.seed, index, pass);
        for s in 2..=light.len() {
            if !params.max_depth.allows(s as u32) {
                break;
            }
            let u = LightPointSample::lens(&scene.camera, &mut lens);
            let Some(c) = connect(&ctx, &light[..s], &[], s, 1, u, &mut counters) else { continue };
            let w = connection_weight(scene, tech, &light, b, &[], &[], c.sampled.as_ref(), s, 1);
            if let Some(film) = c.film {
                splat(Splat { film, value: counters.sanitize(c.value * w) });
            }
        }
    }
    counters
}

/// What a merge reads of a light vertex x_j (compact, stored in the grid's slot order
/// so that a query reads its photons contiguously).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Photon {
    /// Unit direction toward x_{j−1} (where the light came from).
    pub wo: crate::math::Vec3,
    /// Throughput of the light path on arrival.
    pub beta: Rgb,
    /// Geometric normal at the photon (either orientation).
    pub n: crate::math::Vec3,
    /// j: segments of the light path.
    pub depth: u32,
    /// Its part of the merge weight.
    pub sums: PhotonSums,
}

impl Photon {
    /// The record of photon `e` of `paths` (prefix sums `prefix`), with its part of the
    /// merge weight where `weighted` gives the techniques. PPM weighs nothing (its weight
    /// is 1) and leaves the sums at zero: on spot_mirror they were about a tenth of its
    /// time, on the thread that builds the records.
    pub fn new(scene: &Scene, weighted: Option<&Techniques>, paths: &LightPaths, prefix: &[f64], e: &CacheEntry) -> Self {
        let (light, j) = (e.subpath(paths), e.s as usize - 1);
        let x = &light[j];
        let sums = match weighted {
            Some(tech) => PhotonSums::new(scene, tech, light, &prefix[e.start as usize..][..light.len()], j),
            None => PhotonSums::default(),
        };
        Self { wo: x.wo, beta: x.beta, n: x.ng, depth: j as u32, sums }
    }
}

/// The end point of photon `e`.
#[inline]
pub fn photon_position(paths: &LightPaths, e: &CacheEntry) -> crate::math::Vec3 {
    e.subpath(paths)[e.s as usize - 1].p
}

/// One sample of `mode` for each pixel in `pixels` of pass `pass` into `out`.
#[allow(clippy::too_many_arguments)]
pub fn render_pixels<Q: RayQuery + ?Sized>(
    scene: &Scene,
    tracer: &Q,
    params: &RenderParams,
    mode: MergeMode,
    inputs: &PassInputs,
    pass: u32,
    pixels: Range<u32>,
    out: &mut [Rgb],
) -> Counters {
    let mut counters = Counters::default();
    let (max_camera, _) = path::vertex_budgets(params);
    let ctx = Context { scene, tracer };
    let tech = &inputs.tech;
    let radius = inputs.grid.radius();
    let kernel = 1.0 / (core::f32::consts::PI * radius * radius * inputs.light_paths.max(1) as f32);
    let mut camera_b = [0.0f64; MAX_VERTICES];
    for (slot, pixel) in out.iter_mut().zip(pixels) {
        let camera = path::pixel_camera_subpath(scene, tracer, params, pixel, pass, max_camera, &mut counters);
        let camera_b = &mut camera_b[..camera.len()];
        prefix(scene, &camera, Side::Camera, tech, camera_b);
        // The pixel's own light path, for connections.
        let own = (pixel % inputs.light_paths.max(1)) as usize;
        let (light, light_b): (&[Vertex], &[f64]) = if own < inputs.paths.len() {
            let light = inputs.paths.path(own);
            (light, &inputs.prefix[inputs.paths.starts[own] as usize..][..light.len()])
        } else {
            (&[], &[])
        };
        let mut aux = SampleStream::for_sample(params.seed, Stream::Aux, pixel, pass, 0);
        let mut l = Rgb::ZERO;
        for t in 2..=camera.len() {
            if !params.max_depth.allows(t as u32 - 1) {
                break;
            }
            let y = &camera[t - 1];
            let (u_light, u_point) = (aux.next_f32(), aux.next_2d());
            // s = 0: the camera path reached an emitter.
            let all_dirac_before = camera[1..t - 1].iter().all(|v| v.delta);
            if y.is_light()
                && (mode != MergeMode::Ppm || all_dirac_before)
                && let Some(c) = connect(&ctx, &[], &camera, 0, t, LightPointSample::default(), &mut counters)
            {
                let w = if mode == MergeMode::Ppm { 1.0 } else { connection_weight(scene, tech, &[], &[], &camera, camera_b, None, 0, t) };
                l += counters.sanitize(c.value * w);
            }
            if y.kind == VertexKind::InfiniteLight {
                break;
            }
            if mode == MergeMode::Vcm && tech.connection > 0.0 {
                // s = 1 (a fresh light sample) and s ≥ 2 (the pixel's light path).
                for s in 1..=light.len().max(1) {
                    if !params.max_depth.allows((s + t - 1) as u32) {
                        break;
                    }
                    let u = LightPointSample { u_light, u_point };
                    let Some(c) = connect(&ctx, light, &camera, s, t, u, &mut counters) else { continue };
                    let w = connection_weight(scene, tech, light, light_b, &camera, camera_b, c.sampled.as_ref(), s, t);
                    l += counters.sanitize(c.value * w);
                }
            }
            if tech.merge > 0.0 && mergeable(scene, y) {
                l += merge_at(scene, mode, inputs, &camera, camera_b, t, kernel, params, &mut counters);
                if mode == MergeMode::Ppm {
                    break;
                }
            }
        }
        *slot = l;
    }
    counters
}

/// Σ over the photons within r of camera vertex `camera[t − 1]` of their weighted
/// merge estimates.
#[allow(clippy::too_many_arguments)]
fn merge_at(
    scene: &Scene,
    mode: MergeMode,
    inputs: &PassInputs,
    camera: &[Vertex],
    camera_b: &[f64],
    t: usize,
    kernel: f32,
    params: &RenderParams,
    counters: &mut Counters,
) -> Rgb {
    let y = &camera[t - 1];
    let material = scene.material(y.material, y.uv);
    let wo = y.frame.to_local(y.wo);
    // PPM's weight is 1: no sums and no densities.
    let sums = (mode != MergeMode::Ppm).then(|| CameraSums::new(scene, &inputs.tech, camera, camera_b, t));
    let mut sum = Rgb::ZERO;
    inputs.grid.query_slots(y.p, |k| {
        let photon = &inputs.photons[k as usize];
        if !params.max_depth.allows(photon.depth + t as u32 - 1) || photon.n.dot(y.ng).abs() < MIN_NORMAL_COSINE {
            return;
        }
        let wi = y.frame.to_local(photon.wo);
        // With the camera's sums, the densities that weigh this photon against them.
        let (f, weighing) = match &sums {
            None => (material.eval(wo, wi, TransportMode::Radiance), None),
            Some(sums) => {
                let (f, toward_light, toward_camera) = material.eval_pdfs(wo, wi, TransportMode::Radiance);
                (f, Some((sums, MergeDensities { toward_light, toward_camera })))
            }
        };
        if f.is_black() {
            return;
        }
        let cos_g = y.ng.dot(photon.wo).abs();
        let correction = if cos_g > 0.0 { wi.z.abs() / cos_g } else { 0.0 };
        let w = weighing.map_or(1.0, |(sums, d)| merge_weight_from_sums(&inputs.tech, &photon.sums, sums, d));
        sum += counters.sanitize(y.beta * f * photon.beta * (correction * kernel * w));
    });
    sum
}
