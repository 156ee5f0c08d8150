//! The estimators by name, and each one's configuration: a plain struct whose defaults
//! are documented here once (hosts only parse into it), whose scene-dependent defaults
//! (M, |D|, M', N_S) are resolved from the film size, and whose validation names the
//! field and its allowed range.

use core::fmt;

use crate::merge::RadiusRule;

/// The light-transport estimators, in the order hosts list them.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum EstimatorKind {
    /// Path tracing: camera paths with next-event estimation and MIS (Mitsuba's `path`).
    Pt,
    /// Light tracing: light paths connected to the camera (Mitsuba's `ptracer`).
    Lt,
    /// Bidirectional path tracing with multiple importance sampling (Veach 1997).
    Bdpt,
    /// Light-vertex-cache BDPT: M light paths per pass into a cache, N uniform
    /// connections per camera vertex (Davidovič et al. 2014).
    Lvcbpt,
    /// Subspace-based probabilistic connections (Su, Li, Wang 2022): Γ-guided
    /// connections to cached light vertices, Γ trained by Adam before rendering.
    Spcbpt,
    /// Progressive photon mapping: photons merged at the first non-Dirac camera vertex.
    Ppm,
    /// Bidirectional photon mapping: merges at every camera vertex, balance heuristic.
    Bpm,
    /// Vertex connection and merging (UPS): BDPT's connections and every merge under
    /// one balance heuristic (Georgiev et al. 2012).
    Vcm,
    /// Segment path tracing (Wang, West, Hachisuka 2025): the sequential segment sampler
    /// from the camera with a kernel between segments, light-sampled last segment by MIS.
    Spt,
    /// Segment light tracing: the sequential segment sampler from the lights with a kernel
    /// between segments, last segment to the pinhole.
    Slt,
    /// Segment BDPT: camera and light segment sequences joined by bridge segments, MIS
    /// over every technique.
    Sbdpt,
    /// Multi-vertex path filtering: recursive MMIS (eq. 18) over camera segment
    /// sequences, computed by propagation, progressive kernel.
    Mvf,
    /// Photon filtering: recursive MMIS over light segment sequences, then photon density
    /// estimation at the first non-Dirac camera vertex.
    Phf,
    /// Bidirectional path filtering: recursive MMIS over camera and light segment
    /// sequences together (Wang, West, Hachisuka 2025 §5).
    Bpf,
}

impl EstimatorKind {
    /// Every estimator, in listing order (its index is the browser's and the C ABI's id).
    pub const ALL: [EstimatorKind; 14] = [
        Self::Pt,
        Self::Lt,
        Self::Bdpt,
        Self::Lvcbpt,
        Self::Spcbpt,
        Self::Ppm,
        Self::Bpm,
        Self::Vcm,
        Self::Spt,
        Self::Slt,
        Self::Sbdpt,
        Self::Mvf,
        Self::Phf,
        Self::Bpf,
    ];

