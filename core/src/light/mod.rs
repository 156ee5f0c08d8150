//! Light sources: area emitters (triangles, spheres), point and spot lights, and lights
//! at infinity (directional, constant environment, environment map).
//!
//! Every light offers two sampling techniques, each with its density beside it:
//! - **Direct lighting** ([`Light::sample_li`] / [`Light::pdf_li`]): a point on the light
//!   seen from a reference point, with its density per steradian at that point (pbrt-v4
//!   `SampleLi` / `PDF_Li`).
//! - **Emission** ([`Light::sample_le`] / [`Light::pdf_le`]): the first vertex and
//!   direction of a light path, with a density over the light's area (or the scene disk
//!   for lights at infinity) and one per steradian (pbrt-v4 `SampleLe` / `PDF_Le`).
//!
//! Conventions:
//! - Densities are *geometric*: they describe the sampling technique, not whether light
//!   is emitted there. A direction toward the back of a one-sided emitter (or toward a
//!   sphere light from inside it) has a positive density and its sample carries zero
//!   radiance; callers skip the shadow ray when `radiance.is_black()`. `None` means the
//!   technique produced no sample at all (degenerate geometry, the reference point on
//!   the light's own plane, a zero-area light).
//! - Delta lights (point, spot, directional) carry `pdf = 1` (the discrete probability
//!   of their single choice) and `is_delta = true` in their samples; [`Light::pdf_li`]
//!   returns 0 for them, since no other technique can hit them. In
//!   [`Light::pdf_le`] a delta component also reports 1, flagged by the sample's
//!   `delta_pos` / `delta_dir`.
//! - The triangle reads its normal from its own winding; the sphere takes the `n` given
//!   (the hit's or the sample's outward normal: exact where p − centre rounds badly on a
//!   small sphere far from the origin), or recomputes it from `p` when `n` is zero.
//! - Lights at infinity need the scene's bounding sphere ([`Light::set_scene_bounds`]):
//!   emission starts on a disk of that radius perpendicular to the direction, one radius
//!   upstream of the centre (pbrt-v4 `DirectionalLight::SampleLe`).

mod envmap;
mod infinite;
mod point;
mod sphere;
mod triangle;
pub(crate) use triangle::TriangleLanes;

use crate::math::{Bounds3, Vec2, Vec3};
use crate::measure::{AreaPdf, SolidAnglePdf};
use crate::spectrum::Rgb;

pub use envmap::EnvMapError;
use envmap::EnvMapLight;
use infinite::{DirectionalLight, EnvironmentLight};
use point::{PointLight, SpotLight};
use sphere::SphereLight;
use triangle::TriangleLight;

/// A point on a light seen from a reference point (from [`Light::sample_li`]).
#[derive(Clone, Copy, Debug)]
pub struct LightSample {
    /// Unit world direction from the reference point toward the light.
    pub wi: Vec3,
    /// Distance to the sampled point; `f32::INFINITY` for lights at infinity.
    pub dist: f32,
    /// The sampled point; for lights at infinity a point far along `wi`, outside the
    /// scene's bounding sphere (a shadow-ray target).
    pub p: Vec3,
    /// Unit normal of the light surface at `p`; `Vec3::ZERO` for point, spot and
    /// infinite lights.
    pub n: Vec3,
    /// Radiance arriving at the reference point along `-wi` (for point and spot lights
    /// intensity / dist², for directional lights the irradiance).
    pub radiance: Rgb,
    /// Density per steradian at the reference point; 1 for delta lights.
    pub pdf: SolidAnglePdf,
    pub is_delta: bool,
}

/// The start of a light path (from [`Light::sample_le`]).
#[derive(Clone, Copy, Debug)]
pub struct EmissionSample {
    /// Origin of the path.
    pub p: Vec3,
    /// Unit normal of the light surface at `p`; `Vec3::ZERO` if none.
    pub n: Vec3,
    /// Unit direction in which the light travels.
    pub dir: Vec3,
    /// Le(p, dir) for area lights; the intensity toward `dir` for point and spot lights;
    /// the radiance (environment) or irradiance (directional) for lights at infinity.
    pub radiance: Rgb,
    /// Density of `p` per unit area (1 for a delta position).
    pub pdf_pos: AreaPdf,
    /// Density of `dir` per steradian (1 for a delta direction).
    pub pdf_dir: SolidAnglePdf,
    pub delta_pos: bool,
    pub delta_dir: bool,
}

