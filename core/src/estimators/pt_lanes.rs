//! Path tracing's shading over lanes of paths: the vertices of one step of the lane
//! loop that lie on Lambertian surfaces, shaded together.
//!
//! # Why
//!
//! A path tracer that shades one vertex at a time spends about half its instructions
//! outside the ray queries, spread thin over a light choice, a point on the light, a
//! BSDF value and density, the MIS weight, a cosine-weighted direction, the frame,
//! roulette and the ray offsets (docs/lanes.md). None of it depends on the other paths,
//! so a batch of paths can do each part together: SIMD registers hold one quantity of
//! 8 or 16 paths, and one instruction advances them all. Mitsuba 3 compiles its whole
//! loop this way; here the lane loop ([`crate::transport::lanes`]) already keeps a batch
//! of paths in flight, and this module shades the common case over it.
//!
//! # What runs over lanes
//!
//! `CameraPaths::arrive_batch` (in `pt.rs`) takes each traced lane through the scalar
//! first half of an arrival (`reach`: emission found, the medium crossed, the depth
//! cap, the kernel junction). A vertex whose material is Lambertian, with no segment
//! kernel moving its next segment and no absorbing medium in the scene, joins the
//! batch; any other takes the scalar second half (`shade`). The batch then runs, each
//! phase a loop over the lanes in structure-of-arrays form ([`crate::math::soa`]):
//!
//! 1. **Prepare** (lanes): the shading frame, wo in it, the origin of the light sample
//!    and the bounce's random numbers (the counter-based hash, [`uniform_at`]).
//! 2. **Choose** (one lane at a time): the light ∝ power (an alias-table lookup), and
//!    for a triangle light a copy of it into lane form ([`TriangleLanes`]); any other
//!    light draws here with its own sampler.
//! 3. **Draw** (lanes): the point on each triangle light, its solid-angle density and
//!    radiance (`TriangleLight::sample_li`'s arithmetic).
//! 4. **Evaluate** (lanes): next-event estimation's f |cos| L w / p_L and its shadow ray,
//!    the Lambertian sample that continues the path (cosine-weighted, Malley's method)
//!    and its throughput f |cos| / p.
//! 5. **Leave** (one lane at a time): the pending sample and shadow ray, β, roulette and
//!    the next ray, written back to each path.
//!
//! The lane phases are compiled for the instruction set the host chose ([`simd::run`]).
//!
//! # Same bits as one path at a time
//!
//! Each lane does the scalar code's operations in the scalar code's order: where the
//! scalar code branches, the lane code computes both sides and selects
//! ([`crate::math::soa::select3`]), which gives the taken side's bits; Rust never fuses a
//! multiply and an add, and the elementary functions are the core's own at every width
//! ([`crate::math::elementary`]). So the images are the same at every batch width and
//! instruction set, bit for bit (`tests/tests/lane_widths.rs`), as the lane loop
//! promises.
//!
//! Nothing here allocates: the scratch lives on the stack of `render_pixels`, once per
//! range of pixels.

use crate::geometry::{Ray, RayLanes, offset_ray_origin, spawn_ray, spawn_ray_to};
use crate::light::TriangleLanes;
use crate::math::simd;
use crate::math::soa::{BounceLanes, LANES, Lane, Vec3s, over_lanes, select_rgb, select3, whole_groups};
use crate::math::{Frame, Vec2, Vec3};
use crate::rng::uniform_at;
use crate::scene::Scene;
use crate::spectrum::Rgb;
use crate::transport::lane_vertices::LambertVertices;
use crate::transport::walk::Layout;
use crate::transport::{Heuristic, RenderParams};

/// PT's random dimensions per bounce (`Walk`'s layout, module notes of
/// `transport::walk`): light choice 0, point on the light 1–2, lobe 3, direction 4–5,
/// roulette 6. `pt.rs` walks with this layout too.
pub(super) const LAYOUT: Layout = Layout { per_bounce: 8, light: 0, lobe: 3, roulette: 6 };

/// Phase 1's results.
struct Prepared {
    /// The shading frame (its normal is the vertex's `ns`).
    s: Vec3s,
    t: Vec3s,
    /// wo in the shading frame.
    wo: Vec3s,
    /// Where the light sample is taken from (`walk::light_origin`).
    origin: Vec3s,
    /// The light choice, the point on the light (2), the direction (2).
    u: [Lane; 5],
}

/// The light samples (phases 2 and 3).
struct Drawn {
    ok: [bool; LANES],
    /// Lane's light is a triangle (drawn in phase 3) rather than drawn in phase 2.
    triangle: [bool; LANES],
    wi: Vec3s,
    p: Vec3s,
    n: Vec3s,
    radiance: Vec3s,
    dist: Lane,
    pdf: Lane,
    pmf: Lane,
    delta: [bool; LANES],
}

