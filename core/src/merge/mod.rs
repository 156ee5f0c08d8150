//! Vertex merging's shared machinery: what photon mapping, bidirectional photon mapping,
//! VCM/UPS and the segment filters all need to find light vertices near a point.
//!
//! - [`grid`]: a hash grid over points, rebuilt every pass into storage it keeps, whose
//!   queries visit only the (at most eight) cells a ball of radius r can touch;
//! - [`cells`]: a grid of cells half the query radius, hashed by rows so that a query
//!   scans a few contiguous runs (the segment filters', whose passes are queries);
//! - [`radius`]: the kernel radius: its initial value r₀ (the segment paper's heuristic,
//!   4 × the mean pixel footprint, or a fraction of the scene's bounding radius as in
//!   SmallVCM, or absolute) and the progressive schedule r_i = r₀ (i + 1)^((α − 1)/2)
//!   (Knaus and Zwicker 2011, with per-pass radius reduction as in Hachisuka and Jensen's
//!   progressive photon mapping; α = 0.67 as in the segment paper);
//! - the kernel itself is the uniform disk: a light vertex within distance r of a camera
//!   vertex is merged with weight 1/(π r² N_L), N_L the light paths of the pass.
//!
//! The grid is compiled with the cargo feature `hash-grid` (implied by `merging` and
//! `filtering`); the radius rules always, since every configuration names one.
//!
//! The pass index in the schedule is the global pass number, so a render split into pass
//! ranges on several machines gets the same radius in every pass.

#[cfg(feature = "hash-grid")]
pub mod cells;
#[cfg(feature = "hash-grid")]
pub mod grid;
pub mod radius;
#[cfg(feature = "hash-grid")]
mod slots;

#[cfg(feature = "hash-grid")]
pub use cells::CellGrid;
#[cfg(feature = "hash-grid")]
pub use grid::HashGrid;
pub use radius::{Footprint, RadiusRule, progressive_radius};
