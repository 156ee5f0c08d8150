//! Command-line syntax (clap derive): `ember render [SCENE] [OPTIONS]`.
//!
//! Options are parsed and range-checked here, once; the rest of the program reads typed
//! values (the estimator as an enum, depths as integers) and never a string.

use std::path::{Path, PathBuf};

use clap::{Args, Parser, Subcommand};

pub use ember_host::setup::DEFAULT_SPP;
/// Resolution of the built-in scene when `--width`/`--height` are not given.
pub const DEFAULT_RESOLUTION: (u32, u32) = (512, 512);

/// ember: a physically based light-transport renderer.
#[derive(Parser, Debug, Clone, PartialEq)]
#[command(name = "ember", version, about, propagate_version = true)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand, Debug, Clone, PartialEq)]
pub enum Command {
    /// Render a scene to a linear-RGB EXR image, with a tone-mapped PNG beside it.
    Render(RenderArgs),
    /// Compare an EXR image with a reference: relMSE, MAPE, mean absolute error, ratio of means.
    Compare(CompareArgs),
    /// Error against time: snapshots at 1, 1.41, 2, 2.83, … seconds (scene loading and preprocessing included; estimators interleaved, each on its own clock)
    /// against a reference, averaged over seeds; writes a CSV and log-log plots.
    Convergence(ConvergenceArgs),
    /// Every estimator on every suite scene at equal time, threads and seeds; writes a
    /// markdown table and the plots.
    Suite(SuiteArgs),
    /// Run an estimator's preprocessing once and save its result (SPCBPT's κ trees, Q and
    /// Γ) for `render --model`: the tasks of a split render then skip it.
    Train(TrainArgs),
    /// Print the scene plan: what each estimator's techniques need, whether the scene has
    /// it, what a pilot of camera and light paths measured, and what a render leaves out
    /// (docs/plan.md).
    Plan(PlanArgs),
    /// Merge the partial images of a split render (`render --passes` or `--task-index`)
    /// into the final image: checks that the parts belong together and cover every pass
    /// once; the result equals a single-process render bit for bit (docs/distributed.md).
    Merge(MergeArgs),
}

/// The scene and the settings that decide a render's plan or preprocessing, shared by
/// `plan` and `train` (the renders that use their result must match them).
#[derive(Args, Debug, Clone, PartialEq)]
pub struct SceneSelection {
    /// Mitsuba 3 XML scene file. Omit it for the built-in Cornell box.
    #[arg(value_name = "SCENE")]
    pub scene: Option<PathBuf>,
    /// A built-in scene instead of a file (as for `render`).
    #[arg(long, value_name = "NAME", conflicts_with = "scene", value_parser = ["cornell-box", "glass-spheres"])]
    pub builtin: Option<String>,
    /// Threads [default: all cores].
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub threads: Option<u32>,
    /// Random seed (as for `render`).
    #[arg(long, value_name = "N", default_value_t = 0)]
    pub seed: u64,
    /// Image width (as for `render`).
    #[arg(long, value_name = "PIXELS", value_parser = clap::value_parser!(u32).range(1..=65536))]
    pub width: Option<u32>,
    /// Image height (as for `render`).
    #[arg(long, value_name = "PIXELS", value_parser = clap::value_parser!(u32).range(1..=65536))]
    pub height: Option<u32>,
    /// Longest path, in segments (as for `render`).
    #[arg(long, value_name = "N", allow_negative_numbers = true, value_parser = clap::value_parser!(i32).range(-1..))]
    pub max_depth: Option<i32>,
    #[command(flatten)]
    pub defines: Defines,
}

impl SceneSelection {
    /// The `render` options these stand for (render-only options at their defaults).
    pub fn render_args(&self) -> RenderArgs {
        let Command::Render(mut r) = Cli::parse_from(["ember", "render"]).command else { unreachable!("`render` parses to Render") };
        r.scene = self.scene.clone();
        r.builtin = self.builtin.clone();
        r.threads = self.threads;
        r.seed = self.seed;
        r.width = self.width;
        r.height = self.height;
        r.max_depth = self.max_depth;
        r.defines = self.defines.clone();
        r
    }
}

/// Options of `ember plan`.
#[derive(Args, Debug, Clone, PartialEq)]
pub struct PlanArgs {
    #[command(flatten)]
    pub selection: SceneSelection,
    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
    /// Camera and light path pairs the pilot traces.
    #[arg(long, value_name = "N", default_value_t = ember_core::plan::pilot::DEFAULT_SAMPLES, value_parser = clap::value_parser!(u32).range(1..=10_000_000))]
    pub pilot_samples: u32,
}

