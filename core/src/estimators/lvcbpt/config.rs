//! LVCBPT's configuration (compiled in every build, so a host can name the estimator a
//! build leaves out).

use crate::transport::config::{ConfigError, MAX_DATASET, MAX_LIGHT_PATHS, check_u32, light_paths_for};

/// LVCBPT's settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LvcbptConfig {
    /// Light paths per pass, M [default: min(100 000, W·H)].
    pub light_paths: Option<u32>,
    /// Connections per camera vertex, N (default 3).
    pub connections: u32,
    /// Light paths measuring c̄, the mean cacheable vertices per path (default 16 384).
    pub probe_paths: u32,
}

impl LvcbptConfig {
    /// The defaults.
    pub const DEFAULT: Self = Self { light_paths: None, connections: 3, probe_paths: 16_384 };

    /// M for a film of `pixels` pixels.
    pub fn light_paths_for(&self, pixels: u32) -> u32 {
        light_paths_for(self.light_paths, pixels)
    }

    /// Check every field against its range.
    pub fn validate(&self) -> Result<(), ConfigError> {
        if let Some(m) = self.light_paths {
            check_u32("light-paths", m, 1..=MAX_LIGHT_PATHS, "1..=4000000")?;
        }
        check_u32("connections", self.connections, 1..=1000, "1..=1000")?;
        check_u32("probe-paths", self.probe_paths, 1..=MAX_DATASET, "1..=20000000")
    }
}

impl Default for LvcbptConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}
