//! `--estimator auto`: the estimator chosen per scene by a pilot race, its time counted
//! in the render's budget.
//!
//! Every candidate ([`CANDIDATES`]) renders the scene at a quarter of the resolution per
//! axis (so a pass costs about 1/16 of a full one) for an equal slice of the budget, in
//! [`BATCHES`] batches. From the batches' images the race estimates, per candidate:
//!
//! - the variance of one pass per pixel, σ²(p) = Σ_b n_b (X_b − X̄)² / (B − 1), from the
//!   batch means X_b of n_b passes each (an unbiased estimate for independent passes);
//! - a bias: the candidates' per-pixel median image is the reference r; over blocks of
//!   8×8 pixels, what the squared difference of a candidate's block mean to the
//!   reference's exceeds its own variance counts as squared bias. This is what exposes
//!   a path tracer that never finds a light seen through a mirror: its variance is
//!   small because its image is black;
//! - the time of a pass at full resolution: the pilot's pass time times the pixel
//!   ratio, but for a fixed part of a pass (dispatch, staging, commit) that does not
//!   scale, found by timing PT's pass at both sizes (up to three passes of PT on the
//!   render's own scene first); the setup's time times the ratio.
//!
//! The predicted relMSE (the suite's metric, (x − r)²/(r² + 0.01)) after the remaining
//! time T is mean_p σ²(p)/(r² + 0.01) · t_pass / (T − t_setup) + bias², and the
//! candidate with the smallest one renders. Without `--time` the race assumes
//! [`NOMINAL_SECONDS`] of rendering.
//!
//! The merging candidates keep their radius in pixel footprints and one light path per
//! pixel, so a pilot kernel holds as many photons as a full one: the per-pass variance
//! and the cost of a merge carry over, and the pass time scales with the pixels. (A
//! radius kept in world units would hold 1/16 of the photons, and a full pass would
//! then cost 16 × more per merge than the pixel ratio says: measured, BPM's pass time
//! was underestimated 6× that way on enclosed.) The kernel is 4× wider in world units
//! than the render's, so the pilot overstates merging's bias.
//!
//! Known limit (docs/plan.md): a few batches see no rare fireflies, so variance is
//! underestimated where they dominate.

use std::time::{Duration, Instant};

use ember_core::render::{EstimatorConfig, EstimatorKind, Film};

use crate::cli::RenderArgs;
use crate::driver::{DriverConfig, Limits};
use crate::estimators::{CoreRenderer, PreparedScene};

/// The estimators the race runs: between them the best at equal time on every suite
/// scene (docs/results.md, docs/results-merging.md).
pub const CANDIDATES: [EstimatorKind; 5] = [EstimatorKind::Pt, EstimatorKind::Lt, EstimatorKind::Bdpt, EstimatorKind::Ppm, EstimatorKind::Bpm];
/// Batches per candidate.
pub const BATCHES: usize = 4;
/// The share of the budget each candidate's pilot takes.
pub const SHARE: f64 = 0.02;
/// The rendering time the race assumes without `--time`.
pub const NOMINAL_SECONDS: f64 = 10.0;
/// The pilot's resolution divisor per axis.
const DOWNSCALE: u32 = 4;
/// Bias blocks, in pilot pixels per side.
const BLOCK: u32 = 8;

/// One candidate's race result.
#[derive(Clone, Debug)]
pub struct Entry {
    /// The estimator.
    pub kind: EstimatorKind,
    /// Passes in the pilot.
    pub passes: u32,
    /// Seconds per pass at full resolution (estimated).
    pub pass_seconds: f64,
    /// Setup seconds at full resolution (estimated).
    pub setup_seconds: f64,
    /// Mean over pixels of σ²/(r² + 0.01) for one pass.
    pub variance: f64,
    /// Squared relative bias against the median image.
    pub bias: f64,
    /// Predicted relMSE after the remaining time.
    pub predicted: f64,
}

