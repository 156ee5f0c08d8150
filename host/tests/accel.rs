//! The ray-query structure against brute force: random rays against random triangles
//! and spheres, closest hit and occlusion, with both hierarchies and both sphere paths
//! (list and BVH); and rays spawned from hits never re-hit their own surface.

use ember_core::geometry::{Ray, RayQuery, spawn_ray};
use ember_core::rng::{SampleStream, Stream};
use ember_core::shapes::{SceneGeometry, Sphere, Triangle};
use ember_host::accel::{AccelWith, PrimitiveRef, SPHERE_LIST_MAX, TriangleBvh, Wide};
use glam::{DVec3, Vec3};
use obvhs::bvh2::Bvh2;
use obvhs::cwbvh::CwBvh;

fn point(s: &mut SampleStream, lo: f32, hi: f32) -> Vec3 {
    Vec3::new(s.next_f32(), s.next_f32(), s.next_f32()) * (hi - lo) + Vec3::splat(lo)
}

fn direction(s: &mut SampleStream) -> Vec3 {
    let (u, v) = (s.next_f32(), s.next_f32());
    let z = 1.0 - 2.0 * u;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * std::f32::consts::PI * v;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// Random triangles (some with vertex normals, some emitting) and spheres (some with
/// inward normals) in [-1, 1]³.
fn scene(seed: u32, triangles: usize, spheres: usize) -> SceneGeometry {
    let mut s = SampleStream::for_sample(11, Stream::Aux, seed, 0, 0);
    let mut g = SceneGeometry::default();
    for i in 0..triangles {
        let c = point(&mut s, -1.0, 1.0);
        let size = 0.05 + 0.25 * s.next_f32();
        let p = [c + size * direction(&mut s), c + size * direction(&mut s), c + size * direction(&mut s)];
        let n = (i % 3 == 0).then(|| [direction(&mut s), direction(&mut s), direction(&mut s)]);
        g.triangles.push(Triangle { p, n, uv: None, material: i as u32 % 5, emitter: (i % 7 == 0).then_some(i as u32) });
    }
    for i in 0..spheres {
        g.spheres.push(Sphere {
            center: point(&mut s, -1.0, 1.0),
            radius: 0.03 + 0.2 * s.next_f32(),
            flip_normals: i % 2 == 1,
            material: 100 + i as u32,
            emitter: (i % 3 == 0).then_some(1000 + i as u32),
        });
    }
    g
}

/// Exact (f64) closest hit: distance, primitive and, for triangles, the smallest
/// barycentric (how close the ray passes to an edge).
#[derive(Clone, Copy, Debug)]
struct Reference {
    t: f64,
    prim: PrimitiveRef,
    edge: f64,
}

/// All hits with t in (-1e-4, t_max), sorted (the slightly negative ones let the caller
/// see an origin lying on a surface).
fn brute_hits(g: &SceneGeometry, o: Vec3, d: Vec3, t_max: f32) -> Vec<Reference> {
    let (o, d) = (o.as_dvec3(), d.as_dvec3());
    let mut hits = Vec::new();
    for (i, t) in g.triangles.iter().enumerate() {
        // Möller–Trumbore in f64.
        let [p0, p1, p2] = t.p.map(|p| p.as_dvec3());
        let (e1, e2) = (p1 - p0, p2 - p0);
        let pv = d.cross(e2);
        let det = e1.dot(pv);
        if det.abs() < 1e-300 {
            continue;
        }
        let tv = o - p0;
        let u = tv.dot(pv) / det;
        let qv = tv.cross(e1);
        let v = d.dot(qv) / det;
        let tt = e2.dot(qv) / det;
        if u >= 0.0 && v >= 0.0 && u + v <= 1.0 && tt > -1e-4 && tt < t_max as f64 {
            hits.push(Reference { t: tt, prim: PrimitiveRef::Triangle(i as u32), edge: u.min(v).min(1.0 - u - v) });
        }
    }
    for (i, s) in g.spheres.iter().enumerate() {
        let f: DVec3 = o - s.center.as_dvec3();
        let (a, b, c) = (d.dot(d), 2.0 * f.dot(d), f.dot(f) - (s.radius as f64).powi(2));
        let disc = b * b - 4.0 * a * c;
        if disc < 0.0 {
            continue;
        }
        for tt in [(-b - disc.sqrt()) / (2.0 * a), (-b + disc.sqrt()) / (2.0 * a)] {
            if tt > -1e-4 && tt < t_max as f64 {
                // Grazing hits (tiny discriminant) are as ambiguous as edge hits.
                let edge = (disc.sqrt() / (2.0 * a.sqrt() * s.radius as f64)).min(1.0);
                hits.push(Reference { t: tt, prim: PrimitiveRef::Sphere(i as u32), edge });
            }
        }
    }
    hits.sort_by(|a, b| a.t.total_cmp(&b.t));
    hits
}

/// Is the reference answer for this ray decidable in f32 (no hit within 1e-4 of an
/// edge, no two hits within 1e-4 relative of each other, none within 1e-4 of t_max,
/// the origin not on a surface)?
fn clear_cut(hits: &[Reference], t_max: f32, d: Vec3) -> bool {
    // An origin within 1e-5 of a surface: which side it is on is up to rounding.
    if hits.iter().any(|h| (h.t * d.length() as f64).abs() < 1e-5) {
        return false;
    }
    let hits: Vec<Reference> = hits.iter().filter(|h| h.t > 0.0).copied().collect();
    let near_edge = hits.iter().take(2).any(|h| h.edge < 1e-4);
    let tie = hits.len() >= 2 && (hits[1].t - hits[0].t) < 1e-4 * hits[0].t;
    let at_end = t_max.is_finite() && hits.iter().any(|h| (h.t - t_max as f64).abs() < 1e-4 * t_max as f64);
    !(near_edge || tie || at_end)
}

fn check_against_brute_force<B: TriangleBvh>(g: &SceneGeometry, rays: u32, min_hits: f64) {
    let accel = AccelWith::<B>::new(g);
    assert_eq!(accel.triangle_count(), g.triangles.len());
    let mut s = SampleStream::for_sample(5, Stream::Aux, g.triangles.len() as u32, g.spheres.len() as u32, 0);
    let (mut checked, mut hits, mut occluded) = (0, 0, 0);
    for _ in 0..rays {
        let o = point(&mut s, -1.3, 1.3);
        // Unnormalised directions, and every third ray with a finite t_max.
        let d = direction(&mut s) * (0.5 + 2.0 * s.next_f32());
        let t_max = if s.next_f32() < 0.33 { 0.2 + 1.5 * s.next_f32() } else { f32::INFINITY };
        let all = brute_hits(g, o, d, t_max);
        if !clear_cut(&all, t_max, d) {
            continue;
        }
        let reference: Vec<Reference> = all.into_iter().filter(|h| h.t > 0.0).collect();
        checked += 1;
        let ray = Ray::new(o, d, t_max);
        let got = accel.intersect_primitive(&ray);
        assert_eq!(accel.occluded(&ray), !reference.is_empty(), "occlusion of {ray:?}");
        assert_eq!(accel.intersect(&ray).is_some(), !reference.is_empty());
        match (got, reference.first()) {
            (None, None) => {}
            (Some((hit, prim)), Some(r)) => {
                hits += 1;
                occluded += 1;
                assert_eq!(prim, r.prim, "primitive of {ray:?}");
                // 1e-4 relative, or a few f32 ulps of the coordinates (~1) in distance.
                let err = (hit.t as f64 - r.t).abs();
                assert!(err < 1e-4 * r.t || err * (d.length() as f64) < 1e-6, "t {} vs {} for {ray:?}", hit.t, r.t);
                check_record(g, &ray, &hit, prim);
            }
            (got, want) => panic!("{ray:?}: got {got:?}, want {want:?}"),
        }
    }
    // The ambiguous rays are few, and the rest exercise both outcomes.
    assert!(checked as f64 > 0.97 * rays as f64, "only {checked} of {rays} rays were clear-cut");
    assert!(hits as f64 > min_hits * rays as f64 && hits < rays * 9 / 10, "{hits} hits of {rays}");
    let _ = occluded;
}

/// The hit record's fields follow the contract of `SurfaceHit`.
fn check_record(g: &SceneGeometry, ray: &Ray, hit: &ember_core::geometry::SurfaceHit, prim: PrimitiveRef) {
    assert!((hit.p - ray.at(hit.t)).length() < 1e-4, "p is on the ray");
    assert!((hit.ng.length() - 1.0).abs() < 1e-5 && (hit.ns.length() - 1.0).abs() < 1e-5);
    assert!(hit.ng.dot(hit.ns) >= 0.0, "ns in ng's hemisphere");
    match prim {
        PrimitiveRef::Triangle(i) => {
            let t = &g.triangles[i as usize];
            let winding = (t.p[1] - t.p[0]).cross(t.p[2] - t.p[0]).normalize();
            assert!(hit.ng.dot(winding) > 0.9999, "ng follows the winding, not the ray");
            let (b1, b2) = (hit.uv.x, hit.uv.y);
            let q = (1.0 - b1 - b2) * t.p[0] + b1 * t.p[1] + b2 * t.p[2];
            assert!((q - hit.p).length() < 1e-4, "uv are the barycentrics (b1, b2)");
            match t.n {
                None => assert_eq!(hit.ns, hit.ng),
                Some(n) => {
                    let mut want = ((1.0 - b1 - b2) * n[0] + b1 * n[1] + b2 * n[2]).normalize();
                    if want.dot(hit.ng) < 0.0 {
                        want = -want;
                    }
                    assert!((want - hit.ns).length() < 1e-3, "ns {:?} vs {want:?}", hit.ns);
                }
            }
            assert_eq!((hit.material, hit.emitter), (t.material, t.emitter));
        }
        PrimitiveRef::Sphere(i) => {
            let s = &g.spheres[i as usize];
            let out = (hit.p - s.center).normalize();
            let want = if s.flip_normals { -out } else { out };
            assert!(hit.ng.dot(want) > 0.9999, "sphere normal outward unless flipped");
            assert!(((hit.p - s.center).length() - s.radius).abs() < 1e-5);
            assert_eq!(hit.ns, hit.ng);
            assert_eq!((hit.material, hit.emitter), (s.material, s.emitter));
        }
    }
}

#[test]
fn cwbvh_with_sphere_list_agrees_with_brute_force() {
    check_against_brute_force::<CwBvh>(&scene(1, 600, 3), 20_000, 0.2);
}

/// The production structure. Seen failing: with the BVH4 keeping the last packet hit
/// instead of the nearest (its `t_max` not cut), and with the listed spheres' boxes
/// (`SphereBox`, which let rays skip the f64 test) shrunk to 0.9 r (all three list
/// variants).
#[test]
fn bvh4_with_sphere_list_agrees_with_brute_force() {
    check_against_brute_force::<Wide>(&scene(1, 600, 3), 20_000, 0.2);
}

#[test]
fn bvh4_with_sphere_bvh_agrees_with_brute_force() {
    check_against_brute_force::<Wide>(&scene(2, 300, 40), 20_000, 0.2);
}

#[test]
fn bvh2_with_sphere_list_agrees_with_brute_force() {
    check_against_brute_force::<Bvh2>(&scene(1, 600, 3), 20_000, 0.2);
}

#[test]
fn cwbvh_with_sphere_bvh_agrees_with_brute_force() {
    let g = scene(2, 300, 40);
    assert!(g.spheres.len() > SPHERE_LIST_MAX);
    check_against_brute_force::<CwBvh>(&g, 20_000, 0.2);
}

#[test]
fn bvh2_with_sphere_bvh_agrees_with_brute_force() {
    check_against_brute_force::<Bvh2>(&scene(2, 300, 40), 20_000, 0.2);
}

#[test]
fn spheres_only_and_triangles_only_scenes() {
    check_against_brute_force::<Wide>(&scene(3, 0, 12), 5_000, 0.04);
    check_against_brute_force::<Wide>(&scene(4, 400, 0), 5_000, 0.2);
    // Fewer triangles than one leaf packet: the root holds a single leaf.
    check_against_brute_force::<Wide>(&scene(4, 3, 0), 2_000, 0.0);
    let empty = AccelWith::<Wide>::new(&SceneGeometry::default());
    let ray = Ray::new(Vec3::ZERO, Vec3::X, f32::INFINITY);
    assert!(empty.intersect(&ray).is_none() && !empty.occluded(&ray));
}

/// Rays leaving a hit point through `spawn_ray`, into either hemisphere, never hit
/// their own triangle again; on a sphere, only an inward ray hits it again, and then on
/// the far side of the chord.
#[test]
fn spawned_rays_do_not_rehit_their_surface() {
    let g = scene(5, 600, 6);
    let accel = AccelWith::<Wide>::new(&g);
    let mut s = SampleStream::for_sample(6, Stream::Aux, 0, 0, 0);
    let mut spawned = 0;
    for _ in 0..20_000 {
        let ray = Ray::new(point(&mut s, -1.3, 1.3), direction(&mut s), f32::INFINITY);
        let Some((hit, prim)) = accel.intersect_primitive(&ray) else { continue };
        for _ in 0..4 {
            let d = direction(&mut s);
            let next = spawn_ray(hit.p, hit.ng, d);
            spawned += 1;
            let Some((h2, p2)) = accel.intersect_primitive(&next) else { continue };
            if p2 != prim {
                continue;
            }
            match prim {
                PrimitiveRef::Triangle(i) => panic!("triangle {i} re-hit at t = {} from {:?}", h2.t, hit.p),
                PrimitiveRef::Sphere(i) => {
                    let sp = &g.spheres[i as usize];
                    let n_out = (hit.p - sp.center).normalize();
                    let cos = d.dot(n_out);
                    assert!(cos < 0.0, "sphere {i} re-hit by an outward ray");
                    // The far end of the chord from the (offset) origin, in f64.
                    let exact = brute_hits(&g, next.origin, next.dir, f32::INFINITY).into_iter().find(|h| h.prim == p2 && h.t > 0.0).expect("reference hit");
                    let chord = 2.0 * sp.radius as f64 * -cos as f64;
                    assert!(exact.t > 0.5 * chord, "reference is the far side");
                    assert!((h2.t as f64 - exact.t).abs() < 1e-4 * exact.t, "t {} vs {}", h2.t, exact.t);
                }
            }
        }
    }
    assert!(spawned > 20_000, "{spawned} spawned rays");
}

/// Degenerate and invalid input: nothing panics, nothing is hit.
#[test]
fn degenerate_input_is_harmless() {
    let mut g = scene(7, 50, 2);
    g.triangles.push(Triangle { p: [Vec3::ONE; 3], n: None, uv: None, material: 0, emitter: None });
    g.triangles.push(Triangle { p: [Vec3::ZERO, Vec3::X, Vec3::splat(f32::NAN)], n: None, uv: None, material: 0, emitter: None });
    g.spheres.push(Sphere { center: Vec3::ZERO, radius: 0.0, flip_normals: false, material: 0, emitter: None });
    let accel = AccelWith::<Wide>::new(&g);
    assert_eq!((accel.triangle_count(), accel.sphere_count()), (50, 2));
    for ray in [
        Ray::new(Vec3::ZERO, Vec3::ZERO, f32::INFINITY),
        Ray::new(Vec3::splat(f32::NAN), Vec3::X, f32::INFINITY),
        Ray::new(Vec3::ZERO, Vec3::new(f32::INFINITY, 0.0, 0.0), 1.0),
        Ray::new(Vec3::ZERO, Vec3::X, 0.0),
        Ray::new(Vec3::ZERO, Vec3::X, f32::NAN),
        Ray::new(Vec3::ZERO, Vec3::X, -1.0),
    ] {
        assert!(accel.intersect(&ray).is_none() && !accel.occluded(&ray), "{ray:?}");
    }
}

/// The built-in Cornell box seen through its camera. Its rectangles do not meet
/// exactly (their transforms round to ~1e-7 gaps: a corner vertex at x = -0.99999994 on
/// one wall, -1.0 on the next), so the pixel-centre rays along the image diagonals,
/// which aim exactly at the box's edges, can pass between two walls: every ray must
/// agree with brute force (hit the same primitive or miss in both), and a ray bounced
/// off a hit never re-hits the primitive it left.
#[test]
fn cornell_box_camera_rays_agree_with_brute_force() {
    let (scene, geometry, _) = ember_core::scene::builtin::cornell_box(128, 128).build().expect("built-in scene");
    let accel = AccelWith::<Wide>::new(&geometry);
    let mut s = SampleStream::for_sample(8, Stream::Aux, 0, 0, 0);
    let mut misses = 0;
    for y in 0..128 {
        for x in 0..128 {
            let ray = scene.camera.generate_ray(glam::Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
            let reference = brute_hits(&geometry, ray.origin, ray.dir, f32::INFINITY);
            let reference = reference.iter().find(|h| h.t > 0.0);
            let Some((hit, prim)) = accel.intersect_primitive(&ray) else {
                assert!(reference.is_none() || reference.unwrap().edge < 1e-5, "pixel ({x}, {y}) missed {reference:?}");
                misses += 1;
                continue;
            };
            if let Some(r) = reference.filter(|r| r.edge > 1e-5) {
                assert_eq!(prim, r.prim, "pixel ({x}, {y})");
            }
            for _ in 0..4 {
                let next = spawn_ray(hit.p, hit.ng, direction(&mut s));
                if let Some((h2, p2)) = accel.intersect_primitive(&next) {
                    assert_ne!(p2, prim, "bounce from pixel ({x}, {y}) re-hit its triangle at t = {}", h2.t);
                }
            }
        }
    }
    assert!(misses < 128, "{misses} pixels miss the room");
}

/// A closed box of flat, finely tessellated walls, shot from inside at points exactly on
/// its edges: no ray escapes. This pins the padding of the leaf boxes (`box_padding`):
/// obvhs's slab test misses a flat leaf box hit exactly on its rim by an ulp. With the
/// padding set to zero, 2 244 (BVH2) and 5 609 (CWBVH) of these 120 000 rays escaped.
#[test]
fn closed_box_does_not_leak_at_edges() {
    const H: f32 = 3.0;
    const K: usize = 16;
    let mut g = SceneGeometry::default();
    for axis in 0..3 {
        for side in [-H, H] {
            let at = |i: usize, j: usize| {
                let mut p = [0.0; 3];
                p[axis] = side;
                p[(axis + 1) % 3] = -H + 2.0 * H * i as f32 / K as f32;
                p[(axis + 2) % 3] = -H + 2.0 * H * j as f32 / K as f32;
                Vec3::from(p)
            };
            for i in 0..K {
                for j in 0..K {
                    let t = |p| Triangle { p, n: None, uv: None, material: 0, emitter: None };
                    g.triangles.push(t([at(i, j), at(i + 1, j), at(i + 1, j + 1)]));
                    g.triangles.push(t([at(i, j), at(i + 1, j + 1), at(i, j + 1)]));
                }
            }
        }
    }
    let bvh2 = AccelWith::<Bvh2>::new(&g);
    let cwbvh = AccelWith::<CwBvh>::new(&g);
    let bvh4 = AccelWith::<Wide>::new(&g);
    let mut s = SampleStream::for_sample(9, Stream::Aux, 0, 0, 0);
    let mut escaped = [0, 0, 0];
    for i in 0..120_000u32 {
        // A point on one of the 12 edges: two coordinates at ±H, the third free.
        let edge = i % 12;
        let free = (edge / 4) as usize;
        let mut target = [0.0f32; 3];
        target[free] = (2.0 * s.next_f32() - 1.0) * H;
        target[(free + 1) % 3] = if edge % 2 == 0 { H } else { -H };
        target[(free + 2) % 3] = if (edge / 2) % 2 == 0 { H } else { -H };
        let origin = point(&mut s, -2.5, 2.5);
        let ray = Ray::new(origin, Vec3::from(target) - origin, f32::INFINITY);
        escaped[0] += bvh2.intersect(&ray).is_none() as u32;
        escaped[1] += cwbvh.intersect(&ray).is_none() as u32;
        escaped[2] += bvh4.intersect(&ray).is_none() as u32;
    }
    assert_eq!(escaped, [0, 0, 0], "rays escaped the closed box (BVH2, CWBVH, BVH4)");
}

/// The renderer shares one structure between its threads.
#[test]
fn accel_is_sync_and_send() {
    fn shareable<T: Sync + Send>() {}
    shareable::<ember_host::accel::Accel>();
    shareable::<AccelWith<Bvh2>>();
}
