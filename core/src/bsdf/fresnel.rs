//! Fresnel reflectance of dielectric and conducting interfaces, unpolarised, as in
//! Mitsuba 3 (`include/mitsuba/render/fresnel.h`).

use crate::math::{Vec3, Vec4, safe_sqrt};
use crate::spectrum::Rgb;

/// Result of [`dielectric`]: the reflectance and what a refraction needs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct DielectricFresnel {
    /// Unpolarised reflectance F ∈ [0, 1] (1 under total internal reflection).
    pub f: f32,
    /// Signed cosine of the transmitted direction with the normal (opposite sign to the
    /// incident cosine; 0 under total internal reflection).
    pub cos_t: f32,
    /// Relative index η_t/η_i in the direction of travel.
    pub eta_it: f32,
    /// Its reciprocal η_i/η_t, also the scale of the tangential part of the refracted ray.
    pub eta_ti: f32,
}

/// Unpolarised Fresnel reflectance at a dielectric interface (the average of the s and p
/// amplitude reflectances squared; Born & Wolf §1.5.2).
///
/// `cos_i` is the cosine between the incident direction (pointing away from the surface)
/// and the normal; `eta` = η_inside/η_outside, where the normal points outside. A negative
/// `cos_i` means the light arrives from inside, which inverts `eta`. Index matching
/// (`eta == 1`) reflects nothing; grazing incidence (`cos_i == 0`) reflects everything.
#[inline]
pub(crate) fn dielectric(cos_i: f32, eta: f32) -> DielectricFresnel {
    let outside = cos_i >= 0.0;
    let rcp_eta = 1.0 / eta;
    let (eta_it, eta_ti) = if outside { (eta, rcp_eta) } else { (rcp_eta, eta) };

    // Snell: cos²θ_t = 1 − sin²θ_i / η_it².
    let cos_t_sqr = 1.0 - (1.0 - cos_i * cos_i) * eta_ti * eta_ti;
    let cos_i_abs = cos_i.abs();
    let cos_t_abs = safe_sqrt(cos_t_sqr);

    let f = if eta == 1.0 {
        0.0
    } else if cos_i_abs == 0.0 || cos_t_sqr <= 0.0 {
        1.0
    } else {
        let a_s = (cos_i_abs - eta_it * cos_t_abs) / (cos_i_abs + eta_it * cos_t_abs);
        let a_p = (cos_t_abs - eta_it * cos_i_abs) / (cos_t_abs + eta_it * cos_i_abs);
        (0.5 * (a_s * a_s + a_p * a_p)).clamp(0.0, 1.0)
    };
    let cos_t = if cos_i >= 0.0 { -cos_t_abs } else { cos_t_abs };
    DielectricFresnel { f, cos_t, eta_it, eta_ti }
}

/// Refract `w` (pointing away from the surface) through the microfacet `m`, given the
/// `cos_t` and `eta_ti` of [`dielectric`]`(w·m, η)`: t = m (w·m η_ti + cos_t) − w η_ti
/// (Mitsuba's `refract`; Walter et al. 2007, §5).
#[inline]
pub(crate) fn refract(w: Vec3, m: Vec3, cos_t: f32, eta_ti: f32) -> Vec3 {
    m * (w.dot(m) * eta_ti + cos_t) - w * eta_ti
}

/// Unpolarised Fresnel reflectance of a conductor with complex relative index
/// η + i·k, for light arriving from outside with cosine `cos_i` ≥ 0 (K. D. Möller,
/// *Optics*, 1988, as used by Mitsuba's `fresnel_conductor`). The scalar reference form
/// of [`conductor`], which runs the same operations on three channels at once.
#[cfg(test)]
pub(crate) fn conductor_1(cos_i: f32, eta: f32, k: f32) -> f32 {
    let cos2 = cos_i * cos_i;
    let sin2 = 1.0 - cos2;
    let sin4 = sin2 * sin2;
    let temp_1 = eta * eta - k * k - sin2;
    let a2pb2 = safe_sqrt(temp_1 * temp_1 + 4.0 * k * k * eta * eta);
    let a = safe_sqrt(0.5 * (a2pb2 + temp_1));
    let term_1 = a2pb2 + cos2;
    let term_2 = 2.0 * cos_i * a;
    let r_s = (term_1 - term_2) / (term_1 + term_2);
    let term_3 = a2pb2 * cos2 + sin4;
    let term_4 = term_2 * sin2;
    let r_p = r_s * (term_3 - term_4) / (term_3 + term_4);
    let r = 0.5 * (r_s + r_p);
    // 0/0 only for the degenerate η = k = 0 at grazing incidence: call it a mirror.
    if r.is_finite() { r.clamp(0.0, 1.0) } else { 1.0 }
}

