//! `--estimator auto`: the estimator chosen per scene by a pilot race, its time counted
//! in the render's budget.
//!
//! Every candidate ([`CANDIDATES`]) renders the scene at a quarter of the resolution per
//! axis (so a pass costs about 1/16 of a full one) for an equal slice of the budget, in
//! [`BATCHES`] batches. From the batches' images the race estimates, per candidate:
//!
//! - the variance of one pass per pixel, σ²(p) = Σ_b n_b (X_b − X̄)² / (B − 1), from the
//!   batch means X_b of n_b passes each (an unbiased estimate for independent passes);
//! - a bias, over blocks of 8×8 pixels: what the squared difference of a candidate's
//!   block mean to the median of the *other* unbiased candidates' block means (PT, LT,
//!   BDPT; all others where fewer than two are there) exceeds the variance of both
//!   (`reference`, `block_bias`, `block_estimate`). This is what exposes a path
//!   tracer that never finds a light seen through a mirror: its variance is small
//!   because its image is black;
//! - the time of a pass at full resolution: the pilot's pass time (its fastest batch
//!   after the first) times the pixel ratio, but for a fixed part of a pass (dispatch,
//!   staging, commit) that does not scale, found by timing PT's pass at both sizes (one
//!   untimed and up to two timed passes of PT on the render's own scene first); the setup's
//!   time times the ratio.
//!
//! PT's passes at full size have the render's seed: where PT wins, the render continues
//! their film ([`Head`]).
//!
//! A candidate whose first batch shows full passes far too slow to fit [`MIN_PASSES`]
//! stops there when an earlier one fits them, and the probe's fourth batch runs only where
//! it ends within 1.25× the probe's share: each batch renders at least one pass, so slow
//! passes otherwise cost several times their slice.
//!
//! The predicted relMSE (the suite's metric, (x − r)²/(r² + 0.01)) after the remaining
//! time T is mean_p σ²(p)/(r² + 0.01) · t_pass / (T − t_setup) + bias², and the
//! candidate with the smallest one renders, among those that fit [`MIN_PASSES`] full
//! passes in the remaining time where any does. Without `--time` the race assumes
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
//! PT's own passes underestimate its variance where rare bright samples dominate it (a
//! caustic on a diffuse wall, found only by BSDF sampling toward a glossy highlight): a
//! pilot of about 2 % of the render's samples often holds none. So PT's variance is also
//! estimated from BDPT's samples ([`EstimatorConfig::PtMoment`], [`PROBE_SHARE`] of the
//! budget at the pilot's size, in [`BATCHES`] batches whose estimates are combined by
//! their median): each strategy's term of PT's second moment, which BDPT
//! samples with its light-side strategies where PT's densities are small. Less the
//! squared mean it is a lower estimate of PT's variance (the cross terms between path
//! lengths are left out), and the larger of the two counts. Where the batches' median
//! exceeds PT's own term their mean counts instead ([`probe_variance`]): a right-skewed
//! estimate's median reads low. Where the probe's estimate is the larger, PT's block
//! variances are scaled alike, so that PT's block means, low where its pilot missed
//! the bright samples, do not read as a bias of the candidates PT is a reference for.
//!
//! A camera-side candidate's variance at the pilot's size holds the spread of the image
//! within a pilot pixel, which at full size it does not, and is normalised by the pilot
//! pixel's mean² where the relMSE divides each full pixel by its own. Both are taken out
//! ([`spread`]) with the spread estimated from PT's full-size passes (products of
//! independent passes, shrunk by their noise): BDPT on veach-mis read 0.58 the old way
//! against 0.49 measured at full size. The probe's estimate is left as it is: PT's rare
//! bright samples do not follow the image's brightness within a pilot pixel, and the
//! probe read about the same at both sizes.
//!
//! Known limits (docs/plan.md): where an estimator's error gathers in small dark regions
//! (PT's caustic fireflies) the full-size relMSE weighs it more than the pilot's.

use std::time::{Duration, Instant};

use ember_core::estimators::{EstimatorConfig, EstimatorKind};
use ember_core::render::Film;