    /// The name as typed on a command line.
    pub fn name(self) -> &'static str {
        match self {
            Self::Pt => "pt",
            Self::Lt => "lt",
            Self::Bdpt => "bdpt",
            Self::Lvcbpt => "lvcbpt",
            Self::Spcbpt => "spcbpt",
            Self::Ppm => "ppm",
            Self::Bpm => "bpm",
            Self::Vcm => "vcm",
            Self::Spt => "spt",
            Self::Slt => "slt",
            Self::Sbdpt => "sbdpt",
            Self::Mvf => "mvf",
            Self::Phf => "phf",
            Self::Bpf => "bpf",
        }
    }

    /// One line for help texts.
    pub fn summary(self) -> &'static str {
        match self {
            Self::Pt => "path tracing with next-event estimation and MIS (Mitsuba's `path`)",
            Self::Lt => "light tracing: light paths connected to the camera (Mitsuba's `ptracer`)",
            Self::Bdpt => "bidirectional path tracing with every (s, t) strategy and balance-heuristic MIS",
            Self::Lvcbpt => "light-vertex-cache BDPT: N uniform connections to M cached light paths per pass",
            Self::Spcbpt => "subspace-based probabilistic connections: Γ-guided connections, Γ trained before rendering",
            Self::Ppm => "progressive photon mapping: photons merged at the first non-specular camera vertex, shrinking radius",
            Self::Bpm => "bidirectional photon mapping: merges at every camera vertex under the balance heuristic",
            Self::Vcm => "vertex connection and merging (UPS): BDPT's connections and photon merges under one balance heuristic",
            Self::Spt => {
                "segment path tracing: segments sampled in sequence from the camera, joined by a kernel (--kernel), light-sampled last segment by MIS; = pt with the Dirac kernel"
            }
            Self::Slt => {
                "segment light tracing: segments sampled in sequence from the lights, joined by a kernel (--kernel), last segment to the camera; = lt with the Dirac kernel"
            }
            Self::Sbdpt => {
                "segment BDPT: camera and light segment sequences joined by a kernel (--kernel), every pair of prefixes by a bridge segment, balance-heuristic MIS; = bdpt with the Dirac kernel"
            }
            Self::Mvf => {
                "multi-vertex path filtering: camera segments reused by every kernel they fall in, recursive marginal MIS computed by propagation, shrinking kernel (--alpha)"
            }
            Self::Phf => {
                "photon filtering: light segments reused by every kernel they fall in (recursive marginal MIS by propagation), then photon density estimation; shrinking kernel"
            }
            Self::Bpf => {
                "bidirectional path filtering: camera and light segments (--beta light paths per pixel) reused by every kernel they fall in, recursive marginal MIS by propagation; shrinking kernel"
            }
        }
    }

    /// The estimator called `name` ([`Self::name`]).
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|e| e.name() == name)
    }

    /// The estimator with index `i` in [`Self::ALL`].
    pub fn from_index(i: u32) -> Option<Self> {
        Self::ALL.get(i as usize).copied()
    }

    /// This estimator with its default configuration.
    pub fn default_config(self) -> EstimatorConfig {
        match self {
            Self::Pt => EstimatorConfig::Pt,
            Self::Lt => EstimatorConfig::Lt,
            Self::Bdpt => EstimatorConfig::Bdpt,
            Self::Lvcbpt => EstimatorConfig::Lvcbpt(LvcbptConfig::DEFAULT),
            Self::Spcbpt => EstimatorConfig::Spcbpt(SpcbptConfig::DEFAULT),
            Self::Ppm => EstimatorConfig::Merging(MergeMode::Ppm, MergingConfig::DEFAULT),
            Self::Bpm => EstimatorConfig::Merging(MergeMode::Bpm, MergingConfig::DEFAULT),
            Self::Vcm => EstimatorConfig::Merging(MergeMode::Vcm, MergingConfig::DEFAULT),
            Self::Spt => EstimatorConfig::Segment(SegmentAlgorithm::PathTracing, SegmentConfig::DEFAULT),
            Self::Slt => EstimatorConfig::Segment(SegmentAlgorithm::LightTracing, SegmentConfig::DEFAULT),
            Self::Sbdpt => EstimatorConfig::Segment(SegmentAlgorithm::Bidirectional, SegmentConfig::DEFAULT),
            Self::Mvf => EstimatorConfig::Filter(FilterSide::Camera, FilterConfig::DEFAULT),
            Self::Phf => EstimatorConfig::Filter(FilterSide::Light, FilterConfig::DEFAULT),
            Self::Bpf => EstimatorConfig::Filter(FilterSide::Both, FilterConfig::DEFAULT),
        }
    }
}

impl EstimatorKind {
    /// The cargo feature of `ember-core` that compiles this estimator, or `None` for PT
    /// and LT, which every build holds (docs/features.md). The list itself, its order and
    /// its indices are the same in every build.
    pub fn cargo_feature(self) -> Option<&'static str> {
        match self {
            Self::Pt | Self::Lt => None,
            Self::Bdpt => Some("bdpt"),
            Self::Lvcbpt => Some("lvcbpt"),
            Self::Spcbpt => Some("spcbpt"),
            Self::Ppm | Self::Bpm | Self::Vcm => Some("merging"),
            Self::Spt | Self::Slt | Self::Sbdpt => Some("segments"),
            Self::Mvf | Self::Phf | Self::Bpf => Some("filtering"),
        }
    }

    /// Is this estimator's code in this build? [`super::Renderer::new`] refuses one that is
    /// not ([`super::RendererError::NotCompiled`]).
    pub fn is_compiled(self) -> bool {
        match self {
            Self::Pt | Self::Lt => true,
            Self::Bdpt => cfg!(feature = "bdpt"),
            Self::Lvcbpt => cfg!(feature = "lvcbpt"),
            Self::Spcbpt => cfg!(feature = "spcbpt"),
            Self::Ppm | Self::Bpm | Self::Vcm => cfg!(feature = "merging"),
            Self::Spt | Self::Slt | Self::Sbdpt => cfg!(feature = "segments"),
            Self::Mvf | Self::Phf | Self::Bpf => cfg!(feature = "filtering"),
        }
    }
}

impl fmt::Display for EstimatorKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Which vertex-merging estimator ([`EstimatorConfig::Merging`]; also
/// `estimators::vcm::MergeMode`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MergeMode {
    /// Progressive photon mapping: merge at the first non-Dirac camera vertex, no MIS.
    Ppm,
    /// Bidirectional photon mapping: merge at every camera vertex, balance heuristic.
    Bpm,
    /// Vertex connection and merging.
    Vcm,
}

/// An estimator and its settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum EstimatorConfig {
    /// Path tracing (its MIS heuristic is [`crate::transport::RenderParams::heuristic`]).
    Pt,
    /// Light tracing: W·H light paths per pass.
    Lt,
    /// BDPT: one light path per pixel sample.
    Bdpt,
    /// Not an image but a probe: BDPT's samples, each strategy's contribution replaced by
    /// its term of PT's second moment, so that a pixel's mean over passes estimates the
    /// second moment of one PT sample there, rare bright samples included
    /// ([`crate::estimators::bdpt::probe`]; `--estimator auto`'s race). Its kind is BDPT.
    PtMoment,
    /// LVCBPT.
    Lvcbpt(LvcbptConfig),
    /// SPCBPT.
    Spcbpt(SpcbptConfig),
    /// PPM, BPM or VCM.
    Merging(MergeMode, MergingConfig),
    /// Segment PT, LT or BDPT.
    Segment(SegmentAlgorithm, SegmentConfig),
    /// Multi-vertex path filtering (camera side) or photon filtering (light side).
    Filter(FilterSide, FilterConfig),
}

