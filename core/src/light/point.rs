//! Point and spot lights (delta in position).
//!
//! Direct lighting returns the light's position with density 1 (a discrete choice) and
//! radiance I(−wi)/d². Emission samples a direction: uniform on the sphere for the point
//! light (p = 1/(4π)), uniform in the cutoff cone for the spot (p = 1/(2π(1 − cos θ_c))),
//! as Mitsuba 3's `point` and `spot` do.
//!
//! Spot falloff (Mitsuba 3 `spot.cpp`, `falloff_curve`): with θ the angle to the axis,
//! θ_b the beam width and θ_c the cutoff,
//!   f(θ) = 1 for θ ≤ θ_b;  (θ_c − θ)/(θ_c − θ_b) for θ_b < θ < θ_c;  0 for θ ≥ θ_c.

use super::{EmissionSample, LightSample};
use crate::math::{Frame, PI, TWO_PI, Vec2, Vec3, cos, safe_acos, sin, sqrt};
use crate::measure::{AreaPdf, SolidAnglePdf};
use crate::spectrum::Rgb;
use crate::warp;

/// Shared by point and spot: the vector to the light, its length and direction.
#[inline]
fn toward(position: Vec3, p_ref: Vec3) -> Option<(Vec3, f32, f32)> {
    let d = position - p_ref;
    let dist2 = d.length_squared();
    // A subnormal squared distance (|d| below ~1e-19) leaves too few bits to normalise
    // d: the direction came out 0.2 % short of unit length (found by fuzzing).
    if !(dist2 >= f32::MIN_POSITIVE) || !dist2.is_finite() {
        return None;
    }
    let dist = sqrt(dist2);
    Some((d / dist, dist, dist2))
}

/// Shared by point and spot: the Dirac sample of a light at `position` seen from
/// `p_ref`, radiance I·falloff(wi)/d² (`falloff` of the direction toward the light).
#[inline]
fn sample_from_position(position: Vec3, intensity: Rgb, p_ref: Vec3, falloff: impl FnOnce(Vec3) -> f32) -> Option<LightSample> {
    let (wi, dist, dist2) = toward(position, p_ref)?;
    let radiance = intensity * (falloff(wi) / dist2);
    // A reference point (almost) on the light: 1/d² overflows (found by fuzzing).
    if !radiance.is_finite() {
        return None;
    }
    Some(LightSample { wi, dist, p: position, n: Vec3::ZERO, radiance, pdf: SolidAnglePdf(1.0), is_delta: true })
}

#[derive(Clone, Copy, Debug)]
pub(super) struct PointLight {
    pub(super) position: Vec3,
    pub(super) intensity: Rgb,
}

impl PointLight {
    pub(super) fn sample_li(&self, p_ref: Vec3) -> Option<LightSample> {
        sample_from_position(self.position, self.intensity, p_ref, |_| 1.0)
    }

    pub(super) fn sample_le(&self, u_dir: Vec2) -> Option<EmissionSample> {
        let dir = warp::sample_uniform_sphere(u_dir);
        let (pdf_pos, pdf_dir) = Self::pdf_le();
        Some(EmissionSample { p: self.position, n: Vec3::ZERO, dir, radiance: self.intensity, pdf_pos, pdf_dir, delta_pos: true, delta_dir: false })
    }

    /// (1 (delta), 1/(4π)).
    pub(super) fn pdf_le() -> (AreaPdf, SolidAnglePdf) {
        (AreaPdf(1.0), warp::uniform_sphere_pdf())
    }

    /// Φ = 4π I.
    pub(super) fn power(&self) -> f32 {
        4.0 * PI * self.intensity.average()
    }
}

#[derive(Clone, Copy, Debug)]
pub(super) struct SpotLight {
    pub(super) position: Vec3,
    /// Local frame with the spot's axis as normal.
    frame: Frame,
    intensity: Rgb,
    /// Cutoff θ_c and beam width θ_b in radians, 0 ≤ θ_b ≤ θ_c ≤ π.
    cutoff: f32,
    beam: f32,
    cos_cutoff: f32,
    cos_beam: f32,
}

impl SpotLight {
    /// Angles in degrees, clamped to 0 ≤ beam ≤ cutoff ≤ 180; a zero `direction` points
    /// the spot along +z (Mitsuba's local axis).
    pub(super) fn new(position: Vec3, direction: Vec3, intensity: Rgb, cutoff_deg: f32, beam_deg: f32) -> Self {
        let axis = direction.normalize_or(Vec3::Z);
        let cutoff = cutoff_deg.clamp(0.0, 180.0).to_radians();
        let beam = beam_deg.clamp(0.0, 180.0).to_radians().min(cutoff);
        Self { position, frame: Frame::from_normal(axis), intensity, cutoff, beam, cos_cutoff: cos(cutoff), cos_beam: cos(beam) }
    }

    /// Mitsuba's falloff for a unit direction `local` in the spot's frame.
    #[inline]
    pub(super) fn falloff(&self, local: Vec3) -> f32 {
        let cos_theta = local.z;
        if cos_theta <= self.cos_cutoff {
            0.0
        } else if cos_theta >= self.cos_beam || self.cutoff <= self.beam {
            1.0
        } else {
            ((self.cutoff - safe_acos(cos_theta)) / (self.cutoff - self.beam)).clamp(0.0, 1.0)
        }
    }

    pub(super) fn sample_li(&self, p_ref: Vec3) -> Option<LightSample> {
        sample_from_position(self.position, self.intensity, p_ref, |wi| self.falloff(self.frame.to_local(-wi)))
    }

    /// Uniform direction in the cutoff cone (Mitsuba 3 `SpotLight::sample_ray`).
    pub(super) fn sample_le(&self, u_dir: Vec2) -> Option<EmissionSample> {
        let local = warp::sample_uniform_cone(u_dir, self.cos_cutoff);
        let dir = self.frame.to_world(local).normalize_or_zero();
        let (pdf_pos, pdf_dir) = self.pdf_le(dir);
        if !pdf_dir.is_positive() || !pdf_dir.value().is_finite() {
            return None;
        }
        Some(EmissionSample {
            p: self.position,
            n: Vec3::ZERO,
            dir,
            radiance: self.intensity * self.falloff(local),
            pdf_pos,
            pdf_dir,
            delta_pos: true,
            delta_dir: false,
        })
    }

    /// (1 (delta), 1/(2π(1 − cos θ_c)) inside the cutoff cone).
    pub(super) fn pdf_le(&self, dir: Vec3) -> (AreaPdf, SolidAnglePdf) {
        (AreaPdf(1.0), warp::uniform_cone_pdf(self.frame.to_local(dir), self.cos_cutoff))
    }

    /// Φ = 2π I ∫ f(θ) sin θ dθ = 2π I [1 − (sin θ_c − sin θ_b)/(θ_c − θ_b)] (integrating the
    /// linear ramp by parts), with the difference quotient written as
    /// cos((θ_c+θ_b)/2) · sin(w/2)/(w/2), w = θ_c − θ_b, so it stays exact as w → 0.
    pub(super) fn power(&self) -> f32 {
        let half_width = 0.5 * (self.cutoff - self.beam);
        let sinc = if half_width > 0.0 { sin(half_width) / half_width } else { 1.0 };
        let quotient = cos(0.5 * (self.cutoff + self.beam)) * sinc;
        TWO_PI * (1.0 - quotient).max(0.0) * self.intensity.average()
    }
}
