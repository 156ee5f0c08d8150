//! Eq. (18)'s weights over one pass's nodes: the MMIS denominators of every sampled
//! segment and the rows of the propagation ([`super::graph`]).
//!
//! For a continuation s' = (x', y') leaving node u (x' = u's end, virtual perturbation),
//! the techniques able to draw it are the continuations and light samples conditioned on
//! every node t whose kernel covers x':
//!
//!   Σ_t p(s' | t) = Σ_t K(t → x') [q_t p_σ(ŝ' | t) + c_t P_L p_L(ŝ' | x')] |n_y'·ŝ'| / d²,
//!
//! with p_σ(ŝ' | t) the density of t's BSDF (for t's own incoming direction: the shift
//! invariance of eq. 6) and c_t = 1 where t drew a light sample. Each K(t → ·) is t's
//! own kernel: the pass's, narrower on glossy nodes (`nodes::scale_kernels`). The factor
//! |n_y'·ŝ'|/d² cancels against G(s') in eq. (18), leaving per solid angle at x'
//!
//!   D(s') = Σ_t K(t → x') [q_t p_σ(ŝ' | t) + c_t P_L p_L(ŝ' | x')],
//!
//! and the term node v's segment gains from s' is K(v → x') f_r(v; ŝ') |n_x'·ŝ'| L(s') / D(s').
//! Visibility is shared inside a kernel: s' is reused with its own end and radiance, no
//! ray is traced. Nodes and continuations drawn from a Dirac lobe are neither reused nor
//! reuse: a Dirac node keeps its own continuation with f |cos| / (q p) (its density in
//! every other technique is zero).

use alloc::vec::Vec;

use super::graph::{Real, Rgb3, rgb, scale3};
use super::node_grid::{KernelOf, KernelPoint, NodeGrid};
use super::nodes::{NONE, Node};
use crate::bsdf::TransportMode;
use crate::scene::Scene;
use crate::segment::Kernel;
use crate::spectrum::Rgb;

/// What the weights read: the pass's nodes, their kernel points (same order), the grid
/// over their positions (built for queries of radius √2 r at least: the disk kernel's
/// support reaches that far) and the kernel.
#[derive(Clone, Copy, Debug)]
pub struct Neighbourhood<'a> {
    pub scene: &'a Scene,
    pub nodes: &'a [Node],
    /// [`KernelPoint::of`] each node.
    pub points: &'a [KernelPoint],
    pub grid: &'a NodeGrid,
    pub kernel: Kernel,
}

/// The MMIS denominators of one node's two segments (per solid angle at its end).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "wire", derive(serde::Serialize, serde::Deserialize))]
pub struct Denominators {
    /// D of its continuation.
    pub next: f64,
    /// D of its light-sampled segment.
    pub light: f64,
}

