//! SPCBPT's learned pieces: sub-path classification κ, the subspace matrix Γ and its
//! MIS-aware training [Su, Li, Wang 2022, "SPCBPT"].
//!
//! SPCBPT connects each eye sub-path Z̄ to light sub-paths resampled from a cache with the
//! approximate optimal selection function of eq. 7,
//!
//! ```text
//! γ_r(Ȳ, Z̄) = Γ(κ_L(Ȳ) | κ_E(Z̄)) · f_y(Ȳ) / Q(κ_L(Ȳ)),      Q(i) = ∫_{κ_L(ȳ)=i} f_y   (eq. 7, 8)
//! ```
//!
//! sampled in two stages (eq. 9): a light subspace from the Γ column of Z̄'s eye subspace,
//! then a cached vertex ∝ f_y/p inside it. With N connections per eye vertex the strategy
//! t ≥ 2 has pdf N·p(Z̄)·γ_r (eq. 11), weighted by the balance heuristic (eq. 12). Note that
//! eq. 10 as printed omits the light sub-path's own pdf p(Ȳ); the renderer (not this module)
//! divides by both sub-path pdfs.
//!
//! This module is the pure mathematics, with no scene or tracer knowledge:
//! - [`features`]: what κ looks at — the end vertex (position, normal, incident direction).
//! - [`classify`]: the distance of eq. 18, centroids drawn ∝ contribution (section 6.4),
//!   nearest-centroid κ (eq. 17), the decision tree that fits it (section 7.2.2), and the
//!   light-source (u, v) bins (section 7.2.1).
//! - [`subspace_matrix`]: Γ = column-normalised σ(Θ) mixed with m·uniform (section 7.3).
//! - [`loss`]: the variance bound Σ f²/(p·F(x|Γ)) of eq. 15 with F of eq. 16, and its exact
//!   gradient w.r.t. Θ through the mixture and the column normalisation.
//! - [`adam`], [`train`]: mini-batch Adam over the dataset (section 7.3); hosts parallelise
//!   by calling [`loss_and_gradient`] on sub-ranges of a batch.
//!
//! Q (eq. 19) is a plain average of f_y/p per light subspace and lives with the renderer,
//! which traces the M' light paths. Empty subspaces at render time are also the renderer's
//! business (restricted, renormalised Γ columns in sampling and in every MIS denominator).
//! Derivations, choices and measurements: docs/spcbpt-training.md.

pub mod adam;
pub mod classify;
pub mod features;
pub mod loss;
pub mod subspace_matrix;
pub mod train;

pub use adam::{Adam, AdamParams};
pub use classify::{DecisionTree, DistanceParams, LightSourceBins, TreeParams, nearest_centroid, sample_centroids};
pub use features::SubpathFeature;
pub use loss::{TrainingSet, TrainingSplit, loss_and_gradient, loss_and_gradient_indexed, loss_only};
pub use subspace_matrix::{SubspaceMatrix, gamma_from_theta};
pub use train::{TrainParams, batch_for_steps, train};