impl EstimatorConfig {
    /// Which estimator this configures.
    pub fn kind(&self) -> EstimatorKind {
        match self {
            Self::Pt => EstimatorKind::Pt,
            Self::Lt => EstimatorKind::Lt,
            Self::Bdpt | Self::PtMoment => EstimatorKind::Bdpt,
            Self::Lvcbpt(_) => EstimatorKind::Lvcbpt,
            Self::Spcbpt(_) => EstimatorKind::Spcbpt,
            Self::Merging(MergeMode::Ppm, _) => EstimatorKind::Ppm,
            Self::Merging(MergeMode::Bpm, _) => EstimatorKind::Bpm,
            Self::Merging(MergeMode::Vcm, _) => EstimatorKind::Vcm,
            Self::Segment(SegmentAlgorithm::PathTracing, _) => EstimatorKind::Spt,
            Self::Segment(SegmentAlgorithm::LightTracing, _) => EstimatorKind::Slt,
            Self::Segment(SegmentAlgorithm::Bidirectional, _) => EstimatorKind::Sbdpt,
            Self::Filter(FilterSide::Camera, _) => EstimatorKind::Mvf,
            Self::Filter(FilterSide::Light, _) => EstimatorKind::Phf,
            Self::Filter(FilterSide::Both, _) => EstimatorKind::Bpf,
        }
    }

    /// Check every field against its range.
    pub fn validate(&self) -> Result<(), ConfigError> {
        match self {
            Self::Pt | Self::Lt | Self::Bdpt | Self::PtMoment => Ok(()),
            Self::Lvcbpt(c) => c.validate(),
            Self::Spcbpt(c) => c.validate(),
            Self::Merging(_, c) => c.validate(),
            Self::Segment(_, c) => c.validate(),
            Self::Filter(_, c) => c.validate(),
        }
    }
}

/// What an estimator is expected to hold for one film, estimated before anything is
/// allocated, so a host can refuse a render that cannot fit instead of aborting in the
/// middle of it (the estimate, not a bound: light-path lengths are only known after
/// tracing; 8 vertices per path are assumed, the suite's scenes average 3–25).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MemoryEstimate {
    /// Estimated bytes: the film plus the estimator's per-pass stores and setup data.
    pub bytes: u64,
    /// The largest part, in words.
    pub largest: &'static str,
    /// What to lower to shrink it, as the command line spells it.
    pub lower: &'static str,
}

/// Bytes per pixel of the film: the exact u128 sums and the staged f32 camera sample.
pub const FILM_BYTES_PER_PIXEL: u64 = 48 + 12;
/// Assumed vertices per light path for the estimate.
#[cfg(any(feature = "lvcbpt", feature = "spcbpt", feature = "filtering", feature = "merging"))]
const VERTICES_PER_PATH: u64 = 8;
/// Assumed kernel neighbours per node of path filtering for the estimate.
#[cfg(feature = "filtering")]
const FILTER_NEIGHBOURS: u64 = 64;

