//! Absorbing media inside glass (issue 56): what PT and LT must get right.
//!
//! - **PT against the analytic transmittance.** A camera looks, at normal incidence
//!   (fov 2°), through a glass slab of thickness d (η = 1.5) at a large emitter behind it.
//!   Only paths that cross the slab reach the emitter: once straight through, or after
//!   2k internal reflections, each crossing of the slab attenuated by T = exp(−σ_t d):
//!   L = L_e (1 − F)² T / (1 − F² T²), F = ((η − 1)/(η + 1))² = 0.04. With σ_t = 0 the
//!   same formula gives the clear slab, so the ratio of the two checks exp(−σ_t d) with
//!   the Fresnel terms, which nearly cancel. Checked per channel (σ_t differs by channel)
//!   to 4 standard errors. Seen failing with the transmittance's test of the face turned
//!   round (`ng · dir < 0`: the segments *outside* the slab, which end on its front
//!   faces, were attenuated instead: red read 0.338 against 0.718, z = −277).
//! - **PT, LT and BDPT agree** on a diffuse floor lit through an absorbing slab by an
//!   area light above it (the camera between floor and slab): per 8 × 8 block, z-test per
//!   block and channel, Šidák-corrected. Seen failing with LT's `Walk::pass_medium`
//!   removed (LT read the clear slab's light: red 0.552 against PT's 0.493, z = −3.9,
//!   the first channel checked).
//! - **Every estimator agrees with PT** through a rough absorbing slab
//!   ([`every_estimator_sees_the_rough_absorbing_slab`]): all 14 of the registry, colour
//!   balance and level, with the injected bugs it was seen to catch.
//! - **The filters through the smooth slab** ([`filter_estimators_see_the_absorbing_slab`]):
//!   their Dirac continuations, which carry T in their throughput.

use ember_core::bsdf::{Material, MicrofacetKind};
use ember_core::camera::{FovAxis, PerspectiveCamera};
use ember_core::estimators::{
    EstimatorConfig, EstimatorKind, FilterConfig, FilterReuse, FilterSide, KernelChoice, Renderer, RendererError, SegmentAlgorithm, SegmentConfig,
};
use ember_core::math::Mat4;
use ember_core::merge::RadiusRule;
use ember_core::scene::{AreaEmission, MediumIntruder, Scene, SceneBuilder, SceneError, builtin};
use ember_core::spectrum::Rgb;
use ember_core::transport::{MaxDepth, RenderParams};
use ember_tests::chi2::sidak;
use ember_tests::render::{Passes, assert_blocks_agree, push_block_means, spcbpt_config};
use ember_tests::stats::{MeanVar, normal_two_sided_p};
use ember_tests::tracer::BruteForce;
use glam::Vec3;

/// The slab's extinction per unit length, per channel.
const SIGMA_T: [f32; 3] = [0.5, 1.0, 2.0];
/// The slab's thickness.
const D: f32 = 0.5;
const ETA: f32 = 1.5;

/// Camera at the origin looking along +z through a 40 × 40 slab z ∈ [2, 2 + D] at an
/// emitter (radiance 1, facing the camera) at z = 5; the slab absorbs with `sigma_t`.
fn slab_scene(sigma_t: Option<Rgb>) -> (Scene, BruteForce) {
    let mut b = SceneBuilder::new();
    let cam = builtin::look_at(Vec3::ZERO, Vec3::new(0.0, 0.0, 1.0), Vec3::Y);
    b.set_camera(PerspectiveCamera::new(cam, 2.0, FovAxis::X, 16, 16));
    let glass = b.add_material(Material::dielectric(ETA, 1.0, Rgb::ONE, Rgb::ONE));
    let glass = match sigma_t {
        Some(s) => b.add_interior(glass, s),
        None => glass,
    };
    b.add_cube(Mat4::from_translation(Vec3::new(0.0, 0.0, 2.0 + D / 2.0)) * Mat4::from_scale(Vec3::new(20.0, 20.0, D / 2.0)), false, glass, None);
    let black = b.add_material(Material::diffuse(Rgb::ZERO));
    let light = AreaEmission { radiance: Rgb::ONE, two_sided: false };
    // The rectangle faces +z; flipped, it faces the camera.
    b.add_rectangle(Mat4::from_translation(Vec3::new(0.0, 0.0, 5.0)) * Mat4::from_scale(Vec3::splat(50.0)), true, black, Some(light));
    let (scene, geometry, _) = b.build().expect("scene");
    (scene, BruteForce::new(geometry))
}

