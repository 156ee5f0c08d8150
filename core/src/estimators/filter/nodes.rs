//! The segments one pass of multi-vertex path filtering samples: camera paths traced by
//! the sequential segment sampler (eq. 15) with virtual perturbation (each segment starts
//! where the previous one ended; the kernel is accounted for in the weights), one node per
//! segment end, with what the weights of eq. (18) need of it.

use alloc::vec::Vec;

use crate::bsdf::{Material, TransportMode};
use crate::geometry::{Ray, RayQuery, SurfaceHit, spawn_ray};
use crate::math::Vec3;
use crate::rng::{SampleStream, Stream};
use crate::scene::Scene;
use crate::spectrum::Rgb;
use crate::transport::walk::{Layout, Leave, PathState, Roulette, Walk, emitted, environment, shadow_ray};
use crate::transport::{Counters, RenderParams, SurfacePoint};

/// "No node".
pub const NONE: u32 = u32::MAX;

/// The camera walk: radiance, 8 random dimensions per bounce (roulette 1, light choice 1,
/// light point 2, lobe 1, direction 2, spare 1).
const CAMERA_WALK: Walk = Walk { mode: TransportMode::Radiance, layout: Layout { per_bounce: 8, light: 1, lobe: 4, roulette: 0 } };
/// The light walk: importance, the same blocks without the light sample (roulette 1,
/// lobe 1, direction 2).
const LIGHT_WALK: Walk = Walk { mode: TransportMode::Importance, layout: Layout { per_bounce: 8, light: 0, lobe: 1, roulette: 0 } };

/// The BSDF-sampled continuation segment leaving a node.
#[derive(Clone, Copy, Debug, Default)]
#[cfg_attr(feature = "wire", derive(serde::Serialize, serde::Deserialize))]
pub struct Continuation {
    /// Probability that it was attempted (roulette and the depth cap), q.
    pub q: f32,
    /// Unit direction; zero if none was drawn.
    pub dir: Vec3,
    /// Drawn from a Dirac lobe: only its own node may use it.
    pub delta: bool,
    /// f |cos| / p of the draw (what a Dirac continuation carries).
    pub throughput: Rgb,
    /// p_σ of the draw per solid angle, as the sampler reported it: the natural
    /// technique's density in the denominators (re-evaluating the BSDF's pdf can give 0
    /// for a direction its sampler drew, at roughness 1e-5).
    pub pdf: f32,
    /// The node it reached, or [`NONE`].
    pub node: u32,
    /// Radiance from the environment if it escaped.
    pub escaped: Rgb,
    /// P(light) · p_light(dir) per solid angle at the start, if a light sample could have
    /// drawn the same segment (it ended on an area light or escaped to the sky).
    pub light_pdf: f32,
    /// T = exp(−σ_t d) when the segment crossed an absorbing medium (`None`: T = 1). A
    /// Dirac continuation has it in `throughput` too; a reused one takes it from here.
    pub medium: Option<Rgb>,
}

impl Continuation {
    /// The segment's transmittance (1 outside media).
    #[inline]
    pub fn transmittance(&self) -> Rgb {
        self.medium.unwrap_or(Rgb::ONE)
    }
}

/// The light-sampled segment leaving a node (next-event estimation).
#[derive(Clone, Copy, Debug, Default)]
#[cfg_attr(feature = "wire", derive(serde::Serialize, serde::Deserialize))]
pub struct LightSegment {
    /// Was a light sample attempted (non-Dirac material, depth allows)?
    pub attempted: bool,
    /// Unit direction toward the light; zero if none was drawn.
    pub dir: Vec3,
    /// Radiance arriving along it (zero if occluded).
    pub radiance: Rgb,
    /// P(light) · p_light per solid angle at the start (for a point or spot light, P(light)).
    pub pdf: f32,
    /// A Dirac light (point, spot, directional): no BSDF draw reaches it.
    pub delta: bool,
    /// The sampled point on the light.
    pub end: LightEnd,
}

/// A segment's end on a light (what the emission and light-sampling techniques' densities
/// read): the light, the point and its normal (zero for point, spot and infinite lights).
#[derive(Clone, Copy, Debug)]
#[cfg_attr(feature = "wire", derive(serde::Serialize, serde::Deserialize))]
pub struct LightEnd {
    /// The light's index, or [`NONE`]: the end is on no light.
    pub light: u32,
    pub p: Vec3,
    pub n: Vec3,
}