impl EstimatorConfig {
    /// The [`MemoryEstimate`] for a film of `pixels` pixels. An estimator this build
    /// leaves out ([`EstimatorKind::is_compiled`]) is estimated at its film alone: the
    /// sizes of its structures are not known here, and it cannot be constructed.
    pub fn memory_estimate(&self, pixels: u32) -> MemoryEstimate {
        let film = pixels as u64 * FILM_BYTES_PER_PIXEL;
        #[cfg(any(feature = "lvcbpt", feature = "spcbpt", feature = "merging"))]
        let vertex = core::mem::size_of::<crate::path::Vertex>() as u64;
        let (part, largest, lower) = match self {
            Self::Pt | Self::Lt | Self::Bdpt | Self::PtMoment | Self::Segment(..) => (0, "the film", "--width/--height"),
            #[cfg(feature = "lvcbpt")]
            Self::Lvcbpt(c) => (c.light_paths_for(pixels) as u64 * VERTICES_PER_PATH * (vertex + 8), "the light paths of a pass", "--light-paths"),
            #[cfg(feature = "spcbpt")]
            Self::Spcbpt(c) => {
                let paths = c.light_paths_for(pixels) as u64 * VERTICES_PER_PATH * (vertex + 32);
                // D's records (weight, fixed part, split start: 20 B; a 16 B split per
                // connectible vertex) for every sample, and the light-side features of
                // the first 200 000 samples (one 40 B feature per prefix) before the fit
                // keeps 200 000: a bound; ajar at 10⁶ samples holds 40 MiB of D.
                let samples = c.dataset_for(pixels) as u64;
                let dataset = samples * (20 + 16 * VERTICES_PER_PATH) + samples.min(200_000) * VERTICES_PER_PATH * 40;
                let n = c.subspaces_for(pixels) as u64;
                let gamma = n * n * 4 * 2;
                // Named after the largest of the three (Γ of 4096² subspaces is 134 MB, more
                // than the dataset at low resolutions, and was blamed on it).
                let (largest, lower) = if gamma >= dataset && gamma >= paths {
                    ("Γ (subspaces² × 8 bytes)", "--subspaces")
                } else if dataset >= paths {
                    ("the training dataset", "--dataset")
                } else {
                    ("the light paths of a pass", "--light-paths")
                };
                (paths + dataset + gamma, largest, lower)
            }
            #[cfg(feature = "filtering")]
            Self::Filter(side, c) => {
                // Per node: itself, its denominators, two radiance vectors and its row,
                // assuming 64 kernel neighbours, the neighbour budget (a pair is a u32 and three f32).
                let node = core::mem::size_of::<crate::estimators::filter::Node>() as u64 + 16 + 24 + FILTER_NEIGHBOURS * 16;
                // The paths whose nodes a pass holds: MVF's camera paths, PhF's light paths
                // (one per pixel), BPF's camera paths and round(β · pixels) light paths (at
                // 128×96 a BPF pass held 98, 190, 467 and 1562 MB at β = 0, 1, 4, 16).
                let paths = match side {
                    FilterSide::Camera | FilterSide::Light => pixels as u64,
                    FilterSide::Both => pixels as u64 + c.light_paths(pixels) as u64,
                };
                let lower = match side {
                    FilterSide::Both if c.beta > 0.0 => "--beta, --radius-footprints or --max-segments",
                    _ => "--radius-footprints or --max-segments",
                };
                (paths * VERTICES_PER_PATH * node, "the filtering rows of a pass", lower)
            }
            #[cfg(feature = "merging")]
            Self::Merging(mode, c) => {
                // Photons, their grid and records exist only where merging does.
                let photon = if c.merges(*mode) { core::mem::size_of::<crate::estimators::vcm::Photon>() as u64 + 4 * 3 + 12 + 8 } else { 0 };
                (c.light_paths_for(pixels) as u64 * VERTICES_PER_PATH * (vertex + 8 + photon), "the light paths and photons of a pass", "--light-paths")
            }
            #[cfg(not(all(feature = "lvcbpt", feature = "spcbpt", feature = "filtering", feature = "merging")))]
            _ => (0, "the film", "--width/--height"),
        };
        let (largest, lower) = if part >= film { (largest, lower) } else { ("the film", "--width/--height") };
        MemoryEstimate { bytes: film + part, largest, lower }
    }
}

/// A configuration value outside its allowed range.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ConfigError {
    /// The field, as the command line spells its option (without dashes).
    pub field: &'static str,
    /// The value given.
    pub value: f64,
    /// The allowed range, in words.
    pub allowed: &'static str,
}

impl fmt::Display for ConfigError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} = {} is outside its allowed range {}", self.field, self.value, self.allowed)
    }
}

impl core::error::Error for ConfigError {}

fn check_u32(field: &'static str, value: u32, range: core::ops::RangeInclusive<u32>, allowed: &'static str) -> Result<(), ConfigError> {
    if range.contains(&value) { Ok(()) } else { Err(ConfigError { field, value: value as f64, allowed }) }
}

fn check_f32(field: &'static str, value: f32, ok: bool, allowed: &'static str) -> Result<(), ConfigError> {
    if value.is_finite() && ok { Ok(()) } else { Err(ConfigError { field, value: value as f64, allowed }) }
}

/// Largest M: a pass's light paths are held in memory (about 1 KiB per path).
pub const MAX_LIGHT_PATHS: u32 = 4_000_000;
/// Largest |D| and M'.
pub const MAX_DATASET: u32 = 20_000_000;

/// M for a film of `pixels` pixels: `light_paths` where given, else min(100 000, W·H)
/// (at most one light path per pixel sample, as in BDPT).
fn light_paths_for(light_paths: Option<u32>, pixels: u32) -> u32 {
    light_paths.unwrap_or(pixels.clamp(1, 100_000))
}

/// LVCBPT's settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LvcbptConfig {
    /// Light paths per pass, M [default: min(100 000, W·H)].
    pub light_paths: Option<u32>,
    /// Connections per camera vertex, N (default 3).
    pub connections: u32,
    /// Light paths measuring c̄, the mean cacheable vertices per path (default 16 384).
    pub probe_paths: u32,
}

impl LvcbptConfig {
    /// The defaults.
    pub const DEFAULT: Self = Self { light_paths: None, connections: 3, probe_paths: 16_384 };

    /// M for a film of `pixels` pixels.
    pub fn light_paths_for(&self, pixels: u32) -> u32 {
        light_paths_for(self.light_paths, pixels)
    }

    /// Check every field against its range.
    pub fn validate(&self) -> Result<(), ConfigError> {
        if let Some(m) = self.light_paths {
            check_u32("light-paths", m, 1..=MAX_LIGHT_PATHS, "1..=4000000")?;
        }
        check_u32("connections", self.connections, 1..=1000, "1..=1000")?;
        check_u32("probe-paths", self.probe_paths, 1..=MAX_DATASET, "1..=20000000")
    }
}

