//! The hosts' ray-query structure (the CLI's, the C library's and the browser's): a
//! hierarchy over the scene's triangles, exact analytic spheres beside it.
//!
//! # Triangles
//! One hierarchy over every triangle: by default our four-wide BVH ([`Wide`], module
//! `wide`: obvhs's PLOC build collapsed to four children per node and four triangles per
//! leaf, traversed with 4-lane SIMD). After the build the triangles are reordered by the
//! hierarchy's leaf order, so a hit's leaf slot indexes the vertex array directly.
//! Hot data (three `Vec3A` vertices, 48 bytes) and cold data (normals, material,
//! emitter, original index) live in separate arrays, so traversal touches only the
//! former. Triangles are intersected with the watertight test (module `triangle`; the
//! BVH4 runs the same arithmetic four lanes at a time, bit-identical per lane).
//! Degenerate triangles (zero area or non-finite vertices) cannot be hit and are dropped.
//! The hierarchy is built over leaf boxes grown by a few ulps of the scene's scale, as
//! obvhs's slab test is not conservative (see `hit::box_padding`: without it, rays aimed at
//! the edge where two walls meet escaped a closed box).
//!
//! # Which hierarchy: measured
//! `cargo bench -p ember-host --bench bvh` (host/benches/bvh.rs) builds obvhs's BVH2
//! and CWBVH and our BVH4 over a procedural scene of 131 084 triangles (a displaced
//! sphere tessellated into 256 × 256 quads, inside a closed box, seen from inside the
//! box) and traces 512² rays per set, one thread, through this very `RayQuery`
//! implementation (watertight test included), the structures taking turns and each
//! keeping its best of 7:
//!
//! | Mrays/s, 1 thread                     | BVH2 | CWBVH | BVH4 | BVH4 / CWBVH |
//! |---------------------------------------|------|-------|------|--------------|
//! | camera rays, closest hit              | 2.39 | 2.04  | 3.37 | 1.65         |
//! | camera hits → light, occlusion        | 1.94 | 2.73  | 3.21 | 1.18         |
//! | random origin and direction, closest  | 2.05 | 2.64  | 2.92 | 1.10         |
//! | random segments, occlusion            | 1.63 | 2.29  | 2.69 | 1.18         |
//!
//! Builds: 0.10–0.11 s each. Measured on a 2-core x86-64 VM (Xeon, AVX-512, 2 GHz) shared
//! with other work: absolute rates move by up to 2× from run to run, the ratios much
//! less. On the 36-triangle Cornell box the difference is larger: callgrind counts about
//! 1 240 instructions per closest-hit query with obvhs's CWBVH and 940 with the BVH4,
//! the hit record included (docs/performance.md). [`AccelWith`] keeps the obvhs variants for the benchmark and
//! the tests (the CWBVH native only: obvhs's `build_cwbvh` reads the clock).
//!
//! # Against Embree
//! With the cargo feature `embree`, module `embree` answers the same queries through
//! Embree 3.13 (robust scene, one ray or packets of 4/8/16), for comparison:
//! `host-cli/benches/embree.rs` traces PT's recorded rays of every suite scene and of a
//! million-triangle scene through both. On PT's single rays Embree was 0.68–1.05× our
//! speed on the suite scenes and 1.08× on the big one (docs/performance.md, "Our BVH4
//! against Embree 3.13"), so the renderer keeps ours.
//!
//! # On every target
//! Every hierarchy here is built by [`build_bvh2_without_clock`] (module `build`: obvhs's
//! `build_bvh2` step for step, without its `Instant`, which traps in the browser), and
//! the BVH4's lanes are glam's `Vec4` (SSE on x86-64, NEON on AArch64, `simd128` on
//! wasm32), so this module compiles for `wasm32-unknown-unknown` and the browser's module
//! (`host-wasm`) traces the CLI's hierarchy with the CLI's code: same boxes, same
//! build, same tests, same hits.
//!
//! # Spheres
//! Analytic spheres are intersected exactly, in f64 (module `sphere`). Scenes hold a handful
//! (the suite's largest has three), and one ray–sphere test costs about as much as one
//! ray–box test, so up to [`SPHERE_LIST_MAX`] spheres are simply tested in a list (a
//! hierarchy would add a box test per sphere and save nothing). Above that they get
//! their own BVH2 over their bounding boxes, so a scene of many spheres stays
//! logarithmic. Keeping them out of the triangle hierarchy keeps its leaf loop free of a
//! per-primitive type branch.
//!
//! # Queries
//! `intersect` traces the triangles first, then the spheres with `t_max` cut to the
//! triangle hit. `occluded` tests the (few, cheap) spheres first, then the triangles
//! with obvhs's any-hit early exit (`ray_traverse_miss`, which stops at the first hit).
//! A ray with a non-finite origin or direction, a zero direction, or a `t_max` that is
//! not positive hits nothing.

