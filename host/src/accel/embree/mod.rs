//! Ray queries through Embree 3.13 (Intel's kernels, the ones Mitsuba 3 calls), behind
//! the cargo feature `embree`: the same [`RayQuery`] answers as [`super::Accel`], for
//! comparing the two and for rendering with either.
//!
//! # What it builds
//! The triangles our own structure keeps (the same `hit::can_be_hit` filter), as one
//! Embree triangle geometry over shared buffers: the vertices, deduplicated by their
//! bits (a closed mesh has about half a vertex per triangle, so 12 bytes of vertex and 12
//! of index per triangle instead of our 48 of leaf-ordered vertices), and one index
//! triple per kept triangle. Embree's primitive id is the index into the kept list,
//! which also indexes the hit attributes (the same [`super::TriangleAttributes`] our
//! structure keeps, in input order here). The hit record is built by `hit::surface_hit`
//! from Embree's distance and barycentrics (u, v of vertices 1 and 2): the same
//! function, normals and attributes as ours, so a hit on the same triangle at the same t
//! is the same record.
//!
//! # Settings, and why
//! - `RTC_SCENE_FLAG_ROBUST`: Embree's conservative node tests and its full-precision
//!   triangle test, documented as what keeps rays from slipping between neighbouring
//!   triangles. Our closed-room tests (`host-cli/tests/closed_room.rs`) count rays that
//!   escape a closed box through its edges; a leak there is a visible bias, so the
//!   comparison is with the robust mode. (The benchmark can also build without it.)
//! - Build quality medium (Embree's default, as obvhs's `medium_build` is ours).
//! - Semantics: ours accept t in (0, t_max). Embree accepts t in [tnear, tfar], both
//!   ends included, so the ray goes in with tnear the smallest positive normal float and
//!   tfar the float below t_max (∞ becomes `f32::MAX`).
//! - Rays ours refuse (a non-finite origin or direction, a zero direction, t_max not
//!   positive) hit nothing here either, before Embree sees them; a zero component of
//!   a valid direction is Embree's to handle (its `rcp_safe`, which our
//!   `safe_direction` copies).
//!
//! # Spheres
//! Embree would need a user geometry (a callback per sphere) for our exact f64 spheres;
//! instead the spheres stay on our code path: an `AccelWith<Wide>` over the spheres
//! alone, queried after Embree with t_max cut to the triangle hit (closest) or before
//! it (occlusion), exactly as our structure orders them. Its sphere ids are the
//! scene's, as ours are. (Only a scene of more than eight spheres, which gets a sphere
//! BVH2, pads that BVH's boxes by the spheres' scale rather than the whole scene's.)
//!
//! # Packets
//! [`EmbreeAccel::intersect_packets_of`] and [`EmbreeAccel::occluded_packets_of`] answer a
//! slice of rays one at a time ([`Lanes::One`]) or in consecutive groups of 4, 8 or 16
//! through `rtcIntersect4/8/16` / `rtcOccluded4/8/16`, lanes of refused rays masked off;
//! the `coherent` hint is Embree's context flag (Mitsuba sets it for camera rays only).
//! The core's batch queries (`RayQuery::intersect_batch`, `occluded_batch`) go 16 at a
//! time, and its lane loop then keeps 16 paths in flight (`batch_width`).
//!
//! The `unsafe` calls are all in `ffi` (the crate's one unsafe module).

mod ffi;

use std::collections::HashMap;

use ember_core::geometry::{Ray, RayBatch, RayQuery, SurfaceHit};
use ember_core::shapes::SceneGeometry;
use glam::{Vec3, Vec3A};

pub use ffi::{BuildOptions, DeviceInfo, EmbreeError};
use ffi::{EmbreeScene, INVALID_ID, Ray1, RayHit1, RayHitN, RayOnlyN};

use super::{AccelBytes, AccelWith, PrimitiveRef, TriangleAttributes, Wide, hit};

/// How many rays go to Embree per call.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Lanes {
    /// `rtcIntersect1` / `rtcOccluded1`.
    One,
    Four,
    Eight,
    Sixteen,
}

impl Lanes {
    pub const ALL: [Lanes; 4] = [Lanes::One, Lanes::Four, Lanes::Eight, Lanes::Sixteen];

    /// Rays per call.
    pub fn width(self) -> usize {
        match self {
            Lanes::One => 1,
            Lanes::Four => 4,
            Lanes::Eight => 8,
            Lanes::Sixteen => 16,
        }
    }
}

/// A triangle hit as Embree reports it: primitive id, distance, barycentrics u, v.
type TriangleHit = (u32, f32, f32, f32);

