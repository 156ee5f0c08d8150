//! The segment estimators' configuration (segment PT, LT, BDPT; compiled in every build).

use crate::merge::RadiusRule;
use crate::transport::config::{ConfigError, check_radius};

/// Which sequential segment estimator.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SegmentAlgorithm {
    /// Segments from the camera ([`crate::estimators::segment::spt`]).
    PathTracing,
    /// Segments from the lights ([`crate::estimators::segment::slt`]).
    LightTracing,
    /// Segments from both, joined by bridges ([`crate::estimators::segment::sbdpt`]).
    Bidirectional,
}

/// The kernel joining consecutive segments, as chosen on the command line (its radius
/// is resolved per scene from [`SegmentConfig::radius`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum KernelChoice {
    /// x_{i+1} = y_i: the vertex formulation (the default).
    Dirac,
    /// Uniform over the surface within a disk around y_i.
    Disk,
}

/// The segment estimators' settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SegmentConfig {
    /// The kernel (default: Dirac).
    pub kernel: KernelChoice,
    /// The disk kernel's radius (default: 4 pixel footprints, the rule vertex merging
    /// uses for r₀; the radius stays fixed over passes).
    pub radius: RadiusRule,
}

impl SegmentConfig {
    /// The defaults.
    pub const DEFAULT: Self = Self { kernel: KernelChoice::Dirac, radius: RadiusRule::DEFAULT };

    /// Check every field against its range.
    pub fn validate(&self) -> Result<(), ConfigError> {
        check_radius(self.radius)
    }
}

impl Default for SegmentConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}
