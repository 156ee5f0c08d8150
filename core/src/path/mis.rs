//! Balance-heuristic MIS weights of BDPT strategies by pdf ratios (pbrt-v3's
//! `MISWeight`; Veach 1997 §10.2).
//!
//! For a path of n = s + t vertices built by strategy (s, t), the weight is
//! w_{s,t} = p_s / Σ_i p_i = 1 / Σ_i (p_i / p_s). Neighbouring strategies differ by one
//! vertex changing sub-path, so p_{i±1}/p_i is a ratio pdf_rev/pdf_fwd of that vertex;
//! walking outward from the connection accumulates the sum in O(n). Strategies that
//! would need to connect to a Dirac vertex contribute zero. The connection vertices'
//! reverse densities depend on the strategy, so they are recomputed here on copies.

use super::vertex::{Vertex, VertexKind};
use crate::bsdf::TransportMode;
use crate::measure::VertexPdf;
use crate::scene::Scene;

/// pdf ratios treat 0 as 1 so Dirac vertices (density 0 both ways) pass through. Both
/// densities of a ratio belong to the same vertex, so their measure cancels.
#[inline]
pub(crate) fn remap0(x: VertexPdf) -> f64 {
    let x = x.value();
    if x != 0.0 { x as f64 } else { 1.0 }
}

/// Balance-heuristic weight of strategy (s, t). `sampled` replaces the light endpoint
/// for s = 1 or the camera endpoint for t = 1 (both resampled at connection time).
///
/// Only the (up to) four vertices around the connection change their reverse density
/// and Dirac flag for this strategy; they are held as overrides instead of copying the
/// sub-paths, so a weight costs O(s + t) reads and a handful of density evaluations.
pub fn mis_weight(scene: &Scene, light: &[Vertex], camera: &[Vertex], sampled: Option<&Vertex>, s: usize, t: usize) -> f32 {
    mis_weight_counted(scene, light, camera, sampled, s, t, &|_, _| 1.0)
}

/// [`mis_weight`] for estimators whose strategies have different sample counts
/// (LVCBPT, SPCBPT): `count(s', t')` is the number of samples strategy (s', t') takes per
/// camera sample, and w_{s,t} = n_{s,t} p_{s,t} / Σ n_i p_i. With every count 1 (BDPT)
/// each ratio is multiplied by exactly 1.0, so BDPT's weights are unchanged bit for bit.
pub fn mis_weight_counted<C: Fn(usize, usize) -> f64>(
    scene: &Scene,
    light: &[Vertex],
    camera: &[Vertex],
    sampled: Option<&Vertex>,
    s: usize,
    t: usize,
    count: &C,
) -> f32 {
    if s + t == 2 {
        return 1.0;
    }
    let own = count(s, t);
    if !(own > 0.0) {
        return 0.0;
    }
    let mut sum = 0.0f64;
    for_each_strategy_ratio(scene, light, camera, sampled, s, t, &mut |s2, t2, ratio| sum += ratio * (count(s2, t2) / own));
    let w = (1.0 / (1.0 + sum)) as f32;
    if w.is_finite() { w } else { 0.0 }
}

