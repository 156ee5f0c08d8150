//! Isotropic microfacet normal distributions (Beckmann and GGX / Trowbridge–Reitz):
//! the distribution D, Smith's masking Λ and G1, and the sampling of visible normals
//! with its density, side by side.
//!
//! Conventions follow Mitsuba 3 (`include/mitsuba/render/microfacet.h`), whose
//! references the suite is compared against:
//! - `alpha` is the distribution's own roughness (the RMS slope for Beckmann), clamped
//!   below at 10⁻⁴ like Mitsuba's `configure()`;
//! - masking is Smith's separable form G(wo, wi, m) = G1(wo, m)·G1(wi, m);
//! - sampling draws visible normals, D_wo(m) = G1(wo, m) max(0, wo·m) D(m) / cos θo
//!   (Heitz & d'Eon, "Importance Sampling Microfacet-Based BSDFs using the Distribution
//!   of Visible Normals", EGSR 2014).
//!
//! One deliberate difference: Mitsuba evaluates the Beckmann G1 with a rational fit
//! (relative error < 0.35 %); here Λ is evaluated exactly (Walter et al. 2007, §5.1),
//! so that the visible-normal density integrates to exactly one and matches what the
//! sampler (which inverts the exact CDF in both codes) actually draws.

use super::MicrofacetKind;
use crate::math::{INV_PI, PI, Vec2, Vec3, erf, erfinv, exp, ln, safe_sqrt, sin_cos_turns, sqrt};

/// Smallest roughness accepted (Mitsuba clamps to the same value).
pub(crate) const MIN_ALPHA: f32 = 1e-4;
/// 1/√π.
const INV_SQRT_PI: f32 = 0.564_189_58;

/// An isotropic microfacet distribution of normals around +z.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Microfacet {
    pub kind: MicrofacetKind,
    /// Roughness, ≥ [`MIN_ALPHA`].
    pub alpha: f32,
}

impl Microfacet {
    /// Distribution of the given kind; `alpha` below 10⁻⁴ (or NaN) becomes 10⁻⁴.
    #[inline]
    pub fn new(kind: MicrofacetKind, alpha: f32) -> Self {
        // `max` returns the non-NaN operand, so NaN also lands on the floor.
        Self { kind, alpha: alpha.max(MIN_ALPHA) }
    }

    /// Normal distribution D(m) per steradian of microfacet normals, normalised so that
    /// ∫ D(m) cos θm dm = 1 (Walter et al. 2007, §5). Zero for m.z ≤ 0 and,
    /// as in Mitsuba, where D·cos θm underflows below 10⁻²⁰.
    #[inline]
    pub fn d(&self, m: Vec3) -> f32 {
        let cos = m.z;
        if cos <= 0.0 {
            return 0.0;
        }
        let a2 = self.alpha * self.alpha;
        let cos2 = cos * cos;
        let sin2 = m.x * m.x + m.y * m.y;
        let result = match self.kind {
            MicrofacetKind::Beckmann => exp(-sin2 / (a2 * cos2)) / (PI * a2 * cos2 * cos2),
            MicrofacetKind::Ggx => {
                let t = sin2 / a2 + cos2;
                INV_PI / (a2 * t * t)
            }
        };
        // Also maps NaN (0/0 at cos θm → 0) to zero.
        if result * cos > 1e-20 { result } else { 0.0 }
    }

    /// Smith's Λ(v) for the direction `v` (either hemisphere; only |tan θv| matters).
    ///
    /// GGX: Λ = (√(1 + α² tan²θ) − 1)/2. Beckmann, with a = 1/(α |tan θ|):
    /// Λ = (erf(a) − 1)/2 + e^(−a²)/(2a√π) (Walter et al. 2007, §5, through
    /// G1 = 1/(1 + Λ)). Normal incidence gives 0, grazing +∞.
    #[inline]
    pub fn lambda(&self, v: Vec3) -> f32 {
        let xy2 = v.x * v.x + v.y * v.y;
        if xy2 == 0.0 {
            return 0.0;
        }
        let z2 = v.z * v.z;
        if z2 == 0.0 {
            return f32::INFINITY;
        }
        let a2_tan2 = self.alpha * self.alpha * xy2 / z2;
        match self.kind {
            MicrofacetKind::Ggx => 0.5 * (sqrt(1.0 + a2_tan2) - 1.0),
            MicrofacetKind::Beckmann => {
                let a = 1.0 / sqrt(a2_tan2);
                if a >= 8.0 {
                    // erfc(8) < 1e-28 and the second term < 1e-29: no masking to f32 precision.
                    return 0.0;
                }
                (0.5 * (erf(a) - 1.0) + exp(-a * a) * (0.5 * INV_SQRT_PI) / a).max(0.0)
            }
        }
    }

