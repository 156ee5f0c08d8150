//! The batch ray callbacks (`ember_renderer_create_batched`): an engine tracer answering
//! rays in structure-of-arrays batches gives the same bits as the same tracer answering
//! one ray per call, for the estimators on the lane loop (PT, LT, which then ask whole
//! batches) and the others (one ray per batch); its hits are checked as the single-ray
//! callback's are; a width outside 1..=4096 and missing callbacks are refused.
//!
//! Injected bugs seen to fail here (each run once, reverted), in
//! `ffi/ray_queries.rs`: the batch view's `t_max` pointing at the directions' z
//! (`at(dz)`): 721 pixels of PT differ at width 1; every ray of a batch given the first
//! ray's hit (`answers[0]`): PT at width 7 fails with a hit outside its ray's interval.
#![allow(unsafe_code)]

use std::ffi::{CString, c_void};
use std::sync::atomic::{AtomicU64, Ordering};

use ember_capi::EmberStatus;
use ember_capi::ffi::*;
use ember_core::geometry::{Ray, RayQuery};
use ember_core::math::Vec3;
use ember_host::accel::{Accel, PrimitiveRef};

const W: u32 = 32;
const H: u32 = 24;

/// The engine's tracer: our own BVH over the built-in box, answering by triangle index
/// and the hit point's barycentrics.
struct Engine {
    accel: Accel,
    triangles: Vec<[Vec3; 3]>,
    /// Rays asked in calls of more than one ray.
    batched: AtomicU64,
    /// Answer every hit with t = −1 (a broken tracer).
    broken: bool,
}

impl Engine {
    fn new(broken: bool) -> Self {
        let (_, geometry, _) = ember_core::scene::builtin::cornell_box(W, H).build().unwrap();
        let triangles = geometry.triangles.iter().map(|t| t.p).collect();
        Self { accel: Accel::new(&geometry), triangles, batched: AtomicU64::new(0), broken }
    }

    fn hit(&self, ray: &Ray) -> Option<EmberHit> {
        let (hit, prim) = self.accel.intersect_primitive(ray)?;
        let PrimitiveRef::Triangle(index) = prim else { return None };
        // Barycentrics of the hit point: p − p0 = b1 e1 + b2 e2, solved in the plane.
        let [p0, p1, p2] = self.triangles[index as usize];
        let (e1, e2, d) = (p1 - p0, p2 - p0, hit.p - p0);
        let (a, b, c, d1, d2) = (e1.dot(e1), e1.dot(e2), e2.dot(e2), d.dot(e1), d.dot(e2));
        let det = a * c - b * b;
        let (b1, b2) = ((c * d1 - b * d2) / det, (a * d2 - b * d1) / det);
        Some(EmberHit { t: if self.broken { -1.0 } else { hit.t }, primitive: index, b1: b1.max(0.0), b2: b2.max(0.0).min(1.0 - b1.max(0.0)) })
    }
}

fn engine<'a>(user: *mut c_void) -> &'a Engine {
    // SAFETY: every renderer below is created with a pointer to a live `Engine`.
    unsafe { &*(user as *const Engine) }
}

fn ray_of(r: &EmberRay) -> Ray {
    Ray::new(Vec3::from_array(r.origin), Vec3::from_array(r.dir), r.t_max)
}

extern "C-unwind" fn intersect_one(user: *mut c_void, ray: *const EmberRay, hit: *mut EmberHit) -> bool {
    // SAFETY: valid for the call, by the C API's contract.
    let (ray, hit) = unsafe { (&*ray, &mut *hit) };
    engine(user).hit(&ray_of(ray)).map(|h| *hit = h).is_some()
}

extern "C-unwind" fn occluded_one(user: *mut c_void, ray: *const EmberRay) -> bool {
    // SAFETY: valid for the call.
    engine(user).accel.occluded(&ray_of(unsafe { &*ray }))
}

/// Ray `i` of a batch.
fn batch_ray(b: &EmberRayBatch, i: usize) -> Ray {
    // SAFETY: every pointer holds `count` floats during the call; i < count.
    let at = |p: *const f32| unsafe { *p.add(i) };
    Ray::new(Vec3::new(at(b.origin_x), at(b.origin_y), at(b.origin_z)), Vec3::new(at(b.dir_x), at(b.dir_y), at(b.dir_z)), at(b.t_max))
}

extern "C-unwind" fn intersect_many(user: *mut c_void, rays: *const EmberRayBatch, hits: *mut EmberHit, found: *mut bool) {
    let e = engine(user);
    // SAFETY: valid for the call; `hits` and `found` hold `count` elements.
    let b = unsafe { &*rays };
    let n = b.count as usize;
    if n > 1 {
        e.batched.fetch_add(n as u64, Ordering::Relaxed);
    }
    let (hits, found) = unsafe { (std::slice::from_raw_parts_mut(hits, n), std::slice::from_raw_parts_mut(found, n)) };
    for i in 0..n {
        found[i] = match e.hit(&batch_ray(b, i)) {
            Some(h) => {
                hits[i] = h;
                true
            }
            None => false,
        };
    }
}

