//! Light tracing (particle tracing), splatted to the film.
//!
//! Each light path starts on a light chosen ∝ power, at a point and direction drawn by
//! the light's emission sampler: β₀ = L_e |cos θ| / (P(light) p_A(y₀) p_ω(ω₀)). At every
//! vertex y_i it is connected to the pinhole (the t = 1 strategy of BDPT alone): the
//! contribution β_i f(y_{i−1} → y_i → c) |cos θ_i| · W_e |cos θ_c| / d² lands on the pixel
//! the connection passes through. BSDFs are evaluated in their adjoint form
//! (`TransportMode::Importance`, Veach 1997 ch. 5) with the shading-normal correction.
//! With M = W·H paths per pass, the host divides the pass's splats by M.
//!
//! Lights at infinity seen directly: a light path cannot connect a vertex at infinity to
//! the pinhole, so that term is estimated from the camera side, once per light path: a
//! film position uniform over the whole film (density 1/(W·H) per unit pixel area) and
//! its camera ray; if the ray escapes, it splats L_∞(ω)·W·H at that position, which the
//! host's 1/M makes an unbiased estimate of every pixel's directly visible sky
//! (Mitsuba's particle tracer also renders the visible environment). Its random numbers
//! come from a stream of their own, so the light paths are unchanged.
//!
//! The light paths run on the lane loop ([`crate::transport::lanes`]): a batch of a
//! chunk's paths in flight, their closest-hit rays and their camera connections' shadow
//! rays asked in batches. The first vertex's own connection and the visible-sky ray are
//! asked when a path starts.

use core::ops::Range;

use super::lt_lanes;
use crate::bsdf::{Material, TransportMode};
use crate::geometry::{Ray, RayQuery, SurfaceHit, spawn_ray_to};
use crate::math::{Vec2, Vec3};
use crate::rng::{SampleStream, Stream};
use crate::scene::Scene;
use crate::segment::{Junctions, Kernel, LIGHT_KERNEL_KEY};
use crate::spectrum::Rgb;
use crate::transport::lanes::{self, Arrival, LaneProgram};
use crate::transport::walk::{Bounce, Leave, PathState, Roulette, Walk};
use crate::transport::{Counters, RenderParams, Splat, SurfacePoint};

/// LT's walk: importance, 4 dimensions per bounce (lobe 1, direction 2, roulette 1).
const WALK: Walk = Walk { mode: TransportMode::Importance, layout: lt_lanes::LAYOUT };

/// Trace light paths `paths` of pass `pass`; every camera connection goes to `splat`.
pub fn trace_paths<Q: RayQuery + ?Sized>(
    scene: &Scene,
    tracer: &Q,
    params: &RenderParams,
    pass: u32,
    paths: Range<u32>,
    splat: &mut dyn FnMut(Splat),
) -> Counters {
    trace_paths_with_kernel(scene, tracer, params, Kernel::Dirac, pass, paths, splat)
}

/// [`trace_paths`] with `kernel` joining consecutive segments: segment LT
/// ([`crate::estimators::segment::slt`]); with the Dirac kernel it is LT.
pub(crate) fn trace_paths_with_kernel<Q: RayQuery + ?Sized>(
    scene: &Scene,
    tracer: &Q,
    params: &RenderParams,
    kernel: Kernel,
    pass: u32,
    paths: Range<u32>,
    splat: &mut dyn FnMut(Splat),
) -> Counters {
    // Paths in flight: what the tracer asks for, or more where the shading runs over
    // SIMD lanes (`lt_lanes`: a pinhole camera, no segment kernel, no medium).
    let lanes_pay = kernel == Kernel::Dirac && !scene.camera.has_lens() && scene.interiors.is_empty();
    let width = tracer.batch_width().max(if lanes_pay { params.simd.paths_in_flight() } else { 1 });
    let mut scratch;
    let lanes = if width > 1 && lanes_pay {
        scratch = lt_lanes::Scratch::new();
        Some(&mut scratch)
    } else {
        None
    };
    let mut program = LightPaths { scene, tracer, params, kernel, pass, splat, counters: Counters::default(), lanes };
    let steps = lanes::run_with_width(&mut program, tracer, paths, width);
    program.counters.lanes += steps;
    program.counters
}

