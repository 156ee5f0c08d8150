//! The browser's ray-query structure: an obvhs BVH2 over the scene's triangles, built
//! without obvhs's convenience helpers, and the analytic spheres in a list beside it.
//!
//! # Why BVH2, and why not `build_bvh2`
//! obvhs compiles for `wasm32-unknown-unknown`, but its build helpers
//! (`build_bvh2`, `build_cwbvh`, `…_from_tris`) time themselves with
//! `std::time::Instant::now()`, which traps in the browser ("time not implemented on
//! this platform"). [`build_bvh2_without_clock`] runs the same steps those helpers run
//! (PLOC build, reinsertion, leaf collapse, reinsertion again, with
//! `BvhBuildParams::medium_build`) and no clock. The CLI traverses a CWBVH, whose fast
//! node test is x86-only (about 40 % of native on wasm, see
//! `../shared/docs/ecosystem-notes.md`); BVH2's traversal vectorises with `simd128`
//! (enabled for this target in `.cargo/config.toml`) and runs near native. The layout
//! differs between hosts; the hits do not (same watertight test, below), so the images
//! agree to rounding (docs/wasm.md).
//!
//! # Same primitives tests as the CLI
//! The watertight triangle test and the exact f64 sphere test are the CLI's own source
//! files (`host/src/accel/{triangle,sphere}.rs`), compiled here through `#[path]`:
//! one implementation, so a closest hit is the same bit pattern on both hosts. Leaf
//! boxes are padded by the same few ulps of the scene's scale (obvhs's slab test is not
//! conservative; see `box_padding` in the CLI's `accel/hit.rs`).
//!
//! # Spheres
//! The built-in scenes hold at most a few spheres, so they are tested in a list,
//! triangles first with `t_max` cut to the triangle hit (closest) and spheres first
//! (occlusion), as the CLI does for up to 8 spheres.

#[path = "../../host/src/accel/hit.rs"]
mod hit;
#[path = "../../host/src/accel/sphere.rs"]
mod sphere;
#[path = "../../host/src/accel/triangle.rs"]
mod triangle;

use glam::{Vec3, Vec3A};
use obvhs::BvhBuildParams;
use obvhs::aabb::Aabb;
use obvhs::bvh2::Bvh2;
use obvhs::bvh2::leaf_collapser::collapse;
use obvhs::bvh2::reinsertion::ReinsertionOptimizer;
use obvhs::ploc::PlocBuilder;
use obvhs::ray::{Ray as BvhRay, RayHit};

use ember_core::geometry::{LightId, MaterialId, Ray, RayQuery, SurfaceHit};
use ember_core::shapes::{SceneGeometry, Sphere};

use triangle::WatertightRay;

/// obvhs's `build_bvh2` with the same parameters and steps, minus its `Instant` timing.
pub fn build_bvh2_without_clock(boxes: &[Aabb]) -> Bvh2 {
    let config = BvhBuildParams::medium_build();
    let indices = (0..boxes.len() as u32).collect();
    let mut bvh =
        PlocBuilder::with_capacity(boxes.len()).build(config.ploc_search_distance, boxes, indices, config.sort_precision, config.search_depth_threshold);
    let mut reinsertion = ReinsertionOptimizer::default();
    reinsertion.run(&mut bvh, config.reinsertion_batch_ratio, None);
    collapse(&mut bvh, config.max_prims_per_leaf.clamp(1, 255), config.collapse_traversal_cost);
    let second_ratio = config.reinsertion_batch_ratio * config.post_collapse_reinsertion_batch_ratio_multiplier;
    reinsertion.run(&mut bvh, second_ratio, None);
    bvh
}

/// What a hit needs beyond the vertices (kept apart so traversal stays in cache).
#[derive(Clone, Copy, Debug)]
struct TriangleAttributes {
    /// Unit geometric normal.
    ng: Vec3,
    normals: Option<[Vec3; 3]>,
    texcoords: Option<[glam::Vec2; 3]>,
    material: MaterialId,
    emitter: Option<LightId>,
}

/// Ray queries over a [`SceneGeometry`]: BVH2 over triangles, spheres in a list.
pub struct WasmAccel {
    bvh: Option<Bvh2>,
    /// Vertices in leaf order.
    tris: Vec<[Vec3A; 3]>,
    attrs: Vec<TriangleAttributes>,
    spheres: Vec<Sphere>,
}

impl core::fmt::Debug for WasmAccel {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("WasmAccel").field("triangles", &self.tris.len()).field("spheres", &self.spheres.len()).finish()
    }
}