impl Default for LvcbptConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// The vertex-merging estimators' settings (PPM, BPM, VCM).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MergingConfig {
    /// Light paths per pass, N_L [default: W·H, at most 4 000 000].
    pub light_paths: Option<u32>,
    /// How the initial radius r₀ is chosen (default: 4 pixel footprints, the segment
    /// paper's heuristic).
    pub radius: RadiusRule,
    /// Radius reduction α ∈ (0, 1]: r_i = r₀ (i + 1)^((α − 1)/2) (default 0.67, as in
    /// the segment paper; 1 keeps the radius fixed).
    pub alpha: f32,
    /// VCM: merge (off: BDPT's techniques only, for checks).
    pub merging: bool,
    /// VCM: connect (off: BPM's techniques only, for checks).
    pub connections: bool,
}

impl MergingConfig {
    /// The defaults.
    pub const DEFAULT: Self = Self { light_paths: None, radius: RadiusRule::DEFAULT, alpha: 0.67, merging: true, connections: true };

    /// N_L for a film of `pixels` pixels.
    pub fn light_paths_for(&self, pixels: u32) -> u32 {
        self.light_paths.unwrap_or(pixels.clamp(1, MAX_LIGHT_PATHS))
    }

    /// Does estimator `mode` merge with these settings? PPM and BPM always do; VCM unless
    /// `merging` is off (then no photon, grid or merge count exists).
    pub fn merges(&self, mode: MergeMode) -> bool {
        mode != MergeMode::Vcm || self.merging
    }

    /// Check every field against its range.
    pub fn validate(&self) -> Result<(), ConfigError> {
        if let Some(m) = self.light_paths {
            check_u32("light-paths", m, 1..=MAX_LIGHT_PATHS, "1..=4000000")?;
        }
        check_radius(self.radius)?;
        check_f32("alpha", self.alpha, self.alpha > 0.0 && self.alpha <= 1.0, "(0, 1]")
    }
}

impl Default for MergingConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// Which sequential segment estimator.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SegmentAlgorithm {
    /// Segments from the camera ([`crate::estimators::estimators::spt`]).
    PathTracing,
    /// Segments from the lights ([`crate::estimators::estimators::slt`]).
    LightTracing,
    /// Segments from both, joined by bridges ([`crate::estimators::estimators::sbdpt`]).
    Bidirectional,
}

/// The kernel joining consecutive segments, as chosen on the command line (its radius
/// is resolved per scene from [`SegmentConfig::radius`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum KernelChoice {
    /// x_{i+1} = y_i: the vertex formulation (the default).
    Dirac,
    /// Uniform over the surface within a disk around y_i.
    Disk,
}

/// The segment estimators' settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SegmentConfig {
    /// The kernel (default: Dirac).
    pub kernel: KernelChoice,
    /// The disk kernel's radius (default: 4 pixel footprints, the rule vertex merging
    /// uses for r₀; the radius stays fixed over passes).
    pub radius: RadiusRule,
}

impl SegmentConfig {
    /// The defaults.
    pub const DEFAULT: Self = Self { kernel: KernelChoice::Dirac, radius: RadiusRule::DEFAULT };

    /// Check every field against its range.
    pub fn validate(&self) -> Result<(), ConfigError> {
        check_radius(self.radius)
    }
}

impl Default for SegmentConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// A radius rule's value must be positive and finite; the error names the option.
fn check_radius(rule: RadiusRule) -> Result<(), ConfigError> {
    let r = rule.value();
    let field = match rule {
        RadiusRule::Footprints(_) => "radius-footprints",
        RadiusRule::SceneFraction(_) => "radius-scene",
        RadiusRule::Absolute(_) => "radius",
    };
    check_f32(field, r, r > 0.0 && r <= 1e30, "(0, 1e30]")
}

/// SPCBPT's settings, with the paper's defaults. Scaling rule for small images: the
/// paper renders about 1280×720 with M = 100 000 light paths per pass, |D| = 1 000 000
/// dataset paths and N_S = 1000; here M defaults to min(100 000, W·H), |D| to
/// min(1 000 000, 16·W·H), M' to min(2 000 000, 2·W·H) and N_S to min(1000, ⌊√(W·H)⌋)
/// (at least 16), so Γ's N_S² entries number about the pixels and D holds at least 16
/// paths per entry (measured on ajar, enclosed and a door-like scene at 320×240 and
/// 320×168, 3 seeds: |D| = 10⁶ instead of W·H needs 1.17-1.41x fewer passes to the same
/// relMSE, docs/spcbpt.md; N_S = 1000 instead of ⌊√(W·H)⌋ made passes slower). The
/// paper's training takes 10⁶ / 10⁴ × 2 = 200 Adam steps; a smaller D keeps that budget
/// with smaller batches ([`SpcbptConfig::batch_for`]), since a fixed batch of 10 000 left
/// Γ near uniform (8 steps on ajar at 320×240, docs/spcbpt.md).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpcbptConfig {
    /// Light paths per pass, M [default: min(100 000, W·H)].
    pub light_paths: Option<u32>,
    /// Connections per camera vertex, N (default 3).
    pub connections: u32,
    /// Training paths, |D| [default: min(1 000 000, 16·W·H)].
    pub dataset: Option<u32>,
    /// Subspaces per side, N_S, on the light side shared with the light-source bins
    /// [default: min(1000, ⌊√(W·H)⌋), at least 16].
    pub subspaces: Option<u32>,
    /// Adam learning rate α (the paper's 0.1: measured 4-40× less excess loss than the
    /// public code's 0.01-0.02 within the paper's step budget, docs/spcbpt-training.md).
    pub learning_rate: f32,
    /// Adam mini-batch size at most (default 10 000, the paper's).
    pub batch: u32,
    /// Adam steps at least (default 200, the paper's |D| / batch × epochs): a smaller
    /// dataset is cut into smaller batches; 0 keeps `batch` whatever the dataset's size.
    pub steps: u32,
    /// Training epochs (default 2).
    pub epochs: u32,
    /// Weight of the uniform distribution mixed into Γ (default 0.1).
    pub mixture: f32,
    /// Light vertices retained per subspace across passes, M0 (default 200; 0: none).
    pub reuse: u32,
    /// Weight of the normal/direction terms in the classification distance, k_d (0.05).
    pub k_d: f32,
    /// Share of the N_S light subspaces given to positions on the lights (the paper's
    /// ~20 %); their vertices are cached and Γ-sampled instead of next-event estimation.
    /// 0, or a scene with a point, spot or infinite light, keeps NEE.
    pub light_source_share: f32,
    /// Light paths estimating Q per light subspace, M' [default: min(2 000 000, 2·W·H)].
    pub q_paths: Option<u32>,
}

