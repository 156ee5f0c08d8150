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
use crate::geometry::{Ray, RayQuery, SurfaceHit, spawn_ray, spawn_ray_to};
use crate::math::{Vec2, Vec3};
use crate::rng::{SampleStream, Stream};
use crate::scene::Scene;
use crate::segment::{CAMERA_KERNEL_KEY, Junctions, Kernel, KernelSample, start_cosine};
use crate::spectrum::Rgb;
use crate::transport::{Counters, RenderParams, SurfacePoint, survives_roulette};

/// Random dimensions used per bounce (light choice 1, light point 2, lobe 1, direction 2, roulette 1).
const DIMS_PER_BOUNCE: u32 = 8;

/// Where the path was before the current segment, for the MIS weight of emission found
/// by BSDF sampling.
#[derive(Clone, Copy, Debug)]
struct PrevBounce {
    /// The origin of the BSDF-sampled ray (offset off the surface): light densities are
    /// evaluated from the point the ray was tested from.
    origin: Vec3,
    bsdf_pdf: f32,
    is_delta: bool,
}

/// Render one sample for each pixel in `pixels` (index y·width + x) of pass `pass`
/// into `out[i − pixels.start]`.
pub fn render_pixels<Q: RayQuery + ?Sized>(scene: &Scene, tracer: &Q, params: &RenderParams, pass: u32, pixels: Range<u32>, out: &mut [Rgb]) -> Counters {
    render_pixels_with_kernel(scene, tracer, params, Kernel::Dirac, pass, pixels, out)
}

/// [`render_pixels`] with `kernel` joining consecutive segments: segment PT
/// ([`crate::estimators::estimators::spt`]); with the Dirac kernel it is PT.
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
        // Draw the film point from the pixel filter (and a lens point); outside the
        // image the sample's weight is 0.
        let Some(primary) = scene.camera.sample_ray(pixel % width, pixel / width, &mut rng) else {
            *slot = Rgb::ZERO;
            continue;
        };
        let mut junctions = Junctions::for_path(kernel, params.seed, pixel, pass, CAMERA_KERNEL_KEY);
        let l = walk(scene, tracer, params, primary.ray, &mut rng, junctions.as_mut(), &mut counters);
        *slot = counters.sanitize(l * primary.weight);
    }
    counters
}

/// Radiance arriving along `ray` (a camera ray), estimated by one path.
pub fn radiance<Q: RayQuery + ?Sized>(scene: &Scene, tracer: &Q, params: &RenderParams, ray: Ray, rng: &mut SampleStream, counters: &mut Counters) -> Rgb {
    walk(scene, tracer, params, ray, rng, None, counters)
}

