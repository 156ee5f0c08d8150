//! The environment map (`core/src/light/envmap.rs`): Mitsuba 3's lookup convention, a
//! density that integrates to one and covers every direction with radiance, an unbiased
//! direct-lighting estimate of its integral, and PT, LT and BDPT agreeing on an open
//! floor and in a room it lights through a window (every infinite-light strategy:
//! escaped camera paths, light paths from the scene disk, next-event estimation). The χ²
//! tests of its sampling are in `light_sampling.rs`.

use ember_core::estimators::EstimatorKind;
use ember_core::light::Light;
use ember_core::math::{PI, Vec3};
use ember_core::rng::{SampleStream, Stream};
use ember_core::spectrum::Rgb;
use ember_core::transport::{MaxDepth, RenderParams};
use ember_tests::chi2::sidak;
use ember_tests::render::{assert_blocks_agree, push_block_means, render_pass};
use ember_tests::scenes::window_room_lit;
use ember_tests::stats::MeanVar;
use ember_tests::tracer::BruteForce;

const W: u32 = 16;
const H: u32 = 8;

fn texels() -> Vec<Rgb> {
    (0..W * H).map(|k| Rgb::new((k % W) as f32 + 1.0, (k / W) as f32 + 1.0, if k == 37 { 50.0 } else { 0.5 })).collect()
}

const IDENTITY: [Vec3; 3] = [Vec3::X, Vec3::Y, Vec3::Z];

/// The world direction of (u, v) in Mitsuba's convention (identity frame).
fn dir(u: f32, v: f32) -> Vec3 {
    let (phi, theta) = (2.0 * PI * u, PI * v);
    Vec3::new(phi.sin() * theta.sin(), theta.cos(), -phi.cos() * theta.sin())
}

/// Texel (i, j) sits at u = (i + ½)/W (texel centres in φ) and v = j/(H − 1) (rows at the
/// poles' corners in θ), and halfway between two texels is their mean, across the seam
/// at u = 0 too. Injected bug it caught: rows at texel centres (y = vH − ½) instead of
/// at the corners: texel (0, 1) read green 3.29 for 4.
#[test]
fn lookup_follows_mitsuba() {
    let t = texels();
    let mut light = Light::environment_map(W, H, &t, 2.0, IDENTITY).expect("valid");
    light.set_scene_bounds(Vec3::ZERO, 1.0);
    let close = |a: Rgb, b: Rgb| {
        (a.r - b.r).abs() <= 1e-3 * b.r.abs().max(1.0) && (a.g - b.g).abs() <= 1e-3 * b.g.abs().max(1.0) && (a.b - b.b).abs() <= 1e-3 * b.b.abs().max(1.0)
    };
    for (i, j) in [(0u32, 1u32), (5, 2), (15, 6), (7, 4)] {
        let d = dir((i as f32 + 0.5) / W as f32, j as f32 / (H - 1) as f32);
        let want = t[(j * W + i) as usize] * 2.0;
        assert!(close(light.environment_radiance(d), want), "texel ({i}, {j}): {:?} against {want:?}", light.environment_radiance(d));
    }
    // Across the seam: u = 0 is halfway between the last column and the first.
    let d = dir(0.0, 3.0 / (H - 1) as f32);
    let want = (t[(3 * W + W - 1) as usize] + t[(3 * W) as usize]) * 0.5 * 2.0;
    assert!(close(light.environment_radiance(d), want), "seam: {:?} against {want:?}", light.environment_radiance(d));
    // The zenith reads row 0, the nadir the last row.
    // (Green is the row number + 1 in this map.)
    assert!((light.environment_radiance(Vec3::Y).g - 2.0).abs() < 1e-4);
    assert!((light.environment_radiance(-Vec3::Y).g - H as f32 * 2.0).abs() < 1e-4);
    // A rotated frame: the same lookup, in the rotated directions.
    let r = glam::Mat3::from_rotation_z(0.9);
    let mut turned = Light::environment_map(W, H, &t, 2.0, [r.x_axis, r.y_axis, r.z_axis]).expect("valid");
    turned.set_scene_bounds(Vec3::ZERO, 1.0);
    let d = dir(0.3, 0.4);
    assert!(close(turned.environment_radiance(r * d), light.environment_radiance(d)));
    // Bad input is refused.
    assert!(Light::environment_map(W, H, &t[..5], 1.0, IDENTITY).is_err());
    let mut nan = t.clone();
    nan[3].g = f32::NAN;
    assert!(Light::environment_map(W, H, &nan, 1.0, IDENTITY).is_err());
    assert!(Light::environment_map(W, H, &t, 1.0, [Vec3::X * 2.0, Vec3::Y, Vec3::Z]).is_err());
    assert!(Light::environment_map(W, H, &t, 1.0, [Vec3::X, Vec3::Y, -Vec3::Z]).is_err(), "a mirror is not a rotation");
}

