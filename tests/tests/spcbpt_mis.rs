//! SPCBPT's MIS weights (path-dependent counts: N·Γ(κ_L|κ_E)·W/Q for the Γ-connections,
//! 1 for s ≤ 1, M/(W·H) for t = 1) against an f64 brute force, and their sum over all
//! strategies able to produce one path.
//!
//! The brute force is `lvcbpt_mis.rs`'s (primitive densities only) with each strategy's
//! density product multiplied by the count `path_counts` gives for that split. Checked
//! on the Cornell box with a rough gold and a smooth glass sphere with a trained model:
//! (1) every weight `spcbpt::Strategies::evaluate` applies equals the brute force within 1e-5;
//! (2) re-splitting one full path at every split, the recursive weights (counts from the
//!     joined path of each split) sum to 1 within 1e-5 — which holds only if the counts
//!     are a function of the path alone, not of how it was sampled.
//! Injected-bug checks (each done once, reverted): indexing the count table by t′
//! instead of s′ in `spcbpt::Strategies::evaluate` fails (1) ((1, 2): 0.670 vs 0.934); reading
//! the camera-label memo at the wrong camera index (`n − j` instead of `n − 1 − j` for
//! κ_E in what was `path_counts_labelled`, now `counts::Labels::eye`) fails (1) ((6, 2):
//! 0.0411 vs 0.0277).
//! The memoized count tables (`spcbpt::counts` with a light memo and camera labels, the
//! render loop's path) equal `path_counts` of the joined path bit for bit; each of these
//! injected bugs fails that check: a camera vertex's prefix-weight factor taken with its
//! neighbours swapped ((1, 5): 1.3084742 vs 1.3084739, only bits differ), the light
//! memo's count read for the split next to the connection (`s2 + 1 <= memo.len()`:
//! (7, 1) reads NaN), and the camera split read one vertex off (`n − s2`: (4, 4)).
//! Not caught: taking W from the stored β of x_{s′−1} instead of
//! `light_prefix_weights` — (2) rebuilds every split from copies of the same vertices,
//! so their β agree; the end-to-end test (`spcbpt_agreement.rs`) is what guards that
//! the counts do not depend on how a path was sampled (it fails on this bug at z = −25.4).

use ember_core::estimators::spcbpt::{self, Model, join, memoize_light_path, path_counts};
use ember_core::measure::VertexPdf;
use ember_core::path::mis::mis_weight_counted;
use ember_core::path::{LightPointSample, Vertex, VertexKind, camera_subpath, light_subpath};
use ember_core::rng::{SampleStream, Stream};
use ember_core::scene::Context;
use ember_core::scene::Scene;
use ember_core::spectrum::Rgb;
use ember_core::transport::{Counters, MaxDepth, RenderParams};
use ember_tests::bdpt_oracle::{brute_force_weights, for_each_strategy_split};
use ember_tests::render::{spcbpt_config, spcbpt_model};
use ember_tests::scenes::cornell_with_spheres;
use ember_tests::tracer::BruteForce;
use glam::Vec2;

const LIGHT_TRACING: f64 = 0.37;

#[test]
fn spcbpt_weights_equal_brute_force_and_sum_to_one() {
    let (scene, geometry, _) = cornell_with_spheres(24, 24).build().expect("scene");
    let tracer = BruteForce::new(geometry);
    let params = RenderParams { max_depth: MaxDepth(8), seed: 9, ..RenderParams::default() };
    // s = 1 by next-event estimation (no light-source bins), then through the cache with
    // 8 light-source bins (connect_light_source, its count N·Γ·W₁/Q).
    for bins in [0, 8] {
        let (model, _) = spcbpt_model(&scene, &tracer, &params, spcbpt_config(32, bins, 3000, 3000, 200, 0.1));
        assert_eq!(model.caches_light_sources(), bins > 0);
        check_weights(&scene, &tracer, &params, &model, bins);
    }
}

