//! Shared test kit of the ember workspace: χ² goodness-of-fit tests of samplers,
//! distribution functions for significance levels, and running statistics.
//! Integration tests live in `tests/tests/`.

pub mod bdpt_oracle;
pub mod chi2;
pub mod mmis_1d;
pub mod reference;
pub mod render;
pub mod scenes;
pub mod stats;
pub mod tracer;
