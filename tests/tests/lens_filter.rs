//! Thin lens and pixel filters (issue 25): χ² of the lens and filter-offset samplers,
//! the filter weight's normalisation, and PT/LT/BDPT agreement through a thin lens with
//! a gaussian filter (camera samples by filter importance sampling, splats spread by
//! the filter on the film).

use ember_core::camera::Lens;
use ember_core::filter::Filter;
use ember_core::integrator::{MaxDepth, RenderParams};
use ember_core::math::{Vec2, Vec3};
use ember_core::render::EstimatorKind;
use ember_core::rng::{SampleStream, Stream};
use ember_core::warp::invert_concentric_disk;
use ember_tests::chi2::sidak;
use ember_tests::render::{assert_blocks_agree, push_block_means, render_pass};
use ember_tests::stats::{MeanVar, chi2_survival};
use ember_tests::tracer::BruteForce;

/// χ² statistic and p-value of `counts` against `expected` (bins with expected < 5 pooled).
fn chi2(counts: &[f64], expected: &[f64]) -> (f64, f64) {
    let (mut stat, mut dof, mut pool_o, mut pool_e) = (0.0, 0usize, 0.0, 0.0);
    for (&o, &e) in counts.iter().zip(expected) {
        if e < 5.0 {
            pool_o += o;
            pool_e += e;
        } else {
            stat += (o - e) * (o - e) / e;
            dof += 1;
        }
    }
    if pool_e > 0.0 {
        stat += (pool_o - pool_e) * (pool_o - pool_e) / pool_e;
        dof += 1;
    }
    (stat, chi2_survival(stat, (dof - 1) as f64))
}

/// The lens points of `sample_wi` are uniform over the aperture by area: mapped back to
/// the unit square by the inverse concentric map they fill a 10×10 grid evenly.
/// Injected bug: the lens point drawn as R·u (not R·√u) in radius, i.e. dense at the
/// centre: p = 0 (χ² ≈ 2.7·10⁴ over 99 dof).
#[test]
fn lens_points_are_uniform_by_area() {
    let (scene, _, _) = ember_core::scene::builtin::cornell_box(16, 16).build().expect("scene");
    let lens = Lens::new(0.2, 7.8).unwrap();
    let cam = scene.camera.with_lens(Some(lens));
    let p_ref = Vec3::new(0.1, 1.0, 0.0);
    let n = 200_000;
    let mut counts = vec![0.0; 100];
    let mut rng = SampleStream::for_sample(5, Stream::Aux, 0, 0, 0);
    let inv = cam.forward();
    for _ in 0..n {
        let cs = cam.sample_wi(p_ref, rng.next_2d()).expect("in view");
        // Back to camera space: x is −world x here (the builtin camera looks down −z).
        let d = cs.position - cam.position();
        assert!(d.dot(inv).abs() < 1e-4, "on the lens plane");
        let local = Vec2::new(-d.x, d.y) / lens.radius;
        let u = invert_concentric_disk(local);
        let (i, j) = (((u.x * 10.0) as usize).min(9), ((u.y * 10.0) as usize).min(9));
        counts[j * 10 + i] += 1.0;
    }
    let (stat, p) = chi2(&counts, &vec![n as f64 / 100.0; 100]);
    println!("lens χ² = {stat:.1}, p = {p:.3}");
    assert!(p > 1e-3, "lens points not uniform: χ² = {stat}, p = {p}");
}

