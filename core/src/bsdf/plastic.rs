//! Smooth plastic (Mitsuba 3's `plastic`): a diffuse base under a perfectly smooth
//! dielectric coating, the first material here with lobes of both kinds.
//!
//! With η = η_int/η_ext, F(μ) the coating's Fresnel reflectance at incidence cosine μ
//! from outside, ρ the base's reflectance and R_s the coating's specular scale:
//! - **Dirac lobe**: the mirror direction, weight R_s F(cos θo).
//! - **Continuous lobe**: light crossing the coating twice and scattered by the base,
//!   f(wo, wi) = ρ' (1 − F(cos θo)) (1 − F(cos θi)) / (π η²),
//!   with ρ' = ρ / (1 − F_dr) (`nonlinear`: ρ / (1 − ρ F_dr) per channel), F_dr the
//!   coating's diffuse reflectance seen from inside (internal reflections, summed).
//!   F_dr is Mitsuba's fitted `fresnel_diffuse_reflectance(1/η)` (Egan and Hilgeman
//!   1973 for η < 1, d'Eon and Irving 2011 above; 0.1 % off the integral at η ≤ 2), so
//!   that images match Mitsuba's exactly in expectation.
//!
//! The lobe is chosen with P(Dirac) = F(cos θo) w / (F(cos θo) w + (1 − F(cos θo))(1 − w)),
//! w = mean(R_s) / (mean(ρ) + mean(R_s)), Mitsuba's weights. [`Material::eval`] and
//! [`Material::pdf`] describe the continuous lobe only (its density is
//! (1 − P(Dirac)) cos θi/π); a drawn mirror direction is a sample with `is_delta`, its
//! discrete probability P(Dirac) as `pdf`, the same from either side (the mirror pair has
//! one cosine), so the MIS bookkeeping of the estimators sees a Dirac bounce where it
//! happened and a diffuse vertex everywhere else (connections use the continuous lobe).
//!
//! [`Material::eval`]: super::Material::eval
//! [`Material::pdf`]: super::Material::pdf

use super::{BsdfSample, fresnel};
use crate::math::{INV_PI, Vec2, Vec3, local};
use crate::measure::SolidAnglePdf;
use crate::spectrum::Rgb;
use crate::warp::{cosine_hemisphere_pdf, sample_cosine_hemisphere};

#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Plastic {
    /// η_int / η_ext.
    pub eta: f32,
    /// ρ' of the module notes.
    pub diffuse: Rgb,
    /// ρ itself.
    pub base: Rgb,
    pub specular_reflectance: Rgb,
    /// w of the module notes.
    pub specular_weight: f32,
    /// F_dr seen from inside.
    pub fdr_int: f32,
    pub nonlinear: bool,
}

/// Mitsuba's fit of the hemispherical average of the Fresnel reflectance at relative
/// index `eta` (`fresnel_diffuse_reflectance`).
pub(crate) fn diffuse_fresnel_reflectance(eta: f32) -> f32 {
    let inv = 1.0 / eta;
    if eta < 1.0 {
        0.0636 * inv + eta * (eta * -1.4399 + 0.7099) + 0.6681
    } else {
        // Horner in 1/η: 0.919317 − 3.4793/η + 6.75335/η² − 7.80989/η³ + 4.98554/η⁴ − 1.36881/η⁵.
        0.919317 + inv * (-3.4793 + inv * (6.75335 + inv * (-7.80989 + inv * (4.98554 + inv * -1.36881))))
    }
}

/// ρ' for a base of reflectance `rho` under a coating that reflects `fdr_int` of the
/// base's light back down (module notes; rough plastic's R_int too).
pub(super) fn effective_diffuse(rho: Rgb, fdr_int: f32, nonlinear: bool) -> Rgb {
    // ρ ≤ 1 and F_dr < 1 keep every denominator positive; a texel above 1 (an EXR) with
    // `nonlinear` could still cross zero: no base then rather than a negative one.
    let rho = if nonlinear { Rgb::new(rho.r.min(1.0), rho.g.min(1.0), rho.b.min(1.0)) } else { rho };
    if nonlinear {
        Rgb::new(rho.r / (1.0 - rho.r * fdr_int), rho.g / (1.0 - rho.g * fdr_int), rho.b / (1.0 - rho.b * fdr_int))
    } else {
        rho * (1.0 / (1.0 - fdr_int))
    }
}

