//! PT's shading over lanes of paths: the vertices of one step of the lane loop that sit
//! on Lambertian surfaces, shaded together in structure-of-arrays form.
//!
//! SPIKE: the same arithmetic as the scalar steps (`CameraPaths::shade`), phase by phase
//! over the batch, so that the compiler can run each phase over SIMD lanes.

use super::pt::{CameraPath, CameraPaths, WALK};
use crate::geometry::{Ray, RayQuery, offset_ray_origin};
use crate::math::{Frame, INV_PI, Vec2, Vec3};
use crate::rng::uniform_at;
use crate::spectrum::Rgb;
use crate::transport::SurfacePoint;
use crate::transport::lanes::{Arrival, LANES};
use crate::transport::survives_roulette;
use crate::transport::walk::LastBounce;

type Lane = [f32; LANES];

#[derive(Clone, Copy)]
struct V3 {
    x: Lane,
    y: Lane,
    z: Lane,
}

impl V3 {
    const ZERO: Self = Self { x: [0.0; LANES], y: [0.0; LANES], z: [0.0; LANES] };
    #[inline(always)]
    fn get(&self, i: usize) -> Vec3 {
        Vec3::new(self.x[i], self.y[i], self.z[i])
    }
    #[inline(always)]
    fn set(&mut self, i: usize, v: Vec3) {
        self.x[i] = v.x;
        self.y[i] = v.y;
        self.z[i] = v.z;
    }
    #[inline(always)]
    fn get_rgb(&self, i: usize) -> Rgb {
        Rgb::new(self.x[i], self.y[i], self.z[i])
    }
    #[inline(always)]
    fn set_rgb(&mut self, i: usize, c: Rgb) {
        self.x[i] = c.r;
        self.y[i] = c.g;
        self.z[i] = c.b;
    }
}

/// The Lambertian vertices of one step.
pub(super) struct Lambertian {
    len: usize,
    slot: [u8; LANES],
    p: V3,
    ng: V3,
    ns: V3,
    wo: V3,
    rho: V3,
    two_sided: [bool; LANES],
    base: [u64; LANES],
    dim: [u32; LANES],
}

impl Lambertian {
    pub(super) fn new() -> Self {
        Self {
            len: 0,
            slot: [0; LANES],
            p: V3::ZERO,
            ng: V3::ZERO,
            ns: V3::ZERO,
            wo: V3::ZERO,
            rho: V3::ZERO,
            two_sided: [false; LANES],
            base: [0; LANES],
            dim: [0; LANES],
        }
    }

    pub(super) fn len(&self) -> usize {
        self.len
    }

    pub(super) fn clear(&mut self) {
        self.len = 0;
    }

    #[inline(always)]
    pub(super) fn push(&mut self, slot: u8, sp: &SurfacePoint, rho: Rgb, two_sided: bool, path: &CameraPath) {
        let i = self.len;
        self.slot[i] = slot;
        self.p.set(i, sp.hit.p);
        self.ng.set(i, sp.hit.ng);
        self.ns.set(i, sp.hit.ns);
        self.wo.set(i, sp.wo);
        self.rho.set_rgb(i, rho);
        self.two_sided[i] = two_sided;
        self.base[i] = path.rng.base();
        self.dim[i] = path.state.dimension(&WALK.layout, 0);
        self.len += 1;
    }
}

/// Everything the lane shading keeps per step, allocated once per range of paths.
pub(super) struct Scratch {
    pub(super) batch: Lambertian,
    pre: Prepared,
    drawn: Drawn,
    shaded: Shaded,
}

impl Scratch {
    pub(super) fn new() -> Self {
        Self { batch: Lambertian::new(), pre: Prepared::new(), drawn: Drawn::new(), shaded: Shaded::new() }
    }
}

