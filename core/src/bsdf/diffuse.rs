//! Lambertian reflection (Mitsuba's `diffuse`): f = ρ/π on the front side.

use super::BsdfSample;
use crate::math::{INV_PI, Vec2, Vec3};
use crate::measure::SolidAnglePdf;
use crate::spectrum::Rgb;
use crate::warp::{cosine_hemisphere_pdf, sample_cosine_hemisphere};

/// Ideal diffuse reflector with albedo `reflectance`; black from the back.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Diffuse {
    pub reflectance: Rgb,
}

impl Diffuse {
    /// f(wo, wi) = ρ/π when both directions are above the surface, else 0.
    #[inline]
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Rgb {
        if wo.z > 0.0 && wi.z > 0.0 { self.reflectance * INV_PI } else { Rgb::ZERO }
    }

    /// Cosine-weighted hemisphere density cos θi/π (0 unless both are above the surface).
    #[inline]
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> SolidAnglePdf {
        if wo.z > 0.0 && wi.z > 0.0 { cosine_hemisphere_pdf(wi) } else { SolidAnglePdf::ZERO }
    }

    /// Cosine-weighted direction (Malley's method); `None` from the back side.
    #[inline]
    pub fn sample(&self, wo: Vec3, u: Vec2) -> Option<BsdfSample> {
        if !(wo.z > 0.0) {
            return None;
        }
        let wi = sample_cosine_hemisphere(u);
        let pdf = self.pdf(wo, wi);
        if !pdf.is_positive() {
            return None;
        }
        Some(BsdfSample::continuous_reflection(wi, self.eval(wo, wi), pdf, self.pdf(wi, wo)))
    }
}
