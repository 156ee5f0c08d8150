//! The engine's ray queries behind the core's `RayQuery`: the built-in BVH, or the
//! embedder's callbacks with every hit they return checked against their contract.

use ember_core::geometry::{Ray, RayQuery, SurfaceHit};
use ember_host::accel::Accel;

use super::{Callbacks, EmberHit, EmberRay};
use crate::{EmberStatus, Error, Result, SceneData};

fn c_ray(ray: &Ray) -> EmberRay {
    EmberRay { origin: ray.origin.to_array(), dir: ray.dir.to_array(), t_max: ray.t_max }
}

/// How far a barycentric coordinate may fall outside [0, 1] (and their sum past 1) for
/// the tracer's rounding: a hit point off its triangle by at most this fraction of an edge.
const BARYCENTRIC_TOLERANCE: f32 = 1e-4;

/// The first hit of a call that broke the callback's contract, in words.
pub(super) type Fault = std::sync::OnceLock<String>;

/// The engine's tracer as the core's `RayQuery`: the core builds the surface hit from the
/// triangle the callback names (as the built-in BVH does). A hit that breaks the contract
/// is recorded in `fault` (the first one) and from then on every ray of the call is a
/// miss without asking the callbacks; the call then fails with `CallbackError`. (The
/// core's `RayQuery` has no error path: a miss is the answer that shades nothing.)
pub(super) struct CallbackTracer<'a> {
    cb: &'a Callbacks,
    scene: &'a SceneData,
    fault: &'a Fault,
}

impl CallbackTracer<'_> {
    /// The triangle `hit` names if the hit keeps the contract for `ray` (`Ok(None)`: a
    /// triangle dropped as degenerate, which has no area to be hit); else what is wrong.
    fn check(&self, ray: &Ray, hit: &EmberHit) -> std::result::Result<Option<u32>, String> {
        let count = self.scene.triangle_index.len();
        let index = self.scene.triangle_index.get(hit.primitive as usize).ok_or_else(|| format!("primitive {} of {count} triangles", hit.primitive))?;
        if !(hit.t > 0.0 && hit.t < ray.t_max) {
            return Err(format!("t = {} outside (0, t_max = {})", hit.t, ray.t_max));
        }
        let (b1, b2, e) = (hit.b1, hit.b2, BARYCENTRIC_TOLERANCE);
        if !(b1 >= -e && b2 >= -e && b1 + b2 <= 1.0 + e) {
            return Err(format!("barycentrics ({b1}, {b2}) outside the triangle (b1, b2 >= 0 and b1 + b2 <= 1, to within {e})"));
        }
        Ok(*index)
    }
}

impl RayQuery for CallbackTracer<'_> {
    fn intersect(&self, ray: &Ray) -> Option<SurfaceHit> {
        if self.fault.get().is_some() {
            return None;
        }
        let mut hit = EmberHit::default();
        if !(self.cb.intersect)(self.cb.user_data, &c_ray(ray), &mut hit) {
            return None;
        }
        let tri = match self.check(ray, &hit) {
            Ok(index) => &self.scene.geometry.triangles[index? as usize],
            Err(what) => {
                self.fault.get_or_init(|| format!("the intersect callback returned {what}"));
                return None;
            }
        };
        let ng = (tri.p[1] - tri.p[0]).cross(tri.p[2] - tri.p[0]).normalize();
        let b0 = 1.0 - hit.b1 - hit.b2;
        let p = tri.p[0] * b0 + tri.p[1] * hit.b1 + tri.p[2] * hit.b2;
        // Interpolated shading normals where the triangle has them, on ng's side (as the BVH).
        let ns = tri.n.map(|n| n[0] * b0 + n[1] * hit.b1 + n[2] * hit.b2).and_then(|n| n.try_normalize()).map_or(ng, |n| if n.dot(ng) < 0.0 { -n } else { n });
        Some(SurfaceHit { t: hit.t, p, ng, ns, uv: tri.texcoords(hit.b1, hit.b2), material: tri.material, emitter: tri.emitter })
    }
    fn occluded(&self, ray: &Ray) -> bool {
        self.fault.get().is_none() && (self.cb.occluded)(self.cb.user_data, &c_ray(ray))
    }
}

/// The built-in BVH or the engine's callbacks.
pub(super) enum Tracer<'a> {
    Bvh(&'a Accel),
    Callbacks(CallbackTracer<'a>),
}

impl RayQuery for Tracer<'_> {
    fn intersect(&self, ray: &Ray) -> Option<SurfaceHit> {
        match self {
            Self::Bvh(a) => a.intersect(ray),
            Self::Callbacks(c) => c.intersect(ray),
        }
    }
    fn occluded(&self, ray: &Ray) -> bool {
        match self {
            Self::Bvh(a) => a.occluded(ray),
            Self::Callbacks(c) => c.occluded(ray),
        }
    }
}

pub(super) fn tracer<'a>(scene: &'a SceneData, callbacks: &'a Option<Callbacks>, fault: &'a Fault) -> Tracer<'a> {
    match callbacks {
        Some(cb) => Tracer::Callbacks(CallbackTracer { cb, scene, fault }),
        None => Tracer::Bvh(&scene.accel),
    }
}

/// The call's error if a callback broke its contract during it.
pub(super) fn fault_error(fault: Fault, then: &str) -> Result<()> {
    match fault.into_inner() {
        None => Ok(()),
        Some(what) => Err(Error::new(EmberStatus::CallbackError, format!("{what}; {then}"))),
    }
}
