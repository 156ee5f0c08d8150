//! Rays with an exactly-zero direction component hit what they cross. The segment
//! kernel's projection rays run along surface normals, which are often axis-aligned in
//! one component. Seen failing before `accel::safe_direction`: on the built-in Cornell
//! box's short block (front-face normal (−0.286, 0, 0.958)) every projection ray missed,
//! so the disk kernel's surface share read 0 there (and photon filtering's gather, black).

use ember_core::geometry::RayQuery;
use ember_core::rng::{SampleStream, Stream};
use ember_core::scene::builtin;
use ember_core::segment::Kernel;
use glam::Vec2;

#[test]
fn kernel_projection_rays_along_normals_with_zero_components_hit_the_surface() {
    let (scene, geometry, _) = builtin::cornell_box(128, 128).build().unwrap();
    let tracer = ember_host::accel::Accel::new(&geometry);
    // The short block's front face (twice), the tall block, the floor, the back wall.
    for (x, y) in [(80.0f32, 100.0f32), (64.0, 120.0), (40.0, 60.0), (64.0, 126.0), (64.0, 30.0)] {
        let ray = scene.camera.generate_ray(Vec2::new(x, y));
        let hit = tracer.intersect(&ray).expect("the camera sees the box");
        let mut rng = SampleStream::for_sample(1, Stream::Aux, 0, 0, 7);
        let share = Kernel::Disk { radius: 0.01 }.surface_share(&tracer, &hit, -ray.dir, 4, &mut rng);
        assert_eq!(share, 1.0, "pixel ({x}, {y}): normal {:?}, {share} of the projection rays hit", hit.ng);
    }
}
