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
        let d = self.distr.d(m);
        if d == 0.0 {
            return Rgb::ZERO;
        }
        let g = self.distr.g1(wo, m) * self.distr.g1(wi, m);
        // Both cosines denormal: the product underflows to 0 (fuzzing found 0/0 here).
        let scalar = d * g / (4.0 * wo.z * wi.z);
        if !scalar.is_finite() {
            return Rgb::ZERO;
        }
        fresnel::conductor(wo.dot(m), self.eta, self.k) * self.specular_reflectance * scalar
    }

    /// Density of [`Self::sample`]: D_wo(h) / (4 wi·h).
    #[inline]
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> SolidAnglePdf {
        let Some(m) = reflection_half(wo, wi) else { return SolidAnglePdf::ZERO };
        // The Jacobian's wi·m equals wo·m for the exact half vector; dividing by wo·m lets
        // it cancel the VNDF's own wo·m. With wi·m, a grazing pair (wo + wi nearly
        // cancelling) turned f32 rounding in |wi| into a wrong ratio wi·m / wo·m: albedo
        // 3.3 (GGX) to 5.9 (Beckmann) at 89.999° and α = 1e-4 (stability_extremes.rs).
        SolidAnglePdf(self.distr.visible_pdf(wo, m) / (4.0 * wo.dot(m)))
    }

    /// Reflect `wo` about a visible normal; `None` from the back side or when the
    /// reflection goes below the surface (that mass is absorbed, as in Mitsuba).
    #[inline]
    pub fn sample(&self, wo: Vec3, u: Vec2) -> Option<BsdfSample> {
        let m = self.distr.sample_visible(wo, u)?;
        let wi = reflect(wo, m);
        if !(wi.z > 0.0) {
            return None;
        }
        BsdfSample::checked_reflection(wi, self.eval(wo, wi), self.pdf(wo, wi), self.pdf(wi, wo))
    }
}
