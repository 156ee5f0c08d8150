//! The commands: what `ember render` does between parsing and exiting.
//!
//! `render`: check the options that can fail cheaply (scene file, output path) before
//! any work; build the renderer ([`crate::setup::make_built`]: scene, ray
//! queries, estimator); run the [`driver`](ember_host::driver) into a [`Film`]; write the
//! EXR and the PNG; print a summary. A split render (`--passes`, `--task-*`) renders
//! its range and writes a partial image instead ([`crate::distributed`]).
//!
//! `merge`: check the parts' headers, add their films, write the image. `train`: run
//! SPCBPT's preprocessing and store it ([`crate::trained`]).

use std::fmt;
use std::path::PathBuf;
use std::time::{Duration, Instant};

use ember_core::render::Film;
use ember_formats::image_io::{self, ImageError};
use ember_formats::metrics::{self, ErrorMetrics};
use ember_host::driver::{DriverError, Limits, RenderSummary};

use crate::cli::{Cli, Command, CompareArgs, ConvergenceArgs, MergeArgs, RenderArgs, SplitArgs};
use crate::convergence::{self, ConvergenceSetup};
use crate::estimators::{Built, GUIDE_SAMPLES};
use crate::progress::DriverConfig;
use crate::{distributed, setup, suite};
use ember_formats::error_time::Reference;

/// Everything a command can fail with; each message says what to do or which file.
#[derive(Debug)]
pub enum AppError {
    /// The output path is unusable.
    Output(String),
    /// The estimator could not be built for this scene and these options.
    Estimator(String),
    Driver(DriverError),
    Image(ImageError),
    /// Stopped by Ctrl-C (exit status [`ember_host::interrupt::EXIT_CODE`]); says what was kept.
    Interrupted(String),
}

impl fmt::Display for AppError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Output(m) => f.write_str(m),
            Self::Estimator(m) => write!(f, "cannot set up the renderer: {m}"),
            Self::Driver(e) => e.fmt(f),
            Self::Image(e) => e.fmt(f),
            Self::Interrupted(m) => f.write_str(m),
        }
    }
}

impl std::error::Error for AppError {}