/// Options of `ember train`: those of `render` that decide the preprocessing.
#[derive(Args, Debug, Clone, PartialEq)]
pub struct TrainArgs {
    #[command(flatten)]
    pub selection: SceneSelection,
    /// The estimator whose preprocessing is saved (only spcbpt has one worth saving).
    #[arg(short, long, value_parser = estimator_parser(), default_value_t = EstimatorKind::Spcbpt)]
    pub estimator: EstimatorKind,
    /// Train every technique as asked (as `render --no-plan`); renders that load the
    /// model must then pass --no-plan too, since the model records its configuration.
    #[arg(long)]
    pub no_plan: bool,
    #[command(flatten)]
    pub cache: CacheArgs,
    /// The model file to write.
    #[arg(short, long, value_name = "FILE", default_value = "model.bin")]
    pub output: PathBuf,
}

impl TrainArgs {
    /// The `render` options these stand for (render-only options at their defaults).
    pub fn render_args(&self) -> RenderArgs {
        let mut r = self.selection.render_args();
        r.estimator = EstimatorChoice::Fixed(self.estimator);
        r.no_plan = self.no_plan;
        r.cache = self.cache.clone();
        r
    }
}

/// Options of `ember merge`.
#[derive(Args, Debug, Clone, PartialEq)]
pub struct MergeArgs {
    /// The partial images (EXR files written by `render --passes` or `--task-index`).
    #[arg(value_name = "PARTS", required = true)]
    pub parts: Vec<PathBuf>,
    /// Output EXR file; an sRGB PNG with the same stem is written beside it.
    #[arg(short, long, value_name = "FILE", default_value = "out.exr")]
    pub output: PathBuf,
    /// Exposure of the PNG in stops (as for `render`).
    #[arg(long, value_name = "STOPS", default_value_t = 0.0, allow_negative_numbers = true, value_parser = parse_exposure)]
    pub exposure: f32,
    /// Merge in stages: the parts' ranges must join into one contiguous range, written
    /// as a partial image again (no PNG), which a later merge takes like any part.
    #[arg(long)]
    pub partial: bool,
}

/// Render one share of a split render (docs/distributed.md): a range of passes of a fixed
/// total, written as a partial image that `ember merge` combines.
#[derive(Args, Debug, Clone, Default, PartialEq)]
pub struct SplitArgs {
    /// Render only passes A, A+1, …, B−1 (half-open: B is not rendered) of the --spp
    /// total, and write a partial image (exact sums and a header) for `ember merge`.
    #[arg(long, value_name = "A..B", value_parser = crate::distributed::PassRange::parse, requires = "spp",
          conflicts_with_all = ["task_index", "task_from_env"])]
    pub passes: Option<crate::distributed::PassRange>,
    /// Render task I of --task-count equal shares of the --spp passes (the first
    /// total mod N tasks get one pass more) as a partial image.
    #[arg(long, value_name = "I", requires_all = ["task_count", "spp"], conflicts_with = "task_from_env")]
    pub task_index: Option<u32>,
    /// The number of tasks the --spp passes are split into (with --task-index, or with
    /// --task-from-env under Kubernetes).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub task_count: Option<u32>,
    /// Take the task index from the scheduler: Slurm's SLURM_ARRAY_TASK_ID −
    /// SLURM_ARRAY_TASK_MIN (count SLURM_ARRAY_TASK_COUNT), or Kubernetes'
    /// JOB_COMPLETION_INDEX (count from --task-count). Without this flag the environment
    /// is never read: a render inside an array job stays a whole render.
    #[arg(long, requires = "spp")]
    pub task_from_env: bool,
}

/// Options of `ember convergence`.
#[derive(Args, Debug, Clone, PartialEq)]
pub struct ConvergenceArgs {
    /// Mitsuba 3 XML scene file.
    #[arg(value_name = "SCENE")]
    pub scene: PathBuf,
    /// Estimators to compare, comma separated.
    #[arg(short, long, value_parser = estimator_parser(), value_delimiter = ',', default_values_t = [EstimatorKind::Pt, EstimatorKind::Bdpt])]
    pub estimators: Vec<EstimatorKind>,
    /// Wall-clock budget per estimator and seed, in seconds (preprocessing included).
    #[arg(long, default_value_t = 16.0, value_name = "SECONDS", value_parser = parse_seconds)]
    pub budget: f64,
    /// Independent runs (seeds 0..N) averaged at each checkpoint.
    #[arg(long, default_value_t = 2, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=1000))]
    pub seeds: u32,
    /// Reference EXR (default: reference.exr beside the scene file).
    #[arg(long, value_name = "EXR")]
    pub reference: Option<PathBuf>,
    /// Render threads (default: every core; at most 4 × the cores, and 1024).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub threads: Option<u32>,
    /// Override the scene file's max_depth (-1: unbounded).
    #[arg(long, value_name = "N", allow_negative_numbers = true, value_parser = clap::value_parser!(i32).range(-1..))]
    pub max_depth: Option<i32>,
    /// Refuse a run whose estimators together (each holds its renderer until the end)
    /// would need more than this many bytes (suffixes K, M, G, T: binary) [default: the
    /// memory available].
    #[arg(long, value_name = "BYTES", value_parser = ember_host::memory::parse_size)]
    pub memory_limit: Option<u64>,
    #[command(flatten)]
    pub defines: Defines,
    /// The estimators' options, as `ember render` takes them (each estimator reads its
    /// own; e.g. `--neighbours 128` or `--radius-footprints 2` for the filters).
    #[command(flatten)]
    pub cache: CacheArgs,
    /// Output folder for NAME.csv, NAME-relmse.svg and NAME-mape.svg.
    #[arg(short, long, default_value = "convergence", value_name = "DIR")]
    pub output: PathBuf,
}

