//! `ember-cli`: the `ember` command — its syntax (clap, [`cli`]) and its commands
//! ([`app`]: render, compare, convergence, suite, train, plan, merge), split renders
//! ([`distributed`]), trained models ([`trained`]), the scene plan and `--estimator
//! auto` on threads, and what a terminal shows ([`progress`]).
//!
//! What code here may do: anything a program may (print, exit with a status, read the
//! environment). It builds on `ember-host` (ray queries, the driver, interrupts, memory)
//! and `ember-formats` (scene files, images, metrics); neither depends on it, and the C
//! library links neither it nor clap.
//!
//! The binary (`src/main.rs`) only parses and dispatches; everything lives in this
//! library so the benchmarks and integration tests can reach it.

pub mod app;
pub mod auto;
pub mod cli;
pub mod convergence;
pub mod distributed;
pub mod estimators;
pub mod plan;
pub mod plot;
pub mod progress;
pub mod setup;
pub mod suite;
pub mod trained;

/// The core's film (one film for every host).
pub mod film {
    pub use ember_core::render::Film;
}