    /// Smith's masking of the microfacet `m` seen from `v`: 1/(1 + Λ(v)), and zero when `v`
    /// sees the back of the facet or the facet from the wrong side of the macro-surface
    /// ((v·m)(v·n) ≤ 0), as in Mitsuba's `smith_g1`.
    #[inline]
    pub fn g1(&self, v: Vec3, m: Vec3) -> f32 {
        if v.dot(m) * v.z <= 0.0 {
            return 0.0;
        }
        let l = self.lambda(v);
        if l.is_finite() { 1.0 / (1.0 + l) } else { 0.0 }
    }

    /// Draw a visible normal for the direction `wo` (upper hemisphere, unit) from `u`.
    ///
    /// GGX: Heitz, "Sampling the GGX Distribution of Visible Normals", JCGT 7(4), 2018.
    /// Beckmann: the stretch / sample-slopes / unstretch construction of Heitz & d'Eon
    /// (2014) with the slope sampler of Jakob, "An Improved Visible Normal Sampling
    /// Routine for the Beckmann Distribution" (2014), as in Mitsuba 3.
    /// Returns `None` for `wo.z ≤ 0` or if the construction degenerates numerically.
    /// The density is [`Self::visible_pdf`].
    #[inline]
    pub fn sample_visible(&self, wo: Vec3, u: Vec2) -> Option<Vec3> {
        if !(wo.z > 0.0) {
            return None;
        }
        let a = self.alpha;
        // Step 1: stretch wo to the configuration of roughness 1.
        let vh = Vec3::new(a * wo.x, a * wo.y, wo.z).normalize_or_zero();
        if vh == Vec3::ZERO {
            return None;
        }
        let m = match self.kind {
            MicrofacetKind::Ggx => {
                // Unstretch the stretched-space normal.
                let nh = ggx_visible_stretched(vh, u);
                Vec3::new(a * nh.x, a * nh.y, nh.z.max(0.0)).normalize_or_zero()
            }
            MicrofacetKind::Beckmann => {
                let r = sqrt(vh.x * vh.x + vh.y * vh.y);
                let (sin_phi, cos_phi) = if r > 0.0 { (vh.y / r, vh.x / r) } else { (0.0, 1.0) };
                // Step 2: sample the slopes of the roughness-1 distribution seen from vh.
                let slope = beckmann_visible_slopes_11(vh.z, u);
                // Step 3: rotate back and unstretch.
                let sx = (cos_phi * slope.x - sin_phi * slope.y) * a;
                let sy = (sin_phi * slope.x + cos_phi * slope.y) * a;
                // Step 4: the normal of that slope.
                Vec3::new(-sx, -sy, 1.0).normalize_or_zero()
            }
        };
        if m.z > 0.0 && m.is_finite() { Some(m) } else { None }
    }

    /// Density per steradian of [`Self::sample_visible`]: D_wo(m) = G1(wo, m) max(0, wo·m)
    /// D(m) / cos θo (Heitz & d'Eon 2014), for `wo` in the upper hemisphere.
    #[inline]
    pub fn visible_pdf(&self, wo: Vec3, m: Vec3) -> f32 {
        self.visible_pdf_with(wo, m, || self.d(m), || self.g1(wo, m))
    }