/// Options of `ember suite`.
#[derive(Args, Debug, Clone, PartialEq)]
pub struct SuiteArgs {
    /// Folder holding one folder per scene (scene.xml + reference.exr); repeat to take
    /// scenes from several folders (e.g. `--scenes ../shared/scenes --scenes
    /// ../shared/scenes-extra`). Scene names must be unique across them.
    #[arg(long, default_value = "../shared/scenes", value_name = "DIR", action = clap::ArgAction::Append)]
    pub scenes: Vec<PathBuf>,
    /// Only these scenes (folder names), comma separated; default all.
    #[arg(long, value_delimiter = ',', value_name = "NAMES")]
    pub only: Vec<String>,
    /// Estimators, comma separated.
    #[arg(short, long, value_parser = estimator_parser(), value_delimiter = ',', default_values_t = [EstimatorKind::Pt, EstimatorKind::Lt, EstimatorKind::Bdpt])]
    pub estimators: Vec<EstimatorKind>,
    /// Seconds per estimator, scene and seed (preprocessing included).
    #[arg(long, default_value_t = 30.0, value_name = "SECONDS", value_parser = parse_seconds)]
    pub budget: f64,
    /// Seeds per estimator and scene.
    #[arg(long, default_value_t = 2, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=1000))]
    pub seeds: u32,
    /// Render threads (default: every core; at most 4 × the cores, and 1024).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub threads: Option<u32>,
    /// Refuse a run whose estimators together (each holds its renderer until the end)
    /// would need more than this many bytes (suffixes K, M, G, T: binary) [default: the
    /// memory available].
    #[arg(long, value_name = "BYTES", value_parser = ember_host::memory::parse_size)]
    pub memory_limit: Option<u64>,
    #[command(flatten)]
    pub defines: Defines,
    /// The markdown report; plots and CSVs go to a folder of the same stem beside it.
    #[arg(short, long, default_value = "docs/results.md", value_name = "FILE")]
    pub output: PathBuf,
}

/// Options of `ember compare`.
#[derive(Args, Debug, Clone, PartialEq)]
pub struct CompareArgs {
    /// The image under test (EXR).
    #[arg(value_name = "TEST")]
    pub test: PathBuf,
    /// The reference image (EXR), same resolution.
    #[arg(value_name = "REFERENCE")]
    pub reference: PathBuf,
    /// Write a false-colour PNG of the per-pixel relative error |a − b| / (b + 0.01).
    #[arg(long, value_name = "PNG")]
    pub error_image: Option<PathBuf>,
    /// Relative error shown as full red in the false-colour image (log scale over three decades).
    #[arg(long, default_value_t = 1.0, value_name = "ERR")]
    pub error_max: f32,
    /// Compare only the pixels x0 ≤ x < x1, y0 ≤ y < y1 (a half-open rectangle, (0, 0)
    /// the top-left pixel): e.g. a caustic seen through glass.
    #[arg(long, value_name = "X0,Y0,X1,Y1", value_parser = parse_region)]
    pub region: Option<[u32; 4]>,
}

/// `-D KEY=VALUE`: scene parameters, for every command that loads a scene file.
#[derive(Args, Debug, Clone, Default, PartialEq)]
pub struct Defines {
    /// Set the scene parameter KEY, replacing the file's `<default name="KEY" value="...">`
    /// and filling its `$KEY` (as `mitsuba -D`); repeatable, the last of a KEY wins. A KEY
    /// the scene never uses gives a warning.
    #[arg(short = 'D', long = "define", value_name = "KEY=VALUE", value_parser = parse_define)]
    pub pairs: Vec<(String, String)>,
}

/// `KEY=VALUE`, KEY being letters, digits and `_` (as a scene file's parameter names);
/// VALUE may be empty or hold `=`.
fn parse_define(text: &str) -> Result<(String, String), String> {
    let Some((key, value)) = text.split_once('=') else {
        return Err(format!("'{text}' has no '=': -D takes KEY=VALUE, e.g. -D spp=64"));
    };
    if key.is_empty() {
        return Err(format!("'{text}' has an empty KEY: -D takes KEY=VALUE, e.g. -D spp=64"));
    }
    if !key.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
        return Err(format!("-D parameter name '{key}' must be letters, digits and '_'"));
    }
    Ok((key.to_string(), value.to_string()))
}