/// Visit every OTHER strategy (s', t') able to produce the path of strategy (s, t) with
/// the density ratio p_{s'} / p_{s,t} (f64), by the walk of [`mis_weight`]. SPCBPT's
/// training set reads the ratios one by one (its Γ-dependent counts are path-dependent).
pub fn for_each_strategy_ratio<V: FnMut(usize, usize, f64)>(
    scene: &Scene,
    light: &[Vertex],
    camera: &[Vertex],
    sampled: Option<&Vertex>,
    s: usize,
    t: usize,
    visit: &mut V,
) {
    // The strategy's own endpoints.
    let light_at = |i: usize| strategy_vertex(light, s, sampled, i);
    let camera_at = |i: usize| strategy_vertex(camera, t, sampled, i);
    let qs = (s > 0).then(|| light_at(s - 1));
    let qs_minus = (s > 1).then(|| light_at(s - 2));
    let pt = (t > 0).then(|| camera_at(t - 1));
    let pt_minus = (t > 1).then(|| camera_at(t - 2));

    // Reverse densities around the connection, recomputed for this strategy.
    let mut pt_rev = VertexPdf::ZERO;
    let mut pt_minus_rev = VertexPdf::ZERO;
    let mut qs_rev = VertexPdf::ZERO;
    let mut qs_minus_rev = VertexPdf::ZERO;
    if let Some(pt) = pt {
        // pt's reverse density: from qs (connection), or as a light-path origin (s = 0).
        // At each connection vertex with a neighbour on its own side, both ways through
        // it are evaluated together (`pdf_both_ways`: one material lookup, shared
        // directions).
        pt_rev = match (qs, pt_minus) {
            (Some(q), _) => match qs_minus {
                Some(qm) => {
                    let (to_pt, to_qm) = q.pdf_both_ways(scene, qm, pt, TransportMode::Importance);
                    qs_minus_rev = to_qm;
                    to_pt
                }
                None => q.pdf(scene, None, pt, TransportMode::Importance),
            },
            (None, Some(pm)) => pt.pdf_light_origin(scene, pm),
            (None, None) => VertexPdf::ZERO,
        };
        match (pt_minus, qs) {
            (Some(pm), Some(q)) => (pt_minus_rev, qs_rev) = pt.pdf_both_ways(scene, q, pm, TransportMode::Importance),
            (Some(pm), None) => pt_minus_rev = pt.pdf_light(scene, pm),
            (None, Some(q)) => qs_rev = pt.pdf(scene, None, q, TransportMode::Radiance),
            (None, None) => {}
        }
    }
    let cam_rev = |i: usize| match i {
        _ if i + 1 == t => pt_rev,
        _ if i + 2 == t => pt_minus_rev,
        _ => camera_at(i).pdf_rev,
    };
    let light_rev = |i: usize| match i {
        _ if i + 1 == s => qs_rev,
        _ if i + 2 == s => qs_minus_rev,
        _ => light_at(i).pdf_rev,
    };
    // The connection vertices are joined deterministically: never Dirac here. Nor is
    // the light source as a connection end: next-event estimation reaches point, spot
    // and directional lights too (its flag only bars s = 0, `is_delta_light` below).
    // Counting it as Dirac dropped s = 1 from the other strategies' sums, and BDPT read
    // 1.6× too bright under a point light.
    let cam_delta = |i: usize| i + 1 != t && camera_at(i).delta;
    let light_delta = |i: usize| i > 0 && i + 1 != s && light_at(i).delta;

    // A vertex changing sides also changes which side drew its junction's kernel sample
    // (segment BDPT; 1 for vertex paths). The path's light end has no junction.
    let cam_kernel = |i: usize| if s == 0 && i + 1 == t { 1.0 } else { camera_at(i).kernel_ratio as f64 };
    let light_kernel = |i: usize| light_at(i).kernel_ratio as f64;

    // Ratios are accumulated in f64: they span many magnitudes along long paths.
    // Strategies with more light vertices: move camera vertices to the light side.
    let mut ri = 1.0f64;
    for i in (1..t).rev() {
        ri *= remap0(cam_rev(i)) / remap0(camera_at(i).pdf_fwd) * cam_kernel(i);
        if !cam_delta(i) && !cam_delta(i - 1) {
            visit(s + t - i, i, ri);
        }
    }
    // Strategies with fewer light vertices.
    ri = 1.0;
    for i in (0..s).rev() {
        ri *= remap0(light_rev(i)) / remap0(light_at(i).pdf_fwd) * light_kernel(i);
        let delta_before = if i > 0 { light_delta(i - 1) } else { is_delta_light(scene, light_at(0)) };
        if !light_delta(i) && !delta_before {
            visit(i, s + t - i, ri);
        }
    }
}

/// Vertex `i` of a strategy's sub-path `path` of which it uses `n` vertices: `sampled`
/// replaces the first one where n = 1 (the light point of s = 1, the camera of t = 1,
/// resampled at connection time).
#[inline]
pub(crate) fn strategy_vertex<'a>(path: &'a [Vertex], n: usize, sampled: Option<&'a Vertex>, i: usize) -> &'a Vertex {
    match sampled {
        Some(v) if n == 1 && i == 0 => v,
        _ => &path[i],
    }
}

/// Is `v` a light no path can hit (point, spot, directional)? Strategies ending with an
/// emission hit on it (s = 0) are impossible.
pub(crate) fn is_delta_light(scene: &Scene, v: &Vertex) -> bool {
    match v.kind {
        VertexKind::Light(id) => scene.lights[id as usize].is_delta(),
        VertexKind::InfiniteLight => v.delta,
        _ => false,
    }
}
