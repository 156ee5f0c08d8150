//! VCM's balance-heuristic weights over connections and merges, by prefix sums that
//! each sub-path carries (the recursive form of Georgiev et al. 2012's weights, written
//! in area measure with the core's typed vertex densities).
//!
//! **The techniques of one path.** For a full path x₀ (light end) … x_k (camera), with
//! p→(x_i) the density of the light side generating x_i and p←(x_i) that of the camera
//! side, connection technique s (light vertices x₀…x_{s−1}) has density
//! p_s = Π_{i<s} p→(x_i) · Π_{i≥s} p←(x_i), and merging at x_j (light path to x_j, camera
//! path to a point within r of x_j) has p_{M,j} ≈ p_{j+1} · π r² p←(x_j) per light path.
//! With N_L light paths per pass, η = N_L π r² and counts n_s, the balance heuristic is
//! w = n p / Σ (n_s p_s + η p_{j+1} p←(x_j)).
//!
//! **Prefix sums.** Writing ρ_i = p←(x_i) / p→(x_i), the terms of the denominator that lie
//! on the light side of x_m, divided by p_{m+1}, are
//!
//! S_L(m) = η μ_m p←(x_m) + ρ_m · B_m,  B_i = n_i ν_i + η μ_{i−1} p←(x_{i−1}) + ρ_{i−1} B_{i−1},
//!
//! with B₀ = n₀ ν₀ (s = 0), μ_i = 1 where merging at x_i is possible (a non-Dirac surface
//! vertex, not a light source or the camera) and ν_i = 1 where technique i is (neither end
//! of the connection Dirac). The camera side is the mirror image (B₀ = 0: no technique
//! has no camera vertex). B_i needs p←(x_{i−1}), which the walk stores once x_{i+1}
//! exists; so a sub-path ending at the junction x_m carries B up to m − 1 ([`prefix`]),
//! and a weight needs only the junction's own densities: four for a connection, as in
//! BDPT, and for a merge the camera vertex's BSDF densities toward both sides (the
//! merge's path is taken with the camera vertex's BSDF and position, as VCM does). A
//! weight costs O(1), independent of path length.
//!
//! Dirac densities are taken as 1 in every ratio (they are the same symbolic factor in
//! every technique able to produce the path), as in [`crate::path::mis`]; with η = 0 the
//! weights are BDPT's (to rounding), with all connection counts 0 they are bidirectional
//! photon mapping's.

use crate::bsdf::TransportMode;
use crate::measure::{SolidAnglePdf, VertexPdf};
use crate::path::Vertex;
use crate::path::mis::{is_delta_light, remap0, strategy_vertex};
use crate::scene::Scene;

/// May a path be merged at `v`? The vertices LVCBPT caches: non-Dirac surface points.
pub use crate::path::is_cacheable as mergeable;

/// Sample counts, per camera sample, of the techniques of one pass.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Techniques {
    /// s = 0: a camera path reaching an emitter.
    pub emission: f64,
    /// s = 1: next-event estimation.
    pub next_event: f64,
    /// t = 1: light vertices connected to the pinhole (N_L / (W·H)).
    pub light_tracing: f64,
    /// s, t ≥ 2: connection to the pixel's light path.
    pub connection: f64,
    /// η = N_L π r²: merging (0 where merging is off).
    pub merge: f64,
}

impl Techniques {
    /// n_{s,t}.
    #[inline]
    pub fn count(&self, s: usize, t: usize) -> f64 {
        if s == 0 {
            self.emission
        } else if t == 1 {
            self.light_tracing
        } else if s == 1 {
            self.next_event
        } else {
            self.connection
        }
    }
}

/// Which end a sub-path starts from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    /// Starts at a light.
    Light,
    /// Starts at the camera.
    Camera,
}

/// Count × validity of the technique that cuts `path` before vertex `i` (i vertices
/// from this side), for a path whose junction lies beyond i (so the technique uses a
/// connection or, on the light side at i ≤ 1, emission or next-event estimation).
fn cut(scene: &Scene, path: &[Vertex], side: Side, tech: &Techniques, i: usize) -> f64 {
    match side {
        Side::Light => {
            let ok = if i == 0 { !is_delta_light(scene, &path[0]) } else { !(path[i].delta || (i > 1 && path[i - 1].delta)) };
            if ok { tech.count(i, 2) } else { 0.0 }
        }
        Side::Camera => {
            if i == 0 || path[i].delta || path[i - 1].delta {
                0.0
            } else {
                tech.count(2, i)
            }
        }
    }
}