/// `x0,y0,x1,y1` with x0 < x1 and y0 < y1.
fn parse_region(text: &str) -> Result<[u32; 4], String> {
    let parts: Vec<&str> = text.split(',').map(str::trim).collect();
    let values: Vec<u32> =
        parts.iter().map(|p| p.parse::<u32>()).collect::<Result<_, _>>().map_err(|_| format!("'{text}' is not four non-negative integers x0,y0,x1,y1"))?;
    match values[..] {
        [x0, y0, x1, y1] if x0 < x1 && y0 < y1 => Ok([x0, y0, x1, y1]),
        [_, _, _, _] => Err(format!("'{text}' is empty: need x0 < x1 and y0 < y1")),
        _ => Err(format!("'{text}' is not four integers x0,y0,x1,y1")),
    }
}

/// The light-transport algorithm: the core's one list of estimators.
pub use ember_core::estimators::EstimatorKind;
use ember_core::estimators::{EstimatorConfig, FilterConfig, KernelChoice, LvcbptConfig, MergingConfig, SegmentConfig, SpcbptConfig};
use ember_core::merge::RadiusRule;

/// Parses an estimator name; `--help` lists each with its summary.
fn estimator_parser() -> impl clap::builder::TypedValueParser<Value = EstimatorKind> {
    use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
    PossibleValuesParser::new(EstimatorKind::ALL.map(|e| PossibleValue::new(e.name()).help(e.summary())))
        .map(|name| EstimatorKind::from_name(&name).expect("clap accepts only the listed names"))
}

/// `--estimator` of `ember render`: one of the core's estimators, or `auto`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EstimatorChoice {
    /// The estimator named.
    Fixed(EstimatorKind),
    /// Chosen per scene by the plan and a pilot race ([`crate::auto`]).
    Auto,
}

impl EstimatorChoice {
    /// The name as typed.
    pub fn name(self) -> &'static str {
        match self {
            Self::Fixed(k) => k.name(),
            Self::Auto => "auto",
        }
    }
}

impl std::fmt::Display for EstimatorChoice {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Parses an estimator name or `auto`.
fn estimator_choice_parser() -> impl clap::builder::TypedValueParser<Value = EstimatorChoice> {
    use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
    let mut values: Vec<PossibleValue> = EstimatorKind::ALL.iter().map(|e| PossibleValue::new(e.name()).help(e.summary())).collect();
    values.push(PossibleValue::new("auto").help(
        "chosen per scene: the scene plan and a pilot race of pt, lt, bdpt, ppm and bpm at a quarter of the resolution, counted in --time (docs/plan.md)",
    ));
    PossibleValuesParser::new(values).map(|name| match EstimatorKind::from_name(&name) {
        Some(k) => EstimatorChoice::Fixed(k),
        None => EstimatorChoice::Auto,
    })
}

/// Options of `ember render`.
#[derive(Args, Debug, Clone, PartialEq)]
pub struct RenderArgs {
    /// Mitsuba 3 XML scene file. Omit it to render the built-in Cornell box.
    #[arg(value_name = "SCENE")]
    pub scene: Option<PathBuf>,

    /// Render a built-in scene instead of a file: `cornell-box` (the default without a
    /// SCENE) or `glass-spheres` (caustics through a glass and a mirror sphere).
    #[arg(long, value_name = "NAME", conflicts_with = "scene", value_parser = ["cornell-box", "glass-spheres"])]
    pub builtin: Option<String>,

    /// Light-transport algorithm.
    #[arg(short, long, value_parser = estimator_choice_parser(), default_value_t = EstimatorChoice::Fixed(EstimatorKind::Pt))]
    pub estimator: EstimatorChoice,

    /// Render every technique of the estimator as asked: the scene plan leaves nothing
    /// out (by default it leaves out what the scene cannot use, e.g. VCM's merging where
    /// no specular–diffuse–specular chain exists; `ember plan` shows what and why).
    #[arg(long)]
    pub no_plan: bool,

    #[command(flatten)]
    pub cache: CacheArgs,

    /// Samples per pixel (passes) [default: unlimited when --time is given; else the scene
    /// file's `sample_count` (its sampler's) where it gives one; else 16, as for the
    /// built-in scenes].
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub spp: Option<u32>,

    /// Wall-clock budget in seconds, counted from program start (scene loading and
    /// preprocessing included). The pass running when it expires is finished; with --spp
    /// too, whichever limit comes first stops the render.
    #[arg(long, value_name = "SECONDS", value_parser = parse_seconds)]
    pub time: Option<f64>,

    /// Render threads [default: all cores].
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub threads: Option<u32>,

    /// Random seed. The image is a pure function of the scene, the options and the seed,
    /// whatever the thread count.
    #[arg(long, value_name = "N", default_value_t = 0)]
    pub seed: u64,

    /// SIMD instruction set of the ray queries: scalar, sse, avx2, avx512, neon or
    /// simd128, one this machine offers (overrides the environment's EMBER_SIMD). The
    /// image does not depend on it [default: avx2 where the machine has it, else its widest].
    #[arg(long, value_name = "NAME")]
    pub simd: Option<String>,