/// One candidate's pilot: what the race reads from it.
struct Run {
    kind: EstimatorKind,
    config: EstimatorConfig,
    /// The mean image of all its passes.
    image: Vec<[f32; 3]>,
    /// Per pixel and channel, the variance of one pass ([`pass_variance`]).
    variance: Vec<[f64; 3]>,
    /// Seconds in its passes, and their count.
    seconds: f64,
    passes: u32,
    /// Seconds its setup took.
    setup: f64,
}

/// What the race decided, and its account.
#[derive(Clone, Debug)]
pub struct Choice {
    /// The estimator that renders.
    pub kind: EstimatorKind,
    /// Every candidate's numbers.
    pub entries: Vec<Entry>,
    /// Seconds the race took.
    pub seconds: f64,
    /// The pilot's resolution.
    pub size: (u32, u32),
    /// Seconds of a pass that do not scale with its pixels (from PT at both sizes).
    pub overhead: f64,
}

impl Choice {
    /// The race in words, one line per candidate and one for the choice.
    pub fn describe(&self) -> Vec<String> {
        let mut lines = vec![format!(
            "auto       pilot race at {}x{} in {:.2} s (fixed cost of a pass {:.1} ms):",
            self.size.0,
            self.size.1,
            self.seconds,
            1e3 * self.overhead
        )];
        for e in &self.entries {
            lines.push(format!(
                "auto         {:<5} {:>4} passes, {:.3e} s/pass at full size, setup {:.2} s, variance {:.3e}, bias² {:.3e} -> relMSE {:.3e}",
                e.kind.name(),
                e.passes,
                e.pass_seconds,
                e.setup_seconds,
                e.variance,
                e.bias,
                e.predicted
            ));
        }
        lines.push(format!("auto       renders with {}", self.kind.name()));
        lines
    }
}

/// The pilot's resolution for a film of `w`×`h`: a quarter per axis, at least 16 pixels
/// (or the film's own size where it is smaller).
pub fn pilot_size(w: u32, h: u32) -> (u32, u32) {
    let scale = |n: u32| (n / DOWNSCALE).max(16.min(n)).max(1);
    (scale(w), scale(h))
}