mod build;
#[cfg(feature = "embree")]
pub mod embree;
mod hit;
pub mod isa;
mod sphere;
mod triangle;
mod wide;

use glam::{Vec3, Vec3A};
use obvhs::BvhBuildParams;
use obvhs::aabb::Aabb;
use obvhs::bvh2::Bvh2;
#[cfg(not(target_arch = "wasm32"))]
use obvhs::cwbvh::CwBvh;
use obvhs::ray::{Ray as BvhRay, RayHit};

use ember_core::geometry::{LightId, MaterialId, Ray, RayQuery, SurfaceHit};
use ember_core::shapes::{SceneGeometry, Sphere};

pub use build::build_bvh2_without_clock;
pub use isa::{Isa, IsaError};
pub use triangle::WatertightRay;
pub use wide::Wide;

/// Up to this many spheres are tested in a list; more get a BVH2 of their own.
pub const SPHERE_LIST_MAX: usize = 8;

/// The ray-query structure the CLI renders with (our BVH4 over triangles; see the module
/// documentation for the measurement behind the choice).
pub type Accel = AccelWith<Wide>;

/// Which primitive of the [`SceneGeometry`] a hit landed on (indices into its
/// `triangles` / `spheres`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum PrimitiveRef {
    Triangle(u32),
    Sphere(u32),
}

/// A triangle hierarchy: how it is built and traversed. Triangles are passed in leaf
/// order (`primitive_indices`); hits name a leaf slot.
pub trait TriangleBvh: Send + Sync + Sized {
    /// Name for reports ("BVH2", "CWBVH", "BVH4").
    const NAME: &'static str;
    /// Build over the triangles and their (padded) bounding boxes (non-empty).
    fn build(tris: &[[Vec3A; 3]], boxes: &[Aabb]) -> Self;
    /// Leaf slot → index into the build input.
    fn primitive_indices(&self) -> &[u32];
    /// Closest hit in (0, ray.tmax): leaf slot, distance and barycentrics.
    fn closest(&self, tris: &[[Vec3A; 3]], ray: &BvhRay, wt: &WatertightRay) -> Option<(usize, f32, [f32; 3])>;
    /// True if anything lies in (0, ray.tmax); stops at the first hit.
    fn occluded(&self, tris: &[[Vec3A; 3]], ray: &BvhRay, wt: &WatertightRay) -> bool;
    /// Heap bytes of the hierarchy and what its leaves hold (0 where not counted).
    fn heap_bytes(&self) -> u64 {
        0
    }
}

/// What a ray-query structure holds on the heap, in bytes (`Vec` capacities).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct AccelBytes {
    /// What traversal reads: nodes and the leaves' triangle data.
    pub hierarchy: u64,
    /// The vertices the hit record reads (ours: a leaf-ordered copy; Embree's
    /// structure: the shared vertex and index arrays, which its traversal reads too).
    pub vertices: u64,
    /// Normals, texture coordinates, material, emitter and index per triangle.
    pub attributes: u64,
    /// The spheres and their boxes or hierarchy.
    pub spheres: u64,
}

impl AccelBytes {
    pub fn total(&self) -> u64 {
        self.hierarchy + self.vertices + self.attributes + self.spheres
    }
}

