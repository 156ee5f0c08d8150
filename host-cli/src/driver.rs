//! The render loop: passes of camera and light work in parallel, merged into the film
//! in a fixed order.
//!
//! A *pass* gives every pixel one camera sample (`camera_pass`) and traces
//! `light_paths_per_pass` light paths (`light_pass`). Within a pass the pixels are cut
//! into fixed-size chunks and the light paths likewise; rayon runs the chunks on a local
//! thread pool of `--threads` threads. Each chunk writes its pixels' samples into its own
//! slice of a pass buffer and collects its splats into its own `Vec`. When the pass is
//! done, the buffer and then the splat lists, camera chunks first and light chunks
//! next, each in chunk order, are added to the film on one thread. The chunk sizes do
//! not depend on the thread count and the random numbers depend only on (seed, pixel or
//! path, pass, dimension), so the film is bit-identical for any number of threads.
//!
//! # Stopping
//! The loop stops after `spp` passes or at the wall-clock deadline, whichever comes
//! first. The deadline is checked between passes: a pass in progress when time runs
//! out is finished (an interrupted pass would leave some pixels with one sample fewer
//! than others, and light splats without their normalisation). The first pass always
//! runs, even when preprocessing used up the whole budget, so an image exists.

use core::ops::Range;
use std::io::IsTerminal;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use rayon::prelude::*;

use ember_core::Rgb;

use crate::film::Film;

/// A contribution at a continuous film position (pixel (x, y) covers [x, x+1) × [y, y+1)):
/// the core's type, so estimators splat straight into the driver.
pub use ember_core::integrator::Splat;

/// Work counted by a renderer.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PassStats {
    /// Ray queries (closest hit and occlusion).
    pub rays: u64,
    /// Camera samples and light paths.
    pub samples: u64,
}

impl core::ops::Add for PassStats {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        Self { rays: self.rays + o.rays, samples: self.samples + o.samples }
    }
}

/// What an estimator provides to be driven pass by pass.
pub trait PassRenderer: Sync {
    fn width(&self) -> u32;
    fn height(&self) -> u32;
    /// Camera-side work of pass `pass` for pixels `pixels` (index y*W+x): one sample per
    /// pixel into `out[i - pixels.start]`; may also splat (BDPT's t = 1).
    fn camera_pass(&self, pass: u32, pixels: Range<u32>, out: &mut [Rgb], splat: &mut dyn FnMut(Splat)) -> PassStats;
    /// Number of light paths traced per pass by `light_pass` (0 = none); splats of a
    /// pass are divided by max(this, camera-splatting count) — see `splat_scale`.
    fn light_paths_per_pass(&self) -> u32;
    /// Light-side work of pass `pass` for light paths `paths`.
    fn light_pass(&self, pass: u32, paths: Range<u32>, splat: &mut dyn FnMut(Splat)) -> PassStats;
    /// The factor every splat of one pass is multiplied by before it is added to the film
    /// (e.g. 1/M for M light paths per pass; 1/(W·H) for BDPT whose camera_pass traces
    /// one light path per pixel).
    fn splat_scale(&self) -> f64;
    /// Work that must finish before pass `pass`'s camera and light work starts (the
    /// light paths and vertex caches of LVCBPT and SPCBPT). Runs inside the render thread
    /// pool, so it may use rayon; its splats are merged with the pass's, scaled by
    /// `splat_scale`, in the order they were emitted (which must not depend on the thread
    /// count). State it builds lives behind interior mutability. Default: nothing.
    fn prepare_pass(&self, _pass: u32, _splat: &mut dyn FnMut(Splat)) -> PassStats {
        PassStats::default()
    }
}

/// When to stop.
#[derive(Clone, Copy, Debug)]
pub struct Limits {
    /// Total passes (samples per pixel) the film should hold when the call returns;
    /// a film that already holds some continues from there.
    pub spp: u32,
    /// Wall-clock deadline (checked between passes).
    pub deadline: Option<Instant>,
}

