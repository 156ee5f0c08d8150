//! The one bounce loop: how every estimator steps a path from one surface to the next.
//!
//! # What a step does
//!
//! A path, camera or light, is a [`PathState`]: the ray it is about to trace, its
//! throughput β, the segments traced so far (the current ray's included), the BSDF
//! sample that spawned the ray (for the MIS weight of emission found by it) and the first
//! random dimension of its bounces. One bounce is two halves with the caller's record
//! between them:
//!
//! 1. **Arrive.** [`Walk::trace`] traces the ray: the surface it reaches, or `None` (the
//!    path escaped, to the lights at infinity: [`environment`]). A segment that ran
//!    inside an absorbing medium multiplies β by its transmittance ([`Walk::pass_medium`]). Where a segment kernel
//!    joins segments (segment PT, LT and BDPT), [`Walk::junction`] draws the next
//!    segment's start x around the hit y (eq. 15's p_K, from the kernel's own stream): a
//!    camera walk (radiance) keeps the BSDF at y and leaves from x; a light walk
//!    (importance) moves its shading point to x and multiplies β by the reversed kernel
//!    ratio (the integrand's kernel is the camera-direction one).
//! 2. **Record** (the caller's part): emission [`emitted`] weighted or not, a next-event
//!    sample ([`Walk::draw_light`] picks a light ∝ power and a point on it, per solid
//!    angle at the origin; [`shadow_ray`] tests it), a camera connection, a stored vertex,
//!    a filter node. Nothing here needs more than the vertex and the state.
//! 3. **Leave.** [`Walk::scatter`] samples the BSDF at the shading point (the adjoint for
//!    importance), multiplies β by f_r |cos| / p_ω, applies the caller's roulette rule and
//!    spawns the next ray: t = f_r(wo, ŝ) |n·ŝ| c / p_ω(ŝ), with the cosine taken where the
//!    segment starts (the shading normal, or x's with a kernel: eq. 6) and c the
//!    shading-normal correction of the adjoint (Veach 1997 §5.3; 1 for radiance).
//!
//! Densities are per solid angle at the vertex (`p_ω`, the sampler's own value, as every
//! MIS weight downstream reads it); light choices carry P(light) · p_light(ω).
//!
//! # Roulette
//!
//! Each estimator keeps its rule ([`Roulette`]): Mitsuba's rule on the throughput after
//! the draw, q = min(max β / reference, 0.95) from `rr_depth` surfaces on (PT, LT and the
//! BDPT family: `crate::transport::survives_roulette`, reference 1 for camera paths and
//! the emitted power's for light paths); a probability the caller fixed before the draw
//! (the filters' nodes, whose q must not carry one path's history), survived as β/q; or
//! none (PhF's camera side, which stops at its first diffuse vertex).
//!
//! # Random dimensions
//!
//! Every number of a bounce comes from one block of the path's counter-based stream:
//! bounce k (k = 1 for the surface the first segment reached) uses dimensions
//! `dims + (k − 1) · per_bounce` onward, at the offsets of the caller's [`Layout`]: the
//! light choice (1) and the point on it (2), the lobe (1) and direction (2) of the BSDF
//! sample, roulette (1). Each draw jumps to its own dimension, so a branch that skips a
//! draw shifts nothing after it, and every caller kept the numbers it had before this
//! walk existed (its images are bit for bit the same):
//!
//! | caller | mode | per bounce | light | lobe | roulette | rule |
//! |---|---|---|---|---|---|---|
//! | PT, segment PT (`estimators::pt`) | radiance | 8 | 0 | 3 | 6 | throughput, 1 |
//! | LT, segment LT (`estimators::lt`) | importance | 4 | — | 0 | 3 | throughput, β₀ |
//! | BDPT family sub-paths (`path::walk`) | both | 4 | — | 0 | 3 | throughput |
//! | filter camera nodes (`estimators::filter::nodes`) | radiance | 8 | 1 | 4 | 0 | fixed (albedo) |
//! | filter light nodes (same) | importance | 8 | — | 1 | 0 | fixed (albedo) |
//! | PhF's camera side (`estimators::filter::phf`) | radiance | 3 | — | 0 | — | none |
//!
//! # Lanes
//!
//! Everything a step reads and writes is plain data: [`PathState`], the hit, the
//! [`Bounce`] it returns. No step calls back into the caller, and none needs the path's
//! history, so a lane-parallel engine can run each half over many paths at once (all
//! lanes trace, all record, all scatter) and keep this scalar walk as its reference.
//! Nothing here allocates.