impl Default for LightEnd {
    fn default() -> Self {
        Self { light: NONE, p: Vec3::ZERO, n: Vec3::ZERO }
    }
}

impl LightEnd {
    /// The end at surface point `hit`, if it lies on an emitter.
    pub fn at_surface(hit: &SurfaceHit) -> Self {
        hit.emitter.map_or(Self::default(), |id| Self { light: id, p: hit.p, n: hit.ng })
    }

    pub fn is_light(&self) -> bool {
        self.light != NONE
    }
}

/// Which walk a node belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "wire", derive(serde::Serialize, serde::Deserialize))]
pub enum NodeKind {
    /// A camera path's segment end (`wo` toward the camera).
    Camera,
    /// A light path's segment end (`wo` toward the light).
    Light,
    /// The point a light path left an area light from (bidirectional filtering): the
    /// centre of its first segment's row, neither reused nor a technique's condition.
    Emission,
}

/// One segment end of a camera or light path.
#[derive(Clone, Copy, Debug)]
#[cfg_attr(feature = "wire", derive(serde::Serialize, serde::Deserialize))]
pub struct Node {
    pub hit: SurfaceHit,
    /// Unit direction back along the segment that reached it.
    pub wo: Vec3,
    /// Camera node: L_e of the end back along the segment. Light node: L_e of the
    /// segment's light-side end toward it (the light's, for a first hit; for point and
    /// spot lights intensity / d²), zero unless that end is on a light.
    pub emitted: Rgb,
    /// All-Dirac material: it reuses nothing and is reused by nobody.
    pub delta: bool,
    /// Its kernel's radius over the pass's: below 1 on glossy materials
    /// ([`scale_kernels`]), 1 elsewhere.
    pub kernel_scale: f32,
    pub kind: NodeKind,
    /// A bridge segment (bidirectional filtering with bridges): a light-kind node at a
    /// camera node's point whose segment runs to the light node `pred`, drawn by the
    /// bridge technique rather than by `pred`'s continuation (`next` is empty).
    pub bridge: bool,
    /// A light node's twin (bidirectional filtering): a camera-kind node at light node
    /// `pred`'s point, arriving along `pred`'s continuation, whose own continuation and
    /// light sample give the light junction at `pred` the techniques of its own that a
    /// camera junction has ([`trace_light_nodes`]). No segment arrives at it: it has no
    /// row.
    pub twin: bool,
    /// The node whose continuation reached it, or [`NONE`] (a camera ray's hit; a light
    /// path's first hit from a light without an emission node).
    pub pred: u32,
    /// Light node: the arriving segment's light-side end, if on a light.
    pub source: LightEnd,
    pub next: Continuation,
    /// Camera node: its light-sampled segment.
    pub light: LightSegment,
}

impl Node {
    /// A node at `hit` reached along `-wo`, before its continuation is drawn.
    fn new(scene: &Scene, hit: SurfaceHit, wo: Vec3, kind: NodeKind, pred: u32) -> Self {
        Self {
            hit,
            wo,
            emitted: Rgb::ZERO,
            delta: scene.materials[hit.material as usize].is_delta(),
            kernel_scale: 1.0,
            kind,
            bridge: false,
            twin: false,
            pred,
            source: LightEnd::default(),
            next: Continuation { node: NONE, ..Continuation::default() },
            light: LightSegment::default(),
        }
    }
}

/// Give each node on a glossy material a kernel of its own, narrower than the pass's:
/// radius scale α / `glossy_alpha` for a microfacet roughness α below `glossy_alpha`
/// (floored at 10⁻³), 1 elsewhere; `glossy_alpha` = 0 leaves every scale at 1.
///
/// A kernel moves a segment's start by up to r. Through a glossy lobe of width ~α that
/// moves what the segment sees by an angle ~r/d, so a sharp highlight is smeared over
/// the kernel: on veach-mis (α = 0.01) a light's reflection 3 pixels wide spread over
/// ±4, the pixels around it 10⁴ times their reference. Each technique may have a kernel
/// of its own (the denominators sum K_t(t → x) over the techniques t), so a node's
/// kernel can shrink with its lobe: r_t ∝ α keeps the smear a fixed fraction of the lobe,
/// as the pass's r keeps it on diffuse surfaces. The scale shrinks over passes with r,
/// so the estimator stays consistent.
pub fn scale_kernels(scene: &Scene, glossy_alpha: f32, nodes: &mut [Node]) {
    if !(glossy_alpha > 0.0) {
        return;
    }
    for n in nodes {
        n.kernel_scale = near_specular(&scene.materials[n.hit.material as usize], glossy_alpha).unwrap_or(1.0);
    }
}