impl SpcbptConfig {
    /// The defaults.
    pub const DEFAULT: Self = Self {
        light_paths: None,
        connections: 3,
        dataset: None,
        subspaces: None,
        learning_rate: 0.1,
        batch: 10_000,
        steps: 200,
        epochs: 2,
        mixture: 0.1,
        reuse: 200,
        k_d: 0.05,
        light_source_share: 0.2,
        q_paths: None,
    };

    /// M for a film of `pixels` pixels.
    pub fn light_paths_for(&self, pixels: u32) -> u32 {
        light_paths_for(self.light_paths, pixels)
    }
    /// |D| for a film of `pixels` pixels.
    pub fn dataset_for(&self, pixels: u32) -> u32 {
        self.dataset.unwrap_or(pixels.saturating_mul(16).clamp(1, 1_000_000))
    }
    /// N_S for a film of `pixels` pixels.
    pub fn subspaces_for(&self, pixels: u32) -> u32 {
        self.subspaces.unwrap_or_else(|| (crate::math::sqrt_f64(pixels as f64) as u32).clamp(16, 1000))
    }
    /// The Adam batch for a training set of `paths` paths: `batch`, or smaller so that
    /// `epochs` passes over the set take at least `steps` steps (never below 1).
    #[cfg(feature = "subspace")]
    pub fn batch_for(&self, paths: usize) -> usize {
        crate::subspace::batch_for_steps(paths, self.batch as usize, self.epochs, self.steps)
    }
    /// M' for a film of `pixels` pixels.
    pub fn q_paths_for(&self, pixels: u32) -> u32 {
        self.q_paths.unwrap_or(pixels.saturating_mul(2).clamp(1, 2_000_000))
    }

    /// Check every field against its range.
    pub fn validate(&self) -> Result<(), ConfigError> {
        if let Some(m) = self.light_paths {
            check_u32("light-paths", m, 1..=MAX_LIGHT_PATHS, "1..=4000000")?;
        }
        check_u32("connections", self.connections, 1..=1000, "1..=1000")?;
        if let Some(d) = self.dataset {
            check_u32("dataset", d, 1..=MAX_DATASET, "1..=20000000")?;
        }
        if let Some(n) = self.subspaces {
            check_u32("subspaces", n, 2..=4096, "2..=4096")?;
        }
        if let Some(q) = self.q_paths {
            check_u32("q-paths", q, 1..=MAX_DATASET, "1..=20000000")?;
        }
        check_f32("learning-rate", self.learning_rate, self.learning_rate > 0.0 && self.learning_rate <= 10.0, "(0, 10]")?;
        check_u32("batch", self.batch, 1..=10_000_000, "1..=10000000")?;
        check_u32("steps", self.steps, 0..=1_000_000, "0..=1000000")?;
        check_u32("epochs", self.epochs, 0..=1000, "0..=1000")?;
        check_f32("mixture", self.mixture, (0.0..=1.0).contains(&self.mixture), "[0, 1]")?;
        check_u32("reuse", self.reuse, 0..=100_000, "0..=100000")?;
        check_f32("k-d", self.k_d, (0.0..=1000.0).contains(&self.k_d), "[0, 1000]")?;
        check_f32("light-source-share", self.light_source_share, (0.0..1.0).contains(&self.light_source_share), "[0, 1)")
    }
}

