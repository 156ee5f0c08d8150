//! Shared test kit of the ember workspace: χ² goodness-of-fit tests of samplers,
//! distribution functions for significance levels, and running statistics.
//! Integration tests live in `tests/tests/`.

pub mod chi2;
pub mod stats;
pub mod tracer;
pub mod scenes;
pub mod render;
pub mod reference;
pub mod mmis_1d;
pub mod bdpt_oracle;
