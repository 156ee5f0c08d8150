//! What Γ should have learned: the share of connection contribution by light subspace,
//! per eye subspace (issue 18's oracle, a diagnostic; rendering never calls it).
//!
//! Γ(l | e) picks the light subspace an eye vertex of subspace e connects to. The
//! contribution of the pair is
//!
//! ```text
//! C(e, l) = E[ Σ_{z: κ_E(z) = e}  Σ_{y ∈ cache: κ_L(y) = l}  f(y ↔ z) / (p(Z̄) · p(Ȳ) · M) ]
//! ```
//!
//! the unweighted (no MIS) value of every connection between the pass's cached light
//! vertices of l and the eye vertices of e. [`connection_sums`] estimates it with the
//! renderer's own two-stage choice: a connection drawn with probability
//! N · M_eff · Γ'(l | e) · P_r(y) adds its unweighted f/p divided by that probability,
//! which is unbiased for C(e, l) whatever Γ is, as long as Γ' and P_r are positive where
//! f is (the mixture m keeps every non-empty subspace in Γ'; stage 2 is ∝ f_y/p, positive
//! on every cached vertex that carries light). Occluded connections add nothing, so the
//! oracle's column O(· | e) = C(e, ·) / Σ_l C(e, l) is where light actually arrives.
//!
//! This is the eq. 7 selection without its MIS factor: the loss of eq. 15 also weighs
//! what the other strategies already cover, so the trained Γ need not equal O. A Γ that
//! puts mass where O has none wastes connections on occluders.

use alloc::vec;
use alloc::vec::Vec;
use core::ops::Range;

use super::{CameraLabels, Draw, Model, PassCache, connect_unweighted, draw};
use crate::geometry::RayQuery;
use crate::path::{self, LightPointSample, VertexKind};
use crate::rng::{SampleStream, Stream};
use crate::scene::{Context, Scene};
use crate::subspace::SubspaceMatrix;
use crate::transport::{Counters, RenderParams};

/// Per (eye, light) subspace pair, the summed unweighted connection value (luminance),
/// eye-major: `sums[e · n_light + l]`; and per eye subspace the eye vertices seen.
#[derive(Clone, Debug, PartialEq)]
pub struct ConnectionSums {
    pub n_light: usize,
    pub n_eye: usize,
    pub sums: Vec<f64>,
    pub eye_vertices: Vec<u64>,
    /// Per eye subspace, the sum of its eye vertices' positions (for ordering plots).
    pub eye_positions: Vec<[f64; 3]>,
}

impl ConnectionSums {
    /// Zero sums for `model`'s subspaces.
    pub fn new(model: &Model) -> Self {
        let (n_light, n_eye) = (model.classifier.n_light as usize, model.classifier.n_eye as usize);
        Self { n_light, n_eye, sums: vec![0.0; n_light * n_eye], eye_vertices: vec![0; n_eye], eye_positions: vec![[0.0; 3]; n_eye] }
    }

    /// Add `other`'s sums (hosts sum per-thread parts in a fixed order).
    pub fn add(&mut self, other: &Self) {
        for (a, b) in self.sums.iter_mut().zip(&other.sums) {
            *a += b;
        }
        for (a, b) in self.eye_vertices.iter_mut().zip(&other.eye_vertices) {
            *a += b;
        }
        for (a, b) in self.eye_positions.iter_mut().zip(&other.eye_positions) {
            for k in 0..3 {
                a[k] += b[k];
            }
        }
    }

    /// Column e of the oracle, normalised (None where e saw no light).
    pub fn column(&self, e: usize) -> Option<Vec<f64>> {
        let row = self.sums.get(e * self.n_light..(e + 1) * self.n_light)?;
        let total: f64 = row.iter().sum();
        (total > 0.0).then(|| row.iter().map(|v| v / total).collect())
    }
}

/// Add to `sums` the connections of pixels `pixels` in pass `pass`, drawn as the
/// renderer draws them (the same camera sub-paths and the same auxiliary stream as
/// `render_pixels`, so with the same cache the same connections), each weighted by
/// 1 / its selection probability and left unweighted by MIS.
#[allow(clippy::too_many_arguments)]
pub fn connection_sums<Q: RayQuery + ?Sized>(
    scene: &Scene,
    tracer: &Q,
    params: &RenderParams,
    model: &Model,
    cache: &PassCache,
    pass: u32,
    pixels: Range<u32>,
    sums: &mut ConnectionSums,
) {
    let ctx = Context { scene, tracer };
    let mut counters = Counters::default();
    let (max_camera, _) = path::vertex_budgets(params);
    for pixel in pixels {
        let camera = path::pixel_camera_subpath(scene, tracer, params, pixel, pass, max_camera, &mut counters);
        let labels = CameraLabels::new(scene, model, &camera);
        let mut aux = SampleStream::for_sample(params.seed, Stream::Aux, pixel, pass, 0);
        for t in 2..=camera.len() {
            if !params.max_depth.allows(t as u32 - 1) {
                break;
            }
            // The renderer's draws for s = 0, 1 (kept so the stream stays aligned).
            for _ in 0..=1 {
                let _ = (aux.next_f32(), aux.next_2d());
            }
            let z = &camera[t - 1];
            if z.kind != VertexKind::Surface || !z.is_connectible(scene) {
                continue;
            }
            let e = labels.eye.get(t - 1).copied().unwrap_or(u32::MAX) as usize;
            let Some(Some(stage1)) = cache.gamma_tables.get(e) else { continue };
            if let (Some(n), Some(p)) = (sums.eye_vertices.get_mut(e), sums.eye_positions.get_mut(e)) {
                *n += 1;
                for (k, c) in [z.p.x, z.p.y, z.p.z].into_iter().enumerate() {
                    p[k] += c as f64;
                }
            }
            for _ in 0..model.connections {
                let (u1, u2) = (aux.next_f32(), aux.next_f32());
                let Some(Draw { subspace, light, probability, .. }) = draw(model, cache, stage1, u1, u2) else { continue };
                let s = light.len();
                if !params.max_depth.allows((s + t - 1) as u32) {
                    continue;
                }
                let Some(c) = connect_unweighted(&ctx, model, light, &camera[..t], s, t, LightPointSample::default(), &mut counters) else { continue };
                let value = c.value.luminance() as f64 / probability as f64;
                if value.is_finite()
                    && value > 0.0
                    && let Some(slot) = sums.sums.get_mut(e * sums.n_light + subspace)
                {
                    *slot += value;
                }
            }
        }
    }
}

