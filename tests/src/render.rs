//! Single-threaded pass rendering for tests: one image per pass, so per-pass statistics
//! (independent across passes) give honest error bars.

use ember_core::geometry::RayQuery;
use ember_core::integrator::{Counters, RenderParams, Splat, bdpt, lt, pt};
use ember_core::scene::Scene;
use ember_core::spectrum::Rgb;

use crate::stats::{MeanVar, normal_two_sided_p};

/// The estimators under test.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Estimator {
    Pt,
    Lt,
    Bdpt,
}

impl Estimator {
    pub const ALL: [Estimator; 3] = [Estimator::Pt, Estimator::Lt, Estimator::Bdpt];
}

/// Render one pass: one sample per pixel (PT, BDPT) or W·H light paths (LT, and BDPT's
/// light paths); returns the pass image in f64 and the counters.
pub fn render_pass<Q: RayQuery>(est: Estimator, scene: &Scene, tracer: &Q, params: &RenderParams, pass: u32) -> (Vec<[f64; 3]>, Counters) {
    let (w, h) = (scene.camera.width(), scene.camera.height());
    let n = (w * h) as usize;
    let mut img = vec![[0.0f64; 3]; n];
    let mut camera = vec![Rgb::ZERO; n];
    let mut splats: Vec<Splat> = Vec::new();
    let counters = match est {
        Estimator::Pt => pt::render_pixels(scene, tracer, params, pass, 0..n as u32, &mut camera),
        Estimator::Lt => lt::trace_paths(scene, tracer, params, pass, 0..n as u32, &mut |s| splats.push(s)),
        Estimator::Bdpt => bdpt::render_pixels(scene, tracer, params, pass, 0..n as u32, &mut camera, &mut |s| splats.push(s)),
    };
    for (px, c) in img.iter_mut().zip(&camera) {
        *px = c.to_f64();
    }
    let scale = 1.0 / n as f64;
    for s in splats {
        let (x, y) = (s.film.x.floor() as i64, s.film.y.floor() as i64);
        if x >= 0 && y >= 0 && (x as u32) < w && (y as u32) < h {
            let px = &mut img[(y as u32 * w + x as u32) as usize];
            for c in 0..3 {
                px[c] += s.value[c] as f64 * scale;
            }
        }
    }
    (img, counters)
}

/// Per-channel means over square `block`×`block` pixel blocks of a `width`-wide image,
/// blocks in row-major order (the comparisons between estimators and references).
pub fn block_means(img: &[[f64; 3]], width: usize, block: usize) -> Vec<[f64; 3]> {
    let height = img.len() / width.max(1);
    let (bx, by) = (width / block, height / block);
    let mut sums = vec![[0.0f64; 3]; bx * by];
    for (i, px) in img.iter().enumerate() {
        let (x, y) = (i % width, i / width);
        if x / block < bx && y / block < by {
            let s = &mut sums[(y / block) * bx + x / block];
            for c in 0..3 {
                s[c] += px[c] / (block * block) as f64;
            }
        }
    }
    sums
}

/// Add one pass image's [`block_means`] to per-block, per-channel statistics.
pub fn push_block_means(stats: &mut [[MeanVar; 3]], img: &[[f64; 3]], width: usize, block: usize) {
    for (s, mean) in stats.iter_mut().zip(&block_means(img, width, block)) {
        for c in 0..3 {
            s[c].push(mean[c]);
        }
    }
}

/// Two-sided z-test of every block and channel of `other` against `reference` (means of
/// independent passes); panics naming `name`, the block and channel when p ≤ `alpha`.
/// Returns the smallest p.
pub fn assert_blocks_agree(name: &str, reference: &[[MeanVar; 3]], other: &[[MeanVar; 3]], alpha: f64) -> f64 {
    let mut min_p = 1.0f64;
    for (b, (x, y)) in reference.iter().zip(other).enumerate() {
        for c in 0..3 {
            let z = (x[c].mean() - y[c].mean()) / (x[c].std_error().powi(2) + y[c].std_error().powi(2)).sqrt();
            let p = normal_two_sided_p(z);
            min_p = min_p.min(p);
            assert!(p > alpha, "{name}: block {b}, channel {c}: reference {} vs {} (z = {z:.2})", x[c].mean(), y[c].mean());
        }
    }
    min_p
}
