//! Panics inside ember's calls are reported once, as the status and `ember_last_error`,
//! and never printed: not through the host's panic hook, nor the default one. Every other
//! panic still reaches the host's hook. (A file of its own: a test process has one panic
//! hook, and this one counts every panic.)
//!
//! Injected bugs seen to fail here (each run once, reverted):
//! - no hook installed (as before issue 51): the host's hook ran once per render thread
//!   whose chunk panicked (4 of 4 here), and once for the phase call's panic;
//! - a hook silent for every panic (not chaining to the previous one): the host's own
//!   panics counted 0, not 2;
//! - the render threads' name prefix misspelt ("ember-renderer-"): the host's hook ran
//!   for the panics on ember's render threads.
#![allow(unsafe_code)]

use std::ffi::{CString, c_void};
use std::sync::atomic::{AtomicUsize, Ordering};

use ember_capi::EmberStatus;
use ember_capi::ffi::*;

static HOST_HOOK_CALLS: AtomicUsize = AtomicUsize::new(0);

extern "C-unwind" fn panicking_intersect(_: *mut c_void, _: *const EmberRay, _: *mut EmberHit) -> bool {
    panic!("engine tracer bug");
}

extern "C-unwind" fn never_occluded(_: *mut c_void, _: *const EmberRay) -> bool {
    false
}

fn last_error() -> String {
    unsafe { std::ffi::CStr::from_ptr(ember_last_error()) }.to_string_lossy().into_owned()
}

#[test]
fn panics_inside_ember_reach_the_status_once_and_the_host_hook_never() {
    // The host's hook, installed before its first ember call: it counts, and prints (so
    // this test's own failures show).
    std::panic::set_hook(Box::new(|info| {
        HOST_HOOK_CALLS.fetch_add(1, Ordering::SeqCst);
        eprintln!("host hook: {info}");
    }));
    let (mut scene, mut by_passes, mut by_phases) = (0, 0, 0);
    let name = CString::new("cornell-box").unwrap();
    assert_eq!(unsafe { ember_scene_builtin(name.as_ptr(), 16, 16, &mut scene) }, EmberStatus::Ok);
    let pt = CString::new("pt").unwrap();
    let settings = EmberRenderSettings {
        estimator: pt.as_ptr(),
        seed: 1,
        max_depth: 3,
        threads: 4,
        light_paths: 0,
        connections: 0,
        radius_footprints: 0.0,
        options: std::ptr::null(),
    };
    let callbacks = EmberRayCallbacks { user_data: std::ptr::null_mut(), intersect: Some(panicking_intersect), occluded: Some(never_occluded) };
    assert_eq!(unsafe { ember_renderer_create(scene, &settings, &callbacks, &mut by_passes) }, EmberStatus::Ok);
    assert_eq!(unsafe { ember_renderer_create(scene, &settings, &callbacks, &mut by_phases) }, EmberStatus::Ok);

    // On ember's render threads: every chunk panics, the call reports one of them.
    assert_eq!(ember_render_passes(by_passes, 1), EmberStatus::Panic);
    let message = last_error();
    assert_eq!(message.matches("engine tracer bug").count(), 1, "{message}");
    // On the calling thread, mapping a chunk of the host's own phase.
    assert_eq!(ember_pass_start(by_phases, 0), EmberStatus::Ok);
    let mut info = EmberPhaseInfo::default();
    assert_eq!(unsafe { ember_phase_begin(by_phases, &mut info) }, EmberStatus::Ok);
    assert_eq!(ember_phase_map(by_phases, 0), EmberStatus::Panic);
    assert_eq!(last_error(), "panic inside ember: engine tracer bug");
    assert_eq!(HOST_HOOK_CALLS.load(Ordering::SeqCst), 0, "panics inside ember reached the host's hook");

    // The host's own panics, on this thread and on a thread of its own, reach its hook.
    assert!(std::panic::catch_unwind(|| panic!("the host's own")).is_err());
    assert!(std::thread::spawn(|| panic!("the host's own thread")).join().is_err());
    assert_eq!(HOST_HOOK_CALLS.load(Ordering::SeqCst), 2, "the host's panics did not reach its hook");

    for r in [by_passes, by_phases] {
        assert_eq!(ember_renderer_destroy(r), EmberStatus::Ok);
    }
    assert_eq!(ember_scene_destroy(scene), EmberStatus::Ok);
}
