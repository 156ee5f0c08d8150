//! White furnace: inside a closed box whose walls all emit Le and reflect diffusely with
//! albedo a, the radiance is Le / (1 − a) in every direction. PT, LT and BDPT must each
//! agree with it within a Šidák-corrected bound from their own estimated variance.
//!
//! Per-pass image means are independent across passes (each pass has its own random
//! streams), so their spread gives the standard error of the overall mean.
//!
//! Injected-bug checks (each done once, reverted): dropping the |cos θ| of the light-path
//! origin in `lt` (β₀ = Le / pdfs) made LT read 3.00 for 2 (z ≈ 28); omitting the 1/q
//! Russian-roulette compensation (then inline in `pt`, now `survives_roulette`) made PT
//! read 1.90 (z ≈ −139).

use ember_core::transport::{MaxDepth, RenderParams};
use ember_tests::chi2::sidak;
use ember_tests::render::{PT_LT_BDPT, render_pass};
use ember_tests::scenes::furnace_box;
use ember_tests::stats::{MeanVar, normal_two_sided_p};
use ember_tests::tracer::BruteForce;

#[test]
fn every_estimator_matches_the_furnace() {
    let (albedo, le) = (0.5f32, 1.0f32);
    let truth = le as f64 / (1.0 - albedo as f64);
    let (scene, geometry, _) = furnace_box(albedo, le, 16, 16).build().expect("scene");
    let tracer = BruteForce::new(geometry);
    let params = RenderParams { max_depth: MaxDepth::UNBOUNDED, seed: 3, ..RenderParams::default() };
    let alpha = sidak(0.01, PT_LT_BDPT.len());
    for est in PT_LT_BDPT {
        let mut mv = MeanVar::default();
        for pass in 0..200 {
            let (img, c) = render_pass(est, &scene, &tracer, &params, pass);
            assert_eq!(c.discarded, 0, "{est:?} discarded samples");
            let mean: f64 = img.iter().map(|p| p[0] + p[1] + p[2]).sum::<f64>() / (3.0 * img.len() as f64);
            mv.push(mean);
        }
        let z = (mv.mean() - truth) / mv.std_error();
        let p = normal_two_sided_p(z);
        println!("{est:?}: mean {:.5} ± {:.5} (truth {truth}), z = {z:.2}, p = {p:.3}", mv.mean(), mv.std_error());
        assert!(p > alpha, "{est:?} disagrees with the furnace: {} vs {truth}, z = {z:.2}", mv.mean());
        // The bound must be tight enough to mean something: 1% of the value.
        assert!(mv.std_error() < 0.01 * truth, "{est:?} too noisy for a useful test: se {}", mv.std_error());
    }
}
