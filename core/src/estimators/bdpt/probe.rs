//! PT's second moment per pixel, estimated from BDPT's samples (`--estimator auto`'s race;
//! docs/plan.md).
//!
//! A few passes of PT underestimate its variance where that variance rests on rare bright
//! samples: on veach-mis, a diffuse wall lit by a small light through a glossy plate,
//! which PT reaches only by sampling the wall's BSDF toward the plate's highlight. The
//! race's pilot holds about 2 % of a render's samples and often sees none of them. BDPT
//! samples those paths by its light-side strategies, with densities where PT's are small,
//! so it can estimate what PT's samples would square to without PT drawing them.
//!
//! Per path length, PT combines two strategies, s = 0 (BSDF sampling reaches the emitter)
//! and s = 1 (next-event estimation), one sample each, with MIS weights w₀, w₁. Its
//! second moment over path space is
//!
//!   M = ∫ Σ_{i ∈ {0,1}} w_i(x)² f(x)² / p_i(x) dx,
//!
//! so Var = M − Σ_i μ_i² for μ_i = ∫ w_i f, and with the balance heuristic
//! Σ_i w_i²/p_i = 1/(p₀ + p₁). BDPT estimates any path integral as Σ_{s,t} w_{s,t} g/p_{s,t};
//! with g = f² Σ_i w_i²/p_i one strategy's term is
//!
//!   w_{s,t} F² Σ_i w_i² / r_i,   F = f / p_{s,t},   r_i = p_i / p_{s,t},
//!
//! F the connection's unweighted value and r_i the density ratios of BDPT's own MIS walk
//! ([`for_each_strategy_ratio`]). The terms of different path lengths of one PT camera
//! path are correlated, and their cross terms are left out: M is the sum over lengths,
//! a lower estimate of a pixel's second moment where several lengths matter (auto takes
//! the larger of this and PT's own estimate).
//!
//! Two densities differ between the estimators, and are converted here:
//! - next-event estimation: BDPT's walk counts it with the light's position density (the
//!   density the weights use, [`crate::path::Vertex::pdf_light_origin`]), while both PT
//!   and BDPT's s = 1 connection draw a sphere light's point from the cone it subtends.
//!   The ratio c = p_cone / p_position at the light vertex converts: r₁ = c r̃₁, and for
//!   s = 1 itself p_{1,t} = c p̃_{1,t} (a triangle light has c = 1);
//! - splats: a t = 1 contribution's value V is W·H times what a pixel sample's would be
//!   (the film divides the pass's splats by the W·H light paths), so its square carries
//!   one more 1/(W·H).
//!
//! Russian roulette's survival probabilities are left out of both densities (they differ
//! only from the sixth segment on, at the default `rr_depth`).

use core::ops::Range;

use super::Sample;
use crate::geometry::RayQuery;
use crate::path::Vertex;
use crate::path::mis::{for_each_strategy_ratio, mis_weight, strategy_vertex};
use crate::scene::Scene;
use crate::segment::Kernel;
use crate::spectrum::Rgb;
use crate::transport::{Counters, Heuristic, RenderParams, Splat};

