//! A brute-force ray tracer over [`SceneGeometry`]: every triangle and sphere is tested
//! for every ray. Slow but obviously correct; tests use it so estimator checks do not
//! depend on the host's BVH.

use ember_core::geometry::{Ray, RayQuery, SurfaceHit};
use ember_core::shapes::SceneGeometry;
use glam::Vec3;

/// Linear-scan ray queries.
#[derive(Debug, Clone)]
pub struct BruteForce {
    pub geometry: SceneGeometry,
}

impl BruteForce {
    pub fn new(geometry: SceneGeometry) -> Self {
        Self { geometry }
    }

    fn closest(&self, ray: &Ray, any: bool) -> Option<SurfaceHit> {
        let mut best: Option<SurfaceHit> = None;
        let mut t_max = ray.t_max;
        for tri in &self.geometry.triangles {
            if let Some((t, b1, b2)) = intersect_triangle(ray, tri.p, t_max) {
                t_max = t;
                let ng = (tri.p[1] - tri.p[0]).cross(tri.p[2] - tri.p[0]).normalize();
                let ns = match tri.n {
                    Some(n) => {
                        let s = (n[0] * (1.0 - b1 - b2) + n[1] * b1 + n[2] * b2).normalize_or_zero();
                        if s == Vec3::ZERO {
                            ng
                        } else if s.dot(ng) < 0.0 {
                            -s
                        } else {
                            s
                        }
                    }
                    None => ng,
                };
                best = Some(SurfaceHit { t, p: ray.at(t), ng, ns, uv: tri.texcoords(b1, b2), material: tri.material, emitter: tri.emitter });
                if any {
                    return best;
                }
            }
        }
        for s in &self.geometry.spheres {
            if let Some(t) = intersect_sphere(ray, s.center, s.radius, t_max) {
                t_max = t;
                let p = ray.at(t);
                let local = (p - s.center).normalize();
                let n = if s.flip_normals { -local } else { local };
                let uv = ember_core::shapes::sphere_texcoords(local);
                best = Some(SurfaceHit { t, p, ng: n, ns: n, uv, material: s.material, emitter: s.emitter });
                if any {
                    return best;
                }
            }
        }
        best
    }
}

impl RayQuery for BruteForce {
    fn intersect(&self, ray: &Ray) -> Option<SurfaceHit> {
        self.closest(ray, false)
    }
    fn occluded(&self, ray: &Ray) -> bool {
        self.closest(ray, true).is_some()
    }
}

/// Möller–Trumbore in f64 (precision is not what these tests measure).
fn intersect_triangle(ray: &Ray, p: [Vec3; 3], t_max: f32) -> Option<(f32, f32, f32)> {
    let (o, d) = (ray.origin.as_dvec3(), ray.dir.as_dvec3());
    let (p0, p1, p2) = (p[0].as_dvec3(), p[1].as_dvec3(), p[2].as_dvec3());
    let (e1, e2) = (p1 - p0, p2 - p0);
    let h = d.cross(e2);
    let det = e1.dot(h);
    if det == 0.0 {
        return None;
    }
    let inv = 1.0 / det;
    let s = o - p0;
    let b1 = s.dot(h) * inv;
    if !(0.0..=1.0).contains(&b1) {
        return None;
    }
    let q = s.cross(e1);
    let b2 = d.dot(q) * inv;
    if b2 < 0.0 || b1 + b2 > 1.0 {
        return None;
    }
    let t = e2.dot(q) * inv;
    (t > 0.0 && t < t_max as f64).then_some((t as f32, b1 as f32, b2 as f32))
}

fn intersect_sphere(ray: &Ray, c: Vec3, r: f32, t_max: f32) -> Option<f32> {
    let (o, d) = ((ray.origin - c).as_dvec3(), ray.dir.as_dvec3());
    let a = d.length_squared();
    let b = o.dot(d);
    // Discriminant in the numerically stable form (Ray Tracing Gems ch. 7).
    let f = o - d * (b / a);
    let disc = (r as f64).powi(2) - f.length_squared();
    if disc < 0.0 {
        return None;
    }
    let q = -b - b.signum() * (a * disc).sqrt();
    let (t0, t1) = (q / a, (o.length_squared() - (r as f64).powi(2)) / q);
    let (t0, t1) = if t0 <= t1 { (t0, t1) } else { (t1, t0) };
    [t0, t1].into_iter().find(|&t| t > 1e-6 * (1.0 + o.length()) / a.sqrt() && t < t_max as f64).map(|t| t as f32)
}
