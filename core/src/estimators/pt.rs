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
//!
//! The paths run on the lane loop ([`crate::transport::lanes`]): a batch of a chunk's
//! pixels in flight, their closest-hit rays and their next-event shadow rays asked in
//! batches, a finished lane refilled with the next pixel. One path's steps are the same
//! whatever runs beside it, so the image is the same at every batch width.

use core::ops::Range;

use super::pt_lanes;
use crate::bsdf::{Material, TransportMode};
use crate::geometry::{Ray, RayQuery, SurfaceHit};
use crate::math::Vec3;
use crate::rng::{SampleStream, Stream};
use crate::scene::Scene;
use crate::segment::{CAMERA_KERNEL_KEY, Junctions, Kernel, start_cosine};
use crate::spectrum::Rgb;
use crate::transport::lanes::{self, Arrival, LaneProgram};
use crate::transport::walk::{Bounce, LastBounce, Leave, Moved, PathState, Roulette, Walk, light_origin, shadow_ray};
use crate::transport::{Counters, RenderParams, SurfacePoint};

/// PT's walk: radiance, 8 dimensions per bounce (light choice 1, light point 2, lobe 1,
/// direction 2, roulette 1).
const WALK: Walk = Walk { mode: TransportMode::Radiance, layout: pt_lanes::LAYOUT };

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
    let items = pixels.start..pixels.start.saturating_add(out.len() as u32).min(pixels.end);
    // Paths in flight: what the tracer asks for, or more where the shading runs over
    // SIMD lanes (`pt_lanes`: PT's own vertices, not a segment kernel's moved starts; no
    // medium).
    let lanes_pay = kernel == Kernel::Dirac && scene.interiors.is_empty();
    let width = tracer.batch_width().max(if lanes_pay { params.simd.paths_in_flight() } else { 1 });
    let mut scratch;
    let lanes = if width > 1 && lanes_pay {
        scratch = pt_lanes::Scratch::new();
        Some(&mut scratch)
    } else {
        None
    };
    let mut paths = CameraPaths { scene, tracer, params, kernel, pass, first: pixels.start, out, counters: Counters::default(), lanes };
    let steps = lanes::run_with_width(&mut paths, tracer, items, width);
    paths.counters.lanes += steps;
    paths.counters
}

/// Radiance arriving along `ray` (a camera ray), estimated by one path.
pub fn radiance<Q: RayQuery + ?Sized>(scene: &Scene, tracer: &Q, params: &RenderParams, ray: Ray, rng: &mut SampleStream, counters: &mut Counters) -> Rgb {
    if !params.max_depth.allows(1) {
        return Rgb::ZERO;
    }
    let mut paths = CameraPaths { scene, tracer, params, kernel: Kernel::Dirac, pass: 0, first: 0, out: &mut [], counters: Counters::default(), lanes: None };
    let state = PathState::new(ray, Rgb::ONE, rng.dimension() + WALK.layout.per_bounce);
    let path = CameraPath { pixel: 0, rng: rng.clone(), junctions: None, state, l: Rgb::ZERO, pending: Rgb::ZERO };
    let path = lanes::run_one(&mut paths, tracer, path);
    *rng = path.rng;
    *counters += paths.counters;
    path.l
}

/// PT's camera paths over a range of pixels, on the lane loop: the camera walk of PT and
/// of segment PT ([`crate::estimators::segment::spt`]) on the one walk
/// ([`crate::transport::walk`]). With no kernel (the Dirac kernel) each segment starts
/// where the previous one ended, which is path tracing; otherwise each next segment
/// starts at a point the kernel draws around the end of the previous one (eq. 15's p_K),
/// from a random stream of its own, so the walk's own random numbers keep PT's layout.
/// What PT records per vertex: emission weighted against light sampling, and next-event
/// estimation.
struct CameraPaths<'a, Q: ?Sized> {
    scene: &'a Scene,
    tracer: &'a Q,
    params: &'a RenderParams,
    kernel: Kernel,
    pass: u32,
    /// The pixel of `out[0]`.
    first: u32,
    out: &'a mut [Rgb],
    counters: Counters,
    /// Room for shading over lanes (`None`: one path at a time).
    lanes: Option<&'a mut pt_lanes::Scratch>,
}

/// One pixel's camera path in flight.
struct CameraPath {
    pixel: u32,
    rng: SampleStream,
    junctions: Option<Junctions>,
    state: PathState,
    /// Radiance gathered so far.
    l: Rgb,
    /// β times the next-event sample waiting for its shadow ray.
    pending: Rgb,
}