/// Σ_{i ∈ PT's strategies} w_i² / r_i for the path strategy (s, t) built, relative to its
/// own density p_{s,t} (module essay). 0 where PT can reach the path by neither strategy.
pub fn pt_moment_factor(scene: &Scene, light: &[Vertex], camera: &[Vertex], sampled: Option<&Vertex>, s: usize, t: usize, heuristic: Heuristic) -> f64 {
    let n = s + t;
    if n == 2 {
        // An emitter seen directly: PT's camera ray alone, weight 1, as BDPT's (0, 2).
        return if s == 0 { 1.0 } else { 0.0 };
    }
    // Walk densities relative to the strategy's own: r̃₀ = p̃_{0,n} / p̃_{s,t}, r̃₁ likewise.
    let (mut r0, mut r1) = (0.0f64, 0.0f64);
    match s {
        0 => r0 = 1.0,
        1 => r1 = 1.0,
        _ => {}
    }
    for_each_strategy_ratio(scene, light, camera, sampled, s, t, &mut |s2, t2, ratio| {
        debug_assert_eq!(s2 + t2, n);
        match s2 {
            0 => r0 = ratio,
            1 => r1 = ratio,
            _ => {}
        }
    });
    // The path's vertex k counted from its light end.
    let vertex = |k: usize| if k < s { strategy_vertex(light, s, sampled, k) } else { strategy_vertex(camera, t, sampled, n - 1 - k) };
    if r1 > 0.0 {
        let c = cone_over_position(scene, vertex(0), vertex(1));
        if s == 1 {
            // The strategy's own density is c p̃: every ratio to it divides by c.
            r0 /= c;
        } else {
            r1 *= c;
        }
    }
    let h = |r: f64| match heuristic {
        Heuristic::Balance => r,
        Heuristic::Power => r * r,
    };
    let total = h(r0) + h(r1);
    if !(total > 0.0) || !total.is_finite() {
        return 0.0;
    }
    // w_i² / r_i, w_i = h(r_i) / Σ_j h(r_j): PT's own MIS weight of strategy i.
    let term = |r: f64| if r > 0.0 { (h(r) / total) * (h(r) / total) / r } else { 0.0 };
    let m = term(r0) + term(r1);
    if m.is_finite() { m } else { 0.0 }
}

/// The density with which next-event estimation from `from` reaches the light point `at`
/// (PT's `sample_li`, converted to area at `at`), over the position density BDPT's walk
/// counts for it; 1 where the two agree (triangles, Dirac and infinite lights) or
/// either is not positive.
fn cone_over_position(scene: &Scene, at: &Vertex, from: &Vertex) -> f64 {
    let Some(id) = at.light_id() else { return 1.0 };
    let light = &scene.lights[id as usize];
    if light.is_delta_position() || light.is_infinite() {
        return 1.0;
    }
    let d = at.p - from.exit.p;
    let dist2 = d.length_squared();
    if !(dist2 > 0.0) {
        return 1.0;
    }
    let wi = d / crate::math::sqrt(dist2);
    let cos_at = at.ng.dot(wi).abs();
    let sampled = light.pdf_li(from.exit.p, wi, at.p, at.ng).to_area(cos_at, dist2).0 as f64;
    let position = light.pdf_le(at.p, at.ng, -wi).0.0 as f64;
    if sampled > 0.0 && position > 0.0 && sampled.is_finite() && position.is_finite() { sampled / position } else { 1.0 }
}

/// One BDPT sample per pixel in `pixels`, each strategy's contribution replaced by its
/// term of PT's second moment (module essay): per pixel, the mean over passes estimates
/// the second moment of one PT sample of that pixel. Camera-side terms go to `out`,
/// t = 1 terms to `splat` (the film scales them by 1/(W·H) as BDPT's). BDPT's streams,
/// so the probe draws BDPT's paths.
pub fn render_pixels<Q: RayQuery + ?Sized>(
    scene: &Scene,
    tracer: &Q,
    params: &RenderParams,
    pass: u32,
    pixels: Range<u32>,
    out: &mut [Rgb],
    splat: &mut dyn FnMut(Splat),
) -> Counters {
    let light_paths = (scene.camera.width() as f64 * scene.camera.height() as f64).max(1.0);
    let sample = Sample { scene, tracer, params, kernel: Kernel::Dirac, pass };
    sample.each_strategy(pixels, out, splat, |light, camera, s, t, c, counters| {
        let value = counters.sanitize(c.value);
        if value.is_black() {
            return Rgb::ZERO;
        }
        let sampled = c.sampled.as_ref();
        let weight = mis_weight(scene, light, camera, sampled, s, t) as f64;
        // A splat's value is W·H times a pixel sample's (module essay).
        let scale = if c.film.is_some() { 1.0 / light_paths } else { 1.0 };
        let factor = weight * pt_moment_factor(scene, light, camera, sampled, s, t, params.heuristic) * scale;
        counters.sanitize(value.map(|v| (v as f64 * v as f64 * factor) as f32))
    })
}