/// A lens connection and the primary ray agree: the ray that `generate_ray_lens` draws
/// through the connection's film point from the same lens sample starts at the
/// connection's lens point and heads for the connected point; without a lens the lens
/// sample changes nothing. Injected bug: the connection's film point taken as the
/// pinhole's (film_position of the direction, ignoring the focus plane): the ray misses
/// by up to 0.082 in direction (|Δdir| against the 1e-3 tolerance).
#[test]
fn lens_connection_inverts_the_primary_ray() {
    let (scene, _, _) = ember_core::scene::builtin::cornell_box(24, 16).build().expect("scene");
    let pinhole = scene.camera;
    let cam = pinhole.with_lens(Lens::new(0.25, 4.0));
    let mut rng = SampleStream::for_sample(9, Stream::Aux, 2, 0, 0);
    let mut checked = 0;
    for _ in 0..20_000 {
        let p = Vec3::new(rng.next_f32() * 2.0 - 1.0, rng.next_f32() * 2.0, rng.next_f32() * 2.0 - 1.0);
        let u = rng.next_2d();
        let Some(cs) = cam.sample_wi(p, u) else { continue };
        let ray = cam.generate_ray_lens(cs.film, u);
        assert!((ray.origin - cs.position).length() < 1e-4, "origin {} vs {}", ray.origin, cs.position);
        assert!((ray.dir + cs.wi).length() < 1e-3, "direction {} vs {}", ray.dir, -cs.wi);
        checked += 1;
        if let Some(ps) = pinhole.sample_wi(p, u) {
            let p0 = pinhole.sample_wi(p, Vec2::ZERO).unwrap();
            assert_eq!((ps.film, ps.importance, ps.position), (p0.film, p0.importance, p0.position));
        }
    }
    assert!(checked > 10_000, "{checked}");
}

/// The filter offsets follow `pdf_offset`, for tent and gaussian.
/// Injected bug: the gaussian's truncation constant erf(r/(σ√2)) left out of the sample
/// map (the untruncated normal, clamped): p = 0 (χ² ≈ 250).
#[test]
fn filter_offsets_follow_their_density() {
    for f in [Filter::Tent { radius: 1.0 }, Filter::Tent { radius: 1.6 }, Filter::Gaussian { stddev: 0.5 }, Filter::Gaussian { stddev: 1.1 }] {
        let r = f.radius() as f64;
        let bins = 40;
        let n = 200_000;
        let mut counts = vec![0.0; bins];
        let mut rng = SampleStream::for_sample(7, Stream::Aux, 1, 0, 0);
        for _ in 0..n {
            let d = f.sample_offset(rng.next_f32()) as f64;
            counts[(((d + r) / (2.0 * r) * bins as f64) as usize).min(bins - 1)] += 1.0;
        }
        // Expected counts by Simpson's rule on each bin.
        let expected: Vec<f64> = (0..bins)
            .map(|b| {
                let (a, h) = (-r + 2.0 * r * b as f64 / bins as f64, 2.0 * r / bins as f64);
                let k = 16;
                let mut s = 0.0;
                for i in 0..=k {
                    let w = if i == 0 || i == k { 1.0 } else if i % 2 == 1 { 4.0 } else { 2.0 };
                    s += w * f.pdf_offset((a + h * i as f64 / k as f64) as f32) as f64;
                }
                s * h / (3.0 * k as f64) * n as f64
            })
            .collect();
        let (stat, p) = chi2(&counts, &expected);
        println!("{f:?}: χ² = {stat:.1}, p = {p:.3}");
        assert!(p > 1e-3, "{f:?}: χ² = {stat}, p = {p}");
    }
}

