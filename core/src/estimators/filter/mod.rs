//! Multi-vertex path filtering (MVF) as recursive marginal MIS over segments (Wang, West
//! and Hachisuka 2025, eq. 18–19; West, Georgiev and Hachisuka 2022, §5).
//!
//! Each pass traces one camera path per pixel with the sequential segment sampler from
//! the camera (eq. 15), each segment starting where the previous one ended (virtual
//! perturbation: the kernel's draw x_{i+1} ~ K(y_i) is the identity, and the kernel
//! enters the weights only). Every segment end y is a node ([`nodes`]). The segments
//! leaving node u, its BSDF continuation and its light sample, can then continue any
//! segment whose end v has u in its kernel: eq. (18) estimates the radiance along v's
//! segment as
//!
//!   ⟨L(s_v)⟩ = L_e(s_v) + Σ_{s'} K(s_v, s') f_r(s_v, s') G(s') ⟨L(s')⟩ / Σ_t p(s' | t),
//!
//! summing over every sampled segment s' and, in the denominator, over every technique t
//! able to draw s' (the continuation and the light sample conditioned on each node whose
//! kernel covers s's start: Fig. 3). The pixel is eq. (19) with the camera segment alone
//! (its technique is the camera's). [`weights`] reduces the terms to densities per solid
//! angle and shares visibility inside a kernel: no ray is traced to reuse a segment, as
//! both papers do.
//!
//! **Propagation.** Expanded, eq. (18) is a sum over every chain of kernel hops, a number
//! of segment paths exponential in depth. Because each denominator belongs to one segment
//! s' and not to the chain that reached it, the sum regroups as a product of sums (the
//! marginal MIS paper's eq. 14 regrouped per kernel), and L_d (radiance with at most d
//! further segments) follows from L_{d−1} in one sweep over the rows ([`graph`]): cost
//! O(d · Σ n²) for n nodes per kernel, linear in depth. A node's own continuation is
//! always among the techniques of the segments it continues with, so every segment a
//! chain uses has positive density (the classical technique the papers keep).
//!
//! **Approximations**, both shared with the papers: visibility and the BSDF at the
//! reused segment's start are taken from its own node (bias that vanishes with the
//! kernel); a node whose path ended at the depth cap has no continuation of its own, so
//! chains reaching it at a shallower depth continue only through its neighbours'.
//!
//! **Kernel**: the disk kernel of [`crate::segment::Kernel`], r₀ from the radius rule
//! shared with vertex merging (4 pixel footprints by default), shrinking over passes as
//! r_i = r₀ (i + 1)^((α − 1)/2) with α = 0.67 (Knaus and Zwicker 2011): consistent.

// Bidirectional path filtering ([`bpf`], weights in [`bidir`]) is the same estimator over
// camera and light segments together: docs/bidirectional-filtering.md.
pub mod bidir;
pub mod bpf;
pub mod bridge;
pub mod graph;
pub mod mvf;
pub mod node_grid;
pub mod nodes;
pub mod pass;
pub mod phf;
mod row_order;
pub mod weights;

pub use bidir::BidirDenominators;
pub use bidir::Bidirectional;
pub use bpf::Bpf;
pub use bridge::trace_bridges;
pub use graph::{FilterGraph, Real};
pub use mvf::Mvf;
pub use node_grid::{KernelPoint, NodeGrid, Side, kernel_points};
pub use nodes::{Node, scale_kernels, trace_camera_nodes, trace_light_nodes};
pub use pass::{FilterChunk, FilterPass};
pub use phf::Phf;
pub use weights::{Denominators, Neighbourhood};
