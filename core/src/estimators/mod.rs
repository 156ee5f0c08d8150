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
#[cfg(feature = "lvcbpt")]
pub mod lvcbpt;
pub mod pt;
#[cfg(feature = "segments")]
pub mod segment;
#[cfg(feature = "spcbpt")]
pub mod spcbpt;
#[cfg(feature = "merging")]
pub mod vcm;

mod payload;

pub use payload::{Absent, ChunkOutput, PhaseBuffers, PhaseData, types as payload_types};
#[cfg(any(feature = "merging", feature = "segments", feature = "filtering"))]
pub(crate) use payload::{map_footprint, reduce_footprint};
