//! `ember-core`: the `no_std` heart of the ember light-transport library.
//!
//! Densities (warps, materials, lights, camera), random streams, the ray-query trait an
//! engine implements, and the estimators built on them. No threads, files, clocks or
//! printing live here; allocation happens only at setup, in caller-visible places.
//!
//! Glossary: `wo` is the direction toward where the path came from, `wi` the sampled or
//! connected direction (both point away from the surface); `beta` is a path throughput;
//! `pdf_fwd`/`pdf_rev` are the densities of sampling a vertex in the path's own
//! direction and in the opposite one.
#![no_std]
// Documentation is enforced where hosts and engines program against the core: the render
// protocol (`render`, `#![warn(missing_docs)]` there, denied by the test command's
// clippy). Elsewhere public fields and small math helpers document themselves by name.
//
// Cargo features (docs/features.md) leave estimator families and the structures only they
// use out of a build; the default compiles everything. PT and LT are always here.

extern crate alloc;

pub mod alias;
pub mod bsdf;
pub mod camera;
pub mod estimators;
pub mod fnv;
pub mod geometry;
pub mod light;
pub mod math;
pub mod measure;
pub mod merge;
#[cfg(feature = "mmis")]
pub mod mmis;
#[cfg(feature = "path")]
pub mod path;
pub mod pixel_filter;
pub mod plan;
pub mod render;
pub mod rng;
pub mod scene;
pub mod segment;
pub mod shapes;
pub mod spectrum;
#[cfg(feature = "subspace")]
pub mod subspace;
pub mod texture;
pub mod transport;
pub mod warp;

pub use math::{Vec2, Vec3};
pub use measure::{AreaPdf, SolidAnglePdf};
pub use spectrum::Rgb;
