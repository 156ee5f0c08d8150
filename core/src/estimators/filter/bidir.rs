//! Eq. (18)'s weights over the union of camera and light segments (bidirectional path
//! filtering, Wang et al. 2025 §5 and Fig. 3).
//!
//! Every node stands for the segment that reached it. A camera node's segment runs from
//! its predecessor (or the camera) to it; a light node u's segment s = (x, y) runs from u
//! (x, the camera side) to its predecessor w (y, the light side: a light node, an
//! emission node, or the light itself). Radiance flows from y to x in both. The pool of
//! segments a junction reuses is every continuation and light-sampled segment leaving a
//! camera node, and every segment arriving at a light node, whose start x lies in the
//! junction's kernel.
//!
//! **Techniques.** A segment s = (x, y) with direction ŝ from x to y can be drawn
//! - by the continuation of every camera node t whose kernel covers x: K(t → x) q_t
//!   p_σ(ŝ | t) per area at x and solid angle at x;
//! - by the light sample of every such t, if y is on a light: K(t → x) c_t P_L p_L(ŝ | x);
//! - by the continuation of every light node t whose kernel covers y, the adjoint draw
//!   K(t → y) q_t p*_σ(−ŝ | t) per area at y and solid angle at y;
//! - by the emission, N_L samples, if y is on a light: N_L P_L p_pos(y) p_dir(−ŝ | y).
//!
//! In one measure, per area at x and solid angle at x (area at y = solid angle · d² /
//! |n_y·ŝ|; y's Dirac for point and spot lights, ŝ's for directional ones, as their
//! light samples report them):
//!
//!   D(s) = Σ_cam K [q p_σ + c P_L p_L] + Σ_light K q p*_σ |n_x·ŝ| / |n_y·ŝ| + N_L P_L p_pos p_dir |n_x·ŝ| J,
//!
//! J = 1 / |n_y·ŝ| on an area light, 1 / d² for a point light, 1 for lights at infinity
//! (p_pos their disk's). The term a junction at y_v (f_r there) gains from s is
//! K(y_v → x) f_r(ŝ) |n_x·ŝ| L(s) / D(s), as in multi-vertex path filtering, whose
//! weights these are when no light paths are traced.
//!
//! **Light samples end at the light.** A light-sampled segment carries L_e only; its
//! density belongs to the emitted part of the segment's radiance and not to what the
//! light's surface reflects. So a reused segment that ends on a light enters as
//! (L − L_e) / D_r + L_e / D, D_r = D without the light samples' terms: the emitted
//! part under every technique, the reflected part under those that can continue (a
//! pair flagged [`REFLECTED`]: no cancellation between two large terms).
//!
//! **Dirac vertices.** A segment into a Dirac vertex y (mirror, glass) continues there
//! with a Dirac draw, so the balance heuristic between the camera side (drawing the
//! segment into y) and the light side (drawing the segment beyond y, then the Dirac
//! bounce) would have to compare densities across the bounce. Instead, with light paths
//! traced, every segment path through a Dirac vertex reached from a non-Dirac camera
//! vertex is left to the light side: a camera continuation that ends at a Dirac vertex
//! is not reused (the camera ray's own chain through glass, from the pixel, still is),
//! and a light segment leaving a Dirac light node w is reused with the light side's
//! density carried through the bounce,
//!
//!   D(s) = D(s_w) |n_u·ŝ| / |n_w·ŝ_w|,
//!
//! D(s_w) of the segment that reached w (light techniques and emission only: nothing on
//! the camera side draws it), so that |n_u·ŝ| L(s) / D(s) is the light path's flux at u,
//! photon mapping's estimate. Such paths stay covered: light paths reach every Dirac
//! chain, and the segment beyond it reuses camera and light segments alike. A Dirac
//! light node passes on its arriving segment's radiance with the throughput of its
//! adjoint draw (refraction's η² factors cancel between entering and leaving a medium;
//! reused segments start in the light's medium). Without light paths (β = 0) the
//! camera side keeps these paths as multi-vertex path filtering does.
//!
//! **Light junctions.** A camera junction's estimate of L is unbiased given the junction:
//! every segment it reuses is either drawn from it (its own continuation and light
//! sample: techniques conditioned on it) or independent of it. A light node's is not if
//! it reuses the segment that arrived at it, because that segment placed the junction:
//! its start sits at K(0) for certain, not with the density D assumes. Counted anyway, a
//! light-traced chain was weighted against the camera's as if both were present wherever
//! a kernel held a light node, and the image came out too bright by up to ~25 % where
//! kernels hold few nodes (small radii, few light paths; docs/bidirectional-filtering.md,
//! "Small kernels"), a bias that grew as the kernel shrank. So:
//! - a light junction does not reuse its own arriving segment, and counts the emission
//!   technique without its own path (N_L − 1 samples in its pool: D_b − D_b,emit / N_L),
//!   unless the row is a Dirac light node's: only the light side draws that segment, so
//!   its chain is photon filtering's, whose own arrival matches its kernel count (and
//!   without it, paths from a diffuse vertex through glass to the light are lost);
//! - a reused light segment b conditions the light node u that it reached (u's position is
//!   b's start), so u's term K(u → y_a) q_u p*_σ |n_x·ŝ| / |n_y·ŝ| leaves D_a for that
//!   pair: the pair (a, b) enters over (D_a − D_a,u) D_b, a factor in b's row coefficient.
//!
//! **The BSDF at a light junction.** A junction's BSDF is the one where its incoming
//! segment arrives (eq. 6: f_r at y_i). At a camera junction that is the junction's own
//! node, whose arrival it keeps. At a light junction (a light or emission node's segment
//! s, leaving w) the incoming segments are the reused ones, so each pair takes the BSDF
//! of the reused segment's own node u, with s's direction as the outgoing one. Taken at
//! w, it was the lobe that drew s: on a glossy surface that curves within the kernel
//! (spot_mirror's sphere, GGX α = 0.02), neighbours' lobes miss ŝ, D(s) holds little more
//! than w's own technique, and every arrival in the kernel met w's lobe, so the light
//! leaving w was counted once per arrival (the room 60× too bright;
//! `host-cli/tests/filter_scenes.rs`). On diffuse scenes the two agree.
//!
//! **Merges only** ([`crate::estimators::FilterReuse::Merges`], the reduction to BPM). A
//! camera junction reuses its own continuation and light sample and merges the light
//! segments in its kernel; a light junction follows its own path. A merged segment
//! s = (x, y) leaving light node w at y is the light technique's sample, whose density is
//! the marginal λ(w) q p*, estimated by the light nodes near w. Counting w itself in that
//! estimate, with its own chain's K(0) (the first light junction's) in L(s), made the
//! chain its own density estimate: with N other light nodes near w, a merge weighed
//! K(0) a / (K A + (1 + N) K(0) a) against the exact λ a / (K A + λ a) (A the camera
//! junction's density, a = q p*). In the sparse limit it was counted beside the camera's
//! path at a / (A + a) (the image 13–19 % too bright at 0.1–0.2 pixel footprints). Now a
//! chain merges with its reflected part times X_o / (K(0) a), X_o the other light nodes'
//! terms, over the junction's techniques, the emission and X_o. By Mecke's formula (given
//! a light node at w, the others are distributed as the light nodes near any point), the
//! merges' mean weight E[N / (α + N)], α = K A / (K(0) a), is exactly what the camera's
//! continuation loses to the light nodes near its end, E[1 − α / (α + N)]. The pair
//! correction above applies to camera rows as well: the light node merged at the next
//! junction leaves D of the continuation that reached it (without: −3.6 % at 0.5
//! footprints with β = 4). The emitted part of a merged segment that ends on a
//! reflective emitter keeps its weight over the full D (not corrected).
//!
//! **Bridge segments** ([`crate::estimators::FilterReuse::Bridges`], the segment paper's
//! §6.4): each camera node c that may take another segment joins one of the pass's M
//! bridge ends (non-Dirac light nodes), drawn uniformly, by a shadow ray. The bridge is a
//! light-kind node at c whose segment runs to its end l: reused like a light segment
//! arriving at c, its radiance l's reflection toward c from l's row (a light junction).
//! Its technique draws a segment from x to y with density (1 / M) Σ_c K(c → x)
//! Σ_l K(l → y) per area at x and at y: every D gains (1 / M) Σ K_c Σ K_l d² / |n_y·ŝ|,
//! the two sums taken in the grid queries D already makes. A bridge end u near y_a is
//! also a light node b reached, so the pair correction removes u's share of it from D_a
//! along with its continuation's term (without: −3.9 % at 0.5 footprints, β = 1).
//!
//! **Twins** (2026-11-28). A camera junction's estimate of L covers its camera segments
//! whatever its kernel holds: its own continuation and light sample are there at K(0),
//! and its own term is in every neighbour's D. A light junction w had no technique of
//! its own among the camera segments it reuses, so their part of L reached it only
//! through the camera nodes that happened to lie in its kernel: with the drawer's K(0)
//! in each one's D, the sum over them has mean P(some node in the kernel) of the true
//! part (Mecke's formula: for m camera nodes per kernel, m E[1/(1 + N)] = 1 − e^(−m)
//! with N Poisson(m)), and the image came out 2–8 % dark where kernels hold about one
//! camera node and light nodes are dense. So every non-Dirac light node w whose
//! continuation reached a node gets a twin ([`super::nodes::trace_light_nodes`]): a
//! camera-kind node at w, arriving along w's continuation (so sampling the BSDF the
//! light junction evaluates), with its own light sample and continuation and a camera
//! walk after them. The twin is an ordinary camera node to every junction and every D;
//! at w's light junction it is the own technique at K(0), and the light junction is
//! complete as a camera junction is. One more camera path per light node.
//! - The segment arriving at a light node u placed u, and so u's twin: the twin's term
//!   leaves D of that segment, as the drawing node's own arrival leaves a light
//!   junction's pool.
//! - A twin's segments do *not* take the pair correction above. The twin's light node
//!   is a condition of the twin's sample, present whichever segment the twin draws;
//!   a reached light node is a consequence of the sample. Given every node of the
//!   pass, each complete pool's weights sum to 1 over its drawers, so D_a keeps its
//!   value (removing the twin's light node from D_a made the discrete model of
//!   `scripts/bpf-weight-model.py` 2–3 % too bright).
//! - A twin has no row: no segment arrives at it.
//!
//! Brute force (`scripts/bpf-weight-model.py`): a world of 40 cells, each cell one
//! kernel, the rules of this module applied literally, against the exact path sum. With
//! sparse camera nodes (10 camera and 40 light paths per pass): before 0.9895 ± 0.0037,
//! with twins 0.9965 ± 0.0027, MVF 0.9946 ± 0.0050; with the depth cap at 5 segments:
//! before 0.9923 ± 0.0036, with twins 1.0005 ± 0.0029 (MVF 0.9767 ± 0.0044, its cap's
//! bias). On the 16×16 Cornell box at depth 8, β = 1, r = 0.5 footprints the
//! image mean went from 0.955 to 0.976 of the path tracer's (β = 0: 0.987); what
//! remains is measured in docs/bidirectional-filtering.md, "Small kernels".

