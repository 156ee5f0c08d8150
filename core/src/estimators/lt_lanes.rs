//! Light tracing's shading over lanes of paths: the light-path vertices of one step of
//! the lane loop that lie on Lambertian surfaces, shaded together.
//!
//! The counterpart of `pt_lanes` (whose notes say why and how) for `lt.rs`'s light
//! paths. At each vertex y_i light tracing does two things (module notes of `lt.rs`):
//!
//! - **The camera connection** (the t = 1 strategy alone): β f*(y_{i−1} → y_i → c)
//!   |cos θ_i| c_sn · W_e |cos θ_c| / d², with f* the adjoint BSDF and c_sn Veach's
//!   shading-normal correction (`bsdf::shading_normal_correction`), landing on the pixel
//!   the connection passes through, with its shadow ray to the pinhole.
//! - **The continuation**: a cosine-weighted direction from the Lambertian lobe, whose
//!   throughput f |cos| c_sn / p multiplies β (`Walk::scatter` in importance mode).
//!
//! Both run over lanes here, in two phases compiled for the host's instruction set
//! ([`simd::kernel!`]): **prepare** (the shading frame, wo in it, the direction's two
//! random numbers) and **evaluate** (the pinhole's film point, importance and shadow
//! ray, the BSDF value and correction; the sample and its throughput). `lt.rs` then
//! writes each path's splat and continuation one lane at a time (`leave_lambertian`).
//!
//! Only pinhole cameras connect over lanes: a thin lens draws its lens point from each
//! path's auxiliary stream, which stays scalar. Each lane does the scalar code's
//! operations in its order (selects where it branches), so images are the same at every
//! width and instruction set (`tests/tests/lane_widths.rs`).

use crate::bsdf::{LambertLane, TransportMode, shading_normal_correction};
use crate::camera::PerspectiveCamera;
use crate::geometry::{Ray, RayLanes, spawn_ray_to};
use crate::math::simd;
use crate::math::soa::{BounceLanes, LANES, Lane, Vec3s, over_lanes, select_rgb, whole_groups};
use crate::math::{Frame, Vec2, Vec3};
use crate::rng::uniform_at;
use crate::spectrum::Rgb;
use crate::transport::lane_vertices::LambertVertices;
use crate::transport::walk::Layout;
use crate::transport::{RenderParams, SurfacePoint};

/// LT's random dimensions per bounce (`Walk`'s layout, module notes of
/// `transport::walk`): lobe 0, direction 1–2, roulette 3. `lt.rs` walks with it too.
pub(super) const LAYOUT: Layout = Layout { per_bounce: 4, light: 0, lobe: 0, roulette: 3 };

/// The Lambertian vertices of one step, with what the camera connection needs of
/// their paths.
struct Vertices {
    v: LambertVertices,
    /// The path's throughput β.
    beta: Vec3s,
    /// The path may connect to the camera here (its depth allows one more segment).
    connect: [bool; LANES],
}

/// Phase 1's results.
struct Prepared {
    /// The shading frame (its normal is the vertex's `ns`).
    s: Vec3s,
    t: Vec3s,
    /// wo in the shading frame.
    wo: Vec3s,
    /// The direction's two numbers.
    u: [Lane; 2],
}

/// Phase 2's results.
struct Shaded {
    /// The camera connection: the splat's film point and value, its shadow ray.
    film_x: Lane,
    film_y: Lane,
    value: Vec3s,
    splat: [bool; LANES],
    shadow: RayLanes,
    /// The BSDF sample (throughput f |cos| c_sn / p).
    bounce: BounceLanes,
}

/// Everything the lane shading keeps, made once per range of light paths.
pub(super) struct Scratch {
    batch: Vertices,
    pre: Prepared,
    shaded: Shaded,
}

/// What the lane shading found for one vertex of the batch.
pub(super) struct Shaded1 {
    /// The vertex's index among the step's traced lanes.
    pub slot: usize,
    /// The camera connection: film point, value (β included), shadow ray.
    pub splat: Option<(Vec2, Rgb, Ray)>,
    /// The BSDF sample: its throughput, the next ray's direction and p (`None`: no
    /// sample).
    pub bounce: Option<(Rgb, Vec3, f32)>,
    /// The vertex's position and geometric normal (the next ray leaves from them).
    pub p: Vec3,
    pub ng: Vec3,
}

impl Scratch {
    pub(super) fn new() -> Self {
        let zero = [0.0; LANES];
        let v = Vec3s::ZERO;
        Self {
            batch: Vertices { v: LambertVertices::new(), beta: v, connect: [false; LANES] },
            pre: Prepared { s: v, t: v, wo: v, u: [zero; 2] },
            shaded: Shaded { film_x: zero, film_y: zero, value: v, splat: [false; LANES], shadow: RayLanes::ZERO, bounce: BounceLanes::ZERO },
        }
    }

