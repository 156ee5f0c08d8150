//! Exact ray–sphere intersection.
//!
//! The quadratic |o + t·d − c|² = r² is solved with the two numerically robust steps of
//! Haines et al., "Precision Improvements for Ray/Sphere Intersection" (Ray Tracing
//! Gems, ch. 7), as pbrt-v4's `Sphere::BasicIntersect` does:
//! - the discriminant is formed as 4a·(r − |v|)(r + |v|) with v = f − (f·d / a)·d, the
//!   offset of the centre from the ray's closest approach, instead of b² − 4ac (which
//!   cancels catastrophically for small spheres far from the origin);
//! - the smaller-magnitude root is taken as c/q with q = −½(b + sign(b)·√Δ), avoiding the
//!   cancellation of −b + √Δ.
//!
//! Everything runs in f64. A scene holds few analytic spheres, so the cost is nil, and
//! the result's error (~1e-16 relative) is far below the 256-ulp f32 offset that
//! `spawn_ray` applies: a ray leaving a sphere never re-hits it at t ≈ 0, without the
//! interval arithmetic pbrt needs in f32.

use glam::{DVec3, Vec3, Vec3A};
use obvhs::ray::Ray as BvhRay;

use ember_core::shapes::Sphere;

/// A box around a sphere, grown so that a ray whose f32 slab test misses it cannot hit
/// the sphere: by 10⁻⁴ of the radius and 10⁻⁶ of the coordinates' scale (far above the
/// rounding of c ± r), with the far distances widened by 1 + 2γ₃ as in pbrt-v4. It lets
/// the list of spheres skip the f64 quadratic for rays that pass far from a sphere (most
/// of them: on veach-mis and glossy every query tested every light sphere). The f64
/// test still decides every ray that enters the box, so hits are unchanged.
#[derive(Clone, Copy, Debug)]
#[allow(dead_code, reason = "the browser host compiles this file and tests its few spheres without boxes")]
pub(crate) struct SphereBox {
    min: Vec3A,
    max: Vec3A,
}

#[allow(dead_code, reason = "see SphereBox")]
impl SphereBox {
    pub(crate) fn new(s: &Sphere) -> Self {
        let c = Vec3A::from(s.center);
        let pad = s.radius * (1.0 + 1e-4) + (c.abs().max_element() + s.radius) * 1e-6;
        Self { min: c - Vec3A::splat(pad), max: c + Vec3A::splat(pad) }
    }

    /// False only if the ray certainly misses the box over [0, t_max]; `ray` carries the
    /// exact inverse of a direction with no zero component (see `accel::Query`).
    #[inline]
    pub(crate) fn may_hit(&self, ray: &BvhRay, t_max: f32) -> bool {
        let t0 = (self.min - ray.origin) * ray.inv_direction;
        let t1 = (self.max - ray.origin) * ray.inv_direction;
        let near = t0.min(t1).max_element().max(0.0);
        let far = t0.max(t1).min_element() * super::hit::SLAB_WIDEN;
        near <= far && near <= t_max * super::hit::SLAB_WIDEN
    }
}

/// Ray parameter of the first intersection of the ray with the sphere in (0, t_max).
#[inline]
pub(crate) fn intersect(s: &Sphere, origin: Vec3, dir: Vec3, t_max: f32) -> Option<f32> {
    let (o, d, c, r) = (origin.as_dvec3(), dir.as_dvec3(), s.center.as_dvec3(), s.radius as f64);
    let f = o - c;
    let a = d.length_squared();
    let b = 2.0 * f.dot(d);
    let cc = f.length_squared() - r * r;
    // Discriminant from the closest-approach offset (RTG ch. 7, eq. 7.10).
    let v = f - (b / (2.0 * a)) * d;
    let len = v.length();
    let discrim = 4.0 * a * (r + len) * (r - len);
    if discrim.is_nan() || discrim < 0.0 {
        return None;
    }
    let root = discrim.sqrt();
    let q = if b < 0.0 { -0.5 * (b - root) } else { -0.5 * (b + root) };
    let (mut t0, mut t1) = (q / a, cc / q);
    if t0 > t1 {
        core::mem::swap(&mut t0, &mut t1);
    }
    let t_max = t_max as f64;
    // First root in (0, t_max).
    let t = if t0 > 0.0 && t0 < t_max {
        t0
    } else if t1 > 0.0 && t1 < t_max {
        t1
    } else {
        return None;
    };
    let t32 = t as f32;
    // Rounding to f32 may land on t_max: step one ulp back to keep the interval open.
    let t32 = if (t32 as f64) < t_max { t32 } else { f32_prev(t32) };
    (t32 > 0.0).then_some(t32)
}

/// The largest f32 below a positive finite `x`.
#[inline]
fn f32_prev(x: f32) -> f32 {
    f32::from_bits(x.to_bits() - 1)
}

/// Hit point, outward-or-inward unit normal and Mitsuba's (φ/2π, θ/π) parameterisation
/// (`ember_core::shapes::sphere_texcoords`) for a hit at `t`. The point is re-projected onto the sphere's surface (pbrt-v4
/// §6.8.5) so that its error is a few ulps whatever the ray's length.
#[inline]
pub(crate) fn surface(s: &Sphere, origin: Vec3, dir: Vec3, t: f32) -> (Vec3, Vec3, glam::Vec2) {
    let c = s.center.as_dvec3();
    let r = s.radius as f64;
    let p = origin.as_dvec3() + dir.as_dvec3() * t as f64;
    let mut local = p - c;
    let len = local.length();
    local = if len > 0.0 { local / len } else { DVec3::Z };
    let p = (c + local * r).as_vec3();
    let n = local.as_vec3().normalize_or(Vec3::Z);
    let ng = if s.flip_normals { -n } else { n };
    (p, ng, ember_core::shapes::sphere_texcoords(n))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sphere(c: Vec3, r: f32) -> Sphere {
        Sphere { center: c, radius: r, flip_normals: false, material: 0, emitter: None }
    }

    #[test]
    fn small_far_sphere_is_hit_accurately() {
        // A 1 mm sphere 10 km away: b² − 4ac would lose every digit here.
        let s = sphere(Vec3::new(1.0e4, 0.0, 0.0), 1.0e-3);
        let t = intersect(&s, Vec3::ZERO, Vec3::X, f32::INFINITY).expect("hit");
        assert!(((t as f64) - (1.0e4 - 1.0e-3)).abs() < 1e-3, "t = {t}");
        assert!(intersect(&s, Vec3::ZERO, Vec3::new(1.0, 5.0e-8, 0.0).normalize(), f32::INFINITY).is_some());
        assert!(intersect(&s, Vec3::ZERO, Vec3::new(1.0, 2.0e-6, 0.0).normalize(), f32::INFINITY).is_none());
    }

    #[test]
    fn inside_hits_far_side_and_t_max_is_exclusive() {
        let s = sphere(Vec3::ZERO, 2.0);
        assert_eq!(intersect(&s, Vec3::ZERO, Vec3::Y, f32::INFINITY), Some(2.0));
        assert_eq!(intersect(&s, Vec3::ZERO, Vec3::Y, 2.0), None);
        assert_eq!(intersect(&s, Vec3::new(0.0, 5.0, 0.0), Vec3::Y, f32::INFINITY), None);
        let (p, n, uv) = surface(&s, Vec3::ZERO, Vec3::Y, 2.0);
        assert_eq!(p, Vec3::new(0.0, 2.0, 0.0));
        assert_eq!(n, Vec3::Y);
        assert!((uv.x - 0.25).abs() < 1e-6 && (uv.y - 0.5).abs() < 1e-6);
    }
}
