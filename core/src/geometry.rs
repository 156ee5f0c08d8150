//! Rays, surface hits and the ray-query trait through which hosts and embedding engines
//! plug in their own tracer.

use crate::math::soa::{Lane, Vec3s};
use crate::math::{Vec2, Vec3};

/// A ray `origin + t·dir`, t in (0, t_max). `dir` need not be unit length, but the
/// estimators always pass unit directions so that `t` is a distance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    pub origin: Vec3,
    pub dir: Vec3,
    pub t_max: f32,
}

impl Ray {
    #[inline]
    pub fn new(origin: Vec3, dir: Vec3, t_max: f32) -> Self {
        Self { origin, dir, t_max }
    }
    #[inline]
    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + self.dir * t
    }
}

/// Index of a material in the scene description.
pub type MaterialId = u32;
/// Index of a light in the scene description.
pub type LightId = u32;

/// What a closest-hit query reports: enough to shade, nothing engine-specific.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "wire", derive(serde::Serialize, serde::Deserialize))]
pub struct SurfaceHit {
    /// Ray parameter of the hit.
    pub t: f32,
    /// Hit position.
    pub p: Vec3,
    /// Unit geometric normal, oriented by the primitive's winding (not flipped toward the
    /// ray): one-sided emitters and materials read the side from it.
    pub ng: Vec3,
    /// Unit shading normal (interpolated); equal to `ng` where the mesh has none. Always
    /// in the same hemisphere as `ng`.
    pub ns: Vec3,
    /// Texture coordinates, as Mitsuba defines them: a triangle's interpolated per-vertex
    /// coordinates or its barycentrics (b₁, b₂) where it has none
    /// ([`crate::shapes::Triangle::texcoords`]); (φ/2π, θ/π) on a sphere
    /// ([`crate::shapes::sphere_texcoords`]).
    pub uv: Vec2,
    pub material: MaterialId,
    /// The area light attached to this primitive, if any.
    pub emitter: Option<LightId>,
}

/// Ray queries against the scene's geometry. Implemented by hosts (our BVH4 in the CLI
/// and the browser) or by an embedding engine's own tracer. Implementations must be
/// thread-safe to share (`Sync`) if a host renders in parallel.
///
/// The batch methods answer many rays at once, structure-of-arrays in and out, so that a
/// tracer can use wide SIMD over rays (packets for coherent rays, streams) and keep its
/// code and data in cache across a batch. The lane loop of the estimators
/// (`transport::lanes`) asks through them. Their defaults loop over the single-ray
/// methods, so an implementor that has only those (the C ABI's callbacks, the tests'
/// brute-force tracer) answers batches unchanged, and a tracer that overrides them must
/// answer exactly as the single-ray methods would: the estimators' images do not depend
/// on how a query was asked.
pub trait RayQuery {
    /// Closest intersection with t in (0, ray.t_max), or `None`.
    fn intersect(&self, ray: &Ray) -> Option<SurfaceHit>;
    /// True if anything blocks the ray for t in (0, ray.t_max). May stop at the first hit.
    fn occluded(&self, ray: &Ray) -> bool;

    /// How many rays this tracer answers best at once: the number of paths the lane
    /// loop keeps in flight (clamped to `transport::lanes::LANES`). 1, the default,
    /// asks one ray at a time, as a depth-first path tracer does; the images are the
    /// same at every width.
    fn batch_width(&self) -> usize {
        1
    }

    /// [`Self::intersect`] for rays `0..n` of `rays` into `hits[..n]`, where `n` is the
    /// shorter of `rays.len()` and `hits.len()`; the rest of `hits` is left as it was.
    fn intersect_batch(&self, rays: RayBatch<'_>, hits: &mut [Option<SurfaceHit>]) {
        for (hit, ray) in hits.iter_mut().zip(rays.iter()) {
            *hit = self.intersect(&ray);
        }
    }

    /// [`Self::occluded`] for rays `0..n` of `rays` into `occluded[..n]`, `n` as for
    /// [`Self::intersect_batch`].
    fn occluded_batch(&self, rays: RayBatch<'_>, occluded: &mut [bool]) {
        for (o, ray) in occluded.iter_mut().zip(rays.iter()) {
            *o = self.occluded(&ray);
        }
    }
}

/// A ray per lane of a lane kernel (the shadow rays of `estimators::pt_lanes` and
/// `lt_lanes`), in structure-of-arrays form and owned, where [`RayBatch`] borrows.
#[derive(Clone, Copy, Debug)]
pub struct RayLanes {
    pub origin: Vec3s,
    pub dir: Vec3s,
    pub t_max: Lane,
}

impl RayLanes {
    pub const ZERO: Self = Self { origin: Vec3s::ZERO, dir: Vec3s::ZERO, t_max: [0.0; crate::math::soa::LANES] };

    /// Lane `i`'s ray.
    #[inline(always)]
    pub fn get(&self, i: usize) -> Ray {
        Ray { origin: self.origin.get(i), dir: self.dir.get(i), t_max: self.t_max[i] }
    }

    #[inline(always)]
    pub fn set(&mut self, i: usize, ray: Ray) {
        self.origin.set(i, ray.origin);
        self.dir.set(i, ray.dir);
        self.t_max[i] = ray.t_max;
    }
}