/// For a material of microfacet roughness α below `glossy_alpha` (near-specular), its
/// kernel scale α / `glossy_alpha` (floored at 10⁻³); `None` for every other material.
/// The one rule for "near-specular": [`scale_kernels`] narrows these nodes' kernels, and
/// PhF's camera side passes these vertices instead of gathering there.
#[inline]
pub(super) fn near_specular(material: &Material, glossy_alpha: f32) -> Option<f32> {
    material.roughness().and_then(|a| kernel_scale(a, glossy_alpha))
}

/// α / `glossy_alpha` clamped to [10⁻³, 1) where α < `glossy_alpha`.
#[inline]
fn kernel_scale(alpha: f32, glossy_alpha: f32) -> Option<f32> {
    (alpha < glossy_alpha).then(|| (alpha / glossy_alpha).max(1e-3))
}

/// Trace the camera paths of pixels `pixels` in pass `pass`, at most `max_segments`
/// segments each: their nodes go to `nodes` (indices local to it, `next.node` included),
/// and for each pixel `first` gets the index of the node its camera ray reached (or
/// [`NONE`]) and `sky` the environment radiance if it escaped.
#[allow(clippy::too_many_arguments)]
pub fn trace_camera_nodes<Q: RayQuery + ?Sized>(
    scene: &Scene,
    tracer: &Q,
    params: &RenderParams,
    max_segments: u32,
    pass: u32,
    pixels: core::ops::Range<u32>,
    nodes: &mut Vec<Node>,
    first: &mut Vec<u32>,
    sky: &mut Vec<Rgb>,
) -> Counters {
    let mut counters = Counters::default();
    let width = scene.camera.width().max(1);
    for pixel in pixels {
        let mut rng = SampleStream::for_sample(params.seed, Stream::Camera, pixel, pass, 0);
        // The film applies the pixel filter when the pass is committed.
        let primary = scene.camera.sample_ray(pixel % width, pixel / width, &mut rng);
        let (node, escaped) = match primary {
            Some(p) if max_segments >= 1 => walk(scene, tracer, params, max_segments, p.ray, &mut rng, nodes, &mut counters),
            _ => (NONE, Rgb::ZERO),
        };
        first.push(node);
        sky.push(escaped);
    }
    counters
}

/// P(light) · p_light per solid angle of light sampling from `origin` drawing `dir`, for
/// a segment ending at `hit` (on an area light) or escaping (`hit` = None).
pub fn light_density(scene: &Scene, origin: Vec3, dir: Vec3, hit: Option<&SurfaceHit>) -> f32 {
    match hit {
        Some(h) => h.emitter.map_or(0.0, |id| scene.light_pmf(id) * scene.lights[id as usize].pdf_li(origin, dir, h.p, h.ng).0),
        None => scene.infinite_lights().map(|(id, l)| scene.light_pmf(id) * l.pdf_li(origin, dir, Vec3::ZERO, Vec3::ZERO).0).sum(),
    }
}

/// One camera path on the one walk ([`crate::transport::walk`]); returns the index of its
/// first node (or [`NONE`]) and the environment radiance if the camera ray escaped.
#[allow(clippy::too_many_arguments)]
fn walk<Q: RayQuery + ?Sized>(
    scene: &Scene,
    tracer: &Q,
    params: &RenderParams,
    max_segments: u32,
    ray: Ray,
    rng: &mut SampleStream,
    nodes: &mut Vec<Node>,
    counters: &mut Counters,
) -> (u32, Rgb) {
    let first_dim = rng.dimension();
    let path = PathState::new(ray, Rgb::ONE, first_dim + CAMERA_WALK.layout.per_bounce);
    walk_on(scene, tracer, params, max_segments, path, NONE, rng, nodes, counters)
}