use alloc::vec::Vec;

use super::bridge::{self, bridge_end, bridges_from};
use super::graph::{REFLECTED, Real, Rgb3, add3, mul3, rgb, scale3};
use super::node_grid::{KernelOf, KernelPoint, Side};
use super::nodes::{LightEnd, NONE, Node, NodeKind};
use super::weights::Neighbourhood;
use crate::bsdf::TransportMode;
use crate::math::{Frame, Vec3};
use crate::spectrum::Rgb;

/// The denominators of a node's reusable segments under bidirectional filtering: MVF's
/// two ([`super::Denominators`]) and the light side's and the bridges' parts.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "wire", derive(serde::Serialize, serde::Deserialize))]
pub struct BidirDenominators {
    /// D of its continuation.
    pub next: f64,
    /// D of its light-sampled segment.
    pub light: f64,
    /// The light samples' part of `next`.
    pub next_light: f64,
    /// Light node: D of its arriving segment.
    pub arrive: f64,
    /// The light samples' part of `arrive`.
    pub arrive_light: f64,
    /// With merges only: D of the arriving segment at its own path's junction (its own
    /// technique and the emission).
    pub arrive_own: f64,
    /// With merges only: the part of `arrive` (and `arrive_own`) of the light node whose
    /// continuation drew the arriving segment, K(0) q p* |n_x·ŝ| / |n_y·ŝ|; 0 where the
    /// emission drew it.
    pub arrive_self: f64,
    /// With bridges: Σ K(c → x) over the camera nodes c that start bridges, x this node
    /// (the start of each of its reusable segments).
    pub starts: f64,
    /// The emission technique's part of `next`, `light` and `arrive` (all N_L light
    /// paths'), which a light junction counts without its own path's.
    pub next_emit: f64,
    pub light_emit: f64,
    pub arrive_emit: f64,
}

