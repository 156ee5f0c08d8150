//! Rough dielectric interface (Mitsuba's `roughdielectric`): Walter et al.,
//! "Microfacet Models for Refraction through Rough Surfaces", EGSR 2007.
//!
//! With η the relative index η_t/η_i seen from `wo` (η_int/η_ext from outside, its
//! inverse from inside) and m the microfacet normal, flipped to m.z > 0:
//! - reflection (wo, wi on the same side), m = (wo + wi)/|wo + wi|:
//!   f = R_s F(wo·m) D(m) G1(wo,m) G1(wi,m) / (4 |cos θo| |cos θi|)                      (eq. 20)
//! - transmission, generalised half vector m ∝ wo + η wi (eq. 16):
//!   f = T_s s (1 − F) D G η² |wo·m| |wi·m| / (|cos θo| |cos θi| (wo·m + η wi·m)²)        (eq. 21)
//!   with s = 1/η² for [`TransportMode::Radiance`] and s = 1 for
//!   [`TransportMode::Importance`]. Radiance-mode f(wo, wi) is the physical BTDF for light
//!   arriving along wi and leaving along wo; the Importance-mode value is its adjoint,
//!   f*(wo, wi) = f(wi, wo) (Veach's thesis §5.2; Mitsuba's "missing term" comment).
//!
//! Sampling draws a visible normal for ±wo (whichever is above the surface), then
//! reflects with probability F(wo·m) and refracts otherwise, so
//! p(wi) = D_wo(m) F / (4 |wi·m|) for reflection and
//! p(wi) = D_wo(m) (1 − F) η² |wi·m| / (wo·m + η wi·m)² for transmission (eq. 17).
//! Samples whose reflection or refraction lands on the wrong side of the macro-surface
//! are absorbed (`None`; their mass is missing from the pdf too).

use super::microfacet::Microfacet;
use super::{BsdfSample, TransportMode, fresnel};
use crate::math::{Vec2, Vec3, reflect};
use crate::measure::SolidAnglePdf;
use crate::spectrum::Rgb;

/// Rough glass-like interface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct RoughDielectric {
    pub distr: Microfacet,
    /// η_int / η_ext.
    pub eta: f32,
    pub specular_reflectance: Rgb,
    pub specular_transmittance: Rgb,
}

/// The microfacet configuration linking `wo` and `wi`.
#[derive(Clone, Copy, Debug)]
struct Config {
    /// Microfacet normal, m.z > 0.
    m: Vec3,
    reflect: bool,
    /// η_t/η_i seen from `wo`.
    eta: f32,
    dot_o: f32,
    dot_i: f32,
}

impl RoughDielectric {
    /// Half vector (reflection) or generalised half vector (transmission) of (wo, wi),
    /// or `None` for grazing directions and configurations where a direction sees the
    /// back of its facet (Mitsuba's side filter, replicated in eval and pdf).
    #[inline]
    fn config(&self, wo: Vec3, wi: Vec3) -> Option<Config> {
        let (co, ci) = (wo.z, wi.z);
        if co == 0.0 || ci == 0.0 {
            return None;
        }
        let reflect = co * ci > 0.0;
        let eta = if co > 0.0 { self.eta } else { 1.0 / self.eta };
        let m = super::microfacet::half_vector(wo, wi, reflect, eta)?;
        let (dot_o, dot_i) = (wo.dot(m), wi.dot(m));
        if dot_o * co <= 0.0 || dot_i * ci <= 0.0 {
            return None;
        }
        Some(Config { m, reflect, eta, dot_o, dot_i })
    }

    /// BSDF value (module docs), without the cosine.
    #[inline]
    pub fn eval(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> Rgb {
        let Some(c) = self.config(wo, wi) else { return Rgb::ZERO };
        let d = self.distr.d(c.m);
        if d == 0.0 {
            return Rgb::ZERO;
        }
        let f = fresnel::dielectric(c.dot_o, self.eta).f;
        let g = self.distr.g1(wo, c.m) * self.distr.g1(wi, c.m);
        let cos_oi = (wo.z * wi.z).abs();
        // Denormal cosines underflow cos_oi to 0: no finite value (as in the rough conductor).
        let value = if c.reflect {
            self.specular_reflectance * (f * d * g / (4.0 * cos_oi))
        } else {
            let denom = c.dot_o + c.eta * c.dot_i;
            let scale = match mode {
                TransportMode::Radiance => 1.0 / (c.eta * c.eta),
                TransportMode::Importance => 1.0,
            };
            let v = scale * (1.0 - f) * d * g * c.eta * c.eta * (c.dot_o * c.dot_i).abs() / (cos_oi * denom * denom);
            self.specular_transmittance * v
        };
        if value.is_finite() { value } else { Rgb::ZERO }
    }

    /// Density of [`Self::sample`] (module docs).
    #[inline]
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> SolidAnglePdf {
        let Some(c) = self.config(wo, wi) else { return SolidAnglePdf::ZERO };
        let wo_up = if wo.z > 0.0 { wo } else { -wo };
        let p_m = self.distr.visible_pdf(wo_up, c.m);
        if p_m == 0.0 {
            return SolidAnglePdf::ZERO;
        }
        let f = fresnel::dielectric(c.dot_o, self.eta).f;
        let p = if c.reflect {
            // |wo·m| = |wi·m| for reflection; wo·m cancels the VNDF's (see rough_conductor.rs).
            p_m * f / (4.0 * c.dot_o.abs())
        } else {
            let denom = c.dot_o + c.eta * c.dot_i;
            p_m * (1.0 - f) * c.eta * c.eta * c.dot_i.abs() / (denom * denom)
        };
        SolidAnglePdf(p)
    }

    /// Sample a visible normal, then reflect (`u_lobe` < F) or refract. `None` at grazing
    /// `wo` and for samples absorbed by the side test.
    #[inline]
    pub fn sample(&self, wo: Vec3, u_lobe: f32, u: Vec2, mode: TransportMode) -> Option<BsdfSample> {
        if wo.z == 0.0 || !wo.is_finite() {
            return None;
        }
        let wo_up = if wo.z > 0.0 { wo } else { -wo };
        let m = self.distr.sample_visible(wo_up, u)?;
        let fr = fresnel::dielectric(wo.dot(m), self.eta);
        let reflected = u_lobe < fr.f;
        let wi = if reflected { reflect(wo, m) } else { fresnel::refract(wo, m, fr.cos_t, fr.eta_ti).normalize_or_zero() };
        // A reflection must stay on wo's side, a refraction must cross.
        if (wi.z * wo.z > 0.0) != reflected || wi.z == 0.0 {
            return None;
        }
        let pdf = self.pdf(wo, wi);
        let f = self.eval(wo, wi, mode);
        if !(pdf.value() > 0.0 && pdf.value().is_finite() && f.is_finite()) {
            return None;
        }
        Some(BsdfSample { wi, f, pdf, pdf_rev: self.pdf(wi, wo), is_delta: false, is_transmission: !reflected, eta: if reflected { 1.0 } else { fr.eta_it } })
    }

    /// Reflectance-like colour at normal incidence: F0·R_s + (1 − F0)·T_s.
    #[inline]
    pub fn albedo_hint(&self) -> Rgb {
        let f0 = fresnel::dielectric(1.0, self.eta).f;
        self.specular_reflectance * f0 + self.specular_transmittance * (1.0 - f0)
    }
}