/// The camera walk from `path`'s ray on, its first hit the successor of node `parent`
/// (or a path's first node if [`NONE`]); returns that first node (or [`NONE`]) and the
/// environment radiance if the path's first ray escaped with no parent.
#[allow(clippy::too_many_arguments)]
fn walk_on<Q: RayQuery + ?Sized>(
    scene: &Scene,
    tracer: &Q,
    params: &RenderParams,
    max_segments: u32,
    mut path: PathState,
    origin: u32,
    rng: &mut SampleStream,
    nodes: &mut Vec<Node>,
    counters: &mut Counters,
) -> (u32, Rgb) {
    let mut parent = origin;
    let mut first = NONE;
    loop {
        let Some(hit) = CAMERA_WALK.trace(tracer, &path, counters) else {
            let env = environment(scene, path.ray.dir);
            if parent == NONE {
                return (NONE, env);
            }
            nodes[parent as usize].next.escaped = env;
            break;
        };
        let index = nodes.len() as u32;
        if parent == NONE {
            first = index;
        } else {
            nodes[parent as usize].next.node = index;
            // The continuation crossed an absorbing medium: it carries T.
            if let Some(t) = scene.transmittance(&path.ray, &hit) {
                nodes[parent as usize].next.throughput *= t;
                nodes[parent as usize].next.medium = Some(t);
            }
        }
        let sp = SurfacePoint::new(hit, -path.ray.dir);
        let mut node = Node::new(scene, hit, sp.wo, NodeKind::Camera, parent);
        node.emitted = emitted(scene, &hit, sp.wo);
        let leave = camera_step(scene, tracer, params, max_segments, &mut path, &sp, &mut node, rng, counters);
        nodes.push(node);
        if !leave {
            break;
        }
        parent = index;
    }
    // Light densities of continuations that ended on a light or escaped.
    fill_light_densities(scene, nodes, if origin != NONE { origin } else { first });
    (first, Rgb::ZERO)
}

/// A camera node's segments at `sp`: its light sample (shadow ray included) and its
/// continuation ([`continue_path`]); says whether the path goes on.
#[allow(clippy::too_many_arguments)]
fn camera_step<Q: RayQuery + ?Sized>(
    scene: &Scene,
    tracer: &Q,
    params: &RenderParams,
    max_segments: u32,
    path: &mut PathState,
    sp: &SurfacePoint,
    node: &mut Node,
    rng: &mut SampleStream,
    counters: &mut Counters,
) -> bool {
    let material = sp.material(scene);
    let more = path.segments < max_segments && params.max_depth.allows(path.segments + 1);

    // The light-sampled segment (next-event estimation), shadow ray included.
    if more && !node.delta && scene.light_selection.is_some() {
        node.light.attempted = true;
        if let Some(draw) = CAMERA_WALK.draw_light(scene, path, sp.reflection_origin(), rng) {
            let ls = &draw.sample;
            node.light.dir = ls.wi;
            node.light.pdf = draw.pmf * ls.pdf.0;
            node.light.delta = ls.is_delta;
            node.light.end = LightEnd { light: draw.light as u32, p: ls.p, n: ls.n };
            counters.rays += 1;
            if !tracer.occluded(&shadow_ray(&sp.hit, ls)) {
                // Across an absorbing medium (a rough dielectric's interior), T.
                let hit = &sp.hit;
                node.light.radiance = ls.radiance * scene.transmittance_to(ls.p, hit.p, hit.ng, hit.material).unwrap_or(Rgb::ONE);
            }
        }
    }

    continue_path(params, path, sp, &material, CAMERA_WALK, more, node, rng)
}

/// For each continuation along the path starting at node `first`: the density with which
/// light sampling from its start draws it.
fn fill_light_densities(scene: &Scene, nodes: &mut [Node], first: u32) {
    let mut i = first;
    while i != NONE {
        let n = nodes[i as usize];
        if n.next.dir != Vec3::ZERO && !n.next.delta {
            let origin = SurfacePoint::new(n.hit, n.wo).reflection_origin();
            let end = (n.next.node != NONE).then(|| nodes[n.next.node as usize].hit);
            nodes[i as usize].next.light_pdf = light_density(scene, origin, n.next.dir, end.as_ref());
        }
        i = n.next.node;
    }
}

