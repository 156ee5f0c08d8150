//! Diffuse triangle emitter.
//!
//! Direct lighting samples the area uniformly and converts to solid angle,
//! p_ω = p_A d² / |cos θ_light| (pbrt-v4 `Triangle::Sample(ctx, u)` in its area branch;
//! Veach's thesis eq. 8.10). Emission samples a uniform point and a cosine-weighted
//! direction (on a side chosen with probability ½ when two-sided), p = (1/A)·(|cos|/π)
//! [·½] (pbrt-v4 `DiffuseAreaLight::SampleLe`).

use super::{EmissionSample, LightSample, finite_or_zero};
use crate::math::soa::{LANES, Lane, Vec3s, select_rgb};
use crate::math::{Bounds3, Frame, PI, Vec2, Vec3, sqrt};
use crate::measure::{AreaPdf, SolidAnglePdf};
use crate::spectrum::Rgb;
use crate::warp;

#[derive(Clone, Copy, Debug)]
pub(super) struct TriangleLight {
    p0: Vec3,
    p1: Vec3,
    p2: Vec3,
    /// Unit normal of the winding, (p1−p0)×(p2−p0); zero for a degenerate triangle.
    n: Vec3,
    /// Area; 0 for a degenerate triangle, which then never yields a sample.
    area: f32,
    radiance: Rgb,
    two_sided: bool,
}

impl TriangleLight {
    pub(super) fn new(p0: Vec3, p1: Vec3, p2: Vec3, radiance: Rgb, two_sided: bool) -> Self {
        let c = (p1 - p0).cross(p2 - p0);
        let len = c.length();
        let (n, area) = if len > 0.0 && len.is_finite() { (c / len, 0.5 * len) } else { (Vec3::ZERO, 0.0) };
        Self { p0, p1, p2, n, area, radiance, two_sided }
    }

    /// Point at barycentrics (b0, b1), b2 = 1 − b0 − b1.
    #[inline]
    fn point(&self, b: Vec2) -> Vec3 {
        b.x * self.p0 + b.y * self.p1 + (1.0 - b.x - b.y) * self.p2
    }

    /// Inverse of the position sampling of [`Self::sample_le`]: the `u_pos` in [0,1)² that
    /// produces surface point `p` (projected onto the triangle's plane; clamped).
    pub(super) fn position_uv(&self, p: Vec3) -> Vec2 {
        // Barycentrics of p by the 2×2 normal equations of p − p2 = b0 e0 + b1 e1.
        let (e0, e1, d) = (self.p0 - self.p2, self.p1 - self.p2, p - self.p2);
        let (a00, a01, a11) = (e0.dot(e0), e0.dot(e1), e1.dot(e1));
        let (r0, r1) = (d.dot(e0), d.dot(e1));
        let det = a00 * a11 - a01 * a01;
        if !(det > 0.0) {
            return Vec2::ZERO;
        }
        let b0 = ((a11 * r0 - a01 * r1) / det).clamp(0.0, 1.0);
        let b1 = ((a00 * r1 - a01 * r0) / det).clamp(0.0, 1.0 - b0);
        warp::invert_uniform_triangle(Vec2::new(b0, b1))
    }

    /// Radiance leaving the triangle toward `w`.
    #[inline(always)]
    pub(super) fn radiance(&self, w: Vec3) -> Rgb {
        let c = self.n.dot(w);
        select_rgb((c > 0.0) | (self.two_sided & (c < 0.0)), self.radiance, Rgb::ZERO)
    }

    /// Uniform point on the area, converted to solid angle at `p_ref` by [`Self::pdf_li`].
    #[inline]
    pub(super) fn sample_li(&self, p_ref: Vec3, u: Vec2) -> Option<LightSample> {
        let (sample, ok) = self.sample_li_lane(p_ref, u);
        ok.then_some(sample)
    }

    /// [`Self::sample_li`] without branches: the sample and whether it exists (false for a
    /// degenerate triangle, a reference point on the light, a grazing direction). Every
    /// quantity is computed either way, so lanes of paths draw together
    /// ([`TriangleLanes`]); where it exists, the sample has `sample_li`'s bits.
    #[inline(always)]
    fn sample_li_lane(&self, p_ref: Vec3, u: Vec2) -> (LightSample, bool) {
        let p = self.point(warp::sample_uniform_triangle(u));
        let d = p - p_ref;
        let dist2 = d.length_squared();
        let dist = sqrt(dist2);
        let wi = d / dist;
        let pdf = self.pdf_li(p_ref, wi, p);
        let ok = self.area > 0.0 && dist2 > 0.0 && pdf.is_positive();
        (LightSample { wi, dist, p, n: self.n, radiance: self.radiance(-wi), pdf, is_delta: false }, ok)
    }