/// A light source (a closed set of kinds, dispatched by `match`).
#[derive(Clone, Debug)]
pub struct Light {
    kind: Kind,
}

#[derive(Clone, Debug)]
enum Kind {
    Triangle(TriangleLight),
    Sphere(SphereLight),
    Point(PointLight),
    Spot(SpotLight),
    Directional(DirectionalLight),
    Environment(EnvironmentLight),
    EnvMap(EnvMapLight),
}

/// A density that overflowed (a nearly degenerate light) is no density at all.
#[inline]
pub(crate) fn finite_or_zero(pdf: SolidAnglePdf) -> SolidAnglePdf {
    if pdf.value().is_finite() && pdf.value() > 0.0 { pdf } else { SolidAnglePdf::ZERO }
}

impl Light {
    /// Diffuse triangle emitter with uniform `radiance`, emitting on the side of
    /// (p1−p0)×(p2−p0) (both sides if `two_sided`). `sample_li` samples the area
    /// uniformly; `sample_le` samples a uniform point and a cosine-weighted direction.
    pub fn triangle(p0: Vec3, p1: Vec3, p2: Vec3, radiance: Rgb, two_sided: bool) -> Self {
        Self { kind: Kind::Triangle(TriangleLight::new(p0, p1, p2, radiance, two_sided)) }
    }

    /// Diffuse emitter on the outside of a sphere. `sample_li` samples the cone of
    /// directions subtended by the sphere uniformly by solid angle (pbrt-v4
    /// `Sphere::Sample(ctx, u)`), and the area uniformly when the reference point is
    /// inside.
    pub fn sphere(center: Vec3, radius: f32, radiance: Rgb) -> Self {
        Self { kind: Kind::Sphere(SphereLight::new(center, radius, radiance)) }
    }

    /// Isotropic point light of the given intensity (W/sr per channel).
    pub fn point(position: Vec3, intensity: Rgb) -> Self {
        Self { kind: Kind::Point(PointLight { position, intensity }) }
    }

    /// Mitsuba 3 `spot`: intensity × falloff, where the falloff is 1 within
    /// `beam_width_deg` of `direction`, decreases linearly in angle to 0 at
    /// `cutoff_angle_deg`, and is 0 beyond. Emission samples are uniform in the cutoff cone.
    pub fn spot(position: Vec3, direction: Vec3, intensity: Rgb, cutoff_angle_deg: f32, beam_width_deg: f32) -> Self {
        Self { kind: Kind::Spot(SpotLight::new(position, direction, intensity, cutoff_angle_deg, beam_width_deg)) }
    }

    /// Light arriving from infinitely far away, travelling along `direction`, with the
    /// given irradiance on a surface perpendicular to it.
    pub fn directional(direction: Vec3, irradiance: Rgb) -> Self {
        Self { kind: Kind::Directional(DirectionalLight::new(direction, irradiance)) }
    }

    /// Mitsuba's `constant` emitter: the same radiance from every direction at infinity.
    pub fn constant_environment(radiance: Rgb) -> Self {
        Self { kind: Kind::Environment(EnvironmentLight::new(radiance)) }
    }

    /// Mitsuba's `envmap`: radiance at infinity from a latitude–longitude image of
    /// `width × height` linear RGB texels (row 0 at the zenith, +y of the local frame),
    /// times `scale`, in the frame whose axes in world space are `to_world` (a rotation);
    /// importance-sampled by the image (see `envmap.rs`). The image is shared by clones.
    pub fn environment_map(width: u32, height: u32, texels: &[Rgb], scale: f32, to_world: [Vec3; 3]) -> Result<Self, EnvMapError> {
        Ok(Self { kind: Kind::EnvMap(EnvMapLight::new(width, height, texels, scale, to_world)?) })
    }