/// The image mean per channel over `passes` passes of PT, with its standard error.
fn pt_mean(scene: &Scene, tracer: &BruteForce, passes: u32) -> [MeanVar; 3] {
    let params = RenderParams { max_depth: MaxDepth::UNBOUNDED, seed: 56, ..RenderParams::default() };
    let mut runner = Passes::new(scene, tracer, &params, EstimatorKind::Pt.default_config());
    let mut stats = [MeanVar::default(); 3];
    for pass in 0..passes {
        let (img, c) = runner.pass_image(pass);
        assert_eq!(c.discarded, 0);
        for ch in 0..3 {
            stats[ch].push(img.iter().map(|p| p[ch]).sum::<f64>() / img.len() as f64);
        }
    }
    stats
}

#[test]
fn pt_through_an_absorbing_slab_matches_the_analytic_transmittance() {
    let f = ((ETA as f64 - 1.0) / (ETA as f64 + 1.0)).powi(2);
    let through = |t: f64| (1.0 - f).powi(2) * t / (1.0 - f * f * t * t);
    let (clear_scene, clear_tracer) = slab_scene(None);
    let (scene, tracer) = slab_scene(Some(Rgb::new(SIGMA_T[0], SIGMA_T[1], SIGMA_T[2])));
    let clear = pt_mean(&clear_scene, &clear_tracer, 24);
    let absorbing = pt_mean(&scene, &tracer, 24);
    for c in 0..3 {
        let t = (-(SIGMA_T[c] as f64) * D as f64).exp();
        for (name, s, want) in [("clear", &clear[c], through(1.0)), ("absorbing", &absorbing[c], through(t))] {
            let z = (s.mean() - want) / s.std_error().max(1e-9);
            assert!(z.abs() < 4.0, "{name} slab, channel {c}: PT {} ± {} against {want} (z = {z:.2})", s.mean(), s.std_error());
        }
        let ratio = absorbing[c].mean() / clear[c].mean();
        let want = through(t) / through(1.0);
        println!("channel {c}: ratio {ratio:.5}, analytic {want:.5}, exp(-sigma_t d) = {t:.5}");
    }
}

/// A 1 × 1 diffuse floor at z = 0, an absorbing slab z ∈ [0.6, 1.0] (1.2 × 1.2) above it
/// and an area light (1 × 1, facing down) at z = 1.5; the camera at z = 0.45 looks down.
fn lit_floor(rough: bool) -> (Scene, BruteForce) {
    let mut b = SceneBuilder::new();
    let cam = builtin::look_at(Vec3::new(0.0, 0.0, 0.45), Vec3::ZERO, Vec3::Y);
    b.set_camera(PerspectiveCamera::new(cam, 90.0, FovAxis::X, RES, RES));
    let floor = b.add_material(Material::diffuse(Rgb::splat(0.7)));
    b.add_rectangle(Mat4::from_scale(Vec3::splat(0.5)), false, floor, None);
    let glass = if rough {
        Material::rough_dielectric(MicrofacetKind::Ggx, 0.6, ETA, 1.0, Rgb::ONE, Rgb::ONE)
    } else {
        Material::dielectric(ETA, 1.0, Rgb::ONE, Rgb::ONE)
    };
    let glass = b.add_material(glass);
    let glass = b.add_interior(glass, Rgb::new(0.3, 1.0, 3.0));
    b.add_cube(Mat4::from_translation(Vec3::new(0.0, 0.0, 0.8)) * Mat4::from_scale(Vec3::new(0.6, 0.6, 0.2)), false, glass, None);
    let black = b.add_material(Material::diffuse(Rgb::ZERO));
    // A small light under the rough slab makes BDPT's joins across it carry most of the image.
    let (le, half) = if rough { (100.0, 0.1) } else { (4.0, 0.5) };
    let light = AreaEmission { radiance: Rgb::splat(le), two_sided: false };
    b.add_rectangle(Mat4::from_translation(Vec3::new(0.0, 0.0, 1.5)) * Mat4::from_scale(Vec3::splat(half)), true, black, Some(light));
    let (scene, geometry, _) = b.build().expect("scene");
    (scene, BruteForce::new(geometry))
}

