//! SPCBPT's MIS sample counts (eqs. 11, 12 in expected-value form) as a deterministic
//! function of a full path: the light-prefix weights W, the subspace labels of every
//! split, and the memos that let a connection read most of them instead of
//! recomputing them ([`CameraLabels`] per camera path, [`PrefixMemo`] per light vertex).
//! The memos run the same functions on the same vertices as a joined path would, so
//! counts — and therefore the weights of all strategies of one path — are identical
//! with or without them (tested bit for bit in `tests/tests/spcbpt_mis.rs`).
//!
//! With both memos a connection of light prefix y₀…y_{s−1} to camera prefix
//! z_{t−1}…z₀ computes in full only the splits next to the connection (s′ = s − 1, s,
//! s + 1: their labels and prefix weights involve both sub-paths). A split inside the
//! light prefix (s′ ≤ s − 2) reads its whole count from the prefix's memo. A split inside
//! the camera prefix (s′ ≥ s + 2) reads N·Γ(l | e) and Q(l) from the camera memo and
//! multiplies by W(x₀…x_{s′−1}), which continues the light prefix's product through the
//! two junction vertices and then through factors of the camera vertices alone (also in
//! the camera memo). Every value is the same product of the same factors in the same
//! order as the joined path's, so the same bits.

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

/// x = `light` followed by `camera` reversed (x[j] = camera[n − 1 − j] for j ≥ s): a
/// full path read in place, without copying its vertices.
#[derive(Clone, Copy)]
struct Joined<'a> {
    light: &'a [Vertex],
    camera: &'a [Vertex],
}

impl Joined<'_> {
    #[inline]
    fn len(&self) -> usize {
        self.light.len() + self.camera.len()
    }
    #[inline]
    fn at(&self, j: usize) -> &Vertex {
        match self.light.get(j) {
            Some(v) => v,
            None => &self.camera[self.len() - 1 - j],
        }
    }
}

/// What vertex x_k does to the light prefix's f/p when the prefix is continued through
/// it from x_{k−1} towards x_{k+1}.
#[derive(Clone, Copy, Debug, Default)]
pub enum Factor {
    /// Not a surface: the product stops (every later W is 0).
    #[default]
    Stop,
    /// A Dirac vertex counts 1.
    Keep,
    /// A zero density: the product becomes zero.
    Zero,
    /// f(x_{k−1} → x_k → x_{k+1}) and G(x_k, x_{k+1}) / p: the product becomes w · f · scale.
    Scale(Rgb, f32),
}

impl Factor {
    fn of(scene: &Scene, prev: &Vertex, v: &Vertex, next: &Vertex) -> Self {
        if v.kind != VertexKind::Surface {
            return Self::Stop;
        }
        if scene.materials[v.material as usize].is_delta() {
            return Self::Keep;
        }
        let mut turned = *v;
        turned.wo = (prev.p - v.p).normalize_or_zero();
        let pdf = turned.pdf(scene, Some(prev), next, TransportMode::Importance).value();
        if pdf > 0.0 { Self::Scale(turned.f(scene, next, TransportMode::Importance), geometry(v, next) / pdf) } else { Self::Zero }
    }

    #[inline]
    fn apply(self, w: Rgb) -> Option<Rgb> {
        match self {
            Self::Stop => None,
            Self::Keep => Some(w),
            Self::Zero => Some(Rgb::ZERO),
            Self::Scale(f, scale) => Some(w * f * scale),
        }
    }
}

/// W(x₀…x_{k−1}) for k = 0..=n (index k = number of light vertices): the light prefix's
/// f/p as a deterministic function of the path (Dirac vertices count 1, no roulette).
/// Entry 1 is the light-source vertex alone, Le(x₀→x₁)/p(x₀) (the stage-2 weight of
/// [`super::cache_weight`]); entry 0 is unused (0).
pub fn light_prefix_weights(scene: &Scene, x: &[Vertex], out: &mut [f32]) {
    prefix_weights(scene, Joined { light: x, camera: &[] }, &[], None, out, &mut |_, _| {});
}