/// obvhs's hierarchies call back per triangle: the scalar watertight test.
fn closest_by_callback(
    traverse: impl FnOnce(&mut RayHit, &mut dyn FnMut(&BvhRay, usize) -> f32) -> bool,
    tris: &[[Vec3A; 3]],
    wt: &WatertightRay,
) -> Option<(usize, f32, [f32; 3])> {
    let mut hit = RayHit::none();
    // obvhs accepts a distance iff it is below the current t_max, exactly when `hit`
    // returns Some: the last barycentrics seen belong to the closest hit.
    let mut bary = [0.0; 3];
    let found = traverse(&mut hit, &mut |r, i| {
        let v = &tris[i];
        wt.hit(v[0], v[1], v[2], r.tmax).map_or(f32::INFINITY, |(t, b)| {
            bary = b;
            t
        })
    });
    found.then_some((hit.primitive_id as usize, hit.t, bary))
}

fn any_hit_callback(tris: &[[Vec3A; 3]], wt: &WatertightRay) -> impl FnMut(&BvhRay, usize) -> f32 {
    move |r, i| {
        let v = &tris[i];
        wt.hit(v[0], v[1], v[2], r.tmax).map_or(f32::INFINITY, |(t, _)| t)
    }
}

impl TriangleBvh for Bvh2 {
    const NAME: &'static str = "BVH2";
    fn build(_: &[[Vec3A; 3]], boxes: &[Aabb]) -> Self {
        build_bvh2_without_clock(boxes, BvhBuildParams::medium_build())
    }
    fn primitive_indices(&self) -> &[u32] {
        &self.primitive_indices
    }
    fn closest(&self, tris: &[[Vec3A; 3]], ray: &BvhRay, wt: &WatertightRay) -> Option<(usize, f32, [f32; 3])> {
        closest_by_callback(|hit, f| self.ray_traverse(*ray, hit, f), tris, wt)
    }
    fn occluded(&self, tris: &[[Vec3A; 3]], ray: &BvhRay, wt: &WatertightRay) -> bool {
        !self.ray_traverse_miss(*ray, any_hit_callback(tris, wt))
    }
}

/// Native only: obvhs's `build_cwbvh` reads the clock, which traps in the browser.
#[cfg(not(target_arch = "wasm32"))]
impl TriangleBvh for CwBvh {
    const NAME: &'static str = "CWBVH";
    fn build(_: &[[Vec3A; 3]], boxes: &[Aabb]) -> Self {
        obvhs::cwbvh::builder::build_cwbvh(boxes, BvhBuildParams::medium_build(), &mut std::time::Duration::default())
    }
    fn primitive_indices(&self) -> &[u32] {
        &self.primitive_indices
    }
    fn closest(&self, tris: &[[Vec3A; 3]], ray: &BvhRay, wt: &WatertightRay) -> Option<(usize, f32, [f32; 3])> {
        let ray = *ray;
        closest_by_callback(
            |hit, f| {
                let found = self.ray_traverse(stretched(&ray), hit, |r, i| f(&BvhRay { tmax: r.tmax * INV_T_STRETCH, ..ray }, i) * T_STRETCH);
                hit.t *= INV_T_STRETCH;
                found
            },
            tris,
            wt,
        )
    }
    fn occluded(&self, tris: &[[Vec3A; 3]], ray: &BvhRay, wt: &WatertightRay) -> bool {
        let ray = *ray;
        let mut f = any_hit_callback(tris, wt);
        !self.ray_traverse_miss(stretched(&ray), |r, i| f(&BvhRay { tmax: r.tmax * INV_T_STRETCH, ..ray }, i) * T_STRETCH)
    }
}

impl TriangleBvh for Wide {
    const NAME: &'static str = "BVH4";
    fn build(tris: &[[Vec3A; 3]], boxes: &[Aabb]) -> Self {
        Wide::build(tris, boxes)
    }
    fn primitive_indices(&self) -> &[u32] {
        self.order()
    }
    #[inline]
    fn closest(&self, _: &[[Vec3A; 3]], ray: &BvhRay, wt: &WatertightRay) -> Option<(usize, f32, [f32; 3])> {
        Wide::closest(self, ray, wt)
    }
    #[inline]
    fn occluded(&self, _: &[[Vec3A; 3]], ray: &BvhRay, wt: &WatertightRay) -> bool {
        Wide::occluded(self, ray, wt)
    }
    fn heap_bytes(&self) -> u64 {
        Wide::heap_bytes(self)
    }
}

