//! SPCBPT's MIS sample counts (eqs. 11, 12 in expected-value form) as a deterministic
//! function of a full path: the light-prefix weights W, the subspace labels of every
//! split, and the memos that let a connection read most of them instead of
//! recomputing them (camera labels per camera path, [`PrefixMemo`] per light vertex).
//! The memos run the same functions on the same vertices as a joined path would, so
//! counts — and therefore the weights of all strategies of one path — are identical
//! with or without them (tested bit for bit in `tests/tests/spcbpt_mis.rs`).

use super::Model;
use crate::bsdf::TransportMode;
use crate::path::{self, Vertex, VertexKind};
use crate::scene::Scene;
use crate::spectrum::Rgb;

/// Scalar of a radiometric value (the RGB sum, as the paper's code).
#[inline]
pub fn scalar(c: Rgb) -> f32 {
    c.sum()
}

/// W(x₀…x_{k−1}) for k = 0..=n (index k = number of light vertices): the light prefix's
/// f/p as a deterministic function of the path (Dirac vertices count 1, no roulette).
/// Entry 1 is the light-source vertex alone, Le(x₀→x₁)/p(x₀) (the stage-2 weight of
/// [`super::cache_weight`]); entry 0 is unused (0).
pub fn light_prefix_weights(scene: &Scene, x: &[Vertex], out: &mut [f32]) {
    light_prefix_weights_from(scene, x, &[], out, &mut |_, _| {});
}

/// [`light_prefix_weights`] reading W of the first `known.len()` vertices (≥ 2) from their
/// memo and continuing the product from there; `each(k, w)` sees the RGB product
/// W(x₀…x_k) after each vertex it computes (k ≥ 1), `None` once the product stops.
fn light_prefix_weights_from(scene: &Scene, x: &[Vertex], known: &[PrefixMemo], out: &mut [f32], each: &mut dyn FnMut(usize, Option<Rgb>)) {
    let n = x.len().min(out.len().saturating_sub(1));
    out.iter_mut().for_each(|w| *w = 0.0);
    if n < 2 {
        return;
    }
    let (mut w, first) = if known.len() >= 2 && known.len() <= n {
        let s = known.len();
        for (k, m) in known.iter().enumerate() {
            out[k + 1] = m.w;
        }
        match known[s - 1].w_rgb {
            Some(w) => (w, s - 1),
            None => return,
        }
    } else {
        let (x0, x1) = (&x[0], &x[1]);
        let position = x0.pdf_light_origin(scene, x1).value();
        let le = x0.le(scene, x1);
        out[1] = if position > 0.0 { finite(scalar(le) / position) } else { 0.0 };
        // The two-vertex light prefix's density: origin × the next vertex's area density.
        let origin = position * x0.pdf_light(scene, x1).value();
        let w = if origin > 0.0 { le * (geometry(x0, x1) / origin) } else { Rgb::ZERO };
        out[2] = finite(scalar(w));
        each(1, Some(w));
        (w, 1)
    };
    for k in first..n - 1 {
        let (prev, v, next) = (&x[k - 1], &x[k], &x[k + 1]);
        if v.kind != VertexKind::Surface {
            each(k + 1, None);
            return;
        }
        if !scene.materials[v.material as usize].is_delta() {
            let mut turned = *v;
            turned.wo = (prev.p - v.p).normalize_or_zero();
            let pdf = turned.pdf(scene, Some(prev), next, TransportMode::Importance).value();
            w = if pdf > 0.0 { w * turned.f(scene, next, TransportMode::Importance) * (geometry(v, next) / pdf) } else { Rgb::ZERO };
        }
        out[k + 2] = finite(scalar(w));
        each(k + 1, Some(w));
    }
}

/// What the counts of a split need of light-path vertex y_k, computed once per pass
/// from the light path alone ([`memoize_light_path`]), for every connection to a
/// prefix of that path.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "wire", derive(serde::Serialize, serde::Deserialize))]
pub struct PrefixMemo {
    /// κ_L(y_k) seen from y_{k−1} (k ≥ 1, surfaces), or y₀'s light-source bin; u32::MAX
    /// where undefined.
    pub light: u32,
    /// κ_E(y_k) seen from y_{k+1} (surfaces with a successor); u32::MAX where undefined.
    /// Unused for a prefix's last vertex, whose successor is the connected camera vertex.
    pub eye: u32,
    /// W(y₀…y_k): entry k + 1 of [`light_prefix_weights`].
    pub w: f32,
    /// The RGB product behind `w` (k ≥ 1), continued along a camera sub-path; `None` where
    /// the product stopped (a non-surface vertex) or for y₀.
    pub w_rgb: Option<Rgb>,
}

/// Append the memo of light path `path` (one entry per vertex) to `out`.
pub fn memoize_light_path(scene: &Scene, model: &Model, path: &[Vertex], out: &mut alloc::vec::Vec<PrefixMemo>) {
    let first = out.len();
    let mut w = [0.0f32; 2 * path::MAX_VERTICES + 1];
    let mut rgb = [None; 2 * path::MAX_VERTICES];
    light_prefix_weights_from(scene, path, &[], &mut w, &mut |k, v| {
        if let Some(slot) = rgb.get_mut(k) {
            *slot = v;
        }
    });
    for (k, v) in path.iter().enumerate() {
        let surface = v.kind == VertexKind::Surface;
        let light = if k == 0 {
            model.classifier.light_source_of(scene, v).unwrap_or(u32::MAX)
        } else if surface {
            model.classifier.light_of(v, path[k - 1].p)
        } else {
            u32::MAX
        };
        let eye = if surface && k >= 1 && k + 1 < path.len() { model.classifier.eye_of(v, path[k + 1].p) } else { u32::MAX };
        out.push(PrefixMemo { light, eye, w: w.get(k + 1).copied().unwrap_or(0.0), w_rgb: rgb.get(k).copied().flatten() });
    }
    debug_assert_eq!(out.len() - first, path.len());
}