    /// Image width in pixels; given without --height, the height follows the film's
    /// aspect ratio, rounded to the nearest pixel [default: the scene's film; 512 for the
    /// built-in scene].
    #[arg(long, value_name = "PIXELS", value_parser = clap::value_parser!(u32).range(1..=65536))]
    pub width: Option<u32>,

    /// Image height in pixels; given without --width, the width follows the film's aspect
    /// ratio, rounded to the nearest pixel [default: the scene's film; 512 for the
    /// built-in scene].
    #[arg(long, value_name = "PIXELS", value_parser = clap::value_parser!(u32).range(1..=65536))]
    pub height: Option<u32>,

    /// Longest path, in segments, as Mitsuba's max_depth: 1 = directly visible emitters
    /// only, 2 = direct illumination, -1 = unbounded (Russian roulette ends paths)
    /// [default: the scene's integrator; -1 for the built-in scene].
    #[arg(long, value_name = "N", allow_negative_numbers = true,
          value_parser = clap::value_parser!(i32).range(-1..))]
    pub max_depth: Option<i32>,

    // Scene parameters (`-D KEY=VALUE`); refused without a SCENE file.
    #[command(flatten)]
    pub defines: Defines,

    #[command(flatten)]
    pub split: SplitArgs,

    /// Load the preprocessing's result from FILE (written by `ember train` with the same
    /// scene, estimator options, seed and resolution) instead of computing it: SPCBPT's
    /// κ trees, Q and Γ. A file that does not match, or is damaged, is refused.
    #[arg(long, value_name = "FILE")]
    pub model: Option<PathBuf>,

    /// Every SECONDS, at the end of a pass, rewrite the output (atomically) with the passes
    /// so far. An image written with --checkpoint, or at an interrupt, holds its exact
    /// sums beside the RGB, so --resume can continue it.
    #[arg(long, value_name = "SECONDS", value_parser = parse_seconds)]
    pub checkpoint: Option<f64>,

    /// Continue IMAGE (written with --checkpoint or at an interrupt, by this program with
    /// this scene, estimator, options and seed): render the passes it lacks up to --spp
    /// (or for --time, counted afresh) and write an image bit-identical to an
    /// uninterrupted render of the same total. IMAGE may be the output itself.
    #[arg(long, value_name = "IMAGE", conflicts_with_all = ["passes", "task_index", "task_from_env"])]
    pub resume: Option<PathBuf>,

    /// Output EXR file (linear RGB, 32-bit float); an sRGB PNG with the same stem is
    /// written beside it. A split render writes only the partial EXR; `{task}` in the
    /// name becomes the task index, `{passes}` the range (e.g. `8-16`).
    #[arg(short, long, value_name = "FILE", default_value = "out.exr")]
    pub output: PathBuf,
    /// Refuse a render whose estimated memory exceeds this many bytes (suffixes K, M, G,
    /// T: binary) [default: the memory available: the smaller of MemAvailable and the
    /// cgroup's remaining limit].
    #[arg(long, value_name = "BYTES", value_parser = ember_host::memory::parse_size)]
    pub memory_limit: Option<u64>,

    /// Exposure of the PNG in stops (the PNG is linear × 2^STOPS, clamped, sRGB-encoded;
    /// the EXR is never scaled).
    #[arg(long, value_name = "STOPS", default_value_t = 0.0, allow_negative_numbers = true,
          value_parser = parse_exposure)]
    pub exposure: f32,

    /// Denoiser guides written as extra channels of the EXR (`albedo.R`, ..., `normal.B`):
    /// the first non-specular surface's albedo and world-space shading normal, averaged
    /// over 16 rays a pixel, as Intel Open Image Denoise takes them. Comma separated.
    #[arg(long, value_name = "LIST", value_delimiter = ',', value_parser = ["albedo", "normal"])]
    pub aov: Vec<String>,
}

