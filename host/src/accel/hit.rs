//! What both hosts' triangle structures share beyond the intersection test: which
//! triangles can be hit, how far leaf boxes are padded, and the hit record. The browser
//! host (`host-wasm/src/accel.rs`) compiles this file through `#[path]`, so a hit is the
//! same numbers on both hosts.

use ember_core::geometry::{LightId, MaterialId, SurfaceHit};
use ember_core::shapes::{SceneGeometry, Triangle, texcoords_at};
use glam::{Vec2, Vec3, Vec3A};

/// A triangle the structures keep: finite vertices and a non-zero area.
pub(crate) fn can_be_hit(t: &Triangle) -> bool {
    let n = (t.p[1] - t.p[0]).cross(t.p[2] - t.p[0]);
    t.p.iter().all(|p| p.is_finite()) && n.is_finite() && n.length_squared() > 0.0
}

/// 1 + 2γ₃ (γₙ = nε / (1 − nε), ε the unit roundoff): pbrt-v4's widening of a slab
/// test's far distance, which makes the test conservative for the box as stored. Our
/// own slab tests (the BVH4's nodes, the listed spheres' boxes) apply it on top of the
/// padding below; the browser host's BVH2 (obvhs's test) relies on the padding alone.
#[allow(dead_code, reason = "the browser host compiles this file and has no slab test of its own")]
pub(crate) const SLAB_WIDEN: f32 = 1.0 + 2.0 * (3.0 * f32::EPSILON * 0.5) / (1.0 - 3.0 * f32::EPSILON * 0.5);

/// How far every leaf box is grown: 2⁻¹⁹ of the scene's largest coordinate (8 ulps).
///
/// obvhs's slab test is not conservative (pbrt-v4 widens t_max by 1 + 2γ(3) for this;
/// obvhs does not): a flat box, such as an axis-aligned wall's, hit exactly on its rim
/// can be missed by a few ulps. A camera ray through the exact edge where two such
/// walls meet then misses both boxes and leaks out of a closed room, although the
/// watertight triangle test would have caught it. Measured: unpadded, the BVH2 let 2
/// of 1 M pixel-centre camera rays (the benchmark scene at 1024²) escape its closed
/// box, and rays aimed exactly at the edges of a closed tessellated box escaped by
/// thousands (test `closed_box_does_not_leak_at_edges`: 2 244 BVH2, 5 609 CWBVH of
/// 120 000; none padded). Growing the boxes by a few ulps of the scene's scale closes
/// those gaps at no measurable cost. The slab test's error grows with the distance of
/// the ray origin, so the margin covers origins up to roughly ten scene sizes away.
pub(crate) fn box_padding(geometry: &SceneGeometry) -> f32 {
    let b = geometry.bounds();
    let scale = if b.is_empty() { 1.0 } else { b.min.abs().max(b.max.abs()).max_element().max(1e-3) };
    if scale.is_finite() { scale * (1.0 / 524_288.0) } else { 0.0 }
}

/// The unit geometric normal of triangle `v` (by its winding), computed once per
/// triangle when the structure is built.
pub(crate) fn geometric_normal(v: &[Vec3A; 3]) -> Vec3 {
    let (p0, p1, p2) = (Vec3::from(v[0]), Vec3::from(v[1]), Vec3::from(v[2]));
    (p1 - p0).cross(p2 - p0).normalize()
}

/// The full record of a hit at distance `t` with barycentrics `b` on triangle `v` with
/// geometric normal `ng` ([`geometric_normal`]); vertex normals `normals`, if any, are
/// interpolated and turned to the geometric side; texture coordinates as
/// [`Triangle::texcoords`].
#[allow(clippy::too_many_arguments)]
#[inline]
pub(crate) fn surface_hit(
    v: &[Vec3A; 3],
    ng: Vec3,
    normals: Option<[Vec3; 3]>,
    texcoords: Option<[Vec2; 3]>,
    material: MaterialId,
    emitter: Option<LightId>,
    t: f32,
    b: [f32; 3],
) -> SurfaceHit {
    let (p0, p1, p2) = (Vec3::from(v[0]), Vec3::from(v[1]), Vec3::from(v[2]));
    // Interpolating the vertices is more accurate than o + t·d far from the origin.
    let p = b[0] * p0 + b[1] * p1 + b[2] * p2;
    let ns = normals.map(|n| b[0] * n[0] + b[1] * n[1] + b[2] * n[2]).and_then(|n| n.try_normalize()).map_or(ng, |n| if n.dot(ng) < 0.0 { -n } else { n });
    SurfaceHit { t, p, ng, ns, uv: texcoords_at(texcoords, b), material, emitter }
}