/// Trace light paths `paths` of pass `pass`, at most `max_segments` segments each. Each
/// hit is a light node (`wo` points back toward the light; no light sample): it goes to
/// `nodes`, its predecessor on its own path to `pred` (also in [`Node::pred`]), and its
/// base flux to `base`: β₀ / `paths_per_pass` for a first hit, β₀ = L_e |cos| /
/// (P(light) p_pos p_dir) (the emission technique, `paths_per_pass` samples of it), zero
/// otherwise (photon filtering's A₀). Each node also records the arriving segment's L_e
/// and light-side end ([`Node::emitted`], [`Node::source`]).
///
/// With `emission_nodes` (bidirectional filtering), a path leaving an area light starts
/// with an [`NodeKind::Emission`] node at its origin (found by a ray back from the first
/// hit along the unoccluded emission segment), the first hit's predecessor; the centre
/// of the row of radiance reflected by the light's own surface. Indices are local to
/// `nodes`.
///
/// With `twins` (bidirectional filtering), after each path every non-Dirac light node w
/// whose continuation reached a node gets a **twin**: a camera node at w ([`Node::twin`],
/// `pred` = w) arriving along w's continuation, followed by a camera walk from it (its
/// light sample and continuation at segment 2, so at most `max_segments` − 2 segments).
/// The light junction at w (the row of w's successor) then reuses a continuation drawn
/// from itself at K(0), as a camera junction does (module notes of [`super::bidir`],
/// "Twins"). Their nodes follow the path's, with [`NONE`] and zero in `pred` and `base`.
#[allow(clippy::too_many_arguments)]
pub fn trace_light_nodes<Q: RayQuery + ?Sized>(
    scene: &Scene,
    tracer: &Q,
    params: &RenderParams,
    max_segments: u32,
    paths_per_pass: u32,
    pass: u32,
    paths: core::ops::Range<u32>,
    emission_nodes: bool,
    twins: bool,
    nodes: &mut Vec<Node>,
    pred: &mut Vec<u32>,
    base: &mut Vec<Rgb>,
) -> Counters {
    let mut counters = Counters::default();
    let Some(table) = scene.light_selection.as_ref() else { return counters };
    for path in paths {
        let mut rng = SampleStream::for_sample(params.seed, Stream::Light, path, pass, 0);
        let chosen = table.sample(rng.next_f32());
        let light = &scene.lights[chosen.index];
        let (u_pos, u_dir) = (rng.next_2d(), rng.next_2d());
        if max_segments == 0 {
            continue;
        }
        let Some(es) = light.sample_le(u_pos, u_dir) else { continue };
        let pdf_pos = chosen.pmf * if es.delta_pos { 1.0 } else { es.pdf_pos.0 };
        if !(pdf_pos > 0.0) || !es.pdf_dir.is_positive() || es.radiance.is_black() {
            continue;
        }
        let cos0 = if es.n == Vec3::ZERO { 1.0 } else { es.n.dot(es.dir).abs() };
        let beta0 = es.radiance * (cos0 / (pdf_pos * es.pdf_dir.0));
        let ray = if es.n == Vec3::ZERO { Ray::new(es.p, es.dir, f32::INFINITY) } else { spawn_ray(es.p, es.n, es.dir) };
        let start = Emission { light: chosen.index as u32, sample: es, beta0, paths_per_pass, with_node: emission_nodes && light.has_area() };
        let first = nodes.len();
        let out = LightNodes { nodes: &mut *nodes, pred: &mut *pred, base: &mut *base };
        light_walk(scene, tracer, params, max_segments, ray, start, &mut rng, out, &mut counters);
        if twins {
            let before = nodes.len();
            trace_twins(scene, tracer, params, max_segments, pass, path, first..before, nodes, &mut counters);
            let added = nodes.len() - before;
            pred.extend(core::iter::repeat_n(NONE, added));
            base.extend(core::iter::repeat_n(Rgb::ZERO, added));
        }
    }
    counters
}