const RES: u32 = 16;
const BLOCK: u32 = 8;
const BLOCKS: usize = ((RES / BLOCK) * (RES / BLOCK)) as usize;

/// Per-block statistics of `kind` over `n` passes of `scene`.
fn block_stats(scene: &Scene, tracer: &BruteForce, kind: EstimatorKind, n: u32) -> Vec<[MeanVar; 3]> {
    let params = RenderParams { max_depth: MaxDepth(12), seed: 9, ..RenderParams::default() };
    let mut passes = Passes::new(scene, tracer, &params, kind.default_config());
    let mut s = vec![[MeanVar::default(); 3]; BLOCKS];
    for pass in 0..n {
        let (img, c) = passes.pass_image(pass);
        assert_eq!(c.discarded, 0);
        push_block_means(&mut s, &img, RES as usize, BLOCK as usize);
    }
    s
}

#[test]
fn pt_lt_and_bdpt_agree_through_an_absorbing_slab() {
    let (scene, tracer) = lit_floor(false);
    let pt = block_stats(&scene, &tracer, EstimatorKind::Pt, 200);
    assert!(pt[0][0].mean() > 0.01 && pt[0][0].mean() > pt[0][2].mean(), "the floor is lit, blue absorbed most: {:?}", pt[0].map(|s| s.mean()));
    let alpha = sidak(0.01, 2 * BLOCKS * 3);
    for kind in [EstimatorKind::Lt, EstimatorKind::Bdpt] {
        let other = block_stats(&scene, &tracer, kind, 200);
        let min_p = assert_blocks_agree(&format!("{kind:?} vs PT through an absorbing slab"), &pt, &other, alpha);
        println!("{kind:?}: {} comparisons, smallest p = {min_p:.4}", BLOCKS * 3);
    }
}

/// The filter estimators (MVF, BPF, PhF: kernel estimators, consistent but biased at a
/// finite kernel) through the same smooth absorbing slab. Their node walks carry T on the
/// continuation that crossed the medium, so the image's colour (green and blue against
/// red, which T changes by channel: 0.89, 0.67, 0.30 across the slab) must be PT's within
/// 3 %. Their level is checked loosely (20 %): BPF reads 14 % below PT on this scene with
/// or without absorption (σ_t = 0 gives the same shortfall, every channel alike), a
/// limitation of BPF here, not of the media. Seen failing with T removed from the light
/// nodes' walk (`filter::nodes`: BPF's green/red 1.35× PT's) and from the camera nodes'
/// (MVF's, 1.35×). PhF's own camera-side T is not pinned here: its camera paths stop at
/// the floor, which the camera sees directly (its photons come from the light nodes).
#[test]
fn filter_estimators_see_the_absorbing_slab() {
    let (scene, tracer) = lit_floor(false);
    let mean = |kind: EstimatorKind, n: u32| {
        let stats = block_stats(&scene, &tracer, kind, n);
        [0, 1, 2].map(|c| stats.iter().map(|b| b[c].mean()).sum::<f64>() / stats.len() as f64)
    };
    let pt = mean(EstimatorKind::Pt, 200);
    for kind in [EstimatorKind::Mvf, EstimatorKind::Bpf, EstimatorKind::Phf] {
        let m = mean(kind, 60);
        println!("{kind:?}: {m:?} against PT {pt:?}");
        assert!((m[0] / pt[0] - 1.0).abs() < 0.2, "{kind:?}: red {} against PT's {}", m[0], pt[0]);
        for c in 1..3 {
            let balance = (m[c] / m[0]) / (pt[c] / pt[0]);
            assert!((balance - 1.0).abs() < 0.03, "{kind:?} channel {c} against red: {balance} of PT's");
        }
    }
}

