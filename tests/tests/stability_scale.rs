//! Scale and translation invariance of the Cornell box (issue 8): scaled by 1e-4 … 1e4,
//! and translated by 1e5, the rendered image mean stays within 1e-4 of the unit-scale one.
//!
//! f32 cannot hold the box far from the origin: at 1e5 its ulp is 0.0078, so the light's
//! 0.02 gap below the ceiling is two ulps, and a 256-ulp ray offset is 2 units, the size
//! of the box (with f32 world coordinates). As pbrt-v4 does, the scene is built in a camera-centred frame computed in
//! f64: every vertex is transformed to the world (scale, then translation) in f64, the
//! camera position subtracted in f64, and only then rounded to f32. (The Mitsuba loader
//! does the same for every file: `host-cli/src/mitsuba/build.rs`,
//! `camera_centred_frame`.) The image is invariant under translation and scale; radiance
//! does not depend on units.
//!
//! Same seeds at every scale, so the renders are correlated and the comparison is tight:
//! the check is |mean_s / mean_1 − 1| ≤ 1e-4 for PT and BDPT, and no sample is discarded
//! as non-finite (the bound was 1 % while light paths' Russian roulette compared their
//! power with 1: BDPT moved by −0.5 % at scales ≤ 1e-2; seen failing with that rule
//! restored, issue 14). The unit-scale mean's standard error (about 8 %) is printed: with the
//! same random numbers at every scale, agreement to 1e-4, far below it, means the same
//! paths are sampled, not merely the same integral.
//!
//! Injected bug (run once, reverted): building the translated box in world coordinates
//! (no camera-centred frame): PT's mean at translation 1e5 drops by 46.5 %.
//! This test also found the absolute near-origin offset of `offset_ray_origin` (then
//! 1/65536 within 1/32 of the origin): +2.3 % at scale 1e-4; offsets are now relative to
//! |p| (`core/src/geometry.rs`), and PT's mean is the same to 1e-5 at every scale.

use ember_core::camera::{FovAxis, PerspectiveCamera};
use ember_core::estimators::EstimatorKind;
use ember_core::scene::{AreaEmission, Scene, SceneBuilder};
use ember_core::transport::{MaxDepth, RenderParams};
use ember_tests::render::render_pass;
use ember_tests::scenes::cornell;
use ember_tests::stats::MeanVar;
use ember_tests::tracer::BruteForce;
use glam::{DVec3, Mat4, Vec3};

const RES: u32 = 16;
const PASSES: u32 = 24;

/// The built-in Cornell box with every vertex mapped to the world by `p·scale + offset`
/// in f64 and, when `camera_centred`, expressed relative to the camera in f64 before
/// rounding to f32.
pub fn transformed_cornell(scale: f64, offset: DVec3, camera_centred: bool) -> (Scene, BruteForce) {
    let (unit, geometry, _) = cornell(RES, RES).build().expect("the Cornell box builds");
    let camera_unit = DVec3::new(0.0, 1.0, 6.8);
    let camera_world = camera_unit * scale + offset;
    let frame_origin = if camera_centred { camera_world } else { DVec3::ZERO };
    let map = |p: Vec3| ((p.as_dvec3() * scale + offset) - frame_origin).as_vec3();
    let mut b = SceneBuilder::new();
    let c = (camera_world - frame_origin).as_vec3();
    // The built-in camera's rotation (looking down −z, image x = world −x) at `c`.
    let cam = Mat4::from_cols_array(&[-1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, c.x, c.y, c.z, 1.0]);
    b.set_camera(PerspectiveCamera::new(cam, 19.5, FovAxis::X, RES, RES));
    for m in &unit.materials {
        b.add_material(*m);
    }
    for t in &geometry.triangles {
        let emission = t.emitter.map(|id| {
            let n = (t.p[1] - t.p[0]).cross(t.p[2] - t.p[0]).normalize();
            AreaEmission { radiance: unit.lights[id as usize].radiance(t.p[0], n, n), two_sided: false }
        });
        assert!(b.add_triangle(t.p.map(map), t.n, t.material, emission), "a triangle degenerated at scale {scale}");
    }
    let (scene, geometry, _) = b.build().expect("the transformed box builds");
    (scene, BruteForce::new(geometry))
}

fn image_mean(est: EstimatorKind, scene: &Scene, tracer: &BruteForce) -> (f64, f64) {
    let params = RenderParams { max_depth: MaxDepth(6), seed: 3, ..RenderParams::default() };
    let mut per_pass = MeanVar::default();
    for pass in 0..PASSES {
        let (img, counters) = render_pass(est, scene, tracer, &params, pass);
        assert_eq!(counters.discarded, 0, "{est:?}: non-finite samples");
        let m = img.iter().map(|p| p[0] + p[1] + p[2]).sum::<f64>() / (3 * img.len()) as f64;
        assert!(m.is_finite());
        per_pass.push(m);
    }
    (per_pass.mean(), (per_pass.variance() / PASSES as f64).sqrt())
}

#[test]
fn cornell_box_mean_is_invariant_under_scale_and_translation() {
    let cases = [(1e-4, 0.0), (1e-2, 0.0), (1e2, 0.0), (1e4, 0.0), (1.0, 1e5), (1e2, 1e5)];
    let mut report = Vec::new();
    for est in [EstimatorKind::Pt, EstimatorKind::Bdpt] {
        let (scene, tracer) = transformed_cornell(1.0, DVec3::ZERO, true);
        let (reference, se) = image_mean(est, &scene, &tracer);
        report.push(format!("{est:?} unit scale: mean {reference:.5} ± {se:.5} ({:.2} %)", 100.0 * se / reference));
        for &(scale, shift) in &cases {
            let (scene, tracer) = transformed_cornell(scale, DVec3::new(shift, -0.5 * shift, 0.25 * shift), true);
            let (mean, _) = image_mean(est, &scene, &tracer);
            let rel = mean / reference - 1.0;
            report.push(format!("{est:?} scale {scale:e}, translation {shift:e}: mean {mean:.5} ({:+.3} %)", 100.0 * rel));
            assert!(rel.abs() <= 1e-4, "{}", report.join("\n"));
        }
    }
    println!("{}", report.join("\n"));
}