/// Run a parsed command line; `start` is when the program started.
pub fn run(cli: &Cli, start: Instant) -> Result<(), AppError> {
    match &cli.command {
        Command::Render(args) => {
            if let Err(e) = ember_host::interrupt::install() {
                eprintln!("warning: {e}");
            }
            let report = render(args, start, true, |a| crate::setup::make_built_at(a, start))?;
            println!("{report}");
            if report.summary.interrupted {
                let s = if report.summary.passes == 1 { "" } else { "es" };
                return Err(AppError::Interrupted(format!(
                    "interrupted by {}: the image holds the {} completed pass{s}",
                    ember_host::interrupt::signal_name(),
                    report.summary.passes
                )));
            }
            Ok(())
        }
        Command::Compare(args) => {
            let m = compare_files(args)?;
            println!("relMSE     {:.6e}", m.rel_mse);
            println!("MAPE       {:.4} %", m.mape);
            println!("MAE        {:.6e}", m.mae);
            println!("mean ratio {:.6} (test / reference)", m.mean_ratio);
            println!("worst {}    {:.1} % of the relative squared error (fireflies)", metrics::WORST_PIXELS, 100.0 * m.worst8_share);
            Ok(())
        }
        Command::Convergence(args) => run_convergence(args),
        Command::Train(args) => {
            if args.estimator != ember_core::estimators::EstimatorKind::Spcbpt {
                // Refused before the scene loads: only SPCBPT's preprocessing is worth storing.
                return Err(AppError::Estimator(format!("{} has no trained state to save: only spcbpt trains a model", args.estimator.name())));
            }
            let out = &args.output;
            if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty() && !d.is_dir()) {
                return Err(AppError::Output(format!("output directory '{}' does not exist", dir.display())));
            }
            // `train X/scene.xml -o X/scene.xml` replaced the scene with the model.
            let inputs: Vec<&std::path::Path> = args.selection.scene.iter().map(|p| p.as_path()).collect();
            ember_formats::files::probe_output(out, &inputs).map_err(AppError::Output)?;
            let r = setup::make_core_renderer(&args.render_args()).map_err(AppError::Estimator)?;
            let bytes = crate::trained::encode(&r.renderer, &r.identity(), r.width(), r.height()).map_err(AppError::Estimator)?;
            image_io::write_atomically(out, |temp| std::fs::write(temp, &bytes), |e| e).map_err(|e| AppError::Output(format!("{}: {e}", out.display())))?;
            println!("trained    {} for {} in {:.2} s; wrote {} ({} bytes)", r.kind().name(), r.prepared.name, r.setup_seconds, out.display(), bytes.len());
            Ok(())
        }
        Command::Plan(args) => {
            let r = args.selection.render_args();
            let prepared = setup::prepare(&r).map_err(AppError::Estimator)?;
            for w in &prepared.warnings {
                eprintln!("warning: {w}");
            }
            let max_depth = r.max_depth.or(prepared.max_depth).unwrap_or(-1);
            let plans = crate::plan::plans_for_all(&prepared, max_depth, r.seed, r.thread_count(), args.pilot_samples).map_err(AppError::Estimator)?;
            if args.json {
                print!("{}", crate::plan::json_all(&prepared, &plans));
            } else {
                print!("{}", crate::plan::describe_all(&prepared, &plans));
            }
            Ok(())
        }
        Command::Merge(args) => {
            let (header, exr, png) = merge(args)?;
            let t = header.tallies;
            println!(
                "merged     {} parts: passes {} of {} of {} with {}, {}x{}, seed {}",
                args.parts.len(),
                header.passes,
                header.total,
                header.scene,
                header.estimator,
                header.width,
                header.height,
                header.seed
            );
            println!("discarded  {} samples (NaN, infinite or negative); {} clamped sums", t.discarded, t.saturated);
            match png {
                Some(png) => println!("wrote      {} and {}", exr.display(), png.display()),
                None => println!("wrote      {} (partial: passes {} of {}; merge it with the others)", exr.display(), header.passes, header.total),
            }
            Ok(())
        }
        Command::Suite(args) => {
            ember_formats::files::probe_output(&args.output, &[]).map_err(AppError::Output)?;
            let threads = crate::cli::thread_count(args.threads);
            let results = suite::run(args, threads).map_err(AppError::Estimator)?;
            // As a user would type it from the repository root.
            let command = format!("cargo run --release -p ember-cli -- {}", std::env::args().skip(1).collect::<Vec<_>>().join(" "));
            let report = suite::report(args, threads, &results, &command);
            let write = |temp: &std::path::Path| std::fs::write(temp, &report);
            image_io::write_atomically(&args.output, write, |e| e).map_err(|e| AppError::Output(format!("{}: {e}", args.output.display())))?;
            println!("{report}");
            println!("wrote {}", args.output.display());
            Ok(())
        }
    }
}

/// `ember convergence`: error against time for one scene.
fn run_convergence(args: &ConvergenceArgs) -> Result<(), AppError> {
    // The output folder first (`-o /dev/full` failed after the whole run).
    let out = &args.output;
    if out.exists() && !out.is_dir() {
        return Err(AppError::Output(format!("output folder '{}' exists and is not a folder", out.display())));
    }
    std::fs::create_dir_all(out).map_err(|e| AppError::Output(format!("cannot create output folder '{}': {e}", out.display())))?;
    ember_formats::files::probe_output(&out.join("convergence.md"), &[]).map_err(AppError::Output)?;
    // The scene first: a missing scene was reported as a missing reference beside it.
    ember_formats::files::open_regular(&args.scene).map_err(|e| AppError::Estimator(format!("scene {}: {e}", args.scene.display())))?;
    convergence::check_distinct(&args.estimators).map_err(AppError::Estimator)?;
    let reference_path = args.reference.clone().unwrap_or_else(|| args.scene.with_file_name("reference.exr"));
    let reference = Reference::load(&reference_path).map_err(AppError::Output)?;
    let threads = crate::cli::thread_count(args.threads);
    let setup = ConvergenceSetup {
        estimators: args.estimators.clone(),
        budget_seconds: args.budget,
        seeds: args.seeds,
        threads,
        max_depth: args.max_depth,
        memory_limit: args.memory_limit,
        options: args.cache.clone(),
    };
    let prepare = setup::preparer(&args.scene, &args.defines.pairs);
    let points = convergence::measure(&setup, &reference, &prepare, |c| {
        println!(
            "{:5} seed {} at {:7.2} s: relMSE {:.4e}  MAPE {:7.3} %  ({} passes)",
            c.estimator.name(),
            c.seed,
            c.elapsed_seconds,
            c.metrics.rel_mse,
            c.metrics.mape,
            c.passes
        );
    })
    .map_err(AppError::Estimator)?;
    if let Some((rel, mape)) = reference.floor {
        println!("reference noise floor: relMSE {rel:.4e}, MAPE {mape:.3} %");
    }
    let name = args.scene.parent().and_then(|p| p.file_name()).map_or("scene".to_string(), |n| n.to_string_lossy().into_owned());
    let files = convergence::write_outputs(&args.output, &name, &name, &points, &args.estimators, &reference).map_err(AppError::Output)?;
    for f in files {
        println!("wrote {}", f.display());
    }
    Ok(())
}