/// How to run.
#[derive(Clone, Copy, Debug)]
pub struct DriverConfig {
    pub threads: usize,
    /// Pixels per camera work item.
    pub pixel_chunk: u32,
    /// Light paths per light work item.
    pub light_chunk: u32,
    /// Draw a progress bar when stderr is a terminal.
    pub progress: bool,
}

impl DriverConfig {
    /// Default chunk sizes (small enough to balance, large enough to amortise the
    /// per-chunk splat list) with `threads` threads.
    pub fn with_threads(threads: usize) -> Self {
        Self { threads, pixel_chunk: 1024, light_chunk: 1024, progress: true }
    }
}

/// What a render did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderSummary {
    pub passes: u32,
    /// Seconds spent in the pass loop.
    pub render_seconds: f64,
    /// Seconds since program start when the loop ended (preprocessing included).
    pub total_seconds: f64,
    pub stats: PassStats,
    pub samples_per_second: f64,
    pub rays_per_second: f64,
    /// Samples and splats discarded for NaN, infinite or negative values.
    pub discarded: u64,
    pub threads: usize,
}

/// Problems the driver reports.
#[derive(Debug)]
pub enum DriverError {
    /// The thread pool could not be created.
    ThreadPool(String),
    /// The film and the renderer disagree on the resolution.
    Resolution { film: (u32, u32), renderer: (u32, u32) },
}

impl core::fmt::Display for DriverError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::ThreadPool(e) => write!(f, "could not start the render threads: {e}"),
            Self::Resolution { film, renderer } => {
                write!(f, "film is {}x{} but the renderer draws {}x{}", film.0, film.1, renderer.0, renderer.1)
            }
        }
    }
}

impl std::error::Error for DriverError {}

