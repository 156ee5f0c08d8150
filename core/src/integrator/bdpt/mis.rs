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
use super::MAX_VERTICES;
use crate::scene::Scene;

/// pdf ratios treat 0 as 1 so Dirac vertices (density 0 both ways) pass through.
#[inline]
fn remap0(x: f32) -> f64 {
    if x != 0.0 { x as f64 } else { 1.0 }
}

/// Balance-heuristic weight of strategy (s, t). `sampled` replaces the light endpoint
/// for s = 1 or the camera endpoint for t = 1 (both resampled at connection time).
pub fn mis_weight(scene: &Scene, light: &[Vertex], camera: &[Vertex], sampled: Option<&Vertex>, s: usize, t: usize) -> f32 {
    if s + t == 2 {
        return 1.0;
    }
    // Copies we may modify: the light prefix (s) and camera prefix (t).
    let mut lv: heapless::Vec<Vertex, MAX_VERTICES> = heapless::Vec::new();
    let mut cv: heapless::Vec<Vertex, MAX_VERTICES> = heapless::Vec::new();
    for v in &light[..s] {
        let _ = lv.push(*v);
    }
    for v in &camera[..t] {
        let _ = cv.push(*v);
    }
    if let Some(v) = sampled {
        if s == 1 {
            lv[0] = *v;
        } else if t == 1 {
            cv[0] = *v;
        }
    }

    // Recompute the reverse densities around the connection.
    if t > 0 {
        let pt = cv[t - 1];
        let pt_minus = if t > 1 { Some(cv[t - 2]) } else { None };
        let qs = if s > 0 { Some(lv[s - 1]) } else { None };
        let qs_minus = if s > 1 { Some(lv[s - 2]) } else { None };
        // pt's reverse density: from qs (connection), or as a light-path origin (s = 0).
        cv[t - 1].pdf_rev = match (qs, pt_minus) {
            (Some(q), _) => q.pdf(scene, qs_minus.as_ref(), &pt),
            (None, Some(pm)) => pt.pdf_light_origin(scene, &pm),
            (None, None) => 0.0,
        };
        if let Some(pm) = pt_minus {
            cv[t - 2].pdf_rev = match qs {
                Some(q) => pt.pdf(scene, Some(&q), &pm),
                None => pt.pdf_light(scene, &pm),
            };
        }
        if let Some(q) = qs {
            lv[s - 1].pdf_rev = pt.pdf(scene, pt_minus.as_ref(), &q);
            if let Some(qm) = qs_minus {
                lv[s - 2].pdf_rev = q.pdf(scene, Some(&pt), &qm);
            }
        }
        // The connection vertices are connected deterministically: never Dirac here.
        cv[t - 1].delta = false;
    }
    if s > 0 {
        lv[s - 1].delta = false;
    }

    // Ratios are accumulated in f64: they span many magnitudes along long paths.
    let mut sum = 0.0f64;
    // Strategies with more light vertices: move camera vertices to the light side.
    let mut ri = 1.0f64;
    for i in (1..t).rev() {
        ri *= remap0(cv[i].pdf_rev) / remap0(cv[i].pdf_fwd);
        if !cv[i].delta && !cv[i - 1].delta {
            sum += ri;
        }
    }
    // Strategies with fewer light vertices.
    ri = 1.0;
    for i in (0..s).rev() {
        ri *= remap0(lv[i].pdf_rev) / remap0(lv[i].pdf_fwd);
        let delta_before = if i > 0 { lv[i - 1].delta } else { is_delta_light(scene, &lv[0]) };
        if !lv[i].delta && !delta_before {
            sum += ri;
        }
    }
    let w = (1.0 / (1.0 + sum)) as f32;
    if w.is_finite() { w } else { 0.0 }
}

fn is_delta_light(scene: &Scene, v: &Vertex) -> bool {
    match v.kind {
        VertexKind::Light(id) => scene.lights[id as usize].is_delta(),
        VertexKind::InfiniteLight => v.delta,
        _ => false,
    }
}