/// Options of the cache-based estimators (LVCBPT, SPCBPT): parsed into the core's
/// [`LvcbptConfig`] and [`SpcbptConfig`], whose documentation holds the defaults and the
/// scaling rule for small images; the core validates the ranges.
#[derive(Args, Debug, Clone, PartialEq)]
#[command(next_help_heading = "LVCBPT / SPCBPT / PPM / BPM / VCM")]
pub struct CacheArgs {
    /// Light paths per pass, M [default: min(100000, W·H); PPM, BPM, VCM: N_L = W·H].
    #[arg(long, value_name = "M", value_parser = clap::value_parser!(u32).range(1..))]
    pub light_paths: Option<u32>,
    /// Connections per camera vertex, N.
    #[arg(long, value_name = "N", default_value_t = SpcbptConfig::DEFAULT.connections)]
    pub connections: u32,
    /// SPCBPT: training paths, |D| [default: min(1000000, 16·W·H)].
    #[arg(long, value_name = "PATHS", value_parser = clap::value_parser!(u32).range(1..))]
    pub dataset: Option<u32>,
    /// SPCBPT: subspaces per side, N_S, on the light side shared with the light-source
    /// bins [default: min(1000, ⌊√(W·H)⌋), at least 16: Γ has about one entry per pixel,
    /// D at least 16 paths per entry].
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(2..))]
    pub subspaces: Option<u32>,
    /// SPCBPT: Adam learning rate α (the paper's 0.1: measured 4-40x less excess loss than
    /// the public code's 0.01-0.02 within the paper's step budget, docs/spcbpt-training.md).
    #[arg(long, value_name = "ALPHA", default_value_t = SpcbptConfig::DEFAULT.learning_rate)]
    pub learning_rate: f32,
    /// SPCBPT: Adam mini-batch size at most (a small D gets smaller batches, see --steps).
    #[arg(long, value_name = "PATHS", default_value_t = SpcbptConfig::DEFAULT.batch)]
    pub batch: u32,
    /// SPCBPT: Adam steps at least (the paper's 10⁶ paths / 10⁴ per batch × 2 epochs); a
    /// D smaller than batch × steps / epochs is cut into smaller batches. 0: batch as given.
    #[arg(long, value_name = "N", default_value_t = SpcbptConfig::DEFAULT.steps)]
    pub steps: u32,
    /// SPCBPT: training epochs.
    #[arg(long, value_name = "N", default_value_t = SpcbptConfig::DEFAULT.epochs)]
    pub epochs: u32,
    /// SPCBPT: weight of the uniform distribution mixed into Γ.
    #[arg(long, value_name = "M", default_value_t = SpcbptConfig::DEFAULT.mixture)]
    pub mixture: f32,
    /// SPCBPT: light vertices retained per subspace across passes, M0.
    #[arg(long, value_name = "M0", default_value_t = SpcbptConfig::DEFAULT.reuse)]
    pub reuse: u32,
    /// SPCBPT: weight of the normal/direction terms in the classification distance, k_d.
    #[arg(long, value_name = "K", default_value_t = SpcbptConfig::DEFAULT.k_d)]
    pub k_d: f32,
    /// SPCBPT: share of the N_S light subspaces given to positions on the lights (the
    /// paper's ~20 %); their vertices are cached and Γ-sampled instead of next-event
    /// estimation. 0, or a scene with a point, spot or infinite light, keeps NEE.
    #[arg(long, value_name = "SHARE", default_value_t = SpcbptConfig::DEFAULT.light_source_share, value_parser = parse_share)]
    pub light_source_share: f32,
    /// SPCBPT: light paths estimating Q per light subspace, M' [default: min(2000000, 2·W·H)].
    #[arg(long, value_name = "PATHS", value_parser = clap::value_parser!(u32).range(1..))]
    pub q_paths: Option<u32>,
    /// SPT/SLT/SBDPT: the kernel joining consecutive segments: dirac (x_{i+1} = y_i, the vertex
    /// formulation: spt = pt, slt = lt, sbdpt = bdpt) or disk (uniform over the surface within a disk of
    /// the radius below around y_i; its radius stays fixed over passes).
    #[arg(long, value_name = "KERNEL", value_enum, default_value_t = KernelArg::Dirac)]
    pub kernel: KernelArg,
    /// PPM/BPM/VCM/MVF/PhF/BPF: initial merging radius r₀ in scene units; SPT/SLT/SBDPT: the disk kernel's
    /// radius [default: 4 pixel footprints].
    #[arg(long, value_name = "R", allow_negative_numbers = true, conflicts_with_all = ["radius_footprints", "radius_scene"])]
    pub radius: Option<f32>,
    /// PPM/BPM/VCM/MVF/PhF/BPF: r₀ as a multiple of the mean pixel footprint (hit distance × pixel
    /// angle, averaged over the image; the segment paper's 4) [default: 4].
    #[arg(long, value_name = "K", allow_negative_numbers = true, conflicts_with = "radius_scene")]
    pub radius_footprints: Option<f32>,
    /// PPM/BPM/VCM/MVF/PhF/BPF: r₀ as a fraction of the scene's bounding-sphere radius (SmallVCM's 0.003).
    #[arg(long, value_name = "F", allow_negative_numbers = true)]
    pub radius_scene: Option<f32>,
    /// PPM/BPM/VCM/MVF/PhF/BPF: radius reduction α in (0, 1]: r_i = r₀ (i + 1)^((α − 1)/2); 1 keeps r fixed.
    #[arg(long, value_name = "ALPHA", allow_negative_numbers = true, default_value_t = MergingConfig::DEFAULT.alpha)]
    pub alpha: f32,
    /// MVF/PhF/BPF: segments per path at most, each one propagation sweep per pass, 1 to 64
    /// [default: the scene's max_depth; 16 where it is unbounded].
    #[arg(long, value_name = "N")]
    pub max_segments: Option<u32>,
    /// BPF: light paths per camera path, β in [0, 16] (N_L = β · width · height per pass;
    /// the segment paper's 0.25, and 1 on caustics).
    #[arg(long, value_name = "BETA", allow_negative_numbers = true, default_value_t = FilterConfig::DEFAULT.beta)]
    pub beta: f32,
    /// BPF: which segment paths its junctions form: `every` segment in a kernel (the
    /// paper's estimator), only bidirectional photon mapping's `merges` (its reduction
    /// to BPM), or every segment and `bridges` from each camera node to a light node (the
    /// paper's Fig. 7)
    #[arg(long, value_name = "REUSE", default_value = "every", value_parser = ["every", "merges", "bridges"])]
    pub filter_reuse: String,
    /// MVF/PhF/BPF: nodes on materials of microfacet roughness α below this get a kernel
    /// α / this times the pass's, so glossy highlights are not smeared over the kernel;
    /// 0 to 1, 0 gives every node the pass's kernel
    #[arg(long, value_name = "ALPHA", allow_negative_numbers = true, default_value_t = FilterConfig::DEFAULT.glossy_alpha)]
    pub glossy_alpha: f32,
    /// MVF/PhF/BPF: the mean number of nodes per kernel a pass keeps at most, 1 to 4096:
    /// where nodes crowd (caustics, a spot light's pool) the pass lowers its radius, since
    /// a pass costs O(Σ n²) in the kernels' populations n
    #[arg(long, value_name = "N", default_value_t = FilterConfig::DEFAULT.neighbours)]
    pub neighbours: u32,
}

