//! BVH2 and CWBVH (obvhs) against our BVH4 (`accel/wide.rs`) through the CLI's `RayQuery` implementation, on camera
//! rays and on incoherent rays, closest hit and occlusion, one thread.
//!
//! Scene: a sphere tessellated into 256 × 256 quads (131 072 triangles), radially
//! displaced by a few sines, inside a closed 6 × 6 × 6 box (12 triangles), seen from
//! inside the box. Ray sets (512² = 262 144 rays each, fixed seeds):
//! - camera closest: a 512² pinhole camera looking at the sphere;
//! - camera occlusion: shadow rays from those rays' hit points to a point near the
//!   ceiling (next-event estimation from primary hits);
//! - random closest: uniform origins in the box, uniform directions (path bounces);
//! - random occlusion: segments between two uniform points in the box (connections).
//!
//! Run: `cargo bench -p ember-host --bench bvh`. Prints Mrays/s per set (best of 7,
//! the three structures taking turns) and the CWBVH / BVH2 and BVH4 / CWBVH ratios.

use std::hint::black_box;
use std::time::Instant;

use ember_core::geometry::{Ray, RayQuery, spawn_ray_to};
use ember_core::rng::{SampleStream, Stream};
use ember_core::shapes::{SceneGeometry, Triangle};
use ember_host::accel::{AccelWith, TriangleBvh, Wide};
use glam::Vec3;
use obvhs::bvh2::Bvh2;
use obvhs::cwbvh::CwBvh;

const N: usize = 256;
const HALF: f32 = 3.0;
const LIGHT: Vec3 = Vec3::new(0.3, 2.9, 0.2);
const REPS: usize = 7;
const RES: u32 = 512;

fn scene() -> SceneGeometry {
    let mut g = SceneGeometry::default();
    let vertex = |i: usize, j: usize| {
        let theta = std::f32::consts::PI * i as f32 / N as f32;
        let phi = 2.0 * std::f32::consts::PI * j as f32 / N as f32;
        let r = 1.5 + 0.2 * (8.0 * theta).sin() * (6.0 * phi).cos() + 0.05 * (23.0 * theta + phi).sin();
        Vec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin()) * r
    };
    let tri = |p: [Vec3; 3]| Triangle { p, n: None, uv: None, material: 0, emitter: None };
    for i in 0..N {
        for j in 0..N {
            let (a, b, c, d) = (vertex(i, j), vertex(i + 1, j), vertex(i + 1, j + 1), vertex(i, j + 1));
            g.triangles.push(tri([a, b, c]));
            g.triangles.push(tri([a, c, d]));
        }
    }
    // The box: 6 faces, 2 triangles each.
    let h = HALF;
    let corners = |axis: usize, side: f32| -> [Vec3; 4] {
        let q = [(-h, -h), (h, -h), (h, h), (-h, h)];
        q.map(|(u, v)| {
            let mut p = [0.0; 3];
            p[axis] = side;
            p[(axis + 1) % 3] = u;
            p[(axis + 2) % 3] = v;
            Vec3::from(p)
        })
    };
    for axis in 0..3 {
        for side in [-h, h] {
            let [a, b, c, d] = corners(axis, side);
            g.triangles.push(tri([a, b, c]));
            g.triangles.push(tri([a, c, d]));
        }
    }
    g
}

fn uniform_in_box(s: &mut SampleStream) -> Vec3 {
    (Vec3::new(s.next_f32(), s.next_f32(), s.next_f32()) * 2.0 - Vec3::ONE) * (HALF * 0.99)
}