    /// [`Self::visible_pdf`] with D(m) and G1(wo, m) supplied by the caller (drawn only
    /// when needed), so that a model evaluating its value and density together computes
    /// them once. Same operations, same bits.
    #[inline]
    pub fn visible_pdf_with(&self, wo: Vec3, m: Vec3, d: impl FnOnce() -> f32, g1: impl FnOnce() -> f32) -> f32 {
        if !(wo.z > 0.0) {
            return 0.0;
        }
        let cos_om = wo.dot(m);
        if cos_om <= 0.0 {
            return 0.0;
        }
        let d = d();
        if d == 0.0 {
            return 0.0;
        }
        d * g1() * cos_om / wo.z
    }
}

/// Slopes of visible normals of the roughness-1 Beckmann distribution seen from a
/// direction with cosine `cos_theta_i` in the xz-plane (φ = 0).
///
/// Jakob's numerical inversion (Mitsuba's `sample_visible_11`): the x-slope CDF,
/// parameterised in the erf domain, is inverted by three Newton steps from the analytic
/// solution for grazing incidence; the y-slope is Gaussian, erf⁻¹(2u − 1).
/// The generalised half vector (Walter et al. 2007, eq. 16): wo + wi for a reflection,
/// wo + η wi for a refraction (η the index ratio the caller uses for that side), unit and
/// turned to the upper hemisphere; `None` where it vanishes or is not finite.
#[inline]
pub(super) fn half_vector(wo: Vec3, wi: Vec3, reflect: bool, eta: f32) -> Option<Vec3> {
    let h = if reflect { wo + wi } else { wo + wi * eta };
    let l2 = h.length_squared();
    if !(l2 > 0.0 && l2.is_finite()) {
        return None;
    }
    let m = h / sqrt(l2);
    Some(if m.z < 0.0 { -m } else { m })
}

/// The GGX visible-normal draw in the stretched space where the distribution is the unit
/// hemisphere (Heitz, "Sampling the GGX Distribution of Visible Normals", JCGT 7(4),
/// 2018): `vh` the stretched unit view direction (z > 0), `u` uniform; the caller
/// unstretches by its roughness (isotropic here, anisotropic in `principled`).
#[inline]
pub(super) fn ggx_visible_stretched(vh: Vec3, u: Vec2) -> Vec3 {
    // Orthonormal basis around vh (T1 is horizontal).
    let lensq = vh.x * vh.x + vh.y * vh.y;
    let t1 = if lensq > 0.0 { Vec3::new(-vh.y, vh.x, 0.0) / sqrt(lensq) } else { Vec3::X };
    let t2 = vh.cross(t1);
    // Uniform point on the disk, warped onto the visible half of the projection.
    let r = sqrt(u.x);
    let (sp, cp) = sin_cos_turns(u.y);
    let p1 = r * cp;
    let s = 0.5 * (1.0 + vh.z);
    let p2 = (1.0 - s) * safe_sqrt(1.0 - p1 * p1) + s * (r * sp);
    // Reproject onto the hemisphere.
    t1 * p1 + t2 * p2 + vh * safe_sqrt(1.0 - p1 * p1 - p2 * p2)
}

fn beckmann_visible_slopes_11(cos_theta_i: f32, u: Vec2) -> Vec2 {
    let tan_theta_i = safe_sqrt(1.0 - cos_theta_i * cos_theta_i) / cos_theta_i;
    let cot_theta_i = 1.0 / tan_theta_i;

    // Search interval, in the erf() domain.
    let maxval = erf(cot_theta_i);

    // Initial guess: the analytic solution for θi = π/2, the most nonlinear case.
    let u = Vec2::new(u.x.clamp(1e-6, 1.0 - 1e-6), u.y.clamp(1e-6, 1.0 - 1e-6));
    let mut x = maxval - (maxval + 1.0) * erf(sqrt(-ln(u.x)));

    // Normalisation of the CDF: 1 + erf(cot θi) + tan θi e^(−cot²θi)/√π. At normal
    // incidence tan = 0 and the e^(−∞) term must not become 0·∞.
    let tail = if tan_theta_i > 0.0 { INV_SQRT_PI * tan_theta_i * exp(-cot_theta_i * cot_theta_i) } else { 0.0 };
    let target = u.x * (1.0 + maxval + tail);

    // Three Newton iterations on 1 + x + tan e^(−erfinv(x)²)/√π = target.
    for _ in 0..3 {
        let slope = erfinv(x);
        let value = 1.0 + x + INV_SQRT_PI * tan_theta_i * exp(-slope * slope) - target;
        let derivative = 1.0 - slope * tan_theta_i;
        let step = value / derivative;
        if step.is_finite() {
            x = (x - step).clamp(-1.0, maxval);
        }
    }
    Vec2::new(erfinv(x), erfinv(2.0 * u.y - 1.0))
}

