//! LVCBPT's recursive balance-heuristic weights with sample counts against a brute-force
//! evaluation (f64, every strategy, each density product multiplied by its count
//! n_{s,t}: 1 for s ≤ 1, M/(W·H) for t = 1, N/c̄ for s, t ≥ 2).
//!
//! The brute force is BDPT's (`bdpt_mis.rs`: primitive densities only, converted to area
//! here) with the counts added. Checked on the Cornell box with a rough gold and a
//! smooth glass sphere, with deliberately unequal counts (0.37 and 2.9):
//! (1) every weight `connect_counted` applies equals the brute force within 1e-5;
//! (2) over all strategies able to produce a full path, the weights sum to 1 within 1e-5.
//! Injected-bug checks (each done once, reverted), both in `mis_weight_counted`:
//! - the light-side loop using the camera-side count (count(s+t−i, i) instead of
//!   count(i, s+t−i)) fails (1) ((2, 1): 0.908 vs 0.812) and (2) (Σw = 1.098);
//! - the ratios not divided by the strategy's own count fails (1) ((2, 1): 0.921 vs
//!   0.812) and (2) (Σw = 0.914).

use ember_core::estimators::lvcbpt::StrategyCounts;
use ember_core::path::mis::mis_weight_counted;
use ember_core::path::{LightPointSample, Vertex, camera_subpath, connect, light_subpath};
use ember_core::rng::{SampleStream, Stream};
use ember_core::scene::Context;
use ember_core::transport::{Counters, MaxDepth, RenderParams};
use ember_tests::bdpt_oracle::{brute_force_weights, for_each_strategy_split, full_path};
use ember_tests::scenes::cornell_with_spheres;
use ember_tests::tracer::BruteForce;
use glam::Vec2;

const COUNTS: StrategyCounts = StrategyCounts { light_tracing: 0.37, connection: 2.9 };

#[test]
fn counted_weights_equal_brute_force_and_sum_to_one() {
    let (scene, geometry, _) = cornell_with_spheres(24, 24).build().expect("scene");
    let tracer = BruteForce::new(geometry);
    let params = RenderParams { max_depth: MaxDepth(8), seed: 9, ..RenderParams::default() };
    let count = |s: usize, t: usize| COUNTS.count(s, t);
    let (mut checked, mut worst) = (0usize, 0.0f64);
    for i in 0..2500u32 {
        let mut counters = Counters::default();
        let ctx = Context { scene: &scene, tracer: &tracer };
        let mut rng = SampleStream::for_sample(3, Stream::Camera, i, 0, 0);
        let film = rng.next_2d() * Vec2::splat(24.0);
        let cam = camera_subpath(&scene, &tracer, &params, film, 9, &mut rng, &mut counters);
        let mut lrng = SampleStream::for_sample(3, Stream::Light, i, 0, 0);
        let light = light_subpath(&scene, &tracer, &params, 8, &mut lrng, &mut counters);
        for t in 1..=cam.len() {
            for s in 0..=light.len() {
                if (s == 1 && t == 1) || s + t < 2 || s + t > 9 {
                    continue;
                }
                let u = LightPointSample { u_light: lrng.next_f32(), u_point: lrng.next_2d() };
                let Some(c) = connect(&ctx, &light[..s], &cam[..t.max(1)], s, t, u, &mut counters) else { continue };
                let c = c.weighted(mis_weight_counted(&scene, &light[..s], &cam[..t.max(1)], c.sampled.as_ref(), s, t, &count));
                let Some(x) = full_path(&light, &cam, s, t, c.sampled) else { continue };
                let bf = brute_force_weights(&scene, &x, |s, t| COUNTS.count(s, t));
                let expected = bf[s].expect("a strategy that produced a path must be possible");
                let diff = (expected - c.weight as f64).abs();
                worst = worst.max(diff);
                assert!(diff <= 1e-5, "(s, t) = ({s}, {t}), n = {}: recursive {} vs brute force {expected}; all {bf:?}", x.len(), c.weight);
                checked += 1;
            }
        }
    }
    println!("checked {checked} strategy weights, worst |Δw| = {worst:e}");
    assert!(checked > 4000, "too few connections exercised: {checked}");
}

#[test]
fn counted_weights_of_one_path_sum_to_one() {
    let (scene, geometry, _) = cornell_with_spheres(24, 24).build().expect("scene");
    let tracer = BruteForce::new(geometry);
    let count = |s: usize, t: usize| COUNTS.count(s, t);
    let params = RenderParams { max_depth: MaxDepth(8), seed: 5, ..RenderParams::default() };
    let (mut paths, mut worst) = (0usize, 0.0f64);
    for i in 0..1000u32 {
        let mut counters = Counters::default();
        let ctx = Context { scene: &scene, tracer: &tracer };
        let mut rng = SampleStream::for_sample(2, Stream::Camera, i, 0, 0);
        let film = rng.next_2d() * Vec2::splat(24.0);
        let cam = camera_subpath(&scene, &tracer, &params, film, 9, &mut rng, &mut counters);
        let mut lrng = SampleStream::for_sample(2, Stream::Light, i, 0, 0);
        let light = light_subpath(&scene, &tracer, &params, 8, &mut lrng, &mut counters);
        // Full paths from the light sub-path joined to the camera path at a diffuse vertex.
        for s in 2..=light.len() {
            for t in 2..=cam.len() {
                if s + t > 9 || connect(&ctx, &light, &cam, s, t, LightPointSample { u_light: 0.5, u_point: Vec2::splat(0.5) }, &mut counters).is_none() {
                    continue;
                }
                let mut x: Vec<Vertex> = light[..s].to_vec();
                x.extend(cam[..t].iter().rev().copied());
                let n = x.len();
                let mut sum = 0.0f64;
                for_each_strategy_split(&scene, &x, |s2, t2, l, c| sum += mis_weight_counted(&scene, l, c, None, s2, t2, &count) as f64);
                worst = worst.max((sum - 1.0).abs());
                assert!((sum - 1.0).abs() <= 1e-5, "weights of a {n}-vertex path sum to {sum}");
                paths += 1;
            }
        }
    }
    println!("{paths} full paths, worst |Σw − 1| = {worst:e}");
    assert!(paths > 2000, "too few paths: {paths}");
}
