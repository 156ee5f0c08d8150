//! Cross-renderer check: our path tracer on the built-in Cornell box (the suite's
//! geometry, materials and camera) against Mitsuba 3's reference of the same scene.
//!
//! We render at 32×32; each of our 8×8-pixel blocks covers exactly a 64×64 block of the
//! 256×256 reference (box filter: pixel values are area averages), so block means are
//! the same measurement. Our per-pass block means give a standard error; the reference's
//! own error is estimated from its two half-sample images. z-test per block and channel,
//! Šidák-corrected. This pins conventions a self-consistent renderer can get wrong
//! together: handedness of the camera, fov axis, the twosided wrapper, emitter sides.
//!
//! Injected-bug check (done once, reverted): mirroring the film horizontally (the
//! pbrt-style camera the suite README warns about) fails at the first block, the red
//! wall's corner (z = −92).

use ember_core::estimators::EstimatorKind;
use ember_core::transport::{MaxDepth, RenderParams};
use ember_tests::chi2::sidak;
use ember_tests::reference::{read_exr, scenes_dir};
use ember_tests::render::{block_means, render_pass};
use ember_tests::scenes::cornell;
use ember_tests::stats::{MeanVar, normal_two_sided_p};
use ember_tests::tracer::BruteForce;

#[test]
fn path_tracer_matches_mitsuba_on_the_cornell_box() {
    const RES: u32 = 32;
    const BLOCK: u32 = 8;
    let dir = scenes_dir().join("cornell-box");
    let reference = read_exr(&dir.join("reference.exr")).expect("the suite's reference must be beside the repository (../shared/scenes)");
    let half_a = read_exr(&dir.join("reference-half-a.exr")).unwrap();
    let half_b = read_exr(&dir.join("reference-half-b.exr")).unwrap();
    let scale = reference.width / RES as usize;

    let (scene, geometry, _) = cornell(RES, RES).build().unwrap();
    let tracer = BruteForce::new(geometry);
    // The scene file's max_depth is 30.
    let params = RenderParams { max_depth: MaxDepth(30), seed: 23, ..RenderParams::default() };
    let nb = (RES / BLOCK) as usize;
    let mut stats = vec![[MeanVar::default(); 3]; nb * nb];
    for pass in 0..256 {
        let (img, _) = render_pass(EstimatorKind::Pt, &scene, &tracer, &params, pass);
        for (s, v) in stats.iter_mut().zip(&block_means(&img, RES as usize, BLOCK as usize)) {
            for c in 0..3 {
                s[c].push(v[c]);
            }
        }
    }
    let alpha = sidak(0.01, nb * nb * 3);
    let rb = BLOCK as usize * scale;
    let mut min_p = 1.0f64;
    for by in 0..nb {
        for bx in 0..nb {
            let r = reference.block_mean(bx, by, rb, rb);
            let (a, b) = (half_a.block_mean(bx, by, rb, rb), half_b.block_mean(bx, by, rb, rb));
            for c in 0..3 {
                let ours = &stats[by * nb + bx][c];
                let ref_se = 0.5 * (a[c] - b[c]).abs();
                let se = (ours.std_error().powi(2) + ref_se * ref_se).sqrt();
                let z = (ours.mean() - r[c]) / se;
                let p = normal_two_sided_p(z);
                min_p = min_p.min(p);
                assert!(p > alpha, "block ({bx}, {by}) channel {c}: ours {} ± {} vs Mitsuba {} (z = {z:.2})", ours.mean(), ours.std_error(), r[c]);
            }
        }
    }
    println!("{} comparisons with Mitsuba, smallest p = {min_p:.4}", nb * nb * 3);
}
