//! Rough plastic (Mitsuba 3 `roughplastic`, isotropic): a diffuse base under a rough
//! dielectric coating, with the coating's internal scattering folded into the base as
//! Mitsuba does (`nonlinear` false by default).
//!
//!   f(wo, wi) = R_s F(wo·h) D(h) G1(wo, h) G1(wi, h) / (4 cos θo cos θi)
//!             + ρ' T(cos θo) T(cos θi) / (π η²),
//!
//! with h the half vector, F the dielectric Fresnel term at η = η_int/η_ext, T(μ) the
//! coating's transmittance for light arriving at cosine μ (the fraction of a visible-
//! normal refraction that leaves the facet unmasked), and ρ' = ρ/(1 − R_int) (or
//! ρ/(1 − ρ R_int) per channel, `nonlinear`), R_int the coating's hemispherical
//! reflectance from inside. T is tabulated at 64 cosines and interpolated linearly, and
//! R_int is 2 ∫ R(μ) μ dμ over the same cosines; both are Gauss–Legendre quadratures of
//! expectations over visible normals (32² nodes from outside, 128² from inside), as
//! Mitsuba 3's `eval_transmittance` and `eval_reflectance` compute them, so the model is
//! the one its references were rendered with. f is symmetric in (wo, wi).
//!
//! Sampling picks the coating with probability ∝ (1 − T(cos θo)) w_s, the base with
//! ∝ T(cos θo)(1 − w_s), w_s = mean(R_s)/(mean(ρ) + mean(R_s)); the coating reflects a
//! visible normal, the base draws a cosine-weighted direction. The density is the
//! mixture of both: p = P_s D_wo(h)/(4 wo·h) + P_d cos θi/π.

use alloc::vec::Vec;

use super::microfacet::{Microfacet, reflection_half};
use super::plastic::effective_diffuse;
use super::{BsdfSample, fresnel};
use crate::math::{Vec2, Vec3, reflect, sqrt};
use crate::measure::SolidAnglePdf;
use crate::spectrum::Rgb;
use crate::warp;

/// Cosines at which the coating's transmittance is tabulated (Mitsuba's
/// `MI_ROUGH_TRANSMITTANCE_RES`).
const RES: usize = 64;

/// Rough plastic; black from the back.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct RoughPlastic {
    pub distr: Microfacet,
    /// η_int / η_ext.
    pub eta: f32,
    /// ρ' (module notes): the base's reflectance with the internal reflections folded in.
    pub diffuse: Rgb,
    /// ρ itself, for the albedo hint.
    pub base: Rgb,
    pub specular_reflectance: Rgb,
    /// w_s of the module notes.
    pub specular_weight: f32,
    /// T at cos θ = max(10⁻⁶, k/(RES − 1)).
    pub transmittance: [f32; RES],
    /// The coating's internal reflectance R_int, and `nonlinear`: what ρ' needs.
    pub internal: f32,
    pub nonlinear: bool,
}

/// Gauss–Legendre nodes and weights on [−1, 1] (Newton's method on P_n from the
/// Chebyshev guesses; double precision).
fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        let mut x = libm::cos(core::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5));
        let mut dp = 1.0;
        for _ in 0..100 {
            // P_n(x) and P_n'(x) by the three-term recurrence.
            let (mut p0, mut p1) = (1.0f64, x);
            for k in 2..=n {
                let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
                p0 = p1;
                p1 = p2;
            }
            let p = if n == 0 { 1.0 } else { p1 };
            let prev = if n <= 1 { 1.0 } else { p0 };
            dp = n as f64 * (x * p - prev) / (x * x - 1.0);
            let dx = p / dp;
            x -= dx;
            if dx.abs() < 1e-15 {
                break;
            }
        }
        out.push((x, 2.0 / ((1.0 - x * x) * dp * dp)));
    }
    out
}

/// Expectation over visible normals seen from `wi` (a Gauss–Legendre quadrature of the
/// unit square the sampler maps, on `nodes` in each axis) of the coating's unmasked
/// transmission (`transmit`) or reflection, at relative index `eta` seen from `wi`'s
/// side. Mitsuba takes 32 nodes for η > 1 and 128 otherwise.
fn coating_average(distr: &Microfacet, wi: Vec3, eta: f32, transmit: bool, nodes: &[(f64, f64)]) -> f32 {
    let mut sum = 0.0f64;
    for &(x, wx) in nodes {
        for &(y, wy) in nodes {
            let u = Vec2::new((0.5 * x + 0.5) as f32, (0.5 * y + 0.5) as f32);
            let Some(m) = distr.sample_visible(wi, u) else { continue };
            let fr = fresnel::dielectric(wi.dot(m), eta);
            let value = if transmit {
                let wo = fresnel::refract(wi, m, fr.cos_t, fr.eta_ti);
                if wo.z * wi.z >= 0.0 { 0.0 } else { distr.g1(wo.normalize_or_zero(), m) * (1.0 - fr.f) }
            } else {
                let wo = reflect(wi, m);
                if wo.z <= 0.0 || wi.z <= 0.0 { 0.0 } else { distr.g1(wo, m) * fr.f }
            };
            sum += f64::from(value) * wx * wy * 0.25;
        }
    }
    sum as f32
}