#[inline]
pub(super) fn finite(x: f32) -> f32 {
    if x.is_finite() && x > 0.0 { x } else { 0.0 }
}

/// |cos| |cos| / d² with shading normals (what β carries along a segment).
fn geometry(a: &Vertex, b: &Vertex) -> f32 {
    path::vertex::cosines_over_distance2(a, a.frame.n, b, b.ng)
}

/// Subspace labels of a camera sub-path's own vertices, computed once per camera path:
/// `eye[i]` = κ_E(z_i) seen from z_{i−1}, `light[i]` = κ_L(z_i) seen from z_{i+1}
/// (u32::MAX where undefined). A split whose two classified vertices and their
/// neighbours all lie on the camera sub-path reads them here instead of descending the
/// trees again (same features, so the same labels: the counts do not change).
#[derive(Clone, Debug, Default)]
pub struct CameraLabels {
    pub eye: heapless::Vec<u32, { path::MAX_VERTICES }>,
    pub light: heapless::Vec<u32, { path::MAX_VERTICES }>,
}

impl CameraLabels {
    pub fn new(model: &Model, camera: &[Vertex]) -> Self {
        let mut labels = Self::default();
        for i in 0..camera.len() {
            let surface = camera[i].kind == VertexKind::Surface;
            let eye = if surface && i >= 1 { model.classifier.eye_of(&camera[i], camera[i - 1].p) } else { u32::MAX };
            let light = if surface && i + 1 < camera.len() { model.classifier.light_of(&camera[i], camera[i + 1].p) } else { u32::MAX };
            let _ = labels.eye.push(eye);
            let _ = labels.light.push(light);
        }
        labels
    }
}

/// Labels and weights of a full path already known from the sub-paths it joins:
/// `camera` for the camera sub-path (x[s..] reversed), `light` the memo of the light
/// prefix x[..s].
#[derive(Clone, Copy, Debug, Default)]
pub struct KnownLabels<'a> {
    pub camera: Option<&'a CameraLabels>,
    pub light: &'a [PrefixMemo],
    pub s: usize,
}

/// Sample counts n_{s'} of every split of full path `x` (s' = 0..=n), into `out`.
pub fn path_counts(scene: &Scene, model: &Model, light_tracing: f64, x: &[Vertex], out: &mut [f64]) {
    path_counts_labelled(scene, model, light_tracing, x, KnownLabels::default(), out)
}

/// [`path_counts`] for x = light prefix (`known.s` vertices) + a camera sub-path, reading
/// what `known` holds instead of recomputing it (the same values either way).
pub fn path_counts_labelled(scene: &Scene, model: &Model, light_tracing: f64, x: &[Vertex], known: KnownLabels, out: &mut [f64]) {
    let n = x.len();
    let s_known = known.s;
    let memo = if known.light.len() == s_known && s_known <= n { known.light } else { &[] };
    let read = |l: Option<&u32>| l.copied().filter(|&l| l != u32::MAX);
    // Camera index of full-path vertex j (j ≥ s): x[j] = camera[n − 1 − j].
    let eye_of = |j: usize| -> u32 {
        // Seen from x[j + 1]: both on the camera path, or both on the light prefix.
        let known_label = if j >= s_known {
            known.camera.and_then(|c| read(c.eye.get(n - 1 - j)))
        } else if j + 1 < s_known {
            read(memo.get(j).map(|m| &m.eye))
        } else {
            None
        };
        known_label.unwrap_or_else(|| model.classifier.eye_of(&x[j], x[j + 1].p))
    };
    let light_of = |j: usize| -> u32 {
        // Seen from x[j − 1]: both on the camera path, or both on the light prefix.
        let known_label = if j > s_known {
            known.camera.and_then(|c| read(c.light.get(n - 1 - j)))
        } else if j >= 1 && j < s_known {
            read(memo.get(j).map(|m| &m.light))
        } else {
            None
        };
        known_label.unwrap_or_else(|| model.classifier.light_of(&x[j], x[j - 1].p))
    };
    let mut w = [0.0f32; 2 * path::MAX_VERTICES + 1];
    light_prefix_weights_from(scene, x, memo, &mut w, &mut |_, _| {});
    for s in 0..=n.min(out.len() - 1) {
        let t = n - s;
        out[s] = if t == 1 {
            light_tracing
        } else if s == 1 && model.caches_light_sources() {
            // The light-source vertex through the cache: N · Γ(bin | κ_E) · W₁ / Q(bin).
            let z = &x[1];
            let bin = read(memo.first().map(|m| &m.light)).or_else(|| model.classifier.light_source_of(scene, &x[0]));
            match bin {
                Some(l) if z.kind == VertexKind::Surface && z.is_connectible(scene) => {
                    let q = model.q.get(l as usize).copied().unwrap_or(0.0);
                    if q > 0.0 { model.connections as f64 * model.gamma.get(l, eye_of(1)) as f64 * w[1] as f64 / q as f64 } else { 0.0 }
                }
                _ => 0.0,
            }
        } else if s <= 1 || t == 0 {
            1.0
        } else {
            let (y, z) = (&x[s - 1], &x[s]);
            if y.kind != VertexKind::Surface || z.kind != VertexKind::Surface {
                0.0
            } else {
                let l = light_of(s - 1);
                let e = eye_of(s);
                let q = model.q.get(l as usize).copied().unwrap_or(0.0);
                if q > 0.0 { model.connections as f64 * model.gamma.get(l, e) as f64 * w[s] as f64 / q as f64 } else { 0.0 }
            }
        };
    }
}
