//! Built-in scenes, compiled into every host so `ember render` works with no files.

use super::{AreaEmission, SceneBuilder};
use crate::bsdf::Material;
use crate::camera::{FovAxis, PerspectiveCamera};
use crate::math::Mat4;
use crate::spectrum::Rgb;

/// Mitsuba's row-major 4×4 `matrix` value as a glam (column-major) matrix.
pub fn mat4_row_major(m: [f32; 16]) -> Mat4 {
    Mat4::from_cols_array(&m).transpose()
}

/// The Cornell box of the benchmark suite (Bitterli's version, CC0): the same geometry,
/// materials, light and camera as `scenes/cornell-box/scene.xml`, so the default render
/// can be compared with that scene's Mitsuba reference.
pub fn cornell_box(width: u32, height: u32) -> SceneBuilder {
    let mut b = SceneBuilder::new();
    let camera = mat4_row_major([-1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 0.0, 0.0, -1.0, 6.8, 0.0, 0.0, 0.0, 1.0]);
    b.set_camera(PerspectiveCamera::new(camera, 19.5, FovAxis::X, width, height));

    let white = b.add_material(Material::diffuse(Rgb::new(0.725, 0.71, 0.68)).two_sided());
    let red = b.add_material(Material::diffuse(Rgb::new(0.63, 0.065, 0.05)).two_sided());
    let green = b.add_material(Material::diffuse(Rgb::new(0.14, 0.45, 0.091)).two_sided());
    let black = b.add_material(Material::diffuse(Rgb::ZERO).two_sided());

    let rect = |m: [f32; 16]| mat4_row_major(m);
    // Floor, ceiling, back wall, right wall, left wall.
    b.add_rectangle(
        rect([-4.37114e-8, 1.0, 4.37114e-8, 0.0, 0.0, -8.74228e-8, 2.0, 0.0, 1.0, 4.37114e-8, 1.91069e-15, 0.0, 0.0, 0.0, 0.0, 1.0]),
        false,
        white,
        None,
    );
    b.add_rectangle(
        rect([-1.0, 7.64274e-15, -1.74846e-7, 0.0, 8.74228e-8, 8.74228e-8, -2.0, 2.0, 0.0, -1.0, -4.37114e-8, 0.0, 0.0, 0.0, 0.0, 1.0]),
        false,
        white,
        None,
    );
    b.add_rectangle(
        rect([1.91069e-15, 1.0, 1.31134e-7, 0.0, 1.0, 3.82137e-15, -8.74228e-8, 1.0, -4.37114e-8, 1.31134e-7, -2.0, -1.0, 0.0, 0.0, 0.0, 1.0]),
        false,
        white,
        None,
    );
    b.add_rectangle(
        rect([4.37114e-8, -1.74846e-7, 2.0, 1.0, 1.0, 3.82137e-15, -8.74228e-8, 1.0, 3.82137e-15, 1.0, 2.18557e-7, 0.0, 0.0, 0.0, 0.0, 1.0]),
        false,
        green,
        None,
    );
    b.add_rectangle(
        rect([-4.37114e-8, 8.74228e-8, -2.0, -1.0, 1.0, 3.82137e-15, -8.74228e-8, 1.0, 0.0, -1.0, -4.37114e-8, 0.0, 0.0, 0.0, 0.0, 1.0]),
        false,
        red,
        None,
    );
    // Short and tall boxes.
    b.add_cube(
        rect([0.0851643, 0.289542, 1.31134e-8, 0.328631, 3.72265e-9, 1.26563e-8, -0.3, 0.3, -0.284951, 0.0865363, 5.73206e-16, 0.374592, 0.0, 0.0, 0.0, 1.0]),
        false,
        white,
        None,
    );
    b.add_cube(
        rect([
            0.286776,
            0.098229,
            -2.29282e-15,
            -0.335439,
            -4.36233e-9,
            1.23382e-8,
            -0.6,
            0.6,
            -0.0997984,
            0.282266,
            2.62268e-8,
            -0.291415,
            0.0,
            0.0,
            0.0,
            1.0,
        ]),
        false,
        white,
        None,
    );
    // The light: a one-sided rectangle facing down.
    let light = AreaEmission { radiance: Rgb::new(17.0, 12.0, 4.0), two_sided: false };
    b.add_rectangle(
        rect([0.235, -1.66103e-8, -7.80685e-9, -0.005, -2.05444e-8, 3.90343e-9, -0.0893, 1.98, 2.05444e-8, 0.19, 8.30516e-9, -0.03, 0.0, 0.0, 0.0, 1.0]),
        false,
        black,
        Some(light),
    );
    b
}

/// Mitsuba's `lookat` transform: camera-to-world with local +z toward `target`, local
/// +x = cross(up, forward) (to the image's left) and local +y the re-orthogonalised up.
pub fn look_at(origin: crate::math::Vec3, target: crate::math::Vec3, up: crate::math::Vec3) -> Mat4 {
    let forward = (target - origin).normalize();
    let left = up.cross(forward).normalize();
    let new_up = forward.cross(left);
    Mat4::from_cols(left.extend(0.0), new_up.extend(0.0), forward.extend(0.0), origin.extend(1.0))
}
