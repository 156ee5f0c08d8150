//! Watertight ray–triangle intersection (Woop, Benthin and Wald, "Watertight Ray/Triangle
//! Intersection", JCGT 2(1), 2013), as in pbrt-v4's `IntersectTriangle`.
//!
//! The ray is turned into the +z axis by a per-ray permutation and shear; the triangle's
//! vertices are transformed the same way and the three 2-D edge functions decide the
//! hit. Two triangles sharing an edge evaluate that edge's function on bit-identical
//! inputs, so no ray slips between them (Möller–Trumbore can leak through shared edges,
//! which shows up as light leaking through the seams of a closed room). Edge functions
//! that round to exactly zero are recomputed in f64. Hits need t > 0 (see `hit`: the
//! callers' origins are offset off their surfaces, so pbrt-v4's rounding-error bound on
//! t is not applied).

use glam::{Vec3A, Vec3Swizzles};

/// The axis permutation (kx, ky, kz) that makes the dominant direction axis z: cyclic,
/// so one swizzle. Applied as a swizzle chosen per ray (a branch every triangle of that
/// ray takes the same way) instead of runtime array indexing, which sent every vertex
/// through memory: 2.1 % fewer instructions per PT sample (docs/performance.md).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Permutation {
    /// kz = x: (y, z, x).
    Yzx,
    /// kz = y: (z, x, y).
    Zxy,
    /// kz = z: (x, y, z).
    Xyz,
}

impl Permutation {
    #[inline(always)]
    fn apply(self, v: Vec3A) -> Vec3A {
        match self {
            Self::Yzx => v.yzx(),
            Self::Zxy => v.zxy(),
            Self::Xyz => v,
        }
    }
}

/// The per-ray part of the watertight test, computed once per query.
#[derive(Clone, Copy, Debug)]
pub struct WatertightRay {
    /// The origin, permuted.
    origin: Vec3A,
    permutation: Permutation,
    /// Shear so that the permuted direction becomes (0, 0, 1).
    sx: f32,
    sy: f32,
    sz: f32,
}

impl WatertightRay {
    /// Prepare the permutation and shear for a ray with non-zero direction `dir`.
    #[inline]
    pub(crate) fn new(origin: Vec3A, dir: Vec3A) -> Self {
        let a = dir.abs();
        let kz = if a.x > a.y {
            if a.x > a.z { 0 } else { 2 }
        } else if a.y > a.z {
            1
        } else {
            2
        };
        let permutation = match kz {
            0 => Permutation::Yzx,
            1 => Permutation::Zxy,
            _ => Permutation::Xyz,
        };
        let d = permutation.apply(dir);
        let sz = 1.0 / d.z;
        Self { origin: permutation.apply(origin), permutation, sx: -d.x * sz, sy: -d.y * sz, sz }
    }

    /// The input axes feeding the permuted x, y and z, the permuted origin and the shear
    /// (sx, sy, sz): what a packet of triangles needs to run this test lane by lane.
    #[inline(always)]
    #[allow(dead_code, reason = "the browser host compiles this file without the BVH4")]
    pub(crate) fn parts(&self) -> ([usize; 3], [f32; 3], [f32; 3]) {
        let axis = match self.permutation {
            Permutation::Yzx => [1, 2, 0],
            Permutation::Zxy => [2, 0, 1],
            Permutation::Xyz => [0, 1, 2],
        };
        (axis, self.origin.into(), [self.sx, self.sy, self.sz])
    }