/// Last key of the visible-sky stream, keeping it apart from every other `Stream::Aux` stream.
const SKY_KEY: u32 = 0x5c00;

/// The directly visible lights at infinity, from one camera ray through a film position
/// uniform over the whole film (see the module notes).
fn visible_sky<Q: RayQuery + ?Sized>(scene: &Scene, tracer: &Q, rng: &mut SampleStream, counters: &mut Counters, splat: &mut dyn FnMut(Splat)) {
    let (w, h) = (scene.camera.width() as f32, scene.camera.height() as f32);
    let film = rng.next_2d() * Vec2::new(w, h);
    let u_lens = scene.camera.lens_u(rng);
    let ray = scene.camera.generate_ray_lens(film, u_lens);
    counters.rays += 1;
    if tracer.intersect(&ray).is_some() {
        return;
    }
    let sky = scene.infinite_lights().fold(Rgb::ZERO, |acc, (_, l)| acc + l.environment_radiance(ray.dir));
    if !sky.is_black() {
        splat(Splat { film, value: counters.sanitize(sky * (w * h)) });
    }
}

/// LT's light paths over a range of path indices, on the lane loop; segment LT's
/// ([`crate::estimators::segment::slt`]) when a kernel is given: then at every surface the
/// path reaches, the next segment starts at a point the kernel draws around it, and the
/// shading point (BSDF, camera connection, continuation) moves there, which is where
/// eq. (6) evaluates f_r in light order.
struct LightPaths<'a, Q: ?Sized> {
    scene: &'a Scene,
    tracer: &'a Q,
    params: &'a RenderParams,
    kernel: Kernel,
    pass: u32,
    splat: &'a mut dyn FnMut(Splat),
    counters: Counters,
    /// Room for shading over lanes (`None`: one path at a time).
    lanes: Option<&'a mut lt_lanes::Scratch>,
}

/// One light path in flight.
struct LightPath {
    rng: SampleStream,
    /// The visible-sky stream, which also draws the lens points of camera connections.
    sky: SampleStream,
    junctions: Option<Junctions>,
    state: PathState,
    roulette: Roulette,
    /// The camera connection waiting for its shadow ray.
    pending: Option<Splat>,
}

