//! Error against run time: an estimator's error to a reference as a function of
//! wall-clock seconds, preprocessing included.
//!
//! For each estimator and seed the clock starts before the scene is loaded (the
//! estimators of one seed run interleaved, each on its own clock: see [`measure`]); the film is
//! snapshotted at checkpoints spaced by a factor √2 (1, 1.41, 2, 2.83, … s up to the
//! budget), fine enough that a time to reach an error target is read to within ±20 %
//! before interpolation ([`ember_formats::error_time::time_to_reach`] interpolates log-log between checkpoints). The deadline is
//! checked between passes, so a snapshot lands when the pass running at its checkpoint
//! ends: the CSV records the actual elapsed seconds, and the plot uses them. relMSE and
//! MAPE (see [`ember_formats::metrics`]) are averaged over seeds at each checkpoint. The
//! record itself (checkpoints, the reference and its floor, seed averages, time to reach a
//! target, the CSV) is [`ember_formats::error_time`], which a Python package shares.
//!
//! The reference's own noise floor comes from its two half-sample images: their squared
//! difference is about 4× the full reference's squared error, so the floor drawn is
//! relMSE(half a, half b)/4 and MAPE(half a, half b)/2. An estimate near the floor
//! cannot be ranked against another.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use ember_core::estimators::EstimatorKind;
use ember_host::driver::Limits;
use ember_host::scene::PreparedScene;

use crate::cli::CacheArgs;
use crate::estimators::CoreRenderer;
use crate::film::Film;
use crate::plot::{self, Floor, Series};
use crate::progress::DriverConfig;
use ember_formats::error_time::{Checkpoint, Reference, averaged, checkpoints, csv};
use ember_formats::metrics;

/// What to measure.
#[derive(Clone, Debug)]
pub struct ConvergenceSetup {
    pub estimators: Vec<EstimatorKind>,
    pub budget_seconds: f64,
    pub seeds: u32,
    pub threads: usize,
    /// Overrides of the scene file's depth.
    pub max_depth: Option<i32>,
    /// Memory the renderers may claim together (`--memory-limit`); `None`: what the
    /// machine has available ([`ember_host::memory::available_bytes`]).
    pub memory_limit: Option<u64>,
    /// The estimators' options (`ember convergence`'s, as `ember render` takes them; the
    /// defaults in `ember suite`).
    pub options: CacheArgs,
}

/// Refuse an estimator list that names one twice (`-e pt,pt` ran PT twice); `convergence`
/// and `suite` check it before any work.
pub fn check_distinct(estimators: &[EstimatorKind]) -> Result<(), String> {
    match estimators.iter().enumerate().find(|(i, e)| estimators[..*i].contains(e)) {
        Some((_, dup)) => Err(format!("-e names {} twice: each estimator runs once per seed (--seeds sets the repeats)", dup.name())),
        None => Ok(()),
    }
}

/// Refuse, before building them, estimators whose renderers (all held at once, one per
/// estimator) would together need more memory than `limit` or the memory available.
fn check_memory(prepared: &PreparedScene, estimators: &[EstimatorKind], options: &CacheArgs, limit: Option<u64>) -> Result<(), String> {
    let camera = &prepared.scene.camera;
    let mut total = 0u64;
    let mut largest = (0u64, EstimatorKind::Pt);
    for &e in estimators {
        let (bytes, _) = prepared.memory_need(&options.config_for(e));
        total = total.saturating_add(bytes);
        if bytes > largest.0 {
            largest = (bytes, e);
        }
    }
    match crate::setup::memory_budget(limit) {
        (Some(a), source) if total > a => Err(format!(
            "the {} estimators, run side by side at {}×{}, would need about {} ({} the most, {}), more than the {} of {source}; run fewer estimators, lower the resolution or raise --memory-limit",
            estimators.len(),
            camera.width(),
            camera.height(),
            ember_host::memory::human(total),
            largest.1,
            ember_host::memory::human(largest.0),
            ember_host::memory::human(a)
        )),
        _ => Ok(()),
    }
}

/// One estimator's run of one seed: its renderer, film and own clock.
struct Run {
    estimator: EstimatorKind,
    renderer: CoreRenderer,
    film: Film,
    /// Time this run has had so far (its preprocessing included).
    spent: Duration,
}