/// The weights of bidirectional filtering: the neighbourhood and the emission's sample
/// count N_L.
#[derive(Clone, Copy, Debug)]
pub struct Bidirectional<'a> {
    pub hood: Neighbourhood<'a>,
    /// Light paths traced in the pass (the emission technique's samples).
    pub light_paths: f64,
    /// Reuse only bidirectional photon mapping's segment paths
    /// ([`crate::estimators::FilterReuse::Merges`]).
    pub merges_only: bool,
    /// With bridge segments ([`crate::estimators::FilterReuse::Bridges`]): 1 / M, the chance
    /// that a camera node's bridge goes to a given one of the pass's M bridge ends.
    pub bridge_choice: Option<f64>,
}

/// The segment a whose row reuses b, as the pair correction reads it.
#[derive(Clone, Copy, Debug)]
struct PairSegment {
    /// D_a, as the junction that reuses a divides by it.
    d: f64,
    /// The node at a's start x_a.
    start: u32,
    /// With bridges: (1 / M) Σ K(c → x_a) d_a² / |n_ya·ŝ_a|, so that a bridge end u near
    /// y_a has the term K(u → y_a) times this in D_a.
    bridge: f64,
}

/// Where a reusable segment ends on its light side.
#[derive(Clone, Copy, Debug)]
enum Far {
    /// A surface point (position, geometric normal), on a light or not.
    Surface(Vec3, Vec3, LightEnd),
    /// A light without a surface there (point, spot, at infinity; or an area light whose
    /// emission node was not found).
    Light(LightEnd),
    /// Escaped: every light at infinity.
    Sky,
}

/// A segment leaving a node, as the camera-side techniques see it.
#[derive(Clone, Copy, Debug)]
struct CameraSegment {
    /// Its direction.
    dir: Vec3,
    /// P_L p_L of drawing it by a light sample from the node (0 if none can).
    nee: f64,
    /// Can a BSDF draw reach its end (not a Dirac light)?
    bsdf: bool,
    /// The node that drew it and its sampler's density, if a camera continuation.
    own: Option<(u32, f64)>,
}

impl Far {
    fn light(&self) -> Option<LightEnd> {
        match *self {
            Far::Surface(_, _, e) | Far::Light(e) if e.is_light() => Some(e),
            _ => None,
        }
    }
}