/// Run the race for a render of `full` (already prepared) with `args`; `load` prepares
/// the same scene at a given resolution; the budget runs from `start`.
pub fn choose(
    args: &RenderArgs,
    full: PreparedScene,
    max_depth: i32,
    start: Instant,
    load: &dyn Fn(u32, u32) -> Result<PreparedScene, String>,
) -> Result<(Choice, PreparedScene), String> {
    let race_start = Instant::now();
    let budget = args.time.unwrap_or(NOMINAL_SECONDS + start.elapsed().as_secs_f64());
    let slice = (SHARE * budget).max(0.02);
    let (fw, fh) = (full.scene.camera.width(), full.scene.camera.height());
    let (w, h) = pilot_size(fw, fh);
    let ratio = (fw as f64 * fh as f64) / (w as f64 * h as f64);
    let threads = args.thread_count();
    // A pass has a fixed cost (dispatch, staging, commit) besides its pixels', which the
    // pixel ratio would scale too: PT's pass time at full size, measured on the render's
    // own scene for up to three passes, gives it (o below).
    let mut pt = CoreRenderer::with_config(full, args.cache.config_for(EstimatorKind::Pt), max_depth, args.seed ^ 0x5eed_a071, threads)?;
    let mut film = Film::with_filter(fw, fh, pt.camera_filter());
    let limits = Limits { spp: 3, deadline: Some(Instant::now() + Duration::from_secs_f64(slice)), interrupt: Some(crate::interrupt::flag()), first_pass: 0 };
    let summary = pt.render(&mut film, limits, DriverConfig { progress: false, ..DriverConfig::with_threads(threads) }, start).map_err(|e| e.to_string())?;
    let pt_full = summary.render_seconds / summary.passes.max(1) as f64;
    let full = pt.prepared;
    let mut prepared = Some(load(w, h)?);
    let mut runs: Vec<Run> = Vec::new();
    for kind in CANDIDATES {
        let scene = prepared.take().ok_or("the pilot scene was lost")?;
        let config = args.cache.config_for(kind);
        let mut r = CoreRenderer::with_config(scene, config, max_depth, args.seed ^ 0x5eed_a070, threads)?;
        let mut film = Film::with_filter(w, h, r.camera_filter());
        let mut batches: Vec<(u32, Vec<[f32; 3]>)> = Vec::new();
        let mut render_seconds = 0.0;
        let (mut held, mut prev) = (0u32, vec![[0.0f32; 3]; (w * h) as usize]);
        for b in 0..BATCHES {
            let deadline = Instant::now() + Duration::from_secs_f64(slice / BATCHES as f64);
            let limits = Limits { spp: u32::MAX, deadline: Some(deadline), interrupt: Some(crate::interrupt::flag()), first_pass: 0 };
            let summary =
                r.render(&mut film, limits, DriverConfig { progress: false, ..DriverConfig::with_threads(threads) }, start).map_err(|e| e.to_string())?;
            render_seconds += summary.render_seconds;
            // The batch's own mean from the running means before and after it.
            let cum = film.to_rgb_f32();
            let n = film.passes() - held;
            let batch: Vec<[f32; 3]> = cum
                .iter()
                .zip(&prev)
                .map(|(c, p)| core::array::from_fn(|k| ((c[k] as f64 * film.passes() as f64 - p[k] as f64 * held as f64) / n.max(1) as f64) as f32))
                .collect();
            batches.push((n, batch));
            held = film.passes();
            prev = cum;
            if summary.interrupted {
                break;
            }
            // A candidate whose first batch overran its whole slice has passes too slow
            // for this budget: one more batch gives its variance, no more.
            if b >= 1 && render_seconds > 2.0 * slice {
                break;
            }
        }
        let variance = pass_variance(&batches, &prev);
        runs.push(Run { kind, config, image: prev, variance, seconds: render_seconds, passes: film.passes(), setup: r.setup_seconds });
        prepared = Some(r.prepared);
    }
    // The reference: per pixel and channel, the median of the candidates' images.
    let pixels = (w * h) as usize;
    let mut reference = vec![[0.0f32; 3]; pixels];
    for (p, rp) in reference.iter_mut().enumerate() {
        for (k, rk) in rp.iter_mut().enumerate() {
            let mut v: Vec<f32> = runs.iter().map(|r| r.image[p][k]).collect();
            v.sort_by(f32::total_cmp);
            *rk = v[v.len() / 2];
        }
    }
    // Each candidate's per-pass variance per pixel and channel; the median over the
    // candidates of the variance of their mean images stands for the reference's (a
    // median of similar estimates has about the variance of one).
    let reference_variance: Vec<[f64; 3]> = (0..pixels)
        .map(|p| {
            core::array::from_fn(|k| {
                let mut v: Vec<f64> = runs.iter().map(|r| r.variance[p][k] / r.passes.max(1) as f64).collect();
                v.sort_by(f64::total_cmp);
                v[v.len() / 2]
            })
        })
        .collect();
    let remaining = (budget - start.elapsed().as_secs_f64()).max(0.05 * budget);
    // t_low = o + b, t_full = o + ratio·b for PT: the fixed part o of a pass.
    let pt_low = runs.iter().find(|r| r.kind == EstimatorKind::Pt).map_or(0.0, |r| r.seconds / r.passes.max(1) as f64);
    let overhead = if ratio > 1.0 { ((pt_low * ratio - pt_full) / (ratio - 1.0)).clamp(0.0, pt_low) } else { 0.0 };
    let mut entries = Vec::new();
    for Run { kind, config, image: mean, variance: variance_px, seconds, passes, setup } in runs {
        let rel = |p: usize, k: usize| (reference[p][k] as f64).powi(2) + 0.01;
        let variance = (0..pixels).map(|p| (0..3).map(|k| variance_px[p][k] / rel(p, k)).sum::<f64>()).sum::<f64>() / (3 * pixels.max(1)) as f64;
        let bias = block_bias(w, h, &mean, &reference, &variance_px, passes.max(1), &reference_variance);
        let low = seconds / passes.max(1) as f64;
        let pass_seconds = if kind == EstimatorKind::Pt { pt_full } else { (low - overhead).max(0.0) * ratio + overhead };
        let setup_seconds = setup * ratio;
        let left = (remaining - setup_seconds).max(pass_seconds).max(1e-3);
        // A merging radius shrinks as r_i ∝ (i + 1)^((α − 1)/2), so a pass's variance
        // (∝ 1/r²) grows as (i + 1)^(1 − α): the render's passes, up to N = left / t_pass,
        // average (N / n_pilot)^(1 − α) times the pilot's first n_pilot.
        let growth = match config {
            EstimatorConfig::Merging(_, c) => ((left / pass_seconds) / passes.max(1) as f64).max(1.0).powf(1.0 - c.alpha as f64),
            _ => 1.0,
        };
        let predicted = variance * growth * pass_seconds / left + bias;
        entries.push(Entry {
            kind,
            passes,
            pass_seconds,
            setup_seconds,
            variance,
            bias,
            predicted: if predicted.is_nan() { f64::INFINITY } else { predicted },
        });
    }
    let best = entries.iter().min_by(|a, b| a.predicted.total_cmp(&b.predicted)).map_or(EstimatorKind::Pt, |e| e.kind);
    Ok((Choice { kind: best, entries, seconds: race_start.elapsed().as_secs_f64(), size: (w, h), overhead }, full))
}