/// `ember compare`: read both images, check their sizes, compute the metrics and
/// optionally write the false-colour error image.
pub fn compare_files(args: &CompareArgs) -> Result<ErrorMetrics, AppError> {
    // Never overwrite an input.
    if let Some(png) = &args.error_image {
        if [&args.test, &args.reference].iter().any(|input| ember_formats::files::same_file(png, input)) {
            return Err(AppError::Output(format!("--error-image '{}' is one of the images being compared; choose another file", png.display())));
        }
        ember_formats::files::probe_output(png, &[]).map_err(AppError::Output)?;
    }
    let test = image_io::read_exr(&args.test).map_err(AppError::Image)?;
    let reference = image_io::read_exr(&args.reference).map_err(AppError::Image)?;
    // A NaN or infinite pixel makes every metric NaN: refuse, naming the file.
    image_io::check_finite(&args.test, &test).and_then(|()| image_io::check_finite(&args.reference, &reference)).map_err(AppError::Image)?;
    if (test.width, test.height) != (reference.width, reference.height) {
        return Err(AppError::Output(format!(
            "'{}' is {}x{} but the reference '{}' is {}x{}",
            args.test.display(),
            test.width,
            test.height,
            args.reference.display(),
            reference.width,
            reference.height
        )));
    }
    let (mut test, mut reference) = (test, reference);
    if let Some([x0, y0, x1, y1]) = args.region {
        if x1 > test.width || y1 > test.height {
            return Err(AppError::Output(format!("--region {x0},{y0},{x1},{y1} reaches outside the {}x{} images", test.width, test.height)));
        }
        let crop = |pixels: &[[f32; 3]], width: u32| -> Vec<[f32; 3]> {
            (y0..y1).flat_map(|y| (x0..x1).map(move |x| (y * width + x) as usize)).map(|i| pixels[i]).collect()
        };
        test.pixels = crop(&test.pixels, test.width);
        reference.pixels = crop(&reference.pixels, reference.width);
        (test.width, test.height, reference.width, reference.height) = (x1 - x0, y1 - y0, x1 - x0, y1 - y0);
    }
    if let Some(png) = &args.error_image {
        let err = metrics::per_pixel_relative_error(&test.pixels, &reference.pixels);
        let colours: Vec<[f32; 3]> = err.iter().map(|&e| metrics::false_colour(e, args.error_max)).collect();
        // The PNG writer applies the sRGB curve; undo it so the ramp shows as designed.
        let linear: Vec<[f32; 3]> = colours.iter().map(|c| c.map(|v| v.powf(2.2))).collect();
        image_io::write_png(png, test.width, test.height, &linear, 0.0).map_err(AppError::Image)?;
    }
    Ok(metrics::compare(&test.pixels, &reference.pixels))
}

/// What `render` did, printed as the closing summary.
#[derive(Clone, Debug)]
pub struct RenderReport {
    pub scene: String,
    pub estimator: &'static str,
    pub width: u32,
    pub height: u32,
    pub max_depth: i32,
    pub seed: u64,
    /// The ray queries' instruction set.
    pub simd: ember_host::accel::Isa,
    /// The lane kernels' level.
    pub shading: ember_core::math::simd::Level,
    pub summary: RenderSummary,
    pub exr: PathBuf,
    /// The PNG beside the EXR (none for a partial image).
    pub png: Option<PathBuf>,
    /// A split render's share: the passes the partial image holds, of the total.
    pub partial: Option<(crate::distributed::PassRange, u32)>,
}