    /// Tell a light at infinity the scene's bounding sphere; a no-op for other lights.
    pub fn set_scene_bounds(&mut self, center: Vec3, radius: f32) {
        match &mut self.kind {
            Kind::Directional(l) => l.disk.set(center, radius),
            Kind::Environment(l) => l.disk.set(center, radius),
            Kind::EnvMap(l) => l.disk.set(center, radius),
            _ => {}
        }
    }

    /// If this is a triangle light, copy it into lane `i` of `lanes` (true); else false.
    /// The lane shading draws from triangle lights over SIMD lanes ([`TriangleLanes`]).
    #[inline]
    pub(crate) fn set_triangle_lane(&self, lanes: &mut TriangleLanes, i: usize) -> bool {
        match &self.kind {
            Kind::Triangle(l) => {
                lanes.set(i, l);
                true
            }
            _ => false,
        }
    }

    /// Sample a point on the light as seen from `p_ref` (see [`LightSample`]).
    #[inline]
    pub fn sample_li(&self, p_ref: Vec3, u: Vec2) -> Option<LightSample> {
        match &self.kind {
            Kind::Triangle(l) => l.sample_li(p_ref, u),
            Kind::Sphere(l) => l.sample_li(p_ref, u),
            Kind::Point(l) => l.sample_li(p_ref),
            Kind::Spot(l) => l.sample_li(p_ref),
            Kind::Directional(l) => l.sample_li(p_ref),
            Kind::Environment(l) => l.sample_li(p_ref, u),
            Kind::EnvMap(l) => l.sample_li(p_ref, u),
        }
    }

    /// Density per steradian with which [`Light::sample_li`] from `p_ref` returns the
    /// direction `wi` reaching the light at `p_light` (normal `n_light`). 0 for delta
    /// lights. The sphere and the lights at infinity use only `wi`.
    #[inline]
    pub fn pdf_li(&self, p_ref: Vec3, wi: Vec3, p_light: Vec3, n_light: Vec3) -> SolidAnglePdf {
        let _ = n_light;
        match &self.kind {
            Kind::Triangle(l) => l.pdf_li(p_ref, wi, p_light),
            Kind::Sphere(l) => l.pdf_li(p_ref, wi),
            Kind::Environment(l) => l.pdf_li(),
            Kind::EnvMap(l) => l.pdf_li(wi),
            Kind::Point(_) | Kind::Spot(_) | Kind::Directional(_) => SolidAnglePdf::ZERO,
        }
    }

    /// Area lights: radiance leaving `p` (normal `n`) toward `w` (0 from the back of a
    /// one-sided emitter). 0 for the other lights.
    #[inline]
    pub fn radiance(&self, p: Vec3, n: Vec3, w: Vec3) -> Rgb {
        match &self.kind {
            Kind::Triangle(l) => l.radiance(w),
            Kind::Sphere(l) => l.radiance(p, n, w),
            _ => Rgb::ZERO,
        }
    }

    /// Lights at infinity: radiance arriving from direction `dir` (pointing toward the
    /// sky). 0 for other lights, including the directional light (a delta in direction
    /// that no ray can hit).
    #[inline]
    pub fn environment_radiance(&self, dir: Vec3) -> Rgb {
        match &self.kind {
            Kind::Environment(l) => l.radiance,
            Kind::EnvMap(l) => l.radiance(dir),
            _ => Rgb::ZERO,
        }
    }

    /// Sample the start of a light path: a position from `u_pos` and a direction from
    /// `u_dir` (see [`EmissionSample`]).
    #[inline]
    pub fn sample_le(&self, u_pos: Vec2, u_dir: Vec2) -> Option<EmissionSample> {
        match &self.kind {
            Kind::Triangle(l) => l.sample_le(u_pos, u_dir),
            Kind::Sphere(l) => l.sample_le(u_pos, u_dir),
            Kind::Point(l) => l.sample_le(u_dir),
            Kind::Spot(l) => l.sample_le(u_dir),
            Kind::Directional(l) => l.sample_le(u_pos),
            Kind::Environment(l) => l.sample_le(u_pos, u_dir),
            Kind::EnvMap(l) => l.sample_le(u_pos, u_dir),
        }
    }

