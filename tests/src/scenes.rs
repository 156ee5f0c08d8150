//! Analytic and small scenes shared by the integration tests.

use ember_core::bsdf::{MicrofacetKind, Material};
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
