//! Warps from the unit square to common domains.
//!
//! Each warp is a triple placed together, as in pbrt-v4: `sample_X(u)`, `X_pdf(..)` and
//! `invert_X(..)` with `invert_X(sample_X(u)) ≈ u`. Densities carry their measure:
//! directions are per steradian ([`SolidAnglePdf`]), points on planar domains per unit
//! area ([`AreaPdf`], for the canonical unit-sized domain; callers scale by their own area).

use crate::math::{INV_2PI, INV_4PI, INV_PI, PI, TWO_PI, Vec2, Vec3, atan2, safe_sqrt, sin_cos_quarter, sin_cos_turns, sqrt};
use crate::measure::{AreaPdf, SolidAnglePdf};

/// Wrap an angle from `atan2` into [0, 2π).
#[inline]
fn wrap_angle(phi: f32) -> f32 {
    if phi < 0.0 { phi + TWO_PI } else { phi }
}

/// Clamp a reconstructed sample into [0, 1) (inverse warps may land a hair outside).
#[inline]
fn unit(x: f32) -> f32 {
    x.clamp(0.0, 1.0 - f32::EPSILON * 0.5)
}

// ---------------------------------------------------------------- disk (concentric)

/// Shirley–Chiu concentric map of [0,1)² onto the unit disk (area-preserving, low distortion).
#[inline]
pub fn sample_concentric_disk(u: Vec2) -> Vec2 {
    let o = 2.0 * u - Vec2::ONE;
    // θ = φ in the wedges around ±x, θ = π/2 − φ around ±y (so cos θ = sin φ): either
    // way the series sees |φ| ≤ π/4 and needs no reduction. Written without branches
    // (the wedge picks the ratio and the result, one sine and cosine serves both) so
    // that lanes of paths draw it together (`estimators::pt_lanes`).
    let x_wedge = o.x.abs() > o.y.abs();
    let centre = o.x == 0.0 && o.y == 0.0;
    let (num, den) = if x_wedge { (o.y, o.x) } else { (o.x, o.y) };
    let ratio = num / den;
    let (s, c) = sin_cos_quarter((PI / 4.0) * if centre { 0.0 } else { ratio });
    let d = if x_wedge { Vec2::new(o.x * c, o.x * s) } else { Vec2::new(o.y * s, o.y * c) };
    if centre { Vec2::ZERO } else { d }
}

/// Density of [`sample_concentric_disk`] per unit area: 1/π.
#[inline]
pub fn concentric_disk_pdf(p: Vec2) -> AreaPdf {
    if p.length_squared() <= 1.0 { AreaPdf(INV_PI) } else { AreaPdf(0.0) }
}

/// Inverse of [`sample_concentric_disk`].
#[inline]
pub fn invert_concentric_disk(p: Vec2) -> Vec2 {
    let r = p.length();
    if r == 0.0 {
        return Vec2::splat(0.5);
    }
    let mut phi = atan2(p.y, p.x);
    // Map phi into (-π/4, 7π/4] so that each of the four wedges is contiguous.
    if phi < -PI / 4.0 {
        phi += TWO_PI;
    }
    let (x, y) = if phi < PI / 4.0 {
        (r, r * phi * (4.0 / PI))
    } else if phi < 3.0 * PI / 4.0 {
        (-r * (phi - PI / 2.0) * (4.0 / PI), r)
    } else if phi < 5.0 * PI / 4.0 {
        (-r, -r * (phi - PI) * (4.0 / PI))
    } else {
        (r * (phi - 3.0 * PI / 2.0) * (4.0 / PI), -r)
    };
    Vec2::new(unit(0.5 * (x + 1.0)), unit(0.5 * (y + 1.0)))
}

// ---------------------------------------------------------------- hemisphere, uniform