/// Midpoint quadrature over (θ, φ) on a grid finer than the map: ∫ p dω = 1, and every
/// direction with radiance has density (light tracing draws its directions from here
/// alone). A map whose lower half is black checks the support at the black/lit border.
/// Injected bug it caught: cell weights from the cell's own texel only (no neighbours):
/// 91 200 grid directions just below the border had radiance and no density.
#[test]
fn density_integrates_to_one_and_covers_the_radiance() {
    let mut t = texels();
    for k in (W * H / 2) as usize..t.len() {
        t[k] = Rgb::ZERO;
    }
    let mut light = Light::environment_map(W, H, &t, 1.0, IDENTITY).expect("valid");
    light.set_scene_bounds(Vec3::ZERO, 1.0);
    let (nt, np) = (800usize, 1600usize);
    let mut integral = 0.0f64;
    let mut uncovered = 0usize;
    for a in 0..nt {
        let theta = (a as f64 + 0.5) / nt as f64 * core::f64::consts::PI;
        for b in 0..np {
            let phi = (b as f64 + 0.5) / np as f64 * 2.0 * core::f64::consts::PI;
            let w = Vec3::new((phi.sin() * theta.sin()) as f32, theta.cos() as f32, (-phi.cos() * theta.sin()) as f32);
            let pdf = light.pdf_li(Vec3::ZERO, w, w, Vec3::ZERO).0 as f64;
            integral += pdf * theta.sin() * (core::f64::consts::PI / nt as f64) * (2.0 * core::f64::consts::PI / np as f64);
            if light.environment_radiance(w).average() > 0.0 && !(pdf > 0.0) {
                uncovered += 1;
            }
        }
    }
    assert!((integral - 1.0).abs() < 2e-3, "∫ p dω = {integral}");
    assert_eq!(uncovered, 0, "directions with radiance and no density");
}

/// E[L/p] over `sample_li` equals ∫ L dω by quadrature, to 4 standard errors.
#[test]
fn direct_lighting_estimates_the_integral() {
    let t = texels();
    let r = glam::Mat3::from_rotation_x(0.3);
    let mut light = Light::environment_map(W, H, &t, 1.0, [r.x_axis, r.y_axis, r.z_axis]).expect("valid");
    light.set_scene_bounds(Vec3::ZERO, 1.0);
    let mut quad = 0.0f64;
    let (nt, np) = (600usize, 1200usize);
    for a in 0..nt {
        let theta = (a as f64 + 0.5) / nt as f64 * core::f64::consts::PI;
        for b in 0..np {
            let phi = (b as f64 + 0.5) / np as f64 * 2.0 * core::f64::consts::PI;
            let w = Vec3::new((phi.sin() * theta.sin()) as f32, theta.cos() as f32, (-phi.cos() * theta.sin()) as f32);
            quad +=
                light.environment_radiance(w).average() as f64 * theta.sin() * (core::f64::consts::PI / nt as f64) * (2.0 * core::f64::consts::PI / np as f64);
        }
    }
    let mut est = MeanVar::default();
    for k in 0..200_000u32 {
        let mut rng = SampleStream::for_sample(5, Stream::Aux, k, 0, 0);
        let s = light.sample_li(Vec3::ZERO, rng.next_2d()).expect("a sample");
        est.push((s.radiance.average() / s.pdf.0) as f64);
    }
    let z = (est.mean() - quad) / est.std_error();
    assert!(z.abs() < 4.0, "E[L/p] = {} ± {}, quadrature {quad} (z = {z:.2})", est.mean(), est.std_error());
}

/// The density follows the radiance across a small sun (issue 52): on a 64 × 32 map with
/// a dim sky and a 5-texel sun 2000× brighter (the shape of `scenes-extra/textured`'s),
/// L̄(ω)/p(ω) of `sample_li`'s directions between θ = π/4 and 3π/4 stays within a factor
/// 1.3 from smallest to largest, and the relative variance of L̄/p over all directions
/// is below 0.05: the bilinear density is the radiance's own interpolation times sin θ
/// on the lattice rows. Passing: max/min = 1.12, relative variance 3·10⁻⁴. The
/// piecewise-constant density before issue 52 (cells weighted by the brightest texel a
/// lookup reads) fails it: max/min = 2.2·10³, relative variance 1.48 on this map.
/// Injected bug: the lattice without sin θ (s_j = 1): max/min = 1.41.
#[test]
fn density_follows_the_radiance_across_a_small_sun() {
    let (w, h) = (64u32, 32u32);
    let sun = [(20u32, 10u32), (21, 10), (19, 11), (20, 11), (21, 11)];
    let t: Vec<Rgb> = (0..w * h).map(|k| if sun.contains(&(k % w, k / w)) { Rgb::new(900.0, 800.0, 650.0) } else { Rgb::new(0.3, 0.4, 0.6) }).collect();
    let mut light = Light::environment_map(w, h, &t, 1.0, IDENTITY).expect("valid");
    light.set_scene_bounds(Vec3::ZERO, 1.0);
    let lum = |c: Rgb| (0.2126 * c.r + 0.7152 * c.g + 0.0722 * c.b) as f64;
    let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
    let mut est = MeanVar::default();
    for k in 0..100_000u32 {
        let mut rng = SampleStream::for_sample(8, Stream::Aux, k, 0, 0);
        let s = light.sample_li(Vec3::ZERO, rng.next_2d()).expect("a sample");
        let ratio = lum(s.radiance) / s.pdf.0 as f64;
        est.push(ratio);
        let theta = s.wi.y.clamp(-1.0, 1.0).acos();
        if (0.25 * PI..=0.75 * PI).contains(&theta) {
            lo = lo.min(ratio);
            hi = hi.max(ratio);
        }
    }
    let rel_var = est.variance() / (est.mean() * est.mean());
    println!("L/p max/min = {:.3}, relative variance {rel_var:.4}", hi / lo);
    assert!(hi / lo < 1.3, "L/p from {lo} to {hi}");
    assert!(rel_var < 0.05, "relative variance {rel_var}");
}

