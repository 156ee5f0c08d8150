//! The engine's ray queries behind the core's `RayQuery`: the built-in BVH, or the
//! embedder's callbacks (one ray per call, or batches of rays in arrays) with every hit
//! they return checked against their contract; and the C types that describe them.

use ember_core::geometry::{Ray, RayBatch, RayQuery, SurfaceHit};
use ember_host::accel::Accel;

use std::ffi::c_void;

use crate::{EmberStatus, Error, Result, SceneData};

/// A ray: points `origin + t·dir` for t in (0, t_max).
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct EmberRay {
    pub origin: [f32; 3],
    pub dir: [f32; 3],
    pub t_max: f32,
}

/// The closest hit an engine's tracer found: the distance, the triangle's index in the
/// scene description, and the barycentrics of the hit point
/// `(1 − b1 − b2)·p0 + b1·p1 + b2·p2`. Checked: t in (0, t_max), the index below the
/// triangle count, and the point in the triangle, `b1 ≥ 0`, `b2 ≥ 0`, `b1 + b2 ≤ 1`, each
/// with a tolerance of 1e-4 for the tracer's rounding; any other hit (NaN included) fails
/// the call with `EMBER_STATUS_CALLBACK_ERROR`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct EmberHit {
    pub t: f32,
    pub primitive: u32,
    pub b1: f32,
    pub b2: f32,
}

/// The engine's ray tracer. `intersect` fills `hit` and returns true for the closest hit
/// with t in (0, t_max), false for none; `occluded` returns true if anything is hit in
/// (0, t_max). Both are called from the render threads, concurrently unless `threads` is 1.
/// A callback written in Rust may panic (the call returns `EMBER_STATUS_PANIC`); a C++
/// exception must not leave a callback.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct EmberRayCallbacks {
    pub user_data: *mut c_void,
    // "C-unwind", so a Rust callback's panic reaches ember's `catch_unwind` instead of
    // aborting; for C the ABI is "C"'s. (Spelled out, not as the aliases below: cbindgen
    // would not see through `Option<alias>`.)
    pub intersect: Option<extern "C-unwind" fn(user_data: *mut c_void, ray: *const EmberRay, hit: *mut EmberHit) -> bool>,
    pub occluded: Option<extern "C-unwind" fn(user_data: *mut c_void, ray: *const EmberRay) -> bool>,
}

/// `EmberRayCallbacks::intersect`.
type IntersectFn = extern "C-unwind" fn(*mut c_void, *const EmberRay, *mut EmberHit) -> bool;
/// `EmberRayCallbacks::occluded`.
type OccludedFn = extern "C-unwind" fn(*mut c_void, *const EmberRay) -> bool;

/// Rays in structure-of-arrays form, for the batch callbacks: ray `i` (below `count`)
/// starts at (`origin_x[i]`, `origin_y[i]`, `origin_z[i]`), goes along (`dir_x[i]`,
/// `dir_y[i]`, `dir_z[i]`) and covers t in (0, `t_max[i]`). Every pointer holds `count`
/// floats, valid during the call only.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct EmberRayBatch {
    pub origin_x: *const f32,
    pub origin_y: *const f32,
    pub origin_z: *const f32,
    pub dir_x: *const f32,
    pub dir_y: *const f32,
    pub dir_z: *const f32,
    pub t_max: *const f32,
    pub count: u32,
}

/// The engine's ray tracer answering rays in batches (`ember_renderer_create_batched`).
/// `intersect` writes, for each ray `i` of the batch, `found[i]` (a closest hit with t in
/// (0, t_max)) and, where found, `hits[i]` (checked as `EmberHit` says); `occluded`
/// writes `occluded[i]`, true if anything is hit in (0, t_max). `width` (1 to 4096) is
/// the batch size the engine answers best: the renderer keeps up to that many paths in
/// flight (at most 32 today; the path tracers and light tracers do, the other estimators
/// ask one ray at a time) and never asks more rays in one call. The image does not depend
/// on `width`. Called from the render threads as `EmberRayCallbacks` are.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct EmberRayBatchCallbacks {
    pub user_data: *mut c_void,
    pub width: u32,
    pub intersect: Option<extern "C-unwind" fn(user_data: *mut c_void, rays: *const EmberRayBatch, hits: *mut EmberHit, found: *mut bool)>,
    pub occluded: Option<extern "C-unwind" fn(user_data: *mut c_void, rays: *const EmberRayBatch, occluded: *mut bool)>,
}

/// `EmberRayBatchCallbacks::intersect`.
type IntersectBatchFn = extern "C-unwind" fn(*mut c_void, *const EmberRayBatch, *mut EmberHit, *mut bool);
/// `EmberRayBatchCallbacks::occluded`.
type OccludedBatchFn = extern "C-unwind" fn(*mut c_void, *const EmberRayBatch, *mut bool);

/// The largest `EmberRayBatchCallbacks::width` accepted.
pub(super) const MAX_BATCH_WIDTH: u32 = 4096;

/// The engine's callbacks, checked non-null: one ray per call, or batches.
#[derive(Clone, Copy, Debug)]
pub enum Callbacks {
    Single { user_data: *mut c_void, intersect: IntersectFn, occluded: OccludedFn },
    Batch { user_data: *mut c_void, width: usize, intersect: IntersectBatchFn, occluded: OccludedBatchFn },
}

// SAFETY: the embedder promises (ember.h, docs/embedding.md) that `user_data` and the
// callbacks may be used from several threads at once when `threads` is not 1.
unsafe impl Send for Callbacks {}
// SAFETY: as above.
unsafe impl Sync for Callbacks {}

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