    pub(super) fn clear(&mut self) {
        self.batch.v.clear();
    }

    /// The vertices in the batch.
    pub(super) fn len(&self) -> usize {
        self.batch.v.len
    }

    /// Add the vertex at `sp` (traced lane `slot`) of a path of throughput `beta`, whose
    /// random stream is `base` and whose bounce draws from dimension `dim`; `connect`: it
    /// may connect to the camera.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    pub(super) fn push(&mut self, slot: u8, sp: &SurfacePoint, lobe: LambertLane, beta: Rgb, connect: bool, base: u64, dim: u32) {
        let b = &mut self.batch;
        let i = b.v.push(slot, sp, lobe, base, dim);
        b.beta.set_rgb(i, beta);
        b.connect[i] = connect;
    }

    /// Vertex `i`'s results.
    #[inline(always)]
    pub(super) fn lane(&self, i: usize) -> Shaded1 {
        let (b, s) = (&self.batch.v, &self.shaded);
        let splat = s.splat[i].then(|| (Vec2::new(s.film_x[i], s.film_y[i]), s.value.rgb(i), s.shadow.get(i)));
        let bounce = s.bounce.get(i);
        Shaded1 { slot: b.slot[i] as usize, splat, bounce, p: b.p.get(i), ng: b.ng.get(i) }
    }
}

/// Shade the batch's vertices (see the module notes); read each one's results with
/// [`Scratch::lane`]. The camera must be a pinhole.
pub(super) fn shade(camera: &PerspectiveCamera, params: &RenderParams, scratch: &mut Scratch) {
    let Scratch { batch, pre, shaded } = scratch;
    let groups = whole_groups(batch.v.len);
    prepare(params.simd, &batch.v, pre, groups);
    evaluate(params.simd, camera, batch, pre, shaded, groups);
}

simd::kernel! {
/// Phase 1: frames, wo, the direction's random numbers.
fn prepare(isa, b: &LambertVertices, out: &mut Prepared, groups: usize) {
    over_lanes!(groups, |i| {
        let frame = b.frame(i);
        out.s.set(i, frame.s);
        out.t.set(i, frame.t);
        let wo_local = frame.to_local(b.wo.get(i));
        out.wo.set(i, wo_local);
        let (base, d) = (b.base[i], b.dim[i]);
        out.u[0][i] = uniform_at(base, d.wrapping_add(LAYOUT.lobe + 1));
        out.u[1][i] = uniform_at(base, d.wrapping_add(LAYOUT.lobe + 2));
    });
}
}

simd::kernel! {
/// Phase 2: the camera connection (`LightPaths::arrive`, `SurfacePoint::f_cos` in
/// importance mode) and the BSDF sample (`Walk::scatter` in importance mode).
fn evaluate(isa, camera: &PerspectiveCamera, batch: &Vertices, pre: &Prepared, out: &mut Shaded, groups: usize) {
    over_lanes!(groups, |i| {
        let b = &batch.v;
        let frame = Frame { s: pre.s.get(i), t: pre.t.get(i), n: b.ns.get(i) };
        let wo_local = pre.wo.get(i);
        let lobe = b.lobe(i);
        let (p, ng, ns, wo) = (b.p.get(i), b.ng.get(i), b.ns.get(i), b.wo.get(i));

        // The camera connection.
        let (cs, on_film) = camera.connect_pinhole_lane(p);
        let wi_local = frame.to_local(cs.wi);
        let (f, _) = lobe.eval_pdf(wo_local, wi_local);
        let correction = shading_normal_correction(TransportMode::Importance, wo, cs.wi, ng, ns);
        let f_cos = select_rgb(f.is_black(), Rgb::ZERO, f * (wi_local.z.abs() * correction));
        let value = batch.beta.rgb(i) * f_cos * camera.arriving_importance(&cs);
        out.splat[i] = batch.connect[i] & on_film & !value.is_black();
        out.film_x[i] = cs.film.x;
        out.film_y[i] = cs.film.y;
        out.value.set_rgb(i, value);
        let shadow = spawn_ray_to(p, ng, cs.position, Vec3::ZERO);
        out.shadow.set(i, shadow);

        // The BSDF sample, with the adjoint's correction.
        let (wi_local, f, pdf, ok) = lobe.sample(wo_local, Vec2::new(pre.u[0][i], pre.u[1][i]));
        let wi = frame.to_world(wi_local);
        let correction = shading_normal_correction(TransportMode::Importance, wo, wi, ng, ns);
        out.bounce.set(i, wi, f * (wi_local.z.abs() * correction / pdf), pdf, ok);
    });
}
}