use crate::cli::RenderArgs;
use ember_host::driver::Limits;
use ember_host::scene::PreparedScene;

use crate::estimators::CoreRenderer;
use crate::progress::DriverConfig;

mod estimates;
mod spread;
use estimates::{Estimate, batch_mean, block_bias, block_estimate, drift_free_variance, median, pass_variance, probe_variance, reference};
use spread::{full_size_term, pixel_spread};

/// The estimators the race runs: between them the best at equal time on every suite
/// scene (docs/results.md, docs/results-merging.md).
pub const CANDIDATES: [EstimatorKind; 5] = [EstimatorKind::Pt, EstimatorKind::Lt, EstimatorKind::Bdpt, EstimatorKind::Ppm, EstimatorKind::Bpm];
/// Batches per candidate.
pub const BATCHES: usize = 4;
/// The share of the budget each candidate's pilot takes.
pub const SHARE: f64 = 0.02;
/// The share of the budget the PT-moment probe takes.
pub const PROBE_SHARE: f64 = 0.01;
/// The rendering time the race assumes without `--time`.
pub const NOMINAL_SECONDS: f64 = 10.0;
/// The pilot's resolution divisor per axis.
const DOWNSCALE: u32 = 4;
/// The fewest full passes a candidate must fit in the remaining time to be chosen over
/// one that fits them (see [`Entry::fits`]).
pub const MIN_PASSES: f64 = 4.0;
/// A candidate stops after its first batch where its full passes, judged from that
/// batch, would fit [`MIN_PASSES`] only in this many times the time the race leaves
/// (the first batch is cold, so it reads slow; this margin keeps borderline ones).
const SLOW_MARGIN: f64 = 2.0;

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
    /// For PT, the same from BDPT's samples ([`EstimatorConfig::PtMoment`]); `variance`
    /// is the larger of the two.
    pub probed: Option<f64>,
    /// The variance from the candidate's own passes.
    pub own: f64,
    /// Squared relative bias against the median image.
    pub bias: f64,
    /// Predicted relMSE after the remaining time.
    pub predicted: f64,
    /// Whether [`MIN_PASSES`] full passes fit in the remaining time. A candidate that
    /// fits fewer renders a handful of passes: the driver finishes the pass in progress
    /// at the deadline, so the render overshoots its budget by up to a pass, and the
    /// pilot gave such a candidate one or two passes, whose variance is a one-degree-of-
    /// freedom guess (spot_mirror, seed 3: BPM's 5.2 s passes in 7.7 s left, predicted
    /// 1.1e-2 from two pilot passes, measured 4.8e-2 against PPM's 0.5–1.3e-2). It is
    /// chosen only where no candidate fits.
    pub fits: bool,
    /// Seconds the race spent on it (its setup and pilot passes).
    pub seconds: f64,
    /// Whether it stopped after its first batch, its passes far too slow to fit
    /// [`MIN_PASSES`] while an earlier candidate fits them: never chosen then.
    pub stopped: bool,
}

/// One candidate's pilot: what the race reads from it.
struct Run {
    kind: EstimatorKind,
    config: EstimatorConfig,
    /// The mean image of all its passes.
    image: Vec<[f32; 3]>,
    /// Per pixel and channel, the variance of one pass ([`pass_variance`]).
    variance: Vec<[f64; 3]>,
    /// Per bias block and channel, the block's mean and that mean's variance.
    blocks: Estimate,
    /// Seconds per pass at the pilot's size (the fastest warm batch's), and the passes
    /// in all.
    pass_seconds: f64,
    passes: u32,
    /// Seconds its setup took.
    setup: f64,
    /// Seconds the race spent on it.
    seconds: f64,
    /// Whether it stopped after its first batch, too slow to be chosen.
    dropped: bool,
}

