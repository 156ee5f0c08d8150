//! Bridge segments (Wang et al. 2025, §6.4 and Fig. 7), the sampler and its density side
//! by side.
//!
//! **The sampler** ([`trace_bridges`]): each camera node c that may take another segment
//! ([`bridges_from`]) picks one of the pass's M bridge ends ([`bridge_end`]: non-Dirac
//! light nodes) uniformly and joins it by a shadow ray. A visible bridge becomes a
//! light-kind node at c whose segment runs to its end l; bidirectional filtering reuses
//! it like a light segment arriving at c, and its radiance is l's reflection toward c,
//! from l's row ([`super::bidir`], "Bridge segments").
//!
//! **The density** ([`density`]): with virtual perturbation at both ends, the technique
//! draws a segment from x to y with density (1 / M) Σ_c K(c → x) Σ_l K(l → y) per area at
//! x and at y, the sums over the bridge starts and ends around each. In the measure of
//! the denominators (per area and solid angle at x) that is
//!
//!   (1 / M) Σ K_c Σ K_l d² / |n_y·ŝ|.
//!
//! Both sides make the same geometric test ([`bridge_geometry`]), so that no bridge is
//! ever drawn where its density is declared zero.

use alloc::vec::Vec;

use super::nodes::{Continuation, LightEnd, LightSegment, NONE, Node, NodeKind};
use crate::geometry::RayQuery;
use crate::math::Vec3;
use crate::rng::{SampleStream, Stream};
use crate::scene::Scene;
use crate::spectrum::Rgb;
use crate::transport::{Counters, SurfacePoint};

/// Can a camera node start a bridge (the depth allows another segment, as for its light
/// sample)?
#[inline]
pub fn bridges_from(n: &Node) -> bool {
    n.kind == NodeKind::Camera && !n.delta && n.light.attempted
}

/// The least |n_y·ŝ| at a bridge's end. A bridge between two points of one plane (two
/// nodes on the same wall) runs along it: its density per solid angle, d² / |n_y·ŝ|, is
/// unbounded, and where rounding makes the cosine 0 a sampled bridge would enter with no
/// term of its own in D, counted as though the BSDF had drawn it (the built-in Cornell
/// box 1.4 % too bright at 0.1 footprints). Such bridges are neither traced nor counted:
/// the technique's support leaves them out, and the other techniques cover them.
pub const MIN_BRIDGE_COS: f64 = 1e-4;

/// (d², |n_y·ŝ|) of a bridge from `x` to `y` (normal `ny`), or `None` where there is no
/// bridge ([`MIN_BRIDGE_COS`]): the one test both the sampler and the density make.
#[inline]
pub fn bridge_geometry(x: Vec3, y: Vec3, ny: Vec3) -> Option<(f64, f64)> {
    let v = y - x;
    let d2 = v.length_squared() as f64;
    if !(d2 > 1e-12) {
        return None;
    }
    let cos_y = ny.dot(v).abs() as f64 / crate::math::sqrt_f64(d2);
    (cos_y > MIN_BRIDGE_COS).then_some((d2, cos_y))
}

/// Can a bridge end at this node (a non-Dirac light node, not itself a bridge)?
#[inline]
pub fn bridge_end(n: &Node) -> bool {
    n.kind == NodeKind::Light && !n.delta && !n.bridge
}

/// The bridge technique's density in D's measure for a segment from `x` to the surface
/// point `y` (normal `ny`): `choice` · `starts` · `ends` · d² / |n_y·ŝ|, with `choice` =
/// 1 / M and `starts`, `ends` the sums of K over the bridge starts around x and the
/// bridge ends around y; 0 where [`bridge_geometry`] admits no bridge.
#[inline]
pub fn density(choice: f64, starts: f64, ends: f64, x: Vec3, y: Vec3, ny: Vec3) -> f64 {
    if !(starts > 0.0 && ends > 0.0) {
        return 0.0;
    }
    let Some((d2, cos_y)) = bridge_geometry(x, y, ny) else { return 0.0 };
    choice * starts * ends * d2 / cos_y
}

/// Bridge segments for camera nodes `range` of `nodes` (bidirectional filtering with
/// bridges, the segment paper's §6.4): each camera node that may take another segment
/// ([`bridges_from`]) joins one of the pass's bridge ends `ends`, drawn
/// uniformly, by a shadow ray. A visible bridge becomes a light-kind node at the camera
/// node's point whose `pred` is the end: its radiance is the end's reflection toward
/// the camera node, found by the end's row like a light node's. Appended to `out`.
/// Its random number derives from (seed, pass, camera node).
#[allow(clippy::too_many_arguments)]
pub fn trace_bridges<Q: RayQuery + ?Sized>(
    scene: &Scene,
    tracer: &Q,
    seed: u64,
    pass: u32,
    nodes: &[Node],
    ends: &[u32],
    range: core::ops::Range<usize>,
    out: &mut Vec<Node>,
) -> Counters {
    let mut counters = Counters::default();
    if ends.is_empty() {
        return counters;
    }
    for (i, c) in nodes[range.clone()].iter().enumerate() {
        if !bridges_from(c) {
            continue;
        }
        let index = (range.start + i) as u32;
        let mut rng = SampleStream::for_sample(seed, Stream::Camera, index, BRIDGE_SAMPLE, pass);
        let pick = ((rng.next_f32() * ends.len() as f32) as usize).min(ends.len() - 1);
        let end = ends[pick];
        let l = &nodes[end as usize];
        if bridge_geometry(c.hit.p, l.hit.p, l.hit.ng).is_none() {
            continue;
        }
        let to = l.hit.p - c.hit.p;
        let dir = to / to.length();
        let sp = SurfacePoint::new(c.hit, c.wo);
        counters.rays += 1;
        if tracer.occluded(&sp.spawn_to(l.hit.p, l.hit.ng)) {
            continue;
        }
        let mut node = *c;
        node.kind = NodeKind::Light;
        node.bridge = true;
        node.twin = false;
        node.wo = dir;
        node.pred = end;
        node.source = LightEnd::at_surface(&l.hit);
        node.emitted = l.hit.emitter.map_or(Rgb::ZERO, |id| scene.lights[id as usize].radiance(l.hit.p, l.hit.ng, -dir));
        node.next = Continuation { node: NONE, ..Continuation::default() };
        node.light = LightSegment::default();
        out.push(node);
    }
    counters
}

/// The `sample` field of a bridge's random-number key (camera streams use their pass's
/// samples below it).
const BRIDGE_SAMPLE: u32 = u32::MAX - 1;