/// The camera walk of PT and of segment PT ([`crate::estimators::estimators::spt`]): with `junctions`
/// `None` (the Dirac kernel) each segment starts where the previous one ended, which is
/// path tracing; otherwise each next segment starts at a point the kernel draws around
/// the end of the previous one (eq. 15's p_K), from a random stream of its own, so the
/// walk's own random numbers keep PT's layout.
fn walk<Q: RayQuery + ?Sized>(
    scene: &Scene,
    tracer: &Q,
    params: &RenderParams,
    mut ray: Ray,
    rng: &mut SampleStream,
    mut junctions: Option<&mut Junctions>,
    counters: &mut Counters,
) -> Rgb {
    let mut l = Rgb::ZERO;
    // max_depth 0 allows no segment at all: not even the camera ray (black, as Mitsuba).
    if !params.max_depth.allows(1) {
        return l;
    }
    let mut beta = Rgb::ONE;
    let mut prev: Option<PrevBounce> = None;
    let first_dim = rng.dimension();
    // `segments` counts the segment the current ray is about to trace.
    let mut segments = 1u32;
    loop {
        counters.rays += 1;
        let Some(hit) = tracer.intersect(&ray) else {
            // Escaped: add the infinite lights, weighted against light sampling.
            for (id, light) in scene.infinite_lights() {
                let le = light.environment_radiance(ray.dir);
                if le.is_black() {
                    continue;
                }
                let w = emission_weight(params, prev, || scene.light_pmf(id) * light.pdf_li(prev_p(prev), ray.dir, Vec3::ZERO, Vec3::ZERO).0);
                l += beta * le * w;
            }
            break;
        };
        let sp = SurfacePoint::new(hit, -ray.dir);

        // Add emission found by BSDF sampling (or seen directly).
        if let Some(id) = hit.emitter {
            let light = &scene.lights[id as usize];
            let le = light.radiance(hit.p, hit.ng, -ray.dir);
            if !le.is_black() {
                let w = emission_weight(params, prev, || scene.light_pmf(id) * light.pdf_li(prev_p(prev), ray.dir, hit.p, hit.ng).0);
                l += beta * le * w;
            }
        }
        if !params.max_depth.allows(segments + 1) {
            break;
        }
        rng.set_dimension(first_dim + segments * DIMS_PER_BOUNCE);
        let material = sp.material(scene);
        let wo_local = sp.frame.to_local(sp.wo);

        // Start the next segment: at this vertex, or where the kernel puts it.
        let moved = match junctions.as_deref_mut() {
            Some(j) => {
                counters.rays += 1;
                j.sample(tracer, &hit, sp.wo)
            }
            None => KernelSample::AtEnd,
        };
        let start = moved.moved();

        // Sample a light (next-event estimation) unless the BSDF is all Dirac.
        let u_light = rng.next_f32();
        let u_point = rng.next_2d();
        if !material.is_delta() {
            let at = Shading { sp: &sp, material: &material, wo_local, start };
            l += beta * next_event(scene, tracer, params, &at, u_light, u_point, counters);
        }

        // Sample the BSDF to continue the path.
        let u_lobe = rng.next_f32();
        let u_dir = rng.next_2d();
        let Some(bs) = material.sample(wo_local, u_lobe, u_dir, TransportMode::Radiance) else { break };
        let wi = sp.frame.to_world(bs.wi);
        if !bs.pdf.is_positive() {
            break;
        }
        // f_r |cos| / p_ω, the cosine at the segment's start (eq. 6, 15).
        let cos = match start {
            None => bs.wi.z.abs(),
            Some(x) => x.ns.dot(wi).abs(),
        };
        beta *= bs.f * (cos / bs.pdf.0);
        if beta.is_black() || !beta.is_finite() {
            break;
        }
        segments += 1;
        if !survives_roulette(params, segments, &mut beta, 1.0, rng) {
            break;
        }
        ray = match start {
            None => sp.spawn(wi),
            Some(x) => spawn_ray(x.p, x.ng, wi),
        };
        prev = Some(PrevBounce { origin: ray.origin, bsdf_pdf: bs.pdf.0, is_delta: bs.is_delta });
    }
    l
}

#[inline]
fn prev_p(prev: Option<PrevBounce>) -> Vec3 {
    prev.map_or(Vec3::ZERO, |p| p.origin)
}

/// MIS weight of emission reached by the BSDF-sampled segment from `prev`.
#[inline]
fn emission_weight(params: &RenderParams, prev: Option<PrevBounce>, light_pdf: impl FnOnce() -> f32) -> f32 {
    match prev {
        None => 1.0,
        Some(p) if p.is_delta => 1.0,
        Some(p) => params.heuristic.weight(p.bsdf_pdf, light_pdf()),
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

/// One light sample from `at.sp`: choose a light ∝ power, sample a point on it, trace
/// the shadow ray, weight against BSDF sampling. Returns the weighted contribution
/// (without β). With a kernel-moved `start` (segment PT) the light is sampled from
/// there, the BSDF is still the one of `sp` (eq. 6) and the cosine the one at `start`.
fn next_event<Q: RayQuery + ?Sized>(
    scene: &Scene,
    tracer: &Q,
    params: &RenderParams,
    at: &Shading,
    u_light: f32,
    u_point: Vec2,
    counters: &mut Counters,
) -> Rgb {
    let (sp, start) = (at.sp, at.start);
    let Some(table) = scene.light_selection.as_ref() else { return Rgb::ZERO };
    let chosen = table.sample(u_light);
    let light = &scene.lights[chosen.index];
    // Seen from where reflected rays start (see `SurfacePoint::reflection_origin`).
    let origin = match start {
        None => sp.reflection_origin(),
        Some(x) => spawn_ray(x.p, x.ng, sp.wo).origin,
    };
    let Some(ls) = light.sample_li(origin, u_point) else { return Rgb::ZERO };
    if !ls.pdf.is_positive() || ls.radiance.is_black() {
        return Rgb::ZERO;
    }
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
    let shadow = match (start, ls.dist.is_finite()) {
        (None, true) => sp.spawn_to(ls.p, ls.n),
        (None, false) => sp.spawn(ls.wi),
        (Some(x), true) => spawn_ray_to(x.p, x.ng, ls.p, ls.n),
        (Some(x), false) => spawn_ray(x.p, x.ng, ls.wi),
    };
    if tracer.occluded(&shadow) {
        return Rgb::ZERO;
    }
    let light_pdf = chosen.pmf * ls.pdf.0;
    let w = if ls.is_delta { 1.0 } else { params.heuristic.weight(light_pdf, bsdf_pdf) };
    f * ls.radiance * (w / light_pdf)
}