/// The prefix sums B_i of sub-path `path` into `out` (same length): B_i for i ≤ len − 2;
/// the last entry is NaN (it needs the junction). See the module notes.
pub fn prefix(scene: &Scene, path: &[Vertex], side: Side, tech: &Techniques, out: &mut [f64]) {
    let n = path.len().min(out.len());
    for i in 0..n {
        out[i] = if i + 1 == n {
            f64::NAN
        } else if i == 0 {
            cut(scene, path, side, tech, 0)
        } else {
            let prev = &path[i - 1];
            // Merging at an endpoint (the light source, the camera) is no technique.
            let merge = if i > 1 && mergeable(scene, prev) { tech.merge * remap0(prev.pdf_rev) } else { 0.0 };
            cut(scene, path, side, tech, i) + merge + remap0(prev.pdf_rev) / remap0(prev.pdf_fwd) * out[i - 1]
        };
    }
}

/// One side's junction: its last vertex with the density the other side has of it,
/// whether a merge there counts, and the vertex before it with its reverse density
/// (which depends on the junction) and prefix sum.
struct Junction<'a> {
    vertex: &'a Vertex,
    rev: VertexPdf,
    merge: bool,
    /// n_m ν_m: the technique cutting just before the junction vertex.
    cut: f64,
    /// The vertex before, its reverse density and prefix sum, and whether merging at it
    /// is a technique (not at a sub-path's first vertex).
    prev: Option<(&'a Vertex, VertexPdf, f64, bool)>,
}

/// S(m) = η μ_m p←(v_m) + ρ_m (n_m ν_m + η μ_{m−1} p←(v_{m−1}) + ρ_{m−1} B_{m−1}).
fn side_sum(scene: &Scene, tech: &Techniques, j: &Junction) -> f64 {
    let mut inner = j.cut;
    if let Some((v, rev, b, can_merge)) = j.prev {
        if can_merge && mergeable(scene, v) {
            inner += tech.merge * remap0(rev);
        }
        inner += remap0(rev) / remap0(v.pdf_fwd) * b;
    }
    let own_merge = if j.merge { tech.merge * remap0(j.rev) } else { 0.0 };
    own_merge + remap0(j.rev) / remap0(j.vertex.pdf_fwd) * inner
}