/// [`light_prefix_weights`] of `x`, reading W of the first `known.len()` vertices (≥ 2)
/// from their memo and continuing the product from there, through the camera memo's
/// factors past x_s where `camera` is given; `each(k, w)` sees the RGB product
/// W(x₀…x_k) after each vertex it computes (k ≥ 1), `None` once the product stops.
fn prefix_weights(scene: &Scene, x: Joined, known: &[PrefixMemo], camera: Option<&CameraLabels>, out: &mut [f32], each: &mut dyn FnMut(usize, Option<Rgb>)) {
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
        let (x0, x1) = (x.at(0), x.at(1));
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
    let s = x.light.len();
    for k in first..n - 1 {
        // Past x_s the vertex and both its neighbours lie on the camera sub-path.
        let factor = match camera {
            Some(c) if k > s => c.factor.get(x.len() - 1 - k).copied().unwrap_or_default(),
            _ => Factor::of(scene, x.at(k - 1), x.at(k), x.at(k + 1)),
        };
        match factor.apply(w) {
            Some(next) => w = next,
            None => {
                each(k + 1, None);
                return;
            }
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
    /// The count of the split between y_{k−1} and y_k (between the light source and the
    /// rest for k = 0), which depends on y₀…y_{k+1} alone; read for prefixes longer than
    /// k + 1 (NaN for a path's last vertex, where it is undefined).
    pub count: f64,
}

/// Append the memo of light path `path` (one entry per vertex) to `out`.
pub fn memoize_light_path(scene: &Scene, model: &Model, path: &[Vertex], out: &mut alloc::vec::Vec<PrefixMemo>) {
    let first = out.len();
    let mut w = [0.0f32; 2 * path::MAX_VERTICES + 1];
    let mut rgb = [None; 2 * path::MAX_VERTICES];
    let x = Joined { light: path, camera: &[] };
    prefix_weights(scene, x, &[], None, &mut w, &mut |k, v| {
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
        out.push(PrefixMemo { light, eye, w: w.get(k + 1).copied().unwrap_or(0.0), w_rgb: rgb.get(k).copied().flatten(), count: f64::NAN });
    }
    debug_assert_eq!(out.len() - first, path.len());
    // Counts from the labels and weights just stored (splits k ≤ n − 2 have t ≥ 2 on the
    // light path itself, so none of them is the light-tracing split).
    let memo = &out[first..];
    let mut counts = [f64::NAN; 2 * path::MAX_VERTICES + 1];
    let labels = Labels { model, x, memo, camera: None };
    for (k, count) in counts.iter_mut().enumerate().take(path.len().saturating_sub(1)) {
        *count = split_count(scene, model, 0.0, x, &labels, &w, k);
    }
    for (m, count) in out[first..].iter_mut().zip(counts) {
        m.count = count;
    }
}

#[inline]
pub(super) fn finite(x: f32) -> f32 {
    if x.is_finite() && x > 0.0 { x } else { 0.0 }
}

/// |cos| |cos| / d² with shading normals (what β carries along a segment).
fn geometry(a: &Vertex, b: &Vertex) -> f32 {
    path::vertex::cosines_over_distance2(a, a.frame.n, b, b.ng)
}

/// A split of the camera sub-path between z_{i+1} (light side) and z_i: N·Γ(l | e) and
/// Q(l), with `q` = 0 where the count is 0 (a vertex not a surface, or an empty Q).
#[derive(Clone, Copy, Debug, Default)]
pub struct CameraSplit {
    pub gamma_n: f64,
    pub q: f32,
}

/// What the counts need of a camera sub-path's own vertices, computed once per camera
/// path: `eye[i]` = κ_E(z_i) seen from z_{i−1}, `light[i]` = κ_L(z_i) seen from z_{i+1}
/// (u32::MAX where undefined); `split[i]` the split between z_{i+1} and z_i (1 ≤ i,
/// i + 2 < len); `factor[i]` what z_i does to a light prefix continued from z_{i+1}
/// towards z_{i−1} (1 ≤ i, i + 1 < len). A split whose two classified vertices and their
/// neighbours all lie on the camera sub-path reads them here instead of descending the
/// trees and evaluating the BSDF again (same features, same operations: the counts do
/// not change).
#[derive(Clone, Debug, Default)]
pub struct CameraLabels {
    pub eye: heapless::Vec<u32, { path::MAX_VERTICES }>,
    pub light: heapless::Vec<u32, { path::MAX_VERTICES }>,
    pub split: heapless::Vec<CameraSplit, { path::MAX_VERTICES }>,
    pub factor: heapless::Vec<Factor, { path::MAX_VERTICES }>,
}

impl CameraLabels {
    pub fn new(scene: &Scene, model: &Model, camera: &[Vertex]) -> Self {
        let mut labels = Self::default();
        for i in 0..camera.len() {
            let surface = camera[i].kind == VertexKind::Surface;
            let eye = if surface && i >= 1 { model.classifier.eye_of(&camera[i], camera[i - 1].p) } else { u32::MAX };
            let light = if surface && i + 1 < camera.len() { model.classifier.light_of(&camera[i], camera[i + 1].p) } else { u32::MAX };
            let _ = labels.eye.push(eye);
            let _ = labels.light.push(light);
        }
        for i in 0..camera.len() {
            let mut split = CameraSplit::default();
            if i >= 1 && i + 2 < camera.len() && camera[i].kind == VertexKind::Surface && camera[i + 1].kind == VertexKind::Surface {
                let (l, e) = (labels.light[i + 1], labels.eye[i]);
                let q = model.q.get(l as usize).copied().unwrap_or(0.0);
                if q > 0.0 {
                    split = CameraSplit { gamma_n: model.connections as f64 * model.gamma.get(l, e) as f64, q };
                }
            }
            let _ = labels.split.push(split);
            let factor = if i >= 1 && i + 1 < camera.len() { Factor::of(scene, &camera[i + 1], &camera[i], &camera[i - 1]) } else { Factor::Stop };
            let _ = labels.factor.push(factor);
        }
        labels
    }
}

/// The labels of a joined path, read from the memos where both vertices that define one
/// lie on one sub-path, classified otherwise.
struct Labels<'a> {
    model: &'a Model,
    x: Joined<'a>,
    /// The light prefix's memo (empty, or one entry per vertex of `x.light`).
    memo: &'a [PrefixMemo],
    camera: Option<&'a CameraLabels>,
}

impl Labels<'_> {
    #[inline]
    fn read(l: Option<&u32>) -> Option<u32> {
        l.copied().filter(|&l| l != u32::MAX)
    }
    /// κ_E(x_j) seen from x_{j+1}.
    fn eye(&self, j: usize) -> u32 {
        let (n, s) = (self.x.len(), self.memo.len());
        // Known when both are on the camera path, or both on the light prefix.
        let known = if j >= self.x.light.len() {
            self.camera.and_then(|c| Self::read(c.eye.get(n - 1 - j)))
        } else if j + 1 < s {
            Self::read(self.memo.get(j).map(|m| &m.eye))
        } else {
            None
        };
        known.unwrap_or_else(|| self.model.classifier.eye_of(self.x.at(j), self.x.at(j + 1).p))
    }
    /// κ_L(x_j) seen from x_{j−1}.
    fn light(&self, j: usize) -> u32 {
        let (n, s) = (self.x.len(), self.memo.len());
        let known = if j > self.x.light.len() {
            self.camera.and_then(|c| Self::read(c.light.get(n - 1 - j)))
        } else if j >= 1 && j < s {
            Self::read(self.memo.get(j).map(|m| &m.light))
        } else {
            None
        };
        known.unwrap_or_else(|| self.model.classifier.light_of(self.x.at(j), self.x.at(j - 1).p))
    }
    /// y₀'s light-source bin.
    fn source(&self, scene: &Scene) -> Option<u32> {
        Self::read(self.memo.first().map(|m| &m.light)).or_else(|| self.model.classifier.light_source_of(scene, self.x.at(0)))
    }
}

/// The count of split s′ of `x`, computed from its labels and the prefix weights `w`.
fn split_count(scene: &Scene, model: &Model, light_tracing: f64, x: Joined, labels: &Labels, w: &[f32], s2: usize) -> f64 {
    let n = x.len();
    let t = n - s2;
    if t == 1 {
        light_tracing
    } else if s2 == 1 && model.caches_light_sources() {
        // The light-source vertex through the cache: N · Γ(bin | κ_E) · W₁ / Q(bin).
        let z = x.at(1);
        match labels.source(scene) {
            Some(l) if z.kind == VertexKind::Surface && z.is_connectible(scene) => {
                let q = model.q.get(l as usize).copied().unwrap_or(0.0);
                if q > 0.0 { model.connections as f64 * model.gamma.get(l, labels.eye(1)) as f64 * w[1] as f64 / q as f64 } else { 0.0 }
            }
            _ => 0.0,
        }
    } else if s2 <= 1 || t == 0 {
        1.0
    } else {
        let (y, z) = (x.at(s2 - 1), x.at(s2));
        if y.kind != VertexKind::Surface || z.kind != VertexKind::Surface {
            0.0
        } else {
            let l = labels.light(s2 - 1);
            let e = labels.eye(s2);
            let q = model.q.get(l as usize).copied().unwrap_or(0.0);
            if q > 0.0 { model.connections as f64 * model.gamma.get(l, e) as f64 * w[s2] as f64 / q as f64 } else { 0.0 }
        }
    }
}

/// Sample counts n_{s'} of every split of full path `x` (s' = 0..=n), into `out`.
pub fn path_counts(scene: &Scene, model: &Model, light_tracing: f64, x: &[Vertex], out: &mut [f64]) {
    counts(scene, model, light_tracing, x, &[], &[], None, out)
}

/// [`path_counts`] of x = `light` followed by `camera` reversed, read in place: `memo` is
/// the light sub-path's memo (used only with one entry per vertex of `light`), `camera`
/// the labels of a camera path of which `camera` is a prefix (used only for t ≥ 2). The
/// same values either way; with both memos a connection costs O(1) label look-ups and
/// BSDF evaluations instead of O(n) (module docs).
#[allow(clippy::too_many_arguments)]
pub fn counts(
    scene: &Scene,
    model: &Model,
    light_tracing: f64,
    light: &[Vertex],
    memo: &[PrefixMemo],
    camera: &[Vertex],
    labels: Option<&CameraLabels>,
    out: &mut [f64],
) {
    let x = Joined { light, camera };
    let (s, n) = (light.len(), x.len());
    let memo = if memo.len() == s { memo } else { &[] };
    let labels = labels.filter(|_| camera.len() >= 2);
    let mut w = [0.0f32; 2 * path::MAX_VERTICES + 1];
    prefix_weights(scene, x, memo, labels, &mut w, &mut |_, _| {});
    let known = Labels { model, x, memo, camera: labels };
    for s2 in 0..=n.min(out.len() - 1) {
        out[s2] = if s2 + 2 <= memo.len() {
            // Inside the light prefix, next vertex included: the memo's count.
            memo[s2].count
        } else if let Some(c) = labels.filter(|_| s2 >= s + 2 && s2 + 2 <= n) {
            // Inside the camera prefix, the light side's predecessor included.
            let split = c.split.get(n - 1 - s2).copied().unwrap_or_default();
            if split.q > 0.0 { split.gamma_n * w[s2] as f64 / split.q as f64 } else { 0.0 }
        } else {
            split_count(scene, model, light_tracing, x, &known, &w, s2)
        };
    }
}