/// Run every estimator and seed; `prepare` loads the scene (timed as preprocessing).
///
/// The estimators of one seed are INTERLEAVED: each is built on its own clock (scene
/// loading and preprocessing), then for each checkpoint in turn every estimator renders
/// until its own clock reaches it. A machine shared with other work then slows all of
/// them alike within each round, instead of whichever happened to run during a busy
/// spell (measured here: up to 35 % fewer passes for one estimator between two
/// sequential runs of the same command).
pub fn measure(
    setup: &ConvergenceSetup,
    reference: &Reference,
    prepare: &dyn Fn() -> Result<PreparedScene, String>,
    mut on_checkpoint: impl FnMut(&Checkpoint),
) -> Result<Vec<Checkpoint>, String> {
    let mut out = Vec::new();
    let (rw, rh) = (reference.image.width as usize, reference.image.height as usize);
    let config = DriverConfig { progress: false, ..DriverConfig::with_threads(setup.threads) };
    for seed in 0..setup.seeds {
        let mut runs = Vec::new();
        for &estimator in &setup.estimators {
            let start = Instant::now();
            let prepared = prepare()?;
            if runs.is_empty() {
                check_memory(&prepared, &setup.estimators, &setup.options, setup.memory_limit)?;
            }
            let depth = setup.max_depth.or(prepared.max_depth).unwrap_or(-1);
            let renderer = CoreRenderer::with_config(prepared, setup.options.config_for(estimator), depth, seed as u64, setup.threads)?;
            let (w, h) = (renderer.width(), renderer.height());
            if (w as usize, h as usize) != (rw, rh) {
                return Err(format!("the scene renders {w}x{h} but the reference is {rw}x{rh}"));
            }
            let film = Film::with_filter(w, h, renderer.camera_filter());
            runs.push(Run { estimator, renderer, film, spent: start.elapsed() });
        }
        for target in checkpoints(setup.budget_seconds) {
            for run in &mut runs {
                let target_duration = Duration::from_secs_f64(target);
                if run.spent < target_duration {
                    // The run's own clock: it started `spent` ago as far as it knows.
                    let now = Instant::now();
                    let start = now.checked_sub(run.spent).unwrap_or(now);
                    let limits = Limits { spp: u32::MAX, deadline: Some(start + target_duration), interrupt: None, first_pass: 0 };
                    run.renderer.render(&mut run.film, limits, config, start).map_err(|e| e.to_string())?;
                    run.spent += now.elapsed();
                }
                let image = run.film.to_rgb_f32();
                let c = Checkpoint {
                    estimator: run.estimator,
                    seed,
                    target_seconds: target,
                    elapsed_seconds: run.spent.as_secs_f64(),
                    passes: run.film.passes(),
                    metrics: metrics::compare(&image, &reference.image.pixels),
                };
                on_checkpoint(&c);
                out.push(c);
            }
        }
    }
    Ok(out)
}

/// The two plots (relMSE and MAPE against seconds) as SVG strings.
pub fn plots(title: &str, points: &[Checkpoint], estimators: &[EstimatorKind], reference: &Reference) -> (String, String) {
    let series = |pick: fn(&(f64, f64, f64)) -> f64| -> Vec<Series> {
        estimators.iter().map(|&e| Series { label: e.name().to_string(), points: averaged(points, e).iter().map(|p| (p.0, pick(p))).collect() }).collect()
    };
    let floor = |v: Option<f64>| v.map(|y| vec![Floor { label: "reference noise".into(), y }]).unwrap_or_default();
    let rel =
        plot::log_log_svg(&format!("{title}: relMSE"), "seconds (preprocessing included)", "relMSE", &series(|p| p.1), &floor(reference.floor.map(|f| f.0)));
    let mape =
        plot::log_log_svg(&format!("{title}: MAPE"), "seconds (preprocessing included)", "MAPE (%)", &series(|p| p.2), &floor(reference.floor.map(|f| f.1)));
    (rel, mape)
}

/// Write `NAME.csv`, `NAME-relmse.svg` and `NAME-mape.svg` into `dir`.
pub fn write_outputs(
    dir: &Path,
    name: &str,
    title: &str,
    points: &[Checkpoint],
    estimators: &[EstimatorKind],
    reference: &Reference,
) -> Result<Vec<PathBuf>, String> {
    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let (rel, mape) = plots(title, points, estimators, reference);
    let files = [(format!("{name}.csv"), csv(points)), (format!("{name}-relmse.svg"), rel), (format!("{name}-mape.svg"), mape)];
    let mut written = Vec::new();
    for (file, body) in files {
        let path = dir.join(file);
        ember_formats::image_io::write_atomically(&path, |temp| std::fs::write(temp, &body), |e| e).map_err(|e| format!("{}: {e}", path.display()))?;
        written.push(path);
    }
    Ok(written)
}