/// The half vector of a reflection configuration: both directions above the surface and
/// on the front of the facet between them, or `None` (shared by the microfacet
/// reflection models).
#[inline]
pub(super) fn reflection_half(wo: Vec3, wi: Vec3) -> Option<Vec3> {
    if !(wo.z > 0.0 && wi.z > 0.0) {
        return None;
    }
    let h = wo + wi;
    let l2 = h.length_squared();
    if !(l2 > 0.0) {
        return None;
    }
    let m = h / crate::math::sqrt(l2);
    if wo.dot(m) > 0.0 && wi.dot(m) > 0.0 { Some(m) } else { None }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;

    /// ∫ over the upper hemisphere of g(m) dm by the midpoint rule in (cos θ, φ), with
    /// cos θ = 1 − t^k to resolve narrow peaks near the pole.
    fn hemisphere_integral(g: impl Fn(Vec3) -> f64) -> f64 {
        let (nt, np, k) = (2000usize, 256usize, 3.0f64);
        let mut total = 0.0;
        for i in 0..nt {
            let t = (i as f64 + 0.5) / nt as f64;
            let one_minus_cos = t.powf(k);
            let dcos = k * t.powf(k - 1.0) / nt as f64;
            let cos = 1.0 - one_minus_cos;
            let sin = (1.0 - cos * cos).max(0.0).sqrt();
            for j in 0..np {
                let phi = (j as f64 + 0.5) / np as f64 * core::f64::consts::TAU;
                let m = Vec3::new((sin * phi.cos()) as f32, (sin * phi.sin()) as f32, cos as f32);
                total += g(m) * dcos * core::f64::consts::TAU / np as f64;
            }
        }
        total
    }

    #[test]
    fn projected_area_and_visible_normals_are_normalised() {
        for kind in [MicrofacetKind::Beckmann, MicrofacetKind::Ggx] {
            for alpha in [0.05f32, 0.3, 1.0] {
                let d = Microfacet::new(kind, alpha);
                // GGX's tail holds mass down to the horizon: allow for the quadrature.
                let tol = 2e-3;
                let proj = hemisphere_integral(|m| d.d(m) as f64 * m.z as f64);
                assert!((proj - 1.0).abs() < tol, "{kind:?} {alpha}: ∫D cos = {proj}");
                for theta in [0.0f32, 0.8, 1.4] {
                    let wo = Vec3::new(theta.sin(), 0.0, theta.cos());
                    let vis = hemisphere_integral(|m| d.visible_pdf(wo, m) as f64);
                    assert!((vis - 1.0).abs() < tol, "{kind:?} {alpha} θ={theta}: ∫D_wo = {vis}");
                }
            }
        }
    }

    #[test]
    fn lambda_limits() {
        for kind in [MicrofacetKind::Beckmann, MicrofacetKind::Ggx] {
            let d = Microfacet::new(kind, 0.5);
            assert_eq!(d.lambda(Vec3::Z), 0.0);
            assert_eq!(d.g1(Vec3::new(1.0, 0.0, 0.0), Vec3::Z), 0.0);
            let g = d.g1(Vec3::new(0.6, 0.0, 0.8), Vec3::Z);
            assert!(g > 0.8 && g < 1.0, "{kind:?} {g}");
        }
        // Beckmann: Λ(a = 1) from the closed form.
        let d = Microfacet::new(MicrofacetKind::Beckmann, 1.0);
        let v = Vec3::new(core::f32::consts::FRAC_1_SQRT_2, 0.0, core::f32::consts::FRAC_1_SQRT_2);
        let expected = 0.5 * (0.842_700_8 - 1.0) + (-1.0f32).exp() * 0.5 * INV_SQRT_PI;
        assert!((d.lambda(v) - expected).abs() < 1e-5);
    }
}