/// The weight of connection (s, t) of `light` and `camera` (with prefix sums `light_b`,
/// `camera_b` from [`prefix`]); `sampled` replaces the light endpoint for s = 1 or the
/// camera for t = 1, as [`crate::path::connect`] returns it.
#[allow(clippy::too_many_arguments)]
pub fn connection_weight(
    scene: &Scene,
    tech: &Techniques,
    light: &[Vertex],
    light_b: &[f64],
    camera: &[Vertex],
    camera_b: &[f64],
    sampled: Option<&Vertex>,
    s: usize,
    t: usize,
) -> f32 {
    if s + t == 2 {
        return 1.0;
    }
    let own = tech.count(s, t);
    if !(own > 0.0) {
        return 0.0;
    }
    let light_at = |i: usize| strategy_vertex(light, s, sampled, i);
    let camera_at = |i: usize| strategy_vertex(camera, t, sampled, i);
    let pt = camera_at(t - 1);
    let pt_minus = (t > 1).then(|| camera_at(t - 2));
    let sum = if s == 0 {
        // The camera path's last vertex is the light source: all other techniques have
        // fewer camera vertices.
        let rev = match pt_minus {
            Some(pm) => pt.pdf_light_origin(scene, pm),
            None => VertexPdf::ZERO,
        };
        let prev = pt_minus.map(|pm| (pm, pt.pdf_light(scene, pm), camera_b[t - 2], t > 2));
        let cut = if pt_minus.is_some_and(|pm| !pm.delta) { tech.count(1, t - 1) } else { 0.0 };
        side_sum(scene, tech, &Junction { vertex: pt, rev, merge: false, cut, prev })
    } else {
        let qs = light_at(s - 1);
        let qs_minus = (s > 1).then(|| light_at(s - 2));
        // Densities around the connection, for this technique.
        let pt_rev = qs.pdf(scene, qs_minus, pt, TransportMode::Importance);
        let qs_rev = pt.pdf(scene, pt_minus, qs, TransportMode::Radiance);
        let light_cut = if s == 1 {
            if is_delta_light(scene, qs) { 0.0 } else { tech.count(0, t + 1) }
        } else if s > 2 && qs_minus.is_some_and(|q| q.delta) {
            0.0
        } else {
            tech.count(s - 1, t + 1)
        };
        let light_side = Junction {
            vertex: qs,
            rev: qs_rev,
            merge: s > 1 && mergeable(scene, qs),
            cut: light_cut,
            prev: qs_minus.map(|qm| (qm, qs.pdf(scene, Some(pt), qm, TransportMode::Radiance), light_b[s - 2], s > 2)),
        };
        let camera_cut = if t > 1 && !pt_minus.is_some_and(|p| p.delta) { tech.count(s + 1, t - 1) } else { 0.0 };
        let camera_side = Junction {
            vertex: pt,
            rev: pt_rev,
            merge: t > 1 && mergeable(scene, pt),
            cut: camera_cut,
            prev: pt_minus.map(|pm| (pm, pt.pdf(scene, Some(qs), pm, TransportMode::Importance), camera_b[t - 2], t > 2)),
        };
        side_sum(scene, tech, &light_side) + side_sum(scene, tech, &camera_side)
    };
    let w = (own / (own + sum)) as f32;
    if w.is_finite() { w } else { 0.0 }
}

/// The camera vertex's BSDF densities a merge needs (solid angle, at the camera vertex):
/// toward the photon's predecessor given the camera direction, and back toward the
/// camera's predecessor given the photon's direction.
#[derive(Clone, Copy, Debug)]
pub struct MergeDensities {
    /// p(ω_o → ω_photon): the camera side continuing toward the light path.
    pub toward_light: SolidAnglePdf,
    /// p(ω_photon → ω_o): the light side continuing toward the camera path.
    pub toward_camera: SolidAnglePdf,
}

/// A photon's part of [`merge_weight`], computed once per pass: the light-side sum is
/// S_L = η R + (R / p→(x_j)) (n_j ν_j + a · p←(x_{j−1})), where R is the camera side's
/// density of the merge point and p←(x_{j−1}) = p_ω · `g_prev` the only factor that
/// depends on the camera vertex (through its BSDF density p_ω toward x_{j−1}).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PhotonSums {
    /// p→(x_j), Dirac taken as 1.
    pub fwd: f32,
    /// n_j ν_j: the technique connecting x_{j−1} to the camera side's x_j.
    pub cut: f32,
    /// Converts a solid-angle density at x_j toward x_{j−1} to x_{j−1}'s vertex density.
    pub g_prev: f32,
    /// η μ_{j−1} + B_{j−1} / p→(x_{j−1}).
    pub a: f64,
}

impl PhotonSums {
    /// The sums of light vertex `light[j]` (j ≥ 1) with prefix sums `light_b`.
    pub fn new(scene: &Scene, tech: &Techniques, light: &[Vertex], light_b: &[f64], j: usize) -> Self {
        let (x, x_prev) = (&light[j], &light[j - 1]);
        let mu = if j > 1 && mergeable(scene, x_prev) { tech.merge } else { 0.0 };
        Self {
            fwd: remap0(x.pdf_fwd) as f32,
            cut: if j > 1 && x_prev.delta { 0.0 } else { tech.count(j, 2) as f32 },
            g_prev: x.convert_density(SolidAnglePdf(1.0), x_prev, TransportMode::Radiance).value(),
            a: mu + light_b[j - 1] / remap0(x_prev.pdf_fwd),
        }
    }
}