    /// Inverse of the position part of [`Light::sample_le`]: the `u_pos` ∈ [0,1)² whose
    /// sample is surface point `p` (triangle and sphere lights; equal-area cells of `u_pos`
    /// are equal-area pieces of the light). (0, 0) for lights without a surface.
    #[inline]
    pub fn position_uv(&self, p: Vec3) -> Vec2 {
        match &self.kind {
            Kind::Triangle(l) => l.position_uv(p),
            Kind::Sphere(l) => l.position_uv(p),
            _ => Vec2::ZERO,
        }
    }

    /// Triangle and sphere lights: a surface that rays can hit and light paths start on at
    /// a non-Dirac position.
    #[inline]
    pub fn has_area(&self) -> bool {
        matches!(self.kind, Kind::Triangle(_) | Kind::Sphere(_))
    }

    /// Densities with which [`Light::sample_le`] returns a path leaving `p` (normal `n`)
    /// along `dir`: per unit area and per steradian. Delta components report 1.
    #[inline]
    pub fn pdf_le(&self, p: Vec3, n: Vec3, dir: Vec3) -> (AreaPdf, SolidAnglePdf) {
        match &self.kind {
            Kind::Triangle(l) => l.pdf_le(dir),
            Kind::Sphere(l) => l.pdf_le(p, n, dir),
            Kind::Point(_) => PointLight::pdf_le(),
            Kind::Spot(l) => l.pdf_le(dir),
            Kind::Directional(l) => l.pdf_le(),
            Kind::Environment(l) => l.pdf_le(),
            Kind::EnvMap(l) => l.pdf_le(dir),
        }
    }

    /// Total emitted power (average over the RGB channels), for light selection. Lights
    /// at infinity count the power crossing the scene's bounding disk (pbrt-v4 `Phi`).
    /// Saturates at `f32::MAX`: a light too bright for f32 (a point light of intensity
    /// 1e38 has 4π·1e38) stays selectable, where an infinite weight would be dropped by
    /// the selection table and the scene reported as unlit.
    pub fn power(&self) -> f32 {
        let power = match &self.kind {
            Kind::Triangle(l) => l.power(),
            Kind::Sphere(l) => l.power(),
            Kind::Point(l) => l.power(),
            Kind::Spot(l) => l.power(),
            Kind::Directional(l) => l.power(),
            Kind::Environment(l) => l.power(),
            Kind::EnvMap(l) => l.power(),
        };
        if power == f32::INFINITY { f32::MAX } else { power }
    }

    /// The box around a light with a surface (triangle, sphere); `None` for lights
    /// without one (the scene plan measures emitter extents with it).
    pub fn surface_bounds(&self) -> Option<Bounds3> {
        match &self.kind {
            Kind::Triangle(l) => Some(l.bounds()),
            Kind::Sphere(l) => Some(l.bounds()),
            _ => None,
        }
    }

    /// Point, spot and directional lights: no ray can hit them.
    #[inline]
    pub fn is_delta(&self) -> bool {
        matches!(self.kind, Kind::Point(_) | Kind::Spot(_) | Kind::Directional(_))
    }

    /// Where a point or spot light sits; `None` for lights with an extent or at infinity.
    pub fn delta_position(&self) -> Option<Vec3> {
        match &self.kind {
            Kind::Point(l) => Some(l.position),
            Kind::Spot(l) => Some(l.position),
            _ => None,
        }
    }

    /// Point and spot lights: emission starts at one point.
    #[inline]
    pub fn is_delta_position(&self) -> bool {
        matches!(self.kind, Kind::Point(_) | Kind::Spot(_))
    }

    /// The directional light: emission along one direction, so nothing can connect to it.
    #[inline]
    pub fn is_delta_direction(&self) -> bool {
        matches!(self.kind, Kind::Directional(_))
    }

    /// Directional and environment lights.
    #[inline]
    pub fn is_infinite(&self) -> bool {
        matches!(self.kind, Kind::Directional(_) | Kind::Environment(_) | Kind::EnvMap(_))
    }
}
