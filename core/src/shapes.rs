//! The flat geometry a host hands to its ray-query structure: triangles and analytic
//! spheres, each with its material and (if it emits) its light.

use alloc::vec::Vec;

use crate::geometry::{LightId, MaterialId};
use crate::math::{Bounds3, Vec3};

/// One triangle of the scene's geometry.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Triangle {
    pub p: [Vec3; 3],
    /// Per-vertex shading normals, if the mesh has them.
    pub n: Option<[Vec3; 3]>,
    pub material: MaterialId,
    pub emitter: Option<LightId>,
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