/// The twins of light nodes `light` (one light path's, indices local to `nodes`) and
/// their camera walks (see [`trace_light_nodes`]). The k-th twin of light path `path`
/// draws from its own stream (sample index 1 + k), so a path's twins do not shift its
/// own random numbers.
#[allow(clippy::too_many_arguments)]
fn trace_twins<Q: RayQuery + ?Sized>(
    scene: &Scene,
    tracer: &Q,
    params: &RenderParams,
    max_segments: u32,
    pass: u32,
    path: u32,
    light: core::ops::Range<usize>,
    nodes: &mut Vec<Node>,
    counters: &mut Counters,
) {
    let mut k = 0u32;
    for w_index in light {
        let w = nodes[w_index];
        if w.kind != NodeKind::Light || w.delta || w.bridge || w.next.node == NONE || w.next.delta {
            continue;
        }
        k += 1;
        let mut rng = SampleStream::for_sample(params.seed, Stream::Light, path, pass, k);
        // A camera node at w arriving along w's continuation: the chain reaches the
        // light junction at w after at least two segments (the pixel's and the one
        // arriving at w's successor), so the twin's continuation is segment 3 or later.
        let mut state = PathState::new(Ray::new(w.hit.p, w.next.dir, f32::INFINITY), Rgb::ONE, rng.dimension());
        state.segments = 2;
        let sp = SurfacePoint::new(w.hit, w.next.dir);
        let mut twin = Node::new(scene, w.hit, w.next.dir, NodeKind::Camera, w_index as u32);
        twin.twin = true;
        let goes_on = camera_step(scene, tracer, params, max_segments, &mut state, &sp, &mut twin, &mut rng, counters);
        let index = nodes.len() as u32;
        nodes.push(twin);
        if goes_on {
            walk_on(scene, tracer, params, max_segments, state, index, &mut rng, nodes, counters);
        } else {
            fill_light_densities(scene, nodes, index);
        }
    }
}

/// How a light path started.
struct Emission {
    light: u32,
    sample: crate::light::EmissionSample,
    beta0: Rgb,
    paths_per_pass: u32,
    /// Add an emission node at the origin.
    with_node: bool,
}

/// Where a light walk writes.
struct LightNodes<'a> {
    nodes: &'a mut Vec<Node>,
    pred: &'a mut Vec<u32>,
    base: &'a mut Vec<Rgb>,
}

/// The emission node at the origin of a light path whose first segment ends at `hit`:
/// the light's surface, found by a ray back along that (unoccluded) segment.
fn emission_node<Q: RayQuery + ?Sized>(
    scene: &Scene,
    tracer: &Q,
    hit: &SurfaceHit,
    es: &crate::light::EmissionSample,
    counters: &mut Counters,
) -> Option<Node> {
    let back = -es.dir;
    let dist = (hit.p - es.p).length();
    let mut ray = spawn_ray(hit.p, hit.ng, back);
    ray.t_max = dist * 1.01 + 1e-4;
    counters.rays += 1;
    let found = tracer.intersect(&ray)?;
    if found.emitter.is_none() || (found.p - es.p).length() > 1e-3 * (1.0 + dist) {
        return None;
    }
    let mut node = Node::new(scene, found, es.dir, NodeKind::Emission, NONE);
    node.next = Continuation { q: 1.0, dir: es.dir, node: NONE, ..Continuation::default() };
    Some(node)
}