    /// p_ω = (1/A) · d² / |n·wi|; 0 when the direction grazes the plane.
    #[inline(always)]
    pub(super) fn pdf_li(&self, p_ref: Vec3, wi: Vec3, p_light: Vec3) -> SolidAnglePdf {
        let dist2 = (p_light - p_ref).length_squared();
        finite_or_zero(warp::uniform_triangle_pdf(self.area).to_solid_angle(self.n.dot(wi), dist2))
    }

    /// Uniform point, cosine-weighted direction about the emitting side's normal.
    pub(super) fn sample_le(&self, u_pos: Vec2, u_dir: Vec2) -> Option<EmissionSample> {
        if self.area <= 0.0 {
            return None;
        }
        let p = self.point(warp::sample_uniform_triangle(u_pos));
        // Two-sided: pick the side with the first dimension, then reuse it rescaled.
        let (ux, side) = match (self.two_sided, u_dir.x < 0.5) {
            (false, _) => (u_dir.x, 1.0),
            (true, true) => (2.0 * u_dir.x, 1.0),
            (true, false) => (2.0 * u_dir.x - 1.0, -1.0),
        };
        let local = warp::sample_cosine_hemisphere(Vec2::new(ux, u_dir.y));
        let dir = Frame::from_normal(side * self.n).to_world(local).normalize_or_zero();
        let (pdf_pos, pdf_dir) = self.pdf_le(dir);
        if !pdf_dir.is_positive() || !pdf_pos.is_positive() {
            return None;
        }
        Some(EmissionSample { p, n: self.n, dir, radiance: self.radiance(dir), pdf_pos, pdf_dir, delta_pos: false, delta_dir: false })
    }

    /// (1/A, cos/π) one-sided; (1/A, |cos|/(2π)) two-sided.
    pub(super) fn pdf_le(&self, dir: Vec3) -> (AreaPdf, SolidAnglePdf) {
        let pdf_pos = warp::uniform_triangle_pdf(self.area);
        let cos = self.n.dot(dir);
        let pdf_dir = if self.two_sided {
            warp::cosine_hemisphere_pdf(Vec3::new(0.0, 0.0, cos.abs())) * 0.5
        } else {
            warp::cosine_hemisphere_pdf(Vec3::new(0.0, 0.0, cos))
        };
        (pdf_pos, pdf_dir)
    }

    /// Φ = π A L (twice that when two-sided).
    pub(super) fn bounds(&self) -> Bounds3 {
        Bounds3::EMPTY.union_point(self.p0).union_point(self.p1).union_point(self.p2)
    }

    pub(super) fn power(&self) -> f32 {
        let sides = if self.two_sided { 2.0 } else { 1.0 };
        sides * PI * self.area * self.radiance.average()
    }
}

/// Triangle lights chosen by lanes of paths, one per lane, in structure-of-arrays form:
/// [`Self::set`] copies lane `i`'s light in, [`Self::sample_li`] draws from it with
/// `TriangleLight::sample_li`'s arithmetic. The copy is the gather (one light per lane,
/// anywhere in the scene's list); the draw is what runs over SIMD lanes.
#[derive(Clone, Debug)]
pub(crate) struct TriangleLanes {
    p0: Vec3s,
    p1: Vec3s,
    p2: Vec3s,
    n: Vec3s,
    area: Lane,
    radiance: Vec3s,
    two_sided: [bool; LANES],
}

impl TriangleLanes {
    pub(crate) fn new() -> Self {
        Self { p0: Vec3s::ZERO, p1: Vec3s::ZERO, p2: Vec3s::ZERO, n: Vec3s::ZERO, area: [0.0; LANES], radiance: Vec3s::ZERO, two_sided: [false; LANES] }
    }

    #[inline(always)]
    pub(super) fn set(&mut self, i: usize, l: &TriangleLight) {
        self.p0.set(i, l.p0);
        self.p1.set(i, l.p1);
        self.p2.set(i, l.p2);
        self.n.set(i, l.n);
        self.area[i] = l.area;
        self.radiance.set_rgb(i, l.radiance);
        self.two_sided[i] = l.two_sided;
    }

    /// Lane `i`'s draw from `p_ref`: `TriangleLight::sample_li` of its light, and whether
    /// it exists.
    #[inline(always)]
    pub(crate) fn sample_li(&self, i: usize, p_ref: Vec3, u: Vec2) -> (LightSample, bool) {
        let light = TriangleLight {
            p0: self.p0.get(i),
            p1: self.p1.get(i),
            p2: self.p2.get(i),
            n: self.n.get(i),
            area: self.area[i],
            radiance: self.radiance.rgb(i),
            two_sided: self.two_sided[i],
        };
        light.sample_li_lane(p_ref, u)
    }
}