fn check_weights(scene: &Scene, tracer: &BruteForce, params: &RenderParams, model: &Model, bins: u32) {
    let params = *params;
    let (mut checked, mut worst, mut emitter_hits, mut memo_checks) = (0usize, 0.0f64, 0usize, 0usize);
    let (mut paths, mut worst_sum) = (0usize, 0.0f64);
    for i in 0..1500u32 {
        let mut counters = Counters::default();
        let mut rng = SampleStream::for_sample(4, Stream::Camera, i, 0, 0);
        let film = rng.next_2d() * Vec2::splat(24.0);
        let cam = camera_subpath(scene, tracer, &params, film, 9, &mut rng, &mut counters);
        let mut lrng = SampleStream::for_sample(4, Stream::Light, i, 0, 0);
        let light = light_subpath(scene, tracer, &params, 8, &mut lrng, &mut counters);
        let mut light_memo = Vec::new();
        memoize_light_path(scene, model, &light, &mut light_memo);
        let labels_all = spcbpt::CameraLabels::new(scene, model, &cam);
        for t in 1..=cam.len() {
            for s in 0..=light.len() {
                if (s == 1 && t == 1) || s + t < 3 || s + t > 9 {
                    continue;
                }
                // Odd paths go through the memos of the render loop: labels of the whole
                // camera path (read for the prefix `cam[..t]`) and the light path's
                // per-vertex memo (read for `light[..s]`).
                let labels = (i % 2 == 1).then(|| spcbpt::CameraLabels::new(scene, model, &cam));
                let memo = if i % 2 == 1 { &light_memo[..s] } else { &[][..] };
                let strategies = spcbpt::Strategies { ctx: Context { scene, tracer }, model, light_tracing: LIGHT_TRACING };
                let u = LightPointSample { u_light: lrng.next_f32(), u_point: lrng.next_2d() };
                let Some(c) = strategies.evaluate_labelled(&light[..s], &cam[..t], labels.as_ref(), memo, s, t, u, &mut counters) else { continue };
                let x = join(&light, &cam, c.sampled, s, t);
                if x.last().unwrap().kind == VertexKind::InfiniteLight {
                    continue;
                }
                // The memos change no count, bit for bit (else the strategies of one path,
                // some evaluated with memos and some without, would not sum to one).
                {
                    let fresh_light = c.sampled.is_none() || t == 1;
                    let (mut with, mut without) = ([0.0f64; 70], [0.0f64; 70]);
                    let light_x = if s == 1 && c.sampled.is_some() { &x[..1] } else { &light[..s] };
                    let cam_x: Vec<Vertex> = x[s..].iter().rev().copied().collect();
                    let memo = if fresh_light { &light_memo[..s] } else { &[][..] };
                    spcbpt::counts(scene, model, LIGHT_TRACING, light_x, memo, &cam_x, Some(&labels_all), &mut with);
                    path_counts(scene, model, LIGHT_TRACING, &x, &mut without);
                    assert!(
                        with.iter().zip(&without).all(|(a, b)| a.to_bits() == b.to_bits()),
                        "({s}, {t}): counts with memos {:?} vs without {:?}",
                        &with[..x.len() + 1],
                        &without[..x.len() + 1]
                    );
                    memo_checks += 1;
                }
                // A camera path that hit an emitter must find the light-source bin a light
                // path starting there would (else the s = 0 and s = 1 counts of one path
                // disagree and its weights do not sum to one).
                if s == 0 && bins > 0 {
                    let y = &x[0];
                    let id = y.emitter.expect("an s = 0 path ends on an emitter");
                    let as_light = Vertex::light(id, y.p, y.ng, Rgb::ZERO, VertexPdf::discrete(1.0), false);
                    let (a, b) = (model.classifier.light_source_of(scene, y), model.classifier.light_source_of(scene, &as_light));
                    assert!(a.is_some() && a == b, "emitter hit at {:?}: bin {a:?}, as a light vertex {b:?}", y.p);
                    emitter_hits += 1;
                }
                let mut counts = [0.0f64; 70];
                path_counts(scene, model, LIGHT_TRACING, &x, &mut counts);
                let bf = brute_force_weights(scene, &x, |s, _| counts[s]);
                let expected = bf[s].expect("a strategy that produced a path must be possible");
                let diff = (expected - c.weight as f64).abs();
                worst = worst.max(diff);
                assert!(diff <= 1e-5, "(s, t) = ({s}, {t}): recursive {} vs brute force {expected}; all {bf:?}", c.weight);
                checked += 1;
                // (2) for exact joins (s, t ≥ 2): every split of the same path.
                if s >= 2 && t >= 2 {
                    let n = x.len();
                    let mut sum = 0.0f64;
                    for_each_strategy_split(scene, &x, |s2, t2, l, cm| {
                        let joined = join(l, cm, None, s2, t2);
                        let mut c2 = [0.0f64; 70];
                        path_counts(scene, model, LIGHT_TRACING, &joined, &mut c2);
                        sum += mis_weight_counted(scene, l, cm, None, s2, t2, &|a: usize, _b: usize| c2[a]) as f64;
                    });
                    worst_sum = worst_sum.max((sum - 1.0).abs());
                    assert!((sum - 1.0).abs() <= 1e-5, "weights of a {n}-vertex path sum to {sum}");
                    paths += 1;
                }
            }
        }
    }
    println!(
        "{bins} light-source bins: checked {checked} weights (worst |Δw| = {worst:e}), {paths} paths summed (worst |Σw − 1| = {worst_sum:e}), {emitter_hits} emitter hits classified, {memo_checks} count tables equal with memos"
    );
    assert!(checked > 3000 && paths > 500, "too few: {checked} weights, {paths} paths");
    assert!(bins == 0 || emitter_hits >= 10, "too few emitter hits: {emitter_hits}");
    // The same on 2000 emission samples: as a light vertex and as an emitting surface hit.
    if bins > 0 {
        let mut rng = SampleStream::for_sample(5, Stream::Aux, 0, 0, 0);
        let mut seen = std::collections::BTreeSet::new();
        for _ in 0..2000 {
            let id = ((rng.next_f32() * scene.lights.len() as f32) as usize).min(scene.lights.len() - 1);
            let Some(es) = scene.lights[id].sample_le(rng.next_2d(), rng.next_2d()) else { continue };
            let y = Vertex::light(id as u32, es.p, es.n, Rgb::ZERO, VertexPdf::discrete(1.0), false);
            let mut hit = y;
            hit.kind = VertexKind::Surface;
            let (a, b) = (model.classifier.light_source_of(scene, &y), model.classifier.light_source_of(scene, &hit));
            assert!(a.is_some() && a == b, "light {id} at {:?}: bin {a:?} as a light vertex, {b:?} as a surface hit", es.p);
            seen.insert(a.unwrap());
        }
        assert_eq!(seen.len() as u32, bins, "every bin is reached");
    }
}
