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

/// The Lambertian model as lane code uses it (`estimators::pt_lanes`, `lt_lanes`): the
/// reflectance and two-sidedness of a [`super::Material`] whose lobe is Lambertian, with
/// its evaluation and sampling written without branches. Each function gives the bits
/// of the `Material` method it names, mirroring included, where that method returns a
/// value; where it returns nothing, the flag says so and the values are whatever the
/// arithmetic gave (a select away from being read).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct LambertLane {
    pub rho: Rgb,
    pub two_sided: bool,
}

impl LambertLane {
    /// Seen from the back (a two-sided material mirrors the front there).
    #[inline(always)]
    fn mirrored(self, wo: Vec3) -> bool {
        self.two_sided & (wo.z < 0.0)
    }

    /// `Material::eval_pdf` in either mode (the lobe is symmetric): f (not the cosine)
    /// and p_ω for local `wo` and `wi`.
    #[inline(always)]
    pub fn eval_pdf(self, wo: Vec3, wi: Vec3) -> (Rgb, f32) {
        let m = self.mirrored(wo);
        let (wo_z, wi_z) = (if m { -wo.z } else { wo.z }, if m { -wi.z } else { wi.z });
        let above = (wo_z > 0.0) & (wi_z > 0.0);
        let f = if above { self.rho * INV_PI } else { Rgb::ZERO };
        let f = if f.is_finite() { f } else { Rgb::ZERO };
        let pdf = if above { wi_z.max(0.0) * INV_PI } else { 0.0 };
        (f, if pdf.is_finite() & (pdf >= 0.0) { pdf } else { 0.0 })
    }

    /// `Material::sample` (the lobe has one technique, so no lobe number): local wi, f and
    /// p_ω, and whether the sample exists.
    #[inline(always)]
    pub fn sample(self, wo: Vec3, u: Vec2) -> (Vec3, Rgb, f32, bool) {
        let m = self.mirrored(wo);
        let wo_z = if m { -wo.z } else { wo.z };
        // `Material::sample_front`'s test, then `Diffuse::sample`'s.
        let wo_ok = (wo_z.abs() >= f32::MIN_POSITIVE) & wo.is_finite() & (wo_z > 0.0);
        let d = sample_cosine_hemisphere(u);
        let up = (wo_z > 0.0) & (d.z > 0.0);
        let pdf = if up { d.z.max(0.0) * INV_PI } else { 0.0 };
        let f = if up { self.rho * INV_PI } else { Rgb::ZERO };
        let pdf_rev = if up { wo_z.max(0.0) * INV_PI } else { 0.0 };
        let ok = wo_ok & (pdf > 0.0) & f.is_finite() & pdf.is_finite() & pdf_rev.is_finite();
        (Vec3::new(d.x, d.y, if m { -d.z } else { d.z }), f, pdf, ok)
    }
}