/// Uniform direction on the +z hemisphere.
#[inline]
pub fn sample_uniform_hemisphere(u: Vec2) -> Vec3 {
    let z = u.x;
    let r = safe_sqrt(1.0 - z * z);
    let (s, c) = sin_cos_turns(u.y);
    Vec3::new(r * c, r * s, z)
}

/// Density of [`sample_uniform_hemisphere`]: 1/(2π) on z > 0.
#[inline]
pub fn uniform_hemisphere_pdf(w: Vec3) -> SolidAnglePdf {
    if w.z > 0.0 { SolidAnglePdf(INV_2PI) } else { SolidAnglePdf(0.0) }
}

/// Inverse of [`sample_uniform_hemisphere`].
#[inline]
pub fn invert_uniform_hemisphere(w: Vec3) -> Vec2 {
    Vec2::new(unit(w.z), unit(wrap_angle(atan2(w.y, w.x)) * INV_2PI))
}

// ---------------------------------------------------------------- hemisphere, cosine

/// Cosine-weighted direction on the +z hemisphere (Malley's method on the concentric disk).
#[inline(always)]
pub fn sample_cosine_hemisphere(u: Vec2) -> Vec3 {
    let d = sample_concentric_disk(u);
    let z = safe_sqrt(1.0 - d.length_squared());
    Vec3::new(d.x, d.y, z)
}

/// Density of [`sample_cosine_hemisphere`]: cos θ / π on z > 0.
#[inline]
pub fn cosine_hemisphere_pdf(w: Vec3) -> SolidAnglePdf {
    SolidAnglePdf(w.z.max(0.0) * INV_PI)
}

/// Inverse of [`sample_cosine_hemisphere`].
#[inline]
pub fn invert_cosine_hemisphere(w: Vec3) -> Vec2 {
    invert_concentric_disk(Vec2::new(w.x, w.y))
}

// ---------------------------------------------------------------- sphere

/// Uniform direction on the unit sphere.
#[inline]
pub fn sample_uniform_sphere(u: Vec2) -> Vec3 {
    let z = 1.0 - 2.0 * u.x;
    let r = safe_sqrt(1.0 - z * z);
    let (s, c) = sin_cos_turns(u.y);
    Vec3::new(r * c, r * s, z)
}

/// Density of [`sample_uniform_sphere`]: 1/(4π).
#[inline]
pub fn uniform_sphere_pdf() -> SolidAnglePdf {
    SolidAnglePdf(INV_4PI)
}

/// Inverse of [`sample_uniform_sphere`].
#[inline]
pub fn invert_uniform_sphere(w: Vec3) -> Vec2 {
    Vec2::new(unit(0.5 * (1.0 - w.z)), unit(wrap_angle(atan2(w.y, w.x)) * INV_2PI))
}

// ---------------------------------------------------------------- cone

/// Uniform direction in the cone around +z with half-angle cosine `cos_max`.
///
/// Written in terms of 1 − cos θ so narrow cones (cos_max → 1, e.g. small distant
/// sphere lights) keep their precision: sin²θ = (1−cos θ)(1+cos θ).
#[inline]
pub fn sample_uniform_cone(u: Vec2, cos_max: f32) -> Vec3 {
    let one_minus_cos_max = 1.0 - cos_max;
    let one_minus_cos = u.x * one_minus_cos_max;
    let cos_theta = 1.0 - one_minus_cos;
    let sin_theta = safe_sqrt(one_minus_cos * (2.0 - one_minus_cos));
    let (s, c) = sin_cos_turns(u.y);
    Vec3::new(sin_theta * c, sin_theta * s, cos_theta)
}

/// Density of [`sample_uniform_cone`]: 1/(2π(1 − cos_max)) inside the cone.
#[inline]
pub fn uniform_cone_pdf(w: Vec3, cos_max: f32) -> SolidAnglePdf {
    if w.z >= cos_max && cos_max < 1.0 { SolidAnglePdf(1.0 / (TWO_PI * (1.0 - cos_max))) } else { SolidAnglePdf(0.0) }
}