impl<Q: RayQuery + ?Sized> LaneProgram for LightPaths<'_, Q> {
    type Path = LightPath;

    fn start(&mut self, index: u32) -> Option<LightPath> {
        let (scene, params, tracer) = (self.scene, self.params, self.tracer);
        let mut rng = SampleStream::for_sample(params.seed, Stream::Light, index, self.pass, 0);
        let mut sky = SampleStream::for_sample(params.seed, Stream::Aux, index, self.pass, SKY_KEY);
        let junctions = Junctions::for_path(self.kernel, params.seed, index, self.pass, LIGHT_KERNEL_KEY);
        let table = scene.light_selection.as_ref()?;
        if params.max_depth.allows(1) && scene.infinite_lights().next().is_some() {
            visible_sky(scene, tracer, &mut sky, &mut self.counters, self.splat);
        }
        // Sample the light path's first vertex and direction.
        let chosen = table.sample(rng.next_f32());
        let light = &scene.lights[chosen.index];
        let (u_pos, u_dir) = (rng.next_2d(), rng.next_2d());
        let es = light.sample_le(u_pos, u_dir)?;
        let pdf_pos = chosen.pmf * if es.delta_pos { 1.0 } else { es.pdf_pos.0 };
        if !(pdf_pos > 0.0) || !es.pdf_dir.is_positive() {
            return None;
        }

        // Connect the light vertex itself to the camera (a directly visible emitter).
        if params.max_depth.allows(1) && !light.is_infinite() {
            let u_lens = scene.camera.lens_u(&mut sky);
            if let Some(cs) = scene.camera.sample_wi(es.p, u_lens) {
                let le = light.radiance(es.p, es.n, cs.wi);
                let cos_light = if es.n == Vec3::ZERO { 1.0 } else { es.n.dot(cs.wi).abs() };
                let value = le * (cos_light * scene.camera.arriving_importance(&cs) / pdf_pos);
                if !value.is_black() {
                    self.counters.rays += 1;
                    if !tracer.occluded(&spawn_ray_to(es.p, es.n, cs.position, Vec3::ZERO)) {
                        (self.splat)(Splat { film: cs.film, value: self.counters.sanitize(value) });
                    }
                }
            }
        }

        let cos0 = if es.n == Vec3::ZERO { 1.0 } else { es.n.dot(es.dir).abs() };
        let beta = es.radiance * (cos0 / (pdf_pos * es.pdf_dir.0));
        let roulette = Roulette::Throughput { reference: crate::transport::light_roulette_reference(beta) };
        let ray = if es.n == Vec3::ZERO { crate::geometry::Ray::new(es.p, es.dir, f32::INFINITY) } else { crate::geometry::spawn_ray(es.p, es.n, es.dir) };
        let state = PathState::new(ray, beta, rng.dimension() + WALK.layout.per_bounce);
        Some(LightPath { rng, sky, junctions, state, roulette, pending: None })
    }

    fn ray(&self, path: &LightPath) -> Ray {
        path.state.ray
    }

    fn arrive(&mut self, path: &mut LightPath, arrived: Option<SurfaceHit>) -> Arrival {
        let Some(sp) = self.reach(path, arrived) else { return Arrival { shadow: None, continues: false } };
        let material = sp.material(self.scene);
        self.shade(path, &sp, &material)
    }

    fn arrive_batch(&mut self, lanes: &mut [Option<LightPath>], lane_of: &[u8], hits: &[Option<SurfaceHit>], arrivals: &mut [Arrival]) {
        let Some(scratch) = self.lanes.take() else { return lanes::arrive_each(self, lanes, lane_of, hits, arrivals) };
        scratch.clear();
        for (k, hit) in hits.iter().enumerate() {
            let path = lanes[lane_of[k] as usize].as_mut().expect("a traced lane holds a path");
            let Some(sp) = self.reach(path, *hit) else {
                arrivals[k] = Arrival { shadow: None, continues: false };
                continue;
            };
            let material = sp.material(self.scene);
            match material.lambertian() {
                // `lanes` exists only where the camera is a pinhole, no segment kernel
                // moves the shading point and no medium absorbs.
                Some(lobe) => {
                    let connect = self.params.max_depth.allows(path.state.segments + 1);
                    scratch.push(k as u8, &sp, lobe, path.state.beta, connect, path.rng.base(), path.state.dimension(&WALK.layout, 0));
                }
                None => arrivals[k] = self.shade(path, &sp, &material),
            }
        }
        if scratch.len() > 0 {
            self.counters.lanes.shaded += scratch.len() as u64;
            lt_lanes::shade(&self.scene.camera, self.params, scratch);
            for i in 0..scratch.len() {
                let v = scratch.lane(i);
                let path = lanes[lane_of[v.slot] as usize].as_mut().expect("a traced lane holds a path");
                arrivals[v.slot] = self.leave_lambertian(path, &v);
            }
        }
        self.lanes = Some(scratch);
    }

    fn leave(&mut self, path: &mut LightPath, arrival: Arrival, occluded: Option<bool>) -> bool {
        if let (Some(s), Some(false)) = (path.pending.take(), occluded) {
            (self.splat)(Splat { film: s.film, value: self.counters.sanitize(s.value) });
        }
        arrival.continues
    }

    fn finish(&mut self, _: LightPath) {}
}

