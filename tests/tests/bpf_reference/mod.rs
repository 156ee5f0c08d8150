//! The reference for `bidirectional_filtering.rs`'s f64 recursion tests: eq. (18) of
//! bidirectional path filtering written out for the union of camera and light segments,
//! in AREA measure at both ends of each reused segment, by scanning every node (no grid,
//! no denominators of the estimator's). Exponential in depth.
//!
//! The term of a reused segment s = (x, y) at a junction c is K(c → x) f_r(c) G(s) L(s) /
//! Σ_t p_t(s), with G = |n_x·ŝ| |n_y·ŝ| / d² (shading normal at x) and each technique's
//! density per unit area at x and at y:
//! - camera node t: K(t → x) [q_t p_σ(ŝ) |n_y·ŝ|/d² + c_t P_L p_A(y)] (p_A the light
//!   sampler's area density);
//! - light node t: K(t → y) q_t p*_σ(−ŝ) |n_x·ŝ|/d²;
//! - emission: N_L P_L p_pos(y) p_dir(−ŝ) |n_x·ŝ|/d²;
//! - with bridges: (1 / M) Σ_c K(c → x) Σ_l K(l → y).
//!
//! Every segment: a segment ending on a light carries its emitted part over all of its
//! techniques and its reflected part over all but the light samples (which end there).
//!
//! Merges only (`Naive::merges_only`, BPM's technique set; module notes of
//! `ember_core::estimators::filter::bidir`, "Merges only"):
//! - a camera junction c reuses its own continuation and light sample and the light
//!   segments whose start lies in its kernel; of the camera techniques only c's own
//!   count, at K(c → x), beside every light node's and the emission;
//! - the emission's samples, like light samples, carry L_e alone: the reflected part is
//!   over the techniques without both;
//! - a light segment s drawn by light node w's continuation (s arriving at light node u
//!   reached from w) merges at a camera junction with its reflected part times X_o / a_w
//!   over c's continuation and X_o (a_w w's own term at K(0), X_o the other light nodes'
//!   terms), its emitted part over the full sum;
//! - the camera junction's pair correction: a light node u merged there leaves D of the
//!   continuation a that reached the junction (D_a as the previous junction divides by
//!   it, its own techniques at K(0));
//! - a light junction (a light node's segment leaving light node w) follows its own
//!   chain: w's arriving segment alone, over w's predecessor's own technique and the
//!   emission;
//! - the segment leaving an emission node, the emission's sample, carries L_e alone:
//!   nothing merges at the emission node (the estimator merges there; the merges-only
//!   test's notes).

use ember_core::bsdf::TransportMode;
use ember_core::estimators::filter::Node;
use ember_core::estimators::filter::nodes::{NONE, NodeKind};
use ember_core::math::Frame;
use ember_core::scene::Scene;
use ember_core::segment::Kernel;
use ember_core::spectrum::Rgb;
use ember_core::transport::SurfacePoint;
use glam::Vec3;

pub fn f64s(c: Rgb) -> [f64; 3] {
    [c.r as f64, c.g as f64, c.b as f64]
}

/// The reference over one pass's nodes.
pub struct Naive<'a> {
    pub scene: &'a Scene,
    pub nodes: &'a [Node],
    pub kernel: Kernel,
    pub light_paths: f64,
    /// With bridges: 1 / M.
    pub bridge_choice: Option<f64>,
    /// BPM's technique set (`FilterReuse::Merges`).
    pub merges_only: bool,
}

/// A reusable segment: its start node, direction, light-side end and what it carries.
pub struct Seg {
    x: usize,
    dir: Vec3,
    y: Vec3,
    ny: Vec3,
    /// The light at y, if any.
    light: Option<u32>,
    /// Drawn by the emission or reflected by y: continues at node `next` (its L), or
    /// carries `constant` (a light sample: L_e alone).
    next: Option<usize>,
    constant: [f64; 3],
}

/// A pooled segment with its techniques' densities, each summed over its kind.
pub struct Pooled {
    s: Seg,
    /// Every camera node's continuation and light sample.
    camera: f64,
    /// The light samples' part of `camera`.
    nee: f64,
    /// Every light node's continuation.
    light: f64,
    /// The part of `light` of the light node whose continuation drew s (its sampler's
    /// density), 0 unless s arrives at a light node reached from one.
    own: f64,
    bridge: f64,
    emission: f64,
}