impl Default for CacheArgs {
    fn default() -> Self {
        let d = SpcbptConfig::DEFAULT;
        Self {
            light_paths: d.light_paths,
            connections: d.connections,
            dataset: d.dataset,
            subspaces: d.subspaces,
            learning_rate: d.learning_rate,
            batch: d.batch,
            steps: d.steps,
            epochs: d.epochs,
            mixture: d.mixture,
            reuse: d.reuse,
            k_d: d.k_d,
            light_source_share: d.light_source_share,
            q_paths: d.q_paths,
            kernel: KernelArg::Dirac,
            radius: None,
            radius_footprints: None,
            radius_scene: None,
            alpha: MergingConfig::DEFAULT.alpha,
            max_segments: None,
            beta: FilterConfig::DEFAULT.beta,
            filter_reuse: "every".into(),
            glossy_alpha: FilterConfig::DEFAULT.glossy_alpha,
            neighbours: FilterConfig::DEFAULT.neighbours,
        }
    }
}

impl CacheArgs {
    /// LVCBPT's configuration from these options.
    pub fn lvcbpt(&self) -> LvcbptConfig {
        LvcbptConfig { light_paths: self.light_paths, connections: self.connections, ..LvcbptConfig::DEFAULT }
    }
    /// SPCBPT's configuration from these options.
    pub fn spcbpt(&self) -> SpcbptConfig {
        SpcbptConfig {
            light_paths: self.light_paths,
            connections: self.connections,
            dataset: self.dataset,
            subspaces: self.subspaces,
            learning_rate: self.learning_rate,
            batch: self.batch,
            steps: self.steps,
            epochs: self.epochs,
            mixture: self.mixture,
            reuse: self.reuse,
            k_d: self.k_d,
            light_source_share: self.light_source_share,
            q_paths: self.q_paths,
        }
    }
    /// The radius rule from --radius, --radius-footprints or --radius-scene.
    fn radius_rule(&self) -> RadiusRule {
        match (self.radius, self.radius_footprints, self.radius_scene) {
            (Some(r), _, _) => RadiusRule::Absolute(r),
            (_, Some(k), _) => RadiusRule::Footprints(k),
            (_, _, Some(f)) => RadiusRule::SceneFraction(f),
            _ => RadiusRule::DEFAULT,
        }
    }
    /// The merging estimators' configuration from these options.
    pub fn merging(&self) -> MergingConfig {
        MergingConfig { light_paths: self.light_paths, radius: self.radius_rule(), alpha: self.alpha, ..MergingConfig::DEFAULT }
    }
    /// The segment estimators' configuration from these options.
    pub fn segment(&self) -> SegmentConfig {
        let kernel = match self.kernel {
            KernelArg::Dirac => KernelChoice::Dirac,
            KernelArg::Disk => KernelChoice::Disk,
        };
        SegmentConfig { kernel, radius: self.radius_rule() }
    }
    /// Path filtering's configuration from these options.
    pub fn filter(&self) -> FilterConfig {
        FilterConfig {
            radius: self.radius_rule(),
            alpha: self.alpha,
            max_segments: self.max_segments,
            beta: self.beta,
            reuse: match self.filter_reuse.as_str() {
                "merges" => ember_core::estimators::FilterReuse::Merges,
                "bridges" => ember_core::estimators::FilterReuse::Bridges,
                _ => ember_core::estimators::FilterReuse::Every,
            },
            glossy_alpha: self.glossy_alpha,
            neighbours: self.neighbours,
        }
    }
    /// The configuration of `estimator` (these options apply to the cache-based and
    /// merging estimators only).
    pub fn config_for(&self, estimator: EstimatorKind) -> EstimatorConfig {
        match (estimator, estimator.default_config()) {
            (EstimatorKind::Lvcbpt, _) => EstimatorConfig::Lvcbpt(self.lvcbpt()),
            (EstimatorKind::Spcbpt, _) => EstimatorConfig::Spcbpt(self.spcbpt()),
            (_, EstimatorConfig::Merging(mode, _)) => EstimatorConfig::Merging(mode, self.merging()),
            (_, EstimatorConfig::Segment(algorithm, _)) => EstimatorConfig::Segment(algorithm, self.segment()),
            (_, EstimatorConfig::Filter(side, _)) => EstimatorConfig::Filter(side, self.filter()),
            (_, other) => other,
        }
    }
}