impl<'a, Q: RayQuery + ?Sized> LightPaths<'a, Q> {
    /// The first half of an arrival: the medium crossed and the shading point (where a
    /// segment kernel moved it); `None` if the path escaped.
    #[inline(always)]
    fn reach(&mut self, path: &mut LightPath, arrived: Option<SurfaceHit>) -> Option<SurfacePoint> {
        self.counters.rays += 1;
        let arrived = arrived?;
        // Attenuate by an absorbing medium the segment crossed.
        Walk::pass_medium(self.scene, &mut path.state, &arrived);
        // The next segment starts here, or where the kernel puts it (the shading point
        // moves there, β takes the kernel's reversed ratio).
        let hit = WALK.junction(self.tracer, &mut path.state, &arrived, path.junctions.as_mut(), &mut self.counters).map_or(arrived, |m| m.at);
        Some(SurfacePoint::new(hit, -path.state.ray.dir))
    }

    /// The second half, one path at a time: the camera connection and the continuation.
    #[inline(always)]
    fn shade(&mut self, path: &mut LightPath, sp: &SurfacePoint, material: &Material) -> Arrival {
        let (scene, params) = (self.scene, self.params);
        let hit = sp.hit;
        // Connect this vertex to the camera: segments + 1 segments in all.
        let mut shadow = None;
        path.pending = None;
        if !material.is_delta() && params.max_depth.allows(path.state.segments + 1) {
            // The lens point from the auxiliary stream, so the walk's dimensions stay.
            let u_lens = scene.camera.lens_u(&mut path.sky);
            if let Some(cs) = scene.camera.sample_wi(hit.p, u_lens) {
                let f = sp.f_cos(scene, cs.wi, TransportMode::Importance);
                let value = path.state.beta * f * scene.camera.arriving_importance(&cs);
                if !value.is_black() {
                    self.counters.rays += 1;
                    shadow = Some(sp.spawn_to(cs.position, Vec3::ZERO));
                    path.pending = Some(Splat { film: cs.film, value });
                }
            }
        }
        if !params.max_depth.allows(path.state.segments + 2) {
            return Arrival { shadow, continues: false };
        }

        // Sample the adjoint BSDF to continue.
        let leave = WALK.scatter(params, &mut path.state, sp, sp.frame.to_local(sp.wo), material, None, path.roulette, &mut path.rng);
        Arrival { shadow, continues: matches!(leave, Leave::Continues(_)) }
    }

    /// A Lambertian vertex's arrival from what the lane shading found for it
    /// (`lt_lanes`): its splat pending, and `Walk::scatter`'s continuation (roulette by
    /// throughput against the path's reference) from its BSDF sample.
    #[inline(always)]
    fn leave_lambertian(&mut self, path: &mut LightPath, v: &lt_lanes::Shaded1) -> Arrival {
        let layout = WALK.layout;
        let mut shadow = None;
        path.pending = None;
        if let Some((film, value, ray)) = v.splat {
            self.counters.rays += 1;
            shadow = Some(ray);
            path.pending = Some(Splat { film, value });
        }
        if !self.params.max_depth.allows(path.state.segments + 2) {
            return Arrival { shadow, continues: false };
        }
        // Where `Walk::scatter`'s draw leaves the stream (the lobe and the direction).
        path.rng.set_dimension(path.state.dimension(&layout, layout.lobe + 3));
        let Some((throughput, wi, pdf)) = v.bounce else { return Arrival { shadow, continues: false } };
        let bounce = Bounce { wi, pdf, delta: false, throughput };
        let continues = matches!(WALK.advance(self.params, &mut path.state, bounce, v.p, v.ng, path.roulette, &mut path.rng), Leave::Continues(_));
        Arrival { shadow, continues }
    }
}