impl Neighbourhood<'_> {
    /// K(t → x) for the point `x` with geometric normal `nx` (t's own kernel).
    #[inline]
    pub(super) fn kernel_at(&self, t: &Node, x: crate::math::Vec3, nx: crate::math::Vec3) -> f64 {
        KernelPoint::of(t).density_at(&self.kernel, x, nx)
    }

    /// The BSDF density of node t for leaving along `dir` (its own incoming direction),
    /// in transport mode `mode`.
    #[inline]
    pub(super) fn bsdf_pdf(&self, t: &Node, dir: crate::math::Vec3, mode: TransportMode) -> f64 {
        self.scene.material(t.hit.material, t.hit.uv).pdf_world(t.hit.ns, t.wo, dir, mode).0 as f64
    }

    /// The density of node t's own draw of `dir` in the denominators: the one its sampler
    /// reported (`sampled`; re-evaluating can give 0 for a direction the sampler drew, at
    /// roughness 1e-5), unless re-evaluating gives more than twice that. The rows
    /// re-evaluate the BSDF's value for the same direction, and where a lobe is
    /// ill-conditioned in f32 (rough glass nearly index-matched: the generalised half
    /// vector of wo + η wi, η ≈ 1, moves with the last bit of a direction) the sampler's
    /// density and the re-evaluated value disagree by any factor: found by fuzzing
    /// (`mis_weights`), a density of 2.8e-12 against 1.2e9 re-evaluated at η = 1.00003,
    /// α = 10⁻⁴, and a propagated radiance of 1e38. The larger density pairs the row's
    /// value with its own density. Elsewhere the two agree to rounding and the sampler's
    /// is kept (the same bits as before).
    #[inline]
    pub(super) fn own_pdf(&self, t: &Node, dir: crate::math::Vec3, mode: TransportMode, sampled: f32) -> f64 {
        let again = self.bsdf_pdf(t, dir, mode);
        if again > 2.0 * sampled as f64 { again } else { sampled as f64 }
    }

    /// Call `visit(index, node)` for every non-Dirac node whose end lies in the support of
    /// the kernel around `center` (as_center: K(center → node)) or whose kernel covers
    /// `center`'s end (otherwise: K(node → center)), with that density.
    fn each_neighbour(&self, center: &Node, as_center: bool, mut visit: impl FnMut(u32, &Node, f64)) {
        let c = KernelPoint::of(center);
        let of = if as_center { KernelOf::Centre { p: c.p, n: c.side, scale: c.scale } } else { KernelOf::Nodes { x: c.p, nx: c.side } };
        self.grid.query_kernel(None, c.p, self.kernel, of, |i, k| visit(i, &self.nodes[i as usize], k as f64));
    }

    /// D of node `index`'s continuation and light-sampled segment. Its own technique
    /// enters with the density its sampler reported (`Continuation::pdf`), so D is never
    /// below K(u → u) q_u p_σ > 0 for a segment that was drawn.
    pub fn denominators(&self, index: u32) -> Denominators {
        let mut d = Denominators::default();
        let u = &self.nodes[index as usize];
        if u.delta {
            return d;
        }
        let (next, light) = (&u.next, &u.light);
        let next_ok = next.dir != crate::math::Vec3::ZERO && !next.delta;
        let light_ok = light.dir != crate::math::Vec3::ZERO;
        self.each_neighbour(u, false, |i, t, k| {
            if next_ok {
                let p_sigma =
                    if i == index { self.own_pdf(t, next.dir, TransportMode::Radiance, next.pdf) } else { self.bsdf_pdf(t, next.dir, TransportMode::Radiance) };
                let mut p = t.next.q as f64 * p_sigma;
                if t.light.attempted {
                    p += next.light_pdf as f64;
                }
                d.next += k * p;
            }
            if light_ok {
                let mut p = if t.light.attempted { light.pdf as f64 } else { 0.0 };
                if !light.delta {
                    p += t.next.q as f64 * self.bsdf_pdf(t, light.dir, TransportMode::Radiance);
                }
                d.light += k * p;
            }
        });
        d
    }

    /// Node v's row of the propagation in `T`: L_e, the constant one-segment-later terms
    /// and the (target, coefficient) pairs. `dens` holds every node's denominators.
    pub fn row<T: Real>(&self, v: &Node, dens: &[Denominators], pairs: &mut Vec<(u32, Rgb3<T>)>) -> (Rgb3<T>, Rgb3<T>) {
        pairs.clear();
        let emission = rgb::<T>(v.emitted);
        let mut direct = [T::zero(); 3];
        if v.delta {
            // Only its own continuation, with the Dirac draw's f |cos| / (q p).
            let c = rgb::<T>(v.next.throughput);
            if v.next.node != NONE {
                pairs.push((v.next.node, c));
            } else if !v.next.escaped.is_black() {
                direct = super::graph::add3(direct, super::graph::mul3(c, rgb::<T>(v.next.escaped)));
            }
            return (emission, direct);
        }
        let frame = crate::math::Frame::from_normal(v.hit.ns);
        let material = self.scene.material(v.hit.material, v.hit.uv);
        let wo = frame.to_local(v.wo);
        let f = |dir: crate::math::Vec3| material.eval_from_local(&frame, wo, dir, TransportMode::Radiance);
        self.each_neighbour(v, true, |i, u, k| {
            let d = &dens[i as usize];
            let n = u.hit.ns;
            // The continuation.
            if u.next.dir != crate::math::Vec3::ZERO && !u.next.delta && d.next > 0.0 {
                let fr = f(u.next.dir);
                if !fr.is_black() {
                    let scale = T::from_f32(n.dot(u.next.dir).abs()) * T::from_f64(k) / T::from_f64(d.next);
                    let c = scale3(rgb::<T>(fr), scale);
                    if u.next.node != NONE {
                        // The reached node's radiance, through the medium the segment crossed.
                        pairs.push((u.next.node, scale3(rgb::<T>(fr * u.next.transmittance()), scale)));
                    } else if !u.next.escaped.is_black() {
                        direct = super::graph::add3(direct, super::graph::mul3(c, rgb::<T>(u.next.escaped)));
                    }
                }
            }
            // The light-sampled segment.
            if !u.light.radiance.is_black() && d.light > 0.0 {
                let fr = f(u.light.dir);
                if !fr.is_black() {
                    let scale = T::from_f32(n.dot(u.light.dir).abs()) * T::from_f64(k) / T::from_f64(d.light);
                    direct = super::graph::add3(direct, scale3(super::graph::mul3(rgb::<T>(fr), rgb::<T>(u.light.radiance)), scale));
                }
            }
        });
        (emission, direct)
    }
}