impl WasmAccel {
    /// Build; degenerate triangles and spheres (zero area, non-finite) are dropped.
    pub fn new(geometry: &SceneGeometry) -> Self {
        let kept: Vec<usize> = (0..geometry.triangles.len()).filter(|&i| hit::can_be_hit(&geometry.triangles[i])).collect();
        let input: Vec<[Vec3A; 3]> = kept.iter().map(|&i| geometry.triangles[i].p.map(Vec3A::from)).collect();
        let pad = hit::box_padding(geometry);
        let (bvh, tris, attrs) = if input.is_empty() {
            (None, Vec::new(), Vec::new())
        } else {
            let boxes: Vec<Aabb> = input
                .iter()
                .map(|v| {
                    let b = Aabb::from_points(v);
                    Aabb::new(b.min - Vec3A::splat(pad), b.max + Vec3A::splat(pad))
                })
                .collect();
            let bvh = build_bvh2_without_clock(&boxes);
            // Reorder by leaf slot once, dropping the indirection from traversal.
            let tris = bvh.primitive_indices.iter().map(|&k| input[k as usize]).collect();
            let attrs = bvh
                .primitive_indices
                .iter()
                .map(|&k| {
                    let t = &geometry.triangles[kept[k as usize]];
                    let ng = hit::geometric_normal(&input[k as usize]);
                    TriangleAttributes { ng, normals: t.n, texcoords: t.uv, material: t.material, emitter: t.emitter }
                })
                .collect();
            (Some(bvh), tris, attrs)
        };
        let spheres = geometry.spheres.iter().filter(|s| s.center.is_finite() && s.radius.is_finite() && s.radius > 0.0).copied().collect();
        Self { bvh, tris, attrs, spheres }
    }

    /// Number of triangles kept.
    pub fn triangle_count(&self) -> usize {
        self.tris.len()
    }

    fn triangle_hit(&self, slot: usize, t: f32, b: [f32; 3]) -> SurfaceHit {
        let a = &self.attrs[slot];
        hit::surface_hit(&self.tris[slot], a.ng, a.normals, a.texcoords, a.material, a.emitter, t, b)
    }
}

/// A ray obvhs can take, or `None` for rays that hit nothing by definition.
fn query(ray: &Ray) -> Option<BvhRay> {
    let ok = ray.origin.is_finite() && ray.dir.is_finite() && ray.dir != Vec3::ZERO && ray.t_max > 0.0;
    ok.then(|| BvhRay::new(ray.origin.into(), ray.dir.into(), 0.0, ray.t_max))
}

impl RayQuery for WasmAccel {
    fn intersect(&self, ray: &Ray) -> Option<SurfaceHit> {
        let q = query(ray)?;
        let mut best: Option<SurfaceHit> = None;
        if let Some(bvh) = &self.bvh {
            let wt = WatertightRay::new(q.origin, q.direction);
            let mut hit = RayHit::none();
            // obvhs accepts a distance iff it is below the current t_max, exactly when
            // the closure returns a finite value: the last barycentrics are the closest's.
            let mut bary = [0.0; 3];
            if bvh.ray_traverse(q, &mut hit, |r, i| {
                let v = &self.tris[i];
                wt.hit(v[0], v[1], v[2], r.tmax).map_or(f32::INFINITY, |(t, b)| {
                    bary = b;
                    t
                })
            }) {
                best = Some(self.triangle_hit(hit.primitive_id as usize, hit.t, bary));
            }
        }
        let mut t_max = best.map_or(ray.t_max, |h| h.t);
        for s in &self.spheres {
            if let Some(t) = sphere::intersect(s, ray.origin, ray.dir, t_max) {
                t_max = t;
                let (p, ng, uv) = sphere::surface(s, ray.origin, ray.dir, t);
                best = Some(SurfaceHit { t, p, ng, ns: ng, uv, material: s.material, emitter: s.emitter });
            }
        }
        best
    }

    fn occluded(&self, ray: &Ray) -> bool {
        let Some(q) = query(ray) else { return false };
        if self.spheres.iter().any(|s| sphere::intersect(s, ray.origin, ray.dir, ray.t_max).is_some()) {
            return true;
        }
        let Some(bvh) = &self.bvh else { return false };
        let wt = WatertightRay::new(q.origin, q.direction);
        !bvh.ray_traverse_miss(q, |r, i| {
            let v = &self.tris[i];
            wt.hit(v[0], v[1], v[2], r.tmax).map_or(f32::INFINITY, |(t, _)| t)
        })
    }
}