/// E[w] over a pixel's camera samples is 1 in the interior (the weight's f/(p ∫f) has
/// mean 1) and K_c's integral ∫_F h_c = 1 holds at the border (midpoint quadrature).
/// Injected bug: K_c computed as ∫_F f / ∫f (inverted): the border pixel's ∫_F h_c is
/// 0.83 instead of 1.
#[test]
fn filter_weights_are_normalised() {
    for f in [Filter::Tent { radius: 1.3 }, Filter::Gaussian { stddev: 0.5 }, Filter::Gaussian { stddev: 0.8 }] {
        let (scene, _, _) = ember_core::scene::builtin::cornell_box(12, 12).build().expect("scene");
        let cam = scene.camera.with_filter(f);
        // E[w] = ∫_F h_c = 1 for an interior pixel and for the corner one (whose samples
        // outside F weigh 0).
        for (px, py) in [(6u32, 5u32), (0, 0)] {
            let mut m = MeanVar::default();
            for s in 0..100_000u32 {
                let mut rng = SampleStream::for_sample(3, Stream::Camera, py * 12 + px, s, 0);
                m.push(cam.sample_ray(px, py, &mut rng).map_or(0.0, |p| p.weight as f64));
            }
            let z = (m.mean() - 1.0) / m.std_error().max(1e-12);
            println!("{f:?}: E[w] at pixel ({px}, {py}) = {:.6} (z = {z:.2})", m.mean());
            assert!(z.abs() < 4.0 || (m.mean() - 1.0).abs() < 1e-6, "{f:?} ({px}, {py}): E[w] = {} (z = {z:.2})", m.mean());
        }
        // ∫_F h_c(x) dx = 1 at border pixels: h_c is separable, so a product of 1-D
        // midpoint rules over [max(0, c − r), min(W, c + r)].
        let axis = |i: u32, extent: u32| {
            let c = i as f64 + 0.5;
            let (lo, hi) = ((c - f.radius() as f64).max(0.0), (c + f.radius() as f64).min(extent as f64));
            let k = 20_000;
            let step = (hi - lo) / k as f64;
            (0..k).map(|j| f.splat_weight((lo + (j as f64 + 0.5) * step) as f32, i, extent) as f64 * step).sum::<f64>()
        };
        for (px, py) in [(0u32, 0u32), (1, 0), (11, 5)] {
            let sum = axis(px, 12) * axis(py, 12);
            println!("{f:?}: ∫_F h_c at pixel ({px}, {py}) = {sum:.6}");
            assert!((sum - 1.0).abs() < 1e-4, "{f:?} ({px}, {py}): ∫_F h_c = {sum}");
        }
    }
}

/// PT, LT and BDPT agree per 4×4 block on the Cornell box seen through a thin lens
/// focused on the back wall with Mitsuba's default gaussian filter: the lens connection
/// (W_e cosθ/d² at the lens point), the filtered splats and the importance-sampled
/// filter weights all estimate the same image. Injected bugs: the shadow ray of LT's
/// connections ending at the lens centre instead of the lens point (|z| up to 7 on LT
/// vs PT); the splats added to one pixel with weight 1 while camera samples are filtered
/// (|z| = 6.1).
#[test]
fn pt_lt_bdpt_agree_through_a_thin_lens_with_a_gaussian_filter() {
    let (w, h, block) = (16usize, 16usize, 4usize);
    let (mut scene, geometry, _) = ember_core::scene::builtin::cornell_box(w as u32, h as u32).build().expect("scene");
    scene.camera = scene.camera.with_lens(Lens::new(0.3, 5.0)).with_filter(Filter::MITSUBA_DEFAULT);
    let tracer = BruteForce::new(geometry);
    let params = RenderParams { max_depth: MaxDepth(4), seed: 17, ..RenderParams::default() };
    let count = (w / block) * (h / block);
    let estimators = [(EstimatorKind::Pt, 48u32), (EstimatorKind::Lt, 48), (EstimatorKind::Bdpt, 32)];
    let stats: Vec<Vec<[MeanVar; 3]>> = estimators
        .iter()
        .map(|&(est, passes)| {
            let mut stats = vec![[MeanVar::default(); 3]; count];
            for pass in 0..passes {
                let (img, counters) = render_pass(est, &scene, &tracer, &params, pass);
                assert_eq!(counters.discarded, 0);
                push_block_means(&mut stats, &img, w, block);
            }
            stats
        })
        .collect();
    let alpha = sidak(0.01, 3 * count * 3);
    for (a, b) in [(0, 1), (0, 2), (1, 2)] {
        let p = assert_blocks_agree(&format!("thin lens + gaussian: {:?} vs {:?}", estimators[a].0, estimators[b].0), &stats[a], &stats[b], alpha);
        println!("{:?} vs {:?}: smallest p = {p:.4}", estimators[a].0, estimators[b].0);
    }
}
