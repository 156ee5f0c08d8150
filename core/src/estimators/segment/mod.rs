//! The segment estimators of Wang, West and Hachisuka 2025 (the segment path integral,
//! eq. 3–4, and its kernels: [`crate::segment`], whose notes derive them):
//!
//! - [`spt`]: segment path tracing, the sequential sampler of eq. (15) from the camera
//!   with the sequential estimator (eq. 16) and the light-sampled last segment combined
//!   by eq. (17); with the Dirac kernel it is PT.
//! - [`slt`]: segment light tracing, eq. (15) from the lights, the last segment to the
//!   pinhole; with the Dirac kernel it is LT.
//! - [`sbdpt`]: segment BDPT, camera and light segment sequences joined by bridge
//!   segments under the balance heuristic over every technique; with the Dirac kernel
//!   it is BDPT.
//! - `phases`: their one phase per pass, after the footprint setup that resolves the
//!   disk kernel's radius ([`Segments`]).
//!
//! docs/segments.md has the derivations and what each test proves.

mod phases;
pub mod sbdpt;
pub mod slt;
pub mod spt;

pub use phases::Segments;
