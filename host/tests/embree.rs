//! Embree's ray queries (feature `embree`) against ours: the same answers at every
//! packet width, on random triangles and spheres; the robust mode's reason, rays aimed
//! exactly at the shared edges of a closed, tessellated box; and PT's image through
//! either.
//!
//! Run: `cargo test --release -p ember-host --features embree --test embree` (needs
//! Debian's `libembree-dev`; `scripts/test.sh` installs it when it can).

#![cfg(feature = "embree")]

use ember_core::geometry::{Ray, RayQuery};
use ember_core::rng::{SampleStream, Stream};
use ember_core::shapes::{SceneGeometry, Sphere, Triangle};
use ember_host::accel::embree::{BuildOptions, EmbreeAccel, Lanes};
use ember_host::accel::{Accel, PrimitiveRef};
use glam::Vec3;

fn point(s: &mut SampleStream, lo: f32, hi: f32) -> Vec3 {
    Vec3::new(s.next_f32(), s.next_f32(), s.next_f32()) * (hi - lo) + Vec3::splat(lo)
}

fn direction(s: &mut SampleStream) -> Vec3 {
    let (u, v) = (s.next_f32(), s.next_f32());
    let z = 1.0 - 2.0 * u;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = std::f32::consts::TAU * v;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// A closed box of half-size `h` whose walls are `k` × `k` quads (two triangles each).
fn tessellated_box(h: f32, k: usize) -> SceneGeometry {
    let mut g = SceneGeometry::default();
    for axis in 0..3 {
        for side in [-h, h] {
            let at = |i: usize, j: usize| {
                let mut p = [0.0; 3];
                p[axis] = side;
                p[(axis + 1) % 3] = -h + 2.0 * h * i as f32 / k as f32;
                p[(axis + 2) % 3] = -h + 2.0 * h * j as f32 / k as f32;
                Vec3::from(p)
            };
            for i in 0..k {
                for j in 0..k {
                    let t = |p| Triangle { p, n: None, uv: None, material: axis as u32, emitter: None };
                    g.triangles.push(t([at(i, j), at(i + 1, j), at(i + 1, j + 1)]));
                    g.triangles.push(t([at(i, j), at(i + 1, j + 1), at(i, j + 1)]));
                }
            }
        }
    }
    g
}

/// Random triangles (some with vertex normals, some emitting) and a few spheres, inside
/// a closed box so most rays hit something.
fn scene() -> SceneGeometry {
    let mut s = SampleStream::for_sample(31, Stream::Aux, 0, 0, 0);
    let mut g = tessellated_box(2.0, 3);
    for i in 0..300 {
        let c = point(&mut s, -1.0, 1.0);
        let size = 0.05 + 0.25 * s.next_f32();
        let p = [c + size * direction(&mut s), c + size * direction(&mut s), c + size * direction(&mut s)];
        let n = (i % 3 == 0).then(|| [direction(&mut s), direction(&mut s), direction(&mut s)]);
        g.triangles.push(Triangle { p, n, uv: None, material: i % 5, emitter: (i % 7 == 0).then_some(i) });
    }
    for i in 0..3 {
        g.spheres.push(Sphere { center: point(&mut s, -1.0, 1.0), radius: 0.1 + 0.2 * s.next_f32(), flip_normals: i == 1, material: 7, emitter: None });
    }
    g
}

/// Random rays from inside (a third with a finite t_max, as shadow rays have), and the
/// rays both refuse: Embree at every width answers as ours (same primitive, t within
/// 1e-5 of max(t, 1), the same record; the same occlusion). A ray whose hit lies within
/// 1e-4 of a triangle edge may name either neighbour (none of these do).
#[test]
fn answers_match_ours_at_every_width() {
    let g = scene();
    let (ours, theirs) = (Accel::new(&g), EmbreeAccel::new(&g).expect("Embree builds"));
    assert_eq!((theirs.triangle_count(), theirs.sphere_count()), (ours.triangle_count(), ours.sphere_count()));
    let mut s = SampleStream::for_sample(32, Stream::Aux, 0, 0, 0);
    let rays: Vec<Ray> = (0..20_000)
        .map(|i| Ray::new(point(&mut s, -1.5, 1.5), direction(&mut s), if i % 3 == 0 { 0.1 + s.next_f32() } else { f32::INFINITY }))
        .chain([
            Ray::new(Vec3::ZERO, Vec3::ZERO, 1.0),
            Ray::new(Vec3::ZERO, Vec3::X, 0.0),
            Ray::new(Vec3::NAN, Vec3::X, 1.0),
            Ray::new(Vec3::ZERO, Vec3::X, f32::NAN),
        ])
        .collect();
    for lanes in Lanes::ALL {
        let mut hits = vec![None; rays.len()];
        theirs.intersect_packets_of(&rays, lanes, lanes == Lanes::Sixteen, &mut hits);
        let mut blocked = vec![false; rays.len()];
        theirs.occluded_packets_of(&rays, lanes, false, &mut blocked);
        for (i, ray) in rays.iter().enumerate() {
            match (ours.intersect_primitive(ray), hits[i]) {
                (None, None) => {}
                (Some((a, pa)), Some((b, pb))) => {
                    assert_eq!(pa, pb, "ray {i}, {lanes:?}");
                    // Embree's t is rounded differently: an error of a few ulps of the
                    // scene's coordinates (unit scale here), not of t itself.
                    assert!((a.t - b.t).abs() <= 1e-5 * a.t.max(1.0), "ray {i}, {lanes:?}: t {} against {}", a.t, b.t);
                    assert_eq!((a.ng, a.material, a.emitter), (b.ng, b.material, b.emitter), "ray {i}, {lanes:?}");
                    assert!((a.p - b.p).length() <= 1e-5 * a.p.length().max(1.0), "ray {i}, {lanes:?}");
                    if matches!(pa, PrimitiveRef::Triangle(_)) {
                        assert!((a.ns - b.ns).length() < 1e-4, "ray {i}, {lanes:?}");
                    }
                }
                (a, b) => panic!("ray {i}, {lanes:?}: ours {a:?}, Embree {b:?}"),
            }
            assert_eq!(blocked[i], ours.occluded(ray), "ray {i}, {lanes:?}");
        }
    }
    // The trait's answers are the single-ray batch's.
    for ray in &rays[..1000] {
        assert_eq!(theirs.intersect(ray), theirs.intersect_primitive(ray).map(|(h, _)| h));
        assert_eq!(theirs.occluded(ray), ours.occluded(ray));
    }
}

/// Rays from inside a closed box of 16 × 16 quads per wall, aimed exactly at its 12
/// outer edges and at the shared edges between its triangles (grid lines and quad
/// diagonals): with `RTC_SCENE_FLAG_ROBUST` none escapes, at any width, as none escapes
/// ours (`accel.rs`: `closed_box_does_not_leak_at_edges`). Without the flag, the count
/// that escapes is printed (it is why the host builds robust scenes).
#[test]
fn robust_scenes_do_not_leak_at_edges() {
    const H: f32 = 3.0;
    const K: usize = 16;
    let g = tessellated_box(H, K);
    let ours = Accel::new(&g);
    let robust = EmbreeAccel::new(&g).expect("Embree builds");
    let fast = EmbreeAccel::with_options(&g, BuildOptions { robust: false, threads: 0 }).expect("Embree builds");
    let mut s = SampleStream::for_sample(9, Stream::Aux, 0, 0, 0);
    let rays: Vec<Ray> = (0..60_000u32)
        .map(|i| {
            let mut target = [0.0f32; 3];
            let free = (i % 3) as usize;
            if i % 2 == 0 {
                // One of the 12 outer edges: two coordinates at ±H, the third free.
                target[free] = (2.0 * s.next_f32() - 1.0) * H;
                target[(free + 1) % 3] = if s.next_f32() < 0.5 { H } else { -H };
                target[(free + 2) % 3] = if s.next_f32() < 0.5 { H } else { -H };
            } else {
                // A grid line or a quad's diagonal on a wall.
                let cell = 2.0 * H / K as f32;
                let (a, b) = ((s.next_f32() * K as f32).floor(), s.next_f32());
                let on_diagonal = i % 4 == 1;
                target[free] = if s.next_f32() < 0.5 { H } else { -H };
                target[(free + 1) % 3] = -H + cell * (a + if on_diagonal { b } else { 0.0 });
                target[(free + 2) % 3] = -H + cell * ((s.next_f32() * K as f32).floor() + b);
            }
            let origin = point(&mut s, -2.5, 2.5);
            Ray::new(origin, Vec3::from(target) - origin, f32::INFINITY)
        })
        .collect();
    let escapes = |hits: &[Option<_>]| hits.iter().filter(|h| h.is_none()).count();
    let ours_escaped = rays.iter().filter(|r| ours.intersect(r).is_none()).count();
    let mut hits = vec![None; rays.len()];
    for lanes in Lanes::ALL {
        robust.intersect_packets_of(&rays, lanes, false, &mut hits);
        assert_eq!(escapes(&hits), 0, "{lanes:?}: rays escaped the robust scene");
    }
    fast.intersect_packets_of(&rays, Lanes::One, false, &mut hits);
    println!("escaped of {}: ours {ours_escaped}, Embree robust 0, Embree not robust {}", rays.len(), escapes(&hits));
    assert_eq!(ours_escaped, 0);
}

/// PT renders the built-in Cornell box (64², 32 passes, unbounded depth) through both:
/// the same random numbers meet the same surfaces, so the images agree closely (hits
/// differ in the last bits of t, which moves later vertices by ulps): the image means
/// within 0.5 %, each 8 × 8 block's mean within 3 %. Seen failing with Embree's u and v
/// passed to the hit record as (b0, b1) instead of (b1, b2).
#[test]
fn pt_images_agree_through_either() {
    use ember_core::Rgb;
    use ember_core::estimators::pt;
    use ember_core::transport::{Heuristic, MaxDepth, RenderParams};
    const W: u32 = 64;
    let (scene, geometry, _) = ember_core::scene::builtin::cornell_box(W, W).build().expect("built-in scene");
    let params = RenderParams { max_depth: MaxDepth(-1), seed: 3, heuristic: Heuristic::Power, ..RenderParams::default() };
    let render = |tracer: &dyn RayQuery| {
        let mut sum = vec![0.0f64; (W * W) as usize];
        let mut out = vec![Rgb::ZERO; (W * W) as usize];
        for pass in 0..32 {
            pt::render_pixels(&scene, tracer, &params, pass, 0..W * W, &mut out);
            sum.iter_mut().zip(&out).for_each(|(s, c)| *s += (c.r + c.g + c.b) as f64);
        }
        sum
    };
    let ours = render(&Accel::new(&geometry));
    let theirs = render(&EmbreeAccel::new(&geometry).expect("Embree builds"));
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let (a, b) = (mean(&ours), mean(&theirs));
    assert!(a > 0.0 && (a - b).abs() <= 5e-3 * a, "image means {a} and {b}");
    for by in 0..W / 8 {
        for bx in 0..W / 8 {
            let block = |img: &[f64]| (0..64).map(|k| img[((by * 8 + k / 8) * W + bx * 8 + k % 8) as usize]).sum::<f64>();
            let (x, y) = (block(&ours), block(&theirs));
            assert!((x - y).abs() <= 0.03 * x.max(y).max(1e-3 * a * 64.0), "block ({bx}, {by}): {x} against {y}");
        }
    }
}