impl Pooled {
    /// Every technique (all segments reused).
    fn all(&self) -> f64 {
        self.camera + self.light + self.bridge + self.emission
    }
    /// All but the light samples (all segments reused).
    fn reflected(&self) -> f64 {
        self.all() - self.nee
    }
}

impl Naive<'_> {
    fn k(&self, t: &Node, p: Vec3, n: Vec3) -> f64 {
        self.kernel.scaled(t.kernel_scale).density(&t.hit, t.wo, p, n).0 as f64
    }
    fn pdf(&self, t: &Node, dir: Vec3, mode: TransportMode) -> f64 {
        let frame = Frame::from_normal(t.hit.ns);
        self.scene.materials[t.hit.material as usize].pdf(frame.to_local(t.wo), frame.to_local(dir), mode).0 as f64
    }
    /// |y − x|², at least 10⁻²⁰⁰. Every density of a segment and its G carry one 1/d², which
    /// cancels in the estimate, but a light sample can end exactly on x (a camera node on
    /// the emitting sphere, drawing the point its offset origin sits above: d² = 0, seen
    /// at this file's seed once the samplers' angles came from `sin_cos_turns`), and
    /// 0/0 would make the reference NaN where the core, whose densities are in a measure
    /// without 1/d² (`Bidirectional::emission_density`), is finite. The floor keeps the
    /// ratios and touches no segment of positive length.
    fn d2(&self, s: &Seg) -> f64 {
        (s.y.as_dvec3() - self.nodes[s.x].hit.p.as_dvec3()).length_squared().max(1e-200)
    }
    /// Light node t's density for segment s per unit area at x and y (0 unless t's
    /// kernel covers y and t continued).
    fn light_term(&self, t: &Node, s: &Seg, own: bool) -> f64 {
        if t.delta || t.kind != NodeKind::Light || !(t.next.q > 0.0) {
            return 0.0;
        }
        let x = &self.nodes[s.x];
        let k = self.k(t, s.y, s.ny);
        let p_sigma = if own { t.next.pdf as f64 } else { self.pdf(t, -s.dir, TransportMode::Importance) };
        k * t.next.q as f64 * p_sigma * x.hit.ng.dot(s.dir).abs() as f64 / self.d2(s)
    }
    /// Camera node t (index `i`)'s densities for segment s per unit area at x and y:
    /// (continuation, light sample), K(t → x) included.
    fn camera_term(&self, i: usize, t: &Node, s: &Seg) -> (f64, f64) {
        let x = &self.nodes[s.x];
        let k = self.k(t, x.hit.p, x.hit.ng);
        if k == 0.0 {
            return (0.0, 0.0);
        }
        let (d2, cos_y) = (self.d2(s), s.ny.dot(s.dir).abs() as f64);
        // The segment's own draw: the density its sampler reported.
        let own = i == s.x && s.dir == x.next.dir;
        let p_sigma = if own { x.next.pdf as f64 } else { self.pdf(t, s.dir, TransportMode::Radiance) };
        let mut nee = 0.0;
        if let (Some(id), true) = (s.light, t.light.attempted) {
            let light = &self.scene.lights[id as usize];
            // From the offset origin light sampling uses at x.
            let origin = SurfacePoint::new(x.hit, x.wo).reflection_origin();
            let p_solid = light.pdf_li(origin, s.dir, s.y, s.ny).0 as f64;
            nee = k * self.scene.light_pmf(id) as f64 * p_solid * cos_y / d2;
        }
        (k * t.next.q as f64 * p_sigma * cos_y / d2, nee)
    }
    /// Every technique's density for segment s, per unit area at x and y.
    fn techniques(&self, s: Seg) -> Pooled {
        let x = &self.nodes[s.x];
        let d2 = self.d2(&s);
        let cos_x = x.hit.ng.dot(s.dir).abs() as f64;
        let mut p = Pooled { camera: 0.0, nee: 0.0, light: 0.0, own: 0.0, bridge: 0.0, emission: 0.0, s };
        for (i, t) in self.nodes.iter().enumerate() {
            if t.delta {
                continue;
            }
            match t.kind {
                // A light node's twin is no technique of the segment that placed it.
                NodeKind::Camera if t.twin && x.kind == NodeKind::Light && t.pred as usize == p.s.x => {}
                NodeKind::Camera => {
                    let (bsdf, nee) = self.camera_term(i, t, &p.s);
                    p.camera += bsdf + nee;
                    p.nee += nee;
                }
                NodeKind::Light => {
                    let own = x.kind == NodeKind::Light && !x.bridge && x.pred as usize == i;
                    let term = self.light_term(t, &p.s, own);
                    p.light += term;
                    if own {
                        p.own = term;
                    }
                }
                _ => {}
            }
        }
        p.bridge = self.bridge_term(&p.s, None);
        if let Some(id) = p.s.light {
            let light = &self.scene.lights[id as usize];
            let (pos, dir) = light.pdf_le(p.s.y, p.s.ny, -p.s.dir);
            p.emission = self.light_paths * self.scene.light_pmf(id) as f64 * pos.0 as f64 * dir.0 as f64 * cos_x / d2;
        }
        p
    }
    /// With bridges: the bridge technique's density for segment s per unit area at x and
    /// y, (1 / M) Σ_c K(c → x) Σ_l K(l → y) over every bridge start c (the twin of a light
    /// node x left out: the segment arriving at x placed it) and every bridge end l, or
    /// with `end` the one end l alone (its share, for the pair correction).
    fn bridge_term(&self, s: &Seg, end: Option<&Node>) -> f64 {
        let Some(choice) = self.bridge_choice else { return 0.0 };
        let x = &self.nodes[s.x];
        if ember_core::estimators::filter::bridge::bridge_geometry(x.hit.p, s.y, s.ny).is_none() {
            return 0.0;
        }
        use ember_core::estimators::filter::bridge::{bridge_end, bridges_from};
        let own_twin = |c: &Node| c.twin && x.kind == NodeKind::Light && c.pred as usize == s.x;
        let starts: f64 = self.nodes.iter().filter(|c| bridges_from(c) && !own_twin(c)).map(|c| self.k(c, x.hit.p, x.hit.ng)).sum();
        let ends: f64 = match end {
            Some(l) if bridge_end(l) => self.k(l, s.y, s.ny),
            Some(_) => 0.0,
            None => self.nodes.iter().filter(|l| bridge_end(l)).map(|l| self.k(l, s.y, s.ny)).sum(),
        };
        choice * starts * ends
    }
    /// Every reusable segment of the pass with its techniques.
    pub fn pool(&self) -> Vec<Pooled> {
        let mut pool = Vec::new();
        for (i, u) in self.nodes.iter().enumerate() {
            if u.delta {
                continue;
            }
            match u.kind {
                NodeKind::Camera => {
                    if u.next.dir != Vec3::ZERO && !u.next.delta && u.next.node != NONE {
                        let y = &self.nodes[u.next.node as usize].hit;
                        pool.push(Seg { x: i, dir: u.next.dir, y: y.p, ny: y.ng, light: y.emitter, next: Some(u.next.node as usize), constant: [0.0; 3] });
                    }
                    if !u.light.radiance.is_black() {
                        let e = u.light.end;
                        pool.push(Seg { x: i, dir: u.light.dir, y: e.p, ny: e.n, light: Some(e.light), next: None, constant: f64s(u.light.radiance) });
                    }
                }
                NodeKind::Light => {
                    let (y, ny) =
                        if u.pred != NONE { (self.nodes[u.pred as usize].hit.p, self.nodes[u.pred as usize].hit.ng) } else { (u.source.p, u.source.n) };
                    let light = u.source.is_light().then_some(u.source.light);
                    pool.push(Seg { x: i, dir: u.wo, y, ny, light, next: Some(i), constant: [0.0; 3] });
                }
                NodeKind::Emission => {}
            }
        }
        pool.into_iter().map(|s| self.techniques(s)).collect()
    }
    /// G(s) = |n_x·ŝ| |n_y·ŝ| / d², shading normal at x.
    fn g(&self, s: &Seg) -> f64 {
        self.nodes[s.x].hit.ns.dot(s.dir).abs() as f64 * s.ny.dot(s.dir).abs() as f64 / self.d2(s)
    }
    /// f_r for s arriving at the junction: at a camera junction `centre`'s own BSDF toward
    /// `wo`; on the light side that of s's own node x.
    fn f_r(&self, centre: &Node, wo: Vec3, s: &Seg) -> [f64; 3] {
        let at = if centre.kind == NodeKind::Camera { centre } else { &self.nodes[s.x] };
        let frame = Frame::from_normal(at.hit.ns);
        f64s(self.scene.materials[at.hit.material as usize].eval(frame.to_local(wo), frame.to_local(s.dir), TransportMode::Radiance))
    }
    /// The junction node `v`'s segment leaves from and the direction back along it: a
    /// camera node's own; a light node's predecessor (a bridge's end, toward its start);
    /// `None` for the rest.
    fn junction(&self, v: usize) -> Option<(usize, Vec3)> {
        let node = &self.nodes[v];
        match node.kind {
            NodeKind::Camera => Some((v, node.wo)),
            NodeKind::Light if node.pred != NONE && node.bridge => Some((node.pred as usize, -node.wo)),
            NodeKind::Light if node.pred != NONE => Some((node.pred as usize, self.nodes[node.pred as usize].next.dir)),
            _ => None,
        }
    }

    /// L along node `v`'s segment with at most `depth` further segments.
    pub fn radiance(&self, pool: &[Pooled], v: usize, depth: u32) -> [f64; 3] {
        if self.merges_only {
            return self.radiance_merges(pool, v, depth);
        }
        let node = &self.nodes[v];
        let mut l = f64s(node.emitted);
        let Some((centre_index, wo)) = self.junction(v).filter(|_| depth > 0) else { return l };
        let centre = &self.nodes[centre_index];
        assert!(!centre.delta, "the scene has no Dirac material");
        // Segment a (v's own) for the pair correction, with D_a as its junction divides by it.
        let a = pool.iter().find(|p| match node.kind {
            NodeKind::Camera => node.pred != NONE && p.s.x == node.pred as usize && p.s.next == Some(v),
            _ => self.nodes[centre_index].kind == NodeKind::Light && p.s.x == v && p.s.next == Some(v),
        });
        let d_a = a.map(|a| if a.all() > a.reflected() && !node.emitted.is_black() { a.reflected() } else { a.all() });
        // A light junction: not its own arrival, not its own path's emission.
        let light_junction = centre.kind == NodeKind::Light && !node.delta;
        for p in pool {
            let s = &p.s;
            let x = &self.nodes[s.x];
            let k = self.k(centre, x.hit.p, x.hit.ng);
            if k == 0.0 || p.all() == 0.0 || (light_junction && x.kind == NodeKind::Light && s.x == centre_index) {
                continue;
            }
            // D_a without the light node that drew s (an instance s conditions), D_b
            // without the junction's own path's emission.
            let dep = match (a, d_a) {
                (Some(a), Some(d)) if x.kind == NodeKind::Light => d / (d - self.light_term(x, &a.s, false) - self.bridge_term(&a.s, Some(x))),
                _ => 1.0,
            };
            let own = if light_junction { p.emission / self.light_paths } else { 0.0 };
            let (all, reflected) = ((p.all() - own) / dep, (p.reflected() - own) / dep);
            // The BSDF at the junction vertex: the camera junction's own; on the light
            // side (a light node's or an emission node's segment), that of the node where
            // the reused segment arrives (x).
            let fr = self.f_r(centre, wo, s);
            let carried = match s.next {
                None => s.constant.map(|c| c / all),
                Some(n) => {
                    let (e, total) = (f64s(self.nodes[n].emitted), self.radiance(pool, n, depth - 1));
                    std::array::from_fn(|c| e[c] / all + if reflected > 0.0 { (total[c] - e[c]) / reflected } else { 0.0 })
                }
            };
            let g = self.g(s);
            for c in 0..3 {
                l[c] += k * fr[c] * g * carried[c];
            }
        }
        l
    }
    /// [`Self::radiance`] with merges only (the module notes' rules).
    fn radiance_merges(&self, pool: &[Pooled], v: usize, depth: u32) -> [f64; 3] {
        assert!(self.bridge_choice.is_none(), "merges only has no bridges");
        let node = &self.nodes[v];
        let mut l = f64s(node.emitted);
        let Some((centre_index, wo)) = self.junction(v).filter(|_| depth > 0) else { return l };
        let centre = &self.nodes[centre_index];
        assert!(!centre.delta && !node.twin && !node.bridge, "no Dirac material, twins or bridges");
        let mut add = |k: f64, p: &Pooled, carried: [f64; 3]| {
            let (fr, g) = (self.f_r(centre, wo, &p.s), self.g(&p.s));
            for c in 0..3 {
                l[c] += k * fr[c] * g * carried[c];
            }
        };
        // What segment s from node `n` carries: its emitted part over `all`, its reflected
        // part over `reflected` times `gain`.
        let carried = |s: &Seg, all: f64, reflected: f64, gain: f64| -> [f64; 3] {
            match s.next {
                None => s.constant.map(|c| c / all),
                Some(n) => {
                    let (e, total) = (f64s(self.nodes[n].emitted), self.radiance_merges(pool, n, depth - 1));
                    std::array::from_fn(|c| e[c] / all + if reflected > 0.0 { gain * (total[c] - e[c]) / reflected } else { 0.0 })
                }
            }
        };
        match centre.kind {
            NodeKind::Camera => {
                // Segment a, from the previous camera junction b to v, with D_a as b
                // divides by it: b's own techniques at K(b → b), the light nodes' and the
                // emission; its reflected part's where v emits.
                let a = pool.iter().find(|p| node.pred != NONE && p.s.x == node.pred as usize && p.s.next == Some(v));
                let a = a.filter(|a| self.nodes[a.s.x].kind == NodeKind::Camera);
                let d_a = a.map(|a| {
                    let (bsdf, nee) = self.camera_term(a.s.x, &self.nodes[a.s.x], &a.s);
                    let ends = a.emission + nee;
                    let all = bsdf + nee + a.light + a.emission;
                    if ends > 0.0 && !node.emitted.is_black() { all - ends } else { all }
                });
                for p in pool {
                    let x = &self.nodes[p.s.x];
                    if !(p.s.x == v || x.kind == NodeKind::Light) {
                        continue;
                    }
                    let k = self.k(centre, x.hit.p, x.hit.ng);
                    if k == 0.0 {
                        continue;
                    }
                    // The camera techniques: the junction's own, at K(centre → x).
                    let (bsdf, nee) = self.camera_term(v, centre, &p.s);
                    let all = bsdf + nee + p.light + p.emission;
                    if all == 0.0 {
                        continue;
                    }
                    // The pair correction: a merged light node x out of D_a.
                    let fix = match (a, d_a) {
                        (Some(a), Some(d)) if x.kind == NodeKind::Light => d / (d - self.light_term(x, &a.s, false)),
                        _ => 1.0,
                    };
                    let carried = if x.kind == NodeKind::Light && p.own > 0.0 {
                        // A light path's own chain: its drawer's K(0) term traded for
                        // the other light nodes' terms.
                        let others = p.light - p.own;
                        carried(&p.s, all, bsdf + others, others / p.own)
                    } else {
                        carried(&p.s, all, bsdf + p.light, 1.0)
                    };
                    add(k * fix, p, carried);
                }
            }
            NodeKind::Light => {
                // Its own chain: w's arriving segment alone, at K(w → w).
                let p = pool.iter().find(|p| p.s.x == centre_index && p.s.next == Some(centre_index)).expect("w's arriving segment");
                let all = p.own + p.emission;
                if all > 0.0 {
                    let k = self.k(centre, centre.hit.p, centre.hit.ng);
                    add(k, p, carried(&p.s, all, p.own, 1.0));
                }
            }
            // The segment leaving an emission node: drawn by the emission, it carries L_e
            // alone.
            NodeKind::Emission => {}
        }
        l
    }
}