/// Shade the batch's vertices: next-event estimation and the BSDF sample, as
/// `CameraPaths::shade` does one at a time.
pub(super) fn shade<Q: RayQuery + ?Sized>(
    paths: &mut CameraPaths<'_, Q>,
    scratch: &mut Scratch,
    lanes: &mut [Option<CameraPath>],
    lane_of: &[u8],
    arrivals: &mut [Arrival],
) {
    let Scratch { batch: b, pre, drawn: ls, shaded: out } = scratch;
    let n = b.len;
    let layout = WALK.layout;
    prepare(b, pre);
    let (org, u) = (&pre.org, &pre.u);

    // 2. The light draws, one lane at a time (a table lookup and the light's own sampler).
    let scene = paths.scene;
    ls.ok[..n].fill(false);
    if let Some(table) = scene.light_selection.as_ref() {
        for i in 0..n {
            let chosen = table.sample(u[0][i]);
            let Some(l) = scene.lights[chosen.index].sample_li(org.get(i), Vec2::new(u[1][i], u[2][i])) else { continue };
            if !l.pdf.is_positive() || l.radiance.is_black() {
                continue;
            }
            ls.ok[i] = true;
            ls.wi.set(i, l.wi);
            ls.p.set(i, l.p);
            ls.n.set(i, l.n);
            ls.rad.set_rgb(i, l.radiance);
            ls.dist[i] = l.dist;
            ls.pdf[i] = l.pdf.0;
            ls.pmf[i] = chosen.pmf;
            ls.delta[i] = l.is_delta;
        }
    }

    // 3. Next-event values and shadow rays; the BSDF samples.
    evaluate(b, pre, ls, paths.params.heuristic, out);
    let Shaded { nee, nee_ok, sh_o, sh_d, sh_t, bwi, bthr, bpdf, bok } = out;

    // 4. Back to the paths: the pending sample, β, roulette, the next ray.
    let params = paths.params;
    for i in 0..n {
        let k = b.slot[i] as usize;
        let path = lanes[lane_of[k] as usize].as_mut().expect("a traced lane holds a path");
        let mut shadow = None;
        if nee_ok[i] {
            paths.counters.rays += 1;
            path.pending = path.state.beta * nee.get_rgb(i);
            shadow = Some(Ray { origin: sh_o.get(i), dir: sh_d.get(i), t_max: sh_t[i] });
        }
        let d0 = b.dim[i];
        let continues = 'scatter: {
            path.rng.set_dimension(d0.wrapping_add(layout.lobe + 3));
            if !bok[i] {
                break 'scatter false;
            }
            let state = &mut path.state;
            state.beta *= bthr.get_rgb(i);
            if state.beta.is_black() || !state.beta.is_finite() {
                break 'scatter false;
            }
            path.rng.set_dimension(d0.wrapping_add(layout.roulette));
            state.segments += 1;
            if !survives_roulette(params, state.segments, &mut state.beta, 1.0, &mut path.rng) {
                break 'scatter false;
            }
            let (p, ng) = (b.p.get(i), b.ng.get(i));
            state.ray = crate::geometry::spawn_ray(p, ng, bwi.get(i));
            state.last = Some(LastBounce { origin: state.ray.origin, pdf: bpdf[i], delta: false });
            true
        };
        arrivals[k] = Arrival { shadow, continues };
    }
}

/// SIMD groups of lanes.
const GROUP: usize = 8;

/// `n` lanes rounded up to whole groups of [`GROUP`] (the lanes past `n` compute on
/// stale data and are never read), and never past the batch.
#[inline(always)]
fn whole_groups(n: usize) -> usize {
    n.next_multiple_of(GROUP).min(LANES)
}

/// `a` where `c`, else `b`, component by component (a select, never a branch).
#[inline(always)]
fn select3(c: bool, a: Vec3, b: Vec3) -> Vec3 {
    Vec3::new(if c { a.x } else { b.x }, if c { a.y } else { b.y }, if c { a.z } else { b.z })
}