/// Phase 4's results.
struct Shaded {
    /// Next-event estimation: f |cos| L w / p_L, and whether there is one.
    nee: Vec3s,
    nee_ok: [bool; LANES],
    shadow: RayLanes,
    /// The BSDF sample (throughput f |cos| / p).
    bounce: BounceLanes,
}

/// Everything the lane shading keeps, made once per range of pixels.
pub(super) struct Scratch {
    pub(super) batch: LambertVertices,
    pre: Prepared,
    drawn: Drawn,
    triangles: TriangleLanes,
    shaded: Shaded,
}

impl Scratch {
    pub(super) fn new() -> Self {
        let zero = [0.0; LANES];
        Self {
            batch: LambertVertices::new(),
            pre: Prepared { s: Vec3s::ZERO, t: Vec3s::ZERO, wo: Vec3s::ZERO, origin: Vec3s::ZERO, u: [zero; 5] },
            drawn: Drawn {
                ok: [false; LANES],
                triangle: [false; LANES],
                wi: Vec3s::ZERO,
                p: Vec3s::ZERO,
                n: Vec3s::ZERO,
                radiance: Vec3s::ZERO,
                dist: zero,
                pdf: zero,
                pmf: zero,
                delta: [false; LANES],
            },
            triangles: TriangleLanes::new(),
            shaded: Shaded { nee: Vec3s::ZERO, nee_ok: [false; LANES], shadow: RayLanes::ZERO, bounce: BounceLanes::ZERO },
        }
    }
}

/// Shade the batch's vertices (phases 1 to 4 of the module notes); read each one's
/// results with [`Scratch::lane`].
pub(super) fn shade(scene: &Scene, params: &RenderParams, scratch: &mut Scratch) {
    let Scratch { batch: b, pre, drawn, triangles, shaded } = scratch;
    let n = b.len;
    let isa = params.simd;
    let groups = whole_groups(n);

    // 1. Frames, wo, origins, random numbers.
    prepare(isa, b, pre, groups);

    // 2. The light choices; triangle lights copied into lanes, any other light drawn.
    drawn.ok = [false; LANES];
    drawn.triangle = [false; LANES];
    if let Some(table) = scene.light_selection.as_ref() {
        for i in 0..n {
            let chosen = table.sample(pre.u[0][i]);
            drawn.pmf[i] = chosen.pmf;
            let light = &scene.lights[chosen.index];
            if light.set_triangle_lane(triangles, i) {
                drawn.triangle[i] = true;
                continue;
            }
            let Some(l) = light.sample_li(pre.origin.get(i), Vec2::new(pre.u[1][i], pre.u[2][i])) else { continue };
            drawn.ok[i] = l.pdf.is_positive() && !l.radiance.is_black();
            drawn.wi.set(i, l.wi);
            drawn.p.set(i, l.p);
            drawn.n.set(i, l.n);
            drawn.radiance.set_rgb(i, l.radiance);
            drawn.dist[i] = l.dist;
            drawn.pdf[i] = l.pdf.0;
            drawn.delta[i] = l.is_delta;
        }
    }

    // 3 and 4. The triangle lights' points; next-event values, shadow rays, BSDF samples.
    draw_triangles(isa, triangles, pre, drawn, groups);
    evaluate(isa, b, pre, drawn, params.heuristic, shaded, groups);
}

/// What the lane shading found for one vertex of the batch.
pub(super) struct Shaded1 {
    /// The vertex's index among the step's traced lanes.
    pub slot: usize,
    /// Next-event estimation's f |cos| L w / p_L (without β) and its shadow ray.
    pub nee: Option<(Rgb, Ray)>,
    /// The BSDF sample: f |cos| / p, the next ray's direction and p (`None`: no sample).
    pub bounce: Option<(Rgb, Vec3, f32)>,
    /// The vertex's position and geometric normal (the next ray leaves from them).
    pub p: Vec3,
    pub ng: Vec3,
}

impl Scratch {
    /// The vertices shaded by the last [`shade`].
    pub(super) fn len(&self) -> usize {
        self.batch.len
    }

    /// Vertex `i`'s results.
    #[inline(always)]
    pub(super) fn lane(&self, i: usize) -> Shaded1 {
        let (b, s) = (&self.batch, &self.shaded);
        let nee = s.nee_ok[i].then(|| (s.nee.rgb(i), s.shadow.get(i)));
        let bounce = s.bounce.get(i);
        Shaded1 { slot: b.slot[i] as usize, nee, bounce, p: b.p.get(i), ng: b.ng.get(i) }
    }
}