impl Default for SpcbptConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_indices_are_stable() {
        for (i, e) in EstimatorKind::ALL.into_iter().enumerate() {
            assert_eq!(EstimatorKind::from_name(e.name()), Some(e));
            assert_eq!(EstimatorKind::from_index(i as u32), Some(e));
            assert_eq!(e.default_config().kind(), e);
        }
        assert_eq!(EstimatorKind::from_name("PT"), None);
        // The browser page passes these indices.
        assert_eq!(EstimatorKind::from_index(2), Some(EstimatorKind::Bdpt));
    }

    /// The default build holds every estimator: a feature left out of `default` (or a
    /// family added without a feature arm) fails here.
    #[cfg(all(feature = "bdpt", feature = "lvcbpt", feature = "spcbpt", feature = "merging", feature = "segments", feature = "filtering"))]
    #[test]
    fn every_estimator_is_compiled_with_every_family() {
        for e in EstimatorKind::ALL {
            assert!(e.is_compiled(), "{e}");
        }
        let families: alloc::collections::BTreeSet<_> = EstimatorKind::ALL.into_iter().filter_map(EstimatorKind::cargo_feature).collect();
        assert_eq!(families.into_iter().collect::<alloc::vec::Vec<_>>(), ["bdpt", "filtering", "lvcbpt", "merging", "segments", "spcbpt"]);
    }

    #[test]
    fn invalid_values_name_their_field() {
        assert!(SpcbptConfig::DEFAULT.validate().is_ok());
        assert!(LvcbptConfig::DEFAULT.validate().is_ok());
        let cases: [(SpcbptConfig, &str); 6] = [
            (SpcbptConfig { mixture: f32::NAN, ..SpcbptConfig::DEFAULT }, "mixture"),
            (SpcbptConfig { mixture: 1.5, ..SpcbptConfig::DEFAULT }, "mixture"),
            (SpcbptConfig { learning_rate: 0.0, ..SpcbptConfig::DEFAULT }, "learning-rate"),
            (SpcbptConfig { light_source_share: 1.0, ..SpcbptConfig::DEFAULT }, "light-source-share"),
            (SpcbptConfig { subspaces: Some(1_000_000), ..SpcbptConfig::DEFAULT }, "subspaces"),
            (SpcbptConfig { k_d: f32::INFINITY, ..SpcbptConfig::DEFAULT }, "k-d"),
        ];
        for (c, field) in cases {
            assert_eq!(c.validate().map_err(|e| e.field), Err(field));
        }
        let e = LvcbptConfig { connections: 0, ..LvcbptConfig::DEFAULT }.validate().unwrap_err();
        assert_eq!(e.field, "connections");
        let m = MergingConfig::DEFAULT;
        assert!(m.validate().is_ok());
        for (c, field) in [
            (MergingConfig { alpha: 0.0, ..m }, "alpha"),
            (MergingConfig { alpha: f32::NAN, ..m }, "alpha"),
            (MergingConfig { radius: RadiusRule::Absolute(-1.0), ..m }, "radius"),
            (MergingConfig { radius: RadiusRule::Footprints(f32::INFINITY), ..m }, "radius-footprints"),
            (MergingConfig { radius: RadiusRule::SceneFraction(0.0), ..m }, "radius-scene"),
        ] {
            assert_eq!(c.validate().map_err(|e| e.field), Err(field));
        }
        let f = FilterConfig::DEFAULT;
        assert!(f.validate().is_ok() && FilterConfig { glossy_alpha: 0.0, ..f }.validate().is_ok());
        for (c, field) in [
            (FilterConfig { glossy_alpha: -0.1, ..f }, "glossy-alpha"),
            (FilterConfig { glossy_alpha: 1.5, ..f }, "glossy-alpha"),
            (FilterConfig { glossy_alpha: f32::NAN, ..f }, "glossy-alpha"),
            (FilterConfig { beta: 17.0, ..f }, "beta"),
        ] {
            assert_eq!(c.validate().map_err(|e| e.field), Err(field));
        }
    }

    #[test]
    fn memory_estimates_grow_with_what_they_name() {
        #[cfg(feature = "merging")]
        {
            let small = EstimatorKind::Vcm.default_config().memory_estimate(64 * 64);
            let large = EstimatorKind::Vcm.default_config().memory_estimate(4096 * 4096);
            assert!(large.bytes > 1000 * small.bytes && large.lower == "--light-paths");
        }
        // BPF's light paths scale with β; Γ is named where it dominates. Injected bugs
        // checked: estimating BPF from the pixels alone (as before issue 51) fails the first
        // assertion; naming the dataset whenever it outweighs the light paths fails the
        // second.
        #[cfg(feature = "filtering")]
        {
            let bpf = |beta: f32| EstimatorConfig::Filter(FilterSide::Both, FilterConfig { beta, ..FilterConfig::DEFAULT }).memory_estimate(128 * 96);
            assert!(bpf(16.0).bytes > 16 * bpf(0.0).bytes && bpf(16.0).lower.contains("--beta"), "{:?} {:?}", bpf(16.0), bpf(0.0));
        }
        #[cfg(feature = "spcbpt")]
        {
            let c = SpcbptConfig { subspaces: Some(4096), ..SpcbptConfig::DEFAULT };
            let e = EstimatorConfig::Spcbpt(c).memory_estimate(64 * 48);
            assert!(e.bytes > 4096 * 4096 * 8 && e.lower == "--subspaces", "{e:?}");
        }
        let film = EstimatorKind::Pt.default_config().memory_estimate(u32::MAX);
        assert_eq!((film.bytes, film.lower), (u32::MAX as u64 * FILM_BYTES_PER_PIXEL, "--width/--height"));
    }

    #[test]
    fn scene_defaults_follow_the_film() {
        let c = SpcbptConfig::DEFAULT;
        assert_eq!(c.light_paths_for(64 * 48), 64 * 48);
        assert_eq!(c.light_paths_for(1280 * 720), 100_000);
        assert_eq!(c.dataset_for(1280 * 720), 1_000_000);
        assert_eq!(c.dataset_for(160 * 120), 307_200);
        assert_eq!(c.subspaces_for(1280 * 720), 960);
        assert_eq!(c.subspaces_for(2000 * 1000), 1000);
        assert_eq!(c.subspaces_for(100), 16);
        assert_eq!(c.q_paths_for(1280 * 720), 1_843_200);
    }
}