/// How far Γ is from the oracle, averaged over eye subspaces weighted by their share of
/// the total connection contribution.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct OracleDistance {
    /// Σ_e w_e KL(O(·|e) ‖ Γ(·|e)), in nats.
    pub kl: f64,
    /// The same for the uniform Γ(l|e) = 1/n_light (what LVCBPT's choice is closest to).
    pub kl_uniform: f64,
    /// Σ_e w_e Σ_{l: O(l|e) = 0} Γ(l|e): Γ's mass on light subspaces that gave this eye
    /// subspace nothing (occluded, or facing away).
    pub wasted: f64,
    /// Eye subspaces with a contribution.
    pub columns: usize,
}

/// Compare Γ (a model's `gamma`) with the oracle `sums`.
pub fn distance(gamma: &SubspaceMatrix, sums: &ConnectionSums) -> OracleDistance {
    let totals: Vec<f64> = (0..sums.n_eye).map(|e| sums.sums[e * sums.n_light..(e + 1) * sums.n_light].iter().sum()).collect();
    let all: f64 = totals.iter().sum();
    let mut out = OracleDistance::default();
    if !(all > 0.0) {
        return out;
    }
    let uniform = 1.0 / sums.n_light as f64;
    for (e, &total) in totals.iter().enumerate() {
        if !(total > 0.0) {
            continue;
        }
        let w = total / all;
        out.columns += 1;
        for (l, &v) in sums.sums[e * sums.n_light..(e + 1) * sums.n_light].iter().enumerate() {
            let (o, g) = (v / total, gamma.get(l as u32, e as u32) as f64);
            if o > 0.0 {
                out.kl += w * o * libm::log(o / g.max(1e-30));
                out.kl_uniform += w * o * libm::log(o / uniform);
            } else {
                out.wasted += w * g;
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sums(n_light: usize, values: &[f64]) -> ConnectionSums {
        let n_eye = values.len() / n_light;
        ConnectionSums { n_light, n_eye, sums: values.to_vec(), eye_vertices: vec![1; n_eye], eye_positions: vec![[0.0; 3]; n_eye] }
    }

    #[test]
    fn distance_against_closed_forms() {
        // One eye subspace, O = (3/4, 1/4) against a uniform Γ = (1/2, 1/2).
        let d = distance(&SubspaceMatrix::uniform(2, 1), &sums(2, &[3.0, 1.0]));
        let kl = 0.75 * libm::log(1.5) + 0.25 * libm::log(0.5);
        assert!((d.kl - kl).abs() < 1e-6 && (d.kl_uniform - kl).abs() < 1e-12, "{d:?}");
        assert_eq!((d.wasted, d.columns), (0.0, 1));
        // A light subspace that gave nothing: Γ's mass there is wasted; KL only over O > 0.
        let d = distance(&SubspaceMatrix::uniform(4, 1), &sums(4, &[1.0, 0.0, 0.0, 1.0]));
        assert!((d.wasted - 0.5).abs() < 1e-6 && (d.kl - libm::log(2.0)).abs() < 1e-6, "{d:?}");
        // Eye subspaces weigh by their share of the total; an empty one is skipped.
        let d = distance(&SubspaceMatrix::uniform(2, 3), &sums(2, &[1.0, 1.0, 0.0, 0.0, 2.0, 0.0]));
        assert_eq!(d.columns, 2);
        assert!((d.kl - 0.5 * libm::log(2.0)).abs() < 1e-6 && (d.wasted - 0.25).abs() < 1e-6, "{d:?}");
    }

    #[test]
    fn columns_normalise_and_sums_add() {
        let mut a = sums(2, &[1.0, 3.0, 0.0, 0.0]);
        assert_eq!(a.column(0), Some(vec![0.25, 0.75]));
        assert_eq!(a.column(1), None);
        a.add(&sums(2, &[1.0, 1.0, 2.0, 2.0]));
        assert_eq!(a.sums, vec![2.0, 4.0, 2.0, 2.0]);
        assert_eq!(a.eye_vertices, vec![2, 2]);
    }
}