/// Per-pass image means (r, g, b) of `config` on `scene` over `n` passes.
fn pass_means(scene: &Scene, tracer: &BruteForce, config: EstimatorConfig, n: u32) -> Vec<[f64; 3]> {
    let params = RenderParams { max_depth: MaxDepth(12), seed: 9, ..RenderParams::default() };
    let mut passes = Passes::new(scene, tracer, &params, config);
    (0..n)
        .map(|pass| {
            let (img, c) = passes.pass_image(pass);
            assert_eq!(c.discarded, 0, "{config:?}: non-finite samples");
            [0, 1, 2].map(|ch| img.iter().map(|p| p[ch]).sum::<f64>() / img.len() as f64)
        })
        .collect()
}

/// Mean and standard error of channel `c` over passes.
fn channel(m: &[[f64; 3]], c: usize) -> (f64, f64) {
    let mut s = MeanVar::default();
    for p in m {
        s.push(p[c]);
    }
    (s.mean(), s.std_error())
}

/// Channel `c` over red (the colour the slab's transmittance gives), with its standard
/// error by the delta method (the channels of one pass are correlated).
fn balance(m: &[[f64; 3]], c: usize) -> (f64, f64) {
    let n = m.len() as f64;
    let (mr, mc) = (channel(m, 0).0, channel(m, c).0);
    let cov = |a: usize, b: usize, ma: f64, mb: f64| m.iter().map(|p| (p[a] - ma) * (p[b] - mb)).sum::<f64>() / (n - 1.0) / n;
    let r = mc / mr;
    let var = r * r * (cov(c, c, mc, mc) / (mc * mc) + cov(0, 0, mr, mr) / (mr * mr) - 2.0 * cov(0, c, mr, mc) / (mr * mc));
    (r, var.max(0.0).sqrt())
}