impl<Q: RayQuery + ?Sized> LaneProgram for CameraPaths<'_, Q> {
    type Path = CameraPath;

    fn start(&mut self, pixel: u32) -> Option<CameraPath> {
        let width = self.scene.camera.width().max(1);
        let mut rng = SampleStream::for_sample(self.params.seed, Stream::Camera, pixel, self.pass, 0);
        // Draw the film point in the pixel (and a lens point).
        let Some(primary) = self.scene.camera.sample_ray(pixel % width, pixel / width, &mut rng) else {
            self.write(pixel, Rgb::ZERO);
            return None;
        };
        // max_depth 0 allows no segment at all: not even the camera ray (black, as Mitsuba).
        if !self.params.max_depth.allows(1) {
            let black = self.counters.sanitize(Rgb::ZERO);
            self.write(pixel, black);
            return None;
        }
        let junctions = Junctions::for_path(self.kernel, self.params.seed, pixel, self.pass, CAMERA_KERNEL_KEY);
        let state = PathState::new(primary.ray, Rgb::ONE, rng.dimension() + WALK.layout.per_bounce);
        Some(CameraPath { pixel, rng, junctions, state, l: Rgb::ZERO, pending: Rgb::ZERO })
    }

    fn ray(&self, path: &CameraPath) -> Ray {
        path.state.ray
    }

    fn arrive(&mut self, path: &mut CameraPath, hit: Option<SurfaceHit>) -> Arrival {
        match self.reach(path, hit) {
            Reached::Done(arrival) => arrival,
            Reached::Surface(v) => {
                let material = v.sp.material(self.scene);
                self.shade(path, &v, &material)
            }
        }
    }

    fn arrive_batch(&mut self, lanes: &mut [Option<CameraPath>], lane_of: &[u8], hits: &[Option<SurfaceHit>], arrivals: &mut [Arrival]) {
        let Some(scratch) = self.lanes.take() else { return lanes::arrive_each(self, lanes, lane_of, hits, arrivals) };
        let batch = &mut scratch.batch;
        batch.clear();
        for (k, hit) in hits.iter().enumerate() {
            let path = lanes[lane_of[k] as usize].as_mut().expect("a traced lane holds a path");
            match self.reach(path, *hit) {
                Reached::Done(arrival) => arrivals[k] = arrival,
                Reached::Surface(v) => {
                    let material = v.sp.material(self.scene);
                    match material.lambertian() {
                        // `lanes` exists only without a segment kernel (`moved` is then
                        // always `None`) and without a medium.
                        Some(lobe) if v.moved.is_none() => {
                            batch.push(k as u8, &v.sp, lobe, path.rng.base(), path.state.dimension(&WALK.layout, 0));
                        }
                        _ => arrivals[k] = self.shade(path, &v, &material),
                    }
                }
            }
        }
        if scratch.len() > 0 {
            self.counters.lanes.shaded += scratch.len() as u64;
            pt_lanes::shade(self.scene, self.params, scratch);
            for i in 0..scratch.len() {
                let v = scratch.lane(i);
                let path = lanes[lane_of[v.slot] as usize].as_mut().expect("a traced lane holds a path");
                arrivals[v.slot] = self.leave_lambertian(path, &v);
            }
        }
        self.lanes = Some(scratch);
    }

    fn leave(&mut self, path: &mut CameraPath, arrival: Arrival, occluded: Option<bool>) -> bool {
        if occluded == Some(false) {
            path.l += path.pending;
        }
        arrival.continues
    }

    fn finish(&mut self, path: CameraPath) {
        // The film spreads the sample under the pixel filter (`render::Film`).
        let value = self.counters.sanitize(path.l);
        self.write(path.pixel, value);
    }
}

impl<'a, Q: RayQuery + ?Sized> CameraPaths<'a, Q> {
    fn write(&mut self, pixel: u32, value: Rgb) {
        if let Some(slot) = self.out.get_mut(pixel.wrapping_sub(self.first) as usize) {
            *slot = value;
        }
    }

    /// The first half of an arrival: the emission found (or the sky), the medium
    /// crossed, and where the next segment starts; `Done` if the path ends here.
    #[inline(always)]
    fn reach(&mut self, path: &mut CameraPath, hit: Option<SurfaceHit>) -> Reached {
        let (scene, params) = (self.scene, self.params);
        let end = Reached::Done(Arrival { shadow: None, continues: false });
        let ray = path.state.ray;
        self.counters.rays += 1;
        let Some(hit) = hit else {
            // Escaped: add the infinite lights, weighted against light sampling.
            for (id, light) in scene.infinite_lights() {
                let le = light.environment_radiance(ray.dir);
                if le.is_black() {
                    continue;
                }
                let w =
                    emission_weight(params, path.state.last, || scene.light_pmf(id) * light.pdf_li(prev_p(path.state.last), ray.dir, Vec3::ZERO, Vec3::ZERO).0);
                path.l += path.state.beta * le * w;
            }
            return end;
        };
        let sp = SurfacePoint::new(hit, -ray.dir);
        // Attenuate by an absorbing medium the segment crossed.
        Walk::pass_medium(scene, &mut path.state, &hit);

        // Add emission found by BSDF sampling (or seen directly).
        if let Some(id) = hit.emitter {
            let light = &scene.lights[id as usize];
            let le = light.radiance(hit.p, hit.ng, -ray.dir);
            if !le.is_black() {
                let w = emission_weight(params, path.state.last, || scene.light_pmf(id) * light.pdf_li(prev_p(path.state.last), ray.dir, hit.p, hit.ng).0);
                path.l += path.state.beta * le * w;
            }
        }
        if !params.max_depth.allows(path.state.segments + 1) {
            return end;
        }
        // Start the next segment: at this vertex, or where the kernel puts it.
        let moved = WALK.junction(self.tracer, &mut path.state, &hit, path.junctions.as_mut(), &mut self.counters);
        Reached::Surface(Vertex { sp, moved })
    }

