//! Path tracing with next-event estimation.
//!
//! Estimates the pixel measurement I = ∫ W_e L dA dω by walking a path from the camera.
//! At each non-Dirac vertex two techniques reach an emitter: sampling a light (pick a
//! light ∝ power, then a point on it: density p_L = P(light) · p_light(ω), per solid
//! angle) and sampling the BSDF (p_B(ω), per solid angle), which continues the walk.
//! Both estimates of the emitted radiance are combined by one-sample-each MIS with the
//! balance or power heuristic, w_L = h(p_L, p_B), w_B = h(p_B, p_L) (Veach 1997,
//! eq. 9.13/9.14); emitters reached after a Dirac bounce, or seen directly, carry weight 1.
//! Throughput β = Π f |cos θ| / p_B; Russian roulette from `rr_depth` keeps it unbiased.

use core::ops::Range;

use crate::bsdf::{Material, TransportMode};
use crate::geometry::{Ray, RayQuery, SurfaceHit};
use crate::math::Vec3;
use crate::rng::{SampleStream, Stream};
use crate::scene::Scene;
use crate::segment::{CAMERA_KERNEL_KEY, Junctions, Kernel, start_cosine};
use crate::spectrum::Rgb;
use crate::transport::walk::{LastBounce, Layout, Leave, PathState, Roulette, Walk, light_origin, shadow_ray};
use crate::transport::{Counters, RenderParams, SurfacePoint};

/// PT's walk: radiance, 8 dimensions per bounce (light choice 1, light point 2, lobe 1,
/// direction 2, roulette 1).
const WALK: Walk = Walk { mode: TransportMode::Radiance, layout: Layout { per_bounce: 8, light: 0, lobe: 3, roulette: 6 } };

/// Render one sample for each pixel in `pixels` (index y·width + x) of pass `pass`
/// into `out[i − pixels.start]`.
pub fn render_pixels<Q: RayQuery + ?Sized>(scene: &Scene, tracer: &Q, params: &RenderParams, pass: u32, pixels: Range<u32>, out: &mut [Rgb]) -> Counters {
    render_pixels_with_kernel(scene, tracer, params, Kernel::Dirac, pass, pixels, out)
}

/// [`render_pixels`] with `kernel` joining consecutive segments: segment PT
/// ([`crate::estimators::segment::spt`]); with the Dirac kernel it is PT.
pub(crate) fn render_pixels_with_kernel<Q: RayQuery + ?Sized>(
    scene: &Scene,
    tracer: &Q,
    params: &RenderParams,
    kernel: Kernel,
    pass: u32,
    pixels: Range<u32>,
    out: &mut [Rgb],
) -> Counters {
    let mut counters = Counters::default();
    let width = scene.camera.width().max(1);
    for (slot, pixel) in out.iter_mut().zip(pixels) {
        let mut rng = SampleStream::for_sample(params.seed, Stream::Camera, pixel, pass, 0);
        // Draw the film point in the pixel (and a lens point).
        let Some(primary) = scene.camera.sample_ray(pixel % width, pixel / width, &mut rng) else {
            *slot = Rgb::ZERO;
            continue;
        };
        let mut junctions = Junctions::for_path(kernel, params.seed, pixel, pass, CAMERA_KERNEL_KEY);
        let l = walk(scene, tracer, params, primary.ray, &mut rng, junctions.as_mut(), &mut counters);
        // The film spreads the sample under the pixel filter (`render::Film`).
        *slot = counters.sanitize(l);
    }
    counters
}

/// Radiance arriving along `ray` (a camera ray), estimated by one path.
pub fn radiance<Q: RayQuery + ?Sized>(scene: &Scene, tracer: &Q, params: &RenderParams, ray: Ray, rng: &mut SampleStream, counters: &mut Counters) -> Rgb {
    walk(scene, tracer, params, ray, rng, None, counters)
}