/// obvhs's CWBVH node test culls every child whose box the ray leaves before t = 10⁻⁴
/// (an absolute constant in its `intersect_ray`, "ray.tmin?"): hits closer than 10⁻⁴
/// along the ray were lost. A ray leaving a concave corner (its origin offset off one
/// wall, within 10⁻⁴ of the other) escaped through the corner: light leaking into a closed
/// room, 229 of 230 escapes in 20 M bounces in window_env with its window covered, and a
/// bias growing as scenes shrink. The CWBVH is traversed with the direction divided by
/// 2²⁴ (t in units 2²⁴ times larger, exact: a power of two), which moves that cut to
/// 6·10⁻¹² of a unit; the closure and the caller keep the ray's own units.
#[cfg(not(target_arch = "wasm32"))]
const T_STRETCH: f32 = 16_777_216.0;
#[cfg(not(target_arch = "wasm32"))]
const INV_T_STRETCH: f32 = 1.0 / T_STRETCH;

#[cfg(not(target_arch = "wasm32"))]
#[inline]
fn stretched(ray: &BvhRay) -> BvhRay {
    // The inverse direction scaled, not recomputed: obvhs's `safe_inverse` clamps tiny
    // components, and the stretched direction's would all count as tiny.
    BvhRay {
        origin: ray.origin,
        direction: ray.direction * INV_T_STRETCH,
        inv_direction: ray.inv_direction * T_STRETCH,
        tmin: ray.tmin * T_STRETCH,
        tmax: ray.tmax * T_STRETCH,
    }
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
    original: u32,
}

/// Ray queries over a [`SceneGeometry`] with triangle hierarchy `B`.
pub struct AccelWith<B: TriangleBvh> {
    bvh: Option<B>,
    /// Vertices in leaf order.
    tris: Vec<[Vec3A; 3]>,
    attrs: Vec<TriangleAttributes>,
    /// Spheres (in BVH leaf order when `sphere_bvh` is set) and their original indices.
    spheres: Vec<Sphere>,
    /// Conservative boxes of the listed spheres: a ray that misses one skips the f64 test.
    sphere_boxes: Vec<sphere::SphereBox>,
    sphere_ids: Vec<u32>,
    sphere_bvh: Option<Bvh2>,
    /// The level the core's lane kernels run with on this machine ([`Isa::select_shading`]).
    shading: ember_core::math::simd::Level,
}

impl<B: TriangleBvh> core::fmt::Debug for AccelWith<B> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("AccelWith")
            .field("bvh", &B::NAME)
            .field("triangles", &self.tris.len())
            .field("spheres", &self.spheres.len())
            .field("sphere_bvh", &self.sphere_bvh.is_some())
            .finish()
    }
}

fn finite(v: Vec3) -> bool {
    v.is_finite()
}

/// Grow a box by `pad` on every side.
trait Padded {
    fn padded(self, pad: f32) -> Self;
}

impl Padded for Aabb {
    fn padded(self, pad: f32) -> Self {
        Aabb::new(self.min - Vec3A::splat(pad), self.max + Vec3A::splat(pad))
    }
}

impl AccelWith<Wide> {
    /// The instruction set the triangle queries run with (module `isa`): the default set
    /// ([`Isa::best`]) unless [`AccelWith::set_isa`] chose another (a scene without
    /// triangles reports that default).
    pub fn isa(&self) -> Isa {
        self.bvh.as_ref().map_or_else(Isa::best, Wide::isa)
    }

    /// Run the triangle queries with `isa`; refused if this machine does not offer it.
    /// Images do not depend on it (module `isa`).
    pub fn set_isa(&mut self, isa: Isa) -> Result<(), IsaError> {
        match &mut self.bvh {
            Some(bvh) => bvh.set_isa(isa),
            None => Isa::from_name(isa.name()).map(drop),
        }
    }
}