/// The pass range a `render` command asks for, with its task index if it names one
/// (`None` for a whole render).
fn requested_range(split: &SplitArgs, total: u32) -> Result<Option<(distributed::PassRange, Option<u32>)>, String> {
    let task = |index, count| distributed::PassRange::of_task(index, count, total).map(|r| Some((r, Some(index))));
    if let Some(r) = split.passes {
        if r.end > total {
            return Err(format!("--passes {r} reaches past the --spp total of {total} passes"));
        }
        return Ok(Some((r, None)));
    }
    if split.task_from_env {
        let (index, count) = distributed::task_from_env(|name| std::env::var(name).ok(), split.task_count)?;
        return task(index, count);
    }
    match (split.task_index, split.task_count) {
        (Some(i), Some(n)) => task(i, n),
        (None, Some(_)) => Err("--task-count needs --task-index or --task-from-env".into()),
        _ => Ok(None),
    }
}

/// `ember render` with the renderer built by `make` (the estimator wiring, or a test's).
pub fn render(args: &RenderArgs, start: Instant, progress: bool, make: impl FnOnce(&RenderArgs) -> Result<Built, String>) -> Result<RenderReport, AppError> {
    // Fail early on what needs no work. A split render's range needs only the options.
    if !args.aov.is_empty() && args.split != crate::cli::SplitArgs::default() {
        return Err(AppError::Output("--aov is not written by split renders (their parts hold sums, not images)".into()));
    }
    let split = match args.spp {
        Some(total) => requested_range(&args.split, total).map_err(AppError::Output)?,
        // clap requires --spp with the others; --task-count alone must not pass silently.
        None if args.split != crate::cli::SplitArgs::default() => {
            return Err(AppError::Output("--task-count needs --task-index or --task-from-env, and --spp (the total)".into()));
        }
        None => None,
    };
    let (mut exr, png) = args.output_paths().map_err(AppError::Output)?;
    if let Some((range, task)) = split {
        if args.split.task_from_env && distributed::placeholder(&exr).is_none() {
            // Every task of an array wrote to out.exr, each replacing the last.
            return Err(AppError::Output(format!(
                "--task-from-env: the output '{}' names neither {{task}} nor {{passes}}, so every task of the array would write the same file (e.g. -o 'parts/p-{{task}}.exr')",
                exr.display()
            )));
        }
        exr = distributed::expand_output(&exr, range, task).map_err(AppError::Output)?;
        // A part is only ever replaced by the same passes (a re-run of its own task).
        if exr.exists() {
            match distributed::read_partial_header(&exr) {
                Ok(h) if h.passes == range => {}
                Ok(h) => {
                    return Err(AppError::Output(format!(
                        "'{}' holds passes {} of another task; this render's passes are {range}: give each task its own output (-o 'p-{{task}}.exr')",
                        exr.display(),
                        h.passes
                    )));
                }
                Err(_) => {
                    return Err(AppError::Output(format!(
                        "'{}' exists and is not a part of passes {range}: a split render writes only new parts or its own",
                        exr.display()
                    )));
                }
            }
        }
    } else if let Some(p) = distributed::placeholder(&exr) {
        // A whole render wrote a file literally named `p-{task}.exr`.
        return Err(AppError::Output(format!(
            "output '{}' names {p}, which only a split render fills in (--task-index, --task-from-env or --passes)",
            exr.display()
        )));
    }
    if let Some(dir) = exr.parent().filter(|d| !d.as_os_str().is_empty() && !d.is_dir()) {
        return Err(AppError::Output(format!("output directory '{}' does not exist", dir.display())));
    }
    // Both files tried before any work; never over the scene or the model.
    let inputs: Vec<&std::path::Path> = args.scene.iter().chain(args.model.iter()).map(|p| p.as_path()).collect();
    for out in [&exr, &png] {
        ember_formats::files::probe_output(out, &inputs).map_err(AppError::Output)?;
    }

    if args.estimator == crate::cli::EstimatorChoice::Auto && (split.is_some() || args.model.is_some() || args.resume.is_some()) {
        // The race depends on timing: tasks of one split render could choose differently.
        return Err(AppError::Estimator("--estimator auto chooses by a timed race: name the estimator for split renders, --model and --resume".into()));
    }
    // The image to continue: read (and its checks) before any work.
    let resumed = match &args.resume {
        Some(path) => {
            let (header, film) = distributed::read_partial(path).map_err(|e| {
                AppError::Output(if e.contains("is not a partial image") {
                    // A plain image: say so in --resume's terms, not merge's.
                    format!(
                        "--resume {}: the image holds no exact sums; only images written with --checkpoint or at an interrupt hold the sums a render continues from",
                        path.display()
                    )
                } else {
                    format!("--resume: {e}")
                })
            })?;
            if header.passes.start != 0 {
                return Err(AppError::Output(format!(
                    "--resume {}: it holds passes {}, a part of a split render: merge the parts instead",
                    path.display(),
                    header.passes
                )));
            }
            Some((path.clone(), header, film))
        }
        None => None,
    };
    // Build the scene, the ray queries and the estimator.
    let built = make(args).map_err(AppError::Estimator)?;
    let mut renderer = built.renderer;
    // The files the scene read are known now: never write over one (a texture beside the
    // scene was overwritten by the PNG written beside `-o T/textures/tiles.exr`).
    let read = renderer.inputs();
    let read: Vec<&std::path::Path> = read.iter().map(|p| p.as_path()).collect();
    for out in [&exr, &png] {
        ember_formats::files::probe_output(out, &read).map_err(AppError::Output)?;
    }
    let (width, height) = renderer.size();
    let identity = if split.is_some() || args.resume.is_some() || args.checkpoint.is_some() {
        Some(renderer.identity().ok_or_else(|| AppError::Estimator("this renderer cannot be split into pass ranges".into()))?)
    } else {
        None
    };

    // Render passes until the spp or time limit.
    // (cli::parse_seconds bounds --time; a deadline past what Instant holds would be never.)
    let deadline = args.time.and_then(|t| Duration::try_from_secs_f64(t).ok().and_then(|d| start.checked_add(d)));
    // --spp, else unlimited under --time, else the scene file's sample count, else the default.
    let spp = ember_host::setup::pass_limit(args.spp, args.time, built.file_spp);
    let (mut first_pass, end) = split.map_or((0, spp), |(r, _)| (r.start, r.end));
    // A resumed render is the split render of the passes the image lacks, merged with it.
    if let (Some((path, header, _)), Some(identity)) = (&resumed, &identity) {
        let this = partial_header(identity, width, height, distributed::PassRange { start: 0, end: end.max(1) }, end, Default::default());
        if let Some(problem) = distributed::identity_mismatch(header, &this) {
            return Err(AppError::Output(format!("--resume {}: the image is not of this render: {problem}", path.display())));
        }
        first_pass = header.passes.end;
    }
    // A film the race began continues (its passes are this render's first), unless the
    // render is split into pass ranges (refused with auto anyway) or asked for fewer.
    let mut film = match built.film {
        Some(f) if split.is_none() && resumed.is_none() && (f.width(), f.height()) == (width, height) && f.passes() <= end => f,
        _ => Film::with_filter(width, height, renderer.filter()),
    };
    let held_before = film.passes();
    if held_before > 0 {
        eprintln!("continues  the {held_before} full-size pass{} the race rendered", if held_before == 1 { "" } else { "es" });
    }
    let limits = Limits { spp: end, deadline, interrupt: Some(ember_host::interrupt::flag()), first_pass };
    let config = DriverConfig { progress, ..DriverConfig::with_threads(args.thread_count()) };
    if progress && !std::io::IsTerminal::is_terminal(&std::io::stderr()) {
        // A log's first line: what is being rendered and until when.
        let mut until = match (args.time, spp) {
            (Some(t), u32::MAX) => format!("for {t} s"),
            (Some(t), n) => format!("{n} passes or {t} s"),
            (None, n) => format!("{n} passes"),
        };
        if let Some((r, _)) = split {
            until = format!("passes {r} of {until}");
        }
        eprintln!(
            "render: {} with {}, {width}x{height}, {until}, {} threads",
            built.scene,
            renderer.estimator_name().unwrap_or(args.estimator.name()),
            config.threads
        );
    }
    // With --checkpoint, the render runs in slices ending at a pass boundary after each
    // period, the output rewritten after each (the driver continues a film that holds
    // passes, so the slices render the passes one call would).
    let checkpoint = args.checkpoint.and_then(|t| Duration::try_from_secs_f64(t).ok());
    let mut summary: Option<RenderSummary> = None;
    loop {
        let slice_end = checkpoint.and_then(|c| Instant::now().checked_add(c));
        let slice = Limits { deadline: [deadline, slice_end].into_iter().flatten().min(), ..limits };
        let s = renderer.render(&mut film, slice, config, start).map_err(AppError::Driver)?;
        let done = s.interrupted || first_pass + film.passes() >= end || deadline.is_some_and(|d| Instant::now() >= d) || s.passes == 0;
        summary = Some(match summary {
            Some(before) => before.then(s),
            None => s,
        });
        if done {
            break;
        }
        if let Some(identity) = &identity {
            let (image, header) = whole_so_far(identity, &film, &resumed, first_pass, width, height, end);
            // A checkpoint that cannot be written is not worth the render: warn and go on
            // (the final write falls back to a rescue location).
            match distributed::write_partial(&exr, &header, &image) {
                Ok(()) => eprintln!("checkpoint {} passes written to {}", header.passes.end, exr.display()),
                Err(e) => eprintln!("warning: checkpoint of {} passes not written: {e}", header.passes.end),
            }
        }
    }
    let mut summary = summary.expect("the loop renders at least once");
    // The report counts the image's passes, the race's and the resumed image's among them.
    summary.passes += held_before + resumed.as_ref().map_or(0, |(_, h, _)| h.passes.len());
    if summary.interrupted && summary.passes == 0 {
        return Err(AppError::Interrupted("interrupted before any pass completed: nothing written".into()));
    }
    for line in renderer.memory_report() {
        eprintln!("{line}");
    }
    if film.saturated() > 0 {
        eprintln!("warning: {} additions passed the film's largest sum (2^64 per pixel) and were clamped", film.saturated());
    }

    // Write the images: a split render's partial image (what it holds: time limits and
    // interrupts may stop it early), else the EXR and the PNG.
    let base = RenderReport {
        scene: built.scene,
        estimator: renderer.estimator_name().unwrap_or(args.estimator.name()),
        width,
        height,
        max_depth: built.max_depth,
        seed: args.seed,
        simd: built.simd,
        shading: built.shading,
        summary,
        exr: exr.clone(),
        png: None,
        partial: None,
    };
    if let (Some(identity), Some((range, _))) = (&identity, split) {
        let held = distributed::PassRange { start: range.start, end: range.start + film.passes() };
        let header = partial_header(identity, width, height, held, spp, film.tallies());
        write_or_rescue(&exr, |p| distributed::write_partial(p, &header, &film))?;
        return Ok(RenderReport { partial: Some((held, spp)), ..base });
    }
    // A resumed render's image is the resumed one's passes and these, merged exactly. With
    // --checkpoint, or at an interrupt, the image keeps its exact sums (--resume continues
    // it); the PNG is written as usual.
    let keep_sums = args.checkpoint.is_some() || base.summary.interrupted;
    if resumed.is_some() || keep_sums {
        let identity = match identity {
            Some(i) => i,
            None => renderer.identity().ok_or_else(|| AppError::Estimator("this renderer cannot keep its sums".into()))?,
        };
        let (whole, header) = whole_so_far(&identity, &film, &resumed, first_pass, width, height, end);
        if keep_sums {
            write_or_rescue(&exr, |p| distributed::write_partial(p, &header, &whole))?;
            write_or_rescue(&png, |p| image_io::write_png(p, width, height, &whole.to_rgb_f32(), args.exposure))?;
            return Ok(RenderReport { png: Some(png), ..base });
        }
        film = whole;
    }
    let image = film.to_rgb_f32();
    if args.aov.is_empty() {
        write_or_rescue(&exr, |p| image_io::write_exr(p, width, height, &image))?;
    } else {
        let (albedo, normal) =
            renderer.guides(GUIDE_SAMPLES, args.seed, args.thread_count()).ok_or_else(|| AppError::Output("this renderer cannot write --aov".into()))?;
        let mut extra: Vec<(&str, &[[f32; 3]])> = Vec::new();
        for name in &args.aov {
            match name.as_str() {
                "albedo" => extra.push(("albedo", &albedo)),
                _ => extra.push(("normal", &normal)),
            }
        }
        write_or_rescue(&exr, |p| image_io::write_exr_with(p, width, height, &image, &extra))?;
    }
    write_or_rescue(&png, |p| image_io::write_png(p, width, height, &image, args.exposure))?;
    Ok(RenderReport { png: Some(png), ..base })
}