/// The camera walk of PT and of segment PT ([`crate::estimators::segment::spt`]) on the one walk
/// ([`crate::transport::walk`]): with `junctions` `None` (the Dirac kernel) each segment
/// starts where the previous one ended, which is path tracing; otherwise each next
/// segment starts at a point the kernel draws around the end of the previous one (eq.
/// 15's p_K), from a random stream of its own, so the walk's own random numbers keep PT's
/// layout. What PT records per vertex: emission weighted against light sampling, and
/// next-event estimation.
fn walk<Q: RayQuery + ?Sized>(
    scene: &Scene,
    tracer: &Q,
    params: &RenderParams,
    ray: Ray,
    rng: &mut SampleStream,
    mut junctions: Option<&mut Junctions>,
    counters: &mut Counters,
) -> Rgb {
    let mut l = Rgb::ZERO;
    // max_depth 0 allows no segment at all: not even the camera ray (black, as Mitsuba).
    if !params.max_depth.allows(1) {
        return l;
    }
    let first_dim = rng.dimension();
    let mut path = PathState::new(ray, Rgb::ONE, first_dim + WALK.layout.per_bounce);
    loop {
        let ray = path.ray;
        let Some(hit) = WALK.trace(tracer, &path, counters) else {
            // Escaped: add the infinite lights, weighted against light sampling.
            for (id, light) in scene.infinite_lights() {
                let le = light.environment_radiance(ray.dir);
                if le.is_black() {
                    continue;
                }
                let w = emission_weight(params, path.last, || scene.light_pmf(id) * light.pdf_li(prev_p(path.last), ray.dir, Vec3::ZERO, Vec3::ZERO).0);
                l += path.beta * le * w;
            }
            break;
        };
        let sp = SurfacePoint::new(hit, -ray.dir);

        // Add emission found by BSDF sampling (or seen directly).
        if let Some(id) = hit.emitter {
            let light = &scene.lights[id as usize];
            let le = light.radiance(hit.p, hit.ng, -ray.dir);
            if !le.is_black() {
                let w = emission_weight(params, path.last, || scene.light_pmf(id) * light.pdf_li(prev_p(path.last), ray.dir, hit.p, hit.ng).0);
                l += path.beta * le * w;
            }
        }
        if !params.max_depth.allows(path.segments + 1) {
            break;
        }
        let material = sp.material(scene);

        // Start the next segment: at this vertex, or where the kernel puts it.
        let moved = WALK.junction(tracer, &mut path, &hit, junctions.as_deref_mut(), counters);
        let start = moved.as_ref().map(|m| &m.at);

        // Sample a light (next-event estimation) unless the BSDF is all Dirac.
        let wo_local = sp.frame.to_local(sp.wo);
        if !material.is_delta() {
            let at = Shading { sp: &sp, material: &material, wo_local, start };
            l += path.beta * next_event(scene, tracer, params, &path, &at, rng, counters);
        }

        // Sample the BSDF to continue the path.
        let roulette = Roulette::Throughput { reference: 1.0 };
        let Leave::Continues(_) = WALK.scatter(params, &mut path, &sp, wo_local, &material, start, roulette, rng) else { break };
    }
    l
}

#[inline]
fn prev_p(prev: Option<LastBounce>) -> Vec3 {
    prev.map_or(Vec3::ZERO, |p| p.origin)
}

/// MIS weight of emission reached by the BSDF-sampled segment from `prev`.
#[inline]
fn emission_weight(params: &RenderParams, prev: Option<LastBounce>, light_pdf: impl FnOnce() -> f32) -> f32 {
    match prev {
        None => 1.0,
        Some(p) if p.delta => 1.0,
        Some(p) => params.heuristic.weight(p.pdf, light_pdf()),
    }
}

/// What next-event estimation needs of the vertex it starts from: the surface point,
/// its material (textures resolved once per vertex), the outgoing direction in the
/// shading frame, and where a kernel moved the segment's start (segment PT).
struct Shading<'a> {
    sp: &'a SurfacePoint,
    material: &'a Material,
    wo_local: Vec3,
    start: Option<&'a SurfaceHit>,
}

/// One light sample from `at.sp` at the path's current bounce: choose a light ∝ power,
/// sample a point on it, trace the shadow ray, weight against BSDF sampling. Returns the
/// weighted contribution (without β). With a kernel-moved `start` (segment PT) the light
/// is sampled from there, the BSDF is still the one of `sp` (eq. 6) and the cosine the
/// one at `start`.
fn next_event<Q: RayQuery + ?Sized>(
    scene: &Scene,
    tracer: &Q,
    params: &RenderParams,
    path: &PathState,
    at: &Shading,
    rng: &mut SampleStream,
    counters: &mut Counters,
) -> Rgb {
    let (sp, start) = (at.sp, at.start);
    let from = start.unwrap_or(&sp.hit);
    // Seen from where reflected rays start (see `SurfacePoint::reflection_origin`).
    let Some(draw) = WALK.draw_light(scene, path, light_origin(from, sp.wo), rng) else { return Rgb::ZERO };
    let ls = &draw.sample;
    // f |cos| (eq. 6): the BSDF at `sp`, the cosine at the segment's start.
    let wi_local = sp.frame.to_local(ls.wi);
    // The BSDF's density is needed for the MIS weight unless the light is a Dirac one;
    // evaluating both together shares their common terms (bit-identical).
    let (f, bsdf_pdf) = if ls.is_delta {
        (at.material.eval(at.wo_local, wi_local, TransportMode::Radiance), 0.0)
    } else {
        let (f, pdf) = at.material.eval_pdf(at.wo_local, wi_local, TransportMode::Radiance);
        (f, pdf.0)
    };
    if f.is_black() {
        return Rgb::ZERO;
    }
    let f = f * start_cosine(sp, start, ls.wi, wi_local, TransportMode::Radiance);
    counters.rays += 1;
    if tracer.occluded(&shadow_ray(from, ls)) {
        return Rgb::ZERO;
    }
    let light_pdf = draw.pmf * ls.pdf.0;
    let w = if ls.is_delta { 1.0 } else { params.heuristic.weight(light_pdf, bsdf_pdf) };
    f * ls.radiance * (w / light_pdf)
}