/// Which sub-paths path filtering filters.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FilterSide {
    /// Camera paths: multi-vertex path filtering ([`crate::estimators::filter::Mvf`]).
    Camera,
    /// Light paths: photon filtering ([`crate::estimators::filter::Phf`]).
    Light,
    /// Both: bidirectional path filtering ([`crate::estimators::filter::Bpf`]).
    Both,
}

/// Path filtering's settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FilterConfig {
    /// How the initial kernel radius r₀ is chosen (default: 4 pixel footprints, the
    /// segment paper's heuristic).
    pub radius: RadiusRule,
    /// Kernel reduction α ∈ (0, 1]: r_i = r₀ (i + 1)^((α − 1)/2) (default 0.67).
    pub alpha: f32,
    /// Segments per path at most [default: the scene's max_depth; 16 where it is
    /// unbounded]. Each costs one propagation sweep.
    pub max_segments: Option<u32>,
    /// Bidirectional filtering: light paths per camera path, β ∈ [0, 16] (default 0.25,
    /// the segment paper's; it used 1 on its caustic scene). 0 traces none: MVF's
    /// segments with BPF's weights.
    pub beta: f32,
    /// Bidirectional filtering: which segment paths a junction forms (default: every).
    pub reuse: FilterReuse,
    /// Nodes on a material of microfacet roughness α below this get a kernel α / this
    /// times the pass's (`estimators::filter::nodes::scale_kernels`); 0 gives every node
    /// the pass's kernel. In [0, 1] (default 0.05).
    pub glossy_alpha: f32,
}

/// Which segments bidirectional filtering's junctions reuse.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FilterReuse {
    /// Every segment whose start lies in the junction's kernel: the paper's estimator.
    Every,
    /// Bidirectional photon mapping's segment paths only: a camera junction reuses its
    /// own continuation and light sample and the light segments in its kernel (a merge),
    /// a light junction its own path. The reduction to BPM (recursive MMIS over BPM's
    /// techniques), for testing and for measuring what the filtering adds.
    Merges,
    /// Every segment in a kernel, and bridge segments: each camera node joins a light
    /// node of the pass by a shadow ray, the bridge reused like a light segment (the
    /// segment paper's §6.4 and Fig. 7).
    Bridges,
}

/// Largest β.
pub const MAX_FILTER_BETA: f32 = 16.0;

/// Segments per path where neither max_depth nor `--max-segments` bounds them.
pub const DEFAULT_FILTER_SEGMENTS: u32 = 16;
/// Largest `--max-segments` (one propagation phase each).
pub const MAX_FILTER_SEGMENTS: u32 = 64;

impl FilterConfig {
    /// The defaults.
    pub const DEFAULT: Self = Self { radius: RadiusRule::DEFAULT, alpha: 0.67, max_segments: None, beta: 0.25, reuse: FilterReuse::Every, glossy_alpha: 0.05 };

    /// Light paths per pass for a film of `pixels` pixels: round(β · pixels), at least one
    /// where β > 0.
    pub fn light_paths(&self, pixels: u32) -> u32 {
        if !(self.beta > 0.0) {
            return 0;
        }
        (libm::round(self.beta as f64 * pixels as f64) as u32).max(1)
    }

    /// Are bridge segments traced?
    pub fn bridges(&self) -> bool {
        self.reuse == FilterReuse::Bridges && self.beta > 0.0
    }

    /// Segments per path under `max_depth`.
    pub fn segments(&self, max_depth: crate::transport::MaxDepth) -> u32 {
        let cap = self.max_segments.unwrap_or(if max_depth.0 < 0 { DEFAULT_FILTER_SEGMENTS } else { MAX_FILTER_SEGMENTS });
        max_depth.capped(cap.min(MAX_FILTER_SEGMENTS))
    }

    /// Check every field against its range.
    pub fn validate(&self) -> Result<(), ConfigError> {
        check_radius(self.radius)?;
        check_f32("alpha", self.alpha, self.alpha > 0.0 && self.alpha <= 1.0, "(0, 1]")?;
        check_f32("beta", self.beta, self.beta >= 0.0 && self.beta <= MAX_FILTER_BETA, "0 to 16")?;
        check_f32("glossy-alpha", self.glossy_alpha, (0.0..=1.0).contains(&self.glossy_alpha), "0 to 1")?;
        match self.max_segments {
            Some(n) if !(1..=MAX_FILTER_SEGMENTS).contains(&n) => Err(ConfigError { field: "max-segments", value: n as f64, allowed: "1 to 64" }),
            _ => Ok(()),
        }
    }
}

impl Default for FilterConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}
