//! Denoiser guides: per pixel, the albedo and shading normal of the first non-specular
//! surface seen, in the form Intel Open Image Denoise takes as its `albedo` and `normal`
//! auxiliary images.
//!
//! A camera ray is followed through Dirac bounces (mirrors, glass, smooth plastic's mirror
//! lobe when drawn), at most [`MAX_SPECULAR`] of them, to the first surface with a
//! continuous lobe. There the guide is the material's reflectance-like colour at its
//! texture coordinates ([`crate::bsdf::Material::albedo_hint`], clamped to [0, 1]) and the
//! world-space shading normal facing the ray. A ray that escapes, or stays on Dirac
//! surfaces, gives zero for both: OIDN reads zero albedo as "no texture detail to keep".
//! Each pixel averages `samples` camera rays drawn as the estimators draw them (film points
//! uniform in the pixel, and the lens; the pixel filter is not applied); random numbers
//! come from their own stream per pixel, so the guides do not depend on the thread count
//! or on the estimator.

use crate::bsdf::TransportMode;
use crate::geometry::{RayQuery, spawn_ray};
use crate::math::{Frame, Vec3};
use crate::rng::{SampleStream, Stream};
use crate::scene::Scene;
use crate::spectrum::Rgb;
use core::ops::Range;

/// Dirac bounces followed before giving up.
pub const MAX_SPECULAR: u32 = 8;

/// Keeps the guides' random numbers apart from every estimator's camera samples.
const GUIDE_PASS: u32 = 0x6a0d_0000;

/// The guides of one ray.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Guides {
    /// Reflectance-like colour in [0, 1].
    pub albedo: Rgb,
    /// World-space unit shading normal facing the ray (zero where nothing was found).
    pub normal: Vec3,
}

/// The guides along camera ray `ray` (see the module notes).
pub fn first_surface<Q: RayQuery + ?Sized>(scene: &Scene, tracer: &Q, mut ray: crate::geometry::Ray, rng: &mut SampleStream) -> Guides {
    for _ in 0..=MAX_SPECULAR {
        let Some(hit) = tracer.intersect(&ray) else { return Guides::default() };
        let material = scene.material(hit.material, hit.uv);
        let facing = if hit.ns.dot(ray.dir) > 0.0 { -hit.ns } else { hit.ns };
        let frame = Frame::from_normal(hit.ns);
        let wo = frame.to_local(-ray.dir);
        if !material.is_delta() {
            let a = material.albedo_hint();
            let albedo = Rgb::new(a.r.clamp(0.0, 1.0), a.g.clamp(0.0, 1.0), a.b.clamp(0.0, 1.0));
            return Guides { albedo, normal: facing };
        }
        let Some(s) = material.sample(wo, rng.next_f32(), rng.next_2d(), TransportMode::Radiance) else { return Guides::default() };
        ray = spawn_ray(hit.p, hit.ng, frame.to_world(s.wi));
    }
    Guides::default()
}

/// The mean guides of `pixels` (row-major indices), `samples` rays each, written to
/// `albedo` and `normal` (one entry per pixel of the range).
pub fn render_guides<Q: RayQuery + ?Sized>(scene: &Scene, tracer: &Q, seed: u64, samples: u32, pixels: Range<u32>, albedo: &mut [Rgb], normal: &mut [Vec3]) {
    let width = scene.camera.width().max(1);
    let n = samples.max(1);
    for ((pixel, a), nrm) in pixels.zip(albedo.iter_mut()).zip(normal.iter_mut()) {
        let (mut sum_a, mut sum_n, mut sum_w) = (Rgb::ZERO, Vec3::ZERO, 0.0f32);
        for s in 0..n {
            let mut rng = SampleStream::for_sample(seed, Stream::Camera, pixel, GUIDE_PASS + s, 0);
            // The camera's own sampling: the film point in the pixel and the lens.
            let Some(primary) = scene.camera.sample_ray(pixel % width, pixel / width, &mut rng) else { continue };
            let g = first_surface(scene, tracer, primary.ray, &mut rng);
            sum_a += g.albedo;
            sum_n += g.normal;
            sum_w += 1.0;
        }
        // The mean over film points uniform in the pixel (guides ignore the pixel filter).
        let inv = if sum_w > 0.0 { 1.0 / sum_w } else { 0.0 };
        *a = sum_a * inv;
        *nrm = sum_n * inv;
    }
}
