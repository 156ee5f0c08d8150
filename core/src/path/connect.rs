//! Evaluation of one (s, t) strategy: join the first s light vertices and the first t
//! camera vertices (pbrt-v3's `ConnectBDPT`) into the UNWEIGHTED contribution f/p of the
//! full path. Weighting is a separate step ([`super::mis`], or an estimator's own
//! counts), applied with [`Connection::weighted`].

use super::vertex::{Vertex, VertexKind};
use crate::bsdf::TransportMode;
use crate::camera::PerspectiveCamera;
use crate::geometry::{Ray, RayQuery, spawn_ray_to};
use crate::math::{Vec2, Vec3};
use crate::measure::VertexPdf;
use crate::rng::SampleStream;
use crate::scene::Context;
use crate::spectrum::Rgb;
use crate::transport::Counters;

/// The random numbers of a resampled endpoint: for strategy s = 1 which light and where
/// on it; for t = 1 `u_point` picks the lens point (ignored without a lens). Other
/// strategies ignore them.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LightPointSample {
    /// Chooses the light.
    pub u_light: f32,
    /// Chooses the point on it (s = 1), or on the lens (t = 1).
    pub u_point: Vec2,
}

impl LightPointSample {
    /// The numbers of a t = 1 strategy: the lens point from `rng`, which gives nothing up
    /// without a lens ([`PerspectiveCamera::lens_u`]).
    pub fn lens(camera: &PerspectiveCamera, rng: &mut SampleStream) -> Self {
        Self { u_light: 0.0, u_point: camera.lens_u(rng) }
    }
}

/// A strategy's full path, connected but not weighted.
#[derive(Clone, Copy, Debug)]
pub struct Connection {
    /// f/p of the full path (no MIS weight).
    pub value: Rgb,
    /// The film position, for t = 1.
    pub film: Option<Vec2>,
    /// The endpoint resampled at connection time (the light point for s = 1, the
    /// camera for t = 1), which replaces the sub-path's own endpoint in the full path.
    pub sampled: Option<Vertex>,
}

/// A connection with its MIS weight applied.
#[derive(Clone, Copy, Debug)]
pub struct Weighted {
    /// weight · f/p.
    pub value: Rgb,
    /// The film position, for t = 1.
    pub film: Option<Vec2>,
    /// The MIS weight that was applied.
    pub weight: f32,
    /// See [`Connection::sampled`].
    pub sampled: Option<Vertex>,
}

impl Connection {
    /// Apply MIS weight `weight`.
    #[inline]
    pub fn weighted(self, weight: f32) -> Weighted {
        Weighted { value: self.value * weight, film: self.film, weight, sampled: self.sampled }
    }
}

/// Connect strategy (s, t): the full path's unweighted f/p, its film position (t = 1)
/// and its resampled endpoint (s = 1, t = 1). `u` drives the light resampling of s = 1.
pub fn connect<Q: RayQuery + ?Sized>(
    ctx: &Context<'_, Q>,
    light: &[Vertex],
    camera: &[Vertex],
    s: usize,
    t: usize,
    u: LightPointSample,
    counters: &mut Counters,
) -> Option<Connection> {
    let (scene, tracer) = (ctx.scene, ctx.tracer);
    let (u_light, u_point) = (u.u_light, u.u_point);
    // An escaped camera path can only be used as is (s = 0).
    if t > 1 && s != 0 && camera[t - 1].kind == VertexKind::InfiniteLight {
        return None;
    }
    let mut sampled: Option<Vertex> = None;
    let mut film = None;
    let value: Rgb;
    if s == 0 {
        // The camera path itself reached an emitter.
        let pt = &camera[t - 1];
        if !pt.is_light() {
            return None;
        }
        value = pt.le(scene, &camera[t - 2]) * pt.beta;
    } else if t == 1 {
        // Connect a light-path vertex (s ≥ 2: (1, 1) is covered by (0, 2)) to the camera.
        let qs = &light[s - 1];
        if !qs.is_connectible(scene) || qs.kind != VertexKind::Surface {
            return None;
        }
        // The lens point from u_point (nothing drawn without a lens).
        let cs = scene.camera.sample_wi(qs.p, u_point)?;
        // Importance arriving at qs per unit projected area: W_e |cos θ_c| / d².
        let cam = Vertex::camera(cs.position, Rgb::splat(scene.camera.arriving_importance(&cs)));
        let v = qs.beta * qs.f(scene, &cam, TransportMode::Importance) * cam.beta * cs.wi.dot(qs.frame.n).abs();
        if v.is_black() {
            return None;
        }
        counters.rays += 1;
        if tracer.occluded(&spawn_ray_to(qs.p, qs.ng, cam.p, Vec3::ZERO)) {
            return None;
        }
        film = Some(cs.film);
        sampled = Some(cam);
        value = v;
    } else if s == 1 {
        // Sample a fresh point on a light (next-event estimation).
        let pt = &camera[t - 1];
        if !pt.is_connectible(scene) {
            return None;
        }
        let table = scene.light_selection.as_ref()?;
        let chosen = table.sample(u_light);
        let id = chosen.index as u32;
        let light_ref = &scene.lights[chosen.index];
        // From the start of the segment toward the light (`pt.p` but for segment BDPT).
        let ls = light_ref.sample_li(pt.exit.p, u_point)?;
        if !ls.pdf.is_positive() || ls.radiance.is_black() {
            return None;
        }
        let beta_l = ls.radiance / (ls.pdf.0 * chosen.pmf);
        let mut lv = if light_ref.is_infinite() {
            let mut v = Vertex::infinite(ls.p, beta_l, VertexPdf::ZERO);
            // A directional light is a Dirac in direction: no other strategy reaches it.
            v.delta = light_ref.is_delta();
            v
        } else {
            Vertex::light(id, ls.p, ls.n, beta_l, VertexPdf::ZERO, light_ref.is_delta())
        };
        lv.pdf_fwd = lv.pdf_light_origin(scene, pt);
        let mut v = pt.beta * pt.f(scene, &lv, TransportMode::Radiance) * lv.beta;
        if pt.is_on_surface() {
            v *= ls.wi.dot(pt.exit.ns).abs();
        }
        if let Some(tr) = scene.transmittance_to(ls.p, pt.exit.p, pt.exit.ng, pt.exit.material) {
            v *= tr;
        }
        if v.is_black() {
            return None;
        }
        counters.rays += 1;
        let x = &pt.exit;
        let shadow = if ls.dist.is_finite() { spawn_ray_to(x.p, x.ng, ls.p, ls.n) } else { crate::geometry::spawn_ray(x.p, x.ng, ls.wi) };
        if tracer.occluded(&shadow) {
            return None;
        }
        sampled = Some(lv);
        value = v;
    } else {
        // Join two interior vertices.
        let (qs, pt) = (&light[s - 1], &camera[t - 1]);
        if !qs.is_connectible(scene) || !pt.is_connectible(scene) {
            return None;
        }
        let mut v = qs.beta * qs.f(scene, pt, TransportMode::Importance) * pt.f(scene, qs, TransportMode::Radiance) * pt.beta;
        if v.is_black() {
            return None;
        }
        v *= geometry_term(qs, pt);
        // Through an absorbing medium (a rough dielectric's interior) between them.
        if let Some(tr) = scene.transmittance_to(qs.p, pt.exit.p, pt.exit.ng, pt.exit.material) {
            v *= tr;
        }
        if v.is_black() {
            return None;
        }
        counters.rays += 1;
        let occluded = tracer.occluded(&connect_ray(qs, pt));
        counters.connections.record(v, occluded);
        if occluded {
            return None;
        }
        value = v;
    }
    if value.is_black() {
        return None;
    }
    Some(Connection { value, film, sampled })
}