/// Inverse of [`sample_uniform_cone`].
#[inline]
pub fn invert_uniform_cone(w: Vec3, cos_max: f32) -> Vec2 {
    let u0 = (1.0 - w.z) / (1.0 - cos_max);
    Vec2::new(unit(u0), unit(wrap_angle(atan2(w.y, w.x)) * INV_2PI))
}

// ---------------------------------------------------------------- triangle

/// Uniform barycentrics (b0, b1) on a triangle; b2 = 1 − b0 − b1.
#[inline]
pub fn sample_uniform_triangle(u: Vec2) -> Vec2 {
    let su0 = sqrt(u.x);
    Vec2::new(1.0 - su0, u.y * su0)
}

/// Density of [`sample_uniform_triangle`] per unit area on a triangle of area `area`.
#[inline]
pub fn uniform_triangle_pdf(area: f32) -> AreaPdf {
    if area > 0.0 { AreaPdf(1.0 / area) } else { AreaPdf(0.0) }
}

/// Inverse of [`sample_uniform_triangle`] from barycentrics (b0, b1).
#[inline]
pub fn invert_uniform_triangle(b: Vec2) -> Vec2 {
    let su0 = 1.0 - b.x;
    let u1 = if su0 > 0.0 { b.y / su0 } else { 0.5 };
    Vec2::new(unit(su0 * su0), unit(u1))
}

// ---------------------------------------------------------------- linear

/// x ∈ [0, 1) with density ∝ (1 − x) a + x b ([`linear_pdf`]); `a`, `b` ≥ 0, not both 0
/// (pbrt-v4 `SampleLinear`). Inverts the CDF a x + (b − a) x²/2 = u (a + b)/2 in the
/// form without cancellation, x = u (a + b) / (a + √(a² + u (b² − a²))): x = u where
/// a = b, √u where a = 0.
#[inline]
pub fn sample_linear(u: f32, a: f32, b: f32) -> f32 {
    let den = a + sqrt((a * a + u * (b * b - a * a)).max(0.0));
    if !(den > 0.0) {
        return u;
    }
    unit(u * (a + b) / den)
}

/// Density of [`sample_linear`] at x ∈ [0, 1]: 2 ((1 − x) a + x b) / (a + b).
#[inline]
pub fn linear_pdf(x: f32, a: f32, b: f32) -> f32 {
    if !(0.0..=1.0).contains(&x) || !(a + b > 0.0) {
        return 0.0;
    }
    2.0 * ((1.0 - x) * a + x * b) / (a + b)
}

/// Inverse of [`sample_linear`]: the CDF at x.
#[inline]
pub fn invert_linear(x: f32, a: f32, b: f32) -> f32 {
    if !(a + b > 0.0) {
        return unit(x);
    }
    unit(x * ((2.0 - x) * a + x * b) / (a + b))
}

#[cfg(test)]
mod tests {
    use super::*;
    use alloc::vec::Vec;

    /// The concentric map as it was written with branches (before lanes shaded with it).
    fn concentric_disk_branchy(u: Vec2) -> Vec2 {
        let o = 2.0 * u - Vec2::ONE;
        if o.x == 0.0 && o.y == 0.0 {
            return Vec2::ZERO;
        }
        if o.x.abs() > o.y.abs() {
            let (s, c) = crate::math::sin_cos_small((PI / 4.0) * (o.y / o.x));
            Vec2::new(o.x * c, o.x * s)
        } else {
            let (s, c) = crate::math::sin_cos_small((PI / 4.0) * (o.x / o.y));
            Vec2::new(o.y * s, o.y * c)
        }
    }

