//! The harder built-in scene, "glass-spheres": the Cornell room lit by a small, bright
//! ceiling light, with a smooth glass sphere and a smooth mirror sphere.
//!
//! It is harder than the Cornell box for a path tracer in the way the papers' scenes
//! are: the caustic the glass sphere throws on the floor and the light seen through
//! both spheres are paths of the form L S+ D E or E S+ L, which next-event estimation
//! cannot connect (a delta BSDF sits next to the light), so unidirectional PT only finds
//! them by hitting a small light by chance; light tracing and BDPT (its t = 1 and s ≥ 1
//! strategies) sample them directly. The light is a quarter of the Cornell light's area
//! at 4.5× the radiance, so the total power is about that of the Cornell box and the
//! two scenes share an exposure. Every surface has an analytic form (rectangles and
//! spheres), so any host's tracer can render it; no file is read.

use super::{AreaEmission, SceneBuilder};
use crate::bsdf::Material;
use crate::camera::{FovAxis, PerspectiveCamera};
use crate::math::Vec3;
use crate::spectrum::Rgb;

use super::builtin::{look_at, mat4_row_major};

/// The scene's name for hosts (`--builtin glass-spheres`, the page's scene menu).
pub const GLASS_SPHERES: &str = "glass-spheres";

/// Build "glass-spheres" at `width` × `height`; see the module documentation.
pub fn glass_spheres(width: u32, height: u32) -> SceneBuilder {
    let mut b = SceneBuilder::new();
    let camera = look_at(Vec3::new(0.0, 1.0, 6.8), Vec3::new(0.0, 1.0, 0.0), Vec3::Y);
    b.set_camera(PerspectiveCamera::new(camera, 19.5, FovAxis::X, width, height));

    let white = b.add_material(Material::diffuse(Rgb::new(0.725, 0.71, 0.68)).two_sided());
    let red = b.add_material(Material::diffuse(Rgb::new(0.63, 0.065, 0.05)).two_sided());
    let green = b.add_material(Material::diffuse(Rgb::new(0.14, 0.45, 0.091)).two_sided());
    let black = b.add_material(Material::diffuse(Rgb::ZERO).two_sided());
    let glass = b.add_material(Material::dielectric(1.5, 1.0, Rgb::ONE, Rgb::ONE));
    // Mitsuba's default conductor (η = 0, k = 1): a perfect mirror.
    let mirror = b.add_material(Material::conductor(Rgb::ZERO, Rgb::ONE, Rgb::ONE));

    // The room [-1, 1] × [0, 2] × [-1, 1], open toward the camera (+z).
    let quad = |b: &mut SceneBuilder, c: [[f32; 3]; 4], m| {
        let p = c.map(Vec3::from_array);
        b.add_mesh(&p, None, &[[0, 1, 2], [0, 2, 3]], m, None);
    };
    quad(&mut b, [[-1.0, 0.0, -1.0], [-1.0, 0.0, 1.0], [1.0, 0.0, 1.0], [1.0, 0.0, -1.0]], white); // floor
    quad(&mut b, [[-1.0, 2.0, -1.0], [1.0, 2.0, -1.0], [1.0, 2.0, 1.0], [-1.0, 2.0, 1.0]], white); // ceiling
    quad(&mut b, [[-1.0, 0.0, -1.0], [1.0, 0.0, -1.0], [1.0, 2.0, -1.0], [-1.0, 2.0, -1.0]], white); // back
    quad(&mut b, [[1.0, 0.0, -1.0], [1.0, 0.0, 1.0], [1.0, 2.0, 1.0], [1.0, 2.0, -1.0]], green); // right (+x)
    quad(&mut b, [[-1.0, 0.0, -1.0], [-1.0, 2.0, -1.0], [-1.0, 2.0, 1.0], [-1.0, 0.0, 1.0]], red); // left (−x)

    b.add_sphere(Vec3::new(-0.42, 0.4, 0.25), 0.4, false, glass, None);
    b.add_sphere(Vec3::new(0.45, 0.4, -0.4), 0.4, false, mirror, None);

    // A 0.2 × 0.2 light just below the ceiling, facing down (rectangle normal +z → −y).
    let light = AreaEmission { radiance: Rgb::new(76.5, 54.0, 18.0), two_sided: false };
    let to_world = mat4_row_major([0.1, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0, 1.98, 0.0, 0.1, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0]);
    b.add_rectangle(to_world, false, black, Some(light));
    b
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builds_with_one_area_light_and_two_spheres() {
        let (scene, geometry, warnings) = glass_spheres(32, 24).build().expect("builds");
        assert_eq!(geometry.spheres.len(), 2);
        assert_eq!(geometry.triangles.len(), 12);
        assert_eq!(scene.lights.len(), 2, "the light rectangle is two emitting triangles");
        assert_eq!(warnings.degenerate_triangles, 0);
        // The light faces down: its triangles' normals point to −y.
        let t = geometry.triangles.iter().find(|t| t.emitter.is_some()).expect("emitter");
        let n = (t.p[1] - t.p[0]).cross(t.p[2] - t.p[0]);
        assert!(n.y < 0.0 && n.x == 0.0 && n.z == 0.0, "light normal {n:?}");
    }
}
