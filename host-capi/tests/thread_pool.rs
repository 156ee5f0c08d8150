//! One thread pool per renderer, not per call (issue 55): the render threads of
//! `ember_render_passes` are started by the first call and serve every later one until
//! the renderer is destroyed.
//!
//! Injected bug seen failing here: `ember_render_passes` calling `driver::render` again,
//! which builds a pool per call: the second call's render threads had other thread ids
//! (the first call's had exited).
#![allow(unsafe_code)]

use std::collections::BTreeSet;
use std::ffi::CString;

use ember_capi::EmberStatus;
use ember_capi::ffi::*;

/// Thread ids of this process's threads named `ember-render-N` (Linux: /proc/self/task).
fn render_threads() -> BTreeSet<u64> {
    let Ok(tasks) = std::fs::read_dir("/proc/self/task") else { return BTreeSet::new() };
    tasks
        .flatten()
        .filter(|t| std::fs::read_to_string(t.path().join("comm")).is_ok_and(|name| name.starts_with("ember-render-")))
        .filter_map(|t| t.file_name().to_str().and_then(|id| id.parse().ok()))
        .collect()
}

#[test]
#[cfg(target_os = "linux")]
fn the_render_threads_outlive_the_call_and_serve_the_next() {
    let (mut scene, mut renderer) = (0, 0);
    let name = CString::new("cornell-box").unwrap();
    assert_eq!(unsafe { ember_scene_builtin(name.as_ptr(), 16, 16, &mut scene) }, EmberStatus::Ok);
    let (est, options) = (CString::new("pt").unwrap(), CString::new("").unwrap());
    let settings = EmberRenderSettings {
        estimator: est.as_ptr(),
        seed: 1,
        max_depth: -1,
        threads: 2,
        light_paths: 0,
        connections: 0,
        radius_footprints: 0.0,
        options: options.as_ptr(),
    };
    assert_eq!(unsafe { ember_renderer_create(scene, &settings, std::ptr::null(), &mut renderer) }, EmberStatus::Ok);
    assert_eq!(ember_render_passes(renderer, 1), EmberStatus::Ok);
    let first = render_threads();
    assert_eq!(first.len(), 2, "the renderer's 2 threads after its first call: {first:?}");
    // Threads of a pool dropped at the end of a call exit within milliseconds.
    std::thread::sleep(std::time::Duration::from_millis(200));
    assert_eq!(ember_render_passes(renderer, 2), EmberStatus::Ok);
    assert_eq!(render_threads(), first, "the second call rendered on other threads");
    assert_eq!(ember_renderer_destroy(renderer), EmberStatus::Ok);
    assert_eq!(ember_scene_destroy(scene), EmberStatus::Ok);
}
