//! The render loop on threads: the core's render protocol ([`ember_core::render`]) with
//! each phase's chunks mapped in parallel and reduced in chunk order.
//!
//! Every estimator's work is a sequence of phases (its setup, then per pass its light
//! paths, caches and camera samples); each phase is a map over fixed-size chunks of an
//! index range, followed by the estimator's reduction. This host maps the chunks on a
//! local rayon pool of `--threads` threads, each into its own reusable [`ChunkOutput`],
//! and hands them to the reduction in chunk order on one thread. The chunk sizes are the
//! estimator's and the random numbers depend only on (seed, index, pass, dimension), so
//! the film is bit-identical for any number of threads, and to the core's serial runner.
//!
//! # Stopping
//! The loop stops after `spp` passes or at the wall-clock deadline, whichever comes
//! first. The deadline is checked between passes: a pass in progress when time runs
//! out is finished (an interrupted pass would leave some pixels with one sample fewer
//! than others, and light splats without their normalisation). The first pass always
//! runs, even when preprocessing used up the whole budget, so an image exists. An
//! interrupt (Ctrl-C, [`crate::interrupt`]) is checked before every pass, the first
//! included: the pass in progress is finished and the summary says so.
//!
//! # Progress
//! The driver prints nothing: it tells a [`Progress`] the host passes (the command
//! line's progress bar and log lines) when setup phases start, when a pass ends and when
//! it stops. A library host passes none.

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use rayon::prelude::*;

use ember_core::geometry::RayQuery;
use ember_core::render::{Band, ChunkOutput, Context, Film, Phase, PhaseBuffers, Phased};
use ember_core::transport::ConnectionStats;
use ember_core::transport::lanes::LaneStats;

/// A contribution at a continuous film position: the core's type.
pub use ember_core::transport::Splat;

/// Work counted by a renderer.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PassStats {
    /// Ray queries (closest hit and occlusion).
    pub rays: u64,
    /// Camera samples and light paths.
    pub samples: u64,
    /// Interior connections traced, and how many the shadow ray found occluded.
    pub connections: ConnectionStats,
    /// The lane loop's steps, busy lanes and lane-shaded arrivals (PT, LT).
    pub lanes: LaneStats,
}

impl core::ops::Add for PassStats {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        let mut connections = self.connections;
        connections += o.connections;
        let mut lanes = self.lanes;
        lanes += o.lanes;
        Self { rays: self.rays + o.rays, samples: self.samples + o.samples, connections, lanes }
    }
}