/// Every estimator of the registry through the rough (GGX 0.6) absorbing slab of
/// [`lit_floor`], where paths cross the slab's interior on walk segments, on
/// connections (BDPT's joins between its faces, segment BDPT's bridges, LVCBPT's and
/// SPCBPT's cached-vertex connections), in merged photons (PPM, BPM, VCM) and on the
/// filters' reused segments (MVF, PhF, BPF). PT is held to the closed form by
/// [`pt_through_an_absorbing_slab_matches_the_analytic_transmittance`]; here the 13
/// others are held to PT on the image mean per channel, each pass an independent
/// estimate:
///
/// - **Colour balance**, green and blue over red (what T changes: 0.89, 0.67, 0.30 per
///   crossing of the slab's thickness), against PT's, for all 13: z-test, the standard
///   error by the delta method (a pass's channels are correlated), with an allowance of
///   1 % of PT's value for the estimators with a kernel (PPM, BPM, VCM, MVF, PhF, BPF;
///   SPT, SLT, SBDPT run with the disk kernel, r = 0.03, so that segment BDPT's bridges
///   join kernel-moved ends), whose blur could shift the balance a little (measured:
///   0.25 % at most).
/// - **Level**: LT, BDPT, LVCBPT, SPCBPT against PT, and segment BDPT and LT against
///   segment PT with the same disk kernel (the same segment path integral), per channel
///   by z-test; the kernel estimators within 15 % of PT (measured: 5–8 % low for the
///   merging ones, 6–8 % high for the filters: their kernels' bias on this scene).
///
/// All 44 z-tests together Šidák-corrected to 1 %; failures are collected and reported
/// together. About 2.5–4 s on one core. Injected bugs seen to fail it, one at a time
/// (reverted): T removed from BDPT's interior join in `path::connect` (blue over red,
/// BDPT z = 15, LVCBPT 19, SPCBPT 15, SBDPT 14; VCM not caught: its merges carry those
/// paths); T kept off only the joins with a kernel-moved end, i.e. segment BDPT's
/// bridges alone (SBDPT z = 13.7, every other estimator passing); the light sub-path
/// walk's `pass_medium` removed in `path::walk` (BDPT, LVCBPT, SPCBPT, SBDPT, BPM, VCM
/// z > 100, PPM's photons white); T left out of the filters' reused continuations,
/// `Continuation::transmittance` returning 1 (MVF, PhF balance 1.0, BPF 0.72 against
/// 0.32; level 1.20, 1.20, 1.17 of PT's). Before this test the filters read the rough
/// slab as clear glass: that last bug was the code.
#[test]
fn every_estimator_sees_the_rough_absorbing_slab() {
    let (scene, tracer) = lit_floor(true);
    let disk = SegmentConfig { kernel: KernelChoice::Disk, radius: RadiusRule::Absolute(0.03) };
    let segment = |a| EstimatorConfig::Segment(a, disk);
    // (estimator, configuration, passes, has a kernel)
    let runs = [
        (EstimatorKind::Lt, EstimatorKind::Lt.default_config(), 100, false),
        (EstimatorKind::Bdpt, EstimatorKind::Bdpt.default_config(), 100, false),
        (EstimatorKind::Lvcbpt, EstimatorKind::Lvcbpt.default_config(), 100, false),
        (EstimatorKind::Spcbpt, EstimatorConfig::Spcbpt(spcbpt_config(16, 4, 2000, 2000, RES * RES, 0.5)), 100, false),
        (EstimatorKind::Ppm, EstimatorKind::Ppm.default_config(), 50, true),
        (EstimatorKind::Bpm, EstimatorKind::Bpm.default_config(), 50, true),
        (EstimatorKind::Vcm, EstimatorKind::Vcm.default_config(), 50, true),
        (EstimatorKind::Spt, segment(SegmentAlgorithm::PathTracing), 200, true),
        (EstimatorKind::Slt, segment(SegmentAlgorithm::LightTracing), 100, true),
        (EstimatorKind::Sbdpt, segment(SegmentAlgorithm::Bidirectional), 100, true),
        (EstimatorKind::Mvf, EstimatorKind::Mvf.default_config(), 60, true),
        (EstimatorKind::Phf, EstimatorKind::Phf.default_config(), 60, true),
        (EstimatorKind::Bpf, EstimatorKind::Bpf.default_config(), 60, true),
    ];
    let listed: Vec<_> = runs.iter().map(|r| r.0).chain([EstimatorKind::Pt]).collect();
    assert!(EstimatorKind::ALL.iter().all(|k| listed.contains(k)), "an estimator of the registry is not checked");
    let pt = pass_means(&scene, &tracer, EstimatorKind::Pt.default_config(), 400);
    let results: Vec<_> = runs.iter().map(|&(kind, config, n, kernel)| (kind, pass_means(&scene, &tracer, config, n), kernel)).collect();
    let of = |k: EstimatorKind| &results.iter().find(|r| r.0 == k).expect("run").1;
    // (name, estimator, reference): the same integral, compared per channel.
    let levels = [
        ("LT vs PT", of(EstimatorKind::Lt), &pt),
        ("BDPT vs PT", of(EstimatorKind::Bdpt), &pt),
        ("LVCBPT vs PT", of(EstimatorKind::Lvcbpt), &pt),
        ("SPCBPT vs PT", of(EstimatorKind::Spcbpt), &pt),
        ("SBDPT vs SPT (disk)", of(EstimatorKind::Sbdpt), of(EstimatorKind::Spt)),
        ("SLT vs SPT (disk)", of(EstimatorKind::Slt), of(EstimatorKind::Spt)),
    ];
    let alpha = sidak(0.01, levels.len() * 3 + runs.len() * 2);
    let mut failed = Vec::new();
    for (name, m, reference) in levels {
        for c in 0..3 {
            let ((a, sa), (b, sb)) = (channel(m, c), channel(reference, c));
            let z = (a - b) / (sa * sa + sb * sb).sqrt();
            println!("{name}, channel {c}: {a:.5} vs {b:.5} (z = {z:.2})");
            if normal_two_sided_p(z) <= alpha {
                failed.push(format!("{name}, channel {c}: {a:.5} vs {b:.5} (z = {z:.2})"));
            }
        }
    }
    let pt_red = channel(&pt, 0).0;
    for (kind, m, kernel) in &results {
        let level = channel(m, 0).0 / pt_red;
        if *kernel && (level - 1.0).abs() >= 0.15 {
            failed.push(format!("{kind:?}: red {level:.3} of PT's"));
        }
        for c in 1..3 {
            let ((a, sa), (b, sb)) = (balance(m, c), balance(&pt, c));
            let allowance = if *kernel { 0.01 * b } else { 0.0 };
            let z = ((a - b).abs() - allowance).max(0.0) / (sa * sa + sb * sb).sqrt();
            println!("{kind:?}: channel {c} over red {a:.4} against PT's {b:.4} (z beyond the allowance {z:.2}), level {level:.3}");
            if normal_two_sided_p(z) <= alpha {
                failed.push(format!("{kind:?}: channel {c} over red {a:.4} against PT's {b:.4} (z = {z:.2} beyond the allowance {allowance:.4})"));
            }
        }
    }
    assert!(failed.is_empty(), "α = {alpha:.1e} per test:\n{}", failed.join("\n"));
}