fn sky(w: u32, h: u32) -> Vec<Rgb> {
    (0..w * h)
        .map(|k| {
            let (i, j) = (k % w, k / w);
            if (15..=16).contains(&i) && j == 5 {
                Rgb::new(60.0, 50.0, 40.0)
            } else if j >= h - 2 {
                Rgb::ZERO
            } else {
                Rgb::new(0.3, 0.4, 0.6) * (1.0 + j as f32 / 4.0)
            }
        })
        .collect()
}

fn sky_light() -> Light {
    let (w, h) = (32u32, 16u32);
    let r = glam::Mat3::from_rotation_y(0.2) * glam::Mat3::from_rotation_x(0.15);
    Light::environment_map(w, h, &sky(w, h), 1.0, [r.x_axis, r.y_axis, r.z_axis]).expect("valid")
}

/// Per-block, per-channel statistics of `estimators` (with their pass counts).
fn blocks(scene: &ember_core::scene::Scene, tracer: &BruteForce, estimators: &[(EstimatorKind, u32)], width: usize, block: usize) -> Vec<Vec<[MeanVar; 3]>> {
    let params = RenderParams { max_depth: MaxDepth(6), seed: 31, ..RenderParams::default() };
    let count = (width / block) * (scene.camera.height() as usize / block);
    estimators
        .iter()
        .map(|&(est, passes)| {
            let mut stats = vec![[MeanVar::default(); 3]; count];
            for pass in 0..passes {
                let (img, counters) = render_pass(est, scene, tracer, &params, pass);
                assert_eq!(counters.discarded, 0);
                push_block_means(&mut stats, &img, width, block);
            }
            stats
        })
        .collect()
}

/// Every pair of `stats` agrees per block and channel, Šidák-corrected over all of them.
fn assert_agree(name: &str, stats: &[Vec<[MeanVar; 3]>]) {
    let pairs: Vec<(usize, usize)> = (0..stats.len()).flat_map(|a| (a + 1..stats.len()).map(move |b| (a, b))).collect();
    let alpha = sidak(0.01, pairs.len() * stats[0].len() * 3);
    for (a, b) in pairs {
        assert_blocks_agree(&format!("{name}: estimators {a} and {b}"), &stats[a], &stats[b], alpha);
    }
}

/// PT, LT and BDPT agree per block on an open floor under a rotated map with a sun and
/// a black band at the nadir, and PT and BDPT in the window room it lights through the
/// window, as they do under the constant sky (`estimator_agreement.rs`). Injected bug it
/// caught: the emitted radiance of a light path read at its travel direction instead
/// of the direction toward the sky (`sample_le`): PT against LT on the open floor,
/// block 5, red, z = 8.3. (Halving `pdf_le` went unseen here: it enters only MIS weights of
/// strategies that carry little; the emission χ² test in `light_sampling.rs` sees it.)
#[test]
fn estimators_agree_under_an_environment_map() {
    let (scene, geometry, _) = ember_tests::scenes::open_floor(16, 12, sky_light()).build().expect("scene");
    let tracer = BruteForce::new(geometry);
    let open = blocks(&scene, &tracer, &[(EstimatorKind::Pt, 300), (EstimatorKind::Lt, 300), (EstimatorKind::Bdpt, 150)], 16, 4);
    assert_agree("open floor", &open);
    let (scene, geometry, _) = window_room_lit(16, 12, sky_light()).build().expect("scene");
    let tracer = BruteForce::new(geometry);
    let room = blocks(&scene, &tracer, &[(EstimatorKind::Pt, 600), (EstimatorKind::Bdpt, 300)], 16, 4);
    assert_agree("window room", &room);
}
