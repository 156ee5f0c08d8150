//! Smooth conductor (Mitsuba's `conductor`): a Dirac mirror lobe weighted by the
//! conductor Fresnel reflectance with complex index η + ik per RGB channel.

use super::{BsdfSample, fresnel};
use crate::math::{Vec3, local};
use crate::measure::SolidAnglePdf;
use crate::spectrum::Rgb;

/// Perfectly smooth metal; black from the back.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Conductor {
    /// Real part of the relative index of refraction (metal / outside medium), per channel.
    pub eta: Rgb,
    /// Imaginary part (absorption coefficient), per channel.
    pub k: Rgb,
    pub specular_reflectance: Rgb,
}

impl Conductor {
    /// Fresnel reflectance at incidence cosine `cos_i`, times the specular reflectance.
    #[inline]
    pub fn reflectance(&self, cos_i: f32) -> Rgb {
        fresnel::conductor(cos_i, self.eta, self.k) * self.specular_reflectance
    }

    /// The mirror direction, chosen with probability 1: f·|cos θi|/pdf = F(cos θo)·R_s.
    #[inline]
    pub fn sample(&self, wo: Vec3) -> Option<BsdfSample> {
        if !(wo.z > 0.0) {
            return None;
        }
        let wi = local::reflect(wo);
        let f = self.reflectance(wo.z) / wi.z;
        Some(BsdfSample { wi, f, pdf: SolidAnglePdf(1.0), pdf_rev: SolidAnglePdf(1.0), is_delta: true, is_transmission: false, eta: 1.0 })
    }
}