/// Per pixel and channel, the variance of one pass, Σ_b n_b (X_b − X̄)² / (B − 1), from
/// the batch means X_b of n_b passes and the mean image X̄ (infinite with one batch).
fn pass_variance(batches: &[(u32, Vec<[f32; 3]>)], mean: &[[f32; 3]]) -> Vec<[f64; 3]> {
    (0..mean.len())
        .map(|p| {
            core::array::from_fn(|k| {
                if batches.len() < 2 {
                    return f64::INFINITY;
                }
                let s: f64 = batches.iter().map(|(n, im)| *n as f64 * (im[p][k] as f64 - mean[p][k] as f64).powi(2)).sum();
                s / (batches.len() - 1) as f64
            })
        })
        .collect()
}

/// Squared relative bias of `mean` against `reference` over blocks of [`BLOCK`]² pixels:
/// per block and channel max(0, (m̄ − r̄)² − Var(m̄) − Var(r̄)) / (r̄² + 0.01), averaged,
/// where Var(m̄) is the block's mean per-pass variance over its pixel count and
/// `passes`, and Var(r̄) the same of the reference's per-pixel variances.
fn block_bias(w: u32, h: u32, mean: &[[f32; 3]], reference: &[[f32; 3]], variance: &[[f64; 3]], passes: u32, reference_variance: &[[f64; 3]]) -> f64 {
    let (bw, bh) = (w.div_ceil(BLOCK), h.div_ceil(BLOCK));
    let mut total = 0.0;
    let mut count = 0usize;
    for by in 0..bh {
        for bx in 0..bw {
            for k in 0..3 {
                let (mut m, mut r, mut v, mut vr, mut n) = (0.0f64, 0.0f64, 0.0f64, 0.0f64, 0usize);
                for y in by * BLOCK..((by + 1) * BLOCK).min(h) {
                    for x in bx * BLOCK..((bx + 1) * BLOCK).min(w) {
                        let p = (y * w + x) as usize;
                        m += mean[p][k] as f64;
                        r += reference[p][k] as f64;
                        v += variance[p][k];
                        vr += reference_variance[p][k];
                        n += 1;
                    }
                }
                let n = n.max(1) as f64;
                let (m, r) = (m / n, r / n);
                let var_mean = v / (n * n) / passes as f64 + vr / (n * n);
                let excess = (m - r).powi(2) - var_mean;
                if excess.is_finite() && excess > 0.0 {
                    total += excess / (r * r + 0.01);
                }
                count += 1;
            }
        }
    }
    total / count.max(1) as f64
}
