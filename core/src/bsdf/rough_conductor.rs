//! Rough conductor (Mitsuba's `roughconductor`): the Cook–Torrance / Walter microfacet
//! reflection model with a conductor Fresnel term,
//!
//!   f(wo, wi) = R_s F(wo·h) D(h) G1(wo, h) G1(wi, h) / (4 cos θo cos θi),  h = (wo + wi)/|wo + wi|
//!
//! (Walter et al., "Microfacet Models for Refraction through Rough Surfaces", EGSR 2007,
//! eq. 20), sampled by reflecting a visible normal: p(wi) = D_wo(h) / (4 wi·h) (ibid.,
//! eq. 14 for the Jacobian of the half-vector map).

use super::microfacet::{Microfacet, reflection_half};
use super::{BsdfSample, fresnel};
use crate::math::{Vec2, Vec3, reflect};
use crate::measure::SolidAnglePdf;
use crate::spectrum::Rgb;

/// Rough metal; black from the back.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct RoughConductor {
    pub distr: Microfacet,
    /// Real part of the relative index of refraction (metal / outside medium), per channel.
    pub eta: Rgb,
    /// Imaginary part (absorption coefficient), per channel.
    pub k: Rgb,
    pub specular_reflectance: Rgb,
}

impl RoughConductor {
    /// BSDF value (module docs), without the cosine.
    #[inline]
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Rgb {
        let Some(m) = reflection_half(wo, wi) else { return Rgb::ZERO };
        self.eval_at(wo, wi, m, self.distr.d(m), self.distr.g1(wo, m), || self.distr.g1(wi, m))
    }

    /// The value at half vector `m` given D(m) and G1(wo, m) (G1(wi, m) drawn only
    /// when needed): what [`Self::eval`], [`Self::eval_pdf`] and [`Self::sample`] share.
    #[inline]
    fn eval_at(&self, wo: Vec3, wi: Vec3, m: Vec3, d: f32, g1_wo: f32, g1_wi: impl FnOnce() -> f32) -> Rgb {
        if d == 0.0 {
            return Rgb::ZERO;
        }
        let g = g1_wo * g1_wi();
        let scalar = d * g / (4.0 * wo.z * wi.z);
        if !scalar.is_finite() {
            return Rgb::ZERO;
        }
        fresnel::conductor(wo.dot(m), self.eta, self.k) * self.specular_reflectance * scalar
    }

    #[inline]
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> SolidAnglePdf {
        let Some(m) = reflection_half(wo, wi) else { return SolidAnglePdf::ZERO };
        SolidAnglePdf(self.distr.visible_pdf(wo, m) / (4.0 * wo.dot(m)))
    }

    /// (`eval`, `pdf`) with the half vector, D and G1(wo) computed once: bit-identical to
    /// calling both (next-event estimation needs both for every light sample).
    #[inline]
    pub fn eval_pdf(&self, wo: Vec3, wi: Vec3) -> (Rgb, SolidAnglePdf) {
        let Some(m) = reflection_half(wo, wi) else { return (Rgb::ZERO, SolidAnglePdf::ZERO) };
        let (d, g1_wo) = (self.distr.d(m), self.distr.g1(wo, m));
        let f = self.eval_at(wo, wi, m, d, g1_wo, || self.distr.g1(wi, m));
        let pdf = SolidAnglePdf(self.distr.visible_pdf_with(wo, m, || d, || g1_wo) / (4.0 * wo.dot(m)));
        (f, pdf)
    }

    /// (`eval`, `pdf`, `pdf` reversed) with the half vector, D and both G1 computed once:
    /// bit-identical to the three calls (a photon merge weighs every photon it finds by
    /// both densities).
    #[inline]
    pub fn eval_pdfs(&self, wo: Vec3, wi: Vec3) -> (Rgb, SolidAnglePdf, SolidAnglePdf) {
        let Some(m) = reflection_half(wo, wi) else { return (Rgb::ZERO, SolidAnglePdf::ZERO, SolidAnglePdf::ZERO) };
        let (d, g1_wo, g1_wi) = (self.distr.d(m), self.distr.g1(wo, m), self.distr.g1(wi, m));
        let f = self.eval_at(wo, wi, m, d, g1_wo, || g1_wi);
        let pdf = SolidAnglePdf(self.distr.visible_pdf_with(wo, m, || d, || g1_wo) / (4.0 * wo.dot(m)));
        let pdf_rev = SolidAnglePdf(self.distr.visible_pdf_with(wi, m, || d, || g1_wi) / (4.0 * wi.dot(m)));
        (f, pdf, pdf_rev)
    }

    /// A visible normal, reflected. The value and both densities share one half vector
    /// (`reflection_half` is symmetric in its arguments, bit for bit), one D and both G1:
    /// the same bits as calling `eval`, `pdf` and `pdf` reversed.
    #[inline]
    pub fn sample(&self, wo: Vec3, u: Vec2) -> Option<BsdfSample> {
        let m = self.distr.sample_visible(wo, u)?;
        let wi = reflect(wo, m);
        if !(wi.z > 0.0) {
            return None;
        }
        let Some(h) = reflection_half(wo, wi) else {
            return BsdfSample::checked_reflection(wi, Rgb::ZERO, SolidAnglePdf::ZERO, SolidAnglePdf::ZERO);
        };
        let (d, g1_wo, g1_wi) = (self.distr.d(h), self.distr.g1(wo, h), self.distr.g1(wi, h));
        let f = self.eval_at(wo, wi, h, d, g1_wo, || g1_wi);
        let pdf = SolidAnglePdf(self.distr.visible_pdf_with(wo, h, || d, || g1_wo) / (4.0 * wo.dot(h)));
        let pdf_rev = SolidAnglePdf(self.distr.visible_pdf_with(wi, h, || d, || g1_wi) / (4.0 * wi.dot(h)));
        BsdfSample::checked_reflection(wi, f, pdf, pdf_rev)
    }
}