impl CallbackTracer<'_> {
    /// The surface hit the engine's `hit` names for `ray`, or `None` (recording the
    /// fault) if it breaks the contract.
    fn record(&self, ray: &Ray, hit: &EmberHit) -> Option<SurfaceHit> {
        let tri = match self.check(ray, hit) {
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
}

/// Rays per call of a batch callback at most (the stack buffers of one call).
const CHUNK: usize = 64;

/// The batch callbacks' view of rays `from..from + n` of `rays` (`n` ≤ what is left):
/// pointers into the core's own arrays, no copy.
fn c_batch(rays: &RayBatch<'_>, from: usize, n: usize) -> EmberRayBatch {
    let at = |s: &[f32]| s[from..from + n].as_ptr();
    let ([ox, oy, oz], [dx, dy, dz]) = (rays.origin, rays.dir);
    EmberRayBatch { origin_x: at(ox), origin_y: at(oy), origin_z: at(oz), dir_x: at(dx), dir_y: at(dy), dir_z: at(dz), t_max: at(rays.t_max), count: n as u32 }
}

impl RayQuery for CallbackTracer<'_> {
    fn intersect(&self, ray: &Ray) -> Option<SurfaceHit> {
        if self.fault.get().is_some() {
            return None;
        }
        match *self.cb {
            Callbacks::Single { user_data, intersect, .. } => {
                let mut hit = EmberHit::default();
                if !intersect(user_data, &c_ray(ray), &mut hit) {
                    return None;
                }
                self.record(ray, &hit)
            }
            Callbacks::Batch { .. } => {
                let mut out = [None];
                let one = RayBatch {
                    origin: [&[ray.origin.x], &[ray.origin.y], &[ray.origin.z]],
                    dir: [&[ray.dir.x], &[ray.dir.y], &[ray.dir.z]],
                    t_max: &[ray.t_max],
                };
                self.intersect_batch(one, &mut out);
                out[0]
            }
        }
    }

    fn occluded(&self, ray: &Ray) -> bool {
        if self.fault.get().is_some() {
            return false;
        }
        match *self.cb {
            Callbacks::Single { user_data, occluded, .. } => occluded(user_data, &c_ray(ray)),
            Callbacks::Batch { .. } => {
                let mut out = [false];
                let one = RayBatch {
                    origin: [&[ray.origin.x], &[ray.origin.y], &[ray.origin.z]],
                    dir: [&[ray.dir.x], &[ray.dir.y], &[ray.dir.z]],
                    t_max: &[ray.t_max],
                };
                self.occluded_batch(one, &mut out);
                out[0]
            }
        }
    }

    fn batch_width(&self) -> usize {
        match *self.cb {
            Callbacks::Single { .. } => 1,
            Callbacks::Batch { width, .. } => width,
        }
    }

    fn intersect_batch(&self, rays: RayBatch<'_>, hits: &mut [Option<SurfaceHit>]) {
        let Callbacks::Batch { user_data, intersect, .. } = *self.cb else {
            for (hit, ray) in hits.iter_mut().zip(rays.iter()) {
                *hit = self.intersect(&ray);
            }
            return;
        };
        let n = rays.len().min(hits.len());
        for from in (0..n).step_by(CHUNK) {
            let count = CHUNK.min(n - from);
            let out = &mut hits[from..from + count];
            out.fill(None);
            if self.fault.get().is_some() {
                continue;
            }
            let (mut found, mut answers) = ([false; CHUNK], [EmberHit::default(); CHUNK]);
            intersect(user_data, &c_batch(&rays, from, count), answers.as_mut_ptr(), found.as_mut_ptr());
            for (i, slot) in out.iter_mut().enumerate() {
                if found[i] && self.fault.get().is_none() {
                    let ray = rays.ray(from + i).expect("i < the batch's length");
                    *slot = self.record(&ray, &answers[i]);
                }
            }
        }
        if self.fault.get().is_some() {
            // After a fault every ray of the call is a miss (see the type's notes).
            hits[..n].fill(None);
        }
    }

    fn occluded_batch(&self, rays: RayBatch<'_>, occluded: &mut [bool]) {
        let Callbacks::Batch { user_data, occluded: callback, .. } = *self.cb else {
            for (o, ray) in occluded.iter_mut().zip(rays.iter()) {
                *o = self.occluded(&ray);
            }
            return;
        };
        let n = rays.len().min(occluded.len());
        for from in (0..n).step_by(CHUNK) {
            let count = CHUNK.min(n - from);
            let out = &mut occluded[from..from + count];
            out.fill(false);
            if self.fault.get().is_none() {
                callback(user_data, &c_batch(&rays, from, count), out.as_mut_ptr());
            }
        }
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
    fn batch_width(&self) -> usize {
        match self {
            Self::Bvh(a) => a.batch_width(),
            Self::Callbacks(c) => c.batch_width(),
        }
    }
    fn intersect_batch(&self, rays: RayBatch<'_>, hits: &mut [Option<SurfaceHit>]) {
        match self {
            Self::Bvh(a) => a.intersect_batch(rays, hits),
            Self::Callbacks(c) => c.intersect_batch(rays, hits),
        }
    }
    fn occluded_batch(&self, rays: RayBatch<'_>, occluded: &mut [bool]) {
        match self {
            Self::Bvh(a) => a.occluded_batch(rays, occluded),
            Self::Callbacks(c) => c.occluded_batch(rays, occluded),
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