use super::{Counters, RenderParams, SurfacePoint, survives_roulette};
use crate::bsdf::{Material, TransportMode, shading_normal_correction};
use crate::geometry::{Ray, RayQuery, SurfaceHit, spawn_ray, spawn_ray_to};
use crate::light::LightSample;
use crate::math::Vec3;
use crate::rng::SampleStream;
use crate::scene::Scene;
use crate::segment::{Junctions, KernelSample};
use crate::spectrum::Rgb;

/// Where in its bounce's block of random dimensions each draw of a walk lies.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Layout {
    /// Dimensions per bounce.
    pub per_bounce: u32,
    /// The light choice (then 2 for the point on the light); unused if no light is drawn.
    pub light: u32,
    /// The BSDF lobe (then 2 for the direction).
    pub lobe: u32,
    /// The roulette number; unused with [`Roulette::Never`].
    pub roulette: u32,
}

/// A path between bounces, plain data: what a walk carries from one vertex to the next.
#[derive(Clone, Copy, Debug)]
pub struct PathState {
    /// The ray the path traces next.
    pub ray: Ray,
    /// Throughput β.
    pub beta: Rgb,
    /// Segments traced, the current ray's included (1 for the first).
    pub segments: u32,
    /// The BSDF sample that spawned `ray`; `None` for the first segment.
    pub last: Option<LastBounce>,
    /// First random dimension of bounce 1 (see the module notes).
    pub dims: u32,
}

impl PathState {
    /// A path whose first segment is `ray`, throughput `beta`, its bounces' random
    /// numbers from dimension `dims` on.
    #[inline]
    pub fn new(ray: Ray, beta: Rgb, dims: u32) -> Self {
        Self { ray, beta, segments: 1, last: None, dims }
    }

    /// The first dimension of the current bounce's block, plus `offset`.
    #[inline]
    pub(crate) fn dimension(&self, layout: &Layout, offset: u32) -> u32 {
        self.dims.wrapping_add(self.segments.wrapping_sub(1).wrapping_mul(layout.per_bounce)).wrapping_add(offset)
    }
}

/// The BSDF sample that spawned a path's current ray.
#[derive(Clone, Copy, Debug)]
pub struct LastBounce {
    /// The ray's origin (offset off the surface): light densities for the MIS weight of
    /// emission the ray finds are evaluated from here.
    pub origin: Vec3,
    /// p_ω of the sample.
    pub pdf: f32,
    /// Drawn from a Dirac lobe.
    pub delta: bool,
}

/// How a walk ends paths at random (see the module notes).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Roulette {
    /// Mitsuba's rule on β after the draw ([`survives_roulette`]) with this reference.
    Throughput { reference: f32 },
    /// Survive with probability `q`, chosen by the caller, tested before the draw; a
    /// continuing β is divided by q.
    Fixed { q: f32 },
    /// Never.
    Never,
}

/// A BSDF sample that continued a path (or would have, had roulette not ended it).
#[derive(Clone, Copy, Debug)]
pub struct Bounce {
    /// Unit world direction of the next segment.
    pub wi: Vec3,
    /// p_ω of the draw, as the sampler reported it.
    pub pdf: f32,
    /// Drawn from a Dirac lobe.
    pub delta: bool,
    /// f_r |cos| c / p_ω of the draw (before any roulette).
    pub throughput: Rgb,
}

/// How [`Walk::scatter`] left a vertex.
#[derive(Clone, Copy, Debug)]
pub enum Leave {
    /// No usable direction: the roll of [`Roulette::Fixed`] failed, the BSDF drew none,
    /// or the throughput vanished or overflowed.
    Stopped,
    /// A direction was drawn and roulette then ended the path.
    Ended(Bounce),
    /// The path goes on: the state holds the new ray.
    Continues(Bounce),
}

/// Where a segment kernel moved a junction off the hit (see [`Walk::junction`]).
#[derive(Clone, Copy, Debug)]
pub struct Moved {
    /// The kernel's point: a radiance walk's next segment leaves from it, an importance
    /// walk shades there.
    pub at: SurfaceHit,
    /// K's reversed ratio ([`crate::segment::Kernel::reversed_ratio`]).
    pub ratio: f32,
}

