//! SPCBPT's configuration (compiled in every build).

use crate::transport::config::{ConfigError, MAX_DATASET, MAX_LIGHT_PATHS, check_f32, check_u32, light_paths_for};

/// SPCBPT's settings, with the paper's defaults. Scaling rule for small images: the
/// paper renders about 1280×720 with M = 100 000 light paths per pass, |D| = 1 000 000
/// dataset paths and N_S = 1000; here M defaults to min(100 000, W·H), |D| to
/// min(1 000 000, 16·W·H), M' to min(2 000 000, 2·W·H) and N_S to min(1000, ⌊√(W·H)⌋)
/// (at least 16), so Γ's N_S² entries number about the pixels and D holds at least 16
/// paths per entry (measured on ajar, enclosed and a door-like scene at 320×240 and
/// 320×168, 3 seeds: |D| = 10⁶ instead of W·H needs 1.17-1.41x fewer passes to the same
/// relMSE, docs/spcbpt.md; N_S = 1000 instead of ⌊√(W·H)⌋ made passes slower). The
/// paper's training takes 10⁶ / 10⁴ × 2 = 200 Adam steps; a smaller D keeps that budget
/// with smaller batches ([`SpcbptConfig::batch_for`]), since a fixed batch of 10 000 left
/// Γ near uniform (8 steps on ajar at 320×240, docs/spcbpt.md).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpcbptConfig {
    /// Light paths per pass, M [default: min(100 000, W·H)].
    pub light_paths: Option<u32>,
    /// Connections per camera vertex, N (default 3).
    pub connections: u32,
    /// Training paths, |D| [default: min(1 000 000, 16·W·H)].
    pub dataset: Option<u32>,
    /// Subspaces per side, N_S, on the light side shared with the light-source bins
    /// [default: min(1000, ⌊√(W·H)⌋), at least 16].
    pub subspaces: Option<u32>,
    /// Adam learning rate α (the paper's 0.1: measured 4-40× less excess loss than the
    /// public code's 0.01-0.02 within the paper's step budget, docs/spcbpt-training.md).
    pub learning_rate: f32,
    /// Adam mini-batch size at most (default 10 000, the paper's).
    pub batch: u32,
    /// Adam steps at least (default 200, the paper's |D| / batch × epochs): a smaller
    /// dataset is cut into smaller batches; 0 keeps `batch` whatever the dataset's size.
    pub steps: u32,
    /// Training epochs (default 2).
    pub epochs: u32,
    /// Weight of the uniform distribution mixed into Γ (default 0.1).
    pub mixture: f32,
    /// Light vertices retained per subspace across passes, M0 (default 200; 0: none).
    pub reuse: u32,
    /// Weight of the normal/direction terms in the classification distance, k_d (0.05).
    pub k_d: f32,
    /// Share of the N_S light subspaces given to positions on the lights (the paper's
    /// ~20 %); their vertices are cached and Γ-sampled instead of next-event estimation.
    /// 0, or a scene with a point, spot or infinite light, keeps NEE.
    pub light_source_share: f32,
    /// Light paths estimating Q per light subspace, M' [default: min(2 000 000, 2·W·H)].
    pub q_paths: Option<u32>,
}

impl SpcbptConfig {
    /// The defaults.
    pub const DEFAULT: Self = Self {
        light_paths: None,
        connections: 3,
        dataset: None,
        subspaces: None,
        learning_rate: 0.1,
        batch: 10_000,
        steps: 200,
        epochs: 2,
        mixture: 0.1,
        reuse: 200,
        k_d: 0.05,
        light_source_share: 0.2,
        q_paths: None,
    };

    /// M for a film of `pixels` pixels.
    pub fn light_paths_for(&self, pixels: u32) -> u32 {
        light_paths_for(self.light_paths, pixels)
    }
    /// |D| for a film of `pixels` pixels.
    pub fn dataset_for(&self, pixels: u32) -> u32 {
        self.dataset.unwrap_or(pixels.saturating_mul(16).clamp(1, 1_000_000))
    }
    /// N_S for a film of `pixels` pixels.
    pub fn subspaces_for(&self, pixels: u32) -> u32 {
        self.subspaces.unwrap_or_else(|| (crate::math::sqrt_f64(pixels as f64) as u32).clamp(16, 1000))
    }
    /// The Adam batch for a training set of `paths` paths: `batch`, or smaller so that
    /// `epochs` passes over the set take at least `steps` steps (never below 1).
    #[cfg(feature = "subspace")]
    pub fn batch_for(&self, paths: usize) -> usize {
        crate::subspace::batch_for_steps(paths, self.batch as usize, self.epochs, self.steps)
    }
    /// M' for a film of `pixels` pixels.
    pub fn q_paths_for(&self, pixels: u32) -> u32 {
        self.q_paths.unwrap_or(pixels.saturating_mul(2).clamp(1, 2_000_000))
    }

    /// Check every field against its range.
    pub fn validate(&self) -> Result<(), ConfigError> {
        if let Some(m) = self.light_paths {
            check_u32("light-paths", m, 1..=MAX_LIGHT_PATHS, "1..=4000000")?;
        }
        check_u32("connections", self.connections, 1..=1000, "1..=1000")?;
        if let Some(d) = self.dataset {
            check_u32("dataset", d, 1..=MAX_DATASET, "1..=20000000")?;
        }
        if let Some(n) = self.subspaces {
            check_u32("subspaces", n, 2..=4096, "2..=4096")?;
        }
        if let Some(q) = self.q_paths {
            check_u32("q-paths", q, 1..=MAX_DATASET, "1..=20000000")?;
        }
        check_f32("learning-rate", self.learning_rate, self.learning_rate > 0.0 && self.learning_rate <= 10.0, "(0, 10]")?;
        check_u32("batch", self.batch, 1..=10_000_000, "1..=10000000")?;
        check_u32("steps", self.steps, 0..=1_000_000, "0..=1000000")?;
        check_u32("epochs", self.epochs, 0..=1000, "0..=1000")?;
        check_f32("mixture", self.mixture, (0.0..=1.0).contains(&self.mixture), "[0, 1]")?;
        check_u32("reuse", self.reuse, 0..=100_000, "0..=100000")?;
        check_f32("k-d", self.k_d, (0.0..=1000.0).contains(&self.k_d), "[0, 1000]")?;
        check_f32("light-source-share", self.light_source_share, (0.0..1.0).contains(&self.light_source_share), "[0, 1)")
    }
}

impl Default for SpcbptConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}
