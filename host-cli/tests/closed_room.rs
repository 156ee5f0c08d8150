//! A closed room lit only from outside renders exactly 0, and rays leaving its concave
//! corners do not escape (issue 14, "light through seams").
//!
//! The room is the suite's `window_env` with its window covered by one more rectangle:
//! ten separate rectangles (no shared vertices between them; the file's scales put some
//! walls 1.2·10⁻⁷ short of their neighbours) under a constant environment.
//!
//! What leaked was not the seams: 229 of 230 escapes in 20 M bounce rays were hits the
//! CWBVH never reported (obvhs culls boxes the ray leaves before t = 10⁻⁴, an absolute
//! constant), the rest hits closer than the triangle test's rounding-error bound on t;
//! both happen to a ray leaving one wall within 10⁻⁴ of the next (see `accel.rs`'s
//! `T_STRETCH` and `accel/triangle.rs`). Welding the walls' vertices would not have
//! helped. With both fixed, the remaining escapes are the geometric gaps themselves:
//! 1 in 20 M, the brute-force tracer's count too.
//!
//! 1. 2 M random rays from interior points, then one bounce each from the hit (spawned
//!    as the renderer spawns): the CWBVH and the BVH2 lose no more rays than the
//!    brute-force tracer (which has no BVH) does. Seen failing before the fixes: CWBVH 23
//!    and BVH2 7 escapes against 0 brute-force ones.
//! 2. PT (128 passes) and BDPT (32 passes) at 64×48 render every pixel exactly 0. Seen
//!    failing before: 22 lit pixels in PT (58 at 256 passes).

use std::path::PathBuf;
use std::time::Instant;

use ember_cli::estimators::CoreRenderer;
use ember_cli::progress::DriverConfig;
use ember_core::estimators::EstimatorKind;
use ember_core::geometry::{Ray, RayQuery, spawn_ray};
use ember_core::render::Film;
use ember_core::rng::{SampleStream, Stream};
use ember_formats::mitsuba::{LoadOptions, load_scene_from_str};
use ember_host::accel::{AccelWith, Wide};
use ember_host::driver::Limits;
use ember_host::scene::PreparedScene;
use ember_tests::tracer::BruteForce;
use glam::Vec3;
use obvhs::bvh2::Bvh2;
use obvhs::cwbvh::CwBvh;

fn covered_window_env() -> (String, PathBuf) {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared/scenes/window_env/scene.xml");
    let text = std::fs::read_to_string(&path).expect("window_env scene");
    let cover = r#"<shape type="rectangle" name="cover">
        <transform name="to_world"><scale x="0.5" y="0.30000001192092896"/><translate y="1.5" z="-1.5"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.73 0.73 0.73"/></bsdf>
    </shape>
    <emitter type="constant""#;
    assert!(text.contains(r#"<emitter type="constant""#));
    (text.replacen(r#"<emitter type="constant""#, cover, 1), path)
}

fn load(w: u32, h: u32) -> (ember_core::scene::Scene, ember_core::shapes::SceneGeometry) {
    let (text, path) = covered_window_env();
    let loaded = load_scene_from_str(&text, &path, &LoadOptions { defaults: Vec::new(), width: Some(w), height: Some(h) }).expect("scene loads");
    let (scene, geometry, _) = loaded.builder.build().expect("scene builds");
    (scene, geometry)
}

fn direction(s: &mut SampleStream) -> Vec3 {
    let u = s.next_2d();
    let z = 1.0 - 2.0 * u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * std::f32::consts::PI * u.y;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// Bounce rays that escape through `q`'s closed room, out of `rays`.
fn escapes(q: &dyn RayQuery, bounds: (Vec3, Vec3), rays: u32) -> usize {
    let (lo, hi) = bounds;
    let mut s = SampleStream::for_sample(1, Stream::Aux, 0, 0, 0);
    let mut escaped = 0;
    for _ in 0..rays {
        let o = lo + 0.05 + (hi - lo - 0.1) * Vec3::new(s.next_f32(), s.next_f32(), s.next_f32());
        let d = direction(&mut s);
        let mut d2 = direction(&mut s);
        let Some(h) = q.intersect(&Ray::new(o, d, f32::INFINITY)) else { continue };
        if d2.dot(h.ng) * d.dot(h.ng) > 0.0 {
            d2 = -d2;
        }
        escaped += q.intersect(&spawn_ray(h.p, h.ng, d2)).is_none() as usize;
    }
    escaped
}

#[test]
fn rays_leaving_concave_corners_do_not_escape() {
    let (scene, geometry) = load(64, 48);
    let bounds = (scene.bounds.min, scene.bounds.max);
    let rays = 2_000_000;
    let brute = escapes(&BruteForce::new(geometry.clone()), bounds, rays);
    let cwbvh = escapes(&AccelWith::<CwBvh>::new(&geometry), bounds, rays);
    let bvh2 = escapes(&AccelWith::<Bvh2>::new(&geometry), bounds, rays);
    let bvh4 = escapes(&AccelWith::<Wide>::new(&geometry), bounds, rays);
    println!("escapes of {rays} bounce rays: brute force {brute}, CWBVH {cwbvh}, BVH2 {bvh2}, BVH4 {bvh4}");
    assert!(cwbvh <= brute + 1 && bvh2 <= brute + 1 && bvh4 <= brute + 1, "escapes: brute force {brute}, CWBVH {cwbvh}, BVH2 {bvh2}, BVH4 {bvh4}");
}

fn render(estimator: EstimatorKind, passes: u32) -> Film {
    let (text, path) = covered_window_env();
    let loaded = load_scene_from_str(&text, &path, &LoadOptions { defaults: Vec::new(), width: Some(64), height: Some(48) }).expect("scene loads");
    let (scene, geometry, _) = loaded.builder.build().expect("scene builds");
    let accel = ember_host::accel::Accel::new(&geometry);
    let prepared = PreparedScene { name: "closed room".into(), scene, accel, max_depth: None, spp: None, warnings: Vec::new(), inputs: Vec::new() };
    let mut r = CoreRenderer::with_config(prepared, estimator.default_config(), -1, 3, 2).expect("renderer");
    let mut film = Film::new(64, 48);
    let config = DriverConfig { progress: false, ..DriverConfig::with_threads(2) };
    r.render(&mut film, Limits { spp: passes, deadline: None, interrupt: None, first_pass: 0 }, config, Instant::now()).expect("render");
    film
}

#[test]
fn a_closed_room_lit_from_outside_renders_exactly_zero() {
    for (estimator, passes) in [(EstimatorKind::Pt, 128), (EstimatorKind::Bdpt, 32)] {
        let film = render(estimator, passes);
        let lit = film.sums().iter().filter(|p| p.iter().any(|&v| v != 0.0)).count();
        assert_eq!(lit, 0, "{estimator}: {lit} pixels lit inside a closed room");
    }
}
