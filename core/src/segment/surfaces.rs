//! Uniform points over every surface of the scene, |𝓜| = Σ areas, triangles and analytic
//! spheres alike: the first vertex of the uniform and ray-cast segment samplers
//! (eq. 12–14). A primitive is chosen ∝ its area (alias table), then a point uniform on
//! it, so the density is 1/|𝓜| everywhere.

use alloc::vec::Vec;

use crate::alias::AliasTable;
use crate::geometry::SurfaceHit;
use crate::math::{Vec2, Vec3};
use crate::measure::AreaPdf;
use crate::shapes::SceneGeometry;
use crate::warp::{sample_uniform_sphere, sample_uniform_triangle};

/// Area-proportional choice of a primitive (triangles first, then spheres).
#[derive(Clone, Debug)]
pub struct SurfaceSampler {
    table: AliasTable,
    triangles: usize,
    /// |𝓜| in f64.
    area: f64,
}

/// Area of a triangle.
#[inline]
fn triangle_area(p: &[Vec3; 3]) -> f32 {
    0.5 * (p[1] - p[0]).cross(p[2] - p[0]).length()
}

impl SurfaceSampler {
    /// The sampler over `geometry`, or `None` if it has no area.
    pub fn new(geometry: &SceneGeometry) -> Option<Self> {
        let mut areas: Vec<f32> = geometry.triangles.iter().map(|t| triangle_area(&t.p)).collect();
        areas.extend(geometry.spheres.iter().map(|s| 4.0 * core::f32::consts::PI * s.radius * s.radius));
        let area: f64 = areas.iter().map(|&a| a as f64).sum();
        let table = AliasTable::new(&areas)?;
        (area > 0.0 && area.is_finite()).then_some(Self { table, triangles: geometry.triangles.len(), area })
    }

    /// |𝓜|, the total surface area.
    pub fn area(&self) -> f64 {
        self.area
    }

    /// Density of [`Self::sample`] per unit area: 1/|𝓜| on every surface.
    pub fn pdf(&self) -> AreaPdf {
        AreaPdf((1.0 / self.area) as f32)
    }

    /// A uniform point on the surfaces of `geometry` (the geometry this sampler was built
    /// from), as the hit a ray would report there (t = 0): the primitive's geometric
    /// normal by its winding (a flipped sphere's points inward), its shading normal, its
    /// material and emitter. `u_pick` chooses the primitive, `u` the point on it.
    pub fn sample(&self, geometry: &SceneGeometry, u_pick: f32, u: Vec2) -> Option<SurfaceHit> {
        let i = self.table.sample(u_pick).index;
        if i < self.triangles {
            let t = geometry.triangles.get(i)?;
            let b = sample_uniform_triangle(u);
            let (b0, b1) = (b.x, b.y);
            let b2 = 1.0 - b0 - b1;
            let p = t.p[0] * b0 + t.p[1] * b1 + t.p[2] * b2;
            let ng = (t.p[1] - t.p[0]).cross(t.p[2] - t.p[0]).normalize_or_zero();
            let ns = match t.n {
                Some(n) => {
                    let s = (n[0] * b0 + n[1] * b1 + n[2] * b2).normalize_or_zero();
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
            Some(SurfaceHit { t: 0.0, p, ng, ns, uv: t.texcoords(b1, b2), material: t.material, emitter: t.emitter })
        } else {
            let s = geometry.spheres.get(i - self.triangles)?;
            let d = sample_uniform_sphere(u);
            let n = if s.flip_normals { -d } else { d };
            Some(SurfaceHit {
                t: 0.0,
                p: s.center + d * s.radius,
                ng: n,
                ns: n,
                uv: crate::shapes::sphere_texcoords(d),
                material: s.material,
                emitter: s.emitter,
            })
        }
    }
}