/// What the transmittance rule cannot attenuate is refused for every host, not only by
/// the Mitsuba reader: `build` refuses a camera inside the slab
/// ([`SceneError::InsideMedium`]), and BPF with bridge segments is refused in a scene
/// with a medium ([`RendererError::BridgesInMedium`]). Seen failing with `build`'s check
/// removed (the scene built).
#[test]
fn what_the_media_rule_cannot_see_is_refused() {
    let mut b = SceneBuilder::new();
    let cam = builtin::look_at(Vec3::new(0.0, 0.0, 0.8), Vec3::ZERO, Vec3::Y);
    b.set_camera(PerspectiveCamera::new(cam, 90.0, FovAxis::X, RES, RES));
    let glass = b.add_material(Material::dielectric(ETA, 1.0, Rgb::ONE, Rgb::ONE));
    let glass = b.add_interior(glass, Rgb::ONE);
    b.add_cube(Mat4::from_translation(Vec3::new(0.0, 0.0, 0.8)) * Mat4::from_scale(Vec3::new(0.6, 0.6, 0.2)), false, glass, None);
    match b.build() {
        Err(SceneError::InsideMedium(m, MediumIntruder::Camera)) => assert_eq!(m, glass),
        other => panic!("camera inside the slab: {:?}", other.map(|_| ())),
    }
    let (scene, _) = lit_floor(true);
    let bridges = FilterConfig { reuse: FilterReuse::Bridges, ..FilterConfig::DEFAULT };
    let refused = Renderer::new(&scene, RenderParams::default(), EstimatorConfig::Filter(FilterSide::Both, bridges));
    assert!(matches!(refused, Err(RendererError::BridgesInMedium)), "{refused:?}");
}