impl<B: TriangleBvh> AccelWith<B> {
    /// The level the core's lane kernels run with ([`Isa::select_shading`]; by default the
    /// widest set the machine offers): what a host puts in `RenderParams::simd`.
    pub fn shading_level(&self) -> ember_core::math::simd::Level {
        self.shading
    }

    /// Set [`Self::shading_level`] (images do not depend on it).
    pub fn set_shading_level(&mut self, level: ember_core::math::simd::Level) {
        self.shading = level;
    }
}

impl<B: TriangleBvh> AccelWith<B> {
    /// Build the structure; degenerate primitives (zero-area or non-finite triangles,
    /// spheres with a radius that is not positive and finite) are dropped.
    pub fn new(geometry: &SceneGeometry) -> Self {
        // Keep the triangles that can be hit.
        let kept: Vec<u32> = (0..geometry.triangles.len() as u32).filter(|&i| hit::can_be_hit(&geometry.triangles[i as usize])).collect();
        let input: Vec<[Vec3A; 3]> = kept.iter().map(|&i| geometry.triangles[i as usize].p.map(Vec3A::from)).collect();
        let pad = hit::box_padding(geometry);
        let boxes: Vec<Aabb> = input.iter().map(|v| Aabb::from_points(v).padded(pad)).collect();
        let (bvh, tris, attrs) = if input.is_empty() {
            (None, Vec::new(), Vec::new())
        } else {
            let bvh = B::build(&input, &boxes);
            // Reorder by leaf slot once, dropping the indirection from traversal.
            let order = bvh.primitive_indices();
            let tris = order.iter().map(|&k| input[k as usize]);
            let attrs = order.iter().map(|&k| {
                let original = kept[k as usize];
                let t = &geometry.triangles[original as usize];
                let ng = hit::geometric_normal(&input[k as usize]);
                TriangleAttributes { ng, normals: t.n, texcoords: t.uv, material: t.material, emitter: t.emitter, original }
            });
            let (tris, attrs) = (tris.collect(), attrs.collect());
            (Some(bvh), tris, attrs)
        };

        // Spheres: a list, or a BVH2 over their boxes when there are many.
        let sphere_ids: Vec<u32> = (0..geometry.spheres.len() as u32)
            .filter(|&i| {
                let s = &geometry.spheres[i as usize];
                finite(s.center) && s.radius.is_finite() && s.radius > 0.0
            })
            .collect();
        let (sphere_bvh, sphere_ids) = if sphere_ids.len() > SPHERE_LIST_MAX {
            let boxes: Vec<Aabb> = sphere_ids
                .iter()
                .map(|&i| {
                    let s = &geometry.spheres[i as usize];
                    let (c, r) = (Vec3A::from(s.center), Vec3A::splat(s.radius));
                    Aabb::new(c - r, c + r).padded(pad)
                })
                .collect();
            let bvh = build_bvh2_without_clock(&boxes, BvhBuildParams::medium_build());
            let ids = bvh.primitive_indices.iter().map(|&k| sphere_ids[k as usize]).collect();
            (Some(bvh), ids)
        } else {
            (None, sphere_ids)
        };
        let spheres: Vec<Sphere> = sphere_ids.iter().map(|&i| geometry.spheres[i as usize]).collect();
        let sphere_boxes = spheres.iter().map(sphere::SphereBox::new).collect();
        let shading = Isa::best_for_shading().shading_level();
        Self { bvh, tris, attrs, spheres, sphere_boxes, sphere_ids, sphere_bvh, shading }
    }

    /// Number of triangles kept (degenerate ones dropped).
    pub fn triangle_count(&self) -> usize {
        self.tris.len()
    }

    /// Number of spheres kept.
    pub fn sphere_count(&self) -> usize {
        self.spheres.len()
    }

