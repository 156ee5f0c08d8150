//! Lights at infinity: the directional light (delta in direction) and the constant
//! environment (Mitsuba 3 `directional` and `constant`).
//!
//! Direct lighting returns a shadow-ray target far along `wi`, outside the scene's
//! bounding sphere. Emission starts on the disk of the bounding sphere's radius R,
//! perpendicular to the travel direction and one radius upstream of the centre, so every
//! ray crossing the scene along that direction is covered: p_A = 1/(πR²) (pbrt-v4
//! `DirectionalLight::SampleLe`, `UniformInfiniteLight::SampleLe`). The environment picks
//! its direction uniformly on the sphere, p_ω = 1/(4π).

use super::{EmissionSample, LightSample};
use crate::math::{Frame, PI, Vec2, Vec3};
use crate::measure::{AreaPdf, SolidAnglePdf};
use crate::spectrum::Rgb;
use crate::warp;

/// The scene's bounding sphere, seen as the disk through which emission enters.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct SceneDisk {
    center: Vec3,
    /// 0 until [`SceneDisk::set`] is called: no emission samples, zero power.
    radius: f32,
}

impl SceneDisk {
    pub(super) fn set(&mut self, center: Vec3, radius: f32) {
        self.center = center;
        self.radius = if radius.is_finite() && radius > 0.0 { radius } else { 0.0 };
    }

    /// A point along `wi` from `p_ref` outside the bounding sphere: at distance
    /// 2(R + |p_ref − c|), which exceeds R + |p_ref − c| by R + |p_ref − c| (at least 1).
    #[inline]
    pub(super) fn far_point(&self, p_ref: Vec3, wi: Vec3) -> Vec3 {
        let reach = (2.0 * (self.radius + (p_ref - self.center).length())).max(1.0);
        p_ref + wi * reach
    }

    /// Uniform point on the disk perpendicular to `dir`, one radius upstream of the centre.
    #[inline]
    pub(super) fn sample(&self, u: Vec2, dir: Vec3) -> Vec3 {
        let q = warp::sample_concentric_disk(u) * self.radius;
        let frame = Frame::from_normal(dir);
        self.center + frame.to_world(Vec3::new(q.x, q.y, 0.0)) - self.radius * dir
    }

    /// 1/(πR²).
    #[inline]
    pub(super) fn pdf(&self) -> AreaPdf {
        if self.radius > 0.0 { AreaPdf(warp::concentric_disk_pdf(Vec2::ZERO).value() / (self.radius * self.radius)) } else { AreaPdf::ZERO }
    }

    /// πR².
    #[inline]
    pub(super) fn area(&self) -> f32 {
        PI * self.radius * self.radius
    }

    /// The direct-lighting sample of an environment (any light at infinity that rays can
    /// hit): direction `wi` from `p_ref` toward the sky, radiance and density given.
    #[inline]
    pub(super) fn environment_li(&self, p_ref: Vec3, wi: Vec3, radiance: Rgb, pdf: SolidAnglePdf) -> LightSample {
        LightSample { wi, dist: f32::INFINITY, p: self.far_point(p_ref, wi), n: Vec3::ZERO, radiance, pdf, is_delta: false }
    }

    /// The emission sample of an environment: a path travelling along `dir` (drawn with
    /// density `pdf_dir`) from a uniform point of the disk across it; `None` before the
    /// scene's bounds are known.
    #[inline]
    pub(super) fn environment_le(&self, u_pos: Vec2, dir: Vec3, radiance: Rgb, pdf_dir: SolidAnglePdf) -> Option<EmissionSample> {
        let pdf_pos = self.pdf();
        if !pdf_pos.is_positive() || !pdf_pos.value().is_finite() {
            return None;
        }
        Some(EmissionSample { p: self.sample(u_pos, dir), n: Vec3::ZERO, dir, radiance, pdf_pos, pdf_dir, delta_pos: false, delta_dir: false })
    }
}

#[derive(Clone, Copy, Debug)]
pub(super) struct DirectionalLight {
    /// Unit direction in which the light travels.
    dir: Vec3,
    irradiance: Rgb,
    pub(super) disk: SceneDisk,
}

impl DirectionalLight {
    /// A zero `direction` falls back to +z (Mitsuba's local default).
    pub(super) fn new(direction: Vec3, irradiance: Rgb) -> Self {
        Self { dir: direction.normalize_or(Vec3::Z), irradiance, disk: SceneDisk::default() }
    }

    pub(super) fn sample_li(&self, p_ref: Vec3) -> Option<LightSample> {
        let wi = -self.dir;
        Some(LightSample {
            wi,
            dist: f32::INFINITY,
            p: self.disk.far_point(p_ref, wi),
            n: Vec3::ZERO,
            radiance: self.irradiance,
            pdf: SolidAnglePdf(1.0),
            is_delta: true,
        })
    }

    pub(super) fn sample_le(&self, u_pos: Vec2) -> Option<EmissionSample> {
        let (pdf_pos, pdf_dir) = self.pdf_le();
        if !pdf_pos.is_positive() || !pdf_pos.value().is_finite() {
            return None;
        }
        Some(EmissionSample {
            p: self.disk.sample(u_pos, self.dir),
            n: Vec3::ZERO,
            dir: self.dir,
            radiance: self.irradiance,
            pdf_pos,
            pdf_dir,
            delta_pos: false,
            delta_dir: true,
        })
    }

    /// (1/(πR²), 1 (delta)).
    pub(super) fn pdf_le(&self) -> (AreaPdf, SolidAnglePdf) {
        (self.disk.pdf(), SolidAnglePdf(1.0))
    }

    /// Φ = E πR².
    pub(super) fn power(&self) -> f32 {
        self.irradiance.average() * self.disk.area()
    }
}

#[derive(Clone, Copy, Debug)]
pub(super) struct EnvironmentLight {
    pub(super) radiance: Rgb,
    pub(super) disk: SceneDisk,
}

impl EnvironmentLight {
    pub(super) fn new(radiance: Rgb) -> Self {
        Self { radiance, disk: SceneDisk::default() }
    }

    /// Uniform direction on the sphere.
    pub(super) fn sample_li(&self, p_ref: Vec3, u: Vec2) -> Option<LightSample> {
        Some(self.disk.environment_li(p_ref, warp::sample_uniform_sphere(u), self.radiance, self.pdf_li()))
    }

    /// 1/(4π) for every direction.
    pub(super) fn pdf_li(&self) -> SolidAnglePdf {
        warp::uniform_sphere_pdf()
    }

    /// Uniform direction toward the sky, travelling the opposite way; a uniform point on
    /// the scene disk across it.
    pub(super) fn sample_le(&self, u_pos: Vec2, u_dir: Vec2) -> Option<EmissionSample> {
        self.disk.environment_le(u_pos, -warp::sample_uniform_sphere(u_dir), self.radiance, warp::uniform_sphere_pdf())
    }

    /// (1/(πR²), 1/(4π)).
    pub(super) fn pdf_le(&self) -> (AreaPdf, SolidAnglePdf) {
        (self.disk.pdf(), warp::uniform_sphere_pdf())
    }

    /// Φ = 4π · πR² · L (pbrt-v4 `UniformInfiniteLight::Phi`).
    pub(super) fn power(&self) -> f32 {
        4.0 * PI * self.disk.area() * self.radiance.average()
    }
}
