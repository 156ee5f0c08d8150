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

use ember_core::bsdf::{Material, MicrofacetKind};
use ember_core::camera::{FovAxis, PerspectiveCamera};
use ember_core::estimators::EstimatorKind;
use ember_core::math::Mat4;
use ember_core::scene::{AreaEmission, Scene, SceneBuilder, builtin};
use ember_core::spectrum::Rgb;
use ember_core::transport::{MaxDepth, RenderParams};
use ember_tests::chi2::sidak;
use ember_tests::render::{Passes, assert_blocks_agree, push_block_means};
use ember_tests::stats::MeanVar;
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

/// The same floor under a rough (GGX 0.6) absorbing slab and a small bright light:
/// shadow rays now cross the slab's interior, so BDPT's connections between a vertex on
/// its top face and one on its bottom face carry T (`Scene::transmittance_to`), and
/// agree with PT, whose paths find the light only by crossing the slab on their own
/// segments (800 passes each; smallest p 0.095 against the corrected 0.00084). Seen
/// failing with the interior join's transmittance removed from `path::connect` (blue,
/// block 0: BDPT 0.0728 against PT's 0.0642, z = −3.83); with 200 passes it still
/// passed once, with the light 1 × 1 and GGX 0.3, so the margin is this test's weak
/// point.
#[test]
fn bdpt_connections_across_a_rough_absorbing_slab_agree_with_pt() {
    let (scene, tracer) = lit_floor(true);
    let pt = block_stats(&scene, &tracer, EstimatorKind::Pt, 800);
    let bdpt = block_stats(&scene, &tracer, EstimatorKind::Bdpt, 800);
    let min_p = assert_blocks_agree("BDPT vs PT through a rough absorbing slab", &pt, &bdpt, sidak(0.01, BLOCKS * 3));
    println!("{} comparisons, smallest p = {min_p:.4}", BLOCKS * 3);
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
