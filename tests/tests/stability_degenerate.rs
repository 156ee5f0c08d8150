//! Degenerate scene input (issue 8), through `SceneBuilder` (the Mitsuba loader's cases
//! are in `host-cli/src/mitsuba/tests.rs` and `tests_errors.rs`, with file:line errors):
//! zero-area triangles are dropped with a warning; NaN or ∞ vertices are a typed error;
//! a camera inside geometry and a light with zero power render a finite image (black
//! where nothing is lit) with no discarded sample, and the dark light is a warning.
//!
//! Injected bug (run once, reverted): removing the `is_finite` check in
//! `SceneBuilder::add_triangle` makes the NaN-vertex case build (caught here).

use ember_core::bsdf::Material;
use ember_core::camera::{FovAxis, PerspectiveCamera};
use ember_core::scene::{AreaEmission, Scene, SceneBuilder, SceneError, builtin};
use ember_core::spectrum::Rgb;
use ember_core::transport::{MaxDepth, RenderParams};
use ember_tests::render::{PT_LT_BDPT, render_pass};
use ember_tests::scenes::cornell;
use ember_tests::tracer::BruteForce;
use glam::{Mat4, Vec3};

fn render_all(scene: &Scene, tracer: &BruteForce) -> f64 {
    let params = RenderParams { max_depth: MaxDepth(5), seed: 2, ..RenderParams::default() };
    let mut total = 0.0;
    for est in PT_LT_BDPT {
        for pass in 0..2 {
            let (img, counters) = render_pass(est, scene, tracer, &params, pass);
            assert_eq!(counters.discarded, 0, "{est:?}: non-finite samples");
            assert!(img.iter().flatten().all(|c| c.is_finite() && *c >= 0.0), "{est:?}: bad pixel");
            total += img.iter().flatten().sum::<f64>();
        }
    }
    total
}

#[test]
fn zero_area_triangles_are_dropped_with_a_warning() {
    let mut b = cornell(8, 8);
    let m = b.add_material(Material::diffuse(Rgb::ONE));
    let p = Vec3::new(0.0, 1.0, 0.0);
    assert!(!b.add_triangle([p, p, p], None, m, None));
    assert!(!b.add_triangle([p, p + Vec3::X, p + 2.0 * Vec3::X], None, m, Some(AreaEmission { radiance: Rgb::ONE, two_sided: true })));
    let (scene, geometry, warnings) = b.build().unwrap();
    assert_eq!(warnings.degenerate_triangles, 2);
    assert!(render_all(&scene, &BruteForce::new(geometry)) > 0.0);
}

#[test]
fn non_finite_vertices_are_errors() {
    for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
        let mut b = cornell(8, 8);
        let m = b.add_material(Material::diffuse(Rgb::ONE));
        assert!(!b.add_triangle([Vec3::ZERO, Vec3::X, Vec3::new(0.0, bad, 0.0)], None, m, None));
        assert_eq!(b.build().unwrap_err(), SceneError::NonFinite("a triangle vertex"));
        let mut b = cornell(8, 8);
        b.add_sphere(Vec3::new(bad, 0.0, 0.0), 1.0, false, 0, None);
        assert!(matches!(b.build(), Err(SceneError::NonFinite(_))));
        let mut b = cornell(8, 8);
        b.add_rectangle(Mat4::from_scale(Vec3::new(bad, 1.0, 1.0)), false, 0, None);
        assert!(matches!(b.build(), Err(SceneError::NonFinite(_))), "rectangle scaled by {bad}");
    }
}

#[test]
fn camera_inside_geometry_renders_finite() {
    // The camera inside the tall box (a closed cube, seen from inside: black).
    let mut b = cornell(8, 8);
    b.set_camera(PerspectiveCamera::new(builtin::look_at(Vec3::new(-0.33, 0.6, -0.29), Vec3::new(0.0, 0.6, 1.0), Vec3::Y), 60.0, FovAxis::X, 8, 8));
    let (scene, geometry, _) = b.build().unwrap();
    let total = render_all(&scene, &BruteForce::new(geometry));
    assert!(total.is_finite());
    // And inside a closed emitting box, which must be bright.
    let mut b = SceneBuilder::new();
    b.set_camera(PerspectiveCamera::new(Mat4::IDENTITY, 60.0, FovAxis::X, 8, 8));
    let m = b.add_material(Material::diffuse(Rgb::splat(0.5)));
    b.add_cube(Mat4::IDENTITY, true, m, Some(AreaEmission { radiance: Rgb::ONE, two_sided: false }));
    let (scene, geometry, _) = b.build().unwrap();
    assert!(render_all(&scene, &BruteForce::new(geometry)) > 0.0);
}

#[test]
fn zero_power_lights_warn_and_render_black() {
    let (unit, geometry, _) = cornell(8, 8).build().unwrap();
    let mut b = SceneBuilder::new();
    b.set_camera(unit.camera);
    for m in &unit.materials {
        b.add_material(*m);
    }
    for t in &geometry.triangles {
        b.add_triangle(t.p, t.n, t.material, t.emitter.map(|_| AreaEmission { radiance: Rgb::ZERO, two_sided: false }));
    }
    b.add_light(ember_core::light::Light::point(Vec3::new(0.0, 1.0, 0.0), Rgb::ZERO));
    let (scene, geometry, warnings) = b.build().unwrap();
    assert_eq!(warnings.dark_lights, 3, "two light triangles and the point light");
    assert_eq!(render_all(&scene, &BruteForce::new(geometry)), 0.0);
}