/// Phase 1's results per lane.
struct Prepared {
    s: V3,
    t: V3,
    wol: V3,
    org: V3,
    u: [Lane; 5],
}

impl Prepared {
    fn new() -> Self {
        Self { s: V3::ZERO, t: V3::ZERO, wol: V3::ZERO, org: V3::ZERO, u: [[0.0; LANES]; 5] }
    }
}

/// The light samples per lane.
struct Drawn {
    ok: [bool; LANES],
    wi: V3,
    p: V3,
    n: V3,
    rad: V3,
    dist: Lane,
    pdf: Lane,
    pmf: Lane,
    delta: [bool; LANES],
}

impl Drawn {
    fn new() -> Self {
        Self {
            ok: [false; LANES],
            wi: V3::ZERO,
            p: V3::ZERO,
            n: V3::ZERO,
            rad: V3::ZERO,
            dist: [0.0; LANES],
            pdf: [0.0; LANES],
            pmf: [0.0; LANES],
            delta: [false; LANES],
        }
    }
}

/// Phase 3's results per lane.
struct Shaded {
    nee: V3,
    nee_ok: [bool; LANES],
    sh_o: V3,
    sh_d: V3,
    sh_t: Lane,
    bwi: V3,
    bthr: V3,
    bpdf: Lane,
    bok: [bool; LANES],
}

impl Shaded {
    fn new() -> Self {
        Self {
            nee: V3::ZERO,
            nee_ok: [false; LANES],
            sh_o: V3::ZERO,
            sh_d: V3::ZERO,
            sh_t: [0.0; LANES],
            bwi: V3::ZERO,
            bthr: V3::ZERO,
            bpdf: [0.0; LANES],
            bok: [false; LANES],
        }
    }
}

/// Phase 1: frames, local wo, the light samples' origin, the random numbers.
fn prepare(b: &Lambertian, out: &mut Prepared) {
    match whole_groups(b.len) {
        8 => prepare_n::<8>(b, out),
        16 => prepare_n::<16>(b, out),
        24 => prepare_n::<24>(b, out),
        _ => prepare_n::<LANES>(b, out),
    }
}

#[inline(never)]
fn prepare_n<const N: usize>(b: &Lambertian, out: &mut Prepared) {
    for i in 0..N {
        prepare_lane(b, out, i);
    }
}

#[inline(always)]
fn prepare_lane(b: &Lambertian, out: &mut Prepared, i: usize) {
    let layout = WALK.layout;
    let ns = b.ns.get(i);
    let frame = Frame::from_normal(ns);
    out.s.set(i, frame.s);
    out.t.set(i, frame.t);
    let wo = b.wo.get(i);
    out.wol.set(i, frame.to_local(wo));
    let (p, ng) = (b.p.get(i), b.ng.get(i));
    let side = if ng.dot(wo) >= 0.0 { ng } else { -ng };
    out.org.set(i, offset_ray_origin(p, side));
    let (base, d) = (b.base[i], b.dim[i]);
    out.u[0][i] = uniform_at(base, d.wrapping_add(layout.light));
    out.u[1][i] = uniform_at(base, d.wrapping_add(layout.light + 1));
    out.u[2][i] = uniform_at(base, d.wrapping_add(layout.light + 2));
    out.u[3][i] = uniform_at(base, d.wrapping_add(layout.lobe + 1));
    out.u[4][i] = uniform_at(base, d.wrapping_add(layout.lobe + 2));
}

/// Phase 3: next-event values and shadow rays, the BSDF samples.
fn evaluate(b: &Lambertian, pre: &Prepared, ls: &Drawn, heuristic: crate::transport::Heuristic, out: &mut Shaded) {
    match whole_groups(b.len) {
        8 => evaluate_n::<8>(b, pre, ls, heuristic, out),
        16 => evaluate_n::<16>(b, pre, ls, heuristic, out),
        24 => evaluate_n::<24>(b, pre, ls, heuristic, out),
        _ => evaluate_n::<LANES>(b, pre, ls, heuristic, out),
    }
}

