//! The interior-connection counters (`Counters::connections`, issue 18's occlusion
//! measurement) count what the shadow rays find.
//!
//! In a closed convex box every pair of points on its inner faces sees each other, so
//! BDPT's interior connections are never occluded; in the Cornell box with two spheres
//! many are. Injected-bug check (done once, reverted): `record(v, false)` in
//! `path::connect` (occlusion never recorded) fails the second half.

use ember_core::estimators::bdpt;
use ember_core::spectrum::Rgb;
use ember_core::transport::{MaxDepth, RenderParams};
use ember_tests::scenes::{cornell_with_spheres, furnace_box};
use ember_tests::tracer::BruteForce;

fn stats(builder: ember_core::scene::SceneBuilder) -> ember_core::transport::ConnectionStats {
    let (scene, geometry, _) = builder.build().unwrap();
    let tracer = BruteForce::new(geometry);
    let params = RenderParams { max_depth: MaxDepth(6), seed: 2, ..RenderParams::default() };
    let mut out = vec![Rgb::ZERO; 64];
    let mut total = ember_core::transport::ConnectionStats::default();
    for pass in 0..4 {
        let c = bdpt::render_pixels(&scene, &tracer, &params, pass, 0..64, &mut out, &mut |_| {});
        total += c.connections;
    }
    total
}

#[test]
fn occluded_connections_are_counted() {
    let open = stats(furnace_box(0.5, 1.0, 8, 8));
    assert!(open.traced > 500, "too few connections: {open:?}");
    assert_eq!((open.occluded, open.occluded_value), (0, 0.0), "a convex box occludes nothing: {open:?}");
    assert!(open.value > 0.0);

    let blocked = stats(cornell_with_spheres(8, 8));
    assert!(blocked.traced > 500, "too few connections: {blocked:?}");
    let share = blocked.occluded as f64 / blocked.traced as f64;
    assert!((0.05..0.95).contains(&share), "occluded share {share}: {blocked:?}");
    assert!(blocked.occluded_value > 0.0 && blocked.occluded_value < blocked.value, "{blocked:?}");
}