/// A rough plastic's coating: the microfacet interface and its tables (T at 64 cosines,
/// R_int). Building it is the expensive part of a rough plastic (70 ms for GGX, 0.85 s
/// for Beckmann, whose visible-normal sampler is slower), and it depends on the
/// distribution, α and η only, so hosts build one per distinct coating and give it to
/// every material that has it ([`super::Material::rough_plastic_coated`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlasticCoating {
    distr: Microfacet,
    eta: f32,
    transmittance: [f32; RES],
    internal: f32,
}

impl PlasticCoating {
    /// The coating of distribution `distr` at relative index `eta` (η_int/η_ext).
    pub(crate) fn new(distr: Microfacet, eta: f32) -> Self {
        let nodes = |eta: f32| gauss_legendre(if eta > 1.0 { 32 } else { 128 });
        let (outside, inside) = (nodes(eta), nodes(1.0 / eta));
        let mut transmittance = [0.0f32; RES];
        let mut internal = 0.0f64;
        for (k, t) in transmittance.iter_mut().enumerate() {
            let mu = (k as f32 / (RES - 1) as f32).max(1e-6);
            let wi = Vec3::new(sqrt(1.0 - mu * mu), 0.0, mu);
            *t = coating_average(&distr, wi, eta, true, &outside);
            internal += f64::from(coating_average(&distr, wi, 1.0 / eta, false, &inside) * mu);
        }
        Self { distr, eta, transmittance, internal: (2.0 * internal / RES as f64) as f32 }
    }
}

impl RoughPlastic {
    /// `coating` over a base of reflectance `diffuse`.
    pub fn new(coating: &PlasticCoating, diffuse: Rgb, specular_reflectance: Rgb, nonlinear: bool) -> Self {
        let internal = coating.internal;
        let (d_mean, s_mean) = (diffuse.average(), specular_reflectance.average());
        let specular_weight = if d_mean + s_mean > 0.0 { s_mean / (d_mean + s_mean) } else { 0.5 };
        Self {
            distr: coating.distr,
            eta: coating.eta,
            diffuse: effective_diffuse(diffuse, internal, nonlinear),
            base: diffuse,
            specular_reflectance,
            specular_weight,
            transmittance: coating.transmittance,
            internal,
            nonlinear,
        }
    }

    /// The same coating over another base (a texture's value at a hit), keeping the lobe
    /// weights of the texture's mean as Mitsuba does.
    pub fn with_diffuse(&self, diffuse: Rgb) -> Self {
        Self { diffuse: effective_diffuse(diffuse, self.internal, self.nonlinear), base: diffuse, ..*self }
    }

    /// T(μ), linear between the tabulated cosines (Mitsuba's `lerp_gather`).
    #[inline]
    fn t(&self, mu: f32) -> f32 {
        let x = mu.clamp(0.0, 1.0) * (RES - 1) as f32;
        let i = (x as usize).min(RES - 2);
        let f = x - i as f32;
        self.transmittance[i] * (1.0 - f) + self.transmittance[i + 1] * f
    }

    /// P(coating) for `wo` (module notes).
    #[inline]
    fn p_specular(&self, wo: Vec3) -> f32 {
        let t = self.t(wo.z);
        let ps = (1.0 - t) * self.specular_weight;
        let pd = t * (1.0 - self.specular_weight);
        if ps + pd > 0.0 { ps / (ps + pd) } else { 0.0 }
    }

    /// BSDF value (module notes), without the cosine.
    #[inline]
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Rgb {
        if !(wo.z > 0.0 && wi.z > 0.0) {
            return Rgb::ZERO;
        }
        let mut value = self.diffuse * (self.t(wo.z) * self.t(wi.z) / (core::f32::consts::PI * self.eta * self.eta));
        if let Some(m) = reflection_half(wo, wi) {
            let d = self.distr.d(m);
            let g = self.distr.g1(wo, m) * self.distr.g1(wi, m);
            let s = fresnel::dielectric(wo.dot(m), self.eta).f * d * g / (4.0 * wo.z * wi.z);
            if s.is_finite() {
                value += self.specular_reflectance * s;
            }
        }
        value
    }

    /// Density of [`Self::sample`] (module notes).
    #[inline]
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> SolidAnglePdf {
        if !(wo.z > 0.0 && wi.z > 0.0) {
            return SolidAnglePdf::ZERO;
        }
        let ps = self.p_specular(wo);
        let spec = reflection_half(wo, wi).map_or(0.0, |m| self.distr.visible_pdf(wo, m) / (4.0 * wo.dot(m)));
        SolidAnglePdf(ps * spec + (1.0 - ps) * warp::cosine_hemisphere_pdf(wi).value())
    }

    /// The coating's reflection of a visible normal (with probability P(coating)) or a
    /// cosine-weighted direction off the base. `None` from the back or below the surface.
    #[inline]
    pub fn sample(&self, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        if !(wo.z > 0.0) {
            return None;
        }
        let wi = if u_lobe < self.p_specular(wo) { reflect(wo, self.distr.sample_visible(wo, u)?) } else { warp::sample_cosine_hemisphere(u) };
        if !(wi.z > 0.0) {
            return None;
        }
        BsdfSample::checked_reflection(wi, self.eval(wo, wi), self.pdf(wo, wi), self.pdf(wi, wo))
    }

    /// A reflectance-like colour: the base's, plus the coating's at normal incidence.
    pub fn albedo_hint(&self) -> Rgb {
        let f0 = fresnel::dielectric(1.0, self.eta).f;
        self.base * (1.0 - f0) + self.specular_reflectance * f0
    }
}
