//! Path tracing next to a small sphere light far from the origin (veach-mis's r = 0.05
//! light at (−28.3, 3, 2.7), seen from glossy plates 2.4 units below it): no sample may
//! carry the unweighted light.
//!
//! The defect (issue 14): a BSDF-sampled ray starts at the offset origin (3·10⁻⁵ of the
//! coordinates, here 9·10⁻⁴ off the surface), but the light's density for the MIS
//! weight was evaluated from the surface point. Directions within the offset of the
//! silhouette hit the sphere from the ray's origin and miss it from the surface point:
//! `pdf_li` said 0, the BSDF sample took MIS weight 1 and carried 0.5 × 3040 = 1520
//! where its power-heuristic weight is below 1e-6. Next-event estimation now samples the
//! light as seen from where reflected rays start (`SurfacePoint::reflection_origin`) and
//! the emission weight reads the density from the ray's own origin, so both techniques
//! see the same sphere.
//!
//! 1. Point-wise: directions within ±0.3 % of the silhouette angle as seen from the
//!    reflection origin of 400 random plate points. Every direction whose ray (from that
//!    origin, exact f64 sphere test) hits the sphere has `pdf_li` from the same origin equal
//!    to the cone density; as a control, `pdf_li` from the surface point itself is 0 for
//!    some of them (the old reference), so the check can fail.
//! 2. End to end: 1.5 M PT samples of the plate under that light, direct lighting only:
//!    the largest camera sample stays below 10 (legit samples reach about 0.7, a weight-1
//!    light hit 1520). Seen failing with the old reference point restored in `pt.rs`
//!    (`sample_li(sp.p(), …)` and the density from the surface point): 4 samples above
//!    10, the largest 1520.47, and the mean 0.6 % higher (0.6027 against 0.5992): those
//!    samples were the energy of a band the light sample never covered, counted once
//!    more on top of the cone the light sample did cover.

use ember_core::bsdf::Material;
use ember_core::camera::{FovAxis, PerspectiveCamera};
use ember_core::estimators::pt;
use ember_core::geometry::SurfaceHit;
use ember_core::light::Light;
use ember_core::math::{Frame, Mat4};
use ember_core::rng::{SampleStream, Stream};
use ember_core::scene::{AreaEmission, SceneBuilder, builtin};
use ember_core::spectrum::Rgb;
use ember_core::transport::{MaxDepth, RenderParams, SurfacePoint};
use ember_tests::tracer::BruteForce;
use glam::{Vec2, Vec3};

const CENTER: Vec3 = Vec3::new(-28.2792, 3.0, 2.7);
const RADIUS: f32 = 0.05;
const RADIANCE: f32 = 3039.64;
const PLATE_Y: f32 = 0.6;

fn hit_sphere(o: Vec3, d: Vec3) -> Option<(Vec3, Vec3)> {
    let (o, d, c, r) = (o.as_dvec3(), d.as_dvec3().normalize(), CENTER.as_dvec3(), RADIUS as f64);
    let oc = o - c;
    let b = oc.dot(d);
    let disc = b * b - (oc.length_squared() - r * r);
    if disc < 0.0 {
        return None;
    }
    let t = -b - disc.sqrt();
    (t > 0.0).then(|| {
        let p = o + t * d;
        (p.as_vec3(), ((p - c) / r).as_vec3())
    })
}