/// Ray queries over a [`SceneGeometry`]: triangles through Embree, spheres through ours.
pub struct EmbreeAccel {
    /// `None` when no triangle can be hit.
    /// It also holds the vertex and index arrays it reads, which the hit record reads too.
    embree: Option<EmbreeScene>,
    /// Per kept triangle (Embree's primitive id indexes this).
    attrs: Vec<TriangleAttributes>,
    /// The spheres alone, on our code path.
    spheres: AccelWith<Wide>,
}

impl core::fmt::Debug for EmbreeAccel {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("EmbreeAccel").field("triangles", &self.attrs.len()).field("spheres", &self.spheres).finish()
    }
}

impl EmbreeAccel {
    /// Build with the default options (robust, Embree's default thread count).
    pub fn new(geometry: &SceneGeometry) -> Result<Self, EmbreeError> {
        Self::with_options(geometry, BuildOptions::default())
    }

    /// Build; degenerate primitives are dropped as [`super::Accel::new`] drops them.
    pub fn with_options(geometry: &SceneGeometry, options: BuildOptions) -> Result<Self, EmbreeError> {
        // Keep the triangles that can be hit; share their vertices by bits.
        let mut ids: HashMap<[u32; 3], u32> = HashMap::new();
        let (mut vertices, mut indices, mut attrs) = (Vec::new(), Vec::new(), Vec::new());
        for (original, t) in geometry.triangles.iter().enumerate() {
            if !hit::can_be_hit(t) {
                continue;
            }
            let index = t.p.map(|p| {
                *ids.entry(p.to_array().map(f32::to_bits)).or_insert_with(|| {
                    vertices.push(p.to_array());
                    vertices.len() as u32 - 1
                })
            });
            indices.push(index);
            let ng = hit::geometric_normal(&t.p.map(Vec3A::from));
            attrs.push(TriangleAttributes { ng, normals: t.n, texcoords: t.uv, material: t.material, emitter: t.emitter, original: original as u32 });
        }
        // Hold what is used (the buffers live as long as the scene).
        vertices.shrink_to_fit();
        indices.shrink_to_fit();
        attrs.shrink_to_fit();
        let embree = if indices.is_empty() { None } else { Some(EmbreeScene::new(vertices, indices, options)?) };
        let spheres = AccelWith::<Wide>::new(&SceneGeometry { triangles: Vec::new(), spheres: geometry.spheres.clone() });
        Ok(Self { embree, attrs, spheres })
    }

    /// Number of triangles kept (degenerate ones dropped).
    pub fn triangle_count(&self) -> usize {
        self.attrs.len()
    }

    /// Number of spheres kept.
    pub fn sphere_count(&self) -> usize {
        self.spheres.sphere_count()
    }

    /// The device's version and native packet widths (`None` without triangles).
    pub fn device_info(&self) -> Option<DeviceInfo> {
        self.embree.as_ref().map(EmbreeScene::info)
    }

    /// What the structure holds: Embree's own allocations (its hierarchy and leaf data,
    /// by its memory monitor), the vertex and index arrays (which Embree and the hit
    /// record both read), the hit attributes, the spheres; and the most Embree held at
    /// once while building.
    pub fn bytes(&self) -> (AccelBytes, u64) {
        let (now, peak) = self.embree.as_ref().map_or((0, 0), EmbreeScene::embree_bytes);
        let vertices = self.embree.as_ref().map_or(0, EmbreeScene::buffer_bytes);
        let attributes = (self.attrs.capacity() * size_of::<TriangleAttributes>()) as u64;
        (AccelBytes { hierarchy: now, vertices, attributes, spheres: self.spheres.bytes().spheres }, peak)
    }

    /// Closest hit and the primitive it belongs to.
    pub fn intersect_primitive(&self, ray: &Ray) -> Option<(SurfaceHit, PrimitiveRef)> {
        let embree_ray = to_embree(ray)?;
        let triangle = self.embree.as_ref().and_then(|e| {
            let mut rh = RayHit1 { ray: embree_ray, hit: ffi::Hit1 { geom_id: INVALID_ID, ..Default::default() } };
            e.intersect1(&mut rh, false);
            (rh.hit.geom_id != INVALID_ID).then_some((rh.hit.prim_id, rh.ray.tfar, rh.hit.u, rh.hit.v))
        });
        self.finish_closest(ray, triangle)
    }

