//! Diffuse emitter on the outside of a sphere.
//!
//! Direct lighting from outside samples the cone of directions the sphere subtends
//! uniformly by solid angle, p_ω = 1 / (2π (1 − cos θ_max)) with sin θ_max = r/d, and
//! finds the point on the sphere from the angle α at its centre (pbrt-v4
//! `Sphere::Sample(ctx, u)`, which avoids a ray–sphere intersection). Unlike pbrt-v4, the
//! cone is sampled through 1 − cos θ = sin²θ / (1 + cos θ), exact at every size, instead of
//! a Taylor branch for small cones: [`sample_narrow_cone`] is the f32-stable variant of
//! [`crate::warp::sample_uniform_cone`], which takes cos θ_max and so rounds 1 − cos θ_max
//! by percents below θ_max ≈ 3·10⁻³ rad and loses it entirely below about 3·10⁻⁴ rad. From inside, the area is sampled uniformly and
//! converted to solid angle (the sample then carries zero radiance: the emitter is
//! one-sided, facing out).
//!
//! Emission samples a uniform point and a cosine-weighted direction about the outward
//! normal.

use super::{EmissionSample, LightSample, finite_or_zero};
use crate::math::{Bounds3, Frame, INV_4PI, PI, TWO_PI, Vec2, Vec3, safe_sqrt, sin_cos_turns, sqrt};
use crate::measure::{AreaPdf, SolidAnglePdf};
use crate::spectrum::Rgb;
use crate::warp;

/// Relative slack on r, and absolute slack in radians, when deciding whether a direction
/// hits the sphere in [`SphereLight::pdf_li`], so that rays grazing the silhouette keep
/// their density.
const SILHOUETTE_SLACK: f32 = 1e-5;
const DIRECTION_SLACK: f32 = 4e-7;

/// 1 − cos θ_max of a cone with sin²θ_max = `sin2_max`, without cancellation.
#[inline]
fn one_minus_cos(sin2: f32) -> f32 {
    sin2 / (1.0 + safe_sqrt(1.0 - sin2))
}

/// Uniform direction in the cone about +z whose half-angle has 1 − cos θ_max =
/// `one_minus_cos_max`; returns (cos θ, sin²θ, φ in turns). Precise for arbitrarily narrow cones.
#[inline]
fn sample_narrow_cone(u: Vec2, one_minus_cos_max: f32) -> (f32, f32, f32) {
    let omc = u.x * one_minus_cos_max;
    (1.0 - omc, omc * (2.0 - omc), u.y)
}

/// Density of [`sample_narrow_cone`] inside its cone: 1 / (2π (1 − cos θ_max)).
#[inline]
fn narrow_cone_pdf(one_minus_cos_max: f32) -> SolidAnglePdf {
    finite_or_zero(SolidAnglePdf(1.0 / (TWO_PI * one_minus_cos_max)))
}

#[derive(Clone, Copy, Debug)]
pub(super) struct SphereLight {
    center: Vec3,
    /// Radius; a sphere of radius ≤ 0 emits nothing and yields no samples.
    radius: f32,
    radiance: Rgb,
}

impl SphereLight {
    pub(super) fn new(center: Vec3, radius: f32, radiance: Rgb) -> Self {
        let radius = if radius.is_finite() && radius > 0.0 { radius } else { 0.0 };
        Self { center, radius, radiance }
    }

    #[inline]
    fn area_pdf(&self) -> AreaPdf {
        if self.radius > 0.0 { AreaPdf(INV_4PI / (self.radius * self.radius)) } else { AreaPdf::ZERO }
    }

    /// Outward normal at surface point `p`: the caller's `n` where given (exact for a
    /// sampled point, while p − c rounds badly on small spheres far from the origin),
    /// otherwise recomputed from `p`.
    #[inline]
    fn normal_at(&self, p: Vec3, n: Vec3) -> Vec3 {
        if n != Vec3::ZERO { n.normalize_or_zero() } else { (p - self.center).normalize_or_zero() }
    }

    /// Radiance leaving surface point `p` (normal `n`, or zero) toward `w` (outward side only).
    #[inline]
    pub(super) fn radiance(&self, p: Vec3, n: Vec3, w: Vec3) -> Rgb {
        let n = self.normal_at(p, n);
        if self.radius > 0.0 && n.dot(w) > 0.0 { self.radiance } else { Rgb::ZERO }
    }