/// Write a render's output with `write`; if that fails after the work (the disk full, the
/// directory removed meanwhile), write it to a rescue file in the system's temporary
/// folder instead, and fail naming both (the render is never lost to a failed write).
fn write_or_rescue(path: &std::path::Path, write: impl Fn(&std::path::Path) -> Result<(), ImageError>) -> Result<(), AppError> {
    let Err(e) = write(path) else { return Ok(()) };
    let name = path.file_name().map_or_else(|| "out.exr".into(), |n| n.to_string_lossy().into_owned());
    let rescue = std::env::temp_dir().join(format!("ember-rescued-{}-{name}", std::process::id()));
    match write(&rescue) {
        Ok(()) => Err(AppError::Output(format!("{e}; the image was written to {} instead", rescue.display()))),
        Err(again) => Err(AppError::Output(format!("{e}; writing it to {} failed too: {again}", rescue.display()))),
    }
}

/// The partial-image header of `identity`'s render holding `passes` of `total`.
fn partial_header(
    identity: &distributed::RenderIdentity,
    width: u32,
    height: u32,
    passes: distributed::PassRange,
    total: u32,
    tallies: ember_core::render::Tallies,
) -> distributed::PartialHeader {
    distributed::PartialHeader {
        program: ember_host::program_version(),
        scene: identity.scene.clone(),
        scene_hash: identity.scene_hash,
        estimator: identity.estimator.clone(),
        config: identity.config.clone(),
        seed: identity.seed,
        width,
        height,
        passes,
        total,
        tallies,
    }
}

