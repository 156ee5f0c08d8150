//! Analytic and small scenes shared by the integration tests.

use ember_core::bsdf::{Material, MicrofacetKind};
use ember_core::camera::{FovAxis, PerspectiveCamera};
use ember_core::math::Mat4;
use ember_core::scene::{AreaEmission, SceneBuilder, builtin};
use ember_core::spectrum::Rgb;
use glam::Vec3;

/// A closed box [−1, 1]³ whose inward faces all emit `le` and reflect diffusely with
/// albedo `albedo`, viewed from its centre. Radiance is `le / (1 − albedo)` everywhere
/// (the white furnace).
pub fn furnace_box(albedo: f32, le: f32, width: u32, height: u32) -> SceneBuilder {
    let mut b = SceneBuilder::new();
    let cam = builtin::look_at(Vec3::new(0.1, 0.05, -0.2), Vec3::new(0.4, 0.3, 1.0), Vec3::Y);
    b.set_camera(PerspectiveCamera::new(cam, 70.0, FovAxis::X, width, height));
    let m = b.add_material(Material::diffuse(Rgb::splat(albedo)));
    b.add_cube(Mat4::IDENTITY, true, m, Some(AreaEmission { radiance: Rgb::splat(le), two_sided: false }));
    b
}

/// The built-in Cornell box (the suite's geometry).
pub fn cornell(width: u32, height: u32) -> SceneBuilder {
    builtin::cornell_box(width, height)
}

/// The Cornell box with a rough gold sphere and a smooth glass sphere added: Dirac
/// and glossy vertices for the MIS checks.
pub fn cornell_with_spheres(width: u32, height: u32) -> SceneBuilder {
    let mut b = builtin::cornell_box(width, height);
    let gold = b.add_material(Material::rough_conductor(
        MicrofacetKind::Ggx,
        0.2,
        Rgb::new(0.143_036, 0.375_307, 1.442_05),
        Rgb::new(3.983, 2.385_56, 1.603_36),
        Rgb::ONE,
    ));
    let glass = b.add_material(Material::dielectric(1.5046, 1.000_277, Rgb::ONE, Rgb::ONE));
    b.add_sphere(Vec3::new(-0.45, 0.25, 0.45), 0.25, false, gold, None);
    b.add_sphere(Vec3::new(0.4, 0.85, -0.2), 0.2, false, glass, None);
    b
}

/// [`cornell_with_spheres`] lit also by a point light and a spot light: Dirac light
/// positions, which next-event estimation reaches and emission hits cannot.
pub fn cornell_with_delta_lights(width: u32, height: u32) -> SceneBuilder {
    let mut b = cornell_with_spheres(width, height);
    b.add_light(ember_core::light::Light::point(Vec3::new(0.3, 1.5, 0.2), Rgb::new(0.8, 0.6, 0.4)));
    b.add_light(ember_core::light::Light::spot(Vec3::new(-0.5, 1.6, -0.3), Vec3::new(0.3, -1.0, 0.4), Rgb::splat(1.5), 35.0, 25.0));
    b
}

/// A closed diffuse room [−1.5, 1.5] × [0, 2.5] × [−1.5, 1.5] with a 1 × 0.6 window in
/// its back wall, lit only by a constant environment through the window (the suite's
/// window_env, built here without the parser). Camera paths that escape end on an
/// infinite light: BDPT's special cases for infinite vertices all occur.
pub fn window_room(width: u32, height: u32) -> SceneBuilder {
    window_room_lit(width, height, ember_core::light::Light::constant_environment(Rgb::new(1.0, 1.1, 1.3)))
}

/// [`window_room`] lit by `light` (a light at infinity) instead of the constant sky.
pub fn window_room_lit(width: u32, height: u32, light: ember_core::light::Light) -> SceneBuilder {
    let mut b = SceneBuilder::new();
    b.set_camera(PerspectiveCamera::new(builtin::look_at(Vec3::new(0.5, 1.2, 1.3), Vec3::new(0.226, 1.131, 0.341), Vec3::Y), 60.0, FovAxis::Y, width, height));
    let wall = b.add_material(Material::diffuse(Rgb::splat(0.73)).two_sided());
    let rect = |sx: f32, sy: f32, rot: Mat4, t: Vec3| Mat4::from_translation(t) * rot * Mat4::from_scale(Vec3::new(sx, sy, 1.0));
    let (rx, ry) = (core::f32::consts::FRAC_PI_2, core::f32::consts::FRAC_PI_2);
    let walls = [
        rect(1.5, 1.5, Mat4::from_rotation_x(-rx), Vec3::ZERO),                      // floor
        rect(1.5, 1.5, Mat4::from_rotation_x(rx), Vec3::new(0.0, 2.5, 0.0)),         // ceiling
        rect(1.5, 1.25, Mat4::from_rotation_y(ry), Vec3::new(-1.5, 1.25, 0.0)),      // left
        rect(1.5, 1.25, Mat4::from_rotation_y(-ry), Vec3::new(1.5, 1.25, 0.0)),      // right
        rect(1.5, 1.25, Mat4::from_rotation_y(2.0 * ry), Vec3::new(0.0, 1.25, 1.5)), // front
        rect(0.5, 1.25, Mat4::IDENTITY, Vec3::new(-1.0, 1.25, -1.5)),                // back, left of the window
        rect(0.5, 1.25, Mat4::IDENTITY, Vec3::new(1.0, 1.25, -1.5)),                 // back, right
        rect(0.5, 0.6, Mat4::IDENTITY, Vec3::new(0.0, 0.6, -1.5)),                   // below the window
        rect(0.5, 0.35, Mat4::IDENTITY, Vec3::new(0.0, 2.15, -1.5)),                 // above the window
    ];
    for m in walls {
        b.add_rectangle(m, false, wall, None);
    }
    b.add_light(light);
    b
}

/// An open scene under a light at infinity: a 4 × 4 diffuse floor, a diffuse cube and a
/// glossy sphere on it, seen from above at an angle. No walls, so light paths from the
/// scene disk reach the floor as often as camera paths reach the sky: light tracing is
/// efficient here, unlike in [`window_room`].
pub fn open_floor(width: u32, height: u32, light: ember_core::light::Light) -> SceneBuilder {
    let mut b = SceneBuilder::new();
    b.set_camera(PerspectiveCamera::new(builtin::look_at(Vec3::new(0.0, 2.2, 3.0), Vec3::new(0.0, 0.2, 0.0), Vec3::Y), 50.0, FovAxis::Y, width, height));
    let floor = b.add_material(Material::diffuse(Rgb::new(0.6, 0.6, 0.55)));
    let cube = b.add_material(Material::diffuse(Rgb::new(0.7, 0.3, 0.2)));
    let glossy = b.add_material(Material::rough_conductor(MicrofacetKind::Ggx, 0.3, Rgb::splat(0.2), Rgb::splat(3.0), Rgb::ONE));
    b.add_rectangle(Mat4::from_rotation_x(-core::f32::consts::FRAC_PI_2) * Mat4::from_scale(Vec3::splat(2.0)), false, floor, None);
    b.add_cube(Mat4::from_translation(Vec3::new(-0.6, 0.35, 0.0)) * Mat4::from_rotation_y(0.5) * Mat4::from_scale(Vec3::splat(0.35)), false, cube, None);
    b.add_sphere(Vec3::new(0.7, 0.4, 0.3), 0.4, false, glossy, None);
    b.add_light(light);
    b
}