    /// The closest hit given the triangle hit Embree found: the spheres closer than it,
    /// else its record.
    #[inline]
    fn finish_closest(&self, ray: &Ray, triangle: Option<TriangleHit>) -> Option<(SurfaceHit, PrimitiveRef)> {
        // Then the spheres, closer than the triangle hit.
        if self.spheres.sphere_count() > 0 {
            let t_max = triangle.map_or(ray.t_max, |(_, t, _, _)| t);
            if let Some(hit) = self.spheres.intersect_primitive(&Ray { t_max, ..*ray }) {
                return Some(hit);
            }
        }
        let (prim, t, u, v) = triangle?;
        let (e, a) = (self.embree.as_ref()?, &self.attrs[prim as usize]);
        let p = e.indices()[prim as usize].map(|i| Vec3A::from(e.vertices()[i as usize]));
        let hit = hit::surface_hit(&p, a.ng, a.normals, a.texcoords, a.material, a.emitter, t, [1.0 - u - v, u, v]);
        Some((hit, PrimitiveRef::Triangle(a.original)))
    }

    /// Closest hits of `rays` into `out` (same length), `lanes` rays per Embree call.
    pub fn intersect_packets_of(&self, rays: &[Ray], lanes: Lanes, coherent: bool, out: &mut [Option<(SurfaceHit, PrimitiveRef)>]) {
        assert_eq!(rays.len(), out.len(), "one answer per ray");
        match lanes {
            Lanes::One => {
                for (ray, o) in rays.iter().zip(out) {
                    *o = match (to_embree(ray), &self.embree) {
                        (Some(r), Some(e)) => {
                            let mut rh = RayHit1 { ray: r, hit: ffi::Hit1 { geom_id: INVALID_ID, ..Default::default() } };
                            e.intersect1(&mut rh, coherent);
                            let tri = (rh.hit.geom_id != INVALID_ID).then_some((rh.hit.prim_id, rh.ray.tfar, rh.hit.u, rh.hit.v));
                            self.finish_closest(ray, tri)
                        }
                        (Some(_), None) => self.finish_closest(ray, None),
                        (None, _) => None,
                    }
                }
            }
            Lanes::Four => self.intersect_packets::<4>(rays, coherent, out),
            Lanes::Eight => self.intersect_packets::<8>(rays, coherent, out),
            Lanes::Sixteen => self.intersect_packets::<16>(rays, coherent, out),
        }
    }

    fn intersect_packets<const N: usize>(&self, rays: &[Ray], coherent: bool, out: &mut [Option<(SurfaceHit, PrimitiveRef)>]) {
        for (group, answers) in rays.chunks(N).zip(out.chunks_mut(N)) {
            // Load the valid rays into lanes.
            let mut packet = RayHitN::<N> { ray: Default::default(), hit: Default::default() };
            let mut valid = [0i32; N];
            for (l, ray) in group.iter().enumerate() {
                if let Some(r) = to_embree(ray) {
                    set_lane(&mut packet.ray, l, &r);
                    valid[l] = -1;
                }
            }
            // Trace, then finish lane by lane.
            if let Some(e) = &self.embree {
                e.intersect_n(&valid, &mut packet, coherent);
            }
            for (l, (ray, o)) in group.iter().zip(answers).enumerate() {
                let h = &packet.hit;
                let tri = (valid[l] != 0 && h.geom_id[l] != INVALID_ID).then(|| (h.prim_id[l], packet.ray.tfar[l], h.u[l], h.v[l]));
                *o = if valid[l] != 0 { self.finish_closest(ray, tri) } else { None };
            }
        }
    }

    /// Occlusion of `rays` into `out` (same length), `lanes` rays per Embree call.
    pub fn occluded_packets_of(&self, rays: &[Ray], lanes: Lanes, coherent: bool, out: &mut [bool]) {
        assert_eq!(rays.len(), out.len(), "one answer per ray");
        match lanes {
            Lanes::One => rays.iter().zip(out).for_each(|(ray, o)| *o = self.occluded_one(ray, coherent)),
            Lanes::Four => self.occluded_packets::<4>(rays, coherent, out),
            Lanes::Eight => self.occluded_packets::<8>(rays, coherent, out),
            Lanes::Sixteen => self.occluded_packets::<16>(rays, coherent, out),
        }
    }

    #[inline]
    fn occluded_one(&self, ray: &Ray, coherent: bool) -> bool {
        let Some(mut r) = to_embree(ray) else { return false };
        // Spheres first: few and cheap.
        if self.spheres.sphere_count() > 0 && self.spheres.occluded(ray) {
            return true;
        }
        let Some(e) = &self.embree else { return false };
        e.occluded1(&mut r, coherent);
        r.tfar == f32::NEG_INFINITY
    }