/// Unpolarised Fresnel reflectance of a conductor with complex relative index η + i·k
/// per RGB channel, for light arriving from outside with cosine `cos_i` ≥ 0 (K. D.
/// Möller, *Optics*, 1988, as used by Mitsuba's `fresnel_conductor`), the three channels
/// in the lanes of one 4-lane vector: each lane runs the scalar form's operations
/// (`conductor_1`, kept for the tests) in its order, all of them correctly rounded
/// (`+ − × ÷ √`, no fused multiply-add), so each channel is the scalar value to the bit
/// (`conductor_lanes_equal_the_scalar_form`), at about a third of the instructions: the
/// rough conductor calls this once per sample and once per evaluation.
#[inline]
pub(crate) fn conductor(cos_i: f32, eta: Rgb, k: Rgb) -> Rgb {
    let (eta, k) = (Vec4::new(eta.r, eta.g, eta.b, 0.0), Vec4::new(k.r, k.g, k.b, 0.0));
    let cos2 = cos_i * cos_i;
    let sin2 = 1.0 - cos2;
    let sin4 = sin2 * sin2;
    let temp_1 = eta * eta - k * k - Vec4::splat(sin2);
    let a2pb2 = (temp_1 * temp_1 + 4.0 * k * k * eta * eta).max(Vec4::ZERO).sqrt();
    let a = (0.5 * (a2pb2 + temp_1)).max(Vec4::ZERO).sqrt();
    let term_1 = a2pb2 + Vec4::splat(cos2);
    let term_2 = (2.0 * cos_i) * a;
    let r_s = (term_1 - term_2) / (term_1 + term_2);
    let term_3 = a2pb2 * cos2 + Vec4::splat(sin4);
    let term_4 = term_2 * sin2;
    let r_p = r_s * (term_3 - term_4) / (term_3 + term_4);
    let r = 0.5 * (r_s + r_p);
    let lane = |r: f32| if r.is_finite() { r.clamp(0.0, 1.0) } else { 1.0 };
    Rgb::new(lane(r.x), lane(r.y), lane(r.z))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dielectric_known_values() {
        // Normal incidence: ((η−1)/(η+1))² from either side.
        let r0 = ((1.5f32 - 1.0) / 2.5).powi(2);
        assert!((dielectric(1.0, 1.5).f - r0).abs() < 1e-6);
        assert!((dielectric(-1.0, 1.5).f - r0).abs() < 1e-6);
        // Total internal reflection beyond the critical angle from inside.
        assert_eq!(dielectric(-0.5, 1.5).f, 1.0);
        assert_eq!(dielectric(0.0, 1.5).f, 1.0);
        assert_eq!(dielectric(0.3, 1.0).f, 0.0);
        // Reciprocity: F is the same seen from the transmitted side.
        let a = dielectric(0.6, 1.5);
        let b = dielectric(a.cos_t, 1.5);
        assert!((a.f - b.f).abs() < 1e-5, "{a:?} {b:?}");
        assert!((a.eta_it * b.eta_it - 1.0).abs() < 1e-6);
    }

    /// The 4-lane form against the scalar one, bit for bit, over incidence cosines from
    /// grazing to normal and indices from a mirror (η = 0) to gold and aluminium and past
    /// them. Seen failing with `4k²η²` formed as `4 (kη)(kη)`, which rounds
    /// differently (mismatches in the last bit).
    #[test]
    fn conductor_lanes_equal_the_scalar_form() {
        let indices = [(0.0f32, 1.0f32), (0.2, 3.9), (0.143, 3.98), (1.66, 8.1), (1.5, 0.0), (3.0, 0.5), (0.05, 12.0)];
        let mut checked = 0;
        for i in 0..=2000u32 {
            let c = i as f32 / 2000.0;
            for cos_i in [c, c * c * c, 1.0 - c * 1e-3] {
                for &(e, k) in &indices {
                    let (eta, kk) = (Rgb::new(e, e * 0.9, e * 1.1), Rgb::new(k, k * 1.05, k * 0.8));
                    let v = conductor(cos_i, eta, kk);
                    let s = [conductor_1(cos_i, eta.r, kk.r), conductor_1(cos_i, eta.g, kk.g), conductor_1(cos_i, eta.b, kk.b)];
                    assert_eq!([v.r.to_bits(), v.g.to_bits(), v.b.to_bits()], s.map(f32::to_bits), "cos {cos_i}, η {eta:?}, k {kk:?}");
                    checked += 1;
                }
            }
        }
        assert_eq!(checked, 2001 * 3 * indices.len());
    }

    #[test]
    fn conductor_limits() {
        // k = 0 reduces to the dielectric Fresnel.
        for c in [1.0f32, 0.8, 0.4, 0.1] {
            let d = dielectric(c, 1.7).f;
            let k = conductor_1(c, 1.7, 0.0);
            assert!((d - k).abs() < 1e-5, "{c}: {d} vs {k}");
        }
        // Normal incidence: ((η−1)² + k²)/((η+1)² + k²).
        let (n, k) = (0.2f32, 3.9f32);
        let r0 = ((n - 1.0).powi(2) + k * k) / ((n + 1.0).powi(2) + k * k);
        assert!((conductor_1(1.0, n, k) - r0).abs() < 1e-5);
        // Mitsuba's default (η = 0, k = 1) is a perfect mirror; grazing is always 1.
        for c in [1.0f32, 0.5, 0.01] {
            assert!((conductor_1(c, 0.0, 1.0) - 1.0).abs() < 1e-6);
        }
        assert!((conductor_1(0.0, 0.2, 3.9) - 1.0).abs() < 1e-6);
    }
}