/// Passes of the chosen estimator at full size that the race already rendered: PT's
/// timing passes, with the render's seed, when PT wins.
#[derive(Clone, Debug)]
pub struct Head {
    /// The film holding them.
    pub film: Film,
    /// The configuration they were rendered with: the render continues the film only
    /// with the same one (and the same seed, scene and depth).
    pub config: EstimatorConfig,
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
    /// Seconds spent on PT's passes at full size, on preparing the pilot's scene, and on
    /// the PT-moment probe.
    pub stages: [f64; 3],
    /// Passes the render continues from, if any.
    pub head: Option<Head>,
    /// The spread of the image within a pilot pixel (`spread`) over the image, relative to
    /// the image's mean² + 0.01 over it, and the number of PT's full-size passes it came
    /// from.
    pub spread: (f64, usize),
}

impl Choice {
    /// The race in words, one line per candidate and one for the choice.
    pub fn describe(&self) -> Vec<String> {
        let [timing, scene, probe] = self.stages;
        let mut lines = vec![format!(
            "auto       pilot race at {}x{} in {:.2} s (PT at full size {timing:.2} s, pilot scene {scene:.2} s, probe {probe:.2} s; fixed cost of a pass {:.1} ms; spread within a pilot pixel {:.3e} from {} full-size passes):",
            self.size.0,
            self.size.1,
            self.seconds,
            1e3 * self.overhead,
            self.spread.0,
            self.spread.1
        )];
        for e in &self.entries {
            lines.push(format!(
                "auto         {:<5} {:>4} passes in {:.2} s, {:.3e} s/pass at full size, setup {:.2} s, variance {:.3e}{}, bias² {:.3e} -> relMSE {:.3e}{}",
                e.kind.name(),
                e.passes,
                e.seconds,
                e.pass_seconds,
                e.setup_seconds,
                e.variance,
                e.probed.map_or(String::new(), |p| format!(" (own {:.3e}, from BDPT's samples {p:.3e})", e.own)),
                e.bias,
                e.predicted,
                match (e.fits, e.stopped) {
                    (_, true) => format!(" (stopped after one batch: far fewer than {MIN_PASSES} passes fit)"),
                    (false, _) => format!(" (fewer than {MIN_PASSES} passes fit)"),
                    _ => String::new(),
                }
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
    // own scene, gives it (o below).
    // With the render's own seed and configuration: where PT wins, these passes are the
    // render's first ([`Choice::head`]).
    let mut pt = CoreRenderer::with_config(full, args.cache.config_for(EstimatorKind::Pt), max_depth, args.seed, threads)?;
    let mut pt_film = Film::with_filter(fw, fh, pt.camera_filter());
    // One pass first, untimed: the first pass at full size pays for the film's first
    // touch and the pool's start (measured: 70 ms against 50 ms on the Cornell box),
    // which the render's hundreds of passes do not; then two passes timed one by one,
    // of which the faster counts (see `fastest` below). Past the slice no further pass
    // starts (each call renders at least one), and the untimed pass's time stands in.
    // (Skipping the second timed pass where it would end past the slice was tried and
    // not kept: from one timed pass the fixed part of a pass read 1.7–2.7 ms on ajar
    // instead of 0–0.8, LT's full pass came out 5–6e-2 s instead of 8e-2, and auto picked
    // LT on three seeds of eight, 1.5× worse than PPM.)
    let driver = DriverConfig { progress: false, ..DriverConfig::with_threads(threads) };
    let deadline = Instant::now() + Duration::from_secs_f64(slice);
    let (mut cold, mut pt_full) = (f64::INFINITY, f64::INFINITY);
    // Each pass's own image, for the spread of the image within a pilot pixel (`spread`).
    let mut pt_passes: Vec<Vec<[f32; 3]>> = Vec::new();
    let mut pt_cumulative = vec![[0.0f32; 3]; pt_film.pixels()];
    for spp in 1..=3 {
        if spp > 1 && Instant::now() >= deadline {
            break;
        }
        let limits = Limits { spp, deadline: Some(deadline), interrupt: Some(ember_host::interrupt::flag()), first_pass: 0 };
        let summary = pt.render(&mut pt_film, limits, driver, start).map_err(|e| e.to_string())?;
        let per_pass = summary.render_seconds / summary.passes.max(1) as f64;
        if spp == 1 {
            cold = per_pass
        } else {
            pt_full = pt_full.min(per_pass)
        }
        let n = pt_film.passes();
        if summary.passes == 1 && n as usize == pt_passes.len() + 1 {
            let cum = pt_film.to_rgb_f32();
            pt_passes.push(batch_mean(&cum, n, &pt_cumulative, n - 1));
            pt_cumulative = cum;
        }
    }
    if !pt_full.is_finite() {
        pt_full = cold;
    }
    let (full, pt_config) = (pt.prepared, pt.config);
    let timing_seconds = race_start.elapsed().as_secs_f64();
    let scene_start = Instant::now();
    let mut prepared = Some(load(w, h)?);
    let scene_seconds = scene_start.elapsed().as_secs_f64();
    let mut runs: Vec<Run> = Vec::new();
    for (i, kind) in CANDIDATES.into_iter().enumerate() {
        let candidate_start = Instant::now();
        let scene = prepared.take().ok_or("the pilot scene was lost")?;
        let config = args.cache.config_for(kind);
        let mut r = CoreRenderer::with_config(scene, config, max_depth, args.seed ^ 0x5eed_a070, threads)?;
        let mut film = Film::with_filter(w, h, r.camera_filter());
        let mut batches: Vec<(u32, Vec<[f32; 3]>)> = Vec::new();
        let mut render_seconds = 0.0;
        // The pass time is the fastest of the batches' after the first. The first pass
        // pays for the film's first touch and the pool's start, which a render's many
        // passes do not (on window_env a cold first pass made PT's quarter-size pass look
        // slow, the fixed part of a pass came out as 2.1 ms, and LT's full pass was
        // predicted at 2 ms against 25 ms). The fastest, because a batch of 50 ms on
        // this shared machine is easily slowed by other work, which the render's own
        // passes see alike whichever candidate renders: two races in a row on veach-mis
        // timed BDPT's pass at 95 and 147 ms from the batches' totals.
        let mut fastest = f64::INFINITY;
        let mut dropped = false;
        let (mut held, mut prev) = (0u32, vec![[0.0f32; 3]; (w * h) as usize]);
        for b in 0..BATCHES {
            let deadline = Instant::now() + Duration::from_secs_f64(slice / BATCHES as f64);
            let limits = Limits { spp: u32::MAX, deadline: Some(deadline), interrupt: Some(ember_host::interrupt::flag()), first_pass: 0 };
            let summary = r.render(&mut film, limits, driver, start).map_err(|e| e.to_string())?;
            render_seconds += summary.render_seconds;
            if b >= 1 && summary.passes > 0 {
                fastest = fastest.min(summary.render_seconds / summary.passes as f64);
            }
            // The batch's own mean from the running means before and after it.
            let cum = film.to_rgb_f32();
            batches.push((film.passes() - held, batch_mean(&cum, film.passes(), &prev, held)));
            held = film.passes();
            prev = cum;
            if summary.interrupted {
                break;
            }
            // A candidate whose first batch overran its whole slice has passes too slow
            // for this budget: one more batch gives its variance, no more. (Stopping
            // every candidate whose next batch would overrun its slice, after two or
            // three batches, was tried and not kept: on spot_mirror BDPT's two one-pass
            // batches read a variance of 6e-2 and no bias, and auto picked it, 3.3×
            // worse than PPM; caustic, ajar and glossy each lost a seed the same way.)
            if b >= 1 && render_seconds > 2.0 * slice {
                break;
            }
            // One whose full passes, judged by its first batch, fit far fewer than
            // MIN_PASSES in what the race will leave, while an earlier candidate fits
            // them, cannot be chosen ([`choose_entry`]): it stops here. Its second batch
            // cost more than the slice (BPM on glossy: two pilot passes of 0.4 s).
            if b == 0 && summary.passes > 0 {
                let left = budget - start.elapsed().as_secs_f64() - slice * (CANDIDATES.len() - 1 - i) as f64 - PROBE_SHARE * budget;
                let full_pass = |pilot: f64| pilot * ratio;
                let too_slow = full_pass(summary.render_seconds / summary.passes as f64) * MIN_PASSES > SLOW_MARGIN * left;
                if too_slow && runs.iter().any(|r| !r.dropped && full_pass(r.pass_seconds) * MIN_PASSES <= left) {
                    dropped = true;
                    break;
                }
            }
        }
        // A merging candidate's radius shrinks over the pilot, and its mean drifts with it.
        let variance = match config {
            EstimatorConfig::Merging(_, c) => {
                let mut first = 0u32;
                let radius = |i: u32| ((i + 1) as f64).powf((c.alpha as f64 - 1.0) / 2.0);
                let x: Vec<f64> = batches
                    .iter()
                    .map(|(n, _)| {
                        let mean = (first..first + n).map(radius).sum::<f64>() / (*n).max(1) as f64;
                        first += n;
                        mean
                    })
                    .collect();
                drift_free_variance(&batches, &x, &prev)
            }
            _ => pass_variance(&batches, &prev),
        };
        let blocks = block_estimate(w, h, &batches, &prev);
        // A candidate stopped after one batch is timed by it.
        let pass_seconds = if fastest.is_finite() { fastest } else { render_seconds / film.passes().max(1) as f64 };
        let seconds = candidate_start.elapsed().as_secs_f64();
        runs.push(Run { kind, config, image: prev, variance, blocks, pass_seconds, passes: film.passes(), setup: r.setup_seconds, seconds, dropped });
        prepared = Some(r.prepared);
    }
    // The scale of the relMSE: per pixel and channel, the median of the candidates' images.
    let pixels = (w * h) as usize;
    let scale: Vec<[f32; 3]> =
        (0..pixels).map(|p| core::array::from_fn(|k| median(runs.iter().filter(|r| !r.dropped).map(|r| r.image[p][k] as f64).collect()) as f32)).collect();
    // t_low = o + b, t_full = o + ratio·b for PT: the fixed part o of a pass.
    let pt_run = runs.iter().position(|r| r.kind == EstimatorKind::Pt);
    let pt_low = pt_run.map_or(0.0, |i| runs[i].pass_seconds);
    let overhead = if ratio > 1.0 { ((pt_low * ratio - pt_full) / (ratio - 1.0)).clamp(0.0, pt_low) } else { 0.0 };
    let rel = |p: usize, k: usize| (scale[p][k] as f64).powi(2) + 0.01;
    let mean_over = |v: &dyn Fn(usize, usize) -> f64| (0..pixels).map(|p| (0..3).map(|k| v(p, k)).sum::<f64>()).sum::<f64>() / (3 * pixels.max(1)) as f64;
    let mean_over_pixels = |v: &dyn Fn(usize, usize) -> f64| mean_over(&|p, k| v(p, k) / rel(p, k));
    // Each candidate's variance term at full size: its pilot's per-pass variance with the
    // spread of the image within a pilot pixel taken out (`spread`), from PT's full-size
    // passes.
    let pt_variance = pt_run.map_or(&[][..], |i| &runs[i].variance[..]);
    let spread = pixel_spread(&pt_passes, (fw, fh), (w, h), pt_variance);
    let spread_passes = pt_passes.len();
    drop(pt_passes);
    let own: Vec<f64> = runs
        .iter()
        .map(|r| {
            let camera_side = r.kind != EstimatorKind::Lt;
            mean_over(&|p, k| full_size_term(r.variance[p][k], rel(p, k), spread[p][k], camera_side))
        })
        .collect();
    // For the account: the spread relative to the image's mean² + 0.01, both over the image.
    let spread_term = mean_over(&|p, k| spread[p][k]) / mean_over(&rel);
    let race = Race { runs: &runs, own: &own, ratio, overhead, pt_full };
    // PT's second moment per pixel from BDPT's samples, for the rare bright samples that
    // PT's own few passes miss (`EstimatorConfig::PtMoment`). It runs even where PT
    // cannot win: where it finds PT's variance underestimated, PT's block variances are
    // scaled alike, and without that the other candidates read PT's low block means as
    // their bias (tried: skipping the probe where PT's own passes put it past twice the
    // best made BDPT read a squared bias of 2.1e-3 on veach-bidir, seed 2, and auto
    // picked LT, 1.5× worse).
    let (probe_estimate, probe_seconds) = {
        let probe_start = Instant::now();
        let scene = prepared.take().ok_or("the pilot scene was lost")?;
        // In batches of their own films, whose estimates are combined by their median: the
        // probe is heavy-tailed where PT's densities are tiny but BDPT's are not much larger
        // (on the Cornell box one run in six drew one sample near the light that doubled its
        // estimate, while PT's measured relMSE matched its own variance on every seed), and
        // a rare spike must not outvote PT's own passes. PT's caustics on veach-mis, which
        // BDPT samples well, read alike in every batch.
        let mut probe = CoreRenderer::with_config(scene, EstimatorConfig::PtMoment, max_depth, args.seed ^ 0x5eed_a072, threads)?;
        let mut moments = Vec::new();
        let mut first_pass = 0;
        for b in 0..BATCHES {
            let mut film = Film::with_filter(w, h, probe.camera_filter());
            let deadline = Instant::now() + Duration::from_secs_f64(PROBE_SHARE * budget / BATCHES as f64);
            let limits = Limits { spp: u32::MAX, deadline: Some(deadline), interrupt: Some(ember_host::interrupt::flag()), first_pass };
            let summary = probe.render(&mut film, limits, driver, start).map_err(|e| e.to_string())?;
            first_pass += film.passes();
            moments.push(film.to_rgb_f32());
            if summary.interrupted {
                break;
            }
            // Where a pass is longer than a batch's share (each batch renders at least one),
            // the four batches would cost four passes (glossy: 0.26–0.38 s for a 0.1 s
            // share): three give the median, a fourth runs only where it fits the share.
            let spent = probe_start.elapsed().as_secs_f64();
            if b >= 2 && !next_fits(spent, spent / (b + 1) as f64, PROBE_SHARE * budget) {
                break;
            }
        }
        let probe_seconds = probe_start.elapsed().as_secs_f64();
        let pt_own = pt_run.map_or(0.0, |i| own[i]);
        let estimate = probe_variance(moments.iter().map(|m| mean_over_pixels(&|p, k| m[p][k] as f64 - (scale[p][k] as f64).powi(2))).collect(), pt_own);
        (estimate, probe_seconds)
    };
    let remaining = (budget - start.elapsed().as_secs_f64()).max(0.05 * budget);
    let entries = race.entries(probe_estimate, remaining);
    let best = choose_entry(&entries);
    let stages = [timing_seconds, scene_seconds, probe_seconds];
    let head = (best == EstimatorKind::Pt).then_some(Head { film: pt_film, config: pt_config });
    let spread = (spread_term, spread_passes);
    Ok((Choice { kind: best, entries, seconds: race_start.elapsed().as_secs_f64(), size: (w, h), overhead, stages, head, spread }, full))
}

/// What the race's predictions read, past the pilots.
struct Race<'a> {
    runs: &'a [Run],
    /// Each candidate's variance from its own passes (normalised like the relMSE).
    own: &'a [f64],
    /// Full pixels per pilot pixel.
    ratio: f64,
    /// The fixed part of a pass, and PT's full-size pass time.
    overhead: f64,
    pt_full: f64,
}

impl Race<'_> {
    /// Every candidate's prediction after `remaining` seconds, with PT's variance also
    /// from the probe (`probe`, normalised like the variances).
    fn entries(&self, probe: f64, remaining: f64) -> Vec<Entry> {
        let runs = self.runs;
        let probed: Vec<Option<f64>> = runs.iter().map(|r| (r.kind == EstimatorKind::Pt).then_some(probe)).collect();
        // Where the probe finds PT's variance underestimated, so are PT's block means'
        // variances, by the same rare samples: they are scaled alike, so that PT's mean,
        // low where it missed them, does not read as a bias of the candidates it is a
        // reference for (veach-mis, seed 2: BDPT read a squared bias of 9e-4 and lost to PT).
        let blocks: Vec<Estimate> = runs
            .iter()
            .zip(self.own.iter().zip(&probed))
            .map(|(r, (own, probed))| {
                let under = probed.map_or(1.0, |p| p / own).max(1.0);
                let mut b = r.blocks.clone();
                if under.is_finite() {
                    b.variance.iter_mut().for_each(|v| *v = v.map(|x| x * under));
                }
                b
            })
            .collect();
        // The blocks of every candidate that ran all its batches, flagged whether it is
        // unbiased (merging is not).
        let live: Vec<usize> = (0..runs.len()).filter(|&c| !runs[c].dropped).collect();
        let candidates: Vec<(&Estimate, bool)> = live.iter().map(|&c| (&blocks[c], !matches!(runs[c].config, EstimatorConfig::Merging(..)))).collect();
        let mut entries = Vec::new();
        for (c, run) in runs.iter().enumerate() {
            let Run { kind, config, pass_seconds: low, passes, setup, seconds, .. } = run;
            let (kind, config, low, passes, setup, seconds) = (*kind, *config, *low, *passes, *setup, *seconds);
            let (own, probed) = (self.own[c], probed[c]);
            let variance = own.max(probed.unwrap_or(0.0));
            let bias = live.iter().position(|&l| l == c).map_or(0.0, |l| block_bias(&blocks[c], &reference(&candidates, l)));
            // The fixed part is a difference of two timings: where it would be most of a
            // candidate's pilot pass, its noise would decide that candidate's full pass
            // time, so it is held to half of it.
            let fixed = self.overhead.min(0.5 * low);
            let pass_seconds = if kind == EstimatorKind::Pt { self.pt_full } else { (low - fixed) * self.ratio + fixed };
            let setup_seconds = setup * self.ratio;
            let left = (remaining - setup_seconds).max(pass_seconds).max(1e-3);
            // A merging radius shrinks as r_i ∝ (i + 1)^((α − 1)/2), so a pass's variance
            // (∝ 1/r²) grows as (i + 1)^(1 − α): the render's passes, up to N = left /
            // t_pass, average (N / n_pilot)^(1 − α) times the pilot's first n_pilot.
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
                probed,
                own,
                bias,
                predicted: if predicted.is_nan() || run.dropped { f64::INFINITY } else { predicted },
                fits: left >= MIN_PASSES * pass_seconds && !run.dropped,
                seconds,
                stopped: run.dropped,
            });
        }
        entries
    }
}

