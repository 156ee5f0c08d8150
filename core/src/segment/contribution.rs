//! The contribution g_ρ(s̄) of an explicit segment path (eq. 4), factor by factor:
//!
//! W_ρ(s₁) G(s₁) · Π_{i<k} K(s_i, s_{i+1}) f_r(s_i, s_{i+1}) G(s_{i+1}) · L_e(s_k).
//!
//! Estimators never call this in their loops (they divide factor by factor as they
//! sample); it is the definition the tests compare them and a brute-force f64
//! evaluation with. G uses geometric normals and includes visibility; f_r is the BSDF of
//! y_i in its shading frame for the incoming direction of s_i and the outgoing direction
//! of s_{i+1}, which is the shift-invariant form of eq. (6) since only directions enter.
//! With the Dirac kernel a junction contributes its factor 1 only where x_{i+1} = y_i
//! exactly (the Dirac has no value elsewhere).

use super::{Kernel, Point, Segment};
use crate::bsdf::TransportMode;
use crate::geometry::{RayQuery, spawn_ray_to};
use crate::math::Vec2;
use crate::scene::Scene;
use crate::spectrum::Rgb;
use crate::transport::SurfacePoint;

/// G(s) = |n_x·ŝ| |n_y·ŝ| V(x, y) / |x − y|².
pub fn geometry_term<Q: RayQuery + ?Sized>(tracer: &Q, x: &Point, y: &crate::geometry::SurfaceHit) -> f32 {
    let d = y.p - x.p;
    let dist2 = d.length_squared();
    if !(dist2 > 0.0) {
        return 0.0;
    }
    let w = d / crate::math::sqrt(dist2);
    let g = x.cos(w) * y.ng.dot(w).abs() / dist2;
    if g == 0.0 || tracer.occluded(&spawn_ray_to(x.p, x.n, y.p, y.ng)) { 0.0 } else { g }
}

/// g_ρ(s̄) for the segment path `path` (s₁ first, x₁ the pinhole), and the film position
/// of the pixel ρ whose W it carries. `None` where W is zero (outside the frustum) or the
/// path is empty.
pub fn contribution<Q: RayQuery + ?Sized>(scene: &Scene, tracer: &Q, kernel: Kernel, path: &[Segment]) -> Option<(Vec2, Rgb)> {
    let first = path.first()?;
    let last = path.last()?;
    // W_ρ(s₁) G(s₁): the importance arriving at y₁ per unit projected area, times cos at y₁.
    // x₁ is the pinhole, or the lens point the path starts from.
    let cs = scene.camera.connect_from(first.x.p, first.y.p)?;
    let mut g = scene.camera.arriving_importance(&cs) * first.y.ng.dot(cs.wi).abs();
    if tracer.occluded(&spawn_ray_to(first.y.p, first.y.ng, cs.position, crate::math::Vec3::ZERO)) {
        return Some((cs.film, Rgb::ZERO));
    }
    let mut value = Rgb::splat(1.0);
    for pair in path.windows(2) {
        let (s, next) = (&pair[0], &pair[1]);
        let toward = (s.x.p - s.y.p).normalize_or_zero();
        // K(s_i, s_{i+1}).
        let k = match kernel {
            Kernel::Dirac => {
                if next.x.p != s.y.p {
                    return Some((cs.film, Rgb::ZERO));
                }
                1.0
            }
            Kernel::Disk { .. } => kernel.density(&s.y, toward, next.x.p, next.x.n).0,
        };
        // f_r(s_i, s_{i+1}) at y_i (eq. 6), without cosine.
        let sp = SurfacePoint::new(s.y, toward);
        let wi = next.dir();
        let f = sp.material(scene).eval(sp.frame.to_local(toward), sp.frame.to_local(wi), TransportMode::Radiance);
        value *= f;
        g *= k * geometry_term(tracer, &next.x, &next.y);
    }
    // L_e(s_k), emitted at y_k toward x_k.
    let le = match last.y.emitter {
        Some(id) => scene.lights[id as usize].radiance(last.y.p, last.y.ng, (last.x.p - last.y.p).normalize_or_zero()),
        None => Rgb::ZERO,
    };
    Some((cs.film, value * le * g))
}
