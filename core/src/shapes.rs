//! The flat geometry a host hands to its ray-query structure: triangles and analytic
//! spheres, each with its material and (if it emits) its light.

use alloc::vec::Vec;

use crate::geometry::{LightId, MaterialId};
use crate::math::{self, Bounds3, Vec2, Vec3};

/// One triangle of the scene's geometry.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Triangle {
    pub p: [Vec3; 3],
    /// Per-vertex shading normals, if the mesh has them.
    pub n: Option<[Vec3; 3]>,
    /// Per-vertex texture coordinates, if the mesh has them.
    pub uv: Option<[Vec2; 3]>,
    pub material: MaterialId,
    pub emitter: Option<LightId>,
}

impl Triangle {
    /// Texture coordinates at barycentrics (b₁, b₂) (weights of `p[1]` and `p[2]`): the
    /// interpolated per-vertex coordinates, or (b₁, b₂) themselves where the triangle has
    /// none (Mitsuba's convention for meshes without texture coordinates).
    #[inline]
    pub fn texcoords(&self, b1: f32, b2: f32) -> Vec2 {
        texcoords_at(self.uv, [1.0 - b1 - b2, b1, b2])
    }
}

/// [`Triangle::texcoords`] from a triangle's per-vertex coordinates `uv` (if any) and all
/// three barycentrics `b` (hosts whose intersection test yields b₀ itself).
#[inline]
pub fn texcoords_at(uv: Option<[Vec2; 3]>, b: [f32; 3]) -> Vec2 {
    match uv {
        Some(uv) => uv[0] * b[0] + uv[1] * b[1] + uv[2] * b[2],
        None => Vec2::new(b[1], b[2]),
    }
}

/// Mitsuba's texture coordinates on a sphere at unit direction `local` from its centre:
/// (φ/2π, θ/π) with φ = atan2(y, x) in [0, 2π) and θ = acos z.
pub fn sphere_texcoords(local: Vec3) -> Vec2 {
    let mut phi = math::atan2(local.y, local.x);
    if phi < 0.0 {
        phi += 2.0 * core::f32::consts::PI;
    }
    let theta = math::safe_acos(local.z);
    Vec2::new(phi * (0.5 * core::f32::consts::FRAC_1_PI), theta * core::f32::consts::FRAC_1_PI)
}

/// An analytic sphere (intersected exactly by the host, so its light's solid-angle
/// sampling matches the geometry actually hit).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    pub center: Vec3,
    pub radius: f32,
    /// Normals point inward (Mitsuba's `flip_normals`).
    pub flip_normals: bool,
    pub material: MaterialId,
    pub emitter: Option<LightId>,
}

/// Everything a tracer needs.
#[derive(Clone, Debug, Default)]
pub struct SceneGeometry {
    pub triangles: Vec<Triangle>,
    pub spheres: Vec<Sphere>,
}

impl SceneGeometry {
    /// Bounds of all geometry.
    pub fn bounds(&self) -> Bounds3 {
        let mut b = Bounds3::EMPTY;
        for t in &self.triangles {
            for p in t.p {
                b = b.union_point(p);
            }
        }
        for s in &self.spheres {
            b = b.union_point(s.center - Vec3::splat(s.radius)).union_point(s.center + Vec3::splat(s.radius));
        }
        b
    }
}