/// Render passes into `film` until `limits` say stop. `program_start` is when the
/// program started (for the summary's total time).
pub fn render<R: PassRenderer + ?Sized>(
    renderer: &R,
    film: &mut Film,
    limits: Limits,
    config: DriverConfig,
    program_start: Instant,
) -> Result<RenderSummary, DriverError> {
    let (w, h) = (renderer.width(), renderer.height());
    if (film.width(), film.height()) != (w, h) {
        return Err(DriverError::Resolution { film: (film.width(), film.height()), renderer: (w, h) });
    }
    let threads = config.threads.max(1);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .thread_name(|i| format!("ember-render-{i}"))
        .build()
        .map_err(|e| DriverError::ThreadPool(e.to_string()))?;

    // Buffers reused by every pass.
    let pixels = w as usize * h as usize;
    let pixel_chunk = config.pixel_chunk.max(1) as usize;
    let light_chunk = config.light_chunk.max(1) as usize;
    let mut camera_out = vec![Rgb::ZERO; pixels];
    let mut camera_splats: Vec<Vec<Splat>> = vec![Vec::new(); pixels.div_ceil(pixel_chunk)];
    let light_paths = renderer.light_paths_per_pass() as usize;
    let mut light_splats: Vec<Vec<Splat>> = vec![Vec::new(); light_paths.div_ceil(light_chunk)];
    let mut prepare_splats: Vec<Splat> = Vec::new();

    let progress = Progress::new(config.progress, limits, program_start);
    let loop_start = Instant::now();
    let discarded_before = film.discarded();
    let mut stats = PassStats::default();
    let mut passes = 0;
    // Continue a film that already holds passes (checkpointed renders), so pass indices,
    // and with them the random streams, never repeat.
    let first_pass = film.passes();
    for pass in first_pass..limits.spp {
        if pass > first_pass && limits.deadline.is_some_and(|d| Instant::now() >= d) {
            break;
        }
        // Run the pass's chunks in parallel, each into its own output. `with_max_len(1)`
        // makes every chunk its own stealable task: rayon's adaptive splitting otherwise
        // hands a thread runs of 32-64 chunks that cannot be stolen once started, and on
        // 2 threads one worker idled 10 % of every BDPT pass (measured by the
        // render_throughput benchmark).
        let camera_work = || {
            camera_out
                .par_chunks_mut(pixel_chunk)
                .zip(camera_splats.par_iter_mut())
                .enumerate()
                .with_max_len(1)
                .map(|(c, (out, splats))| {
                    splats.clear();
                    let start = (c * pixel_chunk) as u32;
                    let range = start..start + out.len() as u32;
                    renderer.camera_pass(pass, range, out, &mut |s| splats.push(s))
                })
                .reduce(PassStats::default, |a, b| a + b)
        };
        let light_work = || {
            light_splats
                .par_iter_mut()
                .enumerate()
                .with_max_len(1)
                .map(|(c, splats)| {
                    splats.clear();
                    let start = c * light_chunk;
                    let range = start as u32..(start + light_chunk).min(light_paths) as u32;
                    renderer.light_pass(pass, range, &mut |s| splats.push(s))
                })
                .reduce(PassStats::default, |a, b| a + b)
        };
        prepare_splats.clear();
        stats = stats + pool.install(|| renderer.prepare_pass(pass, &mut |s| prepare_splats.push(s)));
        let (cam, light) = pool.install(|| rayon::join(camera_work, light_work));
        stats = stats + cam + light;

        // Merge on this thread in a fixed order.
        film.add_camera_samples(0..pixels as u32, &camera_out);
        let scale = renderer.splat_scale();
        for s in std::iter::once(&prepare_splats).chain(&camera_splats).chain(&light_splats) {
            film.add_splats(s, scale);
        }
        film.end_pass();
        passes += 1;
        progress.pass_done(passes);
    }
    progress.finish();

    let render_seconds = loop_start.elapsed().as_secs_f64();
    let per_second = |n: u64| if render_seconds > 0.0 { n as f64 / render_seconds } else { 0.0 };
    Ok(RenderSummary {
        passes,
        render_seconds,
        total_seconds: program_start.elapsed().as_secs_f64(),
        stats,
        samples_per_second: per_second(stats.samples),
        rays_per_second: per_second(stats.rays),
        discarded: film.discarded() - discarded_before,
        threads,
    })
}

/// The progress bar: over passes when only `spp` limits the render, over the time
/// budget when a deadline does. Hidden unless stderr is a terminal.
struct Progress {
    bar: ProgressBar,
    deadline: Option<(Instant, Duration)>,
}

impl Progress {
    fn new(enabled: bool, limits: Limits, program_start: Instant) -> Self {
        let target = if enabled && std::io::stderr().is_terminal() {
            ProgressDrawTarget::stderr()
        } else {
            ProgressDrawTarget::hidden()
        };
        let by_time = limits.deadline.filter(|_| limits.spp == u32::MAX);
        let (len, template) = match by_time {
            Some(d) => (
                d.saturating_duration_since(program_start).as_millis() as u64,
                "{elapsed_precise} [{wide_bar}] {msg} (ETA {eta})",
            ),
            None => (limits.spp as u64, "{elapsed_precise} [{wide_bar}] {pos}/{len} passes (ETA {eta})"),
        };
        let bar = ProgressBar::with_draw_target(Some(len), target);
        if let Ok(style) = ProgressStyle::with_template(template) {
            bar.set_style(style.progress_chars("=> "));
        }
        Self { bar, deadline: by_time.map(|d| (program_start, d.saturating_duration_since(program_start))) }
    }

    fn pass_done(&self, passes: u32) {
        match self.deadline {
            Some((start, budget)) => {
                self.bar.set_position(start.elapsed().min(budget).as_millis() as u64);
                self.bar.set_message(format!("{passes} passes"));
            }
            None => self.bar.set_position(passes as u64),
        }
    }

    fn finish(&self) {
        self.bar.finish_and_clear();
    }
}

#[cfg(test)]
mod tests;