/// `--kernel`: the segment estimators' kernel ([`KernelChoice`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum KernelArg {
    /// x_{i+1} = y_i: the vertex formulation.
    Dirac,
    /// Uniform over the surface within a disk around y_i.
    Disk,
}

/// A share in [0, 1).
fn parse_share(text: &str) -> Result<f32, String> {
    match text.parse::<f32>() {
        Ok(v) if (0.0..1.0).contains(&v) => Ok(v),
        Ok(v) => Err(format!("{v} is not in [0, 1)")),
        Err(e) => Err(e.to_string()),
    }
}

pub use ember_host::setup::MAX_SECONDS;

fn parse_seconds(s: &str) -> Result<f64, String> {
    let v: f64 = s.parse().map_err(|_| format!("'{s}' is not a number of seconds"))?;
    ember_host::setup::check_seconds(v, s)
}

fn parse_exposure(s: &str) -> Result<f32, String> {
    let v: f32 = s.parse().map_err(|_| format!("'{s}' is not a number of stops"))?;
    if v.is_finite() && v.abs() <= 64.0 { Ok(v) } else { Err(format!("exposure must lie in [-64, 64] stops, got {s}")) }
}

/// `--threads N` where given (capped at 4 × the cores and at 1024, with a warning: more
/// threads than that only add start-up time, and a huge count ran for minutes with no
/// output), else every core.
pub fn thread_count(option: Option<u32>) -> usize {
    let threads = ember_host::driver::capped_threads(option);
    if let Some(n) = option.filter(|&n| n as usize > threads) {
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
        eprintln!("warning: --threads {n} capped at {threads} (4 × {cores} cores, at most 1024)");
    }
    threads
}

impl RenderArgs {
    /// Maximum passes: `--spp`, else unlimited under `--time`, else [`DEFAULT_SPP`] (the
    /// render command puts the scene file's `sample_count` before the last).
    pub fn spp_limit(&self) -> u32 {
        ember_host::setup::pass_limit(self.spp, self.time, None)
    }

    /// Render threads: `--threads`, else every core.
    pub fn thread_count(&self) -> usize {
        thread_count(self.threads)
    }

    /// Resolution: the options where given, `default` (the scene's film) otherwise; one
    /// side alone keeps `default`'s aspect ratio ([`ember_formats::mitsuba::film_size`], the rule
    /// scene files follow too).
    pub fn resolution_or(&self, default: (u32, u32)) -> (u32, u32) {
        ember_formats::mitsuba::film_size(default, self.width, self.height)
    }

    /// Mitsuba max_depth: the option where given, `default` (the scene's) otherwise.
    pub fn max_depth_or(&self, default: i32) -> i32 {
        self.max_depth.unwrap_or(default)
    }

    /// The EXR and PNG paths. The output must name an `.exr` file (or have no
    /// extension, which gets `.exr`).
    pub fn output_paths(&self) -> Result<(PathBuf, PathBuf), String> {
        output_paths(&self.output)
    }
}

/// See [`RenderArgs::output_paths`].
pub fn output_paths(output: &Path) -> Result<(PathBuf, PathBuf), String> {
    // A trailing slash means "into this directory", with the default name (`-o d1/d2/`
    // wrote d1/d2.exr beside the directory).
    let joined;
    let output = if output.as_os_str().to_string_lossy().ends_with('/') {
        joined = output.join("out.exr");
        joined.as_path()
    } else if output.is_dir() {
        return Err(format!("output '{}' is a directory: end it with '/' to write out.exr into it, or name a file", output.display()));
    } else {
        output
    };
    let exr = match output.extension().and_then(|e| e.to_str()) {
        None if output.file_name().is_some() => output.with_extension("exr"),
        Some(e) if e.eq_ignore_ascii_case("exr") => output.to_path_buf(),
        _ => {
            return Err(format!("output '{}' must be an .exr file (a tone-mapped .png is written beside it)", output.display()));
        }
    };
    let png = exr.with_extension("png");
    Ok((exr, png))
}

#[cfg(test)]
mod tests;
