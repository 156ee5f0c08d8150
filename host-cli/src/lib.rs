//! `ember` command-line host: ray queries (obvhs), the parallel render loop, the film
//! and EXR/PNG output around the `no_std` core.
//!
//! The binary (`src/main.rs`) only parses and dispatches; everything lives in this
//! library so the benchmarks and integration tests can reach it.

pub mod accel;
pub mod app;
pub mod auto;
pub mod cli;
pub mod convergence;
pub mod distributed;
pub mod driver;
pub mod estimators;
pub mod files;
pub mod image_io;
pub mod interrupt;
pub mod memory;
pub mod metrics;
pub mod mitsuba;
pub mod plan;
pub mod plot;
pub mod suite;
pub mod trained;

/// The core's film (one film for every host).
pub mod film {
    pub use ember_core::render::Film;
}