#[test]
fn silhouette_hits_from_the_ray_origin_keep_their_light_density() {
    let light = Light::sphere(CENTER, RADIUS, Rgb::splat(RADIANCE));
    let mut rng = SampleStream::for_sample(3, Stream::Aux, 0, 0, 0);
    let (mut hits, mut missed_from_surface) = (0usize, 0usize);
    for _ in 0..400 {
        let p = Vec3::new(-28.8 + rng.next_f32(), PLATE_Y, 2.0 + 1.4 * rng.next_f32());
        let hit = SurfaceHit { t: 1.0, p, ng: Vec3::Y, ns: Vec3::Y, uv: Vec2::ZERO, material: 0, emitter: None };
        let sp = SurfacePoint::new(hit, Vec3::new(0.3, 0.9, -0.2).normalize());
        let o = sp.reflection_origin();
        // Every reflected ray starts there.
        assert_eq!(sp.spawn(Vec3::new(0.1, 0.5, 0.2).normalize()).origin, o);
        let to_c = CENTER - o;
        let d = to_c.length();
        let sin_max = RADIUS / d;
        let theta_max = sin_max.asin();
        let cone = 1.0 / (2.0 * core::f64::consts::PI * (1.0 - (theta_max as f64).cos()));
        let frame = Frame::from_normal(to_c / d);
        for _ in 0..50 {
            let theta = theta_max * (1.0 + 6e-3 * (rng.next_f32() - 0.5));
            let phi = 2.0 * core::f32::consts::PI * rng.next_f32();
            let wi = frame.to_world(Vec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos())).normalize();
            let Some((q, n)) = hit_sphere(o, wi) else { continue };
            hits += 1;
            let pdf = light.pdf_li(o, wi, q, n).0 as f64;
            assert!((pdf / cone - 1.0).abs() < 2e-3, "a ray from {o:?} along {wi:?} hits the light, pdf_li = {pdf} instead of {cone}");
            if light.pdf_li(p, wi, q, n).0 == 0.0 {
                missed_from_surface += 1;
            }
        }
    }
    println!("{hits} silhouette hits from the reflection origin; from the surface point {missed_from_surface} of them have density 0");
    assert!(hits > 5000, "too few silhouette hits: {hits}");
    assert!(missed_from_surface > 100, "the control must see the old reference fail ({missed_from_surface})");
}

#[test]
fn path_tracing_under_a_small_far_sphere_light_has_no_weight_one_light_hits() {
    let (w, h) = (16u32, 16u32);
    let mut b = SceneBuilder::new();
    let eye = Vec3::new(-27.0, 1.6, 2.0);
    b.set_camera(PerspectiveCamera::new(builtin::look_at(eye, Vec3::new(-28.3, PLATE_Y, 2.7), Vec3::Y), 30.0, FovAxis::X, w, h));
    let plate = b.add_material(Material::diffuse(Rgb::splat(0.5)));
    let rect = Mat4::from_translation(Vec3::new(-28.3, PLATE_Y, 2.7))
        * Mat4::from_rotation_x(-core::f32::consts::FRAC_PI_2)
        * Mat4::from_scale(Vec3::new(1.5, 1.5, 1.0));
    b.add_rectangle(rect, false, plate, None);
    let null = b.add_material(Material::diffuse(Rgb::ZERO));
    b.add_sphere(CENTER, RADIUS, false, null, Some(AreaEmission { radiance: Rgb::splat(RADIANCE), two_sided: false }));
    let (scene, geometry, _) = b.build().expect("scene");
    let tracer = BruteForce::new(geometry);
    let params = RenderParams { max_depth: MaxDepth(2), seed: 17, ..RenderParams::default() };
    let mut out = vec![Rgb::ZERO; (w * h) as usize];
    let (mut largest, mut above, mut mean) = (0.0f32, 0usize, 0.0f64);
    let passes = 6000;
    for pass in 0..passes {
        pt::render_pixels(&scene, &tracer, &params, pass, 0..w * h, &mut out);
        for v in &out {
            let m = v.max_component();
            largest = largest.max(m);
            above += (m > 10.0) as usize;
            mean += v.average() as f64;
        }
    }
    mean /= (passes * w * h) as f64;
    println!("{} samples: mean {mean:.4}, largest {largest}, {above} above 10", passes * w * h);
    assert!(mean > 0.01, "the plate must be lit (mean {mean})");
    assert!(above == 0, "{above} samples above 10 (largest {largest}): light hits with MIS weight 1");
}