/// The whole image so far: `film` (passes `first_pass..`), after the resumed image's
/// passes `0..first_pass` where there is one, and its header.
fn whole_so_far(
    identity: &distributed::RenderIdentity,
    film: &Film,
    resumed: &Option<(std::path::PathBuf, distributed::PartialHeader, Film)>,
    first_pass: u32,
    width: u32,
    height: u32,
    end: u32,
) -> (Film, distributed::PartialHeader) {
    let mut whole = match resumed {
        Some((_, _, before)) => before.clone(),
        None => Film::new(width, height),
    };
    debug_assert_eq!(whole.passes(), first_pass);
    // Same size (checked against the header) and disjoint ranges: the merge cannot fail
    // but by a pass count past u32, which the range check excludes.
    let _ = whole.merge(film);
    let passes = distributed::PassRange { start: 0, end: whole.passes().max(1) };
    let header = partial_header(identity, width, height, passes, end.max(whole.passes()), whole.tallies());
    (whole, header)
}

/// `ember merge`: check the parts, merge them, write the EXR and the PNG (or, with
/// `--partial`, one partial image of their contiguous range); returns the merged header
/// and the paths written (no PNG for a partial).
pub fn merge(args: &MergeArgs) -> Result<(distributed::PartialHeader, PathBuf, Option<PathBuf>), AppError> {
    let (exr, png) = crate::cli::output_paths(&args.output).map_err(AppError::Output)?;
    // Never overwrite an input.
    if let Some(part) = args.parts.iter().find(|p| ember_formats::files::same_file(&exr, p) || ember_formats::files::same_file(&png, p)) {
        return Err(AppError::Output(format!("output '{}' is one of the parts being merged; choose another file", part.display())));
    }
    for out in [&exr, &png] {
        ember_formats::files::probe_output(out, &[]).map_err(AppError::Output)?;
    }
    let cover = if args.partial { distributed::Cover::Contiguous } else { distributed::Cover::All };
    let (header, film) = distributed::merge_parts(&args.parts, cover).map_err(AppError::Output)?;
    if args.partial {
        distributed::write_partial(&exr, &header, &film).map_err(AppError::Image)?;
        return Ok((header, exr, None));
    }
    let image = film.to_rgb_f32();
    image_io::write_exr(&exr, header.width, header.height, &image).map_err(AppError::Image)?;
    image_io::write_png(&png, header.width, header.height, &image, args.exposure).map_err(AppError::Image)?;
    Ok((header, exr, Some(png)))
}