    /// The branch-free concentric map gives the branchy one's bits: on a 1021 × 1021
    /// grid, the centre, the wedges' diagonals (|o.x| = |o.y|, where the branch flips;
    /// there both wedges' formulas happen to agree, so `>` as `>=` passes) and the
    /// square's edges. Seen to fail with the y wedge's sine and cosine swapped: 521 905
    /// of 1 044 446 points differ.
    #[test]
    fn the_branch_free_disk_is_the_branchy_one_bit_for_bit() {
        let n = 1021;
        let mut points: Vec<Vec2> = (0..n * n).map(|k| Vec2::new((k % n) as f32 / n as f32, (k / n) as f32 / n as f32)).collect();
        points.extend([Vec2::splat(0.5), Vec2::ZERO, Vec2::new(0.5, 0.0), Vec2::new(0.0, 0.5), Vec2::splat(1.0 - f32::EPSILON / 2.0)]);
        points.extend((0..1000).map(|k| Vec2::splat(k as f32 / 1000.0)));
        points.extend((0..1000).map(|k| Vec2::new(k as f32 / 1000.0, 1.0 - k as f32 / 1000.0)));
        let differ = points
            .iter()
            .filter(|&&u| sample_concentric_disk(u).to_array().map(f32::to_bits) != concentric_disk_branchy(u).to_array().map(f32::to_bits))
            .count();
        assert_eq!(differ, 0, "{differ} of {} points differ", points.len());
    }

    fn grid(mut f: impl FnMut(Vec2)) {
        for i in 0..37 {
            for j in 0..41 {
                f(Vec2::new((i as f32 + 0.31) / 37.0, (j as f32 + 0.77) / 41.0));
            }
        }
    }

    #[test]
    fn inverses_round_trip() {
        let close = |a: Vec2, b: Vec2| (a - b).abs().max_element() < 2e-4;
        grid(|u| {
            assert!(close(invert_concentric_disk(sample_concentric_disk(u)), u), "disk {u}");
            assert!(close(invert_uniform_hemisphere(sample_uniform_hemisphere(u)), u), "hemi {u}");
            assert!(close(invert_cosine_hemisphere(sample_cosine_hemisphere(u)), u), "cos {u}");
            assert!(close(invert_uniform_sphere(sample_uniform_sphere(u)), u), "sphere {u}");
            assert!(close(invert_uniform_cone(sample_uniform_cone(u, 0.3), 0.3), u), "cone {u}");
            assert!(close(invert_uniform_triangle(sample_uniform_triangle(u)), u), "tri {u}");
            for (a, b) in [(1.0, 1.0), (0.0, 3.0), (5.0, 0.0), (0.2, 7.0)] {
                let x = sample_linear(u.x, a, b);
                assert!((invert_linear(x, a, b) - u.x).abs() < 2e-4, "linear {a} {b} {u}");
            }
        });
    }

    /// The linear density integrates to 1 and its CDF is [`invert_linear`].
    #[test]
    fn linear_density_is_its_cdfs_derivative() {
        for (a, b) in [(1.0f32, 1.0f32), (0.0, 3.0), (5.0, 0.0), (0.2, 7.0)] {
            let n = 1000;
            let mut cdf = 0.0f64;
            for i in 0..n {
                let x = (i as f32 + 0.5) / n as f32;
                cdf += linear_pdf(x, a, b) as f64 / n as f64;
                let expected = invert_linear((i + 1) as f32 / n as f32, a, b) as f64;
                assert!((cdf - expected).abs() < 1e-3, "{a} {b} at {x}: {cdf} vs {expected}");
            }
        }
    }

    #[test]
    fn samples_are_unit_and_in_domain() {
        grid(|u| {
            for w in [sample_uniform_hemisphere(u), sample_cosine_hemisphere(u), sample_uniform_sphere(u)] {
                assert!((w.length() - 1.0).abs() < 1e-5);
            }
            assert!(sample_cosine_hemisphere(u).z >= 0.0);
            assert!(sample_uniform_cone(u, 0.9).z >= 0.9 - 1e-6);
            let b = sample_uniform_triangle(u);
            assert!(b.x >= 0.0 && b.y >= 0.0 && b.x + b.y <= 1.0 + 1e-6);
        });
    }
}