/// One light path's nodes (see [`trace_light_nodes`]).
#[allow(clippy::too_many_arguments)]
fn light_walk<Q: RayQuery + ?Sized>(
    scene: &Scene,
    tracer: &Q,
    params: &RenderParams,
    max_segments: u32,
    ray: Ray,
    start: Emission,
    rng: &mut SampleStream,
    out: LightNodes<'_>,
    counters: &mut Counters,
) {
    let first_dim = rng.dimension();
    let mut path = PathState::new(ray, start.beta0, first_dim + LIGHT_WALK.layout.per_bounce);
    let mut parent = NONE;
    while let Some(hit) = LIGHT_WALK.trace(tracer, &path, counters) {
        let (segments, ray) = (path.segments, path.ray);
        if segments == 1
            && start.with_node
            && let Some(e) = emission_node(scene, tracer, &hit, &start.sample, counters)
        {
            parent = out.nodes.len() as u32;
            out.nodes.push(e);
            out.pred.push(NONE);
            out.base.push(Rgb::ZERO);
        }
        let index = out.nodes.len() as u32;
        if parent != NONE {
            out.nodes[parent as usize].next.node = index;
            // The continuation crossed an absorbing medium: it carries T.
            if let Some(t) = scene.transmittance(&ray, &hit) {
                out.nodes[parent as usize].next.throughput *= t;
                out.nodes[parent as usize].next.medium = Some(t);
            }
        }
        let sp = SurfacePoint::new(hit, -ray.dir);
        let material = sp.material(scene);
        let mut node = Node::new(scene, hit, sp.wo, NodeKind::Light, parent);
        if segments == 1 {
            let es = &start.sample;
            node.source = LightEnd { light: start.light, p: es.p, n: es.n };
            // Point and spot lights give intensity: radiance-like per unit solid angle
            // seen from the hit, as their light samples report it.
            let d2 = if es.delta_pos { (hit.p - es.p).length_squared().max(1e-12) } else { 1.0 };
            node.emitted = es.radiance / d2;
        } else {
            let w = &out.nodes[parent as usize].hit;
            node.source = LightEnd::at_surface(w);
            if let Some(id) = w.emitter {
                node.emitted = scene.lights[id as usize].radiance(w.p, w.ng, ray.dir);
            }
        }
        // A light segment and the camera's make two segments: one more must fit.
        let more = segments + 2 <= max_segments && params.max_depth.allows(segments + 2);
        let goes_on = continue_path(params, &mut path, &sp, &material, LIGHT_WALK, more, &mut node, rng);
        out.nodes.push(node);
        out.pred.push(parent);
        out.base.push(if segments == 1 { start.beta0 / start.paths_per_pass.max(1) as f32 } else { Rgb::ZERO });
        if !goes_on {
            break;
        }
        parent = index;
    }
}

/// Least survival probability of the roulette (see [`continue_path`]).
const MIN_SURVIVAL: f32 = 0.25;

/// The continuation of `node` at `sp` on both walks, a step of `walk` with the filters'
/// roulette rule: q is fixed before the draw (recorded in `node.next.q`), so that it does
/// not depend on the direction drawn; then the BSDF draw in the walk's mode (the adjoint,
/// with its shading-normal correction, for importance). Fills `node.next`, updates the
/// path and says whether it goes on.
///
/// From `rr_depth` segments on, q is the node's own albedo (its material's
/// [`crate::bsdf::Material::albedo_hint`], clamped to [`MIN_SURVIVAL`]..0.95), not the
/// path's throughput as in PT. A continuation is reused, with its 1/q, by every path
/// whose kernel covers its start, so q must not carry one path's history. With q from
/// the throughput, a dim path's continuation entered bright paths' rows ×1/q: on the
/// caustic scene a wall node alone in its kernel had a coefficient of 76, and a cycle
/// through it and a ceiling node grew 15× per two sweeps, a pixel 18 000× the
/// reference (`host-cli/tests/filter_scenes.rs`). With q ≈ ρ the coefficients
/// f |cos| / (q p) stay near 1.
#[allow(clippy::too_many_arguments)]
fn continue_path(
    params: &RenderParams,
    path: &mut PathState,
    sp: &SurfacePoint,
    material: &crate::bsdf::Material,
    walk: Walk,
    more: bool,
    node: &mut Node,
    rng: &mut SampleStream,
) -> bool {
    let q = if !more {
        0.0
    } else if path.segments < params.rr_depth {
        1.0
    } else {
        let albedo = material.albedo_hint().max_component();
        if albedo.is_nan() { MIN_SURVIVAL } else { albedo.clamp(MIN_SURVIVAL, 0.95) }
    };
    node.next.q = q;
    let Leave::Continues(b) = walk.scatter(params, path, sp, sp.frame.to_local(sp.wo), material, None, Roulette::Fixed { q }, rng) else { return false };
    node.next.dir = b.wi;
    node.next.delta = b.delta;
    node.next.throughput = b.throughput / q;
    node.next.pdf = b.pdf;
    true
}

#[cfg(test)]
mod tests {
    use super::kernel_scale;

    #[test]
    fn glossy_kernels_shrink_with_roughness() {
        let scale = |a, g| kernel_scale(a, g).unwrap_or(1.0);
        assert!((scale(0.01, 0.05) - 0.2).abs() < 1e-6);
        assert_eq!(scale(0.05, 0.05), 1.0);
        assert_eq!(scale(0.3, 0.05), 1.0);
        assert_eq!(scale(0.0, 0.05), 1e-3);
        assert_eq!(scale(f32::NAN, 0.05), 1.0);
        assert_eq!(scale(0.01, 0.0), 1.0);
    }
}