/// A camera vertex's part of [`merge_weight`] (t ≥ 2), computed once per camera vertex.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CameraSums {
    /// R: the camera side's density of the merge point, p→ of z_{t−1} (Dirac as 1).
    pub r: f64,
    /// n ν of the technique connecting x_j to z_{t−2}.
    pub base: f64,
    /// Whether z_{t−2} is a scattering vertex (t ≥ 3): otherwise no camera-side sum.
    pub has_side: bool,
    /// Converts a solid-angle density at z_{t−1} toward z_{t−2} to its vertex density.
    pub g_prev: f32,
    /// p← of z_{t−2} as its own side generated it (Dirac as 1).
    pub fwd_prev: f64,
    /// η μ_{t−2}.
    pub merge_prev: f64,
    /// n ν of the technique cutting before z_{t−2}, plus η μ_{t−3} p(z_{t−3}) + ρ_{t−3} B_{t−3}.
    pub inner: f64,
}

impl CameraSums {
    /// The sums of camera vertex `camera[t − 1]` with prefix sums `camera_b`.
    pub fn new(scene: &Scene, tech: &Techniques, camera: &[Vertex], camera_b: &[f64], t: usize) -> Self {
        let (y, y_prev) = (&camera[t - 1], &camera[t - 2]);
        let mut sums = Self { r: remap0(y.pdf_fwd), base: if y_prev.delta { 0.0 } else { tech.count(3, t - 1) }, ..Self::default() };
        if t >= 3 {
            let z = &camera[t - 3];
            let cut = if z.delta || y_prev.delta { 0.0 } else { tech.count(4, t - 2) };
            let merge_z = if mergeable(scene, z) { tech.merge * remap0(z.pdf_rev) } else { 0.0 };
            sums.has_side = true;
            sums.g_prev = y.convert_density(SolidAnglePdf(1.0), y_prev, TransportMode::Importance).value();
            sums.fwd_prev = remap0(y_prev.pdf_fwd);
            sums.merge_prev = if mergeable(scene, y_prev) { tech.merge } else { 0.0 };
            sums.inner = cut + merge_z + remap0(z.pdf_rev) / remap0(z.pdf_fwd) * camera_b[t - 3];
        }
        sums
    }
}

/// The weight of merging light vertex `light[j]` (j ≥ 1, prefix sums `light_b`) at
/// camera vertex `camera[t − 1]` (t ≥ 2, prefix sums `camera_b`), with the camera
/// vertex's BSDF densities `d`: [`merge_weight_from_sums`] of the two sides' sums (the
/// estimator computes them once per photon and per camera vertex).
#[allow(clippy::too_many_arguments)]
pub fn merge_weight(
    scene: &Scene,
    tech: &Techniques,
    light: &[Vertex],
    light_b: &[f64],
    j: usize,
    camera: &[Vertex],
    camera_b: &[f64],
    t: usize,
    d: MergeDensities,
) -> f32 {
    if j == 0 || t < 2 {
        return 0.0;
    }
    merge_weight_from_sums(tech, &PhotonSums::new(scene, tech, light, light_b, j), &CameraSums::new(scene, tech, camera, camera_b, t), d)
}

/// The merge weight from the precomputed sums: O(1) and no vertex reads. The merged
/// path is x₀ … x_j, z_{t−2} … z₀ with x_j standing for z_{t−1} (its camera-side density
/// is z_{t−1}'s); it is taken relative to the technique joining x_j to z_{t−2}.
#[inline]
pub fn merge_weight_from_sums(tech: &Techniques, photon: &PhotonSums, camera: &CameraSums, d: MergeDensities) -> f32 {
    let eta = tech.merge;
    let rev_prev = {
        let v = d.toward_light.value() * photon.g_prev;
        if v != 0.0 { v as f64 } else { 1.0 }
    };
    let light = eta * camera.r + camera.r / photon.fwd as f64 * (photon.cut as f64 + photon.a * rev_prev);
    let side = if camera.has_side {
        let v = d.toward_camera.value() * camera.g_prev;
        let rev = if v != 0.0 { v as f64 } else { 1.0 };
        camera.merge_prev * rev + rev / camera.fwd_prev * camera.inner
    } else {
        0.0
    };
    let w = (eta * camera.r / (camera.base + light + side)) as f32;
    if w.is_finite() { w.clamp(0.0, 1.0) } else { 0.0 }
}