/// A light chosen ∝ power and a point on it, seen from a vertex.
#[derive(Clone, Copy, Debug)]
pub struct LightDraw {
    /// The light's index.
    pub light: usize,
    /// P(light).
    pub pmf: f32,
    /// The point, its direction, radiance and p_light per solid angle (positive, radiance
    /// not black).
    pub sample: LightSample,
}

/// How one estimator walks: its transport mode and its random-dimension layout.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Walk {
    pub mode: TransportMode,
    pub layout: Layout,
}

impl Walk {
    /// Trace the state's ray: the surface it reaches, or `None` if it escaped.
    #[inline]
    pub fn trace<Q: RayQuery + ?Sized>(&self, tracer: &Q, state: &PathState, counters: &mut Counters) -> Option<SurfaceHit> {
        counters.rays += 1;
        tracer.intersect(&state.ray)
    }

    /// The segment the state's ray traced to `hit` crossed an absorbing medium: multiply
    /// β by its transmittance (`crate::scene` media notes: a segment that reaches the
    /// back face of a surface with an interior ran inside it). Nothing changes where the
    /// scene has no medium.
    #[inline]
    pub fn pass_medium(scene: &Scene, state: &mut PathState, hit: &SurfaceHit) {
        if let Some(t) = scene.transmittance(&state.ray, hit) {
            state.beta *= t;
        }
    }

    /// The junction at `hit` (the state's ray reached it): `None` where it stays at the
    /// hit (no `junctions`, the Dirac kernel, or the kernel's miss mass); otherwise the
    /// point the kernel drew around it. A light walk shades at that point and multiplies
    /// β by the kernel's reversed ratio; a camera walk keeps the hit's BSDF and leaves
    /// from it.
    #[inline]
    pub fn junction<Q: RayQuery + ?Sized>(
        &self,
        tracer: &Q,
        state: &mut PathState,
        hit: &SurfaceHit,
        junctions: Option<&mut Junctions>,
        counters: &mut Counters,
    ) -> Option<Moved> {
        let j = junctions?;
        counters.rays += 1;
        let KernelSample::Moved(at) = j.sample(tracer, hit, -state.ray.dir) else { return None };
        let ratio = j.kernel.reversed_ratio(hit, &at);
        if self.mode == TransportMode::Importance {
            state.beta *= ratio;
        }
        Some(Moved { at, ratio })
    }

    /// Next-event estimation's draw at the current bounce: a light ∝ power (dimension
    /// `light`) and a point on it (the next two) as seen from `origin`; `None` if the
    /// scene has no lights or the sample carries nothing.
    #[inline(always)]
    pub fn draw_light(&self, scene: &Scene, state: &PathState, origin: Vec3, rng: &mut SampleStream) -> Option<LightDraw> {
        let table = scene.light_selection.as_ref()?;
        rng.set_dimension(state.dimension(&self.layout, self.layout.light));
        let u_light = rng.next_f32();
        let u_point = rng.next_2d();
        let chosen = table.sample(u_light);
        let sample = scene.lights[chosen.index].sample_li(origin, u_point)?;
        if !sample.pdf.is_positive() || sample.radiance.is_black() {
            return None;
        }
        Some(LightDraw { light: chosen.index, pmf: chosen.pmf, sample })
    }