impl Bidirectional<'_> {
    fn nodes(&self) -> &[Node] {
        self.hood.nodes
    }

    /// P_L p_L of light sampling from `x` drawing `dir` toward light end `end` (P_L for a
    /// Dirac light, as its samples report it).
    fn light_sample_density(&self, x: Vec3, dir: Vec3, end: LightEnd) -> f64 {
        let scene = self.hood.scene;
        let light = &scene.lights[end.light as usize];
        let pmf = scene.light_pmf(end.light) as f64;
        if light.is_delta() { pmf } else { pmf * light.pdf_li(x, dir, end.p, end.n).0 as f64 }
    }

    /// Are camera continuations into Dirac vertices left to the light side?
    fn light_side_owns_dirac(&self) -> bool {
        self.light_paths > 0.0
    }

    /// D of light node `index`'s arriving segment under the light side's techniques
    /// only (light continuations and emission), carried through Dirac light nodes.
    fn light_side(&self, index: u32, own_only: bool) -> f64 {
        let nodes = self.nodes();
        let u = &nodes[index as usize];
        let dir = u.wo;
        if u.pred != NONE {
            let w = &nodes[u.pred as usize];
            if w.delta && w.kind == NodeKind::Light {
                let cos_w = w.hit.ng.dot(w.wo).abs() as f64;
                return if cos_w > 1e-7 { self.light_side(u.pred, own_only) * u.hit.ng.dot(dir).abs() as f64 / cos_w } else { 0.0 };
            }
        }
        let far = self.arriving_far(u);
        let own = if u.pred != NONE && !u.bridge && nodes[u.pred as usize].kind == NodeKind::Light { u.pred } else { NONE };
        let mut d = 0.0;
        if let Far::Surface(py, ny, _) = far {
            d += self.light_techniques(u, py, ny, dir, own, own_only).0;
        }
        if far.light().is_some() {
            d += self.emission_density(u, dir, far);
        }
        d
    }

    /// The light-side end of light node `u`'s arriving segment.
    fn arriving_far(&self, u: &Node) -> Far {
        if u.pred != NONE {
            // On a light, the end is the node's point (the emission node's, not the
            // emission sample's: one point for every density).
            let w = &self.nodes()[u.pred as usize].hit;
            let end = if u.source.is_light() { LightEnd { light: u.source.light, p: w.p, n: w.ng } } else { u.source };
            Far::Surface(w.p, w.ng, end)
        } else if u.source.is_light() && self.hood.scene.lights[u.source.light as usize].has_area() {
            Far::Surface(u.source.p, u.source.n, u.source)
        } else {
            Far::Light(u.source)
        }
    }

    /// N_L P_L p_pos p_dir |n_x·ŝ| J: the emission technique's density of a segment from
    /// `x` along `dir` ending at `far`, in D's measure.
    fn emission_density(&self, x: &Node, dir: Vec3, far: Far) -> f64 {
        let scene = self.hood.scene;
        let cos_x = x.hit.ng.dot(dir).abs() as f64;
        let one = |end: LightEnd| -> f64 {
            let light = &scene.lights[end.light as usize];
            let (pos, pdir) = light.pdf_le(end.p, end.n, -dir);
            let j = if light.is_infinite() {
                1.0
            } else if light.is_delta_position() {
                1.0 / (end.p - x.hit.p).length_squared().max(1e-12) as f64
            } else {
                let c = end.n.dot(dir).abs() as f64;
                if c > 1e-7 { 1.0 / c } else { 0.0 }
            };
            scene.light_pmf(end.light) as f64 * pos.0 as f64 * pdir.0 as f64 * j
        };
        let sum = match far {
            Far::Sky => scene.infinite_lights().map(|(id, _)| one(LightEnd { light: id, p: Vec3::ZERO, n: Vec3::ZERO })).sum(),
            f => f.light().map_or(0.0, one),
        };
        self.light_paths * sum * cos_x
    }

    /// Σ over camera nodes t whose kernel covers `x`: K(t → x) [q_t p_σ(dir | t) (if
    /// `bsdf`) + c_t `nee`], with node `own`'s continuation density replaced by the one
    /// its sampler reported, for each of the `N` segments leaving `x` in `segments`
    /// (one grid query for all: a camera node's continuation and light sample share
    /// their kernel neighbours). Returns per segment (all, light samples' part, and
    /// Σ K(t → x) over the camera nodes that start bridges, 0 without bridges).
    ///
    /// The twin of light node `twin_of` ([`NONE`] for none) is left out: with x a light
    /// node, the segment arriving at x placed x and so its twin (module notes, "Twins").
    fn camera_techniques<const N: usize>(&self, x: &Node, segments: [CameraSegment; N], twin_of: u32) -> [(f64, f64, f64); N] {
        let mut sums = [(0.0, 0.0, 0.0); N];
        let xp = KernelPoint::of(x);
        // (The camera side's grid holds camera-kind nodes only.)
        let of = KernelOf::Nodes { x: xp.p, nx: xp.side };
        self.hood.grid.query_kernel(Some(Side::Camera), x.hit.p, self.hood.kernel, of, |i, k| {
            let k = k as f64;
            let t = &self.nodes()[i as usize];
            if t.twin && t.pred == twin_of {
                return;
            }
            let starts = self.bridge_choice.is_some() && bridges_from(t);
            for (s, (all, nee_part, start)) in segments.iter().zip(sums.iter_mut()) {
                if s.bsdf {
                    let p = match s.own {
                        Some((o, pdf)) if o == i => self.hood.own_pdf(t, s.dir, TransportMode::Radiance, pdf as f32),
                        _ => self.hood.bsdf_pdf(t, s.dir, TransportMode::Radiance),
                    };
                    *all += k * t.next.q as f64 * p;
                }
                if t.light.attempted && s.nee > 0.0 {
                    *all += k * s.nee;
                    *nee_part += k * s.nee;
                }
                if starts {
                    *start += k;
                }
            }
        });
        sums
    }

    /// What [`Self::camera_techniques`] needs of a segment leaving x along `dir` to
    /// `far`: its light sample density `nee`, and node `own`'s sampler density.
    fn camera_segment(&self, dir: Vec3, far: Far, nee: f64, own: Option<(u32, f64)>) -> CameraSegment {
        CameraSegment { dir, nee, bsdf: !self.delta_end(far), own }
    }

    /// Σ over light nodes t whose kernel covers y = (`py`, `ny`): K(t → y) q_t p*_σ(−dir |
    /// t) · |n_x·ŝ| / |n_y·ŝ|, node `own`'s density replaced by its sampler's (`own_only`:
    /// node `own` alone).
    ///
    /// Also Σ K(t → y) over the bridge ends (0 without bridges or with `own_only`).
    fn light_techniques(&self, x: &Node, py: Vec3, ny: Vec3, dir: Vec3, own: u32, own_only: bool) -> (f64, f64) {
        let cos_y = ny.dot(dir).abs() as f64;
        if !(cos_y > 1e-7) {
            return (0.0, 0.0);
        }
        let (mut sum, mut ends) = (0.0, 0.0);
        let bridges = self.bridge_choice.is_some() && !own_only;
        // The kernels first, without the nodes: most neighbours are skipped without
        // reading theirs (reading every light node in the ball was a fifth of a pass on
        // the Cornell box). (The light side's grid holds light nodes only.)
        self.hood.grid.query_kernel(Some(Side::Light), py, self.hood.kernel, KernelOf::Nodes { x: py, nx: ny }, |i, k| {
            if own_only && i != own {
                return;
            }
            let k = k as f64;
            let t = &self.nodes()[i as usize];
            if bridges && bridge_end(t) {
                ends += k;
            }
            sum += self.light_term_at(t, k, dir, i == own);
        });
        (sum * x.hit.ng.dot(dir).abs() as f64 / cos_y, ends)
    }

    /// The bridge technique's density in D's measure for a segment from `x` to the
    /// surface point (`py`, `ny`), given Σ K over the bridge starts around x and the
    /// bridge ends around y: (1 / M) Σ K_start Σ K_end d² / |n_y·ŝ| (area at y to solid
    /// angle at x).
    fn bridge_density(&self, x: &Node, py: Vec3, ny: Vec3, starts: f64, ends: f64) -> f64 {
        self.bridge_choice.map_or(0.0, |choice| bridge::density(choice, starts, ends, x.hit.p, py, ny))
    }

    /// One light node t's K(t → y) q_t p*_σ(−dir | t) for a segment along `dir` ending at
    /// y = (`py`, `ny`) (its sampler's density if `own`); 0 for nodes that cannot draw it.
    fn light_term(&self, t: &Node, py: Vec3, ny: Vec3, dir: Vec3, own: bool) -> f64 {
        if t.delta || t.kind != NodeKind::Light || !(t.next.q > 0.0) {
            return 0.0;
        }
        self.light_term_at(t, self.hood.kernel_at(t, py, ny), dir, own)
    }

    /// [`Self::light_term`] with K(t → y) = `k` given.
    fn light_term_at(&self, t: &Node, k: f64, dir: Vec3, own: bool) -> f64 {
        if t.delta || t.kind != NodeKind::Light || !(t.next.q > 0.0) || !(k > 0.0) {
            return 0.0;
        }
        let p = if own { self.hood.own_pdf(t, -dir, TransportMode::Importance, t.next.pdf) } else { self.hood.bsdf_pdf(t, -dir, TransportMode::Importance) };
        k * t.next.q as f64 * p
    }

    /// D of a segment leaving node `x` along `dir` to `far`, and the part of it whose
    /// samples carry L_e alone (light samples; with merges only, the emission too). With
    /// merges only, the camera techniques are the junction's and left to the row.
    /// Also Σ K(c → x) over the bridge starts c (0 without bridges).
    /// `camera`: the segment's [`Self::camera_techniques`] (unread with merges only).
    fn sum(&self, x: &Node, dir: Vec3, far: Far, camera: (f64, f64, f64), own_light: u32) -> (f64, f64, f64, f64) {
        let (mut d, mut emitted_only, starts) = if self.merges_only { (0.0, 0.0, 0.0) } else { camera };
        if let Far::Surface(py, ny, _) = far {
            let (light, ends) = self.light_techniques(x, py, ny, dir, own_light, false);
            d += light + self.bridge_density(x, py, ny, starts, ends);
        }
        let mut emission = 0.0;
        if far.light().is_some() || matches!(far, Far::Sky) {
            emission = self.emission_density(x, dir, far);
            d += emission;
            if self.merges_only {
                emitted_only += emission;
            }
        }
        (d, emitted_only, emission, starts)
    }

    /// Does a segment to `far` end at a Dirac light (no BSDF draw reaches it)?
    fn delta_end(&self, far: Far) -> bool {
        far.light().is_some_and(|e| self.hood.scene.lights[e.light as usize].is_delta())
    }

    /// With merges only: the junction c's own techniques for a segment leaving node `x`
    /// along `dir` (its continuation, q p_σ, unless the segment ends at a Dirac light, and
    /// its light sample, c P_L p_L = `nee`), times k = K(c → x); `own_pdf` replaces p_σ
    /// for c's own continuation. Returns (all, light samples' part).
    fn junction(&self, c: &Node, k: f64, dir: Vec3, nee: f64, bsdf: bool, own_pdf: Option<f64>) -> (f64, f64) {
        let mut all = 0.0;
        if bsdf {
            let p =
                own_pdf.map_or_else(|| self.hood.bsdf_pdf(c, dir, TransportMode::Radiance), |p| self.hood.own_pdf(c, dir, TransportMode::Radiance, p as f32));
            all += k * c.next.q as f64 * p;
        }
        let n = if c.light.attempted { k * nee } else { 0.0 };
        (all + n, n)
    }

    /// The denominators of node `index`'s reusable segments: a camera node's
    /// continuation and light sample, a light node's arriving segment.
    pub fn denominators(&self, index: u32) -> BidirDenominators {
        let mut d = BidirDenominators::default();
        let nodes = self.nodes();
        let u = &nodes[index as usize];
        if u.kind == NodeKind::Light && (u.delta || (u.pred != NONE && nodes[u.pred as usize].delta && nodes[u.pred as usize].kind == NodeKind::Light)) {
            // Through a Dirac light node, or into one: the light side's density alone.
            d.arrive = self.light_side(index, self.merges_only);
            d.arrive_own = d.arrive;
            return d;
        }
        if u.delta {
            return d;
        }
        match u.kind {
            NodeKind::Camera => {
                // Its continuation and its light sample, each with its far end and its
                // camera-side query; both queries in one pass over the kernel neighbours.
                let next = &u.next;
                let next_far = (next.dir != Vec3::ZERO && !next.delta).then(|| {
                    let far = if next.node != NONE {
                        let y = &nodes[next.node as usize].hit;
                        Far::Surface(y.p, y.ng, LightEnd::at_surface(y))
                    } else {
                        Far::Sky
                    };
                    (far, self.camera_segment(next.dir, far, next.light_pdf as f64, Some((index, next.pdf as f64))))
                });
                let light = &u.light;
                let light_far = (light.dir != Vec3::ZERO).then(|| {
                    let end = light.end;
                    let far = if self.hood.scene.lights[end.light as usize].has_area() { Far::Surface(end.p, end.n, end) } else { Far::Light(end) };
                    (far, self.camera_segment(light.dir, far, light.pdf as f64, None))
                });
                // A missing segment queries as one no technique can draw (it adds nothing).
                let idle = CameraSegment { dir: Vec3::ZERO, nee: 0.0, bsdf: false, own: None };
                let [next_cam, light_cam] = if self.merges_only || (next_far.is_none() && light_far.is_none()) {
                    [(0.0, 0.0, 0.0); 2]
                } else {
                    self.camera_techniques(u, [next_far.map_or(idle, |f| f.1), light_far.map_or(idle, |f| f.1)], NONE)
                };
                if let Some((far, _)) = next_far {
                    (d.next, d.next_light, d.next_emit, d.starts) = self.sum(u, next.dir, far, next_cam, NONE);
                }
                if let Some((far, _)) = light_far {
                    (d.light, _, d.light_emit, d.starts) = self.sum(u, light.dir, far, light_cam, NONE);
                }
            }
            NodeKind::Light => {
                let dir = u.wo;
                let far = self.arriving_far(u);
                let origin = crate::transport::SurfacePoint::new(u.hit, u.wo).reflection_origin();
                let nee = far.light().map_or(0.0, |end| self.light_sample_density(origin, dir, end));
                let own = if u.pred != NONE && !u.bridge && nodes[u.pred as usize].kind == NodeKind::Light { u.pred } else { NONE };
                let camera = if self.merges_only { (0.0, 0.0, 0.0) } else { self.camera_techniques(u, [self.camera_segment(dir, far, nee, None)], index)[0] };
                (d.arrive, d.arrive_light, d.arrive_emit, d.starts) = self.sum(u, dir, far, camera, own);
                if self.merges_only {
                    // A light junction reuses its own path alone: its own technique and
                    // the emission.
                    if let Far::Surface(py, ny, _) = far {
                        d.arrive_self = self.light_techniques(u, py, ny, dir, own, true).0;
                    }
                    d.arrive_own = d.arrive_light + d.arrive_self;
                }
            }
            NodeKind::Emission => {}
        }
        d
    }

    /// This row's segment a for the pair correction, or `None` where it does not apply
    /// (no light paths, the primary ray, Dirac chains, a light row with merges only).
    fn pair_segment(&self, index: u32, dens: &[BidirDenominators]) -> Option<PairSegment> {
        if !self.light_side_owns_dirac() {
            return None;
        }
        let nodes = self.nodes();
        let v = &nodes[index as usize];
        let emits = !v.emitted.is_black();
        let split = |all: f64, light: f64| if light > 0.0 && emits { all - light } else { all };
        match v.kind {
            NodeKind::Camera => {
                let pred = nodes.get(v.pred as usize)?;
                if pred.delta || pred.kind != NodeKind::Camera {
                    return None;
                }
                let d = &dens[v.pred as usize];
                let (mut all, mut light) = (d.next, d.next_light);
                if self.merges_only {
                    // D_a as the junction at the predecessor divides by: its own
                    // techniques at K(0) added to the light side's.
                    let p = KernelPoint::of(pred);
                    let (ja, jn) =
                        self.junction(pred, p.kernel(&self.hood.kernel, &p), pred.next.dir, pred.next.light_pdf as f64, true, Some(pred.next.pdf as f64));
                    (all, light) = (all + ja, light + jn);
                }
                Some(PairSegment { d: split(all, light), start: v.pred, bridge: self.bridge_factor(pred, d.starts, v) })
            }
            NodeKind::Light => {
                let w = nodes.get(v.pred as usize)?;
                // With merges only a light junction follows its own chain, whose D holds
                // the technique that drew it: nothing to correct.
                if self.merges_only || v.delta || w.delta || w.kind != NodeKind::Light {
                    return None;
                }
                let d = &dens[index as usize];
                Some(PairSegment { d: split(d.arrive, d.arrive_light), start: index, bridge: self.bridge_factor(v, d.starts, w) })
            }
            NodeKind::Emission => None,
        }
    }

    /// Light node u's term in D_a ([`Self::light_term`] converted as in
    /// [`Self::light_techniques`]): K(u → y_a) q_u p*_σ(wo_a | u) |n_xa·ŝ_a| / |n_ya·ŝ_a|,
    /// for segment a from x_a (`start`) to y_a (`centre`), `wo_a` pointing from y_a to x_a.
    ///
    /// With bridges, also u's share of the bridge technique's term when u is a bridge end.
    fn light_instance(&self, u: &Node, centre: &Node, a: &PairSegment, wo_a: Vec3) -> f64 {
        let cos_y = centre.hit.ng.dot(wo_a).abs() as f64;
        if !(cos_y > 1e-7) {
            return 0.0;
        }
        let start = &self.nodes()[a.start as usize];
        let bridge = if a.bridge > 0.0 && bridge_end(u) { self.hood.kernel_at(u, centre.hit.p, centre.hit.ng) * a.bridge } else { 0.0 };
        self.light_term(u, centre.hit.p, centre.hit.ng, -wo_a, false) * start.hit.ng.dot(wo_a).abs() as f64 / cos_y + bridge
    }

    /// [`PairSegment::bridge`] for a segment from `x` to `y`, `starts` = Σ K(c → x) over
    /// the bridge starts ([`BidirDenominators::starts`]; 0 without bridges).
    fn bridge_factor(&self, x: &Node, starts: f64, y: &Node) -> f64 {
        self.bridge_density(x, y.hit.p, y.hit.ng, starts, 1.0)
    }

    /// Node `index`'s row: L_e of its segment, the constant terms and the pairs.
    pub fn row<T: Real>(&self, index: u32, dens: &[BidirDenominators], pairs: &mut Vec<(u32, Rgb3<T>)>) -> (Rgb3<T>, Rgb3<T>) {
        pairs.clear();
        let nodes = self.nodes();
        let v = &nodes[index as usize];
        let emission = rgb::<T>(v.emitted);
        let zero = [T::zero(); 3];
        let (centre, wo) = match v.kind {
            NodeKind::Emission => return (zero, zero),
            // No segment arrives at a twin: nothing reads its L.
            NodeKind::Camera if v.twin => return (zero, zero),
            NodeKind::Camera => (v, v.wo),
            NodeKind::Light if v.pred == NONE => return (emission, zero),
            NodeKind::Light => {
                let w = &nodes[v.pred as usize];
                // A bridge leaves its end w toward its start.
                (w, if v.bridge { -v.wo } else { w.next.dir })
            }
        };
        let mut direct = zero;
        // A light node's radiance arrives through the medium its predecessor's continuation
        // crossed (a Dirac one has T in its throughput already).
        let arrival = if v.kind == NodeKind::Light && !v.bridge { centre.next.medium } else { None };
        if centre.delta {
            // Only the centre's own segment, with its Dirac draw's f |cos| / (q p).
            let c = rgb::<T>(centre.next.throughput);
            match centre.kind {
                NodeKind::Camera if centre.next.node != NONE => pairs.push((centre.next.node, c)),
                NodeKind::Camera => direct = mul3(c, rgb::<T>(centre.next.escaped)),
                NodeKind::Light => pairs.push((v.pred, c)),
                NodeKind::Emission => {}
            }
            return (arrival.map_or(emission, |t| mul3(emission, rgb::<T>(t))), direct);
        }
        if self.merges_only && centre.kind == NodeKind::Emission {
            // With merges only, the emission's samples carry L_e alone (D_r leaves the
            // emission out), as BPM's light sub-paths start with the emitted light: no
            // segment around the emission node is merged into this one. (Merging them
            // gave a reflected part over D_r, the junction's continuation alone: up to
            // 2.5e7× the reference in `bpf_merges_only_equals_the_area_measure_recursion_in_f64`.)
            return (arrival.map_or(emission, |t| mul3(emission, rgb::<T>(t))), zero);
        }
        let centre_index = if v.kind == NodeKind::Camera { index } else { v.pred };
        // The BSDF at the junction vertex: for a camera junction its own (the kept segment
        // arrives there); for a light junction the reused segment's own node, where that
        // segment arrives (module notes, "The BSDF at a light junction").
        let camera_junction = centre.kind == NodeKind::Camera;
        let frame = Frame::from_normal(centre.hit.ns);
        let material = self.hood.scene.material(centre.hit.material, centre.hit.uv);
        let wo_world = wo;
        let wo = frame.to_local(wo);
        // (A local direction's z is its dot with the shading normal, bit for bit: a
        // Lambertian lobe needs no frame.)
        let f = |u: &Node, dir: Vec3| {
            if camera_junction {
                material.eval_from_local(&frame, wo, dir, TransportMode::Radiance)
            } else {
                self.hood.scene.material(u.hit.material, u.hit.uv).eval_world(u.hit.ns, wo_world, dir, TransportMode::Radiance)
            }
        };
        let pair = self.pair_segment(index, dens);
        // A light junction (module notes): without its own arrival, and with its own
        // path's emission out of the emission technique's count.
        let light_junction = centre.kind == NodeKind::Light && !v.delta && !self.merges_only && self.light_side_owns_dirac();
        let own_path = if light_junction && self.light_paths > 0.0 { 1.0 / self.light_paths } else { 0.0 };
        let cp = KernelPoint::of(centre);
        let of = KernelOf::Centre { p: cp.p, n: cp.side, scale: cp.scale };
        self.hood.grid.query_kernel(None, centre.hit.p, self.hood.kernel, of, |i, k| {
            let up = &self.hood.points[i as usize];
            if up.kind == NodeKind::Emission {
                return;
            }
            // Merges only: a camera junction reuses its own segments and light segments,
            // a light junction its own chain.
            if self.merges_only && i != centre_index && (up.kind == NodeKind::Camera || centre.kind == NodeKind::Light) {
                return;
            }
            if light_junction && i == centre_index {
                // Its own arriving segment: the sample that placed it.
                return;
            }
            let k = k as f64;
            let u = &nodes[i as usize];
            let d = &dens[i as usize];
            let n = u.hit.ns;
            // A reused segment along `dir` with denominators (all, light samples' part),
            // reaching node `target` (its L) or carrying `constant`.
            // The pair correction D_a D_b / (D_a − dep) (D_b − own): `dep` the term in D_a
            // of the light node b reached, `emit` D_b's emission part, `own` one light
            // path's share of it at a light junction (module notes).
            // `chain`: with merges only, a light path's own chain merged at a camera
            // junction (module notes): the reflected part's D and the factor that trades the
            // chain's K(0) for the other light nodes' density.
            // `tr`: the segment's transmittance through an absorbing medium.
            #[allow(clippy::too_many_arguments)]
            let mut reuse = |dir: Vec3, all: f64, nee: f64, target: u32, constant: Rgb, dep: f64, emit: f64, chain: Option<(f64, f64)>, tr: Rgb| {
                let (reflected, gain) = chain.unwrap_or((all - nee, 1.0));
                if !(all > 0.0) {
                    return;
                }
                let fr = f(u, dir) * tr;
                if fr.is_black() {
                    return;
                }
                let own = emit * own_path;
                let a_fix = match pair {
                    Some(a) if dep > 0.0 && a.d > dep => a.d / (a.d - dep),
                    _ => 1.0,
                };
                let fix = |d_b: f64| if own > 0.0 && d_b > own { a_fix * d_b / (d_b - own) } else { a_fix };
                let (whole, part) = (fix(all), fix(reflected));
                let g = n.dot(dir).abs() as f64 * k;
                let c = rgb::<T>(fr);
                if target == NONE {
                    direct = add3(direct, scale3(mul3(c, rgb::<T>(constant)), T::from_f64(g * whole / all)));
                    return;
                }
                if chain.is_none() && !(reflected > 0.0) {
                    // Only light samples draw it: its emitted part alone.
                    direct = add3(direct, scale3(mul3(c, rgb::<T>(arriving_emission(nodes, target))), T::from_f64(g * whole / all)));
                    return;
                }
                let e = arriving_emission(nodes, target);
                let coefficient = if reflected > 0.0 { g * gain * part / reflected } else { 0.0 };
                if nee > 0.0 && !e.is_black() {
                    // The reflected part over D_r, the emitted part over D.
                    pairs.push((target | REFLECTED, scale3(c, T::from_f64(coefficient))));
                    direct = add3(direct, scale3(mul3(c, rgb::<T>(e)), T::from_f64(g * whole / all)));
                } else if coefficient > 0.0 {
                    pairs.push((target, scale3(c, T::from_f64(coefficient))));
                }
            };
            // The junction's own techniques, with merges only (camera junctions).
            let at_junction = self.merges_only && centre.kind == NodeKind::Camera;
            match u.kind {
                NodeKind::Camera => {
                    if u.next.dir != Vec3::ZERO && !u.next.delta {
                        let (ja, jn) =
                            if at_junction { self.junction(centre, k, u.next.dir, u.next.light_pdf as f64, true, Some(u.next.pdf as f64)) } else { (0.0, 0.0) };
                        if u.next.node != NONE && nodes[u.next.node as usize].delta && self.light_side_owns_dirac() {
                            // Into a Dirac vertex: the light side's (see the module notes).
                        } else if u.next.node != NONE {
                            reuse(u.next.dir, d.next + ja, d.next_light + jn, u.next.node, Rgb::ZERO, 0.0, d.next_emit, None, u.next.transmittance());
                        } else if !u.next.escaped.is_black() {
                            reuse(u.next.dir, d.next + ja, 0.0, NONE, u.next.escaped, 0.0, d.next_emit, None, Rgb::ONE);
                        }
                    }
                    if !u.light.radiance.is_black() {
                        let ja = if at_junction { self.junction(centre, k, u.light.dir, u.light.pdf as f64, !u.light.delta, None).0 } else { 0.0 };
                        reuse(u.light.dir, d.light + ja, 0.0, NONE, u.light.radiance, 0.0, d.light_emit, None, Rgb::ONE);
                    }
                }
                NodeKind::Light => {
                    let (mut ja, mut jn) = (0.0, 0.0);
                    if at_junction {
                        let far = self.arriving_far(u);
                        let origin = crate::transport::SurfacePoint::new(u.hit, u.wo).reflection_origin();
                        let nee = far.light().map_or(0.0, |end| self.light_sample_density(origin, u.wo, end));
                        (ja, jn) = self.junction(centre, k, u.wo, nee, !self.delta_end(far), None);
                    }
                    let all = if self.merges_only && centre.kind == NodeKind::Light { d.arrive_own } else { d.arrive + ja };
                    let nee = d.arrive_light + jn;
                    // A light path's own chain merged at a camera junction (merges only): its
                    // reflected part over the junction's techniques, the emission and the
                    // other light nodes' continuations, times (others) / (its own K(0) term).
                    let chain = (at_junction && d.arrive_self > 0.0).then(|| {
                        let others = (d.arrive - d.arrive_emit - d.arrive_self).max(0.0);
                        (all - d.arrive_self - nee, others / d.arrive_self)
                    });
                    let dep = pair.as_ref().map_or(0.0, |a| self.light_instance(u, centre, a, wo_world));
                    // u's own value has its arrival's transmittance.
                    reuse(u.wo, all, nee, i, Rgb::ZERO, dep, d.arrive_emit, chain, Rgb::ONE)
                }
                NodeKind::Emission => {}
            }
        });
        match arrival {
            Some(t) => {
                let t = rgb::<T>(t);
                for (_, c) in pairs.iter_mut() {
                    *c = mul3(*c, t);
                }
                (mul3(emission, t), mul3(direct, t))
            }
            None => (emission, direct),
        }
    }
}

/// The emission a node's row starts from, as it arrives there: a light node's (emitted by
/// its predecessor toward it) through the medium its predecessor's continuation crossed,
/// as its row applies it ([`Bidirectional::row`]'s arrival); a camera node's as it
/// leaves the node (the reusing segment carries its own T).
fn arriving_emission(nodes: &[Node], target: u32) -> Rgb {
    let v = &nodes[target as usize];
    match v.kind {
        NodeKind::Light if !v.bridge && v.pred != NONE => v.emitted * nodes[v.pred as usize].next.transmittance(),
        _ => v.emitted,
    }
}