/// `1234567.0` → `"1.23 M"`.
fn si(v: f64) -> String {
    match v {
        v if v >= 1e9 => format!("{:.2} G", v / 1e9),
        v if v >= 1e6 => format!("{:.2} M", v / 1e6),
        v if v >= 1e3 => format!("{:.2} k", v / 1e3),
        v => format!("{v:.0} "),
    }
}

impl fmt::Display for RenderReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let s = &self.summary;
        let depth = if self.max_depth < 0 { "-1 (unbounded)".to_string() } else { self.max_depth.to_string() };
        writeln!(f, "rendered   {} with {}, {}x{}, max depth {}, seed {}", self.scene, self.estimator, self.width, self.height, depth, self.seed)?;
        let setup = (s.total_seconds - s.render_seconds).max(0.0);
        writeln!(f, "time       {:.2} s ({:.2} s setup, {:.2} s rendering) on {} threads", s.total_seconds, setup, s.render_seconds, s.threads)?;
        // The traversal kernels' lanes, and the paths in flight where the estimator
        // shaded over lanes (PT and LT, docs/lanes.md), as the lane loop counted them;
        // the other estimators walk one path at a time.
        let lanes = s.stats.lanes;
        if lanes.width() > 1 {
            writeln!(
                f,
                "simd       {}, {} lanes (ray queries); {} shading, {} paths in flight",
                self.simd,
                self.simd.lanes(),
                self.shading.name(),
                lanes.width()
            )?;
            // Issue 52's occupancy: lane-steps with a path (only a range's tail leaves
            // lanes idle), and the arrivals the lane kernels shaded (Lambertian ones).
            writeln!(
                f,
                "lanes      {:.2} % of lane-steps busy ({} steps), {:.1} % of arrivals shaded over lanes",
                100.0 * lanes.occupancy(),
                lanes.steps,
                100.0 * lanes.shaded_share()
            )?;
        } else {
            writeln!(f, "simd       {}, {} lanes (ray queries; one path at a time)", self.simd, self.simd.lanes())?;
        }
        // Where a pass's time goes, phase by phase (filters, bidirectional estimators):
        // render seconds over the whole loop, every thread's work in its phase.
        if s.phase_seconds.len() > 1 {
            let phases: Vec<String> = s.phase_seconds.iter().map(|(name, t)| format!("{name} {t:.2} s")).collect();
            writeln!(f, "phases     {}", phases.join(", "))?;
        }
        writeln!(f, "passes     {} (samples per pixel)", s.passes)?;
        writeln!(f, "samples    {}samples/s ({}samples)", si(s.samples_per_second), si(s.stats.samples as f64))?;
        writeln!(f, "rays       {}rays/s ({}rays)", si(s.rays_per_second), si(s.stats.rays as f64))?;
        writeln!(f, "discarded  {} samples (NaN, infinite or negative)", s.discarded)?;
        let c = s.stats.connections;
        if c.traced > 0 {
            let share = |part: f64, all: f64| if all > 0.0 { 100.0 * part / all } else { 0.0 };
            writeln!(
                f,
                "connect    {} interior connections traced: {:.1} % occluded, {:.1} % of the value they would carry",
                c.traced,
                share(c.occluded as f64, c.traced as f64),
                share(c.occluded_value, c.value)
            )?;
        }
        match (&self.partial, &self.png) {
            (Some((held, total)), _) => write!(f, "wrote      {} (partial: passes {held} of {total}; `ember merge` the parts)", self.exr.display()),
            (None, Some(png)) => write!(f, "wrote      {} and {}", self.exr.display(), png.display()),
            (None, None) => write!(f, "wrote      {}", self.exr.display()),
        }
    }
}

#[cfg(test)]
mod tests;