    /// Leave the shading point `sp` (`wo_local` its outgoing direction in its shading
    /// frame, which the caller has for its own use too; `material` its material): sample the BSDF (dimensions `lobe`
    /// onward), multiply β by the draw's throughput, apply `roulette`, and spawn the next
    /// ray from `start` (a kernel-moved start of a radiance walk, whose normal takes the
    /// cosine) or from `sp`.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub fn scatter(
        &self,
        params: &RenderParams,
        state: &mut PathState,
        sp: &SurfacePoint,
        wo_local: Vec3,
        material: &Material,
        start: Option<&SurfaceHit>,
        roulette: Roulette,
        rng: &mut SampleStream,
    ) -> Leave {
        // Roll a roulette fixed before the draw.
        if let Roulette::Fixed { q } = roulette {
            rng.set_dimension(state.dimension(&self.layout, self.layout.roulette));
            if !(q > 0.0 && rng.next_f32() < q) {
                return Leave::Stopped;
            }
        }

        // Sample the BSDF for the next direction.
        rng.set_dimension(state.dimension(&self.layout, self.layout.lobe));
        let u_lobe = rng.next_f32();
        let u_dir = rng.next_2d();
        let Some(bs) = material.sample(wo_local, u_lobe, u_dir, self.mode) else { return Leave::Stopped };
        if !bs.pdf.is_positive() {
            return Leave::Stopped;
        }
        let wi = sp.frame.to_world(bs.wi);
        // f_r |cos| c / p_ω, the cosine where the segment starts (eq. 6, 15).
        let cos = match start {
            None => bs.wi.z.abs(),
            Some(x) => x.ns.dot(wi).abs(),
        };
        let correction = shading_normal_correction(self.mode, sp.wo, wi, sp.hit.ng, sp.hit.ns);
        let throughput = bs.f * (cos * correction / bs.pdf.0);
        let bounce = Bounce { wi, pdf: bs.pdf.0, delta: bs.is_delta, throughput };
        let from = start.unwrap_or(&sp.hit);
        self.advance(params, state, bounce, from.p, from.ng, roulette, rng)
    }

    /// [`Self::scatter`]'s second half, once the BSDF has drawn `bounce` (a positive
    /// density): multiply β by its throughput, apply `roulette` (a fixed one was rolled
    /// before the draw), and spawn the next ray from `p` (geometric normal `ng`). The
    /// lane kernels, which draw over lanes of paths (`estimators::pt_lanes`, `lt_lanes`),
    /// finish each path's bounce here.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    pub fn advance(
        &self,
        params: &RenderParams,
        state: &mut PathState,
        bounce: Bounce,
        p: Vec3,
        ng: Vec3,
        roulette: Roulette,
        rng: &mut SampleStream,
    ) -> Leave {
        let throughput = bounce.throughput;
        // Update β and apply the roulette rule.
        match roulette {
            Roulette::Throughput { reference } => {
                state.beta *= throughput;
                if state.beta.is_black() || !state.beta.is_finite() {
                    return Leave::Stopped;
                }
                rng.set_dimension(state.dimension(&self.layout, self.layout.roulette));
                state.segments += 1;
                if !survives_roulette(params, state.segments, &mut state.beta, reference, rng) {
                    return Leave::Ended(bounce);
                }
            }
            Roulette::Fixed { q } => {
                if throughput.is_black() || !throughput.is_finite() {
                    return Leave::Stopped;
                }
                state.beta *= throughput / q;
                state.segments += 1;
            }
            Roulette::Never => {
                state.beta *= throughput;
                if state.beta.is_black() || !state.beta.is_finite() {
                    return Leave::Stopped;
                }
                state.segments += 1;
            }
        }

        // Spawn the next segment.
        state.ray = spawn_ray(p, ng, bounce.wi);
        state.last = Some(LastBounce { origin: state.ray.origin, pdf: bounce.pdf, delta: bounce.delta });
        Leave::Continues(bounce)
    }
}

/// The shadow ray of a light sample `ls` taken from `from`.
#[inline(always)]
pub fn shadow_ray(from: &SurfaceHit, ls: &LightSample) -> Ray {
    if ls.dist.is_finite() { spawn_ray_to(from.p, from.ng, ls.p, ls.n) } else { spawn_ray(from.p, from.ng, ls.wi) }
}

/// The point light samples at a vertex are taken from: where rays leaving `from` toward
/// `wo`'s side start ([`SurfacePoint::reflection_origin`] of the shading point, or of a
/// kernel-moved start).
#[inline]
pub fn light_origin(from: &SurfaceHit, wo: Vec3) -> Vec3 {
    spawn_ray(from.p, from.ng, wo).origin
}

/// L_e leaving `hit` toward `wo`, if it lies on an area light.
#[inline]
pub fn emitted(scene: &Scene, hit: &SurfaceHit, wo: Vec3) -> Rgb {
    hit.emitter.map_or(Rgb::ZERO, |id| scene.lights[id as usize].radiance(hit.p, hit.ng, wo))
}

/// Radiance of the lights at infinity along `dir` (an escaped ray), unweighted.
#[inline]
pub fn environment(scene: &Scene, dir: Vec3) -> Rgb {
    scene.infinite_lights().fold(Rgb::ZERO, |acc, (_, l)| acc + l.environment_radiance(dir))
}