    /// What the structure holds on the heap.
    pub fn bytes(&self) -> AccelBytes {
        let cap = |n: usize, size: usize| (n * size) as u64;
        let spheres = cap(self.spheres.capacity(), size_of::<Sphere>())
            + cap(self.sphere_boxes.capacity(), size_of::<sphere::SphereBox>())
            + cap(self.sphere_ids.capacity(), 4)
            + self
                .sphere_bvh
                .as_ref()
                .map_or(0, |b| cap(b.nodes.capacity(), size_of::<obvhs::bvh2::node::Bvh2Node>()) + cap(b.primitive_indices.capacity(), 4));
        AccelBytes {
            hierarchy: self.bvh.as_ref().map_or(0, B::heap_bytes),
            vertices: cap(self.tris.capacity(), size_of::<[Vec3A; 3]>()),
            attributes: cap(self.attrs.capacity(), size_of::<TriangleAttributes>()),
            spheres,
        }
    }

    /// Feed every value of the geometry the queries see (vertices, shading normals,
    /// materials, emitters, original indices, spheres) to `h` as raw bits, in leaf order
    /// (the build is deterministic): the geometry part of a scene's content hash, without
    /// formatting a float.
    pub fn hash_geometry(&self, h: &mut impl std::hash::Hasher) {
        let bits = |h: &mut dyn std::hash::Hasher, v: Vec3| [v.x, v.y, v.z].iter().for_each(|c| h.write_u32(c.to_bits()));
        h.write_usize(self.tris.len());
        for (t, a) in self.tris.iter().zip(&self.attrs) {
            t.iter().for_each(|&p| bits(h, p.into()));
            match a.normals {
                Some(n) => n.iter().for_each(|&v| bits(h, v)),
                None => h.write_u8(0),
            }
            match a.texcoords {
                Some(uv) => uv.iter().for_each(|v| {
                    h.write_u32(v.x.to_bits());
                    h.write_u32(v.y.to_bits());
                }),
                None => h.write_u8(0),
            }
            h.write_u32(a.material);
            h.write_u32(a.emitter.map_or(u32::MAX, |e| e));
            h.write_u32(a.original);
        }
        h.write_usize(self.spheres.len());
        for (s, &id) in self.spheres.iter().zip(&self.sphere_ids) {
            bits(h, s.center);
            h.write_u32(s.radius.to_bits());
            h.write_u8(s.flip_normals as u8);
            h.write_u32(s.material);
            h.write_u32(s.emitter.map_or(u32::MAX, |e| e));
            h.write_u32(id);
        }
    }

    /// Closest hit and the primitive it belongs to.
    pub fn intersect_primitive(&self, ray: &Ray) -> Option<(SurfaceHit, PrimitiveRef)> {
        let q = Query::new(ray)?;
        // Trace the triangles.
        let mut best: Option<(f32, Candidate)> = None;
        if let Some(bvh) = &self.bvh {
            let wt = WatertightRay::new(q.bvh_ray.origin, q.bvh_ray.direction);
            if let Some((slot, t, bary)) = bvh.closest(&self.tris, &q.bvh_ray, &wt) {
                best = Some((t, Candidate::Triangle(slot, bary)));
            }
        }
        // Then the spheres, closer than the triangle hit.
        let t_max = best.map_or(ray.t_max, |(t, _)| t);
        let sphere = if self.spheres.is_empty() { None } else { self.closest_sphere(ray, &q, t_max) };
        if let Some((t, i)) = sphere {
            best = Some((t, Candidate::Sphere(i)));
        }
        let (t, which) = best?;
        Some(match which {
            Candidate::Triangle(slot, b) => (self.triangle_hit(slot, t, b), PrimitiveRef::Triangle(self.attrs[slot].original)),
            Candidate::Sphere(i) => {
                let s = &self.spheres[i];
                let (p, ng, uv) = sphere::surface(s, ray.origin, ray.dir, t);
                let hit = SurfaceHit { t, p, ng, ns: ng, uv, material: s.material, emitter: s.emitter };
                (hit, PrimitiveRef::Sphere(self.sphere_ids[i]))
            }
        })
    }

