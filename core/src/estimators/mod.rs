//! Every estimator of the pixel measurement, each in its own home: its strategies and
//! weights as functions over index ranges writing into caller storage, its phases (the
//! render protocol of [`crate::render`]) beside them. They stand on the shared
//! vocabulary of [`crate::transport`] and the libraries below it (`path`, `merge`,
//! `segment`, `subspace`).
//!
//! - [`pt`]: path tracing, BSDF sampling + next-event estimation, balance or power MIS.
//! - [`lt`]: light tracing (particle tracing splatted to the film).
//! - [`bdpt`]: bidirectional path tracing with every (s, t) strategy and recursive
//!   balance-heuristic weights.
//! - [`lvcbpt`], [`spcbpt`]: connections to cached light vertices.
//! - [`vcm`]: vertex merging: PPM, BPM and VCM/UPS.
//! - [`segment`]: segment PT, LT and BDPT.
//! - [`filter`]: path filtering by recursive marginal MIS: MVF, PhF and BPF.
//!
//! PT and LT are always compiled; the others each behind their cargo feature (`bdpt`,
//! `lvcbpt`, `spcbpt`, `merging`, `segments`, `filtering`; docs/features.md).

#[cfg(feature = "bdpt")]
pub mod bdpt;
#[cfg(feature = "filtering")]
pub mod filter;
pub mod lt;
mod lt_lanes;
#[cfg(feature = "lvcbpt")]
pub mod lvcbpt;
pub mod pt;
mod pt_lanes;
#[cfg(feature = "segments")]
pub mod segment;
#[cfg(feature = "spcbpt")]
pub mod spcbpt;
#[cfg(feature = "merging")]
pub mod vcm;

mod one_phase;
pub mod options;
mod payload;
mod registry;
mod renderer;

// Each family's configuration lives in its folder and is compiled in every build: a host
// names, and `Renderer::new` refuses by name, an estimator a build leaves out.
#[path = "filter/config.rs"]
mod filter_config;
#[path = "lvcbpt/config.rs"]
mod lvcbpt_config;
#[path = "segment/config.rs"]
mod segment_config;
#[path = "spcbpt/config.rs"]
mod spcbpt_config;
#[path = "vcm/config.rs"]
mod vcm_config;

pub use crate::transport::config::{ConfigError, MAX_DATASET, MAX_LIGHT_PATHS};
pub use filter_config::{DEFAULT_FILTER_SEGMENTS, FilterConfig, FilterReuse, FilterSide, MAX_FILTER_BETA, MAX_FILTER_SEGMENTS};
pub use lvcbpt_config::LvcbptConfig;
pub use registry::{EstimatorConfig, EstimatorKind, FILM_BYTES_PER_PIXEL, MemoryEstimate};
pub use renderer::{Renderer, RendererError};
pub use segment_config::{KernelChoice, SegmentAlgorithm, SegmentConfig};
pub use spcbpt_config::SpcbptConfig;
pub use vcm_config::{MergeMode, MergingConfig};

pub use payload::{Absent, ChunkOutput, PhaseBuffers, PhaseData, types as payload_types};
#[cfg(any(feature = "merging", feature = "segments", feature = "filtering"))]
pub(crate) use payload::{map_footprint, reduce_footprint};