extern "C-unwind" fn occluded_many(user: *mut c_void, rays: *const EmberRayBatch, occluded: *mut bool) {
    let e = engine(user);
    // SAFETY: valid for the call; `occluded` holds `count` elements.
    let b = unsafe { &*rays };
    let n = b.count as usize;
    if n > 1 {
        e.batched.fetch_add(n as u64, Ordering::Relaxed);
    }
    let out = unsafe { std::slice::from_raw_parts_mut(occluded, n) };
    for (i, o) in out.iter_mut().enumerate() {
        *o = e.accel.occluded(&batch_ray(b, i));
    }
}

fn scene() -> EmberScene {
    let (mut scene, name) = (0, CString::new("cornell-box").unwrap());
    assert_eq!(unsafe { ember_scene_builtin(name.as_ptr(), W, H, &mut scene) }, EmberStatus::Ok);
    scene
}

/// Render `passes` of `estimator` with single-ray callbacks (`width` None) or batch
/// callbacks of `width`; the image, or the status that refused it.
fn render(scene: EmberScene, estimator: &str, e: &Engine, width: Option<u32>) -> Result<Vec<f32>, (EmberStatus, String)> {
    let est = CString::new(estimator).unwrap();
    let settings = EmberRenderSettings {
        estimator: est.as_ptr(),
        seed: 3,
        max_depth: -1,
        threads: 2,
        light_paths: 0,
        connections: 0,
        radius_footprints: 0.0,
        options: std::ptr::null(),
    };
    let user = e as *const Engine as *mut c_void;
    let mut r = 0;
    let status = match width {
        None => {
            let cb = EmberRayCallbacks { user_data: user, intersect: Some(intersect_one), occluded: Some(occluded_one) };
            unsafe { ember_renderer_create(scene, &settings, &cb, &mut r) }
        }
        Some(width) => {
            let cb = EmberRayBatchCallbacks { user_data: user, width, intersect: Some(intersect_many), occluded: Some(occluded_many) };
            unsafe { ember_renderer_create_batched(scene, &settings, &cb, &mut r) }
        }
    };
    if status != EmberStatus::Ok {
        return Err((status, last_error()));
    }
    let status = ember_render_passes(r, 2);
    let message = last_error();
    let mut rgb = vec![0.0f32; (W * H * 3) as usize];
    if status == EmberStatus::Ok {
        assert_eq!(unsafe { ember_renderer_image(r, rgb.as_mut_ptr(), rgb.len()) }, EmberStatus::Ok);
    }
    assert_eq!(ember_renderer_destroy(r), EmberStatus::Ok);
    if status == EmberStatus::Ok { Ok(rgb) } else { Err((status, message)) }
}

fn last_error() -> String {
    // SAFETY: a valid NUL-terminated string until this thread's next ember call.
    unsafe { std::ffi::CStr::from_ptr(ember_last_error()) }.to_string_lossy().into_owned()
}

#[test]
fn batch_callbacks_give_the_bits_of_single_ray_callbacks() {
    let scene = scene();
    for (estimator, lanes) in [("pt", true), ("lt", true), ("spt", true), ("bdpt", false)] {
        let single = render(scene, estimator, &Engine::new(false), None).unwrap_or_else(|e| panic!("{estimator}, single-ray callbacks: {e:?}"));
        for width in [1, 7, 32, 4096] {
            let e = Engine::new(false);
            let batched = render(scene, estimator, &e, Some(width)).unwrap_or_else(|e| panic!("{estimator} at width {width}: {e:?}"));
            let differ = single.chunks(3).zip(batched.chunks(3)).filter(|(a, b)| a != b).count();
            assert_eq!(differ, 0, "{estimator} at width {width}: {differ} pixels differ from single-ray callbacks");
            let asked = e.batched.load(Ordering::Relaxed);
            if width > 1 && lanes {
                assert!(asked > 0, "{estimator} at width {width} never asked a batch of more than one ray");
            } else {
                assert_eq!(asked, 0, "{estimator} at width {width} asked batches");
            }
        }
    }
    assert_eq!(ember_scene_destroy(scene), EmberStatus::Ok);
}

#[test]
fn batch_hits_are_checked_and_bad_widths_refused() {
    let scene = scene();
    let Err((status, message)) = render(scene, "pt", &Engine::new(true), Some(16)) else { panic!("a broken batch tracer was accepted") };
    assert_eq!(status, EmberStatus::CallbackError);
    assert!(message.contains("t = -1"), "{message}");
    for width in [0, 4097] {
        let Err((status, message)) = render(scene, "pt", &Engine::new(false), Some(width)) else { panic!("width {width} accepted") };
        assert_eq!(status, EmberStatus::InvalidArgument, "width {width}");
        assert!(message.contains("callbacks.width"), "{message}");
    }
    let est = CString::new("pt").unwrap();
    let settings = EmberRenderSettings {
        estimator: est.as_ptr(),
        seed: 0,
        max_depth: -1,
        threads: 1,
        light_paths: 0,
        connections: 0,
        radius_footprints: 0.0,
        options: std::ptr::null(),
    };
    let mut r = 0;
    assert_ne!(unsafe { ember_renderer_create_batched(scene, &settings, std::ptr::null(), &mut r) }, EmberStatus::Ok);
    let half = EmberRayBatchCallbacks { user_data: std::ptr::null_mut(), width: 4, intersect: Some(intersect_many), occluded: None };
    assert_ne!(unsafe { ember_renderer_create_batched(scene, &settings, &half, &mut r) }, EmberStatus::Ok);
    assert_eq!(ember_scene_destroy(scene), EmberStatus::Ok);
}