/// Strategy (1, t) with a GIVEN light-source vertex `y0` (the first vertex of a light
/// path, e.g. one kept in SPCBPT's cache) instead of a fresh light sample:
/// f/p = Le(y₀→z) · G(y₀, z) · f(z) · β(z) / p(y₀), p(y₀) = `y0.pdf_fwd` (light selection ×
/// position density per area, as `light_subpath` sets it). Its MIS weight is that of the
/// light sub-path [y₀] (its density as a path origin is the same p(y₀) that next-event
/// estimation reports).
pub fn connect_light_source<Q: RayQuery + ?Sized>(
    ctx: &Context<'_, Q>,
    y0: &Vertex,
    camera: &[Vertex],
    t: usize,
    counters: &mut Counters,
) -> Option<Connection> {
    let (scene, tracer) = (ctx.scene, ctx.tracer);
    if t < 2 || !matches!(y0.kind, VertexKind::Light(_)) || !y0.pdf_fwd.is_positive() {
        return None;
    }
    let pt = &camera[t - 1];
    if pt.kind != VertexKind::Surface || !pt.is_connectible(scene) {
        return None;
    }
    let tr = scene.transmittance_to(y0.p, pt.exit.p, pt.exit.ng, pt.exit.material).unwrap_or(Rgb::ONE);
    let value = pt.beta * pt.f(scene, y0, TransportMode::Radiance) * y0.le(scene, pt) * tr * (geometry_term(y0, pt) / y0.pdf_fwd.value());
    if value.is_black() || !value.is_finite() {
        return None;
    }
    counters.rays += 1;
    if tracer.occluded(&spawn_ray_to(pt.exit.p, pt.exit.ng, y0.p, y0.ng)) {
        return None;
    }
    Some(Connection { value, film: None, sampled: None })
}

/// G = |cos θ_q| |cos θ_p| / d² of the segment from camera-side `p` (its exit) to
/// light-side `q`, with shading cosines left to the BSDF factors (the geometric cosines
/// belong to the measure).
#[inline]
fn geometry_term(q: &Vertex, p: &Vertex) -> f32 {
    let d = p.exit.p - q.p;
    let d2 = d.length_squared();
    if !(d2 > 0.0) {
        return 0.0;
    }
    let w = d / crate::math::sqrt(d2);
    let cq = if q.is_on_surface() { q.frame.n.dot(w).abs() } else { 1.0 };
    let cp = if p.is_on_surface() { p.exit.ns.dot(w).abs() } else { 1.0 };
    cq * cp / d2
}

/// The shadow ray of the segment from camera-side `p` (its exit) to light-side `q`.
#[inline]
fn connect_ray(q: &Vertex, p: &Vertex) -> Ray {
    spawn_ray_to(q.p, q.ng, p.exit.p, p.exit.ng)
}