/// Whether one more batch of about `per` seconds, after `spent`, ends within
/// the `slice` (give or take a quarter: batches end at the first pass past their own
/// deadline).
fn next_fits(spent: f64, per: f64, slice: f64) -> bool {
    spent + per <= 1.25 * slice
}

/// The candidate with the smallest predicted relMSE among those that fit
/// [`MIN_PASSES`] passes, or among all where none does.
fn choose_entry(entries: &[Entry]) -> EstimatorKind {
    let any_fits = entries.iter().any(|e| e.fits);
    entries.iter().filter(|e| e.fits || !any_fits).min_by(|a, b| a.predicted.total_cmp(&b.predicted)).map_or(EstimatorKind::Pt, |e| e.kind)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A candidate that fits too few passes loses to one that fits, however small its
    /// prediction; where none fits, the smallest prediction wins. Seen to fail with
    /// `fits` ignored (BPM chosen) and with the fallback left out (PT chosen by default).
    #[test]
    fn a_candidate_must_fit_its_passes() {
        let entry = |kind, predicted, fits| Entry {
            kind,
            passes: 4,
            pass_seconds: 1.0,
            setup_seconds: 0.0,
            variance: 1.0,
            probed: None,
            own: 1.0,
            bias: 0.0,
            predicted,
            fits,
            seconds: 0.1,
            stopped: false,
        };
        let race = [entry(EstimatorKind::Bpm, 1e-2, false), entry(EstimatorKind::Ppm, 2e-2, true), entry(EstimatorKind::Lt, 3e-2, true)];
        assert_eq!(choose_entry(&race), EstimatorKind::Ppm);
        let none = [entry(EstimatorKind::Bpm, 1e-2, false), entry(EstimatorKind::Ppm, 2e-2, false)];
        assert_eq!(choose_entry(&none), EstimatorKind::Bpm);
    }
}