    /// Distance to the triangle (p0, p1, p2) if it lies in (0, t_max), with barycentrics
    /// (b0, b1, b2) of the hit; `None` otherwise.
    #[inline(always)]
    pub(crate) fn hit(&self, p0: Vec3A, p1: Vec3A, p2: Vec3A, t_max: f32) -> Option<(f32, [f32; 3])> {
        // Permute the dominant axis to z, translate to the ray origin, shear x and y (the
        // same operations per component as translating first: bit-identical).
        let p = self.permutation;
        let (a, b, c) = (p.apply(p0) - self.origin, p.apply(p1) - self.origin, p.apply(p2) - self.origin);
        let (az, bz, cz) = (a.z, b.z, c.z);
        let ax = a.x + self.sx * az;
        let ay = a.y + self.sy * az;
        let bx = b.x + self.sx * bz;
        let by = b.y + self.sy * bz;
        let cx = c.x + self.sx * cz;
        let cy = c.y + self.sy * cz;

        // Edge functions; recompute in double precision when one rounds to zero.
        let mut e0 = bx * cy - by * cx;
        let mut e1 = cx * ay - cy * ax;
        let mut e2 = ax * by - ay * bx;
        if e0 == 0.0 || e1 == 0.0 || e2 == 0.0 {
            let d = |x0: f32, y0: f32, x1: f32, y1: f32| (x0 as f64 * y1 as f64 - y0 as f64 * x1 as f64) as f32;
            e0 = d(bx, by, cx, cy);
            e1 = d(cx, cy, ax, ay);
            e2 = d(ax, ay, bx, by);
        }
        if (e0 < 0.0 || e1 < 0.0 || e2 < 0.0) && (e0 > 0.0 || e1 > 0.0 || e2 > 0.0) {
            return None;
        }
        let det = e0 + e1 + e2;
        if det == 0.0 {
            return None;
        }

        // Scaled distance, range test against (0, t_max) before the division.
        let (az, bz, cz) = (az * self.sz, bz * self.sz, cz * self.sz);
        let t_scaled = e0 * az + e1 * bz + e2 * cz;
        if det < 0.0 && (t_scaled >= 0.0 || t_scaled < t_max * det) {
            return None;
        }
        if det > 0.0 && (t_scaled <= 0.0 || t_scaled > t_max * det) {
            return None;
        }
        let inv_det = 1.0 / det;
        let t = t_scaled * inv_det;

        // Reject t not provably positive given the rounding of everything above.
        // Any t > 0 counts. pbrt-v4 also rejects t below a bound on its own rounding
        // error (§6.8.7); here every ray origin is already offset 2⁻¹⁵ of its largest
        // coordinate off its surface (`offset_ray_origin`, 256 ulps, far above that
        // bound), so no surface behind the origin comes near t = 0, and a hit at a tiny
        // positive t is the real neighbour of a concave corner: with the bound, a ray
        // leaving one wall within 10⁻⁶ of the floor passed through the floor (71 of 20 M
        // bounces escaped a closed room).
        if t.is_nan() || t <= 0.0 || t >= t_max {
            return None;
        }
        Some((t, [e0 * inv_det, e1 * inv_det, e2 * inv_det]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::vec3a;

    #[test]
    fn hits_inside_and_misses_outside() {
        let (p0, p1, p2) = (vec3a(0.0, 0.0, 0.0), vec3a(1.0, 0.0, 0.0), vec3a(0.0, 1.0, 0.0));
        let r = WatertightRay::new(vec3a(0.25, 0.25, 1.0), vec3a(0.0, 0.0, -1.0));
        let (t, b) = r.hit(p0, p1, p2, f32::INFINITY).expect("hit");
        assert!((t - 1.0).abs() < 1e-6);
        assert!((b[0] - 0.5).abs() < 1e-6 && (b[1] - 0.25).abs() < 1e-6 && (b[2] - 0.25).abs() < 1e-6);
        assert!(r.hit(p0, p1, p2, 0.99).is_none(), "t_max is exclusive of farther hits");
        let miss = WatertightRay::new(vec3a(0.75, 0.75, 1.0), vec3a(0.0, 0.0, -1.0));
        assert!(miss.hit(p0, p1, p2, f32::INFINITY).is_none());
        let behind = WatertightRay::new(vec3a(0.25, 0.25, 1.0), vec3a(0.0, 0.0, 1.0));
        assert!(behind.hit(p0, p1, p2, f32::INFINITY).is_none());
    }

    /// A ray through the shared edge of two triangles hits exactly one or both, never
    /// neither (the watertightness property).
    #[test]
    fn shared_edges_do_not_leak() {
        let (a, b, c, d) = (vec3a(0.0, 0.0, 0.0), vec3a(1.0, 0.0, 0.0), vec3a(1.0, 1.0, 0.0), vec3a(0.0, 1.0, 0.0));
        for i in 0..1000 {
            // Interior points of the diagonal (its ends are corners of the square).
            let s = (i as f32 + 0.5) / 1000.0;
            // Points on the diagonal a–c, seen from a skewed origin.
            let target = a + (c - a) * s;
            let origin = vec3a(0.3 + 0.7 * s, -0.4, 2.3);
            let r = WatertightRay::new(origin, target - origin);
            let h1 = r.hit(a, b, c, f32::INFINITY).is_some();
            let h2 = r.hit(a, c, d, f32::INFINITY).is_some();
            assert!(h1 || h2, "ray {i} slipped through the shared edge");
        }
    }
}