impl Plastic {
    pub fn new(eta: f32, diffuse: Rgb, specular_reflectance: Rgb, nonlinear: bool) -> Self {
        // The fits hold for ordinary indices; far outside them (η = 10³: the Egan–Hilgeman
        // fit gave F_dr = 64, and a negative base, found by fuzzing) F_dr is a reflectance
        // all the same, kept below 1 so that ρ' stays finite and non-negative.
        let fdr_int = diffuse_fresnel_reflectance(1.0 / eta).clamp(0.0, 1.0 - 1e-6);
        let (d_mean, s_mean) = (diffuse.average(), specular_reflectance.average());
        let specular_weight = if d_mean + s_mean > 0.0 { s_mean / (d_mean + s_mean) } else { 0.5 };
        Self { eta, diffuse: effective_diffuse(diffuse, fdr_int, nonlinear), base: diffuse, specular_reflectance, specular_weight, fdr_int, nonlinear }
    }

    /// The same coating over another base (a texture's value at a hit): Mitsuba keeps the
    /// lobe weights of the texture's mean, and so does this.
    pub fn with_diffuse(&self, diffuse: Rgb) -> Self {
        Self { diffuse: effective_diffuse(diffuse, self.fdr_int, self.nonlinear), base: diffuse, ..*self }
    }

    #[inline]
    fn fresnel(&self, mu: f32) -> f32 {
        fresnel::dielectric(mu, self.eta).f
    }

    /// P(Dirac) at `wo` (module notes).
    #[inline]
    fn p_specular(&self, wo: Vec3) -> f32 {
        let f = self.fresnel(wo.z);
        let ps = f * self.specular_weight;
        let pd = (1.0 - f) * (1.0 - self.specular_weight);
        if ps + pd > 0.0 { ps / (ps + pd) } else { 0.0 }
    }

    /// The continuous lobe's value, without the cosine.
    #[inline]
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Rgb {
        if !(wo.z > 0.0 && wi.z > 0.0) {
            return Rgb::ZERO;
        }
        self.diffuse * ((1.0 - self.fresnel(wo.z)) * (1.0 - self.fresnel(wi.z)) * INV_PI / (self.eta * self.eta))
    }

    /// The continuous lobe's density: (1 − P(Dirac)) cos θi/π.
    #[inline]
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> SolidAnglePdf {
        if !(wo.z > 0.0 && wi.z > 0.0) {
            return SolidAnglePdf::ZERO;
        }
        SolidAnglePdf((1.0 - self.p_specular(wo)) * cosine_hemisphere_pdf(wi).value())
    }

    /// The mirror direction with probability P(Dirac), else a cosine-weighted direction.
    #[inline]
    pub fn sample(&self, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        if !(wo.z > 0.0) {
            return None;
        }
        let p = self.p_specular(wo);
        if u_lobe < p {
            let wi = local::reflect(wo);
            // f·cos θi / pdf = R_s F(cos θo) / P(Dirac), the lobe's weight over its choice.
            let f = self.specular_reflectance * (self.fresnel(wo.z) / wi.z);
            let pdf = SolidAnglePdf(p);
            return Some(BsdfSample { wi, f, pdf, pdf_rev: pdf, is_delta: true, is_transmission: false, eta: 1.0 });
        }
        let wi = sample_cosine_hemisphere(u);
        let pdf = self.pdf(wo, wi);
        if !pdf.is_positive() {
            return None;
        }
        Some(BsdfSample::continuous_reflection(wi, self.eval(wo, wi), pdf, self.pdf(wi, wo)))
    }

    /// A reflectance-like colour: the base's through the coating, plus the coating's at
    /// normal incidence.
    pub fn albedo_hint(&self) -> Rgb {
        let f0 = self.fresnel(1.0);
        self.base * (1.0 - f0) + self.specular_reflectance * f0
    }
}