/// Seconds spent in each phase, by name, summed over its runs, in first-run order.
pub type PhaseTimes = Vec<(&'static str, f64)>;

fn add_time(times: &mut PhaseTimes, name: &'static str, seconds: f64) {
    match times.iter_mut().find(|(n, _)| *n == name) {
        Some((_, t)) => *t += seconds,
        None => times.push((name, seconds)),
    }
}

/// Map and reduce every pending phase of `est`: chunks in parallel on the current rayon
/// pool (each chunk its own stealable task), reductions in chunk order on this thread.
pub fn run_pending<E, Q>(est: &mut E, ctx: &Context<'_, Q>, film: &mut Film, buffers: &mut PhaseBuffers<E::Data>, times: &mut PhaseTimes) -> PassStats
where
    E: Phased<Q> + Sync + ?Sized,
    E::Data: Send,
    Q: RayQuery + Sync + ?Sized,
{
    run_pending_or_abandon(est, ctx, film, buffers, times, never).unwrap_or_default()
}

fn never() -> bool {
    false
}

/// [`run_pending`], dropping the rest of the work when `abandon` turns true: `None` then,
/// the film's staged pass discarded (its committed passes untouched) and the estimator
/// left mid-pass, fit only to be dropped.
fn run_pending_or_abandon<E, Q>(
    est: &mut E,
    ctx: &Context<'_, Q>,
    film: &mut Film,
    buffers: &mut PhaseBuffers<E::Data>,
    times: &mut PhaseTimes,
    abandon: fn() -> bool,
) -> Option<PassStats>
where
    E: Phased<Q> + Sync + ?Sized,
    E::Data: Send,
    Q: RayQuery + Sync + ?Sized,
{
    let mut stats = PassStats::default();
    while let Some(phase) = est.next_phase() {
        match run_phase(est, ctx, &phase, film, buffers, times, abandon) {
            Some(s) => stats = stats + s,
            None => {
                film.discard_staged();
                return None;
            }
        }
    }
    Some(stats)
}

/// Map and reduce one phase (`None`, and nothing reduced, when `abandon` turned true).
fn run_phase<E, Q>(
    est: &mut E,
    ctx: &Context<'_, Q>,
    phase: &Phase,
    film: &mut Film,
    buffers: &mut PhaseBuffers<E::Data>,
    times: &mut PhaseTimes,
    abandon: fn() -> bool,
) -> Option<PassStats>
where
    E: Phased<Q> + Sync + ?Sized,
    E::Data: Send,
    Q: RayQuery + Sync + ?Sized,
{
    let mut stats = PassStats::default();
    let start = Instant::now();
    let outputs = buffers.for_phase(phase);
    let shared: &E = est;
    // `with_max_len(1)` makes every chunk its own stealable task: rayon's adaptive
    // splitting otherwise hands a thread runs of 32-64 chunks that cannot be stolen
    // once started (on 2 threads one worker idled 10 % of every BDPT pass).
    let rays: u64 = outputs
        .par_iter_mut()
        .with_max_len(1)
        .map(|out: &mut ChunkOutput<E::Data>| {
            if abandon() {
                return 0;
            }
            shared.map(ctx, phase, out);
            out.counters.rays
        })
        .sum();
    if abandon() {
        return None;
    }
    stats.rays += rays;
    // In chunk order, so the sums do not depend on the thread count.
    for out in outputs.iter() {
        stats.connections += out.counters.connections;
        stats.lanes += out.counters.lanes;
    }
    if phase.samples {
        stats.samples += phase.items as u64;
    }
    // A pass's splats are committed on the pool too (the same bits as on one thread).
    film.set_parallel_splats(Some(commit_bands));
    est.reduce(ctx, phase, outputs, film);
    add_time(times, phase.name, start.elapsed().as_secs_f64());
    Some(stats)
}

/// Commit a pass's splats band by band on the current rayon pool, each band its own task
/// ([`ember_core::render::ParallelBands`]).
fn commit_bands(bands: &mut [Band<'_>], work: &(dyn Fn(&mut Band<'_>) + Sync)) {
    bands.par_iter_mut().with_max_len(1).for_each(work);
}

/// Run `est`'s setup phases (preprocessing) on `threads` threads; returns each phase's
/// seconds. The setup touches no film. `progress` hears of each phase as it starts
/// (preprocessing can take a while: SPCBPT's training).
pub fn run_setup<E, Q>(est: &mut E, ctx: &Context<'_, Q>, threads: usize, progress: Option<&dyn Progress>) -> Result<PhaseTimes, DriverError>
where
    E: Phased<Q> + Sync + Send + ?Sized,
    E::Data: Send,
    Q: RayQuery + Sync + ?Sized,
{
    let pool = thread_pool(threads, "ember-prepare")?;
    let mut times = PhaseTimes::new();
    let mut film = Film::new(0, 0);
    let mut buffers = PhaseBuffers::new();
    let start = Instant::now();
    while let Some(phase) = est.next_phase() {
        if let Some(p) = progress {
            p.setup_phase(&phase, start.elapsed().as_secs_f64());
        }
        pool.install(|| run_phase(est, ctx, &phase, &mut film, &mut buffers, &mut times, never));
    }
    if let Some(p) = progress {
        p.setup_end();
    }
    Ok(times)
}

/// The threads a host starts for `requested` (`None`: every core): capped, not refused,
/// at 4 × the cores and at 1024 (more only add start-up time; `UINT32_MAX` threads ran
/// for minutes before failing). The command line warns when it caps; a library does not.
pub fn capped_threads(requested: Option<u32>) -> usize {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    match requested {
        Some(n) => (n as usize).min((4 * cores).min(1024)),
        None => cores,
    }
}

/// A rayon pool of `threads` threads named `name-i`.
pub fn thread_pool(threads: usize, name: &'static str) -> Result<rayon::ThreadPool, DriverError> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads.max(1))
        .thread_name(move |i| format!("{name}-{i}"))
        .build()
        .map_err(|e| DriverError::ThreadPool(e.to_string()))
}

/// Which passes to render, and when to stop.
#[derive(Clone, Copy, Debug)]
pub struct Limits {
    /// The index after the last pass to render: with `first_pass` 0, the total passes
    /// (samples per pixel) the film should hold when the call returns. A film that
    /// already holds some continues from there.
    pub spp: u32,
    /// The first pass's index: 0 for a whole render, A for the range A..B of a split one
    /// (docs/distributed.md). The film then holds passes `first_pass ..
    /// first_pass + film.passes()`; an estimator that carries state across passes
    /// replays passes `0..first_pass` first ([`Phased::replay_pass`]), when the film is
    /// still empty.
    pub first_pass: u32,
    /// Wall-clock deadline (checked between passes).
    pub deadline: Option<Instant>,
    /// Set to stop after the pass in progress (checked before every pass). Where it is
    /// given, the pass in progress is also dropped unfinished once a termination signal's
    /// grace has run out ([`crate::interrupt::abandon_pass`], polled before each chunk;
    /// the film keeps the passes committed before it).
    pub interrupt: Option<&'static AtomicBool>,
}

impl Limits {
    fn interrupted(&self) -> bool {
        self.interrupt.is_some_and(|f| f.load(Ordering::SeqCst))
    }
}

/// What the driver reports while it runs, for a host that shows it (the command line's
/// progress bar or log lines). Every method does nothing by default.
pub trait Progress: core::fmt::Debug {
    /// A setup phase of [`run_setup`] starts, `seconds` after the setup began.
    fn setup_phase(&self, _phase: &Phase, _seconds: f64) {}
    /// [`run_setup`] ran its last phase.
    fn setup_end(&self) {}
    /// [`render`] starts under `limits`; `program_start` is when the program started.
    fn start(&self, _limits: &Limits, _program_start: Instant) {}
    /// The setup [`render`] ran before its passes (pending phases, replayed passes) took
    /// `seconds`.
    fn setup_done(&self, _seconds: f64) {}
    /// `passes` passes are rendered in this call.
    fn pass_done(&self, _passes: u32) {}
    /// [`render`] stops after `passes` passes.
    fn finish(&self, _passes: u32) {}
}

/// What a render did.
#[derive(Clone, Debug, PartialEq)]
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
    /// Seconds per phase over the render loop (camera, light paths, …).
    pub phase_seconds: PhaseTimes,
    /// Stopped by an interrupt before the limits were reached.
    pub interrupted: bool,
}

impl RenderSummary {
    /// This render followed by `later` on the same film (a render in slices, as
    /// `--checkpoint` runs it): counts and seconds added, rates recomputed, the later
    /// one's end time and interruption.
    pub fn then(self, later: RenderSummary) -> RenderSummary {
        let render_seconds = self.render_seconds + later.render_seconds;
        let stats = self.stats + later.stats;
        let per_second = |n: u64| if render_seconds > 0.0 { n as f64 / render_seconds } else { 0.0 };
        let mut phase_seconds = self.phase_seconds;
        for (name, t) in later.phase_seconds {
            add_time(&mut phase_seconds, name, t);
        }
        RenderSummary {
            passes: self.passes + later.passes,
            render_seconds,
            total_seconds: later.total_seconds,
            stats,
            samples_per_second: per_second(stats.samples),
            rays_per_second: per_second(stats.rays),
            discarded: self.discarded + later.discarded,
            threads: later.threads,
            phase_seconds,
            interrupted: later.interrupted,
        }
    }
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

/// Render passes of `est` into `film` on `threads` threads until `limits` say stop
/// (pending setup phases run first), telling `progress` how it goes. `program_start` is
/// when the program started (for the summary's total time). The threads are a pool of
/// this call's ([`render_on`] takes one a host keeps between calls).
pub fn render<E, Q>(
    est: &mut E,
    ctx: &Context<'_, Q>,
    film: &mut Film,
    limits: Limits,
    threads: usize,
    progress: Option<&dyn Progress>,
    program_start: Instant,
) -> Result<RenderSummary, DriverError>
where
    E: Phased<Q> + Sync + Send + ?Sized,
    E::Data: Send,
    Q: RayQuery + Sync + ?Sized,
{
    check_resolution(ctx, film)?;
    let pool = render_pool(threads)?;
    render_on(&pool, est, ctx, film, limits, progress, program_start)
}

/// The pool [`render`] starts for `threads` threads (at least 1), named `ember-render-i`:
/// for a host that renders many times with the same threads ([`render_on`]).
pub fn render_pool(threads: usize) -> Result<rayon::ThreadPool, DriverError> {
    thread_pool(threads, "ember-render")
}

fn check_resolution<Q: ?Sized>(ctx: &Context<'_, Q>, film: &Film) -> Result<(), DriverError> {
    let camera = &ctx.scene.camera;
    let (w, h) = (camera.width(), camera.height());
    if (film.width(), film.height()) != (w, h) {
        return Err(DriverError::Resolution { film: (film.width(), film.height()), renderer: (w, h) });
    }
    Ok(())
}

/// [`render`] on the threads of `pool`, which the caller keeps (the C API's renderer
/// starts one on its first render and reuses it: a pool per call cost a thread start per
/// thread and call). The bits do not depend on the pool.
pub fn render_on<E, Q>(
    pool: &rayon::ThreadPool,
    est: &mut E,
    ctx: &Context<'_, Q>,
    film: &mut Film,
    limits: Limits,
    progress: Option<&dyn Progress>,
    program_start: Instant,
) -> Result<RenderSummary, DriverError>
where
    E: Phased<Q> + Sync + Send + ?Sized,
    E::Data: Send,
    Q: RayQuery + Sync + ?Sized,
{
    check_resolution(ctx, film)?;
    let threads = pool.current_num_threads();
    let mut buffers = PhaseBuffers::new();
    let mut times = PhaseTimes::new();
    if let Some(p) = progress {
        p.start(&limits, program_start);
    }
    // Setup not yet run (a renderer built without `run_setup`) counts as setup time.
    let setup_start = Instant::now();
    pool.install(|| run_pending(est, ctx, &mut Film::new(0, 0), &mut buffers, &mut times));
    // A range that starts past 0 needs the state earlier passes leave behind (SPCBPT's
    // reuse FIFOs): replay those passes' state-carrying phases, counted as setup.
    if film.passes() == 0 && limits.first_pass > 0 && est.replay_pass(0) {
        pool.install(|| {
            run_pending(est, ctx, &mut Film::new(0, 0), &mut buffers, &mut times);
            for pass in 1..limits.first_pass {
                est.replay_pass(pass);
                run_pending(est, ctx, &mut Film::new(0, 0), &mut buffers, &mut times);
            }
        });
    }
    if let Some(p) = progress {
        p.setup_done(setup_start.elapsed().as_secs_f64());
    }

    let loop_start = Instant::now();
    let discarded_before = film.discarded();
    let mut stats = PassStats::default();
    let mut passes = 0;
    times.clear();
    // Continue a film that already holds passes (checkpointed renders), so pass indices,
    // and with them the random streams, never repeat.
    let first_pass = limits.first_pass.saturating_add(film.passes());
    let mut interrupted = false;
    for pass in first_pass..limits.spp {
        if limits.interrupted() {
            interrupted = true;
            break;
        }
        if pass > first_pass && limits.deadline.is_some_and(|d| Instant::now() >= d) {
            break;
        }
        est.start_pass(pass);
        let abandon = if limits.interrupt.is_some() { crate::interrupt::abandon_pass } else { never };
        match pool.install(|| run_pending_or_abandon(est, ctx, film, &mut buffers, &mut times, abandon)) {
            Some(s) => stats = stats + s,
            None => {
                interrupted = true;
                break;
            }
        }
        passes += 1;
        crate::interrupt::note_passes(film.passes());
        if let Some(p) = progress {
            p.pass_done(passes);
        }
    }
    if let Some(p) = progress {
        p.finish(passes);
    }

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
        phase_seconds: times,
        interrupted,
    })
}

#[cfg(test)]
mod tests;
