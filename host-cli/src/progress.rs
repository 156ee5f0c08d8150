//! What the command line shows while it renders: a progress bar on a terminal, plain
//! lines on stderr otherwise (a log file, a batch job: when setup ends, after the first
//! pass, then at most every [`LOG_INTERVAL`] seconds, and at the end), and the setup's
//! phases as a spinner or lines. The driver ([`ember_host::driver`]) prints nothing; it
//! tells these [`Progress`] implementations how it goes.

use std::cell::RefCell;
use std::io::IsTerminal;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use ember_core::geometry::RayQuery;
use ember_core::render::{Context, Film, Phase, Phased};
use ember_host::driver::{self, DriverError, Limits, Progress, RenderSummary};

/// Seconds between progress lines when stderr is not a terminal.
pub const LOG_INTERVAL: f64 = 10.0;

/// How the command line runs the driver.
#[derive(Clone, Copy, Debug)]
pub struct DriverConfig {
    pub threads: usize,
    /// Draw a progress bar when stderr is a terminal (log lines otherwise).
    pub progress: bool,
}

impl DriverConfig {
    /// `threads` threads, progress bar on.
    pub fn with_threads(threads: usize) -> Self {
        Self { threads, progress: true }
    }

    /// [`driver::render`] with these threads, showing progress where asked.
    pub fn render<E, Q>(self, est: &mut E, ctx: &Context<'_, Q>, film: &mut Film, limits: Limits, program_start: Instant) -> Result<RenderSummary, DriverError>
    where
        E: Phased<Q> + Sync + Send + ?Sized,
        E::Data: Send,
        Q: RayQuery + Sync + ?Sized,
    {
        let shown = TerminalProgress::default();
        let progress: Option<&dyn Progress> = if self.progress { Some(&shown) } else { None };
        driver::render(est, ctx, film, limits, self.threads, progress, program_start)
    }
}

/// The render loop's progress: a [`Bar`] made when the loop starts (it needs the limits).
#[derive(Debug, Default)]
pub struct TerminalProgress {
    bar: RefCell<Option<Bar>>,
}

impl Progress for TerminalProgress {
    fn start(&self, limits: &Limits, program_start: Instant) {
        *self.bar.borrow_mut() = Some(Bar::new(true, *limits, program_start));
    }
    fn setup_done(&self, seconds: f64) {
        if let Some(b) = &*self.bar.borrow() {
            b.setup_done(seconds);
        }
    }
    fn pass_done(&self, passes: u32) {
        if let Some(b) = &*self.bar.borrow() {
            b.pass_done(passes);
        }
    }
    fn finish(&self, passes: u32) {
        if let Some(b) = self.bar.borrow_mut().take() {
            b.finish(passes);
        }
    }
}

/// The setup's phases (preprocessing can take a while: SPCBPT's training): a spinner
/// naming the phase on a terminal, a line per phase in a log.
#[derive(Debug)]
pub struct SetupSpinner {
    spinner: ProgressBar,
    terminal: bool,
}

impl SetupSpinner {
    pub fn new() -> Self {
        let terminal = std::io::stderr().is_terminal();
        let spinner = ProgressBar::with_draw_target(None, if terminal { ProgressDrawTarget::stderr() } else { ProgressDrawTarget::hidden() });
        Self { spinner, terminal }
    }
}

impl Default for SetupSpinner {
    fn default() -> Self {
        Self::new()
    }
}

impl Progress for SetupSpinner {
    fn setup_phase(&self, phase: &Phase, seconds: f64) {
        if self.terminal {
            self.spinner.set_message(format!("setup: {}", phase.name));
            self.spinner.tick();
        } else {
            eprintln!("setup: {} ({} items) at {seconds:.1} s", phase.name, phase.items);
        }
    }
    fn setup_end(&self) {
        self.spinner.finish_and_clear();
    }
}

/// One render's progress bar: over passes when only `spp` limits the render, over the time
/// budget when a deadline does; on a terminal only. Elsewhere, log lines.
#[derive(Debug)]
struct Bar {
    bar: ProgressBar,
    deadline: Option<(Instant, Duration)>,
    /// Log lines instead of a bar: when the last one was printed.
    log: Option<std::cell::Cell<Option<Instant>>>,
    start: Instant,
}

impl Bar {
    fn new(enabled: bool, limits: Limits, program_start: Instant) -> Self {
        let terminal = std::io::stderr().is_terminal();
        let target = if enabled && terminal { ProgressDrawTarget::stderr() } else { ProgressDrawTarget::hidden() };
        let by_time = limits.deadline.filter(|_| limits.spp == u32::MAX);
        let (len, template) = match by_time {
            Some(d) => (d.saturating_duration_since(program_start).as_millis() as u64, "{elapsed_precise} [{wide_bar}] {msg} (ETA {eta})"),
            None => (limits.spp.saturating_sub(limits.first_pass) as u64, "{elapsed_precise} [{wide_bar}] {pos}/{len} passes (ETA {eta})"),
        };
        let bar = ProgressBar::with_draw_target(Some(len), target);
        if let Ok(style) = ProgressStyle::with_template(template) {
            bar.set_style(style.progress_chars("=> "));
        }
        let log = (enabled && !terminal).then(|| std::cell::Cell::new(None));
        Self { bar, deadline: by_time.map(|d| (program_start, d.saturating_duration_since(program_start))), log, start: program_start }
    }

    fn setup_done(&self, seconds: f64) {
        if self.log.is_some() && seconds >= 0.05 {
            eprintln!("progress: setup done in {seconds:.1} s");
        }
    }

    fn pass_done(&self, passes: u32) {
        match self.deadline {
            Some((start, budget)) => {
                self.bar.set_position(start.elapsed().min(budget).as_millis() as u64);
                self.bar.set_message(format!("{passes} passes"));
            }
            None => self.bar.set_position(passes as u64),
        }
        if let Some(last) = &self.log {
            let now = Instant::now();
            if last.get().is_none_or(|t| now.duration_since(t).as_secs_f64() >= LOG_INTERVAL) {
                last.set(Some(now));
                let s = if passes == 1 { "" } else { "es" };
                eprintln!("progress: {passes} pass{s} at {:.1} s", now.duration_since(self.start).as_secs_f64());
            }
        }
    }

    fn finish(&self, passes: u32) {
        self.bar.finish_and_clear();
        if self.log.is_some() {
            let s = if passes == 1 { "" } else { "es" };
            eprintln!("progress: done, {passes} pass{s} at {:.1} s", self.start.elapsed().as_secs_f64());
        }
    }
}