    pub(super) fn sample_li(&self, p_ref: Vec3, u: Vec2) -> Option<LightSample> {
        if self.radius <= 0.0 {
            return None;
        }
        let to_center = self.center - p_ref;
        let d2 = to_center.length_squared();
        let r2 = self.radius * self.radius;
        let (p, n, wi, pdf) = if d2 <= r2 {
            // Inside: uniform point on the area (its density converted by `pdf_inside`).
            let n = warp::sample_uniform_sphere(u);
            let p = self.center + self.radius * n;
            let wi = (p - p_ref).normalize_or_zero();
            (p, n, wi, self.pdf_inside(p_ref, wi))
        } else {
            // Outside: uniform direction in the subtended cone.
            let sin2_max = r2 / d2;
            let sin_max = sqrt(sin2_max);
            let omc_max = one_minus_cos(sin2_max);
            let pdf = narrow_cone_pdf(omc_max);
            if !pdf.is_positive() {
                return None;
            }
            let (cos_theta, sin2_theta, turns) = sample_narrow_cone(u, omc_max);
            // Angle α at the centre between the direction back to p_ref and the point
            // that the direction θ reaches first (law of sines; pbrt-v4).
            let cos_alpha = sin2_theta / sin_max + cos_theta * safe_sqrt(1.0 - sin2_theta / sin2_max);
            let sin_alpha = safe_sqrt(1.0 - cos_alpha * cos_alpha);
            let (s, c) = sin_cos_turns(turns);
            let frame = Frame::from_normal(to_center / sqrt(d2));
            let n = frame.to_world(-Vec3::new(sin_alpha * c, sin_alpha * s, cos_alpha));
            // The sampled direction itself, exact even where p − p_ref is all rounding (a
            // reference point on the surface): the point lies at azimuth φ + π about the axis.
            let sin_theta = safe_sqrt(sin2_theta);
            let wi = frame.to_world(Vec3::new(-sin_theta * c, -sin_theta * s, cos_theta)).normalize();
            (self.center + self.radius * n, n, wi, pdf)
        };
        let dist2 = (p - p_ref).length_squared();
        if !pdf.is_positive() || dist2 <= 0.0 {
            return None;
        }
        let dist = sqrt(dist2);
        Some(LightSample { wi, dist, p, n, radiance: self.radiance(p, n, -wi), pdf, is_delta: false })
    }

    /// Density of [`Self::sample_li`]: the cone density for directions that hit the
    /// sphere from outside; the converted area density from inside.
    pub(super) fn pdf_li(&self, p_ref: Vec3, wi: Vec3) -> SolidAnglePdf {
        if self.radius <= 0.0 {
            return SolidAnglePdf::ZERO;
        }
        let to_center = self.center - p_ref;
        let d2 = to_center.length_squared();
        let r2 = self.radius * self.radius;
        if d2 <= r2 {
            return self.pdf_inside(p_ref, wi);
        }
        // The ray hits the sphere iff its distance to the centre, |wi × c|, is ≤ r (the
        // cross product stays precise for narrow cones, unlike a cosine), give or take the
        // rounding of a unit f32 direction (a few 1e-8 rad) so sampled directions on the
        // silhouette keep their density.
        let dist = sqrt(d2);
        let miss = wi.cross(to_center).length() - self.radius * (1.0 + SILHOUETTE_SLACK) - DIRECTION_SLACK * dist;
        if wi.dot(to_center) <= 0.0 || miss > 0.0 {
            return SolidAnglePdf::ZERO;
        }
        narrow_cone_pdf(one_minus_cos(r2 / d2))
    }

    /// From inside: p_ω = (1/(4πr²)) t² / |cos|, where the ray leaves the sphere at t and
    /// meets it with |cos| = √disc / r (disc the intersection's discriminant).
    fn pdf_inside(&self, p_ref: Vec3, wi: Vec3) -> SolidAnglePdf {
        let o = p_ref - self.center;
        let len2 = wi.length_squared();
        if len2 <= 0.0 {
            return SolidAnglePdf::ZERO;
        }
        let wi = wi / sqrt(len2);
        let b = o.dot(wi);
        let disc = b * b - (o.length_squared() - self.radius * self.radius);
        let root = safe_sqrt(disc);
        let t = root - b;
        if root <= 0.0 || t <= 0.0 {
            return SolidAnglePdf::ZERO;
        }
        finite_or_zero(self.area_pdf().to_solid_angle(root / self.radius, t * t))
    }

    /// Uniform point, cosine-weighted direction about the outward normal.
    pub(super) fn sample_le(&self, u_pos: Vec2, u_dir: Vec2) -> Option<EmissionSample> {
        if self.radius <= 0.0 {
            return None;
        }
        let n = warp::sample_uniform_sphere(u_pos);
        let p = self.center + self.radius * n;
        let dir = Frame::from_normal(n).to_world(warp::sample_cosine_hemisphere(u_dir)).normalize_or_zero();
        let (pdf_pos, pdf_dir) = self.pdf_le_normal(n, dir);
        if !pdf_pos.is_positive() || !pdf_dir.is_positive() {
            return None;
        }
        Some(EmissionSample { p, n, dir, radiance: self.radiance, pdf_pos, pdf_dir, delta_pos: false, delta_dir: false })
    }

    /// Inverse of the position sampling of [`Self::sample_le`] for surface point `p`.
    pub(super) fn position_uv(&self, p: Vec3) -> Vec2 {
        warp::invert_uniform_sphere(self.normal_at(p, Vec3::ZERO))
    }

    /// (1/(4πr²), cos/π) with cos taken against the outward normal at `p`.
    pub(super) fn pdf_le(&self, p: Vec3, n: Vec3, dir: Vec3) -> (AreaPdf, SolidAnglePdf) {
        self.pdf_le_normal(self.normal_at(p, n), dir)
    }

    #[inline]
    fn pdf_le_normal(&self, n: Vec3, dir: Vec3) -> (AreaPdf, SolidAnglePdf) {
        (self.area_pdf(), warp::cosine_hemisphere_pdf(Vec3::new(0.0, 0.0, n.dot(dir))))
    }

    /// Φ = π · 4πr² · L.
    pub(super) fn bounds(&self) -> Bounds3 {
        let r = Vec3::splat(self.radius.max(0.0));
        Bounds3 { min: self.center - r, max: self.center + r }
    }

    pub(super) fn power(&self) -> f32 {
        PI * 4.0 * PI * self.radius * self.radius * self.radiance.average()
    }
}