    fn occluded_packets<const N: usize>(&self, rays: &[Ray], coherent: bool, out: &mut [bool]) {
        for (group, answers) in rays.chunks(N).zip(out.chunks_mut(N)) {
            // Lanes blocked by a sphere are answered before Embree and masked off.
            let mut packet = RayOnlyN::<N> { ray: Default::default() };
            let mut valid = [0i32; N];
            for (l, (ray, o)) in group.iter().zip(answers.iter_mut()).enumerate() {
                *o = false;
                let Some(r) = to_embree(ray) else { continue };
                if self.spheres.sphere_count() > 0 && self.spheres.occluded(ray) {
                    *o = true;
                    continue;
                }
                set_lane(&mut packet.ray, l, &r);
                valid[l] = -1;
            }
            let Some(e) = &self.embree else { continue };
            if valid.iter().all(|&v| v == 0) {
                continue;
            }
            e.occluded_n(&valid, &mut packet, coherent);
            for (l, o) in answers.iter_mut().enumerate() {
                *o |= valid[l] != 0 && packet.ray.tfar[l] == f32::NEG_INFINITY;
            }
        }
    }
}

/// Our ray in Embree's form, or `None` for a ray ours refuse (see the module
/// documentation for the ends of the interval).
#[inline]
fn to_embree(ray: &Ray) -> Option<Ray1> {
    let ok = ray.origin.is_finite() && ray.dir.is_finite() && ray.dir != Vec3::ZERO && ray.t_max > 0.0;
    ok.then(|| Ray1 {
        org: ray.origin.to_array(),
        tnear: f32::MIN_POSITIVE,
        dir: ray.dir.to_array(),
        time: 0.0,
        tfar: float_below(ray.t_max),
        mask: u32::MAX,
        id: 0,
        flags: 0,
    })
}

/// The largest float below `t` (positive): `f32::MAX` for ∞.
#[inline]
fn float_below(t: f32) -> f32 {
    if t == f32::INFINITY { f32::MAX } else { f32::from_bits(t.to_bits() - 1) }
}

#[inline]
fn set_lane<const N: usize>(p: &mut ffi::RayN<N>, l: usize, r: &Ray1) {
    (p.org_x[l], p.org_y[l], p.org_z[l], p.tnear[l]) = (r.org[0], r.org[1], r.org[2], r.tnear);
    (p.dir_x[l], p.dir_y[l], p.dir_z[l], p.time[l]) = (r.dir[0], r.dir[1], r.dir[2], r.time);
    (p.tfar[l], p.mask[l], p.id[l], p.flags[l]) = (r.tfar, r.mask, r.id, r.flags);
}

/// Rays per Embree call when the lane loop asks in batches ([`RayQuery::batch_width`]).
const BATCH: usize = 16;

impl RayQuery for EmbreeAccel {
    fn intersect(&self, ray: &Ray) -> Option<SurfaceHit> {
        self.intersect_primitive(ray).map(|(h, _)| h)
    }

    fn occluded(&self, ray: &Ray) -> bool {
        self.occluded_one(ray, false)
    }

    /// 16: the lane loop then keeps 16 paths in flight and every batch is one
    /// `rtcIntersect16` / `rtcOccluded16` (incoherent: the batch mixes camera rays with
    /// bounces).
    fn batch_width(&self) -> usize {
        BATCH
    }

    fn intersect_batch(&self, rays: RayBatch<'_>, hits: &mut [Option<SurfaceHit>]) {
        let (mut group, mut answers) = ([Ray::new(Vec3::ZERO, Vec3::ZERO, 0.0); BATCH], [None; BATCH]);
        let n = rays.len().min(hits.len());
        let mut all = rays.iter();
        for chunk in hits[..n].chunks_mut(BATCH) {
            let k = chunk.len();
            group.iter_mut().zip(all.by_ref().take(k)).for_each(|(g, ray)| *g = ray);
            self.intersect_packets::<BATCH>(&group[..k], false, &mut answers[..k]);
            for (h, a) in chunk.iter_mut().zip(&answers[..k]) {
                *h = a.map(|(hit, _)| hit);
            }
        }
    }

    fn occluded_batch(&self, rays: RayBatch<'_>, occluded: &mut [bool]) {
        let mut group = [Ray::new(Vec3::ZERO, Vec3::ZERO, 0.0); BATCH];
        let n = rays.len().min(occluded.len());
        let mut all = rays.iter();
        for chunk in occluded[..n].chunks_mut(BATCH) {
            let k = chunk.len();
            group.iter_mut().zip(all.by_ref().take(k)).for_each(|(g, ray)| *g = ray);
            self.occluded_packets::<BATCH>(&group[..k], false, chunk);
        }
    }
}