simd::kernel! {
/// Phase 1 (see the module notes).
fn prepare(isa, b: &LambertVertices, out: &mut Prepared, groups: usize) {
    let layout = LAYOUT;
    over_lanes!(groups, |i| {
        let frame = b.frame(i);
        out.s.set(i, frame.s);
        out.t.set(i, frame.t);
        let wo = b.wo.get(i);
        out.wo.set(i, frame.to_local(wo));
        // `walk::light_origin`: where rays toward wo's side start.
        let (p, ng) = (b.p.get(i), b.ng.get(i));
        out.origin.set(i, offset_ray_origin(p, select3(ng.dot(wo) >= 0.0, ng, -ng)));
        let (base, d) = (b.base[i], b.dim[i]);
        out.u[0][i] = uniform_at(base, d.wrapping_add(layout.light));
        out.u[1][i] = uniform_at(base, d.wrapping_add(layout.light + 1));
        out.u[2][i] = uniform_at(base, d.wrapping_add(layout.light + 2));
        out.u[3][i] = uniform_at(base, d.wrapping_add(layout.lobe + 1));
        out.u[4][i] = uniform_at(base, d.wrapping_add(layout.lobe + 2));
    });
}
}

simd::kernel! {
/// Phase 3: the lanes whose light is a triangle draw their point on it.
fn draw_triangles(isa, triangles: &TriangleLanes, pre: &Prepared, out: &mut Drawn, groups: usize) {
    over_lanes!(groups, |i| {
        let (l, exists) = triangles.sample_li(i, pre.origin.get(i), Vec2::new(pre.u[1][i], pre.u[2][i]));
        let t = out.triangle[i];
        // `Walk::draw_light`'s test: a positive density and some radiance.
        out.ok[i] = if t { exists && !l.radiance.is_black() } else { out.ok[i] };
        out.wi.set(i, select3(t, l.wi, out.wi.get(i)));
        out.p.set(i, select3(t, l.p, out.p.get(i)));
        out.n.set(i, select3(t, l.n, out.n.get(i)));
        out.radiance.set_rgb(i, select_rgb(t, l.radiance, out.radiance.rgb(i)));
        out.dist[i] = if t { l.dist } else { out.dist[i] };
        out.pdf[i] = if t { l.pdf.0 } else { out.pdf[i] };
        out.delta[i] = if t { false } else { out.delta[i] };
    });
}
}

simd::kernel! {
/// Phase 4: `CameraPaths::next_event` and `Material::sample` of a Lambertian lobe, with
/// `Walk::scatter`'s throughput (radiance: no shading-normal correction).
fn evaluate(isa, b: &LambertVertices, pre: &Prepared, ls: &Drawn, heuristic: Heuristic, out: &mut Shaded, groups: usize) {
    over_lanes!(groups, |i| {
        let frame = Frame { s: pre.s.get(i), t: pre.t.get(i), n: b.ns.get(i) };
        let wo = pre.wo.get(i);
        let lobe = b.lobe(i);
        let (p, ng) = (b.p.get(i), b.ng.get(i));

        // Next-event estimation: f and p_B at the light's direction.
        let wi_world = ls.wi.get(i);
        let wi_local = frame.to_local(wi_world);
        let (f, pdf) = lobe.eval_pdf(wo, wi_local);
        let delta = ls.delta[i];
        out.nee_ok[i] = ls.ok[i] & !f.is_black();
        let f = f * wi_local.z.abs();
        let light_pdf = ls.pmf[i] * ls.pdf[i];
        let w = if delta { 1.0 } else { heuristic.weight(light_pdf, if delta { 0.0 } else { pdf }) };
        out.nee.set_rgb(i, f * ls.radiance.rgb(i) * (w / light_pdf));
        // `walk::shadow_ray`: to the point on a light at a finite distance, else along wi.
        let finite = ls.dist[i].is_finite();
        let to_point = spawn_ray_to(p, ng, ls.p.get(i), ls.n.get(i));
        let along = spawn_ray(p, ng, wi_world);
        let t_max = if finite { to_point.t_max } else { along.t_max };
        out.shadow.set(i, Ray { origin: select3(finite, to_point.origin, along.origin), dir: select3(finite, to_point.dir, along.dir), t_max });

        // The BSDF sample.
        let (wi, f, pdf, ok) = lobe.sample(wo, Vec2::new(pre.u[3][i], pre.u[4][i]));
        out.bounce.set(i, frame.to_world(wi), f * (wi.z.abs() / pdf), pdf, ok);
    });
}
}