    /// Closest sphere hit in (0, t_max): distance and index into `self.spheres`.
    #[inline]
    fn closest_sphere(&self, ray: &Ray, q: &Query, t_max: f32) -> Option<(f32, usize)> {
        if let Some(bvh) = &self.sphere_bvh {
            let mut hit = RayHit::none();
            let mut r = q.bvh_ray;
            r.tmax = t_max;
            let found = bvh.ray_traverse(r, &mut hit, |r, i| sphere::intersect(&self.spheres[i], ray.origin, ray.dir, r.tmax).unwrap_or(f32::INFINITY));
            return found.then_some((hit.t, hit.primitive_id as usize));
        }
        let mut best = None;
        let mut t_max = t_max;
        for (i, (s, b)) in self.spheres.iter().zip(&self.sphere_boxes).enumerate() {
            if !b.may_hit(&q.bvh_ray, t_max) {
                continue;
            }
            if let Some(t) = sphere::intersect(s, ray.origin, ray.dir, t_max) {
                t_max = t;
                best = Some((t, i));
            }
        }
        best
    }

    /// The full record of a hit on the triangle in leaf slot `slot` at distance `t` with
    /// barycentrics `b`.
    fn triangle_hit(&self, slot: usize, t: f32, b: [f32; 3]) -> SurfaceHit {
        let a = &self.attrs[slot];
        hit::surface_hit(&self.tris[slot], a.ng, a.normals, a.texcoords, a.material, a.emitter, t, b)
    }
}

#[derive(Clone, Copy)]
enum Candidate {
    Triangle(usize, [f32; 3]),
    Sphere(usize),
}

/// A validated query ray in obvhs's form.
struct Query {
    bvh_ray: BvhRay,
}

impl Query {
    #[inline]
    fn new(ray: &Ray) -> Option<Self> {
        let (o, d) = (Vec3A::from(ray.origin), Vec3A::from(ray.dir));
        let ok = o.is_finite() && d.is_finite() && d != Vec3A::ZERO && ray.t_max > 0.0;
        ok.then(|| {
            let d = safe_direction(d);
            // The exact inverse: obvhs's `BvhRay::new` clamps components below f32::EPSILON,
            // which shortens the slabs of near-axis rays; here none is below 1e-30.
            Self { bvh_ray: BvhRay { origin: o, direction: d, inv_direction: Vec3A::ONE / d, tmin: 0.0, tmax: ray.t_max } }
        })
    }
}

/// The direction with every component of magnitude below 1e-30 (zero included) replaced
/// by ±1e-30 (its sign kept), as Embree's `rcp_safe` does, so its inverse is finite.
/// obvhs's traversal divides by the direction: with a zero component the node tests of
/// the compressed-wide BVH missed triangles the ray crosses. Seen on the segment kernel's
/// projection rays, which run along surface normals: on the built-in Cornell box's short
/// block, whose front face's normal has y = 0 exactly, every one missed (photon
/// filtering's gather read 0 there). The change of direction, 1e-30 against a unit
/// vector, is far below f32 resolution; larger components keep their bits.
#[inline]
fn safe_direction(d: Vec3A) -> Vec3A {
    d.abs().max(Vec3A::splat(1e-30)).copysign(d)
}

impl<B: TriangleBvh> RayQuery for AccelWith<B> {
    fn intersect(&self, ray: &Ray) -> Option<SurfaceHit> {
        self.intersect_primitive(ray).map(|(h, _)| h)
    }

    fn occluded(&self, ray: &Ray) -> bool {
        let Some(q) = Query::new(ray) else { return false };
        // Spheres first: few and cheap.
        if let Some(bvh) = &self.sphere_bvh {
            let missed = bvh.ray_traverse_miss(q.bvh_ray, |r, i| sphere::intersect(&self.spheres[i], ray.origin, ray.dir, r.tmax).unwrap_or(f32::INFINITY));
            if !missed {
                return true;
            }
        } else if self
            .spheres
            .iter()
            .zip(&self.sphere_boxes)
            .any(|(s, b)| b.may_hit(&q.bvh_ray, ray.t_max) && sphere::intersect(s, ray.origin, ray.dir, ray.t_max).is_some())
        {
            return true;
        }
        // Then the triangles, stopping at the first hit.
        let Some(bvh) = &self.bvh else { return false };
        let wt = WatertightRay::new(q.bvh_ray.origin, q.bvh_ray.direction);
        bvh.occluded(&self.tris, &q.bvh_ray, &wt)
    }
}