impl Neighbourhood<'_> {
    /// Photon filtering's row of light node u, reached from its predecessor w = `pred`
    /// (light order): the flux arriving at u is its base (the emission's, for a first
    /// hit) plus, for w's continuation s = (w, u), the terms of every segment arriving at
    /// a node u' in w's kernel:
    ///
    ///   A(u) = |n_w·ŝ| / D(s) · Σ_{u'} K(w → u') f_r(u'; ŝ, −ŝ_{u'}) A(u'),
    ///
    /// the adjoint of [`Self::row`]: the reused segments are the arriving ones, each
    /// turned into ŝ by the BSDF of the node it arrived at (see the module notes of
    /// [`super::phf`]), and D(s) sums the continuations conditioned on every node whose
    /// kernel covers w. A Dirac w passes on its own flux times f |cos| / (q p).
    pub fn light_row<T: Real>(&self, pred: u32, base: Rgb, dens: &[Denominators], pairs: &mut Vec<(u32, Rgb3<T>)>) -> (Rgb3<T>, Rgb3<T>) {
        pairs.clear();
        let zero = [T::zero(); 3];
        if pred == NONE {
            return (rgb::<T>(base), zero);
        }
        let w = &self.nodes[pred as usize];
        if w.delta {
            pairs.push((pred, rgb::<T>(w.next.throughput)));
            return (rgb::<T>(base), zero);
        }
        let d = dens[pred as usize].next;
        if !(d > 0.0) {
            return (rgb::<T>(base), zero);
        }
        let out = w.next.dir;
        let cos = T::from_f32(w.hit.ns.dot(out).abs()) / T::from_f64(d);
        let centre = KernelPoint::of(w);
        // (Dirac nodes are left out by the query: their BSDF is zero for any reused
        // direction, so they gave no pair.)
        let of = KernelOf::Centre { p: centre.p, n: centre.side, scale: centre.scale };
        self.grid.query_kernel(None, w.hit.p, self.kernel, of, |i, k| {
            // The BSDF of the reused arrival's own node (its frame, its material), as
            // MVF's rows take the BSDF of the node whose arrival they keep. (Through
            // `eval_world`: a Lambertian lobe reads two cosines and builds no frame; the
            // same bits as through the frame.)
            let u = &self.nodes[i as usize];
            let material = self.scene.material(u.hit.material, u.hit.uv);
            let fr = material.eval_world(u.hit.ns, out, u.wo, TransportMode::Radiance);
            if !fr.is_black() {
                // The flux leaving w reaches u through the medium w's continuation crossed.
                pairs.push((i, scale3(rgb::<T>(fr * w.next.transmittance()), cos * T::from_f64(k as f64))));
            }
        });
        (rgb::<T>(base), zero)
    }
}
