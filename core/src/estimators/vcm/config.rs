//! The vertex-merging estimators' configuration (PPM, BPM, VCM; compiled in every build).

use crate::merge::RadiusRule;
use crate::transport::config::{ConfigError, MAX_LIGHT_PATHS, check_f32, check_radius, check_u32};

/// Which vertex-merging estimator ([`crate::estimators::EstimatorConfig::Merging`]; also
/// `estimators::vcm::MergeMode`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MergeMode {
    /// Progressive photon mapping: merge at the first non-Dirac camera vertex, no MIS.
    Ppm,
    /// Bidirectional photon mapping: merge at every camera vertex, balance heuristic.
    Bpm,
    /// Vertex connection and merging.
    Vcm,
}

/// The vertex-merging estimators' settings (PPM, BPM, VCM).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MergingConfig {
    /// Light paths per pass, N_L [default: W·H, at most 4 000 000].
    pub light_paths: Option<u32>,
    /// How the initial radius r₀ is chosen (default: 4 pixel footprints, the segment
    /// paper's heuristic).
    pub radius: RadiusRule,
    /// Radius reduction α ∈ (0, 1]: r_i = r₀ (i + 1)^((α − 1)/2) (default 0.67, as in
    /// the segment paper; 1 keeps the radius fixed).
    pub alpha: f32,
    /// VCM: merge (off: BDPT's techniques only, for checks).
    pub merging: bool,
    /// VCM: connect (off: BPM's techniques only, for checks).
    pub connections: bool,
}

impl MergingConfig {
    /// The defaults.
    pub const DEFAULT: Self = Self { light_paths: None, radius: RadiusRule::DEFAULT, alpha: 0.67, merging: true, connections: true };

    /// N_L for a film of `pixels` pixels.
    pub fn light_paths_for(&self, pixels: u32) -> u32 {
        self.light_paths.unwrap_or(pixels.clamp(1, MAX_LIGHT_PATHS))
    }

    /// Does estimator `mode` merge with these settings? PPM and BPM always do; VCM unless
    /// `merging` is off (then no photon, grid or merge count exists).
    pub fn merges(&self, mode: MergeMode) -> bool {
        mode != MergeMode::Vcm || self.merging
    }

    /// Check every field against its range.
    pub fn validate(&self) -> Result<(), ConfigError> {
        if let Some(m) = self.light_paths {
            check_u32("light-paths", m, 1..=MAX_LIGHT_PATHS, "1..=4000000")?;
        }
        check_radius(self.radius)?;
        check_f32("alpha", self.alpha, self.alpha > 0.0 && self.alpha <= 1.0, "(0, 1]")
    }
}

impl Default for MergingConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}
