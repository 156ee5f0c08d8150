//! Smooth dielectric interface (Mitsuba's `dielectric`): a Dirac reflection chosen with
//! probability F and a Dirac refraction chosen with probability 1 − F, F the unpolarised
//! Fresnel reflectance. Two-sided by nature: from inside (wo.z < 0) the relative index
//! inverts.
//!
//! Weights f·|cos θi|/pdf: R_s for reflection; T_s·(η_i/η_t)² for refraction in
//! [`TransportMode::Radiance`] (radiance is compressed into the denser medium; Veach's
//! thesis §5.2) and T_s in [`TransportMode::Importance`] (importance is not; pbrt-v3
//! `SpecularTransmission`, Mitsuba's `dielectric`).

use super::{BsdfSample, TransportMode, fresnel};
use crate::math::{Vec3, local};
use crate::measure::SolidAnglePdf;
use crate::spectrum::Rgb;

/// Smooth glass-like interface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Dielectric {
    /// η_int / η_ext.
    pub eta: f32,
    pub specular_reflectance: Rgb,
    pub specular_transmittance: Rgb,
}

impl Dielectric {
    /// Choose reflection if `u_lobe` < F, else refraction. `None` at exactly grazing `wo`.
    #[inline]
    pub fn sample(&self, wo: Vec3, u_lobe: f32, mode: TransportMode) -> Option<BsdfSample> {
        if wo.z == 0.0 || !wo.z.is_finite() {
            return None;
        }
        let fr = fresnel::dielectric(wo.z, self.eta);
        if u_lobe < fr.f {
            let wi = local::reflect(wo);
            Some(BsdfSample {
                wi,
                f: self.specular_reflectance * (fr.f / wi.z.abs()),
                pdf: SolidAnglePdf(fr.f),
                // The reverse choice sees the same angle, hence the same F.
                pdf_rev: SolidAnglePdf(fr.f),
                is_delta: true,
                is_transmission: false,
                eta: 1.0,
            })
        } else {
            let wi = fresnel::refract(wo, Vec3::Z, fr.cos_t, fr.eta_ti).normalize_or_zero();
            let t = 1.0 - fr.f;
            if wi.z == 0.0 || !(t > 0.0) {
                return None;
            }
            let scale = match mode {
                TransportMode::Radiance => fr.eta_ti * fr.eta_ti,
                TransportMode::Importance => 1.0,
            };
            let t_rev = 1.0 - fresnel::dielectric(wi.z, self.eta).f;
            Some(BsdfSample {
                wi,
                f: self.specular_transmittance * (t * scale / wi.z.abs()),
                pdf: SolidAnglePdf(t),
                pdf_rev: SolidAnglePdf(t_rev),
                is_delta: true,
                is_transmission: true,
                eta: fr.eta_it,
            })
        }
    }

    /// Reflectance-like colour at normal incidence: F0·R_s + (1 − F0)·T_s.
    #[inline]
    pub fn albedo_hint(&self) -> Rgb {
        let f0 = fresnel::dielectric(1.0, self.eta).f;
        self.specular_reflectance * f0 + self.specular_transmittance * (1.0 - f0)
    }
}