/// Rays in structure-of-arrays form, borrowed: ray `i` starts at
/// (`origin[0][i]`, `origin[1][i]`, `origin[2][i]`), goes along `dir[·][i]` and ends at
/// `t_max[i]`. Its length is the shortest slice's, so a batch never reads past any of
/// them.
#[derive(Clone, Copy, Debug)]
pub struct RayBatch<'a> {
    pub origin: [&'a [f32]; 3],
    pub dir: [&'a [f32]; 3],
    pub t_max: &'a [f32],
}

impl RayBatch<'_> {
    /// Rays in the batch: the shortest of the seven slices.
    #[inline]
    pub fn len(&self) -> usize {
        let shortest = |a: &[&[f32]; 3]| a[0].len().min(a[1].len()).min(a[2].len());
        shortest(&self.origin).min(shortest(&self.dir)).min(self.t_max.len())
    }

    /// True if the batch holds no ray.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Ray `i`, or `None` past the end.
    #[inline]
    pub fn ray(&self, i: usize) -> Option<Ray> {
        (i < self.len()).then(|| {
            let (o, d) = (&self.origin, &self.dir);
            Ray::new(Vec3::new(o[0][i], o[1][i], o[2][i]), Vec3::new(d[0][i], d[1][i], d[2][i]), self.t_max[i])
        })
    }

    /// The rays in order.
    #[inline]
    pub fn iter(&self) -> impl Iterator<Item = Ray> + '_ {
        let ([ox, oy, oz], [dx, dy, dz]) = (self.origin, self.dir);
        // Zipped slice iterators: no index, so no bounds check per component.
        let origins = ox.iter().zip(oy).zip(oz).map(|((&x, &y), &z)| Vec3::new(x, y, z));
        let dirs = dx.iter().zip(dy).zip(dz).map(|((&x, &y), &z)| Vec3::new(x, y, z));
        origins.zip(dirs).zip(self.t_max).map(|((o, d), &t)| Ray::new(o, d, t))
    }
}

/// Offset a ray origin off a surface, robustly at every scale: move `p` along `n` (the
/// geometric normal, pointing to the side the ray leaves toward) by 2⁻¹⁵ ≈ 3·10⁻⁵ of
/// its largest coordinate, i.e. about 256 ulps of that coordinate.
///
/// This is the integer-ulp offset of Wächter and Binder ("A Fast and Robust Method for
/// Avoiding Self-Intersection", Ray Tracing Gems ch. 6) measured on the point's largest
/// coordinate, as pbrt-v4 bounds a hit point's error by its magnitude: rounding in the
/// hit point and in the intersection test are both relative to |p|, so the offset is
/// too, and a scene behaves the same at any scale. (Wächter and Binder's absolute
/// offset of 1/65536 within 1/32 of the origin is 7 % of a Cornell box scaled by 1e-4,
/// which biased its image by 2 %: `tests/tests/stability_scale.rs`.) Scenes are built
/// camera-centred, so geometry passing through the origin is rare; a floor of 10⁻³⁰
/// keeps the origin itself moving.
#[inline]
pub fn offset_ray_origin(p: Vec3, n: Vec3) -> Vec3 {
    const RELATIVE: f32 = 1.0 / 32768.0;
    const FLOOR: f32 = 1e-30;
    let magnitude = p.abs().max_element().max(FLOOR);
    // Non-finite input stays non-finite (the callers' checks catch it), never panics.
    p + n * (magnitude * RELATIVE)
}

/// A ray leaving surface point `p` (geometric normal `ng`) in direction `dir`.
#[inline]
pub fn spawn_ray(p: Vec3, ng: Vec3, dir: Vec3) -> Ray {
    let n = if ng.dot(dir) >= 0.0 { ng } else { -ng };
    Ray::new(offset_ray_origin(p, n), dir, f32::INFINITY)
}

/// A shadow ray from surface point `p` (normal `ng`) to point `q` (normal `nq`, zero for
/// points not on a surface), offset at both ends; `t_max` is in units of the
/// unnormalised direction, so the ray stops just short of `q`.
#[inline]
pub fn spawn_ray_to(p: Vec3, ng: Vec3, q: Vec3, nq: Vec3) -> Ray {
    let d = q - p;
    let from = offset_ray_origin(p, if ng.dot(d) >= 0.0 { ng } else { -ng });
    // Without branches (`|`, not `||`; both ends computed), so that lanes of paths spawn
    // their shadow rays together.
    let on_surface = (nq.x != 0.0) | (nq.y != 0.0) | (nq.z != 0.0);
    let offset = offset_ray_origin(q, if nq.dot(d) <= 0.0 { nq } else { -nq });
    let to = if on_surface { offset } else { q };
    Ray::new(from, to - from, 1.0 - 1e-4)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn offset_moves_to_the_requested_side_at_every_scale() {
        for &s in &[1e-4f32, 1e-2, 1.0, 1e2, 1e5] {
            for &p in &[Vec3::new(s, -s, 0.3 * s), Vec3::new(-s, s, -2.0 * s)] {
                let n = Vec3::new(0.3, -0.5, 0.81).normalize();
                let q = offset_ray_origin(p, n);
                assert!((q - p).dot(n) > 0.0, "scale {s}");
                assert!((q - p).length() < 1e-3 * s.max(1.0), "scale {s}");
            }
        }
    }
}