#[inline(never)]
fn evaluate_n<const N: usize>(b: &Lambertian, pre: &Prepared, ls: &Drawn, heuristic: crate::transport::Heuristic, out: &mut Shaded) {
    for i in 0..N {
        evaluate_lane(b, pre, ls, heuristic, out, i);
    }
}

#[inline(always)]
fn evaluate_lane(b: &Lambertian, pre: &Prepared, ls: &Drawn, heuristic: crate::transport::Heuristic, out: &mut Shaded, i: usize) {
    let frame = Frame { s: pre.s.get(i), t: pre.t.get(i), n: b.ns.get(i) };
    let wo = pre.wol.get(i);
    let rho = b.rho.get_rgb(i);
    let mirrored = b.two_sided[i] && wo.z < 0.0;
    let wo_m = if mirrored { Vec3::new(wo.x, wo.y, -wo.z) } else { wo };
    let (p, ng) = (b.p.get(i), b.ng.get(i));

    // Next-event estimation (`CameraPaths::next_event`).
    let wi_world = ls.wi.get(i);
    let wi_local = frame.to_local(wi_world);
    let wi_mz = if mirrored { -wi_local.z } else { wi_local.z };
    let above = wo_m.z > 0.0 && wi_mz > 0.0;
    let f0 = if above { rho * INV_PI } else { Rgb::ZERO };
    let f0 = if f0.is_finite() { f0 } else { Rgb::ZERO };
    let pdf = if above { wi_mz.max(0.0) * INV_PI } else { 0.0 };
    let pdf = if pdf.is_finite() && pdf >= 0.0 { pdf } else { 0.0 };
    let bsdf_pdf = if ls.delta[i] { 0.0 } else { pdf };
    out.nee_ok[i] = ls.ok[i] && !f0.is_black();
    let f = f0 * wi_local.z.abs();
    let light_pdf = ls.pmf[i] * ls.pdf[i];
    let w = if ls.delta[i] { 1.0 } else { heuristic.weight(light_pdf, bsdf_pdf) };
    out.nee.set_rgb(i, f * ls.rad.get_rgb(i) * (w / light_pdf));
    // `shadow_ray`: to the point on a light at a finite distance, else along the direction.
    let to_point = crate::geometry::spawn_ray_to(p, ng, ls.p.get(i), ls.n.get(i));
    let along = crate::geometry::spawn_ray(p, ng, wi_world);
    let finite = ls.dist[i].is_finite();
    out.sh_o.set(i, select3(finite, to_point.origin, along.origin));
    out.sh_d.set(i, select3(finite, to_point.dir, along.dir));
    out.sh_t[i] = if finite { to_point.t_max } else { along.t_max };

    // The BSDF sample (`Material::sample` of a Lambertian lobe).
    let valid_wo = wo_m.z.abs() >= f32::MIN_POSITIVE && wo_m.is_finite() && wo_m.z > 0.0;
    let d = crate::warp::sample_cosine_hemisphere(Vec2::new(pre.u[3][i], pre.u[4][i]));
    let up = wo_m.z > 0.0 && d.z > 0.0;
    let spdf = if up { d.z.max(0.0) * INV_PI } else { 0.0 };
    let sf = if up { rho * INV_PI } else { Rgb::ZERO };
    let srev = if up { wo_m.z.max(0.0) * INV_PI } else { 0.0 };
    out.bok[i] = valid_wo && spdf > 0.0 && sf.is_finite() && spdf.is_finite() && srev.is_finite();
    let wi_s = if mirrored { Vec3::new(d.x, d.y, -d.z) } else { d };
    out.bwi.set(i, frame.to_world(wi_s));
    out.bpdf[i] = spdf;
    out.bthr.set_rgb(i, sf * (wi_s.z.abs() / spdf));
}
// t
// t