fn uniform_direction(s: &mut SampleStream) -> Vec3 {
    let (u, v) = (s.next_f32(), s.next_f32());
    let z = 1.0 - 2.0 * u;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * std::f32::consts::PI * v;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

struct RaySets {
    camera: Vec<Ray>,
    random: Vec<Ray>,
    connections: Vec<Ray>,
}

fn ray_sets() -> RaySets {
    let res = RES;
    let origin = Vec3::new(0.0, 0.4, -2.9);
    let tan = (30.0f32).to_radians().tan();
    let camera = (0..res * res)
        .map(|i| {
            let (x, y) = ((i % res) as f32 + 0.5, (i / res) as f32 + 0.5);
            let d = Vec3::new((2.0 * x / res as f32 - 1.0) * tan, (1.0 - 2.0 * y / res as f32) * tan, 1.0);
            Ray::new(origin, d.normalize(), f32::INFINITY)
        })
        .collect();
    let random = (0..res * res)
        .map(|i| {
            let mut s = SampleStream::for_sample(1, Stream::Aux, i, 0, 0);
            Ray::new(uniform_in_box(&mut s), uniform_direction(&mut s), f32::INFINITY)
        })
        .collect();
    let connections = (0..res * res)
        .map(|i| {
            let mut s = SampleStream::for_sample(2, Stream::Aux, i, 0, 0);
            let (a, b) = (uniform_in_box(&mut s), uniform_in_box(&mut s));
            Ray::new(a, b - a, 1.0 - 1e-4)
        })
        .collect();
    RaySets { camera, random, connections }
}

/// One timing: Mrays/s and the number of rays that hit (which must agree between the
/// hierarchies).
fn time(rays: &[Ray], f: impl Fn(&Ray) -> bool) -> (f64, usize) {
    let t = Instant::now();
    let hits = rays.iter().filter(|r| f(black_box(r))).count();
    (rays.len() as f64 / t.elapsed().as_secs_f64() / 1e6, black_box(hits))
}

fn build<B: TriangleBvh>(g: &SceneGeometry) -> AccelWith<B> {
    let t = Instant::now();
    let accel = AccelWith::<B>::new(g);
    println!("{:>6}: built over {} triangles in {:.3} s", B::NAME, accel.triangle_count(), t.elapsed().as_secs_f64());
    accel
}

/// The four ray sets against one structure: (Mrays/s, hits) each.
fn run<Q: RayQuery>(accel: &Q, sets: &RaySets, shadow: &[Ray]) -> [(f64, usize); 4] {
    [
        time(&sets.camera, |r| accel.intersect(r).is_some()),
        time(shadow, |r| accel.occluded(r)),
        time(&sets.random, |r| accel.intersect(r).is_some()),
        time(&sets.connections, |r| accel.occluded(r)),
    ]
}

fn main() {
    let g = scene();
    let sets = ray_sets();
    let bvh2 = build::<Bvh2>(&g);
    let cwbvh = build::<CwBvh>(&g);
    let bvh4 = build::<Wide>(&g);
    // Shadow rays from the camera hits toward the light.
    let shadow: Vec<Ray> = sets.camera.iter().filter_map(|r| cwbvh.intersect(r)).map(|h| spawn_ray_to(h.p, h.ng, LIGHT, Vec3::ZERO)).collect();
    // Alternate the two structures and keep each one's best of REPS (robust to other
    // processes sharing the machine).
    let mut best = [[(0.0f64, 0usize); 4]; 3];
    for _ in 0..REPS {
        for (k, r) in [run(&bvh2, &sets, &shadow), run(&cwbvh, &sets, &shadow), run(&bvh4, &sets, &shadow)].into_iter().enumerate() {
            for (b, m) in best[k].iter_mut().zip(r) {
                *b = (b.0.max(m.0), m.1);
            }
        }
    }
    println!("{:<30} {:>7} {:>7} {:>7} {:>13} {:>13}", "Mrays/s, 1 thread, best of 7", "BVH2", "CWBVH", "BVH4", "CWBVH / BVH2", "BVH4 / CWBVH");
    let names = ["camera, closest hit", "camera, occlusion (NEE)", "random, closest hit", "random, occlusion (segments)"];
    for (k, name) in names.iter().enumerate() {
        let (a, b, c) = (best[0][k], best[1][k], best[2][k]);
        assert!(a.1 == b.1 && b.1 == c.1, "{name}: the hierarchies disagree on the hit count");
        println!("{:<30} {:>7.2} {:>7.2} {:>7.2} {:>13.2} {:>13.2}", name, a.0, b.0, c.0, b.0 / a.0, c.0 / b.0);
    }
}