    /// The second half: next-event estimation and the BSDF sample that continues the
    /// path, one path at a time.
    #[inline(always)]
    fn shade(&mut self, path: &mut CameraPath, v: &Vertex, material: &Material) -> Arrival {
        let sp = &v.sp;
        let start = v.moved.as_ref().map(|m| &m.at);

        // Sample a light (next-event estimation) unless the BSDF is all Dirac; its
        // shadow ray is tested with the batch's.
        let wo_local = sp.frame.to_local(sp.wo);
        let mut shadow = None;
        if !material.is_delta() {
            let at = Shading { sp, material, wo_local, start };
            if let Some((ray, value)) = self.next_event(&path.state, &at, &mut path.rng) {
                path.pending = path.state.beta * value;
                shadow = Some(ray);
            }
        }

        // Sample the BSDF to continue the path.
        let roulette = Roulette::Throughput { reference: 1.0 };
        let continues = matches!(WALK.scatter(self.params, &mut path.state, sp, wo_local, material, start, roulette, &mut path.rng), Leave::Continues(_));
        Arrival { shadow, continues }
    }

    /// A Lambertian vertex's arrival from what the lane shading found for it
    /// (`pt_lanes`): its next-event sample pending, and `Walk::scatter`'s continuation
    /// (roulette by throughput, reference 1) from its BSDF sample.
    #[inline(always)]
    fn leave_lambertian(&mut self, path: &mut CameraPath, v: &pt_lanes::Shaded1) -> Arrival {
        let layout = WALK.layout;
        let mut shadow = None;
        if let Some((value, ray)) = v.nee {
            self.counters.rays += 1;
            path.pending = path.state.beta * value;
            shadow = Some(ray);
        }
        // Where `Walk::scatter`'s draw leaves the stream (the lobe and the direction).
        path.rng.set_dimension(path.state.dimension(&layout, layout.lobe + 3));
        let Some((throughput, wi, pdf)) = v.bounce else { return Arrival { shadow, continues: false } };
        let bounce = Bounce { wi, pdf, delta: false, throughput };
        let roulette = Roulette::Throughput { reference: 1.0 };
        let continues = matches!(WALK.advance(self.params, &mut path.state, bounce, v.p, v.ng, roulette, &mut path.rng), Leave::Continues(_));
        Arrival { shadow, continues }
    }

    /// One light sample from `at.sp` at the path's current bounce: choose a light ∝
    /// power, sample a point on it, weight against BSDF sampling. Returns the shadow ray
    /// and the weighted contribution (without β) it carries if unoccluded. With a
    /// kernel-moved `start` (segment PT) the light is sampled from there, the BSDF is
    /// still the one of `sp` (eq. 6) and the cosine the one at `start`.
    #[inline(always)]
    fn next_event(&mut self, path: &PathState, at: &Shading, rng: &mut SampleStream) -> Option<(Ray, Rgb)> {
        let (sp, start) = (at.sp, at.start);
        let from = start.unwrap_or(&sp.hit);
        // Seen from where reflected rays start (see `SurfacePoint::reflection_origin`).
        let draw = WALK.draw_light(self.scene, path, light_origin(from, sp.wo), rng)?;
        let ls = &draw.sample;
        // f |cos| (eq. 6): the BSDF at `sp`, the cosine at the segment's start.
        let wi_local = sp.frame.to_local(ls.wi);
        // The BSDF's density is needed for the MIS weight unless the light is a Dirac
        // one; evaluating both together shares their common terms (bit-identical).
        let (f, bsdf_pdf) = if ls.is_delta {
            (at.material.eval(at.wo_local, wi_local, TransportMode::Radiance), 0.0)
        } else {
            let (f, pdf) = at.material.eval_pdf(at.wo_local, wi_local, TransportMode::Radiance);
            (f, pdf.0)
        };
        if f.is_black() {
            return None;
        }
        let f = f * start_cosine(sp, start, ls.wi, wi_local, TransportMode::Radiance);
        self.counters.rays += 1;
        let light_pdf = draw.pmf * ls.pdf.0;
        let w = if ls.is_delta { 1.0 } else { self.params.heuristic.weight(light_pdf, bsdf_pdf) };
        // Through an absorbing medium behind the vertex (a rough dielectric's interior).
        let tr = self.scene.transmittance_to(ls.p, from.p, from.ng, sp.hit.material).unwrap_or(Rgb::ONE);
        Some((shadow_ray(from, ls), f * ls.radiance * tr * (w / light_pdf)))
    }
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

/// What [`CameraPaths::reach`] leaves for shading.
enum Reached {
    /// The path ends at this step: its arrival.
    Done(Arrival),
    /// It reached a surface it may continue from.
    Surface(Vertex),
}

/// A surface a path reached: the shading point and where a segment kernel moved the
/// next segment's start.
struct Vertex {
    sp: SurfacePoint,
    moved: Option<Moved>,
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
