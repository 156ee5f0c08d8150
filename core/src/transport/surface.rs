//! A shading point built from a ray hit: the frame, the material and the directions in
//! local coordinates, shared by every estimator.

use alloc::borrow::Cow;

use crate::bsdf::{Material, TransportMode, shading_normal_correction};
use crate::geometry::{Ray, SurfaceHit, spawn_ray, spawn_ray_to};
use crate::math::{Frame, Vec3};
use crate::scene::Scene;
use crate::spectrum::Rgb;

/// A surface point reached by a path, with its shading frame.
#[derive(Clone, Copy, Debug)]
pub struct SurfacePoint {
    pub hit: SurfaceHit,
    pub frame: Frame,
    /// Unit direction back toward the previous vertex (world).
    pub wo: Vec3,
}

impl SurfacePoint {
    #[inline]
    pub fn new(hit: SurfaceHit, wo: Vec3) -> Self {
        Self { hit, frame: Frame::from_normal(hit.ns), wo }
    }
    #[inline]
    pub fn p(&self) -> Vec3 {
        self.hit.p
    }
    #[inline]
    pub fn ng(&self) -> Vec3 {
        self.hit.ng
    }
    /// The material here, with its textures' values at this point.
    #[inline]
    pub fn material<'s>(&self, scene: &'s Scene) -> Cow<'s, Material> {
        scene.material(self.hit.material, self.hit.uv)
    }
    /// BSDF value for leaving toward `wi` (world), times |cos θ_i| at the shading
    /// normal and the adjoint shading-normal correction for importance transport.
    #[inline]
    pub fn f_cos(&self, scene: &Scene, wi: Vec3, mode: TransportMode) -> Rgb {
        let m = self.material(scene);
        let (wo_l, wi_l) = (self.frame.to_local(self.wo), self.frame.to_local(wi));
        let f = m.eval(wo_l, wi_l, mode);
        if f.is_black() {
            return Rgb::ZERO;
        }
        f * (wi_l.z.abs() * shading_normal_correction(mode, self.wo, wi, self.hit.ng, self.hit.ns))
    }
    /// Ray leaving this point in direction `dir`.
    #[inline]
    pub fn spawn(&self, dir: Vec3) -> Ray {
        spawn_ray(self.hit.p, self.hit.ng, dir)
    }
    /// The point rays leaving on the incoming side (toward `wo`'s hemisphere of the
    /// geometric normal) start from: every reflected ray's origin. Next-event estimation
    /// samples lights as seen from here, so that a light reached by a reflected BSDF ray
    /// (tested from this very point) and the light sample agree on which directions hit
    /// it: with the surface point itself, directions within the offset (3·10⁻⁵ of the
    /// coordinates) of a small sphere's silhouette hit from one point and miss from the
    /// other, and their BSDF samples carried MIS weight 1 (fireflies on veach-mis).
    #[inline]
    pub fn reflection_origin(&self) -> Vec3 {
        self.spawn(self.wo).origin
    }
    /// Shadow ray from this point to `q` (normal `nq`, zero if not on a surface).
    #[inline]
    pub fn spawn_to(&self, q: Vec3, nq: Vec3) -> Ray {
        spawn_ray_to(self.hit.p, self.hit.ng, q, nq)
    }
}
